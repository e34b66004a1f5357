"""Elastic shafts of the drive line (issue 8, item 4): :mod:`flexgear.dynamics.model.shafts`.

Checks against independent references: hand values and textbook limits of the beam and
torsion formulas (Roark's Table 8.1; Rayleigh's 17/35 and 33/140 masses), a rigid lever on two
springs solved as its own linear system, the closed-form free vibration of two inertias on a
shaft (w^2 = k (J1 + J2) / (J1 J2)) and of an inertia on a shaft driven at constant speed
(w^2 = k / J), the static balance of a slowly turned spur pair (shaft twist = transmitted
torque / k_t, centre deflection = mesh force / k_lat), and the two-inertia formula for the
lowest mode of the linearised spur pair with a soft output shaft.
"""
import copy
import math
import tomllib

import numpy as np
import pytest

from flexgear.config import load_config, parse_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.model.bodies import ANGLE_FREE, ANGLE_PRESCRIBED, ANGLE_SPRING, FIXED, Body, Model, Profile
from flexgear.gears.contact_tables import pack_gears
from flexgear.dynamics.modal.linearise import linearise
from flexgear.dynamics.modal.system import modes
from flexgear.dynamics.model.shafts import (bearing_compliance, bending_mass, lateral_stiffness,
                                            shaft_bending_stiffness, torsional_stiffness)
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.errors import ConfigError

E, NU, RHO = 2.1e11, 0.3, 7850.0
G = E / (2 * (1 + NU))

SPUR = tomllib.loads(preset_path("spur_pair").read_text())
PLANETARY = tomllib.loads(preset_path("mercury_1a").read_text())
SHAFT = {"diameter": 0.020, "length": 0.100, "bearing_span": 0.060, "bearing_stiffness": 1e8}


def spur(shafts, **changes):
    doc = copy.deepcopy(SPUR)
    doc["shafts"] = copy.deepcopy(shafts)
    for section, values in changes.items():
        doc[section].update(values)
    return parse_config(doc)


# ------------------------------------------------------------------------- formulas
def test_torsional_stiffness_hand_value():
    # d = 20 mm, L = 100 mm, steel: G = 2.1e11 / 2.6 = 80.77 GPa, I_p = pi 0.02^4 / 32 = 1.5708e-8 m^4
    assert torsional_stiffness(G, 0.020, 0.100) == pytest.approx(80.769e9 * 1.5708e-8 / 0.1, rel=1e-4)
    assert torsional_stiffness(G, 0.020, 0.100) == pytest.approx(12687.0, rel=1e-4)


def test_bending_stiffness_limits_and_hand_values():
    EI = E * math.pi * 0.020**4 / 64  # 1649.3 N m^2
    # gear at mid-span of 60 mm: 48 E I / s^3 = 3.665e8 N/m
    assert shaft_bending_stiffness(E, 0.020, 0.060, 0.030, "between") == pytest.approx(48 * EI / 0.060**3, rel=1e-12)
    assert shaft_bending_stiffness(E, 0.020, 0.060, 0.030, "between") == pytest.approx(3.665e8, rel=1e-3)
    # off centre: a = 20, b = 40 mm -> F a^2 b^2 / (3 E I s) (Roark Table 8.1 case 1e); symmetric in a, b
    k = shaft_bending_stiffness(E, 0.020, 0.060, 0.020, "between")
    assert k == pytest.approx(3 * EI * 0.060 / (0.020**2 * 0.040**2), rel=1e-12)
    assert k == pytest.approx(shaft_bending_stiffness(E, 0.020, 0.060, 0.040, "between"), rel=1e-12)
    # overhung: span -> 0 is the cantilever 3 E I / c^3; 35 mm beyond a 60 mm span by hand: 4.253e7 N/m
    assert shaft_bending_stiffness(E, 0.020, 1e-9, 0.035, "overhung") == pytest.approx(3 * EI / 0.035**3, rel=1e-6)
    assert shaft_bending_stiffness(E, 0.020, 0.060, 0.035, "overhung") == pytest.approx(4.253e7, rel=1e-3)


def _lever_on_two_springs(span, x_gear, k1, k2):
    """Deflection at x_gear per newton of a rigid bar on springs k1 (x = 0) and k2 (x = span):
    force and moment balance for the two reactions, then the bar's displacement there."""
    R = np.linalg.solve(np.array([[1.0, 1.0], [0.0, span]]), np.array([1.0, x_gear]))  # sum F, sum M about 0
    u1, u2 = R[0] / k1, R[1] / k2
    return u1 + (u2 - u1) * x_gear / span


@pytest.mark.parametrize("arrangement, position", [("between", 0.030), ("between", 0.015), ("overhung", 0.035)])
def test_bearings_in_series_with_the_shaft(arrangement, position):
    span, kB = 0.060, 1e8
    x = position if arrangement == "between" else span + position
    c_lever = _lever_on_two_springs(span, x, kB, kB)
    assert bearing_compliance(span, position, arrangement, kB) == pytest.approx(c_lever, rel=1e-12)
    k_shaft = shaft_bending_stiffness(E, 0.020, span, position, arrangement)
    assert lateral_stiffness(E, 0.020, span, position, arrangement, kB) == pytest.approx(
        1 / (1 / k_shaft + c_lever), rel=1e-12)
    assert lateral_stiffness(E, 0.020, span, position, arrangement, None) == k_shaft


def test_rayleigh_masses_of_the_shaft():
    area = math.pi * 0.020**2 / 4
    # simply supported, mass at mid-span: 17/35 of the span's mass
    assert bending_mass(RHO, 0.020, 0.060, 0.030, "between") == pytest.approx(17 / 35 * RHO * area * 0.060, rel=1e-12)
    # cantilever (span -> 0) with a tip mass: 33/140 of the overhang's mass
    assert bending_mass(RHO, 0.020, 1e-6, 0.035, "overhung") == pytest.approx(33 / 140 * RHO * area * 0.035, rel=1e-4)


# ------------------------------------------------------------------------- the kernel's shaft spring
def _free_frequency(x, h):
    """Angular frequency of a sampled oscillation from its upward zero crossings [rad/s]."""
    x = x - x.mean()
    i = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    t = (i + x[i] / (x[i] - x[i + 1]) + 1) * h  # linear interpolation, sample k at (k + 1) h
    return 2 * math.pi * (len(t) - 1) / (t[-1] - t[0])


def test_two_inertias_on_a_shaft_vibrate_at_the_two_inertia_frequency():
    J1, J2, k = 1.0e-3, 2.0e-3, 100.0
    a = Body("a", mass=1.0, inertia=J1, joint=FIXED, rotation=ANGLE_FREE)
    b = Body("b", mass=1.0, inertia=J2, joint=FIXED, rotation=ANGLE_SPRING, omega0=1.0, torsion_parent=0,
             torsional_stiffness=k)
    model = Model(bodies=[a, b], meshes=[], tables=pack_gears([]), length_scale=1.0)
    h = 2.0**-17
    r = simulate(model, 0.1, h, 1, alpha=0.0, tol=1e-14)
    th, om = r.body[:, :, 2], r.body[:, :, 5]
    w = math.sqrt(k * (J1 + J2) / (J1 * J2))
    assert _free_frequency(th[:, 1] - th[:, 0], h) == pytest.approx(w, rel=1e-4)
    # the shaft's reaction acts on both bodies: angular momentum is kept
    assert np.allclose(J1 * om[:, 0] + J2 * om[:, 1], J2 * 1.0, rtol=0, atol=1e-9 * J2)


def test_inertia_on_a_shaft_from_a_motor_at_constant_speed():
    J, k, w0 = 2.0e-3, 50.0, 30.0
    motor = Body("motor", mass=0.0, inertia=0.0, joint=FIXED, rotation=ANGLE_PRESCRIBED, omega0=w0,
                 speed=Profile.make(w0))
    disc = Body("disc", mass=1.0, inertia=J, joint=FIXED, rotation=ANGLE_SPRING, omega0=w0 + 2.0, torsion_parent=0,
                torsional_stiffness=k)
    model = Model(bodies=[motor, disc], meshes=[], tables=pack_gears([]), length_scale=1.0)
    h = 2.0**-17
    r = simulate(model, 0.1, h, 1, alpha=0.0, tol=1e-14)
    twist = r.body[:, 1, 2] - r.body[:, 0, 2]
    assert _free_frequency(twist, h) == pytest.approx(math.sqrt(k / J), rel=1e-4)
    # amplitude (w_rel / w); the motor's drive torque is what it applies to the shaft, -k * twist
    # (the disc lagging, twist < 0, is driven forward)
    assert np.abs(twist).max() == pytest.approx(2.0 / math.sqrt(k / J), rel=1e-3)
    assert np.allclose(r.body[:, 0, 6], -k * twist, rtol=0, atol=1e-9 * k)


# ------------------------------------------------------------------------- statics of the spur pair
def test_slowly_turned_spur_pair_twists_and_deflects_its_shafts_as_the_static_balance():
    """Pinion driven at 2 Hz through its input shaft, 200 N m on the load inertia at the end of
    the wheel's output shaft (damping ratio 0.5 so that the start settles within the run). Over
    the last two mesh cycles: input twist x k_t = 200 N m x z_p / z_w, output twist x k_t =
    200 N m (each shaft's driving end ahead of its driven end), each centre's deflection x k_lat = the mesh force on it (within 1 %)."""
    shafts = {"input": dict(SHAFT, damping_ratio=0.5), "output": dict(SHAFT, damping_ratio=0.5)}
    cfg = spur(shafts, drive={"speed_hz": 2.0}, load={"ramp": 0.02})
    model = build_model(cfg)
    names = [b.name for b in model.bodies]
    ip, iw, im, il = (names.index(n) for n in ("pinion", "wheel", "motor", "load"))
    kt = model.attrs["shafts"]["input"]["torsional_stiffness"]
    kl = model.attrs["shafts"]["input"]["lateral_stiffness"]
    assert model.attrs["shafts"]["output"]["torsional_stiffness"] == kt
    zp, zw = cfg.gears["pinion"].z, cfg.gears["wheel"].z
    h, cycle = 1e-4, 1.0 / (zp * 2.0)
    t_end = 0.12 + 2 * cycle
    r = simulate(model, t_end, h, 1)
    n = int(round(2 * cycle / h))
    last = slice(r.nsteps - n, r.nsteps)
    th = r.body[last, :, 2]
    assert np.mean(th[:, im] - th[:, ip]) * kt == pytest.approx(200.0 * zp / zw, rel=1e-2)
    sense = np.sign(model.bodies[iw].omega0)  # the wheel turns clockwise; its load lags behind it
    assert sense < 0 and np.mean(th[:, iw] - th[:, il]) * sense * kt == pytest.approx(200.0, rel=1e-2)
    F_wheel = r.mesh[last, 0, 1:3].mean(axis=0)  # on body b (the wheel); the pinion gets -F
    assert np.hypot(*F_wheel) > 5e3
    pin_p = np.asarray(model.bodies[ip].pin)
    pin_w = np.asarray(model.bodies[iw].pin)
    u_p = r.body[last, ip, 0:2].mean(axis=0) - pin_p
    u_w = r.body[last, iw, 0:2].mean(axis=0) - pin_w
    assert np.allclose(u_p * kl, -F_wheel, rtol=0, atol=1e-2 * np.hypot(*F_wheel))
    assert np.allclose(u_w * kl, F_wheel, rtol=0, atol=1e-2 * np.hypot(*F_wheel))


# ------------------------------------------------------------------------- modal analysis
def test_soft_output_shaft_mode_is_the_two_inertia_frequency():
    """Drive free (``--free-drive``), a stiff input shaft, a soft output shaft (6 mm x 300 mm,
    k_t = 34 N m/rad, far below the mesh's ~1.9e5 N m/rad at the wheel): the lowest elastic mode
    is the gear set (referred to the wheel) against the load inertia on the output shaft,
    w^2 = k (J1 + J2) / (J1 J2), with the shaft inertias lumped as documented."""
    d, L, JL = 0.006, 0.300, 0.0123
    shafts = {"input": {"diameter": 0.020, "length": 0.100, "torsional_stiffness": 1e6, "bending": False},
              "output": {"diameter": d, "length": L, "bending": False, "load_inertia": JL}}
    cfg = spur(shafts)
    rigid = build_model(spur({}))
    model = build_model(cfg)
    lin = linearise(model, n_positions=8, free_drive=True)
    res = modes(lin)
    assert "output shaft torsion" in [s.name for s in lin.springs] and "load.theta" in lin.dofs
    Js_in = RHO * math.pi * 0.020**4 / 32 * 0.100
    Js_out = RHO * math.pi * d**4 / 32 * L
    b = {x.name: x for x in rigid.bodies}
    zp, zw = cfg.gears["pinion"].z, cfg.gears["wheel"].z
    J1 = b["wheel"].inertia + Js_out / 2 + (b["pinion"].inertia + Js_in) * (zw / zp) ** 2  # J_s/3 gear + 2/3 motor
    J2 = JL + Js_out / 2
    k = torsional_stiffness(G, d, L)
    f = math.sqrt(k * (J1 + J2) / (J1 * J2)) / (2 * math.pi)
    elastic = res.frequencies[res.frequencies > 0]
    assert res.frequencies[0] == 0.0  # the free drive line's rigid rotation
    assert elastic[0] == pytest.approx(f, rel=1e-3)
    assert res.dominant_spring(int(np.argmax(res.frequencies > 0)))[0] == "output shaft torsion"


# ------------------------------------------------------------------------- presets and bad input
def test_flexible_presets_have_shafts_and_rigid_presets_do_not():
    for name in ("spur_pair_flexible", "mercury_1a_flexible"):
        cfg = load_config(name)
        assert set(cfg.shafts) == {"input", "output"}
        assert cfg.shafts["input"]["body"] == cfg.drive["body"] and cfg.shafts["output"]["body"] == cfg.load["body"]
    for name in ("spur_pair", "mercury_1a"):
        assert load_config(name).shafts is None
    model = build_model(load_config("spur_pair"))
    assert [b.name for b in model.bodies] == ["pinion", "wheel"] and "shafts" not in model.attrs
    assert all(b.torsion_parent == -1 for b in model.bodies)


def test_configured_planetary_shafts_make_the_sun_float_and_the_carrier_drive_a_load():
    doc = copy.deepcopy(PLANETARY)
    doc["shafts"] = {"input": dict(SHAFT, arrangement="overhung", gear_position=0.035), "output": dict(SHAFT)}
    model = build_model(parse_config(doc))
    names = model.coordinate_names()
    assert {"sun.x", "sun.y", "sun.theta", "carrier.x", "carrier.y", "load.theta"} <= set(names)
    load = model.bodies[[b.name for b in model.bodies].index("load")]
    assert load.torque is not None and model.bodies[load.torsion_parent].name == "carrier"


@pytest.mark.parametrize("shafts, match", [
    ({"input": dict(SHAFT, diameter=0.0)}, r"shafts\.input\.diameter = 0\.0: must be > 0"),
    ({"output": dict(SHAFT, length=-0.1)}, r"shafts\.output\.length = -0\.1: must be > 0"),
    ({"input": dict(SHAFT, diameter=20.0)}, r"shafts\.input\.diameter = 20\.0: must be > 0 and <= 10 m"),
    ({"middle": dict(SHAFT)}, r"unknown shaft\(s\) 'shafts\.middle'"),
    ({"input": dict(SHAFT, body="wheel")}, r"shafts\.input\.body = 'wheel': the input shaft carries drive\.body"),
    ({"input": {"length": 0.1}}, r"shafts\.input\.diameter is required"),
    ({"input": dict(SHAFT, gear_position=0.06)}, r"shafts\.input\.gear_position = 0\.06 m: .*inside the span"),
    ({"output": dict(SHAFT, arrangement="overhung")}, r"shafts\.output\.gear_position .* is required"),
    ({"output": dict(SHAFT, arrangement="floating")}, r"shafts\.output\.arrangement = 'floating': must be one of"),
    ({"input": dict(SHAFT, load_inertia=0.1)}, r"shafts\.input\.load_inertia = 0\.1: the load inertia belongs"),
    ({"input": {"diameter": 0.02, "length": 0.1}}, r"shafts\.input\.bearing_span is required"),
    ({"input": {"diameter": 0.02, "length": 0.1, "bending": False, "bearing_stiffness": 1e8}},
     r"shafts\.input\.bearing_stiffness = 100000000\.0 given with shafts\.input\.bending = false"),
    ({"output": dict(SHAFT, damping_ratio=-0.1)}, r"shafts\.output\.damping_ratio = -0\.1: must be >= 0"),
])
def test_bad_shafts_are_named(shafts, match):
    with pytest.raises(ConfigError, match=match):
        spur(shafts)


def test_shaft_on_the_ring_and_conflicting_supports_are_refused():
    doc = copy.deepcopy(PLANETARY)
    doc["shafts"] = {"output": dict(SHAFT, body="ring")}
    with pytest.raises(ConfigError, match=r"shafts\.output\.body = 'ring': .*load\.body = 'carrier'.*ring is held"):
        parse_config(doc)
    doc = copy.deepcopy(SPUR)
    doc["supports"]["pinion"] = {"stiffness": 1e8}
    doc["shafts"] = {"input": dict(SHAFT)}
    with pytest.raises(ConfigError, match=r"supports\.pinion = .* and shafts\.input with bending"):
        parse_config(doc)
    doc["shafts"]["input"]["bending"] = False  # torsion only: the elastic support stays
    del doc["shafts"]["input"]["bearing_span"], doc["shafts"]["input"]["bearing_stiffness"]
    assert parse_config(doc).shafts["input"]["bending"] is False
    doc = copy.deepcopy(PLANETARY)
    doc.update(model="lumped", shafts={"input": dict(SHAFT)})
    with pytest.raises(ConfigError, match=r"\[shafts\] given with model = 'lumped'"):
        parse_config(doc)


def test_shafts_survive_the_configuration_round_trip():
    from flexgear.config.loader import check_config, config_document

    cfg = load_config("mercury_1a_flexible")
    again = parse_config(config_document(cfg))
    assert again.shafts == cfg.shafts
    cfg.shafts["input"]["diameter"] = -1.0
    with pytest.raises(ConfigError, match=r"shafts\.input\.diameter = -1\.0"):
        check_config(cfg)
