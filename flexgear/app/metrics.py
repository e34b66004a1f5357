"""Per-case metrics of a batch: the columns of the summary table.

A :class:`Metric` turns a :class:`~flexgear.results.Result` into one number, per mesh (column
``<name>_<mesh>``, the mesh name with ``-`` as ``_``, e.g. ``rms_force_planet1_ring``) or per
case (column ``<name>``). :data:`DEFAULT_METRICS` is the list the batch uses unless it is given
another one; extend it with your own::

    from flexgear.app.metrics import DEFAULT_METRICS, Metric

    def max_pinion_speed(result):
        return result.bodies["pinion"].angular_velocity.max()

    metrics = DEFAULT_METRICS + (Metric("max_pinion_speed", "rad/s", "largest pinion speed",
                                        max_pinion_speed, per_mesh=False),)
    run_batch("sweep.toml", "out/sweep", metrics=metrics)

(the function must be importable by the worker processes: defined in a module, not a lambda).

Default metrics (per mesh unless marked *case*):

| column | unit | meaning |
|---|---|---|
| `mean_force` | N | mean of the normal tooth force (summed over tooth pairs, a magnitude: back-flank impacts add to it) |
| `rms_force` | N | root mean square of the normal force |
| `dyn_rms_force` | N | RMS of the fluctuation about the mean (the standard deviation) |
| `p2p_force` | N | peak-to-peak normal force (max - min) |
| `peak_force` | N | largest normal force |
| `dynamic_factor` | 1 | peak normal force / static tooth load (the ISO 6336 K_v read on the simulated signal: largest dynamic over static tooth load); the static load is the one the torque balance sets: the mean normal force where the back flanks never touch, else the mean of the pair slots' forces signed by flank, drive flank less back flank (`mean_force` is the mean magnitude, back-flank impacts included) |
| `amp_fm1`, `amp_fm2`, `amp_fm3` | N | amplitude of the mesh harmonics k f_m in the normal force |
| `amp_fy_fm1`, `amp_fy_fm1_minus_fa`, `amp_fy_fm1_plus_fa` | N | planetary sets: the mesh line and its first carrier sidebands f_m -/+ f_a in the vertical force in the global frame (the paper's signal) |
| `te_mean`, `te_p2p` | m | loaded transmission error read from the contact: the approach of the gears along the line of action (the deepest penetration of the overlapping tooth pairs at each output instant, sampled, not filtered), mean and peak-to-peak; it cannot see the material a fault removes, which the gears' angles do (`studies/faults.py`) |
| `contact_pairs_mean`, `contact_pairs_min` | 1 | tooth pairs in contact (pair force > 0): time mean (the loaded contact ratio) and minimum (0 = loss of contact); not for lumped runs, whose pair slots hold the mesh's force |
| `mesh_frequency` | Hz | *case*: mean gear mesh frequency f_m |
| `solver_steps`, `rejected_steps` | 1 | *case*: accepted and rejected integration steps |
| `mesh_efficiency` | 1 | runs with tooth friction: the mesh efficiency over the recorded window (the mesh attribute of the same name); 1, with `friction_loss` and `rms_friction_force` 0, at a coefficient of 0 |
| `friction_loss` | W | runs with tooth friction: the mean power the mesh's friction dissipates (`friction_power`) |
| `rms_friction_force` | N | runs with tooth friction: RMS of the friction force along the flank tangent (`friction_force`) |
| `film_damping_loss` | W | runs with `damping = "squeeze_film"`: the mean power the squeeze films dissipate (`damping_power`) |
| `min_film`, `min_film_ratio` | m, 1 | runs with friction and a lubricant: the thinnest minimum EHL film of the loaded contacts (`film_minimum`) and the least film thickness ratio lambda (`film_ratio`; below 1 boundary, 1 to 3 mixed, above 3 full-film lubrication) |
| `film_corner_contacts` | 1 | runs with friction and a lubricant: the loaded contacts (pair slots over the output samples) outside the involute of either flank, tip corners with no line-contact film, which `min_film` and `min_film_ratio` leave out (the mesh attribute of the same name) |
| `sensor_rms`, `sensor_peak`, `sensor_kurtosis` | signal's, 1 | *per sensor signal* (`<name>_<sensor>_<path model>`, the measured one, with its noise): RMS about the mean, largest deviation from the mean, kurtosis (3 for Gaussian noise) |

Line amplitudes come from :func:`flexgear.results.signals.amplitude_spectrum` (Hann window,
zero-padded 8 times, mean removed) and :func:`~flexgear.results.signals.line_amplitude` within
half a resolution bin (1 / record length) of the line. An amplitude is NaN (empty in the table)
when the record cannot resolve it: the line above 0.4 times the output rate (filter band), or
its neighbouring line closer than 4 bins (f_m for harmonics, f_a for sidebands: a record of at
least 4 / f_a seconds). With a speed table the lines are those of the mean speed.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..results.noise import measured
from ..results.signals import amplitude_spectrum, line_amplitude

ZERO_PADDING = 8
RESOLVE_BINS = 4.0  # hann main lobe: two lines closer than this many bins are not separated
BAND_FRACTION = 0.4  # highest line frequency read, times the output rate


@dataclass(frozen=True)
class Metric:
    """A summary column (or one per mesh).

    Attributes
    ----------
    name : str
        Column name (per-mesh metrics get ``_<mesh>`` appended); letters, digits and ``_``.
    unit : str
        Unit of the value (``1`` for a number).
    description : str
        What the number is (goes into the table's column descriptions).
    func : callable
        ``func(result, mesh)`` for a per-mesh metric (mesh: a :class:`~flexgear.results.MeshSignals`),
        ``func(result, signal)`` for a per-sensor one (signal: one sensor signal, an array), else
        ``func(result)``; returns a float (NaN when the record cannot give it), or None when the
        metric does not apply to this result (no column then, e.g. sidebands of fixed axes).
    per_mesh : bool
        One column per mesh (default) or one per case.
    per_sensor : bool
        One column per sensor signal instead, ``<name>_<sensor>_<path model>`` (the measured
        signal; ``unit`` "signal": the signal's own unit).
    """

    name: str
    unit: str
    description: str
    func: Callable
    per_mesh: bool = True
    per_sensor: bool = False

    def _signals(self, result):
        """(column, sensor, path model, its attributes) of every measured sensor signal of
        ``result`` (not the noise-free copies)."""
        for sensor, s in (getattr(result, "sensors", None) or {}).items():
            for path in measured(s.signals):
                yield f"{self.name}_{column_name(sensor)}_{column_name(path)}", sensor, path, s.signal_attrs[path]

    def compute(self, result) -> dict[str, float]:
        """``{column: value}`` for ``result``."""
        if self.per_sensor:
            values = {col: self.func(result, np.asarray(result.sensors[sensor].signals[path], dtype=float))
                      for col, sensor, path, _ in self._signals(result)}
        elif self.per_mesh:
            values = {f"{self.name}_{column_name(key)}": self.func(result, mesh) for key, mesh in result.meshes.items()}
        else:
            values = {self.name: self.func(result)}
        return {k: float(v) for k, v in values.items() if v is not None}

    def columns(self, result) -> dict[str, tuple[str, str]]:
        """``{column: (unit, description)}`` for ``result``'s meshes."""
        if self.per_sensor:
            return {col: (attrs.get("units", "1") if self.unit == "signal" else self.unit,
                          f"{self.description} (sensor {sensor}, {path})")
                    for col, sensor, path, attrs in self._signals(result)}
        if self.per_mesh:
            return {f"{self.name}_{column_name(key)}": (self.unit, f"{self.description} (mesh {key})")
                    for key in result.meshes}
        return {self.name: (self.unit, self.description)}


def column_name(text: str) -> str:
    """A column name from a mesh name or dotted key: ``planet1-ring`` -> ``planet1_ring``,
    ``drive.speed_hz`` -> ``drive_speed_hz`` (letters, digits and ``_`` only, readable by
    MATLAB's ``readtable`` without renaming)."""
    out = "".join(c if c.isalnum() else "_" for c in text)
    return out if out[:1].isalpha() else "c_" + out


def compute_metrics(result, metrics) -> tuple[dict[str, float], dict[str, tuple[str, str]]]:
    """All metric columns of ``result`` in the order of ``metrics``: ``({column: value},
    {column: (unit, description)})``."""
    values: dict[str, float] = {}
    info: dict[str, tuple[str, str]] = {}
    for m in metrics:
        v = m.compute(result)
        values.update(v)
        info.update({k: u for k, u in m.columns(result).items() if k in v})
    return values, info


# --------------------------------------------------------------------------- force statistics

def mean_force(result, mesh) -> float:
    return np.mean(mesh.normal_force)


def rms_force(result, mesh) -> float:
    return np.sqrt(np.mean(mesh.normal_force**2))


def dynamic_rms_force(result, mesh) -> float:
    return np.std(mesh.normal_force)


def p2p_force(result, mesh) -> float:
    return np.ptp(mesh.normal_force)


def peak_force(result, mesh) -> float:
    return np.max(mesh.normal_force)


def static_force(mesh) -> float:
    """The mesh's static tooth load [N], which the torque balance sets: the mean normal force
    where the back flanks never touch; where they do, the mean over the output samples of the
    pair slots' forces signed by flank, the drive flank's (the side that carries most) less the
    back flank's (the normal force is a magnitude: its mean counts their impacts as load)."""
    f = np.nan_to_num(np.asarray(mesh.pair_force, dtype=float))
    side = np.asarray(mesh.pair_side)
    drive = 1 if f[side > 0].sum() >= f[side < 0].sum() else -1
    if not np.any(f[side == -drive] > 0.0):
        return float(np.mean(mesh.normal_force))
    return float(np.mean(np.sum(np.where(side == drive, f, 0.0) - np.where(side == -drive, f, 0.0), axis=1)))


def dynamic_factor(result, mesh) -> float:
    static = static_force(mesh)
    return np.max(mesh.normal_force) / static if static > 0 else math.nan


# --------------------------------------------------------------------------- spectral lines

def line_or_nan(result, signal, f0: float, spacing: float) -> float:
    """Amplitude of the line at ``f0`` [Hz] in ``signal``, NaN when the record cannot resolve it
    from lines ``spacing`` [Hz] away or ``f0`` lies outside the output band."""
    fs = result.fs
    n = signal.size
    resolution = fs / n
    if not (f0 > 0 and f0 <= BAND_FRACTION * fs and spacing >= RESOLVE_BINS * resolution):
        return math.nan
    f, A = amplitude_spectrum(signal, fs, window="hann", detrend="mean", nfft=ZERO_PADDING * n)
    return line_amplitude(f, A, f0, tol_hz=0.5 * resolution)


def mesh_harmonic(result, mesh, k: int) -> float:
    """Amplitude [N] of the k-th mesh harmonic in the normal force."""
    fm = result.attrs["mesh_frequency"]
    return line_or_nan(result, mesh.normal_force, k * fm, fm)


def vertical_line(result, mesh, j: int) -> float:
    """Amplitude [N] of f_m + j f_a in the vertical global force (planetary sets; None for fixed
    axes)."""
    fm, fa = result.attrs["mesh_frequency"], result.attrs.get("carrier_frequency", 0.0)
    if not fa > 0:
        return None
    return line_or_nan(result, mesh.force_global[:, 1], fm + j * fa, fa)


# --------------------------------------------------------------------------- contact

def approach(mesh) -> np.ndarray:
    """Approach of the gears along the line of action [m] at every output sample: the deepest
    penetration over the tooth pairs that overlap (0 without contact), whether or not a pair
    carries force: a separating pair whose IMPACT damper outweighs its spring carries none while
    it still overlaps, and the loaded pairs alone then read the approach low (rigid gears on
    fixed axes: r_b1 theta_1 + r_b2 theta_2)."""
    return np.max(np.maximum(np.nan_to_num(mesh.penetration, nan=0.0), 0.0), axis=1, initial=0.0)


def te_mean(result, mesh) -> float:
    return np.mean(approach(mesh))


def te_p2p(result, mesh) -> float:
    return np.ptp(approach(mesh))


def contact_pairs_mean(result, mesh) -> float | None:
    """None for a lumped run: its ``pair_force`` holds the mesh's force in slot 0, not the pairs'."""
    return None if result.attrs.get("model") == "lumped" else np.mean(np.sum(mesh.pair_force > 0, axis=1))


def contact_pairs_min(result, mesh) -> float | None:
    return None if result.attrs.get("model") == "lumped" else np.min(np.sum(mesh.pair_force > 0, axis=1))


# --------------------------------------------------------------------------- per case

def mesh_frequency(result) -> float:
    return result.attrs["mesh_frequency"]


def solver_steps(result) -> float:
    return result.attrs["solver_steps"]


def rejected_steps(result) -> float:
    return result.attrs["rejected_steps"]


# --------------------------------------------------------------------------- tooth friction and lubrication
# None without [lubrication] friction (or without a lubricant, for the film): no column, so the
# summary of a frictionless batch keeps its columns

def mesh_efficiency(result, mesh) -> float | None:
    return mesh.attrs.get("mesh_efficiency")


def _without_friction(mesh) -> float | None:
    """A friction figure of a mesh without friction datasets: 0 in a run with ``[lubrication]``
    at a coefficient of 0 (the frictionless model, efficiency 1), else None (no friction)."""
    return 0.0 if mesh.attrs.get("mesh_efficiency") == 1.0 else None


def friction_loss(result, mesh) -> float | None:
    p = getattr(mesh, "friction_power", None)
    return _without_friction(mesh) if p is None else np.mean(p)


def film_damping_loss(result, mesh) -> float | None:
    return None if getattr(mesh, "damping_power", None) is None else np.mean(mesh.damping_power)


def rms_friction_force(result, mesh) -> float | None:
    f = getattr(mesh, "friction_force", None)
    return _without_friction(mesh) if f is None else np.sqrt(np.mean(f**2))


def _least(values) -> float | None:
    """The least finite value of a slot record (nan: no loaded contact), None without the record."""
    if values is None:
        return None
    finite = values[np.isfinite(values)]
    return float(finite.min()) if finite.size else math.nan


def min_film(result, mesh) -> float | None:
    return _least(getattr(mesh, "film_minimum", None))


def min_film_ratio(result, mesh) -> float | None:
    return _least(getattr(mesh, "film_ratio", None))


def film_corner_contacts(result, mesh) -> int | None:
    return None if getattr(mesh, "film_ratio", None) is None else int(mesh.attrs.get("film_corner_contacts", 0))


# --------------------------------------------------------------------------- sensors

def signal_rms(result, x) -> float:
    return np.std(x)


def signal_peak(result, x) -> float:
    return np.max(np.abs(x - np.mean(x)))


def signal_kurtosis(result, x) -> float:
    d = x - np.mean(x)
    m2 = np.mean(d ** 2)
    return np.mean(d ** 4) / m2 ** 2 if m2 > 0 else math.nan


#: The metrics of a batch summary, in column order.
DEFAULT_METRICS: tuple[Metric, ...] = (
    Metric("mean_force", "N", "mean normal tooth force", mean_force),
    Metric("rms_force", "N", "RMS normal tooth force", rms_force),
    Metric("dyn_rms_force", "N", "RMS of the normal force's fluctuation about its mean", dynamic_rms_force),
    Metric("p2p_force", "N", "peak-to-peak normal tooth force", p2p_force),
    Metric("peak_force", "N", "largest normal tooth force", peak_force),
    Metric("dynamic_factor", "1", "dynamic factor: peak normal force / static tooth load", dynamic_factor),
    *(Metric(f"amp_fm{k}", "N", f"amplitude of {k if k > 1 else ''}f_m in the normal force",
             functools.partial(mesh_harmonic, k=k)) for k in (1, 2, 3)),
    Metric("amp_fy_fm1", "N", "amplitude of f_m in the vertical global force", functools.partial(vertical_line, j=0)),
    Metric("amp_fy_fm1_minus_fa", "N", "amplitude of f_m - f_a in the vertical global force",
           functools.partial(vertical_line, j=-1)),
    Metric("amp_fy_fm1_plus_fa", "N", "amplitude of f_m + f_a in the vertical global force",
           functools.partial(vertical_line, j=1)),
    Metric("te_mean", "m", "mean approach along the line of action (loaded transmission error)", te_mean),
    Metric("te_p2p", "m", "peak-to-peak approach along the line of action", te_p2p),
    Metric("contact_pairs_mean", "1", "mean number of tooth pairs in contact (loaded contact ratio)",
           contact_pairs_mean),
    Metric("contact_pairs_min", "1", "least number of tooth pairs in contact", contact_pairs_min),
    Metric("mesh_frequency", "Hz", "mean gear mesh frequency", mesh_frequency, per_mesh=False),
    Metric("solver_steps", "1", "accepted integration steps", solver_steps, per_mesh=False),
    Metric("rejected_steps", "1", "rejected integration steps", rejected_steps, per_mesh=False),
    Metric("mesh_efficiency", "1", "mesh efficiency over the recorded window (tooth friction)", mesh_efficiency),
    Metric("friction_loss", "W", "mean power dissipated by tooth friction", friction_loss),
    Metric("rms_friction_force", "N", "RMS friction force along the flank tangent", rms_friction_force),
    Metric("film_damping_loss", "W", "mean power dissipated by the squeeze films (damping = squeeze_film)",
           film_damping_loss),
    Metric("min_film", "m", "thinnest minimum EHL film of the loaded contacts", min_film),
    Metric("min_film_ratio", "1", "least film thickness ratio lambda of the loaded contacts", min_film_ratio),
    Metric("film_corner_contacts", "1", "loaded contacts at tip corners, without a film (left out of min_film)",
           film_corner_contacts),
    Metric("sensor_rms", "signal", "RMS of the sensor signal about its mean", signal_rms, per_sensor=True),
    Metric("sensor_peak", "signal", "largest deviation of the sensor signal from its mean", signal_peak,
           per_sensor=True),
    Metric("sensor_kurtosis", "1", "kurtosis of the sensor signal (3 for Gaussian noise)", signal_kurtosis,
           per_sensor=True),
)
