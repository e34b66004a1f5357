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


def test_unknown_keys_are_named_with_the_key_meant():
    with pytest.raises(ConfigError, match=r"'simulation.durration'.*allowed in \[simulation\].*; did you mean "
                                          r"'simulation.duration'\?$"):
        loads_config(text().replace("duration = 1.0", "durration = 1.0"))
    with pytest.raises(ConfigError, match=r"'gears.sun.teth'.*; did you mean 'gears.sun.teeth'\?$"):
        loads_config(text().replace("teeth = 24", "teth = 24"))
    with pytest.raises(ConfigError, match="unknown top-level key") as err:
        loads_config(text() + "\n[solver]\nx = 1\n")
    assert "did you mean" not in str(err.value)  # nothing close: no guess
    with pytest.raises(ConfigError, match=r"'simulaton'.*; did you mean 'simulation'\?$"):
        loads_config(text().replace("[simulation]", "[simulaton]"))


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


def test_an_unknown_support_name_shows_the_table_form_as_written():
    """The message shows the table a support may be instead, in TOML as a user writes it (one
    brace, every key of the table), not a format string's escaped ``{{``."""
    with pytest.raises(ConfigError) as err:
        loads_config(text().replace('ring = "fixed"', 'ring = "clamped"'))
    msg = str(err.value)
    assert "supports.ring = 'clamped': must be one of 'fixed'" in msg
    assert "{{" not in msg and "}}" not in msg
    assert "{stiffness = N/m, damping = N s/m, torsional_stiffness = N m/rad, torsional_damping = N m s/rad}" in msg


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


@pytest.mark.parametrize("name", PRESETS)
def test_every_preset_writes_at_the_default_rate_whose_band_holds_the_largest_mesh_lines(name):
    """README: the output is 10 kHz (the schema's default), trustworthy up to 0.8 x Nyquist =
    4 kHz, which keeps MERCURY 1-A's largest mesh lines (5 f_m = 2640 Hz and 4 f_m -+ f_a); the
    flexible presets wrote at 5 kHz, whose trustworthy band ends at 2 kHz, below them."""
    from flexgear.config.loader import SIM_KEYS
    from flexgear.results.decimation import passband_hz

    cfg = load_config(name)
    rate = cfg.simulation["output_rate"]
    assert rate == SIM_KEYS["output_rate"][1] == 10000.0
    if cfg.kind == "planetary":
        zs, zr = cfg.gears["sun"].z, cfg.gears["ring"].z
        f_m = zr * cfg.drive["speed_hz"] * zs / (zs + zr)  # sun driven, ring fixed: 528 Hz
        assert passband_hz(rate) > 5 * f_m + 8.0


def test_lumped_suffix_gives_the_model_the_file_would_with_model_lumped(tmp_path, monkeypatch):
    """``NAME:lumped`` is the configuration with ``model = "lumped"`` added (same document, every
    other key kept), a parameter set stays itself, an existing file whose name ends in ``:lumped``
    is read as it is, and a configuration that has no lumped model says which one and why."""
    from flexgear.config import config_document

    text = preset_path("spur_pair_friction").read_text()
    by_suffix = load_config("spur_pair_friction:lumped")
    by_key = loads_config('model = "lumped"\n' + text)
    assert by_suffix.model == "lumped" and load_config("spur_pair_friction").model == "rigid"
    assert config_document(by_suffix) == dict(config_document(by_key), title=by_suffix.title)
    # the title names the model that runs (the modal report and figures print it)
    assert by_suffix.title == by_key.title + ", lumped model"
    assert load_config("mercury_1a:lumped").title == "MERCURY 1-A planetary gear, lumped model (paper Secs. 3-4)"
    assert load_config("mercury_1a_friction:lumped").title.startswith("MERCURY 1-A planetary gear, lumped model, tooth")
    assert by_suffix.lubrication == by_key.lubrication is not None
    assert load_config("lin_parker_1999:lumped").model == "lumped"
    monkeypatch.chdir(tmp_path)
    (tmp_path / "spur_pair:lumped").write_text(text)
    assert load_config("spur_pair:lumped").model == "rigid"
    with pytest.raises(ConfigError, match=r"'spur_pair_flexible:lumped': \[flexible\] given with model = 'lumped'"):
        load_config("spur_pair_flexible:lumped")
    with pytest.raises(ConfigError, match=r"'spur_pair:rigid' not found .*optionally with ':lumped'"):
        load_config("spur_pair:rigid")


def test_a_name_not_found_suggests_the_file_or_preset_meant(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_gear.toml").write_text(preset_path("spur_pair").read_text())
    with pytest.raises(ConfigError, match=r"'my_gear' not found .*did you mean 'my_gear.toml'\?"):
        load_config("my_gear")
    with pytest.raises(ConfigError, match=r"'spur_pair_frcition' not found .*did you mean 'spur_pair_friction'\?"):
        load_config("spur_pair_frcition")
    with pytest.raises(ConfigError, match=r"'zzz' not found \(a file, or a preset: [^?]*\)$"):
        load_config("zzz")
