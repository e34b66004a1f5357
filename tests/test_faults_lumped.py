"""Faults and errors in the lumped model (flexgear.dynamics.lumped.faults): zero size is the
healthy model bit for bit; a crack changes the mesh stiffness only while the cracked tooth is on
the path of contact (found by the rigid contact search) and more the deeper it is; eccentricity
and pitch errors give the closed-form transmission error; a planet pin error gives the load
sharing of the rigid model's statics with the pin moved."""
import math
import re
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.config import loads_config, preset_path
from flexgear.dynamics.contact.search import MAX_CONTACTS, MeshPair, mesh_contacts
from flexgear.dynamics.lumped.model import build_lumped
from flexgear.errors import ConfigError
from flexgear.gears.geometry import GearPair
from test_lumped_time import _run

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



def test_ring_crack_changes_each_planet_ring_mesh_once_per_carrier_turn_a_third_of_a_turn_apart():
    """MERCURY 1-A, ring tooth 5 cracked on its loaded flank 0.5 and 1 mm deep (FE of the cracked
    ring with a planet, level 0): the tables span z_r = 66 mesh cycles (a carrier turn, the ring
    fixed); each planet-ring mesh (and no sun-planet mesh) loses stiffness over eps_alpha of the
    planet-ring pair in mesh cycles, the deeper crack more; the planets, a third of a turn apart,
    meet the tooth z_r / 3 = 22 mesh cycles after one another."""
    healthy = _build(MERCURY + COARSE_FE)
    P = healthy.k.shape[1]
    lm = {q: _build(MERCURY + COARSE_FE + crack(q, tooth=5, gear="ring")) for q in (0.5e-3, 1.0e-3)}
    cfg = _cfg(MERCURY)
    eps = GearPair(cfg.gears["planet"], cfg.gears["ring"]).contact_ratio
    assert lm[1.0e-3].cycles == 66
    ref = np.tile(healthy.k, 66)
    starts = []
    for m, mesh in enumerate(healthy.model.meshes):
        changed = lm[1.0e-3].k[m] != ref[m]
        if mesh.name.endswith("-ring"):
            assert changed.sum() / P == pytest.approx(eps, abs=2.0 / P)
            assert np.all(lm[1.0e-3].k[m][changed] < lm[0.5e-3].k[m][changed])
            assert np.all(lm[0.5e-3].k[m][changed] < ref[m][changed])
            on = np.nonzero(changed)[0]
            gap = np.nonzero(np.diff(on) > 1)[0]  # the window may wrap around the table's end
            starts.append(on[gap[0] + 1] if len(gap) else on[0])
        else:
            assert not changed.any()
    d = np.diff(np.sort(starts)) / P
    assert np.allclose(d, 22.0, atol=2.0 / P)
    assert np.array_equal(lm[1.0e-3].e, np.tile(healthy.e, 66))  # a crack moves no surface


@pytest.mark.slow
def test_sun_crack_at_the_default_fe_level_changes_every_sun_planet_mesh_once_per_relative_turn():
    """MERCURY 1-A, sun tooth 3 cracked 0.5 and 1 mm deep, the crack FE at the [fe] default level:
    the tables span z_s = 24 mesh cycles; each sun-planet mesh (and no planet-ring mesh) loses
    stiffness over eps_alpha mesh cycles, the deeper crack more (the fast variant: the spur pair
    at level 0 above)."""
    healthy = _build(MERCURY)
    P = healthy.k.shape[1]
    lm = {q: _build(MERCURY + crack(q, gear="sun")) for q in (0.5e-3, 1.0e-3)}
    eps = GearPair(*(_cfg(MERCURY).gears[g] for g in ("sun", "planet"))).contact_ratio
    ref = np.tile(healthy.k, 24)
    for m, mesh in enumerate(healthy.model.meshes):
        changed = lm[1.0e-3].k[m] != ref[m]
        if mesh.name.startswith("sun-"):
            assert changed.sum() / P == pytest.approx(eps, abs=2.0 / P)
            assert np.all(lm[1.0e-3].k[m][changed] < lm[0.5e-3].k[m][changed])
            assert np.all(lm[0.5e-3].k[m][changed] < ref[m][changed])
        else:
            assert not changed.any()

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


def test_eccentricity_sidebands_sit_at_the_rotation_frequency():
    """At the preset's 10 Hz the pinion's run-out modulates the mesh force: lines at k f_m +- f_p
    (f_p = 10 Hz, f_m = 240 Hz) that the healthy run does not have, and none at k f_m +- f_p / 2."""
    text = SPUR.replace(*BACKLASH)
    h = _run(text, 0.2, 1.0)
    f = _run(text + "\n[errors.eccentricity.pinion]\nmagnitude = 5.0e-6\n", 0.2, 1.0)

    def amp(res, fr):
        return abs(_component(res.time, res.meshes["pinion-wheel"].normal_force, fr))

    fm, fp = 240.0, 10.0
    for k in (1, 2):
        for sgn in (-1, 1):
            side, half = amp(f, k * fm + sgn * fp), amp(f, k * fm + sgn * fp / 2)
            assert side > 1e6 * amp(h, k * fm + sgn * fp)
            assert side > 1e4 * half
    assert amp(f, fm) == pytest.approx(amp(h, fm), rel=1e-6)


def _single_contact(res, cfg, margin):
    """Samples where one pinion tooth alone is on the path of contact (its neighbours at least
    ``margin`` [rad] of roll beyond its ends), and that tooth, from the engagement geometry at the
    recorded angles."""
    from flexgear.config.faults import loaded_flanks
    from flexgear.gears.kinematics import contact_roll_range, flank_roll_angle, line_of_action

    pair = GearPair(cfg.gears["pinion"], cfg.gears["wheel"])
    side = loaded_flanks(cfg)["pinion-wheel"][0]
    ga, _ = line_of_action(pair, 0.0, side)  # wheel on the +x axis
    xi = flank_roll_angle(pair.g1, np.arange(pair.g1.z)[None, :], side, res.bodies["pinion"].angle[:, None], ga)
    (a0, a1), _ = contact_roll_range(pair)
    near = (xi >= a0 - margin) & (xi <= a1 + margin)
    alone = near.sum(axis=1) == 1
    return alone, np.argmax(near, axis=1)


def test_pitch_errors_enter_as_the_index_deviation_along_the_line_of_action():
    """Pinion pitch errors drawn for ISO 1328 class 6 (their statistics: test_faults_geometry),
    quasi-static: while pinion tooth k alone carries the load, the wheel runs ahead of the healthy
    run by the tooth's index deviation along the line of action, F_k cos(alpha) / r_b2 (parallel
    involutes: a tooth turned by F_k / r moves its flank by r_b F_k / r), within 2 % of the range
    of the index deviations, for every tooth."""
    from flexgear.gears.faults import PitchErrors, random_pitch_deviations

    text = SPUR.replace("speed_hz = 10.0", "speed_hz = 2.0").replace(*BACKLASH)
    h = _run(text, 0.1, 0.5)
    f = _run(text + "\n[errors.pitch.pinion]\ngrade = 6\nseed = 1\n", 0.1, 0.5)
    cfg = _cfg(text)
    gp, gw = cfg.gears["pinion"], cfg.gears["wheel"]
    F = PitchErrors(deviations=tuple(random_pitch_deviations(gp, 6, 1))).index_deviations()
    alone, tooth = _single_contact(f, cfg, margin=3 * 2 * math.pi / gp.z / 48)
    assert alone.mean() > 0.2
    miss = (f.bodies["wheel"].angle - h.bodies["wheel"].angle)[alone] + F[tooth[alone]] * math.cos(gp.pressure_angle) / gw.rb
    # per tooth, the median: the step from one tooth's deviation to the next rings the wheel on the
    # mesh spring for a few ms after each change of contact, which is dynamics, not the statics
    miss = np.array([np.median(miss[tooth[alone] == k]) for k in range(gp.z)])
    assert np.max(np.abs(miss)) < 0.02 * np.ptp(F) * math.cos(gp.pressure_angle) / gw.rb


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
    model = build_model(_cfg(text))  # the rigid model moves planet 1's pin by the error itself
    rigid = linearise(model, n_positions=48).attrs["cycle"]["force"].mean(axis=1)
    share, share_rigid = run_mean / run_mean.mean(), rigid / rigid.mean()
    assert share == pytest.approx(share_rigid, rel=0.02)
    assert abs(share[names.index("sun-planet1")] - 1.0) > 0.1


# ------------------------------------------------------------------ missing tooth, spall
def test_missing_tooth_and_spall_remove_the_contact_where_the_material_is_gone(healthy_spur):
    """A missing pinion tooth (cut to the root): over its engagement the mesh has half the healthy
    stiffness where it shared the load with a neighbour (2 (eps_alpha - 1) mesh cycles) and none
    where it was alone (2 - eps_alpha). A full-width spall 20 um deep (far beyond the pair's static
    deflection) between two radii: the pair carries nothing while its contact lies between them,
    for (xi(r_2) - xi(r_1)) / (2 pi / z) mesh cycles (xi = sqrt(r^2 / r_b^2 - 1))."""
    P = healthy_spur.k.shape[1]
    ref = np.tile(healthy_spur.k[0], 24)
    lm = _build(SPUR + COARSE_FE + '\n[[faults]]\nkind = "missing"\ngear = "pinion"\ntooth = 3\n')
    pair = GearPair(*(_cfg(SPUR).gears[g] for g in ("pinion", "wheel")))
    eps = pair.contact_ratio
    assert np.sum(lm.k[0] == 0.0) / P == pytest.approx(2.0 - eps, abs=2.0 / P)
    half = np.isclose(lm.k[0], 0.5 * ref, rtol=1e-12)
    assert half.sum() / P == pytest.approx(2.0 * (eps - 1.0), abs=3.0 / P)
    assert np.sum(lm.k[0] != ref) == np.sum(lm.k[0] == 0.0) + half.sum()
    g = pair.g1
    r1, r2 = g.rb * 1.02 * math.hypot(1, math.tan(pair.alpha_w)), g.rb * 1.06 * math.hypot(1, math.tan(pair.alpha_w))
    span = (math.sqrt((r2 / g.rb) ** 2 - 1) - math.sqrt((r1 / g.rb) ** 2 - 1)) / (2 * math.pi / g.z)

    def spall(depth):
        return _build(SPUR + COARSE_FE + f'\n[[faults]]\nkind = "spall"\ngear = "pinion"\ntooth = 3\nflank = "left"\n'
                      f'start_radius = {r1}\nend_radius = {r2}\ndepth = {depth}\n')

    # the presets' soft contact law deflects about 74 um at 10 kN: a 100 um spall unloads the pair
    deep = spall(100e-6)
    changed = deep.k[0] != ref
    assert changed.sum() / P == pytest.approx(span, abs=2.0 / P)
    assert np.all(deep.k[0][changed] < ref[changed])
    # a 20 um one leaves the pair in contact, 20 um further off: the offset rises by 20 um times
    # the pair's share (1 alone, 1/2 with a neighbour), the stiffness stays
    shallow = spall(20e-6)
    e_ref = np.tile(healthy_spur.e[0], 24)
    assert np.array_equal(shallow.k[0], ref)
    rise = (shallow.e[0] - e_ref)[changed]
    assert np.all(np.isclose(rise, 20e-6, rtol=1e-6) | np.isclose(rise, 10e-6, rtol=1e-6))
    assert np.array_equal(shallow.e[0][~changed], e_ref[~changed])


def test_a_fault_that_opens_a_loaded_mesh_is_refused_before_the_time_loop(monkeypatch):
    """A missing pinion tooth leaves the spur mesh (contact ratio < 2) without any pair on the
    path of contact over 2 - eps_alpha mesh cycles per pinion turn: the lumped model's pairs hold
    the nominal path, so nothing would carry the load there (the rigid model's next pair engages
    early). The run is refused, naming the mesh and that span, before any step and before it says
    it simulates; a tooth cut to 0.75 of its height keeps its pair in contact and runs."""
    import flexgear
    from flexgear.dynamics.lumped import time_loop

    eps = GearPair(*(_cfg(SPUR).gears[g] for g in ("pinion", "wheel"))).contact_ratio
    text = SPUR.replace("damping = 3000.0 ", "damping_ratio = 0.05 ")
    missing = '\n[[faults]]\nkind = "missing"\ngear = "pinion"\ntooth = 3\n'
    cfg = _cfg(text + missing)
    cfg.simulation.update(run_in=0.0, duration=0.01)
    lm = build_lumped(cfg)
    P = lm.k.shape[1] // lm.cycles  # positions per mesh cycle
    assert lm.gaps["pinion-wheel"] == pytest.approx(2.0 - eps, abs=2.0 / P)
    monkeypatch.setattr(time_loop, "_drive_angle", lambda *a: pytest.fail("the time loop started"))
    said = []
    with pytest.raises(ConfigError, match=r"mesh pinion-wheel has no tooth pair in contact over 0\.4\d* mesh "
                                          r"cycles of every 24 .*Use the rigid model"):
        flexgear.run(cfg, messages=said.append)
    assert not [m for m in said if "simulating" in m], said
    monkeypatch.undo()
    cut = _cfg(text + missing + "height_fraction = 0.75\n")
    cut.simulation.update(run_in=0.02, duration=0.01)
    assert not build_lumped(cut).gaps
    f = flexgear.run(cut).meshes["pinion-wheel"].normal_force
    assert np.all(np.isfinite(f)) and f.max() < 3.0 * f.mean()



# ------------------------------------------------------------------ what is refused
def test_lumped_bad_fault_input_is_named():
    from flexgear.dynamics.lumped.faults import check_lumped_faults

    ring = MERCURY + '\n[[faults]]\nkind = "crack"\ngear = "ring"\ntooth = 5\nflank = "left"\ndepth = 0.5e-3\n'
    check_lumped_faults(_cfg(ring))  # a ring crack: the FE of the cracked ring with a planet
    cfg = _cfg(MERCURY + "\n[errors.pin.planet1]\ntangential = 1.0e-6\n")
    cfg.lumped = dict(cfg.lumped or {}, parameters={"planets": 3})  # explicit parameters: no tooth geometry
    with pytest.raises(ConfigError, match=r"\[lumped.parameters\]: the explicit parameters have no tooth geometry"):
        check_lumped_faults(cfg)


# ------------------------------------------------------------------ profile errors and relief
def test_profile_slope_and_tip_relief_enter_as_offsets_at_the_contact_radius():
    """Pinion profile slope f_Halpha (every tooth): the table keeps one mesh cycle; the pairs'
    contacts run up the pinion's flank by one base pitch of roll length per mesh cycle, so the
    offset falls at f_Halpha p_b / (L_a - L_F) per cycle (more material towards the tip) except
    where a pair enters or leaves. A tip relief starting at roll angle xi_s: the offset changes only while a
    pair's pinion contact lies beyond xi_s, for (xi_end - xi_s) / (2 pi / z) of each mesh cycle
    (xi_end: the end of the path on the pinion), and rises there (material removed)."""
    from flexgear.gears.faults import roll_length

    f_ha = 4.0e-6
    text = SPUR.replace(*BACKLASH) + COARSE_FE  # errors that add material need a backlash
    healthy = _build(text)
    P = healthy.k.shape[1]
    slope = _build(text + f"\n[errors.profile.pinion]\nslope = {f_ha}\n")
    assert slope.cycles == 1 and np.array_equal(slope.k, healthy.k)
    cfg = _cfg(text)
    pair = GearPair(cfg.gears["pinion"], cfg.gears["wheel"])
    g = pair.g1
    de = slope.e[0] - healthy.e[0]
    rate = np.diff(np.append(de, de[0])) * P  # per mesh cycle, periodic
    dx = g.pb / (roll_length(g, g.ra) - roll_length(g, g.r_form))
    steady = np.isclose(rate, -f_ha * dx, rtol=1e-3)
    # the pairs one base pitch apart share the load equally, so the mean offset falls at the same
    # rate in double contact and jumps by + f_Halpha dx / 2 where a pair enters or leaves
    jumps = rate[~steady] / P  # the step between two positions: the jump and a 1/P cycle's fall
    assert len(jumps) == 2
    assert jumps == pytest.approx(f_ha * dx * (0.5 - 1.0 / P), rel=0.05)
    xi_s = 0.55
    relief = _build(text + f"\n[errors.profile.pinion]\ntip_relief = 5.0e-6\ntip_relief_start_roll_deg = {math.degrees(xi_s)}\n")
    from flexgear.gears.kinematics import contact_roll_range
    (_, xi_end), _ = contact_roll_range(pair)
    rise = relief.e[0] - healthy.e[0]
    assert np.all(rise >= 0.0)
    assert np.sum(rise > 0) / P == pytest.approx((xi_end - xi_s) / (2 * math.pi / g.z), abs=2.0 / P)


def test_crack_tables_are_cached_and_a_corrupt_entry_is_recomputed(tmp_path, monkeypatch, cracked_spur):
    """The crack FE's stiffness ratios are cached (checksummed, written atomically): a second build
    reads them and gives the same tables; a corrupt entry is dropped and recomputed."""
    import flexgear.dynamics.lumped.faults as lf

    monkeypatch.setattr(lf, "user_cache_dir", lambda: tmp_path)
    text = SPUR + COARSE_FE + crack(1.0e-3)
    first = _build(text)
    assert np.array_equal(first.k, cracked_spur[1.0e-3].k)
    npz = list((tmp_path / "crack-ratio").glob("ratio-*.npz"))
    assert len(npz) == 1
    stamp = npz[0].stat().st_mtime_ns
    assert np.array_equal(_build(text).k, first.k)
    assert npz[0].stat().st_mtime_ns == stamp  # read, not rewritten
    npz[0].write_bytes(b"not an npz")
    assert np.array_equal(_build(text).k, first.k)
    with np.load(npz[0]) as z:
        assert len(z["ratio"]) > 10


def test_a_record_shorter_than_a_fault_period_is_warned_and_noted():
    """Pinion run-out at 10 Hz: a 0.05 s record holds half its period, so the run warns, naming
    the error, its period and the duration that holds one, before the model's build, and the
    result's notes keep it; a 0.1 s record (one period) and a zero run-out (healthy) run without
    it."""
    text = SPUR.replace(*BACKLASH)
    ecc = "\n[errors.eccentricity.pinion]\nmagnitude = {}\n"

    def go(duration, e):
        cfg = _cfg(text + ecc.format(e))
        cfg.simulation.update(run_in=0.02, duration=duration)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = flexgear.run(cfg)
        order = [str(w.message) for w in caught]
        said = [m for m in order if "shorter than one period" in m]
        built = [i for i, m in enumerate(order) if "damping ratio" in m]  # the lumped model's build warns
        return said, res.attrs["notes"], order.index(said[0]) < built[0] if said and built else None

    said, notes, first = go(0.05, 5e-6)
    assert len(said) == 1 and first  # before the model's build
    assert re.search(r"simulation\.duration = 0\.05 s is shorter than one period of errors\.eccentricity\.pinion "
                     r"at 10 Hz \(period 0\.1 s\).*simulation\.duration >= 0\.1 s", said[0]), said[0]
    assert said[0] in notes
    for duration, e in ((0.1, 5e-6), (0.05, 0.0)):
        said, notes, _ = go(duration, e)
        assert said == [] and "shorter than one period" not in notes
