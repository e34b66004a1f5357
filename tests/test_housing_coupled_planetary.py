"""MERCURY 1-A with its housing coupled into the multi-body model (issue 23, item 1, planetary set).

The preset ``mercury_1a_coupled_sensors``: the ring bolted into the housing (its elastic support,
1e8 N/m and 3.85e6 N m/rad, between the ring and the bolt circle), the sun's and the carrier's
shaft bearings (1e8 N/m) in the central seat, the feet on ground springs. Short runs: the load
ramps up over 0.05 s; the slowest decay, the coupled set's lowest mode (508 Hz, the housing on
its feet carrying the set) at 2 %, has a time constant of 16 ms.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.linalg as sla

from flexgear.app.run import run
from flexgear.config.loader import loads_config, preset_path
from flexgear.dynamics.integrator.simulation import evaluate, simulate
from flexgear.dynamics.lumped.planetary import parameters_from_config, planetary_system
from flexgear.dynamics.modal.analysis import modal_analysis, report_markdown
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.model.housing import couple_housing, foot_reactions, ground_moment
from flexgear.errors import ConfigError
from flexgear.reduction.housing import reduce_housing

PRESET = "mercury_1a_coupled_sensors"
CAST_IRON_E = 1.1e11
RING = "ring = {stiffness = 1.0e8, damping = 2.0e3, torsional_stiffness = 3.85e6, torsional_damping = 7.7}"


def text(coupled=True, stiffen=1.0, duration=0.05, quantity="acceleration", replace=()):
    """The preset's text; ``stiffen`` multiplies the housing's E and foot stiffness (and its
    cutoff by sqrt(stiffen): the fixed-interface modes rise as sqrt(E))."""
    s = preset_path(PRESET).read_text()
    s = s.replace("coupled = true ", f"coupled = {str(coupled).lower()}\nE = {CAST_IRON_E * stiffen}\n"
                  f"foot_stiffness = {1e8 * stiffen}\ncutoff = {50e3 * np.sqrt(stiffen)} ")
    s = s.replace("duration = 1.0", f"duration = {duration}").replace("run_in = 0.2", "run_in = 0.1")
    s = s.replace('quantity = "acceleration"', f'quantity = "{quantity}"')
    for a, b in replace:
        assert a in s, a
        s = s.replace(a, b)
    return s


def config(**kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return loads_config(text(**kw))


def coupled_model(cfg):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = build_model(cfg)
    red = reduce_housing(cfg.housing)
    couple_housing(model, red)
    return model, red


FLEXIBLE = """
[flexible]
gears = ["sun", "planet", "ring"]
level = 0
cutoff = 100e3
dynamic_cutoff = 0.0
"""


def _feet_balance(cfg, per):
    """Steady state, averaged over the last 20 mesh periods (momenta repeat): the ring's moment
    on the housing, the feet's ground moment, the drive and output torques and the ground
    forces' resultant, of a ``per``-steps-per-mesh-period run of 0.1 s."""
    model, red = coupled_model(cfg)
    fm = cfg.mesh_frequency()
    h = 1.0 / (fm * per)
    t_end = 0.1
    integ = simulate(model, t_end, h, 4)
    nh = model.housing.n
    last = slice(integ.nsteps - 20 * per, integ.nsteps)  # the last 20 mesh periods
    q_h = integ.modal[last, -nh:]
    names = [b.name for b in model.bodies]
    sun, carrier, ring = names.index("sun"), names.index("carrier"), names.index("ring")
    t_in = integ.body[last, sun, 6].mean()  # the sun's drive torque
    t_out = float(model.bodies[carrier].torque(t_end))  # the load on the carrier, ramped up by 0.05 s
    link = next(G for i, G in model.housing.links if i == ring)
    rb = model.bodies[ring]
    twist = integ.body[last, ring, 2] - rb.theta0 - q_h @ link[2]
    twist_rate = integ.body[last, ring, 5] - np.gradient(q_h @ link[2], h)
    m_ring = (rb.torsional_stiffness * twist + rb.torsional_damping * twist_rate).mean()  # the ring's moment on the housing
    m_feet = ground_moment(red, q_h).mean()
    F = foot_reactions(red, q_h).sum(axis=1).mean(axis=0)
    mesh = integ.mesh[last, 0, 0].mean()  # a sun-planet mesh's normal force
    return t_in, t_out, m_ring, m_feet, F, mesh


def _assert_balanced(t_in, t_out, m_ring, m_feet, F, mesh):
    assert abs(t_in) > 10.0 and abs(t_out) > 50.0
    assert abs(m_ring - (t_in + t_out)) < 1e-3 * abs(t_in + t_out), (m_ring, t_in, t_out)
    assert abs(m_feet + m_ring) < 1e-3 * abs(m_ring), (m_feet, m_ring)
    assert np.hypot(*F) < 1e-3 * mesh, (F, mesh)


def test_feet_balance_the_torques_the_set_puts_into_the_housing():
    """Steady state, averaged over whole mesh periods (momenta repeat): the housing's feet take
    the reaction of the gear set. The sun and carrier bearings sit at the centre and carry no
    moment, so the housing's moment comes through the ring's bolts: the ring's torsional spring
    moment on the housing equals the drive plus the output torque, T_in + T_out (the set's
    balance), and the feet's ground moment is its opposite (the housing's balance), both to
    0.1 % (issue 23); the ground forces sum to the set's net force on the housing, zero for
    equally spaced planets of one mass. A seat or bolt anchor that misses a row, a reaction not
    passed to the housing or a wrong sign breaks one of them."""
    _assert_balanced(*_feet_balance(config(), per=76))  # the preset's synchronous grid


def test_feet_balance_the_torques_of_the_flexible_set():
    """The same balances with the sun, the planets and the ring flexible (Craig-Bampton bodies,
    FE level 0, compliant Hertz meshes; the ring's rigid frame on its bolts): the housing's
    coordinates follow the gears' modal ones in q, and the balances hold to 0.1 % as for rigid
    gears (at half the rigid step; balances of means, which the step does not move)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(text() + FLEXIBLE)
    _assert_balanced(*_feet_balance(cfg, per=2 * 76))


def _departure(a, b):
    return np.std(a - b) / np.std(a)


def _mesh_forces(res):
    return np.concatenate([m.normal_force for m in res.meshes.values()])


def _departures(stiffen, run_in=0.1, duration=0.05):
    """The mesh forces' departure from those of the set on its supports to ground (coupled =
    false: the housing a one-way path) for housings ``stiffen`` times stiffer (E and feet)."""
    kw = dict(replace=[("run_in = 0.1", f"run_in = {run_in}")], duration=duration)
    ground = _mesh_forces(run(config(coupled=False, **kw)))
    return {s: _departure(ground, _mesh_forces(run(config(stiffen=s, **kw)))) for s in stiffen}


def test_a_stiff_housing_tends_to_the_grounded_set():
    """The grounded model is the limit of a rigid housing on rigid feet: scaling the housing's
    compliance by 1/s, the mesh forces' departure from the grounded ones falls as 1/s (first
    order in the compliance). From s = 1e3 to 1e4 it falls by a factor within [8, 12.5] of the
    first-order 10. Short runs (the load ramp and 20 ms): the start transient's departure is
    first order in the compliance too. A coupling term that does not vanish with the
    compliance (a force on a seat from the housing's mass, a wrong anchor) stalls the rate."""
    d = _departures((1e3, 1e4), run_in=0.05, duration=0.02)
    assert 8.0 < d[1e3] / d[1e4] < 12.5, d
    assert d[1e4] < 1e-2, d


@pytest.mark.slow
def test_a_stiff_housing_tends_to_the_grounded_set_in_steady_state():
    """As the fast variant, in steady state (0.05 s after a 0.1 s run-in) and from the nominal
    housing on: the nominal housing departs by order one (it moves the set's modes against the
    mesh harmonics), and from s = 100 on the departure falls as 1/s, by [8, 12.5] per decade."""
    d = _departures((1.0, 1e2, 1e3, 1e4))
    assert d[1.0] > 0.1, d
    for lo, hi in ((1e2, 1e3), (1e3, 1e4)):
        assert 8.0 < d[lo] / d[hi] < 12.5, d


def _independent_coupled_system(cfg, red, ks):
    """K, M of Lin & Parker's lumped model of the set (mesh stiffnesses ``ks``) with the reduced
    housing in ground's place, assembled here from the housing's matrices: the sun and carrier
    bearings between their centres and the seat's (u_x, u_y), the ring's bearing and torsion
    between the ring and the least-squares rigid motion of the bolt patches."""
    lumped = planetary_system(parameters_from_config(cfg, ks["sun-planet1"], ks["planet1-ring"]))
    n0, nh = lumped.n, red.n
    K = np.zeros((n0 + nh, n0 + nh))
    M = np.zeros_like(K)
    K[:n0, :n0], M[:n0, :n0] = lumped.K, lumped.M
    feet = np.zeros((nh, nh))
    for p in red.role("foot"):
        for d in (0, 1):
            feet[p.coordinates[d], p.coordinates[d]] = red.housing.foot_stiffness
    K[n0:, n0:] = 0.5 * (red.body.K + red.body.K.T) + feet
    M[n0:, n0:] = 0.5 * (red.body.M + red.body.M.T)
    seat = red.seat("sun").coordinates
    anchors = {}
    for body in ("sun", "carrier"):
        for d, axis in enumerate("xy"):
            a = np.zeros(nh)
            a[seat[d]] = 1.0
            anchors[f"{body} bearing {axis}"] = a
    fit = np.linalg.pinv(red.ring_coupling((0.0, 0.0)))  # (3, n): the bolts' rigid motion
    for d, name in enumerate(("ring bearing x", "ring bearing y", "ring torsion")):
        anchors[name] = fit[d]
    seen = set()
    for s in lumped.springs:
        if s.name in anchors:
            seen.add(s.name)
            g = np.concatenate([s.g, -anchors[s.name]])
            g0 = np.concatenate([s.g, np.zeros(nh)])
            K += s.k * (np.outer(g, g) - np.outer(g0, g0))
    assert seen == set(anchors), seen
    return K, M


def test_modal_includes_the_housing_and_matches_an_independent_construction():
    """``flexgear modal`` of the coupled preset against the eigenproblem assembled independently
    from Lin & Parker's lumped model of the set (same masses, radii, supports, and the modal
    analysis's mean mesh stiffnesses) and the housing's reduced matrices: the lowest 12
    frequencies agree within 0.1 % (the bound between the linearised rigid model and the
    lumped model on ground, tests/test_lumped.py). The housing lowers them against the set on
    ground (it adds compliance and mass), and the gear set's modes stay, only shifted: the
    count of coordinates grows by the housing's."""
    cfg = config()
    res = modal_analysis(cfg, n_positions=6)
    red = reduce_housing(cfg.housing)
    assert res.system.n == 11 + red.n and "housing" in res.system.attrs
    K, M = _independent_coupled_system(cfg, red, res.system.attrs["mesh_stiffness"])
    w2 = sla.eigh(K, M, eigvals_only=True)
    f_ind = np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)
    np.testing.assert_allclose(res.frequencies[:12], f_ind[:12], rtol=1e-5)
    ground = modal_analysis(config(coupled=False), n_positions=6)
    assert np.all(res.frequencies[:11] <= ground.frequencies[:11] * (1 + 1e-9))
    assert "coupled housing" in report_markdown(res)


def test_coupled_transfer_path_is_reciprocal():
    """Reciprocity through the coupled set: with the solver's own tangent (mass, stiffness and
    damping of the coupled model at the kinematic state), a force at sensor A's point along its
    direction gives at B the displacement that the same force at B gives at A, to round-off, at
    frequencies across the housing's modes. A tangent whose gear-housing blocks are not each
    other's transpose (a missed term of a seated bearing) breaks it. The coupled path differs
    from the housing's alone (the gear set moves with it)."""
    cfg = config()
    model, red = coupled_model(cfg)
    q0, v0 = model.initial_state()
    ev = evaluate(model, q0, np.zeros_like(v0))
    Kt, Ct, Mq = ev["Kt"], ev["Ct"], ev["Mq"]
    n, nh = Kt.shape[0], red.n
    rows = red.sensor_rows(cfg.sensors)
    r = np.zeros((2, n))
    r[:, n - nh:] = rows
    assert np.abs(r).max() > 0
    alone = red.body.K + red.ground_stiffness()
    for f in (300.0, 1200.0, 5000.0):
        w = 2 * np.pi * f
        H = np.linalg.solve(Kt - w * w * Mq + 1j * w * Ct, r.T)  # (n, 2) responses to unit forces at A, B
        ab, ba = r[1] @ H[:, 0], r[0] @ H[:, 1]
        assert abs(ab - ba) < 1e-10 * abs(ab), (f, ab, ba)
        Ha = np.linalg.solve(alone - w * w * red.body.M, rows.T)
        assert abs(rows[1] @ Ha[:, 0] - ab) > 1e-3 * abs(ab), f


def test_the_housing_sensors_hear_the_planets_pass():
    """Two carrier revolutions (f_c = 8 Hz) after the preset's run-in. MERCURY 1-A's planets
    are identical, equally spaced and in phase (z_s, z_r multiples of P = 3), so turning the
    carrier by a third maps the whole coupled set, housing included, onto itself: the housing
    sensors' steady state repeats every third of a revolution, and every line lies at a carrier
    order n = 0 (mod 3) (McFadden & Smith 1985; the record's leakage floor measured 1.2e-6 of the
    largest line). The feet break the housing's cyclic symmetry, so the planets passing the
    sensor modulate the mesh harmonics: the sidebands k f_m +- 3 f_c are there (top sensor:
    above 1e-3 of the largest mesh line; measured 1.1e-2). A planet or mesh treated unlike the
    others (phasing, force, record) breaks the symmetry and puts lines at n = +-1 (mod 3)."""
    from test_sensor_paths import line_check

    res = run(loads_config(text(duration=0.25).replace("run_in = 0.1", "run_in = 0.2")))
    for name in ("top", "side"):
        line_check(res, name, "housing_coupled", lambda n: n % 3 == 0, 1e-5)
    y = res.sensors["top"].signals["housing_coupled"]
    revs = round(y.size * res.attrs["carrier_frequency"] / res.fs)
    Y = np.abs(np.fft.rfft(y - y.mean()))
    order = np.arange(Y.size) / revs
    mesh = Y[np.isin(order, [66, 132, 198, 264])].max()
    assert Y[np.isin(order, [129, 135, 195, 201])].max() > 1e-3 * mesh


@pytest.mark.parametrize("swap, match", [
    (('sun = {stiffness = 1.0e8, damping = 2.0e3}', 'sun = "revolute"'), "supports.sun"),
    (('carrier = {stiffness = 1.0e8, damping = 2.0e3}', 'carrier = "revolute"'), "supports.carrier"),
    ((RING, "ring = {stiffness = 1.0e8, damping = 2.0e3}"), "supports.ring.torsional_stiffness"),
    ((RING, 'ring = "fixed"'), "supports.ring"),
])
def test_bad_input_names_the_support(swap, match):
    """A central member on a rigid joint cannot seat in the housing, and a ring without a
    torsional stiffness would put its reaction torque into ground: each a ConfigError naming
    the key, before anything is built (run and modal alike)."""
    cfg = config(replace=[swap])
    with pytest.raises(ConfigError, match=match):
        run(cfg)
    with pytest.raises(ConfigError, match=match.split(".torsional")[0]):
        modal_analysis(cfg)


def flexible_config(**kw):
    """The coupled preset with the sun, the planets and the ring flexible (FE level 0)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return loads_config(text(**kw) + FLEXIBLE)


def test_modal_of_the_flexible_set_includes_the_housing():
    """``flexgear modal`` of the coupled set with flexible gears: the housing's coordinates join
    the flexible system (linearised with its condensed modes). Grounding the housing's
    coordinates gives the grounded flexible set, so by Rayleigh's theorem of constraint every
    frequency of the coupled set lies at or below the grounded one of the same index; its lowest
    mode, the housing on its feet carrying the set, lies far below the grounded set's lowest
    and equals the rigid-gear coupled set's (the gears' elasticity enters it only through the
    meshes, far stiffer than the feet: 0.5 %). A housing left out, or coupled to the modal
    coordinates instead of the frames, fails one of them."""
    flx = modal_analysis(flexible_config(), n_positions=4)
    grd = modal_analysis(flexible_config(coupled=False), n_positions=4)
    rig = modal_analysis(config(), n_positions=4)
    nh = reduce_housing(config().housing).n
    assert flx.system.n == grd.system.n + nh and "housing" in flx.system.attrs
    k = grd.system.n
    assert np.all(flx.frequencies[:k] <= grd.frequencies[:k] * (1 + 1e-9))
    assert flx.frequencies[0] < 0.5 * grd.frequencies[0]
    assert flx.frequencies[0] == pytest.approx(rig.frequencies[0], rel=5e-3)


def test_modal_refuses_a_coupled_housing_it_cannot_include():
    """The lumped model has no housing body: modal analysis says so instead of leaving the
    housing out silently (flexible gears take it: above)."""
    with pytest.raises(ConfigError, match="housing.coupled = true with model = lumped"):
        modal_analysis(loads_config('model = "lumped"\n' + text()))


def test_the_coupled_housing_has_the_same_bits_on_any_blas_thread_count():
    """The coupled housing's stiffness and modal damping do not depend on the BLAS threads of the
    process that couples it (a threaded eigen-solve splits its sums by the thread count): a
    batch's serial cases, run in its driver, and its workers' cases gave mesh forces and
    sensor signals apart in their last bits."""
    from threadpoolctl import threadpool_limits

    cfg = config()
    models = []
    for threads in (2, 1):
        with threadpool_limits(limits=threads, user_api="blas"):
            models.append(coupled_model(cfg)[0].housing)
    a, b = models
    assert all(np.array_equal(getattr(a, m), getattr(b, m)) for m in ("stiffness", "damping", "mass"))
