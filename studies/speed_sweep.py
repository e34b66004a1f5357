"""Speed sweep of the spur pair and of MERCURY 1-A: meshing forces and mesh harmonics against speed.

Runs two batches (``flexgear.app.batch``) over the input speed with the presets otherwise
unchanged, then draws, in the paper's style:

- ``speed_forces.png``: RMS and peak normal tooth force against the input speed (both sets);
- ``speed_harmonics.png``: amplitudes of f_m, 2 f_m, 3 f_m against speed;
- ``order_map_<set>.png``: the normal force's spectrum against speed and mesh order f / f_m
  (a waterfall seen from above: mesh harmonics are vertical lines, a resonance of fixed frequency
  a curve crossing them);

and ``report.md`` with the summary tables. The batches are resumable: running the study again
continues them.

Usage::

    python studies/speed_sweep.py -o out/speed_sweep [--quick] [--workers N] [--overwrite]

``--quick``: four speeds, 0.1 s records (a minute on 2 cores), for a check of the pipeline.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from flexgear.app.batch import run_batch
from flexgear.app.console import markdown_table
from flexgear.app.sweep import loads_sweep
from flexgear.files import check_targets
from flexgear.results.signals import amplitude_spectrum, db
from flexgear.results.store import load
from flexgear.style import COLUMN_WIDTH, DOUBLE_WIDTH, figure, paper_style, save_figure
from flexgear.app.console import run_command

# set -> (preset, driven body, mesh shown, speeds in Hz (full), speeds (quick))
SETS = {
    "spur": ("spur_pair", "pinion", "pinion-wheel", np.round(np.linspace(2.5, 60.0, 24), 3),
             [5.0, 15.0, 30.0, 50.0]),
    "mercury": ("mercury_1a", "sun", "sun-planet1", np.round(np.linspace(5.0, 60.0, 23), 3),
                [10.0, 20.0, 30.0, 50.0]),
}
TITLES = {"spur": "spur pair 24/21", "mercury": "MERCURY 1-A"}


def sweep_text(preset: str, speeds, duration: float, run_in: float) -> str:
    return (f'title = "{preset} speed sweep"\nbase = "{preset}"\n[set]\n"simulation.duration" = {duration}\n'
            f'"simulation.run_in" = {run_in}\n[grid]\n"drive.speed_hz" = [{", ".join(repr(float(s)) for s in speeds)}]\n')


def column(mesh: str) -> str:
    return mesh.replace("-", "_")


def fig_forces(tables):
    """Top: peak, RMS and mean normal force; bottom: the fluctuation (RMS about the mean, and
    half the peak-to-peak)."""
    fig = figure(DOUBLE_WIDTH, 4.2)
    axes = np.array(fig.subplots(2, len(tables), squeeze=False))
    for j, (name, (rows, mesh)) in enumerate(tables.items()):
        v = np.array([r["drive_speed_hz"] for r in rows])
        col = column(mesh)
        top, bottom = axes[0, j], axes[1, j]
        for metric, style, label in (("peak_force", "--s", "peak"), ("rms_force", "-o", "RMS"),
                                     ("mean_force", ":", "mean")):
            top.plot(v, [r[f"{metric}_{col}"] for r in rows], style, ms=2.5, label=label)
        bottom.plot(v, [r[f"dyn_rms_force_{col}"] for r in rows], "-o", ms=2.5, label="RMS of the fluctuation")
        bottom.plot(v, [0.5 * r[f"p2p_force_{col}"] for r in rows], "--s", ms=2.5, label="half peak-to-peak")
        top.set_title(TITLES[name])
        top.set_ylabel(f"normal force {mesh} (N)")
        bottom.set_ylabel("fluctuation (N)")
        bottom.set_xlabel("input speed (Hz)")
        top.legend()
        bottom.legend()
    return fig


def fig_harmonics(tables):
    fig = figure(DOUBLE_WIDTH, 2.4)
    axes = fig.subplots(1, len(tables))
    for ax, (name, (rows, mesh)) in zip(np.atleast_1d(axes), tables.items()):
        v = np.array([r["drive_speed_hz"] for r in rows])
        for k, style in zip((1, 2, 3), ("-o", "--s", ":^")):
            ax.semilogy(v, [r[f"amp_fm{k}_{column(mesh)}"] for r in rows], style, ms=2.5,
                        label=f"{k if k > 1 else ''}$f_m$")
        ax.set_xlabel("input speed (Hz)")
        ax.set_ylabel(f"amplitude in {mesh} (N)")
        ax.set_title(TITLES[name])
        ax.legend()
    return fig


def fig_order_map(directory: Path, rows, mesh: str, title: str, max_order: float = 4.0):
    orders = np.linspace(0.0, max_order, 801)
    speeds, levels = [], []
    for r in rows:
        res = load(directory / r["file"])
        f, A = amplitude_spectrum(res.meshes[mesh].normal_force, res.fs, window="hann")
        fm = res.attrs["mesh_frequency"]
        levels.append(db(np.interp(orders * fm, f, A, right=np.nan), ref=1.0))
        speeds.append(r["drive_speed_hz"])
    levels = np.array(levels)
    fig = figure(COLUMN_WIDTH, 2.8)
    ax = fig.add_subplot()
    finite = levels[np.isfinite(levels)]
    top = float(np.max(finite)) if finite.size else 0.0
    pc = ax.pcolormesh(orders, np.array(speeds), levels, shading="nearest", cmap="viridis", vmin=top - 60.0, vmax=top,
                       rasterized=True)
    for k in range(1, int(max_order) + 1):
        ax.axvline(k, color="w", lw=0.4, ls=":")
    ax.set_xlabel("mesh order $f/f_m$")
    ax.set_ylabel("input speed (Hz)")
    ax.set_title(f"{title}: normal force {mesh}")
    ax.grid(False)
    fig.colorbar(pc, ax=ax, label="amplitude (dB re 1 N)")
    return fig


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", "--out", dest="output", default="out/speed_sweep")
    ap.add_argument("--quick", action="store_true", help="4 speeds, 0.1 s records")
    ap.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    ap.add_argument("--sets", nargs="+", choices=list(SETS), default=list(SETS))
    ap.add_argument("--overwrite", action="store_true", help="replace the figures and report")
    args = ap.parse_args(argv)
    out = Path(args.output)
    figures = ["speed_forces.png", "speed_harmonics.png", "report.md"] + [f"order_map_{s}.png" for s in args.sets]
    check_targets([out / f for f in figures], args.overwrite)
    duration, run_in = (0.1, 0.1) if args.quick else (1.0, 0.2)
    tables = {}
    report = [f"# Speed sweep ({'quick: ' if args.quick else ''}{duration} s records after a {run_in} s run-in)", ""]
    for name in args.sets:
        preset, body, mesh, speeds, quick = SETS[name]
        sweep = loads_sweep(sweep_text(preset, quick if args.quick else speeds, duration, run_in),
                            source=f"{name} speed sweep")
        batch_dir = out / name
        r = run_batch(sweep, batch_dir, workers=args.workers)
        if r.failed or r.pending:
            print(f"{name}: {r.failed} case(s) failed; see {r.summary}", file=sys.stderr)
        rows = [x for x in r.table.records() if x["status"] == "done"]
        tables[name] = (rows, mesh)
        report += [f"## {TITLES[name]} ({preset}, mesh {mesh})", "",
                   markdown_table([[f"{x['drive_speed_hz']:g}", f"{x['mesh_frequency']:.1f}",
                                    f"{x['mean_force_' + column(mesh)]:.1f}", f"{x['rms_force_' + column(mesh)]:.1f}",
                                    f"{x['peak_force_' + column(mesh)]:.1f}",
                                    f"{x['dynamic_factor_' + column(mesh)]:.3f}",
                                    *(f"{x[f'amp_fm{k}_' + column(mesh)]:.2f}" for k in (1, 2, 3))] for x in rows],
                                  ["speed Hz", "f_m Hz", "mean N", "RMS N", "peak N", "K_v", "A(f_m) N", "A(2f_m) N",
                                   "A(3f_m) N"]), "",
                   f"Batch directory: `{batch_dir}` (summary.csv, summary.nc, one result file per speed).", ""]
        with paper_style():
            save_figure(fig_order_map(batch_dir, rows, mesh, TITLES[name]), out / f"order_map_{name}.png",
                        overwrite=args.overwrite)
    with paper_style():
        save_figure(fig_forces(tables), out / "speed_forces.png", overwrite=args.overwrite)
        save_figure(fig_harmonics(tables), out / "speed_harmonics.png", overwrite=args.overwrite)
    text = "\n".join(report)
    (out / "report.md").write_text(text)
    print(text)
    for f in figures:
        print(f"wrote {out / f}")


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
