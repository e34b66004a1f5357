"""Exceptions raised by flexgear. Every message names the parameter, its value and the rule."""


class FlexgearError(Exception):
    """Base class of flexgear errors."""


class ConfigError(FlexgearError, ValueError):
    """A configuration value breaks a rule (unknown key, non-positive size, ...)."""


class GeometryError(FlexgearError, ValueError):
    """A gear or gear set cannot be made or assembled (pointed teeth, overlapping planets, ...)."""


class DivergenceError(FlexgearError, RuntimeError):
    """A simulation diverged; the message says when (simulated time) and where (mesh, body)."""


class EigenSolveError(FlexgearError, RuntimeError):
    """An eigen-solve returned pairs whose residuals exceed the bound (the message gives both)."""


class ResultExistsError(FlexgearError, FileExistsError):
    """Refusing to overwrite an existing result."""


def user_stacklevel() -> int:
    """``stacklevel`` for a ``warnings.warn`` in the calling function that points at the first
    frame outside the flexgear package (the user's line, however deep the call came in)."""
    import os
    import sys

    package = os.path.dirname(os.path.abspath(__file__))
    frame, level = sys._getframe(1), 1
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(package + os.sep):
        frame, level = frame.f_back, level + 1
    return level
