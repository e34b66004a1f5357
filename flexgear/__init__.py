"""flexgear: vibration of spur and planetary gears with rigid and flexible bodies.

The subpackages are the layers of a one-way flow (a module imports only from its own layer or
below; ``tests/test_architecture.py`` checks it)::

    gears -> config -> fe -> stiffness -> reduction -> dynamics -> results -> monitoring -> app
    (base: errors, units, files, style, kernels)

All quantities are SI (m, kg, s, N, rad) inside the package; unit conversions happen once,
when a configuration is read (:mod:`flexgear.config`, :mod:`flexgear.units`).

The names used most are available here, imported on first use::

    import flexgear
    cfg = flexgear.load_config("mercury_1a")
    res = flexgear.run(cfg)
    flexgear.save(res, "out/my_run.h5")
    res = flexgear.load("out/mercury_1a/results.h5")
"""
__version__ = "0.1.0"

__all__ = ["__version__", "load", "load_config", "run", "save"]


def load(path):
    """Read a result file written by ``flexgear run`` (see :func:`flexgear.results.load`)."""
    from .results.store import load as _load

    return _load(path)


def load_config(path_or_preset):
    """Read and validate a configuration (see :func:`flexgear.config.load_config`)."""
    from .config.loader import load_config as _load_config

    return _load_config(path_or_preset)


def run(config, progress=None, messages=None, model=None, threads=None):
    """Simulate a configuration (see :func:`flexgear.app.run.run`). ``progress``: True shows a
    progress bar with the phases of the wait written above it (the first run on a machine
    compiles the solver for minutes), in a notebook too; None (default): that bar in an
    interactive session (stderr a terminal, or a Jupyter kernel), nothing elsewhere (a pipe, a
    log, a batch's worker), where True writes plain progress lines instead; False: nothing."""
    from .app.run import run as _run

    if progress is None:
        from .app.console import watched

        progress = watched()
    return _run(config, progress=progress, messages=messages, model=model, threads=threads)


def save(result, path, overwrite=False):
    """Write a result to an HDF5 file (see :func:`flexgear.results.store.save`)."""
    from .results.store import save as _save

    return _save(result, path, overwrite=overwrite)


_SUBPACKAGES = ("app", "config", "dynamics", "fe", "gears", "monitoring", "reduction", "results", "stiffness")


def __getattr__(name):
    """``flexgear.config``, ``flexgear.results``, ...: a subpackage imported on first use, as
    ``import flexgear.config`` would."""
    if name in _SUBPACKAGES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
