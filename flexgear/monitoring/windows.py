"""Planet-separation windows for a signal heard from a fixed point of a planetary set.

A planet's mesh is heard mainly while the planet passes the measuring point. Windowing the record
around each pass separates one planet's vibration (McFadden 1991, 1994); the sun meshes with
every planet, and its own average is built from all of them (McFadden 1991): each
planet's windows are resampled against the sun angle shifted by that planet's position on the
carrier, so that every window contributes the sun tooth it meets at the same angle of the
average. Without the shifts a plain average holds each sun tooth once per planet, a third of a
turn apart in a three-planet set. Window shapes and weights: :func:`~flexgear.monitoring.tsa.window_weights`.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError, FlexgearError
from .order import AngleSignal, angular_resample
from .tsa import synchronous_average, window_weights

__all__ = ["DEFAULT_SENSOR_ANGLE_DEG", "measuring_angle", "advance_step", "window_span", "planet_weights",
           "carrier_synchronous", "sun_windowed"]

TWO_PI = 2.0 * np.pi
#: measuring point [deg] when neither --sensor-angle nor the analysed sensor gives one
DEFAULT_SENSOR_ANGLE_DEG = 90.0


def measuring_angle(settings, inp) -> float:
    """The measuring point's angle about the set's centre [rad]: ``--sensor-angle`` if given,
    else the analysed sensor's (``inp.sensor_angle_deg``), else 90 deg (above the centre)."""
    for deg in (settings.sensor_angle_deg, inp.sensor_angle_deg, DEFAULT_SENSOR_ANGLE_DEG):
        if deg is not None:
            return math.radians(deg)


def _wrap(a):
    return (np.asarray(a) + np.pi) % TWO_PI - np.pi


def advance_step(inp, name: str, teeth: int) -> int:
    """The step [teeth] by which the tooth of gear ``name`` (``teeth`` teeth) that meets its
    planet at the measuring point advances from pass to pass, in tooth-meshing periods: a
    planet's g = gcd(z_ring, z_planet) (its own passes, one carrier turn apart); the sun's
    gcd(z_sun, (z_sun + z_ring) / N) (every planet's pass, 1/N of a turn apart; MERCURY 1-A: 6,
    so its windows see the sun's teeth in 4 groups), 1 where (z_sun + z_ring) / N is not whole."""
    z_ring = inp.teeth.get("ring")
    if z_ring is None:
        raise FlexgearError(f"{name}: planet windows need the ring's tooth count (body attribute z)")
    if name != "sun":
        return math.gcd(z_ring, teeth)
    n_planets = len(inp.planets)
    per_pass = (teeth + z_ring) // n_planets
    return math.gcd(teeth, per_pass) if per_pass * n_planets == teeth + z_ring else 1


def window_span(inp, settings, name: str, teeth: int) -> tuple[int, float]:
    """The planet window's width in tooth-meshing periods (``--window-teeth``, default the
    gear's :func:`advance_step` g for the rectangular window, 2 g for Hann, so that the windows
    of successive passes tile every tooth) and in carrier angle [rad]; refused wider than the
    planet passing period."""
    g = advance_step(inp, name, teeth)
    z_ring = inp.teeth["ring"]
    teeth = settings.window_teeth or (2 * g if settings.planet_window == "hann" else g)
    n_planets = len(inp.planets)
    width = teeth * TWO_PI / z_ring  # carrier angle of `teeth` tooth-meshing periods
    if width > TWO_PI / n_planets:
        raise ConfigError(f"--window-teeth = {teeth}: the planet window spans {teeth} tooth-meshing periods, "
                          f"longer than the planet passing period ({z_ring}/{n_planets} = {z_ring / n_planets:g} "
                          f"periods: {n_planets} planets on a {z_ring}-tooth ring); choose at most "
                          f"{z_ring // n_planets}")
    return teeth, width


def planet_weights(inp, settings, planet: str, times, width: float) -> np.ndarray:
    """The window weight of ``planet`` at each instant of ``times`` [s]: centred where it passes
    the measuring point, ``width`` [rad of carrier angle] wide."""
    carrier = np.interp(times, inp.time, inp.angles["carrier"])
    offset = _wrap(carrier + inp.planet_position(planet) - measuring_angle(settings, inp))
    return window_weights(offset, width / 2, settings.planet_window)


#: Samples per carrier revolution of the carrier-synchronous part :func:`sun_windowed` removes
CARRIER_SAMPLES = 4096


def carrier_synchronous(inp, signal) -> np.ndarray:
    """The part of ``signal`` that repeats with the carrier (its plain average against the
    carrier's angle relative to the ring, read back at every instant): what the planets' passes
    put into a fixed sensor's record, their mean loads and mesh tones through the moving paths."""
    angle = inp.angles["carrier"] - inp.angles["ring"] if "ring" in inp.angles else inp.angles["carrier"]
    sig = angular_resample(inp.time, signal, angle, CARRIER_SAMPLES, name="carrier")
    avg = synchronous_average(sig).values
    grid = TWO_PI * np.arange(CARRIER_SAMPLES) / CARRIER_SAMPLES
    return np.interp(np.mod(sig.direction * angle, TWO_PI), grid, avg, period=TWO_PI)


def sun_windowed(inp, settings, signal, angle, samples_per_rev: int, reference: str,
                 name: str = "sun") -> tuple[AngleSignal, np.ndarray, int]:
    """The sun's record as McFadden (1991) averages it: for each planet p, ``signal`` resampled
    against the sun's angle relative to the carrier minus (psi_p - psi_ref), the planets'
    positions on the carrier, with p's windows as weights; the planets' revolutions interleaved
    in time order (so that the record's halves are its first and second halves of time). The
    sun tooth that ``reference`` meets keeps its angle. Returns the signal, its weights and the
    window width in tooth-meshing periods.

    The part of the signal that repeats with the carrier (:func:`carrier_synchronous`) is removed
    first: the sun tooth at the sensor repeats every z_sun / g passes (:func:`advance_step`), so
    within the windows whatever repeats with the carrier also repeats with those groups of sun
    teeth, and the planets' passes (a housing sensor's loudest content) would otherwise stand in
    the sun's average as a line at order z_sun / g (9 N on MERCURY 1-A's planet-pass signal, whose
    healthy sun residual is 0.3 N). The sun's own content at the orders that are multiples of
    z_sun / g repeats with the carrier too and goes with it."""
    signal = np.asarray(signal, dtype=float) - carrier_synchronous(inp, signal)
    teeth, width = window_span(inp, settings, name, inp.teeth[name])
    rows = []
    for k, p in enumerate(inp.planets):
        shift = inp.planet_position(p) - inp.planet_position(reference)
        sig = angular_resample(inp.time, signal, np.asarray(angle) - shift, samples_per_rev, name=name)
        w = planet_weights(inp, settings, p, sig.times, width)
        r0 = int(round(sig.angle0 / TWO_PI))
        for r in range(sig.revolutions):
            part = slice(r * samples_per_rev, (r + 1) * samples_per_rev)
            rows.append((r0 + r, k, sig.values[part], w[part], sig.times[part]))
    rows.sort(key=lambda row: row[:2])
    out = AngleSignal(np.concatenate([row[2] for row in rows]), samples_per_rev, rows[0][0] * TWO_PI,
                      sig.direction, np.concatenate([row[4] for row in rows]))
    return out, np.concatenate([row[3] for row in rows]), teeth
