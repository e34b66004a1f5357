"""Configuration: TOML schema, defaults, validation and the built-in presets (layer 2).

The public names are re-exported here, so ``from flexgear.config import load_config`` works.
"""
from .loader import PRESETS, Config, ContactLaw, load_config, loads_config, parse_config, preset_path

__all__ = ["PRESETS", "Config", "ContactLaw", "load_config", "loads_config", "parse_config", "preset_path"]
