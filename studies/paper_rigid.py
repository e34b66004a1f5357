"""Reproduce the paper's rigid-body results (Sec. 2 spur pair, Secs. 3-4 MERCURY 1-A).

Runs both presets unchanged (1 s after the run-in), writes the results, the paper-style figures
(Figs. 3, 4, 7-12) and ``report.md``: a table of expected versus simulated frequencies and
forces, the sun-planet to ring-planet force ratio and its explanation.

Usage::

    python studies/paper_rigid.py -o out/paper_rigid [--duration 1.0] [--overwrite]

Expected values come from kinematics and statics (docs/paper_parameters.md), not from flexgear's output.
"""
from __future__ import annotations

import argparse
import math
import sys
import warnings
from pathlib import Path

import numpy as np

from flexgear.app.console import markdown_table, progress_bar
from flexgear.config import load_config
from flexgear.errors import ResultExistsError
from flexgear.results.plots import paper_figures
from flexgear.results.store import save
from flexgear.app.run import run
from flexgear.results.signals import amplitude_spectrum, find_peaks, line_amplitude


def simulate(preset: str, out: Path, duration: float, overwrite: bool):
    cfg = load_config(preset)
    cfg.simulation["duration"] = duration
    bar, update = progress_bar(cfg.simulation["run_in"] + duration)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            res = run(cfg, progress=update)
        finally:
            bar.close()
    d = out / preset
    d.mkdir(parents=True, exist_ok=True)
    save(res, d / "results.h5", overwrite=overwrite)
    paper_figures(res, d, overwrite=overwrite)
    return cfg, res


def spur_rows(cfg, res):
    m = res.meshes["pinion-wheel"]
    fy = m.force_global[:, 1]
    f, A = amplitude_spectrum(fy, res.fs, window="hann")
    df = f[1] - f[0]
    peaks = sorted(p.freq for p in find_peaks(f, A, 4, fmin=100.0, min_separation_hz=50.0))
    rb = cfg.gears["wheel"].rb
    F0 = cfg.load["torque"] / rb
    rows = []
    for k, fp in enumerate(peaks, start=1):
        rows.append([f"spur: peak {k} of the vertical meshing force (Hz)", f"{240.0 * k:g}", f"{fp:.1f}",
                     "yes" if abs(fp - 240 * k) <= df else "NO"])
    Fm = m.normal_force.mean()
    rows.append(["spur: mean normal tooth force (N) = T / r_b", f"{F0:.1f}", f"{Fm:.1f}",
                 "yes" if abs(Fm / F0 - 1) < 0.02 else "NO"])
    f_w = -res.bodies["wheel"].angular_velocity.mean() / (2 * math.pi)
    rows.append(["spur: wheel speed (Hz) = 10 x 24/21", f"{10 * 24 / 21:.4f}", f"{f_w:.4f}",
                 "yes" if abs(f_w / (10 * 24 / 21) - 1) < 1e-4 else "NO"])
    return rows


def planetary_rows(cfg, res):
    rows = []
    fc = res.bodies["carrier"].angular_velocity.mean() / (2 * math.pi)
    rows.append(["planetary: carrier frequency f_a (Hz), Eq. (7)", "8", f"{fc:.4f}",
                 "yes" if abs(fc / 8 - 1) < 0.005 else "NO"])
    rad = [np.hypot(*res.bodies[f"planet{k}"].position.T).mean() * 1e3 for k in (1, 2, 3)]
    rows.append(["planetary: planet centre circle radius (mm)", "45", f"{np.mean(rad):.4f}",
                 "yes" if max(abs(r - 45) for r in rad) < 1e-3 else "NO"])
    zs, zr = 24, 66
    Ts = 60.0 / (1 + zr / zs)
    F0 = Ts / (3 * cfg.gears["sun"].rb)
    rows.append(["planetary: sun torque (N m) = 60/(1 + z_r/z_s)", f"{Ts:.3f}",
                 f"{res.bodies['sun'].torque.mean():.3f}", "yes" if abs(res.bodies['sun'].torque.mean() / Ts - 1) < 0.02 else "NO"])
    means = {k: m.normal_force.mean() for k, m in res.meshes.items()}
    for k, v in means.items():
        rows.append([f"planetary: mean normal force {k} (N)", f"{F0:.1f}", f"{v:.2f}",
                     "yes" if abs(v / F0 - 1) < 0.03 else "NO"])
    for kind in ("sun-planet{}", "planet{}-ring"):
        vals = [means[kind.format(i)] for i in (1, 2, 3)]
        spread = max(vals) / min(vals) - 1
        rows.append([f"planetary: load sharing {kind.format('k')} (max/min - 1)", "< 1 %", f"{spread*100:.3g} %",
                     "yes" if spread < 0.01 else "NO"])
    fy = res.meshes["planet1-ring"].force_global[:, 1]
    f, A = amplitude_spectrum(fy, res.fs, window="hann")
    df = f[1] - f[0]
    top = find_peaks(f, A, 1, fmin=1.0)[0]
    rows.append(["planetary: largest line of planet1-ring vertical force (Hz)", "8", f"{top.freq:.1f}",
                 "yes" if abs(top.freq - 8) <= df else "NO"])
    for k in (1, 2, 3):
        fm = 528.0 * k
        lo, hi, mid = (line_amplitude(f, A, x, tol_hz=df) for x in (fm - 8, fm + 8, fm))
        rows.append([f"planetary: {k} f_m -+ f_a sidebands / {k} f_m line (N)", f"{fm-8:g}, {fm+8:g} / {fm:g}",
                     f"{lo:.2f}, {hi:.2f} / {mid:.3f}", "-"])
        gap = 20 * math.log10(min(lo, hi) / max(mid, 1e-300))
        rows.append([f"planetary: {k} f_m suppression below its sidebands (dB)", ">= 20" if k < 3 else "-",
                     f"{gap:.1f}", ("yes" if gap >= 20 else "NO") if k < 3 else "-"])
    return rows, means


RATIO_TEXT = """\
The paper concludes that sun-planet forces are three times smaller than ring-planet forces. We
find a ratio of {ratio:.4f} (mean normal forces over the run). Statics requires this: a planet on
an ideal pin carries no torque, so F_sun r_b,p = F_ring r_b,p and its two meshes carry the same
normal force, T_s / (N r_b,s) = 236.5 N, whatever the tooth counts. What differs by about three
is the torque the two meshes exert on the central members: the sun carries
T_s = 60 / (1 + z_r/z_s) = 16 N m and the ring reacts 44 N m, a ratio z_r/z_s = 2.75. The
paper's factor of three most likely compares those torques, or forces that were scaled by
their radii, rather than tooth forces. Its figures show single vertical components of meshes
that turn with the carrier, so the peak values of such signals also depend on the window
shown. We do not tune the model to reproduce the factor.
"""


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", default="out/paper_rigid")
    p.add_argument("--duration", type=float, default=1.0, help="seconds recorded after the run-in")
    p.add_argument("--overwrite", action="store_true")
    a = p.parse_args(argv)
    out = Path(a.output)
    report = out / "report.md"
    if report.exists() and not a.overwrite:
        raise ResultExistsError(f"{report} exists; use --overwrite or another -o")
    out.mkdir(parents=True, exist_ok=True)
    cs, rs = simulate("spur_pair", out, a.duration, a.overwrite)
    cp, rp = simulate("mercury_1a", out, a.duration, a.overwrite)
    rows = spur_rows(cs, rs)
    prow, means = planetary_rows(cp, rp)
    rows += prow
    ratio = np.mean([means[f"sun-planet{k}"] for k in (1, 2, 3)]) / np.mean(
        [means[f"planet{k}-ring"] for k in (1, 2, 3)])
    lines = [f"# Rigid-body baseline: paper versus flexgear ({a.duration:g} s after run-in)", "",
             markdown_table(rows, ["quantity", "expected", "simulated", "within tolerance"]), "",
             "## Sun-planet to ring-planet force ratio", "", RATIO_TEXT.format(ratio=ratio), "",
             "## Solver", ""]
    for name, r in (("spur_pair", rs), ("mercury_1a", rp)):
        at = r.attrs
        sim = at["run_in"] + at["duration"]
        lines.append(f"- {name}: {at['solver_steps']} steps, {at['newton_iterations']} Newton iterations, "
                     f"{at['rejected_steps']} rejected, {at['wall_seconds']:.1f} s wall for {sim:g} s simulated "
                     f"({at['wall_seconds']/sim:.2f} s per simulated second), step {at['step']*1e6:g} us")
    report.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0 if all(r[3] in ("yes", "-") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
