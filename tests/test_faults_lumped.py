"""Faults and errors in the lumped model (flexgear.dynamics.lumped.faults): zero size is the
healthy model bit for bit; a crack changes the mesh stiffness only while the cracked tooth is on
the path of contact (found by the rigid contact search) and more the deeper it is; eccentricity
and pitch errors give the closed-form transmission error; a planet pin error gives the load
sharing of the rigid model's statics with the pin moved."""
import math
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.config import loads_config, preset_path
from flexgear.dynamics.contact.search import MAX_CONTACTS, MeshPair, mesh_contacts
from flexgear.dynamics.lumped.model import build_lumped
from flexgear.errors import ConfigError
from flexgear.gears.geometry import GearPair

SPUR = 'model = "lumped"\n' + preset_path("spur_pair").read_text()
MERCURY = 'model = "lumped"\n' + preset_path("mercury_1a").read_text()
COARSE_FE = "\n[fe]\nlevel = 0\n"  # the crack FE on the coarsest mesh (the default suite's budget)
BACKLASH = ("thinning = 0.0 ", "thinning = 20.0e-6 ")  # errors that move material towards the mate need it


def crack(depth, tooth=3, flank="left", gear="pinion", width=1.0):
    return (f'\n[[faults]]\nkind = "crack"\ngear = "{gear}"\ntooth = {tooth}\nflank = "{flank}"\n'
            f'depth = {depth}\nwidth_fraction = {width}\n')


def _cfg(text):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return loads_config(text)


def _build(text):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_lumped(_cfg(text))


def _run(text, run_in, duration):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(text)
        cfg.simulation.update(run_in=run_in, duration=duration)
        return flexgear.run(cfg)


@pytest.fixture(scope="module")
def healthy_spur():
    return _build(SPUR + COARSE_FE)


# ------------------------------------------------------------------ zero size
def test_zero_size_faults_and_errors_give_the_healthy_lumped_run_bit_for_bit():
    zero = (crack(0.0) + '\n[[faults]]\nkind = "missing"\ngear = "wheel"\ntooth = 2\nheight_fraction = 1.0\n'
            '\n[errors.eccentricity.pinion]\nmagnitude = 0.0\n[errors.pitch.wheel]\ndeviations = '
            + str([0.0] * 21) + '\n')
    a = _run(SPUR, 0.06, 0.02)
    b = _run(SPUR + zero, 0.06, 0.02)
    for name, m in a.meshes.items():
        assert np.array_equal(m.normal_force, b.meshes[name].normal_force)
    for name, body in a.bodies.items():
        assert np.array_equal(body.angle, b.bodies[name].angle)


# ------------------------------------------------------------------ crack
def _search_teeth(model, poses):
    """Teeth (a, b) the rigid contact search reports at the poses ((x, y, theta) of a and b)."""
    mesh = model.meshes[0]
    a, b = model.bodies[mesh.a], model.bodies[mesh.b]
    pair = MeshPair(a.gear, b.gear, mesh.internal, mesh.ncand_a, mesh.ncand_b, 16, 0.0)
    out_f = np.zeros((MAX_CONTACTS, 5))
    out_i = np.zeros((MAX_CONTACTS, 3), np.int64)
    n = mesh_contacts(np.asarray(poses[0], float), np.asarray(poses[1], float), pair, model.tables, out_f, out_i)
    return out_i[:n, :2]


@pytest.fixture(scope="module")
def cracked_spur():
    return {q: _build(SPUR + COARSE_FE + crack(q)) for q in (0.5e-3, 1.0e-3, 1.5e-3)}


def test_crack_changes_the_mesh_stiffness_only_while_the_cracked_tooth_is_in_mesh(healthy_spur, cracked_spur):
    """The table spans z_pinion mesh cycles; it differs from the healthy one exactly at the
    positions where the rigid contact search (at the kinematic poses, the pinion turned 0.2 mrad
    to close its loaded flanks) finds pinion tooth 3 in contact, over about eps_alpha mesh cycles;
    the offset stays (a crack moves no surface)."""
    lm, h = cracked_spur[1.0e-3], healthy_spur
    P = h.k.shape[1]
    z1, z2 = 24, 21
    assert lm.cycles == z1 and lm.k.shape == (1, P * z1)
    ref = np.tile(h.k[0], z1)
    changed = lm.k[0] != ref
    assert np.all(lm.k[0][changed] < ref[changed])
    assert np.array_equal(lm.e, np.tile(h.e, z1))
    pair = GearPair(*(_cfg(SPUR).gears[g] for g in ("pinion", "wheel")))
    assert changed.sum() / P == pytest.approx(pair.contact_ratio, abs=2.0 / P)
    model = lm.model
    A, B = model.bodies[0], model.bodies[1]
    checked = 0
    for p in range(0, P * z1, 3):
        dth = lm.mesh_angle * p / P
        poses = ((*A.pin, A.theta0 + dth + 2e-4), (*B.pin, B.theta0 - dth * z1 / z2))
        found = 3 in _search_teeth(model, poses)[:, 0]
        edge = np.any(changed[max(p - 2, 0):p + 3] != changed[p])  # contact entering or leaving
        if not edge:
            assert found == changed[p], p
            checked += 1
    assert checked > 0.9 * P * z1 / 3


def test_crack_mesh_stiffness_falls_monotonically_with_depth(healthy_spur, cracked_spur):
    P = healthy_spur.k.shape[1]
    ref = np.tile(healthy_spur.k[0], 24)
    window = np.nonzero(cracked_spur[1.0e-3].k[0] != ref)[0]
    k = np.array([ref[window]] + [cracked_spur[q].k[0][window] for q in sorted(cracked_spur)])
    assert np.all(np.diff(k, axis=0) < 0)
    assert len(window) > P


def test_crack_on_the_unloaded_flank_and_partial_width(healthy_spur, cracked_spur):
    """A crack on the compressed fillet (the flank the load does not touch) is closed: the table
    is the healthy one repeated; half the face width cracked (slices in parallel) removes half
    the through crack's stiffness loss."""
    ref = np.tile(healthy_spur.k, 24)
    right = _build(SPUR + COARSE_FE + crack(1.0e-3, flank="right"))
    assert np.array_equal(right.k, ref)
    half = _build(SPUR + COARSE_FE + crack(1.0e-3, width=0.5))
    full = cracked_spur[1.0e-3]
    on = full.k != ref
    assert np.allclose((ref - half.k)[on], 0.5 * (ref - full.k)[on], rtol=1e-9)


# ------------------------------------------------------------------ errors
def _component(t, x, f):
    """Complex amplitude of the line at f [Hz] in x(t) (least squares with a mean)."""
    A = np.column_stack([np.cos(2 * np.pi * f * t), np.sin(2 * np.pi * f * t), np.ones_like(t)])
    c, *_ = np.linalg.lstsq(A, x, rcond=None)
    return c[0] - 1j * c[1]


def test_eccentricity_gives_the_once_per_revolution_transmission_error():
    """Pinion run-out e at phase phi0, sun at 2 Hz (quasi-static): the pinion's toothing centre
    e (cos, sin)(theta_p + phi0) moves along the line of action n = (sin alpha_w, cos alpha_w)
    (wheel on the +x axis, pinion driving counter-clockwise on its left flanks), so the wheel runs
    ahead (clockwise) by n . c / r_b2: the once-per-revolution line of the wheel angle against the
    healthy run has that amplitude and phase (2 %)."""
    text = SPUR.replace("speed_hz = 10.0", "speed_hz = 2.0").replace(*BACKLASH)
    e, phase = 5e-6, math.radians(30.0)
    h = _run(text, 0.1, 1.0)
    f = _run(text + f"\n[errors.eccentricity.pinion]\nmagnitude = {e}\nphase_deg = 30.0\n", 0.1, 1.0)
    cfg = _cfg(text)
    gp, gw = cfg.gears["pinion"], cfg.gears["wheel"]
    aw = GearPair(gp, gw).alpha_w
    t = f.time
    th = f.bodies["pinion"].angle
    pred = -(e * np.cos(th + phase) * math.sin(aw) + e * np.sin(th + phase) * math.cos(aw)) / gw.rb
    meas = f.bodies["wheel"].angle - h.bodies["wheel"].angle
    fp = 2.0
    a_meas, a_pred = _component(t, meas, fp), _component(t, pred, fp)
    assert abs(a_meas) == pytest.approx(e / gw.rb, rel=0.02)
    assert abs(a_meas - a_pred) < 0.02 * abs(a_pred)
    # nothing else changes the mean load
    assert f.meshes["pinion-wheel"].normal_force.mean() == pytest.approx(h.meshes["pinion-wheel"].normal_force.mean(),
                                                                          rel=1e-6)


def _linear_statics(lm):
    """Mean mesh forces [N] over the table of the lumped model's own statics, position by position:
    (K_b + sum_m k_m G_m G_m^T) q = f_load + sum_m k_m e_m G_m (every mesh in contact)."""
    sysl = lm.system
    Kb = sum(s.k * np.outer(s.g, s.g) for s in sysl.springs if s.kind != "mesh")
    f = np.zeros(sysl.n)
    for i, b in enumerate(lm.model.bodies):
        if b.torque is not None and i != lm.drive:
            f += float(b.torque(1e3)) * sysl.bodies[b.name][2][2]
    F = []
    for p in range(lm.k.shape[1]):
        k, e = lm.k[:, p], lm.e[:, p]
        q = np.linalg.solve(Kb + (lm.G.T * k) @ lm.G, f + lm.G.T @ (k * e))
        F.append(k * (lm.G @ q - e))
    return np.mean(F, axis=0)


@pytest.mark.parametrize("sun", ["fixed", "floating"])
def test_planet_pin_error_load_sharing_is_that_of_the_statics(sun):
    """MERCURY 1-A, planet 1's pin 1 um ahead (tangential), sun at 2 Hz (quasi-static), the sun on
    its fixed revolute joint or floating on 1e8 N/m bearings: the lumped run's mean mesh forces
    equal (a) the statics of the lumped model's own linear system (no time solver) within 0.5 %
    and (b) the rigid model's nonlinear statics with planet 1's pin moved by the same vector
    (flexgear.dynamics.modal.linearise; independent of how the error is projected on the lines
    of action) within 2 %; and the error does upset the sharing (planet 1 off by > 10 %)."""
    from flexgear.dynamics.model.assembly import build_model
    from flexgear.dynamics.modal.linearise import linearise

    text = MERCURY.replace("speed_hz = 30.0", "speed_hz = 2.0")
    if sun == "floating":
        text = text.replace('sun = "revolute"', 'sun = {stiffness = 1.0e8, damping = 1.0e3}')
    et = 1.0e-6
    text += f"\n[errors.pin.planet1]\ntangential = {et}\n"
    res = _run(text, 0.1, 0.2)
    lm = _build(text)
    names = [m.name for m in lm.model.meshes]
    run_mean = np.array([res.meshes[nm].normal_force.mean() for nm in names])
    assert run_mean == pytest.approx(_linear_statics(lm), rel=5e-3)
    model = build_model(_cfg(text))
    b = next(b for b in model.bodies if b.name == "planet1")
    psi = math.atan2(b.pin[1], b.pin[0])
    b.pin = (b.pin[0] - et * math.sin(psi), b.pin[1] + et * math.cos(psi))
    rigid = linearise(model, n_positions=48).attrs["cycle"]["force"].mean(axis=1)
    share, share_rigid = run_mean / run_mean.mean(), rigid / rigid.mean()
    assert share == pytest.approx(share_rigid, rel=0.02)
    assert abs(share[names.index("sun-planet1")] - 1.0) > 0.1
