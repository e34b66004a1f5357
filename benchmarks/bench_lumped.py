"""Lumped against rigid MERCURY 1-A per simulated second, and the modal analysis time.

Usage::

    python benchmarks/bench_lumped.py [--duration 1.0]

Prints, from one process: the rigid and the lumped model's integration wall time per simulated
second (after a short warm-up run that compiles or loads the numba caches), their ratio, the
lumped model's build time (rigid model, static equilibria over a mesh cycle) and the time of
the modal analysis of the rigid set (linearisation + eigen-solution, the model built).
Targets: lumped >= 100 x faster than rigid; modal analysis < 1 s.
"""
from __future__ import annotations

import argparse
import time
import warnings

from machine_info import machine
from flexgear.config import load_config, loads_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.lumped.model import build_lumped
from flexgear.dynamics.lumped.time_loop import simulate_lumped
from flexgear.dynamics.modal.linearise import linearise
from flexgear.dynamics.modal.system import modes
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.app.run import time_grid


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per model")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    print(machine())
    cfg = load_config("mercury_1a")
    h, oe = time_grid(cfg.simulation)
    model = build_model(cfg)
    simulate(model, 0.005, h, oe)  # compile / load the cache
    rigid = simulate(model, args.duration, h, oe)
    t0 = time.perf_counter()
    sysl = linearise(model)
    res = modes(sysl)
    t_modal = time.perf_counter() - t0
    lcfg = loads_config('model = "lumped"\n' + preset_path("mercury_1a").read_text())
    t0 = time.perf_counter()
    lm = build_lumped(lcfg)
    t_build = time.perf_counter() - t0
    simulate_lumped(lm, 0.005, h, oe)
    lumped = simulate_lumped(lm, args.duration, h, oe)
    r_s = rigid.wall / args.duration
    l_s = lumped.wall / args.duration
    print(f"MERCURY 1-A, step {h*1e6:.1f} us, {args.duration:g} s simulated each")
    print("| model  | wall s per simulated s | steps | iterations |")
    print("|--------|------------------------|-------|------------|")
    print(f"| rigid  | {r_s:.4f} | {rigid.steps} | {rigid.newton} |")
    print(f"| lumped | {l_s:.5f} | {lumped.steps} | {lumped.newton} |")
    print(f"lumped is {r_s / l_s:.0f} x faster than rigid per simulated second (target >= 100)")
    print(f"lumped model build (rigid model + {lm.k.shape[1]} static positions): {t_build:.2f} s")
    print(f"modal analysis of the rigid set ({len(res.frequencies)} modes, {sysl.attrs['n_positions']} positions): "
          f"{t_modal:.3f} s (target < 1 s)")


if __name__ == "__main__":
    main()
