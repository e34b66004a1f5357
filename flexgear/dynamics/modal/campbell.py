"""Campbell diagram data: natural frequencies against input speed, the mesh-frequency harmonics
and carrier sidebands, and their crossings.

In the stationary linearisation the natural frequencies do not depend on speed (speed effects
are left out, :mod:`flexgear.dynamics.modal.linearise`); the excitation lines grow in proportion to the
input speed: k f_m + j f_a with f_m = (f_m / f_in) f_in and f_a = (f_a / f_in) f_in, the ratios of
the model's kinematics. A crossing is the input speed at which a line meets a natural frequency:
f_in = f_n / (k r_m + j r_a).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import ConfigError


@dataclass(frozen=True)
class Crossing:
    """An excitation line meeting a natural frequency.

    Attributes
    ----------
    input_speed : float
        Input rotation frequency f_in [Hz] at the crossing.
    frequency : float
        The natural frequency [Hz].
    mode : int
        Mode number (1-based, as in the modal table).
    mode_type : str
    harmonic, sideband : int
        k and j of the line k f_m + j f_a.
    label : str
        e.g. ``4f_m+f_a``.
    """

    input_speed: float
    frequency: float
    mode: int
    mode_type: str
    harmonic: int
    sideband: int
    label: str


def line_label(k: int, j: int) -> str:
    """``k f_m + j f_a`` as text (``f_m``, ``4f_m-2f_a``)."""
    s = "f_m" if k == 1 else f"{k}f_m"
    if j:
        s += ("+" if j > 0 else "-") + ("f_a" if abs(j) == 1 else f"{abs(j)}f_a")
    return s


def crossings(frequencies, mode_types, mesh_ratio: float, carrier_ratio: float, speed_range,
              harmonics: int = 4, sidebands: int = 1) -> list[Crossing]:
    """Crossings of the lines k f_m + j f_a (k = 1..harmonics, |j| <= sidebands) with the
    natural frequencies, for input speeds in ``speed_range`` (f_min, f_max) [Hz].

    Parameters
    ----------
    frequencies : array_like
        Natural frequencies [Hz] (0 Hz modes are skipped).
    mesh_ratio, carrier_ratio : float
        f_m / f_in and f_a / f_in (0 for a spur pair).
    """
    lo, hi = speed_range
    if not (0 < lo < hi):
        raise ConfigError(f"speed range {speed_range!r}: must be 0 < f_min < f_max [Hz]")
    if not mesh_ratio > 0:
        raise ConfigError(f"mesh_ratio = {mesh_ratio!r}: must be > 0")
    out = []
    js = range(-sidebands, sidebands + 1) if carrier_ratio > 0 else [0]
    for i, (fn, t) in enumerate(zip(frequencies, mode_types)):
        if fn <= 0:
            continue
        for k in range(1, harmonics + 1):
            for j in js:
                rate = k * mesh_ratio + j * carrier_ratio
                if rate <= 0:
                    continue
                s = fn / rate
                if lo <= s <= hi:
                    out.append(Crossing(float(s), float(fn), i + 1, t, k, j, line_label(k, j)))
    return sorted(out, key=lambda c: c.input_speed)


def campbell_lines(mesh_ratio: float, carrier_ratio: float, speeds, harmonics: int = 4, sidebands: int = 1):
    """Excitation lines over ``speeds`` [Hz]: dict label -> frequencies [Hz]."""
    speeds = np.asarray(speeds, float)
    js = range(-sidebands, sidebands + 1) if carrier_ratio > 0 else [0]
    return {line_label(k, j): (k * mesh_ratio + j * carrier_ratio) * speeds
            for k in range(1, harmonics + 1) for j in js}
