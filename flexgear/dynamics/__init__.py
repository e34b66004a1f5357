"""Multi-body dynamics (layer 6): tooth contact, bodies, model building and the compiled solver."""
