"""Configuration files (TOML): schema, defaults, validation, presets.

A configuration is read once, validated completely (unknown keys, types, ranges) and turned
into SI objects before anything long runs. The contact parameters may be given in ADAMS
model units (``units = "N-mm"``); they are converted once, here (see :mod:`flexgear.units`).

Every value the paper does not give has a documented default in this module and in the
preset files (``flexgear/presets/*.toml``); ``flexgear run --print-config`` shows the full
configuration after defaults.
"""
from __future__ import annotations

import copy
import dataclasses
import difflib
import math
import re
import tomllib
import warnings
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import ConfigError, user_stacklevel
from ..gears.geometry import GearPair, SpurGear
from ..gears.material import Material, effective_modulus
from ..units import UNIT_SYSTEMS, impact_to_si
from .faults import ECCENTRICITY_KEYS, FAULT_KEYS, KIND_KEYS, PIN_KEYS, PITCH_KEYS, PROFILE_KEYS
from .housing import HOUSING_KEYS, SENSOR_KEYS
from .lubrication import LUBRICATION_KEYS
from .lumped_parameters import MEMBER_PARAMETERS, PARAMETERS, parse_parameters
from .mesh_damping import damping_from_ratio, operating_penetration, operating_point, ratio_from_damping
from .schema import check_cutoff

PRESETS = ("spur_pair", "mercury_1a", "spur_pair_flexible", "mercury_1a_flexible", "mercury_1a_sensors",
           "spur_pair_missing_tooth", "mercury_1a_sun_spall", "mercury_1a_errors", "spur_pair_sensors",
           "spur_pair_friction", "mercury_1a_friction", "mercury_1a_coupled_sensors")
# published lumped-parameter sets shipped with the package, loadable by name (modal analysis)
PARAMETER_SETS = ("lin_parker_1999",)

# --------------------------------------------------------------------------------------------
# schema: key -> (kind, default, rule, unit, description); kind in {"float", "int", "bool", "str",
# "profile", "any"}. The unit and description are for the configuration reference
# (flexgear.config.reference, docs/configuration.md); a new table joins it in SECTIONS.
_POS = "> 0"
_NONNEG = ">= 0"

GEAR_KEYS = {
    "teeth": ("int", None, ">= 4", "", "number of teeth (required)"),
    "module": ("float", 2.0e-3, "(0, 1]", "m", "module; the bound catches millimetres given as metres"),
    "pressure_angle_deg": ("float", 20.0, "(0, 45)", "deg", "pressure angle of the basic rack"),
    "profile_shift": ("float", 0.0, None, "", "profile shift coefficient x (in modules)"),
    "addendum": ("float", 1.0, _POS, "", "addendum coefficient h_a* (in modules)"),
    "dedendum": ("float", 1.25, _POS, "", "dedendum coefficient h_f* (in modules)"),
    "tool_tip_radius": ("float", None, _NONNEG, "",
                        "tip radius coefficient rho_f* of the generating tool (in modules); default 0.38 (ISO 53 "
                        "profile A rack), 0.25 for the pinion-type cutter of an internal gear"),
    "face_width": ("float", 0.020, "(0, 10]", "m", "face width"),
    "thinning": ("float", 0.0, _NONNEG, "m", "tooth thinning on the reference circle (backlash allowance)"),
    "internal": ("bool", False, None, "", "an internal gear (the ring of a planetary set)"),
    "bore_diameter": ("float", 0.020, "[0, 100]", "m", "bore of an external gear (the FE body's interface)"),
    "rim_diameter": ("float", 0.160, "(0, 100]", "m", "outer diameter of an internal gear's rim"),
    "cutter_teeth": ("int", 18, ">= 8", "", "teeth of the pinion-type cutter that generates an internal gear"),
    "mass": ("float", None, _POS, "kg", "body mass; default: density x face width x outline area"),
    "inertia": ("float", None, _POS, "kg m^2", "polar moment of inertia; default: from the outline"),
}
MATERIAL_KEYS = {
    "E": ("float", 2.1e11, _POS, "Pa", "Young's modulus"),
    "nu": ("float", 0.3, "(-1, 0.5)", "", "Poisson's ratio"),
    "density": ("float", 7850.0, _POS, "kg/m^3", "density"),
}
CONTACT_KEYS = {
    "units": ("str", "N-mm", UNIT_SYSTEMS, "",
              "unit system of stiffness, damping and penetration_depth, converted to SI once when read"),
    "stiffness": ("any", 3.0e5, None, "N/mm^e (SI: N/m^e)",
                  "IMPACT stiffness K, a number > 0, or \"eq5\": K from the paper's Eq. (5) for each pair"),
    "exponent": ("float", 1.3, "[1, 5]", "", "IMPACT force exponent e (Hertz: 1.5)"),
    "damping": ("float", 3000.0, _NONNEG, "N s/mm (SI: N s/m)", "IMPACT damping C at full penetration_depth"),
    "damping_ratio": ("float", None, _NONNEG, "",
                      "mesh damping ratio at the static operating point instead of damping (exclusive)"),
    "penetration_depth": ("float", 0.3, _POS, "mm (SI: m)", "IMPACT depth d over which the damping ramps in"),
    "outline_spacing": ("float", None, _POS, "m", "outline sample spacing of the contact tables; default module/200"),
    "sdf_resolution": ("float", None, _POS, "m", "signed-distance grid spacing; default module/200"),
}
SIM_KEYS = {
    "duration": ("float", 1.0, _POS, "s", "time recorded after the run-in"),
    "run_in": ("float", 0.2, _NONNEG, "s", "start-up transient simulated and discarded"),
    "output_rate": ("float", 10000.0, _POS, "Hz", "sample rate of the results; at least twice the mesh frequency"),
    "step": ("float", 2.5e-5, _POS, "s", "largest integration step, reduced to divide the output interval"),
    "hht_alpha": ("float", -0.1, "[-1/3, 0]", "", "HHT-alpha numerical damping parameter"),
    "newton_tol": ("float", 1e-10, _POS, "m", "Newton tolerance on the correction of a step"),
    "max_newton": ("int", 12, ">= 2", "", "Newton iterations before a step is halved"),
    "antialias": ("bool", True, None, "", "low-pass (Kaiser FIR) before resampling to output_rate"),
    "synchronous": ("bool", False, None, "",
                    "step rate a whole multiple of the mesh frequency, so that step aliases fall on mesh lines"),
}
DRIVE_KEYS = {
    "body": ("str", None, None, "", "driven body: pinion or wheel (spur); sun, carrier or ring (planetary)"),
    "speed_hz": ("profile", None, None, "Hz", "rotation frequency, counter-clockwise: a constant or [[t_s, f], ...]"),
}
LOAD_KEYS = {
    "body": ("str", None, None, "", "loaded body, not the driven one"),
    "torque": ("profile", None, None, "N m", "torque resisting the body's rotation: a constant or [[t_s, T], ...]"),
    "ramp": ("float", 0.05, _NONNEG, "s",
             "the torque ramped in smoothly over this time (part of the run-in; a shorter run_in is warned)"),
}
SUPPORT_KEYS = {
    "stiffness": ("float", None, _POS, "N/m", "radial bearing stiffness (required)"),
    "damping": ("float", 0.0, _NONNEG, "N s/m", "radial bearing damping"),
    "torsional_stiffness": ("float", None, _POS, "N m/rad", "torsional support (the ring held elastically)"),
    "torsional_damping": ("float", 0.0, _NONNEG, "N m s/rad", "torsional support damping"),
}
_SUPPORT = "an elastic bearing: a table of the keys of `[supports.<body>]`"
SPUR_SUPPORTS = {  # [supports] of a spur pair: "revolute" or a table of SUPPORT_KEYS
    "pinion": ("any", "revolute", ("revolute",), "", f"\"revolute\" (ideal joint to ground) or {_SUPPORT}"),
    "wheel": ("any", "revolute", ("revolute",), "", f"\"revolute\" (ideal joint to ground) or {_SUPPORT}"),
}
PLANETARY_SUPPORTS = {  # [supports] of a planetary set
    "sun": ("any", "revolute", ("revolute",), "", f"\"revolute\" (ideal joint to ground) or {_SUPPORT}"),
    "planets": ("any", "revolute", ("revolute",), "", f"\"revolute\" (ideal joints on the carrier pins) or {_SUPPORT}"),
    "carrier": ("any", "revolute", ("revolute",), "", f"\"revolute\" (ideal joint to ground) or {_SUPPORT} (its "
                "shaft's bearing: what a coupled housing seats)"),
    "ring": ("any", "fixed", ("fixed",), "", f"\"fixed\" (welded to ground) or {_SUPPORT}"),
}
PLANETARY_KEYS = {
    "planets": ("int", 3, ">= 1", "", "number of planets, equally spaced"),
    "first_planet_angle_deg": ("float", 90.0, "[-360, 360]", "deg", "angle of planet 1; the others follow counter-clockwise"),
    "carrier_mass": ("float", 1.5, _POS, "kg", "carrier mass"),
    "carrier_inertia": ("float", 4.0e-3, _POS, "kg m^2", "carrier polar moment of inertia"),
}
SPUR_KEYS = {
    "centre_distance": ("float", None, _POS, "m", "centre distance; default: from the tooth counts and shifts"),
    "line_of_centres_deg": ("float", 0.0, "[-360, 360]", "deg", "direction from the pinion to the wheel"),
}
FE_KEYS = {  # flexgear mesh / modes, and the FE stiffness of model = "lumped"
    "level": ("int", 2, "[0, 5]", "", "mesh refinement level (sizes shrink by sqrt(2) per level)"),
    "order": ("int", 2, "{1, 2}", "", "element order (triangles)"),
    "formulation": ("str", "plane_stress", ("plane_stress", "plane_strain"), "", "plane elasticity formulation"),
    "n_modes": ("int", 10, ">= 1", "", "clamped modes computed by flexgear modes"),
}
FLEX_KEYS = {
    "gears": ("any", [], None, "", "names of the flexible gears, e.g. [\"sun\", \"planet\", \"ring\"]"),
    "level": ("int", 2, "[0, 5]", "", "FE mesh level of the reductions"),
    "order": ("int", 2, "{1, 2}", "", "FE element order"),
    "cutoff": ("float", 100e3, _POS, "Hz", "fixed-interface modes kept; the rest become static residual tables "
               "(at most 1 MHz x sqrt(modulus_scale))"),
    "formulation": ("str", "plane_strain", ("plane_stress", "plane_strain"), "", "plane elasticity formulation"),
    "ring_support": ("str", "rim", ("rim", "bolts"), "", "the ring held on its whole outer rim or on bolts"),
    "bolts": ("int", 12, ">= 1", "", "number of bolts with ring_support = \"bolts\""),
    "search_gap": ("float", 5e-5, _NONNEG, "m", "contacts open by up to this rigid gap are searched too"),
    "modulus_scale": ("float", 1.0, _POS, "", "factor on Young's modulus of the flexible gears (studies)"),
    "dynamic_cutoff": ("float", 2000.0, _NONNEG, "Hz", "modes below are solver coordinates (<= cutoff)"),
    "modal_damping": ("float", 0.0, "[0, 1)", "", "damping ratio of the modal coordinates and condensed modes"),
    "condensation": ("str", "integrated", ("integrated", "static"), "",
                     "modes between dynamic_cutoff and cutoff: integrated in the contact solve with their own "
                     "inertia, or static"),
    "table_points": ("int", 129, ">= 4", "", "flank table radii per flank (self compliance, mode shapes)"),
    "coupling_points": ("int", 17, ">= 2", "",
                        "radii of the tables between flank points, every k-th of table_points"),
}
LUMPED_KEYS = {  # model = "lumped" (flexgear.dynamics.lumped.model)
    "mesh_stiffness": ("str", "contact", ("contact", "iso6336", "fe", "constant"), "", "source of the mesh stiffness"),
    "constant_stiffness": ("any", None, None, "N/m",
                           "{pair = N/m} for mesh_stiffness = \"constant\": pinion-wheel, or sun-planet and "
                           "planet-ring"),
    "dofs": ("str", "planar", ("planar", "rotational"), "", "planar model, or the rotations only"),
    "damping_ratio": ("float", 0.03, _NONNEG, "", "mesh damping ratio for sources other than \"contact\""),
    "backlash": ("float", None, _NONNEG, "m", "along the line of action; default from the gears' thinning"),
    "positions": ("int", 48, ">= 2", "", "static positions over a mesh cycle (stiffness, phasing)"),
    "parameters": ("any", None, None, "", "explicit lumped parameters: the table [lumped.parameters]"),
}
SHAFT_KEYS = {  # [shafts.input], [shafts.output] (flexgear.dynamics.model.shafts)
    "body": ("str", None, None, "", "the body on the shaft; default drive.body (input), load.body (output)"),
    "diameter": ("float", None, "(0, 10]", "m", "solid round shaft (required)"),
    "length": ("float", None, "(0, 10]", "m", "torsional length, coupling or load to the gear (required)"),
    "bending": ("bool", True, None, "", "the body on the shaft's lateral stiffness"),
    "arrangement": ("str", "between", ("between", "overhung"), "", "gear between the bearings, or overhung"),
    "bearing_span": ("float", None, "(0, 10]", "m", "between the two bearings"),
    "gear_position": ("float", None, "(0, 10]", "m", "from the first bearing (default mid-span), or the overhang"),
    "bearing_stiffness": ("float", None, _POS, "N/m", "radial, per bearing; default: rigid bearings"),
    "torsional_stiffness": ("float", None, _POS, "N m/rad", "instead of G pi d^4 / (32 L)"),
    "lateral_stiffness": ("float", None, _POS, "N/m", "at the gear, instead of beam and bearings"),
    "damping_ratio": ("float", 0.02, _NONNEG, "", "damping ratio of each shaft spring"),
    "torsional_damping": ("float", None, _NONNEG, "N m s/rad", "instead of the damping ratio"),
    "lateral_damping": ("float", None, _NONNEG, "N s/m", "instead of the damping ratio"),
    "load_inertia": ("float", None, _POS, "kg m^2", "output shaft only; default LOAD_INERTIA, a steel disc 200 x 10 mm"),
}
LOAD_INERTIA = 7850.0 * math.pi * 0.1**4 * 0.010 / 2  # kg m^2: a steel disc 200 mm x 10 mm (brake disc)
MODELS = ("rigid", "lumped")
TOP_KEYS = {"model", "lumped", "title", "kind", "material", "gear_defaults", "gears", "planetary", "spur", "supports", "drive",
            "load", "contact", "simulation", "fe", "flexible", "shafts", "faults", "errors",
            "lubrication", "housing", "sensors"}
TOP_LEVEL_KEYS = {  # checked in parse_config
    "title": ("str", None, None, "", "a title for figures and reports; default: the kind"),
    "kind": ("str", None, ("spur", "planetary"), "", "the gear set (required)"),
    "model": ("str", "rigid", MODELS, "",
              "rigid: the multi-body model (flexible gears with [flexible]); lumped: the lumped-parameter model"),
}


@dataclass(frozen=True)
class Section:
    """A table of the configuration file as the reference shows it.

    ``name`` is its TOML name (``<...>`` for a name the user picks: ``gears.<name>``; ``""``
    for the top level), ``keys`` the schema it is validated against, ``about`` a sentence or
    two (Markdown); ``array``: an array of tables (``[[name]]``); ``same_keys``: the keys are those of
    another section (listed, not tabulated again).
    """

    name: str
    keys: dict
    about: str
    array: bool = False
    same_keys: str = ""


#: Every table a configuration may hold, in the reference's order: a new table joins here.
SECTIONS = (
    Section("", TOP_LEVEL_KEYS, "Keys at the top of the file."),
    Section("material", MATERIAL_KEYS, "Linear elastic material of every gear."),
    Section("gear_defaults", {k: v for k, v in GEAR_KEYS.items() if k != "teeth"},
            "Defaults for every gear: any key of `[gears.<name>]` but `teeth`.", same_keys="gears.<name>"),
    Section("gears.<name>", GEAR_KEYS,
            "One table per gear: `pinion` and `wheel` (`kind = \"spur\"`), or `sun`, `planet` and `ring` "
            "(`kind = \"planetary\"`; the ring internal). Involute spur gears with generated trochoid roots (ISO 21771)."),
    Section("planetary", PLANETARY_KEYS, "Planets and carrier (`kind = \"planetary\"` only)."),
    Section("spur", SPUR_KEYS, "Placement of a spur pair (`kind = \"spur\"` only)."),
    Section("supports", SPUR_SUPPORTS, "Joints of a spur pair's bodies (`kind = \"spur\"`)."),
    Section("supports", PLANETARY_SUPPORTS, "Joints of a planetary set's bodies (`kind = \"planetary\"`)."),
    Section("supports.<body>", SUPPORT_KEYS, "An elastic support given as a table instead of a joint name."),
    Section("drive", DRIVE_KEYS, "The driven body turns at the prescribed speed (required)."),
    Section("load", LOAD_KEYS, "The torque on the output member (required)."),
    Section("contact", CONTACT_KEYS,
            "The ADAMS IMPACT tooth-contact law, `F = K delta^e + STEP(delta; 0, 0, d, C) d(delta)/dt`, and the "
            "contact tables. Meshes with a flexible gear use line-contact Hertz instead of K and e and keep the "
            "damping."),
    Section("simulation", SIM_KEYS, "Integration and output."),
    Section("fe", FE_KEYS, "FE meshes of `flexgear mesh` and `flexgear modes`, and the FE stiffness of the lumped model."),
    Section("flexible", FLEX_KEYS, "Flexible gears: Craig-Bampton reductions with compliant flanks (`model = \"rigid\"`)."),
    Section("shafts.<end>", SHAFT_KEYS,
            "Elastic shafts: `<end>` is `input` (on `drive.body`, from a motor turning at `drive.speed_hz`) or "
            "`output` (on `load.body`, to a load inertia that carries `load.torque`); `model = \"rigid\"` only."),
    Section("lumped", LUMPED_KEYS, "The lumped-parameter model (`model = \"lumped\"`)."),
    Section("lumped.parameters", PARAMETERS,
            "A lumped planetary set as printed in the literature. Without `[gears]` it is for modal analysis only; with "
            "`[gears]` only the pressure angles and the member tables' mass, inertia and radius may be given, and "
            "they replace the geometry's."),
    Section("lumped.parameters.<member>", MEMBER_PARAMETERS,
            "`<member>` is `sun`, `ring`, `carrier` or `planet`. Give one of `inertia` and `inertia_over_r2` and one "
            "radius key: the carrier takes `radius` or `diameter` (of the planet centres), the gears `base_radius` or "
            "`base_diameter`; the planet has no torsional keys."),
    Section("faults", FAULT_KEYS,
            "A local tooth fault, one table each: which gear, tooth and flank, and its `kind`; the kind's own keys "
            "follow. Tooth `k` is centred at the body angle + 2 pi k / z, counted counter-clockwise: the numbers "
            "of `pair_tooth_a/b` in the results ([faults guide](guide/faults.md)).", array=True),
    *(Section("faults", keys, f"Keys of a fault with `kind = \"{kind}\"`.", array=True)
      for kind, keys in KIND_KEYS.items()),
    Section("errors.eccentricity.<body>", ECCENTRICITY_KEYS, "Run-out of a gear body (`sun`, `planet2`, `ring`, "
            "`pinion`, ...; `planet`: every planet)."),
    Section("errors.pin.<planet>", PIN_KEYS, "Carrier pin position error of a planet (`planet1` ...)."),
    Section("errors.pitch.<body>", PITCH_KEYS, "Tooth spacing errors of a gear body: `deviations`, or a random "
            "sequence of an ISO 1328-1:2013 flank tolerance class (`grade`, `seed`)."),
    Section("lubrication", LUBRICATION_KEYS, "Tooth friction and the lubricant (off without this table): the "
            "friction-coefficient model, the oil's viscosity (directly, or an ISO VG grade at an oil temperature), "
            "roughness, and the mesh damping model ([lubrication guide](guide/lubrication.md))."),
    Section("errors.profile.<body>", PROFILE_KEYS, "Profile slope and form deviations and profile modification "
            "(tip and root relief) of every tooth of a gear body."),
    Section("housing", HOUSING_KEYS, "The gearbox housing (off without this table): a plane body of a wall around "
            "the gears and the end covers that hold the bearing seats and, in a planetary set, the ring gear's bolts; "
            "feet on ground springs. Every key has a default derived from the gears ([housing guide](guide/housing.md))."),
    Section("sensors", SENSOR_KEYS, "A sensor on the housing or the ring, one table each: where it sits, the "
            "direction it measures and the quantity ([housing guide](guide/housing.md)).", array=True),
)


def key_unit(path: str) -> str:
    """The unit of the configuration key at the dotted ``path`` (``load.torque``: "N m",
    ``faults.0.depth``, ``gears.wheel.module``), as :data:`SECTIONS` give it; "" for a key
    without one or unknown."""
    *table, key = path.split(".")
    for section in SECTIONS:
        parts = section.name.split(".") if section.name else []
        names = [p for p in table if not (section.array and p.isdigit())]
        if len(parts) == len(names) and all(a == b or a.startswith("<") for a, b in zip(parts, names)) \
                and key in section.keys:
            return section.keys[key][3]
    return ""


# length rules: (test, text); the upper bounds catch millimetres given as metres and overflowing sizes
_LENGTH_RANGES = {
    "(0, 1]": (lambda v: 0 < v <= 1, "must be > 0 and <= 1 m (a module in mm given as m?)"),
    "(0, 10]": (lambda v: 0 < v <= 10, "must be > 0 and <= 10 m (a length in mm given as m?)"),
    "[0, 100]": (lambda v: 0 <= v <= 100, "must be >= 0 and <= 100 m"),
    "(0, 100]": (lambda v: 0 < v <= 100, "must be > 0 and <= 100 m"),
}


def _check_value(path: str, kind: str, value: Any, rule):
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{path} = {value!r}: must be a number")
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(f"{path} = {value!r}: must be finite")
    elif kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{path} = {value!r}: must be an integer")
    elif kind == "bool":
        if not isinstance(value, bool):
            raise ConfigError(f"{path} = {value!r}: must be true or false")
    elif kind == "str":
        if not isinstance(value, str):
            raise ConfigError(f"{path} = {value!r}: must be a string")
    elif kind == "profile":
        return _check_profile(path, value)
    if rule is None or kind == "any":
        return value
    if isinstance(rule, tuple):
        if value not in rule:
            raise ConfigError(f"{path} = {value!r}: must be one of {', '.join(map(repr, rule))}")
    elif rule == _POS and not value > 0:
        raise ConfigError(f"{path} = {value!r}: must be > 0")
    elif rule == _NONNEG and not value >= 0:
        raise ConfigError(f"{path} = {value!r}: must be >= 0")
    elif rule == ">= 4" and not value >= 4:
        raise ConfigError(f"{path} = {value!r}: must be >= 4")
    elif rule == ">= 8" and not value >= 8:
        raise ConfigError(f"{path} = {value!r}: must be >= 8")
    elif rule == ">= 1" and not value >= 1:
        raise ConfigError(f"{path} = {value!r}: must be >= 1")
    elif rule == ">= 2" and not value >= 2:
        raise ConfigError(f"{path} = {value!r}: must be >= 2")
    elif rule == "(0, 45)" and not 0 < value < 45:
        raise ConfigError(f"{path} = {value!r}: must lie in (0, 45) degrees")
    elif rule == "[-1/3, 0]" and not -1 / 3 - 1e-12 <= value <= 0:
        raise ConfigError(f"{path} = {value!r}: HHT alpha must lie in [-1/3, 0]")
    elif rule == "[0, 1)" and not 0 <= value < 1:
        raise ConfigError(f"{path} = {value!r}: must lie in [0, 1) (a damping ratio)")
    elif rule == "[0, 5]" and not 0 <= value <= 5:
        raise ConfigError(f"{path} = {value!r}: refinement level must lie in [0, 5]")
    elif rule in _LENGTH_RANGES and not _LENGTH_RANGES[rule][0](value):
        raise ConfigError(f"{path} = {value!r}: {_LENGTH_RANGES[rule][1]}")
    elif rule == "[1, 5]" and not 1 <= value <= 5:
        raise ConfigError(f"{path} = {value!r}: must lie in [1, 5] (force exponent of the contact law; Hertz: 1.5)")
    elif rule == "[-360, 360]" and not -360 <= value <= 360:
        raise ConfigError(f"{path} = {value!r}: must lie in [-360, 360] degrees")
    elif rule == "(-1, 0.5)" and not -1 < value < 0.5:
        raise ConfigError(f"{path} = {value!r}: Poisson's ratio must lie in (-1, 0.5)")
    elif rule == "{1, 2}" and value not in (1, 2):
        raise ConfigError(f"{path} = {value!r}: element order must be 1 or 2")
    return value


def _check_profile(path, value):
    """A constant or a table [[t0, v0], [t1, v1], ...] with increasing times (linear in between)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise ConfigError(f"{path} = {value!r}: must be finite")
        return float(value)
    if isinstance(value, list) and value and all(isinstance(p, list) and len(p) == 2 for p in value):
        if any(isinstance(x, bool) or not isinstance(x, (int, float)) for p in value for x in p):
            raise ConfigError(f"{path} = {value!r}: table entries must be numbers [time_s, value]")
        pts = [(float(t), float(v)) for t, v in value]
        if not all(math.isfinite(x) for p in pts for x in p):
            raise ConfigError(f"{path} = {value!r}: table entries must be finite")
        ts = [p[0] for p in pts]
        if any(b <= a for a, b in zip(ts, ts[1:])):
            raise ConfigError(f"{path}: table times {ts} must increase strictly")
        return pts
    raise ConfigError(f"{path} = {value!r}: must be a number or a table [[time_s, value], ...]")


def did_you_mean(unknown, known, prefix: str = "") -> str:
    """``"; did you mean 'a' (for 'b')?"``: the close matches of misspelt keys, or ``""``."""
    near = [(k, m[0]) for k in unknown if (m := difflib.get_close_matches(str(k), list(known), n=1, cutoff=0.7))]
    return ("; did you mean " + ", ".join(repr(prefix + m) + (f" (for {prefix + k!r})" if len(unknown) > 1 else "")
                                          for k, m in near) + "?") if near else ""


def _section(path: str, data: dict, schema: dict, required=()) -> dict:
    if not isinstance(data, dict):
        raise ConfigError(f"[{path}] must be a table")
    unknown = sorted(set(data) - set(schema))
    if unknown:
        raise ConfigError(
            f"unknown key{'s' if len(unknown) > 1 else ''} {', '.join(repr(f'{path}.{k}') for k in unknown)}; "
            f"allowed in [{path}]: {', '.join(sorted(schema))}" + did_you_mean(unknown, schema, f"{path}.")
        )
    out = {}
    for key, (kind, default, rule, *_) in schema.items():
        if key in data:
            out[key] = _check_value(f"{path}.{key}", kind, data[key], rule)
        else:
            if key in required:
                raise ConfigError(f"{path}.{key} is required")
            out[key] = default
    return out


# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ContactLaw:
    """ADAMS IMPACT parameters in SI: F = K delta^e + STEP(delta; 0, 0, d, C) d(delta)/dt."""

    K: float  # N/m^e
    e: float
    C: float  # N s/m
    d: float  # m
    reading: str  # how K was obtained, for the record
    zeta: float = float("nan")  # mesh damping ratio at the static operating point (mesh_damping)
    damping_reading: str = ""  # how C was obtained, for the record


@dataclass
class Config:
    """A validated configuration (SI)."""

    kind: str
    title: str
    material: Material
    gears: dict[str, SpurGear]
    gear_mass: dict[str, tuple[float | None, float | None]]
    contact: dict
    simulation: dict
    drive: dict
    load: dict
    supports: dict
    planetary: dict | None
    spur: dict | None
    fe: dict
    raw: dict = field(repr=False, default_factory=dict)
    flexible: dict | None = None  # [flexible] (None: every gear rigid)
    source: str = ""
    source_text: str = field(repr=False, default="")
    model: str = "rigid"
    lumped: dict | None = None
    shafts: dict | None = None  # [shafts.input], [shafts.output] (None: infinitely stiff drive line)
    faults: tuple = ()  # [[faults]]: flexgear.gears.faults.ToothFault (flexgear.config.faults)
    errors: Any = None  # [errors]: flexgear.gears.faults.Errors, None: perfect gears
    lubrication: Any = None  # [lubrication]: flexgear.gears.lubrication.Lubrication, None: frictionless
    housing: Any = None  # [housing]: flexgear.gears.housing.Housing, None: no housing
    sensors: tuple = ()  # [[sensors]]: flexgear.gears.housing.Sensor (flexgear.config.housing)

    def use_damping_ratio(self, zeta: float) -> "Config":
        """Replace the contact damping C by a mesh damping ratio ``zeta`` (``[contact]
        damping_ratio``: C follows at the static operating point, :meth:`contact_law`); in place,
        returned.

        Raises
        ------
        ConfigError
            For a ratio that is not a finite number >= 0.
        """
        if not (isinstance(zeta, (int, float)) and math.isfinite(zeta) and zeta >= 0):
            raise ConfigError(f"contact.damping_ratio = {zeta!r}: must be a finite number >= 0")
        self.contact["damping"] = None
        self.contact["damping_ratio"] = float(zeta)
        return self

    # ------------------------------------------------------------------ derived
    @property
    def pairs(self) -> dict[str, GearPair]:
        """Distinct meshing pairs by name (geometry only)."""
        g = self.gears
        if self.kind == "spur":
            return {"pinion-wheel": GearPair(g["pinion"], g["wheel"])}
        return {"sun-planet": GearPair(g["sun"], g["planet"]), "planet-ring": GearPair(g["planet"], g["ring"])}

    def contact_law(self, pair: GearPair) -> ContactLaw:
        """IMPACT law in SI for ``pair`` (K from the preset value or from Eq. (5) for this pair)."""
        c = self.contact
        units = c["units"]
        stiff = c["stiffness"]
        if isinstance(stiff, str):
            e_star = effective_modulus(self.material, self.material)
            K_si15 = pair.hertz_stiffness(e_star)  # N/m^1.5
            # numeric value of Eq. (5) in the chosen unit system, then used with exponent e
            K_num = K_si15 if units == "SI" else K_si15 * 1e-3**1.5
            if not math.isclose(c["exponent"], 1.5):
                warnings.warn(
                    f"contact.stiffness = 'eq5' gives K in {'N/m^1.5' if units == 'SI' else 'N/mm^1.5'} "
                    f"but contact.exponent = {c['exponent']}: K is used with exponent {c['exponent']} in "
                    f"{units} units (the paper's reading, docs/paper_parameters.md), not Hertz's 1.5",
                    stacklevel=user_stacklevel(),
                )
            K, e, C, d = impact_to_si(K_num, c["exponent"], c["damping"] or 0.0, c["penetration_depth"], units)
            reading = f"eq5 ({pair.name}: R = {pair.hertz_radius*1e3:.4g} mm) in {units}, e = {e}"
        else:
            K, e, C, d = impact_to_si(stiff, c["exponent"], c["damping"] or 0.0, c["penetration_depth"], units)
            reading = f"K = {stiff:g} in {units} units with e = {e}"
        # mesh damping ratio <-> C at the static operating point (flexgear.config.mesh_damping)
        W, m_e = operating_point(self, pair)
        d0 = operating_penetration(W, K, e)
        point = f"W = {W:.5g} N, delta_0 = {d0*1e6:.4g} um, m_e = {m_e:.4g} kg"
        if not W > 0:  # no static load: the ratio is undefined
            if c["damping_ratio"] is not None:
                raise ConfigError(f"contact.damping_ratio = {c['damping_ratio']!r}: needs a static mesh load to "
                                  f"define the operating point, but the load torque is zero; give contact.damping")
            return ContactLaw(K=K, e=e, C=C, d=d, reading=reading, zeta=float("nan"),
                              damping_reading=f"C = {C:.5g} N s/m given; no static load, damping ratio undefined")
        if c["damping_ratio"] is not None:
            zeta = c["damping_ratio"]
            C = damping_from_ratio(zeta, W, K, e, d, m_e)
            dreading = f"C = {C:.5g} N s/m from damping_ratio = {zeta:g} ({point})"
        else:
            zeta = ratio_from_damping(C, W, K, e, d, m_e)
            dreading = f"C = {C:.5g} N s/m given: damping ratio {zeta:.3g} ({point})"
        return ContactLaw(K=K, e=e, C=C, d=d, reading=reading, zeta=zeta, damping_reading=dreading)

    def mesh_frequency(self, speed_hz: float | None = None) -> float:
        """Gear mesh frequency [Hz] at the drive speed ``speed_hz`` (default: the mean input
        frequency): z f for a spur pair (z of the driven gear), z_r f_carrier for a planetary
        set with a fixed ring."""
        f_in = self.input_frequency if speed_hz is None else speed_hz
        z = {n: g.z for n, g in self.gears.items()}
        if self.kind == "spur":
            return z[self.drive["body"]] * f_in if self.drive["body"] in z else z["pinion"] * f_in
        zs, zr = z["sun"], z["ring"]
        f_c = f_in * zs / (zs + zr) if self.drive["body"] == "sun" else f_in
        return zr * f_c

    @property
    def peak_mesh_frequency(self) -> float:
        """Highest gear mesh frequency [Hz] the drive speed profile reaches."""
        sp = self.drive["speed_hz"]
        top = abs(sp) if isinstance(sp, float) else max(abs(v) for _, v in sp)
        return self.mesh_frequency(top)

    @property
    def input_frequency(self) -> float:
        """Mean input rotation frequency [Hz] of the driven body: the constant, or the time
        average of a speed table over its span (trapezoidal, exact for the linear segments)."""
        sp = self.drive["speed_hz"]
        if isinstance(sp, float):
            return sp
        if len(sp) == 1:
            return sp[0][1]
        area = sum(0.5 * (v0 + v1) * (t1 - t0) for (t0, v0), (t1, v1) in zip(sp, sp[1:]))
        return area / (sp[-1][0] - sp[0][0])


def _gear(name: str, raw: dict, defaults: dict) -> tuple[SpurGear, tuple]:
    merged = dict(defaults)
    merged.update(raw)
    g = _section(f"gears.{name}", merged, GEAR_KEYS, required=("teeth",))
    internal = g["internal"]
    gear = SpurGear(
        z=g["teeth"], module=g["module"], pressure_angle=math.radians(g["pressure_angle_deg"]),
        x=g["profile_shift"], ha=g["addendum"], hf=g["dedendum"], rho_f=g["tool_tip_radius"],
        face_width=g["face_width"], thinning=g["thinning"], internal=internal,
        bore_diameter=0.0 if internal else g["bore_diameter"],
        rim_diameter=g["rim_diameter"] if internal else None, cutter_teeth=g["cutter_teeth"], name=name,
    )
    return gear, (g["mass"], g["inertia"])


def _support(path, value, allowed_names):
    if isinstance(value, str):
        if value not in allowed_names:
            raise ConfigError(f"{path} = {value!r}: must be one of {', '.join(map(repr, allowed_names))} "
                              "or a table {stiffness = N/m, damping = N s/m, torsional_stiffness = N m/rad, "
                              "torsional_damping = N m s/rad}")
        return value
    s = _section(path, value, SUPPORT_KEYS, required=("stiffness",))
    return s


def _flexible(raw, names) -> dict | None:
    """The [flexible] block: which gears are flexible and how they are reduced (None: none).

    Defaults: mesh level 2 (quadratic), mode cutoff 100 kHz (above the first clamped mode of
    every gear of the presets, 31-64 kHz; every mode is condensed quasi-statically at the
    presets' step), plane strain (for b/m = 10 our 3D sector puts plane stress 5.5 % too soft
    and plane strain 2 % too stiff: plane strain is the closer), ring held on its whole rim,
    near contacts reported up to a 50 um rigid gap. Modes below ``dynamic_cutoff`` (default
    2 kHz = 1/(20 h) at the default 25 us step: 20 steps per period, where HHT's period error
    (omega h)^2 / 12 is 0.8 %; the flexible presets, at 6.25 us, set 8 kHz by the same rule) are
    integrated as coordinates, with ``modal_damping`` (default 0:
    the condensed modes carry no damping either; HHT's alpha damps what the step cannot resolve);
    at the presets' defaults the first clamped modes lie at 31-64 kHz (a ring on bolts: 26 kHz), so none is.

    Flank tables: ``table_points`` radii per flank (default 129) for the self compliance and the
    mode shapes, where the contact sits (16 radii left the flexible spur pair's mesh lines above
    the tenth up to 13 % off; 129 radii are within 0.3 % of 257), and ``coupling_points`` of
    them (default 17, every 8th) for the smooth tables between different flank points.
    """
    f = _section("flexible", raw, FLEX_KEYS)
    tp, cp = f["table_points"], f["coupling_points"]
    if cp > tp or (tp - 1) % (cp - 1):
        raise ConfigError(f"flexible.coupling_points = {cp!r}: must be <= flexible.table_points = {tp!r} with "
                          f"table_points - 1 a multiple of coupling_points - 1 (the coupling tables use every "
                          f"k-th table radius), e.g. 17 with 129 or 9 with 65")
    check_cutoff("flexible.cutoff", f["cutoff"], f["modulus_scale"], "modulus_scale")
    if "dynamic_cutoff" not in raw:  # the default never exceeds the cutoff given
        f["dynamic_cutoff"] = min(f["dynamic_cutoff"], f["cutoff"])
    if f["dynamic_cutoff"] > f["cutoff"]:
        raise ConfigError(f"flexible.dynamic_cutoff = {f['dynamic_cutoff']!r} Hz: must be <= flexible.cutoff = "
                          f"{f['cutoff']!r} Hz (modes above the cutoff are not in the reduction)")
    gears = f["gears"]
    if not isinstance(gears, list) or not all(isinstance(g, str) for g in gears):
        raise ConfigError(f"flexible.gears = {gears!r}: must be a list of gear names ({', '.join(names)})")
    bad = [g for g in gears if g not in names]
    if bad:
        raise ConfigError(f"flexible.gears: unknown gear(s) {', '.join(map(repr, bad))}; the gears are "
                          f"{', '.join(names)}")
    if len(set(gears)) != len(gears):
        raise ConfigError(f"flexible.gears = {gears!r}: a gear is listed twice")
    f["gears"] = list(gears)
    return f if gears else None


def parse_config(data: dict, source: str = "") -> Config:
    """Validate a configuration dictionary (as read from TOML) and build SI objects."""
    if not isinstance(data, dict):
        raise ConfigError("configuration must be a TOML table")
    unknown = sorted(set(data) - TOP_KEYS)
    if unknown:
        raise ConfigError(f"unknown top-level key(s) {', '.join(map(repr, unknown))}; allowed: "
                          f"{', '.join(sorted(TOP_KEYS))}" + did_you_mean(unknown, TOP_KEYS))
    kind = data.get("kind")
    if kind not in ("spur", "planetary"):
        raise ConfigError(f"kind = {kind!r}: must be 'spur' or 'planetary'")
    title = data.get("title", kind)
    if not isinstance(title, str):
        raise ConfigError(f"title = {title!r}: must be a string")
    if _parameter_set(data):
        return _parse_parameter_set(data, kind, title, source)
    mat = _section("material", data.get("material", {}), MATERIAL_KEYS)
    material = Material(E=mat["E"], nu=mat["nu"], rho=mat["density"])
    gdef = data.get("gear_defaults", {})
    _section("gear_defaults", {k: v for k, v in gdef.items() if k != "teeth"} | {"teeth": 10}, GEAR_KEYS)
    names = ("pinion", "wheel") if kind == "spur" else ("sun", "planet", "ring")
    graw = data.get("gears", {})
    if not isinstance(graw, dict):
        raise ConfigError("[gears] must be a table of gear tables")
    extra = sorted(set(graw) - set(names))
    missing = [n for n in names if n not in graw]
    if extra or missing:
        raise ConfigError(f"[gears] of a {kind} set must be exactly {', '.join(names)}"
                          + (f"; unknown: {', '.join(extra)}" if extra else "")
                          + (f"; missing: {', '.join(missing)}" if missing else ""))
    gears, masses = {}, {}
    for n in names:
        gears[n], masses[n] = _gear(n, graw[n], gdef)
    if kind == "planetary":
        if not gears["ring"].internal:
            raise ConfigError("gears.ring.internal = false: the ring of a planetary set must be internal")
        for n in ("sun", "planet"):
            if gears[n].internal:
                raise ConfigError(f"gears.{n}.internal = true: the {n} must be an external gear")
    else:
        for n in names:
            if gears[n].internal:
                raise ConfigError(f"gears.{n}.internal = true: a spur pair is made of external gears")
    contact = _section("contact", data.get("contact", {}), CONTACT_KEYS)
    if contact["damping_ratio"] is not None:
        if "damping" in data["contact"]:
            raise ConfigError(f"contact.damping = {data['contact']['damping']!r} and contact.damping_ratio = "
                              f"{contact['damping_ratio']!r}: give one of them, not both")
        contact["damping"] = None  # C follows from the ratio (Config.contact_law)
    st = contact["stiffness"]
    if isinstance(st, str):
        if st != "eq5":
            raise ConfigError(f"contact.stiffness = {st!r}: must be a number or 'eq5'")
    elif isinstance(st, bool) or not isinstance(st, (int, float)) or not (st > 0 and math.isfinite(st)):
        raise ConfigError(f"contact.stiffness = {st!r}: must be a finite number > 0, or 'eq5'")
    sim = _section("simulation", data.get("simulation", {}), SIM_KEYS)
    drive = _section("drive", data.get("drive", {}), DRIVE_KEYS, required=("body", "speed_hz"))
    load = _section("load", data.get("load", {}), LOAD_KEYS, required=("body", "torque"))
    if kind == "spur":
        bodies = ("pinion", "wheel")
        sup_schema = SPUR_SUPPORTS
    else:
        bodies = ("sun", "carrier", "ring")
        sup_schema = PLANETARY_SUPPORTS
    if drive["body"] not in bodies:
        raise ConfigError(f"drive.body = {drive['body']!r}: must be one of {', '.join(bodies)}")
    if load["body"] not in bodies:
        raise ConfigError(f"load.body = {load['body']!r}: must be one of {', '.join(bodies)}")
    if load["body"] == drive["body"]:
        raise ConfigError(f"load.body = drive.body = {load['body']!r}: load another body than the driven one")
    sraw = data.get("supports", {})
    if not isinstance(sraw, dict):
        raise ConfigError("[supports] must be a table")
    unknown = sorted(set(sraw) - set(sup_schema))
    if unknown:
        raise ConfigError(f"unknown key(s) {', '.join(repr('supports.' + k) for k in unknown)}; allowed in "
                          f"[supports]: {', '.join(sup_schema)}")
    supports = {}
    for k, (_, default, allowed, *_) in sup_schema.items():
        supports[k] = _support(f"supports.{k}", sraw.get(k, default), allowed)
    planetary = _section("planetary", data.get("planetary", {}), PLANETARY_KEYS) if kind == "planetary" else None
    if kind == "spur" and "planetary" in data:
        raise ConfigError("[planetary] given for kind = 'spur'")
    spur = _section("spur", data.get("spur", {}), SPUR_KEYS) if kind == "spur" else None
    if kind == "planetary" and "spur" in data:
        raise ConfigError("[spur] given for kind = 'planetary'")
    fe = _section("fe", data.get("fe", {}), FE_KEYS)
    model = data.get("model", "rigid")
    if model not in MODELS:
        raise ConfigError(f"model = {model!r}: must be one of {', '.join(map(repr, MODELS))}")
    lumped = _lumped_section(data.get("lumped", {}), kind) if model == "lumped" else None
    if model != "lumped" and "lumped" in data:
        raise ConfigError("[lumped] given with model = 'rigid'; set model = 'lumped' or remove the section")
    flexible = _flexible(data.get("flexible"), names) if "flexible" in data else None
    if flexible and model != "rigid":
        raise ConfigError(f"[flexible] given with model = {model!r}: flexible gears need the multi-body model "
                          "(model = 'rigid', the default)")
    shafts = _shafts(data["shafts"], drive, load, supports, model) if "shafts" in data else None
    cfg = Config(kind=kind, title=str(title), material=material, gears=gears, gear_mass=masses, contact=contact,
                 simulation=sim, drive=drive, load=load, supports=supports, planetary=planetary, spur=spur,
                 fe=fe, raw=copy.deepcopy(data), source=source, model=model, lumped=lumped,
                 flexible=flexible, shafts=shafts)
    # the laws must be constructible (unit reading) before anything runs
    for pair in cfg.pairs.values():
        pair.check()
    _check_sampling(cfg)
    from .faults import parse_errors, parse_faults

    cfg.faults = parse_faults(data.get("faults"), cfg, _check_value)
    _check_flexible_cracks(cfg)
    cfg.errors = parse_errors(data.get("errors"), cfg, _check_value)
    from .lubrication import parse_lubrication

    cfg.lubrication = parse_lubrication(data.get("lubrication"), cfg, _check_value)
    from .housing import parse_housing, parse_sensors

    cfg.housing = parse_housing(data.get("housing"), cfg, _check_value)
    cfg.sensors = parse_sensors(data.get("sensors"), cfg, _check_value)
    return cfg


def _check_flexible_cracks(cfg) -> None:
    """A flexible gear's body holds one FE slit at most: a second crack across the face width of
    the same body is refused here, not after seconds of building the model."""
    first: dict = {}
    flexible = set((cfg.flexible or {}).get("gears", ())) if cfg.model != "lumped" else set()
    for i, f in enumerate(cfg.faults):
        if f.kind != "crack" or f.null or f.gear not in flexible or f.width_fraction != 1.0:
            continue
        if f.body in first:
            j = first[f.body]
            raise ConfigError(f"faults[{i}] ({f.label()}): a flexible gear is meshed with one root crack across the "
                              f"face width at most, and faults[{j}] ({cfg.faults[j].label()}) is on {f.body} already; "
                              "rule: one such crack per flexible body (a crack with width_fraction < 1 enters its "
                              "tooth's compliant law instead)")
        first[f.body] = i


def _parameter_set(data: dict) -> bool:
    """A lumped parameter set as printed: model = "lumped", [lumped.parameters], no [gears]."""
    lumped = data.get("lumped")
    return (data.get("model") == "lumped" and isinstance(lumped, dict) and "parameters" in lumped
            and not data.get("gears"))


def _parse_parameter_set(data: dict, kind: str, title: str, source: str) -> Config:
    """A lumped planetary set given only by its parameters (no tooth geometry): modal analysis."""
    if kind != "planetary":
        raise ConfigError(f"kind = {kind!r}: [lumped.parameters] without [gears] describes a planetary set; "
                          "set kind = 'planetary'")
    allowed = {"model", "lumped", "title", "kind"}
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise ConfigError(f"{', '.join(map(repr, unknown))} given with [lumped.parameters] and no [gears]: a "
                          "parameter set as printed has no gear geometry, supports or run settings; allowed: "
                          f"{', '.join(sorted(allowed))} (give [gears] to run it in the time domain)")
    lumped = _lumped_section(data["lumped"], kind, has_gears=False)
    return Config(kind=kind, title=str(title), material=Material(E=2.1e11, nu=0.3, rho=7850.0), gears={},
                  gear_mass={}, contact={}, simulation={}, drive={}, load={}, supports={}, planetary=None,
                  spur=None, fe={}, raw=copy.deepcopy(data), source=source, model="lumped", lumped=lumped)


def check_time_domain(cfg: Config) -> None:
    """Raise ConfigError if ``cfg`` cannot be run in the time domain: a lumped parameter set as
    printed (``[lumped.parameters]`` without ``[gears]``) has no tooth counts, hence no speeds,
    mesh frequency or mesh phasing."""
    if not cfg.gears:
        raise ConfigError(f"{cfg.source or 'configuration'}: [lumped.parameters] without [gears] is a parameter set "
                          "for modal analysis (`flexgear modal`); a time-domain run needs the tooth counts (input, "
                          "carrier and mesh frequencies, mesh phasing): add [gears], [planetary], [supports], "
                          "[drive], [load] and [simulation] as in the presets, and the parameters given replace "
                          "those of the geometry")


def ramp_note(cfg: Config) -> str:
    """The message recorded when the load ramp (``[load] ramp``) outlasts the run-in: the record
    then starts with the load torque still rising, and its means read less than the set load."""
    if not cfg.gears:  # a parameter set: no time domain
        return ""
    ramp, run_in = cfg.load["ramp"], cfg.simulation["run_in"]
    if ramp <= run_in:
        return ""
    return (f"load.ramp = {ramp:g} s outlasts simulation.run_in = {run_in:g} s: the record's first "
            f"{ramp - run_in:.3g} s hold the load torque still rising to its set value (its force and transmission "
            "error read low there); set run_in >= ramp")


def _shafts(raw, drive: dict, load: dict, supports: dict, model: str) -> dict | None:
    """[shafts]: the input shaft of the driven body and the output shaft of the loaded body
    (:mod:`flexgear.dynamics.model.shafts`); None when the table is empty."""
    if not isinstance(raw, dict):
        raise ConfigError("[shafts] must be a table with the tables [shafts.input] and/or [shafts.output]")
    unknown = sorted(set(raw) - {"input", "output"})
    if unknown:
        raise ConfigError(f"unknown shaft(s) {', '.join(repr('shafts.' + k) for k in unknown)}; allowed: "
                          "shafts.input (on drive.body), shafts.output (on load.body)")
    if raw and model != "rigid":
        raise ConfigError(f"[shafts] given with model = {model!r}: shafts need the multi-body model "
                          "(model = 'rigid', the default)")
    out = {}
    for name, ends in (("input", drive), ("output", load)):
        if name not in raw:
            continue
        key = f"shafts.{name}"
        s = _section(key, raw[name], SHAFT_KEYS, required=("diameter", "length"))
        owner = ends["body"]
        role = "drive.body" if name == "input" else "load.body"
        if s["body"] is None:
            s["body"] = owner
        elif s["body"] != owner:
            extra = " (the ring is held, it carries no shaft)" if s["body"] == "ring" else ""
            raise ConfigError(f"{key}.body = {s['body']!r}: the {name} shaft carries {role} = {owner!r}{extra}")
        if name == "input" and s["load_inertia"] is not None:
            raise ConfigError(f"{key}.load_inertia = {s['load_inertia']!r}: the load inertia belongs to "
                              "shafts.output (the input shaft ends at the motor, which turns at the prescribed speed)")
        if name == "output" and s["load_inertia"] is None:
            s["load_inertia"] = LOAD_INERTIA
        if not s["bending"]:
            for k in ("lateral_stiffness", "bearing_stiffness", "lateral_damping", "bearing_span", "gear_position"):
                if s[k] is not None:
                    raise ConfigError(f"{key}.{k} = {s[k]!r} given with {key}.bending = false")
        else:
            sup = supports.get(owner, "revolute")
            if sup != "revolute":
                raise ConfigError(f"supports.{owner} = {sup!r} and {key} with bending: the shaft's bending and its "
                                  f"bearings support {owner!r}; give {key}.bearing_stiffness (or "
                                  f"{key}.lateral_stiffness) and leave supports.{owner} = 'revolute', or set "
                                  f"{key}.bending = false")
            if s["bearing_span"] is None:
                if s["lateral_stiffness"] is None:
                    raise ConfigError(f"{key}.bearing_span is required (or {key}.lateral_stiffness, or "
                                      f"{key}.bending = false)")
            elif s["arrangement"] == "between":
                if s["gear_position"] is None:
                    s["gear_position"] = 0.5 * s["bearing_span"]
                elif not s["gear_position"] < s["bearing_span"]:
                    raise ConfigError(f"{key}.gear_position = {s['gear_position']!r} m: the gear between the "
                                      f"bearings lies inside the span, 0 < gear_position < {key}.bearing_span = "
                                      f"{s['bearing_span']!r} m (an overhung gear: arrangement = 'overhung')")
            elif s["gear_position"] is None:
                raise ConfigError(f"{key}.gear_position (the overhang of the gear beyond its bearing) is required "
                                  f"with {key}.arrangement = 'overhung'")
        out[name] = s
    return out or None


def _lumped_section(raw, kind: str, has_gears: bool = True) -> dict:
    """[lumped]: the stiffness source and, for "constant", one stiffness per pair of the set;
    explicit parameters (:mod:`flexgear.config.lumped_parameters`)."""
    out = _section("lumped", raw, LUMPED_KEYS)
    pairs = ("pinion-wheel",) if kind == "spur" else ("sun-planet", "planet-ring")
    if out["parameters"] is not None:
        if kind != "planetary":
            raise ConfigError(f"[lumped.parameters] given for kind = {kind!r}: explicit lumped parameters describe "
                              "a planetary set")
        out["parameters"] = parse_parameters(out["parameters"], has_gears)
        if "mesh_stiffness" not in raw:
            out["mesh_stiffness"] = "constant"
        elif out["mesh_stiffness"] != "constant":
            raise ConfigError(f"lumped.mesh_stiffness = {out['mesh_stiffness']!r}: with [lumped.parameters] the "
                              "meshes are springs of the stiffness given as printed; the source must be 'constant' "
                              "with lumped.constant_stiffness = {sun-planet = N/m, planet-ring = N/m}"
                              + ("" if has_gears else " (no gear geometry: the contact law, ISO 6336 and FE "
                                 "sources do not exist for these pairs)"))
    cs = out["constant_stiffness"]
    if out["mesh_stiffness"] == "constant":
        if not isinstance(cs, dict):
            raise ConfigError("lumped.constant_stiffness is required for lumped.mesh_stiffness = 'constant': a table "
                              f"{{{', '.join(f'{p} = N/m' for p in pairs)}}}")
        for k in cs:
            if k not in pairs:
                raise ConfigError(f"lumped.constant_stiffness.{k}: no such pair in a {kind} set; pairs: "
                                  f"{', '.join(pairs)}")
        for p in pairs:
            if p not in cs:
                raise ConfigError(f"lumped.constant_stiffness.{p} is missing (mesh_stiffness = 'constant')")
            out["constant_stiffness"][p] = _check_value(f"lumped.constant_stiffness.{p}", "float", cs[p], _POS)
    elif cs is not None:
        raise ConfigError(f"lumped.constant_stiffness given with lumped.mesh_stiffness = "
                          f"{out['mesh_stiffness']!r}; it applies only to 'constant'")
    return out


def time_grid(sim: dict, mesh_frequency: float | None = None) -> tuple[float, int]:
    """Integration step h [s] and steps per output sample of a ``[simulation]`` table.

    The rule: ``simulation.step`` is the largest step allowed; the step used is the output
    interval 1/output_rate divided by the smallest integer that brings it to ``step`` or
    below, h = (1/output_rate) / ceil(step_out / step). A step that already divides the output
    interval is used as given. A run stores the step it used in its ``config_toml``, so the
    stored configuration reproduces the run. A step larger than the output interval is an
    error (checked by :func:`parse_config`).

    With ``simulation.synchronous`` and the mesh frequency f_m [Hz] given (a run gives its
    configuration's), the grid is synchronous with the mesh: a whole number N of steps per mesh
    period, h = 1 / (N f_m) <= ``step``, and a whole number m of output samples per mesh period:
    the output rate m f_m is the least at or above ``output_rate``, and N = m q with the fewest q
    steps per sample (at most m - 1 steps per mesh period more than the fewest that fit the
    step: a fraction ``output_rate`` x ``step`` of them at most, a quarter for the presets). An
    output rate below f_m takes one sample every whole number of mesh periods instead (the most
    that keep the rate at or above the one asked). The force's content at mesh harmonics near
    multiples of the step rate, which the integrator and the records sample at every step, then
    folds onto mesh harmonics instead of onto lines |n f_m - j/h| next to them
    (docs/guide/run.md, "Step aliases"), and so does what the output's anti-alias filter leaves
    above its Nyquist frequency. A result records the step and rate used, its
    stored configuration the values asked for (f_m of a set driven backwards counts by its
    magnitude), and the rule applied to the grid it gave gives it back.
    """
    out_dt = 1.0 / sim["output_rate"]
    if sim.get("synchronous") and mesh_frequency:
        fm = abs(mesh_frequency)  # a set driven backwards meshes as often
        per_mesh = 1.0 / (fm * sim["step"])  # steps per mesh period at the largest step allowed
        if sim["output_rate"] < fm:  # a sample every p mesh periods
            n = max(1, int(math.ceil(per_mesh - 1e-9)))
            p = max(1, int(math.floor(fm * out_dt + 1e-9)))
            return 1.0 / (n * fm), p * n
        m = max(1, int(math.ceil(sim["output_rate"] / fm - 1e-9)))  # output samples per mesh period
        q = max(1, int(math.ceil(per_mesh / m - 1e-9)))  # steps per sample
        return 1.0 / (m * q * fm), q
    out_every = max(1, int(math.ceil(out_dt / sim["step"] - 1e-9)))
    return out_dt / out_every, out_every


def _check_sampling(cfg: Config) -> None:
    """Integration step and output rate against the output interval and the mesh frequency."""
    sim = cfg.simulation
    rate, step = sim["output_rate"], sim["step"]
    if step > (1.0 / rate) * (1 + 1e-9):
        raise ConfigError(
            f"simulation.step = {step!r} s: must not exceed the output interval 1/simulation.output_rate "
            f"= 1/{rate:g} Hz = {1 / rate:.6g} s (the step is the largest integration step; it is "
            f"reduced to divide the output interval)")
    if sim["duration"] * rate < 1:
        raise ConfigError(f"simulation.duration = {sim['duration']!r} s: shorter than one output sample "
                          f"(1/simulation.output_rate = {1 / rate:.6g} s)")
    fm = cfg.peak_mesh_frequency
    if rate < 2 * fm:
        raise ConfigError(
            f"simulation.output_rate = {rate:g} Hz: must be at least twice the gear mesh frequency "
            f"{fm:.6g} Hz (drive.speed_hz on {cfg.drive['body']!r}), i.e. >= {2 * fm:.6g} Hz; below that "
            f"the mesh lines fold onto false frequencies")


def config_document(cfg: Config) -> dict:
    """The configuration with every default filled in, as a plain dictionary of TOML types (SI
    values, ``None`` left out): what :func:`parse_config` reads back into the same Config."""
    def clean(d):
        if isinstance(d, dict):
            return {k: clean(v) for k, v in d.items() if v is not None}
        if isinstance(d, (list, tuple)):
            return [clean(v) for v in d]
        return d

    lumped = None
    if cfg.model == "lumped":
        lumped = dict(cfg.lumped or {})  # a rigid configuration switched to lumped in Python: the defaults
        if lumped.get("parameters") is not None:  # as written (inertia_over_r2, degrees, ...)
            lumped["parameters"] = copy.deepcopy(cfg.raw["lumped"]["parameters"])
        if not cfg.gears:  # a parameter set as printed
            return clean({"title": cfg.title, "kind": cfg.kind, "model": "lumped", "lumped": lumped})
    gears = {}
    for name, g in cfg.gears.items():
        gd = {"teeth": g.z, "module": g.module, "pressure_angle_deg": math.degrees(g.pressure_angle),
              "profile_shift": g.x, "addendum": g.ha, "dedendum": g.hf, "tool_tip_radius": g.rho_f,
              "face_width": g.face_width, "thinning": g.thinning, "internal": g.internal}
        if g.internal:
            gd.update(rim_diameter=g.rim_diameter, cutter_teeth=g.cutter_teeth)
        else:
            gd["bore_diameter"] = g.bore_diameter
        m, J = cfg.gear_mass[name]
        if m is not None:
            gd["mass"] = m
        if J is not None:
            gd["inertia"] = J
        gears[name] = gd
    doc = {"title": cfg.title, "kind": cfg.kind,
           "material": {"E": cfg.material.E, "nu": cfg.material.nu, "density": cfg.material.rho},
           "gears": gears}
    if cfg.model == "lumped":
        doc.update(model="lumped", lumped=lumped)
    elif cfg.model != "rigid":  # read back and refused: a value edited in Python runs no other model
        doc["model"] = cfg.model
    if cfg.planetary:
        doc["planetary"] = cfg.planetary
    if cfg.spur:
        doc["spur"] = cfg.spur
    doc.update(supports=cfg.supports, drive=cfg.drive, load=cfg.load, contact=cfg.contact, simulation=cfg.simulation,
               fe=cfg.fe)
    if cfg.flexible:
        doc["flexible"] = cfg.flexible
    if cfg.shafts:
        doc["shafts"] = cfg.shafts
    from .faults import errors_document, faults_document

    if cfg.faults:
        doc["faults"] = faults_document(cfg.faults)
    if cfg.errors is not None:
        doc["errors"] = errors_document(cfg.errors)
    if cfg.lubrication is not None:
        from .lubrication import lubrication_document

        doc["lubrication"] = lubrication_document(cfg.lubrication)
    if cfg.housing is not None or cfg.sensors:
        from .housing import housing_document, sensors_document

        if cfg.housing is not None:
            doc["housing"] = housing_document(cfg.housing)
        if cfg.sensors:
            doc["sensors"] = sensors_document(cfg.sensors)
    return clean(doc)


def check_config(cfg) -> Config:
    """Validate a :class:`Config` again, exactly as a file is validated when it is read.

    A Config may be edited in Python after loading (``cfg.simulation["duration"] = 0.5``);
    :func:`flexgear.app.run.run` calls this first, so an edited value breaks the same rules
    with the same :class:`~flexgear.errors.ConfigError` (key, value, rule) as in a file.

    Returns
    -------
    Config
        A validated copy (``cfg`` itself is not changed): the same gear and material objects,
        the tables (``simulation``, ``contact``, ...) as a file would give them, with removed
        keys back at their defaults and numbers as floats.

    Raises
    ------
    ConfigError, GeometryError
        The first rule broken.
    """
    if not isinstance(cfg, Config):
        raise ConfigError(f"configuration = {cfg!r}: must be a flexgear Config, a file path or a preset name")
    try:
        doc = config_document(cfg)
    except (AttributeError, KeyError, TypeError) as exc:
        raise ConfigError(f"configuration: a section or key was removed or replaced ({exc!r}); "
                          "edit values in place, e.g. cfg.simulation['duration'] = 0.5") from None
    new = parse_config(doc, source=cfg.source)
    return dataclasses.replace(cfg, gear_mass=new.gear_mass, contact=new.contact, simulation=new.simulation,
                               drive=new.drive, load=new.load, supports=new.supports, planetary=new.planetary,
                               spur=new.spur, fe=new.fe, model=new.model, lumped=new.lumped, flexible=new.flexible,
                               shafts=new.shafts, faults=new.faults, errors=new.errors, lubrication=new.lubrication,
                               housing=new.housing, sensors=new.sensors)


def preset_path(name: str) -> Path:
    """Path of a built-in preset file."""
    if name not in PRESETS + PARAMETER_SETS:
        raise ConfigError(f"unknown preset {name!r}; built-in presets: {', '.join(PRESETS)}; parameter sets: "
                          f"{', '.join(PARAMETER_SETS)}")
    return Path(str(resources.files("flexgear") / "presets" / f"{name}.toml"))


#: Suffix of a configuration name that selects its lumped model (``spur_pair:lumped``).
LUMPED_SUFFIX = ":lumped"


def lumped_title(title: str) -> str:
    """The title of ``NAME:lumped``: its preset's fidelity ("rigid", "flexible gears") named as
    the lumped model, or ", lumped model" added, so that reports and figures say what ran."""
    new, n = re.subn(r"\b(rigid|flexible gears)\b", "lumped model", title, count=1)
    return new if n else (f"{title}, lumped model" if title else "lumped model")


def load_config(path_or_preset: str | Path) -> Config:
    """Read and validate a configuration file, or a built-in preset by name; ``NAME:lumped``
    (:data:`LUMPED_SUFFIX`) gives its lumped model, as ``model = "lumped"`` in the file would.
    An existing file is read as it is, colons in its name and all; a directory of a preset's name
    (``flexgear run spur_pair -o spur_pair`` makes one) does not hide the preset."""
    name = str(path_or_preset)
    if name.endswith(LUMPED_SUFFIX) and not Path(path_or_preset).is_file():
        base = name[:-len(LUMPED_SUFFIX)]
        cfg = load_config(base)
        if cfg.model == "lumped":
            return cfg
        data = tomllib.loads(cfg.source_text)
        data["model"] = "lumped"
        data["title"] = lumped_title(cfg.title)
        try:
            lumped = parse_config(data, source=f"{cfg.source} (lumped)")
        except ConfigError as exc:
            raise ConfigError(f"configuration {name!r}: {exc}") from None
        lumped.source_text = cfg.source_text
        return lumped
    p = Path(path_or_preset)
    if (not p.exists() or p.is_dir()) and name in PRESETS + PARAMETER_SETS:
        p = preset_path(str(path_or_preset))
    if not p.exists():
        near = [f"{p}.toml"] if p.with_name(p.name + ".toml").exists() else \
            difflib.get_close_matches(str(path_or_preset), PRESETS, n=2, cutoff=0.75)
        hint = f"; did you mean {' or '.join(map(repr, near))}?" if near else ""
        raise ConfigError(f"configuration {str(path_or_preset)!r} not found (a file, or a preset: "
                          f"{', '.join(PRESETS)}; either optionally with {LUMPED_SUFFIX!r}){hint}")
    if p.is_dir():
        raise ConfigError(f"configuration {str(p)!r} is a directory: give a TOML file or a preset name "
                          f"({', '.join(PRESETS)})")
    try:
        text = p.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"configuration {str(p)!r} is not a text (UTF-8 TOML) file") from None
    except OSError as exc:
        raise ConfigError(f"configuration {str(p)!r} cannot be read: {exc.strerror or exc}") from None
    return loads_config(text, source=str(p))


def loads_config(text: str, source: str = "<string>") -> Config:
    """Validate a configuration given as TOML text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: not valid TOML: {exc}") from None
    cfg = parse_config(data, source=source)
    cfg.source_text = text
    return cfg
