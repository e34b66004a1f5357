"""Cost of the anti-aliased output: the records of a run through the low-pass filter and
resampled to the output rate, the way ``run`` does it and the way it did before.

Usage::

    python benchmarks/bench_decimation.py [--presets mercury_1a spur_pair] [--repeat 7]

Per preset: records of the shapes its run produces (meshes x 3 and bodies x 7 channels per step,
and with ``+friction`` the two friction channels of each mesh), over the preset's run-in,
duration and tail at its step, filled with noise (the cost does not depend on the values).
Times, alternated, best of ``repeat``: scipy.signal.resample_poly one channel at a time over
all records, then the kept samples taken (before); and
:func:`flexgear.results.decimation.decimate_many`, every channel in one compiled pass over the
kept samples only (now). Both give the same bits (checked here too). Figures per simulated
second of output, and their ratio.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.signal import resample_poly

from machine_info import machine
from flexgear.app.run import TAIL_SAMPLES
from flexgear.config import load_config, time_grid
from flexgear.dynamics.model.assembly import build_model
from flexgear.results.decimation import antialias_filter, decimate_many


def scipy_per_channel(records, out_every, keep):
    """The former path: each channel through resample_poly over every record, then ``keep``."""
    out = []
    taps = antialias_filter(out_every)
    for x in records:
        x = x[out_every - 1:]
        cols = np.reshape(x, (len(x), -1))
        y = np.stack([resample_poly(cols[:, c], 1, out_every, window=taps)[: (len(x) - 1) // out_every + 1]
                      for c in range(cols.shape[1])], axis=1)
        out.append(y[keep].reshape((-1,) + x.shape[1:]))
    return out


def bench(preset: str, friction: bool, repeat: int):
    cfg = load_config(preset)
    sim = cfg.simulation
    model = build_model(cfg)
    h, oe = time_grid(sim)
    rate = 1.0 / (oe * h)
    n_runin, n_keep = int(round(sim["run_in"] * rate)), int(round(sim["duration"] * rate))
    steps = (n_runin + n_keep + TAIL_SAMPLES) * oe
    nm, nb = len(model.meshes), len(model.bodies)
    rng = np.random.default_rng(0)
    records = [rng.standard_normal((steps, nm, 3)), rng.standard_normal((steps, nb, 7))]
    if friction:
        records += [rng.standard_normal((steps, nm)), rng.standard_normal((steps, nm))]
    keep = slice(max(n_runin - 1, 0), max(n_runin - 1, 0) + n_keep)
    old, new = scipy_per_channel(records, oe, keep), decimate_many(records, oe, True, keep)  # compiled first
    assert all(np.array_equal(a, b) for a, b in zip(old, new)), "the compiled pass differs from resample_poly"
    best = {"before": np.inf, "now": np.inf}
    for _ in range(repeat):
        for name, f in (("before", lambda: scipy_per_channel(records, oe, keep)),
                        ("now", lambda: decimate_many(records, oe, True, keep))):
            t0 = time.process_time()
            f()
            best[name] = min(best[name], time.process_time() - t0)
    channels = sum(int(np.prod(r.shape[1:])) for r in records)
    return channels, steps, sim["duration"], best


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", nargs="+", default=["mercury_1a", "mercury_1a+friction", "spur_pair"])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    print(f"machine: {machine()}")
    print(f"{'preset':22s} {'channels':>8s} {'steps':>7s} {'before ms/s':>12s} {'now ms/s':>9s} {'ratio':>6s}")
    for p in args.presets:
        name, _, extra = p.partition("+")
        ch, steps, dur, best = bench(name, extra == "friction", args.repeat)
        b, n = 1e3 * best["before"] / dur, 1e3 * best["now"] / dur
        print(f"{p:22s} {ch:8d} {steps:7d} {b:12.1f} {n:9.1f} {b / n:6.2f}")


if __name__ == "__main__":
    main()
