"""Contact damping as a mesh damping ratio: conversion to and from the IMPACT law's C.

The ADAMS IMPACT law (:mod:`flexgear.dynamics.contact.laws`) per tooth pair is::

    F = K delta^e + STEP(delta; 0, 0, d, C) d(delta)/dt

Gear dynamics usually states mesh damping as a ratio zeta (0.03-0.1 is the usual range) of the
mesh's torsional oscillator: the two gears' inertias coupled by the mesh stiffness k along the
line of action, c = 2 zeta sqrt(k m_e). At the static operating point (the conversion's
definitions, used in both directions):

* W: the static normal force of the mesh from the nominal load torque (the largest |T| of a
  torque table): spur pair W = T / r_b of the loaded gear; planetary set with the ring fixed,
  per planet, the same for its sun and ring mesh: W = T_sun / (N r_b,sun), with
  T_sun = T_carrier z_s / (z_s + z_r) when the carrier is loaded;
* delta_0 = (W / K)^(1/e): the penetration of one tooth pair carrying W (the single-contact
  zone, the largest static penetration);
* k = dF/d delta = e K delta_0^(e-1) = e W / delta_0: the tangent mesh stiffness there;
* m_e = 1 / (r_b,a^2 / J_a + r_b,b^2 / J_b): the equivalent mass of the pair on the line of
  action, each gear turning about its own axis. A gear held by the model (the driven gear, at
  prescribed speed; the fixed ring) is infinitely heavy, its term drops out: for the spur preset
  m_e = J_wheel / r_b,wheel^2, and for both planetary meshes with the sun driven and the ring
  fixed m_e = J_planet / r_b,planet^2 (carrier and sun motion, other meshes and the planet pin's
  translation are left out: the ratio describes the mesh, not a mode of the whole set);
* the damping acting at delta_0 is STEP(delta_0; 0, 0, d, C) = C s(delta_0 / d) with
  s(x) = x^2 (3 - 2 x) for x < 1, so C = 2 zeta sqrt(k m_e) / s(delta_0 / d).

For the paper's spur pair (K = 3e5 N/mm^1.3, e = 1.3, d = 0.3 mm, 200 N m on the wheel:
W = 10.14 kN, delta_0 = 74 um, k = 1.79e8 N/m, m_e = 0.117 kg) its C = 3000 N s/mm is
zeta ~ 50 (and ~ 20 at the 43 um of a pair sharing the load with another): heavily overdamped.
"""
from __future__ import annotations

import math


def step_fraction(delta: float, d: float) -> float:
    """s = STEP(delta; 0, 0, d, 1): the fraction of C acting at penetration ``delta`` [m]."""
    x = min(max(delta / d, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def operating_penetration(force: float, K: float, e: float) -> float:
    """Static penetration [m] of one tooth pair carrying ``force`` [N] (K in N/m^e)."""
    return (force / K) ** (1.0 / e)


def tangent_stiffness(force: float, K: float, e: float) -> float:
    """Tangent stiffness dF/d delta [N/m] of the IMPACT spring at the penetration carrying
    ``force`` [N]: e K delta_0^(e-1) = e force / delta_0."""
    return e * force / operating_penetration(force, K, e)


def equivalent_mass(members) -> float:
    """Equivalent mass [kg] on the line of action of gears turning about fixed axes.

    Parameters
    ----------
    members : iterable of (r_b [m], J [kg m^2] or None)
        Base radius and polar moment of inertia of each gear; ``None`` (or inf) for a gear
        the model holds (prescribed speed, fixed), which drops out.
    """
    inv = sum(rb * rb / J for rb, J in members if J is not None and math.isfinite(J))
    if not inv > 0:
        raise ValueError("equivalent_mass: both gears are held; the mesh has no oscillating mass")
    return 1.0 / inv


def damping_from_ratio(zeta: float, force: float, K: float, e: float, d: float, m_e: float) -> float:
    """IMPACT C [N s/m] that gives the mesh damping ratio ``zeta`` at the operating point.

    Parameters
    ----------
    zeta : float
        Mesh damping ratio [-].
    force : float
        Static mesh normal force W [N].
    K, e, d : float
        IMPACT stiffness [N/m^e], exponent [-], full-damping penetration [m].
    m_e : float
        Equivalent mass [kg] (:func:`equivalent_mass`).
    """
    delta0 = operating_penetration(force, K, e)
    c = 2.0 * zeta * math.sqrt(tangent_stiffness(force, K, e) * m_e)
    return c / step_fraction(delta0, d)


def ratio_from_damping(C: float, force: float, K: float, e: float, d: float, m_e: float) -> float:
    """Mesh damping ratio [-] of an IMPACT C [N s/m] at the operating point (inverse of
    :func:`damping_from_ratio`)."""
    delta0 = operating_penetration(force, K, e)
    return C * step_fraction(delta0, d) / (2.0 * math.sqrt(tangent_stiffness(force, K, e) * m_e))


def _max_abs(profile) -> float:
    if isinstance(profile, (int, float)):
        return abs(float(profile))
    return max(abs(v) for _, v in profile)


def operating_point(cfg, pair) -> tuple[float, float]:
    """Static mesh force W [N] and equivalent mass m_e [kg] of ``pair`` in a validated
    configuration (see the module docstring for the definitions).

    Parameters
    ----------
    cfg : flexgear.config.Config
    pair : flexgear.gears.geometry.GearPair
    """
    torque = _max_abs(cfg.load["torque"])
    driven = cfg.drive["body"]
    if cfg.kind == "spur":
        force = torque / cfg.gears[cfg.load["body"]].rb
    else:
        s, r = cfg.gears["sun"], cfg.gears["ring"]
        t_sun = torque * s.z / (s.z + r.z) if cfg.load["body"] == "carrier" else torque
        force = t_sun / (cfg.planetary["planets"] * s.rb)
    members = []
    for g in (pair.g1, pair.g2):
        held = g.name == driven or (cfg.kind == "planetary" and g.name == "ring")
        J = None
        if not held:
            J = cfg.gear_mass[g.name][1]
            if J is None:
                J = g.mass_properties(cfg.material.rho)[1]
        members.append((g.rb, J))
    return force, equivalent_mass(members)
