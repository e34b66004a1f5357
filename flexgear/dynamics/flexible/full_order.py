"""Full-order reference of a flexible spur pair: both gears as unreduced FE bodies.

Verifies the reduced model of :mod:`flexgear.dynamics.flexible.reductions`: the same spur pair,
contact and integrator, with every FE dof of both gears a coordinate (floating frame about the
bore's rotation, no modes, condensation or tables), in a Python time loop with one sparse solve
per gear and step. Scope: spur meshes between external gears on fixed revolute joints, both
gears flexible. Equations: the theory page *Compliant contact and condensation*, section *The
full-order reference*.
"""
from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ...errors import ConfigError
from ...reduction.flank import SIDES, flank_arc_range, flank_group
from ...stiffness.compliance import DEFAULT_SPREAD, MIN_SPREAD
from ...stiffness.hertz import halfplane_compliance
from ..model.bodies import ANGLE_FREE, ANGLE_PRESCRIBED, REVOLUTE, Model
from ..contact.laws import HEALTHY_TERMS, HERTZ_COLUMNS, LAW_HERTZ
from .flank import flank_side
from ..contact.solve import solve_contacts
from ..contact.search import MAX_CONTACTS, MeshPair, mesh_contacts
from ..contact.laws import step
from ..integrator.hht import hht_coefficients
from ..integrator.simulation import COARSE_STRIDE

#: Radii per flank side of the tabulated near field (linear interpolation; smooth in r).
NEAR_FIELD_POINTS = 401


class FlankPatches:
    """Flank patch loads of one FE gear model at any contact radius, from stored quadrature.

        Per flank (tooth k, side s) the facet quadrature of group ``tooth{k}_left/right`` is kept as
        ``B`` (flank dofs x points, ``-L dx_q n_q . phi_i(x_q)``) with the arc lengths ``S_q``, so a
        unit-resultant patch is ``f = B p / (L sum_q dx_q p_q)`` (as
        :func:`flexgear.fe.loads.flank_patch_load` with ``intorder = 8``).

        Parameters
        ----------
        model : FEModel
        gear : SpurGear
        spread, min_spread : float
            Patch half-width and its minimum at the flank's end [modules] (the reduction's).
    """

    def __init__(self, model, gear, spread: float = DEFAULT_SPREAD, min_spread: float = MIN_SPREAD):
        from skfem import FacetBasis

        self.gear = gear
        self.thickness = float(model.thickness)
        self.w_max = spread * gear.module
        self.w_min = min_spread * gear.module
        self.range = {s: flank_arc_range(model, gear, s) for s in SIDES}
        self.dofs = {}
        self.B = {}
        self.S = {}
        self.dx = {}
        rb = gear.rb
        for k in range(gear.z):
            for s in SIDES:
                name = flank_group(gear, k, s)
                if name not in model.mesh.boundaries:
                    raise ConfigError(f"mesh of {gear.name} has no boundary {name!r}")
                fb = FacetBasis(model.mesh, model.basis.elem, facets=model.mesh.boundaries[name], intorder=8)
                x = np.asarray(fb.global_coordinates())  # (2, nf, nq)
                dx = np.asarray(fb.dx)  # (nf, nq)
                nrm = np.asarray(fb.normals)  # (2, nf, nq)
                edofs = np.asarray(fb.element_dofs)  # (nbfun, nf)
                nf, nq = dx.shape
                rows, vals = [], []
                for i in range(edofs.shape[0]):
                    phi = np.asarray(fb.basis[i][0])  # (2, nf, nq)
                    v = -self.thickness * dx * (nrm[0] * phi[0] + nrm[1] * phi[1])
                    rows.append(np.repeat(edofs[i][:, None], nq, axis=1))
                    vals.append(v)
                rows = np.concatenate([r.ravel() for r in rows])
                cols = np.tile(np.arange(nf * nq), edofs.shape[0])
                vals = np.concatenate([v.ravel() for v in vals])
                dofs, local = np.unique(rows, return_inverse=True)
                Bm = np.zeros((dofs.size, nf * nq))
                np.add.at(Bm, (local, cols), vals)
                # the element dofs off the facet have zero trace there: keep the flank's own
                keep = np.abs(Bm).max(axis=1) > 1e-12 * np.abs(Bm).max()
                dofs, Bm = dofs[keep], Bm[keep]
                self.dofs[k, s] = dofs
                self.B[k, s] = Bm
                self.S[k, s] = ((x[0] ** 2 + x[1] ** 2 - rb * rb) / (2.0 * rb)).ravel()
                self.dx[k, s] = dx.ravel()

    def arc(self, r: float) -> float:
        """Involute arc length S(r) = (r^2 - r_b^2) / (2 r_b) [m]."""
        rb = self.gear.rb
        return (r * r - rb * rb) / (2.0 * rb)

    def width(self, side: int, Sc: float) -> tuple[float, float, float]:
        """Half-width w [m] and clipped support (lo, hi) [w] of the patch centred at Sc."""
        S_lo, S_hi = self.range[side]
        w = min(self.w_max, max(self.w_min, min(Sc - S_lo, S_hi - Sc)))
        return w, max(-1.0, (S_lo - Sc) / w), min(1.0, (S_hi - Sc) / w)

    def load(self, tooth: int, side: int, r: float) -> np.ndarray:
        """Patch load on the flank dofs ``self.dofs[tooth, side]`` [N per N] at radius r [m]."""
        key = (tooth % self.gear.z, side)
        Sc = self.arc(r)
        w, _, _ = self.width(side, Sc)
        xi = (self.S[key] - Sc) / w
        p = np.clip(1.0 - xi * xi, 0.0, None) ** 2
        tot = self.thickness * float(self.dx[key] @ p)
        if not tot > 0:
            raise ConfigError(f"{self.gear.name}: the patch at r = {r*1e3:.6g} mm has no support on flank "
                              f"{flank_group(self.gear, tooth, side)}")
        return self.B[key] @ p / tot


@dataclass
class FullOrderGear:
    """One gear as a full FE body (see the module docstring).

    Attributes
    ----------
    body : int
        Index of the multi-body model's body.
    inner : ndarray
        FE dofs that are coordinates (all but the bore's).
    K, M : sparse
        Stiffness and mass on ``inner``.
    coupling : ndarray
        ``m = (M r_perp)[inner]`` [kg m]: inertia coupling of the rotation with the dofs.
    inertia_fe : float
        ``r_perp^T M r_perp`` [kg m^2] of the FE body (for comparison with the model's).
    patches : FlankPatches
    solve : callable
        ``S^-1`` (sparse LU of ``S = M + (1 + alpha) beta h^2 K``).
    flank_dofs : ndarray
        Positions in ``inner`` of the stacked flank dofs ``E`` (all flanks, tooth by tooth).
    flank_index : dict
        (tooth, side) -> positions of that flank's dofs in ``flank_dofs`` (contiguous).
    response : ndarray (ndofs, n_flank)
        ``S^-1 E``; ``green = E^T S^-1 E`` (symmetrised) [1/kg].
    z_coupling : ndarray
        ``S^-1 m`` (on ``inner``); ``z_flank = E^T z``, ``mz = m^T z`` [kg m^2].
    near : dict
        side -> (radii [m], near-field compliance [m/N]) table.
    r_range : (float, float)
        Radius range of the reduction's flank tables [m] (contact radii are clamped to it).
    """

    body: int
    name: str
    inner: np.ndarray
    K: object
    M: object
    coupling: np.ndarray
    inertia_fe: float
    patches: FlankPatches
    solve: object = None
    flank_dofs: np.ndarray = None
    flank_index: dict = field(default_factory=dict)
    green: np.ndarray = None
    response: np.ndarray = None
    z_coupling: np.ndarray = None
    z_flank: np.ndarray = None
    mz: float = 0.0
    near: dict = field(default_factory=dict)
    r_range: tuple = (0.0, 0.0)
    info: dict = field(default_factory=dict)

    @property
    def ndofs(self) -> int:
        return int(self.inner.size)


def full_order_gear(body: int, red, h: float, alpha: float, depth: float) -> FullOrderGear:
    """A gear's full-order data from its reduction's FE model and interface (same mesh, order,
    formulation and support as the reduction), factorised for step h and HHT ``alpha``."""
    import scipy.sparse.linalg as sla

    t0 = time.perf_counter()
    fm = red.body.model
    gear = red.gear
    itf = red.body.interface
    held = np.union1d(itf.boundary, itf.fixed)
    inner = np.setdiff1d(np.arange(fm.ndofs), held)
    pos = np.full(fm.ndofs, -1, np.int64)
    pos[inner] = np.arange(inner.size)
    if np.hypot(*itf.centre) > 1e-12:
        raise ConfigError(f"{gear.name}: the interface frame must sit at the gear axis (the FE origin)")
    rot = fm.rigid_body_modes()[:, 2]  # rigid rotation field (-y, x) about the axis
    Mfull = fm.M.tocsr()
    Mr = Mfull @ rot
    inertia_fe = float(rot @ Mr)
    K = fm.K.tocsr()[inner][:, inner].tocsc()
    M = Mfull[inner][:, inner].tocsc()
    beta, _ = hht_coefficients(alpha)
    S = (M + (1.0 + alpha) * beta * h * h * K).tocsc()
    lu = sla.splu(S, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    patches = FlankPatches(fm, gear)
    t = red.tables
    for s in SIDES:  # the reduction's patch widths (same spread settings)
        w = [patches.width(s, patches.arc(r))[0] for r in t.radius]
        if not np.allclose(w, t.spread[s], rtol=1e-9, atol=0.0):
            raise ConfigError(f"{gear.name}: the reduction's flank patches use other widths than the defaults "
                              f"(spread {np.asarray(t.spread[s]) / gear.module} modules)")
    # stacked flank dofs
    flank_cols, index, n = [], {}, 0
    for k in range(gear.z):
        for s in SIDES:
            dd = pos[patches.dofs[k, s]]
            if np.any(dd < 0):
                raise ConfigError(f"{gear.name}: flank {flank_group(gear, k, s)} touches the bore")
            index[k, s] = np.arange(n, n + dd.size)
            flank_cols.append(dd)
            n += dd.size
    fdofs = np.concatenate(flank_cols)
    W = np.empty((inner.size, n), order="F")  # S^-1 E: the response to a unit load on each flank dof
    e = np.zeros(inner.size)
    for c in range(n):  # one column at a time: SuperLU is slow on a C-ordered block of right-hand sides
        e[fdofs[c]] = 1.0
        W[:, c] = lu.solve(e)
        e[fdofs[c]] = 0.0
    green = W[fdofs]
    green = 0.5 * (green + green.T)
    m = Mr[inner]
    z = lu.solve(m)
    # near field of the patch (the reduction's halfplane_compliance), tabulated in r
    r_lo, r_hi = float(t.radius[0]), float(t.radius[-1])
    near = {}
    rr = np.linspace(r_lo, r_hi, NEAR_FIELD_POINTS)
    for s in SIDES:
        vals = []
        for r in rr:
            w, lo, hi = patches.width(s, patches.arc(r))
            vals.append(halfplane_compliance(w, depth, fm.material, fm.thickness, fm.formulation, lo, hi))
        near[s] = (rr, np.array(vals))
    return FullOrderGear(body=body, name=gear.name, inner=inner, K=K, M=M, coupling=m, inertia_fe=inertia_fe,
                         patches=patches, solve=lu.solve, flank_dofs=fdofs, flank_index=index, green=green, response=W,
                         z_coupling=z, z_flank=z[fdofs], mz=float(m @ z), near=near, r_range=(r_lo, r_hi),
                         info={"ndofs": int(inner.size), "flank_dofs": int(n),
                               "factor_nnz": int(lu.L.nnz + lu.U.nnz),
                               "setup_seconds": time.perf_counter() - t0})


def prescribed_angle(body, t: float) -> tuple[float, float, float]:
    """Angle [rad], speed [rad/s] and acceleration [rad/s^2] of a prescribed rotation at t
    (the kernel's piecewise-linear speed profile, held constant outside its table)."""
    p = body.speed
    tt, vv = np.asarray(p.t, float), np.asarray(p.v, float)
    if tt.size == 1:
        return body.theta0 + vv[0] * t, vv[0], 0.0
    ci = np.concatenate([[0.0], np.cumsum(0.5 * (vv[1:] + vv[:-1]) * np.diff(tt))])
    if t <= tt[0]:
        return body.theta0 + vv[0] * t, vv[0], 0.0
    if t >= tt[-1]:
        return body.theta0 + vv[0] * tt[0] + ci[-1] + vv[-1] * (t - tt[-1]), vv[-1], 0.0
    k = int(np.searchsorted(tt, t) - 1)
    s = (vv[k + 1] - vv[k]) / (tt[k + 1] - tt[k])
    v = vv[k] + s * (t - tt[k])
    return body.theta0 + vv[0] * tt[0] + ci[k] + 0.5 * (vv[k] + v) * (t - tt[k]), v, s


def applied_torque(body, t: float) -> float:
    """The body's applied torque at t with its STEP ramp [N m] (the kernel's applied_torques)."""
    if body.torque is None:
        return 0.0
    T = float(body.torque(t))
    if body.torque_ramp > 0.0:
        T *= step(t, 0.0, 0.0, body.torque_ramp, 1.0)
    return T


@dataclass
class FullOrderRun:
    """Records of :func:`simulate_full_order` on the integration grid (times (k + 1) h).

    ``mesh_force`` (nsteps,): sum of the tooth-pair normal forces [N] (the solver's
    ``mesh_force``); ``elastic_force`` (nsteps,): its elastic part; ``theta``, ``omega``
    (nsteps, n_bodies); ``contacts`` (nsteps,): active contacts.
    """

    h: float
    nsteps: int
    mesh_force: np.ndarray
    elastic_force: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    contacts: np.ndarray
    wall: float
    setup_seconds: float
    newton: int
    solves: int
    gears: list
    info: dict = field(default_factory=dict)


class FullOrderModel:
    """The multi-body spur model with both gears as full FE bodies (see the module docstring).

    Parameters
    ----------
    model : Model
        The flexible multi-body model (:func:`flexgear.dynamics.model.assembly.build_model` of a
        configuration with both gears in ``[flexible]``): bodies, mesh, contact tables and
        Hertz constants are taken from it.
    reductions : dict
        Gear name -> GearReduction (:func:`flexgear.dynamics.flexible.reductions.reduce_flexible_gears`):
        its FE model, interface and flank-table settings.
    h, alpha : float
        Step [s] and HHT alpha.
    """

    def __init__(self, model: Model, reductions: dict, h: float, alpha: float, tol: float = 1e-10,
                 max_newton: int = 12):
        t0 = time.perf_counter()
        if len(model.meshes) != 1:
            raise ConfigError(f"full-order reference: one mesh expected (a spur pair), got {len(model.meshes)}")
        mesh = model.meshes[0]
        if mesh.internal or mesh.law != LAW_HERTZ:
            raise ConfigError("full-order reference: an external mesh with the compliant Hertz law is expected")
        for b in model.bodies:
            if b.joint != REVOLUTE or b.parent != -1 or b.rotation not in (ANGLE_FREE, ANGLE_PRESCRIBED):
                raise ConfigError(f"full-order reference: body {b.name!r} must turn on a fixed revolute joint "
                                  "(free or prescribed rotation)")
        self.model = model
        self.mesh = mesh
        self.h, self.alpha, self.tol, self.max_newton = float(h), float(alpha), float(tol), int(max_newton)
        self.beta, self.gamma = hht_coefficients(self.alpha)
        for b in model.bodies:
            if b.attrs.get("gear") not in reductions:
                raise ConfigError(f"full-order reference: gear {b.attrs.get('gear')!r} (body {b.name!r}) must be "
                                  "flexible (both gears in [flexible] gears)")
        self.gears = []
        for i, b in enumerate(model.bodies):
            gname = b.attrs.get("gear")
            depth = mesh.hertz["depth_a"] if i == mesh.a else mesh.hertz["depth_b"]
            self.gears.append(full_order_gear(i, reductions[gname], self.h, self.alpha, depth))
        self.free = [i for i, b in enumerate(model.bodies) if b.rotation == ANGLE_FREE]
        self.setup_seconds = time.perf_counter() - t0
        hz = mesh.hertz
        self._hertz = (hz["face_width"], hz["hertz_a"], hz["nu_a"], hz["depth_a"], hz["hertz_b"], hz["nu_b"],
                       hz["depth_b"], hz["e_star"], hz["rb_a"], hz["rb_b"])
        self._out_f = np.zeros((MAX_CONTACTS, 5))
        self._out_i = np.zeros((MAX_CONTACTS, 3), np.int64)
        self._cache = np.zeros((4 * MAX_CONTACTS, 4), np.int64)
        self._ncache = np.zeros(1, np.int64)
        # compile (or load) the kernels used per step now, not inside the timed loop
        pose = np.array([[*b.pin, b.theta0] for b in model.bodies], float)
        self.contacts(pose, np.zeros_like(pose))
        solve_contacts(np.eye(MAX_CONTACTS), np.zeros(MAX_CONTACTS), np.ones((MAX_CONTACTS, HERTZ_COLUMNS)),
                       np.zeros(MAX_CONTACTS), np.zeros(MAX_CONTACTS, np.bool_), 1)
        step(0.5, 0.0, 0.0, 1.0, 1.0)
        self.setup_seconds = time.perf_counter() - t0

    # -- contacts -------------------------------------------------------------------------------
    def contacts(self, pose, vel):
        """Contacts of the mesh in poses ``pose`` (nb, 3): list of dicts with the rigid overlap,
        rate, moment arms, and per gear (tooth, side, radius)."""
        mesh, tables = self.mesh, self.model.tables
        a, b = mesh.a, mesh.b
        ga, gb = self.model.bodies[a].gear, self.model.bodies[b].gear
        pair = MeshPair(ga, gb, False, mesh.ncand_a, mesh.ncand_b, COARSE_STRIDE, mesh.gap)
        cnt = mesh_contacts(pose[a], pose[b], pair, tables, self._out_f, self._out_i, False, self._cache, self._ncache)
        za, zb = tables.gear_z[ga], tables.gear_z[gb]
        out = []
        for c in range(cnt):
            dr, px, py, nx, ny = self._out_f[c]
            ta, tb, sa = (int(v) for v in self._out_i[c])
            _, ra = flank_side(px, py, pose[a, 0], pose[a, 1], pose[a, 2], ta, za)
            sb, rb_ = flank_side(px, py, pose[b, 0], pose[b, 1], pose[b, 2], tb, zb)
            vax = vel[a, 0] - vel[a, 2] * (py - pose[a, 1])
            vay = vel[a, 1] + vel[a, 2] * (px - pose[a, 0])
            vbx = vel[b, 0] - vel[b, 2] * (py - pose[b, 1])
            vby = vel[b, 1] + vel[b, 2] * (px - pose[b, 0])
            ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
            mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
            out.append({"depth": float(dr), "rate": nx * (vbx - vax) + ny * (vby - vay), "ma": ma, "mb": mb,
                        "flank": {a: (ta, int(sa), float(ra)), b: (tb, int(sb), float(rb_))}})
        return out

    def hertz_row(self, ra: float, rb_: float) -> np.ndarray:
        """Hertz parameters of a contact at radii ra, rb (the kernel's compliant_mesh_forces)."""
        L, ka, na, da, kb, nb_, db, es, rba, rbb = self._hertz
        ta = math.sqrt(max(ra ** 2 - rba ** 2, (0.05 * rba) ** 2))
        tb = math.sqrt(max(rb_ ** 2 - rbb ** 2, (0.05 * rbb) ** 2))
        R = ta * tb / (ta + tb)
        return np.array([R, L, ka, na, da, kb, nb_, db, es, *HEALTHY_TERMS])

    def flank_load(self, g: FullOrderGear, tooth: int, side: int, r: float):
        """(stacked flank positions, load on them, near-field compliance) of a contact."""
        r = min(max(r, g.r_range[0]), g.r_range[1])  # the tables' clamp
        f = g.patches.load(tooth, side, r)
        rr, cn = g.near[side]
        return g.flank_index[tooth % g.patches.gear.z, side], f, float(np.interp(r, rr, cn))

    def _bracketed_root(self, evaluate, acc0: float, to_length: float, tn: float) -> np.ndarray:
        """Root of the scalar rigid residual R(acc) of one free rotation by Brent's method,
        bracketed by doubling steps from ``acc0``, to a position tolerance ``self.tol``
        (``to_length`` converts an acceleration to a flank position change [m s^2/rad])."""
        from scipy.optimize import brentq

        def f(x):
            return float(evaluate(np.array([x]))[0][0])

        f0 = f(acc0)
        step_ = max(abs(acc0), 1.0) * 1e-3
        lo = hi = acc0
        flo = fhi = f0
        for _ in range(200):
            if flo * fhi < 0.0 or f0 == 0.0:
                break
            step_ *= 2.0
            lo, hi = acc0 - step_, acc0 + step_
            flo, fhi = f(lo), f(hi)
        else:
            raise ConfigError(f"full-order reference: no root of the rotation's residual found at t = {tn:.6f} s")
        if f0 == 0.0:
            return np.array([acc0])
        return np.array([brentq(f, lo, hi, xtol=self.tol / to_length, rtol=4 * np.finfo(float).eps)])

    # -- time loop ------------------------------------------------------------------------------
    def simulate(self, t_end: float, progress=None) -> FullOrderRun:
        """Integrate from rest (the model's initial state, undeformed gears) to ``t_end``."""
        model, h, al, be, ga_ = self.model, self.h, self.alpha, self.beta, self.gamma
        nb_ = len(model.bodies)
        nsteps = int(round(t_end / h))
        gears = self.gears
        free = self.free
        nf = len(free)
        scale = model.length_scale
        # state
        th = np.array([b.theta0 for b in model.bodies], float)
        om = np.array([b.omega0 for b in model.bodies], float)
        ac = np.zeros(nb_)
        u = [np.zeros(g.ndofs) for g in gears]
        v = [np.zeros(g.ndofs) for g in gears]
        a = [np.zeros(g.ndofs) for g in gears]
        rhs_n = [np.zeros(g.ndofs) for g in gears]
        Q_n = np.array([applied_torque(model.bodies[i], 0.0) for i in free])
        coeff = be * h * h
        rec = {k: np.zeros(nsteps) for k in ("F", "Fe", "nc")}
        rec_th = np.zeros((nsteps, nb_))
        rec_om = np.zeros((nsteps, nb_))
        newton = solves = 0
        stalled = [0]  # contact solves that ended without converging
        fallbacks = [0]  # steps solved by bracketing after Newton failed
        mesh = self.mesh
        wall0 = time.perf_counter()
        for k in range(nsteps):
            tn = (k + 1) * h
            uh = [u[i] + h * v[i] + h * h * (0.5 - be) * a[i] for i in range(len(gears))]
            vh = [v[i] + h * (1.0 - ga_) * a[i] for i in range(len(gears))]
            thh = th + h * om + h * h * (0.5 - be) * ac
            omh = om + h * (1.0 - ga_) * ac
            presc = {}
            for i, b in enumerate(model.bodies):
                if b.rotation == ANGLE_PRESCRIBED:
                    presc[i] = prescribed_angle(b, tn)
            bvec, uF, mb_ = [], [], []
            for gi, g in enumerate(gears):
                bb = -(1.0 + al) * (g.K @ uh[gi]) - al * rhs_n[gi]
                if g.body in presc:
                    bb = bb - g.coupling * presc[g.body][2]
                bvec.append(bb)
                mb_.append(float(g.z_coupling @ bb))  # m^T S^-1 b
                uF.append(uh[gi][g.flank_dofs])
            fy = {}  # (gear, flank) -> E_flank^T S^-1 b, on demand

            def flank_y(gi, idx):
                key = (gi, int(idx[0]))
                if key not in fy:
                    fy[key] = gears[gi].response[:, idx[0]:idx[-1] + 1].T @ bvec[gi]
                return fy[key]
            T_app = np.array([applied_torque(model.bodies[i], tn) for i in free])

            def evaluate(acc_free):
                """Residual of the rigid rows and the contact solution for free accelerations."""
                pose = np.zeros((nb_, 3))
                vel = np.zeros((nb_, 3))
                acc_all = np.zeros(nb_)
                for i, b in enumerate(model.bodies):
                    pose[i, 0], pose[i, 1] = b.pin
                    if i in presc:
                        pose[i, 2], vel[i, 2], acc_all[i] = presc[i]
                for j, i in enumerate(free):
                    pose[i, 2] = thh[i] + coeff * acc_free[j]
                    vel[i, 2] = omh[i] + ga_ * h * acc_free[j]
                    acc_all[i] = acc_free[j]
                cs = self.contacts(pose, vel)
                n = len(cs)
                C = np.zeros((MAX_CONTACTS, MAX_CONTACTS))
                dr = np.zeros(MAX_CONTACTS)
                hp = np.zeros((MAX_CONTACTS, HERTZ_COLUMNS))
                loads = []
                for c, con in enumerate(cs):
                    dr[c] = con["depth"]
                    fa = con["flank"][mesh.a]
                    fb = con["flank"][mesh.b]
                    hp[c] = self.hertz_row(fa[2], fb[2])
                    per = []
                    for gi, g in enumerate(gears):
                        tooth, side, r = con["flank"][g.body]
                        idx, f, cn = self.flank_load(g, tooth, side, r)
                        per.append((idx, f))
                        # known part of the elastic approach: predictor + S^-1 b, rotation coupling
                        # (a prescribed rotation's inertia coupling is already in b)
                        acc_g = acc_all[g.body] if g.body in free else 0.0
                        dr[c] -= f @ uF[gi][idx] + coeff * (f @ flank_y(gi, idx) - (f @ g.z_flank[idx]) * acc_g)
                        C[c, c] -= cn
                    loads.append(per)
                for c in range(n):
                    for d in range(n):
                        s = 0.0
                        for gi, g in enumerate(gears):
                            ic, fc = loads[c][gi]
                            idd, fd = loads[d][gi]
                            s += fc @ g.green[np.ix_(ic, idd)] @ fd
                        C[c, d] += (1.0 + al) * coeff * s
                Fe = np.zeros(MAX_CONTACTS)
                active = np.zeros(MAX_CONTACTS, np.bool_)
                if n:
                    # a contact that joins and drops in turn at a vanishing force (a back flank
                    # pushed within 0.1 um of its mate) ends the active-set rounds: the forces
                    # are used as they are, as the reduced model's kernel does; counted
                    if solve_contacts(C, dr, hp, Fe, active, n) < 0:
                        stalled[0] += 1
                Ftot = np.zeros(n)
                for c, con in enumerate(cs):
                    if active[c]:
                        sd = step(con["depth"], 0.0, 0.0, mesh.d, mesh.C)
                        Ftot[c] = max(Fe[c] + sd * con["rate"], 0.0)
                Q = T_app.copy()
                R = np.zeros(nf)
                for j, i in enumerate(free):
                    for c, con in enumerate(cs):
                        if i == mesh.a:
                            Q[j] += Ftot[c] * con["ma"]
                        if i == mesh.b:
                            Q[j] -= Ftot[c] * con["mb"]
                    g = gears[[gg.body for gg in gears].index(i)]
                    gi = gears.index(g)
                    mz_f = sum((g.z_flank[loads[c][gi][0]] @ loads[c][gi][1]) * Fe[c] for c in range(n))
                    R[j] = ((model.bodies[i].inertia - g.mz) * acc_free[j] + mb_[gi]
                            + (1.0 + al) * mz_f - (1.0 + al) * Q[j] + al * Q_n[j])
                return R, Q, cs, Fe[:n], active[:n], Ftot, loads, acc_all

            acc_free = np.array([ac[i] for i in free])
            conv = False
            for it in range(self.max_newton):
                newton += 1
                R, *_ = evaluate(acc_free)
                Jm = np.zeros((nf, nf))
                for j in range(nf):
                    da = 1e-9 / (coeff * scale)
                    pert = acc_free.copy()
                    pert[j] += da
                    Rp, *_ = evaluate(pert)
                    Jm[:, j] = (Rp - R) / da
                dacc = np.linalg.solve(Jm, -R)
                acc_free = acc_free + dacc
                if np.max(np.abs(coeff * dacc)) * scale < self.tol:
                    conv = True
                    break
            if not conv and nf == 1:
                # one free rotation: R(acc) rises with acc (inertia, and the contact force falls
                # as the gear runs ahead), so a bracket and Brent's method find the root where
                # Newton cycles between contact states (a tooth pair opening within the step)
                acc_free = self._bracketed_root(evaluate, ac[free[0]], coeff * scale, tn)
                fallbacks[0] += 1
                conv = True
            if not conv:
                raise ConfigError(f"full-order reference: Newton did not converge at t = {tn:.6f} s")
            R, Q, cs, Fe, active, Ftot, loads, acc_all = evaluate(acc_free)
            # FE accelerations and the Newmark update
            for gi, g in enumerate(gears):
                fvec = np.zeros(g.ndofs)
                for c in range(len(cs)):
                    if active[c]:
                        idx, f = loads[c][gi]
                        np.add.at(fvec, g.flank_dofs[idx], f * Fe[c])
                rhs_full = bvec[gi] + (1.0 + al) * fvec - g.coupling * (acc_all[g.body] if g.body in free else 0.0)
                ag = g.solve(rhs_full)
                solves += 1
                u[gi] = uh[gi] + coeff * ag
                v[gi] = vh[gi] + ga_ * h * ag
                a[gi] = ag
                rhs_n[gi] = -(g.K @ u[gi]) + fvec
            for j, i in enumerate(free):
                th[i] = thh[i] + coeff * acc_free[j]
                om[i] = omh[i] + ga_ * h * acc_free[j]
                ac[i] = acc_free[j]
            for i in presc:
                th[i], om[i], ac[i] = presc[i]
            Q_n = Q
            rec["F"][k] = float(Ftot[Ftot > 0].sum())
            rec["Fe"][k] = float(Fe[active].sum()) if len(cs) else 0.0
            rec["nc"][k] = int(np.count_nonzero(active))
            rec_th[k] = th
            rec_om[k] = om
            if progress is not None and (k + 1) % 200 == 0:
                progress((k + 1) / nsteps)
        wall = time.perf_counter() - wall0
        return FullOrderRun(h=h, nsteps=nsteps, mesh_force=rec["F"], elastic_force=rec["Fe"], theta=rec_th,
                            omega=rec_om, contacts=rec["nc"], wall=wall, setup_seconds=self.setup_seconds,
                            newton=newton, solves=solves,
                            info={"stalled_contact_solves": stalled[0], "bracketed_steps": fallbacks[0]},
                            gears=[g.info | {"name": g.name, "coupling_inertia": g.mz, "inertia_fe": g.inertia_fe}
                                   for g in gears])


# --------------------------------------------------------------------------------------------
# reduced against full order
# --------------------------------------------------------------------------------------------
def window_metrics(F: np.ndarray, h: float, f_mesh: float, cycles: int, f_max: float = 5e3) -> dict:
    """Mean, RMS (total and about the mean), peak-to-peak and mesh-harmonic lines of the last
    ``cycles`` mesh periods of a force signal sampled every h [s].

    The window holds a whole number of mesh periods (``cycles / (f_mesh h)`` must be an
    integer), so with a rectangular window harmonic k of the mesh frequency falls on bin
    ``k * cycles`` exactly; ``lines[k - 1]`` is its single-sided amplitude [N], k = 1 ..
    ``f_max / f_mesh``. ``rms_band`` is the RMS about the mean of the content up to f_max (every
    bin, not only the lines) [N].
    """
    n = cycles / (f_mesh * h)
    if abs(n - round(n)) > 1e-6 * n:
        raise ConfigError(f"cycles = {cycles}: {cycles} mesh periods of {1e3 / f_mesh:.6g} ms are "
                          f"{n:.6g} steps of {h:g} s, not a whole number")
    n = int(round(n))
    if n > F.size:
        raise ConfigError(f"cycles = {cycles}: the run holds only {F.size} steps, {n} needed")
    x = np.asarray(F[-n:], float)
    X = np.fft.rfft(x) / n
    kmax = int(math.floor(f_max / f_mesh + 1e-9))
    lines = np.array([2.0 * abs(X[k * cycles]) for k in range(1, kmax + 1)])
    band = X[1:int(math.floor(f_max * n * h + 1e-9)) + 1]
    return {"mean": float(x.mean()), "rms": float(np.sqrt(np.mean(x * x))),
            "rms_ac": float(x.std()), "rms_band": float(np.sqrt(2.0 * np.sum(np.abs(band) ** 2))),
            "p2p": float(np.ptp(x)), "lines": lines,
            "line_hz": f_mesh * np.arange(1, kmax + 1), "window_steps": n}


def comparable_config(cfg, messages=None):
    """``cfg`` as :func:`reference_comparison` runs both models: without ``[shafts]`` (the
    comparison is about the gears: both turn on fixed revolutes) and without ``[lubrication]``
    (the full-order model has no tooth friction or squeeze film: both take the ``[contact]``
    damper); each block left out is said through ``messages``. ``cfg`` itself is not changed."""
    left = [name for name, block in (("shafts", cfg.shafts), ("lubrication", cfg.lubrication)) if block]
    if not left:
        return cfg
    cfg = copy.copy(cfg)
    for name in left:
        setattr(cfg, name, None)
    if messages:
        why = {"shafts": "both models turn on fixed revolutes",
               "lubrication": "the full-order model has no friction or squeeze film: both take the [contact] damper"}
        for name in left:
            messages(f"full-order reference: [{name}] left out ({why[name]})")
    return cfg


def reference_comparison(cfg, cycles: int = 24, t_end: float | None = None, progress=None,
                         messages=None) -> dict:
    """Run the reduced flexible model and the full-order reference of the spur pair ``cfg``
    (both gears in ``[flexible]``) from rest to ``t_end`` (default: the run-in plus ``cycles``
    mesh periods) with the configuration's step and HHT alpha, and compare the last ``cycles``
    mesh periods of the mesh normal force on the integration grid.

    Returns
    -------
    dict
        ``reduced`` / ``full``: :func:`window_metrics` plus ``wall`` (integration) and
        ``setup`` [s]; ``force_reduced`` / ``force_full`` (per step) [N]; ``relative``:
        (full - reduced) / full of mean, rms, rms_ac, p2p and per line; ``wall_ratio`` (full /
        reduced integration wall time); ``f_mesh``, ``h``, ``t_end``, ``gears`` (dofs, inertia).
    """
    from ..model.assembly import build_model
    from .reductions import reduce_flexible_gears
    from ..integrator.simulation import simulate

    cfg = comparable_config(cfg, messages)
    sim = cfg.simulation
    h, alpha = sim["step"], sim["hht_alpha"]
    t0 = time.perf_counter()
    reductions = reduce_flexible_gears(cfg, messages)
    model = build_model(cfg, reductions=reductions)  # not loaded twice
    setup_reduced = time.perf_counter() - t0
    f_mesh = model.attrs["mesh_frequency"]
    if t_end is None:
        t_end = sim["run_in"] + cycles / f_mesh
    integ = simulate(model, t_end, h, 1, alpha=alpha, tol=sim["newton_tol"], max_newton=sim["max_newton"],
                     condensation=cfg.flexible["condensation"])
    full = FullOrderModel(model, reductions, h, alpha, tol=sim["newton_tol"], max_newton=sim["max_newton"])
    run = full.simulate(t_end, progress=progress)
    Fr = integ.mesh[:, 0, 0]
    Ff = run.mesh_force[: Fr.size]
    mr = window_metrics(Fr, h, f_mesh, cycles)
    mf = window_metrics(Ff, h, f_mesh, cycles)
    mr.update(wall=integ.wall, setup=setup_reduced, steps=integ.steps, newton=integ.newton)
    mf.update(wall=run.wall, setup=run.setup_seconds, steps=run.nsteps, newton=run.newton, solves=run.solves,
              stalled=run.info["stalled_contact_solves"])
    rel = {k: (mf[k] - mr[k]) / mf[k] for k in ("mean", "rms", "rms_ac", "rms_band", "p2p")}
    rel["lines"] = (mf["lines"] - mr["lines"]) / mf["lines"]
    return {"reduced": mr, "full": mf, "relative": rel, "wall_ratio": run.wall / integ.wall,
            "force_reduced": Fr, "force_full": Ff, "f_mesh": f_mesh, "h": h, "t_end": t_end,
            "cycles": cycles, "gears": run.gears,
            "inertia_model": [b.inertia for b in model.bodies]}
