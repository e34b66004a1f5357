"""Sensors of a flexible run through the one-way path models (issue 23, item 3 on flexible gears).

A short flexible spur pair (FE level 0, both gears on their shafts' elastic lateral supports)
with the spur pair's default housing and two sensors. Checks: the loads on the housing are the
bearings' spring-damper forces of the recorded gear frames, and they carry the mesh force less
the gears' momentum change (Newton); each sensor's signal equals the housing's modal
superposition, computed here from the reduced housing's K and M, driven by those loads; the
layout and units are those of rigid runs; the sensors leave the run's forces untouched.
"""
import math

import numpy as np
import pytest
import scipy.linalg as sla

from flexgear.app.run import run
from flexgear.config.loader import loads_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.model.bodies import BEARING
from flexgear.errors import ConfigError
from flexgear.reduction.housing import reduce_housing
from flexgear.results.decimation import settle_samples
from flexgear.results.store import load, save

SENSORS = """
[housing]
damping_ratio = 0.02

[[sensors]]
name = "top"
angle_deg = 90.0
direction = "radial"
quantity = "acceleration"

[[sensors]]
name = "side"
angle_deg = 0.0
direction = "tangential"
quantity = "displacement"
"""


def flexible_spur(sensors: bool = True, coupled: bool = False):
    """The flexible spur pair preset, cheap: FE level 0, 100 kHz cutoff, no modal coordinates,
    a 25 us step, a 10 ms load ramp, 50 ms (12 mesh periods) recorded from the start (no
    run-in: the result holds the loads from the first sample, where the path starts at rest)."""
    text = preset_path("spur_pair_flexible").read_text()
    extra = SENSORS.replace("[housing]\n", "[housing]\ncoupled = true\n" if coupled else "[housing]\n")
    cfg = loads_config(text + (extra if sensors else ""))
    cfg.flexible.update(level=0, cutoff=100e3, dynamic_cutoff=0.0)
    cfg.load["ramp"] = 0.01
    cfg.simulation.update(step=2.5e-5, run_in=0.0, duration=0.05, output_rate=10000.0)
    return cfg


@pytest.fixture(scope="module")
def flex_run(tmp_path_factory):
    cfg = flexible_spur()
    model = build_model(cfg)
    res = run(cfg, model=model)
    f = save(res, tmp_path_factory.mktemp("flexible_sensors") / "results.h5")
    return cfg, model, res, f


def test_flexible_run_writes_sensors_with_units_and_layout(flex_run):
    """``/sensors/<name>/housing_path`` in the sensor's units, with the path's parameters and
    the sensor's definition, and ``/housing_loads/<channel>`` in N, as a rigid run writes them;
    no planet-pass signal on a spur pair."""
    cfg, _, res, f = flex_run
    back = load(f)
    assert res.attrs["model"] == "flexible"
    assert set(back.sensors) == {"top", "side"}
    for s, units in zip(cfg.sensors, ("m/s^2", "m")):
        got = back.sensors[s.name]
        assert list(got.signals) == ["housing_path"]
        attrs = got.signal_attrs["housing_path"]
        assert attrs["units"] == units and "no feedback" in attrs["assumption"]
        assert attrs["channels"] == ["pinion.x", "pinion.y", "wheel.x", "wheel.y"]
        assert got.attrs["quantity"] == s.quantity and got.attrs["point"] == pytest.approx(list(s.point))
        y = got.signals["housing_path"]
        assert y.shape == res.time.shape and np.all(np.isfinite(y)) and np.abs(y).max() > 0
        assert np.array_equal(y, res.sensors[s.name].signals["housing_path"])
    assert list(back.housing_loads) == ["pinion.x", "pinion.y", "wheel.x", "wheel.y"]
    with __import__("h5py").File(f, "r") as h5:
        assert h5["sensors/top/housing_path"].attrs["units"] == "m/s^2"
        assert h5["housing_loads/wheel.y"].attrs["units"] == "N"


def test_flexible_loads_are_the_bearing_forces_and_carry_the_mesh_force(flex_run):
    """Each gear sits on its shaft's elastic lateral support: its load on the seat is the
    spring-damper force ``k (x - pin) + c v`` of its recorded frame (the bore centre; linear, so
    it commutes with the anti-aliasing, 1e-9, past the filter's start-up, where the positions'
    offset from zero rings). Newton on each gear: over the record that force's
    impulse equals the mesh force's on the gear less the change of the gear's momentum
    ``m (v_end - v_start)`` (trapezoidal integrals of the band-limited records; the elastic
    modes' momentum is below 1e-5 of it), 1e-3 of the mesh impulse. A gear whose seat got the
    mesh force directly, or none, fails the first; a sign error, either."""
    cfg, model, res, _ = flex_run
    k0 = settle_samples(int(round(1.0 / (res.fs * res.attrs["step"]))))
    L = {c: v[k0:] for c, v in res.housing_loads.items()}
    F = res.meshes["pinion-wheel"].force_global[k0:]  # the pinion's force on the wheel
    t = res.time[k0:]
    for name, sign in (("pinion", -1.0), ("wheel", 1.0)):
        b = next(x for x in model.bodies if x.name == name)
        assert b.joint == BEARING and b.parent < 0 and b.stiffness > 0
        x, v = res.bodies[name].position[k0:], res.bodies[name].velocity[k0:]
        spring = b.stiffness * (x - np.asarray(b.pin)) + b.damping * v
        got = np.column_stack([L[f"{name}.x"], L[f"{name}.y"]])
        assert np.abs(got - spring).max() <= 1e-9 * np.abs(spring).max()
        impulse = np.trapezoid(sign * F, t, axis=0) - b.mass * (v[-1] - v[0])
        assert np.trapezoid(got, t, axis=0) == pytest.approx(impulse, abs=1e-3 * np.abs(impulse).max())


def modal_response(red, sensors, loads, channels, rate, zeta):
    """Each sensor's quantity (n, n_sensors) from loads (n, n_channels) on the seats, from rest:
    the housing on its feet by modal superposition, ``sum_k phi_k(s) phi_k^T b / (omega_k^2 -
    omega^2 + 2 i zeta omega_k omega) (i omega)^p`` applied on an FFT grid padded far past the
    slowest mode's decay (linear, not circular, convolution)."""
    w2, Phi = sla.eigh(red.body.K + red.ground_stiffness(), red.body.M)
    omega = np.sqrt(w2)
    seats = {shaft: p for p in red.role("seat") for shaft in p.shafts}
    B = np.zeros((red.n, len(channels)))
    for j, ch in enumerate(channels):
        shaft, comp = ch.split(".")
        B[seats[shaft].coordinates["xy".index(comp)], j] = 1.0  # a force at the seat's centre
    C = np.array([red.sensor_row(s.point, s.direction) for s in sensors])
    n = loads.shape[0]
    N = 8 * int(2 ** math.ceil(math.log2(n + 40.0 / (zeta * omega.min()) * rate)))
    f = np.fft.rfftfreq(N, 1.0 / rate)
    w = 2 * math.pi * f
    G = 1.0 / (omega[None, :] ** 2 - w[:, None] ** 2 + 2j * zeta * omega[None, :] * w[:, None])
    U = np.fft.rfft(loads, N, axis=0) @ (Phi.T @ B).T  # (n_f, n_modes)
    Y = (U * G) @ (C @ Phi).T  # (n_f, n_sensors)
    p = np.array([{"displacement": 0, "velocity": 1, "acceleration": 2}[s.quantity] for s in sensors])
    return np.fft.irfft(Y * (1j * w[:, None]) ** p[None, :], N, axis=0)[:n]


def test_flexible_sensor_signal_is_the_housing_response_to_the_recorded_loads(flex_run):
    """The sensors' signals are the reduced housing's response, by modal superposition computed
    here (its own eigenproblem of K + K_feet and M, seat force columns, sensor recovery rows),
    from rest, to the loads the run recorded, within 1e-3 of the signal's peak up to 100 samples
    before the record's end. The path is band-limited (spectral ``(i omega)^p``, housing modes
    above the output Nyquist frequency), so a sample also weighs later loads, with weights
    falling about as 1/k^2; the run drove it with the 40 tail samples that the result drops,
    this reference with loads ending at the last kept sample (measured: 1.6e-4 of the peak for
    the acceleration, 5e-6 for the displacement, up to 100 samples before the end). The mesh
    force fed to the seats in place of the bearing forces is 100 % and 0.7 % off; a channel on
    the wrong seat or axis, a wrong derivative order or a missing foot spring, more."""
    cfg, _, res, _ = flex_run
    channels = list(res.housing_loads)
    loads = np.column_stack([res.housing_loads[c] for c in channels])
    red = reduce_housing(cfg.housing)
    ref = modal_response(red, cfg.sensors, loads, channels, res.fs, cfg.housing.damping_ratio)
    inner = slice(0, res.time.size - 100)
    for j, s in enumerate(cfg.sensors):
        y = res.sensors[s.name].signals["housing_path"]
        assert np.abs(y - ref[:, j])[inner].max() <= 1e-3 * np.abs(y).max(), s.name


def test_flexible_sensors_leave_the_forces_of_the_run_without(flex_run):
    """Sensors are outputs: the mesh forces and the gears' motion are those of the same
    flexible run without them, bit for bit."""
    cfg, model, res, _ = flex_run
    plain = run(flexible_spur(sensors=False), model=model)
    assert not plain.sensors and not plain.housing_loads
    for name, m in plain.meshes.items():
        assert np.array_equal(m.force_global, res.meshes[name].force_global)
    for name, b in plain.bodies.items():
        assert np.array_equal(b.position, res.bodies[name].position)


# --------------------------------------------------------------------------------------------
# the housing coupled in the solver with flexible gears
# --------------------------------------------------------------------------------------------
BEARINGS = "pinion = {stiffness = 5.0e8, damping = 2.0e3}\nwheel = {stiffness = 5.0e8, damping = 2.0e3}"


def coupled_spur(coupled=True, stiffen=1.0, dynamic_cutoff=0.0, duration=0.06):
    """The flexible spur pair (FE level 0, 100 kHz cutoff, 25 us step) on elastic bearings of
    5e8 N/m seated in its default housing (no shafts), sensors in displacement; ``stiffen``
    multiplies the housing's E and foot stiffness (its cutoff by sqrt(stiffen)). 40 ms run-in
    (the load ramps over 10 ms, the housing's lowest mode on its feet, near 1 kHz at 2 %,
    decays in about 8 ms), ``duration`` kept."""
    text = preset_path("spur_pair_flexible").read_text()
    text = text[:text.index("# Shafts")].replace('pinion = "revolute"\nwheel = "revolute"', BEARINGS)
    text += (f"\n[housing]\ndamping_ratio = 0.02\ncoupled = {str(coupled).lower()}\nE = {1.1e11 * stiffen}\n"
             f"foot_stiffness = {1e8 * stiffen}\ncutoff = {50e3 * math.sqrt(stiffen)}\n")
    text += SENSORS[SENSORS.index("[[sensors]]"):].replace('quantity = "acceleration"', 'quantity = "displacement"')
    cfg = loads_config(text)
    cfg.flexible.update(level=0, cutoff=100e3, dynamic_cutoff=dynamic_cutoff)
    cfg.load["ramp"] = 0.01
    cfg.simulation.update(step=2.5e-5, run_in=0.04, duration=duration, output_rate=10000.0)
    return cfg


def test_contact_kernels_count_the_rigid_coordinates_before_the_housing(tmp_path):
    """The coupled housing's coordinates come after the gears' modal coordinates; the contact
    kernels' count of rigid coordinates (:func:`~flexgear.dynamics.flexible.flank.rigid_coordinates`,
    where the modal ones start) must not take them for modes: with modes kept as coordinates it
    is the model's rigid count (n minus the modes would be 47 housing coordinates too many);
    without, the housing's coordinates count among the rigid ones, which no contact reaches."""
    from flexgear.dynamics.flexible.flank import rigid_coordinates
    from flexgear.results.sensors import plan_sensors

    for dynamic_cutoff in (0.0, 1e5):
        cfg = coupled_spur(dynamic_cutoff=dynamic_cutoff)
        model = build_model(cfg)
        plan = plan_sensors(cfg, model, cache_dir=tmp_path)
        assert plan.coupled.shape == (2, model.housing.n) and plan.path is None
        modes = sum(m for _, _, m in model.modal_coordinates())
        n = len(model.coordinate_names())
        assert model.housing_first() == model.rigid_coordinates() + modes == n - model.housing.n
        got = rigid_coordinates(model.pack().flex, n)
        assert got == (model.rigid_coordinates() if modes else n), (dynamic_cutoff, got)
    assert modes == 34  # every mode of both gears under the 100 kHz cutoff


def test_coupled_check_takes_a_bent_shaft_as_an_elastic_seat():
    """The flexible presets carry their gears on their shafts' lateral stiffness: a coupled
    housing accepts them (``supports.* = "revolute"`` there); with ``bending = false`` the
    revolute support is refused, naming it."""
    from flexgear.results.sensors import check_sensor_run

    cfg = flexible_spur(coupled=True)
    check_sensor_run(cfg)
    for spec in cfg.shafts.values():
        spec["bending"] = False
    with pytest.raises(ConfigError, match=r"supports.pinion = 'revolute' with housing.coupled = true"):
        check_sensor_run(cfg)


@pytest.fixture(scope="module", params=[0.0, 1e5], ids=["condensed", "modal"])
def coupled_runs(request):
    """Uncoupled (one-way path), coupled, and coupled with a 100 times stiffer housing; every
    mode condensed, or every mode a solver coordinate (``dynamic_cutoff``)."""
    dc = request.param
    return {name: run(coupled_spur(dynamic_cutoff=dc, **kw)) for name, kw in (
        ("one_way", dict(coupled=False)), ("coupled", {}), ("stiff", dict(stiffen=100.0)))}


@pytest.mark.slow
def test_flexible_stiff_coupled_housing_approaches_uncoupled(coupled_runs):
    """The uncoupled flexible run is the limit of a rigid housing on rigid feet: a 100 times
    stiffer housing shrinks the coupled mesh force's departure from the uncoupled one by far
    more than 10 (first order in the compliance: 100), while the nominal housing departs
    visibly (else the coupling did nothing). With the modes as coordinates, a kernel that took
    housing coordinates for modes would leave the modes without their contact load."""
    f = {k: r.meshes["pinion-wheel"].normal_force for k, r in coupled_runs.items()}
    dep = {k: np.std(f["one_way"] - f[k]) / np.std(f["one_way"]) for k in ("coupled", "stiff")}
    assert dep["coupled"] > 1e-2, dep
    assert dep["stiff"] < dep["coupled"] / 10.0, dep


@pytest.mark.slow
def test_flexible_coupled_sensor_mean_is_the_static_response(coupled_runs):
    """The mean displacement at a sensor is the housing's static response to the mean bearing
    loads, which equilibrium fixes whatever the housing's compliance: the coupled housing's
    signal and the one-way path's agree to 1e-3 of the larger sensor's mean (what is left is
    the mean of the dynamic part over the record). A wrong seat, force share or sensor row
    moves it by order 1."""
    one, cpl = coupled_runs["one_way"], coupled_runs["coupled"]
    means = {n: one.sensors[n].signals["housing_path"].mean() for n in ("top", "side")}
    scale = max(abs(m) for m in means.values())
    for name in ("top", "side"):
        s = cpl.sensors[name]
        assert list(s.signals) == ["housing_coupled"] and s.signal_attrs["housing_coupled"]["units"] == "m"
        assert abs(s.signals["housing_coupled"].mean() - means[name]) < 1e-3 * scale, name


@pytest.mark.slow
@pytest.mark.parametrize("dynamic_cutoff", [0.0, 1e5], ids=["condensed", "modal"])
def test_flexible_coupled_feet_balance_the_shaft_torques(dynamic_cutoff):
    """Steady state with flexible gears: over whole mesh periods (momenta repeat) the feet's
    ground moment is -(T_in + T_out) and their force zero, 0.1 % (issue 23)."""
    from flexgear.dynamics.integrator.simulation import simulate
    from flexgear.dynamics.model.housing import couple_housing, foot_reactions, ground_moment

    cfg = coupled_spur(dynamic_cutoff=dynamic_cutoff)
    model = build_model(cfg)
    red = reduce_housing(cfg.housing)
    couple_housing(model, red)
    per = 160  # steps per mesh period
    integ = simulate(model, 0.08, 1.0 / (cfg.mesh_frequency() * per), 4,
                     condensation=cfg.flexible["condensation"])
    last = slice(integ.nsteps - 10 * per, integ.nsteps)
    q_h = integ.modal[last, -model.housing.n:]
    wheel = [b.name for b in model.bodies].index("wheel")
    t_in = integ.body[last, 0, 6].mean()
    t_out = float(model.bodies[wheel].torque(0.08))
    assert abs(t_in) > 100.0 and abs(t_out) > 100.0
    m_feet = ground_moment(red, q_h).mean()
    assert abs(m_feet + t_in + t_out) < 1e-3 * abs(t_in + t_out), (m_feet, t_in, t_out)
    F = foot_reactions(red, q_h).sum(axis=1).mean(axis=0)
    assert np.hypot(*F) < 1e-3 * integ.mesh[last, 0, 0].mean(), F
