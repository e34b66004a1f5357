"""Linearisation and modal analysis: linear systems, equilibria, the tangent of a flexible model,
mode types and Campbell diagrams."""
