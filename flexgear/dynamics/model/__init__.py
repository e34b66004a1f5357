"""The model the solver integrates: bodies, joints, meshes and shafts, built from a configuration,
and the named tables the compiled kernels read."""
