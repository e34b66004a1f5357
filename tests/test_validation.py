"""Every entry point validates the same way, before any work; no silent substitution.

- ``run(cfg)`` on a Config edited in Python meets the rules of a file (ConfigError naming the
  key), never a numpy/Python exception from deep inside;
- the integration step rule is explicit and the stored configuration reproduces the run;
- an output rate below twice the mesh frequency is refused before running;
- property-based: mutated presets either run cleanly (finite signals) or are refused with a
  flexgear error that names what is wrong.
"""
import copy
import tomllib
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import flexgear
from flexgear.app.run import run
from flexgear.config import PRESETS, load_config, loads_config, parse_config, preset_path, time_grid
from flexgear.errors import ConfigError, DivergenceError, GeometryError


def tiny(preset, **sim):
    cfg = load_config(preset)
    cfg.simulation.update(duration=0.004, run_in=0.0, **sim)
    return cfg


def quiet_run(cfg):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run(cfg)


# ---------------------------------------------------------------- the Python API validates like a file
@pytest.mark.parametrize("key, value, match", [
    ("duration", -1.0, r"simulation\.duration = -1\.0: must be > 0"),
    ("duration", "0.5", r"simulation\.duration = '0\.5': must be a number"),
    ("duration", float("nan"), r"simulation\.duration = nan: must be finite"),
    ("output_rate", 0, r"simulation\.output_rate = 0\.0: must be > 0"),
    ("max_newton", 2.5, r"simulation\.max_newton = 2\.5: must be an integer"),
    ("antialias", "yes", r"simulation\.antialias = 'yes': must be true or false"),
])
def test_run_validates_an_edited_config_like_a_file(key, value, match):
    cfg = load_config("spur_pair")
    cfg.simulation[key] = value
    with pytest.raises(ConfigError, match=match):
        run(cfg)
    doc = tomllib.loads(preset_path("spur_pair").read_text())
    doc["simulation"][key] = value
    with pytest.raises(ConfigError, match=match):  # the same message as for the file's table
        parse_config(doc)


def test_run_validates_edited_gears_contact_and_drive():
    cfg = load_config("mercury_1a")
    cfg.contact["stiffness"] = -3e5
    with pytest.raises(ConfigError, match=r"contact\.stiffness = -300000\.0: must be a finite number > 0"):
        run(cfg)
    cfg = load_config("mercury_1a")
    cfg.drive["speed_hz"] = [[0.0, 30.0], [0.1, float("inf")]]
    with pytest.raises(ConfigError, match=r"drive\.speed_hz = .*must be finite"):
        run(cfg)
    cfg = load_config("mercury_1a")
    cfg.simulation["setp"] = 1e-5  # a typo is an unknown key, as in a file
    with pytest.raises(ConfigError, match=r"unknown key 'simulation\.setp'"):
        run(cfg)


def test_a_removed_key_takes_its_default_as_in_a_file_and_the_config_is_not_changed():
    cfg = tiny("spur_pair", synchronous=False)  # the preset's synchronous grid would move the step
    del cfg.simulation["step"]
    cfg.simulation["duration"] = 0.004  # an int-like float stays as given
    res = quiet_run(cfg)
    assert res.attrs["step"] == 2.5e-5  # the documented default
    assert "step" not in cfg.simulation  # run() validated a copy


def test_config_sources_that_are_not_toml_files(tmp_path, monkeypatch):
    with pytest.raises(ConfigError, match="is a directory"):
        load_config(tmp_path)
    # `flexgear run spur_pair -o spur_pair` leaves a directory of the preset's name: the preset
    # is still the preset (it was refused as a directory, its own name listed as the remedy)
    monkeypatch.chdir(tmp_path)
    for name in ("spur_pair", "mercury_1a"):
        (tmp_path / name).mkdir()
        assert load_config(name).source_text == load_config(preset_path(name)).source_text
    assert load_config("spur_pair:lumped").model == "lumped"
    p = tmp_path / "x.toml"
    p.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe")
    with pytest.raises(ConfigError, match=r"not a text \(UTF-8 TOML\) file"):
        load_config(p)
    with pytest.raises(ConfigError, match="must be a flexgear Config"):
        flexgear.config.check_config({"kind": "spur"})


# ---------------------------------------------------------------- sampling rules
def test_time_grid_rule():
    sim = {"output_rate": 5000.0, "step": 2.5e-5}
    assert time_grid(sim) == (2.5e-5, 8)  # a divisor is used as given
    h, k = time_grid({"output_rate": 5000.0, "step": 3e-5})
    assert k == 7 and h == pytest.approx(2e-4 / 7) and h <= 3e-5  # the largest divisor step below 'step'
    assert time_grid({"output_rate": 5000.0, "step": 2e-4}) == (2e-4, 1)
    assert time_grid({"output_rate": 5000.0, "step": h}) == (h, 7)  # the step used reproduces itself


def test_a_step_larger_than_the_output_interval_is_an_error():
    cfg = load_config("spur_pair")
    cfg.simulation.update(step=0.01, output_rate=5000.0)
    with pytest.raises(ConfigError, match=r"simulation\.step = 0\.01 s: must not exceed the output interval .*0\.0002 s"):
        run(cfg)


@pytest.mark.parametrize("preset, rate, fm", [("spur_pair", 400.0, 240.0), ("mercury_1a", 1000.0, 528.0)])
def test_output_rate_below_twice_the_mesh_frequency_is_refused(preset, rate, fm):
    cfg = load_config(preset)
    cfg.simulation["output_rate"] = rate
    with pytest.raises(ConfigError, match=rf"simulation\.output_rate = {rate:g} Hz: must be at least twice the gear "
                       rf"mesh frequency {fm:g} Hz"):
        run(cfg)


def test_mesh_frequency_check_uses_the_fastest_speed_of_a_table():
    cfg = load_config("spur_pair")
    cfg.drive["speed_hz"] = [[0.0, 10.0], [0.5, 30.0]]  # 720 Hz mesh frequency at the end
    cfg.simulation["output_rate"] = 1000.0
    with pytest.raises(ConfigError, match=r"twice the gear mesh frequency 720 Hz"):
        run(cfg)


def test_the_stored_configuration_reproduces_a_run_with_an_adjusted_step():
    cfg = tiny("spur_pair", step=3e-5, output_rate=5000.0, synchronous=False)
    with pytest.warns(UserWarning, match=r"simulation\.step = 3e-05 s does not divide the output interval"):
        a = run(cfg)
    h = 2e-4 / 7
    assert a.attrs["step"] == pytest.approx(h, rel=1e-15)
    assert "integrated with h = 2.85714e-05 s" in a.attrs["notes"]
    stored = tomllib.loads(a.config_toml)["simulation"]["step"]
    assert stored == a.attrs["step"]  # what is stored is what ran, not the 3e-5 asked for
    b = run(loads_config(a.config_toml))
    assert b.attrs["step"] == a.attrs["step"] and "integrated with h" not in b.attrs["notes"]
    assert np.array_equal(a.meshes["pinion-wheel"].normal_force, b.meshes["pinion-wheel"].normal_force)


def test_the_stored_configuration_reproduces_a_synchronous_run():
    """``simulation.synchronous``: 1/h and the output rate are whole multiples of the mesh
    frequency (240 Hz), the output interval a whole number of steps; the result records the step and
    the output rate used, its configuration keeps those asked for (as a batch compares it with
    the case's) and runs the same grid again, with the same forces."""
    cfg = tiny("spur_pair", step=3e-5, output_rate=5000.0, synchronous=True)
    cfg.load["ramp"] = 0.0  # no run-in: the load's ramp would be warned
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a synchronous grid is asked for: no warning
        a = run(cfg)
    h = 1.0 / (21 * 7 * 240.0)  # 21 samples per mesh period (5040 Hz >= 5000), 7 steps each: h <= 3e-5
    assert a.attrs["step"] == pytest.approx(h, rel=1e-15)
    assert a.attrs["output_rate"] == pytest.approx(21 * 240.0, rel=1e-15)
    assert "147 steps per mesh period" in a.attrs["notes"]
    stored = tomllib.loads(a.config_toml)["simulation"]
    assert (stored["step"], stored["output_rate"], stored["synchronous"]) == (3e-5, 5000.0, True)
    b = run(loads_config(a.config_toml))
    assert (b.attrs["step"], b.attrs["output_rate"]) == (a.attrs["step"], a.attrs["output_rate"])
    assert np.array_equal(a.meshes["pinion-wheel"].normal_force, b.meshes["pinion-wheel"].normal_force)
    assert cfg.simulation["step"] == 3e-5 and cfg.simulation["output_rate"] == 5000.0  # run() changed a copy


def test_a_run_too_large_for_memory_is_refused_before_building_the_model():
    cfg = load_config("spur_pair")
    cfg.simulation["step"] = 1e-14
    with pytest.raises(ConfigError, match=r"simulation\.step = 1e-14 s .* integration steps whose records need"):
        run(cfg)


# ---------------------------------------------------------------- property-based: mutated presets
# the rigid presets: a mutated flexible preset (material, geometry) needs new FE reductions,
# tens of seconds each (the flexible block is validated in tests/test_flexible.py)
BASE = {p: tomllib.loads(preset_path(p).read_text()) for p in PRESETS if not p.endswith("_flexible")}


def _leaves(d, path=()):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _leaves(v, path + (k,))
        else:
            yield path + (k,)


LEAVES = [(p, path) for p in BASE for path in _leaves(BASE[p])]
MUTATIONS = {
    "remove": None, "rename": None,
    "negative": lambda v: -1.0 if not isinstance(v, int) or isinstance(v, bool) else -1,
    "zero": lambda v: 0, "nan": lambda v: float("nan"), "inf": lambda v: float("inf"),
    "-inf": lambda v: float("-inf"), "huge": lambda v: 1e300, "big": lambda v: 1e9, "tiny": lambda v: 1e-300,
    "string": lambda v: "abc", "list": lambda v: [1.0, 2.0], "bool": lambda v: True, "table": lambda v: {"a": 1},
}


def _mutate(doc, path, how):
    node = doc
    for k in path[:-1]:
        node = node[k]
    key = path[-1]
    if how == "remove":
        del node[key]
        return key
    if how == "rename":
        node[key + "_x"] = node.pop(key)
        return key + "_x"
    node[key] = MUTATIONS[how](node[key])
    return key


def _check_mutation(preset, path, how):
    """Either a clean tiny run (finite signals) or a flexgear error that says what is wrong."""
    doc = copy.deepcopy(BASE[preset])
    key = _mutate(doc, path, how)
    gears = set(doc.get("gears", {})) | {"pinion", "wheel", "sun", "planet", "ring"}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cfg = parse_config(doc)
            # keep the runs tiny whatever the mutation asked for (a valid long run is still valid)
            cfg.simulation["duration"] = min(cfg.simulation["duration"], 0.004)
            cfg.simulation["run_in"] = min(cfg.simulation["run_in"], 0.002)
            res = run(cfg)
    except ConfigError as exc:
        assert key in str(exc) or ".".join(path[:-1]) in str(exc), f"{'.'.join(path)} ({how}): {exc}"
        return "refused"
    except GeometryError as exc:  # the gear set cannot be made or assembled: names a gear or pair
        assert any(g in str(exc) for g in gears) or key in str(exc), f"{'.'.join(path)} ({how}): {exc}"
        return "refused"
    except DivergenceError as exc:  # a valid but unrunnable model (gears pass through): says when, where
        assert "diverged at t =" in str(exc), str(exc)
        return "diverged"
    for m in res.meshes.values():
        assert np.all(np.isfinite(m.normal_force)) and np.all(np.isfinite(m.force_global)), m.name
    for b in res.bodies.values():
        assert np.all(np.isfinite(b.angle)) and np.all(np.isfinite(b.position)), b.name
    return "ran"


@settings(max_examples=100, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(st.sampled_from(LEAVES), st.sampled_from(sorted(MUTATIONS)))
def test_mutated_configurations_run_cleanly_or_are_refused_by_name(leaf, how):
    _check_mutation(*leaf, how)


# mutations that once escaped as OverflowError, LinAlgError, ValueError or a silent run
@pytest.mark.parametrize("preset, path, how, outcome", [
    ("spur_pair", ("title",), "negative", "refused"),
    ("spur_pair", ("gear_defaults", "module"), "huge", "refused"),
    ("spur_pair", ("gear_defaults", "dedendum"), "tiny", "refused"),  # no tip clearance
    ("spur_pair", ("contact", "exponent"), "huge", "refused"),
    ("spur_pair", ("contact", "stiffness"), "inf", "refused"),
    ("spur_pair", ("simulation", "step"), "tiny", "refused"),
    ("spur_pair", ("spur", "line_of_centres_deg"), "huge", "refused"),
    ("mercury_1a", ("gears", "ring", "rim_diameter"), "huge", "refused"),
    ("mercury_1a", ("planetary", "first_planet_angle_deg"), "huge", "refused"),
    ("mercury_1a", ("drive", "speed_hz"), "nan", "refused"),
    ("mercury_1a", ("load", "torque"), "inf", "refused"),
    ("spur_pair", ("material", "density"), "tiny", "diverged"),
    ("spur_pair", ("load", "torque"), "huge", "diverged"),
    ("spur_pair", ("contact", "damping"), "huge", "diverged"),
    ("mercury_1a_errors", ("errors", "pin", "planet1", "radial"), "big", "refused"),  # named only [errors]
])
def test_mutations_that_once_crashed(preset, path, how, outcome):
    assert _check_mutation(preset, path, how) == outcome
