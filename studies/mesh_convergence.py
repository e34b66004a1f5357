"""Mesh convergence of the MERCURY 1-A gear FE models.

For each gear (sun and planet clamped at the bore, ring clamped at its outer rim) and each
refinement level: the first ten natural frequencies and the tooth stiffness at the pitch point
(bulk compliance with the near field separated, see flexgear.stiffness). From the three finest
levels: observed order and Richardson-extrapolated value; the default level must lie within
1 % (frequencies) and 2 % (stiffness) of it.

Writes to --out DIR (refuses to overwrite existing results unless --overwrite):
  mesh_convergence.md    table per gear and level, orders, Richardson values, PASS/FAIL
  mesh_convergence.png   log-log relative error vs element size
  mesh_convergence.json  all numbers

Usage (fine levels take minutes; the ring at level 4 needs ~4 GB):
  python studies/mesh_convergence.py --out studies/out/mesh_convergence
  python studies/mesh_convergence.py --gears sun --levels 0 1 2 3 --out /tmp/conv --overwrite
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from flexgear.config import load_config
from flexgear.fe.meshing import USER_CACHE
from flexgear.stiffness.fe_convergence import gear_convergence
from flexgear.errors import ResultExistsError
from flexgear.style import DOUBLE_WIDTH, figure, save_figure, styled
from flexgear.app.console import run_command

OUTPUTS = ("mesh_convergence.md", "mesh_convergence.png", "mesh_convergence.json")


def _table(res, default_level, ftol, ktol) -> list[str]:
    fr, kr = res.freq_rich, res.stiff_rich
    n = res.freqs.shape[1]
    lines = [f"### {res.name} (clamped: {res.clamp})", "",
             "| level | h_tooth [mm] | dofs | " + " | ".join(f"f{i+1} [Hz]" for i in range(n))
             + " | k_tooth [N/m] | max freq err | stiffness err | time [s] |",
             "|" + "---|" * (n + 7)]
    for i, lv in enumerate(res.levels):
        mark = " (default)" if lv == default_level else ""
        lines.append(f"| {lv}{mark} | {res.h[i]*1e3:.3f} | {res.ndofs[i]} | "
                     + " | ".join(f"{f:.1f}" for f in res.freqs[i])
                     + f" | {res.stiffness[i]:.5e} | {np.max(fr.rel_error[i])*100:.3f} % | "
                     f"{kr.rel_error[i]*100:.3f} % | {res.seconds[i]:.1f} |")
    lines.append("| Richardson | 0 | | " + " | ".join(f"{f:.1f}" for f in fr.extrapolated)
                 + f" | {kr.extrapolated:.5e} | | | |")
    lines.append("| observed order | | | " + " | ".join(f"{p:.2f}" for p in fr.order)
                 + f" | {kr.order:.2f} | | | |")
    lines.append("")
    if default_level in res.levels:
        fe, ke = res.level_errors(default_level)
        ok = res.check(default_level, ftol, ktol)
        lines.append(f"Default level {default_level}: max frequency error {fe*100:.3f} % "
                     f"(limit {ftol*100:g} %), stiffness error {ke*100:.3f} % (limit {ktol*100:g} %): "
                     f"**{'PASS' if ok else 'FAIL'}**")
    lines.append("")
    return lines


@styled
def _plot(results, path):
    """Relative error against the Richardson value vs element size, in the flexgear figure
    style (flexgear.style: serif, thin lines, 300 dpi, atomic write)."""
    fig = figure(DOUBLE_WIDTH, 3.2)
    ax = fig.add_subplot()
    colors = ["k", "#1f5fa8", "#c0392b", "#2e8b57", "#8e44ad"]
    markers = ["o", "s", "^", "D", "v"]
    for k, res in enumerate(results):
        c, mk = colors[k % len(colors)], markers[k % len(markers)]
        h = res.h * 1e3
        for j in range(res.freqs.shape[1]):
            ax.loglog(h, res.freq_rich.rel_error[:, j], "-", color=c, linewidth=0.5, alpha=0.45,
                      label=f"{res.name}: natural frequencies $f_1$..$f_{{{res.freqs.shape[1]}}}$" if j == 0 else None)
        ax.loglog(h, res.stiff_rich.rel_error, "--", marker=mk, markersize=3.5, color=c, linewidth=1.0,
                  label=f"{res.name}: tooth stiffness ($p$ = {res.stiff_rich.order:.2f})")
    ax.set_xlabel("Element size on the teeth $h$ [mm]")
    ax.set_ylabel("Relative error to the Richardson value [-]")
    ax.grid(True, which="both")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title("Mesh convergence of the MERCURY 1-A gear FE models (quadratic triangles, plane stress)",
                 loc="left")
    save_figure(fig, path, overwrite=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--out", "--output", dest="out", default="studies/out/mesh_convergence", help="output directory")
    ap.add_argument("--overwrite", action="store_true", help="replace existing results in --out")
    ap.add_argument("--gears", nargs="+", default=["sun", "planet", "ring"], help="gears of the preset (default: all)")
    ap.add_argument("--levels", nargs="+", type=int, default=[1, 2, 3, 4],
                    help="refinement levels (>= 3; the three finest give order and Richardson value)")
    ap.add_argument("--default-level", type=int, default=2, help="the level checked against the Richardson value "
                    "(default 2, flexgear's)")
    ap.add_argument("--order", type=int, default=2, help="element order, 1 or 2 (default 2)")
    ap.add_argument("--modes", type=int, default=10, help="natural frequencies per gear (default 10)")
    ap.add_argument("--freq-tol", type=float, default=0.01, help="the default level's bar for the frequencies, "
                    "relative to the Richardson value (default 0.01)")
    ap.add_argument("--stiff-tol", type=float, default=0.02, help="the same for the tooth stiffness (default 0.02)")
    ap.add_argument("--preset", default="mercury_1a", help="configuration whose gears are meshed (default mercury_1a)")
    ap.add_argument("--cache-dir", default=None,
                    help="mesh cache directory (default: the per-user cache, $FLEXGEAR_CACHE_DIR/meshes or "
                    "~/.cache/flexgear/meshes)")
    a = ap.parse_args(argv)

    out = Path(a.out)
    existing = [p for p in (out / f for f in OUTPUTS) if p.exists()]
    if existing and not a.overwrite:
        raise ResultExistsError(f"--out {out}: {', '.join(p.name for p in existing)} exist; "
                                "pass --overwrite to replace them")
    out.mkdir(parents=True, exist_ok=True)
    cfg = load_config(a.preset)
    t0 = time.perf_counter()
    results = []
    for name in a.gears:
        if name not in cfg.gears:
            raise SystemExit(f"--gears: unknown gear {name!r}; known: {sorted(cfg.gears)}")
        results.append(gear_convergence(cfg.gears[name], a.levels, order=a.order, n_modes=a.modes,
                                        material=cfg.material, cache_dir=a.cache_dir or USER_CACHE,
                                        log=lambda s: print(s, flush=True)))
    md = ["# Mesh convergence of the gear FE models", "",
          f"Preset `{a.preset}`, element order {a.order}, plane stress, levels {a.levels}; "
          f"relative errors against the Richardson extrapolation of the three finest levels "
          f"(observed order p = ln((f1-f2)/(f2-f3))/ln r with r = h1/h2). Tooth stiffness: "
          f"pitch-point bulk stiffness 1/c_bulk of flexgear.stiffness (patch load, near field "
          f"separated). Total time {time.perf_counter() - t0:.0f} s.", ""]
    ok_all = True
    for res in results:
        md += _table(res, a.default_level, a.freq_tol, a.stiff_tol)
        if a.default_level in res.levels:
            ok_all &= res.check(a.default_level, a.freq_tol, a.stiff_tol)
    (out / OUTPUTS[0]).write_text("\n".join(md))
    _plot(results, out / OUTPUTS[1])
    data = {r.name: {"levels": r.levels.tolist(), "h_tooth": r.h.tolist(), "ndofs": r.ndofs.tolist(),
                     "freqs_hz": r.freqs.tolist(), "tooth_stiffness_n_per_m": r.stiffness.tolist(),
                     "seconds": r.seconds.tolist(), "clamp": r.clamp,
                     "freq_order": r.freq_rich.order.tolist(),
                     "freq_richardson": r.freq_rich.extrapolated.tolist(),
                     "freq_rel_error": r.freq_rich.rel_error.tolist(),
                     "stiffness_order": float(r.stiff_rich.order),
                     "stiffness_richardson": float(r.stiff_rich.extrapolated),
                     "stiffness_rel_error": r.stiff_rich.rel_error.tolist()} for r in results}
    (out / OUTPUTS[2]).write_text(json.dumps(data, indent=1))
    print("\n".join(md))
    print(f"wrote {', '.join(str(out / f) for f in OUTPUTS)}")
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
