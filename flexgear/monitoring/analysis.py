"""Condition monitoring of one result: averages per shaft, their indicators, order and envelope spectra.

:func:`monitor` reads a signal of a result file (:mod:`flexgear.monitoring.source`), resamples
it against every shaft's angle (:mod:`~flexgear.monitoring.order`), averages it per shaft
(:mod:`~flexgear.monitoring.tsa`; planets with McFadden's planet-separation windows when the
signal is heard from a fixed point) and computes the indicators
(:mod:`~flexgear.monitoring.indicators`). Shaft angles in a planetary set are taken relative to
the carrier (the carrier's relative to the ring): a sun or planet tooth meets its mates at fixed
angles of that relative rotation, and the mesh order of every shaft is then its tooth count (the
carrier's: the ring's). The full-record order spectrum and the envelope spectrum are taken
against the carrier (planetary: every planetary line is then an integer order) or the first
gear of a spur pair. Choices and definitions: ``docs/guide/monitoring.md``.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass, field
from typing import Sequence

import numpy as np

from ..errors import ConfigError, FlexgearError, user_stacklevel
from ..results.store import Result, save
from . import indicators as ind
from .envelope import envelope
from .leaks import UNSTEADY, partner_share, warn_leaks
from .order import angle_grid, angular_resample, order_spectrum
from .source import MonitorInput, read_input
from .tsa import PLANET_WINDOWS, Average, TSASignals, half_record_change, moment_grid, synchronous_average, \
    tsa_signals, windowed_average
from .windows import measuring_angle, planet_weights, sun_windowed, window_span

__all__ = ["MonitorSettings", "Shaft", "ShaftAverage", "MonitorReport", "monitor", "shafts_of"]

TWO_PI = 2.0 * np.pi


@dataclass
class MonitorSettings:
    """Options of :func:`monitor` (command-line names in brackets).

    Attributes
    ----------
    signal : str or None
        Signal path ``dataset[:column]`` (``--signal``); default: the first sensor, else the first
        mesh's normal force (:func:`~flexgear.monitoring.source.default_signal`).
    sensor_angle_deg : float or None
        Angle of the fixed measuring point around the set's centre, counter-clockwise from +x
        [deg] (``--sensor-angle``); the planet windows are centred where a planet passes it.
        Default: the analysed sensor's angle (a ``/sensors/<name>/...`` signal), else 90 (above
        the centre).
    samples_per_rev : int or None
        Samples per revolution of every average (``--samples-per-rev``); default per shaft, the
        smallest multiple of its mesh order at least as dense as the record at its lowest speed;
        a coarser grid is refused (:func:`~.order.angle_grid`).
    shaft_orders : int
        Shaft orders 1..n counted in the regular signal (``--shaft-orders``). Default 2.
    planet_window : str
        Planet-separation window, ``hann`` or ``rectangular`` (``--planet-window``).
    window_teeth : int or None
        Planet window width in tooth-meshing periods (``--window-teeth``); default the advance
        step g (:func:`~flexgear.monitoring.windows.advance_step`: a planet's gcd(ring teeth,
        planet teeth)) for the rectangular window, 2 g for Hann.
    sun_windows : bool
        Average the sun from the planet windows of a signal heard from a fixed point, each
        planet's shifted by its position (McFadden 1991; ``--sun-windows``): a sun tooth then
        appears once, not once per planet. Default False: the plain average against the sun's
        angle in the carrier.
    min_averages : float
        Least number of averages at any angle for a shaft's average (``--min-averages``);
        windowed averages count the summed window weight. Default 1.
    band_hz : (float, float) or None
        Band of the envelope spectrum [Hz] (``--band``); default the first mesh frequency -/+
        half of it.
    sidebands : int
        Sidebands on each side in the sideband energy ratio (``--sidebands``). Default 3.
    shafts : tuple of str or None
        Shafts to average (``--shafts``); default every one the record allows (the others are
        listed as skipped with the reason); a shaft named here that cannot be averaged is an error.
    """

    signal: str | None = None
    sensor_angle_deg: float | None = None
    samples_per_rev: int | None = None
    shaft_orders: int = 2
    planet_window: str = "hann"
    window_teeth: int | None = None
    sun_windows: bool = False
    min_averages: float = 1.0
    band_hz: tuple | None = None
    sidebands: int = 3
    shafts: tuple | None = None

    def check(self) -> None:
        """Check the values that need no result file.

        Raises
        ------
        ConfigError
            Naming the option, its value and the rule.
        """
        def bad(option, value, rule):
            raise ConfigError(f"{option} = {value!r}: {rule}")

        if self.sensor_angle_deg is not None and not (isinstance(self.sensor_angle_deg, (int, float))
                                                      and math.isfinite(self.sensor_angle_deg)):
            bad("--sensor-angle", self.sensor_angle_deg, "must be a finite angle in degrees")
        if self.samples_per_rev is not None and not (isinstance(self.samples_per_rev, int) and self.samples_per_rev >= 8):
            bad("--samples-per-rev", self.samples_per_rev, "must be an integer >= 8")
        if not (isinstance(self.shaft_orders, int) and self.shaft_orders >= 0):
            bad("--shaft-orders", self.shaft_orders, "must be an integer >= 0")
        if self.planet_window not in PLANET_WINDOWS:
            bad("--planet-window", self.planet_window, f"must be one of {', '.join(PLANET_WINDOWS)}")
        if not isinstance(self.sun_windows, bool):
            bad("--sun-windows", self.sun_windows, "must be True or False")
        if self.window_teeth is not None and not (isinstance(self.window_teeth, int) and self.window_teeth >= 1):
            bad("--window-teeth", self.window_teeth, "must be an integer >= 1 (tooth-meshing periods)")
        if not (isinstance(self.min_averages, (int, float)) and self.min_averages > 0):
            bad("--min-averages", self.min_averages, "must be > 0")
        if self.band_hz is not None:
            b = tuple(self.band_hz)
            if len(b) != 2 or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in b) or not 0 < b[0] < b[1]:
                bad("--band", self.band_hz, "must be two frequencies 0 < LOW < HIGH in Hz")
        if not (isinstance(self.sidebands, int) and self.sidebands >= 1):
            bad("--sidebands", self.sidebands, "must be an integer >= 1")
        if self.shafts is not None and (isinstance(self.shafts, str) or not all(isinstance(x, str) for x in self.shafts)):
            bad("--shafts", self.shafts, "must be a list of shaft names, e.g. ('sun', 'planet1')")


@dataclass(frozen=True)
class Shaft:
    """A shaft to average.

    Attributes
    ----------
    name : str
        ``sun``, ``carrier``, ``planet<i>``, or a spur gear's body name.
    body : str
        The body whose angle is followed.
    reference : str or None
        The angle is taken relative to this body's (planetary: the carrier; the carrier's: the
        ring), None for absolute.
    mesh_order : int
        Teeth meshing per revolution of the relative angle: the gear's tooth count, for the
        carrier the ring's.
    windowed : bool
        Planet averaged with planet-separation windows.
    tooth_mesh : str or None
        The mesh whose recorded contacts number the gear's teeth in the figures.
    """

    name: str
    body: str
    reference: str | None
    mesh_order: int
    windowed: bool = False
    tooth_mesh: str | None = None


@dataclass
class ShaftAverage:
    """The average of one shaft and what follows from it.

    Attributes
    ----------
    shaft : Shaft
    average : Average
        The (weighted) synchronous average and its weights.
    signals : TSASignals
        TSA, regular, residual and difference signals [unit of the signal].
    speed_hz : (float, float, float)
        Least, mean and largest speed of the shaft's (relative) rotation [rev/s].
    window_teeth : int or None
        Planet window width used [tooth-meshing periods].
    tooth_angles : dict[int, float]
        Angle of the revolution [rad] at which each tooth is in mesh on ``shaft.tooth_mesh``
        (from the recorded contacts; empty if not recorded).
    planet_angles : dict[str, float]
        Carrier only: carrier angle of the revolution [rad] at which each planet passes the sensor.
    unsteady : float or None
        A noise-free simulation's only: the RMS of the difference between the residuals of the
        record's two halves over the residual's RMS (:func:`~flexgear.monitoring.tsa.half_record_change`): about 0 where
        the residual repeats with the shaft (its own gear's fault), of order 1 where it holds
        content the average does not cancel; None where it cannot be told.
    partner : (str, int, int) or None
        Spur pair: the meshing gear, the shaft's and its tooth counts; None otherwise.
    partner_share : (float, float) or None
        Spur pair with a common factor of the tooth counts: the residual's power fraction at the
        orders where the partner's own content stays in the average, and a broadband residual's
        (:func:`~flexgear.monitoring.leaks.partner_share`); None otherwise.
    fault_marks : list of (int, str, str, dict)
        Each tooth fault the file records on the shaft's gear: (tooth, kind, mesh, the tooth
        angles [rad] on that mesh), the mesh being the one that loads the faulty flank (a
        planet's flank meets either the sun or the ring; the tooth mesh for a fault on both flanks);
        the carrier's: each ring tooth fault once per planet-ring mesh, at the carrier angles
        where that planet meets the ring's teeth. Empty for a lumped result (no teeth numbered).
    indicators : dict[str, float or None]
        Indicator values (None where undefined, reason in ``notes``).
    notes : dict[str, str]
        Why an indicator is undefined.
    """

    shaft: Shaft
    average: Average
    signals: TSASignals
    speed_hz: tuple
    window_teeth: int | None = None
    tooth_angles: dict = field(default_factory=dict)
    planet_angles: dict = field(default_factory=dict)
    fault_marks: list = field(default_factory=list)
    unsteady: float | None = None
    partner: tuple | None = None
    partner_share: tuple | None = None
    indicators: dict = field(default_factory=dict)
    notes: dict = field(default_factory=dict)

    @property
    def samples_per_rev(self) -> int:
        return self.signals.tsa.size

    @property
    def leaky(self) -> bool:
        """The residual holds content not synchronous with the shaft (``unsteady`` above
        :data:`~flexgear.monitoring.leaks.UNSTEADY`)."""
        return self.unsteady is not None and self.unsteady > UNSTEADY


@dataclass
class OrderSpectrum:
    """An order spectrum against the reference shaft, with the lines to mark.

    Attributes
    ----------
    reference : str
        Shaft the orders count [1/rev].
    orders, amplitude : ndarray
        Spectrum (amplitude in the unit of the signal).
    marks : list of (float, str, str)
        (order, label, kind) with kind ``mesh``, ``sideband``, ``shaft`` or ``planet``.
    band_hz : (float, float) or None
        Envelope spectra: the band demodulated [Hz].
    max_order : float
        Highest trustworthy order (the record's band at the reference's highest speed).
    """

    reference: str
    orders: np.ndarray
    amplitude: np.ndarray
    marks: list
    band_hz: tuple | None
    max_order: float


@dataclass
class MonitorReport:
    """Everything :func:`monitor` computed for one result.

    Attributes
    ----------
    source : MonitorInput
        The signal and kinematics read.
    settings : MonitorSettings
    shafts : dict[str, ShaftAverage]
    skipped : dict[str, str]
        Shafts not averaged, with the reason.
    signal_indicators : dict[str, float]
        RMS, crest factor and kurtosis of the whole record (mean removed).
    orders : OrderSpectrum
        Spectrum of the whole record against the reference shaft.
    envelope : OrderSpectrum
        Envelope spectrum of the band against the reference shaft.
    baseline : list of str
        The healthy results NA4 is normalised by.
    baseline_records : dict[str, int]
        Per shaft, how many of them could be averaged and enter its NA4.
    """

    source: MonitorInput
    settings: MonitorSettings
    shafts: dict
    skipped: dict
    signal_indicators: dict
    orders: OrderSpectrum
    envelope: OrderSpectrum
    baseline: list = field(default_factory=list)
    baseline_records: dict = field(default_factory=dict)

    def rows(self) -> list[dict]:
        """One row per (shaft, indicator): shaft, indicator, value, unit, on, definition, source.
        The shaft ``signal`` holds the whole record's RMS, crest factor and kurtosis."""
        out = []
        units = self.source.units or "1"

        def row(shaft, name, value, on):
            i = ind.INDICATORS[name]
            out.append({"shaft": shaft, "indicator": name, "value": value,
                        "unit": units if i.unit == "signal" else i.unit, "on": on,
                        "definition": i.definition, "source": i.source})

        for name, value in self.signal_indicators.items():
            row("signal", name, value, "whole record, mean removed")
        for sname, sa in self.shafts.items():
            for name, value in sa.indicators.items():
                row(sname, name, value, ind.INDICATORS[name].on)
        return out

    def to_dict(self) -> dict:
        """A JSON-ready summary: signal, settings, per-shaft data and indicators, definitions."""
        from .. import __version__

        src = self.source
        shafts = {}
        for name, sa in self.shafts.items():
            shafts[name] = {
                "body": sa.shaft.body, "relative_to": sa.shaft.reference, "mesh_order": sa.shaft.mesh_order,
                "samples_per_rev": sa.samples_per_rev, "averages": sa.average.averages,
                "planet_window": ({"shape": self.settings.planet_window, "teeth": sa.window_teeth}
                                  if sa.window_teeth is not None else None),
                "speed_hz": {"min": sa.speed_hz[0], "mean": sa.speed_hz[1], "max": sa.speed_hz[2]},
                "max_order": sa.signals.max_order, "indicators": sa.indicators, "undefined": sa.notes,
                "residual_unsteady": sa.unsteady,
                "partner_share": None if sa.partner_share is None else
                {"gear": sa.partner[0], "share": sa.partner_share[0], "broadband": sa.partner_share[1]}}
        return {
            "flexgear_version": __version__, "result": str(src.path),
            "signal": {"path": src.signal_path, "units": src.units, "description": src.description,
                       "samples": int(src.time.size), "rate_hz": src.fs, "passband_hz": src.passband_hz},
            "settings": {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self.settings).items()},
            "baseline": list(self.baseline), "na4_baseline_records": self.baseline_records,
            "signal_indicators": self.signal_indicators,
            "shafts": shafts, "skipped": self.skipped,
            "order_reference": self.orders.reference, "envelope_band_hz": list(self.envelope.band_hz),
            "definitions": {k: {"unit": (src.units or "1") if v.unit == "signal" else v.unit, "on": v.on,
                                "definition": v.definition, "source": v.source}
                            for k, v in ind.INDICATORS.items()},
        }


# --------------------------------------------------------------------------- shafts

def _tooth_mesh(inp: MonitorInput, body: str, prefer: str | None) -> str | None:
    """The mesh that numbers ``body``'s teeth: ``prefer`` if it holds the body, else the first."""
    names = [n for n, m in inp.meshes.items() if body in (m.body_a, m.body_b)]
    if prefer in names:
        return prefer
    return names[0] if names else None


def shafts_of(inp: MonitorInput) -> tuple[list[Shaft], dict[str, str]]:
    """The shafts of a result to average, and those left out with the reason.

    Planetary: the sun and each planet relative to the carrier, the carrier relative to the ring.
    A planet is windowed unless the signal is a dataset of one of its own meshes (then the planet
    alone is in it, and the other planets are not). Spur pair: both gears, absolute.
    """
    shafts, skipped = [], {}
    sig_mesh = inp.signal_mesh
    if inp.planetary:
        ring = "ring" if "ring" in inp.angles else None
        if "sun" in inp.teeth and "sun" in inp.angles:
            shafts.append(Shaft("sun", "sun", "carrier", inp.teeth["sun"], False,
                                _tooth_mesh(inp, "sun", sig_mesh)))
        if "ring" in inp.teeth:
            shafts.append(Shaft("carrier", "carrier", ring, inp.teeth["ring"]))
        else:
            skipped["carrier"] = "the ring's tooth count is not in the file (body attribute z or mesh z_a/z_b)"
        own = None
        if sig_mesh is not None:
            own = next((p for p in inp.planets if p in sig_mesh.split("-")), None)
        for p in inp.planets:
            if own is not None and p != own:
                skipped[p] = f"the signal {inp.signal_path} is a dataset of mesh {sig_mesh}, where {p} does not mesh"
                continue
            shafts.append(Shaft(p, p, "carrier", inp.teeth[p], own is None,
                                _tooth_mesh(inp, p, f"{p}-ring" if own is None else sig_mesh)))
        return shafts, skipped
    gears = [b for m in inp.meshes.values() for b in (m.body_a, m.body_b)]  # mesh order: pinion, wheel
    gears += sorted(inp.teeth)
    for b in dict.fromkeys(gears):
        if b in inp.teeth and b in inp.angles:
            shafts.append(Shaft(b, b, None, inp.teeth[b], False, _tooth_mesh(inp, b, sig_mesh)))
    return shafts, skipped


def _relative_angle(inp: MonitorInput, shaft: Shaft) -> np.ndarray:
    a = inp.angles[shaft.body]
    return a - inp.angles[shaft.reference] if shaft.reference else a


def _speeds(inp: MonitorInput, angle: np.ndarray) -> tuple[float, float, float]:
    w = np.abs(np.gradient(angle, inp.time)) / TWO_PI
    return float(w.min()), float(abs(angle[-1] - angle[0]) / TWO_PI / (inp.time[-1] - inp.time[0])), float(w.max())


# --------------------------------------------------------------------------- averaging

class _Skip(Exception):
    """A shaft that cannot be averaged (message names the option)."""


def _tooth_angles(inp: MonitorInput, body: str, mesh: str | None, angle: np.ndarray,
                  direction: int) -> dict[int, float]:
    """Angle of the revolution (in the average's coordinate) at which each tooth of ``body`` is
    in ``mesh``: the middle of its loaded contact; none for a lumped result, whose pair slots
    carry no tooth numbers."""
    from scipy.stats import circmean

    m = inp.meshes.get(mesh) if mesh else None
    if m is None or inp.model == "lumped":
        return {}
    teeth = m.teeth_of(body)
    psi = np.broadcast_to(np.mod(direction * angle, TWO_PI)[:, None], teeth.shape)
    return {int(k): float(np.mod(circmean(psi[teeth == k]), TWO_PI)) for k in np.unique(teeth[teeth >= 0])}


def _fault_marks(inp: MonitorInput, shaft: Shaft, tooth_angles: dict, angle: np.ndarray, direction: int) -> list:
    """:attr:`ShaftAverage.fault_marks` of ``shaft`` (none for a lumped result, which numbers no
    teeth); the carrier's: its ring's tooth faults, one mark per planet-ring mesh."""
    out = []
    if inp.model == "lumped":
        return out
    if shaft.name == "carrier":
        ring = [n for n, m in sorted(inp.meshes.items()) if "ring" in (m.body_a, m.body_b)]
        for tooth, kind, _ in inp.faulty_teeth.get("ring", []):
            out += [(tooth, kind, mesh, _tooth_angles(inp, "ring", mesh, angle, direction)) for mesh in ring]
        return out
    for tooth, kind, flank in inp.faulty_teeth.get(shaft.body, []):
        mesh = shaft.tooth_mesh
        if flank is not None and mesh in inp.meshes and inp.meshes[mesh].flank_of(shaft.body) not in (flank, None):
            mesh = next((n for n, m in inp.meshes.items() if shaft.body in (m.body_a, m.body_b)
                         and m.flank_of(shaft.body) == flank), mesh)
        angles = tooth_angles if mesh == shaft.tooth_mesh else _tooth_angles(inp, shaft.body, mesh, angle, direction)
        out.append((tooth, kind, mesh, angles))
    return out


def _indicators(sig: TSASignals, baseline_m2: Sequence[float], sidebands: int) -> tuple[dict, dict]:
    z = sig.teeth
    empty = {name: f"the {name} signal is numerically zero (RMS below {ind.NUMERICAL_FLOOR:g} of the TSA's)"
             for name, x in (("residual", sig.residual), ("difference", sig.difference))
             if ind.numerically_zero(x, sig.tsa)}
    # peaks and moments of the continuous waveforms, independent of the angle grid (moment_grid)
    tsa, res, diff = (moment_grid(x, sig.max_order) for x in (sig.tsa, sig.residual, sig.difference))
    calls = {
        "rms": lambda: ind.rms(sig.tsa),
        "crest_factor": lambda: ind.crest_factor(tsa),
        "kurtosis": lambda: ind.kurtosis(tsa),
        "fm0": lambda: ind.fm0(tsa, z, sig.max_order),
        "fm4": lambda: ind.fm4(diff),
        "na4": lambda: ind.na4(res, baseline_m2),
        "na4_star": lambda: ind.na4_star(res, baseline_m2),
        "m6a": lambda: ind.m6a(diff),
        "m8a": lambda: ind.m8a(diff),
        "energy_ratio": lambda: ind.energy_ratio(sig.difference, sig.regular),
        **{name: (lambda h=h: ind.sideband_energy_ratio(sig.tsa, z, h, sidebands, sig.max_order))
           for h, name in ((1, "ser"), (2, "ser2"), (3, "ser3"))},
    }
    values, notes = {}, {}
    for name, f in calls.items():
        on = ind.INDICATORS[name].on
        if on in empty:
            values[name], notes[name] = None, empty[on]
            continue
        try:
            values[name] = f()
        except ValueError as exc:
            values[name] = None
            notes[name] = str(exc)
    return values, notes


#: A baseline's shaft speed may differ from the analysed record's by this fraction without a
#: warning (the speed sets the mesh forces' dynamics and with them the residual's variance).
BASELINE_SPEED_TOL = 0.02

#: The planet windows' least coverage may fall short of --min-averages by this fraction: the
#: carrier's speed varies a little, and a whole cycle of passes covers each angle once only to
#: about 2e-5 (a 1 s run of MERCURY 1-A with a cracked sun: 0.99998).
COVERAGE_TOL = 1e-3


def _average_shaft(inp: MonitorInput, settings: MonitorSettings, shaft: Shaft,
                   band_order: int | None = None) -> ShaftAverage:
    """The TSA of ``shaft`` and its signals, band-limited at the record's trustworthy band (and at
    the order ``band_order``: a baseline at the analysed record's, so that NA4's variances
    cover the orders of its residual)."""
    angle = _relative_angle(inp, shaft)
    speed = _speeds(inp, angle)
    if not speed[0] > 0:
        raise _Skip(f"its rotation stops during the record (least speed {speed[0]:g} rev/s)")
    n = angle_grid(inp.fs, speed[0], shaft.mesh_order, settings.samples_per_rev, shaft.name)
    if n < 2 * shaft.mesh_order + 2:
        raise ConfigError(f"--samples-per-rev = {n}: {shaft.name} needs more than twice its mesh order "
                          f"{shaft.mesh_order} samples per revolution")
    max_order = int(min(inp.passband_hz / speed[2], (n - 1) // 2))
    if band_order is not None:
        max_order = min(max_order, band_order)
    if max_order < shaft.mesh_order + settings.sidebands:
        raise _Skip(f"its mesh order {shaft.mesh_order} and {settings.sidebands} sidebands exceed the record's "
                    f"trustworthy band ({inp.passband_hz:g} Hz = order {max_order} at {speed[2]:.4g} rev/s)")
    x = inp.signal - inp.signal.mean()
    sun = settings.sun_windows and shaft.name == "sun" and inp.signal_mesh is None  # heard from a fixed point
    teeth = weights = None  # a plain average
    try:
        if sun:  # the windows of every planet, each at its own shift (windows.sun_windowed)
            reference = next((p for p in inp.planets if p in (shaft.tooth_mesh or "").split("-")), inp.planets[0])
            sig, weights, teeth = sun_windowed(inp, settings, x, angle, n, reference)
        else:
            sig = angular_resample(inp.time, x, angle, n, name=shaft.name)
    except ValueError as exc:
        raise _Skip(str(exc)) from None
    if shaft.windowed:
        teeth, width = window_span(inp, settings, shaft.name, shaft.mesh_order)
        weights = planet_weights(inp, settings, shaft.body, sig.times, width)
    if weights is not None:
        avg = windowed_average(sig, weights)
    else:
        avg = synchronous_average(sig)
    if avg.averages < settings.min_averages * (1 - COVERAGE_TOL):
        what = (f"the planet windows ({teeth} teeth, {settings.planet_window}) give {avg.averages:.6g} averages at "
                f"the least covered angle over {sig.revolutions} revolutions" if weights is not None else
                f"the record holds {sig.revolutions} whole revolutions")
        raise _Skip(f"{what}, fewer than --min-averages = {settings.min_averages:g}; record a longer run "
                    f"(flexgear run --duration; simulation.duration in a configuration or a sweep) or lower "
                    "--min-averages")
    signals = tsa_signals(avg.values, shaft.mesh_order, settings.shaft_orders, max_order)
    tooth_angles = _tooth_angles(inp, shaft.body, shaft.tooth_mesh, angle, sig.direction)
    unsteady = None  # a noise-free simulation's residual above round-off: does it repeat with the shaft?
    if inp.simulated_noise_free and not ind.numerically_zero(signals.residual, signals.tsa):
        unsteady = half_record_change(sig, weights, signals.residual, shaft.mesh_order, settings.shaft_orders,
                                      max_order)
    out = ShaftAverage(shaft, avg, signals, speed, teeth, tooth_angles=tooth_angles,
                       fault_marks=_fault_marks(inp, shaft, tooth_angles, angle, sig.direction), unsteady=unsteady)
    mesh = inp.meshes.get(shaft.tooth_mesh) if not inp.planetary and shaft.tooth_mesh else None
    other = None if mesh is None else mesh.body_b if mesh.body_a == shaft.body else mesh.body_a
    if other in inp.teeth:  # a spur pair: does the residual sit where the partner's content stays?
        out.partner = (other, shaft.mesh_order, inp.teeth[other])
        out.partner_share = partner_share(signals.residual, shaft.mesh_order, inp.teeth[other], max_order,
                                          settings.shaft_orders)
    if shaft.name == "carrier":
        alpha = measuring_angle(settings, inp)
        out.planet_angles = {p: float(np.mod(sig.direction * (alpha - inp.planet_position(p)), TWO_PI))
                             for p in inp.planets}
    return out


# --------------------------------------------------------------------------- spectra

def _reference(inp: MonitorInput, shafts: list[Shaft]) -> Shaft:
    by_name = {s.name: s for s in shafts}
    if "carrier" in by_name:
        return by_name["carrier"]
    if not shafts:
        raise FlexgearError(f"{inp.path}: no gear with a recorded angle and tooth count; nothing to average")
    return shafts[0]


def _marks(inp: MonitorInput, ref: Shaft, shafts: list[Shaft], top: float) -> list:
    """Lines to mark in reference orders: mesh harmonics, their sidebands, shaft and planet-pass orders."""
    ref_rate = _speeds(inp, _relative_angle(inp, ref))[1]
    marks = []
    for k in range(1, int(top // ref.mesh_order) + 1):
        c = k * ref.mesh_order
        marks.append((float(c), f"{k}z" if k > 1 else "z", "mesh"))
        marks.extend((float(c + j), "", "sideband") for j in (-3, -2, -1, 1, 2, 3) if 0 < c + j <= top)
    for s in shafts:
        if s is ref:
            continue
        rate = _speeds(inp, _relative_angle(inp, s))[1] / ref_rate
        marks.append((rate, s.name, "shaft"))
    if ref.name == "carrier" and inp.planets:
        marks.append((float(len(inp.planets)), "planet pass", "planet"))
    merged: dict[float, tuple] = {}  # planets turn alike: one mark, the names joined
    for order, label, kind in marks:
        key = round(order, 9)
        if key in merged and label:
            o, lab, k = merged[key]
            both_planets = all(x == "planets" or x in inp.planets for x in (lab, label))
            merged[key] = (o, "planets" if both_planets else f"{lab}, {label}", k)
        else:
            merged.setdefault(key, (order, label, kind))
    return list(merged.values())


def _reference_spectra(inp: MonitorInput, settings: MonitorSettings, ref: Shaft, shafts: list[Shaft]):
    angle = _relative_angle(inp, ref)
    speed = _speeds(inp, angle)
    n = angle_grid(inp.fs, speed[0], ref.mesh_order, settings.samples_per_rev, ref.name)
    top = inp.passband_hz / speed[2]
    try:
        sig = angular_resample(inp.time, inp.signal - inp.signal.mean(), angle, n, name=ref.name)
    except ValueError as exc:  # too short a record for the reference shaft's order spectrum
        raise ConfigError(f"{ref.name}, the reference shaft of the order and envelope spectra: "
                          f"{str(exc).split(': ', 1)[-1]} (one revolution takes {1.0 / speed[1]:.3g} s: flexgear run "
                          "--duration; simulation.duration in a configuration or a sweep)") from None
    o, a = order_spectrum(sig)
    marks = _marks(inp, ref, shafts, top)
    mesh_hz = ref.mesh_order * speed[1]
    band = tuple(settings.band_hz) if settings.band_hz else (0.5 * mesh_hz, min(1.5 * mesh_hz, inp.passband_hz))
    if not band[0] < band[1]:
        raise ConfigError(f"the default envelope band {band[0]:g}-{band[1]:g} Hz is empty (mesh frequency "
                          f"{mesh_hz:g} Hz, trustworthy band {inp.passband_hz:g} Hz); give one with --band LOW HIGH")
    if not band[1] < inp.fs / 2:
        raise ConfigError(f"--band = {band[0]:g} {band[1]:g} Hz: the upper edge must lie below the record's Nyquist "
                          f"frequency {inp.fs / 2:g} Hz")
    if band[1] > inp.passband_hz * (1 + 1e-9):
        raise ConfigError(f"--band = {band[0]:g} {band[1]:g} Hz: the upper edge lies above the record's trustworthy "
                          f"band, {inp.passband_hz:g} Hz (the output's anti-alias filter bends the signal above it)")
    env = envelope(inp.signal, inp.fs, band)
    esig = angular_resample(inp.time, env - env.mean(), angle, n, name=ref.name)
    eo, ea = order_spectrum(esig)
    env_top = (band[1] - band[0]) / speed[2]
    env_marks = [m for m in marks if m[2] in ("shaft", "planet")] + [(1.0, ref.name, "shaft")]
    return (OrderSpectrum(ref.name, o, a, marks, None, top),
            OrderSpectrum(ref.name, eo, ea, env_marks, band, env_top))


# --------------------------------------------------------------------------- entry point

def _baseline_m2(paths, settings: MonitorSettings, current: MonitorInput, averaged: dict,
                 skip_empty: bool = False, cache: dict | None = None) -> tuple[dict[str, list[float]], list[str]]:
    """Variance of each shaft's residual signal in the healthy baseline results, read at the
    signal path of the ``current`` result (a baseline's own default could be another signal),
    band-limited at the highest order of that shaft in the current result (``averaged``, its
    ShaftAverages: a baseline run at another speed has another trustworthy band). A baseline
    whose shaft turns more than :data:`BASELINE_SPEED_TOL` faster or slower than the current
    record's is used, with a warning: another operating point has another vibration level.
    A baseline given twice, the current result itself, or one whose residual is numerically
    zero (a noise-free healthy simulation: no variance to normalise by, NA4 would grow with the
    number of baselines) is refused; with ``skip_empty`` the last kind is left out instead.
    ``cache`` (a dict, kept by the caller for one ``settings``) holds the baselines read and the
    averages taken, by file, signal, shaft and band: a severity table averages each healthy case
    once, not once per case."""
    cache = {} if cache is None else cache
    out: dict[str, list[float]] = {}
    names = []
    for p in paths:
        if (p, current.signal_path) not in cache:
            try:
                with warnings.catch_warnings(record=True) as said:
                    warnings.simplefilter("always")
                    inp = read_input(p, current.signal_path)
            except FlexgearError as exc:
                raise FlexgearError(f"--baseline {p}: {exc} (the baseline is read at the analysed signal, "
                                    f"{current.signal_path})") from None
            for w in said:  # the baseline's, not the analysed record's: named so
                warnings.warn(f"--baseline {p}: {w.message}", w.category, stacklevel=user_stacklevel())
            cache[p, current.signal_path] = inp, shafts_of(inp)[0]
        inp, shafts = cache[p, current.signal_path]
        if inp.path.resolve() == current.path.resolve():
            raise ConfigError(f"--baseline {p}: the result under analysis itself; give healthy records")
        if str(inp.path) in names:
            raise ConfigError(f"--baseline {p}: given twice; each healthy record once")
        for s in shafts:
            if s.name not in averaged:
                continue
            key = (p, current.signal_path, s.name, averaged[s.name].signals.max_order)
            if key not in cache:
                try:
                    sa = _average_shaft(inp, settings, s, key[-1])
                except _Skip:
                    sa = None
                cache[key] = None if sa is None else (  # speed, residual variance, residual numerically zero
                    sa.speed_hz[1], float(np.var(sa.signals.residual)),
                    ind.numerically_zero(sa.signals.residual, sa.signals.tsa))
            if cache[key] is None:
                continue
            theirs, variance, empty = cache[key]
            mine = averaged[s.name].speed_hz[1]
            if abs(theirs / mine - 1) > BASELINE_SPEED_TOL:
                warnings.warn(f"--baseline {p}: {s.name} turns at {theirs:.4g} rev/s there, at {mine:.4g} rev/s in "
                              f"the record analysed: NA4 is normalised by another operating point's residual "
                              "variance", stacklevel=user_stacklevel())
            if empty:
                if skip_empty:
                    continue
                raise ConfigError(f"--baseline {p}: {s.name}'s residual signal is numerically zero (RMS below "
                                  f"{ind.NUMERICAL_FLOOR:g} of its TSA's), as a noise-free healthy simulation's is: it "
                                  "has no variance to normalise NA4 by; use a baseline with measurement noise, or none "
                                  "(NA4 is then the residual's kurtosis)")
            out.setdefault(s.name, []).append(variance)
        names.append(str(inp.path))
    return out, names


def monitor(result, settings: MonitorSettings | None = None, baseline: Sequence = (),
            skip_empty_baselines: bool = False, baseline_cache: dict | None = None) -> MonitorReport:
    """Condition monitoring of one result file.

    Parameters
    ----------
    result : str, Path or Result
        A ``results.h5`` (or its directory), flexgear's or another program's in the same layout,
        or a :class:`~flexgear.results.store.Result` in memory (read through a temporary file;
        the report names it ``<in-memory result>``).
    settings : MonitorSettings, optional
        Options; defaults as documented there.
    baseline : sequence of paths or Results, optional
        Healthy results (same set, same signal path) whose residual variances normalise NA4.
    skip_empty_baselines : bool, optional
        Leave out a baseline shaft whose residual is numerically zero (a noise-free simulation)
        instead of refusing it, as a severity table does with its healthy cases.
    baseline_cache : dict, optional
        Kept between calls with the same ``settings`` (an empty dict at first): the baselines'
        averages are taken once and reused, as a severity table does for its healthy cases.

    Returns
    -------
    MonitorReport

    Raises
    ------
    ConfigError
        An option out of range, a planet window longer than the planet passing period, a band
        above the Nyquist frequency, or a shaft named in ``settings.shafts`` that cannot be
        averaged (too few revolutions: the message names ``--min-averages``).
    FlexgearError
        A missing or unusable file or signal path (the message lists the file's signals).
    """
    if isinstance(result, Result) or any(isinstance(b, Result) for b in baseline):
        return _monitor_in_memory(result, settings, baseline, skip_empty_baselines)
    settings = settings or MonitorSettings()
    settings.check()
    inp = read_input(result, settings.signal)
    shafts, skipped = shafts_of(inp)
    if settings.shafts is not None:
        known = {s.name for s in shafts} | set(skipped)
        unknown = [s for s in settings.shafts if s not in known]
        if unknown:
            raise ConfigError(f"--shafts {' '.join(unknown)}: not a shaft of this result; its shafts: "
                              f"{', '.join(sorted(known))}")
        for s in settings.shafts:
            if s in skipped:
                raise ConfigError(f"--shafts {s}: {skipped[s]}")
        shafts = [s for s in shafts if s.name in settings.shafts]
    every = shafts_of(inp)[0]
    orders, env = _reference_spectra(inp, settings, _reference(inp, every), every)
    done = {}
    for s in shafts:
        try:
            done[s.name] = _average_shaft(inp, settings, s)
        except _Skip as exc:
            if settings.shafts is not None:
                raise ConfigError(f"--shafts {s.name}: {exc}") from None
            skipped[s.name] = str(exc)
    if not done:
        raise ConfigError("no shaft could be averaged: " + "; ".join(f"{k}: {v}" for k, v in skipped.items()))
    base_m2, base_names = _baseline_m2(baseline, settings, inp, done, skip_empty_baselines, baseline_cache)
    for name, sa in done.items():
        sa.indicators, sa.notes = _indicators(sa.signals, base_m2.get(name, []), settings.sidebands)
    fixed_frame = inp.signal_mesh is None or inp.signal_path.split("/")[2].startswith("force_global")
    warn_leaks(inp.signal_path, inp.path, done, inp.signal_path.startswith("sensors/"), inp.planetary and fixed_frame)
    x = inp.signal - inp.signal.mean()
    sig_ind = {}
    for name in ("rms", "crest_factor", "kurtosis"):
        try:
            sig_ind[name] = getattr(ind, name)(x)
        except ValueError:
            sig_ind[name] = None  # a constant signal: undefined
    return MonitorReport(inp, settings, done, skipped, sig_ind, orders, env, base_names,
                         {name: len(base_m2.get(name, [])) for name in done})


def _monitor_in_memory(result, settings, baseline, skip_empty_baselines) -> MonitorReport:
    """:func:`monitor` of results held in memory: each written to a temporary file, read, and
    named ``<in-memory result>`` (``<in-memory baseline i>``) in the report."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory(prefix="flexgear-monitor-") as tmp:
        names = {}

        def file(r, name):
            if not isinstance(r, Result):
                return r
            path = save(r, Path(tmp) / f"{name}.h5")
            names[str(path)] = f"<in-memory {name.replace('_', ' ')}>"
            return path

        rep = monitor(file(result, "result"), settings, [file(b, f"baseline_{i}") for i, b in enumerate(baseline)],
                      skip_empty_baselines)
    rep.source.path = Path(names.get(str(rep.source.path), str(rep.source.path)))
    rep.baseline = [names.get(b, b) for b in rep.baseline]
    return rep
