"""Sensors of rigid and lumped runs through the simplified path models (issue 23, items 2-3).

Physical checks: the housing path's signal of a harmonic mesh force, through the loads, the
anti-aliasing and the path, equals the full FE model's harmonic response (1 %); reciprocity of
the path's time-domain response; the planet-pass signal of a constant or mesh-periodic
planet-ring force holds only the lines of McFadden & Smith's rule; in a rigid MERCURY 1-A run the
loads on the housing balance (Newton: the set's momentum stays zero) and the ring's moment
balances the drive and load torques; the sensor spectra hold only the lines planet-passing
theory allows.
"""
import math
import time
from types import SimpleNamespace

import numpy as np
import pytest

from flexgear.app.run import run
from flexgear.config.loader import load_config, loads_config, preset_path
from flexgear.dynamics.model.bodies import ANGLE_FIXED, FIXED, REVOLUTE
from flexgear.errors import ConfigError
from flexgear.gears.housing import Sensor
from flexgear.reduction.housing import reduce_housing
from flexgear.reduction.paths import TransferPath, housing_inputs, planet_pass_signal
from flexgear.results.sensors import SensorPlan, housing_loads, record_sensors, records_of
from flexgear.results.store import load, save
from test_housing import SENSORS, full_model_with_patches, point_row


def body(name, joint=REVOLUTE, parent=-1, pin=(0.0, 0.0), mass=0.0, gear=None):
    return SimpleNamespace(name=name, joint=joint, parent=parent, pin=pin, mass=mass, inertia=0.0, stiffness=0.0,
                           damping=0.0, rotation=ANGLE_FIXED, torsion_parent=-1, theta0=0.0, torsional_stiffness=0.0,
                           torsional_damping=0.0, attrs={"gear": gear or name})


def mesh(name, a, b, internal=False):
    return SimpleNamespace(name=name, a=a, b=b, internal=internal)


@pytest.fixture(scope="module")
def spur_cfg():
    return loads_config(preset_path("spur_pair").read_text() + "\n[housing]\n" + SENSORS)


@pytest.fixture(scope="module")
def spur_red(spur_cfg, tmp_path_factory):
    return reduce_housing(spur_cfg.housing, cache_dir=tmp_path_factory.mktemp("housing"))


# --------------------------------------------------------------------------------------------
# housing path
# --------------------------------------------------------------------------------------------
def full_harmonic(red, sensors, load, f):
    """Full FE model's response at each sensor to the generalised load ``load`` (n,) at f [Hz],
    undamped (patches tied rigidly, feet on their springs)."""
    import scipy.sparse as sp

    from flexgear.fe.elasticity import single_threaded_blas, symmetric_lu

    Kf, Mf, P = full_model_with_patches(red)
    nq = red.body.n_interface
    Kg = sp.diags(np.concatenate([np.diag(red.ground_stiffness())[:nq], np.zeros(Kf.shape[0] - nq)]), format="csc")
    b = np.zeros(Kf.shape[0])
    b[:nq] = load[:nq]
    C = np.array([P.T @ point_row(red, s.point, s.direction) for s in sensors])
    with single_threaded_blas():
        return C @ symmetric_lu(Kf + Kg - (2 * np.pi * f) ** 2 * Mf).solve(b)


def test_harmonic_mesh_force_gives_the_full_fe_harmonic_response(spur_cfg, spur_red):
    """A spur pair's mesh force F0 cos(2 pi f t) along its line of action, recorded at 40 kHz:
    the loads on the seats (pinion -F, wheel +F), anti-aliased to 10 kHz and sent through the
    housing path, give each sensor, once the start transient has died out, the reduced housing's
    harmonic response (amplitude and phase, within the anti-aliasing filter's 0.1 % passband
    ripple) and the full FE model's amplitude within 1 % (undamped: the modal damping changes
    the amplitude by (2 zeta r)^2 / (1 - r^2)^2 relative, r = f / f_mode; the phase it adds is
    the reduced model's), below and between the housing's modes."""
    path = TransferPath(spur_red, spur_cfg.sensors)
    model = SimpleNamespace(bodies=[body("pinion"), body("wheel", pin=(0.045, 0.0))],
                            meshes=[mesh("pinion-wheel", 0, 1)])
    h, oe = 1 / 40000, 4
    ns = 16000
    t = (np.arange(ns) + 1) * h
    d = np.array([math.cos(0.35), math.sin(0.35)])
    B = housing_inputs(spur_red)
    amp = {f"{shaft}.{c}": sgn * d[k] for sgn, shaft in ((-1, "pinion"), (1, "wheel")) for k, c in enumerate("xy")}
    unit = sum(a * B[ch] for ch, a in amp.items())
    fr = path.frequencies
    for f in (0.4 * fr[0], 0.5 * (fr[0] + fr[1]), 0.5 * (fr[1] + fr[2])):
        assert f < 3000.0  # inside the trustworthy band of the 10 kHz output
        F = 250.0 * np.cos(2 * np.pi * f * t)
        mesh_rec = np.zeros((ns, 1, 3))
        mesh_rec[:, 0, 1:3] = F[:, None] * d
        body_rec = np.zeros((ns, 2, 7))
        body_rec[:, 1, 0] = 0.045
        plan = SensorPlan(spur_cfg.sensors, path, False)
        n_out = ns // oe
        keep = slice(n_out // 2, n_out - 50)  # the transient gone (decay e^-17 and more), the filter's edge apart
        out, _ = record_sensors(plan, spur_cfg, model, mesh_rec, body_rec, h, oe, True, keep, 1 / (oe * h))
        to = (np.arange(n_out) + 1) * oe * h
        A = np.column_stack([np.cos(2 * np.pi * f * to[keep]), np.sin(2 * np.pi * f * to[keep])])
        reduced = 250.0 * path.frf(f)[0] @ np.array([amp.get(c, 0.0) for c in path.channels])
        full = 250.0 * full_harmonic(spur_red, spur_cfg.sensors, unit, f)
        for j, s in enumerate(spur_cfg.sensors):
            y = out[s.name].signals["housing_path"]
            c, *_ = np.linalg.lstsq(A, y, rcond=None)
            got = complex(c[0], -c[1])
            assert abs(got - reduced[j]) <= 1e-3 * abs(reduced[j]), (f, s.name, got, reduced[j])
            disp = abs(got) / (2 * np.pi * f) ** {"displacement": 0, "acceleration": 2}[s.quantity]
            assert disp == pytest.approx(abs(full[j]), rel=0.01), (f, s.name)
            assert out[s.name].signal_attrs["housing_path"]["units"] == s.units


@pytest.fixture(scope="module")
def mercury_red(tmp_path_factory):
    cfg = load_config("mercury_1a_sensors")
    return cfg, reduce_housing(cfg.housing, cache_dir=tmp_path_factory.mktemp("housing"))


def test_ring_load_on_tied_bolts_is_balanced_by_the_feet(mercury_red):
    """Statics of the housing path's model: a force or moment of the ring on the housing, through
    its bolts tied to a rigid ring, is balanced by the feet's spring forces (resultant and moment
    about the centre, 1e-9). Every bolt taking the whole load would give 12 times it."""
    cfg, red = mercury_red
    path = TransferPath(red, cfg.sensors, ring=(1.0, 4e-3))
    T = path.tie
    K = T.T @ (red.body.K + red.ground_stiffness()) @ T
    inputs = housing_inputs(red)
    B = T.T @ np.column_stack([inputs[c] for c in ("ring.x", "ring.y", "ring.moment")])
    k = red.housing.foot_stiffness
    feet = red.role("foot")
    for j, unit in enumerate(np.eye(3)):
        q = T @ np.linalg.solve(K, B[:, j])
        R = np.array([-k * q[list(p.coordinates[:2])] for p in feet])
        M = sum(p.centre[0] * r[1] - p.centre[1] * r[0] for p, r in zip(feet, R))
        assert np.allclose([*R.sum(axis=0), M], -unit, atol=1e-9), (j, R.sum(axis=0), M)


def test_ring_sensor_is_reciprocal_with_a_housing_sensor(mercury_red):
    """On the ring tied to the bolts: a point force on the ring read by a housing sensor equals
    the same force at the housing sensor read on the ring (Maxwell-Betti, 1e-10), at frequencies
    below, between and above the housing's modes on its feet."""
    from flexgear.reduction.recovery import rigid_row

    cfg, red = mercury_red
    top = cfg.sensors[0]
    rim = Sensor("rim", "ring", (0.08 * math.cos(0.7), 0.08 * math.sin(0.7)), (math.cos(2.0), math.sin(2.0)),
                 "displacement")
    E = red.ring_coupling()
    ring_force = E @ np.linalg.solve(E.T @ E, rigid_row(rim.point, rim.direction))  # shared out over the bolts
    top_d = Sensor("top", "housing", top.point, top.direction, "displacement")
    f = [300.0, 1300.0, 5000.0]
    a = TransferPath(red, [top_d], inputs={"f": ring_force}, ring=(1.0, 4e-3)).frf(f)[:, 0, 0]
    b = TransferPath(red, [rim], inputs={"f": red.sensor_row(top.point, top.direction)}, ring=(1.0, 4e-3)).frf(f)[:, 0, 0]
    assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max()
    with pytest.raises(ConfigError, match="'rim' is on the ring, not on the housing"):
        TransferPath(red, [rim], ring=None)


def test_path_response_is_reciprocal_in_the_time_domain(spur_cfg, spur_red):
    """Maxwell-Betti through the path's FFT evaluation: a force history at sensor A read at B
    equals the same force at B read at A, to round-off."""
    a, b = spur_cfg.sensors
    ra, rb = spur_red.sensor_row(a.point, a.direction), spur_red.sensor_row(b.point, b.direction)
    sa = Sensor("a", "housing", a.point, a.direction, "acceleration")
    sb = Sensor("b", "housing", b.point, b.direction, "acceleration")
    rng = np.random.default_rng(3)
    F = rng.standard_normal(3000)
    y_ab = TransferPath(spur_red, [sb], inputs={"f": ra}).response({"f": F}, 10000.0)[:, 0]
    y_ba = TransferPath(spur_red, [sa], inputs={"f": rb}).response({"f": F}, 10000.0)[:, 0]
    assert np.abs(y_ab - y_ba).max() <= 1e-10 * np.abs(y_ab).max()


# --------------------------------------------------------------------------------------------
# planet-pass window
# --------------------------------------------------------------------------------------------
def planetary_records(P, z_r, x_of_psi, spr=4800, revs=4):
    """Records of a fixed-ring planetary set on the integration grid: P equally spaced planets at
    45 mm turning with the carrier, ``spr`` steps per revolution, planet i's ring mesh normal
    force ``x_of_psi(psi_i)``; bodies sun, carrier, planets, ring."""
    ns = spr * revs
    psi0 = math.pi / 2 + 2 * np.pi * np.arange(ns)[:, None] / spr
    psi = psi0 + 2 * np.pi * np.arange(P) / P
    nb = P + 3
    body_rec = np.zeros((ns, nb, 7))
    body_rec[:, 2:2 + P, 0] = 0.045 * np.cos(psi)
    body_rec[:, 2:2 + P, 1] = 0.045 * np.sin(psi)
    mesh_rec = np.zeros((ns, 2 * P, 3))
    mesh_rec[:, P:, 0] = x_of_psi(psi)
    bodies = [body("sun"), body("carrier")] + [body(f"planet{i + 1}", parent=1, gear="planet") for i in range(P)] \
        + [body("ring", joint=FIXED)]
    meshes = [mesh(f"sun-planet{i + 1}", 0, 2 + i) for i in range(P)] + \
        [mesh(f"planet{i + 1}-ring", 2 + i, nb - 1, internal=True) for i in range(P)]
    return SimpleNamespace(bodies=bodies, meshes=meshes), mesh_rec, body_rec


@pytest.mark.parametrize("P, z_r, window, width", [(3, 66, "hann", 120.0), (4, 66, "hann", 360.0),
                                                  (4, 66, "rectangular", 90.0), (5, 67, "hann", 200.0)])
def test_planet_pass_lines_follow_mcfadden_smith(P, z_r, window, width):
    """Constant force plus the first two ring-mesh harmonics of each planet through the window,
    at the solver rate, anti-aliased 4:1: the kept whole revolutions hold lines only at carrier
    orders n = 0 (mod P); the others are below 1e-9 of the largest line."""
    spr, oe = 4800, 4
    model, mesh_rec, body_rec = planetary_records(
        P, z_r, lambda psi: 400.0 + 30.0 * np.cos(z_r * psi + 0.3) + 8.0 * np.cos(2 * z_r * psi - 1.0), spr)
    th = math.radians(100.1)  # off the grid of planet angles: no sample on a rectangular window's edge
    sensors = (Sensor("s", "housing", (0.089 * math.cos(th), 0.089 * math.sin(th)), (0.0, 1.0), window=window,
                      window_width_deg=width),)
    per = spr // oe  # output samples per revolution
    keep = slice(per, 3 * per)  # two whole revolutions away from the filter's edges
    out, loads = record_sensors(SensorPlan(sensors, None, True), None, model, mesh_rec, body_rec, 1e-5, oe, True,
                                keep, 1 / (oe * 1e-5))
    assert loads == {}  # no housing path
    y = out["s"].signals["planet_pass"]
    Y = np.abs(np.fft.rfft(y)) / y.size
    orders = np.arange(Y.size) / 2  # two revolutions: bin k is carrier order k / 2
    ok = np.array([o == int(o) and int(o) % P == 0 for o in orders])
    assert Y[~ok].max() < 1e-9 * Y[ok].max()
    # the rule is not vacuous: surviving mesh sidebands are there (the full-width Hann window
    # has W_0, W_+-1 only: with P = 4 the first harmonic 66 +- 1 loses all, the second, 132, stays)
    near = [int(o) for o in orders[ok] if min(abs(o - z_r), abs(o - 2 * z_r)) <= 2 * P]
    assert max(Y[2 * n] for n in near) > 1e-3 * Y[0]
    if z_r % P:  # the tooth-meshing line itself is suppressed (McFadden & Smith's asymmetry)
        assert Y[2 * z_r] < 1e-9 * Y[ok].max()
    if window == "hann":  # band-limited well inside the passband: the window itself at the output instants
        rows = np.arange(spr * 4)[oe - 1::oe][keep]
        psi = np.arctan2(body_rec[rows, 2:2 + P, 1], body_rec[rows, 2:2 + P, 0])
        ref = planet_pass_signal(mesh_rec[rows, P:, 0], psi, th, window, math.radians(width))
        assert np.abs(y - ref).max() < 2e-3 * np.abs(ref).max()


# --------------------------------------------------------------------------------------------
# a rigid MERCURY 1-A run with sensors
# --------------------------------------------------------------------------------------------
def with_model(preset, model):
    text = preset_path(preset).read_text()
    return loads_config(text if model == "rigid" else f'model = "{model}"\n' + text)


def sensors_run(duration, tmp_path, model="rigid"):
    cfg = with_model("mercury_1a_sensors", model)
    cfg.simulation["duration"] = duration
    res = run(cfg)
    f = save(res, tmp_path / "results.h5")
    return cfg, res, f


@pytest.fixture(scope="module", params=["rigid", "lumped"])
def short_run(request, tmp_path_factory):
    """Two carrier revolutions (f_c = 8 Hz) after the run-in, rigid and lumped."""
    return sensors_run(0.25, tmp_path_factory.mktemp("sensors"), request.param)


def test_sensors_are_written_with_units_definition_and_parameters(short_run):
    cfg, res, f = short_run
    back = load(f)
    assert set(back.sensors) == {"top", "side"}
    for s in cfg.sensors:
        got = back.sensors[s.name]
        assert got.attrs["point"] == pytest.approx(list(s.point)) and got.attrs["quantity"] == "acceleration"
        assert list(got.signals) == ["housing_path", "planet_pass"]  # the first one is monitor's default
        hp, pp = got.signal_attrs["housing_path"], got.signal_attrs["planet_pass"]
        assert hp["units"] == "m/s^2" and hp["damping_ratio"] == cfg.housing.damping_ratio
        assert "no feedback" in hp["assumption"] and "ring.moment" in hp["channels"]
        assert pp["units"] == "N" and pp["window"] == "hann" and pp["window_width_deg"] == 180.0
        assert pp["sensor_angle_deg"] == pytest.approx(s.angle_deg)
        for k in got.signals:
            assert np.array_equal(got.signals[k], res.sensors[s.name].signals[k])
            assert got.signals[k].shape == res.time.shape and np.all(np.isfinite(got.signals[k]))
    channels = res.sensors["top"].signal_attrs["housing_path"]["channels"]
    assert list(back.housing_loads) == channels
    assert all(np.array_equal(back.housing_loads[c], res.housing_loads[c]) for c in channels)
    with __import__("h5py").File(f, "r") as h5:
        assert h5.attrs["layout_version"] == 5
        assert h5["sensors/top/housing_path"].attrs["units"] == "m/s^2"
        assert h5["housing_loads/ring.moment"].attrs["units"] == "N m"
        assert h5["housing_loads/sun.x"].attrs["units"] == "N"


def test_sensor_run_keeps_the_forces_of_the_run_without(short_run):
    """Sensors are outputs: the mesh forces are those of the same run without them, bit for bit."""
    cfg, res, _ = short_run
    plain = with_model("mercury_1a", res.attrs["model"])
    plain.simulation["duration"] = cfg.simulation["duration"]
    ref = run(plain)
    for name, m in ref.meshes.items():
        assert np.array_equal(m.force_global, res.meshes[name].force_global)


def test_loads_on_the_housing_balance(short_run):
    """Newton on the whole set: the sun, carrier and ring loads on the housing sum to minus the
    set's momentum rate, zero here (centres fixed, equally spaced planets of one mass); the
    ring's mean moment on the housing equals the drive torque plus the load torque over whole
    carrier revolutions (the set's angular momentum returns), 0.1 %."""
    cfg, res, _ = short_run
    from flexgear.dynamics.lumped.model import build_lumped
    from flexgear.dynamics.model.assembly import build_model

    model = build_lumped(cfg).model if cfg.model == "lumped" else build_model(cfg)
    mesh_rec, body_rec = records_of(res, model)
    ch = ("sun.x", "sun.y", "carrier.x", "carrier.y", "ring.x", "ring.y", "ring.moment")
    L = housing_loads(cfg, model, mesh_rec, body_rec, 1 / res.fs, ch)
    scale = np.abs(mesh_rec[:, :, 1:3]).max()
    assert np.abs(L[:, 0] + L[:, 2] + L[:, 4]).max() < 1e-9 * scale
    assert np.abs(L[:, 1] + L[:, 3] + L[:, 5]).max() < 1e-9 * scale
    drive = res.bodies["sun"].torque.mean()
    load_torque = -cfg.load["torque"]  # resists the carrier's counter-clockwise turn
    assert L[:, 6].mean() == pytest.approx(drive + load_torque, rel=1e-3)
    # the loads the run recorded (computed at every step, then anti-aliased) obey the same laws
    R = res.housing_loads
    for c in "xy":
        assert np.abs(R[f"sun.{c}"] + R[f"carrier.{c}"] + R[f"ring.{c}"]).max() < 1e-9 * scale
    assert R["ring.moment"].mean() == pytest.approx(drive + load_torque, rel=1e-3)


def line_check(res, name, path, allowed, floor):
    """Largest line outside ``allowed`` (a predicate on the carrier order) relative to the
    largest allowed line other than 0 Hz, over the record's whole carrier revolutions."""
    y = res.sensors[name].signals[path]
    fc = res.attrs["carrier_frequency"]
    per = res.fs / fc
    assert abs(per - round(per)) < 1e-9 and abs(y.size / per - round(y.size / per)) < 1e-9
    revs = int(round(y.size / per))
    Y = np.abs(np.fft.rfft(y - y.mean())) / y.size
    band = np.arange(Y.size) / revs * fc <= res.attrs["passband_hz"]
    order = np.arange(Y.size) / revs
    ok = np.array([o == int(o) and allowed(int(o)) for o in order])
    worst = Y[band & ~ok].max() / Y[band & ok].max()
    assert worst < floor, (name, path, worst)
    return worst


def check_lines(res, floor):
    """Planet-passing theory for MERCURY 1-A (P = 3, z_r = 66 = 0 mod 3, f_m = 66 f_c): every
    line is at a whole carrier order (healthy gears repeat every carrier revolution); the
    planet-pass signal only at orders n = 0 (mod 3)."""
    for name in ("top", "side"):
        line_check(res, name, "housing_path", lambda n: True, floor)
        line_check(res, name, "planet_pass", lambda n: n % 3 == 0, floor)


def test_mercury_sensor_lines(short_run):
    check_lines(short_run[1], 1e-6)


@pytest.mark.slow
def test_mercury_sensor_lines_one_second(tmp_path):
    check_lines(sensors_run(1.0, tmp_path)[1], 1e-6)


def test_monitor_works_on_the_sensor_result(short_run, tmp_path):
    """``flexgear monitor`` on the preset's result: the first sensor's housing path by default,
    the planet windows centred on that sensor's angle; the other signal by --signal."""
    from flexgear.app.cli import main
    from flexgear.monitoring.source import read_input

    _, _, f = short_run
    inp = read_input(f)
    assert inp.signal_path == "sensors/top/housing_path" and inp.units == "m/s^2"
    assert inp.sensor_angle_deg == pytest.approx(90.0)
    assert read_input(f, "sensors/side/planet_pass").sensor_angle_deg == pytest.approx(0.0, abs=1e-9)
    assert main(["monitor", str(f), "-o", str(tmp_path / "m")]) == 0
    assert main(["monitor", str(f), "-o", str(tmp_path / "p"), "--signal", "sensors/side/planet_pass"]) == 0
    assert any((tmp_path / "m").iterdir()) and any((tmp_path / "p").iterdir())


def test_bad_sensor_input_names_the_key():
    base = preset_path("mercury_1a").read_text() + "\n[housing]\n[[sensors]]\nname = \"a\"\nangle_deg = 0.0\n"
    for extra, message in (("window = \"kaiser\"\n", r"sensors\[0\].window = 'kaiser': must be one of"),
                           ("window_width_deg = 0.0\n", r"sensors\[0\].window_width_deg = 0.0: must lie in \(0, 360\]"),
                           ("window_width_deg = 400.0\n", r"sensors\[0\].window_width_deg = 400.0"),
                           ("quantity = \"jerk\"\n", r"sensors\[0\].quantity = 'jerk'"),
                           ("body = \"carrier\"\n", r"sensors\[0\].body = 'carrier'")):
        t0 = time.perf_counter()
        with pytest.raises(ConfigError, match=message):
            loads_config(base + extra)
        assert time.perf_counter() - t0 < 5.0


def test_which_path_models_each_sensor_gets(tmp_path):
    """A ring sensor: the planet-pass window, and the housing path when the ring is held by its
    bolts (it moves with them), not on an elastic support; a spur pair's housing sensor: the
    housing path only (no planets)."""
    from flexgear.dynamics.model.bodies import BEARING
    from flexgear.results.sensors import plan_sensors

    cfg = loads_config(preset_path("mercury_1a_sensors").read_text()
                       + '\n[[sensors]]\nname = "rim"\nbody = "ring"\nangle_deg = 45.0\n')
    model, mesh_rec, body_rec = planetary_records(3, 66, lambda psi: 400.0 + 0 * psi, spr=400, revs=2)
    plan = plan_sensors(cfg, model, cache_dir=tmp_path)
    assert [s.name for s in plan.path.sensors] == ["top", "side", "rim"] and plan.path.ring == (0.0, 0.0)
    out, loads = record_sensors(plan, cfg, model, mesh_rec, body_rec, 1e-4, 4, True, slice(0, 200), 2500.0)
    assert list(loads) == list(plan.path.channels)
    assert list(out["rim"].signals) == ["housing_path", "planet_pass"]
    cfg.supports["ring"] = {"stiffness": 1e8, "damping": 1e3}  # the ring on an elastic support
    model.bodies[-1].joint = BEARING
    plan = plan_sensors(cfg, model, cache_dir=tmp_path)
    assert [s.name for s in plan.path.sensors] == ["top", "side"]
    out, _ = record_sensors(plan, cfg, model, mesh_rec, body_rec, 1e-4, 4, True, slice(0, 200), 2500.0)
    assert list(out["rim"].signals) == ["planet_pass"]
    spur = loads_config(preset_path("spur_pair").read_text() + "\n[housing]\n" + SENSORS)
    spur.simulation["duration"] = 0.1
    res = run(spur)
    assert set(res.sensors) == {"top", "side"}
    assert all(list(s.signals) == ["housing_path"] for s in res.sensors.values())
    assert res.sensors["side"].signal_attrs["housing_path"]["units"] == "m"
    assert res.sensors["top"].signal_attrs["housing_path"]["channels"] == ["pinion.x", "pinion.y", "wheel.x", "wheel.y"]


def test_elastic_bearing_passes_the_mesh_force_to_its_seat(tmp_path):
    """A wheel on an elastic bearing (spring-damper to the housing): its seat load is the
    spring-damper force, which on average over the record carries the mesh force on the wheel
    (Newton: the wheel's momentum returns, 0.1 %); the pinion's revolute seat carries the
    opposite force at every sample."""
    text = preset_path("spur_pair").read_text().replace('wheel = "revolute"',
                                                        "wheel = {stiffness = 2.0e8, damping = 2.0e3}")
    cfg = loads_config(text + "\n[housing]\n" + SENSORS)
    cfg.simulation["duration"] = 0.2  # two pinion revolutions (10 Hz)
    res = run(cfg)
    F = res.meshes["pinion-wheel"].force_global  # the pinion's force on the wheel
    L = res.housing_loads
    for k, c in enumerate("xy"):
        assert np.abs(L[f"pinion.{c}"] + F[:, k]).max() < 1e-9 * np.abs(F).max()
        assert L[f"wheel.{c}"].mean() == pytest.approx(F[:, k].mean(), rel=1e-3, abs=1e-3 * np.abs(F).max())
    assert np.abs(L["wheel.x"] - F[:, 0]).max() > 1e-3 * np.abs(F).max()  # it is the spring's, not the mesh's
