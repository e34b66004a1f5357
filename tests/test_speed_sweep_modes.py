"""studies/speed_sweep_modes.py: the flexible model in the speed sweep (a fast check of one
speed, and the whole --quick study, slow)."""
import math
import warnings
from pathlib import Path

import numpy as np
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


def test_flexible_sweep_records_the_step_of_its_runs():
    """Each sweep point keeps the step and HHT alpha its run integrated with: the flexible
    preset's own (6.25 us in its file), not the rigid presets' 25 us the study assumed."""
    import tomllib

    from flexgear.config import preset_path

    study = _study()
    preset = tomllib.loads(preset_path("spur_pair_flexible").read_text())["simulation"]
    cfg = load_config("spur_pair_flexible")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = study.rigid_sweep(cfg.source_text, [10.0], 0.01, 0.005, "pinion-wheel", "flexible")
    assert rows[0]["step"] == pytest.approx(preset["step"], rel=1e-12) and preset["step"] == 6.25e-6
    assert rows[0]["alpha"] == cfg.simulation["hht_alpha"]


def test_peaks_are_matched_at_the_step_their_runs_used():
    """A resonance of the 4th harmonic where 4 f_m meets an 8.9 kHz mode as an alpha = 0
    integrator renders it at h = 6.25 us, (1 / pi h) atan(omega h / 2) (closed form; 8.79 kHz),
    is matched to that mode within 0.1 %; the same peak read at the rigid presets' 25 us (where
    the mode would ring at 7.6 kHz, 16 % lower) is not within the 5 % window."""
    from types import SimpleNamespace

    study = _study()
    modal = SimpleNamespace(frequencies=np.array([0.0, 8900.0]), mode_type=["-", "-"])
    h, r_m = 6.25e-6, 24.0
    rendered = math.atan(2 * math.pi * 8900.0 * h / 2) / (math.pi * h)
    s0 = rendered / (4 * r_m)
    speeds = s0 * np.linspace(0.9, 1.1, 21)
    rows = [dict(speed=s, step=h, alpha=0.0, **{f"h{k}": 1.0 for k in range(1, 4)},
                 h4=1.0 / (1.0 + ((s - s0) / (0.02 * s0)) ** 2)) for s in speeds]
    table, matched = study.match_peaks("flexible", rows, modal, r_m)
    assert [m[1:] for m in matched] == [(4, 2)]
    assert table[0][6] == "6.25" and abs(float(table[0][8])) < 0.1
    at_25 = [dict(r, step=25e-6) for r in rows]
    assert study.match_peaks("flexible", at_25, modal, r_m)[1] == []


def test_tie_back_leaves_out_numerical_noise():
    """A mesh force with its mesh line, a -60 dB tone off every line and a -160 dB one at a
    mode's frequency (numerical noise): the -60 dB tone is tied back, the noise is not (it was
    listed as the mode's free vibration)."""
    from types import SimpleNamespace

    study = _study()
    fs, fm = 20000.0, 240.0
    t = np.arange(int(fs)) / fs  # 1 s: integer frequencies fall on bins
    x = (100 + 10 * np.sin(2 * np.pi * fm * t) + 0.01 * np.sin(2 * np.pi * 1234 * t)
         + 1e-7 * np.sin(2 * np.pi * 3457 * t))
    res = SimpleNamespace(fs=fs, meshes={"m": SimpleNamespace(normal_force=x)},
                          attrs={"carrier_frequency": 0.0, "mesh_frequency": fm})
    modal = SimpleNamespace(frequencies=np.array([3457.0]), mode_type=["-"])
    rows, _ = study.tie_back(res, modal, "m", "normal")
    freqs = [float(r[0]) for r in rows]
    assert any(abs(f - 1234) < 2 for f in freqs)
    assert not any(abs(f - 3457) < 2 for f in freqs)
    assert all(float(r[2]) >= study.NOISE_FLOOR_DB for r in rows)


def test_a_resonance_peak_is_matched_to_a_mode_its_harmonic_excites():
    """With three equally spaced planets and a 24-tooth sun every mesh harmonic excites the
    rotational modes only (k z_s / N an integer, Parker 2000): a peak of the first harmonic at a
    translational mode's frequency is not that mode's resonance (the flexible MERCURY 1-A's was
    labelled with its 1249 Hz translational mode), one at a rotational mode's is; without the
    phasing (no sun tooth count) the nearest mode is taken, whatever its type."""
    from types import SimpleNamespace

    study = _study()
    system = SimpleNamespace(planets=[0, 1, 2], has_central_translation=lambda: True)
    modal = SimpleNamespace(frequencies=np.array([1000.0, 1100.0]), mode_type=["translational", "rotational"],
                            harmonic=[1, 0], system=system)
    speeds = np.arange(80.0, 120.5, 0.5)  # mesh ratio 10: f_m from 800 to 1200 Hz
    f = 10.0 * speeds
    h1 = 1.0 / np.abs(1.0 - (f / 1000.0) ** 2 + 0.02j) + 1.0 / np.abs(1.0 - (f / 1100.0) ** 2 + 0.02j)
    rows = [dict(speed=s, h1=a, h2=1.0, h3=1.0, h4=1.0, step=25e-6, alpha=-0.1) for s, a in zip(speeds, h1)]
    _, phased = study.match_peaks("rigid", rows, modal, 10.0, sun_teeth=24)
    assert [(round(s), k, i) for s, k, i in phased] == [(110, 1, 2)]
    _, unphased = study.match_peaks("rigid", rows, modal, 10.0)
    assert [(round(s), k, i) for s, k, i in unphased] == [(100, 1, 1), (110, 1, 2)]
    table, _ = study.match_peaks("flexible", rows, modal, 10.0, sun_teeth=24)
    assert table[0][4] == "no excited mode within 5 %"
