"""Multi-body dynamics (layer 6): tooth contact, bodies, model building and the compiled solver."""
from .threads import use_openmp

use_openmp()  # before any parallel loop runs (flexgear.dynamics.threads)
