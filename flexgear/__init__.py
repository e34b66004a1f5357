"""flexgear: vibration of spur and planetary gears with rigid and flexible bodies.

Data flows one way::

    geometry -> (meshing -> fe -> reduction) -> contact -> bodies -> solver -> results -> signals/plots

All quantities are SI (m, kg, s, N, rad) inside the package; unit conversions happen once,
when a configuration is read (:mod:`flexgear.config`, :mod:`flexgear.units`).
"""
__version__ = "0.1.0"


def load(path):
    """Read a result file written by ``flexgear run`` (see :mod:`flexgear.results`)."""
    from .results import load as _load

    return _load(path)
