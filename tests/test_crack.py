"""Root crack: geometry and its checks, the slit mesh, the cracked tooth's FE stiffness against
depth, mesh convergence, the published potential-energy model, a partial-width crack in 3D and
the rigid-model representations.

Default-suite checks use coarse meshes (level 0-2); ``-m slow`` runs the finer ones. The figures
are in docs/theory/crack.md.
"""
import math

import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.errors import ConfigError
from flexgear.fe.crack import (CrackMesh, crack_node_pairs, cracked_mesh_digest, fillet_curve,
                               mesh_cracked_gear, root_crack)
from flexgear.fe.elasticity import assemble, static_solve
from flexgear.fe.loads import flank_patch_load
from flexgear.fe.meshing import USER_CACHE, MeshSettings, mesh_gear
from flexgear.gears.geometry import GearPair
from flexgear.stiffness.compliance import clamp_group, involute_arc, tooth_compliance
from flexgear.stiffness.crack import (crack_convergence, crack_pair_stiffness, partial_width_stiffness,
                                      rigid_crack_errors)
from flexgear.stiffness.crack_energy import (beam_compliance, crack_tip_in_beam, pe_tooth_compliance)
from flexgear.fe.convergence import errors_decrease

NU45 = math.radians(45.0)
L0 = MeshSettings(level=0)


@pytest.fixture(scope="module")
def cfg():
    return load_config("spur_pair")


@pytest.fixture(scope="module")
def pinion(cfg):
    return cfg.gears["pinion"]


@pytest.fixture(scope="module")
def cache():
    """The session's mesh cache (tests/conftest.py: the test processes share it, never the
    user's): a mesh that several tests here and in other files use is meshed once."""
    return USER_CACHE


# ------------------------------------------------------------------ geometry
def test_start_is_the_30_degree_tangent_point_of_the_fillet(pinion):
    """ISO 6336-3's critical section: the fillet tangent makes 30 deg with the centre line there;
    the point lies on the fillet, between the root circle and the form circle."""
    c = root_crack(pinion, 1e-3, NU45)
    assert math.degrees(c.start_tangent) == pytest.approx(30.0, abs=0.5)
    assert pinion.rf < c.start_radius < pinion.r_form
    # the fillet's tangent falls from near 90 deg at the root land to near radial at the involute
    fil = fillet_curve(pinion)
    assert fil.tangent[0] > math.radians(75) and fil.tangent[-1] < math.radians(10)
    # tangent at the start from the outline itself (independent of the fillet sampling)
    ol = pinion.tooth_outline(pinion.module / 2000)
    p = ol.points
    i = int(np.argmin(np.hypot(*(p - np.array(c.start)).T)))
    t = p[i + 5] - p[i - 5]
    assert math.degrees(math.atan2(abs(t[1]), abs(t[0]))) == pytest.approx(30.0, abs=0.5)


@pytest.mark.parametrize("tooth, side", [(0, 1), (7, 1), (3, -1)])
def test_crack_line_depth_angle_and_frame(pinion, tooth, side):
    """The tip lies depth from the start, at the angle nu to the tooth's centre line, running
    towards the gear axis; the crack of tooth k / of the right flank is tooth 0's rotated /
    mirrored."""
    q, nu = 1.2e-3, math.radians(60)
    c = root_crack(pinion, q, nu, tooth=tooth, side=side)
    ref = root_crack(pinion, q, nu)
    s, tp = np.array(c.start), np.array(c.tip)
    assert np.hypot(*(tp - s)) == pytest.approx(q, rel=1e-12)
    axis = np.array([math.cos(2 * math.pi * tooth / pinion.z), math.sin(2 * math.pi * tooth / pinion.z)])
    d = (tp - s) / q
    assert math.degrees(math.acos(abs(d @ axis))) == pytest.approx(60.0, abs=1e-9)
    assert d @ axis < 0  # towards the gear axis
    assert np.hypot(*s) == pytest.approx(ref.start_radius, rel=1e-12)
    assert np.hypot(*tp) == pytest.approx(np.hypot(*ref.tip), rel=1e-12)
    # the normal points to the tooth tip's side of the crack line
    tip_of_tooth = pinion.ra * axis
    assert (tip_of_tooth - s) @ c.normal > 0


def test_start_radius_instead_of_tangent(pinion):
    c = root_crack(pinion, 1e-3, NU45)
    c2 = root_crack(pinion, 1e-3, NU45, start_radius=c.start_radius)
    assert np.allclose(c2.start, c.start, atol=1e-9)


@pytest.mark.parametrize("kw, words", [
    (dict(depth=5e-3, angle=math.radians(90)), ["depth = 5 mm", "leaves the tooth", "rule: depth <="]),
    (dict(depth=11e-3, angle=math.radians(20)), ["depth = 11 mm", "neighbouring tooth space", "rule: depth <="]),
    (dict(depth=1e-3, angle=0.0), ["angle = 0 deg", "(0, 90] deg"]),
    (dict(depth=1e-3, angle=math.radians(95)), ["angle = 95 deg", "(0, 90] deg"]),
    (dict(depth=-1e-4, angle=NU45), ["depth = -0.0001", ">= 0"]),
    (dict(depth=1e-5, angle=NU45), ["depth = 0.01 mm", "at least"]),
    (dict(depth=1e-3, angle=NU45, start_tangent=math.radians(89)), ["start_tangent = 89 deg", "off the root fillet", "rule:"]),
    (dict(depth=1e-3, angle=NU45, start_tangent=math.radians(0.5)), ["start_tangent = 0.5 deg", "off the root fillet"]),
    (dict(depth=1e-3, angle=NU45, start_radius=24e-3), ["start_radius = 24 mm", "off the root fillet", "must lie in"]),
    (dict(depth=1e-3, angle=NU45, start_radius=21e-3, start_tangent=0.5), ["both given"]),
    (dict(depth=1e-3, angle=NU45, tooth=24), ["tooth = 24", "0 <= tooth < z = 24"]),
    (dict(depth=1e-3, angle=NU45, side=0), ["side = 0", "+1"]),
    (dict(depth=1e-3, angle=math.radians(90), start_tangent=math.radians(78)), ["makes", "with the fillet", "at least 15 deg"]),
    (dict(depth=float("nan"), angle=NU45), ["depth = nan", "finite"]),
])
def test_bad_crack_is_a_clear_error_before_meshing(pinion, monkeypatch, kw, words):
    """Each rule is checked by root_crack (pure geometry, no gmsh); the message names the
    parameter, its value and the rule."""
    _refused_before_meshing(pinion, monkeypatch, kw, words)


def _refused_before_meshing(gear, monkeypatch, kw, words):
    import gmsh

    monkeypatch.setattr(gmsh, "initialize", lambda *a, **k: pytest.fail("gmsh called"))
    kw = dict(kw)
    depth, angle = kw.pop("depth"), kw.pop("angle")
    with pytest.raises(ConfigError) as e:
        root_crack(gear, depth, angle, name="faults[0]", **kw)
    msg = str(e.value)
    assert msg.startswith("faults[0]:")
    for w in words:
        assert w in msg, msg


def test_crack_limits_are_consistent(pinion):
    """The deepest crack the depth rule allows is accepted; just beyond it is refused."""
    nu = math.radians(90)
    with pytest.raises(ConfigError) as e:
        root_crack(pinion, 5e-3, nu)
    q_max = float(str(e.value).split("rule: depth <= ")[1].split(" mm")[0]) * 1e-3
    root_crack(pinion, 0.999 * q_max, nu)
    with pytest.raises(ConfigError):
        root_crack(pinion, 1.001 * q_max, nu)


def test_a_foreign_gear_is_refused(cfg, pinion):
    c = root_crack(pinion, 1e-3, NU45)
    with pytest.raises(ConfigError, match="another gear"):
        mesh_cracked_gear(cfg.gears["wheel"], c, L0, cache_dir=None)


# ------------------------------------------------------------------ mesh
@pytest.fixture(scope="module")
def ring():
    return load_config("mercury_1a").gears["ring"]


@pytest.fixture(scope="module", params=["pinion", "ring"])
def cracked_l0(request, cache):
    """(gear, crack, mesh): a 1 mm crack at 45 deg in the spur pinion and in MERCURY's ring, level 0."""
    gear = request.getfixturevalue(request.param)
    c = root_crack(gear, 1e-3, NU45)
    return gear, c, mesh_cracked_gear(gear, c, L0, cache_dir=cache)


def test_crack_faces_share_only_the_tip(cracked_l0, cache):
    gear, c, gm = cracked_l0
    a, b = gm.node_sets["crack_body"], gm.node_sets["crack_tooth"]
    shared = np.intersect1d(a, b)
    assert len(shared) == 1 and np.allclose(gm.points[shared[0]], c.tip, atol=1e-12)
    pairs = crack_node_pairs(gm)
    assert len(pairs) == len(a) - 1 and np.all(pairs[:, 0] != pairs[:, 1])
    assert np.array_equal(gm.points[pairs[:, 0]], gm.points[pairs[:, 1]])
    # the pairs lie on the crack line, from the mouth (the start) to just short of the tip
    d = gm.points[pairs[:, 0]] - np.array(c.start)
    assert np.allclose(d @ c.normal, 0.0, atol=1e-12)
    assert np.max(np.hypot(*d.T)) < c.depth and np.min(np.hypot(*d.T)) < 1e-12
    # every crack edge borders one triangle only: the faces are boundaries
    bnd = {tuple(sorted(e)) for e in gm.boundary_edges().tolist()}
    for name in ("crack_body", "crack_tooth"):
        for e in gm.facet_groups[name][:, :2].tolist():
            assert tuple(sorted(e)) in bnd
    # the triangles on the tooth side use the copies, those on the body side the originals
    tri_side = (gm.points[gm.triangles[:, :3]].mean(axis=1) - np.array(c.start)) @ c.normal
    uses_b = np.isin(gm.triangles, pairs[:, 1]).any(axis=1)
    uses_a = np.isin(gm.triangles, pairs[:, 0]).any(axis=1)
    assert np.all(tri_side[uses_b] > 0) and np.all(tri_side[uses_a] < 0)
    # no material removed; valid counter-clockwise elements; vertices numbered first
    healthy = mesh_gear(gear, L0, cache_dir=cache)
    assert gm.corner_areas().min() > 0
    assert gm.corner_areas().sum() == pytest.approx(healthy.corner_areas().sum(), rel=1e-4)
    assert gm.triangles[:, :3].max() + 1 == gm.n_vertices and gm.triangles[:, 3:].min() >= gm.n_vertices
    # refined at the tip: the edges at the tip are about the tip size, far smaller than h_tooth
    tip = shared[0]
    e = gm.triangles[np.any(gm.triangles[:, :3] == tip, axis=1)][:, :3]
    lengths = np.hypot(*(gm.points[e] - gm.points[tip]).reshape(-1, 2).T)
    lengths = lengths[lengths > 0]
    assert np.max(lengths) < 3 * gm.info["h_crack_tip"] < 0.5 * gm.info["h_tooth"]


def test_zero_depth_is_the_healthy_mesh_and_cache_round_trip(cracked_l0, cache):
    pinion, c, gm = cracked_l0  # the pinion or the ring
    healthy = mesh_gear(pinion, L0, cache_dir=cache)
    zero = mesh_cracked_gear(pinion, root_crack(pinion, 0.0, NU45), L0, cache_dir=cache)
    assert zero.key == healthy.key
    assert np.array_equal(zero.points, healthy.points) and np.array_equal(zero.triangles, healthy.triangles)
    again = mesh_cracked_gear(pinion, c, L0, cache_dir=cache)
    assert again.info["source"] == "cache" and again.key == gm.key != healthy.key
    assert np.array_equal(again.points, gm.points) and np.array_equal(again.triangles, gm.triangles)
    assert np.array_equal(crack_node_pairs(again), crack_node_pairs(gm))
    deeper = mesh_cracked_gear(pinion, root_crack(pinion, 1.1e-3, NU45), L0, cache_dir=cache)
    assert deeper.key != gm.key
    # the key without meshing, for caches built on the mesh (the reduction's)
    assert cracked_mesh_digest(pinion, c, L0) == gm.key
    assert cracked_mesh_digest(pinion, root_crack(pinion, 0.0, NU45), L0) == healthy.key


def _flank_load(model, gear, tooth, side, r):
    from skfem import FacetBasis

    name = f"tooth{tooth}_{'left' if side > 0 else 'right'}"
    fb = FacetBasis(model.mesh, model.basis.elem, facets=model.mesh.boundaries[name], intorder=8)
    return flank_patch_load(fb, gear.rb, float(involute_arc(gear, r)), 0.5 * gear.module,
                            model.thickness, 2, "test")


@pytest.mark.parametrize("name, tooth, side", [("pinion", 0, 1), ("pinion", 5, -1), ("ring", 0, 1), ("ring", 40, -1)])
def test_crack_opens_under_the_load_on_its_flank(request, cfg, cache, name, tooth, side):
    """Loaded on the cracked flank the tooth bends away from it: the fillet there is in tension
    and the faces part, most at the mouth and least next to the tip (opening ~ sqrt(r)); a ring's
    tooth (clamped at its rim) as an external one (clamped at its bore)."""
    pinion = request.getfixturevalue(name)
    c = root_crack(pinion, 1e-3, NU45, tooth=tooth, side=side)
    gm = mesh_cracked_gear(pinion, c, L0, cache_dir=cache)
    model = assemble(gm, cfg.material, pinion.face_width)
    load = 1e4 * _flank_load(model, pinion, tooth, side, pinion.r)
    u = static_solve(model, model.group_dofs(clamp_group(pinion)), load)
    U = model.nodal_field(u)
    pairs = crack_node_pairs(gm)
    opening = (U[pairs[:, 1]] - U[pairs[:, 0]]) @ c.normal
    dist = np.hypot(*(gm.points[pairs[:, 0]] - np.array(c.tip)).T)
    o = np.argsort(dist)
    assert np.all(opening > 0)
    assert np.all(np.diff(opening[o]) > 0)
    # the near-tip field: opening ~ sqrt(distance) (LEFM), within 25 % between the two nodes
    # closest to the tip and the quarter of the crack
    near, mid = o[0], o[np.argmin(np.abs(dist - 0.25 * c.depth))]
    ratio = (opening[mid] / opening[near]) / math.sqrt(dist[mid] / dist[near])
    assert 0.75 < ratio < 1.25


# ------------------------------------------------------------------ stiffness against depth
DEPTHS = (0.5e-3, 1.0e-3, 1.5e-3)


@pytest.fixture(scope="module")
def depth_series(cfg, cache):
    """Single-pair stiffness of the spur pair (pinion cracked), level 0, at the paper's load."""
    pair = cfg.pairs["pinion-wheel"]
    load = 200.0 / pair.g2.rb
    out = []
    healthy = None
    for q in DEPTHS:
        cps = crack_pair_stiffness(pair, q, NU45, load, settings=L0, material=cfg.material,
                                   n_positions=12, healthy=healthy, cache_dir=cache)
        healthy = cps.healthy
        out.append(cps)
    return out


def test_single_pair_stiffness_falls_monotonically_with_depth(depth_series):
    on = depth_series[0].on_path
    k = np.array([depth_series[0].k_healthy[on]] + [c.k_cracked[on] for c in depth_series])
    assert np.all(np.isfinite(k))
    assert np.all(np.diff(k, axis=0) < 0), np.diff(k, axis=0)
    dc = np.array([c.delta_c[on] for c in depth_series])
    assert np.all(dc > 0) and np.all(np.diff(dc, axis=0) > 0)
    # the crack's extra compliance is load independent and enters k in series
    c0 = depth_series[1]
    assert np.allclose(1 / c0.k_cracked[on] - 1 / c0.k_healthy[on], c0.delta_c[on], rtol=1e-9)


# ------------------------------------------------------------------ convergence
def test_cracked_tooth_converges_on_coarse_levels(cfg, pinion, cache):
    """Levels 0, 1, 2 with the crack tip refined in proportion: the cracked tooth's compliance
    at the pitch point rises monotonically under refinement (a conforming FE model is too
    stiff), with a positive observed order and errors against the Richardson value falling."""
    res = crack_convergence(pinion, 1e-3, NU45, [0, 1, 2], [pinion.r], material=cfg.material,
                            cache_dir=cache)
    assert np.all(np.diff(res.cracked[:, 0]) > 0)
    assert res.rich.monotone[0] and res.rich.order[0] > 0.5
    assert errors_decrease(res.rich.rel_error)[0]
    assert res.rich.rel_error[-1, 0] < 0.01
    assert np.allclose(res.h_tip / res.h, res.h_tip[0] / res.h[0])  # tip refined with the level


@pytest.mark.slow
def test_cracked_tooth_default_level_is_converged(cfg, pinion, tmp_path):
    """Levels 1-4: the default level 2 is within 1 % of the Richardson value at the pitch point,
    with an observed order near the smooth problem's (the graded tip zone removes the r^(1/2)
    singularity's h^1 limit); the crack's extra compliance varies by < 1 % over the levels; a
    4x finer tip at level 2 moves the cracked compliance by < 0.2 %."""
    res = crack_convergence(pinion, 1e-3, NU45, [1, 2, 3, 4], [pinion.r], material=cfg.material,
                            cache_dir=tmp_path)
    assert res.rich.monotone[0] and 1.0 < res.rich.order[0] < 3.0
    assert errors_decrease(res.rich.rel_error)[0]
    assert res.rich.rel_error[1, 0] < 0.01
    delta = res.cracked[:, 0] - res.healthy[:, 0]
    assert np.ptp(delta) / delta[-1] < 0.01
    c = root_crack(pinion, 1e-3, NU45)
    gm = mesh_cracked_gear(pinion, c, MeshSettings(level=2), cache_dir=tmp_path, crack_mesh=CrackMesh(refine=2))
    model = assemble(gm, cfg.material, pinion.face_width, "plane_strain")
    fine = tooth_compliance(pinion, [pinion.r], model=model, neighbours=False).bulk[0]
    assert fine == pytest.approx(res.cracked[1, 0], rel=2e-3)


# ------------------------------------------------------------------ internal gear (ring)
def test_ring_crack_starts_at_the_60_degree_tangent_and_runs_towards_the_rim(ring):
    """ISO 6336-3's critical section of an internal gear: the fillet tangent at 60 deg to the
    centre line, between the form circle and the root circle (which lies outside it). The tooth
    points to the centre, so the crack runs outwards into the rim, at nu to the centre line's
    direction tip -> root, towards the centre line; the config layer's crack path
    (flexgear.gears.faults.crack_path, sampled independently) puts it at the same place."""
    from flexgear.gears.faults import Crack, crack_path

    c = root_crack(ring, 1e-3, NU45)
    assert math.degrees(c.start_tangent) == pytest.approx(60.0, abs=0.5)
    assert ring.r_form < c.start_radius < ring.rf
    ol = ring.tooth_outline(ring.module / 2000)
    p = ol.points
    i = int(np.argmin(np.hypot(*(p - np.array(c.start)).T)))
    t = p[i + 5] - p[i - 5]
    assert math.degrees(math.atan2(abs(t[1]), abs(t[0]))) == pytest.approx(60.0, abs=0.5)
    for tooth, side, nu in ((0, 1, 45.0), (17, -1, 70.0)):
        q = 1.2e-3
        c = root_crack(ring, q, math.radians(nu), tooth=tooth, side=side)
        s, tp = np.array(c.start), np.array(c.tip)
        axis = np.array([math.cos(2 * math.pi * tooth / ring.z), math.sin(2 * math.pi * tooth / ring.z)])
        d = (tp - s) / q
        assert np.hypot(*(tp - s)) == pytest.approx(q, rel=1e-12)
        assert math.degrees(math.acos(d @ axis)) == pytest.approx(nu, abs=1e-9)  # outwards, away from the axis
        assert np.allclose(c.direction, d, atol=1e-12)
        # towards the centre line: the tip's polar angle lies nearer the tooth's than the start's
        ang = lambda v: math.atan2(axis[0] * v[1] - axis[1] * v[0], v @ axis)  # noqa: E731
        assert side * ang(s) > side * ang(tp)
        assert (ring.ra * axis - s) @ c.normal > 0  # the normal points to the tooth tip's side
        p0, p1 = crack_path(ring, Crack(gear="ring", tooth=tooth, flank=side, depth=q, angle=math.radians(nu)))
        rot = np.array([[axis[0], -axis[1]], [axis[1], axis[0]]])  # tooth frame -> gear frame
        assert np.allclose(rot @ p0, s, atol=1e-6) and np.allclose(rot @ p1, tp, atol=1e-6)


@pytest.mark.parametrize("kw, words", [
    (dict(depth=20e-3, angle=NU45), ["depth = 20 mm", "leaves the tooth", "rule: depth <="]),
    (dict(depth=6e-3, angle=math.radians(90)), ["depth = 6 mm", "leaves the tooth", "rule: depth <="]),
    (dict(depth=8e-3, angle=math.radians(60)), ["depth = 8 mm", "neighbouring tooth space", "rule: depth <="]),
    (dict(depth=1e-3, angle=0.0), ["angle = 0 deg", "(0, 90] deg"]),
    (dict(depth=1e-3, angle=math.radians(95)), ["angle = 95 deg", "(0, 90] deg"]),
    (dict(depth=1e-3, angle=NU45, start_tangent=math.radians(20)), ["start_tangent = 20 deg", "off the root fillet"]),
    (dict(depth=1e-3, angle=NU45, start_radius=66e-3), ["start_radius = 66 mm", "off the root fillet", "must lie in"]),
    (dict(depth=1e-3, angle=NU45, start_radius=68e-3, start_tangent=1.0), ["both given", "60 deg tangent point"]),
    (dict(depth=1e-3, angle=NU45, tooth=66), ["tooth = 66", "0 <= tooth < z = 66"]),
])
def test_bad_ring_crack_is_a_clear_error_before_meshing(ring, monkeypatch, kw, words):
    """The external tooth's rules hold for the ring; the rim bounds the crack as the bore does."""
    _refused_before_meshing(ring, monkeypatch, kw, words)


def test_ring_crack_limit_is_where_the_line_reaches_the_rim(ring):
    """At 20 deg the crack leaves through the rim: the deepest allowed crack ends a ligament of
    0.1 module inside the rim circle, along the straight line from the start."""
    nu = math.radians(20)
    with pytest.raises(ConfigError) as e:
        root_crack(ring, 20e-3, nu)
    q_max = float(str(e.value).split("rule: depth <= ")[1].split(" mm")[0]) * 1e-3
    c = root_crack(ring, 0.999 * q_max, nu)
    s, d = np.array(c.start), c.direction
    R = 0.5 * ring.rim_diameter
    t_rim = -(s @ d) + math.sqrt((s @ d) ** 2 - (s @ s - R * R))  # |s + t d| = R
    assert q_max == pytest.approx(t_rim - 0.1 * ring.module, abs=1e-5)
    with pytest.raises(ConfigError):
        root_crack(ring, 1.001 * q_max, nu)


@pytest.fixture(scope="module")
def ring_depth_series(cache):
    """Single-pair stiffness of MERCURY's planet-ring pair, the ring cracked (gear 2), level 0, at
    the static mesh force (carrier torque 60 N m: z_s / (z_s + z_r) of it on the sun, three planets)."""
    cfg = load_config("mercury_1a")
    pair = GearPair(cfg.gears["planet"], cfg.gears["ring"])
    s, r = cfg.gears["sun"], cfg.gears["ring"]
    load = 60.0 * s.z / (s.z + r.z) / (3 * s.rb)
    out, healthy = [], None
    for q in DEPTHS:
        cps = crack_pair_stiffness(pair, q, NU45, load, cracked=2, settings=L0, material=cfg.material,
                                   n_positions=12, healthy=healthy, cache_dir=cache)
        healthy = cps.healthy
        out.append(cps)
    return out


def test_ring_single_pair_stiffness_falls_monotonically_with_depth(ring_depth_series):
    """The planet-ring pair with the ring tooth cracked: stiffness falls with depth at every point
    of the path, the crack's extra compliance grows and is load independent (in series); it is
    largest with the contact at the ring's tip (the longest lever about the cracked root: the
    ring's roll angle grows towards its root), so the ratio rises along the ring's roll angle."""
    test_single_pair_stiffness_falls_monotonically_with_depth(ring_depth_series)
    for c in ring_depth_series:
        on = c.on_path
        o = np.argsort(c.roll[on])
        assert c.ratio[on][o][0] < c.ratio[on][o][-1] - 0.005


def test_ring_cracked_tooth_converges_on_coarse_levels(cfg, ring, cache):
    """As the pinion's (test_cracked_tooth_converges_on_coarse_levels): the ring's cracked tooth
    at the reference circle, levels 0-2, rim clamped."""
    res = crack_convergence(ring, 1e-3, NU45, [0, 1, 2], [ring.r], material=cfg.material, cache_dir=cache)
    assert np.all(np.diff(res.cracked[:, 0]) > 0)
    assert res.rich.monotone[0] and res.rich.order[0] > 0.5
    assert errors_decrease(res.rich.rel_error)[0]
    assert res.rich.rel_error[-1, 0] < 0.01
    assert np.allclose(res.h_tip / res.h, res.h_tip[0] / res.h[0])
    delta = res.cracked[:, 0] - res.healthy[:, 0]
    assert np.all(delta > 0) and np.ptp(delta) / delta[-1] < 0.03


@pytest.mark.slow
def test_ring_cracked_tooth_default_level_is_converged(cfg, ring, tmp_path):
    """Levels 1-4: the default level 2 within 1 % of the Richardson value, the crack's extra
    compliance within 1 % over the levels (as the pinion's)."""
    res = crack_convergence(ring, 1e-3, NU45, [1, 2, 3, 4], [ring.r], material=cfg.material, cache_dir=tmp_path)
    assert res.rich.monotone[0] and res.rich.order[0] > 1.0
    assert errors_decrease(res.rich.rel_error)[0]
    assert res.rich.rel_error[1, 0] < 0.01
    delta = res.cracked[:, 0] - res.healthy[:, 0]
    assert np.ptp(delta) / delta[-1] < 0.01


# ------------------------------------------------------------------ potential-energy model
def test_beam_compliance_is_timoshenkos_cantilever():
    """Uniform section 2h, force inclined by a1 at (d, h_F): bending of M = F (cos a1 (d - x) -
    sin a1 h_F) plus shear (factor 1.2) and axial terms, in closed form."""
    E, G, L, h, d, hF, a1 = 2.1e11, 8.1e10, 0.02, 1.5e-3, 4e-3, 1.0e-3, 0.3
    x = np.linspace(0, 6e-3, 20001)
    c = beam_compliance(x, np.full_like(x, 2 * h), d, hF, a1, E, G, L)
    I, A = (2 * h) ** 3 * L / 12, 2 * h * L
    ca, sa = math.cos(a1), math.sin(a1)
    bend = (ca * ca * d ** 3 / 3 - ca * sa * hF * d ** 2 + sa * sa * hF * hF * d) / (E * I)
    assert c.bending == pytest.approx(bend, rel=1e-7)
    assert c.shear == pytest.approx(1.2 * ca * ca * d / (G * A), rel=1e-9)
    assert c.axial == pytest.approx(sa * sa * d / (E * A), rel=1e-9)


@pytest.fixture(scope="module")
def pe_vs_fe(cfg, pinion, cache):
    """FE (level 0, plane stress as the papers' E) and PE tooth compliance at five radii."""
    radii = np.linspace(pinion.r_form + 0.3e-3, pinion.ra - 0.2e-3, 5)
    healthy = assemble(mesh_gear(pinion, L0, cache_dir=cache), cfg.material, pinion.face_width)
    fe_h = tooth_compliance(pinion, radii, model=healthy, neighbours=False).bulk
    pe_h = pe_tooth_compliance(pinion, radii, cfg.material).total
    dfe, dpe = [], []
    for q in DEPTHS:
        c = root_crack(pinion, q, NU45)
        model = assemble(mesh_cracked_gear(pinion, c, L0, cache_dir=cache), cfg.material, pinion.face_width)
        dfe.append(tooth_compliance(pinion, radii, model=model, neighbours=False).bulk - fe_h)
        dpe.append(pe_tooth_compliance(pinion, radii, cfg.material, tip=crack_tip_in_beam(pinion, c)).total - pe_h)
    return radii, fe_h, pe_h, np.array(dfe), np.array(dpe)


def test_potential_energy_model_against_fe(pe_vs_fe):
    """Tian (2004) / Wu, Zuo & Parey (2008) / Chen & Shao (2011), the crack tip placed where the
    FE crack's is. Both give a compliance growing with depth. The differences are those of the
    model's assumptions (docs/theory/crack.md): without the fillet and rim the healthy beam is stiffer
    than the FE tooth; the crack only shrinks the beam's sections (no tip singularity, no
    rotation of the cracked root), so the model's crack compliance scales with the bending
    lever and its share of the FE's grows from the root to the tip at every depth, from well
    below it near the root."""
    radii, fe_h, pe_h, dfe, dpe = pe_vs_fe
    assert np.all(pe_h < fe_h)
    assert np.all(np.diff(dfe, axis=0) > 0) and np.all(np.diff(dpe, axis=0) > 0)
    share = dpe / dfe
    assert np.all(np.diff(share, axis=1) > 0), share
    assert np.all(share[:, 0] < 0.5)


# ------------------------------------------------------------------ partial width
def test_partial_width_slices():
    kh, kc = np.array([3.0e8, 3.2e8]), np.array([2.4e8, 2.5e8])
    assert np.allclose(partial_width_stiffness(kh, kc, 0.0), kh)
    assert np.allclose(partial_width_stiffness(kh, kc, 1.0), kc)
    assert np.allclose(partial_width_stiffness(kh, kc, 0.25), 0.75 * kh + 0.25 * kc)
    with pytest.raises(ConfigError, match="fraction = 1.5"):
        partial_width_stiffness(kh, kc, 1.5)


def _check_partial(r):
    # the crack softens the sector the more the wider it is
    assert np.all(np.diff(r.k3d) < 0)
    # plane-stress slices are a lower bound (cut slices are less constrained than the 3D body)
    assert np.all(r.slice_error("plane_stress") < 0)
    # slices calibrated on the 3D healthy and through-cracked sector: the partial crack is
    # stiffer than them (the healthy width supports the cracked part); the slices overstate the
    # partial crack's stiffness loss by less than half of it
    f = r.fractions[1:-1]
    err = r.slice_error("3d")[1:-1]
    assert np.all(err < 0)
    assert np.all(-err < 0.5 * f * (1 - r.k3d[-1] / r.k3d[0]))


def test_extruded_sector_with_partial_crack(pinion):
    """The 3D half sector: valid tetrahedra filling the 2D sector times b/2, the crack nodes
    copied on the levels inside the crack only (its front across the width shared), the crack
    faces free boundaries there and nowhere else."""
    from flexgear.stiffness.compliance3d import mesh_sector
    from flexgear.stiffness.crack3d import SECTOR_CRACK_MESH, extrude_sector, glued_sector

    c = root_crack(pinion, 1e-3, NU45)
    sm2 = mesh_sector(pinion, dim=2, h=2.5e-3, n_teeth=1, crack=c, crack_mesh=SECTOR_CRACK_MESH)
    half = 0.5 * pinion.face_width
    z = np.array([0.0, 0.25, 0.5, 0.75, 1.0]) * half
    pairs = crack_node_pairs(sm2.gear_mesh)
    area = glued_sector(sm2).mesh
    p = area.p[:, area.t]
    area = 0.5 * np.sum(np.abs((p[0, 1] - p[0, 0]) * (p[1, 2] - p[1, 0]) - (p[0, 2] - p[0, 0]) * (p[1, 1] - p[1, 0])))
    n2 = sm2.gear_mesh.n_nodes - len(pairs)
    for f, open_levels in ((0.0, 0), (0.5, 2), (1.0, 5)):  # f = 0.5: levels 0.75, 1.0 of z
        m = extrude_sector(sm2, pinion, f, z).mesh
        q = m.p[:, m.t]
        vol = np.einsum("ij,ij->j", np.cross((q[:, 1] - q[:, 0]).T, (q[:, 2] - q[:, 0]).T).T, q[:, 3] - q[:, 0]) / 6
        assert vol.min() > 0 and vol.sum() == pytest.approx(area * half, rel=1e-12)
        assert m.nvertices == n2 * len(z) + len(pairs) * open_levels
        assert len(m.boundaries["symmetry"]) > 0 and len(m.boundaries["flank"]) > 0


def test_partial_width_crack_3d_coarse(cfg, pinion):
    from flexgear.stiffness.crack3d import partial_crack_check

    r = partial_crack_check(pinion, root_crack(pinion, 1e-3, NU45), (0.0, 0.5, 1.0), h=2.5e-3,
                            strips=2, material=cfg.material)
    _check_partial(r)


@pytest.mark.slow
def test_partial_width_crack_3d(cfg, pinion):
    from flexgear.stiffness.crack3d import partial_crack_check

    r = partial_crack_check(pinion, root_crack(pinion, 1e-3, NU45), (0.0, 0.25, 0.5, 0.75, 1.0),
                            h=1.5e-3, strips=4, material=cfg.material)
    _check_partial(r)


# ------------------------------------------------------------------ rigid representations
def test_rigid_representations_closed_forms(depth_series):
    """The errors of :func:`rigid_crack_errors` against a direct evaluation: the series
    representation solved for the approach of F = K delta_c^e with delta = delta_c + dc F, the
    contact-law factor as the FE ratio at the reference load."""
    from scipy.optimize import brentq

    cps = depth_series[1]
    K, e = 2.38e9, 1.3
    F = 0.7 * cps.load
    err = rigid_crack_errors(cps, {"law": (K, e)}, [cps.load, F])
    on = cps.on_path
    kh, kc = cps.at_load(F)
    fe = (kc / kh)[on]
    j = 3
    dc = cps.delta_c[on][j]
    delta = (F / K) ** (1 / e) + dc * F  # approach of the cracked pair: contact + series spring
    f_at = brentq(lambda f: (f / K) ** (1 / e) + dc * f - delta, 1e-6 * F, 10 * F)
    assert f_at == pytest.approx(F, rel=1e-10)
    ratio = (F / delta) / (F / (F / K) ** (1 / e))
    assert err.series["law"][1, j] == pytest.approx(ratio / fe[j] - 1, rel=1e-9)
    assert np.allclose(err.law_table[0], 0.0, atol=1e-12)  # exact at the reference load
    assert err.law_table[1, j] == pytest.approx(cps.ratio[on][j] / fe[j] - 1, rel=1e-12)
    assert err.law_constant[0, j] == pytest.approx(np.mean(cps.ratio[on]) / cps.ratio[on][j] - 1, rel=1e-12)
