"""Sweep files: a base configuration and axes over configuration keys, expanded into cases.

A sweep file is TOML::

    title = "speed sweep"            # optional
    base = "spur_pair"               # a preset name or a configuration file (relative to this file)

    [set]                            # fixed overrides for every case
    "simulation.duration" = 0.5

    [grid]                           # full factorial: every combination, in the order written
    "drive.speed_hz" = [5.0, 10.0, 20.0]
    "load.torque" = [100.0, 200.0]

    [zip]                            # lists of equal length varied together (one axis)
    "contact.damping" = [1000.0, 3000.0]
    "contact.penetration_depth" = [0.1, 0.3]

    [sample]                         # random or Latin-hypercube samples (one axis)
    method = "lhs"                   # "lhs" (scipy.stats.qmc.LatinHypercube) or "random"
    n = 16
    seed = 1                         # required: the same seed gives the same cases
    [sample.ranges]
    "drive.speed_hz" = [5.0, 30.0]   # uniform in [min, max]
    "contact.damping" = {min = 300.0, max = 3.0e4, scale = "log"}

    [derived]                        # keys computed for every case, in the order written
    "load.torque" = "20 * drive.speed_hz"                       # an arithmetic expression
    "contact.exponent" = {axis = "drive.speed_hz", values = [1.3, 1.4, 1.5]}  # one per axis value
    "simulation.step" = [2.5e-5, 2.5e-5, 1.25e-5, ...]          # one value per case

Keys are dotted paths into the configuration's TOML tables (``drive.speed_hz`` is
``[drive] speed_hz``); quoted or unquoted dotted keys are the same; a number indexes an array of
tables the base has (``faults.0.depth``: the first ``[[faults]]`` entry's depth). Values are given as in a
configuration file (the ``[contact]`` block in its own units, ``*_deg``, ``*_hz``).

Cases are the outer product of the grid axes (in the order written), then the zip axis, then
the sample axis; case 0 takes the first value of every axis and the last axis varies fastest.
Expressions (:func:`evaluate_expression`) may use numbers, ``+ - * / // % **``, parentheses,
the case's configuration values by dotted path (swept, derived above them, or given in the base
file), ``pi``, ``e`` and the functions ``abs min max sqrt exp log log10 sin cos tan round int
float``. They are parsed with :mod:`ast` and evaluated node by node; nothing else is allowed.

Every case is built as a TOML dictionary (base file, then ``[set]``, the axis values and the
derived keys) and validated by :func:`flexgear.config.parse_config`, exactly as ``flexgear run``
validates a file, before anything runs; an error names the sweep file, the case and its values.
A case is identified by the SHA-256 of its full configuration after defaults
(:func:`flexgear.app.run.resolved_toml`).
"""
from __future__ import annotations

import ast
import copy
import hashlib
import itertools
import math
import operator
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..config import LUMPED_SUFFIX, PRESETS, Config, parse_config, preset_path, ramp_note
from ..errors import ConfigError, FlexgearError

SWEEP_KEYS = ("title", "base", "set", "grid", "zip", "sample", "derived")
SAMPLE_KEYS = ("method", "n", "seed", "ranges")
SAMPLE_METHODS = ("lhs", "random")
KEY_HASH_LENGTH = 12  # hex digits of the configuration hash naming a case's files
DEFAULT_MAX_CASES = 1000  # a larger sweep runs only when asked (--yes, max_cases=None)


class CaseLimitError(ConfigError):
    """A sweep has more cases than the limit (``--max-cases``) and ``--yes`` was not given."""


@dataclass(frozen=True)
class Axis:
    """One dimension of a sweep.

    Attributes
    ----------
    kind : str
        ``"grid"`` (one key), ``"zip"`` or ``"sample"`` (one or more keys varied together).
    name : str
        Dimension name: the key of a grid axis, ``"zip"`` or ``"sample"``.
    keys : tuple of str
        Dotted configuration paths set by this axis.
    points : list of tuple
        For every position along the axis, the values of ``keys``.
    """

    kind: str
    name: str
    keys: tuple[str, ...]
    points: list[tuple]

    def __len__(self) -> int:
        return len(self.points)


@dataclass
class SweepCase:
    """One case of a sweep.

    Attributes
    ----------
    index : int
        Position in the sweep (0-based, C order over the axes).
    position : tuple of int
        Index along every axis.
    values : dict
        Swept and derived values by dotted path, as written into the configuration.
    data : dict
        The case's configuration as a TOML dictionary (what ``parse_config`` validated).
    config : Config
        The validated configuration.
    config_toml : str
        Full configuration after defaults (what the result file stores).
    key : str
        Short SHA-256 of ``config_toml``: the case's file name.
    """

    index: int
    position: tuple[int, ...]
    values: dict
    data: dict
    config: Config = field(repr=False)
    config_toml: str = field(repr=False)
    key: str

    def label(self) -> str:
        """``case 3 (drive.speed_hz = 20.0, load.torque = 100.0)``."""
        return _label(self.index, self.values)


@dataclass
class Sweep:
    """An expanded, validated sweep.

    Attributes
    ----------
    source : str
        The sweep file (or ``"<string>"``).
    title : str
        Title (default: the file name).
    base : str
        The base configuration as given (preset name or path).
    axes : list of Axis
        The dimensions, in case order.
    derived : dict
        Derived keys and their specification (expression, per-axis table or list).
    cases : list of SweepCase
        All cases, ``len(cases) == prod(shape)``.
    text : str
        The sweep file's text.
    warnings : list of str
        Distinct warnings raised while validating the cases.
    """

    source: str
    title: str
    base: str
    axes: list[Axis]
    derived: dict
    cases: list[SweepCase]
    text: str = ""
    warnings: list[str] = field(default_factory=list)

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of points along every axis."""
        return tuple(len(a) for a in self.axes)

    @property
    def swept_keys(self) -> list[str]:
        """Every key a case's values hold: axis keys, then derived keys."""
        return [k for a in self.axes for k in a.keys] + list(self.derived)


# --------------------------------------------------------------------------- helpers

def _short(v) -> str:
    s = repr(v)
    return s if len(s) <= 40 else s[:37] + "..."


def _label(index: int, values: dict) -> str:
    vals = ", ".join(f"{k} = {_short(v)}" for k, v in values.items())
    return f"case {index}" + (f" ({vals})" if vals else "")


def flatten_keys(table: dict, prefix: str = "", leaf_fields=()) -> dict[str, Any]:
    """``{"drive": {"speed_hz": [..]}}`` and ``{"drive.speed_hz": [..]}`` -> ``{"drive.speed_hz": [..]}``.

    Nested tables are followed down to their first non-table value, or to a table with one of
    ``leaf_fields`` (e.g. ``{min = .., max = ..}``), which is a value.
    """
    out: dict[str, Any] = {}
    for k, v in table.items():
        path = f"{prefix}{k}"
        if isinstance(v, dict) and v and not (set(leaf_fields) & set(v)):
            out.update(flatten_keys(v, path + ".", leaf_fields))
        else:
            out[path] = v
    return out


def _index(d: list, part: str, path: str) -> int:
    """The list index a dotted path's ``part`` names (``faults.0.depth``: the first [[faults]]
    entry); KeyError naming the path when it is not one of the list's."""
    if not part.isdigit() or int(part) >= len(d):
        raise KeyError(f"{path}: {part!r} is not an index of the list there (entries 0 to {len(d) - 1}: "
                       "a dotted path indexes an array of tables, e.g. faults.0.depth, and cannot add an entry)")
    return int(part)


def set_path(data: dict, path: str, value) -> None:
    """Set ``data[a][b][c] = value`` for ``path = "a.b.c"``, creating tables on the way (a
    non-table value on the way is replaced by a table). A number indexes an existing array of
    tables: ``faults.0.depth`` is the first ``[[faults]]`` entry's depth."""
    *parents, last = path.split(".")
    d = data
    for j, p in enumerate(parents):
        if isinstance(d, list):
            d = d[_index(d, p, path)]
            continue
        if not isinstance(d.get(p), (dict, list)):
            if (parents + [last])[j + 1].isdigit():
                raise KeyError(f"{path}: the base configuration has no array of tables {'.'.join(parents[:j + 1])!r} "
                               "to index (a dotted path indexes an existing array, e.g. faults.0.depth over a base "
                               "with [[faults]], and cannot add an entry; sweep the whole list instead, e.g. "
                               "faults = [[{...}], ...])")
            d[p] = {}
        d = d[p]
    if isinstance(d, list):
        d[_index(d, last, path)] = copy.deepcopy(value)
    else:
        d[last] = copy.deepcopy(value)


#: keys a case sets that take the place of another key of the base: one or the other, never both
#: (the mesh damping as a coefficient or as a ratio)
REPLACES = {"contact.damping_ratio": "contact.damping", "contact.damping": "contact.damping_ratio"}


def drop_replaced(data: dict, given) -> None:
    """Remove from ``data`` the base's key that a key in ``given`` (the keys a case sets)
    replaces (:data:`REPLACES`), unless the case sets both."""
    for key in given:
        other = REPLACES.get(key)
        if other is None or other in given:
            continue
        *parents, last = other.split(".")
        d = data
        for p in parents:
            d = d.get(p) if isinstance(d, dict) else None
        if isinstance(d, dict):
            d.pop(last, None)


def get_path(data: dict, path: str):
    """``data[a][b][c]`` for ``path = "a.b.c"`` (a number indexes an array of tables); KeyError
    if a part is missing."""
    d = data
    for p in path.split("."):
        if isinstance(d, list):
            d = d[_index(d, p, path)]
        elif not isinstance(d, dict) or p not in d:
            raise KeyError(path)
        else:
            d = d[p]
    return d


def config_key(config_toml: str) -> str:
    """Short SHA-256 (hex) of a full configuration text: the name of a case's files."""
    return hashlib.sha256(config_toml.encode("utf-8")).hexdigest()[:KEY_HASH_LENGTH]


# --------------------------------------------------------------------------- expressions

_BINOPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
           ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod, ast.Pow: operator.pow}
_UNARY = {ast.UAdd: operator.pos, ast.USub: operator.neg}
_FUNCS = {"abs": abs, "min": min, "max": max, "sqrt": math.sqrt, "exp": math.exp, "log": math.log,
          "log10": math.log10, "sin": math.sin, "cos": math.cos, "tan": math.tan, "round": round,
          "int": int, "float": float}
_CONSTS = {"pi": math.pi, "e": math.e}
_MAX_INT = 2**63
_MAX_EXPONENT = 1024


def _dotted(node) -> str | None:
    """``a.b.c`` for a Name/Attribute chain, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
        return ".".join(reversed(parts))
    return None


def evaluate_expression(text: str, lookup) -> float | int:
    """Evaluate a restricted arithmetic expression.

    Parameters
    ----------
    text : str
        E.g. ``"20 * drive.speed_hz"``, ``"sqrt(load.torque) / 2"``.
    lookup : callable(str) -> number
        Value of a dotted name (raises KeyError when unknown).

    Returns
    -------
    int or float

    Raises
    ------
    ValueError
        For syntax outside the allowed subset, unknown names or functions, non-numeric values,
        and arithmetic errors (division by zero, overflow), with the reason.
    """
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ValueError(f"not a valid expression ({exc.msg})") from None

    def num(v, what):
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ValueError(f"{what} = {v!r} is not a number")
        if isinstance(v, int) and abs(v) > _MAX_INT:
            raise ValueError(f"{what}: integer too large")
        return v

    def ev(node):
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant):
            return num(node.value, "constant")
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            a, b = ev(node.left), ev(node.right)
            if isinstance(node.op, ast.Pow) and abs(b) > _MAX_EXPONENT:
                raise ValueError(f"exponent {b!r} too large (at most {_MAX_EXPONENT})")
            return num(_BINOPS[type(node.op)](a, b), "result")
        if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            return _UNARY[type(node.op)](ev(node.operand))
        if isinstance(node, ast.Call):
            name = node.func.id if isinstance(node.func, ast.Name) else None
            if name not in _FUNCS or node.keywords:
                raise ValueError(f"function {ast.unparse(node.func)!r} is not allowed; allowed: "
                                 f"{', '.join(sorted(_FUNCS))}")
            return num(_FUNCS[name](*[ev(a) for a in node.args]), f"{name}(...)")
        name = _dotted(node)
        if name is not None:
            if name in _CONSTS:
                return _CONSTS[name]
            try:
                return num(lookup(name), name)
            except KeyError:
                raise ValueError(f"unknown name {name!r} (a dotted configuration key set in the base "
                                 f"file or the sweep, or one of {', '.join(_CONSTS)})") from None
        raise ValueError(f"{ast.unparse(node)!r}: only numbers, configuration keys, + - * / // % **, "
                         "parentheses and the listed functions are allowed")

    try:
        return ev(tree)
    except (ArithmeticError, TypeError) as exc:
        raise ValueError(f"{type(exc).__name__}: {exc}") from None


# --------------------------------------------------------------------------- reading

def _err(source: str, msg: str) -> ConfigError:
    return ConfigError(f"{source}: {msg}")


def _axis_list(source, section, key, value) -> list:
    if not isinstance(value, list):
        raise _err(source, f"[{section}] {key} = {_short(value)}: an axis must be a list of values")
    if not value:
        raise _err(source, f"[{section}] {key} = []: an axis needs at least one value")
    return value


def _read_base(base, directory: Path, source: str) -> dict:
    if not isinstance(base, str) or not base:
        raise _err(source, f"base = {base!r}: must be a preset name ({', '.join(PRESETS)}) or a "
                           "configuration file")
    p = Path(base)
    if not p.is_absolute():
        p = directory / p
    if not p.exists() and base.endswith(LUMPED_SUFFIX):  # its lumped model, as load_config reads it
        data = _read_base(base[:-len(LUMPED_SUFFIX)], directory, source)
        return data | {"model": "lumped"}
    if not p.exists():
        if base in PRESETS:
            p = preset_path(base)
        else:
            raise _err(source, f"base = {base!r}: no such file (relative to {str(directory)!r}) "
                               f"and not a preset ({', '.join(PRESETS)}; either optionally with "
                               f"{LUMPED_SUFFIX!r})")
    try:
        return tomllib.loads(p.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise _err(source, f"base file {str(p)!r} is not valid TOML: {exc}") from None


def _sample_axis(source: str, spec) -> Axis | None:
    if not isinstance(spec, dict):
        raise _err(source, "[sample] must be a table (method, n, seed, [sample.ranges])")
    unknown = sorted(set(spec) - set(SAMPLE_KEYS))
    if unknown:
        raise _err(source, f"unknown key(s) {', '.join('sample.' + k for k in unknown)}; allowed in "
                           f"[sample]: {', '.join(SAMPLE_KEYS)}")
    method = spec.get("method", "lhs")
    if method not in SAMPLE_METHODS:
        raise _err(source, f"sample.method = {method!r}: must be one of {', '.join(SAMPLE_METHODS)}")
    n = spec.get("n")
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise _err(source, f"sample.n = {n!r}: must be an integer >= 1")
    seed = spec.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise _err(source, f"sample.seed = {seed!r}: must be given, an integer >= 0 (the same seed "
                           "gives the same cases)")
    ranges = spec.get("ranges", {})
    ranges = flatten_keys(ranges, leaf_fields=("min", "max", "scale")) if isinstance(ranges, dict) else None
    if not ranges:
        raise _err(source, "[sample.ranges] must give at least one key = [min, max]")
    bounds = []
    for key, r in ranges.items():
        where = f"sample.ranges.{key} = {_short(r)}"
        scale = "linear"
        if isinstance(r, dict):
            bad = sorted(set(r) - {"min", "max", "scale"})
            if bad:
                raise _err(source, f"{where}: unknown field(s) {', '.join(bad)}; allowed: min, max, scale")
            lo, hi, scale = r.get("min"), r.get("max"), r.get("scale", "linear")
        elif isinstance(r, list) and len(r) == 2:
            lo, hi = r
        else:
            raise _err(source, f"{where}: must be [min, max] or {{min = .., max = .., scale = \"log\"}}")
        for v in (lo, hi):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise _err(source, f"{where}: min and max must be finite numbers")
        if not lo < hi:
            raise _err(source, f"{where}: min must be < max")
        if scale not in ("linear", "log"):
            raise _err(source, f"{where}: scale must be 'linear' or 'log'")
        if scale == "log" and not lo > 0:
            raise _err(source, f"{where}: a log scale needs min > 0")
        bounds.append((float(lo), float(hi), scale))
    u = unit_samples(method, n, len(bounds), seed)
    points = []
    for row in u:
        vals = []
        for x, (lo, hi, scale) in zip(row, bounds):
            if scale == "log":
                vals.append(float(math.exp(math.log(lo) + x * (math.log(hi) - math.log(lo)))))
            else:
                vals.append(float(lo + x * (hi - lo)))
        points.append(tuple(vals))
    return Axis("sample", "sample", tuple(ranges), points)


def unit_samples(method: str, n: int, d: int, seed: int) -> np.ndarray:
    """``n`` points in the unit cube [0, 1)^d: Latin hypercube (scipy.stats.qmc) or uniform
    random (numpy default_rng), reproducible from ``seed``."""
    if method == "random":
        return np.random.default_rng(seed).random((n, d))
    from scipy.stats import qmc

    try:
        engine = qmc.LatinHypercube(d=d, rng=seed)
    except TypeError:  # scipy < 1.15
        engine = qmc.LatinHypercube(d=d, seed=seed)
    return engine.random(n)


def read_sweep(path, max_cases: int | None = None, progress=None) -> Sweep:
    """Read, expand and validate a sweep file (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The sweep file.
    max_cases : int or None
        Raise :class:`CaseLimitError` (before building any case) when the sweep has more cases.
    progress : callable(done, total), optional
        Called after each case is validated (a large sweep takes a while).
    """
    plan = open_sweep(path, max_cases=max_cases)
    cases = []
    for case in plan.cases():
        cases.append(case)
        if progress is not None:
            progress(len(cases), plan.n_cases)
    return plan.sweep(cases)


def open_sweep(path, max_cases: int | None = None) -> SweepPlan:
    """Read a sweep file and check its form, without building any case: the number of cases and
    the axes are known at once, the cases are built and validated one by one by
    :meth:`SweepPlan.cases` (``flexgear batch --dry-run`` lists them as they come)."""
    p = Path(path)
    if not p.exists():
        raise ConfigError(f"sweep file {str(path)!r} not found")
    return plan_sweep(p.read_text(), source=str(p), directory=p.parent, max_cases=max_cases)


def loads_sweep(text: str, source: str = "<string>", directory=".", max_cases: int | None = None) -> Sweep:
    """Expand and validate a sweep given as TOML text; relative ``base`` paths are taken from
    ``directory``; see :func:`read_sweep`."""
    plan = plan_sweep(text, source, directory, max_cases)
    return plan.sweep(list(plan.cases()))


@dataclass
class SweepPlan:
    """A sweep file read and checked, its cases not yet built (:func:`open_sweep`)."""

    source: str
    title: str
    base_name: Any
    base: dict
    fixed: dict
    axes: list[Axis]
    derived: dict
    text: str
    warnings: list[str] = field(default_factory=list)

    @property
    def n_cases(self) -> int:
        return math.prod(len(a) for a in self.axes)

    def cases(self):
        """Build and validate the cases one by one, in order (a generator); the warnings they
        raise collect in :attr:`warnings`, each once."""
        return _iter_cases(self)

    def sweep(self, cases: list) -> Sweep:
        """The :class:`Sweep` of these (all) cases."""
        return Sweep(source=self.source, title=self.title, base=str(self.base_name), axes=self.axes,
                     derived=self.derived, cases=cases, text=self.text, warnings=self.warnings)


def plan_sweep(text: str, source: str = "<string>", directory=".", max_cases: int | None = None) -> SweepPlan:
    """Check a sweep given as TOML text (see :func:`open_sweep`)."""
    try:
        spec = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: not valid TOML: {exc}") from None
    unknown = sorted(set(spec) - set(SWEEP_KEYS))
    if unknown:
        raise _err(source, f"unknown top-level key(s) {', '.join(map(repr, unknown))}; allowed: "
                           f"{', '.join(SWEEP_KEYS)}")
    for sec in ("set", "grid", "zip", "sample", "derived"):
        if sec in spec and not isinstance(spec[sec], dict):
            raise _err(source, f"[{sec}] must be a table")
    base = _read_base(spec.get("base"), Path(directory), source)
    title = spec.get("title", Path(source).stem)
    if not isinstance(title, str):
        raise _err(source, f"title = {title!r}: must be a string")
    fixed = flatten_keys(spec.get("set", {}))
    axes = []
    for key, values in flatten_keys(spec.get("grid", {})).items():
        axes.append(Axis("grid", key, (key,), [(v,) for v in _axis_list(source, "grid", key, values)]))
    zipped = flatten_keys(spec.get("zip", {}))
    if zipped:
        lists = {k: _axis_list(source, "zip", k, v) for k, v in zipped.items()}
        lengths = {k: len(v) for k, v in lists.items()}
        if len(set(lengths.values())) > 1:
            raise _err(source, "[zip] lists must have equal lengths: "
                               + ", ".join(f"{k} has {n}" for k, n in lengths.items()))
        axes.append(Axis("zip", "zip", tuple(lists), list(zip(*lists.values()))))
    if "sample" in spec:
        axes.append(_sample_axis(source, spec["sample"]))
    derived = flatten_keys(spec.get("derived", {}), leaf_fields=("axis", "values"))
    seen: dict[str, str] = {}
    for where, keys in ([("[set]", list(fixed))] + [(f"[{a.kind}]", list(a.keys)) for a in axes]
                        + [("[derived]", list(derived))]):
        for k in keys:
            if k in seen:
                raise _err(source, f"{k!r} is given twice ({seen[k]} and {where}); give each key once")
            seen[k] = where
    n_cases = math.prod(len(a) for a in axes)
    if max_cases is not None and n_cases > max_cases:
        raise CaseLimitError(f"{source}: the sweep has {n_cases} cases, more than the limit of {max_cases}; "
                             "pass --yes to run them all (or raise --max-cases)")
    for key, d in derived.items():
        _check_derived(source, key, d, axes, n_cases)
    return SweepPlan(source, title, spec.get("base"), base, fixed, axes, derived, text)


def _check_derived(source, key, d, axes, n_cases):
    where = f"[derived] {key} = {_short(d)}"
    if isinstance(d, str):
        return
    if isinstance(d, list):
        if len(d) != n_cases:
            raise _err(source, f"{where}: a list gives one value per case; the sweep has {n_cases} "
                               f"case(s), the list {len(d)} value(s)")
        return
    if isinstance(d, dict):
        bad = sorted(set(d) - {"axis", "values"})
        if bad or "axis" not in d or "values" not in d:
            raise _err(source, f"{where}: a table needs exactly axis = \"<swept key>\" and values = [...]")
        ax = [a for a in axes if d["axis"] in a.keys and a.kind in ("grid", "zip")]
        if not ax:
            raise _err(source, f"{where}: axis {d['axis']!r} is not a [grid] or [zip] key of this sweep")
        if not isinstance(d["values"], list) or len(d["values"]) != len(ax[0]):
            n = len(d["values"]) if isinstance(d["values"], list) else "no list of"
            raise _err(source, f"{where}: needs one value per point of axis {d['axis']!r} "
                               f"({len(ax[0])}), got {n} values")
        return
    raise _err(source, f"{where}: must be an expression (string), a list with one value per case, or "
                       "{axis = \"<key>\", values = [...]}")


def _iter_cases(plan: SweepPlan):
    from .run import resolved_toml  # with the solver: not needed to read and size a sweep

    source, base, fixed, axes, derived = plan.source, plan.base, plan.fixed, plan.axes, plan.derived
    by_key: dict[str, str] = {}  # configuration key -> label of the case that has it
    messages = plan.warnings
    for index, position in enumerate(itertools.product(*(range(len(a)) for a in axes))):
        values = {}
        for a, i in zip(axes, position):
            values.update(zip(a.keys, a.points[i]))
        data = copy.deepcopy(base)
        label = _label(index, values)
        try:
            for k, v in itertools.chain(fixed.items(), values.items()):
                set_path(data, k, v)
        except KeyError as exc:
            raise _err(source, f"{label}: {exc.args[0]}") from None
        drop_replaced(data, set(flatten_keys(fixed)) | set(flatten_keys(values)))
        for key, d in derived.items():
            try:
                v = _derived_value(d, data, axes, position, index)
            except ValueError as exc:
                raise _err(source, f"{label}: [derived] {key} = {_short(d)}: {exc}") from None
            values[key] = v
            set_path(data, key, v)
        label = _label(index, values)
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                cfg = parse_config(copy.deepcopy(data), source=f"{source} {label}")
                if cfg.kind == "planetary":
                    from ..dynamics.model.assembly import check_planetary

                    check_planetary(cfg)
        except FlexgearError as exc:
            raise _err(source, f"{label}: {exc}") from None
        for w in [str(w.message) for w in caught] + [ramp_note(cfg)]:
            if w and w not in messages:
                messages.append(w)
        text_cfg = resolved_toml(cfg)
        case = SweepCase(index, position, values, data, cfg, text_cfg, config_key(text_cfg))
        if case.key in by_key:
            raise _err(source, f"{case.label()} and {by_key[case.key]} have the same configuration; "
                               "every case must differ")
        by_key[case.key] = case.label()
        yield case


def _derived_value(d, data, axes, position, index):
    if isinstance(d, str):
        return evaluate_expression(d, lambda name: get_path(data, name))
    if isinstance(d, list):
        return d[index]
    for a, i in zip(axes, position):
        if d["axis"] in a.keys:
            return d["values"][i]
    raise ValueError(f"axis {d['axis']!r} not found")
