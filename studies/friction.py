"""Tooth friction and the lubricant film of the spur pair and MERCURY 1-A (rigid model).

The presets ``spur_pair_friction`` and ``mercury_1a_friction`` (their lubricant, the rigid
IMPACT contact) each run as a batch (``flexgear.app.batch``) over four ``[lubrication]`` blocks:
friction off (a constant coefficient of 0: the frictionless model bit for bit), a constant
coefficient (0.05), Benedict & Kelley (1961) and Xu et al. (2007), all with the preset's
lubricant (so every case records the EHL film). A third batch sweeps the spur pair's mesh
efficiency over the load and the speed (the preset's friction model) and over the constant
coefficient. Writes:

- ``force_<set>.png``: the force of gear a on gear b across the line of action (along the flank
  tangent) against time over a few mesh periods, every variant, the pitch-point crossings of the
  contacts marked (from the recorded contact positions);
- ``spectrum_<set>.png``: amplitude spectra of the normal force, the force across the line of
  action and the bearing reactions (x, y) of the driven gear's and the driving gear's bearings;
- ``efficiency.png``: the mesh efficiency against the output torque at each speed, and against
  the constant coefficient;
- ``film_<set>.png``: the central and minimum film thickness of every recorded contact against its
  position on the line of action, for each variant;
- ``report.md`` (the tables behind the figures) and ``checks.json`` (the numbers the test reads).

Across the line of action: t = n rotated by +90 deg, n the unit normal of the line of action
(the one of the two tangents to both base circles along which the force of gear a on gear b
acts, chosen as the one carrying the larger mean force), from the bodies' recorded centres.
Bearing reactions: R = m dv/dt - (the mesh forces on the gear) [N] of the gear's centre (the
ground or the carrier pin holds it), dv/dt of the recorded centre velocity.

Usage::

    python studies/friction.py -o out/friction [--quick] [--sets spur mercury] [--workers N] [--overwrite]

``--quick``: 0.05 s records after a 0.1 s run-in, the efficiency sweep over two loads and two
speeds, for a check of the pipeline (a few minutes on 2 cores).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import tomllib
from pathlib import Path

import numpy as np

from flexgear.app.batch import run_batch
from flexgear.app.console import markdown_table
from flexgear.app.sweep import loads_sweep
from flexgear.config import load_config, preset_path
from flexgear.config.faults import mesh_pairs
from flexgear.files import check_targets
from flexgear.results.friction_plot import pitch_crossings
from flexgear.results.signals import amplitude_spectrum
from flexgear.results.store import load
from flexgear.style import DOUBLE_WIDTH, figure, paper_style, save_figure
from flexgear.app.console import run_command

SETS = {"spur": ("spur_pair_friction", ["pinion-wheel"], ["pinion", "wheel"]),
        "mercury": ("mercury_1a_friction", ["sun-planet1", "planet1-ring"], ["sun", "planet1"])}
VARIANTS = ("off", "constant", "benedict_kelley", "xu")
STYLES = {"off": "k-", "constant": "C0-", "benedict_kelley": "C1-", "xu": "C2-"}
MU = 0.05
#: the variants as the figures name them
LABELS = {"off": "no friction", "constant": rf"constant $\mu$ = {MU:g}", "benedict_kelley": "Benedict & Kelley",
          "xu": "Xu et al."}
#: the film figure's markers: the films of the variants nearly coincide (the film follows the load
#: and the kinematics, not the coefficient), so each lies inside the one drawn before it
FILM_MARKERS = {"constant": ("o", 4.5), "benedict_kelley": ("s", 2.8), "xu": (".", 1.8)}
#: keys of the presets' [lubrication] that describe the lubricant and the surfaces
LUBRICANT_KEYS = ("iso_vg", "oil_temperature_c", "viscosity", "density", "pressure_viscosity", "roughness",
                  "gear_roughness", "sliding_speed_scale")
COEFFICIENTS = (0.02, 0.05, 0.1)
LOADS = {"full": (50.0, 100.0, 200.0, 400.0), "quick": (100.0, 200.0)}  # N m on the wheel
SPEEDS = {"full": (2.5, 5.0, 10.0, 20.0), "quick": (5.0, 10.0)}  # Hz, pinion


# --------------------------------------------------------------------------- cases

def lubricant(preset: str) -> dict:
    """The lubricant and surface keys of the preset's ``[lubrication]``."""
    lub = tomllib.loads(preset_path(preset).read_text())["lubrication"]
    return {k: v for k, v in lub.items() if k in LUBRICANT_KEYS}


def variant_block(variant: str, preset: str, mu: float = MU) -> dict:
    """The ``[lubrication]`` table of a variant (module docstring)."""
    lub = lubricant(preset)
    if variant == "off":
        return {"friction_model": "constant", "friction_coefficient": 0.0}
    if variant == "constant":
        return {"friction_model": "constant", "friction_coefficient": float(mu), **lub}
    if variant == "xu" and "roughness" not in lub and "gear_roughness" not in lub:
        raise ValueError(f"{preset}: the xu model needs a roughness")
    return {"friction_model": variant, **lub}


def _toml_value(v) -> str:
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
    return json.dumps(v)


def variants_sweep(set_name: str, duration: float, run_in: float) -> str:
    preset = SETS[set_name][0]
    blocks = ", ".join(_toml_value(variant_block(v, preset)) for v in VARIANTS)
    return (f'title = "friction variants: {set_name}"\nbase = "{preset}"\n[set]\n'
            f'"simulation.duration" = {duration}\n"simulation.run_in" = {run_in}\n'
            f'[grid]\nlubrication = [{blocks}]\n')


def efficiency_sweeps(quick: bool, duration: float, run_in: float) -> dict:
    """{name: sweep text} of the spur pair's efficiency: load x speed with the preset's model,
    and the constant coefficient at the preset's operating point."""
    preset = SETS["spur"][0]
    key = "quick" if quick else "full"
    head = (f'base = "{preset}"\n[set]\n"simulation.duration" = {duration}\n"simulation.run_in" = {run_in}\n')
    blocks = ", ".join(_toml_value(variant_block("constant", preset, mu)) for mu in COEFFICIENTS)
    return {"load_speed": (f'title = "spur efficiency: load x speed"\n{head}[grid]\n'
                           f'"load.torque" = {list(LOADS[key])}\n"drive.speed_hz" = {list(SPEEDS[key])}\n'),
            "coefficient": f'title = "spur efficiency: coefficient"\n{head}[grid]\nlubrication = [{blocks}]\n'}


def finished(batch_dir: Path) -> list[tuple[dict, Path]]:
    """(swept values, result file) of each finished case of a batch, in case order."""
    out = []
    for js in sorted((batch_dir / "cases").glob("*.json")):
        rec = json.loads(js.read_text())
        if rec.get("status") == "done" and js.with_suffix(".h5").is_file():
            out.append((rec["case"], rec["values"], js.with_suffix(".h5")))
    return [(v, p) for _, v, p in sorted(out, key=lambda r: r[0])]


def variant_of(values: dict) -> str:
    lub = values["lubrication"]
    if lub["friction_model"] == "constant":
        return "off" if lub["friction_coefficient"] == 0.0 else "constant"
    return lub["friction_model"]


# --------------------------------------------------------------------------- signals

def line_of_action(res, cfg, mesh: str):
    """(n, t): (N, 2) unit normal of the line of action along which gear a pushes gear b, and
    the flank tangent t = n rotated by +90 deg, at every sample (module docstring)."""
    m = res.meshes[mesh]
    pair = mesh_pairs(cfg)[mesh][2]
    pa, pb = res.bodies[m.body_a].position, res.bodies[m.body_b].position
    e = pb - pa
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    F = m.force_global
    best = None
    for sgn in (1.0, -1.0):
        a = sgn * (0.5 * math.pi - pair.alpha_w)
        c, s = math.cos(a), math.sin(a)
        n = np.column_stack([c * e[:, 0] - s * e[:, 1], s * e[:, 0] + c * e[:, 1]])
        proj = np.sum(F * n, axis=1)
        n *= np.sign(proj.mean()) or 1.0
        score = abs(proj.mean())
        if best is None or score > best[0]:
            best = (score, n)
    n = best[1]
    return n, np.column_stack([-n[:, 1], n[:, 0]])


def across_force(res, cfg, mesh: str) -> np.ndarray:
    """Force of gear a on gear b across the line of action, F . t [N] (:func:`line_of_action`)."""
    _, t = line_of_action(res, cfg, mesh)
    return np.sum(res.meshes[mesh].force_global * t, axis=1)


def bearing_reaction(res, body: str) -> np.ndarray:
    """(N, 2) force [N] the support (ground or carrier pin) puts on ``body``'s centre:
    m dv/dt minus the mesh forces on the body."""
    b = res.bodies[body]
    acc = np.gradient(b.velocity, res.time, axis=0)
    R = b.attrs["mass"] * acc
    for m in res.meshes.values():
        if m.body_b == body:
            R = R - m.force_global
        elif m.body_a == body:
            R = R + m.force_global
    return R


def reversal_check(res, cfg, mesh: str, crossings) -> dict:
    """The force across the line of action at the pitch-point crossings ``crossings`` [s] (away
    from the record's ends) and two output samples before and after each (the contact 0.2 to
    0.3 mm from the pitch point in the quick study, where the sliding speed is many times the
    regularisation speed); ``reversed``: the share of crossings where before and after have
    opposite signs; ``at_max``: the largest |force| at a crossing [N]."""
    t = res.time
    d = 2.0 / res.fs
    tc = np.asarray(crossings, float)
    tc = tc[(tc - d > t[0]) & (tc + d < t[-1])]
    f = across_force(res, cfg, mesh)
    before, at, after = np.interp(tc - d, t, f), np.interp(tc, t, f), np.interp(tc + d, t, f)
    return {"crossings": int(tc.size), "reversed": float(np.mean(before * after < 0)) if tc.size else float("nan"),
            "at_max": float(np.max(np.abs(at))) if tc.size else float("nan"),
            "before": before.tolist(), "after": after.tolist()}


# --------------------------------------------------------------------------- figures

def fig_force(runs, cfg, meshes, title):
    fig = figure(DOUBLE_WIDTH, 2.2 * len(meshes))
    axes = np.atleast_1d(fig.subplots(len(meshes), 1, squeeze=False)[:, 0])
    for ax, mesh in zip(axes, meshes):
        ref = runs.get("constant") or next(iter(runs.values()))
        t0 = ref.time[0]
        span = 4.0 / float(ref.attrs["mesh_frequency"])
        for v, res in runs.items():
            keep = res.time - t0 <= span
            ax.plot((res.time[keep] - t0) * 1e3, across_force(res, cfg, mesh)[keep], STYLES[v], lw=0.8,
                    label=LABELS[v])
        for n, tc in enumerate(pitch_crossings(ref, mesh)):
            if tc - t0 <= span:
                ax.axvline((tc - t0) * 1e3, color="0.5", ls=":", lw=0.6, label="pitch point" if n == 0 else None)
        ax.set_ylabel(f"{mesh}: force across\nthe line of action (N)")
    # one legend, above the traces (not on them)
    axes[0].legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), fontsize="x-small", ncol=5, frameon=False)
    axes[-1].set_xlabel("time (ms)")
    fig.suptitle(title)
    return fig


def spectra(res, cfg, mesh, bodies):
    """{label: signal} whose spectra are shown."""
    m = res.meshes[mesh]
    out = {"normal force": m.normal_force, "across LOA": across_force(res, cfg, mesh)}
    for b in bodies:
        R = bearing_reaction(res, b)
        out[f"{b} bearing x"], out[f"{b} bearing y"] = R[:, 0], R[:, 1]
    return out


def fig_spectrum(runs, cfg, mesh, bodies, title, f_max):
    ref = next(iter(runs.values()))
    labels = list(spectra(ref, cfg, mesh, bodies))
    fig = figure(DOUBLE_WIDTH, 1.4 * len(labels))
    axes = np.atleast_1d(fig.subplots(len(labels), 1, squeeze=False)[:, 0])
    fm = float(ref.attrs["mesh_frequency"])
    for v, res in runs.items():
        sig = spectra(res, cfg, mesh, bodies)
        for ax, lab in zip(axes, labels):
            f, A = amplitude_spectrum(sig[lab], res.fs)
            keep = f <= f_max
            ax.semilogy(f[keep], A[keep], STYLES[v], lw=0.6, label=LABELS[v])
    for ax, lab in zip(axes, labels):
        for k in range(1, int(f_max / fm) + 1):
            ax.axvline(k * fm, color="0.6", lw=0.4, ls=":")
        top = max(np.nanmax(line.get_ydata()) for line in ax.get_lines() if len(line.get_ydata()) > 2)
        ax.set_ylim(top * 1e-4, top * 3)  # four decades: the lines that differ between variants
        ax.set_ylabel(f"{lab.replace('across LOA', 'force across LOA')}\namplitude (N)", fontsize="small")
    axes[0].legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), fontsize="x-small", ncol=4, frameon=False)
    axes[-1].set_xlabel(f"frequency (Hz); dotted: mesh harmonics k f_m, f_m = {fm:g} Hz")
    fig.suptitle(title)
    return fig


def fig_film(runs, meshes, title):
    fig = figure(DOUBLE_WIDTH, 2.2 * len(meshes))
    axes = np.atleast_1d(fig.subplots(len(meshes), 2, squeeze=False))
    for i, mesh in enumerate(meshes):
        for v, res in runs.items():
            m = res.meshes[mesh]
            if m.film_central is None:
                continue
            s = m.contact_position
            marker, size = FILM_MARKERS.get(v, (".", 1.8))
            for j, (h, what) in enumerate(((m.film_central, "central"), (m.film_minimum, "minimum"))):
                ok = np.isfinite(h)
                axes[i, j].plot(s[ok] * 1e3, h[ok] * 1e6, STYLES[v][:2] + marker, ms=size, mfc="none" if size > 2
                                else None, mew=0.6, ls="none", label=LABELS[v])
                axes[i, j].set_title(f"{mesh}: {what} film thickness (involute contacts)", fontsize="small")
        for j in range(2):
            axes[i, j].axvline(0.0, color="0.5", ls=":", lw=0.6, label="pitch point" if j == 0 else None)
            axes[i, j].set_ylabel(r"film thickness $h$ ($\mu$m)")
            axes[i, j].set_xlabel("contact position from the pitch point (mm)")
        axes[i, 0].legend(fontsize="x-small", markerscale=1.5)
    fig.suptitle(title)
    return fig


def fig_efficiency(load_speed, coefficient, model=""):
    fig = figure(DOUBLE_WIDTH, 2.6)
    ax1, ax2 = fig.subplots(1, 2)
    for speed in sorted({r["speed_hz"] for r in load_speed}):
        rows = sorted((r for r in load_speed if r["speed_hz"] == speed), key=lambda r: r["torque"])
        ax1.plot([r["torque"] for r in rows], [100 * r["efficiency"] for r in rows], "-o", ms=3,
                 label=f"pinion {speed:g} Hz")
    ax1.set_xlabel("torque on the wheel (N m)")
    ax1.set_ylabel("mesh efficiency (%)")
    ax1.legend(fontsize="x-small")
    ax1.set_title(model or "the preset's friction model", fontsize="small")
    ax2.plot([r["mu"] for r in coefficient], [100 * r["efficiency"] for r in coefficient], "-o", ms=3,
             label="simulated")
    ax2.plot([r["mu"] for r in coefficient], [100 * r["closed_form"] for r in coefficient], "k--", lw=0.8,
             label=r"1 - $\mu H_V$ (rigid involutes, Ohlendorf)")
    ax2.set_xlabel(r"constant friction coefficient $\mu$ (-)")
    ax2.set_ylabel("mesh efficiency (%)")
    ax2.legend(fontsize="x-small")
    ax2.set_title("constant coefficient", fontsize="small")
    return fig


# --------------------------------------------------------------------------- main

def _fmt(v, f=".4g") -> str:
    return "-" if v is None or (isinstance(v, float) and not np.isfinite(v)) else format(v, f)


def main(argv=None):
    from flexgear.gears.lubrication import loss_factor

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", "--out", dest="output", default="out/friction")
    ap.add_argument("--quick", action="store_true", help="0.05 s records, a 2 x 2 efficiency sweep")
    ap.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    ap.add_argument("--sets", nargs="+", choices=list(SETS), default=list(SETS), help="gear sets (default both)")
    ap.add_argument("--overwrite", action="store_true", help="replace the figures and report")
    args = ap.parse_args(argv)
    out = Path(args.output)
    figures = (["efficiency.png", "report.md", "checks.json"]
               + [f"{k}_{s}.png" for s in args.sets for k in ("force", "spectrum", "film")])
    check_targets([out / f for f in figures], args.overwrite)
    duration, run_in = (0.05, 0.1) if args.quick else (0.5, 0.2)
    checks = {"sets": {}}
    report = [f"# Tooth friction and lubrication ({'quick: ' if args.quick else ''}{duration} s records after a "
              f"{run_in} s run-in, rigid model)", "",
              "Variants: `off` (constant coefficient 0: the frictionless model), `constant` (mu = "
              f"{MU}), `benedict_kelley` (Benedict & Kelley 1961), `xu` (Xu et al. 2007); every variant with "
              "the preset's lubricant (its film recorded). Formulas, sources and ranges: "
              "docs/guide/lubrication.md.", ""]
    for set_name in args.sets:
        preset, meshes, bodies = SETS[set_name]
        cfg = load_config(preset)
        batch_dir = out / set_name
        r = run_batch(loads_sweep(variants_sweep(set_name, duration, run_in), source=f"{set_name} variants"),
                      batch_dir, workers=args.workers)
        if r.failed or r.pending:
            print(f"{set_name}: {r.failed} case(s) failed; see {r.summary}", file=sys.stderr)
        runs = {variant_of(v): load(p) for v, p in finished(batch_dir)}
        runs = {v: runs[v] for v in VARIANTS if v in runs}
        if not runs:
            continue
        ref = next(iter(runs.values()))
        f_max = float(ref.attrs["passband_hz"])
        title = f"{preset}: {cfg.title}"
        with paper_style():
            save_figure(fig_force(runs, cfg, meshes, title), out / f"force_{set_name}.png", overwrite=args.overwrite)
            save_figure(fig_spectrum(runs, cfg, meshes[0], bodies, title, f_max), out / f"spectrum_{set_name}.png",
                        overwrite=args.overwrite)
            save_figure(fig_film(runs, meshes, title), out / f"film_{set_name}.png", overwrite=args.overwrite)
        rows, rec = [], {}
        # the pitch-point crossings of the constant coefficient's run mark every variant's (the
        # kinematics differ by the friction's small effect on the transmission error)
        crossings = {mesh: pitch_crossings(runs.get("constant", ref), mesh) for mesh in meshes}
        for v, res in runs.items():
            for mesh in meshes:
                m = res.meshes[mesh]
                across = across_force(res, cfg, mesh)
                rev = reversal_check(res, cfg, mesh, crossings[mesh])
                near = None if m.film_central is None else np.abs(m.contact_position) < 0.2e-3
                film = (float(np.nanmean(m.film_central[near])) if near is not None and np.isfinite(
                    m.film_central[near]).any() else None)
                lam = (float(np.nanmean(m.film_ratio[near])) if near is not None and np.isfinite(
                    m.film_ratio[near]).any() else None)
                eff = m.attrs.get("mesh_efficiency")
                rec[f"{v}/{mesh}"] = {"across_rms": float(np.sqrt(np.mean(across ** 2))),
                                      "normal_mean": float(np.mean(m.normal_force)),
                                      "efficiency": eff, "reversal": rev, "film_central_pitch": film,
                                      "lambda_pitch": lam}
                rows.append([v, mesh, _fmt(float(np.mean(m.normal_force))),
                             _fmt(float(np.sqrt(np.mean(across ** 2)))),
                             _fmt(None if eff is None else 100 * eff, ".3f"),
                             f"{rev['reversed'] * 100:.0f} % of {rev['crossings']}", _fmt(rev["at_max"], ".3g"),
                             _fmt(None if film is None else film * 1e6, ".3g"), _fmt(lam, ".3g")])
        checks["sets"][set_name] = rec
        report += [f"## {title}", "",
                   markdown_table(rows, ["variant", "mesh", "mean normal force (N)", "RMS across LOA (N)",
                                         "mesh efficiency (%)", "across-LOA force reversed at the pitch point",
                                         "max. abs. across LOA at the pitch point (N)",
                                         "h_c at the pitch point (um)", "lambda at the pitch point"]), "",
                   "The force across the line of action is the friction (up to the normal force of the tip-"
                   "corner contacts the soft IMPACT contact lets touch outside the path of contact, which the "
                   "`off` row shows); it changes sign where the contact crosses the pitch point "
                   "(reversal column: its sign two output samples before and after each crossing the constant "
                   "coefficient's run records; the same instants for every variant). Without friction it vanishes "
                   "at the pitch point, where one pair carries the load on the involutes. Each pair's friction "
                   "reverses there (each run's `pair_friction_force`); the mesh's total reverses only "
                   "while the other pairs in contact do not outweigh it: a coefficient that differs between the "
                   "approach and the recess, as Xu et al.'s does (the slide-to-roll ratio, entrainment speed and "
                   "radii differ there), can keep the total's sign through the crossing, and the column then reads "
                   "low. "
                   f"Figures: `force_{set_name}.png`, `spectrum_{set_name}.png`, `film_{set_name}.png`. "
                   f"Batch directory: `{batch_dir}`.", ""]
    # efficiency of the spur pair
    pair = mesh_pairs(load_config(SETS["spur"][0]))["pinion-wheel"][2]
    hv = loss_factor(pair)
    load_speed, coefficient = [], []
    for name, text in efficiency_sweeps(args.quick, duration, run_in).items():
        batch_dir = out / f"efficiency_{name}"
        r = run_batch(loads_sweep(text, source=f"efficiency {name}"), batch_dir, workers=args.workers)
        if r.failed or r.pending:
            print(f"efficiency {name}: {r.failed} case(s) failed; see {r.summary}", file=sys.stderr)
        for values, p in finished(batch_dir):
            res = load(p)
            eff = res.meshes["pinion-wheel"].attrs["mesh_efficiency"]
            if name == "load_speed":
                load_speed.append({"torque": values["load.torque"], "speed_hz": values["drive.speed_hz"],
                                   "efficiency": eff})
            else:
                mu = values["lubrication"]["friction_coefficient"]
                coefficient.append({"mu": mu, "efficiency": eff, "closed_form": 1.0 - mu * hv})
    coefficient.sort(key=lambda r: r["mu"])
    checks["efficiency"] = {"load_speed": load_speed, "coefficient": coefficient, "H_V": hv}
    with paper_style():
        lub = load_config(SETS["spur"][0]).lubrication
        oil = lub.lubricant
        named = LABELS.get(lub.friction_model, lub.friction_model) + (
            f", ISO VG {oil.iso_vg} at {oil.temperature_c:g} °C" if oil is not None and oil.iso_vg else "")
        save_figure(fig_efficiency(load_speed, coefficient, named), out / "efficiency.png", overwrite=args.overwrite)
    report += ["## Mesh efficiency of the spur pair", "",
               f"Against the load and the speed with the preset's friction model (Xu et al. 2007, its lubricant); "
               f"against a constant coefficient at the preset's 200 N m, 10 Hz, with Ohlendorf's 1 - mu H_V "
               f"(H_V = {hv:.4f}) of rigid involutes sharing the load equally. The soft IMPACT contact lets the "
               "loaded tip corners touch outside the ideal path of contact, where the sliding is fastest, so the "
               "simulated loss exceeds mu H_V (docs/guide/lubrication.md, In the rigid model).", "",
               markdown_table([[f"{r['torque']:g}", f"{r['speed_hz']:g}", f"{100 * r['efficiency']:.3f}"]
                               for r in sorted(load_speed, key=lambda r: (r["speed_hz"], r["torque"]))],
                              ["torque (N m)", "pinion (Hz)", "efficiency (%)"]), "",
               markdown_table([[f"{r['mu']:g}", f"{100 * r['efficiency']:.3f}", f"{100 * r['closed_form']:.3f}"]
                               for r in coefficient], ["mu", "efficiency (%)", "1 - mu H_V (%)"]), "",
               "Figure: `efficiency.png`.", ""]
    (out / "checks.json").write_text(json.dumps(checks, indent=1) + "\n")
    text = "\n".join(report)
    (out / "report.md").write_text(text)
    print(text)
    for f in figures:
        print(f"wrote {out / f}")


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
