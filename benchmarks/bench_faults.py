"""Benchmark of faulty gears: a faulted run's cost per simulated second against the healthy one,
at each fidelity, and the faulty gear's reduction uncached and cached.

For the spur pair (``spur_pair``; ``spur_pair_flexible`` for the flexible model; 40 um thinning
per gear in every run, healthy too, which the eccentricity needs) and each fault of ``--faults``
(``missing``: pinion tooth 5 down to 70 % of its height, which leaves its pair the contact the
lumped model needs; ``spall``: 25 um deep on its loaded flank; ``crack``: 1 mm at 45 deg at its
root; ``eccentricity``: 20 um run-out of the wheel; ``partial_crack``, ``partial_spall``: the
crack and the spall over half the face width), prints per fidelity (lumped, rigid, flexible) the
wall time per simulated second of the healthy and the faulted model and their ratio. The two
models are built first (outside the timing), the kernels compiled or loaded by a short warm-up
run of each, then the healthy and the faulted run alternate ``--repeat`` times, back to back in
one process, and the fastest of each counts: on a shared machine compare the ratios, not the
times. Then the faulty pinion's FE mesh and reduction (``reduce_gear`` with the faults) in a
fresh empty cache directory, and again from that cache.

Targets (issue 22): faulted <= 1.25 x healthy per simulated second at each fidelity; the faulty
gear's mesh and reduction <= 30 s uncached, < 1 s cached.

Usage::

    python benchmarks/bench_faults.py [--duration 0.1] [--level 2] [--faults missing crack eccentricity]
                                      [--fidelities lumped rigid flexible] [--repeat 2]
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine_info import machine  # noqa: E402

from flexgear.app.run import time_grid  # noqa: E402
from flexgear.config import loads_config, preset_path  # noqa: E402
from flexgear.dynamics.flexible.reductions import reduction_jobs  # noqa: E402
from flexgear.dynamics.integrator.simulation import simulate  # noqa: E402
from flexgear.dynamics.lumped.model import build_lumped  # noqa: E402
from flexgear.dynamics.lumped.time_loop import simulate_lumped  # noqa: E402
from flexgear.dynamics.model.assembly import build_model  # noqa: E402
from flexgear.reduction.gear import reduce_gear  # noqa: E402

RATIO_TARGET = 1.25
LUMPED_DURATION = 1.0  # s: at least this much simulated per lumped run (about 15 ms of wall time a second)
REDUCTION_TARGETS = (30.0, 1.0)  # s uncached, cached
FAULTS = {
    "missing": '\n[[faults]]\nkind = "missing"\ngear = "pinion"\ntooth = 5\nheight_fraction = 0.7\n',
    "spall": ('\n[[faults]]\nkind = "spall"\ngear = "pinion"\ntooth = 5\nflank = "left"\nstart_radius = 23.5e-3\n'
              'end_radius = 24.5e-3\ndepth = 25.0e-6\n'),
    "crack": '\n[[faults]]\nkind = "crack"\ngear = "pinion"\ntooth = 5\nflank = "left"\ndepth = 1.0e-3\n',
    "eccentricity": "\n[errors.eccentricity.wheel]\nmagnitude = 20.0e-6\nphase_deg = 30.0\n",
    # over half the face width: the flexible model's series compliance and compliant-law slices
    "partial_crack": ('\n[[faults]]\nkind = "crack"\ngear = "pinion"\ntooth = 5\nflank = "left"\ndepth = 1.0e-3\n'
                      'width_fraction = 0.5\n'),
    "partial_spall": ('\n[[faults]]\nkind = "spall"\ngear = "pinion"\ntooth = 5\nflank = "left"\n'
                      'start_radius = 23.5e-3\nend_radius = 24.5e-3\ndepth = 25.0e-6\nwidth_fraction = 0.5\n'),
}


def load() -> str:
    return f"load {os.getloadavg()[0]:.1f}"


def config(fidelity: str, extra: str, level: int, duration: float):
    """The spur pair (flexible preset for ``flexible``, FE level ``level``) with ``extra`` blocks
    and 40 um thinning per gear, healthy too (the eccentricity would close the presets' zero
    backlash)."""
    preset = "spur_pair_flexible" if fidelity == "flexible" else "spur_pair"
    text = preset_path(preset).read_text().replace("thinning = 0.0 ", "thinning = 40.0e-6 ")
    if fidelity == "lumped":
        text = 'model = "lumped"\n' + text
    cfg = loads_config(text.replace("[simulation]", extra + "\n[simulation]"))
    if cfg.flexible:
        cfg.flexible["level"] = level
    cfg.simulation.update(duration=duration)
    return cfg


CLOCK = {"cpu": False}  # --cpu: the process's CPU time (steadier on a loaded machine; one thread)


def runner(cfg):
    """``run(t_end)`` -> wall seconds (CPU seconds with --cpu) of the integration of the model of
    ``cfg`` (built here)."""
    h, oe = time_grid(cfg.simulation)
    if cfg.model == "lumped":
        lm = build_lumped(cfg)
        go = lambda t: simulate_lumped(lm, t, h, oe)  # noqa: E731
    else:
        model = build_model(cfg)
        go = lambda t: simulate(model, t, h, oe, threads=1 if CLOCK["cpu"] else None)  # noqa: E731
    if not CLOCK["cpu"]:
        return lambda t: go(t).wall

    def cpu(t):
        t0 = time.process_time()
        go(t)
        return time.process_time() - t0

    return cpu


def per_second(fidelity: str, fault: str, level: int, duration: float, repeat: int) -> tuple[float, float]:
    """Best wall time per simulated second of the healthy and the faulted model, back to back
    (lumped: at least LUMPED_DURATION simulated, its runs being too short to time otherwise)."""
    if fidelity == "lumped":
        duration = max(duration, LUMPED_DURATION)
    runs = [runner(config(fidelity, "", level, duration)), runner(config(fidelity, FAULTS[fault], level, duration))]
    h = time_grid(config(fidelity, "", level, duration).simulation)[0]
    for r in runs:
        r(20 * h)  # compile or load the kernels
    best = [float("inf"), float("inf")]
    for _ in range(repeat):
        for i, r in enumerate(runs):
            best[i] = min(best[i], r(duration) / duration)
    return best[0], best[1]


def reduction_times(fault: str, level: int) -> tuple[float, float] | None:
    """Wall time of the faulty pinion's mesh and reduction in an empty cache, then cached (None
    for an error, which leaves the FE body healthy)."""
    cfg = config("flexible", FAULTS[fault], level, 0.01)
    with tempfile.TemporaryDirectory() as tmp:
        jobs, cache = reduction_jobs(cfg, Path(tmp))
        if "pinion" not in jobs or not jobs["pinion"].get("faults"):
            return None
        out = []
        for _ in range(2):
            t0 = time.perf_counter()
            reduce_gear(**jobs["pinion"], cache_dir=cache)
            out.append(time.perf_counter() - t0)
    return out[0], out[1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.1, help="simulated seconds per timed run")
    ap.add_argument("--level", type=int, default=2, help="FE mesh level of the flexible gears (preset: 2)")
    ap.add_argument("--faults", nargs="+", choices=sorted(FAULTS), default=["missing", "crack", "eccentricity"])
    ap.add_argument("--fidelities", nargs="+", choices=("lumped", "rigid", "flexible"),
                    default=["lumped", "rigid", "flexible"])
    ap.add_argument("--repeat", type=int, default=2, help="alternating timed runs of each model (the best counts)")
    ap.add_argument("--cpu", action="store_true", help="time the process's CPU, one solver thread (a loaded machine)")
    args = ap.parse_args(argv)
    CLOCK["cpu"] = args.cpu
    warnings.simplefilter("ignore")
    print(machine())
    print(f"spur pair, {args.duration:g} s simulated per run (lumped: >= {LUMPED_DURATION:g} s), best of "
          f"{args.repeat} alternating runs{' (CPU seconds, one thread)' if args.cpu else ''}; "
          f"flexible: FE level {args.level}")
    print("| fidelity | fault | healthy s/s | faulted s/s | ratio | target | load |")
    print("|---|---|---|---|---|---|---|")
    worst = 0.0
    for fid in args.fidelities:
        for fault in args.faults:
            h, f = per_second(fid, fault, args.level, args.duration, args.repeat)
            worst = max(worst, f / h)
            print(f"| {fid} | {fault} | {h:.4g} | {f:.4g} | {f / h:.3f} | <= {RATIO_TARGET} | {load()} |", flush=True)
    print(f"largest ratio {worst:.3f} (target <= {RATIO_TARGET})")
    if "flexible" in args.fidelities:
        print(f"faulty pinion, FE level {args.level}: mesh + reduction (targets {REDUCTION_TARGETS[0]:g} s uncached, "
              f"< {REDUCTION_TARGETS[1]:g} s cached)")
        for fault in args.faults:
            t = reduction_times(fault, args.level)
            if t is None:
                print(f"  {fault}: the FE body stays nominal (an error, or a fault over part of the face width), no reduction of its own")
            else:
                print(f"  {fault}: uncached {t[0]:.1f} s, cached {t[1]:.3f} s ({load()})", flush=True)


if __name__ == "__main__":
    main()
