"""Rigid-body simulations against expected physics (shortened runs of the presets).

Expected values come from kinematics and statics (docs/paper_parameters.md), never from
flexgear's own output: mesh frequency z f, carrier frequency f_s z_s/(z_s + z_r), normal
tooth force T / r_b, sun torque T_c / (1 + z_r/z_s), per-planet force T_s / (N r_b,s).
"""
import math

import numpy as np
import pytest

from flexgear.dynamics.model.assembly import build_model
from flexgear.errors import DivergenceError
from flexgear.results.store import load, save
from flexgear.app.run import run
from flexgear.results.signals import amplitude_spectrum, find_peaks, line_amplitude

from conftest import short


# ----------------------------------------------------------------------------- spur pair
def test_spur_pair_transmits_the_tooth_ratio(spur_result):
    r = spur_result
    f_pin = r.bodies["pinion"].angular_velocity.mean() / (2 * math.pi)
    f_wheel = r.bodies["wheel"].angular_velocity.mean() / (2 * math.pi)
    assert f_pin == pytest.approx(10.0, rel=1e-9)
    assert f_wheel == pytest.approx(-10.0 * 24 / 21, rel=1e-5)
    # the angle, not only the speed, follows the ratio up to the elastic tooth deflection
    th_p = r.bodies["pinion"].angle - r.bodies["pinion"].angle[0]
    th_w = r.bodies["wheel"].angle - r.bodies["wheel"].angle[0]
    rb_w = 21e-3 * math.cos(math.radians(20))
    assert np.max(np.abs(th_w + th_p * 24 / 21)) * rb_w < 20e-6  # < 20 um on the base circle


def test_spur_pair_mean_normal_force_is_torque_over_base_radius(spur_result):
    rb_w = 21e-3 * math.cos(math.radians(20))
    expected = 200.0 / rb_w  # 10.14 kN
    assert expected == pytest.approx(10.14e3, rel=1e-3)
    F = spur_result.meshes["pinion-wheel"].normal_force
    assert F.mean() == pytest.approx(expected, rel=0.02)  # 0.7 % above: tip-corner contact (docs/validation.md)
    # drive torque: 200 Nm x 24/21 plus the power dissipated by the contact damping (>= 0)
    T = spur_result.bodies["pinion"].torque.mean()
    assert 200 * 24 / 21 <= T <= 1.02 * 200 * 24 / 21


def test_spur_pair_spectrum_shows_mesh_harmonics(spur_result):
    r = spur_result
    fy = r.meshes["pinion-wheel"].force_global[:, 1]
    f, A = amplitude_spectrum(fy, r.fs, window="hann")
    df = f[1] - f[0]
    peaks = find_peaks(f, A, 4, fmin=100.0, min_separation_hz=50.0)
    got = sorted(p.freq for p in peaks)
    for k, fk in enumerate(got, start=1):
        assert abs(fk - 240.0 * k) <= df  # 240, 480, 720, 960 Hz within one bin


def test_spur_pair_force_acts_on_the_line_of_action(spur_result):
    m = spur_result.meshes["pinion-wheel"]
    ang = np.degrees(np.arctan2(np.abs(m.force_global[:, 0]), np.abs(m.force_global[:, 1])))
    assert np.median(ang) == pytest.approx(20.0, abs=0.2)  # horizontal centre line: LOA at 20 deg from vertical


def test_time_step_convergence():
    """The default step is converged: halving it changes the force spectrum below 2.5 kHz little."""
    a = run(short("spur_pair", 0.05, run_in=0.05))
    b = run(short("spur_pair", 0.05, run_in=0.05, step=1.25e-5))
    fa = a.meshes["pinion-wheel"].normal_force
    fb = b.meshes["pinion-wheel"].normal_force
    assert np.std(fa - fb) < 0.1 * np.std(fb)
    assert fa.mean() == pytest.approx(fb.mean(), rel=1e-3)


# ----------------------------------------------------------------------------- planetary
def test_carrier_frequency_and_planet_circle(planetary_result):
    r = planetary_result
    fc = r.bodies["carrier"].angular_velocity.mean() / (2 * math.pi)
    assert fc == pytest.approx(30.0 * 24 / 90, rel=0.005)  # 8 Hz (Eq. 7)
    pos = [r.bodies[f"planet{k}"].position for k in (1, 2, 3)]
    for p in pos:
        np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), 0.045, atol=1e-6)
    ang = [np.arctan2(p[:, 1], p[:, 0]) for p in pos]
    for i, j in ((0, 1), (1, 2), (2, 0)):
        d = np.degrees(np.angle(np.exp(1j * (ang[j] - ang[i]))))
        np.testing.assert_allclose(d, 120.0, atol=1e-3)


def test_planetary_static_equilibrium(planetary_result):
    r = planetary_result
    rb_s = 24e-3 * math.cos(math.radians(20))
    T_sun = 60.0 / (1 + 66 / 24)  # 16 N m
    F = T_sun / (3 * rb_s)  # 236.5 N per planet, same at the sun and ring meshes
    assert F == pytest.approx(236.5, rel=1e-3)
    means = {k: m.normal_force.mean() for k, m in r.meshes.items()}
    for k, v in means.items():
        assert v == pytest.approx(F, rel=0.03), k
    for kind in ("sun-planet{}", "planet{}-ring"):
        vals = [means[kind.format(i)] for i in (1, 2, 3)]
        assert max(vals) / min(vals) - 1 < 0.01
    assert r.bodies["sun"].torque.mean() == pytest.approx(T_sun, rel=0.02)


def test_planet_ring_vertical_force_spectrum(planetary_result):
    """Carrier line at f_a, sidebands at k f_m +- f_a, and the mesh line itself suppressed
    (the paper's Fig. 9): the mesh force turns with the carrier, so its vertical component is
    the mesh force modulated by the carrier angle."""
    r = planetary_result
    fy = r.meshes["planet1-ring"].force_global[:, 1]
    f, A = amplitude_spectrum(fy, r.fs, window="hann")
    df = f[1] - f[0]
    fa, fm = 8.0, 528.0
    top = find_peaks(f, A, 1, fmin=1.0)[0]
    assert abs(top.freq - fa) <= df
    for k in (1, 2):
        lo = line_amplitude(f, A, k * fm - fa, tol_hz=df)
        hi = line_amplitude(f, A, k * fm + fa, tol_hz=df)
        mid = line_amplitude(f, A, k * fm, tol_hz=df)
        floor = np.median(A[(f > k * fm - 100) & (f < k * fm + 100)])
        assert min(lo, hi) > 10 * floor
        assert 20 * math.log10(min(lo, hi) / mid) >= 20.0


def test_planets_are_phase_shifted_by_a_third_of_a_carrier_turn(planetary_result):
    """Planet k's vertical ring force is planet 1's advanced by (k-1)/3 of a carrier turn (the
    paper's Fig. 10): planet 2 is 120 deg ahead, where planet 1 will be a third of a turn later.
    The carrier-frequency component, fitted by least squares at exactly f_a, must show equal
    amplitudes and phases 120 deg apart."""
    r = planetary_result
    t = r.time
    fa = 8.0
    X = np.column_stack([np.cos(2 * np.pi * fa * t), np.sin(2 * np.pi * fa * t), np.ones_like(t)])
    amp, ph = [], []
    for k in (1, 2, 3):
        y = r.meshes[f"planet{k}-ring"].force_global[:, 1]
        (a, b, _), *_ = np.linalg.lstsq(X, y, rcond=None)
        amp.append(math.hypot(a, b))
        ph.append(math.degrees(math.atan2(-b, a)))  # y ~ A cos(2 pi fa t + phase)
    assert max(amp) / min(amp) - 1 < 0.01
    assert amp[0] == pytest.approx(236.5, rel=0.03)  # the whole mesh force turns with the carrier
    for k in (1, 2):
        d = (ph[k] - ph[k - 1] + 180) % 360 - 180
        assert d == pytest.approx(120.0, abs=1.0)


# ----------------------------------------------------------------------------- robustness
def test_divergence_stops_with_time_and_place():
    cfg = short("spur_pair", 0.2, run_in=0.0)
    cfg.contact["stiffness"] = 10.0  # N/mm^1.3: far too soft for 200 N m (the teeth pass through)
    cfg.contact["damping"] = 0.0
    with pytest.raises(DivergenceError, match=r"diverged at t = \d+\.\d+ s in mesh 'pinion-wheel'.*penetration"):
        run(cfg)


def test_a_run_is_a_pure_function_of_its_configuration(tmp_path):
    cfg = short("spur_pair", 0.01, run_in=0.01)
    a = run(cfg)
    path = save(a, tmp_path / "r.h5")
    back = load(path)
    np.testing.assert_array_equal(back.meshes["pinion-wheel"].normal_force, a.meshes["pinion-wheel"].normal_force)
    # the stored configuration reproduces the run exactly
    from flexgear.config import loads_config

    b = run(loads_config(back.config_toml))
    np.testing.assert_array_equal(b.meshes["pinion-wheel"].force_global, a.meshes["pinion-wheel"].force_global)
    assert not any(np.isnan(m.normal_force).any() for m in b.meshes.values())


def test_initial_position_is_centred_and_free_of_interference():
    """The assembled planetary set starts with every tooth pair at zero penetration (the
    phasing formulas place each planet in the middle of its mating gaps)."""
    from flexgear.config import load_config
    from flexgear.dynamics.integrator.simulation import evaluate

    m = build_model(load_config("mercury_1a"))
    q, v = m.initial_state()
    e = evaluate(m, q, v)
    assert e["max_depth"] < 1e-8
