"""``[housing]`` and ``[[sensors]]``: the gearbox housing and the sensors on it
(``Config.housing``, a :class:`flexgear.gears.housing.Housing`, None without the block;
``Config.sensors``, a tuple of :class:`~flexgear.gears.housing.Sensor`). Read and validated
here, before anything runs; written back for :func:`~flexgear.config.loader.config_document`.
Geometry, defaults and path models: ``docs/guide/housing.md``.

Example::

    [housing]                      # every key has a default derived from the gears
    outline = "circle"             # circle | rounded_rectangle
    diameter = 0.178               # m
    wall_thickness = 0.008         # m
    foot_angles_deg = [-135.0, -45.0]

    [[sensors]]
    name = "top"
    angle_deg = 90.0               # on the housing's outer rim, above the centre
    direction = "radial"           # radial | tangential | x | y, or direction_deg = 30.0
    quantity = "acceleration"      # acceleration | velocity | displacement

Every broken rule is a ConfigError naming the key: a housing that does not enclose the ring or
that collides with a gear, holes that overlap or leave the cover, bolts off the ring's rim, feet
off the outline; a sensor off its body, an unknown body, quantity or direction, two sensors of
one name.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from ..gears.geometry import GearPair
from ..gears.housing import (CAST_IRON, DIRECTIONS, NOISE_KEYS, OUTLINES, QUANTITIES, QUANTITY_UNITS, SENSOR_BODIES,
                             WINDOWS, Housing, HousingOutline, RingBolts, Seat, Sensor, check_sensor_names,
                             foot_positions, sensor_direction)
from ..gears.material import Material
from .schema import check_cutoff, check_table

#: smallest wall of the default housing [m] (module docstring of the guide: how defaults are chosen)
MIN_WALL = 0.008
#: default radial gap between the ring gear's rim and the wall [m]
RING_GAP = 0.001
#: bearing outer diameter over shaft diameter: a 618-series bearing (61804: 20 x 32 x 7 mm)
SEAT_RATIO = 1.6
DEFAULT_FEET_DEG = (-135.0, -45.0)

# schema: key -> (kind, default, rule, unit, description), as the loader's
HOUSING_KEYS = {
    "outline": ("str", None, OUTLINES, "", "circle or rounded_rectangle; default: a circle around a planetary "
                "set's ring, a rounded rectangle around a spur pair"),
    "diameter": ("float", None, "(0, 10]", "m", "outline = circle: outer diameter; default: the ring's rim + 2 mm gap "
                 "+ 2 walls"),
    "width": ("float", None, "(0, 10]", "m", "outline = rounded_rectangle: extent along x; default: the gears' tip "
              "circles + 1.2 walls of clearance on each side + 2 walls"),
    "height": ("float", None, "(0, 10]", "m", "outline = rounded_rectangle: extent along y; default as width"),
    "corner_radius": ("float", None, ">= 0", "m", "outline = rounded_rectangle: default the tip clearance + a wall"),
    "centre": ("any", None, None, "m", "[x, y] of the outline's centre; default: the ring's axis, or the centre "
               "of the box around a spur pair's tip circles"),
    "wall_thickness": ("float", None, "(0, 10]", "m", "default max(8 mm, 0.025 a + 1 mm), a the centre distance"),
    "depth": ("float", None, "(0, 10]", "m", "axial length of the wall (its out-of-plane thickness); default twice "
              "the widest gear's face width"),
    "cover_thickness": ("float", None, "(0, 10]", "m", "both end covers together (the inner region's out-of-plane "
                        "thickness); default two walls"),
    "seat_diameter": ("float", None, "(0, 10]", "m", "bearing seat bores; default 1.6 x the shaft (a 618-series "
                      "bearing's outer diameter)"),
    "bolts": ("int", None, ">= 3", "", "planetary: bolts holding the ring to the cover; default 12, or [flexible] "
              "bolts for a flexible ring on bolts"),
    "bolt_circle_diameter": ("float", None, "(0, 10]", "m", "planetary: default midway between the ring's root "
                             "circle and rim"),
    "bolt_diameter": ("float", None, "(0, 10]", "m", "planetary: bolt hole diameter; default half the ring's rim "
                      "thickness (root to rim)"),
    "foot_angles_deg": ("any", None, None, "deg", "feet where rays from the outline's centre at these angles "
                        "meet it; default [-135, -45]"),
    "foot_points": ("any", None, None, "m", "[[x, y], ...]: feet at these points of the outline, instead of "
                    "foot_angles_deg"),
    "foot_width": ("float", None, "(0, 10]", "m", "length of each foot pad along the outline; default 2.5 walls"),
    "foot_stiffness": ("float", 1e8, "> 0", "N/m", "ground stiffness of each foot in x and in y"),
    "E": ("float", CAST_IRON.E, "> 0", "Pa", "Young's modulus (default grey cast iron EN-GJL-250)"),
    "nu": ("float", CAST_IRON.nu, "(-1, 0.5)", "", "Poisson's ratio"),
    "density": ("float", CAST_IRON.rho, "> 0", "kg/m^3", "density"),
    "damping_ratio": ("float", 0.02, "(0, 1)", "", "modal damping ratio of the housing on its feet"),
    "level": ("int", 2, "[0, 5]", "", "mesh refinement level (two elements through the wall at 2)"),
    "order": ("int", 2, (1, 2), "", "element order (triangles)"),
    "cutoff": ("float", 50e3, "> 0", "Hz", "fixed-interface modes kept by the Craig-Bampton reduction (at most "
               "1 MHz x sqrt(E / 1.1e11 Pa), the modes scaling with the wall's stiffness)"),
    "coupled": ("bool", False, None, "", "the housing is a body of the multi-body model (bearings seated in it, "
                "feet on ground springs) and the sensors read its coordinates; false: the one-way path models"),
}
SENSOR_KEYS = {
    "name": ("str", None, None, "", "unique name (required): the results' `/sensors/<name>`"),
    "body": ("str", "housing", SENSOR_BODIES, "", "housing (needs [housing]) or ring (planetary sets)"),
    "position": ("any", None, None, "m", "[x, y]: a point of the body (or angle_deg)"),
    "angle_deg": ("float", None, "[-360, 360]", "deg", "on the body's outer rim at this angle about its centre "
                  "(counter-clockwise from +x), instead of position"),
    "direction": ("str", None, DIRECTIONS, "", "radial, tangential (about the body's centre), x or y; default "
                  "radial"),
    "direction_deg": ("float", None, "[-360, 360]", "deg", "the measured direction, counter-clockwise from +x, "
                      "instead of direction"),
    "quantity": ("str", "acceleration", QUANTITIES, "", "acceleration, velocity or displacement"),
    "window": ("str", "hann", WINDOWS, "", "planetary: the planet-pass path model's window of the angle between a "
               "planet and the sensor (McFadden & Smith 1985)"),
    "window_width_deg": ("float", 360.0, "(0, 360]", "deg", "planetary: the planet-pass window's angular width "
                         "(360: the raised cosine over the whole carrier revolution)"),
    "noise_rms": ("float", None, ">= 0", "m/s^2, m/s or m", "measurement noise: white Gaussian noise of this RMS, "
                  "in the sensor's quantity, added to its signals in that quantity (not the planet-pass force)"),
    "snr_db": ("float", None, "[-40, 200]", "dB", "measurement noise instead of noise_rms: white Gaussian noise at "
               "this signal-to-noise ratio 20 log10(rms signal / rms noise), the signal's rms about its mean, on "
               "each of the sensor's signals"),
    "noise_seed": ("int", None, ">= 0", "", "seed of the noise (default: one derived from the whole configuration, "
                   "so a rerun draws the same noise and another case other noise; the seed used is recorded)"),
}


def _point(path, value) -> tuple[float, float]:
    if (not isinstance(value, list) or len(value) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in value)):
        raise ConfigError(f"{path} = {value!r}: must be a point [x, y] of two finite numbers (m)")
    return (float(value[0]), float(value[1]))


def _shaft_diameter(gear) -> float:
    """A gear's shaft [m]: its bore, or for a solid gear 0.4 x its root diameter."""
    return gear.bore_diameter if gear.bore_diameter else 0.8 * gear.rf


def set_layout(cfg) -> dict:
    """What the housing surrounds: ``ring`` (centre, root and rim radius) or None, ``gears``
    (name, centre, tip radius) that turn inside the wall, ``seats`` (name, shafts, centre,
    shaft diameter) and the centre distance ``a`` [m]."""
    g = cfg.gears
    if cfg.kind == "planetary":
        r = g["ring"]
        a = GearPair(g["sun"], g["planet"]).centre_distance
        return {"ring": ((0.0, 0.0), float(r.rf), 0.5 * float(r.rim_diameter)), "gears": [], "a": a,
                "seats": [("centre", ("sun", "carrier"), (0.0, 0.0), _shaft_diameter(g["sun"]))],
                "width": max(x.face_width for x in g.values())}
    p, w = g["pinion"], g["wheel"]
    a = cfg.spur["centre_distance"] or GearPair(p, w).centre_distance
    beta = math.radians(cfg.spur["line_of_centres_deg"])
    cw = (a * math.cos(beta), a * math.sin(beta))
    return {"ring": None, "gears": [("pinion", (0.0, 0.0), float(p.ra)), ("wheel", cw, float(w.ra))], "a": a,
            "seats": [("pinion", ("pinion",), (0.0, 0.0), _shaft_diameter(p)),
                      ("wheel", ("wheel",), cw, _shaft_diameter(w))],
            "width": max(p.face_width, w.face_width)}


def parse_housing(raw, cfg, check_value) -> Housing | None:
    """The ``[housing]`` table of a configuration whose gears are read (None: absent), every
    default filled in from the gear set (``docs/guide/housing.md``) and every rule checked."""
    if raw is None:
        return None
    v = check_table("housing", raw, HOUSING_KEYS, check_value)
    lay = set_layout(cfg)
    wall = v["wall_thickness"] or max(MIN_WALL, 0.025 * lay["a"] + 0.001)
    check_cutoff("housing.cutoff", v["cutoff"], v["E"] / CAST_IRON.E, f"E / {CAST_IRON.E:g} Pa")
    planetary = lay["ring"] is not None
    if not planetary:
        for k in ("bolts", "bolt_circle_diameter", "bolt_diameter"):
            if v[k] is not None:
                raise ConfigError(f"housing.{k} = {v[k]!r}: bolts hold a planetary set's ring gear; a spur pair has "
                                  "none (remove the key)")
    outline = _outline(v, raw, lay, wall)
    # the widest gear's radius: the ring's rim, or the larger tip circle of a spur pair
    span = lay["ring"][2] if planetary else max(r for *_, r in lay["gears"])
    if wall > span:
        raise ConfigError(f"housing.wall_thickness = {wall!r} m: must not exceed the widest gear's radius "
                          f"({span:.6g} m), a wall thicker than the gear set it holds (a length in mm given as m?)")
    seat_d = v["seat_diameter"] or SEAT_RATIO * max(d for *_, d in lay["seats"])
    seats = tuple(Seat(name, shafts, c, seat_d) for name, shafts, c, _ in lay["seats"])
    bolts = None
    if planetary:
        _, r_root, r_rim = lay["ring"]
        fx = cfg.flexible or {}
        on_bolts = "ring" in fx.get("gears", ()) and fx.get("ring_support") == "bolts"
        bolts = RingBolts(v["bolts"] or (fx["bolts"] if on_bolts else 12), v["bolt_circle_diameter"] or (r_root + r_rim),
                          v["bolt_diameter"] or 0.5 * (r_rim - r_root))
    if v["foot_points"] is not None and v["foot_angles_deg"] is not None:
        raise ConfigError("housing.foot_points and housing.foot_angles_deg: give one of them")
    angles = points = None
    if v["foot_points"] is not None:
        pts = v["foot_points"]
        if not isinstance(pts, list) or not pts:
            raise ConfigError(f"housing.foot_points = {pts!r}: must be a non-empty list of points [[x, y], ...] (m)")
        points = tuple(_point(f"housing.foot_points[{k}]", p) for k, p in enumerate(pts))
        feet = foot_positions(outline, points=points)
    else:
        angles = DEFAULT_FEET_DEG if v["foot_angles_deg"] is None else v["foot_angles_deg"]
        if (not isinstance(angles, (list, tuple)) or not angles
                or any(isinstance(a, bool) or not isinstance(a, (int, float)) or not math.isfinite(a) for a in angles)):
            raise ConfigError(f"housing.foot_angles_deg = {angles!r}: must be a non-empty list of finite angles (deg)")
        angles = tuple(float(a) for a in angles)
        feet = foot_positions(outline, angles=[math.radians(a) for a in angles])
    housing = Housing(outline=outline, wall_thickness=wall, depth=v["depth"] or 2.0 * lay["width"],
                      cover_thickness=v["cover_thickness"] or 2.0 * wall, seats=seats, bolts=bolts, feet=feet,
                      foot_angles_deg=angles, foot_points_given=points, foot_width=v["foot_width"] or 2.5 * wall,
                      foot_stiffness=v["foot_stiffness"], material=Material(E=v["E"], nu=v["nu"], rho=v["density"]),
                      damping_ratio=v["damping_ratio"], level=v["level"], order=v["order"], cutoff=v["cutoff"],
                      coupled=v["coupled"])
    housing.check(ring=lay["ring"], gears=lay["gears"])
    return housing


def _outline(v, raw, lay, wall) -> HousingOutline:
    planetary = lay["ring"] is not None
    kind = v["outline"] or ("circle" if planetary else "rounded_rectangle")
    circle_keys, rect_keys = ("diameter",), ("width", "height", "corner_radius")
    for k in (rect_keys if kind == "circle" else circle_keys):
        if k in raw:
            raise ConfigError(f"housing.{k} = {raw[k]!r} belongs to another outline than housing.outline = {kind!r}")
    if v["centre"] is not None:
        centre = _point("housing.centre", v["centre"])
    if kind == "circle":
        if v["centre"] is None:
            centre = lay["ring"][0] if planetary else tuple(np.mean([c for _, c, _ in lay["gears"]], axis=0))
        if v["diameter"] is not None:
            return HousingOutline.circle(centre, v["diameter"])
        if planetary:
            return HousingOutline.circle(centre, 2.0 * (lay["ring"][2] + RING_GAP + wall))
        gap = 1.2 * wall
        reach = max(math.hypot(c[0] - centre[0], c[1] - centre[1]) + ra for _, c, ra in lay["gears"])
        return HousingOutline.circle(centre, 2.0 * (reach + gap + wall))
    # rounded rectangle: the box around the tip circles (or the ring's rim) with a clearance
    gap = RING_GAP if planetary else 1.2 * wall
    circles = [lay["ring"][::2]] if planetary else [(c, ra) for _, c, ra in lay["gears"]]
    lo = np.min([np.asarray(c) - r for c, r in circles], axis=0) - gap - wall
    hi = np.max([np.asarray(c) + r for c, r in circles], axis=0) + gap + wall
    if v["centre"] is None:
        centre = tuple(float(x) for x in 0.5 * (lo + hi))
    half = np.maximum(np.asarray(centre) - lo, hi - np.asarray(centre))
    width = v["width"] if v["width"] is not None else float(2 * half[0])
    height = v["height"] if v["height"] is not None else float(2 * half[1])
    r = v["corner_radius"] if v["corner_radius"] is not None else gap + wall
    if r > 0.5 * min(width, height):
        raise ConfigError(f"housing.corner_radius = {r!r} m: must not exceed half the smaller of width and height "
                          f"({0.5 * min(width, height):.6g} m)")
    return HousingOutline((float(centre[0]), float(centre[1])), float(width), float(height), float(r))


def parse_sensors(raw, cfg, check_value) -> tuple:
    """The ``[[sensors]]`` list of a configuration whose ``housing`` is read: a tuple of Sensor."""
    if raw is None:
        return ()
    if not isinstance(raw, list) or not all(isinstance(s, dict) for s in raw):
        raise ConfigError("sensors must be a list of tables ([[sensors]] blocks)")
    bodies = ("housing", "ring") if cfg.kind == "planetary" else ("housing",)
    out = []
    for i, s in enumerate(raw):
        key = f"sensors[{i}]"
        v = check_table(key, s, SENSOR_KEYS, check_value)
        if v["name"] is None or not v["name"].strip():
            raise ConfigError(f"{key}.name is required (a non-empty string: the results' /sensors/<name>)")
        label = f"sensor {v['name']!r} ({key})"
        body = v["body"]
        if body not in bodies:
            raise ConfigError(f"{label}: {key}.body = {body!r}: a {cfg.kind} set has no {body}; bodies: "
                              f"{', '.join(bodies)}")
        if body == "housing" and cfg.housing is None:
            raise ConfigError(f"{label}: {key}.body = 'housing' needs a [housing] table (an empty one takes the "
                              "defaults derived from the gears)")
        if (v["position"] is None) == (v["angle_deg"] is None):
            raise ConfigError(f"{label}: give exactly one of {key}.position ([x, y], m) and {key}.angle_deg "
                              "(on the body's outer rim)")
        if v["direction"] is not None and v["direction_deg"] is not None:
            raise ConfigError(f"{label}: give one of {key}.direction and {key}.direction_deg")
        for k in ("window", "window_width_deg"):
            if cfg.kind != "planetary" and k in s:
                raise ConfigError(f"{label}: {key}.{k} = {s[k]!r}: the planet-pass path model needs planets; a spur "
                                  "set has none (remove the key)")
        if v["noise_rms"] is not None and v["snr_db"] is not None:
            unit = QUANTITY_UNITS[v["quantity"]]
            raise ConfigError(f"{label}: give one of {key}.noise_rms (an absolute level, {unit}) and {key}.snr_db "
                              "(relative to each signal), not both")
        if v["noise_seed"] is not None and v["noise_seed"] >= 2 ** 63:
            raise ConfigError(f"{label}: {key}.noise_seed = {v['noise_seed']}: must be < 2^63 (a 64-bit signed "
                              "integer, as the result file records it)")
        if v["noise_seed"] is not None and v["noise_rms"] is None and v["snr_db"] is None:
            raise ConfigError(f"{label}: {key}.noise_seed = {v['noise_seed']!r} without noise: give {key}.noise_rms "
                              f"or {key}.snr_db too (or remove the seed)")
        centre, point = _place(label, key, body, v, cfg)
        label_dir = None if v["direction_deg"] is not None else (v["direction"] or "radial")
        direction = sensor_direction(label_dir, None if v["direction_deg"] is None else math.radians(v["direction_deg"]),
                                     point, centre)
        out.append(Sensor(name=v["name"], body=body, point=point, direction=direction, quantity=v["quantity"],
                          angle_deg=v["angle_deg"], direction_label=label_dir, direction_deg=v["direction_deg"],
                          window=v["window"], window_width_deg=v["window_width_deg"],
                          **{k: v[k] for k in NOISE_KEYS}))
    check_sensor_names(out)
    return tuple(out)


def _place(label, key, body, v, cfg):
    """(body centre, sensor point) [m], the point checked to lie on the body."""
    if body == "housing":
        h = cfg.housing
        centre = tuple(h.outline.centre)
        if v["angle_deg"] is not None:
            return centre, tuple(float(x) for x in h.outline.point_at_angle(math.radians(v["angle_deg"])))
        p = _point(f"{key}.position", v["position"])
        tol = 1e-6 * max(h.outline.width, h.outline.height)
        if not h.contains(p, tol):
            raise ConfigError(f"{label}: {key}.position = [{p[0]:.6g}, {p[1]:.6g}] m lies off the housing (outside "
                              "its outline, in its cavity or in a hole); a sensor sits on its body")
        return centre, p
    ring = cfg.gears["ring"]
    r_root, r_rim = float(ring.rf), 0.5 * float(ring.rim_diameter)
    if v["angle_deg"] is not None:
        a = math.radians(v["angle_deg"])
        return (0.0, 0.0), (r_rim * math.cos(a), r_rim * math.sin(a))
    p = _point(f"{key}.position", v["position"])
    r = math.hypot(*p)
    tol = 1e-6 * r_rim
    if not r_root - tol <= r <= r_rim + tol:
        raise ConfigError(f"{label}: {key}.position = [{p[0]:.6g}, {p[1]:.6g}] m lies off the ring (radius "
                          f"{r * 1e3:.4g} mm; the ring's rim spans {r_root * 1e3:.4g} to {r_rim * 1e3:.4g} mm, root "
                          "circle to outer rim)")
    return (0.0, 0.0), p


def housing_document(h: Housing) -> dict:
    """The ``[housing]`` table of ``h`` as :func:`parse_housing` reads it back (every value
    explicit)."""
    o = h.outline
    doc = {"outline": o.kind, "centre": [float(o.centre[0]), float(o.centre[1])]}
    if o.kind == "circle":
        doc["diameter"] = o.width
    else:
        doc.update(width=o.width, height=o.height, corner_radius=o.corner_radius)
    doc.update(wall_thickness=h.wall_thickness, depth=h.depth, cover_thickness=h.cover_thickness)
    if h.seats:
        doc["seat_diameter"] = h.seats[0].diameter
    if h.bolts is not None:
        doc.update(bolts=h.bolts.count, bolt_circle_diameter=h.bolts.circle_diameter,
                   bolt_diameter=h.bolts.hole_diameter)
    if h.foot_angles_deg is not None:
        doc["foot_angles_deg"] = list(h.foot_angles_deg)
    else:
        given = h.foot_points_given if h.foot_points_given is not None else h.foot_points()
        doc["foot_points"] = [[float(x), float(y)] for x, y in given]
    doc.update(foot_width=h.foot_width, foot_stiffness=h.foot_stiffness, E=h.material.E, nu=h.material.nu,
               density=h.material.rho, damping_ratio=h.damping_ratio, level=h.level, order=h.order, cutoff=h.cutoff)
    if h.coupled:
        doc["coupled"] = True
    return doc


def sensors_document(sensors) -> list:
    """The ``[[sensors]]`` list as :func:`parse_sensors` reads it back."""
    out = []
    for s in sensors:
        d = {"name": s.name, "body": s.body}
        if s.angle_deg is not None:
            d["angle_deg"] = s.angle_deg
        else:
            d["position"] = [float(s.point[0]), float(s.point[1])]
        if s.direction_deg is not None:
            d["direction_deg"] = s.direction_deg
        else:
            d["direction"] = s.direction_label
        d["quantity"] = s.quantity
        for k in ("window", "window_width_deg"):  # planetary only: written where not the default
            if getattr(s, k) != SENSOR_KEYS[k][1]:
                d[k] = getattr(s, k)
        d.update({k: getattr(s, k) for k in NOISE_KEYS if getattr(s, k) is not None})
        out.append(d)
    return out
