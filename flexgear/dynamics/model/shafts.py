"""Elastic shafts of the drive line (``[shafts.input]``, ``[shafts.output]``) from their dimensions.

The input shaft ties the driven body to a *motor* body at the prescribed speed, the output
shaft the output member to a *load* body of inertia ``load_inertia``: each a torsional spring
k_t = G pi d^4 / (32 L), plus the shaft's bending stiffness at the gear in series with its
rolling bearings as an elastic support of the body (Euler-Bernoulli, Roark's Formulas Table
8.1; :func:`lateral_stiffness`), the shaft's Rayleigh inertia and dampers c = 2 zeta sqrt(k m)
(:func:`reflected_inertia`). Formulas: the theory page *Shafts*. SI units.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .bodies import ANGLE_FREE, ANGLE_PRESCRIBED, ANGLE_SPRING, BEARING, REVOLUTE, Body, Model
from ...errors import ConfigError

_GAUSS = np.polynomial.legendre.leggauss(4)  # exact for w^2, w cubic on each beam piece


def polar_moment(d: float) -> float:
    """Polar second moment of area of a solid round shaft, pi d^4 / 32 [m^4] (d in m)."""
    return math.pi * d**4 / 32.0


def torsional_stiffness(G: float, d: float, length: float) -> float:
    """k_t = G pi d^4 / (32 L) [N m/rad] of a solid round shaft (G [Pa], d, L [m])."""
    return G * polar_moment(d) / length


def shaft_bending_stiffness(E: float, d: float, span: float, position: float, arrangement: str) -> float:
    """Lateral stiffness [N/m] of the shaft at the gear on rigid simple supports.

    Parameters
    ----------
    E : float
        Young's modulus [Pa].
    d : float
        Shaft diameter [m].
    span : float
        Bearing span s [m].
    position : float
        "between": distance a of the gear from the first bearing (0 < a < s) [m];
        "overhung": overhang c of the gear beyond the nearer bearing (c > 0) [m].
    arrangement : str
        "between" (k = 3 E I s / (a^2 b^2)) or "overhung" (k = 3 E I / (c^2 (s + c))).
    """
    EI = E * math.pi * d**4 / 64.0
    if arrangement == "between":
        a, b = position, span - position
        return 3.0 * EI * span / (a * a * b * b)
    c = position
    return 3.0 * EI / (c * c * (span + c))


def bearing_compliance(span: float, position: float, arrangement: str, bearing_stiffness: float | None) -> float:
    """Lateral compliance [m/N] at the gear from two radial bearings of stiffness k_B [N/m] each
    (0 for rigid bearings, ``None``)."""
    if bearing_stiffness is None:
        return 0.0
    if arrangement == "between":
        a, b = position, span - position
        lever = (b / span) ** 2 + (a / span) ** 2
    else:
        c = position
        lever = ((span + c) / span) ** 2 + (c / span) ** 2
    return lever / bearing_stiffness


def lateral_stiffness(E: float, d: float, span: float, position: float, arrangement: str,
                      bearing_stiffness: float | None = None) -> float:
    """Lateral stiffness [N/m] at the gear: shaft bending in series with the two bearings."""
    return 1.0 / (1.0 / shaft_bending_stiffness(E, d, span, position, arrangement)
                  + bearing_compliance(span, position, arrangement, bearing_stiffness))


def deflection_shape(span: float, position: float, arrangement: str):
    """Static deflection shape under a force at the gear, normalised to 1 there.

    Returns
    -------
    pieces : list of (x0, x1, w)
        Beam pieces [m] (coordinate from the first bearing) with ``w(x)`` the normalised
        deflection (a cubic on each piece).
    """
    s = span
    if arrangement == "between":
        a, b = position, s - position
        w_g = a * a * b * b / (3.0 * s)  # deflection at the gear per F / EI

        def left(x):
            return b * x * (s * s - b * b - x * x) / (6.0 * s) / w_g

        def right(x):
            u = s - x
            return a * u * (s * s - a * a - u * u) / (6.0 * s) / w_g

        return [(0.0, a, left), (a, s, right)]
    c = position
    w_g = c * c * (s + c) / 3.0

    def inside(x):
        return -c * x * (s * s - x * x) / (6.0 * s) / w_g

    def overhang(x):
        u = x - s
        return u * (2.0 * c * s + 3.0 * c * u - u * u) / 6.0 / w_g

    return [(0.0, s, inside), (s, s + c, overhang)]


def bending_mass(rho: float, d: float, span: float, position: float, arrangement: str) -> float:
    """Rayleigh mass [kg] of the shaft at the gear: rho A times the integral of the squared
    normalised static deflection over the bearing span (and overhang)."""
    area = math.pi * d * d / 4.0
    xg, wg = _GAUSS
    total = 0.0
    for x0, x1, w in deflection_shape(span, position, arrangement):
        x = 0.5 * (x1 - x0) * xg + 0.5 * (x1 + x0)
        total += 0.5 * (x1 - x0) * float(np.sum(wg * w(x) ** 2))
    return rho * area * total


@dataclass
class ShaftProperties:
    """Stiffness, damping and lumped inertia of one shaft (SI)."""

    name: str  # "input" or "output"
    body: str  # the gear set body it carries
    torsional_stiffness: float  # N m/rad
    lateral_stiffness: float | None  # N/m (None: no bending)
    polar_inertia: float  # J_s of the torsional length [kg m^2]
    gear_inertia: float  # share of J_s lumped on the body [kg m^2]
    end_inertia: float  # share on the motor / load body [kg m^2]
    bending_mass: float  # Rayleigh mass added to the body [kg]
    damping_ratio: float
    torsional_damping: float | None  # N m s/rad (None: from the damping ratio)
    lateral_damping: float | None  # N s/m (None: from the damping ratio)
    load_inertia: float = 0.0  # output shaft: inertia of the load [kg m^2]
    source: str = ""  # how the stiffnesses were obtained


def shaft_properties(cfg, name: str) -> ShaftProperties:
    """The properties of ``[shafts.<name>]`` of a validated configuration."""
    spec = cfg.shafts[name]
    mat = cfg.material
    G = mat.E / (2.0 * (1.0 + mat.nu))
    d, L = spec["diameter"], spec["length"]
    kt = spec["torsional_stiffness"] or torsional_stiffness(G, d, L)
    how = ["k_t given" if spec["torsional_stiffness"] else f"k_t = G pi d^4/(32 L) = {kt:.5g} N m/rad"]
    kl = None
    m_b = 0.0
    if spec["bending"]:
        arr, span, pos = spec["arrangement"], spec["bearing_span"], spec["gear_position"]
        kl = spec["lateral_stiffness"] or lateral_stiffness(mat.E, d, span, pos, arr, spec["bearing_stiffness"])
        m_b = bending_mass(mat.rho, d, span, pos, arr) if span is not None else 0.0
        how.append("k_lat given" if spec["lateral_stiffness"] else
                   f"k_lat = {kl:.5g} N/m ({arr}, span {span*1e3:.4g} mm, gear at {pos*1e3:.4g} mm, bearings "
                   + (f"{spec['bearing_stiffness']:.3g} N/m)" if spec["bearing_stiffness"] else "rigid)"))
    Js = mat.rho * polar_moment(d) * L
    share = 1.0 / 3.0 if name == "input" else 0.5
    return ShaftProperties(name=name, body=spec["body"], torsional_stiffness=kt, lateral_stiffness=kl,
                           polar_inertia=Js, gear_inertia=share * Js, end_inertia=(1.0 - share) * Js,
                           bending_mass=m_b, damping_ratio=spec["damping_ratio"],
                           torsional_damping=spec["torsional_damping"], lateral_damping=spec["lateral_damping"],
                           load_inertia=spec.get("load_inertia") or 0.0, source="; ".join(how))


def reflected_inertia(bodies: list[Body], i: int) -> float:
    """Inertia [kg m^2] of the bodies reflected to body i's rotation: sum_j (J_j w_j^2 +
    m_j v_j^2) / w_i^2 at their initial (nominal) speeds; a body on a parent's pin moves with
    v_j = w_parent |pin_j| (the parent turning about its own centre)."""
    w = bodies[i].omega0
    if w == 0.0:
        return bodies[i].inertia
    total = 0.0
    for b in bodies:
        v = bodies[b.parent].omega0 * math.hypot(*b.pin) if b.parent >= 0 else 0.0
        total += b.inertia * b.omega0**2 + b.mass * v * v
    return total / (w * w)


def attach_shafts(model: Model, cfg) -> None:
    """Put the configured shafts into ``model`` (in place): the motor body (prescribed speed)
    and the input shaft on the driven body, the output shaft and the load body on the loaded
    body, each body with its shaft's bending support. New bodies go to the end of the list, so
    the indices of the gear set's bodies do not change. The properties are listed in
    ``model.attrs["shafts"]``."""
    shafts = getattr(cfg, "shafts", None)
    if not shafts:
        return
    index = {b.name: i for i, b in enumerate(model.bodies)}
    gear_set = list(model.bodies)
    info = {}
    for name in ("input", "output"):
        if name not in shafts:
            continue
        p = shaft_properties(cfg, name)
        i = index.get(p.body)
        if i is None:  # the loader checks this; a model built by hand may not match
            raise ConfigError(f"shafts.{name}.body = {p.body!r}: no such body in the model "
                              f"({', '.join(index)})")
        gear = model.bodies[i]
        gear.inertia += p.gear_inertia
        if p.lateral_stiffness is not None:
            if gear.joint != REVOLUTE or gear.parent >= 0:
                raise ConfigError(f"shafts.{name}: body {gear.name!r} is not on a plain revolute joint to ground; "
                                  f"its support must be 'revolute' when the shaft's bending is modelled "
                                  f"(bending = false keeps the support)")
            gear.joint = BEARING
            gear.mass += p.bending_mass
            gear.stiffness = p.lateral_stiffness
            gear.damping = (p.lateral_damping if p.lateral_damping is not None
                            else 2.0 * p.damping_ratio * math.sqrt(p.lateral_stiffness * gear.mass))
        if name == "input":
            if gear.rotation != ANGLE_PRESCRIBED:
                raise ConfigError(f"shafts.input: body {gear.name!r} is not the driven body")
            end = Body(name="motor", mass=0.0, inertia=p.end_inertia, joint=REVOLUTE, pin=gear.pin,
                       rotation=ANGLE_PRESCRIBED, theta0=gear.theta0, omega0=gear.omega0, speed=gear.speed,
                       attrs={"role": "motor (prescribed speed), motor end of the input shaft", "z": 0})
            gear.rotation = ANGLE_SPRING
            gear.speed = None
            gear.attrs["role"] = gear.attrs.get("role", "").replace("driven (prescribed speed)",
                                                                     "driven through the input shaft")
            spring_body = gear  # the spring sits on the gear, tied to the motor
        else:
            if gear.torque is None or gear.rotation != ANGLE_FREE:
                raise ConfigError(f"shafts.output: body {gear.name!r} is not the loaded body")
            end = Body(name="load", mass=0.0, inertia=p.load_inertia + p.end_inertia, joint=REVOLUTE, pin=gear.pin,
                       rotation=ANGLE_SPRING, theta0=gear.theta0, omega0=gear.omega0, torque=gear.torque,
                       torque_ramp=gear.torque_ramp,
                       attrs={"role": "load inertia at the end of the output shaft", "z": 0})
            gear.torque = None
            gear.torque_ramp = 0.0
            spring_body = end
        model.bodies.append(end)
        k = len(model.bodies) - 1
        spring_body.torsion_parent = i if spring_body is end else k
        spring_body.torsional_stiffness = p.torsional_stiffness
        if p.torsional_damping is not None:
            c = p.torsional_damping
        else:
            J = reflected_inertia(gear_set, i) if name == "input" else end.inertia
            c = 2.0 * p.damping_ratio * math.sqrt(p.torsional_stiffness * J)
        spring_body.torsional_damping = c
        gear.attrs["shaft"] = name
        info[name] = {"body": gear.name, "torsional_stiffness": p.torsional_stiffness,
                      "lateral_stiffness": p.lateral_stiffness, "torsional_damping": c,
                      "lateral_damping": gear.damping if p.lateral_stiffness is not None else None,
                      "polar_inertia": p.polar_inertia, "gear_inertia": p.gear_inertia,
                      "end_inertia": end.inertia, "bending_mass": p.bending_mass, "source": p.source}
    model.attrs["shafts"] = info
