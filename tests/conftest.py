"""Shared fixtures: shortened runs of the two presets, computed once per test session."""
import warnings

import pytest

from flexgear.config import load_config
from flexgear.app.run import run


def short(preset, duration, run_in=0.1, **sim):
    cfg = load_config(preset)
    cfg.simulation.update(duration=duration, run_in=run_in, **sim)
    return cfg


@pytest.fixture(scope="session")
def spur_result():
    return run(short("spur_pair", 0.25))


@pytest.fixture(scope="session")
def planetary_result():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run(short("mercury_1a", 0.5))
