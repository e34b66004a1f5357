"""Wall time per simulated second of the rigid presets, JIT compile time reported apart.

Usage::

    python benchmarks/bench_rigid.py [--duration 1.0]

Prints, per preset: model build time (outlines and signed distance fields), one-off numba
compile time (a 5 ms run in a fresh process, including loading the on-disk cache when it
exists), wall seconds per simulated second, steps and Newton iterations. Targets on a 2-core
machine: mercury_1a <= 5 s, spur_pair <= 2 s per simulated second.
"""
from __future__ import annotations

import argparse
import time
import warnings

from machine_info import machine
from flexgear.dynamics.model.assembly import build_model
from flexgear.config import load_config
from flexgear.app.run import run, time_grid
from flexgear.dynamics.integrator.simulation import simulate


def bench(preset: str, duration: float):
    cfg = load_config(preset)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = build_model(cfg)
    t_build = time.perf_counter() - t0
    h, oe = time_grid(cfg.simulation)
    t0 = time.perf_counter()
    simulate(model, 0.005, h, oe)  # compiles (or loads the numba cache)
    t_jit = time.perf_counter() - t0
    cfg.simulation.update(duration=duration, run_in=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = run(cfg)
    a = res.attrs
    sim = duration + 40 / a["output_rate"]  # the output rate used (the synchronous grid moves it)
    return dict(preset=preset, build=t_build, jit=t_jit, wall=a["wall_seconds"], per_s=a["wall_seconds"] / sim,
                steps=a["solver_steps"], newton=a["newton_iterations"], rejected=a["rejected_steps"], h=a["step"])


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--duration", type=float, default=1.0)
    args = p.parse_args()
    print(f"machine: {machine()}")
    print(f"{'preset':<11} {'build s':>8} {'jit s':>7} {'wall s/sim s':>13} {'steps':>7} {'newton':>7} "
          f"{'newton/step':>11} {'rejected':>8} {'step us':>8}")
    for preset in ("spur_pair", "mercury_1a"):
        r = bench(preset, args.duration)
        print(f"{r['preset']:<11} {r['build']:8.2f} {r['jit']:7.2f} {r['per_s']:13.2f} {r['steps']:7d} "
              f"{r['newton']:7d} {r['newton']/r['steps']:11.2f} {r['rejected']:8d} {r['h']*1e6:8.1f}")


if __name__ == "__main__":
    main()
