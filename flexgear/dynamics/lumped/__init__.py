"""Lumped-parameter models: published planetary models from explicit parameters, and the lumped
model of a configuration with its compiled time loop."""
