"""Flexible gears in the multi-body solver (issue 8): contact on compliant flanks.

Checks against independent references: the closed-form Hertz approach of
:mod:`flexgear.stiffness.hertz`, the full static FE compliance of
:func:`flexgear.stiffness.compliance.tooth_compliance`, the loaded-mesh transmission error of
:func:`flexgear.stiffness.loaded_mesh.loaded_mesh`, and the rigid model with the same contact law
in the limit of stiff gears. FE meshes at level 1 (coarse) keep the default suite fast; the
reductions are cached after the first run.
"""
import copy
import math
import tomllib

import numpy as np
import pytest

from flexgear.config import load_config, parse_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.model.bodies import pack_flex
from flexgear.dynamics.flexible.condensed import static_frequency
from flexgear.dynamics.contact.laws import HEALTHY_TERMS, HERTZ_COLUMNS, HERTZ_SERIES, LAW_HERTZ, hertz_line
from flexgear.dynamics.flexible.flank import flank_influence
from flexgear.dynamics.contact.solve import solve_contacts
from flexgear.dynamics.contact.search import MAX_CONTACTS
from flexgear.dynamics.flexible.reductions import flex_body, make_flexible, reduce_flexible_gears
from flexgear.dynamics.integrator.simulation import evaluate, simulate
from flexgear.errors import ConfigError
from flexgear.fe.meshing import MeshSettings, mesh_cache_dir
from flexgear.gears.geometry import GearPair
from flexgear.gears.material import Material
from flexgear.stiffness.compliance import tooth_compliance
from flexgear.stiffness.hertz import hertz_approach, plane_constants

SPUR = tomllib.loads(preset_path("spur_pair").read_text())


def spur(flexible=None, **drive):
    doc = copy.deepcopy(SPUR)
    if flexible is not None:
        doc["flexible"] = flexible
    doc["drive"].update(drive)
    return parse_config(doc)


COARSE = {"gears": ["pinion", "wheel"], "level": 1, "formulation": "plane_stress"}


@pytest.fixture(scope="module")
def coarse_reductions():
    return reduce_flexible_gears(spur(COARSE))


# ------------------------------------------------------------------------- contact law
def test_hertz_line_is_the_stiffness_hertz_approach():
    steel = Material(E=2.1e11, nu=0.3, rho=7850.0)
    E1, nu1 = plane_constants(steel, "plane_strain")
    args = (0.006, 0.02, 1 / (math.pi * E1), nu1, 0.002, 1 / (math.pi * E1), nu1, 0.0025, 0.5 * E1)
    for F in (10.0, 1e3, 1e4, 3e4):
        h, dh = hertz_line(F, *args)
        ref = hertz_approach(F, 0.006, 0.02, steel, steel, 0.002, 0.0025, "plane_strain")
        assert h == pytest.approx(ref, rel=1e-12)
        dF = 1e-4 * F
        slope = (hertz_approach(F + dF, 0.006, 0.02, steel, steel, 0.002, 0.0025)
                 - hertz_approach(F - dF, 0.006, 0.02, steel, steel, 0.002, 0.0025)) / (2 * dF)
        assert dh == pytest.approx(slope, rel=1e-6)


def _hertz_rows(n):
    steel = Material(E=2.1e11, nu=0.3, rho=7850.0)
    E1, nu1 = plane_constants(steel, "plane_strain")
    hp = np.zeros((MAX_CONTACTS, HERTZ_COLUMNS))
    hp[:, HERTZ_SERIES:] = HEALTHY_TERMS  # healthy teeth
    hp[:n, :9] = [0.006, 0.02, 1 / (math.pi * E1), nu1, 0.002, 1 / (math.pi * E1), nu1, 0.002, 0.5 * E1]
    return hp


def test_contact_solve_satisfies_the_compliant_law_and_complementarity():
    """delta_rigid = C F + h(F) on the active set; an open contact that the coupling pushes
    into its mate joins; one pulled away stays open with F = 0."""
    hp = _hertz_rows(3)
    C = np.zeros((MAX_CONTACTS, MAX_CONTACTS))
    C[:3, :3] = [[2.0e-9, -0.6e-9, 0.3e-9], [-0.6e-9, 2.5e-9, 0.0], [0.3e-9, 0.0, 2.0e-9]]
    dr = np.zeros(MAX_CONTACTS)
    dr[:3] = [30e-6, -2e-6, -1e-6]  # contact 1 is open by 2 um, contact 2 by 1 um
    F = np.zeros(MAX_CONTACTS)
    active = np.zeros(MAX_CONTACTS, bool)
    assert solve_contacts(C, dr, hp, F, active, 3) > 0
    assert active[:3].tolist() == [True, True, False]
    for i in (0, 1):
        h, _ = hertz_line(F[i], *hp[i, :9])
        assert dr[i] - C[i, :3] @ F[:3] - h == pytest.approx(0.0, abs=1e-14)
    assert F[2] == 0.0 and dr[2] - C[2, :3] @ F[:3] < 0.0
    assert F[1] > 0.0  # closed by the deflection of contact 0 (negative coupling)


# ------------------------------------------------------------------------- compliance tables
def test_flank_compliance_equals_the_full_static_fe(coarse_reductions):
    """The kernel's compliance (modes condensed + residual tables, linear in r) equals the full
    static FE solution with the near field removed, on the loaded tooth and its neighbour."""
    cfg = spur(COARSE)
    g, red = cfg.gears["pinion"], coarse_reductions["pinion"]
    table = pack_flex([flex_body(0, red)])
    r = np.linspace(red.tables.radius[0], red.tables.radius[-1], 7)
    tc = tooth_compliance(g, r, settings=MeshSettings(level=1), material=cfg.material,
                          formulation="plane_stress", cache_dir=mesh_cache_dir())
    for i, ri in enumerate(r):
        own = flank_influence(table, 0, 3, 1, ri, 3, 1, ri)
        assert own == pytest.approx(tc.bulk[i], rel=2e-3), ri
        for j in (0, 6):
            nb = flank_influence(table, 0, 4, 1, r[j], 3, 1, ri)
            assert nb == pytest.approx(tc.coupling[1][j, i], rel=2e-3)
            nb = flank_influence(table, 0, 2, 1, r[j], 3, 1, ri)
            assert nb == pytest.approx(tc.coupling[-1][j, i], rel=2e-3)
    # by symmetry the right flank of tooth k mirrors the left flank
    assert flank_influence(table, 0, 5, -1, r[3], 5, -1, r[3]) == pytest.approx(tc.bulk[3], rel=2e-3)


def test_kernel_self_compliance_at_the_table_radii_is_the_static_fe_exactly(coarse_reductions):
    """At the table radii of the tables' own tooth (no interpolation, no cyclic symmetry) the
    solver's self compliance of a flank point, its condensed modes plus the residual self table
    (packed, read by the kernel), equals the static FE compliance ``f^T K_ii^-1 f`` (own sparse
    solve, bore held) less the near field that the Hertz law carries, to round-off (1e-9), on
    both flanks: a residual or modal part scaled by any factor fails."""
    from flexgear.fe.elasticity import static_solve
    from flexgear.reduction.flank import flank_patch_loads

    cfg = spur(COARSE)
    g, red = cfg.gears["pinion"], coarse_reductions["pinion"]
    table = pack_flex([flex_body(0, red)])
    model, body, t = red.body.model, red.body, red.tables
    held = np.union1d(body.interface.boundary, body.interface.fixed)
    pick = np.arange(0, t.radius.size, 16)
    r = t.radius[pick]
    for side in (1, -1):
        F, *_ = flank_patch_loads(model, g, 0, side, r)
        full = np.einsum("ij,ij->j", F, static_solve(model, held, F)) - t.near_field[side][pick]
        own = np.array([flank_influence(table, 0, 0, side, rj, 0, side, rj) for rj in r])
        assert np.max(np.abs(own / full - 1)) < 1e-9, side


def test_kernel_compliance_between_any_two_flanks_is_the_full_static_fe(coarse_reductions):
    """``flank_influence`` between flank points of any two teeth and sides (not the same
    flank) equals the full static FE compliance ``f_out^T K_ii^-1 f_in`` (own sparse solve with
    the bore held), at the coupling tables' radii: the packing of the modes and of the residual
    tables for every tooth distance, their indexing in the kernel and the cyclic wrap of the
    tooth distance. Loaded tooth 0 is the tables' own tooth (round-off); tooth z - 2 uses them by
    cyclic symmetry (the mesh is not exactly symmetric). Halfway between coupling radii (every
    8th table radius) the linear interpolation of these smooth fields stays within 0.5 %."""
    from flexgear.fe.elasticity import static_solve
    from flexgear.reduction.flank import flank_patch_loads

    cfg = spur(COARSE)
    g, red = cfg.gears["pinion"], coarse_reductions["pinion"]
    table = pack_flex([flex_body(0, red)])
    model, body = red.body.model, red.body
    held = np.union1d(body.interface.boundary, body.interface.fixed)
    rc = red.tables.coupling_radius
    assert np.array_equal(rc, red.tables.radius[::red.tables.coupling_stride]) and rc.size == 17
    r_mid = 0.5 * (rc[[1, 8, 14]] + rc[[2, 9, 15]])
    z = g.z
    for r, k_in, tol in ((rc[[0, 5, 11, 15]], 0, 1e-9), (rc[[0, 5, 11, 15]], z - 2, 3e-3), (r_mid, 0, 5e-3)):
        F_in = {s: flank_patch_loads(model, g, k_in, s, r)[0] for s in (1, -1)}
        U = dict(zip((1, -1), np.split(static_solve(model, held, np.hstack([F_in[1], F_in[-1]])), 2, axis=1)))
        for d, s_out, s_in in ((z // 2, 1, -1), (z // 3, -1, -1), (0, -1, 1), (1, 1, -1), (-1, 1, 1),
                               (5, -1, 1)):
            k_out = (k_in + d) % z
            F_out, *_ = flank_patch_loads(model, g, k_out, s_out, r)
            full = F_out.T @ U[s_in]
            kernel = np.array([[flank_influence(table, 0, k_out, s_out, ro, k_in, s_in, ri) for ri in r]
                               for ro in r])
            assert np.abs(kernel - full).max() < tol * np.abs(full).max(), (k_in, d, s_out, s_in)


def test_modal_frame_columns_match_the_contact_geometry(coarse_reductions):
    """The FE tooth numbering and flank sides are those of the contact search: the frame
    columns of the modal table (the rigid normal of each flank) equal the contact normal."""
    cfg = spur(COARSE)
    m = build_model(cfg)
    q, v = m.initial_state()
    q[-1] -= 2e-5 / cfg.gears["wheel"].rb
    e = evaluate(m, q, v)
    w = e["work"]
    assert e["count"][0] >= 1
    for c in range(e["count"][0]):
        for gi, name in enumerate(("pinion", "wheel")):
            pose = w.bodies.pose[gi]
            red = coarse_reductions[name]
            tooth = (w.contacts.tooth_a if gi == 0 else w.contacts.tooth_b)[0, c]
            r = math.hypot(w.contacts.x[0, c] - pose[0], w.contacts.y[0, c] - pose[1])
            phi = math.atan2(w.contacts.y[0, c] - pose[1], w.contacts.x[0, c] - pose[0]) - pose[2]
            rel = (phi - tooth * 2 * math.pi / red.modal.shape[0] + math.pi) % (2 * math.pi) - math.pi
            side = 1 if rel >= 0 else -1
            if gi == 0:
                assert side == w.contacts.side_a[0, c]
            n = np.array([w.contacts.nx[0, c], w.contacts.ny[0, c]]) * (1 if gi == 0 else -1)
            th = pose[2]
            n_local = np.array([[math.cos(th), math.sin(th)], [-math.sin(th), math.cos(th)]]) @ n
            j = int(np.argmin(abs(red.tables.radius - r)))
            a = red.modal[tooth, (1, -1).index(side), j, :2]
            # 0.1 = 5.7 deg: the patch-weighted normal 0.1 mm below the tip (the nearest of 129
            # table radii) averages over the tip's edge (3.2 deg); the neighbouring tooth would be
            # 17 deg off (0.30), the other flank about 40 deg
            assert np.linalg.norm(a / np.linalg.norm(a) - n_local) < 0.1


# ------------------------------------------------------------------------- configuration
@pytest.mark.parametrize("block, match", [
    ({"gears": ["pinion", "gear3"]}, r"flexible.gears: unknown gear\(s\) 'gear3'"),
    ({"gears": "pinion"}, r"flexible.gears = 'pinion': must be a list"),
    ({"gears": ["pinion"], "level": 9}, r"flexible.level = 9: refinement level must lie in \[0, 5\]"),
    ({"gears": ["pinion"], "cutoff": 0.0}, r"flexible.cutoff = 0.0: must be > 0"),
    ({"gears": ["pinion"], "cutoff": -5e3}, r"flexible.cutoff = -5000.0: must be > 0"),
    ({"gears": ["pinion"], "formulation": "3d"}, r"flexible.formulation = '3d'"),
    ({"gears": ["pinion"], "stiff": 1}, r"unknown key 'flexible.stiff'"),
])
def test_bad_flexible_blocks_are_named(block, match):
    with pytest.raises(ConfigError, match=match):
        spur(block)


def test_flexible_ring_needs_a_support():
    doc = tomllib.loads(preset_path("mercury_1a").read_text())
    doc["flexible"] = {"gears": ["ring"], "ring_support": "none"}
    with pytest.raises(ConfigError, match=r"flexible.ring_support = 'none': must be one of 'rim', 'bolts'"):
        parse_config(doc)


def test_cutoff_below_the_first_mode_is_refused():
    cfg = spur({"gears": ["wheel"], "level": 0, "cutoff": 1000.0})
    with pytest.raises(ConfigError, match=r"\[flexible\] gear 'wheel': .*below the first"):
        reduce_flexible_gears(cfg)


def test_presets_select_the_compliant_law_for_flexible_meshes():
    for name in ("spur_pair_flexible", "mercury_1a_flexible"):
        cfg = load_config(name)
        assert cfg.flexible["formulation"] == "plane_strain" and cfg.flexible["condensation"] == "integrated"
        # no mode that the preset's step resolves is left to the static residual tables
        assert cfg.flexible["cutoff"] >= static_frequency(cfg.simulation["step"], cfg.simulation["hht_alpha"])
    rigid = build_model(load_config("spur_pair"))
    assert all(m.law != LAW_HERTZ for m in rigid.meshes) and rigid.pack().flex.body.size == 0


# ------------------------------------------------------------------------- rigid limit, statics
def _forces_at(model, offsets, rb):
    q, v = model.initial_state()
    out = []
    for d in offsets:
        qq = q.copy()
        qq[-1] -= d / rb
        out.append(evaluate(model, qq, v)["mesh"][0, 0])
    return np.array(out)


def test_stiff_flexible_gears_give_the_rigid_model_with_the_same_law():
    """Modulus x 1000 in the FE bodies (the Hertz law unchanged): the mesh force equals the
    rigid model's with the line-contact Hertz law, within 1 %."""
    # the modes scale with sqrt(E): the cutoff too (100 kHz x sqrt(1000))
    cfg = spur({"gears": ["pinion", "wheel"], "level": 0, "modulus_scale": 1000.0, "cutoff": 3.2e6})
    stiff = build_model(cfg)
    rigid_cfg = spur(None)
    rigid = make_flexible(build_model(rigid_cfg), cfg, reductions={}, hertz_meshes="all")
    rb = cfg.gears["wheel"].rb
    offsets = [2e-6, 5e-6, 1e-5, 1.5e-5]
    f_stiff, f_rigid = _forces_at(stiff, offsets, rb), _forces_at(rigid, offsets, rb)
    assert np.all(f_rigid > 100.0)
    assert np.max(np.abs(f_stiff / f_rigid - 1)) < 1e-2
    # the real modulus is much softer: the FE compliance carries most of the deflection
    soft = build_model(spur({"gears": ["pinion", "wheel"], "level": 0}))
    assert np.all(_forces_at(soft, offsets, rb) < 0.6 * f_rigid)


def test_slowly_turned_flexible_pair_reproduces_the_loaded_mesh_transmission_error():
    """Quasi-static: pinion at 0.5 Hz, 200 N m on the wheel. The transmission error (rigid
    approach of the loaded pairs) over one mesh cycle against ``loaded_mesh`` at the same load,
    mesh level and formulation, with contact outside the path of contact (``extended=True``:
    under load the approaching tooth's tip corner meets the mate's flank before the path and
    the leaving pair stays in contact after it, as the contact search on the real outlines
    finds): the single-pair and double-pair levels, the peak to peak and the mean within 3 %,
    the share of the cycle with two loaded pairs within the static grid's resolution (1/24),
    and the mean mesh stiffness c_gamma within 3 %."""
    from flexgear.stiffness.loaded_mesh import loaded_mesh

    cfg = spur(COARSE, speed_hz=0.5)
    m = build_model(cfg)
    g1, g2 = cfg.gears["pinion"], cfg.gears["wheel"]
    h, cycle = 1e-4, 1.0 / (g1.z * 0.5)
    t_end = 0.1 + 2 * cycle
    r = simulate(m, t_end, h, 1)
    t = (np.arange(r.records.pair_force.shape[0]) + 1) * h
    sel = t > t_end - cycle
    te = np.where(r.records.pair_force[sel, 0] > 0, r.records.pair_depth[sel, 0], -1.0).max(axis=1)
    F = 200.0 / g2.rb
    assert r.records.mesh_force[sel, 0].mean() == pytest.approx(F, rel=3e-3)
    lm = loaded_mesh(GearPair(g1, g2), F, settings=MeshSettings(level=1), material=cfg.material,
                     formulation="plane_stress", cache_dir=mesh_cache_dir(), extended=True)
    assert te.max() == pytest.approx(lm.te.max(), rel=0.03)
    assert te.min() == pytest.approx(lm.te.min(), rel=0.03)
    assert np.ptp(te) == pytest.approx(lm.te_peak_to_peak, rel=0.03)
    assert te.mean() == pytest.approx(lm.te.mean(), rel=0.03)
    two = np.mean((r.records.pair_force[sel, 0] > 0).sum(axis=1) >= 2)
    assert two == pytest.approx(np.mean(lm.n_pairs >= 2), abs=1.0 / len(lm.s))
    assert np.mean(F / te) / g1.face_width == pytest.approx(lm.c_gamma, rel=0.03)


# ------------------------------------------------------------------------- step convergence
def test_step_stays_converged_with_the_flank_compliance():
    """The flexible spur pair at the paper's speed under the load ramp: the mesh force with
    steps h = 50, 25, 12.5 us converges and at the presets' 25 us differs from the 12.5 us run
    by < 1 % of the mean force. HHT-alpha is second order for smooth forces; the tooth pairs
    entering and leaving contact (the Hertz law's compliance is unbounded at F -> 0) make the
    force non-smooth, so first order is what to expect: measured ratio of successive
    differences 0.505 (required < 0.6, i.e. order > 0.7)."""
    cfg = spur(COARSE)
    m = build_model(cfg)
    t_end, grid = 0.03, 5e-5
    runs = {}
    for h in (5e-5, 2.5e-5, 1.25e-5):
        r = simulate(m, t_end, h, 1)
        k = int(round(grid / h))
        runs[h] = r.records.mesh_force[k - 1::k, 0]
    sel = slice(int(0.01 / grid), None)
    F = {h: f[sel] for h, f in runs.items()}
    e1 = np.sqrt(np.mean((F[5e-5] - F[2.5e-5]) ** 2))
    e2 = np.sqrt(np.mean((F[2.5e-5] - F[1.25e-5]) ** 2))
    assert e2 < 0.6 * e1
    assert e2 < 1e-2 * np.mean(F[1.25e-5])


def test_a_flexible_run_after_a_rigid_one_calls_its_own_time_loop_before_the_forces(monkeypatch):
    """A process that ran a rigid model holds the rigid overload of the time loop; a flexible
    model's run must still call (compile or load) its own time loop before it evaluates the
    forces alone (``initial_acceleration``), so that its force kernels compile inside the time
    loop as in a fresh process, not alone first and then again for it."""
    import flexgear.dynamics.integrator.simulation as sim

    events = []

    class Spy:
        def __init__(self, name, fn):
            self.name, self.fn = name, fn

        def __call__(self, *args, **kw):
            events.append((self.name, args[4] if self.name == "integrate" else None))
            return self.fn(*args, **kw)

        def __getattr__(self, attr):  # the dispatcher's own attributes (its signatures)
            return getattr(self.fn, attr)

    monkeypatch.setattr(sim, "integrate", Spy("integrate", sim.integrate))
    monkeypatch.setattr(sim, "initial_acceleration", Spy("forces", sim.initial_acceleration))
    for cfg in (spur(None), spur(COARSE)):
        events.clear()
        simulate(build_model(cfg), 2e-4, 2.5e-5, 8)
        assert events[:2] == [("integrate", 0), ("forces", None)], events[:3]


def test_ring_and_planet_conventions_match_the_contact_geometry():
    """MERCURY 1-A with every gear flexible (mesh level 0): for every contact of the six meshes
    the flank the kernel looks up (tooth, side, radius; the ring's teeth and flanks included) is
    the one the contact acts on: its FE normal equals the contact normal (within 0.05; measured
    0.004 at levels 0 and 1; a neighbouring tooth's normal is 2 sin(pi / z) away, 0.095 on the
    ring, and the other flank's 2 cos(20 deg) = 1.9)."""
    from flexgear.dynamics.flexible.flank import flank_side

    doc = tomllib.loads(preset_path("mercury_1a").read_text())
    doc["flexible"] = {"gears": ["sun", "planet", "ring"], "level": 0}
    cfg = parse_config(doc)
    reds = reduce_flexible_gears(cfg)
    m = build_model(cfg)
    r = simulate(m, 0.06, 2.5e-5, 8)
    w = evaluate(m, r.q, r.v, t=0.06)["work"]
    P, C = w.bodies.pose, w.contacts
    seen = 0
    for k, mesh in enumerate(m.meshes):
        for c in range(C.count[k]):
            for bi, tooth in ((mesh.a, C.tooth_a[k, c]), (mesh.b, C.tooth_b[k, c])):
                red = reds[m.bodies[bi].attrs["gear"]]
                side, rad = flank_side(C.x[k, c], C.y[k, c], P[bi, 0], P[bi, 1], P[bi, 2], tooth, red.modal.shape[0])
                n = np.array([C.nx[k, c], C.ny[k, c]]) * (1 if bi == mesh.a else -1)
                th = P[bi, 2]
                n_local = np.array([[math.cos(th), math.sin(th)], [-math.sin(th), math.cos(th)]]) @ n
                a = red.modal[tooth, (1, -1).index(side), int(np.argmin(abs(red.tables.radius - rad))), :2]
                assert np.linalg.norm(a / np.linalg.norm(a) - n_local) < 0.05, (mesh.name, bi)
                seen += 1
    assert seen >= 12


# ------------------------------------------------------------------------- frame inertia
def test_condensed_modes_carry_the_static_fe_deflection_under_the_gears_own_inertia_load(coarse_reductions):
    """The flank displacement per unit acceleration of the body frame that the condensed modes
    give (``FlexBody.acceleration_shape``, sum_i A_i S_i / omega_i^2 over the modes below the
    100 kHz cutoff) equals the static FE solution under the d'Alembert load of that
    acceleration, ``K_ii u = -M_ir a`` with the bore held (a full sparse solve, no modes), read
    through the reduction's flank patch, within 2 % of the largest component for x, y and
    theta (measured 0.2 % at a quarter of the flank to 1.3 % at three quarters, level 1: the
    tooth's own inertia load near the tip needs modes above the cutoff)."""
    from conftest import inertia_load_deflection

    red = coarse_reductions["pinion"]
    fe_deflection = inertia_load_deflection(red)
    fb = flex_body(0, red)
    T = fb.acceleration_shape
    assert T.shape == fb.shape.shape[:3] + (3,)
    r = red.tables.radius
    J = r.size
    for tooth, side in ((0, 1), (0, -1), (7, 1), (13, -1)):
        si = 0 if side > 0 else 1
        for j in (J // 4, J // 2, 3 * J // 4):
            fe = fe_deflection(tooth, side, r[j])
            model = -T[tooth, si, j]  # displacement under unit acceleration
            scale = np.abs(fe).max()
            assert scale > 0.0
            assert np.abs(model - fe).max() < 0.02 * scale, (tooth, side, j, model, fe)
