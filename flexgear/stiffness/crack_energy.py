"""Potential-energy (cantilever beam) model of a spur gear tooth with a root crack, the published
analytical model the FE of :mod:`flexgear.stiffness.crack` is compared with.

References
----------
* X. Tian, *Dynamic simulation for system response of gearbox including localized gear faults*,
  M.Sc. thesis, University of Alberta, 2004 (bending, shear and axial energies of the tooth as a
  non-uniform cantilever; the crack reduces the effective section).
* S. Wu, M. J. Zuo, A. Parey, *Simulation of spur gear dynamics and estimation of fault growth*,
  Journal of Sound and Vibration 317 (2008) 608-624 (the same crack model in a dynamic model).
* Z. Chen, Y. Shao, *Dynamic simulation of spur gear with tooth root crack propagating along
  tooth width and crack depth*, Engineering Failure Analysis 18 (2011) 2149-2164 (root circle
  below the base circle: a straight profile between them; a crack along the face width as
  independent slices in parallel).

Model (implemented here from the equations, not from the papers' code). The tooth is a
cantilever along its centre line, clamped at the root circle (x = 0), with half thickness h(x):
the involute above the base circle and, below it, the straight continuation h = h_b of Chen &
Shao. A force F along the line of action acts at the contact point (x = d, lateral offset
h_F) at the angle alpha_1 = alpha_y - psi to the normal of the centre line (alpha_y: pressure
angle at the contact radius, psi: half tooth angle there). With M(x) = F [cos(alpha_1) (d - x) -
sin(alpha_1) h_F] the stored energy gives the compliance::

    c_b = int_0^d [cos a1 (d - x) - sin a1 h_F]^2 / (E I(x)) dx
    c_s = int_0^d 1.2 cos^2 a1 / (G A(x)) dx,      c_a = int_0^d sin^2 a1 / (E A(x)) dx

with I = H^3 L / 12, A = H L over the section height H(x). Healthy: H = 2 h(x). Cracked (crack
tip at x_t, lateral offset h_q from the centre line, h_q = h_c - q sin(nu) for a crack of depth
q at angle nu from a start at offset h_c): every section above the tip's level that reaches past
h_q keeps only the part between the far flank and the tip's offset::

    H(x) = h(x) + min(h(x), h_q)   for x >= x_t,      H(x) = 2 h(x) below

(Tian's effective section: the material on the cracked side of the line through the tip
parallel to the centre line carries no bending stress up to where the flank comes inside it,
h(x) = h_q, Tian's g_c). With the crack starting at the root circle, as in the papers, x_t <= 0
and the rule reduces to theirs; here the tip is placed where the FE crack's tip is, so both
models cut the same ligament. The model has no crack-tip singularity, no rotation of the
tooth's root (fillet foundation) and keeps the moment about the centre line (no shift of the
neutral axis in the reduced section); E is the plane formulation's E1 (plane stress: E).
Contact: the load-independent line-contact compliance of Yang & Lin used by these papers,
c_h = 4 (1 - nu^2) / (pi E L).

All SI: m, N, Pa; compliances m/N.
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
    """Compliance of a cantilever of section height ``height(x)`` (x from the clamp) [m/N] to a
    force at (d, h_load) inclined by ``alpha1`` to the normal of its axis (module docstring).

    Parameters
    ----------
    x, height : ndarray
        Samples of the axis position and section height H [m], x increasing from 0; integrated
        from 0 to d with the trapezoidal rule on the samples (plus the point d).
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
        E1 of the formulation for the bending and axial terms (plane stress: E).
    tip : tuple (x_t, h_q), optional
        Crack tip in the beam's coordinates: position along the axis from the root circle and
        lateral offset from the centre line, positive towards the loaded flank [m]
        (:func:`crack_tip_in_beam`). None: healthy.

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
    L = min(pair.g1.face_width, pair.g2.face_width)
    c1 = pe_tooth_compliance(pair.g1, r1, material, formulation, tip if cracked == 1 else None).total
    c2 = pe_tooth_compliance(pair.g2, r2, material, formulation, tip if cracked == 2 else None).total
    return 1.0 / (c1 + c2 + pe_contact_compliance(material, L))
