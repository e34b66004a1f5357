"""Elastic bearings, an elastically supported ring, and time profiles of speed and torque."""
import math
import warnings

import numpy as np
import pytest

from flexgear.config import loads_config, preset_path
from flexgear.app.run import run


def cfg_from(preset, replace, **sim):
    text = preset_path(preset).read_text()
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new)
    cfg = loads_config(text)
    cfg.simulation.update(**sim)
    return cfg


def test_elastic_bearing_deflects_by_force_over_stiffness():
    k = 2e8
    cfg = cfg_from("spur_pair", [('wheel = "revolute"', f"wheel = {{stiffness = {k}, damping = 2e3}}")],
                   duration=0.1, run_in=0.15)
    r = run(cfg)
    centre = np.array([0.045, 0.0])
    disp = r.bodies["wheel"].position - centre
    F = r.meshes["pinion-wheel"].force_global  # exerted by the pinion on the wheel
    # statics: the bearing carries the tooth force, k * displacement = F
    np.testing.assert_allclose(disp.mean(axis=0) * k, F.mean(axis=0), rtol=0.01, atol=0.01 * np.abs(F).max())
    assert np.hypot(*disp.mean(axis=0)) == pytest.approx(200 / (0.021 * math.cos(math.radians(20))) / k, rel=0.03)


def test_elastically_supported_ring_reacts_the_torque():
    kt = 2e5
    cfg = cfg_from("mercury_1a", [('ring = "fixed"', "ring = {stiffness = 5e8, damping = 5e3, "
                                   f"torsional_stiffness = {kt}, torsional_damping = 20.0}}")],
                   duration=0.125, run_in=0.15)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = run(cfg)
    # ring reaction torque = carrier torque - sun torque = 60 - 16 = 44 N m (clockwise on the ring)
    theta = r.bodies["ring"].angle.mean()
    assert -kt * theta == pytest.approx(44.0, rel=0.03)
    # equally spaced planets: the radial forces on the ring cancel, its centre stays put
    assert np.hypot(*r.bodies["ring"].position.mean(axis=0)) < 1e-7
    assert r.bodies["carrier"].angular_velocity.mean() / (2 * math.pi) == pytest.approx(8.0, rel=0.005)


def test_speed_and_torque_profiles():
    cfg = cfg_from("spur_pair", [("speed_hz = 10.0", "speed_hz = [[0.0, 5.0], [0.2, 10.0], [0.3, 10.0]]"),
                                 ("torque = 200.0 ", "torque = [[0.0, 100.0], [0.2, 100.0], [0.25, 200.0]] ")],
                   duration=0.2, run_in=0.1, antialias=False, synchronous=False)  # plain samples: exact kinematics
    r = run(cfg)
    t = r.time
    # prescribed angle is the exact integral of the piecewise-linear speed
    f = np.interp(t, [0, 0.2, 0.3], [5, 10, 10])
    np.testing.assert_allclose(r.bodies["pinion"].angular_velocity, 2 * np.pi * f, rtol=1e-9)
    ang = 2 * np.pi * np.where(t < 0.2, 5 * t + 12.5 * t**2, 1.5 + 10 * (t - 0.2))
    np.testing.assert_allclose(r.bodies["pinion"].angle - r.bodies["pinion"].angle[0], ang - ang[0], atol=1e-9)
    # the tooth force follows the load torque (quasi-static), T / r_b
    rb = 0.021 * math.cos(math.radians(20))
    F = r.meshes["pinion-wheel"].normal_force
    assert F[(t > 0.12) & (t < 0.2)].mean() == pytest.approx(100 / rb, rel=0.02)
    assert F[t > 0.27].mean() == pytest.approx(200 / rb, rel=0.02)


def test_rattle_at_light_load_uses_both_flanks():
    """Backlash (50 um thinning per gear), a pinion speed oscillating by +-30 % at 40 Hz and a
    light load (0.05 N m): when the pinion decelerates faster than the load can slow the
    wheel (needs J_w alpha = 0.25 N m), the wheel overruns, crosses the backlash and hits its
    back flanks; the mesh alternates drive-flank contact, free flight and back-flank impacts."""
    t = np.arange(0.0, 0.41, 0.001)
    table = ", ".join(f"[{ti:.3f}, {10 + 3 * math.sin(2 * math.pi * 40 * ti):.6f}]" for ti in t)
    cfg = cfg_from("spur_pair", [("speed_hz = 10.0", f"speed_hz = [{table}]"), ("torque = 200.0 ", "torque = 0.05 "),
                                 ("thinning = 0.0 ", "thinning = 50e-6 ")],
                   duration=0.2, run_in=0.2, antialias=False, synchronous=False)  # a speed table: the plain grid
    r = run(cfg)
    m = r.meshes["pinion-wheel"]
    active = m.pair_force > 0
    sides = set(m.pair_side[active].tolist())
    assert sides == {-1, 1}  # drive and back flanks both carry load at times
    free = m.normal_force == 0.0
    assert 0.05 < free.mean() < 0.95  # free flight through the backlash between impacts
    # impacts: far larger than the static load 0.05 / r_b = 2.5 N
    assert m.normal_force.max() > 100 * 0.05 / (0.021 * math.cos(math.radians(20)))
