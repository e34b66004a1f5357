"""Step convergence of the flexible presets in the frequency domain: the mesh-force spectrum as
the step is refined, with the flexible bodies' added stiffness.

The flexible models' mesh resonance is stiff (spur pair: 9.3 kHz pinion held, 14.9 kHz with the
shafts; flexible MERCURY 1-A: an 8.9 kHz rotational mode) and HHT-alpha renders a mode of angular
frequency omega at a lower frequency (period error about (omega h)^2 / 12;
:func:`flexgear.dynamics.modal.analysis.integrated_frequency`), so the dynamic amplification of the
mesh-harmonic lines a few kHz below it depends on the step. For each preset (as it is, shafts
included), each damping (the preset's paper IMPACT C, ``paper``, or a 5 % mesh damping ratio,
``ratio``) and each step, the run goes from rest over the preset's run-in plus ``cycles`` mesh
periods; on the integration grid the last ``cycles`` mesh periods of the mesh normal force give
the mean, the RMS about the mean and the mesh-harmonic lines up to 5 kHz
(:func:`flexgear.dynamics.flexible.full_order.window_metrics`). The finest step is the reference; the
ratio of successive differences (halving the step) gives the observed order.

Prints the tables and writes ``step_spectrum.json`` to ``--out``.

Usage::

    python studies/step_spectrum.py --out out/step [--presets spur_pair_flexible mercury_1a_flexible]
        [--level 1] [--steps 25e-6 12.5e-6 10e-6 6.25e-6 3.125e-6 1.5625e-6] [--dampings paper ratio]
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.flexible.full_order import window_metrics
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.app.console import run_command

F_MAX = 5e3  # Hz: the band the issue asks to be converged
FLOOR = 0.1  # a line's error is relative to the line, or to this fraction of the band's largest line if larger


def preset_config(name: str, damping: str = "paper", level: int | None = None, step: float | None = None):
    """The preset ``name`` with the paper's IMPACT C (``damping = "paper"``) or a 5 % mesh
    damping ratio instead (``"ratio"``), at FE mesh ``level`` and largest step ``step`` [s]
    (None: the preset's)."""
    if damping not in ("paper", "ratio"):
        raise ValueError(f"damping = {damping!r}: 'paper' or 'ratio'")
    cfg = load_config(name)
    if damping == "ratio":
        cfg.use_damping_ratio(0.05)
    if level is not None:
        cfg.flexible["level"] = level
    if step is not None:
        cfg.simulation["step"] = step
    return cfg


def window_cycles(f_mesh: float, steps, at_least: int = 20) -> int:
    """The smallest number of mesh periods >= ``at_least`` that is a whole number of every step."""
    for c in range(at_least, 100 * at_least):
        if all(abs(c / (f_mesh * h) - round(c / (f_mesh * h))) < 1e-6 * c / (f_mesh * h) for h in steps):
            return c
    raise ValueError(f"no whole number of mesh periods of {f_mesh} Hz fits the steps {steps}")


def run(cfg, h: float, cycles: int, f_mesh: float, meshes=(0,), tol: float = 1e-12) -> dict:
    """Simulate from rest over the run-in plus ``cycles`` mesh periods with step h [s]; the
    window metrics of the mesh normal force of each mesh index in ``meshes``.

    ``tol`` [m] is the Newton tolerance on the position change (the solver's default 1e-10 m):
    the recorded force is that of the last Newton evaluation, up to the mesh stiffness times
    the tolerance away from the accepted state (4e8 N/m x 1e-10 m = 0.04 N on the spur pair),
    a noise that moves lines of a few N by 1-2 %; 1e-12 m keeps it out of the step's error."""
    model = build_model(cfg)
    t_end = cfg.simulation["run_in"] + cycles / f_mesh
    t0 = time.perf_counter()
    r = simulate(model, t_end, h, 1, alpha=cfg.simulation["hht_alpha"], tol=tol,
                 condensation=cfg.flexible["condensation"] if cfg.flexible else "integrated")
    wall = time.perf_counter() - t0
    out = {"h": h, "wall": wall, "t_end": t_end, "meshes": {}}
    for k in meshes:
        m = window_metrics(r.mesh[:, k, 0], h, f_mesh, cycles, f_max=F_MAX)
        out["meshes"][model.meshes[k].name] = {"mean": m["mean"], "rms_ac": m["rms_ac"],
                                               "lines": m["lines"].tolist(), "line_hz": m["line_hz"].tolist()}
    return out


def line_error(L, ref):
    """|L - ref| relative to each line of ``ref``, or to FLOOR x its largest line if larger (along
    the last axis: rows may be meshes)."""
    L, ref = np.asarray(L, float), np.asarray(ref, float)
    return np.abs(L - ref) / np.maximum(ref, FLOOR * ref.max(axis=-1, keepdims=True))


def errors(runs: list[dict], mesh: str) -> list[dict]:
    """Differences of each run to the last (finest) one: mean and RMS about the mean (relative),
    every line relative to itself (``lines``, ``raw``: a line near zero, e.g. a cancellation,
    makes this meaningless) and relative to max(line, FLOOR x the band's largest line)
    (``max``, at ``argmax_hz``: the measure of ``tests/test_step_spectrum.py``), and the largest
    line difference in N (``abs``)."""
    ref = runs[-1]["meshes"][mesh]
    L = np.array(ref["lines"])
    out = []
    for r in runs[:-1]:
        m = r["meshes"][mesh]
        d = np.array(m["lines"]) - L
        floored = line_error(m["lines"], L)
        out.append({"h": r["h"], "mean": m["mean"] / ref["mean"] - 1.0, "rms_ac": m["rms_ac"] / ref["rms_ac"] - 1.0,
                    "lines": (d / L).tolist(), "raw": float(np.abs(d / L).max()), "max": float(floored.max()),
                    "argmax_hz": float(np.array(ref["line_hz"])[np.argmax(floored)]), "abs": float(np.abs(d).max())})
    return out


def orders(runs: list[dict], mesh: str) -> list[tuple]:
    """Observed order from the step pairs (h, h/2) and (h/2, h/4) among the runs: log2 of the
    ratio of the largest line changes |L(h) - L(h/2)| / |L(h/2) - L(h/4)| (in N)."""
    by_h = {round(r["h"] * 1e9): np.array(r["meshes"][mesh]["lines"]) for r in runs}
    out = []
    for h in sorted(by_h, reverse=True):
        if h % 4 == 0 and h // 2 in by_h and h // 4 in by_h:
            d1 = np.abs(by_h[h] - by_h[h // 2]).max()
            d2 = np.abs(by_h[h // 2] - by_h[h // 4]).max()
            out.append((h * 1e-9, float(d1), float(d2), math.log2(d1 / d2)))
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("-o", "--out", "--output", dest="out", required=True, help="output directory")
    p.add_argument("--presets", nargs="+", default=["spur_pair_flexible", "mercury_1a_flexible"],
                   help="flexible presets to run (default both)")
    p.add_argument("--dampings", nargs="+", default=["paper", "ratio"],
                   help="mesh damping: 'paper' (the ADAMS C) and/or 'ratio' (a 5 %% damping ratio; default both)")
    p.add_argument("--level", type=int, default=1, help="FE mesh level of the flexible gears (default 1)")
    p.add_argument("--steps", nargs="+", type=float, default=[25e-6, 12.5e-6, 10e-6, 6.25e-6, 3.125e-6, 1.5625e-6],
                   help="integration steps [s], coarse to fine")
    p.add_argument("--no-shafts", action="store_true", help="leave out the presets' shafts")
    p.add_argument("--tol", type=float, default=1e-12, help="Newton tolerance [m] (solver default 1e-10)")
    a = p.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    steps = sorted(a.steps, reverse=True)
    result = {}
    for name in a.presets:
        for damping in a.dampings:
            cfg = preset_config(name, damping, a.level)
            if a.no_shafts:
                cfg.shafts = None
            model = build_model(cfg)
            fm = cfg.mesh_frequency()
            cycles = window_cycles(fm, steps)
            meshes = [0] if len(model.meshes) == 1 else [0, len(model.meshes) // 2]
            runs = []
            for h in steps:
                cfg.simulation["step"] = h
                runs.append(run(cfg, h, cycles, fm, meshes, a.tol))
                print(f"{name} {damping} h={h * 1e6:g} us: {runs[-1]['wall']:.1f} s", flush=True)
            key = f"{name}/{damping}/level{a.level}"
            result[key] = {"runs": runs, "cycles": cycles, "f_mesh": fm}
            for mesh in runs[-1]["meshes"]:
                print(f"\n## {key}, mesh {mesh}: {cycles} mesh periods of {fm:g} Hz, reference "
                      f"h = {steps[-1] * 1e6:g} us")
                ref = runs[-1]["meshes"][mesh]
                print("lines [N]: " + " ".join(f"{x:.1f}" for x in ref["lines"]))
                print(f"line errors: 'max' relative to max(line, {FLOOR:g} x largest line), 'raw' to the line itself")
                print(f"{'h [us]':>7} {'mean %':>9} {'rms_ac %':>9} {'max %':>7} {'at Hz':>6} {'raw %':>8} {'max N':>7}  "
                      "each line % of itself")
                for e in errors(runs, mesh):
                    print(f"{e['h'] * 1e6:7.3f} {100 * e['mean']:+9.4f} {100 * e['rms_ac']:+9.3f} {100 * e['max']:7.2f} "
                          f"{e['argmax_hz']:6.0f} {100 * e['raw']:8.2f} {e['abs']:7.3f}  "
                          + " ".join(f"{100 * x:+.2f}" for x in e["lines"]))
                for h, d1, d2, o in orders(runs, mesh):
                    print(f"order from {h * 1e6:g}/{h * 5e5:g}/{h * 2.5e5:g} us: max line change {d1:.3g} N -> "
                          f"{d2:.3g} N, order {o:.2f}")
            (out / "step_spectrum.json").write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
