"""Benchmark of the flexible models: wall time per simulated second, flexible against rigid.

For each preset pair (``spur_pair`` / ``spur_pair_flexible``, ``mercury_1a`` /
``mercury_1a_flexible``) prints the preprocessing time of the flexible model (reductions,
uncached on the first run, then from the cache), the generalised coordinate count, the
condensed mode count, and the wall time per simulated second of both models from the same
process (compile time excluded: one short warm-up run first), with their ratio.

Targets (issue 8, 2 cores): flexible MERCURY 1-A <= 10 s per simulated second, flexible spur
pair <= 3 s.

Usage::

    python benchmarks/bench_flexible.py [--duration 0.1] [--level 2] [--check]
"""
from __future__ import annotations

import argparse
import sys
import time

from flexgear.config import load_config
from flexgear.dynamics.assembly import build_model
from flexgear.dynamics.solver import simulate

TARGETS = {"spur_pair_flexible": 3.0, "mercury_1a_flexible": 10.0}


def _per_second(model, duration, h):
    simulate(model, 8 * h, h, 8)  # compile or load the kernels
    t0 = time.perf_counter()
    r = simulate(model, duration, h, 8)
    wall = time.perf_counter() - t0
    return wall / duration, r


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=0.1, help="simulated time per run [s]")
    p.add_argument("--level", type=int, default=None, help="FE mesh level of the reductions (default: preset)")
    p.add_argument("--check", action="store_true", help="exit 1 if a target is missed")
    a = p.parse_args(argv)
    ok = True
    for rigid_name in ("spur_pair", "mercury_1a"):
        flex_name = rigid_name + "_flexible"
        cfg = load_config(flex_name)
        if a.level is not None:
            cfg.flexible["level"] = a.level
        h = cfg.simulation["step"]
        t0 = time.perf_counter()
        flex = build_model(cfg)
        t_pre = time.perf_counter() - t0
        rigid = build_model(load_config(rigid_name))
        s_rigid, _ = _per_second(rigid, a.duration, h)
        s_flex, r = _per_second(flex, a.duration, h)
        n = len(flex.initial_state()[0])
        modes = sum(f.shape.shape[3] for f in flex.flex)
        modal = sum(f.modes for f in flex.flex)
        print(f"{flex_name}: preprocessing {t_pre:.2f} s (level {cfg.flexible['level']}), {n} coordinates "
              f"({flex.rigid_coordinates()} rigid + {modal} modal, dynamic_cutoff "
              f"{cfg.flexible['dynamic_cutoff']:g} Hz), {len(flex.flex)} flexible bodies with {modes} condensed modes")
        print(f"  wall per simulated second: flexible {s_flex:.2f} s, rigid {s_rigid:.2f} s, "
              f"ratio {s_flex / s_rigid:.2f}; Newton iterations per step {r.newton / max(r.steps, 1):.2f}, "
              f"rejected steps {r.rejected}")
        if s_flex > TARGETS[flex_name]:
            ok = False
            print(f"  target missed: {s_flex:.2f} s > {TARGETS[flex_name]} s")
    return 0 if (ok or not a.check) else 1


if __name__ == "__main__":
    sys.exit(main())
