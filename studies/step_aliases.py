"""Step aliases of the rigid MERCURY 1-A planet-ring force: which setting moves them, and how far.

The integrator evaluates the contact forces at its steps only, so content of the mesh force at a
mesh harmonic n f_m near a multiple j/h of the step rate appears |n f_m - j/h| from a mesh line
(docs/guide/run.md, "Step aliases"). For each variant of the preset (the step, the input speed, the contact
tables, the full-search interval, HHT alpha, the synchronous grid) the run goes from rest over
the run-in plus ``--window`` seconds; on the raw step-rate records of the planet1-ring normal
force (Blackman-Harris window) every mesh harmonic up to 4 kHz gives the largest component
between it and the next, off the mesh line and its carrier sidebands k f_m +- {0, 1, 2} f_c,
relative to the neighbouring mesh line (the largest of k f_m and k f_m +- f_c). The table lists
the predicted offset (1/h folded by f_m), the offset of the largest such component over all
harmonics, its amplitude and the largest ratio. A variant whose line moves as predicted (the
step, the speed) and the ones that leave it (tables, search, alpha) locate the cause.

Writes ``step_aliases.json`` to ``--out`` and prints the table.

Usage::

    python studies/step_aliases.py --out out/aliases [--window 0.5] [--quick]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.signal import get_window

from flexgear.config import check_config, load_config, time_grid
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.results.signals import amplitude_spectrum
from flexgear.app.console import run_command

BAND = 4000.0  # Hz: the default output's trustworthy band
GUARD = 3.5  # carrier periods: the mesh line, its sidebands +-f_c, +-2 f_c and their window main lobes

# (name, [simulation] / [contact] / [drive] changes, run kwargs)
VARIANTS = [
    ("plain 25 us", {"simulation": {"synchronous": False}}, {}),
    ("plain 20 us", {"simulation": {"synchronous": False, "step": 2e-5}}, {}),
    ("plain 12.5 us", {"simulation": {"synchronous": False, "step": 1.25e-5}}, {}),
    ("plain 25 us, 31 Hz input", {"simulation": {"synchronous": False}, "drive": {"speed_hz": 31.0}}, {}),
    ("plain 25 us, tables m/400", {"simulation": {"synchronous": False},
                                   "contact": {"outline_spacing": 5e-6, "sdf_resolution": 5e-6}}, {}),
    ("plain 25 us, full search every step", {"simulation": {"synchronous": False}}, {"full_every": 1}),
    ("plain 25 us, alpha = 0", {"simulation": {"synchronous": False, "hht_alpha": 0.0}}, {}),
    ("plain 25 us, alpha = -0.3", {"simulation": {"synchronous": False, "hht_alpha": -0.3}}, {}),
    ("synchronous", {"simulation": {"synchronous": True}}, {}),
    ("plain 5 us", {"simulation": {"synchronous": False, "step": 5e-6}}, {}),
]
QUICK = ("plain 25 us", "plain 20 us", "synchronous")


def fold(rate: float, f_mesh: float) -> float:
    """Distance [Hz] from the nearest mesh harmonic at which a harmonic next to ``rate`` [Hz]
    (a multiple of the step rate) lands."""
    r = rate % f_mesh
    return min(r, f_mesh - r)


def off_set_lines(f, A, f_mesh: float, f_c: float, band: float = BAND, guard: float = GUARD):
    """Per mesh harmonic k f_m up to ``band``: (k, neighbouring mesh line [N], frequency [Hz] and
    amplitude [N] of the largest component between k f_m + guard f_c and k f_m + f_m / 2, either
    side). The neighbouring mesh line is the largest of k f_m and k f_m +- f_c (the turning
    carrier and the planets' weight move the planet-ring force's lines there)."""
    df = f[1] - f[0]
    out = []
    for k in range(1, int(band / f_mesh) + 1):
        ref = max(A[np.abs(f - (k * f_mesh + j * f_c)) <= 2 * df].max() for j in (-1, 0, 1))
        d = np.abs(f - k * f_mesh)
        sel = (d > max(guard * f_c, 6 * df)) & (d < f_mesh / 2)
        i = int(np.argmax(np.where(sel, A, 0.0)))
        out.append((k, float(ref), float(f[i]), float(A[i])))
    return out


def variant_config(changes: dict):
    cfg = load_config("mercury_1a")
    for block, kv in changes.items():
        getattr(cfg, block).update(kv)
    return check_config(cfg)


def measure(name: str, changes: dict, kwargs: dict, window: float, mesh: str = "planet1-ring") -> dict:
    """Simulate a variant over the run-in plus ``window`` [s] and measure its off-set lines on
    the raw step-rate records."""
    cfg = variant_config(changes)
    sim = cfg.simulation
    f_mesh = cfg.mesh_frequency()
    f_c = f_mesh / cfg.gears["ring"].z
    h, _ = time_grid(sim, f_mesh)
    model = build_model(cfg)
    t0 = time.perf_counter()
    r = simulate(model, sim["run_in"] + window, h, 1, alpha=sim["hht_alpha"], **kwargs)
    wall = time.perf_counter() - t0
    m = [x.name for x in model.meshes].index(mesh)
    x = r.mesh[int(round(sim["run_in"] / h)):, m, 0]
    f, A = amplitude_spectrum(x, 1.0 / h, window=get_window("blackmanharris", len(x)))
    lines = off_set_lines(f, A, f_mesh, f_c)
    k, ref, fl, a = max(lines, key=lambda v: v[3])
    worst = max(v[3] / v[1] for v in lines)
    return {"name": name, "h": h, "f_mesh": f_mesh, "predicted_hz": fold(1.0 / h, f_mesh),
            "offset_hz": fl - k * f_mesh, "at_harmonic": k, "amplitude_n": a, "worst_ratio": worst, "wall": wall,
            "lines": lines}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("-o", "--out", "--output", dest="out", required=True)
    p.add_argument("--window", type=float, default=0.5, help="seconds analysed after the run-in")
    p.add_argument("--quick", action="store_true", help=f"only {', '.join(QUICK)}")
    a = p.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    print(f"{'variant':40s} {'h [us]':>8s} {'f_m':>7s} {'predicted':>9s} {'largest at':>12s} {'[N]':>8s} {'ratio':>8s}")
    for name, changes, kwargs in VARIANTS:
        if a.quick and name not in QUICK:
            continue
        row = measure(name, changes, kwargs, a.window)
        rows.append(row)
        print(f"{name:40s} {row['h'] * 1e6:8.3f} {row['f_mesh']:7.1f} {row['predicted_hz']:9.1f} "
              f"{row['at_harmonic']:3d} f_m {row['offset_hz']:+6.1f} {row['amplitude_n']:8.4f} "
              f"{20 * np.log10(row['worst_ratio']):6.1f} dB", flush=True)
    (out / "step_aliases.json").write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
