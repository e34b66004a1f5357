"""Contact damping as a mesh damping ratio: conversion to and from the IMPACT law's C.

The ratio zeta is that of the mesh's torsional oscillator at the static operating point
(definitions used both ways): W the static normal force of the mesh from the nominal load
torque (planetary: per planet, ``W = T_sun / (N r_b,sun)``), ``delta_0 = (W / K)^(1/e)`` the
penetration of one tooth pair carrying W, ``k = e W / delta_0`` the tangent stiffness there,
``m_e = 1 / (r_b,a^2 / J_a + r_b,b^2 / J_b)`` the equivalent mass on the line of action (a gear
held by the model drops out), and ``C = 2 zeta sqrt(k m_e) / s(delta_0 / d)`` with
``s(x) = x^2 (3 - 2 x)`` the IMPACT damping ramp. See the theory page *Contact law and search*,
section *Damping as a mesh damping ratio*.
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


def static_mesh_force(cfg, torque: float) -> float:
    """Static normal force [N] of a mesh under the load torque ``torque`` [N m] (torque balance
    on the base circles): a spur pair torque / r_b of the loaded gear; a planetary set (ring
    fixed, the planets sharing equally) T_s / (N r_b,sun), T_s the torque on the sun, the
    carrier's times z_s / (z_s + z_r)."""
    if cfg.kind == "spur":
        return torque / cfg.gears[cfg.load["body"]].rb
    s, r = cfg.gears["sun"], cfg.gears["ring"]
    t_sun = torque * s.z / (s.z + r.z) if cfg.load["body"] == "carrier" else torque
    return t_sun / (cfg.planetary["planets"] * s.rb)


def operating_point(cfg, pair) -> tuple[float, float]:
    """Static mesh force W [N] and equivalent mass m_e [kg] of ``pair`` in a validated
    configuration (see the module docstring for the definitions).

    Parameters
    ----------
    cfg : flexgear.config.Config
    pair : flexgear.gears.geometry.GearPair
    """
    force = static_mesh_force(cfg, _max_abs(cfg.load["torque"]))
    driven = cfg.drive["body"]
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
