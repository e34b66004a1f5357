"""Assembly of stiffness and mass (scikit-fem): symmetry, rigid bodies, mass, formulations."""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

from flexgear.errors import ConfigError
from flexgear.fe.elasticity import (
    assemble,
    clamped_modes,
    lame_2d,
    static_solve,
    strain_energy,
)
from flexgear.fe.loads import traction_load
from flexgear.gears.geometry import SpurGear
from flexgear.gears.material import Material
from flexgear.fe.meshing import Circle, MeshSettings, mesh_gear, mesh_polygon

STEEL = Material()


@pytest.fixture(scope="module")
def sun():
    return SpurGear(z=24, module=2e-3, bore_diameter=0.02, face_width=0.02, name="sun")


@pytest.fixture(scope="module", params=[1, 2], ids=["P1", "P2"])
def sun_model(request, sun):
    g = mesh_gear(sun, MeshSettings(level=0, order=request.param), cache_dir=None)
    return g, assemble(g, STEEL, sun.face_width)


def _outline_area(gear):
    x, y = gear.outline().points.T
    polygon = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    return polygon - np.pi * (gear.bore_diameter / 2) ** 2


def _norm(A):
    return spla.norm(A, 1)


def test_matrices_symmetric(sun_model):
    _, m = sun_model
    for A in (m.K, m.M):
        assert _norm(A - A.T) <= 1e-14 * _norm(A)
    # M positive definite: its smallest eigenvalue (shift-invert near 0) is positive
    lam = spla.eigsh(m.M, k=1, sigma=0, which="LM", return_eigenvectors=False)
    assert lam[0] > 0


def test_rigid_body_modes_have_zero_strain_energy(sun_model):
    _, m = sun_model
    R = m.rigid_body_modes()
    for j in range(3):
        r = R[:, j]
        rel = abs(r @ (m.K @ r)) / (_norm(m.K) * (r @ r))
        assert rel < 1e-12, (j, rel)
    # a genuine deformation has energy: u_x = x (uniform stretch)
    u = np.zeros(m.ndofs)
    u[m.node_dofs[:, 0]] = m.node_coords[:, 0]
    assert u @ (m.K @ u) / (_norm(m.K) * (u @ u)) > 1e-4


def test_free_body_has_three_zero_frequencies(sun_model):
    _, m = sun_model
    f, phi = clamped_modes(m, [], 4)
    assert np.all(f[:3] < 1e-4 * f[3])
    assert f[3] > 10e3  # first elastic in-plane mode of a 52 mm steel gear: tens of kHz


def test_total_mass_gear(sun, sun_model):
    g, m = sun_model
    expected = STEEL.rho * _outline_area(sun) * sun.face_width
    ex = np.zeros(m.ndofs)
    ey = np.zeros(m.ndofs)
    ex[m.node_dofs[:, 0]] = 1.0
    ey[m.node_dofs[:, 1]] = 1.0
    assert ex @ (m.M @ ey) == pytest.approx(0.0, abs=1e-14 * expected)
    assert ey @ (m.M @ ey) == pytest.approx(ex @ (m.M @ ex), rel=1e-12)
    if g.order == 2:  # curved elements: only the outline sampling limits the agreement
        assert m.mass() == pytest.approx(expected, rel=1e-4)
    else:  # straight chords of the bore add material (body h = 2 m): within 1 %
        assert m.mass() == pytest.approx(expected, rel=1e-2)


def test_total_mass_rectangle_and_annulus_exact():
    rect = mesh_polygon([(0, 0), (0.3, 0), (0.3, 0.1), (0, 0.1)], h=0.03, order=2)
    m = assemble(rect, STEEL, 0.02)
    assert m.mass() == pytest.approx(STEEL.rho * 0.03 * 0.02, rel=1e-12)
    ann = mesh_polygon(Circle(0, 0, 0.1), [Circle(0, 0, 0.06)], h=0.01, order=2)
    m = assemble(ann, STEEL, 0.02)
    assert m.mass() == pytest.approx(STEEL.rho * np.pi * (0.1**2 - 0.06**2) * 0.02, rel=1e-6)


def test_node_dof_map_matches_basis(sun_model):
    g, m = sun_model
    dl = m.basis.doflocs
    for c in (0, 1):
        assert np.allclose(dl[:, m.node_dofs[:, c]].T, g.points, rtol=0, atol=1e-15)
    assert np.array_equal(np.sort(m.node_dofs.ravel()), np.arange(m.ndofs))
    hub = m.group_dofs("hub")
    assert len(hub) == 2 * len(g.node_sets["hub"])


def test_skfem_mesh_input_gives_same_matrices(sun):
    g = mesh_gear(sun, MeshSettings(level=0), cache_dir=None)
    a = assemble(g, STEEL, 0.02)
    b = assemble(g.to_skfem(), STEEL, 0.02)
    assert _norm(a.K - b.K) <= 1e-14 * _norm(a.K) and _norm(a.M - b.M) == 0


def test_lame_plane_stress():
    lam, mu = lame_2d(STEEL, "plane_stress")
    E, nu = STEEL.E, STEEL.nu
    assert lam == pytest.approx(E * nu / (1 - nu**2), rel=1e-14)
    assert mu == pytest.approx(STEEL.G, rel=1e-14)
    lam3, _ = lame_2d(STEEL, "plane_strain")
    assert lam3 == pytest.approx(E * nu / ((1 + nu) * (1 - 2 * nu)), rel=1e-14)


@pytest.mark.parametrize("order", [1, 2])
def test_uniaxial_tension_patch(order):
    """Uniform tension: exact linear solution, reproduced to round-off.

    Plane stress: u_x(L) = s L / E, u_y(H) = -nu s H / E. Plane strain (free lateral edges):
    u_x(L) = s L (1 - nu^2) / E, i.e. stiffer.
    """
    Lx, Hy, s, t = 0.2, 0.05, 1e8, 0.01
    g = mesh_polygon([(0, 0), (Lx, 0), (Lx, Hy), (0, Hy)], h=0.02, order=order,
                     edge_names={"left": [3], "right": [1], "bottom": [0]})
    E, nu = STEEL.E, STEEL.nu
    res = {}
    for form in ("plane_stress", "plane_strain"):
        m = assemble(g, STEEL, t, form)
        fixed = np.concatenate([m.nodal_dofs(g.node_sets["left"])[:, 0],
                                m.nodal_dofs(g.node_sets["bottom"])[:, 1]])
        f = traction_load(m, "right", lambda x, y: (s + 0 * x, 0 * y))
        assert f.sum() == pytest.approx(s * Hy * t, rel=1e-12)
        u = m.nodal_field(static_solve(m, fixed, f))
        res[form] = u
    nu_eff = {"plane_stress": nu, "plane_strain": nu / (1 - nu)}
    E_eff = {"plane_stress": E, "plane_strain": E / (1 - nu**2)}
    for form, u in res.items():
        x, y = g.points.T
        assert np.allclose(u[:, 0], s * x / E_eff[form], rtol=0, atol=1e-9 * s * Lx / E)
        assert np.allclose(u[:, 1], -nu_eff[form] * s * y / E_eff[form], rtol=0,
                           atol=1e-9 * s * Lx / E)
    assert res["plane_strain"][:, 0].max() < res["plane_stress"][:, 0].max()


def test_plane_strain_stiffer_than_plane_stress_gear(sun):
    g = mesh_gear(sun, MeshSettings(level=0), cache_dir=None)
    ms = assemble(g, STEEL, sun.face_width, "plane_stress")
    me = assemble(g, STEEL, sun.face_width, "plane_strain")
    # tangential load on tooth 0's left flank, hub clamped: compliance f.u smaller in plane strain
    nodes = g.node_sets["tooth0_left"]
    f = np.zeros(ms.ndofs)
    f[ms.nodal_dofs(nodes)[:, 1]] = -100.0 / len(nodes)
    us = static_solve(ms, ms.group_dofs("hub"), f)
    ue = static_solve(me, me.group_dofs("hub"), f)
    cs, ce = f @ us, f @ ue
    assert 0 < ce < cs
    # C_strain - C_stress is positive semi-definite, and C_strain <= c C_stress with
    # c = (1 - nu) / ((1 + nu)(1 - 2 nu)) (equal-biaxial state), so 1 < cs/ce <= c
    nu = STEEL.nu
    assert 1.0 < cs / ce <= (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    assert strain_energy(ms, us) == pytest.approx(0.5 * cs, rel=1e-10)
    fs, _ = clamped_modes(ms, ms.group_dofs("hub"), 3)
    fe_, _ = clamped_modes(me, me.group_dofs("hub"), 3)
    assert np.all(fe_ > fs)


def test_clamped_modes_properties(sun):
    g = mesh_gear(sun, MeshSettings(level=0), cache_dir=None)
    m = assemble(g, STEEL, sun.face_width)
    fixed = m.group_dofs("hub")
    f, phi = clamped_modes(m, fixed, 6)
    assert np.all(np.diff(f) >= 0) and f[0] > 0
    assert np.all(phi[fixed] == 0)
    G = phi.T @ (m.M @ phi)
    assert np.allclose(G, np.eye(6), atol=1e-8)
    w2 = (2 * np.pi * f) ** 2
    free = np.setdiff1d(np.arange(m.ndofs), fixed)
    r = (m.K @ phi - (m.M @ phi) * w2)[free]
    assert np.linalg.norm(r) <= 1e-8 * np.linalg.norm((m.K @ phi)[free])
    # the two-fold symmetric pair (modes 2, 3) of an axisymmetric-like body
    assert f[2] / f[1] - 1 < 1e-3


def test_static_solve_prescribed_rigid_translation(sun):
    g = mesh_gear(sun, MeshSettings(level=0, order=1), cache_dir=None)
    m = assemble(g, STEEL, sun.face_width)
    fixed = m.group_dofs("hub")
    ux = np.zeros(m.ndofs)
    ux[m.node_dofs[:, 0]] = 1e-6
    u = static_solve(m, fixed, np.zeros(m.ndofs), u_fixed=ux[fixed])
    assert np.allclose(u, ux, rtol=0, atol=1e-15)


def test_bad_arguments(sun):
    g = mesh_polygon([(0, 0), (1, 0), (0, 1)], h=0.5, order=1)
    with pytest.raises(ConfigError, match="formulation"):
        assemble(g, STEEL, 0.01, "plane_strian")
    with pytest.raises(ConfigError, match="thickness"):
        assemble(g, STEEL, 0.0)
    m = assemble(g, STEEL, 0.01)
    with pytest.raises(ConfigError, match="n_modes"):
        clamped_modes(m, [], m.ndofs)
    with pytest.raises(ConfigError, match="f.shape"):
        static_solve(m, [0, 1], np.zeros(3))


def test_output_files_and_no_overwrite(sun, tmp_path):
    import meshio

    from flexgear.errors import ResultExistsError
    from flexgear.fe.output import clamped_gear_modes, write_mesh_outputs, write_mode_outputs

    s = MeshSettings(level=0)
    cache = tmp_path / "cache"
    vtu, png = write_mesh_outputs(sun, STEEL, s, tmp_path, cache_dir=cache)
    gm = mesh_gear(sun, s, cache_dir=cache)
    assert vtu.name == "sun_mesh.vtu" and png.stat().st_size > 10_000
    assert meshio.read(vtu).points.shape[0] == gm.n_nodes
    vtu, png, csv, md = write_mode_outputs(sun, STEEL, s, tmp_path, n_modes=6, cache_dir=cache)
    vt = meshio.read(vtu)
    assert sorted(vt.point_data) == [f"mode{i}" for i in range(1, 7)]
    _, _, freqs, _ = clamped_gear_modes(sun, STEEL, s, 6, cache_dir=cache)
    rows = csv.read_text().splitlines()
    assert rows[0] == "mode,frequency_Hz" and len(rows) == 7
    assert float(rows[1].split(",")[1]) == pytest.approx(freqs[0], rel=1e-9)
    assert "| 6 |" in md.read_text()
    before = png.stat().st_mtime_ns
    with pytest.raises(ResultExistsError, match="sun_modes"):
        write_mode_outputs(sun, STEEL, s, tmp_path, n_modes=6, cache_dir=cache)
    with pytest.raises(ResultExistsError, match="sun_mesh"):
        write_mesh_outputs(sun, STEEL, s, tmp_path, cache_dir=cache)
    assert png.stat().st_mtime_ns == before
    write_mode_outputs(sun, STEEL, s, tmp_path, n_modes=6, cache_dir=cache, overwrite=True)


GMSH_PIPE_SCRIPT = """
import os, sys, threading
from flexgear.fe.meshing import mesh_polygon

square = [(0, 0), (0.1, 0), (0.1, 0.1), (0, 0.1)]
if sys.argv[1] == "thread":
    t = threading.Thread(target=mesh_polygon, args=(square,), kwargs=dict(h=0.05, order=1))
    t.start()
    t.join()
else:
    mesh_polygon(square, h=0.05, order=1)
r, w = os.pipe()
os.close(r)
try:
    os.write(w, b"x")
except BrokenPipeError:
    print("BrokenPipeError")
"""


@pytest.mark.parametrize("where", ["main", "thread"])
def test_meshing_keeps_python_s_sigpipe_handling(where):
    """Gmsh's library resets SIGPIPE to its default action when it initialises: a process that
    had meshed then ended, without a word, on a write to a closed pipe (a batch driver on
    Ctrl-C, writing to a worker that had gone). After meshing, in the main thread or another,
    such a write raises BrokenPipeError, as in any Python program."""
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-c", GMSH_PIPE_SCRIPT, where], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0 and p.stdout.strip() == "BrokenPipeError", (p.returncode, p.stderr[-2000:])
