"""What the housing sensors of MERCURY 1-A hear, healthy and with tooth faults of growing size.

MERCURY 1-A with its default housing and the two radial accelerometers of the preset
``mercury_1a_sensors`` (``top`` above the ring at 90 deg, ``side`` at 0 deg), through both path
models of a rigid or lumped run (``housing_path``: the reduced housing's one-way response to the
bearing and ring loads; ``planet_pass``: McFadden & Smith's window over the planet-ring forces).
Three fault families, each a batch (``flexgear.app.batch``) over its severity, the first case
healthy (a fault of zero size is the healthy model bit for bit):

- ``sun_crack``: a root crack in sun tooth 3 (loaded flank), lumped model, crack depth;
- ``planet_crack``: a root crack in planet 1's tooth 3 (sun-side flank), lumped model, depth;
- ``sun_spall``: a spall band across sun tooth 3's flank at the pitch circle, rigid model, spall
  depth (the rigid contact model simulates spalls, not cracks).

Writes, in the paper's style:

- ``time_<family>.png``: the sensor signals over one carrier revolution, healthy against the
  largest fault, both sensors, both path models;
- ``spectrum_<family>.png``: their spectra with the mesh harmonics, the sidebands planet-passing
  allows and the fault's lines marked (full band, and a zoom around the strongest mesh harmonic);
- ``indicators.png``: FM4, NA4 and the sideband energy ratio of the faulty shaft's
  time-synchronous average (``flexgear.monitoring``) against severity, for each sensor and path
  model side by side; ``<family>/monitor/severity.{csv,json,png}``: every indicator of every
  shaft for the ``side`` sensor's housing path;
- ``report.md``: the line families and why they are there, the tables behind the figures.

The batches are resumable: running the study again continues them.

Usage::

    python studies/sensor_signals.py -o out/sensor_signals [--quick] [--workers N] [--overwrite]

``--quick``: 0.25 s records (two carrier revolutions), the sun crack at three depths and the
other two faults at one (about a minute on 2 cores), for a check of the pipeline.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from flexgear.app.batch import run_batch
from flexgear.app.console import markdown_table
from flexgear.app.sweep import loads_sweep
from flexgear.config import load_config
from flexgear.files import check_targets
from flexgear.monitoring import MonitorSettings, monitor
from flexgear.monitoring.indicators import INDICATORS
from flexgear.monitoring.outputs import SeverityTable, write_severity
from flexgear.results.signals import amplitude_spectrum
from flexgear.results.store import load
from flexgear.style import DOUBLE_WIDTH, figure, paper_style, save_figure
from flexgear.app.console import run_command

PRESET = "mercury_1a_sensors"
SENSORS = ("top", "side")
PATHS = ("housing_path", "planet_pass")
#: the sensor and path model whose indicators of every shaft go to <family>/monitor
MAIN_SIGNAL = "sensors/side/housing_path"
SHOWN = ("fm4", "na4", "ser")

# family -> model, fault table (without its severity), severity key, full and quick severities,
# unit and scale of the severity axis, faulty shaft in the monitoring, title
FAMILIES = {
    "sun_crack": ("lumped", {"kind": "crack", "gear": "sun", "tooth": 3, "flank": "left", "angle_deg": 45.0},
                  "depth", [0.0, 0.4e-3, 0.8e-3, 1.2e-3], [0.0, 0.6e-3, 1.2e-3], "mm", 1e3, "sun",
                  "sun crack (lumped)"),
    "planet_crack": ("lumped", {"kind": "crack", "gear": "planet", "planet": 1, "tooth": 3, "flank": "left",
                                "angle_deg": 45.0},
                     "depth", [0.0, 0.4e-3, 0.8e-3, 1.2e-3], [0.0, 1.2e-3], "mm", 1e3, "planet1",
                     "planet 1 crack (lumped)"),
    "sun_spall": ("rigid", {"kind": "spall", "gear": "sun", "tooth": 3, "flank": "left",
                            "start_radius": 23.5e-3, "end_radius": 24.5e-3},
                  "depth", [0.0, 3e-6, 6e-6, 12e-6], [0.0, 12e-6], "um", 1e6, "sun", "sun spall (rigid)"),
}


# --------------------------------------------------------------------------- kinematics and lines

def kinematics(cfg) -> dict:
    """Frequencies of the preset's planetary set [Hz]: sun f_s, carrier f_c, mesh f_m, the
    planets' count P and the gears' teeth, and the fault frequencies (Feng & Zuo 2012): a local
    sun fault meets the N planets at N (f_s - f_c) = N f_m / z_s, a fault on one planet flank
    meets its mate once per planet revolution relative to the carrier, f_m / z_p."""
    g = cfg.gears
    zs, zp, zr = g["sun"].z, g["planet"].z, g["ring"].z
    P = int(cfg.planetary["planets"])
    fs = float(cfg.drive["speed_hz"])
    fc = fs * zs / (zs + zr)
    fm = zr * fc
    return {"f_s": fs, "f_c": fc, "f_m": fm, "P": P, "z_s": zs, "z_p": zp, "z_r": zr,
            "sun": P * fm / zs, "planet1": fm / zp}


def allowed_sidebands(k: int, zr: int, P: int, q_max: int) -> list[int]:
    """Sideband orders q (lines at k f_m + q f_c) that the planet-pass signal of P equally spaced,
    equally phased planets keeps around the k-th mesh harmonic (McFadden & Smith 1985): those
    with k z_r + q = 0 (mod P)."""
    return [q for q in range(-q_max, q_max + 1) if (k * zr + q) % P == 0]


def mesh_lines(kin: dict, f_max: float) -> list[float]:
    return [k * kin["f_m"] for k in range(1, int(f_max / kin["f_m"]) + 1)]


# --------------------------------------------------------------------------- batches

def sweep_text(family: str, severities, duration: float, run_in: float) -> str:
    model, fault, key, *_ = FAMILIES[family]
    cases = []
    for s in severities:
        items = ", ".join(f"{k} = {json.dumps(v)}" for k, v in {**fault, key: float(s)}.items())
        cases.append(f"[{{{items}}}]")
    return (f'title = "MERCURY 1-A sensors: {family}"\nbase = "{PRESET}"\n[set]\nmodel = "{model}"\n'
            f'"simulation.duration" = {duration}\n"simulation.run_in" = {run_in}\n'
            f'[grid]\nfaults = [{", ".join(cases)}]\n')


def family_cases(batch_dir: Path, key: str) -> list[tuple[float, Path]]:
    """(severity, result file) of each finished case of a family's batch, by severity (the
    severity is the fault's ``key`` in the case's swept ``faults`` list)."""
    out = []
    for js in sorted((batch_dir / "cases").glob("*.json")):
        rec = json.loads(js.read_text())
        if rec.get("status") == "done" and js.with_suffix(".h5").is_file():
            out.append((float(rec["values"]["faults"][0][key]), js.with_suffix(".h5")))
    return sorted(out, key=lambda c: c[0])


def indicator_tables(cases, shaft: str) -> dict:
    """Monitoring of every case for every (sensor, path model): ``{(sensor, path): {"reports":
    [{shaft: {indicator: value}}], "signal": ..., "units": ...}}``. NA4 of each case is
    normalised by the healthy cases (least severity) other than itself, those whose residual is
    not numerically zero (a noise-free healthy case has no variance to give)."""
    healthy = [p for s, p in cases if s == cases[0][0]]
    out = {}
    for sensor in SENSORS:
        for path in PATHS:
            settings = MonitorSettings(signal=f"sensors/{sensor}/{path}")
            reports, units, skipped = [], "1", set()
            for _, f in cases:
                rep = monitor(f, settings, baseline=[p for p in healthy if p != f], skip_empty_baselines=True)
                reports.append({n: dict(sa.indicators) for n, sa in rep.shafts.items()})
                units = rep.source.units or "1"
                skipped.update(v for k, v in rep.skipped.items() if k == shaft)
            out[sensor, path] = {"reports": reports, "units": units, "skipped": sorted(skipped)}
    return out


def severity_of(family: str, tables: dict, cases, key_label: str) -> SeverityTable:
    rec = tables[tuple(MAIN_SIGNAL.split("/")[1:])]
    units = {k: rec["units"] if v.unit == "signal" else v.unit for k, v in INDICATORS.items()}
    return SeverityTable(key_label, MAIN_SIGNAL, [s for s, _ in cases], [str(p) for _, p in cases],
                         rec["reports"], [str(p) for s, p in cases if s == cases[0][0]], units)


# --------------------------------------------------------------------------- spectra

def signal_of(res, sensor: str, path: str) -> np.ndarray:
    return np.asarray(res.sensors[sensor].signals[path], dtype=float)


def line_level(f, A, freqs, tol: float) -> float:
    """Root of the summed squares of the largest amplitude within ``tol`` of each frequency."""
    total = 0.0
    for x in freqs:
        m = np.abs(f - x) <= tol
        if m.any():
            total += float(A[m].max()) ** 2
    return float(np.sqrt(total))


def fault_line_freqs(kin: dict, shaft: str, f_max: float, j_max: int = 3) -> list[float]:
    """The fault's lines that are no whole carrier order: k f_m +- j f_fault and j f_fault."""
    ff, fc = kin[shaft], kin["f_c"]
    out = []
    for k in range(0, int(f_max / kin["f_m"]) + 1):
        for j in range(-j_max, j_max + 1):
            x = k * kin["f_m"] + j * ff
            if 0 < x < f_max and abs(x / fc - round(x / fc)) > 0.1:
                out.append(x)
    return sorted(set(np.round(out, 6)))


def fig_time(results, kin, title: str):
    fig = figure(DOUBLE_WIDTH, 4.4)
    axes = np.array(fig.subplots(len(PATHS), len(SENSORS), squeeze=False))
    for i, path in enumerate(PATHS):
        for j, sensor in enumerate(SENSORS):
            ax = axes[i, j]
            for label, res, style in results[::-1]:  # the healthy signal drawn over the faulty one
                t = res.time - res.time[0]
                keep = t <= 1.0 / kin["f_c"]
                ax.plot(t[keep] * 1e3, signal_of(res, sensor, path)[keep], style, lw=0.6, label=label)
            units = res.sensors[sensor].signal_attrs[path]["units"]
            ax.set_title(f"{sensor}, {path.replace('_', ' ')}")
            ax.set_ylabel(f"signal ({units})")
            if i == len(PATHS) - 1:
                ax.set_xlabel("time over one carrier revolution (ms)")
            ax.legend(loc="upper right")
    fig.suptitle(title)
    return fig


def _marks(ax, xs, top, color, ls, label, lo, hi):
    shown = [x for x in xs if lo <= x <= hi]
    for n, x in enumerate(shown):
        ax.axvline(x, color=color, ls=ls, lw=0.5, alpha=0.8, label=label if n == 0 else None)


def fig_spectrum(results, kin, shaft: str, title: str, f_max: float):
    """Rows: sensor x path model; columns: the band up to f_max with the mesh harmonics, and a
    zoom around the harmonic strongest at the faulty case's side sensor with the allowed
    sidebands and the fault's lines."""
    fig = figure(DOUBLE_WIDTH, 6.0)
    rows = [(s, p) for s in SENSORS for p in PATHS]
    axes = np.array(fig.subplots(len(rows), 2, squeeze=False))
    fm, fc = kin["f_m"], kin["f_c"]
    res_f = results[-1][1]
    f, A = amplitude_spectrum(signal_of(res_f, "side", "housing_path"), res_f.fs)
    k_star = max(range(1, int(f_max / fm) + 1), key=lambda k: line_level(f, A, [k * fm], 0.6 * fc))
    zoom = (k_star * fm - 12.5 * fc, k_star * fm + 12.5 * fc)
    sidebands = [k_star * fm + q * fc for q in allowed_sidebands(k_star, kin["z_r"], kin["P"], 12) if q]
    faults = fault_line_freqs(kin, shaft, f_max)
    for i, (sensor, path) in enumerate(rows):
        for j, (lo, hi) in enumerate(((0.0, f_max), zoom)):
            ax = axes[i, j]
            for label, res, style in results:
                f, A = amplitude_spectrum(signal_of(res, sensor, path), res.fs)
                keep = (f >= lo) & (f <= hi)
                ax.semilogy(f[keep], np.maximum(A[keep], 1e-12), style, lw=0.6, label=label)
            top = ax.get_ylim()[1]
            _marks(ax, mesh_lines(kin, f_max), top, "k", "-", "$k f_m$", lo, hi)
            if j == 1:
                _marks(ax, sidebands, top, "tab:green", ":", "allowed sidebands", lo, hi)
                _marks(ax, faults, top, "tab:red", "--", "fault lines", lo, hi)
            units = res.sensors[sensor].signal_attrs[path]["units"]
            ax.set_ylabel(f"{sensor}, {path.split('_')[0]}\n({units})")
            if i == 0:
                ax.set_title("0 to %.0f Hz" % f_max if j == 0 else f"around {k_star} $f_m$")
            if i == len(rows) - 1:
                ax.set_xlabel("frequency (Hz)")
    axes[0, 1].legend(loc="upper right", fontsize="x-small")
    fig.suptitle(title)
    return fig


def fig_indicators(summary: dict):
    fig = figure(DOUBLE_WIDTH, 4.6)
    axes = np.array(fig.subplots(len(SHOWN), len(summary), squeeze=False))
    for j, (family, (sev, unit, shaft, tables)) in enumerate(summary.items()):
        for i, name in enumerate(SHOWN):
            ax = axes[i, j]
            for (sensor, path), style in zip(tables, ("-o", "--s", "-^", ":v")):
                vals = [r.get(shaft, {}).get(name) for r in tables[sensor, path]["reports"]]
                y = np.array([np.nan if v is None else v for v in vals], dtype=float)
                ax.plot(sev, y, style, ms=3, label=f"{sensor}, {path.split('_')[0]}")
            if not any(line.get_ydata().size and np.isfinite(line.get_ydata()).any() for line in ax.get_lines()):
                ax.text(0.5, 0.5, f"{shaft} not averaged:\nrecord too short (report.md)", ha="center",
                        va="center", transform=ax.transAxes, fontsize="small")
            ax.set_ylabel(f"{name.upper()} ({shaft})")
            if i == 0:
                ax.set_title(FAMILIES[family][-1])
            if i == len(SHOWN) - 1:
                ax.set_xlabel(f"severity ({unit})")
    axes[0, 0].legend(fontsize="x-small")
    return fig


# --------------------------------------------------------------------------- report

def line_families_text(kin: dict, f_max: float) -> list[str]:
    fm, fc, P, zr = kin["f_m"], kin["f_c"], kin["P"], kin["z_r"]
    q_first = allowed_sidebands(1, zr, P, P)
    return [
        "## Line families marked in the spectra", "",
        f"Operating point: sun {kin['f_s']:g} Hz, carrier f_c = {fc:g} Hz, mesh f_m = z_r f_c = {fm:g} Hz, "
        f"P = {P} planets, z_s = {kin['z_s']}, z_p = {kin['z_p']}, z_r = {zr}.", "",
        f"- **Mesh harmonics** k f_m (black, solid; k = 1..{int(f_max / fm)} below {f_max:g} Hz): the tooth-"
        "meshing excitation of every mesh. MERCURY 1-A's planets mesh in phase (z_s and z_r are multiples "
        f"of {P}), so the P meshes add up at every harmonic instead of cancelling.",
        "- **Planet-pass sidebands** k f_m + q f_c (green, dotted, in the zoom): McFadden & Smith (1985): a "
        "sensor fixed on the housing hears each planet-ring mesh through a window that travels with the "
        "carrier; with P equally spaced planets the sum keeps only the carrier orders n = k z_r + q with "
        f"n = 0 (mod P), so q = -k z_r (mod P). Here z_r = {zr} = 0 (mod {P}): the mesh harmonics "
        f"themselves survive and the sidebands sit at q = {', '.join(f'{q:+d}' for q in q_first if q)}, "
        f"... (every {P * fc:g} Hz), symmetric about each harmonic. The planet-pass path model obeys this "
        "rule exactly on a healthy set. The housing-path model also hears the bearing forces, which "
        "rotate with the carrier; a force vector turning with planet i adds the orders n = +-1 (mod P), "
        f"so with P = {P} every whole carrier order (every {fc:g} Hz) may carry a line at that path. "
        "A healthy rigid or lumped set repeats every carrier revolution: all its lines are whole "
        "carrier orders.",
        f"- **Sun fault lines** (red, dashed, sun families): a local sun fault meets the {P} planets "
        f"{P} times per sun revolution relative to the carrier, f_sf = P (f_s - f_c) = P f_m / z_s = "
        f"{kin['sun']:g} Hz (Feng & Zuo 2012). It modulates the meshes: lines at j f_sf and sidebands "
        "k f_m +- j f_sf (j = 1..3 marked). Only those that are no whole carrier order are marked, as "
        "the others coincide with healthy lines. f_sf is a carrier order times "
        f"{kin['sun'] / fc:.4g}, so the fault's lines fall between the healthy ones.",
        f"- **Planet fault lines** (red, dashed, planet family): a fault on one flank of a planet tooth "
        f"meets its mate once per planet revolution relative to the carrier, f_pf = f_m / z_p = "
        f"{kin['planet1']:.4g} Hz (Feng & Zuo 2012), at both meshes of that flank pair (the crack here is "
        "on the sun-side flank); marked as for the sun. The planet passes the sensor once per carrier "
        "revolution, so its fault is heard with the window's modulation too, which spreads it over "
        "carrier-order sidebands of these lines. Its first line lies "
        f"{abs(kin['planet1'] - round(kin['planet1'] / (P * fc)) * P * fc):.3g} Hz from an allowed planet-pass "
        "line: a Hann-windowed record separates them only if it is longer than about twice the inverse of "
        "that gap, so on the planet-pass path the planet family's fault-line level is the healthy lines' "
        "leakage in shorter records.",
        "- **Fault-line level** (tables): the root sum square of the marked fault lines over that of the "
        "mesh harmonics; zero on a healthy set (its lines are whole carrier orders) up to the window's "
        "leakage. A spall's level need not grow with its depth once the spall is deeper than the contact "
        "penetration (the tooth then loses contact over the band whatever the depth).",
        "",
    ]


def fault_level_rows(family, cases, kin, shaft, f_max):
    """Per case and sensor/path: the fault-line level (root sum square of the marked fault lines)
    relative to the mesh-line level (root sum square of the mesh harmonics)."""
    rows = []
    for sev, path_h5 in cases:
        res = load(path_h5)
        row = [f"{sev * FAMILIES[family][6]:g}"]
        for sensor in SENSORS:
            for path in PATHS:
                f, A = amplitude_spectrum(signal_of(res, sensor, path), res.fs)
                tol = 0.6 * (f[1] - f[0])
                fl = line_level(f, A, fault_line_freqs(kin, shaft, f_max), tol)
                ml = line_level(f, A, mesh_lines(kin, f_max), tol)
                row.append(fl / ml if ml > 0 else float("nan"))
        rows.append(row)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", "--out", dest="output", default="out/sensor_signals")
    ap.add_argument("--quick", action="store_true", help="0.25 s records, fewer severities")
    ap.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    ap.add_argument("--families", nargs="+", choices=list(FAMILIES), default=list(FAMILIES))
    ap.add_argument("--overwrite", action="store_true", help="replace the figures and report")
    args = ap.parse_args(argv)
    out = Path(args.output)
    figures = (["indicators.png", "report.md", "fault_levels.json"] + [f"time_{f}.png" for f in args.families]
               + [f"spectrum_{f}.png" for f in args.families])
    check_targets([out / f for f in figures], args.overwrite)
    duration, run_in = (0.25, 0.2) if args.quick else (1.0, 0.2)
    cfg = load_config(PRESET)
    kin = kinematics(cfg)
    f_max = 0.8 * 0.5 * float(cfg.simulation["output_rate"])  # trustworthy band (0.8 x Nyquist)
    report = [f"# Sensor signals of MERCURY 1-A ({'quick: ' if args.quick else ''}{duration} s records "
              f"after a {run_in} s run-in)", "",
              f"Preset `{PRESET}`: sensors {', '.join(SENSORS)} (radial accelerometers at 90 and 0 deg on the "
              "housing's rim), path models housing_path (m/s^2) and planet_pass (N, a windowed force).", ""]
    report += line_families_text(kin, f_max)
    summary, levels = {}, {}
    for family in args.families:
        model, fault, key, full, quick, unit, scale, shaft, title = FAMILIES[family]
        severities = quick if args.quick else full
        sweep = loads_sweep(sweep_text(family, severities, duration, run_in), source=f"{family} sweep")
        batch_dir = out / family
        r = run_batch(sweep, batch_dir, workers=args.workers)
        if r.failed or r.pending:
            print(f"{family}: {r.failed} case(s) failed; see {r.summary}", file=sys.stderr)
        cases = family_cases(batch_dir, key)
        if len(cases) < 2:
            print(f"{family}: fewer than two finished cases, skipped", file=sys.stderr)
            continue
        tables = indicator_tables(cases, shaft)
        sev = [s * scale for s, _ in cases]
        summary[family] = (sev, unit, shaft, tables)
        (batch_dir / "monitor").mkdir(parents=True, exist_ok=True)
        write_severity(severity_of(family, tables, cases, f"faults[0].{key}"), batch_dir / "monitor",
                       overwrite=args.overwrite)
        healthy, worst = load(cases[0][1]), load(cases[-1][1])
        shown = [("healthy", healthy, "-"), (f"{key} {sev[-1]:g} {unit}", worst, "-")]
        with paper_style():
            save_figure(fig_time(shown, kin, title), out / f"time_{family}.png", overwrite=args.overwrite)
            save_figure(fig_spectrum(shown, kin, shaft, title, f_max), out / f"spectrum_{family}.png",
                        overwrite=args.overwrite)
        skipped = sorted({x for v in tables.values() for x in v["skipped"]})
        lv = fault_level_rows(family, cases, kin, shaft, f_max)
        levels[family] = {"severity": [x[0] for x in lv], "unit": unit,
                          **{f"{s}/{p}": [x[1 + 2 * i + j] for x in lv] for i, s in enumerate(SENSORS)
                             for j, p in enumerate(PATHS)}}
        report += [f"## {title}", "",
                   f"Fault: {', '.join(f'{k} = {v}' for k, v in fault.items())}; {key} swept "
                   f"({', '.join(f'{s:g}' for s in sev)} {unit}). Fault frequency {kin[shaft]:.4g} Hz.", "",
                   "Fault-line level: root sum square of the marked fault lines over that of the mesh harmonics "
                   "(0 on a healthy set up to the window's leakage):", "",
                   markdown_table([[x[0], *(f"{v:.3g}" for v in x[1:])] for x in lv],
                                  [f"{key} ({unit})", *(f"{s} {p}" for s in SENSORS for p in PATHS)]), "",
                   f"Indicators of the {shaft}'s time-synchronous average (NA4 against the healthy case, "
                   "where its residual is not numerically zero; else the case's residual kurtosis):", "",
                   markdown_table([[f"{s:g}", *(_fmt(tables[sn, pn]["reports"][n].get(shaft, {}).get(i))
                                                for sn in SENSORS for pn in PATHS for i in SHOWN)]
                                   for n, s in enumerate(sev)],
                                  [f"{key} ({unit})", *(f"{sn[0]}/{pn.split('_')[0]} {i}" for sn in SENSORS
                                                        for pn in PATHS for i in SHOWN)]), "",
                   *([f"The {shaft} was not averaged: {'; '.join(skipped)}.", ""] if skipped else []),
                   "A '-' is an indicator left undefined: FM4 and NA4 of a healthy set whose difference signal "
                   "vanishes (it repeats every carrier revolution, the regular meshing is all there is).", "",
                   f"Figures: `time_{family}.png`, `spectrum_{family}.png`; every indicator of every shaft "
                   f"for {MAIN_SIGNAL}: `{family}/monitor/severity.csv`. Batch directory: `{batch_dir}`.", ""]
    with paper_style():
        save_figure(fig_indicators(summary), out / "indicators.png", overwrite=args.overwrite)
    (out / "fault_levels.json").write_text(json.dumps(levels, indent=1) + "\n")
    text = "\n".join(report)
    (out / "report.md").write_text(text)
    print(text)
    for f in figures:
        print(f"wrote {out / f}")


def _fmt(v) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.3g}"


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
