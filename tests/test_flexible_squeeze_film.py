"""Squeeze-film mesh damping in the flexible model (issue 24 item 3, ``[lubrication] damping =
"squeeze_film"`` on the compliant meshes, flexgear.dynamics.flexible.compliant.compliant_contacts):
each compliant contact's damping force against the closed form at a prescribed approach speed,
its Newton tangent against central differences, the [contact] damper replaced (not added to),
and the energy balance.

The spur pair flexible as in tests/test_flexible_friction.py (tests/test_flexible_errors.py's
flexible_spur: both gears at mesh level 0, no shafts, every mode condensed unless MODAL) at 10 Hz,
VG 100 at 70 degC (eta = 0.0235 Pa s, alpha = 2e-8 1/Pa). The closed form, written out here
independently of flexgear's kernels (as tests/test_squeeze_film.py for the rigid model): the
squeeze film of two cylinders of relative radius R and length L approaching at d delta/dt,
F = 3 sqrt(2) pi eta L (R / h)^(3/2) d delta/dt (Reynolds' equation for pure squeeze), at the
central film thickness of Dowson & Toyoda (1979), h_c = 3.06 R U^0.69 G^0.56 W^-0.10, U = eta u_e /
(E' R), G = alpha E', W = w / (E' R), E' = 2 E*, w = F_e / L the compliant contact's elastic
force per face width; d delta/dt the rate of the rigid frames' overlap at the contact point (the
damper acts between the floating frames, as the IMPACT damper it replaces)."""
import functools
import math
import warnings

import numpy as np
import pytest
from test_flexible_errors import flexible_spur
from test_rigid_friction import _cycles

import flexgear
from flexgear.dynamics.integrator.friction import rigid_friction
from flexgear.dynamics.integrator.simulation import evaluate, simulate
from flexgear.dynamics.model.assembly import build_model
from flexgear.results.store import load, save

ETA = 0.0235  # Pa s: ISO VG 100 at 70 degC
ALPHA = 2.0e-8  # 1/Pa
E, NU, WIDTH = 2.1e11, 0.3, 0.020  # Pa, -, m: the preset's steel and face width
FILM = f'damping = "squeeze_film"\nviscosity = {ETA}\npressure_viscosity = {ALPHA}\n'
NOFRICTION = FILM + "friction_coefficient = 0.0\n"
FRICTION = FILM + "friction_coefficient = 0.05\n"
H = 2.5e-5  # s, the step of tests/test_flexible_friction.py
MODAL = 60e3  # Hz: [flexible] dynamic_cutoff with modal coordinates (tests/test_flexible_friction.py)
OVERLAP = 25e-6  # m: the rigid overlap the wheel is turned into the pinion by (200 N m: 19 to 35 um)


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _cfg(lub, zeta=0.05, ramp=0.02):
    cfg = flexible_spur("\n[lubrication]\n" + lub).use_damping_ratio(zeta)
    cfg.drive["speed_hz"] = 10.0
    cfg.load["ramp"] = ramp
    return cfg


@functools.cache
def _model(lub, modal=0.0):
    cfg = _cfg(lub)
    cfg.flexible.update(dynamic_cutoff=modal)
    model = build_model(cfg)
    return cfg, model, rigid_friction(cfg, model)


def _kinematics(model, e, slot):
    """(d delta/dt, u_e, R) of the contact in ``slot`` of mesh 0 of the evaluation ``e``, from its
    point and normal and the floating frames' poses and velocities: the approach speed along the
    normal, the mean of the flanks' speeds along the tangent t = (-n_y, n_x) (the ground the
    frame), R = rho_a rho_b / (rho_a + rho_b), rho = |(P - O) . n| the involutes' radii of
    curvature."""
    _, _, px, py, nx, ny = e["cf"][0, slot]
    pose, vel = e["pose"], e["vel"]
    P, n, t = np.array([px, py]), np.array([nx, ny]), np.array([-ny, nx])

    def velocity(i):  # material velocity of body i's frame at P
        r = P - pose[i, :2]
        return vel[i, :2] + vel[i, 2] * np.array([-r[1], r[0]])

    a, b = model.meshes[0].a, model.meshes[0].b
    rho_a, rho_b = abs((P - pose[a, :2]) @ n), abs((P - pose[b, :2]) @ n)
    return n @ (velocity(b) - velocity(a)), 0.5 * t @ (velocity(a) + velocity(b)), rho_a * rho_b / (rho_a + rho_b)


def _closed_form(Fe, ddot, ue, R):
    """The film's damping force [N] (module docstring) at elastic force Fe [N]."""
    e_prime = E / (1.0 - NU ** 2)  # E' = 2 E*, 1/E* = 2 (1 - nu^2) / E (two steel gears)
    w = Fe / WIDTH
    h = 3.06 * R * (ETA * abs(ue) / (e_prime * R)) ** 0.69 * (ALPHA * e_prime) ** 0.56 * (w / (e_prime * R)) ** -0.10
    return 3.0 * math.sqrt(2.0) * math.pi * ETA * WIDTH * (R / h) ** 1.5 * ddot


def _loaded(e):
    """[(stacked contact, slot, elastic force)] of the evaluation's active compliant contacts."""
    c = e["work"].contacts
    return [(k, c.joint_slot[k], c.elastic_force[k]) for k in range(c.joint_count[0]) if c.active[k]]


def _state(lub, approach, modal=0.0):
    """(model, table, q, v): the wheel turned into the pinion by OVERLAP along the line of action
    and its speed set so that the contacts' rigid overlaps close at about ``approach`` [m/s]
    (negative: open)."""
    cfg, model, table = _model(lub, modal)
    rb = cfg.pairs["pinion-wheel"].g2.rb
    q, v = model.initial_state()
    j = model.coordinate_names().index("wheel.theta")
    for turn in OVERLAP / rb * np.array([1.0, -1.0, 2.0, -2.0, 4.0, -4.0, 8.0, -8.0]):  # through the backlash
        qq = q.copy()
        qq[j] += turn
        e = evaluate(model, qq, v, friction=table)
        if _loaded(e):
            break
    else:
        raise AssertionError("no contact either way")
    qq[j] += math.copysign((OVERLAP - e["max_depth"]) / rb, turn)  # the deepest rigid overlap OVERLAP
    e = evaluate(model, qq, v, friction=table)
    slot = _loaded(e)[0][1]
    ddot = [_kinematics(model, evaluate(model, qq, v + dw * np.eye(len(v))[j], friction=table), slot)[0]
            for dw in (0.0, 1.0)]
    vv = v.copy()
    vv[j] += (approach - ddot[0]) / (ddot[1] - ddot[0])
    return model, table, qq, vv


@pytest.mark.parametrize("approach", [0.02, -0.004])
def test_pair_damping_force_is_the_closed_form(approach):
    """At a prescribed approach speed of the floating frames (closing 0.02, opening 0.004 m/s)
    each loaded compliant contact's recorded damping force is the closed form at its elastic
    force (1e-9), its normal force the elastic force plus it, and the mesh's damping power their
    sum times the approach speeds. Catches a film coefficient at the wrong load (the total force,
    or the mesh's instead of the contact's), speed, radius or width, and the IMPACT ramp left in."""
    model, table, q, v = _state(NOFRICTION, approach)
    e = evaluate(model, q, v, friction=table)
    fr = e["work"].friction
    loaded = _loaded(e)
    assert len(loaded) >= 1
    power = 0.0
    for _, slot, Fe in loaded:
        ddot, ue, R = _kinematics(model, e, slot)
        assert ddot * approach > 0 and ddot == pytest.approx(approach, rel=0.05)  # the set-up
        assert Fe > 100.0
        fd = _closed_form(Fe, ddot, ue, R)
        assert fr.damping[0, slot] == pytest.approx(fd, rel=1e-9)
        assert e["cf"][0, slot, 0] == pytest.approx(max(Fe + fd, 0.0), rel=1e-9)
        power += fd * ddot
    assert fr.damping_power[0] == pytest.approx(power, rel=1e-9)
    assert np.all(fr.damping[0, e["count"][0]:] == 0.0)


def _tangents(lub, modal):
    """(Kt, Kd, Ct, Cd, nr): the film's part of the Newton matrices (with the film minus with its
    coefficient zeroed, which is the elastic force alone) and central differences of its
    generalised force, at a state closing at 0.05 m/s (a tenth of the entrainment speed, so that
    the coefficient's change with u_e matters); nr rigid coordinates."""
    model, table, q, v = _state(lub, 0.05, modal)
    bare = table._replace(film_factor=np.zeros_like(table.film_factor))
    nr = model.rigid_coordinates()

    def part(q, v):
        a, b = evaluate(model, q, v, friction=table), evaluate(model, q, v, friction=bare)
        assert np.any(a["work"].friction.damping != 0.0) and np.all(b["work"].friction.damping == 0.0)
        return a["rhs"] - b["rhs"], a["Kt"] - b["Kt"], a["Ct"] - b["Ct"]

    _, Kt, Ct = part(q, v)
    eq, ev = 1e-10, 1e-6
    Kd, Cd = np.zeros_like(Kt), np.zeros_like(Ct)
    for j in range(q.size):
        dq = np.zeros(q.size)
        dq[j] = eq * (1.0 if j < nr else 1e-2)  # modal coordinates [sqrt(kg) m]: about 1e-12 m of flank
        Kd[:, j] = -(part(q + dq, v)[0] - part(q - dq, v)[0]) / (2 * dq[j])
        dv = np.zeros(q.size)
        dv[j] = ev
        Cd[:, j] = -(part(q, v + dv)[0] - part(q, v - dv)[0]) / (2 * ev)
    return Kt, Kd, Ct, Cd, nr


def test_film_tangent_is_the_derivative():
    """The film's part of the Newton matrices against central differences of its generalised
    force, friction off, with modal coordinates (the modes below 60 kHz), closing at 0.05 m/s:
    C_t to 1e-6 (c G G^T + dc/du_e d delta/dt G e^T: the velocities enter exactly); K_t's modal
    columns to 1e-5 (a modal coordinate changes the elastic force and nothing of the frames'
    geometry, so those columns are exactly the film's load slope, dc/dw d delta/dt / L G dF_e/dq);
    the rigid columns to 3 % of their size (measured 1.3 %; left out, as in the IMPACT damper's
    tangent: the change of the contact point, normal, arms, u_e and R with q, and of the approach
    speed through the contact point). Dropping the load slope fails the modal columns by 100 %,
    the u_e term C_t by 2 % (c G G^T alone is 0.979 of it here)."""
    Kt, Kd, Ct, Cd, nr = _tangents(NOFRICTION, MODAL)
    assert np.abs(Kt[:nr, nr:]).max() > 0 and np.abs(Ct).max() > 0
    np.testing.assert_allclose(Ct, Cd, rtol=0, atol=1e-6 * np.abs(Ct).max())
    np.testing.assert_allclose(Kt[:, nr:], Kd[:, nr:], rtol=0, atol=1e-5 * np.abs(Kt[:, nr:]).max())
    np.testing.assert_allclose(Kt[:, :nr], Kd[:, :nr], rtol=0, atol=0.03 * np.abs(Kt[:, :nr]).max())


def test_film_tangent_with_friction_is_the_derivative():
    """With friction as well (mu = 0.05; the modes below 60 kHz as coordinates, which the friction
    loads through their tangential flank shapes), the friction follows the film's change of the
    normal force: C_t to 1e-6 (c and dF/du_e in the friction's velocity row); K_t's modal columns
    to 1e-5 (measured 2e-6: the friction's load slope (mu + w dmu/dw) sk dF_e/dq, in the rigid and
    the modal rows); the whole K_t to 2 % of its largest entry, as tests/test_flexible_friction.py
    (the change of the contact point and of the tangential shapes with q left out)."""
    Kt, Kd, Ct, Cd, nr = _tangents(FRICTION, MODAL)
    assert np.abs(Kt[nr:, nr:]).max() > 0
    np.testing.assert_allclose(Ct, Cd, rtol=0, atol=1e-6 * np.abs(Ct).max())
    np.testing.assert_allclose(Kt[:, nr:], Kd[:, nr:], rtol=0, atol=1e-5 * np.abs(Kt[:, nr:]).max())
    np.testing.assert_allclose(Kt, Kd, rtol=0, atol=0.02 * np.abs(Kt).max())


def _short_run(lub, zeta=0.05):
    cfg = _cfg(lub, zeta)
    cfg.simulation.update(run_in=0.02, duration=0.02)
    return flexgear.run(cfg)


def test_squeeze_film_replaces_the_impact_damper(tmp_path):
    """With the squeeze film the [contact] damper plays no part: runs with mesh damping ratios
    0.05 and 0.5 (the IMPACT coefficient ten times larger) are equal bit for bit; the film's
    damping differs from the IMPACT damper's (the IMPACT run differs), and the result carries its
    outputs (the film's force in the loaded slots only), written and read back. Catches the
    IMPACT ramp added to the film, or left in the tangent (the Newton iterates would differ)."""
    film = _short_run(NOFRICTION)
    back = load(save(film, tmp_path / "film.h5")).meshes["pinion-wheel"]
    for f in ("damping_power", "pair_damping_force"):
        assert np.array_equal(getattr(back, f), getattr(film.meshes["pinion-wheel"], f))
    heavy = _short_run(NOFRICTION, zeta=0.5)
    impact = _short_run(f"viscosity = {ETA}\nfriction_coefficient = 0.0\n")
    m, mh, mi = (r.meshes["pinion-wheel"] for r in (film, heavy, impact))
    for f in ("normal_force", "force_global", "pair_force", "penetration", "pair_deflection", "damping_power",
              "pair_damping_force"):
        assert np.array_equal(getattr(m, f), getattr(mh, f)), f
    assert not np.array_equal(m.normal_force, mi.normal_force)
    assert mi.damping_power is None and m.friction_force is None
    assert np.all(m.pair_damping_force[m.pair_tooth_a < 0] == 0.0)
    assert np.any(m.pair_damping_force[m.pair_force > 0] != 0.0)
    # where the film's pull would exceed the elastic force the contact opens: F = 0, the film's -F_e
    assert np.all(m.pair_damping_force[m.pair_force == 0.0] <= 0.0)
    assert np.all(m.damping_power > 0.0)


@functools.cache
def _balance(lub, zeta=0.05, t_end=0.1):
    """(p_in, p_out, p_f, p_d) [W]: the mean input (drive torque x pinion speed), output (load
    torque x wheel speed), friction and film power over whole mesh cycles from 0.05 s of a run of
    t_end (load ramp 0.02 s; the film damps the start-up within a few mesh cycles)."""
    cfg = _cfg(lub, zeta)
    model = build_model(cfg)
    integ = simulate(model, t_end, H, 1, alpha=-0.1, friction=rigid_friction(cfg, model))
    sl = _cycles(integ, model, 0.05)
    p_in = np.mean(integ.body[sl, 0, 6] * integ.body[sl, 0, 5])
    p_out = np.mean(cfg.load["torque"] * np.abs(integ.body[sl, 1, 5]))
    p_f = np.mean(integ.friction["power"][sl, 0]) if integ.friction is not None else 0.0
    p_d = np.mean(integ.damping["power"][sl, 0]) if integ.damping is not None else 0.0
    return p_in, p_out, p_f, p_d


@pytest.mark.parametrize("lub", [NOFRICTION, FRICTION], ids=["film", "film+friction"])
def test_energy_balance(lub):
    """In steady state over whole mesh cycles the input minus the output power equals the power
    the films and the friction dissipate, within 0.5 % of it plus a floor: the input minus the
    output power of the same pair without any mesh damping or friction ([contact] damping ratio 0,
    no film; the gears' modal damping is 0), 0.22 W, 1.5e-5 of the 14.4 kW transmitted, which no
    recorded dissipation explains (0.17 to 0.22 W with one-pass steps off, static condensation or
    half the step; the film's run leaves 0.16 W with HHT alpha = 0 too, so it is not the step's
    numerical damping). Measured: film alone 18.0 W dissipated, 0.17 W left; film and friction
    (mu = 0.05) 166 W, 0.15 W left. Catches a film force on the frames that its recorded power
    does not match (the force at another rate, or clipped otherwise) by more than about 2 % of it."""
    p_in, p_out, p_f, p_d = _balance(lub)
    floor = abs(np.subtract(*_balance("friction_coefficient = 0.0\n", 0.0)[:2]))
    assert p_d > 15.0 and floor < 0.3
    assert abs(p_in - p_out - p_f - p_d) <= 0.005 * (p_d + p_f) + floor


def test_film_without_a_lubricant_is_refused_naming_the_key():
    """The flexible model with the squeeze film and no lubricant is a ConfigError naming
    lubrication.viscosity (and iso_vg), from the configuration alone, before any reduction or
    run (the film needs the viscosity)."""
    from flexgear.errors import ConfigError

    with pytest.raises(ConfigError, match=r"damping = 'squeeze_film' needs the lubricant: lubrication.viscosity"):
        flexible_spur('\n[lubrication]\ndamping = "squeeze_film"\nfriction_coefficient = 0.0\n')


def test_one_pass_steps_move_the_film():
    """One-pass steps (the default with flexible bodies: accepted after one Newton correction, the
    records moved to the corrected state to first order, the film's coefficient at the moved
    elastic force and entrainment speed) record the film as the full iteration converged to 1e-13
    does, over the last 10 ms of a 40 ms run: the film's power at each step and each contact's
    normal force within 1e-5 of their RMS about the mean in 90 % of the samples (measured 4.8e-6
    and 4.9e-6; the full iteration at the same tolerance 4.2e-6 and 2.8e-5), the mesh force and
    each contact's film force no further off than the full iteration at the same tolerance (90 %
    and 99 % quantiles: the film holds the mesh force's fluctuation to 0.6 % of its mean, so
    the tolerance shows in it). With the coefficient left at the unmoved elastic force the film's
    power is off by 1.6e-5 (90 %)."""
    _, model, table = _model(NOFRICTION)
    one, full, ref = (simulate(model, 0.04, H, 1, alpha=-0.1, friction=table, tol=tol, one_pass=op)
                      for op, tol in ((True, 1e-10), (False, 1e-10), (False, 1e-13)))
    assert one.linearised > 0.5 * one.steps and full.linearised == 0
    k0 = round(0.03 / H)

    def errors(run, name):
        a, b = getattr(ref.records, name)[k0:], getattr(run.records, name)[k0:]
        a, b = a.reshape(a.shape[0], -1), b.reshape(b.shape[0], -1)
        rms = np.sqrt(np.mean((a - a.mean(axis=0)) ** 2, axis=0))
        return np.abs(a - b)[:, rms > 0] / rms[rms > 0]

    for name in ("damping_power", "pair_force"):
        assert np.quantile(errors(one, name), 0.9) < 1e-5, name
    for name in ("mesh_force", "pair_damping"):
        for q in (0.9, 0.99):
            assert np.quantile(errors(one, name), q) < np.quantile(errors(full, name), q), name


def test_the_film_on_a_rigid_mesh_of_a_flexible_model_makes_its_steps_iterate():
    """MERCURY 1-A with only the sun flexible: its sun-planet meshes take the compliant law, its
    planet-ring meshes keep IMPACT, whose film (friction.squeeze_contact) has no one-pass move.
    With the film on, linearised_acceptance refuses every step in which such a contact carries
    load, so no step of 4 ms is accepted after one correction while the films of the rigid
    meshes dissipate; with the IMPACT damper the same model accepts most steps so (the refusal is
    the film's)."""
    from flexgear.config import loads_config, preset_path
    from flexgear.dynamics.contact.laws import LAW_HERTZ

    text = (preset_path("mercury_1a_flexible").read_text()
            .replace('gears = ["sun", "planet", "ring"]', 'gears = ["sun"]').replace("level = 2 ", "level = 0 ")
            .replace("ramp = 0.05", "ramp = 0.002"))
    runs, rigid = {}, None
    for name, lub in (("film", NOFRICTION), ("impact", None)):
        cfg = loads_config(text + (f"\n[lubrication]\n{lub}" if lub else ""))
        assert cfg.flexible["gears"] == ["sun"] and cfg.flexible["level"] == 0
        model = build_model(cfg)
        rigid = [m.law != LAW_HERTZ for m in model.meshes]
        assert sorted(rigid) == [False] * 3 + [True] * 3
        table = rigid_friction(cfg, model)
        assert (table is not None) == (name == "film")
        runs[name] = simulate(model, 0.004, cfg.simulation["step"], 8, friction=table, one_pass=True)
    film, impact = runs["film"], runs["impact"]
    assert film.linearised == 0 and impact.linearised > 0.5 * impact.steps
    assert np.all(film.damping["power"][-100:, rigid] > 0)  # the rigid meshes' films act
