"""Tooth friction in the rigid (IMPACT) model (issue 24, flexgear.dynamics.integrator.friction):
the frictionless model bit for bit at a zero coefficient, the sliding kinematics and the sign
change at the pitch point, the mesh efficiency against Ohlendorf's closed form, the energy
balance, the time-step convergence of the regularised sign change, outputs.

The spur pair is turned slowly (pinion 2 Hz) with the preset's contact stiffness raised 100
times (1000 times for the efficiency): the closed forms are those of rigid involutes, and the
preset's contact (43 um penetration under the 200 N m load) lets the loaded tip corners touch
the mating flanks about 1 mm before and after the ideal path of contact (with the stiffness x
100, 0.18 mm; x 1000, 0.07 mm)."""
import functools
import math
import warnings

import h5py
import numpy as np
import pytest

import flexgear
from flexgear.config import loads_config, preset_path
from flexgear.config.faults import mesh_pairs
from flexgear.dynamics.integrator.friction import rigid_friction
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.dynamics.model.assembly import build_model
from flexgear.gears.lubrication import loss_factor, roll_angles, surface_speeds
from flexgear.results.store import load, save

SPUR = preset_path("spur_pair").read_text()
T_LOAD = 200.0  # N m on the spur preset's wheel
MU = 0.05


def _text(stiffness=3.0e7, speed=2.0, lub=f"friction_coefficient = {MU}\n"):
    text = SPUR.replace("stiffness = 3.0e5", f"stiffness = {stiffness}").replace("speed_hz = 10.0",
                                                                                  f"speed_hz = {speed}")
    return text + ("\n[lubrication]\n" + lub if lub else "")


@functools.lru_cache(maxsize=None)
def _simulate(stiffness=3.0e7, lub=f"friction_coefficient = {MU}\n", t_end=0.4, h=2.5e-5, speed=2.0):
    """(cfg, model, Integration) of the spur pair (pinion at ``speed`` [Hz]), every step recorded."""
    cfg = loads_config(_text(stiffness, speed, lub))
    model = build_model(cfg)
    return cfg, model, simulate(model, t_end, h, 1, alpha=-0.1, friction=rigid_friction(cfg, model))


def _cycles(integ, model, t0):
    """Step slice from t0 over a whole number of mesh cycles to the end."""
    h = integ.h
    T = 1.0 / model.attrs["mesh_frequency"]
    i0 = int(round(t0 / h))
    return slice(i0, i0 + int(math.floor((integ.nsteps - i0) * h / T) * T / h + 0.5))


def _powers(integ, sl):
    """Mean input (drive torque x pinion speed), output (load torque x wheel speed) and friction
    power over the steps ``sl`` [W]."""
    p_in = np.mean(integ.body[sl, 0, 6] * integ.body[sl, 0, 5])
    p_out = np.mean(T_LOAD * np.abs(integ.body[sl, 1, 5]))
    return p_in, p_out, np.mean(integ.friction["power"][sl, 0])


def _reversals(integ, sl, window=None):
    """Contact positions s [m] where a tooth pair's friction force changes sign between two
    steps (interpolated), each pair followed through the contact slots by its tooth on the
    pinion; with ``window`` (an s grid [m]) the pair's friction force across each change
    interpolated onto it."""
    fr = integ.friction
    s, f = fr["position"][sl, 0], fr["pair_force"][sl, 0]
    tooth = integ.pair_i[sl, 0, :, 0]
    out, prof = [], []
    for z in np.unique(tooth[tooth >= 0]):
        k, c = np.nonzero(tooth == z)
        order = np.argsort(k)
        k, c = k[order], c[order]
        sz, fz = s[k, c], f[k, c]
        for i in np.nonzero((fz[:-1] * fz[1:] < 0) & (np.diff(k) == 1))[0]:
            out.append(sz[i] - fz[i] * (sz[i + 1] - sz[i]) / (fz[i + 1] - fz[i]))
            if window is not None:
                near = np.abs(sz - sz[i]) < 1.5 * np.max(np.abs(window))
                prof.append(np.interp(window, sz[near], fz[near]))
    return np.array(out), np.array(prof)


def test_zero_coefficient_is_the_frictionless_run_bit_for_bit(tmp_path):
    """A constant coefficient of 0 runs the frictionless model: every signal equal bit for bit,
    and the result file carries no friction datasets. With a coefficient the friction outputs
    are written and read back."""
    def run(text):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cfg = loads_config(text)
            cfg.simulation.update(run_in=0.02, duration=0.02)
            return flexgear.run(cfg)

    plain = run(SPUR)
    zero = run(SPUR + "\n[lubrication]\nfriction_coefficient = 0.0\n")
    for name, m in plain.meshes.items():
        z = zero.meshes[name]
        for f in ("normal_force", "force_global", "pair_force", "penetration", "pair_tooth_a"):
            assert np.array_equal(getattr(m, f), getattr(z, f))
        assert z.friction_force is None and z.sliding_speed is None
    for name, b in plain.bodies.items():
        for f in ("angle", "angular_velocity", "position", "torque"):
            assert np.array_equal(getattr(b, f), getattr(zero.bodies[name], f))
    with h5py.File(save(zero, tmp_path / "zero.h5"), "r") as h5:
        assert not {"friction_force", "friction_power", "sliding_speed", "contact_position",
                    "pair_friction_force"} & set(h5["meshes/pinion-wheel"])
    rubs = run(SPUR + f"\n[lubrication]\nfriction_coefficient = {MU}\n")
    back = load(save(rubs, tmp_path / "mu.h5")).meshes["pinion-wheel"]
    m = rubs.meshes["pinion-wheel"]
    for f in ("friction_force", "friction_power", "sliding_speed", "contact_position", "pair_friction_force"):
        assert np.array_equal(getattr(back, f), getattr(m, f), equal_nan=True)
    on = m.pair_force > 0
    # each contact slot's friction force is mu F (|v_s| >> v0 away from the pitch point)
    far = on & (np.abs(m.sliding_speed) > 5 * 0.01)
    assert np.allclose(np.abs(m.pair_friction_force[far]), MU * m.pair_force[far], rtol=1e-3)
    assert np.all(np.isnan(m.sliding_speed[~on]))
    assert 0.97 < m.attrs["mesh_efficiency"] < 1.0


def test_sliding_speed_and_sign_change_at_the_pitch_point():
    """Constant coefficient, turned slowly: on the path of contact every contact's sliding
    speed is the kinematic u_2 - u_1 (flexgear's sign: t . (V_a - V_b), t = (-n_y, n_x) against
    the pinion's rolling motion), u_i = omega_i rho_i (Niemann & Winter;
    flexgear.gears.lubrication.surface_speeds with the gears' actual speeds and the contact
    position s), and each tooth pair's friction force changes sign where its contact crosses the
    pitch point s = 0 (within 1e-3 of the path of contact), from the side of s < 0 to s > 0
    with the sign of the kinematic sliding speed."""
    cfg, model, integ = _simulate()
    pair = mesh_pairs(cfg)["pinion-wheel"][2]
    sl = slice(int(0.1 / integ.h), None)
    fr = integ.friction
    s, vs = fr["position"][sl, 0], fr["sliding"][sl, 0]
    on = np.isfinite(s)
    gf, ga = pair.path_of_contact
    w1 = np.broadcast_to(integ.body[sl, 0, 5][:, None], s.shape)[on]
    w2 = np.broadcast_to(integ.body[sl, 1, 5][:, None], s.shape)[on]
    xi1, xi2 = roll_angles(pair, s[on])
    u1, u2 = surface_speeds(pair.g1.rb, xi1, w1, pair.g2.rb, xi2, w2, False)
    expect = u2 - u1
    inside = (s[on] > -gf) & (s[on] < ga)
    assert np.max(np.abs(vs[on] - expect)[inside]) < 1e-4 * np.max(np.abs(expect))
    # the friction force has the sliding speed's sign (mu tanh(v_s / v0))
    f = fr["pair_force"][sl, 0][on]
    assert np.all(f * vs[on] >= 0.0) and np.any(f > 0) and np.any(f < 0)
    at, _ = _reversals(integ, sl)
    assert len(at) >= 8
    assert np.max(np.abs(at)) < 1e-3 * (gf + ga)


def test_mesh_efficiency_is_the_closed_form():
    """Constant coefficient 0.05, turned slowly, contact stiffness x 1000: the friction power
    over the power the mesh carries (the recorded mesh efficiency), in steady state over whole
    mesh cycles, equals mu H_V, H_V the tooth loss factor of Ohlendorf (1958; Niemann & Winter,
    Maschinenelemente II, 1989; ISO/TR 14179-2; equal load sharing of rigid involutes), over the
    path of contact the run's contacts cover (the tip corners' contact extends the ISO path by
    0.07 mm at each end), within 1 %; over the ISO path (-g_f, g_a) within 2 %, the loss of the
    extended path being the larger (1 - P_out / P_in agrees too, within 2 %)."""
    cfg, model, integ = _simulate(3.0e8, f"friction_coefficient = {MU}\nsliding_speed_scale = 0.001\n")
    sl = _cycles(integ, model, 0.2)
    pair = mesh_pairs(cfg)["pinion-wheel"][2]
    p_in, p_out, p_f = _powers(integ, sl)
    loss = p_f / integ.friction["through"][sl, 0].mean()
    s = integ.friction["position"][sl, 0]
    pb, u = pair.g1.pb, pair.g2.z / pair.g1.z

    def hv(gf, ga):  # H_V of loss_factor over the path (-gf, ga)
        return math.pi * (u + 1.0) / (pair.g1.z * u) * (1.0 - (gf + ga) / pb + (ga / pb) ** 2 + (gf / pb) ** 2)

    iso = loss_factor(pair)
    assert iso == pytest.approx(hv(*pair.path_of_contact), rel=1e-12)
    covered = hv(-np.nanmin(s), np.nanmax(s))
    assert covered > iso
    assert loss == pytest.approx(MU * covered, rel=0.01)
    assert loss == pytest.approx(MU * iso, rel=0.02)
    assert 1.0 - p_out / p_in == pytest.approx(MU * iso, rel=0.02)


def test_energy_balance():
    """In steady state, over whole mesh cycles, the input power minus the output power equals
    the power the tooth friction dissipates (0.5 %): the friction forces, their moments about
    both centres and the sliding speeds are consistent (the IMPACT damper dissipates next to
    nothing when turned slowly)."""
    _, model, integ = _simulate()
    sl = _cycles(integ, model, 0.2)
    p_in, p_out, p_f = _powers(integ, sl)
    assert p_f > 5e-3 * p_in
    assert p_in - p_out == pytest.approx(p_f, rel=0.005)


def test_regularised_sign_change_converges_with_the_step():
    """The preset's spur pair at its 10 Hz, constant coefficient: mu tanh(v_s / v0) (v0 = 0.01
    m/s) turns over |s| < v0 / (omega_1 (1 + z_1 / z_2)) = 74 um, crossed in about 100 us, one
    step of 100 us. The positions where the tooth pairs' friction forces reverse (about 24 over
    0.1 s) converge as the step is halved from 100 us to 12.5 us: each halving moves their mean
    by at most a third of the move before (HHT-alpha, second order) and narrows their spread."""
    at = {}
    for h in (1e-4, 5e-5, 2.5e-5, 1.25e-5):
        _, _, integ = _simulate(3.0e5, t_end=0.2, h=h, speed=10.0)
        at[h], _ = _reversals(integ, slice(int(round(0.1 / h)), None))
        assert len(at[h]) >= 20
    hs = sorted(at, reverse=True)
    d = [abs(at[a].mean() - at[b].mean()) for a, b in zip(hs, hs[1:])]
    assert d[1] < d[0] / 3 and d[2] < d[1] / 3
    spread = [np.ptp(at[a]) for a in hs]
    assert all(b < a for a, b in zip(spread, spread[1:]))
    assert d[2] < 1e-5 * sum(mesh_pairs(loads_config(SPUR))["pinion-wheel"][2].path_of_contact)


def test_planetary_mesh_losses():
    """MERCURY 1-A (sun driven at 30 Hz, carrier loaded, three planets; contact stiffness x
    100), constant coefficient: each mesh's friction power over the power it carries relative
    to the carrier is mu H_V of its pair (Ohlendorf; the planet-ring mesh internal, u < 0)
    within 2 %, above it (the loaded tip corners extend the path, as on the spur pair), and the
    same on the three planets: the sliding and rolling speeds relative to the carrier and the
    internal mesh's geometry are the kinematic ones."""
    text = preset_path("mercury_1a").read_text().replace("stiffness = 3.0e5", "stiffness = 3.0e7")
    cfg = loads_config(text + f"\n[lubrication]\nfriction_coefficient = {MU}\n")
    model = build_model(cfg)
    integ = simulate(model, 0.25, 2.5e-5, 50, alpha=-0.1, friction=rigid_friction(cfg, model))
    sl = _cycles(integ, model, 0.15)
    loss = integ.friction["power"][sl].mean(axis=0) / integ.friction["through"][sl].mean(axis=0)
    pairs = mesh_pairs(cfg)
    for m, mesh in enumerate(model.meshes):
        hv = MU * loss_factor(pairs[mesh.name][2])
        assert hv < loss[m] < 1.02 * hv, mesh.name
    assert np.ptp(loss[:3]) < 1e-6 * loss[0] and np.ptp(loss[3:]) < 1e-6 * loss[3]


def test_the_pruned_frictionless_solver_is_the_friction_solver_with_every_mesh_off():
    """A frictionless rigid model runs kernels compiled without the friction code (its
    workspace's friction None, which numba prunes: less to compile on the first run); the
    friction solver with every mesh's friction and film off must give the same run bit for bit.
    A flexible model keeps its buffers (its compliant contacts take them)."""
    from flexgear.dynamics.integrator.friction import frictionless_table
    from flexgear.dynamics.integrator.simulation import model_workspace

    model = build_model(loads_config(SPUR))
    arr = model.pack()
    assert model_workspace(model, arr, 3).friction is None
    runs = [simulate(model, 0.01, 2.5e-5, 4, friction=f) for f in (None, frictionless_table(len(model.meshes)))]
    for key in ("mesh", "body", "pair_f", "pair_i"):
        assert np.array_equal(getattr(runs[0], key), getattr(runs[1], key)), key
    assert runs[0].friction is None and runs[1].friction is None


def test_a_zero_coefficient_reads_efficiency_one_and_no_loss_in_a_batch_summary():
    """A sweep over the coefficient from 0 tabulates the zero case as what it is, the
    frictionless mesh: efficiency 1, friction loss and RMS friction force 0 (they were empty,
    NaN in summary.csv, as if not computed); a run without [lubrication] has none of them."""
    from flexgear.app.metrics import DEFAULT_METRICS, compute_metrics

    def columns(text):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cfg = loads_config(text)
            cfg.simulation.update(run_in=0.02, duration=0.02)
            values, _ = compute_metrics(flexgear.run(cfg), DEFAULT_METRICS)
        return {k: values.get(f"{k}_pinion_wheel") for k in ("mesh_efficiency", "friction_loss", "rms_friction_force")}

    assert columns(SPUR + "\n[lubrication]\nfriction_coefficient = 0.0\n") == {
        "mesh_efficiency": 1.0, "friction_loss": 0.0, "rms_friction_force": 0.0}
    plain = columns(SPUR)
    assert all(v is None or math.isnan(v) for v in plain.values()), plain
