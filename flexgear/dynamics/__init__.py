"""Multi-body dynamics (layer 6): tooth contact, bodies, model building and the compiled solver."""
from .kernel_cache import invalidate_if_stale

invalidate_if_stale()
