"""Multi-body dynamics (layer 6): tooth contact, bodies, model building and the compiled solver."""
from .kernel_cache import invalidate_if_stale
from .threads import use_openmp

invalidate_if_stale()
use_openmp()  # before any parallel loop runs (flexgear.dynamics.threads)
