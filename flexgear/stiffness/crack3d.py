"""A root crack over part of the face width: a 3D sector against the plane model's slices.

Checks :func:`flexgear.stiffness.crack.partial_width_stiffness` against the cracked 2D sector of
:func:`~flexgear.stiffness.compliance3d.mesh_sector` extruded in layers over half the face width
(mid-plane a plane of symmetry, crack centred on the width, P2 tetrahedra; half a model keeps
the sparse LU within reach). The contact line is held straight (the mating tooth is much
stiffer along it than the tooth in bending): the patch load on ``strips`` strips gives a
compliance matrix C and the stiffness ``k = 1' C^-1 1``. Plane-stress slices are a lower bound
of the 3D stiffness (slices free of shear across the cuts are less constrained). See the theory
page *Root crack*, section *A crack over part of the face width*.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse.linalg as spla

from ..errors import ConfigError
from ..fe.crack import CrackMesh, RootCrack, crack_node_pairs
from ..fe.loads import flank_patch_load
from ..gears.material import Material
from .compliance import DEFAULT_SPREAD, involute_arc
from .compliance3d import SectorMesh, assemble_sector, mesh_sector


#: Crack-tip refinement of the 3D check (coarser than the gear meshes': the check compares the
#: 3D and plane models on one discretisation).
SECTOR_CRACK_MESH = CrackMesh(tip_size=0.25, grading=0.5)


def glued_sector(sm: SectorMesh) -> SectorMesh:
    """The healthy 2D sector on the same triangulation as the cracked ``sm`` (crack faces joined)."""
    from skfem import MeshTri1

    gm = sm.gear_mesh
    pairs = crack_node_pairs(gm)
    T, keep = _unsplit(gm, pairs)
    P = gm.points[keep]
    new = np.full(gm.n_nodes, -1, np.int64)
    new[keep] = np.arange(len(keep))
    mesh = MeshTri1(P.T.copy(), new[T].T.copy())
    bnd = {}
    for name in ("flank", "clamp"):
        e = new[_unsplit_cells(gm.facet_groups[name], pairs)]
        bnd[name] = _facets(mesh, e)
    return SectorMesh(mesh=mesh.with_boundaries(bnd), dim=2, info=dict(sm.info))


def _unsplit_cells(cells, pairs):
    orig = np.arange(max(int(cells.max()), int(pairs.max())) + 1)
    orig[pairs[:, 1]] = pairs[:, 0]
    return orig[cells]


def _unsplit(gm, pairs):
    """(triangles with the crack faces' copies replaced by the originals, indices of used nodes)."""
    T = _unsplit_cells(gm.triangles, pairs)
    return T, np.setdiff1d(np.arange(gm.n_nodes), pairs[:, 1])


def _facets(mesh, corners) -> np.ndarray:
    """skfem facet indices of the facets with the given corner node tuples (rows)."""
    f = np.sort(mesh.facets, axis=0).T
    lookup = {tuple(r): i for i, r in enumerate(f.tolist())}
    idx = [lookup.get(tuple(sorted(int(v) for v in c))) for c in corners]
    if any(i is None for i in idx):
        raise RuntimeError("sector mesh: a boundary facet is not a mesh facet")
    return np.array(sorted(set(idx)), dtype=np.int64)


def layer_levels(width: float, fraction: float, first: float, growth: float = 1.5,
                 largest: float | None = None) -> np.ndarray:
    """z levels over [0, width] [m] with one at fraction * width, layers of thickness ``first``
    next to it growing by ``growth`` up to ``largest`` away from it (both sides)."""
    largest = width / 4 if largest is None else largest
    zf = fraction * width

    def side(length):
        if length <= 0:
            return np.zeros(0)
        t, steps = first, []
        while sum(steps) + t < length - 1e-12:
            steps.append(t)
            t = min(t * growth, largest)
        steps.append(length - sum(steps))
        if len(steps) > 1 and steps[-1] < 0.5 * steps[-2]:  # no sliver at the end
            steps[-2] += steps.pop()
        return np.cumsum(steps)

    up = zf + side(width - zf)
    down = zf - side(zf)
    return merge_levels(np.concatenate([[0.0, zf, width], up, down]), width)


def merge_levels(z, width: float) -> np.ndarray:
    """Sorted levels in [0, width] with those closer than 1e-9 width to a kept one dropped (0 and
    ``width`` kept exactly)."""
    tol = 1e-9 * width
    z = np.sort(np.clip(np.asarray(z, float), 0.0, width))
    out = [0.0]
    for v in z:
        if v - out[-1] > tol:
            out.append(float(v))
    out[-1] = width if width - out[-1] <= tol else out[-1]
    if out[-1] != width:
        out.append(width)
    return np.array(out)


def extrude_sector(sm: SectorMesh, gear, fraction: float, z) -> SectorMesh:
    """3D half sector from the cracked 2D sector ``sm``: layers at the levels ``z`` [m] (from 0 to
    b/2, including z_f = (1 - fraction) b/2), the crack open for z >= z_f, boundary "symmetry" at
    z = b/2 (module docstring). ``fraction`` 0: healthy, 1: through the width."""
    from skfem import MeshTet1

    gm = sm.gear_mesh
    pairs = crack_node_pairs(gm)
    T2, keep = _unsplit(gm, pairs)
    new = np.full(gm.n_nodes, -1, np.int64)
    new[keep] = np.arange(len(keep))
    tooth_side = np.isin(gm.triangles, pairs[:, 1]).any(axis=1)
    T2 = new[T2]
    cn = new[pairs[:, 0]]  # crack nodes of the glued mesh (tip excluded)
    P2 = gm.points[keep]
    n2 = len(P2)
    z = np.asarray(z, float)
    half = 0.5 * gear.face_width
    zf = (1.0 - fraction) * half
    tol = 1e-9 * half
    L = len(z) - 1
    if not (abs(z[0]) < 1e-12 and abs(z[-1] - half) < tol):
        raise ConfigError("extrude_sector: levels must run from 0 to half the face width")
    if fraction > 0 and not np.any(np.isclose(z, zf, rtol=0, atol=tol)):
        raise ConfigError(f"extrude_sector: no level at the crack's end z = {zf:.6g} m")
    P = np.column_stack([np.tile(P2, (L + 1, 1)), np.repeat(z, n2)])
    # copies of the crack nodes on the levels below the crack's end
    if fraction <= 0:
        open_lv = np.zeros(0, np.int64)
    else:
        open_lv = np.arange(L + 1) if fraction >= 1.0 else np.flatnonzero(z > zf + tol)
    dup = np.full((L + 1, n2), -1, np.int64)
    nxt = len(P)
    for lv in open_lv:
        dup[lv, cn] = nxt + np.arange(len(cn))
        nxt += len(cn)
    extra = [np.column_stack([P2[cn], np.full(len(cn), z[lv])]) for lv in open_lv]
    if extra:
        P = np.vstack([P] + extra)
    v = np.sort(T2, axis=1)
    tets = []
    for lv in range(L):
        b, t = v + lv * n2, v + (lv + 1) * n2
        cells = np.concatenate([np.column_stack([b[:, 0], b[:, 1], b[:, 2], t[:, 0]]),
                                np.column_stack([b[:, 1], b[:, 2], t[:, 0], t[:, 1]]),
                                np.column_stack([b[:, 2], t[:, 0], t[:, 1], t[:, 2]])])
        side = np.tile(tooth_side, 3)
        if fraction > 0 and z[lv] >= zf - tol:  # the layer lies on the open crack
            sub = cells[side]
            lvl = sub // n2
            d = dup[lvl, sub % n2]
            cells[side] = np.where(d >= 0, d, sub)
        tets.append(cells)
    tets = np.vstack(tets)
    p = P[tets]
    vol = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    neg = vol < 0
    tets[neg] = tets[neg][:, [0, 2, 1, 3]]
    mesh = MeshTet1(P.T.copy(), tets.T.copy())
    # boundaries: clamp (all corners on the clamp arc) and the loaded flank (lateral facets over
    # the 2D flank's nodes)
    bf = mesh.boundary_facets()
    fn = mesh.facets[:, bf]
    base = np.where(fn < len(P2) * (L + 1), fn % n2, -1)
    dn = fn >= n2 * (L + 1)
    if np.any(dn):  # a copy: its 2D node
        rows = np.argwhere(dup >= 0)
        owner = np.full(nxt, -1, np.int64)
        owner[dup[rows[:, 0], rows[:, 1]]] = rows[:, 1]
        base[dn] = owner[fn[dn]]
    r_cl = np.hypot(*P2[np.unique(new[_unsplit_cells(gm.facet_groups["clamp"], pairs)])].T).mean()
    on_clamp = np.all(np.abs(np.hypot(*P2[base].transpose(2, 0, 1)) - r_cl) < 1e-9 * r_cl, axis=0)
    flank_nodes = np.unique(new[_unsplit_cells(gm.facet_groups["flank"], pairs)])
    on_flank = np.all(np.isin(base, flank_nodes), axis=0)
    nz = np.abs(np.cross(P[fn[1]] - P[fn[0]], P[fn[2]] - P[fn[0]])[:, 2])
    area2 = np.linalg.norm(np.cross(P[fn[1]] - P[fn[0]], P[fn[2]] - P[fn[0]]), axis=1)
    lateral = nz < 0.5 * area2
    on_sym = np.all(np.abs(P[fn, 2] - half) < tol, axis=0)
    mesh = mesh.with_boundaries({"clamp": bf[on_clamp & lateral], "flank": bf[on_flank & lateral],
                                 "symmetry": bf[on_sym]})
    info = {"n_elements": int(mesh.nelements), "n_vertices": int(mesh.nvertices), "levels": z.tolist(),
            "fraction": float(fraction)}
    return SectorMesh(mesh=mesh, dim=3, info=info)


def strip_stiffness(gear, sm: SectorMesh, material: Material, formulation: str, radius: float,
                    strips: int = 1, spread: float = DEFAULT_SPREAD) -> tuple[float, float]:
    """(rigid-line stiffness [N/m], uniform-load compliance [m/N]) of the sector's flank patch at
    ``radius``, for the whole face width (module docstring); 2D models: strips = 1, the two are
    1/c and c; a 3D half sector (boundary "symmetry") counts twice."""
    from skfem import FacetBasis

    K, basis, t = assemble_sector(sm, material, formulation, gear.face_width)
    Sc = float(involute_arc(gear, radius))
    w = spread * gear.module
    facets = sm.mesh.boundaries["flank"]
    if sm.dim == 2 or strips == 1:
        groups = [facets]
    else:
        zc = sm.mesh.p[2, sm.mesh.facets[:, facets]].mean(axis=0)
        edges = np.linspace(0.0, 0.5 * gear.face_width, strips + 1)
        groups = [facets[(zc >= a) & (zc < b)] for a, b in zip(edges[:-1], edges[1:])]
    F = np.column_stack([flank_patch_load(FacetBasis(sm.mesh, basis.elem, facets=g, intorder=6), gear.rb,
                                          Sc, w, t, sm.dim, f"{gear.name}: patch strip") for g in groups])
    fixed = basis.get_dofs(sm.mesh.boundaries["clamp"]).flatten()
    half = "symmetry" in sm.mesh.boundaries
    if half:
        fixed = np.concatenate([fixed, basis.get_dofs(sm.mesh.boundaries["symmetry"]).keep("u^3").flatten()])
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    U = np.zeros_like(F)
    # K is symmetric positive definite: symmetric ordering, no pivoting (half SuperLU's fill)
    lu = spla.splu(K[free][:, free].tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    U[free] = lu.solve(np.ascontiguousarray(F[free]))
    C = F.T @ U
    one = np.ones(len(groups))
    n = 2.0 if half else 1.0  # the mirror half carries as much
    return n * float(one @ np.linalg.solve(C, one)), float(one @ C @ one) / len(groups) ** 2 / n


@dataclass
class PartialCrackCheck:
    """3D sector with a crack over a fraction of the face width against plane-model slices.

    Attributes
    ----------
    fractions : ndarray (F,)
        Cracked fractions of the face width [-] (0: healthy, 1: through).
    k3d : ndarray (F,)
        3D rigid-line stiffness of the sector [N/m].
    k_stress, k_strain : tuple(float, float)
        Plane stress / plane strain stiffness of the sector, (healthy, through crack) [N/m].
    info : dict
    """

    fractions: np.ndarray
    k3d: np.ndarray
    k_stress: tuple
    k_strain: tuple
    info: dict = field(default_factory=dict)

    def slices(self, which: str = "3d") -> np.ndarray:
        """Slices-in-parallel stiffness at :attr:`fractions` [N/m] from the healthy and through-crack
        stiffness of ``which``: "3d" (the 3D sector's own f = 0 and f = 1 values), "plane_stress"
        or "plane_strain"."""
        if which == "3d":
            k0, k1 = float(np.interp(0.0, self.fractions, self.k3d)), float(np.interp(1.0, self.fractions, self.k3d))
        else:
            k0, k1 = self.k_stress if which == "plane_stress" else self.k_strain
        return self.fractions * k1 + (1.0 - self.fractions) * k0

    def slice_error(self, which: str = "3d") -> np.ndarray:
        """Slices over 3D, minus 1 [-] (negative: the slices are softer)."""
        return self.slices(which) / self.k3d - 1.0


def partial_crack_check(gear, crack: RootCrack, fractions=(0.0, 0.5, 1.0), *, h: float | None = None,
                        n_teeth: int = 1, strips: int = 4, first_layer: float | None = None,
                        radius: float | None = None, material: Material | None = None,
                        crack_mesh: CrackMesh | None = None, log=None) -> PartialCrackCheck:
    """Rigid-line stiffness of a sector with ``crack`` over each fraction of the face width, 3D against the plane models.

        Parameters
        ----------
        gear : SpurGear
        crack : RootCrack
            On tooth 0 (:func:`flexgear.fe.crack.root_crack`).
        fractions : sequence of float
            Cracked fractions of the face width (centred); must include 0 and 1.
        h : float, optional
            Element size on the teeth [m] (default 0.5 m).
        n_teeth : int
            Teeth in the sector (odd).
        strips : int
            Strips of half the contact line (the rigid-line constraint).
        first_layer : float, optional
            Layer thickness next to the crack's end across the width [m] (default h / 2).
        radius : float, optional
            Contact radius [m] (default: the reference circle).
    """
    fr = np.asarray(sorted(set(float(f) for f in fractions)))
    if fr[0] != 0.0 or fr[-1] != 1.0 or np.any((fr < 0) | (fr > 1)):
        raise ConfigError(f"fractions = {list(fractions)}: must lie in [0, 1] and include 0 and 1")
    material = Material() if material is None else material
    h = 0.5 * gear.module if h is None else h
    first = h / 2 if first_layer is None else first_layer
    radius = gear.r if radius is None else radius
    t0 = time.perf_counter()
    crack_mesh = SECTOR_CRACK_MESH if crack_mesh is None else crack_mesh
    sm2 = mesh_sector(gear, dim=2, h=h, n_teeth=n_teeth, crack=crack, crack_mesh=crack_mesh)
    healthy2 = glued_sector(sm2)
    k_stress = tuple(strip_stiffness(gear, s, material, "plane_stress", radius)[0] for s in (healthy2, sm2))
    k_strain = tuple(strip_stiffness(gear, s, material, "plane_strain", radius)[0] for s in (healthy2, sm2))
    k3d, info = [], {"mesh2d": sm2.info, "h": h, "strips": strips, "first_layer": first}
    for f in fr:
        ts = time.perf_counter()
        half = 0.5 * gear.face_width
        z = merge_levels(np.concatenate([layer_levels(half, 1.0 - f, first, largest=h),
                                         np.linspace(0.0, half, strips + 1)]), half)
        sm3 = extrude_sector(sm2, gear, f, z)
        k, _ = strip_stiffness(gear, sm3, material, "3d", radius, strips)
        k3d.append(k)
        info[f"f={f:g}"] = {"tets": sm3.info["n_elements"], "layers": len(z) - 1,
                            "seconds": time.perf_counter() - ts}
        if log:
            log(f"f = {f:g}: {sm3.info['n_elements']} tets, {len(z) - 1} layers, k = {k:.6g} N/m "
                f"({time.perf_counter() - ts:.0f} s)")
    info["seconds"] = time.perf_counter() - t0
    return PartialCrackCheck(fractions=fr, k3d=np.array(k3d), k_stress=k_stress, k_strain=k_strain, info=info)


def main(argv=None) -> int:
    """``python -m flexgear.stiffness.crack3d``: a root crack over part of the face width, 3D sector
    against plane-model slices."""
    import argparse

    from ..config import load_config
    from ..fe.crack import root_crack

    ap = argparse.ArgumentParser(prog="python -m flexgear.stiffness.crack3d", description=main.__doc__)
    ap.add_argument("--preset", default="spur_pair")
    ap.add_argument("--gear", default="pinion")
    ap.add_argument("--depth", type=float, default=1.0e-3, help="crack length [m]")
    ap.add_argument("--angle-deg", type=float, default=45.0)
    ap.add_argument("--fractions", type=float, nargs="+", default=[0.0, 0.25, 0.5, 0.75, 1.0])
    ap.add_argument("--h", type=float, default=None, help="element size on the tooth [m]")
    ap.add_argument("--strips", type=int, default=4)
    a = ap.parse_args(argv)
    cfg = load_config(a.preset)
    g = cfg.gears[a.gear]
    c = root_crack(g, a.depth, math.radians(a.angle_deg))
    r = partial_crack_check(g, c, a.fractions, h=a.h, strips=a.strips, material=cfg.material, log=print)
    print(f"{g.name}: crack {a.depth*1e3:g} mm at {a.angle_deg:g} deg, contact at the reference circle")
    print("fraction   k3d [N/m]     slices(3D ends)  slices(plane stress)  slices(plane strain)")
    for f, k, e3, es, ee in zip(r.fractions, r.k3d, r.slice_error("3d"), r.slice_error("plane_stress"),
                                r.slice_error("plane_strain")):
        print(f"{f:8.3g}   {k:.6e}   {e3*100:+8.2f} %      {es*100:+8.2f} %            {ee*100:+8.2f} %")
    print(f"({r.info['seconds']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
