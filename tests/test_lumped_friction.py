"""Tooth friction in the lumped model (issue 24, model = "lumped"): the frictionless model bit
for bit at a zero coefficient, the sliding kinematics and the sign change at the pitch point,
the mesh efficiency against Ohlendorf's closed form, the energy balance, the time-step
convergence of the regularised sign change, outputs and bad input.

The spur configurations use [contact] damping_ratio = 0.05 instead of the preset's ADAMS damper
(3000 N s/mm, about 28 times critical on the lumped mesh): with that damper the lumped mesh
chatters in and out of contact during the load ramp even without friction, which leaves the
start transient to chance."""
import math
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.config import loads_config, preset_path
from flexgear.config.faults import mesh_pairs
from flexgear.dynamics.lumped.model import build_lumped
from flexgear.dynamics.lumped.time_loop import simulate_lumped
from flexgear.errors import ConfigError
from flexgear.gears.lubrication import loss_factor, pair_speeds, roll_angles, surface_speeds
from flexgear.results.store import load, save, validate

SPUR = ('model = "lumped"\n' + preset_path("spur_pair").read_text()).replace(
    "damping = 3000.0 ", "damping_ratio = 0.05 ")
MERCURY = ('model = "lumped"\n' + preset_path("mercury_1a").read_text()).replace(
    "damping = 3000.0", "damping_ratio = 0.05")
T_LOAD = 200.0  # N m on the spur preset's wheel
# the spur pair with a constant mesh stiffness (about the contact law's mean): no transmission
# error ripple, so the gears turn at their nominal speeds up to the friction's own small effect
CONSTANT = SPUR + ('\n[lumped]\nmesh_stiffness = "constant"\nconstant_stiffness = {pinion-wheel = 3.0e8}\n'
                   'damping_ratio = 0.05\n')


def _cfg(base, lubrication="", speed=None):
    text = base if speed is None else base.replace("speed_hz = 10.0", f"speed_hz = {speed}")
    return loads_config(text + ("\n[lubrication]\n" + lubrication if lubrication else ""))


def _simulate(cfg, t_end, steps_per_mesh=None, h=2.5e-5):
    """Step-level records of a lumped run: (model, Integration, h)."""
    lm = build_lumped(cfg)
    if steps_per_mesh is not None:
        h = 1.0 / (lm.model.attrs["mesh_frequency"] * steps_per_mesh)
    return lm, simulate_lumped(lm, t_end, h, 1, alpha=-0.1), h


def _cycles(integ, lm, h, t0):
    """Step-level slice from t0 over a whole number of mesh cycles to the end."""
    T = 1.0 / lm.model.attrs["mesh_frequency"]
    i0 = int(round(t0 / h))
    n = int(math.floor((integ.nsteps - i0) * h / T) * T / h + 0.5)
    return slice(i0, i0 + n)


def _powers(lm, integ, sl, load_body, load_torque):
    """Mean input power (drive torque x speed), output power (load torque x the loaded body's
    speed) and friction power over the steps ``sl`` [W]."""
    names = [b.name for b in lm.model.bodies]
    d, o = lm.drive, names.index(load_body)
    p_in = np.mean(integ.body[sl, d, 6] * integ.body[sl, d, 5])
    p_out = np.mean(abs(load_torque) * np.abs(integ.body[sl, o, 5]))
    p_f = np.mean(integ.friction["power"][sl].sum(axis=1))
    return p_in, p_out, p_f


def test_zero_coefficient_is_the_frictionless_run_bit_for_bit(tmp_path):
    """A constant coefficient of 0 runs the frictionless model: every signal equal bit for bit,
    and the result file carries no friction datasets (its layout is unchanged)."""
    def run(text):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cfg = loads_config(text)
            cfg.simulation.update(run_in=0.05, duration=0.02)
            return flexgear.run(cfg)

    plain = run(SPUR)
    zero = run(SPUR + "\n[lubrication]\nfriction_coefficient = 0.0\n")
    for name, m in plain.meshes.items():
        z = zero.meshes[name]
        assert np.array_equal(m.normal_force, z.normal_force)
        assert np.array_equal(m.force_global, z.force_global)
        assert z.friction_force is None and z.sliding_speed is None
    for name, b in plain.bodies.items():
        assert np.array_equal(b.angular_velocity, zero.bodies[name].angular_velocity)
    import h5py

    with h5py.File(save(zero, tmp_path / "zero.h5"), "r") as h5:
        assert not {"friction_force", "friction_power", "sliding_speed", "contact_position"} & set(
            h5["meshes/pinion-wheel"])


def test_friction_loop_without_friction_is_the_frictionless_loop():
    """The friction time loop (linearly implicit, LU) with the coefficient set to 0 reproduces
    the frictionless loop (exact solve per contact state, Cholesky) to rounding."""
    import dataclasses

    cfg = _cfg(SPUR, "friction_coefficient = 0.05\n")
    lm = build_lumped(cfg)
    params = lm.friction.params._replace(mu=np.zeros_like(lm.friction.params.mu))
    off = dataclasses.replace(lm, friction=dataclasses.replace(lm.friction, params=params))
    ref = simulate_lumped(dataclasses.replace(lm, friction=None), 0.08, 2.5e-5, 4)
    got = simulate_lumped(off, 0.08, 2.5e-5, 4)
    F0, F1 = ref.mesh[:, 0, 0], got.mesh[:, 0, 0]
    assert np.max(np.abs(F1 - F0)) < 1e-7 * np.max(np.abs(F0))
    assert np.all(got.friction["force"] == 0.0)


@pytest.mark.parametrize("base, lub", [
    (SPUR, "friction_coefficient = 0.05\n"),
    (MERCURY, 'friction_model = "xu"\niso_vg = 220\noil_temperature_c = 60.0\nroughness = 0.5e-6\n'),
], ids=["spur-constant", "mercury_1a-xu"])
def test_linearly_implicit_step_is_the_implicit_step(base, lub):
    """The time loop linearises the friction about the HHT predictor and solves each step once
    (re-linearising where a pair's sliding speed moved more than FRICTION_TOL of max(|v_s|, v0)).
    Against the implicit solution of the same steps (friction_tol 1e-9: Newton to convergence)
    the mesh force, the friction force (max over 0.05-0.1 s) and the mesh efficiency differ by
    less than 0.1 of the implicit scheme's own change from h to h/2 (measured 0.1 % to 1.4 %), with
    under 1.35 solves a step against about 2.3 to 2.9. The spur pair at 10 Hz vibrates its pitch-
    point sliding speed through the tanh's width: a loop that took the predictor's linearisation
    unchecked (friction_tol = inf) is off there by 1.5 times the h to h/2 change of the friction
    force, 0.24 times that of the mesh force. MERCURY 1-A with Xu et al.: the load- and speed-
    dependent coefficient through its tangent (its slopes, test_split_friction_law_...)."""
    lm = build_lumped(_cfg(base, lub))
    h, t_end = 2.5e-5, 0.1
    lin = simulate_lumped(lm, t_end, h, 1)
    ref = simulate_lumped(lm, t_end, h, 1, friction_tol=1e-9)
    half = simulate_lumped(lm, t_end, h / 2, 2, friction_tol=1e-9)
    i0 = int(0.05 / h)
    sl, sl2 = slice(i0, None), slice(2 * i0 + 1, None, 2)
    for get in (lambda x: x.mesh[:, :, 0], lambda x: x.friction["force"]):
        r = get(ref)[sl]
        assert np.max(np.abs(get(lin)[sl] - r)) < 0.1 * np.max(np.abs(get(half)[sl2] - r))

    def loss(x, s):
        return x.friction["power"][s].sum() / x.friction["through"][s].sum()

    assert abs(loss(lin, sl) - loss(ref, sl)) < 0.1 * abs(loss(half, slice(2 * i0, None)) - loss(ref, sl))
    assert lin.newton / lin.steps < 1.35
    assert ref.newton / ref.steps > 2.0


def _crossings(cfg, t_end, steps_per_mesh=None, h=2.5e-5, window=None):
    """Contact positions s [m] where a pair's friction force changes sign (interpolated between
    the steps) after a 0.1 s run-in, and, with ``window`` (an s grid [m]), the pair's friction
    force across each change interpolated onto it."""
    lm, integ, h = _simulate(cfg, t_end, steps_per_mesh, h)
    pair = mesh_pairs(cfg)["pinion-wheel"][2]
    step = pair.g1.rb * abs(integ.body[0, 0, 5]) * h
    fr = integ.friction
    sl = slice(int(0.1 / h), None)
    s = fr["position"][sl, 0]
    out, prof = [], []
    for j in range(s.shape[1]):
        sj, fj = s[:, j], fr["pair_force"][sl, 0, j]
        for i in np.nonzero((fj[:-1] * fj[1:] < 0) & (np.abs(np.diff(sj)) < 1.5 * step))[0]:
            out.append(sj[i] - fj[i] * (sj[i + 1] - sj[i]) / (fj[i + 1] - fj[i]))
            if window is not None:
                k = int(2 * np.max(np.abs(window)) / step) + 3
                near = slice(max(i - k, 0), i + k)
                ok = np.abs(sj[near] - sj[i]) < 1.5 * np.max(np.abs(window))
                prof.append(np.interp(window, sj[near][ok], fj[near][ok]))
    return np.array(out), np.array(prof), lm, integ, h


def test_sliding_speed_and_sign_change_at_the_pitch_point():
    """Constant coefficient, turned slowly (pinion 2 Hz, constant mesh stiffness): every pair's
    sliding speed is the kinematic u_2 - u_1 (flexgear's sign: t . (V_a - V_b), the flank tangent
    t against the pinion's rolling motion), u_i = omega_i rho_i (Niemann & Winter;
    flexgear.gears.lubrication.surface_speeds, with the gears' actual speeds), the contact moves
    at r_b1 omega_1 per second, and the friction force changes sign where the contact crosses the
    pitch point s = 0. It reverses where the whole sliding speed vanishes: the reversal changes
    the friction torque on the wheel and with it the mesh deflection, whose rate moves that point
    by an amount proportional to the speed (6.4 um at 2 Hz with v0 = 0.01 m/s, 1e-3 of the
    path, the same at every step): at half the speed it lies at half the distance from the
    pitch point, so it tends to the kinematic pitch point as the set is turned ever slower."""
    cfg = _cfg(CONSTANT, "friction_coefficient = 0.05\n", speed=2.0)
    at2, _, lm, integ, h = _crossings(cfg, 0.225)
    pair = mesh_pairs(cfg)["pinion-wheel"][2]
    w1 = 2 * math.pi * 2.0
    sl = slice(int(0.1 / h), None)
    fr = integ.friction
    s, vs = fr["position"][sl, 0], fr["sliding"][sl, 0]
    on = np.isfinite(s)
    w2 = np.broadcast_to(integ.body[sl, 1, 5][:, None], s.shape)[on]
    xi1, xi2 = roll_angles(pair, s[on])
    u1, u2 = surface_speeds(pair.g1.rb, xi1, w1, pair.g2.rb, xi2, w2, False)
    expect = u2 - u1
    assert np.max(np.abs(vs[on] - expect)) < 1e-3 * np.max(np.abs(expect))
    assert np.allclose(pair_speeds(pair, s[on], w1)[0], -w1 * s[on] * (1 + 24 / 21), rtol=1e-12, atol=1e-15)
    ds = np.diff(s[:, 0])
    assert np.median(ds[ds > 0]) == pytest.approx(pair.g1.rb * w1 * h, rel=1e-6)
    at1, *_ = _crossings(_cfg(CONSTANT, "friction_coefficient = 0.05\n", speed=1.0), 0.35)
    path = sum(pair.path_of_contact)
    assert len(at2) >= 4 and len(at1) >= 4
    assert np.ptp(at2) < 1e-3 * abs(at2.mean()) and np.ptp(at1) < 1e-3 * abs(at1.mean())
    assert abs(at2.mean()) < 1e-3 * path
    assert at2.mean() / at1.mean() == pytest.approx(2.0, rel=0.03)


def test_regularised_sign_change_converges_with_the_step():
    """The friction force of a pair within 40 um of its reversal at the pitch point (the tanh
    regularisation, v0 = 0.01 m/s: mu tanh(v_s / v0) turns over |s| < v0 / (omega_1 (1 + z_1 /
    z_2)) = 0.37 mm at 2 Hz), as a function of the contact position: halving the step divides
    the change by about 4 (HHT-alpha, second order), from 52 us to 6.5 us, where it is below
    1e-4 of the force."""
    window = np.linspace(-40e-6, 40e-6, 81)
    prof = {}
    for n in (400, 800, 1600, 3200):
        cfg = _cfg(CONSTANT, "friction_coefficient = 0.05\n", speed=2.0)
        at, p, *_ = _crossings(cfg, 0.225, steps_per_mesh=n, window=window)
        prof[n] = p.mean(axis=0)
    d = [np.max(np.abs(prof[a] - prof[2 * a])) for a in (400, 800, 1600)]
    assert all(3.0 < d[i] / d[i + 1] < 5.5 for i in range(2))
    assert d[-1] < 1e-4 * np.max(np.abs(prof[3200]))


def test_mesh_efficiency_is_the_closed_form():
    """Constant coefficient 0.05, turned slowly with a constant mesh stiffness (two pairs share
    the load equally): the mesh efficiency P_out / P_in in steady state, over whole mesh cycles,
    equals 1 - mu H_V, H_V the tooth loss factor of Ohlendorf (1958; Niemann & Winter,
    Maschinenelemente II, 1989; ISO/TR 14179-2), within 1 % of the loss mu H_V. The normal force
    itself changes with the friction moments, by O(mu) of the loss; the mesh's recorded
    efficiency attribute agrees too."""
    mu = 0.05
    cfg = _cfg(CONSTANT, f"friction_coefficient = {mu}\nsliding_speed_scale = 0.001\n", speed=2.0)
    lm, integ, h = _simulate(cfg, 0.5, steps_per_mesh=800)
    sl = _cycles(integ, lm, h, 0.3)
    p_in, p_out, p_f = _powers(lm, integ, sl, "wheel", T_LOAD)
    hv = loss_factor(mesh_pairs(cfg)["pinion-wheel"][2])
    assert 1.0 - p_out / p_in == pytest.approx(mu * hv, rel=0.01)
    through = integ.friction["through"][sl, 0].mean()
    assert p_f / through == pytest.approx(mu * hv, rel=0.01)


@pytest.mark.parametrize("base, load_body, torque, lub", [
    (CONSTANT.replace("speed_hz = 10.0", "speed_hz = 2.0"), "wheel", T_LOAD, "friction_coefficient = 0.05\n"),
    (MERCURY, "carrier", 60.0, "friction_coefficient = 0.05\nsliding_speed_scale = 0.001\n"),
], ids=["spur", "mercury_1a"])
def test_energy_balance(base, load_body, torque, lub):
    """In steady state, over whole mesh cycles, the input power minus the output power equals
    the power the tooth friction dissipates (0.5 %): the friction forces, their moments with the
    arms along the line of action and the sliding speeds are consistent. MERCURY 1-A: sun
    driven at 30 Hz, carrier loaded, three planets, sun-planet and planet-ring (internal)
    meshes."""
    cfg = _cfg(base, lub)
    lm, integ, h = _simulate(cfg, 0.3, steps_per_mesh=200)
    sl = _cycles(integ, lm, h, 0.2)
    p_in, p_out, p_f = _powers(lm, integ, sl, load_body, torque)
    assert p_f > 1e-3 * p_in
    assert p_in - p_out == pytest.approx(p_f, rel=0.005)


def table_powers(lm, integ, h, sl):
    """(P_k, P_c) over the steps ``sl`` [W], summed over the meshes: the power the mesh tables'
    time-varying stiffness and offset put into the vibration, mean(1/2 dk/dt delta^2 - k delta
    de/dt), and the mesh damper's dissipation mean(c (G v)^2) (k, e, c the tables at the drive's
    position, delta the deflection beyond the offset while the drive flank is in contact, G v =
    d(delta + e)/dt the approach rate)."""
    drive = lm.drive
    phi = (integ.body[:, drive, 2] - lm.model.bodies[drive].theta0) / lm.mesh_angle
    P = lm.k.shape[1]
    x = (phi % 1.0) * P
    i = np.floor(x).astype(int) % P
    w = x - np.floor(x)
    p_k = p_c = 0.0
    for m in range(lm.k.shape[0]):
        k, e, c = ((1.0 - w) * tab[m, i] + w * tab[m, (i + 1) % P] for tab in (lm.k, lm.e, lm.c))
        delta = integ.pair_f[:, m, 0, 1]
        rate = np.gradient(delta + e, h)
        p_k += np.mean((0.5 * np.gradient(k, h) * delta ** 2 - k * delta * np.gradient(e, h))[sl])
        p_c += np.mean((c * rate * rate)[sl])
    return p_k, p_c


@pytest.mark.parametrize("base, load_body, torque, speed", [(SPUR, "wheel", T_LOAD, 2.0), (MERCURY, "carrier", 60.0, None)],
                         ids=["spur", "mercury_1a"])
def test_energy_balance_with_the_cycles_mesh_stiffness(base, load_body, torque, speed):
    """With the mesh tables of the `contact` stiffness (the default) the balance holds with the
    power the tables put into the vibration, P_k, and the mesh damper's dissipation, P_c
    (:func:`table_powers`): P_in - P_out + P_k = P_friction + P_c within 0.5 % of the friction
    power (measured 0.035 % spur, 0.033 % MERCURY 1-A). Without P_k and P_c the spur pair at 2 Hz
    misses by 1.4 % (a check from outside found it; the guide had claimed the balance without
    saying it needs a constant stiffness)."""
    cfg = _cfg(base, "friction_coefficient = 0.05\n", speed=speed)
    lm = build_lumped(cfg)
    h = 1.0 / (lm.model.attrs["mesh_frequency"] * 320)
    t_end = 0.5 if speed is not None else 0.3
    integ = simulate_lumped(lm, t_end, h, 1, alpha=-0.1)
    sl = _cycles(integ, lm, h, t_end - 0.2)
    p_in, p_out, p_f = _powers(lm, integ, sl, load_body, torque)
    p_k, p_c = table_powers(lm, integ, h, sl)
    assert np.all(integ.mesh[sl, :, 0] >= 0.0)  # drive flanks only
    assert p_in - p_out + p_k == pytest.approx(p_f + p_c, rel=0.005)
    if speed is not None:
        assert abs(p_in - p_out - p_f) > 0.01 * p_f  # the terms are needed


@pytest.mark.slow
@pytest.mark.parametrize("lub", [
    'friction_model = "benedict_kelley"\niso_vg = 220\noil_temperature_c = 60.0\n',
    'friction_model = "xu"\niso_vg = 220\noil_temperature_c = 60.0\nroughness = 0.5e-6\n',
], ids=["benedict_kelley", "xu"])
def test_energy_balance_lubricated_models(lub):
    """The energy balance of test_energy_balance with the load- and speed-dependent coefficients
    (their Newton tangents in the step), on MERCURY 1-A over 0.5 s (0.5 %)."""
    cfg = _cfg(MERCURY, lub)
    lm, integ, h = _simulate(cfg, 0.5, steps_per_mesh=200)
    sl = _cycles(integ, lm, h, 0.2)
    p_in, p_out, p_f = _powers(lm, integ, sl, "carrier", 60.0)
    assert p_f > 1e-3 * p_in
    assert p_in - p_out == pytest.approx(p_f, rel=0.005)


def test_friction_outputs_in_the_result(tmp_path):
    """A lumped run with friction records, per mesh, the friction force, its power, each pair's
    sliding speed and contact position and the mesh efficiency; they round-trip through the
    result file, and the friction acts across the line of action in force_global."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = _cfg(SPUR, "friction_coefficient = 0.05\n")
        cfg.simulation.update(run_in=0.1, duration=0.05)
        res = flexgear.run(cfg)
    validate(res)
    m = res.meshes["pinion-wheel"]
    n = len(res.time)
    assert m.friction_force.shape == (n,) and m.friction_power.shape == (n,)
    assert m.sliding_speed.shape == m.contact_position.shape == (n, 3)
    assert np.all(m.friction_power > -0.05 * m.friction_power.max())  # >= 0 up to the anti-alias filter
    # |force_global|^2 = N^2 + f^2 (normal and friction perpendicular; to the anti-alias filter)
    both = np.hypot(m.normal_force, m.friction_force)
    assert np.allclose(np.hypot(*m.force_global.T), both, rtol=2e-3)
    assert np.max(np.abs(m.friction_force)) > 0.02 * m.normal_force.mean()
    hv = loss_factor(mesh_pairs(cfg)["pinion-wheel"][2])
    assert 1 - m.attrs["mesh_efficiency"] == pytest.approx(0.05 * hv, rel=0.05)
    back = load(save(res, tmp_path / "friction.h5"))
    b = back.meshes["pinion-wheel"]
    for f in ("friction_force", "friction_power", "sliding_speed", "contact_position"):
        assert np.array_equal(getattr(b, f), getattr(m, f), equal_nan=True)
    assert b.attrs["mesh_efficiency"] == m.attrs["mesh_efficiency"]


def test_bad_input():
    """The lumped model refuses friction and the squeeze film with explicit parameters (no tooth
    geometry); phase 1's checks stay."""
    printed = preset_path("lin_parker_1999").read_text() + "\n[lubrication]\nfriction_coefficient = 0.05\n"
    with pytest.raises(ConfigError, match=r"'lubrication' given with \[lumped.parameters\] and no \[gears\]"):
        loads_config(printed)
    explicit = preset_path("mercury_1a").read_text().replace('kind = "planetary"', '''kind = "planetary"
model = "lumped"
[lumped]
constant_stiffness = {sun-planet = 3.0e8, planet-ring = 3.5e8}
[lumped.parameters]
pressure_angle_deg = 21.0
''') + "\n[lubrication]\nfriction_coefficient = 0.05\n"
    with pytest.raises(ConfigError, match=r"\[lubrication\] with \[lumped.parameters\]: the explicit parameters"):
        build_lumped(loads_config(explicit))
    film = explicit.replace("friction_coefficient = 0.05", 'friction_coefficient = 0.0\ndamping = "squeeze_film"\n'
                            "viscosity = 0.05")
    with pytest.raises(ConfigError, match=r"\[lubrication\] with \[lumped.parameters\]: the explicit parameters"):
        build_lumped(loads_config(film))
    with pytest.raises(ConfigError, match="friction_coefficient = -0.1"):
        _cfg(SPUR, "friction_coefficient = -0.1\n")


def test_friction_with_faults_keeps_the_kinematics():
    """With a fault the tables span L mesh cycles (24 for a pinion spall) and the time loop reads
    them at phi / L; the pairs' contact positions still follow the engagement geometry: the same
    as in the healthy model at every position, on average eps_alpha pairs on the path (1 %)."""
    spall = ('\n[[faults]]\nkind = "spall"\ngear = "pinion"\ntooth = 3\nflank = "left"\n'
             'start_radius = 0.0235\nend_radius = 0.0245\ndepth = 20e-6\n')
    healthy = build_lumped(_cfg(SPUR, "friction_coefficient = 0.05\n"))
    faulty = build_lumped(_cfg(SPUR + spall, "friction_coefficient = 0.05\n"))
    assert faulty.cycles == 24
    from flexgear.dynamics.lumped.friction import pair_positions

    cycles = np.linspace(0.0, 30.0, 3001)  # mesh cycles
    a = pair_positions(healthy.friction, 0, cycles)
    b = pair_positions(faulty.friction, 0, cycles / faulty.cycles)
    assert np.allclose(a, b, atol=1e-12, equal_nan=True)
    on = np.sum(np.isfinite(a), axis=1)
    pair = mesh_pairs(_cfg(SPUR))["pinion-wheel"][2]
    assert on.mean() == pytest.approx(sum(pair.path_of_contact) / pair.g1.pb, rel=0.01)


def test_pair_slots_at_the_output_samples_hold_the_pairs_on_the_path():
    """At every output sample each mesh's first slots hold the pairs on its path of contact
    (position within it, sliding speed finite) and the others nan with no friction force; on
    average eps_alpha pairs (2 %, MERCURY 1-A over about 50 mesh cycles). Which wrong code
    passes: none that leaves an absent pair's slot at 0 or at another sample's pair, or skips a
    pair on the path."""
    cfg = _cfg(MERCURY, "friction_coefficient = 0.05\n")
    lm = build_lumped(cfg)
    integ = simulate_lumped(lm, 0.1, 2.5e-5, 4)
    fr, pairs = integ.friction, mesh_pairs(cfg)
    for m, mesh in enumerate(lm.model.meshes):
        s, vs, f = fr["position"][:, m], fr["sliding"][:, m], fr["pair_force"][:, m]
        on = np.isfinite(s)
        count = on.sum(axis=1)
        assert np.array_equal(on, np.arange(s.shape[1]) < count[:, None]), mesh.name
        assert np.array_equal(np.isfinite(vs), on) and np.all(f[~on] == 0.0), mesh.name
        assert np.all(s[on] >= lm.friction.s_lo[m] - 1e-12) and np.all(s[on] <= lm.friction.s_hi[m] + 1e-12)
        pair = pairs[mesh.name][2]
        assert count.mean() == pytest.approx(sum(pair.path_of_contact) / pair.g1.pb, rel=0.02), mesh.name


@pytest.mark.parametrize("model, kw", [("constant", {"friction_coefficient": 0.07}), ("benedict_kelley", {}),
                                       ("xu", {"roughness": 0.4e-6})])
def test_split_friction_law_is_the_friction_law(model, kw):
    """The lumped loop takes each pair's u_e and R terms once a step (contact_constants) and the
    v_s and w terms at every evaluation (coefficient_slopes_at); the rigid and flexible contacts
    take both at once (friction_coefficient_slopes). mu is the formula as published
    (friction_coefficient, 1e-12), dmu/dv_s, dmu/du_e, dmu/dw its central differences (1e-5),
    below, at and above v_0, through the tanh and past TANH_ONE v_0 (tanh = +-1 exactly there),
    at u_e of either sign and below v_0, and where Benedict & Kelley's logarithm is cut at 0."""
    from flexgear.gears.lubrication import Lubricant, Lubrication
    from flexgear.gears.tribology import (TANH_ONE, coefficient_slopes_at, contact_constants, friction_coefficient,
                                          friction_coefficient_slopes, friction_parameters, law_constants)

    oil = Lubricant(viscosity=0.05, pressure_viscosity=2e-8, density=870.0)
    table = friction_parameters(Lubrication(friction_model=model, lubricant=oil, sliding_speed_scale=0.01, **kw),
                                [("a", "b")], 2.3e11)
    law = law_constants(table)[0]
    assert math.tanh(TANH_ONE) == 1.0
    cut = 0
    for vs in (0.3, -0.2, 0.004, -0.02, 0.0, 0.1999, 0.2001, -0.25, 3.0):
        for ue, w, R in ((1.5, 3e5, 0.008), (0.8, 6e5, 0.004), (0.005, 2e5, 0.01), (-2.0, 1e3, 0.006),
                         (40.0, 1.0, 0.02)):
            mu, dvs, due, dw = slopes = friction_coefficient_slopes(table, law, 0, vs, ue, w, R)
            c0, c1 = contact_constants(table, 0, law, ue, R)
            assert coefficient_slopes_at(table, 0, c0, c1, vs, w, math.log(w), math.sqrt(w))[:3] == (mu, dvs, dw)
            assert mu == pytest.approx(friction_coefficient(table, 0, vs, ue, w, R), rel=1e-12, abs=1e-300)
            cut += mu == 0.0 and vs != 0.0
            for k, h in ((0, 1e-7), (1, 1e-7 * max(1.0, abs(ue))), (2, 1e-6 * w)):
                up, dn = [vs, ue, w], [vs, ue, w]
                up[k] += h
                dn[k] -= h
                fd = (friction_coefficient(table, 0, *up, R) - friction_coefficient(table, 0, *dn, R)) / (2 * h)
                assert slopes[(1, 2, 3)[k]] == pytest.approx(fd, rel=1e-5, abs=1e-9), (k, vs, ue, w, R)
    assert cut > 0 if model == "benedict_kelley" else cut == 0


def test_a_diverging_lumped_run_names_the_damping_ratio():
    """A contact damper far above critical on the lumped mesh's constant viscous damper (ten
    times the spur preset's ADAMS C, itself many times critical there) with a constant
    coefficient diverges during the load ramp: the error says when and where and names
    [contact] damping_ratio, and with the ratio the run is sound."""
    from flexgear.app.run import run
    from flexgear.errors import DivergenceError

    text = preset_path("spur_pair").read_text().replace("damping = 3000.0", "damping = 30000.0")
    cfg = loads_config('model = "lumped"\n' + text + "\n[lubrication]\nfriction_coefficient = 0.05\n")
    cfg.simulation.update(run_in=0.1, duration=0.01)
    with pytest.raises(DivergenceError, match=r"diverged: non-finite state at t = 0\.0\d+ s, mesh 'pinion-wheel'.*"
                                              r"give \[contact\] damping_ratio \(e\.g\. 0\.05\) instead of C"):
        run(cfg)
    f = run(cfg.use_damping_ratio(0.05)).meshes["pinion-wheel"].normal_force
    static = T_LOAD / cfg.gears["wheel"].rb  # N along the line of action, up to the friction's share
    assert np.all(np.isfinite(f)) and f.mean() == pytest.approx(static, rel=0.02)
