"""The tracked fault and error presets run by name and write /faults (short records)."""
import json

import numpy as np
import pytest

from flexgear.app.run import run
from flexgear.config import loads_config, preset_path
from flexgear.results.store import load, save


def short(name: str, duration=0.02, run_in=0.06):
    """The preset with a short record (the load ramp, 0.05 s, ends in the run-in)."""
    text = preset_path(name).read_text()
    assert "duration = 1.0" in text and "run_in = 0.2" in text
    return loads_config(text.replace("duration = 1.0", f"duration = {duration}")
                        .replace("run_in = 0.2", f"run_in = {run_in}"), source=name)


@pytest.fixture(scope="module")
def healthy():
    return run(short("mercury_1a"))


# sun f_s = 30 Hz, z_s = 24, z_r = 66, N = 3 planets: carrier f_c = f_s z_s / (z_s + z_r) = 8 Hz,
# mesh f_m = z_r f_c = 528 Hz. Feng & Zuo 2012 (J. Sound Vib. 331): a local sun fault at
# N f_m / z_s = 66 Hz; a planet pin error turns with the carrier (f_c); a sun run-out modulates the
# meshes at the sun's rotation relative to the carrier, f_s - f_c = 22 Hz.
@pytest.mark.parametrize("name, labels, freqs", [
    ("mercury_1a_sun_spall", ["faults[0] (spall on sun tooth 0, left flank)"], [66.0]),
    ("mercury_1a_errors", ["errors.eccentricity.sun", "errors.pin.planet1 (carrier)"], [22.0, 8.0]),
])
def test_fault_preset_runs_and_writes_its_faults(tmp_path, healthy, name, labels, freqs):
    cfg = short(name)
    res = load(save(run(cfg), tmp_path / "results.h5"))
    assert res.faults is not None
    record = json.loads(res.faults["record"])
    assert [f["kind"] for f in record["faults"]] == [f.kind for f in cfg.faults]
    if name == "mercury_1a_errors":
        assert record["errors"]["pins"]["planet1"]["tangential"] == pytest.approx(2e-6)
        assert record["errors"]["gears"]["sun"]["eccentricity"]["magnitude"] == pytest.approx(10e-6)
    got = dict(zip(res.faults["labels"], res.faults["frequency_hz"]))
    assert got == pytest.approx(dict(zip(labels, freqs)), rel=1e-9)
    # the fault is simulated: the sun-planet forces differ from the healthy preset's
    a, b = res.meshes["sun-planet1"].normal_force, healthy.meshes["sun-planet1"].normal_force
    assert a.shape == b.shape and np.all(np.isfinite(a))
    assert np.max(np.abs(a - b)) > 1e-3 * np.max(np.abs(b))
    # no jam: the sun-planet forces sum to the sun torque over its base radius, T_c z_s / (z_s + z_r) / r_bs
    # (60 N m x 24/90 / (24 mm cos 20 deg) = 709.5 N), however the planets share it; a preload adds to it
    total = sum(np.mean(res.meshes[f"sun-planet{i}"].normal_force) for i in (1, 2, 3))
    assert total == pytest.approx(60.0 * 24 / 90 / (0.024 * np.cos(np.radians(20.0))), rel=0.02)
