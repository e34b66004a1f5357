"""Lumped-parameter planetary model (Lin & Parker's planar model) from explicit parameters or
from a configuration's geometry, linear (modes) and in the time domain.

Bodies: sun, ring, carrier with coordinates x, y (carrier frame, m) and theta (rad); planets with
radial and tangential translations zeta, eta (m, absolute, in the planet's carrier-frame
directions e_r, e_t at its angle psi_n) and theta. Meshes are springs along the line of action:
for the sun-planet mesh, with the sun driving counter-clockwise, the force on the planet acts
along n = sin(alpha_s) e_r + cos(alpha_s) e_t through the pitch point; for the planet-ring mesh
the force on the ring acts along sin(alpha_r) e_r - cos(alpha_r) e_t. A mesh deflection is
g . q = n . (v_a(P) - v_b(P)) (a: the gear that drives through the mesh), so the rotations
enter with the base radii. Bearings: isotropic springs between a central member and ground,
and between a planet and its carrier pin; torsional springs on the central members. Speed
effects (centripetal, gyroscopic) are left out, as in Lin & Parker (1999).

A coordinate may be held (a rigid support, a revolute pin, a prescribed speed): it is removed.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ...config.lumped_parameters import check_planet_spacing
from ...errors import ConfigError
from ..modal.system import LinearSystem, Spring

CENTRAL = ("sun", "ring", "carrier")


@dataclass
class MemberParameters:
    """Mass [kg], polar inertia [kg m^2], radius [m] (base radius of a gear; radius of the
    planet centres for the carrier), translational bearing stiffness [N/m] and torsional
    stiffness [N m/rad] to ground (central members) or to the carrier pin (planets)."""

    mass: float
    inertia: float
    radius: float
    bearing: float = 0.0
    torsional: float = 0.0


@dataclass
class PlanetaryParameters:
    """A planetary set as printed in the lumped-parameter literature (SI units).

    Attributes
    ----------
    planets : int
        Number of planets N (equally spaced unless ``planet_angles`` is given).
    sun, ring, carrier, planet : MemberParameters
    k_sun_planet, k_ring_planet : float
        Mesh stiffnesses [N/m].
    alpha_sun, alpha_ring : float
        Operating pressure angles of the sun-planet and ring-planet meshes [rad].
    first_planet_angle : float
        psi_1 [rad]; planet n at psi_1 + 2 pi (n - 1) / N.
    held : set of str
        Coordinates removed (e.g. ``"ring.theta"``, ``"sun.x"``).
    rigid_pins : bool
        Planets on rigid carrier pins (revolute joints): their centres move with the carrier,
        no zeta, eta coordinates, no planet bearing springs.
    planet_angles : list of float, optional
        Explicit planet angles [rad] (unequal spacing).
    """

    planets: int
    sun: MemberParameters
    ring: MemberParameters
    carrier: MemberParameters
    planet: MemberParameters
    k_sun_planet: float
    k_ring_planet: float
    alpha_sun: float
    alpha_ring: float
    first_planet_angle: float = 0.0
    held: set = field(default_factory=set)
    planet_angles: list | None = None
    rigid_pins: bool = False

    def validate(self, prefix: str = "lumped") -> None:
        """Raise ConfigError naming the first parameter that breaks its rule."""
        if not isinstance(self.planets, int) or self.planets < 1:
            raise ConfigError(f"{prefix}.planets = {self.planets!r}: must be an integer >= 1")
        for name in ("sun", "ring", "carrier", "planet"):
            m = getattr(self, name)
            for key in ("mass", "inertia", "radius"):
                v = getattr(m, key)
                if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                    raise ConfigError(f"{prefix}.{name}.{key} = {v!r}: must be > 0")
            for key in ("bearing", "torsional"):
                v = getattr(m, key)
                if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                    raise ConfigError(f"{prefix}.{name}.{key} = {v!r}: must be >= 0")
        for key in ("k_sun_planet", "k_ring_planet"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ConfigError(f"{prefix}.{key} = {v!r}: must be > 0")
        for key in ("alpha_sun", "alpha_ring"):
            v = getattr(self, key)
            if not 0 < v < math.pi / 2:
                raise ConfigError(f"{prefix}.{key} = {math.degrees(v)!r} deg: must lie in (0, 90) deg")
        angles = self.angles()
        if len(angles) != self.planets:
            raise ConfigError(f"{prefix}.planet_angles = {list(angles)!r}: must hold {prefix}.planets = "
                              f"{self.planets} angles")
        where = (f"{prefix}.planets = {self.planets}" if self.planet_angles is None else
                 f"{prefix}.planet_angles = {[round(math.degrees(x), 6) for x in angles]} deg")
        check_planet_spacing(where, list(angles), self.carrier.radius, self.planet.radius)

    def angles(self) -> np.ndarray:
        if self.planet_angles is not None:
            return np.asarray(self.planet_angles, float)
        return self.first_planet_angle + 2 * math.pi * np.arange(self.planets) / self.planets


def _unit(phi):
    return np.array([math.cos(phi), math.sin(phi)])


def planetary_system(p: PlanetaryParameters) -> LinearSystem:
    """The linear system (mass matrix, springs, bodies) of a lumped planetary model."""
    p.validate()
    psi = p.angles()
    N = p.planets
    names = []
    for c in CENTRAL:
        names += [f"{c}.x", f"{c}.y", f"{c}.theta"]
    for n in range(N):
        if not p.rigid_pins:
            names += [f"planet{n+1}.zeta", f"planet{n+1}.eta"]
        names.append(f"planet{n+1}.theta")
    unknown = sorted(set(p.held) - set(names))
    if unknown:
        raise ConfigError(f"held coordinates {unknown}: unknown; allowed: {', '.join(names)}")
    dofs = [nm for nm in names if nm not in p.held]
    idx = {nm: i for i, nm in enumerate(dofs)}
    n = len(dofs)

    def col(name):
        v = np.zeros(n)
        if name in idx:
            v[idx[name]] = 1.0
        return v

    bodies, centres = {}, {}
    for c in CENTRAL:
        m = getattr(p, c)
        bodies[c] = (m.mass, m.inertia, np.array([col(f"{c}.x"), col(f"{c}.y"), col(f"{c}.theta")]))
        centres[c] = np.zeros(2)
    a = p.carrier.radius
    for k in range(N):
        pn = f"planet{k+1}"
        er, et = _unit(psi[k]), _unit(psi[k] + math.pi / 2)
        J = np.zeros((3, n))
        if p.rigid_pins:  # the pin point of the carrier
            Jc = bodies["carrier"][2]
            J[:2] = Jc[:2] + np.outer(a * et, Jc[2])
        else:
            J[:2] = np.outer(er, col(f"{pn}.zeta")) + np.outer(et, col(f"{pn}.eta"))
        J[2] = col(f"{pn}.theta")
        bodies[pn] = (p.planet.mass, p.planet.inertia, J)
        centres[pn] = a * er

    def velocity_at(body, P):
        """(2, n): velocity of the material point of ``body`` at P per unit coordinate."""
        J = bodies[body][2]
        d = P - centres[body]
        return np.array([J[0] - d[1] * J[2], J[1] + d[0] * J[2]])

    # meshes: translations along the line of action, rotations with the base radii as arms
    # (as Lin & Parker write them, so a published set whose radii do not close the geometry
    # is reproduced as printed)
    springs = []
    rs, rp, rr = p.sun.radius, p.planet.radius, p.ring.radius
    for k in range(N):
        pn = f"planet{k+1}"
        er, et = _unit(psi[k]), _unit(psi[k] + math.pi / 2)
        nv = math.sin(p.alpha_sun) * er + math.cos(p.alpha_sun) * et  # force on the planet
        Js, Jp = bodies["sun"][2], bodies[pn][2]
        g = nv @ (Js[:2] - Jp[:2]) + rs * Js[2] + rp * Jp[2]
        springs.append(Spring(f"sun-{pn}", "mesh", p.k_sun_planet, g))
    for k in range(N):
        pn = f"planet{k+1}"
        er, et = _unit(psi[k]), _unit(psi[k] + math.pi / 2)
        nv = math.sin(p.alpha_ring) * er - math.cos(p.alpha_ring) * et  # force on the ring
        Jp, Jr = bodies[pn][2], bodies["ring"][2]
        g = nv @ (Jp[:2] - Jr[:2]) - rp * Jp[2] + rr * Jr[2]
        springs.append(Spring(f"{pn}-ring", "mesh", p.k_ring_planet, g))
    for c in CENTRAL:
        m = getattr(p, c)
        J = bodies[c][2]
        if m.bearing > 0:
            springs += [Spring(f"{c} bearing x", "support", m.bearing, J[0].copy()),
                        Spring(f"{c} bearing y", "support", m.bearing, J[1].copy())]
        if m.torsional > 0:
            springs.append(Spring(f"{c} torsion", "support", m.torsional, J[2].copy()))
    if p.planet.bearing > 0 and not p.rigid_pins:
        for k in range(N):
            pn = f"planet{k+1}"
            pin = velocity_at("carrier", centres[pn])  # the pin moves with the carrier
            Jp = bodies[pn][2]
            springs += [Spring(f"{pn} bearing x", "bearing", p.planet.bearing, Jp[0] - pin[0]),
                        Spring(f"{pn} bearing y", "bearing", p.planet.bearing, Jp[1] - pin[1])]
    if p.planet.torsional > 0:
        raise ConfigError("lumped.planet.torsional: planets turn freely on their pins; must be 0")
    return LinearSystem(dofs=dofs, bodies=bodies, springs=springs, planets=[f"planet{k+1}" for k in range(N)],
                        planet_angles=psi, central=list(CENTRAL),
                        attrs={"source": "lumped-parameter planetary model (explicit parameters)",
                               "mesh_stiffness": {s.name: s.k for s in springs if s.kind == "mesh"}})


def _member(m, i_r2, d, k, ku=0.0):
    """Member from the literature's form: mass [kg], I/r^2 [kg], diameter [m], bearing [N/m],
    torsional stiffness on u = r theta [N/m] (-> k r^2 N m/rad)."""
    r = d / 2
    return MemberParameters(mass=m, inertia=i_r2 * r * r, radius=r, bearing=k, torsional=ku * r * r)


def lin_parker_example(planets: int) -> PlanetaryParameters:
    """The example system of Lin & Parker (1999, Table 1), as printed: masses [kg] sun 0.4,
    ring 2.35, carrier 5.43, planet 0.66; I/r^2 [kg] 0.39, 3.00, 6.29, 0.61; base diameters
    [mm] 77.4, 275.0, planet 100.3, carrier (planet centres) 176.8; mesh stiffness 5e8 N/m,
    bearing stiffness 1e8 N/m for all members, ring torsional stiffness 1e9 N/m on u, sun and
    carrier free in rotation; pressure angle 24.6 deg."""
    return PlanetaryParameters(
        planets=planets, sun=_member(0.4, 0.39, 77.4e-3, 1e8), ring=_member(2.35, 3.0, 275.0e-3, 1e8, 1e9),
        carrier=_member(5.43, 6.29, 176.8e-3, 1e8), planet=_member(0.66, 0.61, 100.3e-3, 1e8),
        k_sun_planet=5e8, k_ring_planet=5e8, alpha_sun=math.radians(24.6), alpha_ring=math.radians(24.6))


def cooley_parker_example(planets: int) -> PlanetaryParameters:
    """The example system of Cooley & Parker (2012, Table 1) at zero carrier speed: masses [kg]
    sun 3.0, ring 7.64, carrier 12.0, planet 1.86; I/r^2 [kg] 1.75, 8.09, 6.80, 1.25; diameters
    [mm] sun 55.75, ring 109.7, planet 27.0, carrier 88.6; mesh stiffness 1e8 N/m; bearing
    stiffness [N/m] sun 2e7, ring 1e8, carrier 5e7, planet 1e7; torsional stiffness on u [N/m]
    sun 2e7, ring 1e8, carrier 1e8; pressure angle 20 deg. Frequencies are printed there in
    units of sqrt(k_p / m_p)."""
    return PlanetaryParameters(
        planets=planets, sun=_member(3.0, 1.75, 55.75e-3, 2e7, 2e7), ring=_member(7.64, 8.09, 109.7e-3, 1e8, 1e8),
        carrier=_member(12.0, 6.80, 88.6e-3, 5e7, 1e8), planet=_member(1.86, 1.25, 27.0e-3, 1e7),
        k_sun_planet=1e8, k_ring_planet=1e8, alpha_sun=math.radians(20.0), alpha_ring=math.radians(20.0))


def parameters_from_config(cfg, k_sun_planet: float, k_ring_planet: float) -> PlanetaryParameters:
    """Lumped parameters of a planetary configuration's geometry: base radii, operating pressure
    angles, masses and inertias (as the rigid model), supports; mesh stiffnesses given [N/m].
    Held coordinates follow the supports and the drive: revolute -> no translation, fixed ->
    nothing, prescribed speed -> no rotation; planets on revolute pins -> rigid pins."""
    from ...gears.geometry import GearPair

    if cfg.kind != "planetary":
        raise ConfigError(f"kind = {cfg.kind!r}: the lumped planetary model needs kind = 'planetary'")
    g = cfg.gears
    sp, pr = GearPair(g["sun"], g["planet"]), GearPair(g["planet"], g["ring"])
    pc = cfg.planetary

    def member(name, radius):
        m, J = g[name].mass_properties(cfg.material.rho)
        mo, Jo = cfg.gear_mass[name]
        sup = cfg.supports.get(name if name != "planet" else "planets")
        bearing = sup["stiffness"] if isinstance(sup, dict) else 0.0
        tors = (sup.get("torsional_stiffness") or 0.0) if isinstance(sup, dict) else 0.0
        return MemberParameters(mass=mo or m, inertia=Jo or J, radius=radius, bearing=bearing, torsional=tors)

    held = set()
    for name in ("sun", "ring"):
        sup = cfg.supports[name]
        if not isinstance(sup, dict):
            held |= {f"{name}.x", f"{name}.y"}
            if sup == "fixed":
                held.add(f"{name}.theta")
        elif not sup.get("torsional_stiffness") and name == "ring":
            held.add("ring.theta")
    car = cfg.supports.get("carrier", "revolute")
    if not isinstance(car, dict):
        held |= {"carrier.x", "carrier.y"}  # the carrier turns in an ideal revolute joint
    held.add(f"{cfg.drive['body']}.theta")
    a = sp.centre_distance
    p = PlanetaryParameters(
        planets=pc["planets"], sun=member("sun", g["sun"].rb), ring=member("ring", g["ring"].rb),
        carrier=MemberParameters(pc["carrier_mass"], pc["carrier_inertia"], a,
                                 bearing=car["stiffness"] if isinstance(car, dict) else 0.0),
        planet=member("planet", g["planet"].rb), k_sun_planet=k_sun_planet, k_ring_planet=k_ring_planet,
        alpha_sun=sp.alpha_w, alpha_ring=pr.alpha_w, first_planet_angle=math.radians(pc["first_planet_angle_deg"]),
        held=held, rigid_pins=not isinstance(cfg.supports["planets"], dict))
    return p


def explicit_parameters(cfg, free_drive: bool = False) -> PlanetaryParameters:
    """The parameters of a configuration with ``[lumped.parameters]``
    (:mod:`flexgear.config.lumped_parameters`).

    Without ``[gears]``: the set as printed. With ``[gears]``: the geometry's parameters
    (:func:`parameters_from_config`) with the values given replacing them; the driven body's
    rotation is held (prescribed speed) unless ``free_drive``. The mesh stiffnesses are
    ``lumped.constant_stiffness`` [N/m] in both cases.
    """
    opts = cfg.lumped or {}
    given = opts.get("parameters")
    if given is None:
        raise ConfigError("[lumped.parameters] is not given: the lumped parameters follow from the geometry")
    ks = opts["constant_stiffness"]
    if given["explicit"]:
        members = {m: MemberParameters(mass=given[m]["mass"], inertia=given[m]["inertia"], radius=given[m]["radius"],
                                       bearing=given[m]["bearing"], torsional=given[m]["torsional"])
                   for m in CENTRAL + ("planet",)}
        p = PlanetaryParameters(planets=given["planets"], k_sun_planet=ks["sun-planet"],
                                k_ring_planet=ks["planet-ring"], alpha_sun=given["alpha_sun"],
                                alpha_ring=given["alpha_ring"], held=set(given["held"]),
                                planet_angles=list(given["planet_angles"]), rigid_pins=given["rigid_pins"], **members)
    else:
        p = parameters_from_config(cfg, ks["sun-planet"], ks["planet-ring"])
        for m in CENTRAL + ("planet",):
            over = {k: v for k, v in given[m].items() if v is not None and k in ("mass", "inertia", "radius")}
            setattr(p, m, dataclasses.replace(getattr(p, m), **over))
        p.alpha_sun = given["alpha_sun"] if given["alpha_sun"] is not None else p.alpha_sun
        p.alpha_ring = given["alpha_ring"] if given["alpha_ring"] is not None else p.alpha_ring
        if free_drive:
            p.held.discard(f"{cfg.drive['body']}.theta")
    p.validate("lumped.parameters")
    return p
