"""Root cracks and partial face-width faults in the rigid multi-body model (issue 22): a per-tooth
factor of the IMPACT law from the crack FE, and slices in parallel.

The factor is checked against the FE single-pair stiffness ratio computed here
(:func:`flexgear.stiffness.crack.crack_pair_stiffness`, not the model's cached table); the slow
quasi-static run against the closed-form load sharing of the pairs on the path, each pair the
rigid law F = K kappa [w delta^e + (1 - w) (delta - h)_+^e] with kappa from that FE ratio (the
run turns slowly: the IMPACT damping force is below 0.1 % of the load).
"""
import dataclasses
import math
import re
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

from flexgear.app.run import run
from flexgear.config import loads_config, preset_path
from flexgear.config.faults import loaded_flanks
from flexgear.dynamics.contact.teeth import tooth_law
from flexgear.errors import ConfigError
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.model.tooth_laws import nominal_mesh_force
from flexgear.fe.meshing import MeshSettings
from flexgear.gears.geometry import GearPair
from flexgear.gears.kinematics import contact_roll_range, line_of_action
from flexgear.stiffness.crack import crack_pair_stiffness

from test_faults_rigid import SLOW, _signals, engagement, fault, first_engaging, law, pair_loads, spur

COARSE_FE = "\n[fe]\nlevel = 0\n"  # the crack FE on the coarsest mesh (the default suite's budget)
DEPTH = 1.5e-3  # m, at 45 deg: the pair stiffness falls by 11-24 % along the path
SPALL_DEPTH = 20e-6  # m, below the static approach (about 70 um): the recessed slice keeps part of the load


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def crack(tooth=3, flank="left", width=1.0, depth=DEPTH):
    return fault("crack", tooth, flank=flank, depth=depth, angle_deg=45.0, width_fraction=width)


@pytest.fixture(scope="module")
def fe_ratio():
    """(roll angles of the pinion's contact, k_cracked / k_healthy) of the FE at the static mesh
    force of the preset: load torque / base radius of the loaded wheel."""
    cfg = spur(COARSE_FE)
    pair = GearPair(cfg.gears["pinion"], cfg.gears["wheel"])
    load = abs(cfg.load["torque"]) / cfg.gears["wheel"].rb
    cps = crack_pair_stiffness(pair, DEPTH, math.radians(45.0), load, cracked=1, settings=MeshSettings(level=0),
                               material=cfg.material, formulation=cfg.fe["formulation"])
    on = cps.on_path & np.isfinite(cps.ratio)
    order = np.argsort(cps.roll[on])
    return cps.roll[on][order], cps.ratio[on][order]


def test_the_crack_factor_is_the_fe_stiffness_ratio_to_the_power_e(fe_ratio):
    """kappa^(1/e) (the pair's stiffness ratio under the law F = kappa K delta^e, at every load)
    equals the FE ratio along the path, on the cracked flank of the cracked tooth only; half the
    face width cracked: slices in parallel, kappa = rho^e / 2 + 1/2."""
    roll, rho = fe_ratio
    assert rho.min() < 0.85 and np.all(rho < 1.0)  # the crack matters
    cfg = spur(COARSE_FE + crack())
    model = build_model(cfg)
    teeth, e = model.pack().meshes.teeth, model.meshes[0].e
    r = cfg.gears["pinion"].rb * np.sqrt(1.0 + roll**2)

    def law_at(table, g=0, tooth=3, side=1):
        return np.array([tooth_law(table, 0, g, tooth, side, x) for x in r])

    got = law_at(teeth)
    assert np.allclose(got[:, 0] ** (1.0 / e), rho, rtol=2e-3)
    assert np.all(got[:, 1] == 1.0) and np.all(got[:, 2] == 0.0)
    for other in (law_at(teeth, tooth=4), law_at(teeth, side=-1), law_at(teeth, g=1)):
        assert np.all(other == [1.0, 1.0, 0.0])
    half = build_model(spur(COARSE_FE + crack(width=0.5))).pack().meshes.teeth
    assert np.allclose(law_at(half)[:, 0], 0.5 * rho**e + 0.5, rtol=2e-3)
    assert build_model(spur(COARSE_FE + crack(width=0.0))).tooth_laws is None  # no crack: the plain law


def test_a_crack_without_load_is_refused_before_the_fe():
    cfg = spur(COARSE_FE + crack())
    cfg = dataclasses.replace(cfg, load={**cfg.load, "torque": 0.0})
    with pytest.raises(ConfigError, match=re.escape("faults[0] (crack on pinion tooth 3, left flank): load.torque = 0")):
        build_model(cfg)


def test_no_crack_or_a_zero_width_gives_the_healthy_run_bit_for_bit():
    zero = crack(width=0.0) + fault("spall", 7, flank="left", start_roll_deg=20.0, end_roll_deg=24.0,
                                    depth=20e-6, width_fraction=0.0)
    a, b = _signals(run(spur())), _signals(run(spur(COARSE_FE + zero)))
    assert sorted(a) == sorted(b)
    assert not [k for k in a if not np.array_equal(a[k], b[k])]


def sharing(F, K, e, kappa, width, recess):
    """Closed form of the quasi-static mesh: loads of the pairs on the path and their common
    approach delta [m] with sum_i K kappa_i [w_i delta^e + (1 - w_i) (delta - h_i)_+^e] = F."""
    kappa, width, recess = (np.asarray(x, float) for x in (kappa, width, recess))

    def loads(d):
        return K * kappa * (width * d**e + (1.0 - width) * np.maximum(d - recess, 0.0) ** e)

    d = brentq(lambda x: loads(x).sum() - F, 0.0, 1e-2, xtol=1e-15, rtol=1e-13)
    return loads(d), d


def quasi_static(faults: int):
    """A slow run of the spur pair through the engagements of the first ``faults`` of three faulty
    pinion teeth, two pitches apart: a through crack, a crack over half the face width, a spall
    over half the face width (20 um deep, on the upper part of the loaded flank). Returns the
    configuration, the result, the three teeth and the spall's roll band.

    The mesh damping is the ratio 0.05 instead of the preset's C (a damping ratio of about 50):
    its time constant C / k, about 20 ms against the single-contact zone's 0.25 s, makes the
    approach creep for tens of ms after each change of the load sharing, more so the softer the
    cracked pair (a 1-2 % lag of the transmission error); with the ratio 0.05 it is microseconds."""
    probe = spur()
    side = loaded_flanks(probe)["pinion-wheel"][0]
    flank = "left" if side > 0 else "right"
    k0, roll = first_engaging(probe, 0.4)
    g1 = probe.gears["pinion"]
    pair = GearPair(g1, probe.gears["wheel"])
    lo, hi = contact_roll_range(pair)[0]
    d = g1.pb / g1.rb
    teeth = [k0, (k0 - 2 * side) % g1.z, (k0 - 4 * side) % g1.z]
    band = (lo + 1.02 * d, hi - 0.02 * d)
    blocks = [crack(teeth[0], flank), crack(teeth[1], flank, width=0.5),
              fault("spall", teeth[2], flank=flank, start_roll_deg=math.degrees(band[0]),
                    end_roll_deg=math.degrees(band[1]), depth=SPALL_DEPTH, width_fraction=0.5)]
    pitch_t = 1.0 / (SLOW * g1.z)
    t_enter = 0.4 + roll / (2 * math.pi * SLOW)
    eps = (hi - lo) / d
    cfg = spur(COARSE_FE + "".join(blocks[:faults]), speed=SLOW, rate=1000.0, step=5e-5, run_in=0.2,
               duration=t_enter + (2 * (faults - 1) + eps + 0.3) * pitch_t - 0.2)
    cfg = dataclasses.replace(cfg, contact={**cfg.contact, "damping": None, "damping_ratio": 0.05})
    return cfg, run(cfg), teeth[:faults], band


def check_sharing(cfg, res, teeth, band, fe_ratio):
    """At every sample whose loaded pairs lie on the path away from its ends: the loaded
    transmission error -m2 (theta2 - theta2_ideal) and the pair loads equal :func:`sharing` with
    kappa = rho^e of the through crack (``teeth[0]``), rho^e / 2 + 1/2 of the half-width crack
    (``teeth[1]``), and slices (width 1/2, recess the spall depth) inside the spall's band
    (``teeth[2]``), rho the FE ratio at the pair's roll angle (1 %)."""
    full, halfc, spall = (list(teeth) + [-1, -1])[:3]
    xi, (lo, hi), side, pair = engagement(cfg, res, full)
    g1, g2 = pair.g1, pair.g2
    K, e = law(res)
    roll_fe, rho = fe_ratio
    loads = pair_loads(res, g1.z, side)
    total = loads.sum(axis=1)
    model = build_model(cfg)
    th1_0, th2_0 = model.bodies[0].theta0, model.bodies[1].theta0
    ga, gb = line_of_action(pair, 0.0, side)
    a = res.bodies["wheel"].position[0, 0]
    T1 = g1.rb * np.array([math.cos(ga), math.sin(ga)])
    T2 = np.array([a, 0.0]) + g2.rb * np.array([math.cos(gb), math.sin(gb)])
    n = (T2 - T1) / np.hypot(*(T2 - T1))
    m2 = (T2[0] - a) * n[1] - T2[1] * n[0]  # the wheel's moment arm along the line of action
    th1, th2 = res.bodies["pinion"].angle, res.bodies["wheel"].angle
    te = -m2 * (th2 - (th2_0 - g1.z / g2.z * (th1 - th1_0)))
    d = g1.pb / g1.rb
    margin = 0.1 * d
    wall = 3e-3  # rad of roll, about two outline samples: the slices' recess steps at the band's ends
    seen = {k: 0 for k in teeth}
    for i in range(len(res.time)):
        on = np.nonzero((xi[i] >= lo) & (xi[i] <= hi))[0]
        if not len(on) or np.any((xi[i, on] < lo + margin) | (xi[i, on] > hi - margin)):
            continue
        if np.any(loads[i, np.setdiff1d(np.arange(g1.z), on)] > 0):
            continue
        x = xi[i, on]
        kappa, width, recess = np.ones(len(on)), np.ones(len(on)), np.zeros(len(on))
        fe = np.interp(x, roll_fe, rho) ** e
        kappa[on == full] = fe[on == full]
        kappa[on == halfc] = 0.5 * fe[on == halfc] + 0.5
        in_band = (on == spall) & (x > band[0]) & (x < band[1])
        if np.any((on == spall) & ((np.abs(x - band[0]) < wall) | (np.abs(x - band[1]) < wall))):
            continue
        width[in_band], recess[in_band] = 0.5, SPALL_DEPTH
        f, delta = sharing(total[i], K, e, kappa, width, recess)
        assert math.isclose(te[i], delta, rel_tol=0.01), (i, x, te[i], delta)
        assert np.allclose(loads[i, on], f, rtol=0.01, atol=0.01 * total[i]), (i, x, loads[i, on], f)
        for k in seen:
            seen[k] += bool(np.any(on == k) if k != spall else np.any(in_band))
    assert min(seen.values()) > 20, seen
    return seen


def test_quasi_static_cracked_pair_follows_the_fe_ratio(fe_ratio):
    """Fast variant: the through crack's engagement only."""
    check_sharing(*quasi_static(1), fe_ratio)


@pytest.mark.slow
def test_quasi_static_pair_loads_and_transmission_error_follow_the_fe_ratio_and_the_slices(fe_ratio):
    check_sharing(*quasi_static(3), fe_ratio)


def test_a_cracked_pinion_modulates_the_mesh_force_at_its_rotation_frequency():
    """The cracked tooth meshes once per pinion turn (the fault frequency of a local pinion fault
    is the pinion's rotation frequency f_p = 10 Hz, Feng & Zuo 2012): the normal mesh force of the
    cracked pinion gains lines at f_p and beside the mesh frequency, f_m +- f_p; the healthy force
    repeats every mesh period (24 per pinion turn) and has none there."""
    amp = {}
    for name, extra in (("healthy", ""), ("cracked", COARSE_FE + crack())):
        res = run(spur(extra, duration=0.2, run_in=0.2))
        force = res.meshes["pinion-wheel"].normal_force[-2000:]  # two pinion turns at 10 kHz: 5 Hz bins
        amp[name] = np.abs(np.fft.rfft(force - force.mean())) / len(force)
        if name == "cracked":
            assert res.faults["frequency_hz"] == pytest.approx([10.0], rel=1e-12)
    fp, fm = 2, 48  # bins of f_p = 10 Hz and f_m = 240 Hz
    for b in (fp, fm - fp, fm + fp):
        assert amp["cracked"][b] > 10.0 * amp["healthy"][b] and amp["cracked"][b] > 1e-3 * amp["healthy"][fm], b


def test_a_sun_crack_acts_at_every_sun_planet_mesh_at_the_static_mesh_force():
    """MERCURY 1-A, sun tooth 2 cracked: the factor table sits on the sun's side of the three
    sun-planet meshes (gear A) and nowhere else, and the FE ratio is taken at the nominal mesh
    force, the carrier's load torque on the sun (z_s / (z_s + z_r)) over three planets and the
    sun's base radius, which is the mean normal force of the run (1 %)."""
    text = preset_path("mercury_1a").read_text().replace("duration = 1.0 ", "duration = 0.05 ")
    sun = fault("crack", 2, gear="sun", flank="left", depth=1.0e-3)
    cfg = loads_config(text.replace("[simulation]", COARSE_FE + sun + "\n[simulation]"))
    model = build_model(cfg)
    names = [m.name for m in model.meshes]
    first = model.tooth_laws.first
    assert [names[m] for m in np.nonzero(first[:, 0] >= 0)[0]] == ["sun-planet1", "sun-planet2", "sun-planet3"]
    assert np.all(first[:, 1] == -1)
    res = run(cfg)
    s, r = cfg.gears["sun"], cfg.gears["ring"]
    load = cfg.load["torque"] * s.z / (s.z + r.z) / (3 * s.rb)
    assert nominal_mesh_force(cfg) == pytest.approx(load, rel=1e-12)
    for name in names:
        assert np.mean(res.meshes[name].normal_force) == pytest.approx(load, rel=0.01)


RING_TOOTH = 35  # planets 1, 2, 3 start at ring teeth 16, 38, 60 (loaded flanks); planet 1 meets it after 34 ms


def _mercury(extra=""):
    """MERCURY 1-A over one carrier turn after 10 ms (the load ramp of 50 ms included), no
    anti-aliasing filter (each output sample is the state at its instant)."""
    text = preset_path("mercury_1a").read_text()
    for old, new in (("duration = 1.0 ", "duration = 0.17 "), ("run_in = 0.2 ", "run_in = 0.01 "),
                     ("antialias = true", "antialias = false")):
        assert old in text, old
        text = text.replace(old, new)
    return loads_config(text.replace("[simulation]", extra + "\n[simulation]"))


def _ring_engagements(res, tooth, side):
    """{planet-ring mesh: output samples where ``tooth`` of the ring touches the planet on the
    ring's flank ``side``} (the results' pair_tooth_b, and pair_side of the planet = -side)."""
    out = {}
    for name, m in res.meshes.items():
        if name.endswith("-ring"):
            hit = (m.pair_tooth_b == tooth) & (m.pair_side == -side)
            out[name] = np.nonzero(hit.any(axis=1))[0]
    return out


@pytest.fixture(scope="module")
def ring_runs():
    probe = _mercury()
    side = loaded_flanks(probe)["planet1-ring"][1]
    ring = fault("crack", RING_TOOTH, gear="ring", flank="left" if side > 0 else "right", depth=DEPTH)
    return side, (probe, run(probe)), (_mercury(COARSE_FE + ring), None)


def test_a_ring_crack_acts_only_while_the_cracked_ring_tooth_meshes_with_a_planet(ring_runs):
    """MERCURY 1-A, ring tooth 35 cracked on its loaded flank (FE of the cracked ring with a
    planet, level 0). The factor table sits on the ring's side (gear B) of the three planet-ring
    meshes and nowhere else, and is the FE ratio k_cracked / k_healthy of the planet-ring pair
    (computed here) to the power e, at the static mesh force: the carrier torque's share on the
    sun (z_s / (z_s + z_r)) over three planets and the sun's base radius, which a planet passes on
    to the ring, the mean normal force of the planet-ring meshes once loaded (1 %). Over one
    carrier turn each planet meets the cracked tooth once, a third of a turn after the one before
    (the ring fault frequency N f_c = 24 Hz, Feng & Zuo 2012); the run equals the healthy one bit
    for bit until the first planet touches the tooth, and the cracked tooth, softer, carries less
    on the average of each engagement."""
    side, (hcfg, healthy), (cfg, _) = ring_runs
    model = build_model(cfg)
    names = [m.name for m in model.meshes]
    first = model.tooth_laws.first
    assert [names[m] for m in np.nonzero(first[:, 1] >= 0)[0]] == ["planet1-ring", "planet2-ring", "planet3-ring"]
    assert np.all(first[:, 0] == -1)
    s, r, p = cfg.gears["sun"], cfg.gears["ring"], cfg.gears["planet"]
    load = cfg.load["torque"] * s.z / (s.z + r.z) / (3 * s.rb)
    assert nominal_mesh_force(cfg) == pytest.approx(load, rel=1e-12)
    # the factor: the FE ratio of the planet-ring pair with the ring cracked (gear 2), to the power e
    pair = GearPair(p, r)
    cps = crack_pair_stiffness(pair, DEPTH, math.radians(45.0), load, cracked=2, settings=MeshSettings(level=0),
                               material=cfg.material, formulation=cfg.fe["formulation"])
    on = cps.on_path & np.isfinite(cps.ratio)
    rho = cps.ratio[on]
    assert rho.min() < 0.9 and np.all(rho < 1.0)
    radii = r.rb * np.sqrt(1.0 + cps.roll[on] ** 2)
    teeth, e = model.pack().meshes.teeth, model.meshes[names.index("planet1-ring")].e
    for m in (3, 4, 5):
        got = np.array([tooth_law(teeth, m, 1, RING_TOOTH, side, x) for x in radii])
        assert np.allclose(got[:, 0] ** (1.0 / e), rho, rtol=2e-3)
        for other in ((RING_TOOTH + 1, side), (RING_TOOTH, -side)):
            assert tooth_law(teeth, m, 1, other[0], other[1], radii[3]) == (1.0, 1.0, 0.0)
    cracked = run(cfg)
    assert cracked.faults["frequency_hz"] == pytest.approx([3 * 30.0 * s.z / (s.z + r.z)], rel=1e-12)
    # each planet meets the tooth once per carrier turn, the next planet a third of a turn later
    seen = _ring_engagements(cracked, RING_TOOTH, side)
    t = cracked.time
    f_c = 30.0 * s.z / (s.z + r.z)
    period = 1.0 / (r.z * f_c)  # mesh period
    runs = []  # (start time, mesh, samples) of each engagement
    for name, idx in seen.items():
        for part in np.split(idx, np.nonzero(np.diff(idx) > 1)[0] + 1):
            assert len(part) > 10, (name, part)
            runs.append((t[part[0]], name, part))
    runs.sort(key=lambda x: x[0])
    assert t[-1] - runs[0][0] > 1.0 / f_c and len(runs) == 4  # a carrier turn after the first: 3 + 1
    assert sorted(x[1] for x in runs[:3]) == ["planet1-ring", "planet2-ring", "planet3-ring"]
    assert runs[3][1] == runs[0][1]
    assert np.allclose(np.diff([x[0] for x in runs]), 1.0 / (3 * f_c), atol=period)
    # bit for bit until the first contact of the cracked tooth, different from then on
    i0 = runs[0][2][0]
    a, b = _signals(healthy), _signals(cracked)
    assert not [k for k in a if not np.array_equal(a[k][:i0], b[k][:i0])]
    assert not np.array_equal(a["planet1-ring/normal_force"][i0:], b["planet1-ring/normal_force"][i0:])
    # the softer tooth carries less over each engagement
    for _, name, idx in runs:
        def carried(res):
            m = res.meshes[name]
            hit = (m.pair_tooth_b[idx] == RING_TOOTH) & (m.pair_side[idx] == -side)
            return np.sum(np.where(hit, m.pair_force[idx], 0.0))
        assert carried(cracked) < 0.99 * carried(healthy), name
    # the static mesh force is the force the planet-ring meshes carry once loaded
    late = t > 0.07
    for name in ("planet1-ring", "planet2-ring", "planet3-ring"):
        assert np.mean(cracked.meshes[name].normal_force[late]) == pytest.approx(load, rel=0.01)


def test_a_zero_depth_ring_crack_gives_the_healthy_run_bit_for_bit(ring_runs):
    side, (_, healthy), _ = ring_runs
    zero = fault("crack", RING_TOOTH, gear="ring", flank="left" if side > 0 else "right", depth=0.0)
    cfg = _mercury(COARSE_FE + zero)
    assert build_model(cfg).tooth_laws is None
    a, b = _signals(healthy), _signals(run(cfg))
    assert sorted(a) == sorted(b)
    assert not [k for k in a if not np.array_equal(a[k], b[k])]
