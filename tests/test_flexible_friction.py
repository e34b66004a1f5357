"""Tooth friction in the flexible model (issue 24,
flexgear.dynamics.flexible.compliant.compliant_friction): the frictionless model bit for bit at a
zero coefficient, the energy balance, the sign change at the pitch point, the mesh efficiency
against Ohlendorf's closed form, the Newton tangent against finite differences.

The spur pair flexible as in tests/test_flexible_errors.py (both gears at mesh level 0, no
shafts, a 5 % mesh damping ratio), at the preset's 10 Hz, 200 N m, constant coefficient 0.05:
the compliant contacts' rigid overlap (the mesh deflection) is 19 to 35 um."""
import functools
import math
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.config.faults import mesh_pairs
from flexgear.dynamics.integrator.friction import rigid_friction
from flexgear.dynamics.integrator.simulation import evaluate, simulate
from flexgear.dynamics.model.assembly import build_model
from flexgear.gears.lubrication import loss_factor, roll_angles, surface_speeds
from flexgear.results.store import load, save
from test_faults_rigid import _signals
from test_flexible_errors import flexible_spur
from test_rigid_friction import _cycles, _powers, _reversals

MU = 0.05
LUB = f"friction_coefficient = {MU}\n"
H = 2.5e-5  # s, the step of tests/test_flexible_errors.py


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _cfg(lub=None, speed=10.0):
    cfg = flexible_spur("\n[lubrication]\n" + lub if lub else "")
    cfg.drive["speed_hz"] = speed
    cfg.load["ramp"] = 0.05
    return cfg


@functools.lru_cache(maxsize=None)
def _simulate(lub=LUB, t_end=0.3):
    """(cfg, model, Integration) of the flexible spur pair at 10 Hz, every step recorded."""
    cfg = _cfg(lub)
    model = build_model(cfg)
    return cfg, model, simulate(model, t_end, H, 1, alpha=-0.1, friction=rigid_friction(cfg, model))


def hv_shared(pair, s, F, weight=1.0):
    """Ohlendorf's tooth loss factor for any load sharing: (1 + 1/u) / r_b1 times the mean of
    sum_i F_i |s_i| over the mean of sum_i F_i (pairs i at contact positions s_i [m] from the
    pitch point, normal forces F_i [N], arrays (samples, pairs)); the sliding speed of rigid
    involutes is (omega_1 + omega_2) |s| and the power through the mesh omega_1 r_b1 sum F_i.
    With equal sharing over the ISO path it is :func:`~flexgear.gears.lubrication.loss_factor`
    (:func:`test_the_shared_loss_factor_is_ohlendorfs_for_equal_sharing`); ``weight``: each
    pair's friction coefficient over mu (the regularisation near the pitch point)."""
    u = pair.g2.z / pair.g1.z
    return (1.0 + 1.0 / u) / pair.g1.rb * np.sum(F * weight * np.abs(s)) / np.sum(F)


def test_the_shared_loss_factor_is_ohlendorfs_for_equal_sharing():
    """hv_shared with the pairs of rigid involutes on the ISO path (at s_0 + phi + j p_b,
    sharing the load equally) is Ohlendorf's H_V (the rigid test's closed form) to 2e-5 (the sampling of the
    jumps between single and double contact)."""
    pair = mesh_pairs(_cfg())["pinion-wheel"][2]
    gf, ga = pair.path_of_contact
    pb = pair.g1.pb
    phi = (np.arange(200000) + 0.5) / 200000 * pb
    s = -gf + phi[:, None] + pb * np.arange(-2, 3)[None, :]
    on = (s >= -gf) & (s <= ga)
    F = on / on.sum(axis=1, keepdims=True)
    assert hv_shared(pair, np.where(on, s, 0.0), F) == pytest.approx(loss_factor(pair), rel=2e-5)


def test_zero_coefficient_is_the_frictionless_flexible_run_bit_for_bit(tmp_path):
    """A constant coefficient of 0 runs the frictionless flexible model (every signal bit for
    bit, no friction datasets); the friction kernels themselves run with mu = 0 on every mesh
    change nothing either (a tangent or load term not proportional to the friction force would);
    with a coefficient the outputs are written and read back."""
    plain = flexgear.run(flexible_spur())
    zero = flexgear.run(flexible_spur("\n[lubrication]\nfriction_coefficient = 0.0\n"))
    a, b = _signals(plain), _signals(zero)
    assert sorted(a) == sorted(b)
    assert not [k for k in a if not np.array_equal(a[k], b[k])]
    assert zero.meshes["pinion-wheel"].friction_force is None
    # the friction path with mu = 0 on
    cfg = _cfg(LUB)
    model = build_model(cfg)
    fr = rigid_friction(cfg, model)
    fr.params.mu[:] = 0.0
    assert fr.on.all()
    off = simulate(model, 0.08, H, 1, alpha=-0.1)
    on = simulate(model, 0.08, H, 1, alpha=-0.1, friction=fr)
    for k in ("body", "mesh", "pair_f", "pair_i", "q", "v"):
        assert np.array_equal(getattr(off, k), getattr(on, k)), k
    assert off.newton == on.newton
    assert np.all(on.friction["force"] == 0.0) and np.any(on.friction["through"] > 0.0)
    # outputs of a run with friction and a lubricant (the film outputs too)
    rubs = flexgear.run(flexible_spur("\n[lubrication]\n" + LUB + "viscosity = 0.05\n"))
    m = rubs.meshes["pinion-wheel"]
    back = load(save(rubs, tmp_path / "mu.h5")).meshes["pinion-wheel"]
    for f in ("friction_force", "friction_power", "sliding_speed", "contact_position", "pair_friction_force",
              "film_central"):
        assert np.array_equal(getattr(back, f), getattr(m, f), equal_nan=True)
    far = (m.pair_force > 0) & (np.abs(m.sliding_speed) > 5 * 0.01)
    assert np.allclose(np.abs(m.pair_friction_force[far]), MU * m.pair_force[far], rtol=1e-3)
    assert 0.97 < m.attrs["mesh_efficiency"] < 1.0
    assert np.all(np.isfinite(m.film_central[m.pair_force > 0])) and np.all(m.film_central[m.pair_force > 0] > 0)


def test_energy_balance():
    """In steady state, over whole mesh cycles, input minus output power equals the power the
    friction dissipates within 0.5 %: the friction loads on the floating frames and the sliding
    speeds are consistent (the flanks' tangential elastic motion is left out of both, so the
    friction does no work on the elastic coordinates), and the mesh and modal damping dissipate
    little.

    Newton: no step is rejected and none takes more iterations than the frictionless run's
    most; with a smooth friction law (v0 = 1 m/s) the iterations per step are those without
    friction (within 2 %): the tangent is the derivative
    (:func:`test_friction_tangent_is_the_derivative`), and what the sharp regularisation
    (v0 = 0.01 m/s: the friction turns over in two steps at the pitch point) adds, about 8 %
    more iterations, is the law's curvature there."""
    _, model, integ = _simulate()
    sl = _cycles(integ, model, 0.15)
    p_in, p_out, p_f = _powers(integ, sl)
    assert p_f > 5e-3 * p_in
    assert p_in - p_out == pytest.approx(p_f, rel=0.005)
    plain = _simulate(None)[2]
    smooth = _simulate(LUB + "sliding_speed_scale = 1.0\n")[2]
    assert integ.rejected == 0 and smooth.rejected == 0 and integ.max_iter <= plain.max_iter
    assert smooth.newton / smooth.steps < 1.02 * plain.newton / plain.steps


def test_friction_reverses_at_the_pitch_point():
    """Each tooth pair's friction force has the sign of the kinematic sliding speed u_1 - u_2
    (Niemann & Winter; flexgear.gears.lubrication.surface_speeds with the gears' actual speeds at
    the contact position) wherever that is not within the regularisation and the compliant
    contact's offset of zero, and it reverses where the contact crosses the pitch point, within
    1e-3 of the path of contact (9.4 um). The compliant contact point is the deepest point of the
    rigid overlap of the two flanks (19 to 35 um deep): the overlap is what blurs where it
    crosses the pitch point, so the bound is below half the overlap (the rigid model's, with
    1.2 um penetration, is the same 1e-3)."""
    cfg, model, integ = _simulate()
    pair = mesh_pairs(cfg)["pinion-wheel"][2]
    sl = slice(int(0.15 / H), None)
    fr = integ.friction
    s, f = fr["position"][sl, 0], fr["pair_force"][sl, 0]
    on = np.isfinite(s)
    w1 = np.broadcast_to(integ.body[sl, 0, 5][:, None], s.shape)[on]
    w2 = np.broadcast_to(integ.body[sl, 1, 5][:, None], s.shape)[on]
    xi1, xi2 = roll_angles(pair, s[on])
    u1, u2 = surface_speeds(pair.g1.rb, xi1, w1, pair.g2.rb, xi2, w2, False)
    expect = u1 - u2
    sign = np.sign(np.sum(f[on] * expect))  # the flank tangent's orientation is the model's
    depth = integ.pair_f[sl, 0, :, 1][on]
    clear = np.abs(expect) > 3 * 0.01 + (np.abs(w1) + np.abs(w2)) * np.max(depth)
    assert clear.sum() > 0.8 * on.sum()
    assert np.all(sign * np.sign(f[on][clear]) == np.sign(expect[clear]))
    at, _ = _reversals(integ, sl)
    assert len(at) >= 30
    path = sum(pair.path_of_contact)
    assert np.max(np.abs(at)) < 1e-3 * path < 0.5 * np.median(depth[f[on] != 0])


def test_mesh_efficiency_is_the_closed_form():
    """The recorded mesh loss (friction power over the power the mesh carries, steady state,
    whole mesh cycles) is Ohlendorf's mu H_V of the run's own load sharing (hv_shared with the
    contacts' normal forces and positions, the tanh regularisation included) within 1 %.
    Against the closed form of equal sharing on the ISO path the compliance shows: the deflected
    teeth touch 0.65 mm beyond each end of the ISO path, where the sliding is fastest, and share
    the double-contact load unequally; so the loss lies between mu H_V over the ISO path and mu
    H_V with equal sharing over the whole path the contacts cover (+22 %), which bounds it
    (1 - P_out / P_in likewise)."""
    cfg, model, integ = _simulate()
    pair = mesh_pairs(cfg)["pinion-wheel"][2]
    sl = _cycles(integ, model, 0.15)
    p_in, p_out, p_f = _powers(integ, sl)
    loss = p_f / integ.friction["through"][sl, 0].mean()
    s = integ.friction["position"][sl, 0]
    F = integ.pair_f[sl, 0, :, 0]
    on = np.isfinite(s) & (F > 0)
    sa = np.where(on, np.abs(s), 0.0)
    v0 = 0.01
    wsum = np.abs(integ.body[sl, 0, 5]) + np.abs(integ.body[sl, 1, 5])
    reg = np.tanh(wsum[:, None] * sa / v0)  # mu tanh(v_s / v0), v_s = (omega_1 + omega_2) |s|
    assert loss == pytest.approx(MU * hv_shared(pair, sa, np.where(on, F, 0.0), reg), rel=0.01)
    gf, ga = pair.path_of_contact
    pb, u = pair.g1.pb, pair.g2.z / pair.g1.z

    def hv(gf, ga):  # H_V of equal sharing over the path (-gf, ga), the rigid test's form
        return math.pi * (u + 1.0) / (pair.g1.z * u) * (1.0 - (gf + ga) / pb + (ga / pb) ** 2 + (gf / pb) ** 2)

    covered = hv(-np.min(s[on]), np.max(s[on]))
    assert hv(gf, ga) == pytest.approx(loss_factor(pair), rel=1e-12)
    assert MU * loss_factor(pair) < loss < MU * covered
    assert MU * loss_factor(pair) < 1.0 - p_out / p_in < MU * covered


def test_friction_tangent_is_the_derivative():
    """The friction's part of the Newton matrices (with minus without friction) against central
    differences of its generalised force, at a loaded state with modal coordinates (modes below
    60 kHz as coordinates): C_t to 1e-4 (the velocities enter through v_s and the damper
    exactly); K_t to 2 % of its largest entry (the changes of the contact point, normal and
    arms with q are left out, as in the normal force's tangent: mu F / rho against mu k)."""
    cfg = _cfg(LUB)
    cfg.flexible.update(dynamic_cutoff=60e3)
    model = build_model(cfg)
    fr = rigid_friction(cfg, model)
    _, _, integ = _simulate()
    nr = integ.q.size
    q0, v0 = model.initial_state()
    assert q0.size > nr  # modal coordinates after the rigid ones
    q = np.concatenate([integ.q, np.zeros(q0.size - nr)])
    v = np.concatenate([integ.v, np.zeros(q0.size - nr)])
    t = integ.nsteps * H

    def part(q, v):
        a, b = evaluate(model, q, v, t, friction=fr), evaluate(model, q, v, t)
        assert np.all(a["cf"][..., 0] == b["cf"][..., 0])
        return a["rhs"] - b["rhs"], a["Kt"] - b["Kt"], a["Ct"] - b["Ct"], a["count"].sum()

    Q, Kt, Ct, cnt = part(q, v)
    assert cnt >= 1 and np.abs(Q).max() > 0
    eq, ev = 1e-9, 1e-6
    Kd, Cd = np.zeros_like(Kt), np.zeros_like(Ct)
    for j in range(q.size):
        dq = np.zeros(q.size)
        dq[j] = eq
        Kd[:, j] = -(part(q + dq, v)[0] - part(q - dq, v)[0]) / (2 * eq)
        dv = np.zeros(q.size)
        dv[j] = ev
        Cd[:, j] = -(part(q, v + dv)[0] - part(q, v - dv)[0]) / (2 * ev)
    assert np.abs(Kt[:, nr:]).max() > 0  # the normal force's modal columns reach the friction
    assert np.max(np.abs(Ct - Cd)) < 1e-4 * np.max(np.abs(Ct))
    assert np.max(np.abs(Kt - Kd)) < 0.02 * np.max(np.abs(Kt))
