"""3D tooth compliance of a gear sector extruded over its face width, against plane stress and strain.

The plane models are plane stress by default, but a spur tooth is not thin against its face
width, so the assumption is checked: the same sector (``n_teeth`` teeth, clamped on an arc at
``r_clamp``, radial cuts and end faces free) is meshed in 3D (gmsh extrusion, P2 tetrahedra) and
in 2D (P2 triangles of the same size), loaded by the flank patch load of
:mod:`flexgear.stiffness` uniform over the face width (unit resultant), and the work-conjugate
compliances compared: plane strain <= 3D <= plane stress (:func:`compare_formulations`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse.linalg as spla

from ..errors import ConfigError
from ..gears.geometry import FLANK
from ..gears.material import Material
from ..fe.loads import flank_patch_load
from ..fe.meshing import initialize_gmsh
from .compliance import DEFAULT_SPREAD, involute_arc


def sector_outline(gear, n_teeth: int = 3, r_clamp: float | None = None, ds: float | None = None):
    """Closed outline (CCW) of a sector of ``n_teeth`` teeth of an external gear.

        Parameters
        ----------
        gear : SpurGear
            External gear.
        n_teeth : int
            Odd number of teeth, centred on tooth 0 (on the +x axis).
        r_clamp : float, optional
            Radius of the clamped arc [m]; default r_f - 2 m (or the bore radius if larger).
        ds : float, optional
            Outline point spacing [m] (default m/40).

        Returns
        -------
        points : ndarray (N, 2)
            [m], counter-clockwise; the first ``n_arc`` points are the clamp arc.
        labels : ndarray (N,) of str
            Label of the edge starting at each point: 'clamp', 'cut', 'flank_left0' or 'outline'.
    """
    if gear.internal:
        raise ConfigError(f"{gear.name}: sector models are implemented for external gears")
    if n_teeth < 1 or n_teeth % 2 == 0:
        raise ConfigError(f"n_teeth = {n_teeth!r}: must be a positive odd number")
    m = gear.module
    if r_clamp is None:
        r_clamp = max(gear.rf - 2.0 * m, 0.5 * gear.bore_diameter)
    if not 0 < r_clamp < gear.rf:
        raise ConfigError(f"r_clamp = {r_clamp!r}: must lie in (0, r_f = {gear.rf})")
    ds = m / 40 if ds is None else ds
    one = gear.tooth_outline(ds)
    half = n_teeth // 2
    pts, lab = [], []
    # teeth from -half to +half, each from its -pi/z mid-space to +pi/z mid-space
    for k in range(-half, half + 1):
        a = 2 * math.pi * k / gear.z
        c, s = math.cos(a), math.sin(a)
        p = one.points @ np.array([[c, s], [-s, c]])
        lb = np.where((one.kind == FLANK) & (one.side > 0) & (k == 0), "flank_left0", "outline")
        if k != -half:
            p, lb = p[1:], lb[1:]
        pts.append(p)
        lab.append(lb)
    tooth = np.vstack(pts)
    tlab = np.concatenate(lab)
    # the point before the first flank_left0 point starts an edge on the flank as well
    # radial cut at the end, arc back, radial cut at the start
    phi1 = math.atan2(tooth[-1, 1], tooth[-1, 0])
    phi0 = math.atan2(tooth[0, 1], tooth[0, 0])
    r_end = np.hypot(*tooth[-1])
    ncut = max(2, int(math.ceil((r_end - r_clamp) / (4 * ds))))
    rr = np.linspace(r_end, r_clamp, ncut + 1)[1:]
    cut1 = np.column_stack([rr * math.cos(phi1), rr * math.sin(phi1)])
    narc = max(4, int(math.ceil(r_clamp * (phi1 - phi0) / (4 * ds))))
    th = np.linspace(phi1, phi0, narc + 1)[1:]
    arc = np.column_stack([r_clamp * np.cos(th), r_clamp * np.sin(th)])
    rr = np.linspace(r_clamp, np.hypot(*tooth[0]), ncut + 1)[1:-1]
    cut0 = np.column_stack([rr * math.cos(phi0), rr * math.sin(phi0)])
    points = np.vstack([tooth, cut1, arc, cut0])
    # label of the edge from point i to point i + 1 (cyclic)
    tedge = np.where((tlab[:-1] == "flank_left0") & (tlab[1:] == "flank_left0"), "flank_left0",
                     "outline")
    labels = np.concatenate([
        tedge,                                   # along the teeth
        ["cut"] * (len(cut1) + 1),               # tooth end -> ... -> last cut point (on arc)
        ["clamp"] * len(arc),                    # arc, ending at the arc's last point
        ["cut"] * len(cut0),                     # arc end -> ... -> first tooth point
    ])
    # the edge from the last cut1 point (on the arc) to the first arc point is on the arc
    labels[len(tedge) + len(cut1)] = "clamp"
    labels[len(tedge) + len(cut1) + len(arc)] = "cut"
    assert len(labels) == len(points)
    return points, labels


@dataclass
class SectorMesh:
    """Straight-sided mesh of a gear sector with the facets of the loaded flank and clamp.

    Attributes
    ----------
    mesh : skfem.MeshTri1 or skfem.MeshTet1
        With ``boundaries`` "flank" (left flank of the middle tooth) and "clamp" (and the crack
        faces "crack_body", "crack_tooth" of a cracked sector).
    dim : int
        2 or 3.
    info : dict
    gear_mesh : GearMesh or None
        A cracked 2D sector's mesh as a :class:`flexgear.fe.meshing.GearMesh` (order 1).
    """

    mesh: object
    dim: int
    info: dict = field(default_factory=dict)
    gear_mesh: object = None


def _facet_index(mesh, corner_sets):
    """skfem facet indices of facets given by their (sorted) corner vertex tuples."""
    f = np.sort(mesh.facets, axis=0).T
    lookup = {tuple(r): i for i, r in enumerate(f.tolist())}
    out = []
    for c in corner_sets:
        key = tuple(sorted(int(v) for v in c))
        if key in lookup:
            out.append(lookup[key])
    return np.array(sorted(set(out)), dtype=np.int64)


def mesh_sector(gear, *, dim: int = 3, h: float | None = None, h_body: float | None = None,
                n_teeth: int = 3, r_clamp: float | None = None, symmetric: bool = True,
                crack=None, crack_mesh=None) -> SectorMesh:
    """Mesh a gear sector in 2D (triangles) or 3D (tetrahedra, extruded over the face width).

        Parameters
        ----------
        gear : SpurGear
            External gear (face width = extrusion length).
        dim : {2, 3}
        h, h_body : float, optional
            Element size on the tooth outline (default 0.5 m) and away from it (default 2 h) [m].
        n_teeth, r_clamp
            See :func:`sector_outline`.
        symmetric : bool
            3D only: mesh z in [0, b/2] with the mid-plane as boundary "symmetry" (u_z = 0); the
            compliance is that of the full width.
        crack : RootCrack, optional
            2D only: a root crack of tooth 0 meshed as a slit refined at its tip (``crack_mesh``:
            :class:`~flexgear.fe.crack.CrackMesh`).

        Returns
        -------
        SectorMesh
    """
    import gmsh
    from skfem import MeshTet1, MeshTri1

    if dim not in (2, 3):
        raise ConfigError(f"dim = {dim!r}: must be 2 or 3")
    m = gear.module
    h = 0.5 * m if h is None else h
    h_body = 2.0 * h if h_body is None else h_body
    pts, labels = sector_outline(gear, n_teeth, r_clamp)
    feature, i_start = None, None
    if crack is not None:
        from ..fe.crack import CrackFeature

        if dim != 2 or crack.tooth != 0:
            raise ConfigError("mesh_sector: a crack needs dim = 2 and the crack on tooth 0")
        feature = CrackFeature(crack, h, crack_mesh)
        pts, (labels,), i_start = feature.place(pts, labels)
    b = gear.face_width
    t0 = time.perf_counter()
    owner = not gmsh.isInitialized()
    if owner:
        initialize_gmsh(gmsh)
    gmsh.option.setNumber("General.Terminal", 0)
    name = f"fe3d_sector_{id(pts)}"
    gmsh.model.add(name)
    try:
        geo = gmsh.model.geo
        n = len(pts)
        ptags = [geo.addPoint(x, y, 0.0, h) for x, y in pts]
        # group consecutive edges with the same label into splines (lines for cuts/clamp)
        starts = [i for i in range(n) if labels[i] != labels[i - 1] or i == i_start]
        curves, curve_lab = [], []
        for j, s in enumerate(starts):
            e = starts[(j + 1) % len(starts)]
            idx = list(range(s, e + 1)) if e > s else list(range(s, n)) + list(range(0, e + 1))
            tags = [ptags[i % n] for i in idx]
            lab = labels[s]
            if lab == "cut" or len(tags) == 2:
                for a_, b_ in zip(tags[:-1], tags[1:]):
                    curves.append(geo.addLine(a_, b_))
                    curve_lab.append(lab)
            else:
                curves.append(geo.addSpline(tags))
                curve_lab.append(lab)
        loop = geo.addCurveLoop(curves)
        surf = geo.addPlaneSurface([loop])
        fine = [c for c, l in zip(curves, curve_lab) if l in ("outline", "flank_left0")]
        if dim == 3:
            ext = geo.extrude([(2, surf)], 0.0, 0.0, 0.5 * b if symmetric else b)
        crack_curves = [] if feature is None else feature.curves(geo, ptags, h)["crack"]
        geo.synchronize()
        if crack_curves:
            gmsh.model.mesh.embed(1, crack_curves, 2, surf)
        fm = gmsh.model.mesh.field
        d = fm.add("Distance")
        if dim == 2:
            fm.setNumbers(d, "CurvesList", fine)
        else:
            # lateral surfaces generated from the toothed curves
            # extrude returns the top surface, the volume, then one lateral surface per
            # boundary curve of the base surface, in the order of the curve loop
            lat = [e[1] for e in ext[2:] if e[0] == 2]
            fine_s = [s_ for s_, l in zip(lat, curve_lab) if l in ("outline", "flank_left0")]
            fm.setNumbers(d, "SurfacesList", fine_s)
        fm.setNumber(d, "Sampling", 60)
        th_ = fm.add("Threshold")
        fm.setNumber(th_, "InField", d)
        fm.setNumber(th_, "SizeMin", h)
        fm.setNumber(th_, "SizeMax", h_body)
        fm.setNumber(th_, "DistMin", 1.0 * m)
        fm.setNumber(th_, "DistMax", 3.0 * m)
        fm.setAsBackgroundMesh(th_ if feature is None else feature.fields(gmsh, th_))
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.5 * h if feature is None else min(0.5 * h, feature.size_min))
        gmsh.option.setNumber("Mesh.MeshSizeMax", h_body)
        gmsh.option.setNumber("Mesh.ElementOrder", 1)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.mesh.generate(dim)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        xyz = np.asarray(coords).reshape(-1, 3)
        tag2row = np.full(int(np.max(tags)) + 1, -1, np.int64)
        tag2row[np.asarray(tags, np.int64)] = np.arange(len(tags))
        etype = 4 if dim == 3 else 2
        _, enodes = gmsh.model.mesh.getElementsByType(etype)
        cells = tag2row[np.asarray(enodes, np.int64)].reshape(-1, dim + 1)
        # boundary entities of the loaded flank and the clamp
        if dim == 2:
            ents = {"flank": [c for c, l in zip(curves, curve_lab) if l == "flank_left0"],
                    "clamp": [c for c, l in zip(curves, curve_lab) if l == "clamp"]}
            ftype = 1
        else:
            ents = {"flank": [s_ for s_, l in zip(lat, curve_lab) if l == "flank_left0"],
                    "clamp": [s_ for s_, l in zip(lat, curve_lab) if l == "clamp"]}
            if symmetric:
                ents["symmetry"] = [ext[0][1]]
            ftype = 2
        if crack_curves:
            ents["crack"] = crack_curves
        bfac = {}
        for key, es in ents.items():
            allf = []
            for e in es:
                _, fn = gmsh.model.mesh.getElementsByType(ftype, e)
                allf.append(tag2row[np.asarray(fn, np.int64)].reshape(-1, dim))
            bfac[key] = np.vstack(allf)
    finally:
        gmsh.model.remove()
        if owner:
            gmsh.finalize()
    used = np.unique(cells)
    remap = np.full(len(xyz), -1, np.int64)
    remap[used] = np.arange(len(used))
    P = xyz[used, :dim].T.copy()
    T = remap[cells].T.copy()
    gear_mesh = None
    if feature is not None:
        from ..fe.meshing import GearMesh

        gear_mesh = feature.finish(GearMesh(P.T, T.T, 1, {k: remap[v] for k, v in bfac.items()}))
        P, T = gear_mesh.points.T.copy(), gear_mesh.triangles.T.copy()
        bfac = {k: v for k, v in gear_mesh.facet_groups.items()}
    if dim == 2:
        # counter-clockwise triangles
        p0, p1, p2 = (P[:, T[i]] for i in range(3))
        neg = ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0])) < 0
        T[1, neg], T[2, neg] = T[2, neg].copy(), T[1, neg].copy()
        mesh = MeshTri1(P, T)
    else:
        mesh = MeshTet1(P, T)
    bnd = {k: _facet_index(mesh, v if feature is not None else remap[v]) for k, v in bfac.items()}
    for k, v in bnd.items():
        if v.size == 0:
            raise RuntimeError(f"sector mesh: boundary {k!r} not found")
    mesh = mesh.with_boundaries(bnd)
    # the boundaries must be where the outline says (guards the curve/surface bookkeeping)
    rc = np.hypot(*mesh.p[:2, np.unique(mesh.facets[:, bnd["clamp"]])])
    r_clamp_ = np.hypot(*pts[labels == "clamp"][0])
    if not np.allclose(rc, r_clamp_, rtol=1e-3):
        raise RuntimeError("sector mesh: clamp facets are not on the clamp arc")
    xf = mesh.p[:2, np.unique(mesh.facets[:, bnd["flank"]])]
    rf_ = np.hypot(*xf)
    if not np.allclose(np.arctan2(xf[1], xf[0]), gear.involute_half_angle(rf_), atol=0.02 / gear.z):
        raise RuntimeError("sector mesh: flank facets are not on the left flank of tooth 0")
    info = {"h": h, "h_body": h_body, "n_teeth": n_teeth, "seconds": time.perf_counter() - t0,
            "n_elements": int(mesh.nelements), "n_vertices": int(mesh.nvertices),
            "symmetric": bool(symmetric and dim == 3)}
    return SectorMesh(mesh=mesh, dim=dim, info=info, gear_mesh=gear_mesh)


def assemble_sector(sm: SectorMesh, material: Material, formulation: str, thickness: float):
    """Stiffness of a sector mesh: (K [N/m], basis, thickness factor); P2 elements, 2D plane stress
    or strain of ``thickness`` [m], or 3D ("3d", thickness factor 1)."""
    from skfem import Basis, BilinearForm, ElementTetP2, ElementTriP2, ElementVector
    from skfem.helpers import ddot, eye, sym_grad, trace

    E, nu = material.E, material.nu
    mu = E / (2 * (1 + nu))
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    if sm.dim == 2:
        if formulation == "plane_stress":
            lam = 2 * lam * mu / (lam + 2 * mu)
        elif formulation != "plane_strain":
            raise ConfigError(f"formulation = {formulation!r}: 2D needs plane_stress or plane_strain")
        elem = ElementVector(ElementTriP2())
        t = thickness
    else:
        elem = ElementVector(ElementTetP2())
        t = 1.0
    basis = Basis(sm.mesh, elem, intorder=2)  # exact for P2 stiffness on straight elements
    d = sm.dim

    @BilinearForm
    def stiff(u, v, w):
        e = sym_grad(u)
        return t * ddot(2 * mu * e + lam * eye(trace(e), d), sym_grad(v))

    return stiff.assemble(basis).tocsr(), basis, t


def flank_compliance(gear, sm: SectorMesh, *, formulation: str = "3d",
                     material: Material | None = None, radius: float | None = None,
                     spread: float = DEFAULT_SPREAD) -> float:
    """Compliance [m/N] of the middle tooth under a unit line load across the face width.

        Parameters
        ----------
        gear : SpurGear
        sm : SectorMesh
            From :func:`mesh_sector` (2D or 3D).
        formulation : {"3d", "plane_stress", "plane_strain"}
            Must be "3d" for a 3D mesh.
        material : Material, optional
        radius : float, optional
            Contact radius [m] (default: reference circle).
        spread : float
            Patch half-width in modules.

        Returns
        -------
        float
            f . u for the unit-resultant patch load [m/N].
    """
    from skfem import FacetBasis

    material = Material() if material is None else material
    if (sm.dim == 3) != (formulation == "3d"):
        raise ConfigError(f"formulation {formulation!r} does not match a {sm.dim}D mesh")
    K, basis, t = assemble_sector(sm, material, formulation, gear.face_width)
    r = gear.r if radius is None else radius
    Sc = float(involute_arc(gear, r))
    w = spread * gear.module
    rb = gear.rb
    fb = FacetBasis(sm.mesh, basis.elem, facets=sm.mesh.boundaries["flank"], intorder=6)

    f = flank_patch_load(fb, rb, Sc, w, t, sm.dim, f"{gear.name}: load patch at r = {r*1e3:.4g} mm")
    fixed = basis.get_dofs(sm.mesh.boundaries["clamp"]).flatten()
    half = "symmetry" in sm.mesh.boundaries
    if half:
        sym = basis.get_dofs(sm.mesh.boundaries["symmetry"]).keep("u^3").flatten()
        fixed = np.concatenate([fixed, sym])
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    u = np.zeros(K.shape[0])
    lu = spla.splu(K[free][:, free].tocsc(), permc_spec="COLAMD")
    u[free] = lu.solve(f[free])
    # a unit load on half the width displaces twice as much as on the full width
    return float(f @ u) / (2.0 if half else 1.0)


@dataclass
class FormulationComparison:
    """Compliances [m/N] of the same sector and load in 3D, plane stress and plane strain.

    Attributes
    ----------
    c3d, c_stress, c_strain : float
    info : dict
        Mesh sizes, dof counts and times.
    """

    c3d: float
    c_stress: float
    c_strain: float
    info: dict

    @property
    def plane_stress_error(self) -> float:
        """(c_stress - c3d) / c3d: plane stress overestimates the compliance by this [-]."""
        return (self.c_stress - self.c3d) / self.c3d

    @property
    def plane_strain_error(self) -> float:
        """(c_strain - c3d) / c3d [-] (negative: plane strain too stiff)."""
        return (self.c_strain - self.c3d) / self.c3d

    @property
    def position(self) -> float:
        """Where 3D lies between plane strain (0) and plane stress (1) [-]."""
        return (self.c3d - self.c_strain) / (self.c_stress - self.c_strain)


def compare_formulations(gear, *, h: float | None = None, h2d: float | None = None,
                         n_teeth: int = 3, material: Material | None = None,
                         spread: float = DEFAULT_SPREAD, radius: float | None = None) -> FormulationComparison:
    """Pitch-point tooth compliance of a gear sector: 3D vs plane stress vs plane strain.

        Parameters
        ----------
        gear : SpurGear
            External gear; its face width is the extrusion length / plane thickness.
        h, h2d : float, optional
            3D element size on the teeth (default 0.5 m) and 2D size (default: the same) [m].
        n_teeth : int
            Teeth in the sector.
        material : Material, optional
        spread : float
            Patch half-width in modules.
        radius : float, optional
            Contact radius [m] (default reference circle).
    """
    t0 = time.perf_counter()
    m3 = mesh_sector(gear, dim=3, h=h, n_teeth=n_teeth)
    m2 = mesh_sector(gear, dim=2, h=h2d if h2d is not None else h, n_teeth=n_teeth)
    kw = dict(material=material, spread=spread, radius=radius)
    c3 = flank_compliance(gear, m3, formulation="3d", **kw)
    cs = flank_compliance(gear, m2, formulation="plane_stress", **kw)
    ce = flank_compliance(gear, m2, formulation="plane_strain", **kw)
    info = {"mesh3d": m3.info, "mesh2d": m2.info, "seconds": time.perf_counter() - t0}
    return FormulationComparison(c3, cs, ce, info)


def main(argv=None) -> int:
    """``python -m flexgear.stiffness.compliance3d``: pitch-point compliance of the MERCURY 1-A sun, 3D vs 2D."""
    import argparse

    from ..config import load_config

    ap = argparse.ArgumentParser(prog="python -m flexgear.stiffness.compliance3d", description=main.__doc__)
    ap.add_argument("--gear", default="sun")
    ap.add_argument("--h", type=float, nargs="+", default=[1.0e-3],
                    help="element sizes on the teeth [m] (one run each)")
    ap.add_argument("--teeth", type=int, default=3)
    a = ap.parse_args(argv)
    cfg = load_config("mercury_1a")
    g = cfg.gears[a.gear]
    for h in a.h:
        r = compare_formulations(g, h=h, n_teeth=a.teeth, material=cfg.material)
        print(f"{g.name}, {a.teeth} teeth, h = {h*1e3:.3g} mm ({r.info['mesh3d']['n_elements']} tets): "
              f"3D {r.c3d:.5e}, plane stress {r.c_stress:.5e}, plane strain {r.c_strain:.5e} m/N; "
              f"plane-stress error {r.plane_stress_error*100:+.2f} %, plane-strain error "
              f"{r.plane_strain_error*100:+.2f} %, 3D at {r.position:.2f} of the way from strain "
              f"to stress ({r.info['seconds']:.0f} s)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
