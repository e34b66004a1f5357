"""Potential-energy (cantilever beam) model of a spur tooth with a root crack.

The published analytical model that the FE of :mod:`flexgear.stiffness.crack` is compared with
(Tian 2004; Wu, Zuo & Parey, J. Sound Vib. 317 (2008) 608-624; Chen & Shao, Eng. Fail. Anal. 18
(2011) 2149-2164), implemented from its equations: bending, shear and axial energy of the tooth
as a cantilever from the root circle, the crack reducing the effective section (Tian), the
crack tip placed where the FE crack's tip is, plus Yang & Lin's line-contact compliance.
Formulas and assumptions: the theory page *Root crack*, section *Against the potential-energy
model*. All SI: m, N, Pa; compliances m/N.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from ..gears.material import Material
from .hertz import plane_constants

#: Shear correction factor of the papers' rectangular sections.
SHEAR_FACTOR = 1.2


@dataclass(frozen=True)
class BeamCompliance:
    """Compliance components of a cantilever tooth for a unit force [m/N].

    Attributes
    ----------
    bending, shear, axial : float or ndarray
    """

    bending: object
    shear: object
    axial: object

    @property
    def total(self):
        """bending + shear + axial [m/N]."""
        return self.bending + self.shear + self.axial


def beam_compliance(x, height, d: float, h_load: float, alpha1: float, E: float, G: float,
                    width: float) -> BeamCompliance:
    """Compliance [m/N] of a cantilever of section height ``height(x)`` to a force at (d, h_load) inclined by ``alpha1``.

        Parameters
        ----------
        x, height : ndarray
            Axis positions from the clamp, increasing from 0, and section heights H [m]
            (trapezoidal rule from 0 to d).
        d, h_load : float
            Load position along the axis and its lateral offset [m].
        alpha1 : float
            Angle between the force and the normal of the axis [rad].
        E, G : float
            Young's and shear modulus [Pa].
        width : float
            Face width L [m].
    """
    x = np.asarray(x, float)
    H = np.asarray(height, float)
    keep = x < d
    xs = np.append(x[keep], d)
    Hs = np.append(H[keep], np.interp(d, x, H))
    if np.any(Hs <= 0):
        raise ConfigError("beam_compliance: section height <= 0 (a crack cutting the whole section)")
    ca, sa = math.cos(alpha1), math.sin(alpha1)
    I = Hs ** 3 * width / 12.0
    A = Hs * width
    m = ca * (d - xs) - sa * h_load
    return BeamCompliance(bending=float(np.trapezoid(m * m / (E * I), xs)),
                          shear=float(np.trapezoid(SHEAR_FACTOR * ca * ca / (G * A), xs)),
                          axial=float(np.trapezoid(sa * sa / (E * A), xs)))


@dataclass(frozen=True)
class BeamTooth:
    """The tooth of an external gear as the papers' cantilever: axis samples ``x`` from the root
    circle [m] and half thickness ``h`` [m] (straight h_b below the base circle, involute above)."""

    x: np.ndarray
    h: np.ndarray
    rf: float

    def at(self, radius: float, gear) -> tuple[float, float, float]:
        """(d, h_F, alpha_1) of a contact at ``radius`` on the involute: axis position [m],
        lateral offset [m] and force angle [rad]."""
        psi = float(gear.involute_half_angle(radius))
        a_y = math.acos(gear.rb / radius)
        return radius * math.cos(psi) - self.rf, radius * math.sin(psi), a_y - psi


def beam_tooth(gear, n: int = 4000) -> BeamTooth:
    """The papers' beam profile of ``gear`` (external), sampled at ``n`` involute radii."""
    if gear.internal:
        raise ConfigError(f"{gear.name}: the potential-energy tooth model here is for external gears")
    rb, rf, ra = gear.rb, gear.rf, gear.ra
    r = np.linspace(max(rb, rf), ra, n)
    psi = gear.involute_half_angle(r)
    x, h = r * np.cos(psi) - rf, r * np.sin(psi)
    if x[0] > 0:  # Chen & Shao: straight profile h = h_b from the root circle to the base circle
        xs = np.linspace(0.0, x[0], max(2, n // 10), endpoint=False)
        x, h = np.concatenate([xs, x]), np.concatenate([np.full(len(xs), h[0]), h])
    return BeamTooth(x=x, h=h, rf=float(rf))


def pe_tooth_compliance(gear, radius, material: Material | None = None,
                        formulation: str = "plane_stress", tip=None) -> BeamCompliance:
    """Tooth compliance of the potential-energy model at contact radii ``radius`` [m/N].

        Parameters
        ----------
        gear : SpurGear
            External gear; L = its face width.
        radius : float or array_like
            Contact radii on the involute [m].
        material : Material, optional
        formulation : {"plane_stress", "plane_strain"}
            E1 of the formulation for the bending and axial terms.
        tip : tuple (x_t, h_q), optional
            Crack tip: position along the axis from the root circle and lateral offset from the
            centre line, positive towards the loaded flank [m] (:func:`crack_tip_in_beam`). None:
            healthy.

        Returns
        -------
        BeamCompliance
            Arrays over ``radius``.
    """
    material = Material() if material is None else material
    E1, _ = plane_constants(material, formulation)
    G = material.G
    bt = beam_tooth(gear)
    H = 2.0 * bt.h
    if tip is not None:
        x_t, h_q = tip
        cut = bt.x >= x_t
        H = np.where(cut, bt.h + np.minimum(bt.h, h_q), H)
    out = [beam_compliance(bt.x, H, *bt.at(float(r), gear), E1, G, gear.face_width)
           for r in np.atleast_1d(radius)]
    return BeamCompliance(*(np.array([getattr(o, k) for o in out]) for k in ("bending", "shear", "axial")))


def crack_tip_in_beam(gear, crack) -> tuple[float, float]:
    """Tip of a :class:`flexgear.fe.crack.RootCrack` in the beam coordinates of
    :func:`pe_tooth_compliance`: (x_t, h_q) [m] (the crack's own tooth and flank as tooth 0's left)."""
    bt = beam_tooth(gear)
    a = 2.0 * math.pi * crack.tooth / gear.z
    x, y = crack.tip
    xl = math.cos(a) * x + math.sin(a) * y
    yl = (-math.sin(a) * x + math.cos(a) * y) * crack.side
    return xl - bt.rf, yl


def pe_contact_compliance(material: Material, width: float) -> float:
    """Yang & Lin's line-contact compliance 4 (1 - nu^2) / (pi E L) of two equal bodies [m/N]."""
    return 4.0 * (1.0 - material.nu ** 2) / (math.pi * material.E * width)


def pe_pair_stiffness(pair, r1, r2, material: Material | None = None, formulation: str = "plane_stress",
                      tip=None, cracked: int = 1) -> np.ndarray:
    """Single-pair stiffness of the potential-energy model [N/m]: both teeth (contact radii ``r1``,
    ``r2`` [m]) and the line contact in series, the tooth of gear ``cracked`` with the crack tip
    ``tip`` (None: healthy)."""
    material = Material() if material is None else material
    L = pair.face_width
    c1 = pe_tooth_compliance(pair.g1, r1, material, formulation, tip if cracked == 1 else None).total
    c2 = pe_tooth_compliance(pair.g2, r2, material, formulation, tip if cracked == 2 else None).total
    return 1.0 / (c1 + c2 + pe_contact_compliance(material, L))
