"""``[lubrication]``: tooth friction and the lubricant of a gear set (``Config.lubrication``, a
:class:`flexgear.gears.lubrication.Lubrication`; None without the block: frictionless, as the
presets). Read and validated here, before anything runs; written back for
:func:`~flexgear.config.loader.config_document`. Formulas and sources: ``docs/guide/lubrication.md``.

Example::

    [lubrication]
    friction_model = "xu"         # constant | benedict_kelley | xu
    iso_vg = 220                  # ISO 3448 grade (or viscosity = Pa s at the oil temperature)
    oil_temperature_c = 70.0      # degC, through ASTM D341
    pressure_viscosity = 2.0e-8   # 1/Pa
    density = 870.0               # kg/m^3
    roughness = 0.5e-6            # m, composite RMS (or [lubrication.gear_roughness])
    damping = "impact"            # impact | squeeze_film

Every model (lumped, rigid, flexible) takes the tooth friction and the squeeze-film damping
(``damping = "squeeze_film"``, which needs the lubricant).

Every broken rule is a ConfigError naming the key: a non-finite value or one outside the range
of gear oils and lubricated steel contacts (:data:`PLAUSIBLE`, with the unit conversion a slip
needs); an unknown model or ISO VG grade; an oil temperature outside the ASTM D341 range; a key
of one friction model given with another, or a film key without a lubricant; a roughness the
xu formula cannot take (:data:`XU_MAX_ROUGHNESS`).
"""
from __future__ import annotations

import math

from ..errors import ConfigError
from ..gears.lubrication import (DAMPING_MODELS, FRICTION_MODELS, ISO_VG, OIL_TEMPERATURE_RANGE_C,
                                 OIL_TEMPERATURE_REASON, XU_2007, Lubricant, Lubrication)
from .schema import check_table

_T_LO, _T_HI = OIL_TEMPERATURE_RANGE_C
#: (low, high, hint) of the values no gear oil or lubricated steel contact leaves: outside is a
#: slipped unit (the hint converts) or another kind of contact, refused before anything runs.
PLAUSIBLE = {
    "friction_coefficient": (0.0, 1.0, "lubricated steel gears 0.02 to 0.1, dry steel on steel about 0.6 to 0.8"),
    "viscosity": (1e-4, 10.0, "Pa s; gear oils at their working temperature 0.005 to 1 Pa s; a kinematic "
                  "viscosity in mm^2/s (cSt) times 1e-6 times the density in kg/m^3 gives Pa s: 100 mm^2/s at "
                  "870 kg/m^3 is 0.087 Pa s"),
    "pressure_viscosity": (1e-9, 1e-7, "1/Pa; gear oils 1e-8 to 3.5e-8 1/Pa, i.e. 10 to 35 1/GPa: 20 1/GPa is "
                           "2.0e-8 1/Pa"),
    "density": (500.0, 2000.0, "kg/m^3; gear oils 800 to 1000 kg/m^3: 0.87 g/cm^3 is 870 kg/m^3"),
    "roughness": (0.0, 1e-5, "m; RMS roughness of gear flanks: ground 0.1 to 0.5 um, hobbed 1 to 3 um, and "
                  "0.5 um is 0.5e-6 m"),
}


def _range(key: str) -> str:
    """The schema's rule of a :data:`PLAUSIBLE` key, its interval (the reference prints it;
    :func:`parse_lubrication` checks it with the hint)."""
    lo, hi, _ = PLAUSIBLE[key]
    return f"[{lo:g}, {hi:g}]"


# schema: key -> (kind, default, rule, unit, description), as the loader's
LUBRICATION_KEYS = {
    "friction_model": ("str", "constant", FRICTION_MODELS, "",
        "constant (Coulomb) | benedict_kelley | xu"),
    "friction_coefficient": ("float", None, _range("friction_coefficient"), "",
        "constant model: Coulomb coefficient mu [-] (required there)"),
    "xu_coefficients": ("any", None, None, "",
        "xu model: b1 ... b9 of the formula (default Xu et al. 2007)"),
    "sliding_speed_scale": ("float", 0.01, "> 0", "m/s",
        "v0 of mu tanh(v_s / v0) around the pitch point"),
    "viscosity": ("float", None, _range("viscosity"), "Pa s",
        "dynamic viscosity at the oil temperature (or iso_vg)"),
    "iso_vg": ("int", None, tuple(ISO_VG), "",
        "ISO 3448 viscosity grade, with oil_temperature_c (ASTM D341)"),
    "oil_temperature_c": ("float", None, None, "degC",
        "oil inlet temperature (iso_vg: -20 to 150)"),
    "pressure_viscosity": ("float", 2.0e-8, _range("pressure_viscosity"), "1/Pa",
        "Barus alpha (mineral oils 1.5e-8 to 2.5e-8)"),
    "density": ("float", 870.0, _range("density"), "kg/m^3",
        "at the oil temperature (converts iso_vg's kinematic viscosity)"),
    "roughness": ("float", None, _range("roughness"), "m",
        "composite RMS roughness sqrt(Rq_a^2 + Rq_b^2) of every mesh"),
    "gear_roughness": ("any", None, None, "m",
        "{gear = Rq [m]}: RMS roughness per gear, instead of roughness"),
    "damping": ("str", "impact", DAMPING_MODELS, "",
        "impact ([contact] law) | squeeze_film (EHL squeeze film)"),
}
#: keys that belong to one friction model
MODEL_KEYS = {"constant": ("friction_coefficient",), "benedict_kelley": (), "xu": ("xu_coefficients",)}
#: Largest composite RMS roughness [m] flexgear takes with the xu model: the formula's
#: roughness term b9 e^S (S in um) is an exponential of an exponential, which from S = 1 to 2 um
#: alone multiplies mu by exp(b9 (e^2 - e)) = 28 (mean coefficient about 0.5 on the spur preset
#: at S = 1.7 um, an efficiency below zero at 2.3 um): rougher flanks are outside the smooth-
#: surface EHL solutions it was fitted to.
XU_MAX_ROUGHNESS = 1.0e-6


def _plausible(key: str, value: float, path: str | None = None) -> None:
    lo, hi, hint = PLAUSIBLE[key]
    if not lo <= value <= hi:
        raise ConfigError(f"{path or 'lubrication.' + key} = {value!r}: must lie in {_range(key)} ({hint})")


def _celsius(key: str, temp: float, role: str) -> None:
    if not _T_LO <= temp <= _T_HI:
        kelvin = f"; in kelvin? {temp:g} K is {temp - 273.15:g} degC" if 223.0 <= temp <= 473.0 else ""
        raise ConfigError(f"lubrication.{key} = {temp!r}: outside {role}, [{_T_LO:g}, {_T_HI:g}] degC{kelvin}")


def parse_lubrication(raw, cfg, check_value) -> Lubrication | None:
    """The ``[lubrication]`` table of a configuration whose gears are read (None: absent)."""
    if raw is None:
        return None
    # the PLAUSIBLE ranges are checked below, with the hint that converts a slipped unit
    schema = {k: (s[0], s[1], None, *s[3:]) if k in PLAUSIBLE else s for k, s in LUBRICATION_KEYS.items()}
    v = check_table("lubrication", raw, schema, check_value)
    for key in PLAUSIBLE:
        if v.get(key) is not None:
            _plausible(key, v[key])
    model = v["friction_model"]
    for other, keys in MODEL_KEYS.items():
        for k in keys:
            if other != model and k in raw:
                raise ConfigError(f"lubrication.{k} = {raw[k]!r} belongs to friction_model = {other!r}, but "
                                  f"lubrication.friction_model = {model!r}; remove it or change the model")
    if model == "constant" and v["friction_coefficient"] is None:
        raise ConfigError("lubrication.friction_coefficient is required with friction_model = 'constant' "
                          "(Coulomb coefficient, e.g. 0.05; 0 gives the frictionless model)")
    xu = _xu_coefficients(v["xu_coefficients"]) if "xu_coefficients" in raw else None
    lubricant = _lubricant(raw, v)
    if lubricant is None and (model != "constant" or v["damping"] == "squeeze_film"):
        need = f"friction_model = {model!r}" if model != "constant" else "damping = 'squeeze_film'"
        raise ConfigError(f"[lubrication] with {need} needs the lubricant: lubrication.viscosity [Pa s], or "
                          "lubrication.iso_vg with lubrication.oil_temperature_c [degC]")
    roughness, gear_roughness = _roughness(raw, v, cfg)
    if lubricant is None:
        for k in ("pressure_viscosity", "density", "roughness", "gear_roughness"):
            if k in raw:
                raise ConfigError(f"lubrication.{k} = {raw[k]!r} given without a lubricant: it describes the oil "
                                  "film (its thickness, lambda), which a constant coefficient alone does not "
                                  "have; add lubrication.iso_vg with oil_temperature_c (or viscosity), or remove it")
    if model == "xu" and roughness is None and gear_roughness is None:
        raise ConfigError("lubrication.roughness (composite RMS [m]) or [lubrication.gear_roughness] is required "
                          "with friction_model = 'xu' (the formula's roughness S)")
    lub = Lubrication(friction_model=model, friction_coefficient=v["friction_coefficient"],
                      sliding_speed_scale=v["sliding_speed_scale"], lubricant=lubricant, roughness=roughness,
                      gear_roughness=gear_roughness, damping=v["damping"], xu_coefficients=xu)
    if model == "xu":
        worst, a, b = max((lub.mesh_roughness(a, b), a, b) for a, b in (name.split("-") for name in cfg.pairs))
        if worst > XU_MAX_ROUGHNESS:
            which = ("lubrication.roughness" if gear_roughness is None else
                     f"the composite roughness of {a} and {b} ([lubrication.gear_roughness])")
            raise ConfigError(f"{which} = {worst:.3g} m with friction_model = 'xu': above "
                              f"{XU_MAX_ROUGHNESS:g} m (1 um), where the formula's roughness term b9 exp(S) "
                              "drives mu far beyond lubricated gears (mean about 0.5 at 1.7 um); use "
                              "friction_model = 'benedict_kelley' or a constant coefficient for rougher flanks")
    return lub


def _xu_coefficients(value) -> tuple:
    if (not isinstance(value, list) or len(value) != len(XU_2007)
            or any(isinstance(b, bool) or not isinstance(b, (int, float)) or not math.isfinite(b) for b in value)):
        raise ConfigError(f"lubrication.xu_coefficients = {value!r}: must be a list of {len(XU_2007)} finite numbers "
                          f"b1 ... b9 (default, Xu et al. 2007: {list(XU_2007)})")
    return tuple(float(b) for b in value)


def _lubricant(raw, v) -> Lubricant | None:
    given, grade, temp = v["viscosity"], v["iso_vg"], v["oil_temperature_c"]
    if given is not None and grade is not None:
        raise ConfigError(f"lubrication.viscosity = {given!r} and lubrication.iso_vg = {grade!r}: give one of them "
                          "(a viscosity at the oil temperature, or a grade and the oil temperature)")
    if grade is not None:
        if temp is None:
            raise ConfigError(f"lubrication.iso_vg = {grade!r} needs lubrication.oil_temperature_c [degC] (ASTM D341 "
                              f"from the grade's 40 and 100 degC viscosities)")
        _celsius("oil_temperature_c", temp, "the range flexgear applies the ASTM D341 viscosity relation in "
                 f"({OIL_TEMPERATURE_REASON})")
        return Lubricant.from_iso_vg(grade, temp, v["density"], v["pressure_viscosity"])
    if given is not None:
        if temp is not None:
            _celsius("oil_temperature_c", temp, "the range of oil temperatures (with lubrication.viscosity it "
                     "records the temperature the viscosity is given at, and changes nothing)")
        return Lubricant(viscosity=given, pressure_viscosity=v["pressure_viscosity"], density=v["density"],
                         temperature_c=temp)
    for k in ("oil_temperature_c",):
        if k in raw:
            raise ConfigError(f"lubrication.{k} = {raw[k]!r} given without a lubricant: add lubrication.iso_vg "
                              "(or lubrication.viscosity)")
    return None


def _roughness(raw, v, cfg):
    if v["gear_roughness"] is None:
        return v["roughness"], None
    if v["roughness"] is not None:
        raise ConfigError(f"lubrication.roughness = {v['roughness']!r} and [lubrication.gear_roughness]: give the "
                          "composite roughness of every mesh or one roughness per gear, not both")
    table = v["gear_roughness"]
    if not isinstance(table, dict):
        raise ConfigError(f"lubrication.gear_roughness = {table!r}: must be a table {{gear = RMS roughness [m]}}")
    names = tuple(cfg.gears)
    unknown = sorted(set(table) - set(names))
    if unknown:
        raise ConfigError(f"lubrication.gear_roughness: unknown gear(s) {', '.join(map(repr, unknown))}; the gears "
                          f"are {', '.join(names)}")
    out = []
    for g in names:
        if g not in table:
            raise ConfigError(f"lubrication.gear_roughness.{g} is missing (one RMS roughness per gear: "
                              f"{', '.join(names)})")
        val = table[g]
        if isinstance(val, bool) or not isinstance(val, (int, float)) or not math.isfinite(val) or val < 0:
            raise ConfigError(f"lubrication.gear_roughness.{g} = {val!r}: must be a finite number >= 0 (m)")
        _plausible("roughness", float(val), f"lubrication.gear_roughness.{g}")
        out.append((g, float(val)))
    return None, tuple(out)


def lubrication_document(lub: Lubrication) -> dict:
    """The ``[lubrication]`` table of ``lub`` as :func:`parse_lubrication` reads it back."""
    doc = {"friction_model": lub.friction_model, "sliding_speed_scale": lub.sliding_speed_scale,
           "damping": lub.damping}
    if lub.friction_coefficient is not None:
        doc["friction_coefficient"] = lub.friction_coefficient
    if lub.xu_coefficients is not None:
        doc["xu_coefficients"] = list(lub.xu_coefficients)
    oil = lub.lubricant
    if oil is not None:
        if oil.iso_vg is not None:
            doc["iso_vg"] = oil.iso_vg
        else:
            doc["viscosity"] = oil.viscosity
        if oil.temperature_c is not None:
            doc["oil_temperature_c"] = oil.temperature_c
        doc.update(pressure_viscosity=oil.pressure_viscosity, density=oil.density)
    if lub.gear_roughness is not None:
        doc["gear_roughness"] = dict(lub.gear_roughness)
    elif lub.roughness is not None:
        doc["roughness"] = lub.roughness
    return doc

