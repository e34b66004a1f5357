"""Measurement noise at the sensors (``[[sensors]] noise_rms``, ``snr_db``, ``noise_seed``).

Checks: the noise added is white Gaussian of the RMS asked (absolute, or from the signal's RMS
and the SNR), each statistic within four of its sampling standard deviations; the noise-free
signal is the run without noise bit for bit; the noise is reproducible from the recorded seed
and independent between seeds and sensors; the monitor's NA4 of a healthy record against a
healthy baseline, both with noise, is the kurtosis of Gaussian noise (3), where without noise
the baseline is refused; bad settings are named before any computation.
"""
import re
import time

import numpy as np
import pytest

from flexgear.app.cli import main
from flexgear.app.run import run
from flexgear.config.loader import loads_config, preset_path
from flexgear.errors import ConfigError
from flexgear.results.noise import NOISE_FREE
from flexgear.results.sensors import check_sensor_run
from flexgear.results.signals import amplitude_spectrum
from flexgear.results.store import load, save

DURATION = 0.5  # five pinion revolutions after the run-in, 5040 samples at 10080 Hz


def noisy_config(top="", side="", duration=DURATION):
    """The lumped spur pair with its two housing sensors, ``top`` and ``side`` lines added to
    the sensors' tables."""
    text = preset_path("spur_pair_sensors").read_text()
    text = text.replace('name = "top"', 'name = "top"\n' + top, 1).replace('name = "side"', 'name = "side"\n' + side, 1)
    cfg = loads_config('model = "lumped"\n' + text)
    cfg.simulation["duration"] = duration
    return cfg


@pytest.fixture(scope="module")
def runs():
    """(plain, noisy, same again): ``side`` with 0.5 m/s^2 rms of noise, ``top`` at 20 dB SNR."""
    plain = run(noisy_config())
    noisy = run(noisy_config(top="snr_db = 20.0", side="noise_rms = 0.5"))
    again = run(noisy_config(top="snr_db = 20.0", side="noise_rms = 0.5"))
    return plain, noisy, again


def noise_of(res, sensor, path="housing_path"):
    s = res.sensors[sensor]
    return s.signals[path] - s.signals[path + NOISE_FREE]


def check_white_gaussian(e, sigma):
    """``e`` is zero-mean white Gaussian noise of RMS ``sigma``: mean, RMS, kurtosis and the
    first autocorrelations within four sampling standard deviations."""
    n = e.size
    assert abs(e.mean()) < 4 * sigma / np.sqrt(n)
    assert abs(e.std() / sigma - 1) < 4 / np.sqrt(2 * n)
    x = e - e.mean()
    assert abs(np.mean(x ** 4) / np.mean(x ** 2) ** 2 - 3) < 4 * np.sqrt(24 / n)
    for lag in (1, 2, 5, 42):
        assert abs(np.corrcoef(x[:-lag], x[lag:])[0, 1]) < 4 / np.sqrt(n)
    # the floor of the figures' amplitude spectrum (Hann): rms 2 sqrt(1.5 / n) sigma per bin (the guide)
    _, amp = amplitude_spectrum(e, 1.0, window="hann")
    floor = np.sqrt(np.mean(amp[1:-1] ** 2))
    assert floor == pytest.approx(2 * np.sqrt(1.5 / n) * sigma, rel=0.05)


def test_noise_is_white_gaussian_of_the_level_asked(runs):
    plain, noisy, _ = runs
    side, top = noisy.sensors["side"], noisy.sensors["top"]
    clean_top = top.signals["housing_path" + NOISE_FREE]
    check_white_gaussian(noise_of(noisy, "side"), 0.5)
    check_white_gaussian(noise_of(noisy, "top"), clean_top.std() / 10.0)  # 20 dB: a tenth of the rms
    assert side.signal_attrs["housing_path"]["noise_rms"] == 0.5
    assert top.signal_attrs["housing_path"]["snr_db"] == 20.0
    assert top.signal_attrs["housing_path"]["noise_rms"] == pytest.approx(clean_top.std() / 10.0, rel=1e-12)
    snr = 20 * np.log10(clean_top.std() / noise_of(noisy, "top").std())
    assert snr == pytest.approx(20.0, abs=4 * 8.686 / np.sqrt(2 * clean_top.size))
    # the noise-free signals and every other output are those of the run without noise, bit for bit
    for name in ("top", "side"):
        assert np.array_equal(noisy.sensors[name].signals["housing_path" + NOISE_FREE],
                              plain.sensors[name].signals["housing_path"])
        assert list(noisy.sensors[name].signals) == ["housing_path", "housing_path" + NOISE_FREE]
    for name, m in plain.meshes.items():
        assert np.array_equal(m.force_global, noisy.meshes[name].force_global)
    assert all(np.array_equal(v, noisy.housing_loads[k]) for k, v in plain.housing_loads.items())


def test_noise_is_reproducible_from_its_seed_and_independent_between_seeds(runs):
    _, noisy, again = runs
    for name in ("top", "side"):  # a rerun of the same configuration draws the same noise
        assert np.array_equal(noisy.sensors[name].signals["housing_path"], again.sensors[name].signals["housing_path"])
    seed = noisy.sensors["side"].signal_attrs["housing_path"]["noise_seed"]
    assert seed != noisy.sensors["top"].signal_attrs["housing_path"]["noise_seed"]  # every sensor its own
    n = noisy.time.size
    assert abs(np.corrcoef(noise_of(noisy, "side"), noise_of(noisy, "top"))[0, 1]) < 4 / np.sqrt(n)
    fixed = run(noisy_config(top="snr_db = 20.0", side=f"noise_rms = 0.5\nnoise_seed = {seed}"))  # the recorded seed
    # with the same configuration reproduces it
    assert np.array_equal(fixed.sensors["side"].signals["housing_path"], noisy.sensors["side"].signals["housing_path"])
    other = run(noisy_config(side=f"noise_rms = 0.5\nnoise_seed = {seed + 1}"))
    assert other.sensors["side"].signal_attrs["housing_path"]["noise_seed"] == seed + 1
    assert abs(np.corrcoef(noise_of(other, "side"), noise_of(noisy, "side"))[0, 1]) < 4 / np.sqrt(n)


def test_one_seed_in_two_cases_draws_independent_noise_and_remeasure_is_the_run_with_another_seed(runs):
    """Repeated measurements in a batch over the seed: seed 1 of the healthy pair and seed 1 of the
    pair at another load are independent draws (they were the same numbers: every class of a
    dataset shared its noise), and so are seed 1 of two sensors; :func:`remeasure` of a result
    with seed k is the run with seed k, bit for bit, without simulating again."""
    from flexgear.results.noise import remeasure

    _, noisy, _ = runs
    a = run(noisy_config(top="snr_db = 20.0", side="noise_rms = 0.5\nnoise_seed = 1"))
    other_case = noisy_config(top="snr_db = 20.0", side="noise_rms = 0.5\nnoise_seed = 1")
    other_case.load["torque"] = 0.5 * other_case.load["torque"]
    b = run(other_case)
    n = a.time.size
    assert abs(np.corrcoef(noise_of(a, "side"), noise_of(b, "side"))[0, 1]) < 4 / np.sqrt(n)
    again = remeasure(noisy, 1)
    want = run(noisy_config(top="snr_db = 20.0\nnoise_seed = 1", side="noise_rms = 0.5\nnoise_seed = 1"))
    for name in ("top", "side"):
        assert again.sensors[name] == want.sensors[name], name  # signals, noise-free ones and attributes
    assert np.array_equal(noise_of(again, "side"), noise_of(a, "side"))  # the same case and seed: the same draw
    # one seed on two sensors: two independent draws (they were the same numbers, correlation 1)
    assert abs(np.corrcoef(noise_of(want, "side"), noise_of(want, "top"))[0, 1]) < 4 / np.sqrt(n)
    assert loads_config(again.config_toml) == loads_config(want.config_toml)
    assert again.meshes == noisy.meshes and noisy.sensors["side"].signal_attrs["housing_path"]["noise_seed"] != 1
    with pytest.raises(ValueError, match="no sensor with measurement noise"):
        remeasure(runs[0], 1)


def test_noisy_sensors_are_saved_and_give_na4_of_gaussian_noise(runs, tmp_path):
    """Saved and read back with their settings; the monitor's NA4 of the noisy healthy record
    against another healthy record with other noise is the kurtosis of Gaussian noise, 3 (the
    healthy residual is numerically zero: the noise alone remains); the noise-free baseline is
    refused."""
    plain, noisy, _ = runs
    f = save(noisy, tmp_path / "noisy.h5")
    back = load(f)
    a = back.sensors["side"].signal_attrs["housing_path"]
    assert a["noise_rms"] == 0.5 and a["noise_seed"] == noisy.sensors["side"].signal_attrs["housing_path"]["noise_seed"]
    assert np.array_equal(back.sensors["side"].signals["housing_path" + NOISE_FREE],
                          noisy.sensors["side"].signals["housing_path" + NOISE_FREE])
    base = save(run(noisy_config(top="snr_db = 20.0", side="noise_rms = 0.5\nnoise_seed = 7")),
                tmp_path / "base.h5")
    quiet = save(plain, tmp_path / "plain.h5")
    signal = ["--signal", "sensors/side/housing_path", "--shafts", "pinion"]
    assert main(["monitor", str(f), "-o", str(tmp_path / "m"), "--baseline", str(base), *signal]) == 0
    import json

    ind = json.loads((tmp_path / "m" / "indicators.json").read_text())
    shaft = ind["shafts"]["pinion"]
    n = shaft["samples_per_rev"]  # the residual's samples: its kurtosis scatters by sqrt(24 / n)
    assert shaft["indicators"]["fm4"] == pytest.approx(3.0, abs=4 * np.sqrt(24 / n))
    assert shaft["indicators"]["na4"] == pytest.approx(3.0, abs=4 * np.sqrt(24 / n) + 3 * 4 * np.sqrt(2 / n))
    assert main(["monitor", str(f), "-o", str(tmp_path / "q"), "--baseline", str(quiet), *signal]) == 2


def test_the_monitor_warns_on_a_signal_below_its_noise_and_names_the_others(tmp_path):
    """A sensor whose noise floor is far above what it hears: the monitor says so, with the SNR
    and the file's other sensor signals; a signal above its noise gets no warning."""
    import warnings

    from flexgear.monitoring import MonitorSettings, monitor

    f = save(run(noisy_config(top="snr_db = 20.0", side="noise_rms = 1000.0")), tmp_path / "loud.h5")
    with pytest.warns(UserWarning, match=r"sensors/side/housing_path: the sensor hears less than its measurement "
                                         r"noise \(signal-to-noise ratio -\d+ dB.*other sensor signals: "
                                         r"sensors/top/housing_path 20 dB"):
        monitor(f, MonitorSettings(signal="sensors/side/housing_path", shafts=("pinion",)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        monitor(f, MonitorSettings(signal="sensors/top/housing_path", shafts=("pinion",)))


def test_bad_noise_settings_are_named_before_any_computation():
    for top, message in (("noise_rms = -1.0", r"sensors\[0\].noise_rms = -1.0: must be >= 0"),
                         ("snr_db = 300.0", r"sensors\[0\].snr_db = 300.0"),
                         ("noise_rms = 0.1\nsnr_db = 10.0", r"give one of sensors\[0\].noise_rms .* and sensors\[0\]"
                                                           r".snr_db"),
                         ("noise_seed = 3", r"sensors\[0\].noise_seed = 3 without noise"),
                         ("noise_rms = 0.1\nnoise_seed = -2", r"sensors\[0\].noise_seed = -2"),
                         (f"noise_rms = 0.1\nnoise_seed = {2 ** 63}", r"must be < 2\^63"),
                         ("noise_rms = nan", r"sensors\[0\].noise_rms")):
        t0 = time.perf_counter()
        with pytest.raises(ConfigError, match=message):
            noisy_config(top=top)
        assert time.perf_counter() - t0 < 5.0


def test_absolute_noise_on_a_sensor_without_its_quantity_is_refused_before_the_run(monkeypatch):
    """A ring sensor of a planetary set without a housing records the planet-pass force only (N):
    an absolute noise in m/s^2 has no signal to go on (snr_db has)."""
    import flexgear.app.run as app_run

    text = preset_path("mercury_1a").read_text() + '\n[[sensors]]\nname = "rim"\nbody = "ring"\nangle_deg = 0.0\n'
    with monkeypatch.context() as mp:  # refused from the configuration, before the model is built
        mp.setattr(app_run, "build_lumped", lambda *a, **k: pytest.fail("the model was built"))
        mp.setattr(app_run, "build_model", lambda *a, **k: pytest.fail("the model was built"))
        with pytest.raises(ConfigError, match=re.escape("sensor 'rim': sensors.noise_rms = 0.1 m/s^2: the sensor "
                                                        "records no acceleration, only the planet-pass force")):
            run(loads_config('model = "lumped"\n' + text + "noise_rms = 0.1\n"))
        # with a [housing], a ring held by its bolts has a housing path; one on an elastic support has none
        housed = preset_path("mercury_1a_sensors").read_text() + '\n[[sensors]]\nname = "rim"\nbody = "ring"\n' \
            'angle_deg = 0.0\nnoise_rms = 0.1\n'
        check_sensor_run(loads_config(housed))
        elastic = housed.replace('ring = "fixed"', 'ring = {stiffness = 1e8, damping = 1e3}', 1)
        assert elastic != housed
        with pytest.raises(ConfigError, match="sensor 'rim': sensors.noise_rms = 0.1 m/s"):
            run(loads_config(elastic))
    cfg = loads_config('model = "lumped"\n' + text + "snr_db = 30.0\n")
    cfg.simulation["duration"] = 0.05
    res = run(cfg)
    s = res.sensors["rim"]
    assert list(s.signals) == ["planet_pass", "planet_pass" + NOISE_FREE]
    assert s.signal_attrs["planet_pass"]["units"] == "N" and s.signal_attrs["planet_pass"]["snr_db"] == 30.0
