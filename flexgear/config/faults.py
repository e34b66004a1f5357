"""``[[faults]]`` and ``[errors]``: tooth faults and manufacturing / assembly errors of a gear set.

Reads and validates the sections into the data of :mod:`flexgear.gears.faults` (``Config.faults``,
a tuple of :class:`~flexgear.gears.faults.ToothFault`; ``Config.errors``, an
:class:`~flexgear.gears.faults.Errors` or None), writes them back for :func:`~flexgear.config.loader.config_document`,
and derives what the set's kinematics say about them (loaded flanks, characteristic
frequencies). Every rule is checked when the file is read, before anything long runs; a broken
rule is a ConfigError naming the fault (``faults[2] (spall on sun tooth 3, left flank)``), the
key and the rule.

Example::

    [[faults]]
    kind = "crack"        # crack | spall | chip | missing
    gear = "sun"          # a gear of the set; gear = "planet" also needs planet = 1..N
    tooth = 0             # counted counter-clockwise from tooth 0 (as pair_tooth_a/b in results)
    flank = "left"        # left (counter-clockwise side of the tooth) | right
    depth = 1.0e-3        # m
    angle_deg = 45.0      # to the tooth centre line

    [errors.eccentricity.sun]
    magnitude = 10.0e-6   # m
    phase_deg = 0.0

    [errors.pitch.planet]  # "planet": every planet; planet2: one
    grade = 6              # ISO 1328-1:2013 flank tolerance class, drawn with the seed
    seed = 1

What is checked here (geometry, rigid): keys, ranges, gears and planets; errors of at most a
module; a crack that leaves its tooth, a spall off the active flank, a chip larger than the flank
or half the tip land, overlapping faults; errors that close the backlash (the teeth jam) or open
a centre distance until the contact ratio falls below 1. Whether a tangential pin, pitch or
relief error unloads a planet or a tooth pair needs the loaded statics: the time-domain models
answer it.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError, GeometryError
from ..gears.faults import (FAULT_KINDS, FLANK_NAMES, FLANKS, LEFT, RIGHT, Chip, Crack, Eccentricity, Errors,
                            GearErrors, Missing, PinError, PitchErrors, ProfileErrors, Spall, check_crack, crack_path,
                            iso1328_scope, random_pitch_deviations, roll_length, roll_radius)
from ..gears.geometry import FLANK, GearPair
from .schema import check_table as _table
from ..gears.kinematics import (SetKinematics, active_radii, hunting_tooth_frequency, local_fault_frequency, mate_flank,
                                planetary_kinematics, spur_kinematics)

#: Overlap of both flanks [m] still accepted as "not jammed": the IMPACT law of the presets gives
#: about 2 N for it (against mesh forces of 1-4 kN), below the contact tables' accuracy of a flank
#: position.
JAM_TOLERANCE = 1e-7

# --------------------------------------------------------------------------------------------
# schema: key -> (kind, default, rule, unit, description), as flexgear.config.loader's; the rules
# are intervals "[a, b]", "(a, b]", ">= a", "> a" or a tuple of allowed values.
FAULT_KEYS = {
    "kind": ("str", None, tuple(FAULT_KINDS), "",
        "crack | spall | chip | missing"),
    "gear": ("str", None, None, "",
        "the faulty gear: pinion, wheel | sun, planet, ring"),
    "planet": ("int", None, ">= 1", "",
        "which planet (1..N, counter-clockwise from planet 1), gear = \"planet\" only"),
    "tooth": ("int", None, ">= 0", "",
        "tooth index 0..z-1, counter-clockwise from tooth 0 (results' pair_tooth_a/b)"),
    "flank": ("str", None, tuple(FLANKS), "",
        "left (counter-clockwise side of the tooth, pair_side +1) | right"),
}
KIND_KEYS = {
    "crack": {
        "depth": ("float", None, ">= 0", "m",
            "length of the straight crack from its start on the root fillet"),
        "angle_deg": ("float", 45.0, "(0, 90]", "deg",
            "angle to the tooth centre line, towards the root and the centre line"),
        "width_fraction": ("float", 1.0, "[0, 1]", "",
            "part of the face width the crack crosses (1 = through)"),
    },
    "spall": {
        "start_radius": ("float", None, "> 0", "m",
            "lower radius of the spalled band (or start_roll_deg)"),
        "end_radius": ("float", None, "> 0", "m",
            "upper radius (or end_roll_deg)"),
        "start_roll_deg": ("float", None, ">= 0", "deg",
            "roll angle of the involute at the lower radius"),
        "end_roll_deg": ("float", None, ">= 0", "deg",
            "roll angle at the upper radius"),
        "depth": ("float", None, ">= 0", "m",
            "normal to the flank"),
        "width_fraction": ("float", 1.0, "[0, 1]", "",
            "part of the face width spalled (1 = across the face)"),
    },
    "chip": {
        "profile_size": ("float", None, ">= 0", "m",
            "along the flank from the tip corner (arc length)"),
        "tip_size": ("float", None, ">= 0", "m",
            "along the tip land from the tip corner (at most half of it)"),
        "width_fraction": ("float", 1.0, "[0, 1]", "",
            "part of the face width chipped (1 = across the face)"),
    },
    "missing": {
        "height_fraction": ("float", 0.0, "[0, 1]", "",
            "tooth height left: 0 = removed down to the root circle"),
    },
}
ECCENTRICITY_KEYS = {
    "magnitude": ("float", 0.0, ">= 0", "m",
        "offset of the toothing's centre from the rotation axis"),
    "phase_deg": ("float", 0.0, "[-360, 360]", "deg",
        "direction of the offset, counter-clockwise from tooth 0"),
}
PIN_KEYS = {
    "radial": ("float", 0.0, None, "m",
        "planet pin moved away from the carrier axis"),
    "tangential": ("float", 0.0, None, "m",
        "planet pin moved counter-clockwise along the carrier"),
}
PITCH_KEYS = {
    "deviations": ("any", None, None, "m",
        "z single pitch deviations f_p (tooth j -> j+1), summing to zero"),
    "grade": ("int", None, "[1, 11]", "",
        "ISO 1328-1:2013 flank tolerance class of a random sequence"),
    "seed": ("int", None, ">= 0", "",
        "seed of the random sequence (planet shorthand: planet k gets seed + k - 1)"),
}
PROFILE_KEYS = {
    "slope": ("float", 0.0, None, "m",
        "profile slope deviation f_Halpha (material added towards the tip > 0)"),
    "form": ("float", 0.0, ">= 0", "m",
        "profile form deviation f_falpha (range of a waviness)"),
    "form_waves": ("int", 1, ">= 1", "",
        "waves of the form deviation over the profile"),
    "tip_relief": ("float", 0.0, ">= 0", "m",
        "material removed at the tip circle (C_a)"),
    "tip_relief_start_diameter": ("float", None, "> 0", "m",
        "where the tip relief starts (or ..._roll_deg)"),
    "tip_relief_start_roll_deg": ("float", None, ">= 0", "deg",
        "roll angle where the tip relief starts"),
    "root_relief": ("float", 0.0, ">= 0", "m",
        "material removed at the form circle (C_f)"),
    "root_relief_start_diameter": ("float", None, "> 0", "m",
        "where the root relief starts (or ..._roll_deg)"),
    "root_relief_start_roll_deg": ("float", None, ">= 0", "deg",
        "roll angle where the root relief starts"),
    "relief_shape": ("str", "linear", ("linear", "parabolic"), "",
        "growth of the reliefs from their start"),
}
ERROR_SECTIONS = {"eccentricity": ECCENTRICITY_KEYS, "pin": PIN_KEYS, "pitch": PITCH_KEYS, "profile": PROFILE_KEYS}


def _bodies(cfg) -> dict:
    """Gear body name -> gear name (``planet2`` -> ``planet``)."""
    if cfg.kind == "spur":
        return {"pinion": "pinion", "wheel": "wheel"}
    out = {"sun": "sun"}
    out.update({f"planet{k}": "planet" for k in range(1, cfg.planetary["planets"] + 1)})
    out["ring"] = "ring"
    return out


def mesh_pairs(cfg) -> dict:
    """Mesh name (as in results: ``pinion-wheel``, ``sun-planet1``, ``planet1-ring``) ->
    (body a, body b, GearPair)."""
    g = cfg.gears
    if cfg.kind == "spur":
        return {"pinion-wheel": ("pinion", "wheel", GearPair(g["pinion"], g["wheel"]))}
    sp, pr = GearPair(g["sun"], g["planet"]), GearPair(g["planet"], g["ring"])
    out = {}
    N = cfg.planetary["planets"]
    for k in range(1, N + 1):
        out[f"sun-planet{k}"] = ("sun", f"planet{k}", sp)
    for k in range(1, N + 1):
        out[f"planet{k}-ring"] = (f"planet{k}", "ring", pr)
    return out


# ============================================================================================
# [[faults]]
# ============================================================================================
def _fault_name(i: int, raw: dict) -> str:
    what = raw.get("kind", "fault")
    gear = raw.get("gear", "?")
    body = f"planet{raw['planet']}" if gear == "planet" and "planet" in raw else gear
    where = f" on {body} tooth {raw.get('tooth', '?')}"
    flank = f", {raw['flank']} flank" if isinstance(raw.get("flank"), str) else ""
    return f"faults[{i}] ({what}{where}{flank})"


def parse_faults(raw, cfg, check_value) -> tuple:
    """The ``[[faults]]`` list of a configuration whose gears, planets and meshes are read:
    a tuple of ToothFault, every rule checked (module docstring)."""
    if raw is None:
        return ()
    if not isinstance(raw, list) or not all(isinstance(f, dict) for f in raw):
        raise ConfigError("faults must be a list of tables ([[faults]] blocks)")
    bodies = _bodies(cfg)
    faults = []
    for i, f in enumerate(raw):
        name = _fault_name(i, f)
        kind = f.get("kind")
        if kind not in FAULT_KINDS:
            raise ConfigError(f"{name}: kind = {kind!r}: must be one of {', '.join(map(repr, FAULT_KINDS))}")
        schema = dict(FAULT_KEYS)
        schema.update(KIND_KEYS[kind])
        if kind == "missing":
            del schema["flank"]
        try:
            v = _table(f"faults[{i}]", f, schema, check_value)
        except ConfigError as exc:
            raise ConfigError(f"{name}: {exc}") from None
        faults.append(_fault(name, i, v, cfg, bodies))
    _check_overlaps(faults, cfg)
    return tuple(faults)


def _fault(name, i, v, cfg, bodies):
    kind, gear = v["kind"], v["gear"]
    key = f"faults[{i}]"
    if gear is None:
        raise ConfigError(f"{name}: {key}.gear is required ({', '.join(cfg.gears)})")
    if gear not in cfg.gears:
        raise ConfigError(f"{name}: {key}.gear = {gear!r}: unknown gear; the gears of this {cfg.kind} set are "
                          f"{', '.join(cfg.gears)}")
    if gear == "planet":
        N = cfg.planetary["planets"]
        if v["planet"] is None:
            raise ConfigError(f"{name}: {key}.planet is required with gear = 'planet' (1 to {N})")
        if not 1 <= v["planet"] <= N:
            raise ConfigError(f"{name}: {key}.planet = {v['planet']}: unknown planet; rule: 1 <= planet <= {N} "
                              f"(planetary.planets)")
    elif v["planet"] is not None:
        raise ConfigError(f"{name}: {key}.planet = {v['planet']} given for gear = {gear!r}; only gear = 'planet' "
                          "has planets")
    g = cfg.gears[gear]
    if v["tooth"] is None:
        raise ConfigError(f"{name}: {key}.tooth is required (0 to {g.z - 1})")
    if not 0 <= v["tooth"] < g.z:
        raise ConfigError(f"{name}: {key}.tooth = {v['tooth']}: out of range; rule: 0 <= tooth < z = {g.z} "
                          f"({gear} has {g.z} teeth, numbered from 0)")
    common = dict(gear=gear, tooth=v["tooth"], planet=v["planet"])
    if kind != "missing":
        if v["flank"] is None:
            raise ConfigError(f"{name}: {key}.flank is required: 'left' or 'right'")
        common["flank"] = FLANKS[v["flank"]]

    def need(*keys):
        for k in keys:
            if v[k] is None:
                raise ConfigError(f"{name}: {key}.{k} is required for kind = {kind!r}")

    try:
        if kind == "crack":
            need("depth")
            fault = Crack(depth=v["depth"], angle=math.radians(v["angle_deg"]), width_fraction=v["width_fraction"],
                          **common)
            check_crack(g, fault)
        elif kind == "spall":
            fault = _spall(name, key, v, g, common, _active(cfg, v["gear"], v["planet"]))
        elif kind == "chip":
            need("profile_size", "tip_size")
            fault = Chip(profile_size=v["profile_size"], tip_size=v["tip_size"], width_fraction=v["width_fraction"],
                         **common)
            _check_chip(key, g, fault)
        else:
            fault = Missing(height_fraction=v["height_fraction"], **common)
    except GeometryError as exc:
        raise ConfigError(f"{name}: {exc}") from None
    return fault


def _active(cfg, gear: str, planet) -> tuple[float, float]:
    """Radii (low, high) [m] of the active flank of ``gear``: the union over its meshes."""
    lo, hi = math.inf, -math.inf
    for a, b, pair in mesh_pairs(cfg).values():
        ga, gb = active_radii(pair)
        for body, rng in ((a, ga), (b, gb)):
            if body == (f"planet{planet}" if gear == "planet" else gear):
                lo, hi = min(lo, rng[0]), max(hi, rng[1])
    return lo, hi


def _spall(name, key, v, g, common, active):
    by_radius = v["start_radius"] is not None or v["end_radius"] is not None
    by_roll = v["start_roll_deg"] is not None or v["end_roll_deg"] is not None
    if by_radius == by_roll:
        raise ConfigError(f"{name}: give {key}.start_radius and {key}.end_radius, or {key}.start_roll_deg and "
                          f"{key}.end_roll_deg (one pair)")
    if by_radius:
        for k in ("start_radius", "end_radius"):
            if v[k] is None:
                raise ConfigError(f"{name}: {key}.{k} is required with the other radius")
        r0, r1, keys = v["start_radius"], v["end_radius"], ("start_radius", "end_radius")
    else:
        for k in ("start_roll_deg", "end_roll_deg"):
            if v[k] is None:
                raise ConfigError(f"{name}: {key}.{k} is required with the other roll angle")
        r0, r1 = (float(roll_radius(g, math.radians(v[k]))) for k in ("start_roll_deg", "end_roll_deg"))
        keys = ("start_roll_deg", "end_roll_deg")
    if v["depth"] is None:
        raise ConfigError(f"{name}: {key}.depth is required for kind = 'spall'")
    if not r0 < r1:
        raise ConfigError(f"{name}: {key}.{keys[0]} = {v[keys[0]]!r} and {key}.{keys[1]} = {v[keys[1]]!r}: the "
                          f"start must lie below the end (radius {r0 * 1e3:.6g} mm >= {r1 * 1e3:.6g} mm)")
    lo, hi = active
    tol = 1e-9
    if r0 < lo - tol or r1 > hi + tol:
        def roll(r):
            return math.degrees(roll_length(g, r) / g.rb)
        raise ConfigError(
            f"{name}: {key}.{keys[0]}/{keys[1]}: the spall spans r = {r0 * 1e3:.6g} to {r1 * 1e3:.6g} mm, outside "
            f"the active flank of {g.name}, r = {lo * 1e3:.6g} to {hi * 1e3:.6g} mm (roll angle {roll(lo):.5g} to "
            f"{roll(hi):.5g} deg); rule: a spall lies on the active flank")
    half = g.rb * float(np.min(g.half_angle(np.linspace(r0, r1, 65))))
    if v["depth"] >= half:
        raise ConfigError(f"{name}: {key}.depth = {v['depth']!r} m: deeper than the tooth's half thickness there "
                          f"(r_b psi = {half * 1e3:.4g} mm); rule: depth < {half:.6g} m")
    return Spall(start_radius=r0, end_radius=r1, depth=v["depth"], width_fraction=v["width_fraction"], **common)


def _flank_lengths(g) -> tuple[float, float]:
    """Arc length [m] of the involute flank (form circle to tip corner) and of half the tip land."""
    one = g.tooth_outline(g.module / 400)
    n = (len(one.points) + 1) // 2
    p, kind = one.points[:n], one.kind[:n]
    seg = np.hypot(*np.diff(p, axis=0).T)
    fl = np.nonzero(kind == FLANK)[0]
    flank = float(seg[fl[0]:fl[-1]].sum())
    tip = g.ra * abs(math.atan2(p[fl[-1], 1], p[fl[-1], 0]))
    return flank, tip


def _check_chip(key, g, f: Chip):
    flank, tip = _flank_lengths(g)
    if f.profile_size > flank:
        raise GeometryError(f"profile_size = {f.profile_size!r} m: longer than the involute flank "
                            f"({flank * 1e3:.4g} mm from the tip corner to the form circle); rule: a chip ends on the "
                            "flank")
    if f.tip_size > tip:
        raise GeometryError(f"tip_size = {f.tip_size!r} m: longer than half the tip land ({tip * 1e3:.4g} mm); rule: "
                            "a chip ends before the tooth centre line (a larger break: kind = 'missing')")


def chip_low_radius(g, f: Chip) -> float:
    """Radius [m] where a chip's cut meets the flank."""
    one = g.tooth_outline(g.module / 400)
    n = (len(one.points) + 1) // 2
    p = one.points[:n][::-1]  # tip centre -> space centre, right half
    kind = one.kind[:n][::-1]
    corner = int(np.nonzero(kind == FLANK)[0][0])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    r = np.hypot(*p.T)
    return float(np.interp(s[corner] + f.profile_size, s, r))


def _check_overlaps(faults, cfg):
    """Two faults on one tooth of one body may not touch the same material."""
    def span(f):
        g = cfg.gears[f.gear]
        if isinstance(f, Spall):
            return (f.start_radius, f.end_radius)
        if isinstance(f, Chip):
            r = chip_low_radius(g, f)
            return (min(r, g.ra), max(r, g.ra))
        return None

    def segments_cross(a, b):
        (p, q), (r, s) = a, b
        d = lambda u, v, w: (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0])
        return d(p, q, r) * d(p, q, s) <= 0 and d(r, s, p) * d(r, s, q) <= 0

    for i, a in enumerate(faults):
        for j in range(i):
            b = faults[j]
            if a.body != b.body or a.tooth != b.tooth or a.null or b.null:
                continue
            clash = None
            if isinstance(a, Missing) or isinstance(b, Missing):
                clash = "a missing tooth leaves no material for another fault"
            elif isinstance(a, Crack) and isinstance(b, Crack):
                g = cfg.gears[a.gear]
                if a.flank == b.flank or segments_cross(crack_path(g, a), crack_path(g, b)):
                    clash = "the cracks share their start or cross"
            elif not isinstance(a, Crack) and not isinstance(b, Crack) and a.flank == b.flank:
                sa, sb = span(a), span(b)
                if sa[0] < sb[1] and sb[0] < sa[1]:
                    clash = (f"they share the flank between r = {max(sa[0], sb[0]) * 1e3:.5g} and "
                             f"{min(sa[1], sb[1]) * 1e3:.5g} mm")
            if clash:
                raise ConfigError(f"faults[{i}] ({a.label()}) overlaps faults[{j}] ({b.label()}): {clash}; rule: "
                                  "faults on one tooth do not overlap")


def _degrees(angle: float) -> float:
    """Degrees that read back (math.radians) as exactly ``angle`` where a float within a few ulps
    of math.degrees(angle) does (most angles), so that the resolved configuration reproduces
    the same Config."""
    d0 = math.degrees(angle)
    up = down = d0
    for _ in range(8):
        for d in (up, down):
            if math.radians(d) == angle:
                return d
        up, down = math.nextafter(up, math.inf), math.nextafter(down, -math.inf)
    return d0


def _python_int(value):
    """An integer of any kind (numpy's too, as a loop over ``np.arange`` gives) as a Python int;
    anything else as it is, for the rules to refuse."""
    return int(value) if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)) else value


def faults_document(faults) -> list:
    """The faults as TOML tables (SI; spall radii, not roll angles). Faults set in Python are
    checked for what the tables cannot show: the objects themselves, the flank (LEFT, RIGHT or
    the file's "left", "right") and a crack's angle in radians."""
    kinds = "Crack, Spall, Chip, Missing from flexgear.gears.faults"
    if not isinstance(faults, (tuple, list)):
        raise ConfigError(f"faults = {faults!r}: must be a tuple of faults ({kinds}), e.g. (Crack(...),)")
    out = []
    for i, f in enumerate(faults):
        if not isinstance(f, (Crack, Spall, Chip, Missing)):
            raise ConfigError(f"faults[{i}] = {f!r}: must be a fault object ({kinds}); a table as in the file is "
                              "read by flexgear.load_config")
        d = {"kind": f.kind, "gear": f.gear}
        if f.planet is not None:
            d["planet"] = _python_int(f.planet)
        d["tooth"] = _python_int(f.tooth)
        if not isinstance(f, Missing):
            if f.flank not in FLANK_NAMES and f.flank not in FLANKS:
                raise ConfigError(f"faults[{i}].flank = {f.flank!r}: must be LEFT or RIGHT (flexgear.gears.faults; "
                                  "+1, -1) or the file's 'left', 'right'")
            d["flank"] = FLANK_NAMES.get(f.flank, f.flank)
        if isinstance(f, Crack) and not 0.0 < f.angle <= 0.5 * math.pi * (1 + 1e-12):
            raise ConfigError(f"faults[{i}].angle = {f.angle!r} rad ({math.degrees(f.angle):.6g} deg): must lie in "
                              "(0, pi/2]; Crack.angle is in radians (math.radians(45)), the file's angle_deg in "
                              "degrees")
        if isinstance(f, Crack):
            d.update(depth=f.depth, angle_deg=_degrees(f.angle), width_fraction=f.width_fraction)
        elif isinstance(f, Spall):
            d.update(start_radius=f.start_radius, end_radius=f.end_radius, depth=f.depth,
                     width_fraction=f.width_fraction)
        elif isinstance(f, Chip):
            d.update(profile_size=f.profile_size, tip_size=f.tip_size, width_fraction=f.width_fraction)
        else:
            d["height_fraction"] = f.height_fraction
        out.append(d)
    return out


# ============================================================================================
# [errors]
# ============================================================================================
def parse_errors(raw, cfg, check_value) -> Errors | None:
    """The ``[errors]`` block of a configuration whose gears, planets and meshes are read
    (module docstring); None when it is absent or empty."""
    if raw is None:
        return None
    if not isinstance(raw, dict):
        raise ConfigError("[errors] must be a table of the tables eccentricity, pin, pitch, profile")
    unknown = sorted(set(raw) - set(ERROR_SECTIONS))
    if unknown:
        raise ConfigError(f"unknown key(s) {', '.join(repr('errors.' + k) for k in unknown)}; allowed in [errors]: "
                          f"{', '.join(ERROR_SECTIONS)}")
    bodies = _bodies(cfg)
    per = {b: {} for b in bodies}
    pins = {}
    for sec, schema in ERROR_SECTIONS.items():
        tab = raw.get(sec, {})
        if not isinstance(tab, dict):
            raise ConfigError(f"[errors.{sec}] must be a table of gear bodies ({', '.join(bodies)})")
        allowed = [b for b in bodies if b.startswith("planet")] if sec == "pin" else list(bodies)
        if cfg.kind == "planetary":
            allowed.append("planet")  # shorthand: every planet
        expanded = {}
        for body, vals in tab.items():
            if body not in allowed:
                what = "planet pins" if sec == "pin" else "gear bodies"
                extra = " (a spur pair has no planets)" if sec == "pin" and cfg.kind == "spur" else ""
                raise ConfigError(f"errors.{sec}.{body}: unknown {'planet' if sec == 'pin' else 'gear body'}{extra}; "
                                  f"the {what} are {', '.join(allowed) or 'none'}")
            targets = [b for b in bodies if b.startswith("planet")] if body == "planet" else [body]
            for t in targets:
                if t in expanded:
                    raise ConfigError(f"errors.{sec}: {t} is given twice (errors.{sec}.planet sets every planet)")
                expanded[t] = (body, vals)
        for body, (given, vals) in expanded.items():
            path = f"errors.{sec}.{given}"
            v = _table(path, vals, schema, check_value)
            g = cfg.gears[bodies[body]]
            for key in (k for k, spec in schema.items() if spec[3] == "m" and "_diameter" not in k):
                _check_size(f"{path}.{key}", v[key], g)
            if sec == "eccentricity":
                per[body]["eccentricity"] = Eccentricity(magnitude=v["magnitude"], phase=math.radians(v["phase_deg"]))
            elif sec == "pin":
                pins[body] = PinError(radial=v["radial"], tangential=v["tangential"])
            elif sec == "pitch":
                per[body]["pitch"] = _pitch(path, v, g, int(body[6:]) - 1 if given == "planet" else 0)
            else:
                per[body]["profile"] = _profile(path, v, g)
    gears = {b: GearErrors(**e) for b, e in per.items() if e}
    errors = Errors(gears=gears, pins=pins)
    if not gears and not pins:
        return None
    _check_jam(errors, cfg)
    return errors


def _check_size(path: str, value, g) -> None:
    """An error of a gear is at most its module: more is a unit slip (20 for 20e-6 m)."""
    if isinstance(value, float) and abs(value) > g.module:
        raise ConfigError(f"{path} = {value!r} m: more than the module of {g.name} ({g.module * 1e3:g} mm); rule: "
                          "|error| <= m (errors are micrometres, given in metres: 20e-6 for 20 um)")


def _pitch(path, v, g, seed_offset: int) -> PitchErrors:
    dev, grade, seed = v["deviations"], v["grade"], v["seed"]
    if (dev is None) == (grade is None):
        raise ConfigError(f"{path}: give deviations (a list of {g.z} single pitch deviations, m) or grade and seed "
                          "(a random sequence of an ISO 1328-1:2013 class), one of them")
    if dev is not None:
        if seed is not None:
            raise ConfigError(f"{path}.seed given with {path}.deviations; the seed draws a sequence for a grade")
        if not isinstance(dev, list) or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in dev):
            raise ConfigError(f"{path}.deviations = {dev!r}: must be a list of numbers (m)")
        if len(dev) != g.z:
            raise ConfigError(f"{path}.deviations: {len(dev)} values for {g.z} teeth; rule: one single pitch "
                              f"deviation per tooth (tooth j to j+1), z = {g.z}")
        f = [float(x) for x in dev]
        if not all(math.isfinite(x) for x in f):
            raise ConfigError(f"{path}.deviations: must be finite numbers")
        _check_size(f"{path}.deviations[{int(np.argmax(np.abs(f)))}]", max(f, key=abs), g)  # the largest
        total = math.fsum(f)
        if abs(total) > 1e-12 + 1e-9 * math.fsum(abs(x) for x in f):
            raise ConfigError(f"{path}.deviations sum to {total:.6g} m; rule: the single pitch deviations of a "
                              "closed circle sum to zero")
        return PitchErrors(deviations=tuple(f))
    if seed is None:
        raise ConfigError(f"{path}.seed is required with {path}.grade (the random sequence is drawn from it)")
    why = iso1328_scope(g, grade)
    if why:
        raise ConfigError(f"{path}.grade = {grade}: {g.name} lies outside the scope of ISO 1328-1:2013 ({why}); its "
                          "tolerance formulas are not extrapolated: give deviations instead")
    seed += seed_offset
    return PitchErrors(deviations=tuple(map(float, random_pitch_deviations(g, grade, seed))), grade=grade, seed=seed)


def _profile(path, v, g) -> ProfileErrors:
    starts = {}
    lo, hi = sorted((g.r_form, g.ra))
    for which in ("tip_relief", "root_relief"):
        dia, roll = v[f"{which}_start_diameter"], v[f"{which}_start_roll_deg"]
        if dia is not None and roll is not None:
            raise ConfigError(f"{path}: give {which}_start_diameter or {which}_start_roll_deg, not both")
        r = dia / 2 if dia is not None else (float(roll_radius(g, math.radians(roll))) if roll is not None else None)
        key = f"{which}_start_diameter" if dia is not None else f"{which}_start_roll_deg"
        if v[which] > 0 and r is None:
            raise ConfigError(f"{path}.{which} = {v[which]!r} m needs {which}_start_diameter or {which}_start_roll_deg")
        if r is not None and not lo < r < hi:
            raise ConfigError(f"{path}.{key} = {v[key]!r}: the relief starts at r = {r * 1e3:.6g} mm, outside the "
                              f"involute flank of {g.name} (r = {lo * 1e3:.6g} to {hi * 1e3:.6g} mm, form circle to "
                              "tip); rule: it starts strictly inside the flank")
        starts[which] = r
    rt, rr = starts["tip_relief"], starts["root_relief"]
    if rt is not None and rr is not None and v["tip_relief"] > 0 and v["root_relief"] > 0:
        if roll_length(g, rr) > roll_length(g, rt):
            raise ConfigError(f"{path}: the root relief starts above the tip relief (r = {rr * 1e3:.6g} mm beyond "
                              f"{rt * 1e3:.6g} mm towards the tip); rule: the reliefs do not overlap")
    prof = ProfileErrors(slope=v["slope"], form=v["form"], form_waves=v["form_waves"], tip_relief=v["tip_relief"],
                         tip_relief_start=rt, root_relief=v["root_relief"], root_relief_start=rr,
                         relief_shape=v["relief_shape"])
    r = np.linspace(lo, hi, 257)
    thin = g.half_angle(r) + prof.offset(g, r) / g.rb
    if thin.min() <= 0:
        i = int(np.argmin(thin))
        raise ConfigError(f"{path}: the profile errors remove the whole tooth at r = {r[i] * 1e3:.5g} mm (half "
                          f"thickness {g.rb * g.half_angle(r[i]) * 1e3:.4g} mm, offset "
                          f"{prof.offset(g, r[i]) * 1e6:.4g} um); rule: the tooth keeps a positive thickness")
    return prof


def errors_document(errors: Errors | None) -> dict | None:
    """The errors as a TOML table (SI, per body; the planet shorthand expanded)."""
    if errors is None:
        return None
    out = {}
    for body, ge in errors.gears.items():
        if ge.eccentricity is not None:
            out.setdefault("eccentricity", {})[body] = {"magnitude": ge.eccentricity.magnitude,
                                                        "phase_deg": _degrees(ge.eccentricity.phase)}
        if ge.pitch is not None:
            p = ge.pitch
            out.setdefault("pitch", {})[body] = ({"grade": p.grade, "seed": p.seed} if p.grade is not None
                                                 else {"deviations": list(p.deviations)})
        if ge.profile is not None:
            pr = ge.profile
            d = dict(slope=pr.slope, form=pr.form, form_waves=pr.form_waves, tip_relief=pr.tip_relief,
                     root_relief=pr.root_relief, relief_shape=pr.relief_shape)
            if pr.tip_relief_start is not None:
                d["tip_relief_start_diameter"] = 2 * pr.tip_relief_start
            if pr.root_relief_start is not None:
                d["root_relief_start_diameter"] = 2 * pr.root_relief_start
            out.setdefault("profile", {})[body] = d
    for body, pe in errors.pins.items():
        out.setdefault("pin", {})[body] = {"radial": pe.radial, "tangential": pe.tangential}
    return out


# ============================================================================================
# backlash: jam and loss of mesh (rigid geometry)
# ============================================================================================
def backlash(pair: GearPair) -> float:
    """Normal backlash j_bn [m] along the line of action at the working centre distance: the
    thinning of both gears on their base circles, (thinning_1 + thinning_2) cos(alpha)."""
    return (pair.g1.thinning + pair.g2.thinning) * math.cos(pair.g1.pressure_angle)


def contact_ratio_at(pair: GearPair, a: float) -> float:
    """Transverse contact ratio of ``pair`` at the centre distance ``a`` [m] (ISO 21771 with the
    working pressure angle cos(alpha_w) = (r_b2 +- r_b1) / a); 0 if the tip circles no longer
    reach the line of action."""
    g1, g2 = pair.g1, pair.g2
    c = ((g2.rb - g1.rb) if pair.internal else (g1.rb + g2.rb)) / a
    if not 0 < c < 1:
        return 0.0
    t = math.tan(math.acos(c))
    ga = math.sqrt(g1.ra**2 - g1.rb**2) - g1.rb * t
    t2 = math.sqrt(max(g2.ra**2 - g2.rb**2, 0.0))
    gf = (t2 - g2.rb * t) if not pair.internal else (g2.rb * t - t2)
    return max(ga + gf, 0.0) / g1.pb


def _index_spread(pitch: PitchErrors | None, window: int) -> float:
    """Largest range [m] of the index deviations of ``window`` consecutive teeth (cyclic)."""
    if pitch is None or pitch.null:
        return 0.0
    F = pitch.index_deviations()
    z = len(F)
    w = min(window, z)
    ext = np.concatenate([F, F[:w - 1]])
    return float(max(ext[i:i + w].max() - ext[i:i + w].min() for i in range(z)))


def _added(profile: ProfileErrors | None, g, active) -> float:
    """Largest material added [m] by the profile errors on the active flank (>= 0)."""
    if profile is None or profile.null:
        return 0.0
    return max(0.0, float(profile.offset(g, np.linspace(active[0], active[1], 257)).max()))


def _check_jam(errors: Errors, cfg) -> None:
    """Errors must not close the backlash of a mesh (the teeth jam) nor open a centre distance
    until the contact ratio falls below 1 (the teeth lose mesh), in the worst alignment of the
    eccentricities and pin errors (first order along the lines of action)."""
    def ecc(body):
        ge = errors.gears.get(body)
        return ge.eccentricity.magnitude if ge is not None and ge.eccentricity is not None else 0.0

    def ge_of(body):
        return errors.gears.get(body, GearErrors())

    for mesh, (a, b, pair) in mesh_pairs(cfg).items():
        planet = a if a.startswith("planet") else (b if b.startswith("planet") else None)
        pin = errors.pins.get(planet, PinError()) if planet else PinError()
        aw0 = pair.centre_distance
        dr = math.hypot(aw0 + pin.radial, pin.tangential) - aw0  # pin: change of the planet's distance
        e = ecc(a) + ecc(b)
        src = [f"errors.eccentricity.{x}" for x in (a, b) if ecc(x) > 0.0]
        src += [f"errors.pin.{planet}"] if planet and not pin.null else []
        src += [f"errors.{k}.{x}" for k in ("pitch", "profile") for x in (a, b)
                if getattr(ge_of(x), k) is not None and not getattr(ge_of(x), k).null]
        given = f"[errors] ({', '.join(src)})" if src else "[errors]"
        # closure of the backlash: external pairs close when the centre distance shrinks, internal ones
        # when it grows
        close = e + (-dr if not pair.internal else dr)  # largest centre distance change towards the mate
        grow = e + (dr if not pair.internal else -dr)  # ... away from it
        jb = backlash(pair)
        sa = math.sin(pair.alpha_w)
        ca = math.cos(pair.g1.pressure_angle)
        w = int(math.ceil(pair.contact_ratio)) + 1
        ra, rb = active_radii(pair)
        parts = {"centre distance": 2 * sa * max(close, 0.0),
                 "pitch errors": ca * (_index_spread(ge_of(a).pitch, w) + _index_spread(ge_of(b).pitch, w)),
                 "profile errors": 2 * (_added(ge_of(a).profile, pair.g1, ra) + _added(ge_of(b).profile, pair.g2, rb))}
        closure = sum(parts.values())
        if closure > jb + JAM_TOLERANCE:
            what = ", ".join(f"{k} {v * 1e6:.4g} um" for k, v in parts.items() if v > 0)
            now = (pair.g1.thinning, pair.g2.thinning)  # the backlash grows by 2 cos(alpha) per thinning of each
            need = math.ceil((max(now) + (closure - jb) / ca / 2) * 1e7) / 10  # um, rounded up: enough
            raise ConfigError(
                f"{given}: the errors close the backlash of mesh {mesh}: up to {closure * 1e6:.4g} um along the line "
                f"of action ({what}) against a backlash of {jb * 1e6:.4g} um (gears.*.thinning); rule: the errors "
                f"leave a backlash >= 0 (the teeth jam otherwise); give the gears a backlash allowance, e.g. "
                f"thinning = {need:g}e-6 (m) or more on each (now {now[0] * 1e6:.4g} and {now[1] * 1e6:.4g} um), or "
                "smaller errors")
        a_max = aw0 + (grow if not pair.internal else -grow)
        eps = contact_ratio_at(pair, a_max)
        if eps < 1.0:
            raise ConfigError(
                f"{given}: the errors open the centre distance of mesh {mesh} by up to {grow * 1e6:.4g} um: the "
                f"contact ratio falls to {eps:.3f}; rule: eps_alpha >= 1 (the teeth lose mesh otherwise)")


# ============================================================================================
# kinematics: loaded flanks, characteristic frequencies
# ============================================================================================
def set_kinematics(cfg, speed_hz: float | None = None) -> SetKinematics:
    """Rotation frequencies of the set at the drive speed ``speed_hz`` [Hz] (default: the mean
    input frequency)."""
    f = cfg.input_frequency if speed_hz is None else speed_hz
    z = {n: g.z for n, g in cfg.gears.items()}
    if cfg.kind == "spur":
        fp = f if cfg.drive["body"] == "pinion" else -f * z["wheel"] / z["pinion"]
        return spur_kinematics(z["pinion"], z["wheel"], fp)
    fs = f if cfg.drive["body"] == "sun" else f * (z["sun"] + z["ring"]) / z["sun"]
    return planetary_kinematics(z["sun"], z["planet"], z["ring"], cfg.planetary["planets"], fs)


def loaded_flanks(cfg) -> dict:
    """Mesh name -> (flank of body a, flank of body b) that carry the static load (+1 left, -1
    right): the sign of the mesh torque, from the load torque's sign and the way flexgear's
    assembly applies it (a spur pair's load torque resists the rotation of positive drive speed;
    a planetary set's resists the loaded body's actual rotation). A mesh torque that turns gear
    a clockwise loads its left flank."""
    torque = cfg.load["torque"]
    T = torque if isinstance(torque, float) else torque[-1][1]
    kin = set_kinematics(cfg)
    if cfg.kind == "spur":
        # flexgear.dynamics.model.assembly applies +T (counter-clockwise) to the loaded body whichever gear
        # is driven (it resists the rotation of a positive drive speed); the mesh torques balance it:
        # -T on both gears of the external pair
        side_a = LEFT if T >= 0 else RIGHT
        return {"pinion-wheel": (side_a, mate_flank(side_a, False))}
    body = cfg.load["body"]
    f_load = kin.rotation["sun"] if body == "sun" else kin.carrier
    sense = 1.0 if f_load > 0 else -1.0
    # mesh torque on the sun: the sun delivers power (driven sun, loaded carrier): it resists the
    # sun's rotation; a loaded sun: it is the reaction of the load torque
    f_sun = kin.rotation["sun"]
    m_sun = -math.copysign(1.0, f_sun) * math.copysign(1.0, T) if body == "carrier" else math.copysign(1.0, T) * sense
    s_sun = LEFT if m_sun < 0 else RIGHT
    s_p_sun = mate_flank(s_sun, False)  # planet flank at the sun
    s_p_ring = -s_p_sun  # the planet's two mesh torques balance: the other flank at the ring
    out = {}
    for k in range(1, cfg.planetary["planets"] + 1):
        out[f"sun-planet{k}"] = (s_sun, s_p_sun)
    for k in range(1, cfg.planetary["planets"] + 1):
        out[f"planet{k}-ring"] = (s_p_ring, mate_flank(s_p_ring, True))
    return out


def characteristic_fault_frequencies(cfg) -> list[tuple[str, str, float]]:
    """(what, formula, Hz) of a local fault on each gear and of eccentricity / pitch errors, at the
    mean input frequency (:mod:`flexgear.gears.kinematics`)."""
    kin = set_kinematics(cfg)
    rows = []
    if cfg.kind == "spur":
        for g in ("pinion", "wheel"):
            rows.append((f"local fault on the {g}", f"f_{g}", local_fault_frequency(kin, g)))
        rows.append(("hunting tooth (a fault on each gear)", "f_m gcd(z1, z2) / (z1 z2)", hunting_tooth_frequency(kin)))
        for g in ("pinion", "wheel"):
            rows.append((f"{g} eccentricity / pitch errors (sidebands)", f"f_{g}", kin.relative(g)))
        return rows
    rows += [("local fault on the sun", "N f_m / z_s", local_fault_frequency(kin, "sun")),
             ("local fault on a planet, one flank", "f_m / z_p", local_fault_frequency(kin, "planet")),
             ("local fault on a planet, both flanks", "2 f_m / z_p", local_fault_frequency(kin, "planet", True)),
             ("local fault on the ring", "N f_m / z_r = N f_c", local_fault_frequency(kin, "ring")),
             ("sun eccentricity / pitch errors (sidebands)", "f_s - f_c", kin.relative("sun")),
             ("planet eccentricity / pitch errors (sidebands)", "f_p - f_c", kin.relative("planet")),
             ("ring eccentricity / pitch errors (sidebands)", "f_c", kin.relative("ring"))]
    return rows


def fault_frequencies(cfg, healthy: bool = True) -> list[tuple[str, float]]:
    """(label, Hz) of each configured fault and error: the characteristic frequency of a local
    fault (a missing planet tooth engages with the sun and the ring: 2 f_m / z_p; a spall, chip or
    crack on one planet flank: f_m / z_p, a root crack opening only under the load of the flank
    whose fillet it is in), the modulation frequency
    of an eccentricity or pitch error of a body, and the planet's relative rotation for a pin
    error (the load sharing it upsets returns with the carrier: f_c, and the planet's sidebands).
    ``healthy=False`` leaves out the faults of size 0 (errors of size 0 are always left out)."""
    kin = set_kinematics(cfg)
    out = []
    for i, f in enumerate(cfg.faults):
        if f.null and not healthy:
            continue
        both = f.gear == "planet" and isinstance(f, Missing)  # a crack opens under one flank's load only
        size = "; size 0: the healthy tooth" if f.null else ""  # a severity sweep's first case
        out.append((f"faults[{i}] ({f.label()}{size})", local_fault_frequency(kin, f.gear, both)))
    if cfg.errors is not None:
        names = _bodies(cfg)
        for body, ge in cfg.errors.gears.items():
            for what in ("eccentricity", "pitch"):
                if getattr(ge, what) is not None and not getattr(ge, what).null:
                    out.append((f"errors.{what}.{body}", kin.relative(names[body])))
        for body, pe in cfg.errors.pins.items():
            if not pe.null:
                out.append((f"errors.pin.{body} (carrier)", kin.carrier))
    return out
