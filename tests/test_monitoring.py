"""Condition monitoring (flexgear.monitoring): order tracking, synchronous averages, planet windows,
indicators against their closed forms, and the command on synthetic and simulated results."""
import json
import math
import warnings

import numpy as np
import pytest

from flexgear.errors import ConfigError, FlexgearError, ResultExistsError
from flexgear.monitoring import MonitorSettings, monitor
from flexgear.monitoring import indicators as ind
from flexgear.monitoring.envelope import envelope
from flexgear.monitoring.order import angular_resample, order_spectrum, samples_per_revolution
from flexgear.monitoring.outputs import REPORT_FILES, batch_cases, severity_table, write_severity
from flexgear.monitoring.tsa import moment_grid, synchronous_average, tsa_signals
from flexgear.results.signals import amplitude_spectrum, line_amplitude

import monitoring_data as md

FS = 10000.0


# --------------------------------------------------------------------------- order tracking

def test_order_tracking_under_a_speed_ramp_recovers_the_order():
    """A line at order 17 of a shaft accelerating from 10 to 30 rev/s smears over 170-510 Hz in
    time, but after angular resampling it is one line of its amplitude at order 17; a line at
    order 130 (3.9 kHz at the top speed, near the band edge) keeps its waveform to 1e-3."""
    t = np.arange(0, 2.0, 1 / FS)
    theta = 2 * np.pi * (10.0 * t + 5.0 * t ** 2)
    n = samples_per_revolution(FS, 10.0, 24)
    sig = angular_resample(t, 0.7 * np.cos(17 * theta), theta, n)
    orders, amp = order_spectrum(sig)
    assert orders[np.argmax(amp)] == pytest.approx(17.0, abs=1e-9)
    assert amp.max() == pytest.approx(0.7, rel=1e-4)
    f, a_time = amplitude_spectrum(0.7 * np.cos(17 * theta), FS)
    assert a_time.max() < 0.2  # the plain spectrum has no such line
    fast = angular_resample(t, np.cos(130 * theta), theta, n)
    exact = np.cos(130 * (fast.angle0 + 2 * np.pi * np.arange(fast.values.size) / n))
    assert np.max(np.abs(fast.values - exact)) < 1e-3


def test_samples_per_revolution_ignore_a_speeds_round_off():
    """A shaft at 10 rev/s recorded at 10 080 Hz (a grid synchronous with its 240 Hz mesh) needs
    1008 samples per revolution, 42 pitches of 24; the speed as read from the angle record,
    10 (1 - 3e-11), took 43 pitches (1032)."""
    assert samples_per_revolution(10080.0, 10.0 * (1 - 3e-11), 24) == 1008
    assert samples_per_revolution(10080.0, 10.0 * (1 - 1e-6), 24) == 1032  # a slower shaft needs more
    assert samples_per_revolution(10080.0, 10.0, 24) == 1008


def test_order_tracking_follows_clockwise_shafts_and_refuses_standstill():
    t = np.arange(0, 1.0, 1 / FS)
    theta = -2 * np.pi * 12.0 * t
    sig = angular_resample(t, np.cos(5 * theta), theta, 1000)
    assert sig.direction == -1 and sig.revolutions == 11
    o, a = order_spectrum(sig)
    assert o[np.argmax(a)] == pytest.approx(5.0)
    with pytest.raises(ValueError, match="stands still or reverses"):
        angular_resample(t, t, np.sin(2 * np.pi * t), 1000)
    with pytest.raises(ValueError, match="less than one whole revolution"):
        angular_resample(t, t, 0.5 * theta / 12, 1000)


# --------------------------------------------------------------------------- averages

@pytest.mark.parametrize("revolutions", [4, 16, 64])
def test_tsa_noise_falls_as_one_over_sqrt_of_averages(revolutions):
    """Non-synchronous noise in the TSA has the RMS of the resampled noise / sqrt(averages), 5 %."""
    rng = np.random.default_rng(revolutions)
    speed = 2.5  # rev/s: 4000 samples per revolution
    t = np.arange(0, (revolutions + 1.0) / speed, 1 / FS)  # from 0.06 rev: whole revolutions 1..N
    theta = 2 * np.pi * speed * t + 0.37
    n = samples_per_revolution(FS, speed)
    periodic = np.cos(24 * theta) + 0.3 * np.sin(3 * theta)
    noise = rng.normal(0.0, 1.0, t.size)
    total = synchronous_average(angular_resample(t, periodic + noise, theta, n))
    clean = synchronous_average(angular_resample(t, periodic, theta, n))
    resampled = angular_resample(t, noise, theta, n)
    assert total.averages == revolutions
    ratio = np.std(total.values - clean.values) * math.sqrt(revolutions) / np.std(resampled.values)
    assert ratio == pytest.approx(1.0, abs=0.05)


def test_regular_residual_difference_split_by_order():
    """Regular: mesh harmonics and shaft orders 1..2; residual: the rest; difference: the residual
    without the sidebands z -/+ 1 (Lebold et al. 2000)."""
    n, z = 480, 20
    a = 2 * np.pi * np.arange(n) / n
    mesh, shaft, side, other = (np.cos(z * a) + 0.5 * np.cos(2 * z * a), 0.2 * np.cos(a + 1),
                                0.3 * np.cos((z + 1) * a) + 0.1 * np.sin((2 * z - 1) * a), 0.05 * np.cos(7 * a))
    s = tsa_signals(3.0 + mesh + shaft + side + other, z, shaft_orders=2)
    np.testing.assert_allclose(s.regular, mesh + shaft, atol=1e-12)
    np.testing.assert_allclose(s.residual, side + other, atol=1e-12)
    np.testing.assert_allclose(s.difference, other, atol=1e-12)
    low = tsa_signals(mesh + other, z, max_order=z - 1)  # the band ends below the mesh order
    np.testing.assert_allclose(low.tsa, other, atol=1e-12)


def test_planet_windows_reassemble_each_planet_tooth_by_tooth(tmp_path):
    """A housing sensor hears each planet only while it passes (MERCURY 1-A's 24/21/66 teeth, 3
    planets). McFadden's windows (Hann, 2 gcd(66, 21) = 6 teeth) rebuild every planet's own
    vibration, different on every tooth and every planet, to 1e-4 of its amplitude on each tooth;
    a plain average over the planet's angle mixes the three."""
    path = tmp_path / "planetary.h5"
    md.write_planetary(path, duration=1.0)
    rep = monitor(path, MonitorSettings(shafts=("planet1", "planet2", "planet3")))
    assert rep.source.signal_path == "sensors/top/acceleration"  # the default: the first sensor
    n = rep.shafts["planet1"].samples_per_rev
    psi = 2 * np.pi * np.arange(n) / n
    for j in range(md.PLANETS):
        sa = rep.shafts[f"planet{j + 1}"]
        assert sa.shaft.windowed and sa.window_teeth == 6
        want = md.planet_vibration(j, -psi)  # planets turn clockwise in the carrier
        got = sa.average.values
        err = np.abs((got - got.mean()) - (want - want.mean())).reshape(md.Z_PLANET, -1).max(axis=1)
        assert err.max() < 1e-4, f"planet{j + 1}: worst tooth off by {err.max():.2e}"
        other = md.planet_vibration((j + 1) % md.PLANETS, -psi)
        assert np.max(np.abs(got - other)) > 0.3  # the planets differ: a mixed average would show it
    plain = monitor(path, MonitorSettings(signal="sensors/top/acceleration", shafts=("sun",)))
    assert "planet1" not in plain.shafts


def test_sun_windows_put_each_sun_tooth_once_in_the_suns_average(tmp_path):
    """The sun meets every planet; a sensor hears each mesh while its planet passes. With
    --sun-windows each planet's windows are resampled against the sun's angle shifted by the
    planet's position (McFadden 1991): the residual is the sun's own, against the material angle
    m = psi_1 - phi that meets planet 1 (a faulty tooth once, at m = 1 rad), to what the planets'
    tones leave in 4 s (measured 0.03 of the fault's height); the plain average holds
    the faulty tooth once per planet, a third of a turn apart, at about a third of its height.
    The planets' passes (a steady load of 5 heard as each passes) repeat with the carrier, and so
    with the four groups of sun teeth the windows see (6 teeth apart): removed before the
    windows, they leave no line at order 4 (0.002; 0.09 with them in), nor does the sun's own
    content there, which repeats with the carrier as well."""
    path = tmp_path / "planetary.h5"
    md.write_planetary(path, duration=4.0, background=0.0, sun_fault=1.0, pass_load=5.0)
    win = monitor(path, MonitorSettings(shafts=("sun",), sun_windows=True)).shafts["sun"]
    plain = monitor(path, MonitorSettings(shafts=("sun",))).shafts["sun"]
    # the sun tooth at the sensor advances (24 + 66) / 3 = 30 = 6 mod 24 teeth from pass to pass:
    # Hann windows of 2 x 6 teeth tile it
    assert win.window_teeth == 12 and win.average.averages > 0.99 and plain.window_teeth is None
    n, kmax = win.samples_per_rev, win.signals.max_order
    k = np.arange(n // 2 + 1)
    # the residual's orders (guide), but for the multiples of 24 / 6 = 4, which repeat with the carrier
    sun_own = (k > 2) & (k <= kmax) & (k % md.Z_SUN != 0) & (k % 4 != 0)
    amp = np.abs(np.fft.rfft(win.signals.residual)) * 2 / n
    assert amp[4] < 0.01 and amp[8] < 0.01  # the passes' groups (0.09 and 0.13 left in the sun's windows)
    want = md.sun_vibration(np.pi / 2 - 2 * np.pi * np.arange(n) / n, 1.0)  # planet 1 at psi_1 = 90 deg
    own = lambda x: np.fft.irfft(np.where(sun_own, np.fft.rfft(x), 0.0), n)  # noqa: E731
    assert np.max(np.abs(own(win.signals.residual) - own(want))) < 0.05
    assert np.max(np.abs(own(plain.signals.residual) - own(want))) > 0.4  # measured 0.49
    faulty = [np.mod(np.pi / 2 - 1.0 + 2 * np.pi * j / 3, 2 * np.pi) for j in range(3)]
    at = [int(round(a / (2 * np.pi) * n)) % n for a in faulty]
    assert win.signals.residual[at[0]] > 0.5 and max(abs(win.signals.residual[i]) for i in at[1:]) < 0.15
    assert all(0.1 < plain.signals.residual[i] < 0.3 for i in at)  # a third each: every planet's mesh
    from flexgear.app.cli import main

    assert main(["monitor", str(path), "-o", str(tmp_path / "m"), "--shafts", "sun", "--sun-windows"]) == 0
    data = json.loads((tmp_path / "m" / "indicators.json").read_text())
    assert data["settings"]["sun_windows"] is True and data["shafts"]["sun"]["planet_window"]["teeth"] == 12


def test_na4_against_a_healthy_baseline(tmp_path):
    """NA4 divides by the mean residual variance of the baseline results and this one: without a
    baseline it is the residual's kurtosis, against a baseline at half the amplitude (a quarter
    of the variance) that kurtosis x (8/5)^2."""
    import h5py
    import shutil

    path, half = tmp_path / "run.h5", tmp_path / "half.h5"
    md.write_planetary(path, duration=1.0)
    shutil.copy(path, half)
    with h5py.File(half, "r+") as h5:
        h5["sensors/top/acceleration"][...] *= 0.5
    settings = MonitorSettings(shafts=("sun", "planet2"))
    alone = monitor(path, settings)
    for name in ("sun", "planet2"):
        sig = alone.shafts[name].signals
        k = ind.kurtosis(moment_grid(sig.residual, sig.max_order))
        assert alone.shafts[name].indicators["na4"] == pytest.approx(k, rel=1e-9)
        against = monitor(path, settings, baseline=[half])
        assert against.shafts[name].indicators["na4"] == pytest.approx(k * (8 / 5) ** 2, rel=1e-6)
        assert against.baseline_records[name] == 1
    with pytest.raises(FlexgearError, match="--baseline .*missing.h5"):
        monitor(path, settings, baseline=[tmp_path / "missing.h5"])


def test_baselines_are_band_limited_at_the_analysed_records_band(tmp_path):
    """NA4's variances cover the orders of the analysed residual: a baseline whose file trusts a
    wider band, with a sun line above the analysed record's band, normalises NA4 exactly as the
    same record without that line (its own band had counted the line's variance: NA4 0.0066
    for 2.92), to the resampling's leakage of the line into lower orders (1e-5)."""
    import h5py
    import shutil

    path, plain, wide = (tmp_path / f"{n}.h5" for n in ("run", "plain", "wide"))
    md.write_planetary(path, duration=1.0)
    for p in (plain, wide):
        shutil.copy(path, p)
    settings = MonitorSettings(shafts=("sun",))
    top = monitor(path, settings).shafts["sun"].signals.max_order
    with h5py.File(wide, "r+") as h5:
        h5.attrs["passband_hz"] = 0.45 * 10000.0
        sun, carrier = h5["bodies/sun/angle"][()], h5["bodies/carrier/angle"][()]
        h5["sensors/top/acceleration"][...] += 0.5 * np.cos((top + 5) * (sun - carrier))
    assert monitor(wide, settings).shafts["sun"].signals.max_order > top + 5  # the line inside its own band
    want = monitor(path, settings, baseline=[plain]).shafts["sun"].indicators["na4"]
    assert monitor(path, settings, baseline=[wide]).shafts["sun"].indicators["na4"] == pytest.approx(want, rel=1e-5)


def test_a_baseline_at_another_speed_is_used_with_a_warning(tmp_path):
    """A healthy record of the set turning 10 % faster normalises NA4 by another operating point's
    variance: the monitor says so, naming the file, the shaft and both speeds; 1 % passes."""
    import warnings

    import h5py

    path, fast, near = (tmp_path / f"{n}.h5" for n in ("run", "fast", "near"))
    for p, k in ((path, 1.0), (fast, 1.1), (near, 1.01)):
        md.write_planetary(p, duration=1.0)
        with h5py.File(p, "r+") as h5:  # the same samples k times as fast
            h5["time"][...] /= k
            h5.attrs["passband_hz"] *= k
    settings = MonitorSettings(shafts=("sun",))
    with pytest.warns(UserWarning, match=r"--baseline .*fast.h5: sun turns at 24\.2 rev/s there, at 22 rev/s"):
        monitor(path, settings, baseline=[fast])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        monitor(path, settings, baseline=[near])


def test_a_baseline_must_be_another_healthy_record_of_the_same_signal(tmp_path):
    """The baseline is read at the analysed signal's path (a baseline without it is an error, not
    its own default signal); the result itself, a baseline given twice and a baseline whose
    residual is numerically zero (a noise-free healthy simulation: NA4 would grow with the number
    of such baselines) are refused, each naming the file."""
    import h5py
    import shutil

    path, other, plain, quiet = (tmp_path / f"{n}.h5" for n in ("run", "other", "plain", "quiet"))
    md.write_planetary(path, duration=1.0)
    md.write_planetary(other, duration=1.0)
    shutil.copy(path, plain)
    with h5py.File(plain, "r+") as h5:
        del h5["sensors"]  # its default would be the first mesh's force
    shutil.copy(path, quiet)
    with h5py.File(quiet, "r+") as h5:  # the sun's mesh order alone, as a noise-free healthy sun hears it
        sun, carrier = h5["bodies/sun/angle"][()], h5["bodies/carrier/angle"][()]
        h5["sensors/top/acceleration"][...] = np.cos(24 * (sun - carrier))
    settings = MonitorSettings(shafts=("sun",))
    assert monitor(path, settings, baseline=[other]).baseline_records["sun"] == 1
    with pytest.raises(FlexgearError, match=r"--baseline .*plain.h5: .*read at the analysed signal, "
                                            r"sensors/top/acceleration"):
        monitor(path, settings, baseline=[plain])
    with pytest.raises(ConfigError, match=r"--baseline .*run.h5: the result under analysis itself"):
        monitor(path, settings, baseline=[path])
    with pytest.raises(ConfigError, match=r"--baseline .*other.h5: given twice"):
        monitor(path, settings, baseline=[other, other])
    with pytest.raises(ConfigError, match=r"--baseline .*quiet.h5: sun's residual signal is numerically zero"):
        monitor(path, settings, baseline=[quiet])


def test_moments_of_a_numerically_empty_difference_signal_are_undefined(tmp_path):
    """Planet 1 vibrates at its mesh order modulated once per revolution: its TSA is the mesh
    order and the first-order sidebands, its difference signal only resampling round-off, whose
    FM4, M6A and M8A would be noise: they are left undefined, with the reason."""
    path = tmp_path / "planetary.h5"
    md.write_planetary(path, duration=1.0, background=0.0)
    sa = monitor(path, MonitorSettings(shafts=("planet1",))).shafts["planet1"]
    assert all(sa.indicators[k] is None and "numerically zero" in sa.notes[k] for k in ("fm4", "m6a", "m8a"))
    assert sa.indicators["energy_ratio"] < 1e-4 and sa.indicators["ser"] == pytest.approx(0.4, rel=1e-4)


def test_a_faulty_run_keeps_its_planet_averages_and_a_rotating_force_has_no_carrier_fm0(tmp_path):
    """A spalled sun (the preset's) in lumped MERCURY 1-A with its housing sensors, 1 s: the
    carrier's speed varies a little, so the planet windows cover their least covered angle 0.9999
    times, not once, and the planets are still averaged at --min-averages 1 (they were skipped:
    a healthy run's coverage, 1 - 1e-10, passed). In the healthy set the sun-planet force turns
    with the carrier: its mesh lines sit on the carrier's sidebands, and the carrier's FM0 and
    SER, which divide by the mesh line, are undefined (they read 2.8e11 and 1.0e12); the sun's
    FM0 is defined, its SER not: its mesh line stands 2.6 times above the median line of what its
    average leaves of the turning force, which its sidebands would read (SER 2.3 of it)."""
    import flexgear
    from flexgear.config import load_config

    cfg = load_config("mercury_1a_sensors")
    cfg.model = "lumped"
    cfg.faults = load_config("mercury_1a_sun_spall").faults
    path = tmp_path / "sun_spall.h5"
    flexgear.save(flexgear.run(cfg), path)
    with warnings.catch_warnings():  # the sun's fault, not synchronous with the carrier, leaks into its average
        warnings.filterwarnings("ignore", message=".*differs between the record's two halves")
        rep = monitor(path, MonitorSettings(signal="sensors/side/housing_path"))
    for p in ("planet1", "planet2", "planet3"):
        assert 1 - 1e-3 < rep.shafts[p].average.averages < 1 - 1e-9, p
    healthy = load_config("mercury_1a")
    healthy.model = "lumped"
    flexgear.save(flexgear.run(healthy), tmp_path / "healthy.h5")
    with pytest.warns(UserWarning, match="differs between the record's two halves"):
        rot = monitor(tmp_path / "healthy.h5", MonitorSettings(signal="meshes/sun-planet1/force_global:1")).shafts
    for name in ("fm0", "ser"):
        assert rot["carrier"].indicators[name] is None and "turning with the carrier" in rot["carrier"].notes[name]
    assert rot["sun"].indicators["fm0"] > 0
    assert rot["sun"].indicators["ser"] is None and "times above the TSA's median line" in rot["sun"].notes["ser"]


def test_planet_window_longer_than_the_passing_period_is_refused(tmp_path):
    path = tmp_path / "planetary.h5"
    md.write_planetary(path, duration=0.6)
    with pytest.raises(ConfigError, match=r"--window-teeth = 23: .*planet passing period.* at most 22"):
        monitor(path, MonitorSettings(window_teeth=23))


def test_too_few_revolutions_for_the_averages(tmp_path):
    """0.3 s: each planet passes the sensor twice, too few for windows to reach all 21 teeth: the
    planets are reported as skipped naming --min-averages, and an error when asked for."""
    path = tmp_path / "short.h5"
    md.write_planetary(path, duration=0.3)
    rep = monitor(path)
    assert set(rep.shafts) == {"sun", "carrier"}
    assert "--min-averages" in rep.skipped["planet1"]
    with pytest.raises(ConfigError, match=r"--shafts planet2: .*--min-averages = 1"):
        monitor(path, MonitorSettings(shafts=("planet2",)))
    with pytest.raises(ConfigError, match="--min-averages"):
        monitor(path, MonitorSettings(min_averages=4.0, shafts=("carrier",)))


def test_a_record_shorter_than_a_revolution_of_the_reference_shaft_is_an_error(tmp_path, capsys):
    """The order and envelope spectra resample against the reference shaft (the carrier here,
    8 Hz): 0.02 s holds 0.16 of its revolutions, a named error with the duration one takes, also
    from the command (no traceback)."""
    from flexgear.app.cli import main

    path = tmp_path / "short.h5"
    md.write_planetary(path, duration=0.02)
    with pytest.raises(ConfigError, match=r"carrier, the reference shaft of the order and envelope spectra: the "
                                          r"record holds 0.159 revolutions.*one revolution takes 0.125 s"):
        monitor(path)
    assert main(["monitor", str(path), "-o", str(tmp_path / "mon")]) == 2
    assert "flexgear: error: carrier, the reference shaft" in capsys.readouterr().err
    assert not (tmp_path / "mon").exists()


def test_unknown_or_unusable_signal_paths_are_named(tmp_path):
    path = tmp_path / "planetary.h5"
    md.write_planetary(path, duration=0.3)
    with pytest.raises(FlexgearError, match=r"--signal 'meshes/planet9-ring/force_global:1': no dataset .* "
                                            r"signals of 3000 samples in this file: .*sensors/top/acceleration"):
        monitor(path, MonitorSettings(signal="meshes/planet9-ring/force_global:1"))
    with pytest.raises(FlexgearError, match=r"has 2 columns; give one as bodies/planet1/position:J"):
        monitor(path, MonitorSettings(signal="bodies/planet1/position"))
    with pytest.raises(FlexgearError, match="is 1-D; drop ':1'"):
        monitor(path, MonitorSettings(signal="sensors/top/acceleration:1"))
    with pytest.raises(ConfigError, match=r"--band = 100 6000 Hz: .*Nyquist"):
        monitor(path, MonitorSettings(band_hz=(100.0, 6000.0)))
    import h5py

    with h5py.File(path, "r+") as h5:
        h5.attrs["passband_hz"] = 1200.0  # a record that states its trustworthy band
    with pytest.raises(ConfigError, match=r"--band = 100 1400 Hz: .*above the record's trustworthy band, 1200 Hz"):
        monitor(path, MonitorSettings(band_hz=(100.0, 1400.0)))
    with pytest.raises(ConfigError, match="--planet-window = 'kaiser'"):
        monitor(path, MonitorSettings(planet_window="kaiser"))
    with pytest.raises(ConfigError, match="--shafts planet7: not a shaft"):
        monitor(path, MonitorSettings(shafts=("planet7",)))


def test_the_command_refuses_bad_input_before_writing(tmp_path, capsys):
    from flexgear.app.cli import main

    path = tmp_path / "planetary.h5"
    md.write_planetary(path, duration=0.3)
    out = tmp_path / "out"
    for args, message in ((["--signal", "nope"], "--signal 'nope': no dataset"),
                          (["--window-teeth", "40"], "--window-teeth = 40"),
                          (["--min-averages", "0"], "--min-averages = 0.0: must be > 0"),
                          (["--severity", "faults.sun.depth"], "not a flexgear batch directory")):
        assert main(["monitor", str(path), "-o", str(out), *args]) == 2
        assert message in capsys.readouterr().err
        assert not out.exists()


# --------------------------------------------------------------------------- indicators

def test_indicators_of_gaussian_noise():
    """Gaussian: kurtosis 3, m6/m2^3 = 15, m8/m2^4 = 105 (within 6 standard errors at 2^22 samples)."""
    x = np.random.default_rng(1).normal(0.0, 2.0, 2 ** 22)
    assert ind.kurtosis(x) == pytest.approx(3.0, abs=0.015)
    assert ind.fm4(x) == pytest.approx(3.0, abs=0.015)
    assert ind.m6a(x) == pytest.approx(15.0, rel=0.02)
    assert ind.m8a(x) == pytest.approx(105.0, rel=0.05)
    assert ind.rms(x) == pytest.approx(2.0, rel=2e-3)


def test_indicators_of_a_pure_tone():
    """a cos: RMS a/sqrt(2), crest factor sqrt(2), kurtosis 3/2, m6/m2^3 = 5/2, m8/m2^4 = 35/8;
    at the mesh order: FM0 = 2 and no sidebands (SER 0)."""
    n, z = 960, 24
    x = 3.0 * np.cos(z * 2 * np.pi * np.arange(n) / n)
    assert ind.rms(x) == pytest.approx(3.0 / math.sqrt(2), rel=1e-12)
    assert ind.crest_factor(x) == pytest.approx(math.sqrt(2), rel=1e-12)
    assert ind.kurtosis(x) == pytest.approx(1.5, rel=1e-12)
    assert ind.m6a(x) == pytest.approx(2.5, rel=1e-12)
    assert ind.m8a(x) == pytest.approx(35 / 8, rel=1e-12)
    assert ind.fm0(x, z) == pytest.approx(2.0, rel=1e-12)
    assert ind.sideband_energy_ratio(x, z) == pytest.approx(0.0, abs=1e-12)


def test_indicators_of_an_impulse_train():
    """One unit impulse every P samples: crest factor sqrt(P); about its mean the values are
    1 - 1/P once and -1/P P - 1 times, so m_k = ((1 - 1/P)^k + (P - 1)(-1/P)^k) / P and the
    kurtosis is (P^2 - 3P + 3)/(P - 1)."""
    p = 50
    x = np.zeros(100 * p)
    x[::p] = 1.0
    m = {k: ((1 - 1 / p) ** k + (p - 1) * (-1 / p) ** k) / p for k in (2, 4, 6, 8)}
    assert ind.crest_factor(x) == pytest.approx(math.sqrt(p), rel=1e-12)
    assert ind.kurtosis(x) == pytest.approx((p * p - 3 * p + 3) / (p - 1), rel=1e-12)
    assert ind.m6a(x) == pytest.approx(m[6] / m[2] ** 3, rel=1e-12)
    assert ind.m8a(x) == pytest.approx(m[8] / m[2] ** 4, rel=1e-12)


def test_fm0_ser_energy_ratio_and_na4_closed_forms():
    n, z = 1440, 30  # 48 samples per mesh period: u = 2 pi / 3 is a sample
    a = 2 * np.pi * np.arange(n) / n
    # cos u + cos(2u)/2 spans 1.5 (u = 0) to -0.75 (cos u = -1/2): FM0 = 2.25 / 1.5
    assert ind.fm0(np.cos(z * a) + 0.5 * np.cos(2 * z * a), z) == pytest.approx(1.5, rel=1e-12)
    sb = [0.1, 0.05, 0.02, 0.08, 0.04, 0.01]
    x = 2.0 * np.cos(z * a) + sum(s * np.cos((z + d) * a) for s, d in zip(sb, (-1, -2, -3, 1, 2, 3)))
    assert ind.sideband_energy_ratio(x, z) == pytest.approx(sum(sb) / 2.0, rel=1e-12)
    # the same sidebands about the second and third mesh harmonics, each read at its own
    y = x + 0.5 * np.cos(2 * z * a) + sum(s * np.cos((2 * z + d) * a) for s, d in zip(sb[::-1], (-1, -2, -3, 1, 2, 3)))
    y += 0.25 * np.cos(3 * z * a) + 0.03 * np.cos((3 * z - 2) * a)
    assert ind.sideband_energy_ratio(y, z) == pytest.approx(sum(sb) / 2.0, rel=1e-12)
    assert ind.sideband_energy_ratio(y, z, 2) == pytest.approx(sum(sb) / 0.5, rel=1e-12)
    assert ind.sideband_energy_ratio(y, z, 3) == pytest.approx(0.03 / 0.25, rel=1e-12)
    # a mesh line less than SER_FLOOR = 10 times above the median of the other lines (noise, a leak):
    # its sidebands would read that floor, so SER is undefined; 20 times above, it is the sidebands' sum
    far = [q for q in range(4, 700) if min(q % z, z - q % z) > 3]
    for floor, defined in ((0.25, False), (0.05, True)):
        w = y + sum(floor * np.cos(q * a + q) for q in far)
        if defined:
            assert ind.sideband_energy_ratio(w, z) == pytest.approx(sum(sb) / 2.0, rel=1e-9)
        else:
            with pytest.raises(ValueError, match=r"ser: the mesh line at order 30 \(2\) stands less than 10 times "
                                                 r"above the TSA's median line \(0\.2"):
                ind.sideband_energy_ratio(w, z)
    # upper sidebands beyond the record's band are not there to count: refused, not read as 0
    with pytest.raises(ValueError, match=rf"ser3: orders {3 * z} -/\+ 3 do not fit in the TSA's band "
                                         rf"\(orders 1 to {3 * z + 2}\)"):
        ind.sideband_energy_ratio(y, z, 3, max_order=3 * z + 2)
    assert ind.energy_ratio(0.3 * np.cos(7 * a), 2.0 * np.cos(z * a)) == pytest.approx(0.15, rel=1e-12)
    r = np.cos(7 * a) + 0.4 * np.cos(11 * a) ** 3
    k = ind.kurtosis(r)
    assert ind.na4(r) == pytest.approx(k, rel=1e-12)  # no baseline: the residual's kurtosis
    assert ind.na4(r, [r, r]) == pytest.approx(k, rel=1e-12)
    # a healthy baseline of half the amplitude: mean variance (v/4 + v)/2 = 5v/8
    assert ind.na4(r, [0.5 * r]) == pytest.approx(k * (8 / 5) ** 2, rel=1e-12)
    # NA4* (Decker et al. 1994): the baseline's variance v/4 alone, so 16 k; however many
    # healthy records of that variance there are (NA4 moves from (8/5)^2 k towards M^2 k)
    for m in (1, 3, 10):
        assert ind.na4_star(r, [0.5 * r] * m) == pytest.approx(16 * k, rel=1e-12)
    assert ind.na4(r, [0.5 * r] * 10) == pytest.approx(k * (11 / (10 / 4 + 1)) ** 2, rel=1e-12)
    with pytest.raises(ValueError, match=r"na4_star: needs a healthy baseline"):
        ind.na4_star(r, [])


def test_a_residual_at_the_common_factor_orders_is_the_partner_gears():
    """21 and 24 teeth (gcd 3) meet the same teeth every 8 turns of the 21-tooth gear: what
    repeats with the 24-tooth gear stays in its average at the orders 7, 14, 28, 35 (not the
    mesh order 21). A residual made of those lines is the partner's alone (share 1); an impulse,
    a fault of the gear itself, has equal power at every order (share = the broadband one, 4
    of the 37 residual orders 3..40 but 21); co-prime tooth counts have no such orders."""
    from flexgear.monitoring.leaks import common_orders, mostly_partner, partner_share

    n = 2048
    a = 2 * np.pi * np.arange(n) / n
    assert common_orders(21, 24, 40).tolist() == [7, 14, 28, 35]
    partner = sum(np.cos(k * a + k) for k in (7, 14, 28, 35))
    share, broad = partner_share(partner, 21, 24, 40)
    assert share == pytest.approx(1.0, abs=1e-12) and broad == pytest.approx(4 / 37, rel=1e-12)
    impulse = np.zeros(n)
    impulse[0] = 1.0
    assert partner_share(impulse, 21, 24, 40) == pytest.approx((4 / 37, 4 / 37), rel=1e-12)
    assert partner_share(partner, 21, 22, 40) is None and partner_share(np.zeros(n), 21, 24, 40) is None
    assert mostly_partner((share, broad)) and not mostly_partner(partner_share(impulse, 21, 24, 40))


def test_envelope_of_an_amplitude_modulated_tone():
    """(1 + m cos 2 pi f_mod t) cos 2 pi f_c t: the envelope spectrum has m at f_mod (1 %)."""
    t = np.arange(0, 1.0, 1 / FS)
    x = (1 + 0.3 * np.cos(2 * np.pi * 25 * t)) * np.cos(2 * np.pi * 1500 * t) + 0.5 * np.cos(2 * np.pi * 400 * t)
    env = envelope(x, FS, (1200.0, 1800.0))
    f, a = amplitude_spectrum(env[1000:-1000], FS, window="flattop")
    assert line_amplitude(f, a, 25.0, 1.0) == pytest.approx(0.3, rel=0.01)
    with pytest.raises(ValueError, match="need 0 < low < high < fs/2"):
        envelope(x, FS, (1800.0, 1200.0))


# --------------------------------------------------------------------------- results and the command

def _save(result, path):
    from flexgear.results.store import save

    save(result, path)
    return path


def test_monitor_command_on_a_simulated_planetary_result(planetary_result, tmp_path, capsys):
    """`flexgear monitor` on 0.5 s of MERCURY 1-A writes the indicators and figures. The default
    signal is the first mesh's normal force, so the planets not in that mesh are left out; in the
    gears' frame it repeats with the sun and the planet, so their residuals are numerically zero
    (no indicator, no warning: the fixed-frame force's carrier sidebands had read FM4 7.2 for a
    healthy sun), and averaged over the sun's and over the planet's angle in the carrier it peaks
    at a mesh harmonic of each. The mesh's vertical force turns with the carrier: a warning says
    so (its leak makes the sun's residual differ between the record's halves by more than its
    RMS), and the carrier's average holds a line at order 1 of the mean force's magnitude in the
    carrier frame (0.5 %)."""
    from flexgear.monitoring.tsa import tsa_amplitudes
    from flexgear.app.cli import main

    h5 = _save(planetary_result, tmp_path / "results.h5")
    out = tmp_path / "mon"
    assert main(["monitor", str(h5), "-o", str(out)]) == 0
    for name in REPORT_FILES:
        assert (out / name).stat().st_size > 0
    data = json.loads((out / "indicators.json").read_text())
    said = capsys.readouterr().out  # the indicators printed as the JSON holds them, undefined ones explained
    for shaft, entry in data["shafts"].items():
        row = next(line for line in said.splitlines() if line.startswith(f"| {shaft} "))
        cells = [c.strip() for c in row.strip("|").split("|")][1:]
        for cell, name in zip(cells, ind.INDICATORS):
            value = entry["indicators"].get(name)
            assert cell == ("-" if value is None else f"{value:.4g}"), (shaft, name)
            if value is None:
                assert f"- {shaft} {name}: " in said
    first = next(iter(planetary_result.meshes))
    assert data["signal"]["path"] == f"meshes/{first}/normal_force" and data["signal"]["units"] == "N"
    assert data["shafts"]["sun"]["mesh_order"] == 24 and data["shafts"]["carrier"]["mesh_order"] == 66
    in_mesh = [p for p in ("planet1", "planet2", "planet3") if p in first.split("-")]
    assert set(data["shafts"]) == {"sun", "carrier", *in_mesh}
    assert all(p in data["skipped"] for p in {"planet1", "planet2", "planet3"} - set(in_mesh))
    normal = monitor(h5)
    assert len(normal.shafts["sun"].tooth_angles) == 24  # numbered from the recorded contacts
    for shaft, z in (("sun", 24), *((p, 21) for p in in_mesh)):
        assert np.argmax(tsa_amplitudes(normal.shafts[shaft].signals.tsa)) % z == 0
        for name in ("fm4", "na4", "m6a", "m8a"):
            sa = normal.shafts[shaft]
            assert sa.indicators[name] is None and "numerically zero" in sa.notes[name], (shaft, name)
    with pytest.warns(UserWarning, match=r"force_global:1 \(a noise-free simulation\) of \S+results\.h5: the "
                                         r"residual of sun.* differs between the record's two halves") as said:
        rep = monitor(h5, MonitorSettings(signal=f"meshes/{first}/force_global:1"))
    assert said[0].filename == __file__  # the user's line, not flexgear's (errors.user_stacklevel)
    assert rep.shafts["sun"].unsteady > 1.0 and all(sa.unsteady is None for sa in normal.shafts.values())
    force = planetary_result.meshes[first].force_global
    carrier = planetary_result.bodies["carrier"].angle
    in_carrier = np.mean(force[:, 0] * np.exp(-1j * carrier) + 1j * force[:, 1] * np.exp(-1j * carrier))
    assert tsa_amplitudes(rep.shafts["carrier"].signals.tsa)[1] == pytest.approx(abs(in_carrier), rel=5e-3)
    assert main(["monitor", str(h5), "-o", str(out)]) == 2  # refuses to overwrite
    assert "refusing to overwrite" in capsys.readouterr().err


def test_monitor_on_a_simulated_spur_pair(spur_result, tmp_path):
    """Both gears of the spur pair, absolute angles; each gear's TSA of the vertical mesh force
    peaks at a harmonic of its mesh order (24, 21), and the CSV holds every indicator of both."""
    from flexgear.monitoring import write_report

    h5 = _save(spur_result, tmp_path / "results.h5")
    rep = monitor(h5)
    assert list(rep.shafts) == ["pinion", "wheel"]
    assert rep.shafts["wheel"].shaft.mesh_order == 21 and rep.orders.reference == "pinion"
    for shaft, z in (("pinion", 24), ("wheel", 21)):
        assert np.argmax(np.abs(np.fft.rfft(rep.shafts[shaft].signals.tsa))) % z == 0
    written = write_report(rep, tmp_path)
    rows = (tmp_path / "indicators.csv").read_text().splitlines()
    assert len(rows) == 1 + 3 + 2 * len(ind.INDICATORS)
    with pytest.raises(ResultExistsError):
        write_report(rep, tmp_path)
    assert len(written) == len(REPORT_FILES)


def test_indicators_against_fault_severity(tmp_path, capsys):
    """A batch of planetary results with a growing bump on one tooth of planet 1 over a line in its
    difference signal: planet 1's FM4, NA4, M6A and M8A grow with it (a local fault makes the
    difference and residual signals impulsive), planet 2's do not move, and NA4 of the healthy case
    (no other healthy case) is its residual's kurtosis."""
    cases = tmp_path / "batch" / "cases"
    cases.mkdir(parents=True)
    for i, sev in enumerate((0.0, 0.5, 1.0, 2.0)):
        md.write_planetary(cases / f"k{i}.h5", duration=1.0, fault=sev)
        (cases / f"k{i}.json").write_text(json.dumps({"status": "done", "values": {"faults.planet1.depth": sev}}))
    (cases / "k9.json").write_text(json.dumps({"status": "failed", "values": {"faults.planet1.depth": 9.0}}))
    assert [c.severity for c in batch_cases(tmp_path / "batch", "faults.planet1.depth")] == [0.0, 0.5, 1.0, 2.0]
    with pytest.raises(ConfigError, match="--severity 'depth': not a swept key"):
        batch_cases(tmp_path / "batch", "depth")
    table = severity_table(tmp_path / "batch", "faults.planet1.depth",
                           MonitorSettings(shafts=("planet1", "planet2")))
    for name in ("fm4", "na4", "m6a", "m8a"):
        v = table.values("planet1", name)
        assert all(b > a for a, b in zip(v, v[1:])), f"{name}: {v}"
        assert np.ptp(table.values("planet2", name)) < 1e-6 * np.mean(table.values("planet2", name))
    healthy = monitor(cases / "k0.h5", MonitorSettings(shafts=("planet2",)))
    sig = healthy.shafts["planet2"].signals
    assert table.values("planet2", "na4")[0] == pytest.approx(ind.kurtosis(moment_grid(sig.residual, sig.max_order)))
    out = tmp_path / "out"
    out.mkdir()
    paths = write_severity(table, out)
    assert [p.name for p in paths] == ["severity.csv", "severity.json", "severity.png"]
    from flexgear.monitoring.figures import fig_severity

    fig = fig_severity(table)  # every indicator, each over the whole severity range
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert len(shown) == len(ind.INDICATORS) and len({ax.get_xlim() for ax in shown}) == 1
    # an indicator undefined in every case (as SER where no mesh line stands above the floor):
    # its panel says so instead of staying blank
    import copy

    blank = copy.deepcopy(table)
    for report in blank.reports:
        for values in report.values():
            values["ser"] = None
    notes = {name: [t.get_text() for t in ax.texts] for name, ax in zip(ind.INDICATORS, fig_severity(blank).axes)}
    assert any("undefined in every case" in t for t in notes["ser"]) and not notes["fm4"]
    from flexgear.app.cli import main

    assert main(["monitor", str(tmp_path / "batch"), "-o", str(tmp_path / "cli"), "--severity", "faults.planet1.depth",
                 "--shafts", "planet1", "planet2"]) == 0
    said = capsys.readouterr().out
    rows = [line for line in said.splitlines()[said.splitlines().index("planet1:") + 3:] if line.startswith("| ")]
    assert [float(r.split("|")[1]) for r in rows[:4]] == [0.0, 0.5, 1.0, 2.0]
    fm4 = rows[3].split("|")[2 + list(ind.INDICATORS).index("fm4")].strip()
    assert fm4 == f"{table.values('planet1', 'fm4')[3]:.4g}"


def _noisy_batch(tmp_path, cases, seed):
    """A batch directory of synthetic planetary records (md.write_planetary, 1 s) with Gaussian
    noise of 0.05 on the top sensor, one case per (file name, planet 1 fault depth, noise seed)
    of ``cases``; returns its ``cases`` folder."""
    import h5py

    folder = tmp_path / "batch" / "cases"
    folder.mkdir(parents=True)
    rng = np.random.default_rng(seed)
    for name, sev, noise_seed in cases:
        md.write_planetary(folder / f"{name}.h5", duration=1.0, fault=sev)
        with h5py.File(folder / f"{name}.h5", "r+") as h5:
            x = h5["sensors/top/acceleration"]
            x[...] += 0.05 * rng.standard_normal(x.shape)
        (folder / f"{name}.json").write_text(json.dumps({"status": "done", "values": {
            "faults.planet1.depth": sev, "sensors.0.noise_seed": noise_seed}}))
    return folder


def test_repeated_measurements_in_a_severity_table(tmp_path, capsys):
    """A batch over a severity and a noise seed (three repeats each, the case files in hash
    order): the table's rows run by severity, then seed; the seed is a column of the CSV, the
    JSON and the printed table; the files are named as summary.csv names them (relative to the
    batch); the figure draws each case and a line through each severity's mean."""
    import csv

    from flexgear.app.cli import main
    from flexgear.monitoring.figures import fig_severity

    # the case files not in the order of the values
    _noisy_batch(tmp_path, [(f"{(7 * i + 5) % 11:02d}", sev, seed)
                             for i, (sev, seed) in enumerate([(b, s) for b in (0.0, 1.0) for s in (3, 1, 2)])], 3)
    table = severity_table(tmp_path / "batch", "faults.planet1.depth", MonitorSettings(shafts=("planet1",)))
    assert table.severities == [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]
    assert [w["sensors.0.noise_seed"] for w in table.swept] == [1, 2, 3, 1, 2, 3]
    assert all(f.startswith("cases/") and (tmp_path / "batch" / f).is_file() for f in table.files)
    out = tmp_path / "sev"
    assert main(["monitor", str(tmp_path / "batch"), "-o", str(out), "--severity", "faults.planet1.depth",
                 "--shafts", "planet1"]) == 0
    rows = list(csv.DictReader((out / "severity.csv").open()))
    assert [(float(r["severity"]), int(r["sensors.0.noise_seed"])) for r in rows] == [(0, 1), (0, 2), (0, 3),
                                                                                    (1, 1), (1, 2), (1, 3)]
    data = json.loads((out / "severity.json").read_text())
    assert data["cases"][4]["swept"] == {"sensors.0.noise_seed": 2} and data["cases"][4]["not_averaged"] == {}
    assert "| faults.planet1.depth | sensors.0.noise_seed | rms" in capsys.readouterr().out
    fig = fig_severity(table)
    fm4 = np.array(table.values("planet1", "fm4"), dtype=float)
    ax = fig.axes[list(ind.INDICATORS).index("fm4")]
    means = [ln for ln in ax.lines if len(ln.get_xdata()) == 2]
    assert np.allclose(means[0].get_ydata(), [fm4[:3].mean(), fm4[3:].mean()], rtol=1e-12)
    assert any(len(ln.get_xdata()) == 6 and ln.get_linestyle() == "None" for ln in ax.lines)  # every case


def test_na4_star_of_a_faulty_case_does_not_depend_on_how_many_healthy_cases_the_sweep_holds(tmp_path):
    """NA4 normalises by the ensemble's mean variance, the case's own included: with 1 and 3
    healthy noise seeds a faulty case reads more with the larger set, up to ((3 + 1) / (1 + 1))^2
    = 4 times once the fault dominates (a trial's crack: 103 against 291-316). NA4* (Decker et
    al. 1994) divides by the healthy cases' variance alone: the same but for the seeds' scatter
    of that variance, and near the healthy residual's own kurtosis for a healthy case against
    the others."""
    tables = []
    for n_healthy in (1, 3):
        cases = [(f"h{i}", 0.0, i) for i in range(n_healthy)] + [("f", 2.0, 9)]
        _noisy_batch(tmp_path / str(n_healthy), cases, 11)
        tables.append(severity_table(tmp_path / str(n_healthy) / "batch", "faults.planet1.depth",
                                     MonitorSettings(shafts=("planet1",))))
    na4 = [t.values("planet1", "na4")[-1] for t in tables]
    star = [t.values("planet1", "na4_star")[-1] for t in tables]
    assert na4[1] > 1.5 * na4[0], na4  # measured 17.8 and 33.3
    # NA4* moves only with the healthy cases' mean variance (squared; the seeds scatter it by a
    # few %): measured 63.6 and 72.8
    assert abs(star[1] / star[0] - 1) < 0.25 * (na4[1] / na4[0] - 1) and star[0] > 10 * 3, star
    healthy = tables[1].values("planet1", "na4_star")[:3]
    assert all(2.0 < v < 4.5 for v in healthy), healthy
    assert tables[0].values("planet1", "na4_star")[0] is None  # a healthy case with no other: no baseline


def test_a_severity_table_averages_each_healthy_case_once(tmp_path, monkeypatch):
    """Each case's NA4 takes the healthy cases other than itself as baselines: a table of H
    healthy and F faulty cases reads and averages each healthy case once (H averages, not
    H (H - 1) + F H), and gives the NA4 of monitor() run case by case with those baselines."""
    import flexgear.monitoring.analysis as analysis

    cases = _noisy_batch(tmp_path, [(f"k{i}", sev, i) for i, sev in enumerate((0.0, 0.0, 0.0, 1.0, 2.0))], 5)
    settings = MonitorSettings(shafts=("planet1",))
    calls = {"read": 0, "resample": 0}

    def counted(name, f):
        def wrapper(*args, **kwargs):
            calls[name] += 1
            return f(*args, **kwargs)
        return wrapper

    monkeypatch.setattr(analysis, "read_input", counted("read", analysis.read_input))
    monkeypatch.setattr(analysis, "angular_resample", counted("resample", analysis.angular_resample))
    table = severity_table(tmp_path / "batch", "faults.planet1.depth", settings)
    # per case: its own file, its order and envelope spectra (2 resamplings) and planet1's average
    assert calls == {"read": 5 + 3, "resample": 5 * 3 + 3}
    healthy = [cases / f"k{i}.h5" for i in range(3)]
    for i, f in enumerate(table.files):
        path = tmp_path / "batch" / f
        alone = monitor(path, settings, baseline=[p for p in healthy if p != path], skip_empty_baselines=True)
        assert table.values("planet1", "na4")[i] == alone.shafts["planet1"].indicators["na4"]


def test_a_noise_free_healthy_case_does_not_normalise_na4_in_a_severity_table(tmp_path):
    """A batch of noise-free simulations: the healthy case's residual is numerically zero, so it
    gives NA4 no variance and is left out (refusing it would refuse every simulated batch;
    counting it raised NA4 by ((M+1)/M)^2): each faulty case's NA4 is its residual's kurtosis."""
    import h5py

    cases = tmp_path / "batch" / "cases"
    cases.mkdir(parents=True)
    for i, bump in enumerate((0.0, 0.2, 0.4)):
        path = cases / f"k{i}.h5"
        md.write_planetary(path, duration=1.0)
        with h5py.File(path, "r+") as h5:  # the sun's mesh order, and a bump once per sun turn
            rel = h5["bodies/sun/angle"][()] - h5["bodies/carrier/angle"][()]
            d = (rel - 1.0 + np.pi) % (2 * np.pi) - np.pi
            h5["sensors/top/acceleration"][...] = np.cos(24 * rel) + bump * np.exp(-0.5 * (d / 0.05) ** 2)
        (cases / f"k{i}.json").write_text(json.dumps({"status": "done", "values": {"faults.0.depth": bump}}))
    table = severity_table(tmp_path / "batch", "faults.0.depth", MonitorSettings(shafts=("sun",)))
    na4 = table.values("sun", "na4")
    assert na4[0] is None or not np.isfinite(na4[0])  # the healthy case's own residual: undefined
    for i in (1, 2):
        alone = monitor(cases / f"k{i}.h5", MonitorSettings(shafts=("sun",)))
        sig = alone.shafts["sun"].signals
        assert na4[i] == pytest.approx(ind.kurtosis(moment_grid(sig.residual, sig.max_order)), rel=1e-12)


def _depth_batch(tmp_path, edit):
    """A batch directory of synthetic planetary records over ``faults.0.depth`` = 0, 0.5, 1 (1 s
    each), each file edited by ``edit(h5, depth)``; returns its ``cases`` folder."""
    import h5py

    cases = tmp_path / "batch" / "cases"
    cases.mkdir(parents=True)
    for i, depth in enumerate((0.0, 0.5, 1.0)):
        path = cases / f"case{i}.h5"
        md.write_planetary(path, duration=1.0, fault=depth)
        with h5py.File(path, "r+") as h5:
            edit(h5, depth)
        (cases / f"case{i}.json").write_text(json.dumps({"status": "done", "values": {"faults.0.depth": depth}}))
    return cases


def test_a_severity_table_warns_once_per_message_naming_the_cases_by_severity(tmp_path):
    """Every case of a noise-free batch leaks the planets into the sun's average: the table says
    so once, naming the cases by their severity, not once per case by its file's hash (a trial's
    sweep printed eight 400-character warnings, each naming a case file)."""
    def simulated(h5, depth):
        h5.attrs["flexgear_version"] = "test"  # a noise-free simulation: the halves are compared

    _depth_batch(tmp_path, simulated)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        severity_table(tmp_path / "batch", "faults.0.depth", MonitorSettings(shafts=("sun",)))
    leaks = [str(w.message) for w in caught if "differs between the record's two halves" in str(w.message)]
    assert len(leaks) == 1 and leaks[0].startswith("3 of 3 cases (faults.0.depth = 0, 0.5, 1): "), leaks
    assert "case0" not in leaks[0] and ".h5" not in leaks[0]


def test_a_severity_table_charges_a_healthy_baselines_warning_to_its_own_case(tmp_path):
    """A healthy case whose sensor hears less than its measurement noise: the table says so once,
    for that case, with its figures. Read as the other cases' NA4 baseline it gave the warning
    again for the first faulty case ('2 of 3 cases (... = 0, 0.5)' and '1 of 3 cases (0.5)',
    five of three, the healthy file's figures charged to a faulty one). A single monitor call
    names the baseline the warning is about."""
    noise = np.random.default_rng(1).normal(0.0, 30.0, 10000)

    def noisy(h5, depth):  # the healthy case far below its noise, the others well above theirs
        heard = h5["sensors/top/acceleration"][()]
        h5["sensors/top/acceleration_noise_free"] = heard
        h5["sensors/top/acceleration"][...] = heard + (noise if depth == 0.0 else 0.01 * noise)

    cases = _depth_batch(tmp_path, noisy)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        severity_table(tmp_path / "batch", "faults.0.depth", MonitorSettings(shafts=("planet1",)))
    deaf = [str(w.message) for w in caught if "hears less than its measurement noise" in str(w.message)]
    assert len(deaf) == 1 and deaf[0].startswith("1 of 3 cases (faults.0.depth = 0): sensors/top/"), deaf
    with pytest.warns(UserWarning, match=rf"--baseline {cases / 'case0.h5'}: sensors/top/acceleration: the sensor "
                                         "hears less"):
        monitor(cases / "case2.h5", MonitorSettings(shafts=("planet1",)), baseline=[cases / "case0.h5"])


def test_save_figures_draws_what_save_figure_draws(tmp_path):
    """The threaded writer of the monitoring figures gives the pixels of save_figure (RGB), at 300
    dpi, and refuses to overwrite before drawing anything."""
    from PIL import Image

    from flexgear.style import figure, save_figure, save_figures, styled

    @styled
    def make():
        fig = figure(3.5, 2.0, layout=None)
        ax = fig.add_subplot()
        ax.plot(np.sin(np.linspace(0, 9, 200)), color="k")
        ax.set_title("a title")
        return fig

    save_figure(make(), tmp_path / "one.png")
    assert save_figures([(make, tmp_path / "two.png")]) == [tmp_path / "two.png"]
    one, two = Image.open(tmp_path / "one.png"), Image.open(tmp_path / "two.png")
    assert one.size == two.size == (1050, 600)
    np.testing.assert_array_equal(np.asarray(one.convert("RGB")), np.asarray(two))
    with pytest.raises(ResultExistsError):
        save_figures([(lambda: pytest.fail("drawn before the check"), tmp_path / "two.png")])


def test_order_spectra_say_what_their_marks_are(tmp_path):
    """The marks' kinds have a key (above the top panel): mesh orders and their sidebands, in the
    marks' own styles."""
    from matplotlib.colors import to_hex

    from flexgear.monitoring.figures import fig_order_spectra

    path = tmp_path / "run.h5"
    md.write_planetary(path, duration=1.0)
    fig = fig_order_spectra(monitor(path, MonitorSettings(shafts=("sun",))))
    legend = fig.axes[0].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == ["mesh orders k z",
                                                          "sidebands k z -/+ 1 (top panel: to -/+ 3)"]
    drawn = {to_hex(c.get_colors()[0]) for c in fig.axes[0].collections}  # the marks' line collections
    assert {to_hex(h.get_color()) for h in legend.legend_handles} == drawn and len(drawn) == 2


def test_a_faulty_tooth_is_placed_from_its_neighbours_and_a_lumped_record_numbers_none(tmp_path):
    """tsa.png marks a recorded fault where its tooth meshes: from the record, or, for a tooth
    that never meshes (a missing one), a pitch 2 pi / z from its neighbours in the sense the
    record shows. A lumped result's pair slots hold the mesh's force, not numbered teeth: its
    averages number no tooth (every sample read as tooth 0 had put a bogus '0' on the axis)."""
    import flexgear
    from flexgear.monitoring.figures import tooth_angle
    from flexgear.results.store import save

    z, a0 = 24, np.radians(350.0)
    for sense in (1.0, -1.0):
        angles = {k: float(np.mod(a0 - sense * k * 2 * np.pi / z, 2 * np.pi)) for k in range(1, z)}
        assert tooth_angle(angles, 0, z) == pytest.approx(350.0, abs=1e-9)
        assert tooth_angle(angles, 5, z) == pytest.approx(np.degrees(angles[5]))
    assert tooth_angle({}, 0, z) is None
    cfg = flexgear.load_config("spur_pair:lumped")
    cfg.simulation.update(run_in=0.1, duration=0.5)
    path = save(flexgear.run(cfg), tmp_path / "lumped.h5")
    rep = monitor(path)
    assert rep.source.model == "lumped" and all(not sa.tooth_angles for sa in rep.shafts.values())
    import h5py

    with h5py.File(path) as h5:  # and the file says so (it read "tooth index on pinion")
        assert "numbers no teeth" in h5["meshes/pinion-wheel/pair_tooth_a"].attrs["description"]


def test_a_ring_fault_is_marked_on_the_carrier_where_each_planet_meets_it(tmp_path):
    """A ring tooth fault is marked on the carrier's average (the ring turns with no shaft of
    its own: a trial found it marked nowhere), once per planet-ring mesh, the three marks a third
    of a turn apart, and the carrier residual of planet 1's mesh force peaks within a ring tooth
    pitch of planet 1's mark. A lumped result numbers no teeth: no marks."""
    import flexgear
    from flexgear.config import loads_config, preset_path
    from flexgear.monitoring.figures import fig_tsa, tooth_angle

    text = preset_path("mercury_1a").read_text() + """
[[faults]]
kind = "crack"
gear = "ring"
tooth = 10
flank = "left"
depth = 1.0e-3
"""
    cfg = loads_config(text)
    cfg.simulation.update(run_in=0.2, duration=0.5)
    path = flexgear.save(flexgear.run(cfg), tmp_path / "ring.h5")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = monitor(path, MonitorSettings(signal="meshes/planet1-ring/normal_force"))
    sa = rep.shafts["carrier"]
    assert [(t, k, m) for t, k, m, _ in sa.fault_marks] == [(10, "crack", f"planet{n}-ring") for n in (1, 2, 3)]
    marks = [tooth_angle(a, 10, 66) for *_, a in sa.fault_marks]
    gaps = sorted((b - marks[0]) % 360.0 for b in marks[1:])
    assert gaps == pytest.approx([120.0, 240.0], abs=1.0), marks
    res = sa.signals.residual
    peak = 360.0 * np.argmax(np.abs(res)) / res.size
    assert abs((marks[0] - peak + 180.0) % 360.0 - 180.0) < 360.0 / 66, (marks, peak)
    labels = [t.get_text() for t in fig_tsa(rep).axes[2 * list(rep.shafts).index("carrier")].texts]
    assert sum("ring crack, tooth 10" in t for t in labels) == 3, labels
    lumped = loads_config('model = "lumped"\n' + text)
    lumped.simulation.update(run_in=0.2, duration=0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = monitor(flexgear.save(flexgear.run(lumped), tmp_path / "lumped.h5"))
    assert all(sa.fault_marks == [] for sa in rep.shafts.values())


@pytest.mark.parametrize("flank", ["left", "right"])
def test_a_planet_fault_is_marked_where_its_flank_meshes(tmp_path, flank):
    """A planet tooth's flanks meet different mates: with the presets' drive the sun loads the
    left flank and the ring the right one (config.faults.loaded_flanks, from the set's
    kinematics). A spall on planet 1's tooth 3 is marked on the mesh that loads its flank, at the
    angle where its residual peaks (within a tooth pitch), whichever mesh's force is averaged; the
    mark had been put where the tooth meets the mate of the signal's mesh, half a planet turn off
    for the other flank (a trial's planet crack: mark at 318 deg, event at 138 deg). The spall
    repeats with planet 1: its residual is the same in the record's two halves; in the sun's
    average it is another gear's content, which the average does not cancel, and a warning says
    so."""
    import flexgear
    from flexgear.config import loads_config, preset_path
    from flexgear.config.faults import loaded_flanks
    from flexgear.monitoring.leaks import UNSTEADY
    from flexgear.monitoring.figures import tooth_angle

    cfg = loads_config(preset_path("mercury_1a").read_text() + f"""
[[faults]]
kind = "spall"
gear = "planet"
planet = 1
tooth = 3
flank = "{flank}"
start_radius = 20.5e-3
end_radius = 21.5e-3
depth = 50.0e-6
""")
    cfg.simulation.update(run_in=0.1, duration=0.4)
    sign = 1 if flank == "left" else -1
    loads = [m for m in ("sun-planet1", "planet1-ring")
             if loaded_flanks(cfg)[m][0 if m.startswith("planet1") else 1] == sign]
    path = flexgear.save(flexgear.run(cfg), tmp_path / "spall.h5")
    pitch = 360.0 / 21
    for signal in ("meshes/sun-planet1/normal_force", "meshes/planet1-ring/normal_force"):
        with pytest.warns(UserWarning, match=r"the residual of sun.* differs between the record's two halves"):
            rep = monitor(path, MonitorSettings(signal=signal))
        sa = rep.shafts["planet1"]
        (tooth, kind, mesh, angles), = sa.fault_marks
        assert (tooth, kind) == (3, "spall") and [mesh] == loads, signal
        mark = tooth_angle(angles, 3, 21)
        res = sa.signals.residual
        peak = 360.0 * np.argmax(np.abs(res)) / res.size
        assert abs((mark - peak + 180.0) % 360.0 - 180.0) < pitch, (signal, mark, peak)
        # the spall repeats with planet 1, whose residual is the same in both halves of the record;
        # in the sun's average it is content of another gear, which the average does not cancel
        assert sa.unsteady < 0.01 and rep.shafts["sun"].unsteady > UNSTEADY, (sa.unsteady, rep.shafts["sun"].unsteady)


def test_a_default_sensor_that_hears_almost_nothing_is_named_with_the_loudest(tmp_path):
    """The default signal is the file's first sensor signal; where it is below 1 % of the RMS of
    another sensor signal of the same unit (a trial's preset: its top sensor heard 2.8e-5 of the
    side one, and FM4 and NA4 came out undefined without a word), a warning names the loudest and
    --signal; a signal the user names is taken as it is."""
    import h5py

    path = tmp_path / "two_sensors.h5"
    md.write_planetary(path)
    with h5py.File(path, "a") as h5:
        quiet = h5["sensors/top/acceleration"][()]
        h5["sensors/top/acceleration"][...] = 1e-3 * quiet
        h5["sensors/zside/acceleration"] = quiet
        h5["sensors/zside/acceleration"].attrs["units"] = "m/s^2"
    with pytest.warns(UserWarning, match=r"sensors/top/acceleration, the default signal .* under 1% of the RMS "
                                         r"of sensors/zside/acceleration .* --signal sensors/zside/acceleration"):
        monitor(path, MonitorSettings(shafts=("sun",)))
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        monitor(path, MonitorSettings(signal="sensors/top/acceleration", shafts=("sun",)))


def test_the_envelope_key_stays_off_the_spectrum_and_units_are_typeset(tmp_path):
    """The envelope figure's key of marked orders lies above the panel (inside, at its top right,
    it hid a fault's line at carrier order 33), and units show powers as superscripts (m/s²), as
    published figures write them."""
    from flexgear.monitoring.figures import fig_envelope
    from flexgear.style import unit_label

    assert unit_label("m/s^2") == "m/s\u00b2" and unit_label("m s^-1") == "m s\u207b\u00b9"
    assert unit_label("N/mm^1.5") == "N/mm^1.5" and unit_label("N") == "N"
    path = tmp_path / "planetary.h5"
    md.write_planetary(path)
    fig = fig_envelope(monitor(path))
    ax = fig.axes[0]
    renderer = fig.canvas.get_renderer()
    panel = ax.get_window_extent(renderer)
    key = next(t for t in ax.texts if t.get_text().startswith("orders marked"))
    assert key.get_window_extent(renderer).y0 >= panel.y1 - 0.5
    assert "m/s\u00b2" in ax.get_ylabel()
