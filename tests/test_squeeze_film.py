"""Squeeze-film mesh damping in the rigid (IMPACT) model (issue 24 item 3,
``[lubrication] damping = "squeeze_film"``, flexgear.dynamics.integrator.friction.squeeze_contact):
each contact's damping force against the closed form at a prescribed approach speed, its Newton
tangent in the velocities against finite differences, the IMPACT damper replaced (not added to),
the energy balance, and a lighter film damping giving a larger force fluctuation at resonance.

The closed form, written out here independently of flexgear's kernels: the squeeze film of two
cylinders of relative radius R and length L approaching at d delta/dt through an isoviscous film of
thickness h, F = 3 sqrt(2) pi eta L (R / h)^(3/2) d delta/dt (Reynolds' equation for pure squeeze,
e.g. Hamrock, Schmid & Jacobson, Fundamentals of Fluid Film Lubrication, 2004), at the central
film thickness of Dowson & Toyoda (1979), h_c = 3.06 R U^0.69 G^0.56 W^-0.10, U = eta u_e / (E' R),
G = alpha E', W = w / (E' R), E' = 2 E*, w the elastic contact load per face width."""
import functools
import math
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.config import loads_config, preset_path
from flexgear.dynamics.integrator.friction import rigid_friction
from flexgear.dynamics.integrator.simulation import evaluate, simulate
from flexgear.app.run import record_bytes, time_grid
from flexgear.dynamics.model.assembly import build_model
from flexgear.results.store import load, save
from test_rigid_friction import _cycles

SPUR = preset_path("spur_pair").read_text()
T_LOAD = 200.0  # N m on the spur preset's wheel
ETA = 0.0235  # Pa s: ISO VG 100 at 70 degC
ALPHA = 2.0e-8  # 1/Pa
E, NU, WIDTH = 2.1e11, 0.3, 0.020  # Pa, -, m: the preset's steel and face width
FILM = f'damping = "squeeze_film"\nviscosity = {ETA}\npressure_viscosity = {ALPHA}\n'


def _text(lub=FILM + "friction_coefficient = 0.0\n", contact_damping=3000.0, speed=10.0):
    return (SPUR.replace("damping = 3000.0", f"damping = {contact_damping}")
            .replace("speed_hz = 10.0", f"speed_hz = {speed}") + "\n[lubrication]\n" + lub)


def _model(text):
    cfg = loads_config(text)
    model = build_model(cfg)
    return cfg, model, rigid_friction(cfg, model)


def _approach_state(model, table, approach):
    """(q, v): the wheel turned into the pinion by 4e-4 rad (about 8 um of penetration along the
    line of action), its speed changed so that the flanks close at about ``approach`` [m/s]
    (negative: open)."""
    q, v = model.initial_state()
    j = model.coordinate_names().index("wheel.theta")
    for sign in (1.0, -1.0):
        qq = q.copy()
        qq[j] += sign * 4e-4
        if evaluate(model, qq, v)["count"][0] > 0:
            break
    else:
        raise AssertionError("no contact either way")
    ddot = [_closed_form(model, evaluate(model, qq, v + dw * np.eye(len(v))[j], friction=table), 0)[1]
            for dw in (0.0, 1.0)]
    vv = v.copy()
    vv[j] += (approach - ddot[0]) / (ddot[1] - ddot[0])
    return qq, vv


def _closed_form(model, e, c):
    """(F_d, d delta/dt) of contact c of the evaluation ``e``: the closed form (module docstring)."""
    km = model.pack()
    K, ex = km.meshes.K[0], km.meshes.e[0]
    force, depth, px, py, nx, ny = e["cf"][0, c]
    pose, vel = e["pose"], e["vel"]
    a, b = model.meshes[0].a, model.meshes[0].b
    P = np.array([px, py])
    n = np.array([nx, ny])
    t = np.array([-ny, nx])

    def velocity(i):  # material velocity of body i at P
        r = P - pose[i, :2]
        return vel[i, :2] + vel[i, 2] * np.array([-r[1], r[0]])

    ddot = n @ (velocity(b) - velocity(a))
    ue = 0.5 * t @ (velocity(a) + velocity(b))
    rho_a, rho_b = abs((P - pose[a, :2]) @ n), abs((P - pose[b, :2]) @ n)
    R = rho_a * rho_b / (rho_a + rho_b)
    L = WIDTH
    w = K * depth ** ex / L
    e_prime = E / (1.0 - NU ** 2)  # E' = 2 E*, 1/E* = 2 (1 - nu^2) / E (two steel gears)
    h = 3.06 * R * (ETA * abs(ue) / (e_prime * R)) ** 0.69 * (ALPHA * e_prime) ** 0.56 * (w / (e_prime * R)) ** -0.10
    c_sq = 3.0 * math.sqrt(2.0) * math.pi * ETA * L * (R / h) ** 1.5
    return c_sq * ddot, ddot, K * depth ** ex


@pytest.mark.parametrize("ue, w, R", [(0.5, 2.5e5, 3.8e-3), (15.0, 5e5, 3.8e-3), (-2.0, 1e3, 2e-2),
                                       (0.004, 2.5e5, 5e-3)])
def test_film_coefficient_is_the_kernels_composed(ue, w, R):
    """The solver's coefficient (squeeze_film_factor, squeeze_film_slopes) is the squeeze film
    at the central film thickness of the friction's kernels (1e-12; the entrainment speed floored
    at v0 = 0.01 m/s), and its slopes are its derivatives (central differences, 1e-6; 0 in u_e
    below the floor)."""
    from flexgear.gears.tribology import (central_film_thickness, squeeze_film_damping, squeeze_film_factor,
                                          squeeze_film_slopes)
    es = E / (2.0 * (1.0 - NU ** 2))
    k = squeeze_film_factor(ETA, ALPHA, es, WIDTH)
    c, dcu, dcw = squeeze_film_slopes(k, 0.01, ue, w, R)
    hc = central_film_thickness(max(abs(ue), 0.01), ETA, ALPHA, w, R, es)
    assert c == pytest.approx(squeeze_film_damping(ETA, R, hc, WIDTH), rel=1e-12)
    du, dw = 1e-6 * abs(ue), 1e-6 * w
    fd_u = (squeeze_film_slopes(k, 0.01, ue + du, w, R)[0] - squeeze_film_slopes(k, 0.01, ue - du, w, R)[0]) / (2 * du)
    fd_w = (squeeze_film_slopes(k, 0.01, ue, w + dw, R)[0] - squeeze_film_slopes(k, 0.01, ue, w - dw, R)[0]) / (2 * dw)
    assert dcu == pytest.approx(fd_u, rel=1e-6, abs=1e-9 * c / max(abs(ue), 0.01))
    assert dcw == pytest.approx(fd_w, rel=1e-6)
    assert (dcu == 0.0) == (abs(ue) < 0.01)


@pytest.mark.parametrize("approach", [0.02, -0.004])
def test_pair_damping_force_is_the_closed_form(approach):
    """At a prescribed approach speed (the wheel's speed changed so that the flanks close or
    open at about ``approach`` m/s), each contact's recorded damping force is the closed form
    (1e-9), and its normal force the elastic part plus it."""
    _, model, table = _model(_text())
    q, v = _approach_state(model, table, approach)
    e = evaluate(model, q, v, friction=table)
    fr = e["work"].friction
    count = e["count"][0]
    assert count >= 1
    for c in range(count):
        fd, ddot, fe = _closed_form(model, e, c)
        assert ddot * approach > 0 and ddot == pytest.approx(approach, rel=0.05)  # the set-up
        assert fr.damping[0, c] == pytest.approx(fd, rel=1e-9)
        assert e["cf"][0, c, 0] == pytest.approx(max(fe + fd, 0.0), rel=1e-9)
    assert fr.damping_power[0] == pytest.approx(sum(fr.damping[0, c] * _closed_form(model, e, c)[1]
                                                    for c in range(count)), rel=1e-9)


@pytest.mark.parametrize("lub", [FILM + "friction_coefficient = 0.0\n", FILM + "friction_coefficient = 0.05\n"])
def test_velocity_tangent_is_the_derivative(lub):
    """The damping matrix Ct = -dQ/dq' (film, and film with friction: the friction force follows
    the normal force's change with the entrainment speed) equals central differences of the
    generalised force in the velocities (1e-6), at an approach speed a tenth of the entrainment
    speed so that the film coefficient's change with u_e (dc/du_e d delta/dt) matters."""
    _, model, table = _model(_text(lub))
    q, v = _approach_state(model, table, 0.05)
    e = evaluate(model, q, v, friction=table)
    assert np.any(e["work"].friction.damping[0] != 0.0)
    Ct = e["Ct"].copy()
    for k in range(len(v)):
        dv = 1e-6 * max(abs(v[k]), 1.0)
        up, dn = v.copy(), v.copy()
        up[k] += dv
        dn[k] -= dv
        d = (evaluate(model, q, up, friction=table)["rhs"] - evaluate(model, q, dn, friction=table)["rhs"]) / (2 * dv)
        np.testing.assert_allclose(-d, Ct[:, k], rtol=1e-6, atol=1e-9 * np.abs(Ct).max())


def _short_run(text):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(text)
        cfg.simulation.update(run_in=0.02, duration=0.02)
        return flexgear.run(cfg)


def test_squeeze_film_replaces_the_impact_damper(tmp_path):
    """With the squeeze film the [contact] damper plays no part: a run with the paper's 3000 N s/mm
    and one with 30 N s/mm are equal bit for bit; the film's damping differs from the IMPACT
    damper's (the runs differ from the IMPACT run), and the result carries its outputs, written
    and read back."""
    film = _short_run(_text())
    back = load(save(film, tmp_path / "film.h5")).meshes["pinion-wheel"]
    for f in ("damping_power", "pair_damping_force"):
        assert np.array_equal(getattr(back, f), getattr(film.meshes["pinion-wheel"], f))
    light = _short_run(_text(contact_damping=30.0))
    impact = _short_run(_text('viscosity = 0.0235\nfriction_coefficient = 0.0\n'))
    m, ml, mi = (r.meshes["pinion-wheel"] for r in (film, light, impact))
    for f in ("normal_force", "force_global", "pair_force", "penetration", "damping_power", "pair_damping_force"):
        assert np.array_equal(getattr(m, f), getattr(ml, f))
    assert not np.array_equal(m.normal_force, mi.normal_force)
    assert mi.damping_power is None and m.friction_force is None
    on = m.pair_force > 0
    assert np.all(m.pair_damping_force[m.pair_tooth_a < 0] == 0.0) and np.any(m.pair_damping_force[on] != 0.0)


@pytest.mark.parametrize("mu", [0.0, 0.05])
def test_record_estimate_counts_the_film_records(mu):
    """The memory check before a run counts the film's records (one value per mesh and step, one
    per contact slot and output sample), with and without friction: the bytes the solver
    stores."""
    cfg, model, table = _model(_text(FILM + f"friction_coefficient = {mu}\n"))
    h, every = time_grid(cfg.simulation)
    r = simulate(model, 10 * every * h, h, every, friction=table)
    assert r.records.pair_damping.shape[0] == 10
    assert record_bytes(cfg, 10, every, model) == sum(a.nbytes for a in r.records)


@functools.lru_cache(maxsize=None)
def _simulate(text, t_end=0.3, h=2.5e-5):
    cfg = loads_config(text)
    model = build_model(cfg)
    return cfg, model, simulate(model, t_end, h, 1, alpha=-0.1, friction=rigid_friction(cfg, model))


def test_energy_balance():
    """Friction off, in steady state over whole mesh cycles: the input power minus the output
    power equals the power the squeeze films dissipate (0.5 %), the only dissipation of the
    IMPACT-free mesh on rigid supports (the HHT-alpha damping of the step aside)."""
    _, model, integ = _simulate(_text())
    sl = _cycles(integ, model, 0.1)
    p_in = np.mean(integ.body[sl, 0, 6] * integ.body[sl, 0, 5])
    p_out = np.mean(T_LOAD * np.abs(integ.body[sl, 1, 5]))
    p_d = np.mean(integ.damping["power"][sl, 0])
    assert p_d > 1e-4 * p_in
    assert p_in - p_out == pytest.approx(p_d, rel=0.005)


def _fluctuation(speed, alpha, h=4e-6, t_end=0.02):
    """std / mean of the mesh's normal force over whole mesh cycles from 10 ms of a run of the
    spur pair at ``speed`` [Hz] with the film of pressure-viscosity coefficient ``alpha``
    [1/Pa], friction off (load ramp 4 ms)."""
    lub = f'damping = "squeeze_film"\nviscosity = {ETA}\npressure_viscosity = {alpha}\nfriction_coefficient = 0.0\n'
    text = (_text(lub, speed=speed).replace("ramp = 0.05", "ramp = 0.004")
            .replace("output_rate = 10000.0", "output_rate = 40000.0"))
    _, model, integ = _simulate(text, t_end, h)
    F = integ.mesh[_cycles(integ, model, 0.01), 0, 0]
    return F.std() / F.mean()


def test_lighter_film_damping_gives_a_larger_fluctuation_at_resonance():
    """The film coefficient c ~ h_c^-3/2 ~ alpha^-0.84 (h_c ~ G^0.56): with friction off the
    pressure-viscosity coefficient alpha changes the mesh damping alone. At the second-harmonic
    resonance of the spur pair's mesh mode (pinion at 185 Hz: the second mesh harmonic at 8.9
    kHz, the wheel on two pairs' linearised Hertz stiffness 2 x 1.3 F / delta at 8.1 kHz; the
    mesh force fluctuation of the lightest film peaks there over the speed, above 170 and 200
    Hz), the fluctuation grows as the damping falls, alpha = 1e-8, 2e-8, 4e-8 1/Pa (c falling by
    4^0.84 = 3.2 in all; damping ratio about 0.3 at 2e-8)."""
    light = [_fluctuation(s, 4e-8) for s in (170.0, 185.0, 200.0)]
    assert light[1] > light[0] and light[1] > light[2]
    at = [_fluctuation(185.0, a) for a in (1e-8, 2e-8, 4e-8)]
    assert at[0] < at[1] < at[2]
