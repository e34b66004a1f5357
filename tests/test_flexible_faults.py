"""Faults in the flexible (Craig-Bampton) model (issue 22): spalls, chips and missing teeth removed
from the FE body of a flexible gear, which is reduced with them; the faulty teeth and their
neighbours get flank tables of their own (:func:`flexgear.reduction.flank.flank_tables`).

The static checks compare what the solver reads (condensed modes plus residual tables) with the
full-order FE of the same faulty gear: one sparse solve of K with the bore held, the reference of
:mod:`flexgear.dynamics.flexible.full_order` for a static load. The coarsest mesh (level 0) keeps
the reductions to seconds.
"""
import math

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from flexgear.config import load_config
from flexgear.dynamics.flexible.reductions import reduction_jobs
from flexgear.errors import ConfigError
from flexgear.gears.faults import LEFT, RIGHT, Chip, Crack, Missing, Spall
from flexgear.gears.modified import FaultyGear
from flexgear.reduction.flank import SIDES, flank_patch_loads
from flexgear.reduction.gear import reduce_gear

MISSING, CHIPPED, SPALLED = 3, 10, 16


def _job():
    cfg = load_config("spur_pair_flexible")
    cfg.flexible["level"] = 0
    jobs, _ = reduction_jobs(cfg)
    return jobs["pinion"]


def _faults(gear):
    r_spall = (gear.r + 0.5 * (gear.ra - gear.r), gear.ra - 0.15 * (gear.ra - gear.r))
    return (Missing(gear="pinion", tooth=MISSING, height_fraction=0.5),
            Chip(gear="pinion", tooth=CHIPPED, flank=LEFT, profile_size=0.6e-3, tip_size=0.3e-3),
            Spall(gear="pinion", tooth=SPALLED, flank=LEFT, start_radius=r_spall[0], end_radius=r_spall[1],
                  depth=50e-6))


@pytest.fixture(scope="module")
def reductions(tmp_path_factory):
    """The spur pair's pinion at level 0, healthy and with a missing tooth (half height), a chip and
    a spall, reduced into one cache directory."""
    cache = tmp_path_factory.mktemp("reductions")
    job = _job()
    healthy = reduce_gear(**job, cache_dir=cache)
    faulty = reduce_gear(**job, faults=_faults(job["gear"]), cache_dir=cache)
    return job, cache, healthy, faulty


class FullOrder:
    """Static compliance of the full-order FE body of a reduction (bore held, a ring's rim held as
    its ``support="rim"``): f_a^T K^-1 f_b for unit patch loads on two flank points. Of the body
    of ``red``, or of another FE ``model`` of the gear ``gear``."""

    def __init__(self, red=None, *, model=None, gear=None):
        from flexgear.stiffness.compliance import clamp_group

        model = red.body.model if model is None else model
        self.model, self.gear = model, red.gear if gear is None else gear
        held = np.unique(model.nodal_dofs(model.node_sets[clamp_group(self.gear)]).ravel())
        self.free = np.setdiff1d(np.arange(model.ndofs), held)
        self.lu = spla.splu(model.K[self.free][:, self.free].tocsc())

    def load(self, tooth, side, r):
        return flank_patch_loads(self.model, self.gear, tooth, side, [r])[0][self.free, 0]

    def compliance(self, a, b):
        """[m/N] between flank points a and b, each (tooth, side, radius)."""
        fa, fb = self.load(*a), self.load(*b)
        return float(fa @ self.lu.solve(fb))


def reduced_self(red, tooth, side, j):
    """Static self compliance [m/N] the solver reads at table radius j: condensed modes, residual
    self table, half-plane near field."""
    nq = red.body.n_interface
    A = red.modal[tooth, SIDES.index(side), j, nq:] / (2 * math.pi * red.body.frequencies)
    t = red.tables
    return float(A @ A + t.self_residual[side][tooth % t.period][j] + t.near_field[side][j])


def reduced_cross(red, a, b):
    """Static compliance [m/N] between flank points a (displaced) and b (loaded), each (tooth,
    side, coupling-radius index), of different teeth: modes plus the coupling table."""
    t = red.tables
    nq, k = red.body.n_interface, t.coupling_stride
    om = 2 * math.pi * red.body.frequencies
    Aa = red.modal[a[0], SIDES.index(a[1]), a[2] * k, nq:] / om
    Ab = red.modal[b[0], SIDES.index(b[1]), b[2] * k, nq:] / om
    d = (a[0] - b[0]) % red.gear.z
    return float(Aa @ Ab + t.coupling[b[0] % t.period, SIDES.index(a[1]), SIDES.index(b[1]), d, a[2], b[2]])


def test_the_faulty_gears_reduction_has_its_own_cache_entry(reductions):
    job, cache, healthy, faulty = reductions
    assert faulty.key != healthy.key
    again = reduce_gear(**job, cache_dir=cache)  # from the cache: the healthy entry, not the faulty one
    assert again.info["source"] == "cache" and again.key == healthy.key
    assert again.tables.period == 1 and np.array_equal(again.modal, healthy.modal)
    # the healthy entry's key is that of a gear reduced without faults: the plain gear's mesh, no
    # fault record (entries cached before faults existed keep their keys)
    import json

    from flexgear.fe.meshing import mesh_digest
    from flexgear.reduction.gear import reduction_paths

    key = json.loads(reduction_paths(cache, healthy.key)[1].read_text())["key"]
    assert key["mesh"] == mesh_digest(job["gear"], job["settings"]) and "faults" not in key["options"]
    faulty_key = json.loads(reduction_paths(cache, faulty.key)[1].read_text())["key"]
    assert faulty_key["mesh"] != key["mesh"] and len(faulty_key["options"]["faults"]) == 3
    # zero-size faults are the healthy gear, key and all
    zero = (Missing(gear="pinion", tooth=MISSING, height_fraction=1.0),
            Spall(gear="pinion", tooth=2, flank=LEFT, start_radius=0.025, end_radius=0.026, depth=0.0))
    assert reduce_gear(**job, faults=zero, cache_dir=cache).key == healthy.key
    # each fault's size enters the key
    g = job["gear"]
    other = (Missing(gear="pinion", tooth=MISSING, height_fraction=0.6),) + _faults(g)[1:]
    from flexgear.reduction.gear import reduction_cached
    assert reduction_cached(**job, faults=_faults(g), cache_dir=cache)
    assert not reduction_cached(**job, faults=other, cache_dir=cache)
    assert reduction_cached(**job, cache_dir=cache)


def test_the_faults_are_in_the_fe_body(reductions):
    """Material removed: the faulty body is lighter by the removed area times the face width and
    density (the shoelace areas of the outlines), and the missing tooth's flanks end at its cut
    circle."""
    job, _, healthy, faulty = reductions
    g = job["gear"]
    rho = job["material"].rho

    def mass(red):
        M = red.body.model.M
        ux = np.zeros(red.body.model.ndofs)
        ux[red.body.model.nodal_dofs(np.arange(red.body.model.mesh.p.shape[1]))[:, 0]] = 1.0
        return float(ux @ (M @ ux))

    def area(pts):
        x, y = pts.T
        return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))

    removed = area(g.outline().points) - area(FaultyGear(g, _faults(g)).outline().points)
    assert removed > 0.2 * g.module ** 2
    dm = mass(healthy) - mass(faulty)
    assert dm == pytest.approx(rho * g.face_width * removed, rel=0.02)  # the mesh's curved edges
    model = faulty.body.model
    cut = g.rf + 0.5 * (g.ra - g.rf)
    for s in ("left", "right"):
        nodes = np.unique(model.mesh.facets[:, model.mesh.boundaries[f"tooth{MISSING}_{s}"]])
        top = np.hypot(*model.mesh.p[:, nodes]).max()  # the last outline sample below the cut (spacing m/100)
        assert cut - g.module / 100 < top <= cut * (1 + 1e-12)


def test_reduced_static_compliance_of_the_faulty_teeth_equals_the_full_order(reductions):
    """At loaded flank points of the faulty teeth and their neighbours the modes plus the residual
    tables give the full-order compliance (exact up to round-off: same mesh, own tables); a tooth
    far from the faults reads its stand-in's tables, the approximation of shared tables. The
    faulty teeth differ from the healthy gear by much more (> 5 %), so shared tables would fail."""
    job, _, healthy, faulty = reductions
    g = job["gear"]
    full = FullOrder(faulty)
    t = faulty.tables
    assert t.period == g.z
    r = t.radius
    cut = g.rf + 0.5 * (g.ra - g.rf)
    # on the stump, just over a patch half-width (0.2 mm) below the cut
    below = int(np.searchsorted(r, cut - 0.35e-3)) - 1
    assert below > 10
    chip = int(np.searchsorted(r, g.ra - 0.85e-3)) - 1  # just below the chip (0.6 mm along the profile)
    cases = [(MISSING, LEFT, below), (MISSING, RIGHT, below // 2), (MISSING + 1, RIGHT, below),
             (MISSING - 1, LEFT, 5), (CHIPPED, LEFT, chip), (SPALLED, LEFT, int(0.7 * r.size))]
    changed = 0.0
    for tooth, side, j in cases:
        ref = full.compliance((tooth, side, r[j]), (tooth, side, r[j]))
        assert reduced_self(faulty, tooth, side, j) == pytest.approx(ref, rel=1e-6), (tooth, side, j)
        changed = max(changed, abs(ref / reduced_self(healthy, tooth, side, j) - 1.0))
    assert changed > 0.05
    # teeth 7 and 13 (no fault within 3 teeth) read the tables of tooth 21 (flank.shared_teeth): off
    # by the mesh's departure from cyclic symmetry (the healthy gear's tables, shared by every
    # tooth, are off by up to 0.4 % at level 0 at these points) and the faults' far field
    for far in (7, 13):
        for j in (20, 40):
            ref = full.compliance((far, LEFT, r[j]), (far, LEFT, r[j]))
            assert reduced_self(faulty, far, LEFT, j) == pytest.approx(ref, rel=0.01)
    assert reduced_self(faulty, 21, LEFT, 20) == pytest.approx(full.compliance((21, LEFT, r[20]), (21, LEFT, r[20])),
                                                               rel=1e-9)


def test_a_tooth_missing_to_the_root_is_rigid_and_its_neighbours_exact(reductions):
    """No flank left: its modal rows and tables are zero (the contact search finds nothing there);
    its neighbours' compliance is the full order's."""
    job, cache, _, _ = reductions
    red = reduce_gear(**job, faults=(Missing(gear="pinion", tooth=MISSING, height_fraction=0.0),), cache_dir=cache)
    model = red.body.model
    assert f"tooth{MISSING}_left" not in model.mesh.boundaries
    assert not red.modal[MISSING].any()
    for s in SIDES:
        assert not red.tables.self_residual[s][MISSING].any() and not red.tables.self_static[s][MISSING].any()
    full = FullOrder(red)
    r = red.tables.radius
    for tooth, side in ((MISSING + 1, RIGHT), (MISSING - 1, LEFT), (MISSING + 1, LEFT)):
        ref = full.compliance((tooth, side, r[60]), (tooth, side, r[60]))
        assert reduced_self(red, tooth, side, 60) == pytest.approx(ref, rel=1e-6)


def test_coupling_between_a_shared_tooth_and_a_faulty_one_equals_the_full_order(reductions):
    """The tables from a tooth with shared tables to a faulty one come from the faulty tooth's own
    by reciprocity (transposed): against the full order in both directions, several radii."""
    job, _, _, faulty = reductions
    g = job["gear"]
    full = FullOrder(faulty)
    t = faulty.tables
    rc = t.coupling_radius
    shared = MISSING + 2  # two teeth ahead: outside the faulty tooth's neighbours
    for a, b in (((MISSING, LEFT, 3), (shared, RIGHT, 8)), ((shared, LEFT, 12), (MISSING, LEFT, 4)),
                 ((CHIPPED, RIGHT, 14), (CHIPPED - 4, RIGHT, 2))):
        ref = full.compliance((a[0], a[1], rc[a[2]]), (b[0], b[1], rc[b[2]]))
        assert reduced_cross(faulty, a, b) == pytest.approx(ref, rel=1e-6, abs=1e-6 * abs(ref)), (a, b)


def test_bad_faults_are_refused_before_the_reduction(reductions):
    job, cache, _, _ = reductions
    two = (Crack(gear="pinion", tooth=2, flank=LEFT, depth=0.5e-3, angle=0.8),
           Crack(gear="pinion", tooth=9, flank=LEFT, depth=0.5e-3, angle=0.8))
    with pytest.raises(ConfigError, match="crack on pinion tooth 9, left flank: a flexible gear is meshed with one"):
        reduce_gear(**job, faults=two, cache_dir=cache)
    with pytest.raises(ConfigError, match="crack on pinion tooth 2, left flank: depth"):  # below the next space
        reduce_gear(**job, faults=(Crack(gear="pinion", tooth=2, flank=LEFT, depth=5e-3, angle=math.radians(80)),),
                    cache_dir=cache)
    with pytest.raises(ConfigError, match="width_fraction = 1"):
        reduce_gear(**job, faults=(Chip(gear="pinion", tooth=2, flank=LEFT, profile_size=0.3e-3, tip_size=0.2e-3,
                                        width_fraction=0.5),), cache_dir=cache)


# --------------------------------------------------------------------------------------------
# a flexible run with a missing tooth
# --------------------------------------------------------------------------------------------
MISSING_RUN = '\n[[faults]]\nkind = "missing"\ngear = "pinion"\ntooth = 5\nheight_fraction = 0.0\n'
CRACK_RUN = ('\n[[faults]]\nkind = "crack"\ngear = "pinion"\ntooth = 5\nflank = "left"\ndepth = 1.0e-3\n'
         'angle_deg = 45.0\n')


def _spur_run(level, speed, revolutions, missing=True, fault=MISSING_RUN):
    """The flexible spur pair on fixed revolutes (no shafts), pinion tooth 5 missing to the root
    (no flank left; or ``fault``) or healthy, mesh level ``level``, pinion at ``speed`` [Hz], a 5 %
    mesh damping ratio, a 25 us step (as tests/test_full_order.py) and the 100 kHz cutoff, over
    ``revolutions`` pinion turns after the run-in."""
    from flexgear.app.run import run
    from flexgear.config import loads_config, preset_path

    text = preset_path("spur_pair_flexible").read_text()
    cfg = loads_config(text.replace("[simulation]", (fault if missing else "") + "\n[simulation]"))
    cfg = cfg.use_damping_ratio(0.05)
    cfg.shafts = None
    cfg.flexible.update(level=level, cutoff=100e3, dynamic_cutoff=0.0)
    cfg.drive["speed_hz"] = speed
    cfg.load["ramp"] = 0.2 / speed
    cfg.simulation.update(step=2.5e-5, run_in=0.3 / speed, duration=(0.3 + revolutions) / speed, antialias=False,
                          output_rate=10000.0)
    return cfg, run(cfg)


def _tooth_loads(cfg, res):
    """(n samples, z) the force on each pinion tooth at every output sample [N]."""
    m = res.meshes["pinion-wheel"]
    loads = np.zeros((len(res.time), cfg.gears["pinion"].z))
    for c in range(m.pair_force.shape[1]):
        hit = m.pair_tooth_a[:, c] >= 0
        np.add.at(loads, (np.nonzero(hit)[0], m.pair_tooth_a[hit, c]), m.pair_force[hit, c])
    return loads


def _check_missing_tooth(cfg, res, healthy):
    from flexgear.app.metrics import approach

    z = cfg.gears["pinion"].z
    m = res.meshes["pinion-wheel"]
    loads = _tooth_loads(cfg, res)
    turned = np.ptp(res.bodies["pinion"].angle) / (2 * math.pi)
    assert turned > 2.0  # every tooth passed the mesh twice
    assert np.all(loads[:, 5] == 0.0)  # no contact on removed material
    for k in (4, 6):  # its neighbours are loaded while they pass (alone on the path: the whole load)
        assert loads[:, k].max() > 0.9 * loads.sum(axis=1).mean()
    # the transmission error (approach along the line of action), per mesh cycle: where it departs
    # from the healthy run's, it rises, and that happens once per pinion revolution (z cycles)
    f_mesh = cfg.drive["speed_hz"] * z
    cycle = np.floor((res.time - res.time[0]) * f_mesh).astype(int)
    n = cycle.max()  # the last cycle is partial
    te, te0 = approach(m), approach(healthy.meshes["pinion-wheel"])
    peak = np.array([te[cycle == i].max() for i in range(n)])
    peak0 = np.array([te0[cycle == i].max() for i in range(n)])
    jump = peak > peak0 + 0.1 * np.median(peak0)
    events = np.flatnonzero(jump)
    assert events.size >= 2 and np.all(peak[events] > 1.1 * peak0.max())
    first = events[0]
    assert np.all(np.abs((events - first + 2) % z - 2) <= 2)  # within 2 cycles of first + k z
    assert np.any(events >= first + z - 2)  # and it comes back a revolution later


@pytest.fixture(scope="module")
def spur_runs():
    """Level 0, the pinion at 20 Hz, 2.2 revolutions, healthy and with tooth 5 missing."""
    return _spur_run(0, 20.0, 2.2, missing=False)[1], _spur_run(0, 20.0, 2.2)


def test_a_missing_tooth_carries_nothing_and_the_transmission_error_rises_once_a_revolution(spur_runs):
    healthy, (cfg, res) = spur_runs
    _check_missing_tooth(cfg, res, healthy)


def test_a_cracked_tooth_sheds_load_to_its_neighbours_in_a_flexible_run(spur_runs):
    """Pinion tooth 5 cracked at its root on the loaded flank (1 mm, half the module, at 45 deg;
    the slit in the FE body), the run of the missing tooth's: a tooth pair shares the double
    contact zones with a neighbour in proportion to their stiffness, so the cracked, softer tooth
    carries less over its passage (impulse of its pair force) than any healthy tooth does over
    theirs (by 2 % at least; 4.4 % measured), which carry what the healthy run's teeth do (alike
    to 1 %) within the 2 % of the vibration the crack excites, and its neighbours 4 and 6 carry
    more than any of them; it
    still carries the whole load alone in its single contact zone (the crack softens, it does
    not remove). A crack missing from the FE body, or on another tooth, fails the first."""
    healthy = spur_runs[0]
    cfg, res = _spur_run(0, 20.0, 2.2, fault=CRACK_RUN)
    z = cfg.gears["pinion"].z
    dt = res.time[1] - res.time[0]

    def impulses(r):
        loads = _tooth_loads(cfg, r)
        k0 = np.argmax(loads.sum(axis=1) > 0)  # every tooth passes once in the first revolution
        n_rev = int(round(z / (cfg.drive["speed_hz"] * z * dt)))  # samples per pinion revolution
        return loads[k0:k0 + n_rev].sum(axis=0) * dt, loads

    cracked, loads = impulses(res)
    sound, _ = impulses(healthy)
    others = np.delete(np.arange(z), [4, 5, 6])
    assert np.ptp(sound) < 1e-2 * sound.mean()  # the healthy teeth alike
    assert np.abs(cracked[others] / sound.mean() - 1.0).max() < 2e-2  # ringing the crack excites
    assert cracked[5] < 0.98 * cracked[others].min()
    assert cracked[4] > cracked[others].max() and cracked[6] > cracked[others].max()
    total = cracked.sum()
    assert total == pytest.approx(sound.sum(), rel=1e-2)  # the same load passes
    assert loads[:, 5].max() > 0.9 * loads.sum(axis=1).mean()


@pytest.mark.slow
def test_a_missing_tooth_at_the_presets_speed_on_a_finer_mesh():
    """The check above at mesh level 1 and the preset's 10 Hz."""
    healthy = _spur_run(1, 10.0, 2.2, missing=False)[1]
    _check_missing_tooth(*_spur_run(1, 10.0, 2.2), healthy)


# --------------------------------------------------------------------------------------------
# a root crack in the flexible gear
# --------------------------------------------------------------------------------------------
CRACKED = 7
CRACK_DEPTH = 1.0e-3  # m, half the module


@pytest.fixture(scope="module")
def cracked(reductions):
    job, cache, healthy, _ = reductions
    crack = Crack(gear="pinion", tooth=CRACKED, flank=LEFT, depth=CRACK_DEPTH, angle=math.radians(45.0))
    return crack, reduce_gear(**job, faults=(crack,), cache_dir=cache)


def test_a_crack_is_a_slit_refined_at_its_tip_in_the_reduced_body(reductions, cracked):
    """The crack's faces do not share nodes (pairs of coincident nodes, the tip alone shared), the
    mesh is refined at the tip, and a load on the cracked flank opens the slit (full order)."""
    from flexgear.fe.crack import TIP_SIZE

    job, _, healthy, _ = reductions
    crack, red = cracked
    assert red.key != healthy.key
    model = red.body.model
    body, tooth = model.node_sets["crack_body"], model.node_sets["crack_tooth"]
    shared = np.intersect1d(body, tooth)
    assert shared.size == 1  # the tip
    a, b = np.setdiff1d(body, shared), np.setdiff1d(tooth, shared)
    assert a.size == b.size > 3
    pa = model.node_coords[a][np.lexsort(model.node_coords[a].T[::-1])]
    pb = model.node_coords[b][np.lexsort(model.node_coords[b].T[::-1])]
    assert np.array_equal(pa, pb)  # coincident pairs of distinct nodes
    tip = model.node_coords[shared[0]]
    g = job["gear"]
    h_tooth = job["settings"].sizes(g.module)[0]
    p = model.mesh.p
    edges = model.mesh.facets  # every edge of the mesh
    length = np.hypot(*(p[:, edges[0]] - p[:, edges[1]]))
    near = np.hypot(*(0.5 * (p[:, edges[0]] + p[:, edges[1]]) - tip[:, None])) < 0.1 * CRACK_DEPTH
    assert length[near].max() < 2 * TIP_SIZE * h_tooth < 0.5 * length.mean()
    # the slit opens under a load on the cracked flank: the paired nodes move apart
    full = FullOrder(red)
    r = red.tables.radius[64]
    f = full.load(CRACKED, LEFT, r)
    u = np.zeros(model.ndofs)
    u[full.free] = full.lu.solve(f)
    ia = model.nodal_dofs(a[np.lexsort(model.node_coords[a].T[::-1])])
    ib = model.nodal_dofs(b[np.lexsort(model.node_coords[b].T[::-1])])
    opening = np.hypot(*(u[ia] - u[ib]).T).max()
    assert opening > 0.05 * np.abs(u).max()


def test_reduced_static_compliance_of_the_cracked_tooth_equals_the_full_order(reductions, cracked):
    """As for the removed material: the cracked tooth and its neighbours read their own tables, the
    full-order FE of the cracked body (1e-6); the crack makes the loaded flank softer (> 5 % at
    mid-flank for a crack of half the module), the more so the higher the load on the flank (the
    crack weakens the root section, whose share of the compliance grows with the bending arm)."""
    job, _, healthy, _ = reductions
    _, red = cracked
    full = FullOrder(red)
    r = red.tables.radius
    soft = []
    for tooth, side, j in ((CRACKED, LEFT, 20), (CRACKED, LEFT, 64), (CRACKED, LEFT, 110), (CRACKED, RIGHT, 64),
                           (CRACKED + 1, RIGHT, 64), (CRACKED - 1, LEFT, 30)):
        ref = full.compliance((tooth, side, r[j]), (tooth, side, r[j]))
        assert reduced_self(red, tooth, side, j) == pytest.approx(ref, rel=1e-6), (tooth, side, j)
        if tooth == CRACKED and side == LEFT:
            soft.append(ref / reduced_self(healthy, tooth, side, j) - 1.0)
    assert soft[1] > 0.05 and soft[0] < soft[1] < soft[2]


RELIEF = "\n[errors.profile.wheel]\ntip_relief = 5.0e-6\ntip_relief_start_roll_deg = 25.0\n"


def test_the_deformed_view_of_a_faulty_run_uses_the_faulty_mesh(spur_runs, tmp_path):
    """The deformed gears of a faulty flexible result are drawn on the mesh the gear was reduced on
    (the FE field lives there); a frame reconstructs on it."""
    from flexgear.results.deformed import DeformedGears
    from flexgear.results.store import save

    _, (cfg, res) = spur_runs
    path = tmp_path / "results.h5"
    save(res, path)
    view = DeformedGears(path, stresses=False)
    (_, name, _, gm, red), = [b for b in view.bodies if b[1] == "pinion"]
    assert red.faults and gm.n_nodes == red.body.model.mesh.p.shape[1] and "tooth5_left" not in gm.facet_groups
    frame = view.frame(len(res.time) // 2)
    assert frame.gears


def _planet_config():
    from flexgear.config import loads_config, preset_path

    extra = '\n[[faults]]\nkind = "missing"\ngear = "planet"\nplanet = 2\ntooth = 2\nheight_fraction = 0.5\n'
    cfg = loads_config(preset_path("mercury_1a_flexible").read_text().replace("[simulation]", extra + "\n[simulation]"))
    cfg.flexible["level"] = 0
    return cfg


def test_a_faulty_planet_gets_a_reduction_of_its_own(tmp_path):
    """MERCURY 1-A flexible at level 0 with planet 2's tooth 2 missing: planet 2 is reduced with its
    fault (own key, per-tooth tables), the other planets read the healthy planet's reduction."""
    from flexgear.dynamics.flexible.reductions import body_reduction, reduction_jobs

    cfg = _planet_config()
    jobs, _ = reduction_jobs(cfg)
    assert set(jobs) == {"sun", "planet", "ring", "planet2"} and "faults" not in jobs["planet"]
    reds = {name: reduce_gear(**jobs[name], cache_dir=tmp_path) for name in ("planet", "planet2")}
    assert reds["planet2"].key != reds["planet"].key and reds["planet2"].tables.period == cfg.gears["planet"].z
    assert body_reduction(reds, "planet2", "planet") is reds["planet2"]
    assert body_reduction(reds, "planet3", "planet") is reds["planet"] and body_reduction(reds, "sun", "sun") is None


@pytest.mark.slow
def test_a_faulty_planets_body_carries_its_own_tables_in_the_model():
    """The whole MERCURY 1-A model (level 0): planet 2's flexible body has per-tooth tables and its
    own modal flank displacements, planets 1 and 3 share the healthy ones."""
    from flexgear.dynamics.flexible.reductions import reduce_flexible_gears
    from flexgear.dynamics.model.assembly import build_model

    cfg = _planet_config()
    reductions = reduce_flexible_gears(cfg)
    model = build_model(cfg, reductions=reductions)
    z = cfg.gears["planet"].z
    period = {model.bodies[f.body].name: f.self_compliance.shape[0] for f in model.flex}
    assert period["planet2"] == z and period["planet1"] == period["planet3"] == 1 and period["sun"] == 1
    shapes = {model.bodies[f.body].name: f.shape for f in model.flex}
    assert np.array_equal(shapes["planet1"], shapes["planet3"])
    assert not np.array_equal(shapes["planet1"], shapes["planet2"])


@pytest.mark.parametrize("flank", ["left", "right"])
def test_a_crack_on_a_flank_no_mesh_loads_stays_closed_and_a_planets_other_mesh_is_named(flank):
    """The FE slit has no contact between its faces: on the fillet of a flank no mesh loads (the
    spur pinion's right flank under the preset's load) the bending would close it, and the
    flexible pinion is reduced without it, the healthy body (a trial: that crack took 6.7 % of
    the tooth's load in the flexible model, 0 in the rigid and lumped ones, which apply a crack
    on its own flank only); on the loaded flank it is reduced with it. A flexible planet's crack
    is open in both of its meshes: the run warns of the one that would close it."""
    from flexgear.config import loads_config, preset_path
    from flexgear.dynamics.flexible.reductions import flexible_crack_note, loaded_body_flanks

    text = preset_path("spur_pair_flexible").read_text()
    cfg = loads_config(text.replace("[simulation]", CRACK_RUN.replace('"left"', f'"{flank}"') + "\n[simulation]"))
    jobs, _ = reduction_jobs(cfg)
    assert loaded_body_flanks(cfg) == {"pinion": {LEFT}, "wheel": {LEFT}}  # the wheel's mate flank
    note = flexible_crack_note(cfg)
    if flank == "left":
        assert [f.tooth for f in jobs["pinion"]["faults"]] == [5] and note == ""
    else:
        assert "faults" not in jobs["pinion"] and "stay closed, so the flexible gear is reduced without it" in note
    planet = loads_config(preset_path("mercury_1a").read_text() + '\n[flexible]\ngears = ["planet"]\n'
                          '\n[[faults]]\nkind = "crack"\ngear = "planet"\nplanet = 1\ntooth = 3\nflank = "left"\n'
                          'depth = 1.0e-3\n')
    flanks = loaded_body_flanks(planet)
    assert flanks["planet1"] == {LEFT, RIGHT} and len(flanks["sun"]) == len(flanks["ring"]) == 1
    assert "also softens the tooth while its other flank meshes" in flexible_crack_note(planet)
    assert [f.tooth for f in reduction_jobs(planet)[0]["planet1"]["faults"]] == [3]


def test_a_second_crack_on_a_flexible_body_is_refused_when_the_configuration_is_read():
    """A flexible gear's FE body holds one slit: a second full-width crack on it had passed
    check_config and `flexgear info` and was refused only at the model's build, seconds later.
    The rigid model takes both; a second crack on another planet's body is a body of its own."""
    from flexgear.config import loads_config, preset_path

    two = CRACK_RUN + CRACK_RUN.replace("tooth = 5", "tooth = 9")
    text = preset_path("spur_pair_flexible").read_text()
    with pytest.raises(ConfigError, match=r"faults\[1\] \(crack on pinion tooth 9, left flank\): a flexible gear is "
                                          r"meshed with one root crack .* faults\[0\] .* is on pinion already"):
        loads_config(text.replace("[simulation]", two + "\n[simulation]"))
    assert len(loads_config(preset_path("spur_pair").read_text() + two).faults) == 2
    planets = ('\n[[faults]]\nkind = "crack"\ngear = "planet"\nplanet = {}\ntooth = 3\nflank = "left"\n'
               'depth = 1.0e-3\n')
    cfg = loads_config(preset_path("mercury_1a").read_text() + '\n[flexible]\ngears = ["planet"]\n'
                       + planets.format(1) + planets.format(2))
    assert len(cfg.faults) == 2
