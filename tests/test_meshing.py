"""Meshing of gear bodies with gmsh: topology, groups, quality, cache, input checks."""
import json
import math

import gmsh
import numpy as np
import pytest

from flexgear.errors import ConfigError, GeometryError
from flexgear.gears.geometry import SpurGear
from flexgear.fe.meshing import (
    Circle,
    MeshSettings,
    cache_key,
    cache_paths,
    mesh_gear,
    mesh_polygon,
)

M = 2e-3


@pytest.fixture(scope="module")
def sun():
    return SpurGear(z=24, module=M, bore_diameter=0.02, face_width=0.02, name="sun")


@pytest.fixture(scope="module")
def ring():
    return SpurGear(z=66, module=M, internal=True, rim_diameter=0.16, face_width=0.02,
                    name="ring")


@pytest.fixture(scope="module")
def sun_mesh(sun):
    return mesh_gear(sun, MeshSettings(level=0), cache_dir=None)


@pytest.fixture(scope="module")
def ring_mesh(ring):
    return mesh_gear(ring, MeshSettings(level=0), cache_dir=None)


def _no_gmsh(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("gmsh must not be called")

    monkeypatch.setattr(gmsh, "initialize", boom)
    monkeypatch.setattr(gmsh, "model", None)


# ------------------------------------------------------------------ settings
@pytest.mark.parametrize("level", [-1, 6, 2.5, True, "2"])
def test_level_out_of_range(level):
    with pytest.raises(ConfigError) as e:
        MeshSettings(level=level)
    msg = str(e.value)
    assert "mesh.level" in msg and repr(level) in msg and "0..5" in msg


def test_order_checked():
    with pytest.raises(ConfigError, match="mesh.order = 3"):
        MeshSettings(order=3)


def test_sizes_shrink_by_sqrt2_per_level():
    h = [MeshSettings(level=k).sizes(M) for k in range(6)]
    for a, b in zip(h, h[1:]):
        assert a[0] / b[0] == pytest.approx(math.sqrt(2))
        assert a[1] / b[1] == pytest.approx(math.sqrt(2))
    assert h[0][0] < h[0][1]  # teeth finer than body


def test_defaults_are_quadratic_level_2():
    s = MeshSettings()
    assert (s.level, s.order) == (2, 2)


# ------------------------------------------------------------------ topology and groups
def _loops(edges):
    """Number of closed loops formed by boundary edges; every vertex must have degree 2."""
    deg = np.bincount(edges.ravel())
    used = np.flatnonzero(deg)
    assert np.all(deg[used] == 2), "boundary is not a set of closed curves"
    parent = {int(v): int(v) for v in used}

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b in edges:
        parent[find(int(a))] = find(int(b))
    return len({find(int(v)) for v in used})


def _edge_set(e):
    return {tuple(sorted(x)) for x in np.asarray(e)[:, :2].tolist()}


def test_external_gear_boundary_is_outline_plus_bore(sun, sun_mesh):
    g = sun_mesh
    bnd = g.boundary_edges()
    assert _loops(bnd) == 2
    assert _edge_set(bnd) == _edge_set(g.facet_groups["outline"]) | _edge_set(g.facet_groups["hub"])
    # bore nodes (mid-nodes too, order 2) lie on the bore circle
    r = np.hypot(*g.points[g.node_sets["hub"]].T)
    assert np.allclose(r, 0.01, rtol=1e-9, atol=0)
    # the toothed outline spans root to tip circle
    r = np.hypot(*g.points[g.node_sets["outline"]].T)
    assert r.min() == pytest.approx(sun.rf, rel=1e-6) and r.max() == pytest.approx(sun.ra, rel=1e-6)


def test_boundary_groups_present(sun, sun_mesh):
    g = sun_mesh
    names = {"hub", "root_fillets", "tips", "outline"}
    names |= {f"tooth{k}_{s}" for k in range(sun.z) for s in ("left", "right")}
    assert names <= set(g.facet_groups)
    assert "rim" not in g.facet_groups
    for n in names:
        assert len(g.facet_groups[n]) > 0, n
    # outline = flanks + root_fillets + tips, without overlap
    parts = [g.facet_groups[n] for n in names - {"hub", "outline"}]
    assert sum(len(p) for p in parts) == len(g.facet_groups["outline"])
    # flanks between form circle and tip; left flank at positive angle from the tooth centre
    for k in (0, 5, 23):
        for side, sgn in (("left", 1), ("right", -1)):
            p = g.points[g.node_sets[f"tooth{k}_{side}"]]
            r = np.hypot(*p.T)
            assert r.min() >= sun.r_form * (1 - 1e-6) and r.max() <= sun.ra * (1 + 1e-9)
            dth = np.angle(np.exp(1j * (np.arctan2(p[:, 1], p[:, 0]) - 2 * np.pi * k / sun.z)))
            assert np.all(sgn * dth > 0)
    # root/fillet points lie inside the form circle (up to the sampled flank-fillet junction)
    r = np.hypot(*g.points[g.node_sets["root_fillets"]].T)
    assert r.min() == pytest.approx(sun.rf, rel=1e-6)
    assert r.max() <= sun.r_form + 0.01 * M


def test_internal_gear_annulus(ring, ring_mesh):
    g = ring_mesh
    assert {"rim", "outline", "root_fillets", "tooth0_left", "tooth65_right"} <= set(g.facet_groups)
    assert "hub" not in g.facet_groups
    assert _loops(g.boundary_edges()) == 2
    r = np.hypot(*g.points[g.node_sets["rim"]].T)
    assert np.allclose(r, 0.08, rtol=1e-9, atol=0)
    # material between the toothed outline and the rim: every node outside the tip circle
    rr = np.hypot(*g.points.T)
    assert rr.min() == pytest.approx(ring.ra, rel=1e-6) and rr.max() == pytest.approx(0.08)


@pytest.mark.parametrize("which", ["sun_mesh", "ring_mesh"])
def test_element_quality_bounded(which, request):
    g = request.getfixturevalue(which)
    assert g.order == 2 and g.triangles.shape[1] == 6
    assert g.min_angles().min() > 20.0
    assert g.info["min_sicn"] > 0.5
    assert np.all(g.corner_areas() > 0)  # counter-clockwise, none degenerate
    # curved (quadratic) elements keep a positive Jacobian at their quadrature points
    from skfem import Basis, ElementTriP2

    basis = Basis(g.to_skfem(), ElementTriP2(), intorder=4)
    assert np.all(basis.dx > 0)


def test_linear_order(sun):
    g = mesh_gear(sun, MeshSettings(level=0, order=1), cache_dir=None)
    assert g.triangles.shape[1] == 3 and g.n_nodes == g.n_vertices
    assert g.facet_groups["hub"].shape[1] == 2
    assert _loops(g.boundary_edges()) == 2


def test_refinement_increases_elements(sun, sun_mesh):
    g1 = mesh_gear(sun, MeshSettings(level=1), cache_dir=None)
    ratio = g1.n_elements / sun_mesh.n_elements
    assert 1.5 < ratio < 2.5  # h / sqrt(2): about twice the elements


def test_to_skfem_boundaries(sun_mesh):
    m = sun_mesh.to_skfem()
    assert type(m).__name__ == "MeshTri2"
    assert set(m.boundaries) == set(sun_mesh.facet_groups)
    assert len(m.boundaries["hub"]) == len(sun_mesh.facet_groups["hub"])
    # skfem vertices are the GearMesh's first nodes, in order
    assert np.array_equal(m.p[:, : sun_mesh.n_vertices], sun_mesh.points[: sun_mesh.n_vertices].T)
    bf = set(m.boundary_facets().tolist())
    assert set(m.boundaries["outline"].tolist()) <= bf


# ------------------------------------------------------------------ generic polygons
def test_mesh_polygon_groups_and_area():
    g = mesh_polygon([(0, 0), (2, 0), (2, 1), (0, 1)], h=0.2, order=1,
                     edge_names={"left": [3], "right": [1]})
    assert np.allclose(g.points[g.node_sets["left"], 0], 0.0)
    assert np.allclose(g.points[g.node_sets["right"], 0], 2.0)
    assert g.corner_areas().sum() == pytest.approx(2.0, rel=1e-12)
    a = mesh_polygon(Circle(0, 0, 1.0), [Circle(0.2, 0, 0.3)], h=0.1, order=2)
    assert _loops(a.boundary_edges()) == 2
    assert np.allclose(np.hypot(*(a.points[a.node_sets["hole0"]] - [0.2, 0]).T), 0.3)


def test_gmsh_callable_twice_and_finalized():
    assert not gmsh.isInitialized()
    for _ in range(2):
        g = mesh_polygon([(0, 0), (1, 0), (0, 1)], h=0.2, order=2)
        assert g.n_elements > 0
        assert not gmsh.isInitialized()


def test_gmsh_left_initialized_if_caller_owns_it():
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.model.add("user_model")
        mesh_polygon([(0, 0), (1, 0), (0, 1)], h=0.3, order=1)
        assert gmsh.isInitialized()
        assert "user_model" in gmsh.model.list()
    finally:
        gmsh.finalize()


# ------------------------------------------------------------------ cache
def test_cache_hit_does_not_call_gmsh(sun, tmp_path, monkeypatch):
    s = MeshSettings(level=0)
    g1 = mesh_gear(sun, s, cache_dir=tmp_path)
    assert g1.info["source"] == "gmsh"
    vtu, side = cache_paths(tmp_path, g1.key)
    assert vtu.exists() and side.exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temp files
    _no_gmsh(monkeypatch)
    g2 = mesh_gear(sun, s, cache_dir=tmp_path)
    assert g2.info["source"] == "cache" and g2.key == g1.key
    assert np.array_equal(g2.points, g1.points) and np.array_equal(g2.triangles, g1.triangles)
    assert set(g2.facet_groups) == set(g1.facet_groups)
    for k in g1.facet_groups:
        assert np.array_equal(g2.facet_groups[k], g1.facet_groups[k])


def test_cache_key_depends_on_geometry_and_settings(sun):
    k0 = cache_key(sun, MeshSettings(level=0))[0]
    assert cache_key(sun, MeshSettings(level=0))[0] == k0
    assert cache_key(sun, MeshSettings(level=1))[0] != k0
    assert cache_key(sun, MeshSettings(level=0, order=1))[0] != k0
    other = SpurGear(z=24, module=M, bore_diameter=0.018, face_width=0.02, name="sun")
    assert cache_key(other, MeshSettings(level=0))[0] != k0
    renamed = SpurGear(z=24, module=M, bore_diameter=0.02, face_width=0.02, name="planetX")
    assert cache_key(renamed, MeshSettings(level=0))[0] == k0  # the name is not geometry


@pytest.mark.parametrize("damage", ["truncate_vtu", "garbage_vtu", "garbage_json", "stale_key",
                                    "missing_json"])
def test_corrupt_or_stale_cache_is_rebuilt(sun, tmp_path, damage):
    s = MeshSettings(level=0)
    g1 = mesh_gear(sun, s, cache_dir=tmp_path)
    vtu, side = cache_paths(tmp_path, g1.key)
    if damage == "truncate_vtu":
        data = vtu.read_bytes()
        vtu.write_bytes(data[: len(data) // 2])
    elif damage == "garbage_vtu":
        vtu.write_bytes(b"not a mesh")
    elif damage == "garbage_json":
        side.write_text("{")
    elif damage == "stale_key":
        meta = json.loads(side.read_text())
        meta["key"]["format"] = -1
        side.write_text(json.dumps(meta))
    elif damage == "missing_json":
        side.unlink()
    g2 = mesh_gear(sun, s, cache_dir=tmp_path)
    assert g2.info["source"] == "gmsh"
    assert np.array_equal(g2.triangles, g1.triangles)
    g3 = mesh_gear(sun, s, cache_dir=tmp_path)  # the rebuilt entry is valid again
    assert g3.info["source"] == "cache"


# ------------------------------------------------------------------ input errors before gmsh
def test_bore_cutting_ligament_rejected_before_gmsh(monkeypatch):
    g = SpurGear(z=24, module=M, bore_diameter=0.042, face_width=0.02, name="sun")  # rf = 21.5 mm
    _no_gmsh(monkeypatch)
    with pytest.raises(GeometryError) as e:
        mesh_gear(g, MeshSettings(level=0), cache_dir=None)
    msg = str(e.value)
    assert "sun.bore_diameter = 0.042" in msg and "ligament" in msg and "0.041" in msg


def test_thin_ring_rim_rejected_before_gmsh(monkeypatch):
    g = SpurGear(z=66, module=M, internal=True, rim_diameter=0.140, face_width=0.02,
                 name="ring")  # rf = 68.5 mm, minimum rim 1 module = 2 mm -> 141 mm
    _no_gmsh(monkeypatch)
    with pytest.raises(GeometryError) as e:
        mesh_gear(g, MeshSettings(level=0), cache_dir=None)
    msg = str(e.value)
    assert "ring.rim_diameter = 0.14" in msg and "min_rim" in msg and "0.141" in msg
    # a thinner minimum accepts the same ring (rule is a parameter)
    assert MeshSettings(level=0, min_rim=0.5).min_rim == 0.5


def test_bad_settings_rejected_before_gmsh(sun, monkeypatch):
    _no_gmsh(monkeypatch)
    with pytest.raises(ConfigError, match="settings"):
        mesh_gear(sun, {"level": 9}, cache_dir=None)
    with pytest.raises(ConfigError, match="mesh.level = 9"):
        mesh_gear(sun, MeshSettings(level=9), cache_dir=None)
