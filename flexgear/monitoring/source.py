"""What condition monitoring reads from a result file: one signal, the shaft angles and the gear data.

Any HDF5 file in the layout of ``results.h5`` (``docs/results_layout.md``) will do, also one
written by other software: ``/time``, ``/bodies/<body>/angle`` of the gears and the carrier,
their tooth counts (body attribute ``z`` or mesh attributes ``z_a``/``z_b``), and the signal.
The signal is any numeric dataset of n samples named by its path, a 2-D one with the column
after a colon: ``meshes/planet1-ring/force_global:1`` is the vertical force of that mesh.
"""
from __future__ import annotations

import json
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.stats import circmean

from ..errors import FlexgearError, user_stacklevel
from ..gears.kinematics import mate_flank
from ..results.noise import NOISE_FREE, measured

__all__ = ["SIGNAL_OPTION", "MeshTeeth", "MonitorInput", "default_signal", "read_input", "planet_names"]

SIGNAL_OPTION = "--signal"
_PLANET = re.compile(r"^planet(\d+)$")


def planet_names(names) -> list[str]:
    """The ``planet<i>`` names among ``names``, in planet order."""
    return sorted((n for n in names if _PLANET.match(n)), key=lambda s: int(s[len("planet"):]))


@dataclass
class MeshTeeth:
    """The recorded tooth contacts of one mesh, read from the file when first asked for.

    Attributes
    ----------
    body_a, body_b : str
        The mesh's bodies.
    path : Path
        The result file.
    group : str
        The mesh's group in it (``meshes/<mesh>``).
    """

    body_a: str
    body_b: str
    path: Path
    group: str
    internal: bool = False
    _teeth: tuple | None = field(default=None, repr=False)

    def _read(self) -> tuple:
        import h5py

        if self._teeth is None:
            with h5py.File(self.path, "r") as h5:
                self._teeth = _contact_teeth(h5[self.group])
        return self._teeth

    def teeth_of(self, body: str) -> np.ndarray:
        """The teeth of ``body`` in loaded contact at every sample, one column per pair slot
        (-1: none), shape (samples, slots): every pair, not only the most loaded one, so that a
        tooth's contact interval does not shrink where a fault takes its load."""
        return self._read()[0 if body == self.body_a else 1]

    def flank_of(self, body: str) -> int | None:
        """The flank of ``body`` this mesh loads most often (+1 left, -1 right: ``pair_side`` of
        the loaded slot, gear b's the flank that meets it), None without a recorded side."""
        side = self._read()[2]
        if side is None or not np.any(side):
            return None
        side_a = 1 if np.sum(side > 0) >= np.sum(side < 0) else -1
        return side_a if body == self.body_a else mate_flank(side_a, self.internal)


@dataclass
class MonitorInput:
    """A signal of a result and the kinematics monitoring needs, all SI.

    Attributes
    ----------
    path : Path
        The result file.
    time : ndarray, shape (n,)
        Sample instants [s].
    signal : ndarray, shape (n,)
        The analysed signal [``units``].
    signal_path : str
        Its dataset path (with ``:column``).
    units, description : str
        The dataset's ``units`` and ``description`` attributes (empty if absent).
    angles : dict[str, ndarray]
        Unwrapped angle of every body [rad].
    centres : dict[str, ndarray]
        Centre position (n, 2) of every body that has one [m].
    teeth : dict[str, int]
        Tooth count of every gear body.
    meshes : dict[str, MeshTeeth]
        Tooth contacts of the meshes that recorded them.
    passband_hz : float
        Upper edge of the record's trustworthy band [Hz] (attribute ``passband_hz``; without
        it the Nyquist frequency).
    sensor_angle_deg : float or None
        A sensor signal's (``/sensors/<name>/...`` with a ``point`` attribute) angle about the
        set's centre [deg], else None.
    faulty_teeth : dict
        {body: [(tooth, kind, flank)]} of the tooth faults the file records (``/faults``), for
        the figures' marks.
    model : str
        The result's ``model`` attribute ("lumped": its pair slots hold the mesh's force, not
        numbered teeth), "" if absent.
    simulated_noise_free : bool
        The file is a flexgear simulation's and the signal has no measurement noise (any dataset
        but a sensor's measurement that differs from the noise-free copy beside it).
    """

    path: Path
    time: np.ndarray
    signal: np.ndarray
    signal_path: str
    units: str
    description: str
    angles: dict = field(default_factory=dict)
    centres: dict = field(default_factory=dict)
    teeth: dict = field(default_factory=dict)
    meshes: dict = field(default_factory=dict)
    passband_hz: float = 0.0
    sensor_angle_deg: float | None = None
    faulty_teeth: dict = field(default_factory=dict)
    model: str = ""
    simulated_noise_free: bool = False

    @property
    def fs(self) -> float:
        """Sampling rate [Hz]."""
        return float((self.time.size - 1) / (self.time[-1] - self.time[0]))

    @property
    def planets(self) -> list[str]:
        """Planet bodies with an angle, in order."""
        return planet_names(n for n in self.angles if n in self.teeth)

    @property
    def planetary(self) -> bool:
        """True for a planetary set (a carrier and at least one planet)."""
        return "carrier" in self.angles and bool(self.planets)

    @property
    def signal_mesh(self) -> str | None:
        """The mesh the signal belongs to (a dataset under ``/meshes/<mesh>/``), else None."""
        parts = self.signal_path.split("/")
        return parts[1] if len(parts) > 2 and parts[0] == "meshes" else None

    def planet_position(self, planet: str) -> float:
        """Angle of ``planet``'s centre on the carrier [rad]: its polar angle about the carrier's
        centre minus the carrier's angle, averaged over the record."""
        c = self.centres.get("carrier", np.zeros((self.time.size, 2)))
        d = self.centres[planet] - c
        return float(circmean(np.arctan2(d[:, 1], d[:, 0]) - self.angles["carrier"], high=np.pi, low=-np.pi))


def _str(v) -> str:
    return v.decode() if isinstance(v, bytes) else str(v)


def _datasets(h5, n: int) -> list[str]:
    """The signal paths of every numeric dataset of n samples (2-D ones by column)."""
    import h5py

    out = []

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and obj.dtype.kind in "fiu" and obj.shape[:1] == (n,) and name != "time":
            if obj.ndim == 1:
                out.append(name)
            elif obj.ndim == 2:
                out.extend(f"{name}:{j}" for j in range(obj.shape[1]))

    h5.visititems(visit)
    rank = {"sensors": 0, "meshes": 1, "bodies": 2}
    return sorted(out, key=lambda s: rank.get(s.split("/")[0], 3))


def default_signal(h5) -> str:
    """The signal analysed when none is given: the first sensor's first quantity if the file has
    ``/sensors``, else the first mesh's normal force (its vertical force where the file has no
    ``normal_force``). The normal force, in the gears' frame, repeats with each of the mesh's
    gears, so a healthy simulation's residuals are numerically zero; the force in the fixed frame
    of a planetary set's mesh turns with the carrier, and its carrier sidebands, which no gear's
    average cancels, would be the residual of a healthy set (the guide *Condition monitoring*)."""
    import h5py

    if "sensors" in h5:
        for name in h5["sensors"]:
            grp = h5["sensors"][name]
            for q in (grp if isinstance(grp, h5py.Group) else []):
                return f"sensors/{name}/{q}" + (":0" if grp[q].ndim == 2 else "")
    meshes = list(h5.get("meshes", {}))
    if not meshes:
        raise FlexgearError(f"{h5.filename}: no /sensors and no /meshes; name the signal with {SIGNAL_OPTION} PATH")
    first = h5["meshes"][meshes[0]]
    return f"meshes/{meshes[0]}/normal_force" if "normal_force" in first else f"meshes/{meshes[0]}/force_global:1"


#: A default sensor signal below this fraction of the loudest one of the same unit hears almost
#: nothing of the gears (a sensor at a node of the housing's response): a warning names the loudest.
DEAF_RATIO = 1e-2


def _warn_if_deaf(h5, spath: str, units: str, values: np.ndarray) -> None:
    """Warn where the default signal (the first sensor's) is far quieter than another sensor
    signal of the same unit in the file, naming the loudest."""
    if not spath.startswith("sensors/") or ":" in spath:
        return
    rms = {}
    for name, grp in h5["sensors"].items():
        for q in measured(grp):
            d = grp[q]
            if d.ndim == 1 and d.shape == values.shape and _str(d.attrs.get("units", "")) == units:
                rms[f"sensors/{name}/{q}"] = float(np.std(np.asarray(d[()], dtype=float)))
    loudest = max(rms, key=rms.get, default=None)
    mine = float(np.std(values))
    if loudest is not None and loudest != spath and mine < DEAF_RATIO * rms[loudest]:
        warnings.warn(f"{spath}, the default signal (the file's first sensor signal), has under "
                      f"{DEAF_RATIO:.0%} of the RMS of {loudest} ({units}): it hears almost nothing of the gears; "
                      f"name the signal to analyse with {SIGNAL_OPTION} (e.g. {SIGNAL_OPTION} {loudest})",
                      stacklevel=user_stacklevel())  # no figures of the file: over a batch it is said once


def _warn_if_mostly_noise(h5, spath: str, units: str) -> None:
    """Warn where a sensor signal's measurement noise is larger than what the sensor hears (its
    noise-free signal ``<path>_noise_free`` beside it): the indicators then describe the noise.
    The warning names the file's sensor signals with their signal-to-noise ratios."""
    path, _, col = spath.partition(":")
    if not path.startswith("sensors/") or col or path + NOISE_FREE not in h5:
        return

    def snr(p) -> tuple[float, float]:  # (SNR [dB], RMS of the noise-free signal)
        heard = np.asarray(h5[p + NOISE_FREE][()], dtype=float)
        noise = np.asarray(h5[p][()], dtype=float) - heard
        return 20 * np.log10(np.std(heard) / max(np.std(noise), 1e-300)), np.std(heard)

    mine, rms = snr(path)
    if mine >= 0.0:
        return
    others = [f"{p} {snr(p)[0]:.0f} dB" for p in sorted(f"sensors/{name}/{q}" for name in h5["sensors"]
                                                        for q in measured(h5["sensors"][name]))
              if p != path and p + NOISE_FREE in h5]
    warnings.warn(f"{spath}: the sensor hears less than its measurement noise (signal-to-noise ratio {mine:.0f} dB; "
                  f"the signal's RMS without the noise {rms:.2g} {units}): the indicators describe mostly the noise"
                  + (f"; the file's other sensor signals: {', '.join(others)}" if others else ""),
                  stacklevel=user_stacklevel())


def _read_signal(h5, spec: str, n: int) -> tuple[np.ndarray, str, str, str]:
    """(values, normalised path, units, description) of a signal path ``dataset[:column]``."""
    import h5py

    path, _, col = spec.strip().lstrip("/").partition(":")
    obj = h5.get(path)

    def choices() -> str:
        names = _datasets(h5, n)
        head = ", ".join(names[:10])
        return f"signals of {n} samples in this file: {head}" + (f" and {len(names) - 10} more" if len(names) > 10
                                                                else "")

    if not isinstance(obj, h5py.Dataset):
        raise FlexgearError(f"{SIGNAL_OPTION} {spec!r}: no dataset {path!r} in {h5.filename}; {choices()}")
    if obj.dtype.kind not in "fiu" or obj.ndim not in (1, 2) or obj.shape[0] != n:
        raise FlexgearError(f"{SIGNAL_OPTION} {spec!r}: {path!r} has shape {obj.shape} and type {obj.dtype}; a signal "
                            f"is a numeric dataset of {n} samples (as /time), 1-D or 2-D; {choices()}")
    if obj.ndim == 2:
        if not col.strip().isdigit() or int(col) >= obj.shape[1]:
            raise FlexgearError(f"{SIGNAL_OPTION} {spec!r}: {path!r} has {obj.shape[1]} columns; give one as "
                                f"{path}:J with J in 0..{obj.shape[1] - 1} (force_global: 0 = x, 1 = y)")
        values = obj[:, int(col)]
        path = f"{path}:{int(col)}"
    else:
        if col:
            raise FlexgearError(f"{SIGNAL_OPTION} {spec!r}: {path!r} is 1-D; drop ':{col}'")
        values = obj[()]
    values = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(values)):
        raise FlexgearError(f"{SIGNAL_OPTION} {spec!r}: the signal holds NaN or inf values")
    return values, path, _str(obj.attrs.get("units", "")), _str(obj.attrs.get("description", ""))


def _has_contacts(g) -> bool:
    """True if a mesh group holds consistent tooth-pair slots."""
    names = ("pair_force", "pair_tooth_a", "pair_tooth_b")
    return all(k in g for k in names) and len({g[k].shape for k in names}) == 1 and g["pair_force"].ndim == 2 \
        and g["pair_force"].shape[1] > 0


def _contact_teeth(g) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Teeth of a and b of every loaded pair slot at every sample (-1: unloaded), and the
    ``pair_side`` of the slot with the largest force (0: none; None where the file has no sides)."""
    force = g["pair_force"][()]
    ta, tb = g["pair_tooth_a"][()], g["pair_tooth_b"][()]
    best = np.argmax(force, axis=1)
    rows = np.arange(force.shape[0])
    side = None
    if "pair_side" in g and g["pair_side"].shape == force.shape:
        side = np.where(force[rows, best] > 0, g["pair_side"][()][rows, best], 0)
    loaded = force > 0
    return np.where(loaded, ta, -1), np.where(loaded, tb, -1), side


def _faulty_teeth(h5) -> dict:
    """{body: [(tooth, kind, flank)]} from the ``record`` of a result's ``/faults`` (a planet's
    fault on its body ``planetN``; flank +1 left, -1 right, None: both or not recorded; a fault of
    zero size, the healthy tooth, left out); empty
    without one or when it cannot be read."""
    try:
        record = json.loads(h5["faults"].attrs["record"]) if "faults" in h5 else {}
    except (KeyError, ValueError, TypeError):
        return {}
    out: dict = {}
    for f in record.get("faults") or []:
        if not isinstance(f, dict) or "tooth" not in f or "gear" not in f or f.get("null"):
            continue
        body = f"planet{f['planet']}" if f["gear"] == "planet" and f.get("planet") else str(f["gear"])
        flank = f.get("flank")
        out.setdefault(body, []).append((int(f["tooth"]), str(f.get("kind", "fault")),
                                         int(flank) if flank in (1, -1) else None))
    return out


def read_input(path, signal: str | None = None) -> MonitorInput:
    """Read the signal and the kinematics of a result file.

    Parameters
    ----------
    path : str or Path
        A ``results.h5`` (or its directory).
    signal : str, optional
        Signal path ``dataset[:column]``; default :func:`default_signal`.

    Raises
    ------
    FlexgearError
        Missing file, no ``/time``, an unknown or unusable signal path (the message lists the
        file's signals).
    """
    import h5py

    path = Path(path)
    if path.is_dir():
        path = path / "results.h5"
    if not path.is_file():
        raise FlexgearError(f"result file {str(path)!r} not found")
    try:
        h5 = h5py.File(path, "r")
    except OSError as exc:
        raise FlexgearError(f"{str(path)!r} is not an HDF5 result file ({exc})") from None
    with h5:
        if "time" not in h5 or h5["time"].ndim != 1 or h5["time"].shape[0] < 4:
            raise FlexgearError(f"{str(path)!r}: no 1-D /time dataset of at least 4 samples; not a result file")
        time = np.asarray(h5["time"][()], dtype=float)
        n = time.size
        spec = default_signal(h5) if signal is None else signal
        values, spath, units, desc = _read_signal(h5, spec, n)
        _warn_if_mostly_noise(h5, spath, units)
        if signal is None:
            _warn_if_deaf(h5, spath, units, values)
        inp = MonitorInput(path, time, values, spath, units, desc)
        plain = spath.partition(":")[0] + NOISE_FREE
        inp.simulated_noise_free = "flexgear_version" in h5.attrs and not (
            plain in h5 and not np.array_equal(np.asarray(h5[plain][()], dtype=float), values))
        fs = (n - 1) / (time[-1] - time[0])
        inp.passband_hz = float(h5.attrs.get("passband_hz", fs / 2))
        inp.faulty_teeth = _faulty_teeth(h5)
        inp.model = str(h5.attrs.get("model", ""))
        for name, g in h5.get("bodies", {}).items():
            if "angle" in g and g["angle"].shape == (n,):
                inp.angles[name] = np.asarray(g["angle"][()], dtype=float)
                if "position" in g and g["position"].shape == (n, 2):
                    inp.centres[name] = np.asarray(g["position"][()], dtype=float)
                z = int(g.attrs.get("z", 0))
                if z > 0:
                    inp.teeth[name] = z
        parts = spath.split("/")
        if parts[0] == "sensors" and len(parts) == 3 and "point" in h5[f"sensors/{parts[1]}"].attrs:
            x, y = np.asarray(h5[f"sensors/{parts[1]}"].attrs["point"], dtype=float)
            c = inp.centres["carrier"].mean(axis=0) if "carrier" in inp.centres else (0.0, 0.0)
            inp.sensor_angle_deg = float(np.degrees(np.arctan2(y - c[1], x - c[0])))
        for name, g in h5.get("meshes", {}).items():
            a, b = _str(g.attrs.get("body_a", "")), _str(g.attrs.get("body_b", ""))
            for body, key in ((a, "z_a"), (b, "z_b")):
                if body and key in g.attrs and int(g.attrs[key]) > 0:
                    inp.teeth.setdefault(body, int(g.attrs[key]))
            if a and b and _has_contacts(g) and g["pair_force"].shape[0] == n:
                inp.meshes[name] = MeshTeeth(a, b, path, f"meshes/{name}", _str(g.attrs.get("kind", "")) == "internal")
    return inp
