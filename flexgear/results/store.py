"""Simulation results in memory (:class:`Result`) and on disk (HDF5, via h5py).

The solver fills a :class:`Result`; :func:`save` writes it to an HDF5 file and :func:`load`
(also ``flexgear.load``) reads it back bit for bit. The file holds only plain numeric datasets
(SI, each with ``units`` and ``description`` attributes) and scalar/array attributes, so MATLAB
(``h5read``, which reverses the dimension order), h5py or any HDF5 tool reads it without
flexgear. Nested dictionary attributes are flattened to ``parent.child`` names; the attribute
``_flexgear_types`` (JSON) records what rebuilds Python booleans, lists, tuples, nested dicts
and ``None`` exactly. Datasets of 4096 or more elements are gzip-compressed. The datasets,
attributes and layout versions (``layout_version`` 5; older layouts are read with the newer
fields ``None``) are listed on the documentation page *Result file layout*.
"""
from __future__ import annotations

import json
import os
import re
import tempfile
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FlexgearError, ResultExistsError
from ..files import default_file_mode

__all__ = [
    "LAYOUT_VERSION",
    "MeshSignals",
    "BodySignals",
    "SensorSignals",
    "Result",
    "save",
    "load",
    "validate",
]

#: Version of the HDF5 layout written by :func:`save`; :func:`load` reads versions <= this.
LAYOUT_VERSION = 5

_TYPES_ATTR = "_flexgear_types"

# (units, description) of every dataset; the description may contain {a}/{b} (mesh bodies).
_TIME_META = ("s", "output time; first sample = end of run-in")
_MESH_META: dict[str, tuple[str, str]] = {
    "normal_force": ("N", "normal tooth force of the mesh, summed over tooth pairs (magnitude)"),
    "force_global": ("N", "x, y (y vertical) components, global frame, of the force exerted "
                          "by {a} on {b}"),
    "pair_force": ("N", "normal force per tooth-pair contact slot (0 for an empty slot)"),
    "pair_tooth_a": ("1", "tooth index on {a} in each contact slot, -1 = empty slot"),
    "pair_tooth_b": ("1", "tooth index on {b} in each contact slot, -1 = empty slot"),
    "pair_side": ("1", "flank side of the tooth on {a} (+1/-1, see flexgear.geometry), "
                       "0 = empty slot"),
    "penetration": ("m", "penetration of the tooth pair in each contact slot"),
    "pair_deflection": ("m", "elastic flank deflection of both gears in each contact slot (flexible gears)"),
    "friction_force": ("N", "tooth friction force of {a} on {b} along the flank tangent t, summed over the tooth "
                            "pairs, each with the sign of its sliding_speed"),
    "friction_power": ("W", "power dissipated by the mesh's tooth friction (anti-aliased like every output: may dip a "
                           "little below 0 next to a sharp change)"),
    "sliding_speed": ("m/s", "sliding speed t . (V_{a} - V_{b}) of each tooth pair on the path of contact (lumped) "
                             "or contact slot (rigid) (nan: no pair), instantaneous; t = (-n_y, n_x), n the normal "
                             "of the contact force on {a}"),
    "pair_friction_force": ("N", "tooth friction force of {a} on {b} along the flank tangent in each slot of "
                                 "sliding_speed (0: no pair), instantaneous"),
    "contact_position": ("m", "contact position of each tooth pair along the line of action from the pitch point, "
                              "positive towards the tip of {a} (nan: no pair), instantaneous"),
    "damping_power": ("W", "power dissipated by the squeeze films of the mesh's contacts"),
    "pair_damping_force": ("N", "squeeze-film damping force along the normal (of {a} on {b}, positive pushing them "
                                "apart) in each contact slot of pair_force (0: empty slot), instantaneous"),
    "film_central": ("m", "central EHL film thickness (Dowson & Toyoda 1979) of the contact in each slot of "
                          "sliding_speed (nan: no loaded contact, or one off the involutes: a tip corner), "
                          "instantaneous"),
    "film_minimum": ("m", "minimum EHL film thickness (Dowson & Higginson 1977) of the contact in each slot of "
                          "sliding_speed (nan: no loaded contact, or one off the involutes: a tip corner), "
                          "instantaneous"),
    "film_ratio": ("1", "film thickness ratio lambda = film_minimum / composite RMS roughness in each slot of "
                        "sliding_speed (nan: no loaded contact, one off the involutes or no roughness), "
                        "instantaneous"),
}
#: descriptions of a lumped result's pair datasets, whose slots are the pairs along the path of
#: contact, not numbered teeth
_LUMPED_META = dict.fromkeys(("pair_tooth_a", "pair_tooth_b"), "0 in a loaded slot, -1 = empty slot: the lumped "
                             "model numbers no teeth (its slot j is the j-th pair along the path of contact)")
_BODY_META: dict[str, tuple[str, str]] = {
    "position": ("m", "centre x, y in the global frame"),
    "angle": ("rad", "rotation angle, unwrapped, counter-clockwise positive"),
    "velocity": ("m/s", "centre velocity x, y in the global frame"),
    "angular_velocity": ("rad/s", "angular velocity, counter-clockwise positive"),
    "torque": ("N m", "drive (reaction) torque of the prescribed rotation"),
    "modal_coordinates": ("sqrt(kg) m", "mass-normalised modal coordinates of the modes integrated in the solver "
                          "(attribute mode_frequencies of the body, Hz)"),
    "condensed_coordinates": ("sqrt(kg) m", "mass-normalised modal coordinates of the condensed modes at the output "
                              "instants, instantaneous (attribute condensed_frequencies of the body, Hz)"),
}
_RESERVED_ROOT = {"layout_version", "config_toml", _TYPES_ATTR}
_RESERVED_MESH = {"name", "body_a", "body_b", _TYPES_ATTR}
_RESERVED_BODY = {"name", _TYPES_ATTR}
_RESERVED_SENSOR = {_TYPES_ATTR}
_RESERVED_SIGNAL = {"units", "description", _TYPES_ATTR}
_COMPRESS_MIN = 4096  # compress datasets with at least this many elements (gzip, lossless)


class _Equal:
    """Equality of the signal containers: the same type and fields, arrays equal element by
    element (nan equal to nan), so that ``r1 == r2`` compares two results (unhashable, as
    mutable containers are)."""

    __hash__ = None

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        nan = a.dtype.kind in "fc" and b.dtype.kind in "fc"
        return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=nan))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return bool(a == b)


@dataclass(eq=False)
class MeshSignals(_Equal):
    """Output signals of one gear mesh (n output samples, K tooth-pair contact slots).

        Parameters
        ----------
        name : str
            Mesh name containing both body names, e.g. ``"sun-planet1"``, ``"pinion-wheel"``.
        body_a, body_b : str
            Names of the two bodies; forces are those exerted by ``body_a`` on ``body_b``.
        normal_force : ndarray, shape (n,)
            Normal tooth force summed over tooth pairs (magnitude) [N].
        force_global : ndarray, shape (n, 2)
            x, y (y vertical) global components of the force of ``body_a`` on ``body_b`` [N].
        pair_force : ndarray, shape (n, K)
            Normal force per tooth-pair contact slot [N].
        pair_tooth_a, pair_tooth_b : ndarray of int, shape (n, K)
            Tooth index on ``body_a`` / ``body_b`` in each slot, -1 for an empty slot.
        pair_side : ndarray of int8, shape (n, K)
            Flank side (+1/-1, see :mod:`flexgear.gears.geometry`) of the tooth on ``body_a``, 0 = empty.
        penetration : ndarray, shape (n, K)
            Penetration of each slot's tooth pair [m] (flexible mesh: overlap of the rigid outlines).
        pair_deflection : ndarray, shape (n, K), or None
            Elastic flank deflection of both gears in each slot [m] (meshes with a flexible gear).
        friction_force : ndarray, shape (n,), or None
            Tooth friction force of the mesh [N], summed over its tooth pairs: the force of
            ``body_a`` on ``body_b`` along the flank tangent t, each pair's with the sign of its
            sliding speed (it changes sign at the pitch point). None: frictionless run.
        friction_power : ndarray, shape (n,), or None
            Power the mesh's tooth friction dissipates [W] (>= 0).
        sliding_speed : ndarray, shape (n, P), or None
            Sliding speed of each tooth pair [m/s] (lumped: slot j the j-th pair from the start of
            the path of contact; rigid: the contact slots of ``pair_force``; nan: no pair),
            instantaneous at the output instants.
        contact_position : ndarray, shape (n, P), or None
            Position of each of those pairs along the line of action [m], from the pitch point,
            positive towards the tip of ``body_a``'s gear (nan: no pair).
        pair_friction_force : ndarray, shape (n, P), or None
            Friction force of each of those pairs [N] (as ``friction_force``; 0: no pair). The
            rigid model's slots are its contact slots (as ``pair_force``), the lumped model's
            the pairs on the path of contact.
        film_central, film_minimum : ndarray, shape (n, P), or None
            Central and minimum EHL film thickness [m] of the contact in each of those slots
            (:mod:`flexgear.results.film`; nan: no loaded contact). None: no friction outputs,
            or no lubricant configured.
        film_ratio : ndarray, shape (n, P), or None
            Film thickness ratio lambda = ``film_minimum`` / composite RMS roughness [-] (nan:
            no loaded contact or no roughness configured).
        damping_power : ndarray, shape (n,), or None
            Power the squeeze films of the mesh's contacts dissipate [W] (rigid, flexible and lumped runs with
            ``[lubrication] damping = "squeeze_film"``; None otherwise).
        pair_damping_force : ndarray, shape (n, K), or None
            Squeeze-film damping force of each contact slot of ``pair_force`` along the normal
            [N], part of ``pair_force`` (0: empty slot); as ``damping_power``.
        attrs : dict
            Mesh data, e.g. ``z_a``, ``z_b``, ``kind``, contact parameters (SI).
    """

    name: str
    body_a: str
    body_b: str
    normal_force: np.ndarray
    force_global: np.ndarray
    pair_force: np.ndarray
    pair_tooth_a: np.ndarray
    pair_tooth_b: np.ndarray
    pair_side: np.ndarray
    penetration: np.ndarray
    attrs: dict = field(default_factory=dict)
    pair_deflection: np.ndarray | None = None
    friction_force: np.ndarray | None = None
    friction_power: np.ndarray | None = None
    sliding_speed: np.ndarray | None = None
    contact_position: np.ndarray | None = None
    pair_friction_force: np.ndarray | None = None
    film_central: np.ndarray | None = None
    film_minimum: np.ndarray | None = None
    film_ratio: np.ndarray | None = None
    damping_power: np.ndarray | None = None
    pair_damping_force: np.ndarray | None = None


@dataclass(eq=False)
class BodySignals(_Equal):
    """Output signals of one rigid body (n output samples).

        Parameters
        ----------
        name : str
            Body name (``"sun"``, ``"carrier"``, ``"planet1"``, ``"ring"``, ``"pinion"``, ...).
        position, velocity : ndarray, shape (n, 2)
            Centre in the global frame [m] and its velocity [m/s].
        angle, angular_velocity : ndarray, shape (n,)
            Rotation angle, unwrapped [rad], and angular velocity [rad/s], counter-clockwise positive.
        torque : ndarray, shape (n,), or None
            Drive (reaction) torque for a body with prescribed rotation [N m], else None.
        attrs : dict
            Body data, e.g. ``mass`` [kg], ``inertia`` [kg m^2], ``z``, ``role``,
            ``mode_frequencies`` and ``condensed_frequencies`` [Hz] of a flexible body.
        modal_coordinates : ndarray, shape (n, m), or None
            Mass-normalised modal coordinates integrated in the solver [sqrt(kg) m].
        condensed_coordinates : ndarray, shape (n, nq), or None
            Coordinates of the condensed modes [sqrt(kg) m], instantaneous samples at the output
            instants (as the pair slots).
    """

    name: str
    position: np.ndarray
    angle: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    torque: np.ndarray | None
    attrs: dict = field(default_factory=dict)
    modal_coordinates: np.ndarray | None = None
    condensed_coordinates: np.ndarray | None = None


@dataclass(eq=False)
class SensorSignals(_Equal):
    """One sensor's signals, one per path model (n output samples).

    Attributes
    ----------
    name : str
    attrs : dict
        The sensor's definition (:meth:`flexgear.gears.housing.Sensor.definition`).
    signals : dict[str, ndarray (n,)]
        Path model name (``housing_path``, ``planet_pass``) -> signal [``signal_attrs[..]["units"]``].
    signal_attrs : dict[str, dict]
        Path model name -> ``units``, ``description`` and the path model's parameters.
    """

    name: str
    attrs: dict
    signals: dict = field(default_factory=dict)
    signal_attrs: dict = field(default_factory=dict)


@dataclass(eq=False)
class Result(_Equal):
    """A simulation result: output time, mesh and body signals, input and run data.

    Parameters
    ----------
    time : ndarray, shape (n,)
        Output time [s]; the first sample is the end of the run-in.
    meshes : dict[str, MeshSignals]
        Mesh signals by mesh name.
    bodies : dict[str, BodySignals]
        Body signals by body name.
    config_toml : str
        Full input (after defaults) as TOML text.
    attrs : dict
        Run data: ``input_frequency``, ``carrier_frequency`` (0 for fixed-axis sets),
        ``mesh_frequency``, ``output_rate`` [Hz], ``run_in``, ``step`` [s], solver statistics,
        ``flexgear_version``, ...
    sensors : dict[str, SensorSignals]
        Sensor signals by sensor name (runs with ``[[sensors]]``; empty otherwise).
    housing_loads : dict[str, ndarray]
        The loads the gear set puts on the housing that drove the sensors' housing path, by
        channel (``sun.x``, ..., ``ring.moment``) [N, N m] (empty otherwise).
    faults : dict or None
        The configured faults and errors (layout 5, ``/faults``): ``record`` (JSON text of
        :func:`flexgear.gears.faults.fault_record` of each, SI), ``labels`` and ``frequency_hz``
        (the characteristic frequency [Hz] of each fault and error); None for perfect gears.
    """

    time: np.ndarray
    meshes: dict[str, MeshSignals]
    bodies: dict[str, BodySignals]
    config_toml: str
    attrs: dict = field(default_factory=dict)
    sensors: dict = field(default_factory=dict)
    housing_loads: dict = field(default_factory=dict)
    faults: dict | None = None

    def __repr__(self) -> str:
        """A summary (the whole arrays would run to thousands of lines in a notebook)."""
        t, a = np.asarray(self.time), self.attrs
        span = f"{t.size} samples, {t[0]:.6g} to {t[-1]:.6g} s" if t.size else "no samples"
        more = f", sensors {list(self.sensors)}" if self.sensors else ""
        if self.faults:
            more += f", faults {list(np.atleast_1d(self.faults.get('labels', [])))}"
        return (f"<Result {a.get('title', '')!r}: {a.get('model', '?')} {a.get('kind', '')}, {span} at "
                f"{a.get('output_rate', float('nan')):.6g} Hz, meshes {list(self.meshes)}, bodies "
                f"{list(self.bodies)}{more}>")

    @property
    def fs(self) -> float:
        """Sampling rate [Hz] of the output, ``(n - 1) / (time[-1] - time[0])``."""
        t = np.asarray(self.time, dtype=float)
        if t.ndim != 1 or t.size < 2 or not t[-1] > t[0]:
            raise ValueError(
                f"Result.fs: time must be increasing with at least 2 samples, got shape "
                f"{t.shape}" + (f" from {t[0]} s to {t[-1]} s" if t.size else ""))
        return float((t.size - 1) / (t[-1] - t[0]))


# --------------------------------------------------------------------------- validation

def _check_array(where: str, a: Any, shape: tuple) -> np.ndarray:
    """Return ``a`` as ndarray after checking its shape (``None`` in ``shape`` = any)."""
    arr = np.asarray(a)
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{where}: expected a numeric array, got dtype {arr.dtype}")
    if arr.ndim != len(shape) or any(s is not None and s != d for s, d in zip(shape, arr.shape)):
        want = "(" + ", ".join("*" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{where}: expected shape {want}, got {arr.shape}")
    return arr


def _check_name(kind: str, key: str, name: str) -> None:
    if not isinstance(name, str) or not name or "/" in name or name in (".", ".."):
        raise ValueError(f"{kind} name {name!r}: must be a non-empty string without '/'")
    if key != name:
        raise ValueError(f"{kind} stored under key {key!r} has name {name!r}; they must match")


def validate(result: Result) -> None:
    """Check that all arrays of ``result`` have consistent shapes and the names are valid.

    Parameters
    ----------
    result : Result
        The result to check.

    Raises
    ------
    ValueError
        Naming the offending field, its shape and the expected shape.
    """
    t = _check_array("time", result.time, (None,))
    n = t.size
    if not isinstance(result.config_toml, str):
        raise ValueError(f"config_toml: expected str, got {type(result.config_toml).__name__}")
    for key, m in result.meshes.items():
        _check_name("mesh", key, m.name)
        w = f"meshes[{key!r}]"
        _check_array(f"{w}.normal_force", m.normal_force, (n,))
        _check_array(f"{w}.force_global", m.force_global, (n, 2))
        k = _check_array(f"{w}.pair_force", m.pair_force, (n, None)).shape[1]
        for f in ("pair_tooth_a", "pair_tooth_b", "pair_side", "penetration", "pair_deflection"):
            if f == "pair_deflection" and m.pair_deflection is None:
                continue
            arr = _check_array(f"{w}.{f}", getattr(m, f), (n, k))
            if f not in ("penetration", "pair_deflection") and arr.dtype.kind not in "iu":
                raise ValueError(f"{w}.{f}: expected an integer array, got dtype {arr.dtype}")
        for f in ("friction_force", "friction_power", "damping_power"):
            if getattr(m, f) is not None:
                _check_array(f"{w}.{f}", getattr(m, f), (n,))
        if m.pair_damping_force is not None:
            _check_array(f"{w}.pair_damping_force", m.pair_damping_force, (n, k))
        if m.sliding_speed is not None:
            p = _check_array(f"{w}.sliding_speed", m.sliding_speed, (n, None)).shape[1]
            _check_array(f"{w}.contact_position", m.contact_position, (n, p))
            if m.pair_friction_force is not None:
                _check_array(f"{w}.pair_friction_force", m.pair_friction_force, (n, p))
            for f in ("film_central", "film_minimum", "film_ratio"):
                if getattr(m, f) is not None:
                    _check_array(f"{w}.{f}", getattr(m, f), (n, p))
    for key, b in result.bodies.items():
        _check_name("body", key, b.name)
        w = f"bodies[{key!r}]"
        _check_array(f"{w}.position", b.position, (n, 2))
        _check_array(f"{w}.angle", b.angle, (n,))
        _check_array(f"{w}.velocity", b.velocity, (n, 2))
        _check_array(f"{w}.angular_velocity", b.angular_velocity, (n,))
        if b.torque is not None:
            _check_array(f"{w}.torque", b.torque, (n,))
        if b.modal_coordinates is not None:
            _check_array(f"{w}.modal_coordinates", b.modal_coordinates, (n, None))
        if b.condensed_coordinates is not None:
            _check_array(f"{w}.condensed_coordinates", b.condensed_coordinates, (n, None))
    for key, v in result.housing_loads.items():
        _check_name("housing load", key, key)
        _check_array(f"housing_loads[{key!r}]", v, (n,))
    for key, s in result.sensors.items():
        _check_name("sensor", key, s.name)
        for f, values in s.signals.items():
            _check_name("sensor signal", f, f)
            _check_array(f"sensors[{key!r}].signals[{f!r}]", values, (n,))
            if not {"units", "description"} <= set(s.signal_attrs.get(f, {})):
                raise ValueError(f"sensors[{key!r}].signal_attrs[{f!r}]: needs 'units' and 'description'")


# --------------------------------------------------------------------------- attributes

def _write_attrs(obj, attrs: dict, reserved: set, where: str) -> None:
    """Write a (possibly nested) dict as HDF5 attributes of ``obj``, type-preserving."""
    import h5py

    types: dict[str, str] = {}

    def put(prefix: str, d: dict) -> None:
        for key, value in d.items():
            if not isinstance(key, str) or not key or "/" in key or "." in key:
                raise ValueError(f"{where}: attribute name {key!r} must be a non-empty str "
                                 f"without '/' or '.'")
            name = prefix + key
            if name in reserved:
                raise ValueError(f"{where}: attribute name {name!r} is reserved by the result "
                                 f"layout (reserved: {sorted(reserved)})")
            if isinstance(value, dict):
                types[name] = "dict"
                put(name + ".", value)
                continue
            if value is None:
                types[name] = "none"
                obj.attrs[name] = h5py.Empty("f8")
                continue
            if isinstance(value, (list, tuple)):
                types[name] = type(value).__name__
                flat = np.asarray(value, dtype=object).ravel()
                if any(isinstance(v, str) for v in flat) and not all(
                        isinstance(v, str) for v in flat):
                    raise ValueError(f"{where}: attribute {name!r} mixes strings and other "
                                     f"values; HDF5 attributes need one type")
                value = np.asarray(value)
            if isinstance(value, str):
                obj.attrs.create(name, data=value, dtype=_str_dtype())
            elif isinstance(value, (bool, np.bool_)):
                types[name] = "bool"
                obj.attrs[name] = np.int8(bool(value))
            elif isinstance(value, int):
                obj.attrs[name] = np.int64(value)
            elif isinstance(value, float):
                obj.attrs[name] = np.float64(value)
            else:
                arr = np.asarray(value)
                if arr.dtype.kind == "U":
                    obj.attrs.create(name, data=arr.astype(object), dtype=_str_dtype())
                elif arr.dtype.kind in "biufc":
                    obj.attrs[name] = arr if arr.ndim else arr[()]
                else:
                    raise ValueError(
                        f"{where}: attribute {name!r} has unsupported type "
                        f"{type(value).__name__} (use numbers, strings, lists/arrays of them, "
                        f"dicts or None)")

    put("", attrs)
    if types:
        obj.attrs.create(_TYPES_ATTR, data=json.dumps(types, sort_keys=True), dtype=_str_dtype())


def _py(value):
    """Convert an attribute value read by h5py to the Python/numpy value that was written."""
    import h5py

    if isinstance(value, h5py.Empty):
        return None
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "OS":
            return np.array([v.decode("utf-8") if isinstance(v, bytes) else str(v)
                             for v in value.ravel()]).reshape(value.shape)
        return value
    if isinstance(value, np.generic):
        return value.item()
    return value


def _read_attrs(obj, reserved: set) -> dict:
    """Inverse of :func:`_write_attrs`."""
    types = json.loads(_py(obj.attrs[_TYPES_ATTR])) if _TYPES_ATTR in obj.attrs else {}
    out: dict = {}
    # create the (possibly empty) nested dicts first, parents before children
    for name in sorted((n for n, k in types.items() if k == "dict"), key=lambda s: s.count(".")):
        _nested_set(out, name, {})
    for name, raw in obj.attrs.items():
        if name in reserved:
            continue
        value = _py(raw)
        kind = types.get(name)
        if kind == "none":
            value = None
        elif kind == "bool":
            value = bool(value)
        elif kind in ("list", "tuple"):
            seq = value.tolist() if isinstance(value, np.ndarray) else [value]
            value = seq if kind == "list" else tuple(seq)
        _nested_set(out, name, value)
    return out


def _nested_set(d: dict, dotted: str, value) -> None:
    *parents, last = dotted.split(".")
    for p in parents:
        d = d.setdefault(p, {})
    if not (isinstance(value, dict) and isinstance(d.get(last), dict)):
        d[last] = value


def _str_dtype():
    import h5py

    return h5py.string_dtype("utf-8")


# --------------------------------------------------------------------------- save / load

def _write_dataset(group, name: str, data, units: str, description: str):
    arr = np.ascontiguousarray(data)
    kw = {}
    if arr.size >= _COMPRESS_MIN:
        kw = dict(compression="gzip", compression_opts=4, shuffle=True)
    ds = group.create_dataset(name, data=arr, **kw)
    ds.attrs.create("units", data=units, dtype=_str_dtype())
    ds.attrs.create("description", data=description, dtype=_str_dtype())
    return ds


def _housing_load_meta(channel: str) -> tuple[str, str]:
    """(units, description) of a housing load channel ``<body>.x``, ``.y`` or ``.moment``."""
    body, comp = channel.rsplit(".", 1)
    if comp == "moment":
        return "N m", f"moment of the {body} on the housing about its centre, counter-clockwise positive"
    where = "through its bolts" if body == "ring" else "at its bearing seat"
    return "N", f"{comp} component, global frame, of the force of the {body} on the housing {where}"


def save(result: Result, path, overwrite: bool = False) -> Path:
    """Write ``result`` to an HDF5 file, atomically (temporary file, then ``os.replace``).

        Parameters
        ----------
        result : Result
            Checked with :func:`~flexgear.results.store.validate` first.
        path : str or os.PathLike
            Target file (conventionally ``results.h5``); its directory is created if missing.
        overwrite : bool, optional
            Replace an existing file. Default False.

        Returns
        -------
        pathlib.Path
            ``path``.

        Raises
        ------
        ResultExistsError
            If ``path`` exists and ``overwrite`` is False; the existing file is left untouched.
        ValueError
            If arrays have inconsistent shapes or attributes cannot be stored.
    """
    import h5py

    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"save(path={str(path)!r}): a directory; give a file name, e.g. "
                                f"{str(path / 'results.h5')!r}")
    if path.exists() and not overwrite:
        raise ResultExistsError(_exists_message(path))
    validate(result)
    directory = path.parent if str(path.parent) else Path(".")
    directory.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        with h5py.File(tmp, "w", track_order=True) as h5:
            h5.attrs["layout_version"] = np.int64(LAYOUT_VERSION)
            h5.attrs.create("config_toml", data=result.config_toml, dtype=_str_dtype())
            _write_attrs(h5, result.attrs, _RESERVED_ROOT, "Result.attrs")
            _write_dataset(h5, "time", np.asarray(result.time), *_TIME_META)
            gm = h5.create_group("meshes", track_order=True)
            for key, m in result.meshes.items():
                g = gm.create_group(key, track_order=True)
                g.attrs.create("name", data=m.name, dtype=_str_dtype())
                g.attrs.create("body_a", data=m.body_a, dtype=_str_dtype())
                g.attrs.create("body_b", data=m.body_b, dtype=_str_dtype())
                _write_attrs(g, m.attrs, _RESERVED_MESH, f"meshes[{key!r}].attrs")
                lumped = result.attrs.get("model") == "lumped"
                for f, (units, desc) in _MESH_META.items():
                    if getattr(m, f) is not None:
                        if lumped and f in _LUMPED_META:  # its pair slots number no teeth
                            desc = _LUMPED_META[f]
                        _write_dataset(g, f, getattr(m, f), units,
                                       desc.format(a=m.body_a, b=m.body_b))
            if result.faults is not None:
                _write_attrs(h5.create_group("faults", track_order=True), result.faults, {_TYPES_ATTR}, "Result.faults")
            gb = h5.create_group("bodies", track_order=True)
            for key, b in result.bodies.items():
                g = gb.create_group(key, track_order=True)
                g.attrs.create("name", data=b.name, dtype=_str_dtype())
                _write_attrs(g, b.attrs, _RESERVED_BODY, f"bodies[{key!r}].attrs")
                for f, (units, desc) in _BODY_META.items():
                    value = getattr(b, f)
                    if value is not None:
                        _write_dataset(g, f, value, units, desc)
            if result.sensors:
                gs = h5.create_group("sensors", track_order=True)
                for key, s in result.sensors.items():
                    g = gs.create_group(key, track_order=True)
                    _write_attrs(g, s.attrs, _RESERVED_SENSOR, f"sensors[{key!r}].attrs")
                    for f, values in s.signals.items():
                        a = dict(s.signal_attrs[f])
                        ds = _write_dataset(g, f, values, a.pop("units"), a.pop("description"))
                        _write_attrs(ds, a, _RESERVED_SIGNAL, f"sensors[{key!r}].signal_attrs[{f!r}]")
            if result.housing_loads:
                gl = h5.create_group("housing_loads", track_order=True)
                for key, v in result.housing_loads.items():
                    _write_dataset(gl, key, v, *_housing_load_meta(key))
        with open(tmp, "rb+") as fh:  # make the data durable before it becomes visible
            os.fsync(fh.fileno())
        os.chmod(tmp, default_file_mode())  # mkstemp makes 0600; a result is an ordinary file
        if overwrite:
            os.replace(tmp, path)
        else:
            _publish_no_clobber(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def _exists_message(path: Path) -> str:
    return (f"result file {str(path)!r} already exists; refusing to overwrite it. "
            f"Choose another output path, delete the file, or pass overwrite=True "
            f"(command line: --overwrite).")


def _publish_no_clobber(tmp: Path, path: Path) -> None:
    """Move ``tmp`` to ``path`` atomically unless ``path`` exists (also if it appeared while
    writing). Uses a hard link where the file system supports it."""
    try:
        os.link(tmp, path)
    except FileExistsError:
        raise ResultExistsError(_exists_message(path)) from None
    except OSError:  # no hard links here (some network/FAT file systems): check, then replace
        if path.exists():
            raise ResultExistsError(_exists_message(path)) from None
        os.replace(tmp, path)
    else:
        tmp.unlink()


def load(path) -> Result:
    """Read a result file written by :func:`save`.

    Parameters
    ----------
    path : str or os.PathLike
        HDF5 result file.

    Returns
    -------
    Result
        Equal (arrays, dtypes, attributes, ``config_toml``) to the saved result.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    FlexgearError
        If ``path`` is a directory, not an HDF5 file, truncated or otherwise unreadable, not a
        flexgear result, or of a newer layout version (the message names the path and which).
    """
    import h5py

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"result file {str(path)!r} not found")
    if path.is_dir():
        inside = path / "results.h5"
        raise FlexgearError(f"{str(path)!r} is a directory, not a result file; give the file"
                            + (f" ({str(inside)!r})" if inside.exists() else " (a run writes OUTDIR/results.h5)"))
    if not os.access(path, os.R_OK):
        raise FlexgearError(f"{str(path)!r} cannot be read: permission denied")
    try:
        if not h5py.is_hdf5(path):
            raise FlexgearError(f"{str(path)!r} is not an HDF5 file (no HDF5 signature), so not a flexgear result "
                                "file; give the results.h5 a run wrote")
        return _read(path)
    except FlexgearError:
        raise
    except (OSError, KeyError, ValueError, RuntimeError) as exc:
        raise FlexgearError(_unreadable(path, exc)) from None


def _unreadable(path: Path, exc: Exception) -> str:
    """What is wrong with an HDF5 file that h5py cannot read, in words."""
    text = str(exc)
    m = re.search(r"truncated file: eof = (\d+).*stored_eof = (\d+)", text)
    if m:
        return (f"{str(path)!r} is truncated: {int(m.group(1))} bytes of the {int(m.group(2))} it declares "
                "(an interrupted copy or write?); copy or write it again")
    return (f"{str(path)!r} cannot be read as a flexgear result file: it is damaged or incomplete "
            f"({type(exc).__name__}: {text})")


def _read(path: Path) -> Result:
    import h5py

    with h5py.File(path, "r") as h5:
        if "layout_version" not in h5.attrs or "time" not in h5:
            raise FlexgearError(f"{str(path)!r} is not a flexgear result file (no "
                                f"'layout_version' attribute or '/time' dataset)")
        version = int(h5.attrs["layout_version"])
        if version > LAYOUT_VERSION:
            raise FlexgearError(f"{str(path)!r} has result layout_version {version}; this "
                                f"flexgear reads versions <= {LAYOUT_VERSION}; upgrade flexgear")
        meshes: dict[str, MeshSignals] = {}
        for key, g in h5.get("meshes", {}).items():
            meshes[key] = MeshSignals(
                name=_py(g.attrs["name"]), body_a=_py(g.attrs["body_a"]),
                body_b=_py(g.attrs["body_b"]),
                **{f: (g[f][()] if f in g else None) for f in _MESH_META},
                attrs=_read_attrs(g, _RESERVED_MESH))
        bodies: dict[str, BodySignals] = {}
        for key, g in h5.get("bodies", {}).items():
            bodies[key] = BodySignals(
                name=_py(g.attrs["name"]),
                **{f: (g[f][()] if f in g else None) for f in _BODY_META},
                attrs=_read_attrs(g, _RESERVED_BODY))
        sensors: dict[str, SensorSignals] = {}
        for key, g in h5.get("sensors", {}).items():
            s = sensors[key] = SensorSignals(name=key, attrs=_read_attrs(g, _RESERVED_SENSOR))
            for f, ds in g.items():
                s.signals[f] = ds[()]
                s.signal_attrs[f] = {"units": _py(ds.attrs["units"]), "description": _py(ds.attrs["description"]),
                                     **_read_attrs(ds, _RESERVED_SIGNAL)}
        loads = {key: ds[()] for key, ds in h5.get("housing_loads", {}).items()}
        return Result(time=h5["time"][()], meshes=meshes, bodies=bodies,
                      config_toml=_py(h5.attrs["config_toml"]),
                      attrs=_read_attrs(h5, _RESERVED_ROOT), sensors=sensors, housing_loads=loads,
                      faults=_read_attrs(h5["faults"], {_TYPES_ATTR}) if "faults" in h5 else None)
