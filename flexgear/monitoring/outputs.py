"""Files of condition monitoring: the indicators (CSV, JSON) and the figures, of one result or of a
fault-severity sweep (a batch directory).

``indicators.csv`` has one row per shaft and indicator (``shaft, indicator, value, unit, on,
definition, source``; an empty value is an undefined indicator, the reason in the JSON);
``indicators.json`` adds the signal, the settings, every shaft's averaging data and the
definitions. ``severity.csv`` has one row per case of a sweep and one column per shaft and
indicator (``sun_fm4``, ...), ``severity.json`` the same with units and definitions.
"""
from __future__ import annotations

import csv
import io
import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from ..errors import ConfigError, FlexgearError, user_stacklevel
from ..files import atomic_write, check_targets, csv_column
from ..style import save_figure, save_figures
from . import figures
from .analysis import MonitorReport, MonitorSettings, monitor
from .indicators import INDICATORS

__all__ = ["REPORT_FILES", "SEVERITY_FILES", "report_paths", "write_report", "SeverityTable", "batch_cases",
           "severity_table", "write_severity"]

REPORT_FILES = ("indicators.csv", "indicators.json") + figures.MONITOR_FIGURES
SEVERITY_FILES = ("severity.csv", "severity.json", "severity.png")


def _json_value(v):
    """JSON for numpy scalars and arrays (``json.dumps(default=...)``)."""
    return v.tolist() if hasattr(v, "tolist") else str(v)


def _write_text(path: Path, text: str, overwrite: bool) -> Path:
    check_targets([path], overwrite)
    atomic_write(path, lambda p: Path(p).write_text(text))
    return path


def _csv(rows: list[dict], columns: list[str]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if r.get(k) is None else (repr(r[k]) if isinstance(r[k], float) else r[k]))
                    for k in columns})
    return buf.getvalue()


def report_paths(out) -> list[Path]:
    """The files :func:`write_report` writes into ``out``."""
    return [Path(out) / n for n in REPORT_FILES]


def write_report(report: MonitorReport, out, overwrite: bool = False) -> list[Path]:
    """Write the indicators and the figures of ``report`` into the directory ``out`` (created if
    missing).

    Raises
    ------
    ResultExistsError
        If a file exists and ``overwrite`` is False (checked for all files before writing any).
    """
    out = Path(out)
    check_targets(report_paths(out), overwrite)
    out.mkdir(parents=True, exist_ok=True)
    rows = report.rows()
    written = [_write_text(out / "indicators.csv", _csv(rows, ["shaft", "indicator", "value", "unit", "on",
                                                               "definition", "source"]), overwrite)]
    data = report.to_dict()
    written.append(_write_text(out / "indicators.json", json.dumps(data, indent=1, default=_json_value) + "\n",
                               overwrite))
    makers = (figures.fig_tsa, figures.fig_order_spectra, figures.fig_envelope)
    written += save_figures([(lambda f=f: f(report), out / name) for f, name in zip(makers, figures.MONITOR_FIGURES)],
                            overwrite=overwrite)
    return written


# --------------------------------------------------------------------------- fault severity

@dataclass
class SeverityTable:
    """Indicators of several results against a fault-severity value.

    Attributes
    ----------
    key : str
        The swept configuration key holding the severity (e.g. ``faults.0.depth``).
    signal : str
        The analysed signal path.
    severities : list of float
        Severity of each case, increasing (repeats of a severity in the order of their other
        swept values).
    files : list of str
        Each case's result file, relative to the batch directory (as ``summary.csv`` names it).
    reports : list of dict
        Each case's ``{shaft: {indicator: value}}``.
    baseline : list of str
        The healthy cases (severity ``healthy``, default the least), NA4's baseline.
    units : dict
        Unit of each indicator.
    swept : list of dict
        Each case's other swept values (a noise seed of repeated measurements, a speed, ...).
    skipped : list of dict
        Each case's shafts not averaged, ``{shaft: reason}``.
    baseline_records : list of dict
        Each case's ``{shaft: number of healthy cases in its NA4}``: a healthy case other than
        the case itself whose residual is not numerically zero (a noise-free one has no variance).
    """

    key: str
    signal: str
    severities: list
    files: list
    reports: list
    baseline: list
    units: dict = field(default_factory=dict)
    swept: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    baseline_records: list = field(default_factory=list)

    def __post_init__(self):  # a table made without them: no other swept values, every shaft averaged
        self.swept = self.swept or [{} for _ in self.files]
        self.skipped = self.skipped or [{} for _ in self.files]
        self.baseline_records = self.baseline_records or [{} for _ in self.files]

    @property
    def swept_keys(self) -> list[str]:
        """The other swept keys, sorted."""
        return sorted({k for v in self.swept for k in v})

    @property
    def shafts(self) -> list[str]:
        """Shafts present in any case, in first-seen order."""
        return list(dict.fromkeys(s for r in self.reports for s in r))

    def values(self, shaft: str, indicator: str) -> list:
        """The indicator of ``shaft`` in every case (None where absent or undefined)."""
        return [r.get(shaft, {}).get(indicator) for r in self.reports]


class BatchCase(NamedTuple):
    """A finished case of a batch: its severity, result file and other swept values."""

    severity: float
    path: Path
    swept: dict


def batch_cases(batch_dir, key: str) -> list[BatchCase]:
    """Every finished case of a batch directory, by severity and then by its other swept values
    (the repeats of a severity in a stable order, not the case files' hash order).

    Reads ``cases/<key>.json`` (the case's swept values and status) of the batch layout
    (:mod:`flexgear.app.batch`), of the cases that ``summary.csv`` lists: those of the sweep last
    run in the directory, not the files another sweep left there.

    Raises
    ------
    FlexgearError
        No batch directory, no finished case, or ``key`` not among the swept keys.
    """
    d = Path(batch_dir)
    records = sorted((d / "cases").glob("*.json")) if (d / "cases").is_dir() else []
    listed = csv_column(d / "summary.csv", "key")
    if listed is not None:
        listed = set(listed)
        records = [js for js in records if js.stem in listed]
    if not records and (d / "batch.json").is_file():
        raise FlexgearError(f"{str(d)!r}: no case of its batch has finished yet; continue the batch with "
                            f"flexgear batch {str(d / 'sweep.toml')!r} -o {str(d)!r}")
    if not records:
        raise FlexgearError(f"{str(d)!r}: no cases/*.json; not a flexgear batch directory (flexgear batch -o DIR)")
    cases, keys = [], set()
    for js in records:
        try:
            rec = json.loads(js.read_text())
        except (OSError, ValueError):
            continue
        values = rec.get("values", {})
        keys.update(values)
        h5 = js.with_suffix(".h5")
        if rec.get("status") == "done" and key in values and h5.is_file():
            v = values[key]
            if not isinstance(v, (int, float)) or isinstance(v, bool):
                raise ConfigError(f"--severity {key}: the case {js.stem} has the non-numeric value {v!r}")
            cases.append(BatchCase(float(v), h5, {k: x for k, x in values.items() if k != key}))
    if key not in keys:
        raise ConfigError(f"--severity {key!r}: not a swept key of {str(d)!r}; its swept keys: "
                          f"{', '.join(sorted(keys)) or 'none'}")
    if not cases:
        raise FlexgearError(f"{str(d)!r}: no finished case has a result file")
    return sorted(cases, key=lambda c: (c.severity, json.dumps(c.swept, sort_keys=True, default=str)))


def severity_table(batch_dir, key: str, settings: MonitorSettings | None = None,
                   healthy: float | None = None) -> SeverityTable:
    """Indicators of every case of a batch against the swept severity ``key``.

    NA4 of each case is normalised by the residual variances of the healthy cases (severity
    ``healthy``, default the least severity in the batch) other than itself, followed by its own
    (the run-ensemble definition of Zakrajsek et al. 1993 with the healthy cases as the earlier
    records); a healthy case whose residual is numerically zero (a noise-free simulation) has
    no variance to give and is left out.

    Parameters
    ----------
    batch_dir : str or Path
        A ``flexgear batch`` output directory.
    key : str
        The swept key holding the severity, as in the sweep file (``faults.0.depth``).
    settings : MonitorSettings, optional
        Monitoring options (the same signal for every case).
    healthy : float, optional
        Severity of the healthy cases. Default the least one.
    """
    settings = settings or MonitorSettings()
    settings.check()
    cases = batch_cases(batch_dir, key)
    h = cases[0].severity if healthy is None else float(healthy)
    healthy_files = [c.path for c in cases if c.severity == h]
    if not healthy_files:
        raise ConfigError(f"--healthy {h:g}: no case of {key} has this value; values: "
                          f"{', '.join(f'{c.severity:g}' for c in cases)}")
    reports, skipped, used, signal = [], [], [], None
    averaged = {}  # each healthy case's averages, taken once (monitor's baseline_cache)
    given = []  # (case index, category, message) of every warning the cases' analyses gave
    for i, case in enumerate(cases):
        path = case.path
        base = [p for p in healthy_files if p != path]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            rep = monitor(path, settings, baseline=base, skip_empty_baselines=True, baseline_cache=averaged)
        given += [(i, w.category, str(w.message)) for w in caught]
        signal = rep.source.signal_path
        reports.append({name: dict(sa.indicators) for name, sa in rep.shafts.items()})
        skipped.append(dict(rep.skipped))
        used.append(dict(rep.baseline_records))
        units = {k: (rep.source.units or "1") if v.unit == "signal" else v.unit for k, v in INDICATORS.items()}

    for (category, text), which in _said_once(given, cases).items():  # naming the cases by severity
        severities = ", ".join(f"{cases[j].severity:g}" for j in sorted(which))
        warnings.warn(f"{len(which)} of {len(cases)} cases ({key} = {severities}): {text}", category,
                      stacklevel=user_stacklevel())

    def rel(p: Path) -> str:  # as summary.csv names them
        return p.relative_to(Path(batch_dir)).as_posix()

    return SeverityTable(key, signal, [c.severity for c in cases], [rel(c.path) for c in cases], reports,
                         [rel(p) for p in healthy_files], units, [c.swept for c in cases], skipped, used)


def _said_once(given, cases) -> dict:
    """(category, message with its case's file left out) -> the indices of the cases that gave
    it, from (case index, category, message) triples. A warning about a healthy baseline read
    while another case was analysed (``--baseline PATH: ...``) that the baseline's case gives
    itself is that case's, said once (it was charged to the case analysed, with the baseline's
    figures)."""
    own = {(i, c, m) for i, c, m in given}
    said = {}
    for i, category, message in given:
        for j, case in enumerate(cases):
            prefix = f"--baseline {case.path}: "
            if j != i and message.startswith(prefix) and (j, category, message[len(prefix):]) in own:
                break  # the baseline's own warning: said for its case
        else:
            path = cases[i].path
            text = message.replace(f" of {path}", "").replace(str(path), "the case")
            which = said.setdefault((category, text), [])
            if i not in which:
                which.append(i)
    return said


def _cell(v):
    """A swept value as a CSV cell: numbers and text as they are, anything else as JSON."""
    return v if v is None or isinstance(v, (int, float, str)) else json.dumps(v, default=str)


def write_severity(table: SeverityTable, out, overwrite: bool = False) -> list[Path]:
    """Write ``severity.csv``, ``severity.json`` and ``severity.png`` into the directory ``out``."""
    out = Path(out)
    paths = [out / n for n in SEVERITY_FILES]
    check_targets(paths, overwrite)
    names = list(INDICATORS)
    other = table.swept_keys
    cols = ["severity"] + other + ["file"] + [f"{s}_{n}" for s in table.shafts for n in names]
    rows = [{"severity": sev, **{k: _cell(w.get(k)) for k in other}, "file": f,
             **{f"{s}_{n}": r.get(s, {}).get(n) for s in table.shafts for n in names}}
            for sev, w, f, r in zip(table.severities, table.swept, table.files, table.reports)]
    data = {"key": table.key, "signal": table.signal, "baseline": table.baseline,
            "cases": [{"severity": s, "swept": w, "file": f, "indicators": r, "not_averaged": k,
                       "na4_baseline_records": b}
                      for s, w, f, r, k, b in zip(table.severities, table.swept, table.files, table.reports,
                                                  table.skipped, table.baseline_records)],
            "definitions": {k: {"unit": table.units.get(k, v.unit), "on": v.on, "definition": v.definition,
                                "source": v.source} for k, v in INDICATORS.items()}}
    return [_write_text(paths[0], _csv(rows, cols), overwrite),
            _write_text(paths[1], json.dumps(data, indent=1, default=_json_value) + "\n", overwrite),
            save_figure(figures.fig_severity(table), paths[2], overwrite=overwrite)]
