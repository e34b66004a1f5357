"""Explicit lumped-parameter planetary sets in the TOML: ``[lumped.parameters]``.

A published lumped model is printed as masses, inertias, radii, pressure angles and spring
stiffnesses, without tooth geometry. This module reads such a block, checks every value and
returns it in SI as plain numbers (configuration layer;
:func:`flexgear.dynamics.lumped.planetary.explicit_parameters` makes the model's parameters).
Without ``[gears]`` every member's mass, inertia, radius and bearing stiffness is required and
the meshes are springs of ``lumped.constant_stiffness``: modal analysis only (a run needs tooth
counts). With ``[gears]`` the values given replace those derived from the geometry, and both
``flexgear run`` and ``flexgear modal`` work. Keys, units and rules: the configuration
reference page (generated from ``PARAMETERS`` and ``MEMBER_PARAMETERS``).
"""
from __future__ import annotations

import math

from ..errors import ConfigError

MEMBERS = ("sun", "ring", "carrier", "planet")
# key -> (kind, default, rule, unit, description), as the schema of flexgear.config.loader (reference)
MEMBER_PARAMETERS = {
    "mass": ("float", None, "> 0", "kg", "mass (required)"),
    "inertia": ("float", None, "> 0", "kg m^2", "polar moment of inertia"),
    "inertia_over_r2": ("float", None, "> 0", "kg", "I / r^2 as Lin & Parker print it (r: the member's radius)"),
    "base_radius": ("float", None, "> 0", "m", "base radius (sun, ring, planet)"),
    "base_diameter": ("float", None, "> 0", "m", "base diameter (sun, ring, planet)"),
    "radius": ("float", None, "> 0", "m", "radius of the planet centres (carrier)"),
    "diameter": ("float", None, "> 0", "m", "diameter of the planet centres (carrier)"),
    "bearing_stiffness": ("float", None, ">= 0", "N/m",
                          "central members to ground, planets to their carrier pin (required without [gears])"),
    "torsional_stiffness": ("float", None, ">= 0", "N m/rad", "torsional support (central members)"),
    "torsional_stiffness_u": ("float", None, ">= 0", "N/m", "torsional support on u = r theta (central members)"),
}
PARAMETERS = {
    "planets": ("int", None, ">= 1", "", "number of planets"),
    "first_planet_angle_deg": ("float", 0.0, None, "deg", "angle of planet 1, the planets equally spaced"),
    "planet_angles_deg": ("any", None, None, "deg", "a list of the N planet angles instead"),
    "pressure_angle_deg": ("float", None, "(0, 90)", "deg", "pressure angle of both meshes"),
    "pressure_angle_sun_deg": ("float", None, "(0, 90)", "deg", "sun-planet pressure angle"),
    "pressure_angle_ring_deg": ("float", None, "(0, 90)", "deg", "planet-ring pressure angle"),
    "held": ("any", [], None, "", "coordinates removed, e.g. [\"ring.theta\", \"sun.x\", \"planet2.zeta\"]"),
    "rigid_pins": ("bool", False, None, "", "planets on rigid carrier pins"),
} | {m: ("any", None, None, "", f"the {m}'s table `[lumped.parameters.<member>]`") for m in MEMBERS}
MEMBER_KEYS = tuple(MEMBER_PARAMETERS)
PARAMETER_KEYS = tuple(PARAMETERS)
# with [gears]: only these may be given (the rest comes from [planetary] and [supports])
GEOMETRY_OVERRIDES = ("pressure_angle_deg", "pressure_angle_sun_deg", "pressure_angle_ring_deg") + MEMBERS
OVERRIDE_MEMBER_KEYS = ("mass", "inertia", "inertia_over_r2", "base_radius", "base_diameter", "radius", "diameter")


def _number(path: str, value, rule: str = "> 0") -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(f"{path} = {value!r}: must be a finite number")
    value = float(value)
    if rule == "> 0" and not value > 0:
        raise ConfigError(f"{path} = {value!r}: must be > 0")
    if rule == ">= 0" and not value >= 0:
        raise ConfigError(f"{path} = {value!r}: must be >= 0")
    return value


def _bearing(path: str, value) -> float:
    """A bearing stiffness [N/m]: > 0. Zero would leave the member's translation to the meshes
    alone (a planet on a free pin is then a mechanism: zero modes that are not rigid-body
    motions); a member held in translation is listed in ``held`` instead."""
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and not value > 0:
        raise ConfigError(f"{path} = {float(value)!r}: must be > 0 N/m (non-positive bearing stiffnesses are "
                          "errors; a member held in translation: list its coordinates in lumped.parameters.held, "
                          "a floating member: a stiffness small against the mesh stiffness)")
    return _number(path, value)


def _one_of(path: str, raw: dict, keys: tuple, required: bool):
    given = [k for k in keys if k in raw]
    if len(given) > 1:
        raise ConfigError(f"{path}: give one of {', '.join(f'{path}.{k}' for k in keys)}, not {' and '.join(given)}")
    if not given:
        if required:
            raise ConfigError(f"{path}.{keys[0]} is missing (or {', '.join(f'{path}.{k}' for k in keys[1:])})")
        return None
    return given[0]


def _member(path: str, name: str, raw, explicit: bool) -> dict:
    """One member in SI: mass, inertia, radius, bearing, torsional (None where not given)."""
    if not isinstance(raw, dict):
        raise ConfigError(f"[{path}] must be a table")
    allowed = MEMBER_KEYS if explicit else OVERRIDE_MEMBER_KEYS
    radius_keys = ("radius", "diameter") if name == "carrier" else ("base_radius", "base_diameter")
    allowed = [k for k in allowed if k not in (("base_radius", "base_diameter") if name == "carrier"
                                               else ("radius", "diameter"))]
    if name == "planet" or not explicit:
        allowed = [k for k in allowed if not k.startswith("torsional")]
    unknown = sorted(set(raw) - set(allowed))
    if unknown:
        why = ("; with [gears], supports come from [supports]" if not explicit and
               any(k.startswith(("bearing", "torsional")) for k in unknown) else
               "; planets turn freely on their pins" if name == "planet" and
               any(k.startswith("torsional") for k in unknown) else "")
        raise ConfigError(f"unknown key(s) {', '.join(repr(f'{path}.{k}') for k in unknown)}{why}; allowed in "
                          f"[{path}]: {', '.join(allowed)}")
    out = {"mass": None, "inertia": None, "radius": None, "bearing": None, "torsional": None}
    if "mass" in raw:
        out["mass"] = _number(f"{path}.mass", raw["mass"])
    elif explicit:
        raise ConfigError(f"{path}.mass is missing")
    rk = _one_of(path, raw, radius_keys, explicit)
    if rk is not None:
        v = _number(f"{path}.{rk}", raw[rk])
        out["radius"] = v if rk in ("radius", "base_radius") else v / 2
    ik = _one_of(path, raw, ("inertia", "inertia_over_r2"), explicit)
    if ik == "inertia":
        out["inertia"] = _number(f"{path}.inertia", raw["inertia"])
    elif ik == "inertia_over_r2":
        v = _number(f"{path}.inertia_over_r2", raw["inertia_over_r2"])
        if out["radius"] is None:
            raise ConfigError(f"{path}.inertia_over_r2 needs the member's radius: give {path}.{radius_keys[0]} "
                              "(or use inertia in kg m^2)")
        out["inertia"] = v * out["radius"] ** 2
    if explicit:
        if "bearing_stiffness" not in raw:
            raise ConfigError(f"{path}.bearing_stiffness is missing (N/m, > 0)")
        out["bearing"] = _bearing(f"{path}.bearing_stiffness", raw["bearing_stiffness"])
        tk = _one_of(path, raw, ("torsional_stiffness", "torsional_stiffness_u"), False)
        out["torsional"] = 0.0
        if tk == "torsional_stiffness":
            out["torsional"] = _number(f"{path}.torsional_stiffness", raw[tk], ">= 0")
        elif tk == "torsional_stiffness_u":
            out["torsional"] = _number(f"{path}.torsional_stiffness_u", raw[tk], ">= 0") * out["radius"] ** 2
    return out


def coordinate_names(planets: int, rigid_pins: bool) -> list[str]:
    """Coordinates of the lumped planetary model before any is held."""
    names = [f"{c}.{x}" for c in ("sun", "ring", "carrier") for x in ("x", "y", "theta")]
    for n in range(planets):
        names += ([] if rigid_pins else [f"planet{n+1}.zeta", f"planet{n+1}.eta"]) + [f"planet{n+1}.theta"]
    return names


def check_planet_spacing(path: str, angles, carrier_radius: float, planet_radius: float) -> None:
    """Neighbouring planets (circles of ``planet_radius`` [m] on ``carrier_radius`` [m] at
    ``angles`` [rad]) must not overlap; the base circle lies inside the tip circle, so this is
    the least any real planet needs."""
    n = len(angles)
    if n < 2:
        return
    order = sorted(range(n), key=lambda i: angles[i] % (2 * math.pi))
    for i, j in zip(order, order[1:] + order[:1]):
        gap = 2 * carrier_radius * abs(math.sin(0.5 * (angles[j] - angles[i])))
        if gap <= 2 * planet_radius:
            raise ConfigError(f"{path}: planets {i + 1} and {j + 1} collide: on the carrier radius "
                              f"{carrier_radius:.4g} m their centres are {gap:.4g} m apart, not more than the "
                              f"planet base diameter {2 * planet_radius:.4g} m (the geometry cannot hold them)")


def parse_parameters(raw, has_gears: bool, path: str = "lumped.parameters") -> dict:
    """Validate ``[lumped.parameters]``; returns SI values (radians, N/m, ...).

    Returns
    -------
    dict
        ``explicit`` (bool: a full parameter set, no [gears]), ``planets``, ``planet_angles``
        [rad] (None with [gears]), ``alpha_sun``, ``alpha_ring`` [rad] or None, ``held`` (list),
        ``rigid_pins`` (bool) and one dict per member (``mass``, ``inertia``, ``radius``,
        ``bearing``, ``torsional``; None where not given).
    """
    if not isinstance(raw, dict):
        raise ConfigError(f"[{path}] must be a table")
    explicit = not has_gears
    allowed = PARAMETER_KEYS if explicit else GEOMETRY_OVERRIDES
    unknown = sorted(set(raw) - set(allowed))
    if unknown:
        why = ("; with [gears] the planets come from [planetary] and the supports from [supports]"
               if not explicit and set(unknown) & set(PARAMETER_KEYS) else "")
        raise ConfigError(f"unknown key(s) {', '.join(repr(f'{path}.{k}') for k in unknown)}{why}; allowed in "
                          f"[{path}]: {', '.join(allowed)}")
    out = {"explicit": explicit}
    for m in MEMBERS:
        if m in raw:
            out[m] = _member(f"{path}.{m}", m, raw[m], explicit)
        elif explicit:
            raise ConfigError(f"[{path}.{m}] is missing (mass, inertia, radius and bearing stiffness of the {m})")
        else:
            out[m] = _member(f"{path}.{m}", m, {}, False)
    pk = _one_of(path, raw, ("pressure_angle_deg", "pressure_angle_sun_deg"), False)
    if "pressure_angle_deg" in raw and "pressure_angle_ring_deg" in raw:
        raise ConfigError(f"{path}: give {path}.pressure_angle_deg (both meshes) or {path}.pressure_angle_sun_deg "
                          f"and {path}.pressure_angle_ring_deg, not both")
    alphas = {}
    for mesh, key in (("sun", "pressure_angle_sun_deg"), ("ring", "pressure_angle_ring_deg")):
        k = "pressure_angle_deg" if pk == "pressure_angle_deg" else key
        if k not in raw:
            if explicit:
                raise ConfigError(f"{path}.{key} is missing (or {path}.pressure_angle_deg for both meshes)")
            alphas[mesh] = None
            continue
        v = _number(f"{path}.{k}", raw[k])
        if not 0 < v < 90:
            raise ConfigError(f"{path}.{k} = {v!r}: must lie in (0, 90) degrees")
        alphas[mesh] = math.radians(v)
    out["alpha_sun"], out["alpha_ring"] = alphas["sun"], alphas["ring"]
    if not explicit:
        out.update(planets=None, planet_angles=None, held=[], rigid_pins=None)
        return out
    N = raw.get("planets")
    if N is None:
        raise ConfigError(f"{path}.planets is missing (the number of planets)")
    if isinstance(N, bool) or not isinstance(N, int) or N < 1:
        raise ConfigError(f"{path}.planets = {N!r}: must be an integer >= 1")
    ak = _one_of(path, raw, ("first_planet_angle_deg", "planet_angles_deg"), False)
    if ak == "planet_angles_deg":
        lst = raw["planet_angles_deg"]
        if not isinstance(lst, list) or len(lst) != N:
            raise ConfigError(f"{path}.planet_angles_deg = {lst!r}: must be a list of {path}.planets = {N} angles")
        angles = [math.radians(_number(f"{path}.planet_angles_deg[{i}]", v, "any")) for i, v in enumerate(lst)]
        where = f"{path}.planet_angles_deg = {lst!r}"
    else:
        psi1 = _number(f"{path}.first_planet_angle_deg", raw.get("first_planet_angle_deg", 0.0), "any")
        angles = [math.radians(psi1) + 2 * math.pi * n / N for n in range(N)]
        where = f"{path}.planets = {N}"
    check_planet_spacing(where, angles, out["carrier"]["radius"], out["planet"]["radius"])
    rigid = raw.get("rigid_pins", False)
    if not isinstance(rigid, bool):
        raise ConfigError(f"{path}.rigid_pins = {rigid!r}: must be true or false")
    held = raw.get("held", [])
    if not isinstance(held, list) or not all(isinstance(h, str) for h in held):
        raise ConfigError(f"{path}.held = {held!r}: must be a list of coordinate names such as 'ring.theta'")
    names = coordinate_names(N, rigid)
    bad = [h for h in held if h not in names]
    if bad:
        raise ConfigError(f"{path}.held: unknown coordinate(s) {', '.join(map(repr, bad))}; the coordinates are "
                          f"{', '.join(names)}")
    out.update(planets=N, planet_angles=angles, held=list(held), rigid_pins=rigid)
    return out
