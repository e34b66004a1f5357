"""studies/speed_sweep_modes.py: the flexible model in the speed sweep (a fast check of one
speed, and the whole --quick study, slow)."""
import math
import warnings
from pathlib import Path

import pytest

from flexgear.config import load_config
from conftest import load_script

STUDY = Path(__file__).resolve().parents[1] / "studies" / "speed_sweep_modes.py"


def _study():
    return load_script(STUDY)


def test_flexible_model_is_chosen_from_the_configuration():
    study = _study()
    assert study.flexible_preset("mercury_1a", "auto") == "mercury_1a_flexible"
    assert study.flexible_preset("spur_pair", "auto") == "spur_pair_flexible"
    assert study.flexible_preset("my_set.toml", "auto") is None
    assert study.flexible_preset("mercury_1a", "none") is None
    assert study.flexible_preset("mercury_1a", "other.toml") == "other.toml"


def test_flexible_sweep_point_carries_the_static_load():
    """One speed of the flexible spur pair, after the load ramp: the mean normal force is the
    torque over the wheel's base radius, T / r_b (within 2 %, the mesh's dynamic part averages
    out over whole mesh cycles only approximately in 30 ms)."""
    study = _study()
    cfg = load_config("spur_pair_flexible")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = study.rigid_sweep(cfg.source_text, [10.0], 0.06, 0.03, "pinion-wheel", "flexible")
    assert len(rows) == 1
    r = rows[0]
    wheel = cfg.gears["wheel"]
    assert r["mean"] == pytest.approx(cfg.load["torque"] / wheel.rb, rel=0.02)
    assert r["kv"] >= 1.0
    assert all(math.isfinite(r[f"h{k}"]) for k in range(1, study.HARMONICS + 1))


@pytest.mark.slow
def test_quick_study_with_the_flexible_model(tmp_path):
    """The whole study in its --quick form on MERCURY 1-A (a few minutes on 2 cores)."""
    study = _study()
    out = tmp_path / "sweep"
    assert study.main(["-o", str(out), "--quick"]) == 0
    for name in ("report.md", "campbell.png", "sweep.png"):
        assert (out / name).stat().st_size > 0
    report = (out / "report.md").read_text()
    assert "flexible model (`mercury_1a_flexible`): 4 speeds, 4 finished" in report
    assert "step sideband" not in report


@pytest.mark.slow
def test_quick_study_without_the_flexible_model(tmp_path):
    """``--flexible none`` (the modal guide's option): the lumped and rigid sweeps, their peaks
    against the rigid set's modes, and a report that says the flexible model was not run (it
    ended in an AttributeError on the missing flexible modes)."""
    study = _study()
    out = tmp_path / "sweep"
    assert study.main(["-o", str(out), "--quick", "--config", "spur_pair", "--flexible", "none"]) == 0
    for name in ("report.md", "campbell.png", "sweep.png"):
        assert (out / name).stat().st_size > 0
    assert "flexible model: not run (`--flexible none`" in (out / "report.md").read_text()
