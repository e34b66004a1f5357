"""Schema tables of the configuration sections that are read by their own modules
(:mod:`flexgear.config.faults`, :mod:`flexgear.config.lubrication`): key -> (kind, default, rule, unit, description), as the
loader's.

A rule is None, a tuple of allowed values (checked by the loader's value check), or an interval
"[a, b]", "(a, b]", "[a, b)", "(a, b)", ">= a", "> a" (checked here).
"""
from __future__ import annotations

from ..errors import ConfigError

#: the highest mode cutoff of a reduction [Hz], for steel gears and a cast-iron housing (scaled with
#: sqrt of a stiffer modulus: the modes rise with it): the meshes resolve no mode near it
MAX_CUTOFF = 1e6


def check_cutoff(path: str, cutoff: float, stiffening: float, what: str) -> None:
    """Raise ConfigError naming ``path`` if the mode cutoff ``cutoff`` [Hz] lies above
    :data:`MAX_CUTOFF` x sqrt(``stiffening``), the modulus over its reference (``what`` says
    which); a cutoff given in the wrong unit would keep nearly every mode of the mesh."""
    top = MAX_CUTOFF * stiffening ** 0.5  # the modes rise as sqrt(E)
    if cutoff > top:
        raise ConfigError(f"{path} = {cutoff!r} Hz: must be <= {top:.6g} Hz ({MAX_CUTOFF:g} Hz x sqrt({what}); the "
                          "mesh resolves no mode near it, and above it nearly every mode of the mesh would be kept)")


def check_rule(path: str, value, rule, unit: str = "") -> None:
    """Raise ConfigError naming ``path`` if ``value`` breaks the interval ``rule`` (in ``unit``;
    a length above its bound is asked whether it was given in mm)."""
    if rule is None or isinstance(rule, tuple):
        return
    if rule.startswith(">"):
        strict = not rule.startswith(">=")
        a = float(rule.lstrip(">= "))
        if (value <= a) if strict else (value < a):
            raise ConfigError(f"{path} = {value!r}: must be {rule}")
        return
    a, b = (float(v) for v in rule[1:-1].split(","))
    lo_ok = value > a if rule[0] == "(" else value >= a
    hi_ok = value < b if rule[-1] == ")" else value <= b
    if not (lo_ok and hi_ok):
        hint = " (a length in mm given as m?)" if unit == "m" and not hi_ok else ""
        raise ConfigError(f"{path} = {value!r}: must lie in {rule}{' ' + unit if hint else ''}{hint}")


def check_table(path: str, data, schema: dict, check_value) -> dict:
    """A table of ``schema`` keys: unknown keys, types, rules; missing keys None (or default).
    ``check_value(path, kind, value, allowed)`` is the loader's type check."""
    if not isinstance(data, dict):
        raise ConfigError(f"{path} must be a table")
    unknown = sorted(set(data) - set(schema))
    if unknown:
        raise ConfigError(f"unknown key{'s' if len(unknown) > 1 else ''} "
                          f"{', '.join(repr(f'{path}.{k}') for k in unknown)}; allowed: {', '.join(sorted(schema))}")
    out = {}
    for key, (kind, default, rule, unit, *_) in schema.items():
        if key not in data:
            out[key] = default
            continue
        v = check_value(f"{path}.{key}", kind, data[key], rule if isinstance(rule, tuple) else None)
        check_rule(f"{path}.{key}", v, rule, unit if kind == "float" else "")
        out[key] = v
    return out
