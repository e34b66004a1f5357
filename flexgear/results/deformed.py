"""Deformed gears from a flexible result: full FE displacement fields, ParaView time series, snapshots.

For every output sample :class:`DeformedGears` rebuilds the displacement of every node of every
gear mesh: the body's rigid motion (the body frame is the mesh frame; tooth k of the FE mesh is
tooth k of the contact search) plus, for a flexible gear, the static FE solution with the
interface held, ``u = K_ii^-1 f``, under the sample's flank patch loads (those the reduction is
built from, :mod:`flexgear.reduction.flank`), with the quasi-static part of the modes replaced
by the recorded modal (``Phi_d eta``) and condensed (``Phi_c eta_c``) coordinates where the
result carries them. Kept modes plus residual flexibility are exactly ``K_ii^-1``, so this is
the field the solver's flank compliance stands for. Rigid gears are shown undeformed.

The contact points are not stored: the solver's contact search finds them again at the recorded
poses (:func:`flexgear.dynamics.integrator.simulation.evaluate`), matched to the slots by teeth
and side. The load is the pair's *elastic* force (the IMPACT damper does not bend the flanks),
from ``penetration = pair_deflection + h(F_el)`` with the Hertz approach ``h``
(:func:`flexgear.dynamics.contact.laws.hertz_line`). The field's patch-weighted flank
displacement less the near field reproduces the solver's deflection up to the tables'
interpolation in the radius (``tests/test_deformed.py``).

Files (:func:`write_deformed_series`): ``<stem>.pvd`` (a ParaView collection, one time step per
frame) and ``<stem>_NNNN.vtu``, one unstructured grid per frame holding every gear (quadratic
``triangle6``) at ``centre + R(theta) (x + scale u)``, with point data ``displacement`` (true,
global frame, z = 0) [m], ``displacement_magnitude`` [m] and ``body`` (gear index, model order),
and cell data ``von_mises`` [Pa] and ``strain_energy_density`` [J/m^3] (element means; zero on
rigid gears). One grid per frame, not a multiblock, opens in any ParaView or VisIt as a plain
time series; a gear is picked with a Threshold on ``body``.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError, FlexgearError, user_stacklevel
from ..files import atomic_write, check_output_directory, check_targets, output_directory

__all__ = ["FlankLoad", "FlankFields", "GearFrame", "DeformedFrame", "DeformedGears", "frame_indices", "element_stress",
           "deformed_series_paths", "write_deformed_series", "plot_deformed"]


@dataclass
class FlankLoad:
    """One contact load on one flexible gear at one sample.

    Attributes
    ----------
    mesh : str
        Mesh name.
    slot : int
        Tooth-pair slot in the mesh's records.
    tooth, side : int
        Loaded tooth of this gear and its flank (+1 left, -1 right).
    radius : float
        Contact radius on this gear [m] (clamped to the flank tables' range, as the solver does).
    force : float
        Elastic normal force of the pair [N] (into the tooth).
    point, direction : tuple of float
        Contact point [m] and unit direction of the force on this gear, global frame (from the
        contact search at the recorded poses).
    displacement : float
        Patch-weighted mean normal displacement of the flank (into the tooth) in the
        reconstructed field [m].
    near_field : float
        Half-plane near-field compliance of the patch [m/N] (the part the Hertz law carries).
    """

    mesh: str
    slot: int
    tooth: int
    side: int
    radius: float
    force: float
    point: tuple = (0.0, 0.0)
    direction: tuple = (0.0, 0.0)
    displacement: float = 0.0
    near_field: float = 0.0

    @property
    def deflection(self) -> float:
        """Flank deflection without the near field, the solver's measure [m]."""
        return self.displacement - self.near_field * self.force


@dataclass
class GearFrame:
    """One gear at one sample: mesh frame, rigid motion and elastic displacement.

    Attributes
    ----------
    name : str
        Body name.
    points : ndarray (N, 2)
        Mesh nodes in the gear frame [m].
    triangles : ndarray (M, 3 or 6)
        Node indices of the mesh's triangles (meshio order).
    centre : ndarray (2,)
        Body centre in the global frame [m].
    angle : float
        Body rotation [rad].
    displacement : ndarray (N, 2)
        Elastic displacement in the gear frame [m] (zero for a rigid gear).
    flexible : bool
    loads : list of FlankLoad
    von_mises, energy_density : ndarray (M,) or None
        Element means of the von Mises stress [Pa] and the strain energy density [J/m^3] of the
        elastic field (:func:`element_stress`; zero for a rigid gear).
    """

    name: str
    points: np.ndarray
    triangles: np.ndarray
    centre: np.ndarray
    angle: float
    displacement: np.ndarray
    flexible: bool
    loads: list = field(default_factory=list)
    von_mises: np.ndarray | None = None
    energy_density: np.ndarray | None = None

    def rotation(self) -> np.ndarray:
        c, s = math.cos(self.angle), math.sin(self.angle)
        return np.array([[c, -s], [s, c]])

    def global_points(self, scale: float = 1.0) -> np.ndarray:
        """Node positions ``centre + R (x + scale u)`` in the global frame [m]."""
        return self.centre + (self.points + scale * self.displacement) @ self.rotation().T

    def global_displacement(self) -> np.ndarray:
        """Elastic displacement turned into the global frame, ``R u`` (N, 2) [m]."""
        return self.displacement @ self.rotation().T


@dataclass
class DeformedFrame:
    """Every gear at one output sample."""

    index: int
    time: float
    gears: list
    unmatched: list = field(default_factory=list)  # (mesh, slot, force): slots without a contact point


def frame_indices(time, window, every: int = 1, name: str = "window") -> np.ndarray:
    """Output samples in ``window = (t0, t1)`` [s], every ``every``-th.

    Raises
    ------
    ConfigError
        Naming ``name`` when the window is empty, reversed, not finite or outside the record,
        or ``every`` is not a positive integer.
    """
    t = np.asarray(time, float)
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
        raise ConfigError(f"every = {every!r}: must be an integer >= 1")
    try:
        t0, t1 = (float(x) for x in window)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} = {window!r}: give two times T0 T1 in s") from None
    if not (math.isfinite(t0) and math.isfinite(t1)) or t1 < t0:
        raise ConfigError(f"{name} = ({t0:g}, {t1:g}) s: need finite times with T0 <= T1")
    tol = 0.5 * float(np.median(np.diff(t))) if t.size > 1 else 0.0  # half a sampling interval
    if t0 < t[0] - tol or t1 > t[-1] + tol:
        raise ConfigError(f"{name} = ({t0:g}, {t1:g}) s: outside the record, which spans "
                          f"{t[0]:g} .. {t[-1]:g} s (the run-in is not recorded)")
    idx = np.flatnonzero((t >= t0 - tol) & (t <= t1 + tol))
    if idx.size == 0:
        raise ConfigError(f"{name} = ({t0:g}, {t1:g}) s: holds no output sample (sampling interval "
                          f"{2 * tol:g} s)")
    return idx[::every]


def _elastic_force(penetration: float, deflection: float, hp: tuple, extra=None) -> float:
    """Solve ``penetration - deflection = h(F)`` for the elastic force F >= 0 [N]: h the compliant
    law's approach (:func:`~flexgear.dynamics.contact.laws.contact_approach`, increasing and
    concave in F) of the Hertz arguments ``hp`` and the per-tooth terms ``extra`` (series
    compliance [m/N], outline width and recess [m] of flank A and of flank B; healthy by
    default); Newton from below, then bisection safeguard."""
    from ..dynamics.contact.laws import HEALTHY_TERMS, contact_approach

    row = np.array([[*hp, *(HEALTHY_TERMS if extra is None else extra)]], float)

    def approach(F):
        return contact_approach(float(F), row, 0)

    target = penetration - deflection
    if not target > 0.0:
        return 0.0
    lo, hi = 0.0, 1.0
    while approach(hi)[0] < target:
        lo, hi = hi, 2.0 * hi
        if hi > 1e12:
            raise FlexgearError(f"no Hertz force gives an approach of {target:.4g} m")
    F = 0.5 * (lo + hi)
    for _ in range(200):
        h, dh = approach(F)
        if h < target:
            lo = F
        else:
            hi = F
        Fn = F - (h - target) / dh
        if not lo < Fn < hi:
            Fn = 0.5 * (lo + hi)
        if abs(Fn - F) <= 1e-13 * max(F, 1.0):
            return Fn
        F = Fn
    return F


class FlankFields:
    """Static FE fields of flexible gears under flank contact loads (interface held).

    ``elastic_field(red, gear, loads)`` is ``K_ii^-1 f`` of the reduction ``red`` (a
    :class:`~flexgear.reduction.gear.GearReduction` of ``gear``) under the :class:`FlankLoad`
    list ``loads``: the reduction's unit patch at each contact times its force. The flanks'
    facet bases are kept between calls (building one is most of the cost of a load).
    """

    def __init__(self):
        self._bases = {}

    def patch(self, red, gear, tooth: int, side: int, r: float):
        """Unit patch load (ndofs,) at radius r (clamped to the table range) and its near field.

        The load of :func:`flexgear.reduction.flank.flank_patch_loads` with the reduction's
        default spread."""
        from ..reduction.flank import flank_basis, flank_patch
        from ..stiffness.hertz import halfplane_compliance

        t = red.tables
        r = min(max(r, float(t.radius[0])), float(t.radius[-1]))
        fe = red.body.model
        key = (id(red), tooth % gear.z, side)
        if key not in self._bases:
            self._bases[key] = flank_basis(fe, gear, tooth, side)
        f, w, lo, hi = flank_patch(fe, gear, self._bases[key], r)
        near = halfplane_compliance(w, t.depth, fe.material, fe.thickness, fe.formulation, lo, hi)
        return f, near, r

    def elastic_field(self, red, gear, loads: list, eta=None, condensed=None) -> np.ndarray:
        """Elastic displacement (ndofs,) of one gear, interface held [m], under ``loads``
        (FlankLoad list, updated in place with radius, displacement and near field).

        ``eta`` (m,), if given, are the integrated coordinates of the first m modes and
        ``condensed`` (nq,), if given, those of the last nq modes of the reduction (the modes
        the solver condensed in its contact solve, up to the cutoff): for each such set S the
        field is ``K_ii^-1 f + Phi_S (eta_S - Phi_S^T f / omega_S^2)``, the quasi-static part of
        those modes replaced by their motion. With both covering every mode, only the residual
        flexibility (the modes above the cutoff) stays static, as in the solver.
        """
        body = red.body
        f = np.zeros(body.basis.shape[0])
        patches = []
        for ld in loads:
            p, near, r = self.patch(red, gear, ld.tooth, ld.side, ld.radius)
            ld.radius, ld.near_field = r, near
            patches.append(p)
            f += ld.force * p
        u = body.residual.static(f)  # K_ii^-1 f: every mode quasi-static plus the residual
        n = body.n_modes
        sets = []
        if eta is not None:
            eta = np.asarray(eta, float).ravel()
            sets.append((0, eta))
        if condensed is not None:
            condensed = np.asarray(condensed, float).ravel()
            sets.append((n - condensed.size, condensed))
        given = [x.size for _, x in sets]
        if sum(given) > n:
            raise FlexgearError(f"{' + '.join(map(str, given))} modal coordinates (integrated, condensed) for a body "
                                f"reduced with {n} modes")
        for first, x in sets:
            # their quasi-static part Phi Phi^T f / omega^2 is replaced by Phi eta (the rest stays
            # condensed, as in the solver)
            cols = slice(body.n_interface + first, body.n_interface + first + x.size)
            phi = body.basis[:, cols]
            omega2 = (2.0 * np.pi * np.asarray(body.frequencies[first:first + x.size], float)) ** 2
            u = u + phi @ (x - (phi.T @ f) / omega2)
        for ld, p in zip(loads, patches):
            ld.displacement = float(p @ u)
        return u


class DeformedGears:
    """Turns the samples of a result with flexible gears into deformed gear meshes.

        Building it loads (or computes) the reductions and meshes of the result's gears; each
        :meth:`frame` then costs one contact evaluation and one sparse solve per flexible gear.

        Parameters
        ----------
        result : Result, str or Path
            A result, its ``results.h5`` or the directory holding it.
        progress : callable(str), optional
            Messages while the reductions are loaded or computed.
        modal : dict, optional
            Body name -> array (n_samples, m) of the first m modes' coordinates. Default: the
            result's ``modal_coordinates``, else every mode condensed quasi-statically.
        condensed : dict, optional
            Body name -> array (n_samples, nq) of the condensed modes' coordinates. Default: the
            result's ``condensed_coordinates``, else their static response; ``{}`` forces the latter.

        Raises
        ------
        FlexgearError
            A result without flexible gears, or of a layout without ``pair_deflection``.
    """

    def __init__(self, result, progress=None, modal: dict | None = None, stresses: bool = True,
                 condensed: dict | None = None):
        from ..config import loads_config
        from ..dynamics.model.assembly import build_model
        from ..dynamics.flexible.reductions import body_reduction, reduce_flexible_gears
        from ..fe.meshing import MeshSettings, mesh_gear
        from ..reduction.gear import reduction_mesh

        self.result = load_result(result)
        res = self.result
        cfg = loads_config(res.config_toml, "config_toml of the result")
        if not cfg.flexible or not cfg.flexible.get("gears"):
            raise FlexgearError("the result has no flexible gear (its configuration has no [flexible] gears): "
                                "nothing deforms; run a flexible configuration (presets spur_pair_flexible, "
                                "mercury_1a_flexible)")
        self.config = cfg
        self.reductions = reduce_flexible_gears(cfg, progress)
        self.model = build_model(cfg, reductions=self.reductions)  # not loaded twice
        if modal is None:  # the modes the solver integrated (results layout 3), if any
            modal = {name: b.modal_coordinates for name, b in res.bodies.items()
                     if getattr(b, "modal_coordinates", None) is not None}
        self.modal = modal
        if condensed is None:  # the condensed modes' coordinates (results layout 4), if any
            condensed = {name: b.condensed_coordinates for name, b in res.bodies.items()
                         if getattr(b, "condensed_coordinates", None) is not None}
        self.condensed = condensed
        self.stresses = bool(stresses)
        fx = cfg.flexible
        settings = MeshSettings(level=fx["level"], order=fx["order"])
        self._mesh_index = {m.name: k for k, m in enumerate(self.model.meshes)}
        for mesh in self.model.meshes:
            if mesh.attrs.get("flexible"):
                rec = res.meshes.get(mesh.name)
                if rec is None or rec.pair_deflection is None:
                    raise FlexgearError(
                        f"mesh {mesh.name!r} of the result has no pair_deflection: the file was written by an "
                        "older result layout (before flexible gears' flank deflections were recorded); run the "
                        "configuration again with this flexgear")
        self.bodies = []  # (body index, body name, gear, GearMesh, reduction or None)
        for i, b in enumerate(self.model.bodies):
            gname = b.attrs.get("gear")
            if gname is None:
                continue  # the carrier: not a gear
            if b.name not in res.bodies:
                raise FlexgearError(f"the result has no body {b.name!r}; it does not match its configuration")
            red = body_reduction(self.reductions, b.name, gname)
            gm = (mesh_gear(cfg.gears[gname], settings) if red is None  # a faulty gear's own mesh
                  else reduction_mesh(cfg.gears[gname], settings, red.faults))
            self.bodies.append((i, b.name, cfg.gears[gname], gm, red))
        self.fields = FlankFields()

    # ---------------------------------------------------------------- state of a sample
    def _state(self, i: int):
        q, v = self.model.initial_state()
        q, v = q.copy(), v.copy()
        for b, (ix, iy, ith) in zip(self.model.bodies, self.model.coordinate_indices()):
            rb = self.result.bodies[b.name]
            if ix >= 0:
                q[ix], q[iy] = rb.position[i]
                v[ix], v[iy] = rb.velocity[i]
            if ith >= 0:
                q[ith] = rb.angle[i]
                v[ith] = rb.angular_velocity[i]
        return q, v

    def contact_loads(self, i: int) -> tuple[dict, list]:
        """Flank loads of sample ``i`` per flexible body index, and the slots whose contact the
        search did not find again (mesh, slot, recorded force [N])."""
        from ..dynamics.flexible.flank import flank_side
        from ..dynamics.contact.laws import HERTZ_COLUMNS, HERTZ_SERIES
        from ..dynamics.integrator.simulation import evaluate

        q, v = self._state(i)
        t = float(self.result.time[i])
        work = evaluate(self.model, q, v, t=t)["work"]
        pose, C = work.bodies.pose, work.contacts
        flexible = {bi for bi, _, _, _, red in self.bodies if red is not None}
        loads: dict[int, list] = {bi: [] for bi in flexible}
        unmatched = []
        for mesh in self.model.meshes:
            if not mesh.attrs.get("flexible"):
                continue
            k = self._mesh_index[mesh.name]
            rec = self.result.meshes[mesh.name]
            found = {(int(C.tooth_a[k, c]), int(C.tooth_b[k, c]), int(C.side_a[k, c])): c
                     for c in range(C.count[k])}
            # each reported contact's per-tooth terms (a cracked tooth's series compliance, a partial
            # fault's slices; healthy: 0, 1, 0, 1, 0), as the solver used them
            extra = {int(C.joint_slot[j]): tuple(float(v) for v in C.hertz[j, HERTZ_SERIES:HERTZ_COLUMNS])
                     for j in range(int(C.joint_count[0])) if C.joint_mesh[j] == k and C.joint_slot[j] >= 0}
            za = self.model.bodies[mesh.a].attrs["z"]
            zb = self.model.bodies[mesh.b].attrs["z"]
            hz = mesh.hertz
            for s in range(rec.pair_tooth_a.shape[1]):
                ta, tb, sa = int(rec.pair_tooth_a[i, s]), int(rec.pair_tooth_b[i, s]), int(rec.pair_side[i, s])
                if ta < 0:
                    continue
                c = found.get((ta, tb, sa))
                if c is None:
                    unmatched.append((mesh.name, s, float(rec.pair_force[i, s])))
                    continue
                px, py = C.x[k, c], C.y[k, c]
                _, ra = flank_side(px, py, pose[mesh.a, 0], pose[mesh.a, 1], pose[mesh.a, 2], ta, za)
                sb, rb_ = flank_side(px, py, pose[mesh.b, 0], pose[mesh.b, 1], pose[mesh.b, 2], tb, zb)
                Fe = _elastic_force(float(rec.penetration[i, s]), float(rec.pair_deflection[i, s]),
                                    _hertz_arguments(hz, ra, rb_, bool(mesh.internal)),
                                    extra.get(c))
                n = (float(C.nx[k, c]), float(C.ny[k, c]))  # force on a: +F n, on b: -F n
                for bi, tooth, side, r, sgn in ((mesh.a, ta, sa, ra, 1.0), (mesh.b, tb, int(sb), rb_, -1.0)):
                    if bi in loads:
                        loads[bi].append(FlankLoad(mesh=mesh.name, slot=s, tooth=tooth, side=side,
                                                   radius=float(r), force=Fe, point=(float(px), float(py)),
                                                   direction=(sgn * n[0], sgn * n[1])))
        return loads, unmatched

    # ---------------------------------------------------------------- FE fields
    def _patch(self, red, gear, tooth: int, side: int, r: float):
        """:meth:`FlankFields.patch` (bases kept between frames)."""
        return self.fields.patch(red, gear, tooth, side, r)

    def elastic_field(self, red, gear, loads: list, eta=None, condensed=None) -> np.ndarray:
        """:meth:`FlankFields.elastic_field`: the elastic displacement (ndofs,) of one gear
        under ``loads`` (FlankLoad list, updated in place)."""
        return self.fields.elastic_field(red, gear, loads, eta, condensed)

    def frame(self, i: int) -> DeformedFrame:
        """Every gear at output sample ``i``."""
        n = len(self.result.time)
        if not -n <= i < n:
            raise ConfigError(f"sample index {i}: the result has {n} samples")
        i = i % n
        loads, unmatched = self.contact_loads(i)
        gears = []
        for bi, name, gear, gm, red in self.bodies:
            rb = self.result.bodies[name]
            u = np.zeros_like(gm.points)
            body_loads = loads.get(bi, [])
            vm = w = np.zeros(len(gm.triangles))
            if red is not None:
                eta = self.modal[name][i] if name in self.modal else None
                cond = self.condensed[name][i] if name in self.condensed else None
                ufull = self.elastic_field(red, gear, body_loads, eta, cond)
                u = red.body.model.nodal_field(ufull)
                if self.stresses:
                    vm, w = element_stress(red.body.model, ufull)
            gears.append(GearFrame(name=name, points=gm.points, triangles=gm.triangles,
                                   centre=np.asarray(rb.position[i], float), angle=float(rb.angle[i]),
                                   displacement=u, flexible=red is not None, loads=body_loads,
                                   von_mises=vm if self.stresses else None,
                                   energy_density=w if self.stresses else None))
        return DeformedFrame(index=i, time=float(self.result.time[i]), gears=gears, unmatched=unmatched)


def element_stress(fe, u) -> tuple[np.ndarray, np.ndarray]:
    """Element means of the von Mises stress [Pa] and the strain energy density [J/m^3] of a
    displacement ``u`` (ndofs,) of an FE model (plane stress: sigma_zz = 0; plane strain:
    sigma_zz = nu (sigma_xx + sigma_yy)). The energy densities times the element areas and the
    thickness sum to ``u^T K u / 2``."""
    from skfem import Functional
    from skfem.helpers import ddot, eye, sym_grad, trace

    from ..fe.elasticity import lame_2d

    lam, mu = lame_2d(fe.material, fe.formulation)
    nu = fe.material.nu if fe.formulation == "plane_strain" else 0.0
    uh = fe.basis.interpolate(np.asarray(u, float))

    def strain_stress(w):
        e = sym_grad(w["u"])
        return e, 2.0 * mu * e + lam * eye(trace(e), 2)

    @Functional
    def energy(w):
        e, sig = strain_stress(w)
        return 0.5 * ddot(sig, e)

    @Functional
    def mises(w):
        _, sig = strain_stress(w)
        sxx, syy, sxy = sig[0, 0], sig[1, 1], sig[0, 1]
        szz = nu * (sxx + syy)
        return np.sqrt(0.5 * ((sxx - syy) ** 2 + (syy - szz) ** 2 + (szz - sxx) ** 2) + 3.0 * sxy ** 2)

    @Functional
    def area(w):
        return 1.0 + 0.0 * w.x[0]

    a = area.elemental(fe.basis)
    return mises.elemental(fe.basis, u=uh) / a, energy.elemental(fe.basis, u=uh) / a


def _hertz_arguments(hz: dict, ra: float, rb: float, internal: bool) -> tuple:
    """Arguments R, L, ka, na, da, kb, nb, db, E* of ``hertz_line`` at contact radii ra, rb, as the
    kernel ``compliant_contacts`` forms them."""
    ta = math.sqrt(max(ra ** 2 - hz["rb_a"] ** 2, (0.05 * hz["rb_a"]) ** 2))
    tb = math.sqrt(max(rb ** 2 - hz["rb_b"] ** 2, (0.05 * hz["rb_b"]) ** 2))
    R = ta * tb / max(tb - ta, 0.05 * tb) if internal else ta * tb / (ta + tb)
    return (R, hz["face_width"], hz["hertz_a"], hz["nu_a"], hz["depth_a"], hz["hertz_b"], hz["nu_b"],
            hz["depth_b"], hz["e_star"])


def load_result(source):
    """A :class:`~flexgear.results.store.Result` from a Result, an HDF5 file or a directory
    holding ``results.h5``."""
    from .store import Result, load

    if isinstance(source, Result):
        return source
    p = Path(source)
    if p.is_dir():
        p = p / "results.h5"
    if not p.exists():
        raise FlexgearError(f"{str(source)!r}: no result file there (give results.h5 or its directory)")
    return load(p)


# ------------------------------------------------------------------------------- files
def deformed_series_paths(outdir, n_frames: int, stem: str = "deformed") -> list[Path]:
    """Files :func:`write_deformed_series` writes: the ``.pvd`` first, then one ``.vtu`` per frame."""
    out = Path(outdir)
    return [out / f"{stem}.pvd"] + [out / f"{stem}_{k:04d}.vtu" for k in range(n_frames)]


def _frame_mesh(frame: DeformedFrame, scale: float):
    import meshio

    pts, disp, body, cells = [], [], [], []
    off = 0
    for k, g in enumerate(frame.gears):
        xy = g.global_points(scale)
        pts.append(np.column_stack([xy, np.zeros(len(xy))]))
        d = g.global_displacement()
        disp.append(np.column_stack([d, np.zeros(len(d))]))
        body.append(np.full(len(xy), k, dtype=np.int32))
        cells.append(("triangle6" if g.triangles.shape[1] == 6 else "triangle", g.triangles + off))
        off += len(xy)
    D = np.vstack(disp)
    cell_data = {}
    if all(g.von_mises is not None for g in frame.gears):
        cell_data = {"von_mises": [g.von_mises for g in frame.gears],
                     "strain_energy_density": [g.energy_density for g in frame.gears]}
    return meshio.Mesh(np.vstack(pts), cells,
                       point_data={"displacement": D, "displacement_magnitude": np.linalg.norm(D, axis=1),
                                   "body": np.concatenate(body)}, cell_data=cell_data)


def _pvd_text(entries) -> str:
    rows = "\n".join(f'    <DataSet timestep="{t:.10g}" group="" part="0" file="{name}"/>' for t, name in entries)
    return ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")


def write_deformed_series(result, outdir, window, scale: float, every: int = 1, *, overwrite: bool = False,
                          stem: str = "deformed", gears: DeformedGears | None = None, progress=None,
                          messages=None) -> list[Path]:
    """Write the deformed gears over a time window as a ParaView time series (files: module docstring).

        Parameters
        ----------
        result : Result, str or Path
            A result with flexible gears (or its ``results.h5``, or the directory holding it).
        outdir : str or Path
            Output directory (created if missing).
        window : (float, float)
            First and last time [s], within the record.
        scale : float
            Factor on the elastic displacements for the geometry (> 0); ``displacement`` stays true.
        every : int
            Write every ``every``-th output sample of the window.
        overwrite : bool
            Replace existing files (default: refuse, before writing anything).
        gears : DeformedGears, optional
            Reuse an already built one.
        progress : callable(fraction), optional
        messages : callable(str), optional
            Reduction messages.

        Returns
        -------
        list of Path
            The ``.pvd`` and the ``.vtu`` files.
    """
    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not math.isfinite(scale) or scale <= 0:
        raise ConfigError(f"scale = {scale!r}: the displacement scale must be a finite number > 0")
    res = gears.result if gears is not None else load_result(result)
    idx = frame_indices(res.time, window, every)
    out = Path(outdir)
    paths = deformed_series_paths(out, idx.size, stem)
    check_output_directory(out)
    check_targets(paths, overwrite)
    dg = gears if gears is not None else DeformedGears(res, progress=messages)
    entries, missed = [], []
    with output_directory(out):
        for n, (i, path) in enumerate(zip(idx, paths[1:])):
            frame = dg.frame(int(i))
            missed += [(frame.time, *u) for u in frame.unmatched]
            mesh = _frame_mesh(frame, float(scale))
            atomic_write(path, lambda tmp, mesh=mesh: mesh.write(tmp, file_format="vtu"))
            entries.append((frame.time, path.name))
            if progress is not None:
                progress((n + 1) / idx.size)
        atomic_write(paths[0], lambda tmp: Path(tmp).write_text(_pvd_text(entries)))
    if missed:
        t, mesh, slot, force = max(missed, key=lambda m: m[3])
        warnings.warn(f"{len(missed)} recorded tooth-pair contacts were not found again by the contact search at "
                      f"the recorded (anti-aliased) poses and are left out; the largest: {mesh} slot {slot} at "
                      f"t = {t:.6g} s, recorded force {force:.4g} N", stacklevel=user_stacklevel())
    return paths


# ------------------------------------------------------------------------------- figure
def _linear_triangles(tri: np.ndarray) -> np.ndarray:
    """Linear triangles for plotting: each 6-node triangle split into 4."""
    if tri.shape[1] == 3:
        return tri
    return np.vstack([tri[:, [0, 3, 5]], tri[:, [3, 1, 4]], tri[:, [5, 4, 2]], tri[:, [3, 4, 5]]])


def _boundary_polylines(tri: np.ndarray) -> np.ndarray:
    """Boundary edges of a triangle mesh as node-index polylines (K, 2 or 3: ends, mid-node)."""
    quad = tri.shape[1] == 6
    edges = [(0, 1, 3), (1, 2, 4), (2, 0, 5)] if quad else [(0, 1), (1, 2), (2, 0)]
    e = np.vstack([tri[:, list(c)] for c in edges])
    key = np.sort(e[:, :2], axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    b = e[cnt[inv.ravel()] == 1]
    return b[:, [0, 2, 1]] if quad else b


def plot_deformed(result, time: float, scale: float, ax=None, *, zoom: float | None = None,
                  gears: DeformedGears | None = None):
    """Snapshot of the deformed gears at the output sample nearest ``time``: meshes drawn at
    ``centre + R (x + scale u)``, coloured by the true elastic displacement magnitude [um], the
    undeformed outlines in grey, the contact points marked and the scale noted in the title.

    Parameters
    ----------
    result : Result, str, Path or DeformedGears
        A flexible result (a DeformedGears is reused: no setup cost).
    time : float
        Time [s] within the record.
    scale : float
        Displacement scale for the drawing (> 0).
    ax : matplotlib Axes, optional
    zoom : float, optional
        Half-width [m] of a square view centred on the mean contact point (default: whole gears).
    gears : DeformedGears, optional
        Reuse an already built one for ``result``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.tri import Triangulation

    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not math.isfinite(scale) or scale <= 0:
        raise ConfigError(f"scale = {scale!r}: the displacement scale must be a finite number > 0")
    dg = result if isinstance(result, DeformedGears) else (gears or DeformedGears(result))
    t = np.asarray(dg.result.time)
    idx = frame_indices(t, (time, time), 1, name="time")
    i = int(idx[np.argmin(abs(t[idx] - time))])
    frame = dg.frame(i)
    if ax is None:
        fig, ax = plt.subplots(figsize=(7, 5))
    else:
        fig = ax.figure
    umax = max(float(np.linalg.norm(g.displacement, axis=1).max()) for g in frame.gears) * 1e6 or 1.0
    art, points = None, []
    for g in frame.gears:
        xy = g.global_points(scale) * 1e3
        mag = np.linalg.norm(g.displacement, axis=1) * 1e6
        tri = Triangulation(xy[:, 0], xy[:, 1], _linear_triangles(g.triangles))
        art = ax.tripcolor(tri, mag, shading="gouraud", cmap="viridis", vmin=0.0, vmax=umax, rasterized=True)
        rigid = g.global_points(0.0) * 1e3
        ax.add_collection(LineCollection(rigid[_boundary_polylines(g.triangles)], colors="0.5", linewidths=0.4))
        points += [ld.point for ld in g.loads if ld.force > 0]
    if points:
        p = np.array(points) * 1e3
        ax.plot(p[:, 0], p[:, 1], "r+", ms=6, mew=0.8, label="contact points")
    fig.colorbar(art, ax=ax, label="elastic displacement |u| (um)")
    ax.set_aspect("equal")
    if zoom is not None and points:
        c = np.mean(points, axis=0) * 1e3
        ax.set_xlim(c[0] - zoom * 1e3, c[0] + zoom * 1e3)
        ax.set_ylim(c[1] - zoom * 1e3, c[1] + zoom * 1e3)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"t = {frame.time:.5f} s, displacements x {scale:g} (grey: undeformed)", fontsize="medium")
    return fig
