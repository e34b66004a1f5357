"""A root crack in the flexible ring (issue 22): MERCURY 1-A's ring reduced with the crack as a slit
in its FE body (:func:`flexgear.reduction.gear.reduce_gear`), checked from outside:

* the reduced cracked tooth's static compliance against the full-order FE of the same cracked ring
  (the rim held, as the reduction's ``support = "rim"``), for the same patch load on the flank;
* the stiffness drop the flexible model sees against the rigid model's crack law
  (:func:`flexgear.stiffness.crack.crack_pair_stiffness`: the planet-ring pair, the ring cracked);
* the crack tip's mesh convergence of that compliance;
* the reduction's cache key.

Fast variants at mesh level 0 with a 100 kHz cutoff (the ring's first clamped mode lies at 64 kHz
there): a static compliance does not depend on the cutoff, the residual tables carry the modes
above it. The slow ones at the flexible preset's level 2 and cutoff.
"""
import json
import math

import numpy as np
import pytest
from test_flexible_faults import FullOrder, reduced_self

from flexgear.config import load_config
from flexgear.dynamics.flexible.reductions import reduction_jobs
from flexgear.dynamics.model.tooth_laws import nominal_mesh_force
from flexgear.fe.crack import CrackMesh, cracked_mesh_digest, mesh_cracked_gear, root_crack
from flexgear.fe.elasticity import assemble
from flexgear.fe.meshing import mesh_cache_dir, mesh_digest
from flexgear.gears.faults import LEFT, RIGHT, Crack
from flexgear.gears.geometry import GearPair
from flexgear.reduction.gear import reduce_gear, reduction_cached, reduction_paths
from flexgear.stiffness.crack import crack_pair_stiffness

DEPTH = 1.0e-3  # m, half the module
ANGLE = math.radians(45.0)
#: The cracked tooth: tooth 0's left fillet is where crack_pair_stiffness places the crack law's
#: crack, so the reduced body and the law's FE are meshed alike (same mesh key).
TOOTH = 0
#: Table radii of the checks: near the ring's tip (long lever about the cracked root), mid-flank,
#: near its root (the ring's radii grow from tip to root).
POINTS = (20, 64, 110)


def _setup(level: int, cutoff: float | None = None):
    """(cfg, ring reduction job) of the flexible MERCURY 1-A preset at mesh level ``level``."""
    cfg = load_config("mercury_1a_flexible")
    cfg.flexible["level"] = level
    job = reduction_jobs(cfg)[0]["ring"]
    return cfg, (job if cutoff is None else dict(job, cutoff=cutoff))


def _crack(tooth: int = TOOTH, depth: float = DEPTH) -> Crack:
    return Crack(gear="ring", tooth=tooth, flank=LEFT, depth=depth, angle=ANGLE)


def _reductions(level: int, cutoff: float | None, cache):
    cfg, job = _setup(level, cutoff)
    return cfg, job, reduce_gear(**job, cache_dir=cache), reduce_gear(**job, faults=(_crack(),), cache_dir=cache)


@pytest.fixture(scope="module")
def ring():
    """(cache, cfg, job, healthy, cracked): the ring at level 0, healthy and with the crack, in the
    session's cache (tests/conftest.py), where the run of tests/test_flexible_ring_crack_run.py
    finds the cracked ring (one reduction per session)."""
    cache = mesh_cache_dir()
    return (cache,) + _reductions(0, 100e3, cache)


def test_the_cracked_ring_has_its_own_cache_entry(ring):
    """The cracked ring's key holds the cracked mesh's digest and the crack; the healthy ring's key
    is that of a ring reduced without faults (the plain mesh, no fault record), and a crack of
    zero depth reduces to it."""
    cache, _, job, healthy, cracked = ring
    g = job["gear"]
    assert cracked.key != healthy.key
    key = {n: json.loads(reduction_paths(cache, r.key)[1].read_text())["key"] for n, r in (("h", healthy), ("c", cracked))}
    assert key["h"]["mesh"] == mesh_digest(g, job["settings"]) and "faults" not in key["h"]["options"]
    assert key["c"]["mesh"] == cracked_mesh_digest(g, root_crack(g, DEPTH, ANGLE, tooth=TOOTH, side=LEFT),
                                                   job["settings"])
    [rec] = key["c"]["options"]["faults"]
    assert rec["kind"] == "crack" and rec["depth"] == DEPTH and rec["tooth"] == TOOTH
    assert reduce_gear(**job, faults=(_crack(depth=0.0),), cache_dir=cache).key == healthy.key
    assert reduction_cached(**job, faults=(_crack(),), cache_dir=cache)
    assert not reduction_cached(**job, faults=(_crack(depth=1.1e-3),), cache_dir=cache)
    assert not reduction_cached(**job, faults=(_crack(tooth=3),), cache_dir=cache)


def test_the_ring_crack_is_a_slit_its_flank_load_opens_and_the_other_closes(ring):
    """The faces share the tip node only; a load on the cracked flank opens the slit at every node
    pair (the fillet of the loaded flank is the tension side), a load on the other flank of the
    same tooth closes it (the linear FE lets the faces pass through each other there)."""
    _, _, job, _, cracked = ring
    g = job["gear"]
    crack = root_crack(g, DEPTH, ANGLE, tooth=TOOTH, side=LEFT)
    model = cracked.body.model
    body, tooth = model.node_sets["crack_body"], model.node_sets["crack_tooth"]
    shared = np.intersect1d(body, tooth)
    assert shared.size == 1 and np.allclose(model.node_coords[shared[0]], crack.tip, atol=1e-12)
    a, b = np.setdiff1d(body, shared), np.setdiff1d(tooth, shared)
    a = a[np.lexsort(model.node_coords[a].T[::-1])]
    b = b[np.lexsort(model.node_coords[b].T[::-1])]
    assert a.size == b.size > 3 and np.array_equal(model.node_coords[a], model.node_coords[b])
    full = FullOrder(cracked)
    r = cracked.tables.radius[POINTS[1]]
    for side, sense in ((LEFT, 1.0), (RIGHT, -1.0)):
        u = np.zeros(model.ndofs)
        u[full.free] = full.lu.solve(full.load(TOOTH, side, r))
        gap = (u[model.nodal_dofs(b)] - u[model.nodal_dofs(a)]) @ np.asarray(crack.normal)  # tooth face - body face
        assert np.all(sense * gap > 0), side


def _check_against_full_order(g, healthy, cracked):
    """Reduced (modes + residual tables) against full-order compliance at the cracked tooth and its
    neighbours: the same FE model condensed, exact up to round-off (1e-6); teeth far from the
    crack read a stand-in's tables (1 %, as the external gears' check). The cracked flank is
    softer than healthy, the more so the longer the lever from the load to the cracked root."""
    full = FullOrder(cracked)
    r = cracked.tables.radius
    own = [(TOOTH, LEFT, j) for j in POINTS] + [(TOOTH, RIGHT, 64), (TOOTH + 1, RIGHT, 64), (g.z - 1, LEFT, 30)]
    soft = []
    for tooth, side, j in own + [(20, LEFT, 40), (45, RIGHT, 80)]:
        ref = full.compliance((tooth, side, r[j]), (tooth, side, r[j]))
        rel = 1e-6 if (tooth, side, j) in own else 0.01
        assert reduced_self(cracked, tooth, side, j) == pytest.approx(ref, rel=rel), (tooth, side, j)
        if tooth == TOOTH and side == LEFT:
            soft.append(ref / reduced_self(healthy, tooth, side, j) - 1.0)
    assert soft[0] > soft[1] > soft[2] > 0.05  # the ring's tip lies at the small radii


def test_reduced_compliance_of_the_cracked_ring_tooth_equals_the_full_order(ring):
    _, _, job, healthy, cracked = ring
    _check_against_full_order(job["gear"], healthy, cracked)


def _check_crack_law(cfg, job, healthy, cracked, cache):
    """The flexible model's stiffness drop against the rigid model's crack law for the same crack.

    The law's ratio k_c / k_h (crack_pair_stiffness at the flexible model's mesh level and
    formulation) puts the cracked tooth's extra FE compliance dc in series with the healthy
    single-pair stiffness k_h: ratio = 1 / (1 + k_h dc). The flexible model sees dc as its cracked
    tables less its healthy ones, read by linear interpolation between the 129 table radii. Both
    come from the same FE model (the same mesh key: same gear, crack, settings), so they differ by
    that interpolation only, which the tables' second differences put at <= 1.6 % of dc at the
    ends of the path (the patch's clipping at the flank's ends kinks the tables there) and
    <= 0.4 % inside: drop 1 - ratio within 2 % at every point, 0.5 % RMS."""
    g = job["gear"]
    pair = GearPair(cfg.gears["planet"], g)
    cps = crack_pair_stiffness(pair, DEPTH, ANGLE, nominal_mesh_force(cfg), cracked=2, settings=job["settings"],
                               material=job["material"], formulation=job["formulation"], n_positions=12,
                               cache_dir=cache)
    assert cps.crack == root_crack(g, DEPTH, ANGLE, tooth=TOOTH, side=LEFT)  # the reduction's crack
    r = cracked.tables.radius
    dc = np.array([reduced_self(cracked, TOOTH, LEFT, j) - reduced_self(healthy, TOOTH, LEFT, j)
                   for j in range(r.size)])
    on = cps.on_path & np.isfinite(cps.ratio)
    assert on.sum() > 10
    drop_law = 1.0 - cps.ratio[on]
    drop_flex = 1.0 - 1.0 / (1.0 + cps.k_healthy[on] * np.interp(cps.healthy.c2.radius[on], r, dc))
    assert drop_law.min() > 0.01  # a drop the comparison resolves
    err = drop_flex / drop_law - 1.0
    assert np.abs(err).max() < 0.02 and math.sqrt(np.mean(err**2)) < 0.005, err


def test_the_flexible_rings_crack_drop_is_the_rigid_crack_law(ring):
    cache, cfg, job, healthy, cracked = ring
    _check_crack_law(cfg, job, healthy, cracked, cache)


def _tip_series(job, cracked, refines):
    """Full-order compliance [m/N] of the cracked flank at the table radii POINTS on the cracked
    ring meshed with its crack tip refined ``refines`` times (the tip size halves each time; the
    rest of the mesh as the level gives it), rim held. Refinement 0 is the reduction's own mesh
    (the default crack mesh: same key), whose FE model it takes."""
    g = job["gear"]
    crack = root_crack(g, DEPTH, ANGLE, tooth=TOOTH, side=LEFT)
    assert cracked_mesh_digest(g, crack, job["settings"], CrackMesh(refine=0)) == \
        cracked_mesh_digest(g, crack, job["settings"])
    radii = cracked.tables.radius[list(POINTS)]
    out = []
    for k in refines:
        if k == 0:
            full = FullOrder(cracked)
        else:
            gm = mesh_cracked_gear(g, crack, job["settings"], cache_dir=None, crack_mesh=CrackMesh(refine=k))
            full = FullOrder(model=assemble(gm, job["material"], g.face_width, job["formulation"]), gear=g)
        out.append([full.compliance((TOOTH, LEFT, r), (TOOTH, LEFT, r)) for r in radii])
    return np.array(out)


def test_the_cracked_ring_tooth_converges_under_crack_tip_refinement(ring):
    """Level 0, tip refined 0, 1, 2 times (0: the reduction's mesh): at each radius the change from
    one refinement to the next shrinks."""
    _, _, job, _, cracked = ring
    c = _tip_series(job, cracked, (0, 1, 2))
    d = np.abs(np.diff(c, axis=0))
    assert np.all(d[1] < d[0]), d / c[1:]


# --------------------------------------------------------------------------------------------
# the flexible preset's mesh level and cutoff
# --------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_the_cracked_ring_at_the_presets_level(tmp_path):
    """The checks above at the flexible preset's level 2 and cutoff, the crack tip refined three
    times: at each radius each halving of the tip size changes the cracked flank's compliance
    less than the one before."""
    cfg, job, healthy, cracked = _reductions(2, None, tmp_path)
    g = job["gear"]
    _check_against_full_order(g, healthy, cracked)
    _check_crack_law(cfg, job, healthy, cracked, tmp_path)
    c = _tip_series(job, cracked, (0, 1, 2, 3))
    d = np.abs(np.diff(c, axis=0))
    dc = np.array([reduced_self(cracked, TOOTH, LEFT, j) - reduced_self(healthy, TOOTH, LEFT, j) for j in POINTS])
    assert np.all(d[1:] < d[:-1]), d / dc  # relative to the crack's extra compliance


@pytest.mark.slow
def test_a_cracked_flexible_rings_body_carries_its_own_tables_in_the_model():
    """The whole flexible MERCURY 1-A model (level 0) with the ring cracked: the ring's flexible body has per-tooth tables (z
    classes) whose cracked flank is softer than its stand-ins', the sun and planets keep their
    shared ones."""
    from flexgear.config import loads_config, preset_path
    from flexgear.dynamics.flexible.reductions import reduce_flexible_gears
    from flexgear.dynamics.model.assembly import build_model

    extra = f'\n[[faults]]\nkind = "crack"\ngear = "ring"\ntooth = 5\nflank = "left"\ndepth = {DEPTH}\nangle_deg = 45.0\n'
    cfg = loads_config(preset_path("mercury_1a_flexible").read_text().replace("[simulation]", extra + "\n[simulation]"))
    cfg.flexible["level"] = 0
    reductions = reduce_flexible_gears(cfg)
    assert reductions["ring"].faults and reductions["ring"].tables.period == cfg.gears["ring"].z
    model = build_model(cfg, reductions=reductions)
    flex = {model.bodies[f.body].name: f for f in model.flex}
    assert flex["ring"].self_compliance.shape[0] == cfg.gears["ring"].z
    assert flex["sun"].self_compliance.shape[0] == flex["planet1"].self_compliance.shape[0] == 1
    ring = reductions["ring"]
    assert all(reduced_self(ring, 5, LEFT, j) > 1.05 * reduced_self(ring, 40, LEFT, j) for j in POINTS)
