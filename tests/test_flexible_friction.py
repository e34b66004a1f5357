"""Tooth friction in the flexible model (issue 24,
flexgear.dynamics.flexible.compliant.compliant_friction): the frictionless model bit for bit at a
zero coefficient, the energy balance, the sign change at the pitch point, the mesh efficiency
against Ohlendorf's closed form, the Newton tangent against finite differences.

The spur pair flexible as in tests/test_flexible_errors.py (both gears at mesh level 0, no
shafts, a 5 % mesh damping ratio), at the preset's 10 Hz, 200 N m, constant coefficient 0.05:
the compliant contacts' rigid overlap (the mesh deflection) is 19 to 35 um. With modal
coordinates (``dynamic_cutoff`` = MODAL: the pinion's modes at 31, 44.5, 44.5 kHz, the wheel's at
43, 55, 55 kHz) the friction also reaches them (flexgear.dynamics.flexible.sliding): the
elastic sliding speed and the modal friction force against the FE mode shapes at the contact
point, built here from the FE nodes, and the energy balance with the modal work."""
import functools
import math
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.config.faults import mesh_pairs
from flexgear.dynamics.flexible.reductions import body_reduction, reduce_flexible_gears
from flexgear.dynamics.integrator.friction import rigid_friction
from flexgear.reduction.flank import flank_group
from flexgear.stiffness.compliance import DEFAULT_SPREAD, MIN_SPREAD
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
MODAL = 60e3  # Hz: [flexible] dynamic_cutoff of the runs with modal coordinates


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
def _simulate(lub=LUB, t_end=0.3, modal=0.0):
    """(cfg, model, Integration) of the flexible spur pair at 10 Hz, every step recorded
    (``modal``: the dynamic cutoff [Hz], 0: every mode condensed)."""
    cfg = _cfg(lub)
    cfg.flexible.update(dynamic_cutoff=modal)
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
    rubs_cfg = flexible_spur("\n[lubrication]\n" + LUB + "viscosity = 0.05\n")
    rubs = flexgear.run(rubs_cfg)
    m = rubs.meshes["pinion-wheel"]
    back = load(save(rubs, tmp_path / "mu.h5")).meshes["pinion-wheel"]
    for f in ("friction_force", "friction_power", "sliding_speed", "contact_position", "pair_friction_force",
              "film_central"):
        assert np.array_equal(getattr(back, f), getattr(m, f), equal_nan=True)
    far = (m.pair_force > 0) & (np.abs(m.sliding_speed) > 5 * 0.01)
    assert np.allclose(np.abs(m.pair_friction_force[far]), MU * m.pair_force[far], rtol=1e-3)
    assert 0.97 < m.attrs["mesh_efficiency"] < 1.0
    # a film on the involutes (the ISO path of contact), none at the compliant teeth's tip corners beyond it
    gf, ga = mesh_pairs(rubs_cfg)["pinion-wheel"][2].path_of_contact
    s, loaded = m.contact_position, m.pair_force > 0
    inside = loaded & (s >= -gf) & (s <= ga)
    assert np.all(np.isfinite(m.film_central[inside])) and np.all(m.film_central[inside] > 0)
    assert np.all(np.isnan(m.film_central[loaded & ~inside]))
    assert m.attrs["film_corner_contacts"] == np.count_nonzero(loaded & ~inside)


def test_energy_balance():
    """In steady state, over whole mesh cycles, input minus output power equals the power the
    friction dissipates within 0.5 %: the friction loads on the floating frames and the sliding
    speeds are consistent (every mode condensed here: they are normal only, so the friction does
    no work on them; with modal coordinates see test_energy_balance_with_modal_coordinates), and
    the mesh and modal damping dissipate little.

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
    """Each tooth pair's friction force has the sign of the kinematic sliding speed u_2 - u_1
    (flexgear's sign: t . (V_a - V_b), t = (-n_y, n_x) against the pinion's rolling motion)
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
    expect = u2 - u1
    depth = integ.pair_f[sl, 0, :, 1][on]
    clear = np.abs(expect) > 3 * 0.01 + (np.abs(w1) + np.abs(w2)) * np.max(depth)
    assert clear.sum() > 0.8 * on.sum()
    assert np.all(np.sign(f[on][clear]) == np.sign(expect[clear]))
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


@functools.lru_cache(maxsize=None)
def _modal_state(lub=LUB):
    """(cfg, model, friction table, q, v, t, nr): the model with ``[lubrication]`` ``lub`` and the
    modes below MODAL as coordinates, at the loaded state of _simulate() (every mode condensed)
    with the modal coordinates at rest added (q, v); nr rigid coordinates."""
    cfg = _cfg(lub)
    cfg.flexible.update(dynamic_cutoff=MODAL)
    model = build_model(cfg)
    fr = rigid_friction(cfg, model)
    _, _, integ = _simulate()
    nr = integ.q.size
    q0, _ = model.initial_state()
    assert q0.size > nr
    pad = np.zeros(q0.size - nr)
    return cfg, model, fr, np.concatenate([integ.q, pad]), np.concatenate([integ.v, pad]), integ.nsteps * H, nr


def _tangents(lub):
    """(Kt, Kd, Ct, Cd, nr): the friction's part of the Newton matrices (with minus without
    friction) and central differences of its generalised force, at the loaded state of
    _simulate() with the modes below MODAL as coordinates at rest; nr rigid coordinates."""
    _, model, fr, q, v, t, nr = _modal_state(lub)

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
    return Kt, Kd, Ct, Cd, nr


def test_friction_tangent_is_the_derivative():
    """The friction's part of the Newton matrices (with minus without friction) against central
    differences of its generalised force, at a loaded state with modal coordinates (modes below
    60 kHz as coordinates): C_t to 1e-4 (the velocities enter through v_s and the damper
    exactly); K_t to 2 % of its largest entry (the changes of the contact point, normal and
    arms with q are left out, as in the normal force's tangent: mu F / rho against mu k)."""
    Kt, Kd, Ct, Cd, nr = _tangents(LUB)
    assert np.abs(Kt[:, nr:]).max() > 0  # the normal force's modal columns reach the friction
    assert np.max(np.abs(Ct - Cd)) < 1e-4 * np.max(np.abs(Ct))
    assert np.max(np.abs(Kt - Kd)) < 0.02 * np.max(np.abs(Kt))


def test_modal_friction_tangent_is_the_derivative():
    """The modal blocks of the friction's tangent against central differences, with the smooth
    law (v0 = 1 m/s, so that mu changes with v_s at the state): the modal rows (the force -f T)
    and the modal rates' columns (through the elastic sliding speed, -T F dmu/dv_s T^T) of C_t
    to 1e-4 of their own largest entry; the modal rows of K_t (through the normal force, f =
    mu F) to 2 % (as the whole K_t)."""
    Kt, Kd, Ct, Cd, nr = _tangents(LUB + "sliding_speed_scale = 1.0\n")
    for rows, cols in ((slice(nr, None), slice(None)), (slice(None), slice(nr, None))):
        assert np.abs(Ct[rows, cols]).max() > 0
        assert np.max(np.abs(Ct - Cd)[rows, cols]) < 1e-4 * np.max(np.abs(Ct[rows, cols]))
    assert np.abs(Kt[nr:]).max() > 0
    assert np.max(np.abs(Kt - Kd)[nr:]) < 0.02 * np.max(np.abs(Kt[nr:]))


# ---- the modal coordinates (flexgear.dynamics.flexible.sliding) -------------------------------
def fe_patch_displacement(red, tooth, side, r, cols):
    """Patch-weighted means over flank (tooth, side) of a reduced gear at contact radius r of the
    FE basis columns ``cols``, in the body frame, built from the FE nodes: the quadratic facets'
    vertex and midside values and positions, the unit-resultant biweight patch of
    flexgear.reduction.flank (half-width DEFAULT_SPREAD modules, narrowed to the flank's end,
    down to MIN_SPREAD) in the involute arc length, the 5-point Gauss rule on each facet of the
    reduction's assembly (skfem intorder 8). (The biweight's support ends fall inside facets: a
    40-point rule differs by up to 3 % where the patch narrows at the flank's ends, the normal
    table's quadrature error as much as the tangential one's; 2e-4 elsewhere.)
    Returns (U, T, d): the displacement vector (2, len(cols)) [m per unit], its component along
    the flank's own tangent d = R n_in (len(cols),) (n_in into the tooth, towards the tooth's
    centre line; R the turn by +90 degrees) and the mean of d (2,)."""
    fe, gear = red.body.model, red.gear
    V = np.asarray(red.body.basis)[:, cols]
    bd = fe.basis
    ref = fe.mesh.facets[:, fe.mesh.boundaries[flank_group(gear, 0, side)]]
    S = (np.hypot(*fe.mesh.p[:, np.unique(ref)]) ** 2 - gear.rb ** 2) / (2 * gear.rb)
    Sc = (r * r - gear.rb ** 2) / (2 * gear.rb)
    w = min(DEFAULT_SPREAD * gear.module, max(MIN_SPREAD * gear.module, min(Sc - S.min(), S.max() - Sc)))
    xi, wq = np.polynomial.legendre.leggauss(5)
    xi, wq = 0.5 * (xi + 1.0), 0.5 * wq
    N = np.array([(1 - xi) * (1 - 2 * xi), xi * (2 * xi - 1), 4 * xi * (1 - xi)])  # vertex 0, 1, midside
    dN = np.array([4 * xi - 3, 4 * xi - 1, 4 - 8 * xi])
    U, T, d_mean, den = np.zeros((2, len(cols))), np.zeros(len(cols)), np.zeros(2), 0.0
    for f in fe.mesh.boundaries[flank_group(gear, tooth, side)]:
        dofs = [bd.nodal_dofs[:, v] for v in fe.mesh.facets[:, f]] + [bd.facet_dofs[:, f]]
        X = np.array([bd.doflocs[:, d[0]] for d in dofs])  # (3, 2) positions
        u = np.einsum("aq,aic->qic", N, np.array([V[d] for d in dofs]))  # (points, 2, cols)
        x, dx = N.T @ X, dN.T @ X
        ds = np.hypot(*dx.T)
        tau = dx / ds[:, None]
        n_in = np.stack([-tau[:, 1], tau[:, 0]], axis=1)
        e_phi = np.stack([-x[:, 1], x[:, 0]], axis=1)
        n_in *= np.sign(np.sum(n_in * (-side * e_phi), axis=1))[:, None]
        d = np.stack([-n_in[:, 1], n_in[:, 0]], axis=1)
        p = np.clip(1.0 - (((x ** 2).sum(1) - gear.rb ** 2) / (2 * gear.rb) - Sc) ** 2 / w ** 2, 0.0, None) ** 2
        pw = p * ds * wq
        U += np.einsum("q,qic->ic", pw, u)
        T += np.einsum("q,qi,qic->c", pw, d, u)
        d_mean += pw @ d
        den += pw.sum()
    return U / den, T / den, d_mean / den


def _fe_contacts(cfg, model, out):
    """Per loaded compliant contact of an evaluation: (mesh, slot, t = (-n_y, n_x), [side a, side
    b]), each side (U, T, d) of fe_patch_displacement at the contact's tooth, flank and radius on
    that body for its modal coordinates, U and d turned into the global frame."""
    reds = reduce_flexible_gears(cfg)
    names = [b.name for b in model.bodies]
    c_ = out["work"].contacts
    rows = []
    for c in range(c_.joint_count[0]):
        m, kept = c_.joint_mesh[c], c_.joint_slot[c]
        if kept < 0 or c_.force[m, kept] <= 0.0:
            continue
        mesh = model.meshes[m]
        sides = []
        for body, tooth, side, r in ((mesh.a, c_.joint_i[c, 0], c_.flank_side_a[c], c_.flank_radius_a[c]),
                                     (mesh.b, c_.joint_i[c, 1], c_.flank_side_b[c], c_.flank_radius_b[c])):
            f = [fb.body for fb in model.flex].index(body)
            fb = model.flex[f]
            red = body_reduction(reds, names[body], fb.attrs["gear"])
            nq = red.body.n_interface
            U, T, d = fe_patch_displacement(red, tooth, side, r, np.arange(nq, nq + fb.modes))
            th = out["pose"][body, 2]
            rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
            sides.append((rot @ U, T, rot @ d))
        rows.append((m, kept, np.array([-c_.ny[m, kept], c_.nx[m, kept]]), sides))
    return rows


def _first_modal(model):
    """First modal coordinate of each flexible body (model.flex order), after the rigid ones."""
    q0, _ = model.initial_state()
    first = q0.size - sum(fb.modes for fb in model.flex)
    return np.concatenate([[first], first + np.cumsum([fb.modes for fb in model.flex])[:-1]]).astype(int)


def test_elastic_sliding_speed_is_the_fe_tangential_velocity():
    """The kernel's sliding speed with modal rates imposed, less that at rest, equals the flanks'
    tangential velocity computed from the FE mode shapes at the contact point
    (fe_patch_displacement): T_a . q_a' + T_b . q_b' along each flank's own tangent within 1e-3 of
    the elastic speeds' magnitude (the kernel interpolates the tables linearly between 129
    radii); and t . (U_a q_a' - U_b q_b') along the contact's tangent t, the physical sliding
    velocity, within the FE flank's misalignment with the search's involute: |sin delta| times
    the normal elastic speeds (delta the angle between the flank's mean tangent and t; the
    level-0 mesh's quadratic facets follow the involute to about 1e-2 rad). The modal rates
    change neither the contacts nor their normal forces."""
    cfg, model, fr, q, v, t, nr = _modal_state()
    rng = np.random.default_rng(24)
    vd = v.copy()
    vd[nr:] = rng.uniform(-0.01, 0.01, q.size - nr)  # [sqrt(kg) m/s]: elastic flank speeds of mm/s
    moving, still = evaluate(model, q, vd, t, friction=fr), evaluate(model, q, v, t, friction=fr)
    assert np.array_equal(moving["cf"], still["cf"])
    first = _first_modal(model)
    got, own, along_t, scale, bound = [], [], [], [], []
    for m, kept, tvec, sides in _fe_contacts(cfg, model, moving):
        own.append(0.0)
        along_t.append(0.0)
        scale.append(0.0)
        bound.append(0.0)
        for (U, T, d), body, sign in zip(sides, (model.meshes[m].a, model.meshes[m].b), (1.0, -1.0)):
            f = [fb.body for fb in model.flex].index(body)
            qd = vd[first[f]:first[f] + model.flex[f].modes]
            own[-1] += T @ qd
            along_t[-1] += sign * tvec @ U @ qd
            scale[-1] += abs(T @ qd)
            sin_delta = abs(d[0] * tvec[1] - d[1] * tvec[0]) / np.hypot(*d)
            bound[-1] += sin_delta * np.hypot(*(U @ qd)) + 1e-3 * abs(T @ qd)
        got.append(moving["work"].friction.sliding[m, kept] - still["work"].friction.sliding[m, kept])
    got = np.array(got)
    assert len(got) >= 2 and min(scale) > 1e-3
    assert np.allclose(got, own, rtol=0, atol=1e-3 * max(scale))
    assert np.all(np.abs(got - np.array(along_t)) <= np.array(bound))


def test_modal_friction_force_is_the_tangential_shapes_times_the_force():
    """The friction's generalised force on the modal coordinates (the rhs with minus without
    friction at the same state, whose normal forces are the same) is Phi_t^T f: per contact the
    FE tangential shapes at the contact point (fe_patch_displacement's T, along each flank's own
    tangent d = R n_in) times the friction force on that gear, -f t on gear a and +f t on gear b
    (t = d on a, -d on b: -f T on both), within 1e-3 of its largest entry; and the displacement
    vectors U dotted with the force along the contact's t within the flanks' misalignment with
    the search's involute (|sin delta| |U| f per mode, as the sliding speed's test)."""
    cfg, model, fr, q, v, t, nr = _modal_state()
    on, off = evaluate(model, q, v, t, friction=fr), evaluate(model, q, v, t)
    assert np.array_equal(on["cf"][..., 0], off["cf"][..., 0])
    first = _first_modal(model)
    own, along_t, bound = np.zeros(q.size), np.zeros(q.size), np.zeros(q.size)
    for m, kept, tvec, sides in _fe_contacts(cfg, model, on):
        f = on["work"].friction.force[m, kept]
        for (U, T, d), body, sign in zip(sides, (model.meshes[m].a, model.meshes[m].b), (-1.0, 1.0)):
            i = [fb.body for fb in model.flex].index(body)
            sl = slice(first[i], first[i] + model.flex[i].modes)
            own[sl] += -f * T
            along_t[sl] += U.T @ (sign * f * tvec)
            sin_delta = abs(d[0] * tvec[1] - d[1] * tvec[0]) / np.hypot(*d)
            bound[sl] += abs(f) * (sin_delta * np.hypot(*U) + 1e-3 * np.abs(T))
    got = on["rhs"] - off["rhs"]
    assert np.all(np.abs(own[nr:]) > 1.0)  # N/sqrt(kg): a load on every mode of both gears
    assert np.allclose(got[nr:], own[nr:], rtol=0, atol=1e-3 * np.abs(own[nr:]).max())
    assert np.all(np.abs(got[nr:] - along_t[nr:]) <= bound[nr:])


def test_energy_balance_with_modal_coordinates():
    """With the gears' modes below MODAL as coordinates (the friction's tangential load on them
    and their flanks' elastic sliding included), in steady state over whole mesh cycles the
    input minus the output power equals the power the friction dissipates, sum f v_s with the
    elastic v_s, within 0.5 % (as test_energy_balance). The modes (31 to 55 kHz) follow the
    friction's load nearly quasi-statically, so their share of the balance is small (zeroing the
    tangential tables moves input minus output by 0.03 %): this checks that the modal terms keep
    the balance and the Newton iteration sound; the modal force and the elastic sliding speed
    themselves are checked against the FE shapes above."""
    _, model, integ = _simulate(modal=MODAL)
    sl = _cycles(integ, model, 0.15)
    p_in, p_out, p_f = _powers(integ, sl)
    assert p_f > 5e-3 * p_in
    assert p_in - p_out == pytest.approx(p_f, rel=0.005)
    assert integ.rejected == 0 and integ.max_iter <= _simulate(None, modal=MODAL)[2].max_iter


def test_zero_coefficient_with_modal_coordinates_is_frictionless_bit_for_bit():
    """With modal coordinates the friction path at mu = 0 on every mesh (the flanks' elastic
    sliding speed, the modal force -f T, the tangential rows in the Newton matrices and the
    one-pass step) changes no record of the frictionless run, while the elastic sliding speed
    is there (the recorded sliding speeds differ from the rigid frames' alone)."""
    cfg = _cfg(LUB)
    cfg.flexible.update(dynamic_cutoff=MODAL)
    model = build_model(cfg)
    fr = rigid_friction(cfg, model)
    fr.params.mu[:] = 0.0
    assert np.all(fr.tangent_offset >= 0) and fr.tangent_shape.size > 0
    off = simulate(model, 0.04, H, 1, alpha=-0.1)
    on = simulate(model, 0.04, H, 1, alpha=-0.1, friction=fr)
    for k in ("body", "mesh", "pair_f", "pair_i", "q", "v"):
        assert np.array_equal(getattr(off, k), getattr(on, k)), k
    assert off.newton == on.newton
    assert np.all(on.friction["force"] == 0.0)


def test_flank_samples_refuse_an_unknown_direction():
    """The flank samples' direction is "normal" or "tangential": another is a ConfigError naming
    it, before any assembly."""
    from flexgear.errors import ConfigError
    from flexgear.reduction.flank import flank_samples

    with pytest.raises(ConfigError, match="direction = 'radial'"):
        flank_samples(None, None, [0.02], direction="radial")
