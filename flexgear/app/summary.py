"""The summary table of a batch: one row per case, as CSV and as an array over the sweep's axes.

``summary.csv`` (comma-separated, header line, ``.`` decimal point, empty field = no value)
reads with ``pandas.read_csv`` and MATLAB's ``readtable``; column names use only letters,
digits and ``_``. Columns: ``case`` (index), ``status`` (``done``, ``failed``, ``pending``), the
swept and derived keys (``drive.speed_hz`` as ``drive_speed_hz``), the metrics
(:mod:`flexgear.app.metrics`), ``wall_s`` (seconds the case's run took), ``key`` (the case's
configuration hash), ``file`` (its result, relative to the batch directory) and ``error``
(first line of a failed case's error).

``summary.nc`` (netCDF-4/HDF5, written with xarray) holds the same values as arrays indexed by
the sweep's axes: one dimension per ``[grid]`` key (named as its column, with the swept values
as coordinate), ``zip`` and ``sample`` (index, with the keys as coordinates along it). Open it
with ``xarray.open_dataset`` or MATLAB's ``ncread``; units and descriptions are attributes.
"""
from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

import numpy as np

from .. import __version__
from ..config import key_unit
from ..files import atomic_write_together
from ..errors import FlexgearError
from .metrics import column_name

CASE_COLUMNS = {
    "case": ("1", "case index in the sweep (0-based)"),
    "status": ("", "done, failed or pending"),
}
TAIL_COLUMNS = {
    "wall_s": ("s", "wall time of the case's run (model building, integration, resampling)"),
    "key": ("", "short SHA-256 of the case's full configuration: its file name"),
    "file": ("", "result file, relative to the batch directory"),
    "error": ("", "error of a failed case (first line)"),
}


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if isinstance(v, (int, str)):
        return str(v)
    return json.dumps(v)


def _swept_attrs(key: str) -> dict:
    """netCDF attributes of a swept key's coordinate: its long name and unit (none if unitless)."""
    unit = key_unit(key)
    return {"long_name": f"swept value of {key}", **({"units": unit} if unit else {})}


def _numeric(values) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)


class SummaryTable:
    """Rows of a batch's cases (all of them, in sweep order) and the columns' units and meaning.

    Parameters
    ----------
    sweep : Sweep
        The expanded sweep.
    """

    def __init__(self, sweep):
        self.sweep = sweep
        self.swept = {column_name(k): k for k in sweep.swept_keys}
        self.info: dict[str, tuple[str, str]] = dict(CASE_COLUMNS)
        for col, key in self.swept.items():
            self.info[col] = (key_unit(key), f"swept value of {key} (as written in the configuration)")
        self.info.update(TAIL_COLUMNS)
        self.metric_columns: list[str] = []
        self.rows: list[dict] = []
        self._cells: list[str] = []
        for case in sweep.cases:
            row = {"case": case.index, "status": "pending", "key": case.key, "file": None, "error": None,
                   "wall_s": None, "metrics": {}}
            self.rows.append(row)
        clash = [c for c in self.swept if c in CASE_COLUMNS or c in TAIL_COLUMNS]
        if clash:
            raise FlexgearError(f"swept key(s) {clash} clash with the summary's own columns")

    def set(self, index: int, status: str, metrics=None, columns=None, wall_s=None, error=None, file=None):
        """Record a case's outcome."""
        for col, (unit, desc) in (columns or {}).items():
            if col not in self.info:
                if col in self.swept:
                    raise FlexgearError(f"metric column {col!r} clashes with a swept key's column")
                self.info[col] = (unit, desc)
                self.metric_columns.append(col)
        self.rows[index].update(status=status, metrics=dict(metrics or {}), wall_s=wall_s,
                                error=(error.splitlines()[0] if error else None), file=file)

    def count(self, status: str) -> int:
        """Number of rows with ``status``."""
        return sum(r["status"] == status for r in self.rows)

    @property
    def columns(self) -> list[str]:
        """Column names in table order."""
        return list(CASE_COLUMNS) + list(self.swept) + self.metric_columns + list(TAIL_COLUMNS)

    def records(self) -> list[dict]:
        """One dict per case: column -> value (None where there is none)."""
        out = []
        for case, row in zip(self.sweep.cases, self.rows):
            r = {"case": row["case"], "status": row["status"]}
            r.update({col: case.values[key] for col, key in self.swept.items()})
            r.update({col: row["metrics"].get(col) for col in self.metric_columns})
            r.update({c: row[c] for c in TAIL_COLUMNS})
            out.append(r)
        return out

    def csv_text(self) -> str:
        """The table as CSV text."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        cols = self.columns
        w.writerow(cols)
        for r in self.records():
            w.writerow([_cell(r[c]) for c in cols])
        return buf.getvalue()

    def columns_text(self) -> str:
        """Markdown table of the columns: name, unit, meaning."""
        lines = ["| column | unit | meaning |", "|---|---|---|"]
        lines += [f"| `{c}` | {self.info[c][0] or '-'} | {self.info[c][1]} |" for c in self.columns]
        return "\n".join(lines) + "\n"

    # ------------------------------------------------------------------ array form
    def dataset(self):
        """The table as an ``xarray.Dataset`` over the sweep's axes."""
        import xarray as xr

        sweep = self.sweep
        shape = sweep.shape
        dims = tuple(column_name(a.name) if a.kind == "grid" else a.kind for a in sweep.axes)
        coords = {}
        for dim, axis in zip(dims, sweep.axes):
            if axis.kind == "grid":
                vals = [p[0] for p in axis.points]
                coords[dim] = (dim, np.array(vals if _numeric(vals) else [_cell(v) for v in vals], dtype=None
                                             if _numeric(vals) else object),
                               _swept_attrs(axis.keys[0]))
            else:
                coords[dim] = (dim, np.arange(len(axis)), {"long_name": f"{axis.kind} index"})
                for j, key in enumerate(axis.keys):
                    vals = [p[j] for p in axis.points]
                    arr = np.array(vals, dtype=float) if _numeric(vals) else np.array([_cell(v) for v in vals],
                                                                                         dtype=object)
                    coords[column_name(key)] = (dim, arr, _swept_attrs(key))
        records = self.records()
        data_vars = {}

        def grid(col, numeric):
            vals = [r[col] for r in records]
            if numeric:
                arr = np.array([math.nan if v is None else float(v) for v in vals], dtype=float)
            else:
                arr = np.array(["" if v is None else _cell(v) for v in vals], dtype=object)
            return arr.reshape(shape)

        for col in ["case", "status"] + [c for c in self.swept if c not in coords] + self.metric_columns + \
                list(TAIL_COLUMNS):
            vals = [r[col] for r in records if r[col] is not None]
            numeric = col not in ("status", "key", "file", "error") and _numeric(vals)
            unit, desc = self.info[col]
            attrs = {"long_name": desc}
            if unit:
                attrs["units"] = unit
            data_vars[col] = (dims, grid(col, numeric), attrs)
        data_vars["case"] = (dims, np.arange(len(records)).reshape(shape), {"long_name": CASE_COLUMNS["case"][1]})
        return xr.Dataset(data_vars, coords=coords,
                          attrs={"title": sweep.title, "sweep": sweep.source, "flexgear_version": __version__,
                                 "axes": json.dumps([{"kind": a.kind, "keys": list(a.keys)} for a in sweep.axes])})

    def write_both(self, csv_path, nc_path) -> bool:
        """Write the CSV and the netCDF file from this one state, each atomically, moved into
        place together (:func:`flexgear.files.atomic_write_together`), so that a batch killed at
        any moment leaves two summaries that list the same cases as done. Returns False (and
        writes the CSV alone) when xarray or h5netcdf is missing."""
        text = self.csv_text()
        write_csv = (csv_path, lambda tmp: Path(tmp).write_text(text))
        try:
            import h5netcdf  # noqa: F401 - the engine to_netcdf uses
            ds = self.dataset()
        except ImportError:
            atomic_write_together([write_csv])
            return False
        atomic_write_together([(nc_path, lambda tmp: ds.to_netcdf(tmp, engine="h5netcdf")), write_csv])
        return True
