"""Load sweep: loaded transmission error and contact ratio of the spur pair and MERCURY 1-A.

Runs batches (``flexgear.app.batch``) over the load torque at the presets' speeds and reads,
for every mesh, what the results give:

- transmission error under load: the approach of the gears along the line of action, i.e. the
  deepest tooth-pair penetration at each instant (metrics ``te_mean``, ``te_p2p``), against the
  quasi-static expectation of the IMPACT law ``F = K delta^e``: ``(F / K)^(1/e)`` with one pair
  in contact, ``(F / 2K)^(1/e)`` with two, and their time average over a mesh cycle with the
  geometric contact ratio eps (a fraction eps - 1 of the cycle with two pairs);
- contact ratio under load: the mean number of tooth pairs carrying force
  (``contact_pairs_mean``), against the geometric (ISO 21771) contact ratio.

Figures in the paper's style: ``load_te.png``, ``load_contact_ratio.png``; ``report.md``.

Usage::

    python studies/load_sweep.py -o out/load_sweep [--quick] [--workers N] [--overwrite]

``--quick``: three loads, 0.1 s records.
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

from flexgear.app.batch import run_batch
from flexgear.app.console import markdown_table
from flexgear.app.sweep import loads_sweep
from flexgear.files import check_targets
from flexgear.style import DOUBLE_WIDTH, figure, paper_style, save_figure
from flexgear.app.console import run_command

# set -> (preset, meshes shown, torques in N m (full), torques (quick))
SETS = {
    "spur": ("spur_pair", ["pinion-wheel"], [10.0, 20.0, 40.0, 60.0, 80.0, 100.0, 150.0, 200.0, 250.0, 300.0, 400.0],
             [20.0, 100.0, 300.0]),
    "mercury": ("mercury_1a", ["sun-planet1", "planet1-ring"],
                [5.0, 10.0, 20.0, 30.0, 45.0, 60.0, 80.0, 100.0, 120.0, 160.0, 200.0], [10.0, 60.0, 160.0]),
}
TITLES = {"spur": "spur pair 24/21", "mercury": "MERCURY 1-A"}


def sweep_text(preset: str, torques, duration: float, run_in: float) -> str:
    return (f'title = "{preset} load sweep"\nbase = "{preset}"\n[set]\n"simulation.duration" = {duration}\n'
            f'"simulation.run_in" = {run_in}\n[grid]\n"load.torque" = [{", ".join(repr(float(t)) for t in torques)}]\n')


def quasi_static(cfg, mesh: str, force):
    """(one pair, two pairs, cycle mean) approach [m] for the mean normal force ``force`` [N],
    and the geometric contact ratio of the mesh's pair."""
    pair = cfg.pairs[re.sub(r"\d+", "", mesh)]
    law = cfg.contact_law(pair)
    force = np.asarray(force, dtype=float)
    one = (force / law.K) ** (1.0 / law.e)
    two = (force / (2.0 * law.K)) ** (1.0 / law.e)
    eps = pair.contact_ratio
    share_two = min(max(eps - 1.0, 0.0), 1.0)
    return one, two, (1.0 - share_two) * one + share_two * two, eps


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", "--out", dest="output", default="out/load_sweep")
    ap.add_argument("--quick", action="store_true", help="3 loads, 0.1 s records")
    ap.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    ap.add_argument("--sets", nargs="+", choices=list(SETS), default=list(SETS))
    ap.add_argument("--overwrite", action="store_true", help="replace the figures and report")
    args = ap.parse_args(argv)
    out = Path(args.output)
    outputs = [out / "load_te.png", out / "load_contact_ratio.png", out / "report.md"]
    check_targets(outputs, args.overwrite)
    duration, run_in = (0.1, 0.1) if args.quick else (0.5, 0.2)
    panels = []  # (title, torque, rows, mesh, quasi-static)
    report = [f"# Load sweep ({'quick: ' if args.quick else ''}{duration} s records after a {run_in} s run-in)", "",
              "Transmission error under load = approach of the gears along the line of action (deepest tooth-pair "
              "penetration), um. Quasi-static: IMPACT law F = K delta^e with one pair, two pairs, and their mean over "
              "a mesh cycle with the geometric contact ratio.", ""]
    for name in args.sets:
        preset, meshes, torques, quick = SETS[name]
        sweep = loads_sweep(sweep_text(preset, quick if args.quick else torques, duration, run_in),
                            source=f"{name} load sweep")
        r = run_batch(sweep, out / name, workers=args.workers)
        if r.failed or r.pending:
            print(f"{name}: {r.failed} case(s) failed; see {r.summary}", file=sys.stderr)
        rows = [x for x in r.table.records() if x["status"] == "done"]
        cfg = sweep.cases[0].config
        T = np.array([x["load_torque"] for x in rows])
        for mesh in meshes:
            col = mesh.replace("-", "_")
            F = np.array([x[f"mean_force_{col}"] for x in rows])
            qs = quasi_static(cfg, mesh, F)
            panels.append((f"{TITLES[name]}, {mesh}", T, rows, col, qs))
            report += [f"## {TITLES[name]}: {mesh} (geometric contact ratio {qs[3]:.3f})", "",
                       markdown_table([[f"{t:g}", f"{f:.1f}", f"{1e6 * x[f'te_mean_{col}']:.3f}", f"{1e6 * q:.3f}",
                                        f"{1e6 * x[f'te_p2p_{col}']:.3f}", f"{x[f'contact_pairs_mean_{col}']:.3f}",
                                        f"{x[f'contact_pairs_min_{col}']:.0f}"]
                                       for t, f, x, q in zip(T, F, rows, qs[2])],
                                      ["torque N m", "mean force N", "TE mean um", "quasi-static um", "TE p-p um",
                                       "pairs in contact (mean)", "min"]), ""]
    with paper_style():
        fig = figure(DOUBLE_WIDTH, 2.5)
        for ax, (title, T, rows, col, (one, two, mean, eps)) in zip(np.atleast_1d(fig.subplots(1, len(panels))),
                                                                   panels):
            ax.plot(T, [1e6 * x[f"te_mean_{col}"] for x in rows], "o-", ms=2.5, label="simulated, mean")
            ax.plot(T, [1e6 * x[f"te_p2p_{col}"] for x in rows], "s--", ms=2.5, label="simulated, peak-to-peak")
            ax.plot(T, 1e6 * mean, "k-", lw=0.8, label=r"quasi-static, geometric $\varepsilon_\alpha$")
            ax.fill_between(T, 1e6 * two, 1e6 * one, color="0.85", lw=0, label="two pairs .. one pair")
            ax.text(0.97, 0.04, rf"$\varepsilon_\alpha$ = {eps:.3f}", transform=ax.transAxes, ha="right")
            ax.set_xlabel("load torque (N m)")
            ax.set_ylabel(r"approach along the line of action ($\mu$m)")
            ax.set_title(title)
        np.atleast_1d(fig.axes)[0].legend()
        save_figure(fig, outputs[0], overwrite=args.overwrite)
        fig = figure(DOUBLE_WIDTH, 2.3)
        for ax, (title, T, rows, col, (_, _, _, eps)) in zip(np.atleast_1d(fig.subplots(1, len(panels))), panels):
            ax.plot(T, [x[f"contact_pairs_mean_{col}"] for x in rows], "o-", ms=2.5, label="simulated, mean")
            ax.axhline(eps, color="k", lw=0.8, ls="--", label="geometric (ISO 21771)")
            ax.set_xlabel("load torque (N m)")
            ax.set_ylabel("tooth pairs in contact")
            ax.set_title(title)
        np.atleast_1d(fig.axes)[0].legend()
        save_figure(fig, outputs[1], overwrite=args.overwrite)
    text = "\n".join(report)
    (out / "report.md").write_text(text)
    print(text)
    for p in outputs:
        print(f"wrote {p}")


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
