"""Fill the caches before the first real run: ``flexgear warm [CONFIG ...]``.

A first run compiles the kernels (numba, cached on disk by :mod:`flexgear.kernels`) and builds
the contact tables and, for flexible gears, the reductions (cached under the user cache
directory). ``warm`` does that once per configuration with a run a few output samples long, so
that an image built for a cluster, or the nodes of a job array sharing one file system, start
their real runs from warm caches. Each phase is timed and reported.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

from ..config import load_config

#: Configurations warmed by default: the rigid presets and the lumped model of each (the
#: flexible presets reduce their gears, tens of seconds each: name them to warm them too).
DEFAULT_CONFIGS = ("spur_pair", "mercury_1a", "spur_pair:lumped", "mercury_1a:lumped")


@dataclass
class WarmTiming:
    """Wall times [s] of one configuration's warm-up."""

    config: str
    total: float
    build: float  # model building (contact tables, reductions, assembly) including its kernels
    build_kernels: float  # of ``build``: compiling or loading kernels
    solver_kernels: float  # compiling or loading the force kernels and the time loop


def warm_config(name: str, cfg, messages=None) -> WarmTiming:
    """Run the configuration ``cfg`` (named ``name``) for a few output samples, so that
    everything a run of it compiles or tabulates is cached. Its warnings about the configuration
    (a damping ratio, a step) are left to its real runs: the default list warms configurations
    nobody asked about."""
    from .run import run

    cfg.simulation.update(run_in=0.0, duration=4.0 / cfg.simulation["output_rate"])
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = run(cfg, messages=messages).attrs
    return WarmTiming(name, time.perf_counter() - t0, float(a["build_seconds"]),
                      float(a.get("build_compile_seconds", 0.0)), float(a["compile_seconds"]))


def warm(names=DEFAULT_CONFIGS, messages=None) -> list[WarmTiming]:
    """:func:`warm_config` for each name (a preset or TOML path; ``NAME:lumped`` its lumped
    model), in order; every configuration is read first, so a bad name fails before any work
    (its warnings, as :func:`warm_config`'s, are left to the real runs)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        configs = [(name, load_config(name)) for name in names]
    return [warm_config(name, cfg, messages) for name, cfg in configs]
