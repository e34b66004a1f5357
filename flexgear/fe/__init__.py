"""Finite elements of the gear bodies (layer 3): gmsh meshing, scikit-fem stiffness and mass,
loads, eigen and static solves, Richardson extrapolation, VTU/PNG output."""
