"""``flexgear monitor RESULT -o DIR``: condition monitoring of a result, or of a batch against a
fault severity (see :mod:`flexgear.monitoring`).

Kept apart from the CLI's other commands so that :mod:`flexgear.app.cli` only registers it.
"""
from __future__ import annotations

from pathlib import Path

from ..errors import ConfigError, ResultExistsError


def add_monitor_command(subparsers):
    """Register ``flexgear monitor`` on the CLI's subparsers."""
    m = subparsers.add_parser(
        "monitor", help="condition monitoring of a result: order tracking, TSA per shaft, indicators, figures",
        description="Resample a signal of a result against the recorded shaft angles, average it per shaft "
        "(sun or pinion, carrier, wheel, each planet with planet-separation windows), and write the indicators "
        "(RMS, crest factor, kurtosis, FM0, FM4, NA4, M6A, M8A, energy ratio, SER; indicators.csv and .json "
        "with units and definitions) and the figures (TSA, residual, order and envelope spectra). With "
        "--severity, RESULT is a batch directory and the indicators are tabulated and drawn against that swept "
        "key (severity.csv, .json, .png). Definitions: docs/guide/monitoring.md.")
    m.add_argument("result", metavar="RESULT", help="a results.h5 (or its directory); with --severity a batch "
                   "directory (flexgear batch -o DIR)")
    m.add_argument("-o", "--output", metavar="OUTDIR", required=True, help="output directory (created if missing)")
    m.add_argument("--signal", metavar="PATH", help="dataset to analyse, PATH[:COLUMN] for a 2-D one, e.g. "
                   "meshes/planet1-ring/force_global:1 (default: the first sensor, else the first mesh's normal force, "
                   "which repeats with its gears)")
    m.add_argument("--baseline", nargs="+", metavar="H5", default=[], help="healthy results of the same set: NA4 "
                   "is normalised by their residual variance (default: none, NA4 = the residual's kurtosis)")
    m.add_argument("--sensor-angle", type=float, default=None, metavar="DEG", help="angle of the fixed measuring "
                   "point about the set's centre, counter-clockwise from +x; planet windows are centred where a "
                   "planet passes it (default: the analysed sensor's, else 90, above the centre)")
    m.add_argument("--planet-window", choices=("hann", "rectangular"), default="hann",
                   help="planet-separation window shape (default: %(default)s)")
    m.add_argument("--window-teeth", type=int, metavar="N", help="planet window width in tooth-meshing periods "
                   "(default: the step its teeth advance from pass to pass, gcd(ring teeth, planet teeth) for a "
                   "planet, gcd(sun teeth, (sun + ring teeth) / planets) for --sun-windows; doubled for hann)")
    m.add_argument("--sun-windows", action="store_true", help="average the sun from every planet's windows, each "
                   "shifted by the planet's position (McFadden 1991), so that a sun tooth appears once, not once per "
                   "planet (default: the plain average against the sun's angle in the carrier)")
    m.add_argument("--min-averages", type=float, default=1.0, metavar="M", help="least number of averages at any "
                   "angle of a shaft's average (windowed: summed window weight) (default: %(default)s)")
    m.add_argument("--samples-per-rev", type=int, metavar="N", help="samples per revolution of every average "
                   "(default: per shaft, as dense as the record at its lowest speed)")
    m.add_argument("--shaft-orders", type=int, default=2, metavar="N", help="shaft orders 1..N counted in the "
                   "regular signal (default: %(default)s)")
    m.add_argument("--sidebands", type=int, default=3, metavar="N", help="sidebands a side in the sideband "
                   "energy ratio (default: %(default)s)")
    m.add_argument("--band", type=float, nargs=2, metavar=("LOW", "HIGH"), help="band of the envelope spectrum "
                   "in Hz (default: the mesh frequency -/+ half of it)")
    m.add_argument("--shafts", nargs="+", metavar="SHAFT", help="shafts to average, e.g. sun planet1 (default: "
                   "every one the record allows; the others are reported with the reason)")
    m.add_argument("--severity", metavar="KEY", help="RESULT is a batch directory: indicators against this swept "
                   "key, e.g. faults.0.depth")
    m.add_argument("--healthy", type=float, metavar="VALUE", help="with --severity: the severity of the healthy "
                   "cases, NA4's baseline (default: the least)")
    m.add_argument("--overwrite", action="store_true", help="replace existing output files (default: refuse, "
                   "and write nothing)")
    m.set_defaults(func=cmd_monitor)
    return m


def cmd_monitor(args) -> int:
    """Run the analysis, then write its files; every check before the first file."""
    from ..files import check_output_directory, output_directory
    from ..monitoring.analysis import MonitorSettings, monitor
    from ..monitoring.outputs import SEVERITY_FILES, report_paths, severity_table, write_report, write_severity

    settings = MonitorSettings(signal=args.signal, sensor_angle_deg=args.sensor_angle,
                               samples_per_rev=args.samples_per_rev, shaft_orders=args.shaft_orders,
                               planet_window=args.planet_window, window_teeth=args.window_teeth,
                               sun_windows=args.sun_windows, min_averages=args.min_averages,
                               band_hz=tuple(args.band) if args.band else None,
                               sidebands=args.sidebands, shafts=tuple(args.shafts) if args.shafts else None)
    settings.check()
    if args.severity and args.baseline:
        raise ConfigError("--baseline: not with --severity, where the healthy cases are the baseline "
                          "(--healthy VALUE)")
    if args.healthy is not None and not args.severity:
        raise ConfigError("--healthy: only with --severity")
    if not args.severity and (Path(args.result) / "batch.json").is_file():
        raise ConfigError(f"RESULT {args.result!r} is a batch directory: pass --severity KEY (a swept key) to "
                          f"tabulate its cases, or give one case's file, {str(Path(args.result) / 'cases')}/<key>.h5 "
                          "(its summary.csv names each case's file)")
    out = Path(args.output)
    check_output_directory(out)
    targets = [out / n for n in SEVERITY_FILES] if args.severity else report_paths(out)
    existing = [str(p) for p in targets if p.exists()]
    if existing and not args.overwrite:
        raise ResultExistsError(f"{', '.join(existing)} exist{'s' if len(existing) == 1 else ''}; refusing to "
                                "overwrite (use --overwrite or another -o)")
    if args.severity:
        table = severity_table(args.result, args.severity, settings, healthy=args.healthy)
        with output_directory(out):
            for p in write_severity(table, out, overwrite=args.overwrite):
                print(f"wrote {p}")
        print()
        print(severity_text(table))
        return 0
    report = monitor(args.result, settings, baseline=args.baseline)
    for name, why in report.skipped.items():
        print(f"flexgear monitor: {name} not averaged: {why}")
    with output_directory(out):
        for p in write_report(report, out, overwrite=args.overwrite):
            print(f"wrote {p}")
    print()
    print(indicator_table(report))
    return 0


def severity_text(table) -> str:
    """A severity table as Markdown, one table per shaft: a row per case, "-" where undefined."""
    from ..monitoring.indicators import INDICATORS
    from .console import cell, markdown_table

    names = list(INDICATORS)
    other = table.swept_keys  # a noise seed of repeated measurements, ...: a column each
    parts = [f"{table.signal} against {table.key}"]
    healthy = [table.severities[i] for i, f in enumerate(table.files) if f in table.baseline]
    if healthy:
        line = f"healthy cases, NA4's baseline: {table.key} = {healthy[0]:g} ({len(healthy)} case(s))"
        if healthy[0] != 0:
            line += " - not zero: the least severity in the batch, unless --healthy chose it"
        if not any(n for b in table.baseline_records for n in b.values()):
            line += ("; their residuals are numerically zero (noise-free) or they are the only case: NA4 is each "
                     "case's own residual kurtosis")
        parts.append(line)
    for shaft in table.shafts:
        cols = [table.values(shaft, n) for n in names]
        rows = [[cell(sev)] + [cell(table.swept[i].get(k)) for k in other] + [cell(c[i]) for c in cols]
                for i, sev in enumerate(table.severities)]
        parts += ["", f"{shaft}:", markdown_table(rows, [table.key] + other + names)]
    gaps = {f"{table.files[i]}: {shaft}: {why}" for i, k in enumerate(table.skipped) for shaft, why in k.items()}
    if gaps:
        parts += ["", "not averaged:"] + [f"- {g}" for g in sorted(gaps)]
    return "\n".join(parts)


def indicator_table(report) -> str:
    """Every averaged shaft's indicators as a Markdown table, "-" where one is undefined, the
    reasons under it (as indicators.csv and indicators.json hold them)."""
    from ..monitoring.indicators import INDICATORS
    from ..monitoring.leaks import mostly_partner
    from .console import cell, markdown_table

    names = list(INDICATORS)
    rows, why = [], []
    for shaft, avg in report.shafts.items():
        rows.append([shaft] + [cell(avg.indicators.get(n)) for n in names])
        why += [f"- {shaft} {n}: {reason}" for n, reason in avg.notes.items()]
    whole = report.signal_indicators  # the whole record, mean removed, as the CSV's row "signal"
    rows.append(["signal"] + [cell(whole.get(n), none="") for n in names])
    src = report.source
    head = f"{src.signal_path} [{src.units or '-'}] of {src.path}"
    leak = [f"- {shaft}: its halves differ by {avg.unsteady:.2g} of its RMS" for shaft, avg in report.shafts.items()
            if avg.leaky]
    leak += [f"- {shaft}: {avg.partner_share[0]:.0%} of its power at the orders where {avg.partner[0]}'s content stays "
             f"(broadband: {avg.partner_share[1]:.0%})" for shaft, avg in report.shafts.items()
             if mostly_partner(avg.partner_share)]
    return "\n".join([head, "", markdown_table(rows, ["shaft"] + names)] + (["", "undefined:"] + why if why else [])
                     + (["", "residual not repeating with its shaft (content its average does not cancel):"] + leak
                        if leak else []))
