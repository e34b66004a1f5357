"""Configuration: TOML schema, defaults, validation and the built-in presets (layer 2).

The public names are re-exported here, so ``from flexgear.config import load_config`` works.
"""
from .loader import (LUMPED_SUFFIX, PARAMETER_SETS, PRESETS, Config, ContactLaw, check_config, check_time_domain,
                     config_document, key_unit, load_config, loads_config, parse_config, preset_path, ramp_note,
                     time_grid)

__all__ = ["LUMPED_SUFFIX", "PARAMETER_SETS", "PRESETS", "Config", "ContactLaw", "check_config", "check_time_domain",
           "config_document", "key_unit", "load_config", "loads_config", "parse_config", "preset_path", "ramp_note",
           "time_grid"]
