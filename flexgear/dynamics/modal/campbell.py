"""Campbell diagram data: natural frequencies against input speed, the mesh-frequency harmonics,
their crossings, and which crossings planet phasing lets excite their mode.

In the stationary linearisation the natural frequencies do not depend on speed (speed effects
are left out, :mod:`flexgear.dynamics.modal.linearise`); the excitation lines k f_m grow in
proportion to the input speed: f_m = r_m f_in with r_m = f_m / f_in from the model's kinematics. A
crossing is the input speed at which a line meets a natural frequency: f_in = f_n / (k r_m).

The mesh excitation acts in the carrier frame at k f_m; the carrier sidebands k f_m +- j f_a are
what a sensor fixed to the housing hears of it as the planets pass, not separate excitations,
so they are not crossings.

Planet phasing (Parker 2000, J. Sound Vib. 236(4), 561-573; mode types of Lin & Parker 1999):
with N equally spaced planets, planet n (at psi_n = 2 pi n / N) meshes z_s psi_n / (2 pi) mesh
cycles after planet 0, so the k-th mesh harmonic of its sun-planet and ring-planet mesh forces
(z_r = -z_s modulo N) carries the phase exp(i k z_s psi_n): the excitation is the cyclic
harmonic j = +-k z_s (mod N) of the set. A mode of cyclic harmonic j (:func:`~.system.classify`)
is excited only by the harmonics with k z_s = +-j (mod N): rotational modes (j = 0) where
k z_s / N is an integer, translational ones (j = +-1) where (k z_s +- 1) / N is, planet modes
(2 <= j <= N - 2) otherwise; the other crossings are suppressed by phasing.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import ConfigError
from .system import PLANET, ROTATIONAL, TRANSLATIONAL


@dataclass(frozen=True)
class Crossing:
    """A mesh harmonic k f_m meeting a natural frequency.

    Attributes
    ----------
    input_speed : float
        Input rotation frequency f_in [Hz] at the crossing.
    frequency : float
        The natural frequency [Hz].
    mode : int
        Mode number (1-based, as in the modal table).
    mode_type : str
    harmonic : int
        k of the line k f_m.
    label : str
        e.g. ``4f_m``.
    excited : bool
        Whether planet phasing lets the harmonic excite the mode (:func:`excites`; always True
        for a spur pair or modes without a type).
    """

    input_speed: float
    frequency: float
    mode: int
    mode_type: str
    harmonic: int
    label: str
    excited: bool = True


def line_label(k: int) -> str:
    """``k f_m`` as text (``f_m``, ``4f_m``)."""
    return "f_m" if k == 1 else f"{k}f_m"


def phasing_harmonic(k: int, sun_teeth: int, planets: int) -> int:
    """The cyclic harmonic j (0 <= j <= N / 2) of the k-th mesh harmonic's excitation with
    ``planets`` = N equally spaced planets and a sun of ``sun_teeth`` = z_s teeth: k z_s modulo
    N, folded (j and N - j are one degenerate pair)."""
    if not (int(planets) >= 1 and int(sun_teeth) >= 1 and int(k) >= 1):
        raise ConfigError(f"phasing_harmonic: k = {k!r}, sun_teeth = {sun_teeth!r} and planets = {planets!r} "
                          "must be integers >= 1")
    r = (int(k) * int(sun_teeth)) % int(planets)
    return min(r, int(planets) - r)


def excites(k: int, mode_type: str, sun_teeth: int | None, planets: int, mode_harmonic: int = -1,
            central_translation: bool = True) -> bool:
    """Whether the k-th mesh harmonic can excite a mode of type ``mode_type`` (and, if >= 0, cyclic
    harmonic ``mode_harmonic``) of a set with ``planets`` equally spaced planets and a sun of
    ``sun_teeth`` teeth (module docstring). A spur pair (no planets or no tooth count) and an
    unclassified mode (``-``) are always excited. Without central translation (the central
    members only turn) the j = +-1 modes are planet modes too."""
    if not planets or sun_teeth is None or mode_type not in (ROTATIONAL, TRANSLATIONAL, PLANET):
        return True
    j = phasing_harmonic(k, sun_teeth, planets)
    if mode_harmonic is not None and mode_harmonic >= 0:
        return min(mode_harmonic % planets, (-mode_harmonic) % planets) == j
    if mode_type == ROTATIONAL:
        return j == 0
    if mode_type == TRANSLATIONAL:
        return j == 1
    return j >= (2 if central_translation else 1)


def crossings(frequencies, mode_types, mesh_ratio: float, speed_range, harmonics: int = 4, *,
              sun_teeth: int | None = None, planets: int = 0, mode_harmonics=None,
              central_translation: bool = True) -> list[Crossing]:
    """Crossings of the lines k f_m (k = 1..harmonics) with the natural frequencies, for input
    speeds in ``speed_range`` (f_min, f_max) [Hz], each marked ``excited`` or not by planet
    phasing (:func:`excites`).

    Parameters
    ----------
    frequencies : array_like
        Natural frequencies [Hz] (0 Hz modes are skipped).
    mode_types : sequence of str
        Lin & Parker mode types (``-``: unclassified).
    mesh_ratio : float
        f_m / f_in (f_m the mesh frequency in the carrier frame for a planetary set).
    sun_teeth, planets : int
        z_s and the number N of equally spaced planets (None, 0: a spur pair, no phasing).
    mode_harmonics : array_like of int, optional
        Each mode's dominant cyclic harmonic (``ModalResult.harmonic``; -1: unknown).
    central_translation : bool
        Whether a central member can translate (``LinearSystem.has_central_translation``).
    """
    lo, hi = speed_range
    if not (0 < lo < hi):
        raise ConfigError(f"speed range {speed_range!r}: must be 0 < f_min < f_max [Hz]")
    if not mesh_ratio > 0:
        raise ConfigError(f"mesh_ratio = {mesh_ratio!r}: must be > 0")
    if not (isinstance(harmonics, (int, np.integer)) and harmonics >= 1):
        raise ConfigError(f"harmonics = {harmonics!r}: must be an integer >= 1")
    mh = [-1] * len(frequencies) if mode_harmonics is None else [int(h) for h in mode_harmonics]
    out = []
    for i, (fn, t) in enumerate(zip(frequencies, mode_types)):
        if fn <= 0:
            continue
        for k in range(1, harmonics + 1):
            s = fn / (k * mesh_ratio)
            if lo <= s <= hi:
                out.append(Crossing(float(s), float(fn), i + 1, t, k, line_label(k),
                                    excites(k, t, sun_teeth, planets, mh[i], central_translation)))
    return sorted(out, key=lambda c: c.input_speed)


def modal_excites(modal, k: int, sun_teeth: int | None) -> list[bool]:
    """Whether each mode of a :class:`~flexgear.dynamics.modal.system.ModalResult` can respond
    to the k-th mesh harmonic (:func:`excites` with its types, cyclic harmonics, planets and
    central translation; ``sun_teeth`` z_s, None: no phasing)."""
    sysl = modal.system
    mh = [-1] * len(modal.frequencies) if modal.harmonic is None else modal.harmonic
    return [excites(k, t, sun_teeth, len(sysl.planets), int(h), sysl.has_central_translation())
            for t, h in zip(modal.mode_type, mh)]


def modal_crossings(modal, mesh_ratio: float, speed_range, harmonics: int = 4,
                    sun_teeth: int | None = None) -> list[Crossing]:
    """:func:`crossings` of a :class:`~flexgear.dynamics.modal.system.ModalResult`: its mode types,
    cyclic harmonics, planets and central translation; ``sun_teeth`` z_s (None: no phasing)."""
    sysl = modal.system
    return crossings(modal.frequencies, modal.mode_type, mesh_ratio, speed_range, harmonics,
                     sun_teeth=sun_teeth, planets=len(sysl.planets), mode_harmonics=modal.harmonic,
                     central_translation=sysl.has_central_translation())


def campbell_lines(mesh_ratio: float, speeds, harmonics: int = 4):
    """Excitation lines over ``speeds`` [Hz]: dict label -> frequencies [Hz] of k f_m."""
    speeds = np.asarray(speeds, float)
    return {line_label(k): k * mesh_ratio * speeds for k in range(1, harmonics + 1)}
