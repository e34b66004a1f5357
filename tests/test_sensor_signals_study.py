"""The sensor-signals study (studies/sensor_signals.py) and the preset spur_pair_sensors."""
import json
import runpy
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flexgear.app.run import run
from flexgear.config import load_config
from flexgear.config.loader import PRESETS, config_document
from flexgear.results.store import load, save

STUDY = Path(__file__).resolve().parents[1] / "studies" / "sensor_signals.py"


@pytest.fixture(scope="module")
def study():
    return runpy.run_path(str(STUDY))


@pytest.mark.parametrize("zr, P", [(66, 3), (67, 3), (73, 5), (70, 4)])
def test_marked_sidebands_are_those_a_planet_pass_sum_keeps(study, zr, P):
    """The study marks k f_m + q f_c with k z_r + q = 0 (mod P) (McFadden & Smith 1985). Build the
    planet-pass sum of P equally spaced planets on a fixed ring, each meshing at harmonic k with
    the phase its place on the ring gives (k z_r psi_i), heard through a Hann window of half a
    revolution (harmonics q = -4..4 of the carrier angle): its lines above 1e-9 of the largest
    are exactly the marked ones. With z_r = 67, P = 3 the mesh harmonic itself is suppressed and
    the sidebands are one-sided; a rule with the sign of q flipped, or without the modulo, fails."""
    n_rev, spr = 4, 4096
    psi = 2 * np.pi * np.arange(n_rev * spr) / spr           # carrier angle, n_rev revolutions
    for k in (1, 2):
        y = np.zeros_like(psi)
        for i in range(P):
            psi_i = psi + 2 * np.pi * i / P
            d = np.angle(np.exp(1j * psi_i))                   # planet-sensor angle in (-pi, pi]
            w = np.where(np.abs(d) < np.pi / 2, np.cos(d) ** 2, 0.0)
            y += w * np.cos(k * zr * psi_i)
        A = np.abs(np.fft.rfft(y)) / y.size
        orders = np.arange(A.size) / n_rev
        lines = {int(round(o)) - k * zr for o, a in zip(orders, A) if a > 1e-9 * A.max()}
        near = {q for q in lines if abs(q) <= 6}
        allowed = set(study["allowed_sidebands"](k, zr, P, 6))
        assert near <= allowed, (k, sorted(near), sorted(allowed))
        assert {q for q in allowed if abs(q) <= 2} <= near, (k, sorted(near))  # the window's lowest harmonics


def test_fault_frequencies_follow_feng_and_zuo(study):
    """MERCURY 1-A at 30 Hz on the sun: f_c = 30 x 24 / 90 = 8 Hz, f_m = 66 f_c = 528 Hz, a sun
    fault at 3 f_m / 24 = 66 Hz, a planet flank fault at f_m / 21 (Feng & Zuo 2012). None of the
    marked fault lines is a whole carrier order (those coincide with a healthy set's lines)."""
    kin = study["kinematics"](load_config("mercury_1a_sensors"))
    assert (kin["f_c"], kin["f_m"], kin["sun"]) == pytest.approx((8.0, 528.0, 66.0), rel=1e-12)
    assert kin["planet1"] == pytest.approx(528.0 / 21, rel=1e-12)
    for shaft in ("sun", "planet1"):
        f = np.array(study["fault_line_freqs"](kin, shaft, 4000.0))
        assert f.size and np.all(np.abs(f / 8.0 - np.round(f / 8.0)) > 0.1)


@pytest.mark.slow
def test_quick_study_writes_its_figures_and_the_fault_lines_grow(tmp_path, monkeypatch):
    """The quick study end to end (a minute on 2 cores, more with a cold compile). A healthy rigid
    or lumped set repeats every carrier revolution, so at the housing path the sun fault's lines
    (no whole carrier order) are absent (< 1e-6 of the mesh lines); a deeper sun crack softens
    the mesh more each time the tooth meshes, so they grow strictly with depth at both sensors, and
    so does the sun's sideband energy ratio (which is zero for the healthy regular signal)."""
    monkeypatch.setattr(sys, "argv", ["sensor_signals.py", "-o", str(tmp_path), "--quick", "--workers", "2"])
    with pytest.raises(SystemExit) as done:  # a study ends as a program: status 0
        runpy.run_path(str(STUDY), run_name="__main__")
    assert done.value.code == 0
    families = ("sun_crack", "planet_crack", "sun_spall")
    for f in ["indicators.png", "report.md"] + [f"{p}_{x}.png" for x in families for p in ("time", "spectrum")]:
        assert (tmp_path / f).stat().st_size > 0, f
    for x in families:
        assert (pd.read_csv(tmp_path / x / "summary.csv").status == "done").all()
        assert (tmp_path / x / "monitor" / "severity.csv").stat().st_size > 0
    report = (tmp_path / "report.md").read_text()
    for family in ("**Mesh harmonics**", "**Planet-pass sidebands**", "**Sun fault lines**", "**Planet fault lines**"):
        assert family in report
    levels = json.loads((tmp_path / "fault_levels.json").read_text())
    for sensor in ("top", "side"):
        for x in ("sun_crack", "sun_spall"):
            lv = levels[x][f"{sensor}/housing_path"]
            assert lv[0] < 1e-6 and np.all(np.diff(lv) > 0), (x, sensor, lv)
    sev = pd.read_csv(tmp_path / "sun_crack" / "monitor" / "severity.csv")
    assert sev.severity.is_monotonic_increasing and np.all(np.diff(sev.sun_ser) > 0), sev.sun_ser.tolist()


# --------------------------------------------------------------------------------------------
# preset spur_pair_sensors
# --------------------------------------------------------------------------------------------
def test_spur_sensors_preset_is_the_spur_pair_with_a_housing_and_two_sensors():
    assert "spur_pair_sensors" in PRESETS
    cfg, base = load_config("spur_pair_sensors"), config_document(load_config("spur_pair"))
    doc = config_document(cfg)
    assert {k: v for k, v in doc.items() if k not in ("housing", "sensors", "title")} == \
        {k: v for k, v in base.items() if k != "title"}
    assert cfg.housing.outline.kind == "rounded_rectangle"
    assert [(s.name, s.angle_deg, s.direction_label, s.quantity) for s in cfg.sensors] == \
        [("top", 90.0, "radial", "acceleration"), ("side", 0.0, "radial", "acceleration")]


def test_spur_sensors_preset_runs_and_writes_sensors(tmp_path):
    """A short run by name writes /sensors/<name>/housing_path in m/s^2, finite and non-zero, and
    the bearing loads on the housing balance (Newton on the pair: both centres fixed, so the
    pinion's and the wheel's bearing forces are equal and opposite, 1e-9 of their size)."""
    cfg = load_config("spur_pair_sensors")
    cfg.simulation["duration"], cfg.simulation["run_in"] = 0.05, 0.1
    back = load(save(run(cfg), tmp_path / "results.h5"))
    assert set(back.sensors) == {"top", "side"}
    for name, s in back.sensors.items():
        y = s.signals["housing_path"]
        assert s.signal_attrs["housing_path"]["units"] == "m/s^2" and y.shape == back.time.shape
        assert np.all(np.isfinite(y)) and np.sqrt(np.mean(y**2)) > 0, name
    h = back.housing_loads
    for c in ("x", "y"):
        scale = np.abs(h[f"pinion.{c}"]).max()
        assert scale > 0 and np.abs(h[f"pinion.{c}"] + h[f"wheel.{c}"]).max() <= 1e-9 * scale, c
