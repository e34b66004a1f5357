"""Results (layer 7): the HDF5 result file, signal processing and publication-style figures.

``from flexgear.results import Result, load, save`` re-exports :mod:`flexgear.results.store`.
"""
from .store import BodySignals, MeshSignals, Result, load, save

__all__ = ["BodySignals", "MeshSignals", "Result", "load", "save"]
