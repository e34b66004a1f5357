"""Configuration validation: clear errors before anything long runs."""
import pytest

from flexgear.dynamics.model.assembly import build_model
from flexgear.config import PRESETS, load_config, loads_config, preset_path
from flexgear.errors import ConfigError, GeometryError


def text(name="mercury_1a"):
    return preset_path(name).read_text()


@pytest.mark.parametrize("name", PRESETS)
def test_presets_load(name):
    cfg = load_config(name)
    assert cfg.kind in ("spur", "planetary")


def test_unknown_keys_are_named():
    with pytest.raises(ConfigError, match=r"'simulation.durration'.*allowed in \[simulation\]"):
        loads_config(text().replace("duration = 1.0", "durration = 1.0"))
    with pytest.raises(ConfigError, match="'gears.sun.teth'"):
        loads_config(text().replace("teeth = 24", "teth = 24"))
    with pytest.raises(ConfigError, match="unknown top-level key"):
        loads_config(text() + "\n[solver]\nx = 1\n")


@pytest.mark.parametrize("old,new,match", [
    ("face_width = 0.020", "face_width = -0.020", "face_width = -0.02: must be > 0"),
    ("module = 2.0e-3", "module = 0.0", "module = 0.0: must be > 0"),
    ("output_rate = 10000.0", "output_rate = 0", "output_rate = 0.0: must be > 0"),
    ("hht_alpha = -0.1", "hht_alpha = -0.5", r"hht_alpha = -0.5: HHT alpha must lie in \[-1/3, 0\]"),
    ("teeth = 24", "teeth = 24.5", "teeth = 24.5: must be an integer"),
    ("speed_hz = 30.0", "speed_hz = [[0.0, 30.0], [0.0, 35.0]]", "must increase strictly"),
])
def test_bad_values_are_named(old, new, match):
    with pytest.raises(ConfigError, match=match):
        loads_config(text().replace(old, new))


def test_planets_that_cannot_be_equally_spaced():
    cfg = loads_config(text().replace("planets = 3", "planets = 4"))
    with pytest.raises(GeometryError, match=r"4 planets cannot be equally spaced: \(z_s \+ z_r\)/N = \(24 \+ 66\)/4"):
        build_model(cfg)


def test_tooth_counts_that_do_not_fit():
    cfg = loads_config(text().replace("teeth = 66", "teeth = 68"))
    with pytest.raises(GeometryError, match="does not fit.*centre distance"):
        build_model(cfg)


def test_overlapping_planets():
    # six 21-tooth planets on a 45 mm radius: centre spacing 45 mm < tip diameter 46 mm
    t = text().replace("planets = 3", "planets = 6")
    cfg = loads_config(t)
    with pytest.raises(GeometryError, match="neighbouring planets overlap"):
        build_model(cfg)


def test_pointed_teeth_rejected_before_running():
    t = text("spur_pair").replace("teeth = 21\nbore_diameter = 0.020", "teeth = 10\nprofile_shift = 1.2\nbore_diameter = 0.01")
    with pytest.raises(GeometryError, match="pointed teeth"):
        loads_config(t)


def test_bore_cutting_the_root_circle():
    t = text().replace("bore_diameter = 0.020 # m (default)\n\n[gears.planet]", "bore_diameter = 0.044\n\n[gears.planet]")
    with pytest.raises(GeometryError, match="bore cuts the root circle"):
        loads_config(t)


def test_use_damping_ratio_replaces_the_contact_damping():
    """``Config.use_damping_ratio`` gives the same contact law as ``[contact] damping_ratio`` in
    the file, and refuses a ratio that is not a finite number >= 0, naming the key."""
    cfg = load_config("spur_pair").use_damping_ratio(0.05)
    text = preset_path("spur_pair").read_text().replace("damping = 3000.0", "damping_ratio = 0.05", 1)
    ref = loads_config(text)
    pair = cfg.pairs["pinion-wheel"]
    assert cfg.contact_law(pair).C == ref.contact_law(pair).C
    assert cfg.contact_law(pair).zeta == 0.05
    for bad in (-0.1, float("nan"), "0.05"):
        with pytest.raises(ConfigError, match="contact.damping_ratio"):
            load_config("spur_pair").use_damping_ratio(bad)
