"""Rigid kinematics of the meshes: which tooth engages where, and the characteristic frequencies of local faults, eccentricity and pitch errors.

Engagement: in a mesh whose line of action touches the gear's base circle at the global polar
angle gamma, flank ``side`` of tooth k is at the roll angle (:func:`flank_roll_angle`)::

    xi = s sigma (theta + 2 pi k / z + s psi_b - gamma)   (mod 2 pi, in [-pi, pi))

(theta the gear's angle, s = +1 left / -1 right, sigma = +1 external / -1 internal, psi_b the
half tooth angle at the base circle) and is in mesh while xi lies in
:func:`contact_roll_range`. For a pair with a at the origin and b in the direction beta (internal:
the ring at the origin), the mesh loading a's flank s_a has gamma_a = beta - s_a alpha_w; b's
flank is :func:`mate_flank`, gamma_b = gamma_a + pi (external) or gamma_a (internal).

Characteristic frequencies of a planetary set with a fixed ring and of a spur pair after Feng &
Zuo (2012, J. Sound Vib. 331, 4919-4939), sidebands after McFadden & Smith (1985) and Inalpolat
& Kahraman (2009, J. Sound Vib. 323, 677-696): sun N f_m / z_s, planet f_m / z_p (one flank) or
2 f_m / z_p (both), ring N f_c, spur gear i f_i (both gears: the hunting tooth frequency);
eccentricity and pitch errors modulate at the gear's rotation relative to the carrier. Table and
reasons: the guide page on faults, section *Characteristic frequencies*.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .geometry import GearPair, SpurGear


# ============================================================================================
# engagement geometry
# ============================================================================================
def mate_flank(side_a: int, internal: bool) -> int:
    """The flank of gear b that meets flank ``side_a`` of gear a: the same in an external mesh,
    the opposite in an internal one (module :mod:`flexgear.gears.faults`, Flanks)."""
    return -side_a if internal else side_a


def flank_roll_angle(gear: SpurGear, tooth, side: int, theta, gamma):
    """Roll angle [rad] of flank ``side`` of tooth ``tooth`` at the line of action that touches the
    base circle at the global polar angle ``gamma`` [rad], with the gear at angle ``theta`` [rad]
    (module docstring); arrays broadcast."""
    sigma = -1.0 if gear.internal else 1.0
    psi_b = float(gear.involute_half_angle(gear.rb))
    a = np.asarray(theta) + 2 * np.pi * np.asarray(tooth) / gear.z + side * psi_b - np.asarray(gamma)
    return side * sigma * (np.mod(a + np.pi, 2 * np.pi) - np.pi)


def contact_roll_range(pair: GearPair) -> tuple[tuple[float, float], tuple[float, float]]:
    """Roll angles [rad] of the path of contact on gear 1 and on gear 2 of ``pair``, each as
    (start, end) with start < end: the involute between the start of the active profile and the
    mate's or own tip (ISO 21771 path of contact, :attr:`~flexgear.gears.geometry.GearPair.path_of_contact`)."""
    g1, g2, aw = pair.g1, pair.g2, pair.alpha_w
    gf, ga = pair.path_of_contact
    t = math.tan(aw)
    r1 = ((g1.rb * t - gf) / g1.rb, (g1.rb * t + ga) / g1.rb)
    if pair.internal:  # the ring's roll length grows along the path towards the pinion's tip
        r2 = ((g2.rb * t - gf) / g2.rb, (g2.rb * t + ga) / g2.rb)
    else:
        r2 = ((g2.rb * t - ga) / g2.rb, (g2.rb * t + gf) / g2.rb)
    return r1, r2


def active_radii(pair: GearPair) -> tuple[tuple[float, float], tuple[float, float]]:
    """Radii [m] (low, high) of the active flank of gear 1 and of gear 2 of ``pair``."""
    out = []
    for g, (a, b) in zip((pair.g1, pair.g2), contact_roll_range(pair)):
        ra, rb = g.rb * math.hypot(1.0, a), g.rb * math.hypot(1.0, b)
        out.append((min(ra, rb), max(ra, rb)))
    return out[0], out[1]


def line_of_action(pair: GearPair, beta, side_a: int):
    """Base-circle tangent angles (gamma_a, gamma_b) [rad] of the line of action that loads flank
    ``side_a`` of gear 1, with gear 2 (external) or the planet (internal: gear 1 in the ring) in
    the direction ``beta`` [rad] (module docstring); arrays broadcast."""
    beta = np.asarray(beta, float)
    ga = beta - side_a * pair.alpha_w
    return ga, (ga if pair.internal else ga + np.pi)


def in_mesh(gear: SpurGear, tooth, side: int, theta, gamma, roll_range) -> np.ndarray:
    """True where flank ``side`` of tooth ``tooth`` lies on the path of contact (roll angle within
    ``roll_range`` = (start, end) [rad]; :func:`contact_roll_range`)."""
    xi = flank_roll_angle(gear, tooth, side, theta, gamma)
    return (xi >= roll_range[0]) & (xi <= roll_range[1])


# ============================================================================================
# characteristic frequencies
# ============================================================================================
@dataclass(frozen=True)
class SetKinematics:
    """Rotation frequencies [Hz] of a gear set (signed, counter-clockwise positive), from which
    the characteristic frequencies follow.

    ``rotation`` holds every gear (``pinion``, ``wheel``; ``sun``, ``planet``, ``ring``) and, for
    a planetary set, ``carrier``; a planet's entry is its absolute rotation (all planets turn
    alike). ``planets`` is N (0 for a spur pair); ``teeth`` the tooth counts."""

    kind: str
    teeth: dict
    rotation: dict
    planets: int = 0

    @property
    def carrier(self) -> float:
        return self.rotation.get("carrier", 0.0)

    def relative(self, gear: str) -> float:
        """|f_gear - f_carrier| [Hz]: the rotation relative to the frame the meshes stand still in."""
        return abs(self.rotation[gear] - self.carrier)

    @property
    def mesh(self) -> float:
        """Gear mesh frequency f_m [Hz] = z |f - f_c| of any gear of the set."""
        g = "pinion" if self.kind == "spur" else "sun"
        return self.teeth[g] * self.relative(g)


def spur_kinematics(z_pinion: int, z_wheel: int, f_pinion: float) -> SetKinematics:
    """A fixed-axis pair: the wheel turns at -f_pinion z_pinion / z_wheel."""
    return SetKinematics("spur", {"pinion": z_pinion, "wheel": z_wheel},
                         {"pinion": f_pinion, "wheel": -f_pinion * z_pinion / z_wheel})


def planetary_kinematics(z_sun: int, z_planet: int, z_ring: int, planets: int, f_sun: float) -> SetKinematics:
    """A planetary set with a fixed ring driven through the sun at ``f_sun`` [Hz] (Willis):
    f_c = f_s z_s / (z_s + z_r), f_p = f_c - (f_s - f_c) z_s / z_p."""
    fc = f_sun * z_sun / (z_sun + z_ring)
    fp = fc - (f_sun - fc) * z_sun / z_planet
    return SetKinematics("planetary", {"sun": z_sun, "planet": z_planet, "ring": z_ring},
                         {"sun": f_sun, "planet": fp, "ring": 0.0, "carrier": fc}, planets)


def local_fault_frequency(kin: SetKinematics, gear: str, both_flanks: bool = False) -> float:
    """Rate [Hz] at which a local fault on one tooth of ``gear`` engages (module docstring): the
    fault characteristic frequency. ``both_flanks`` matters for a planet only (its flanks mesh with
    the sun and the ring in turn); on the other gears one tooth flank meets every mate alike."""
    z = kin.teeth[gear]
    if kin.kind == "spur":
        return kin.relative(gear)
    if gear == "planet":
        return (2.0 if both_flanks else 1.0) * kin.mesh / z
    return kin.planets * kin.mesh / z


def hunting_tooth_frequency(kin: SetKinematics) -> float:
    """Rate [Hz] at which the same pair of teeth of a spur pair meets again, f_m gcd(z1, z2) /
    (z1 z2)."""
    z1, z2 = kin.teeth["pinion"], kin.teeth["wheel"]
    return kin.mesh * math.gcd(z1, z2) / (z1 * z2)


@dataclass(frozen=True)
class FaultLine:
    """A characteristic frequency [Hz] with its label (``f_fs``, ``f_m+f_fs``, ...)."""

    freq: float
    label: str


def fault_lines(kin: SetKinematics, gear: str, kind: str = "local", both_flanks: bool = False,
                harmonics: int = 3, sidebands: int = 2) -> list[FaultLine]:
    """Characteristic lines of a fault or error on ``gear``: its fundamental f_f and harmonics
    j f_f (j <= ``harmonics``) and the sidebands k f_m +- j f_f (k <= 2, j <= ``sidebands``)
    around the mesh harmonics. ``kind``: ``"local"`` (crack, spall, chip, missing tooth: f_f =
    :func:`local_fault_frequency`) or ``"distributed"`` (eccentricity, pitch errors: f_f = the
    gear's rotation relative to the carrier)."""
    if kind == "local":
        ff = local_fault_frequency(kin, gear, both_flanks)
        sym = "f_f"
    elif kind == "distributed":
        ff = kin.relative(gear)
        sym = "f_r"
    else:
        raise ValueError(f"fault_lines: kind = {kind!r}: 'local' or 'distributed'")
    out = [FaultLine(j * ff, sym if j == 1 else f"{j}{sym}") for j in range(1, harmonics + 1)]
    fm = kin.mesh
    for k in (1, 2):
        m = "f_m" if k == 1 else f"{k}f_m"
        for j in range(1, sidebands + 1):
            s = sym if j == 1 else f"{j}{sym}"
            out += [FaultLine(k * fm - j * ff, f"{m}-{s}"), FaultLine(k * fm + j * ff, f"{m}+{s}")]
    return sorted((ln for ln in out if ln.freq > 0), key=lambda ln: ln.freq)
