"""Triangle meshes of planar gear bodies with the gmsh Python API, cached on disk.

Pipeline position: ``geometry -> meshing -> fe``. :func:`mesh_gear` turns a
:class:`flexgear.gears.geometry.SpurGear` outline into a :class:`GearMesh`; :func:`mesh_polygon`
meshes any polygon/circle domain (verification tests).

Sizes scale with the module m and shrink by sqrt(2) per refinement ``level`` (0..5):
``h_tooth = H_TOOTH m / sqrt(2)**level`` within ``DIST_FINE * m`` of the toothed outline,
growing linearly to ``h_body = H_BODY m / sqrt(2)**level`` over ``DIST_GRADE * m`` (default
level 2: h_tooth = 0.25 m).

Cache: per user (:func:`mesh_cache_dir`: ``$FLEXGEAR_CACHE_DIR/meshes``, else e.g.
``~/.cache/flexgear/meshes``); ``cache_dir=None`` disables it. A mesh is ``<sha256>.vtu``
(meshio) plus a ``<sha256>.json`` sidecar holding the key (gear parameters, outline fingerprint,
mesh settings, gmsh version, :data:`FORMAT_VERSION`), the ``.vtu``'s SHA-256 and the group
names; a missing, corrupt or stale pair is rebuilt. Both are written to temporary names and
moved into place (:func:`os.replace`), the sidecar last.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import math
import os
import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, NamedTuple, Sequence

import numpy as np

from ..errors import ConfigError, GeometryError
from ..files import atomic_write, atomic_write_json, discard_files, entry_lock, jsonable, sha256_file, user_cache_dir
from ..gears.geometry import gear_parameters

log = logging.getLogger(__name__)

#: Bump when the cache layout or the meshing algorithm changes (invalidates old caches).
FORMAT_VERSION = 1

#: Tooth size constant: h_tooth = H_TOOTH * module / sqrt(2)**level.
H_TOOTH = 0.5
#: Body size constant: h_body = H_BODY * module / sqrt(2)**level.
H_BODY = 2.0
#: Distance (in modules) from the toothed outline within which h_tooth is used.
DIST_FINE = 1.0
#: Distance (in modules) over which the size grows from h_tooth to h_body.
DIST_GRADE = 3.0
#: Allowed refinement levels.
LEVELS = range(0, 6)

# outline point kinds (same values as flexgear.geometry; repeated so meshing does not import it)
_ROOT, _FILLET, _FLANK, _TIP = 0, 1, 2, 3

# gmsh element type ids
_GMSH_LINE = {1: 1, 2: 8}
_GMSH_TRI = {1: 2, 2: 9}
_MESHIO_LINE = {1: "line", 2: "line3"}
_MESHIO_TRI = {1: "triangle", 2: "triangle6"}


# --------------------------------------------------------------------------------------------
# settings
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MeshSettings:
    """Mesh refinement settings of a gear body.

    Parameters
    ----------
    level : int
        Refinement level, 0 (coarsest) .. 5. Element sizes shrink by sqrt(2) per level
        (see module docstring). Default 2.
    order : int
        Geometric and interpolation order of the triangles: 1 (3-node) or 2 (6-node,
        curved boundaries). Default 2.
    min_ligament : float
        Smallest allowed radial ligament between bore and root circle of an external gear,
        in modules [-]. Default 0.5.
    min_rim : float
        Smallest allowed rim thickness (rim radius minus root radius) of an internal gear, in
        modules [-]. Default 1.0.

    Raises
    ------
    ConfigError
        If a value is out of range; the message names parameter, value and rule.
    """

    level: int = 2
    order: int = 2
    min_ligament: float = 0.5
    min_rim: float = 1.0

    def __post_init__(self):
        lv = self.level
        if isinstance(lv, bool) or not isinstance(lv, (int, np.integer)) or lv not in LEVELS:
            raise ConfigError(
                f"mesh.level = {lv!r}: refinement level must be an integer in "
                f"{LEVELS.start}..{LEVELS.stop - 1}")
        if isinstance(self.order, bool) or self.order not in (1, 2):
            raise ConfigError(f"mesh.order = {self.order!r}: element order must be 1 or 2")
        for name in ("min_ligament", "min_rim"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ConfigError(f"mesh.{name} = {v!r}: must be a finite number >= 0 (modules)")

    def sizes(self, module: float) -> tuple[float, float]:
        """Target element sizes ``(h_tooth, h_body)`` [m] for a gear of module ``module`` [m]."""
        f = math.sqrt(2.0) ** self.level
        return H_TOOTH * module / f, H_BODY * module / f

    def key(self) -> dict:
        """Everything about the settings that changes the mesh (for the cache hash)."""
        return {"level": int(self.level), "order": int(self.order), "H_TOOTH": H_TOOTH,
                "H_BODY": H_BODY, "DIST_FINE": DIST_FINE, "DIST_GRADE": DIST_GRADE}


class Circle(NamedTuple):
    """A full circle boundary loop for :func:`mesh_polygon`: centre (x, y) [m], radius [m]."""

    x: float
    y: float
    radius: float


# --------------------------------------------------------------------------------------------
# mesh container
# --------------------------------------------------------------------------------------------
@dataclass
class GearMesh:
    """A planar triangle mesh with named boundary groups.

    Attributes
    ----------
    points : ndarray, shape (N, 2)
        Node coordinates [m]. The corner (vertex) nodes come first, ``0..n_vertices-1``,
        then the edge mid-nodes of quadratic meshes.
    triangles : ndarray, shape (M, 3) or (M, 6)
        Node indices per triangle, counter-clockwise; for order 2 the corners then the
        mid-nodes of edges (0-1), (1-2), (2-0) (gmsh/meshio ``triangle6`` order).
    order : int
        1 or 2.
    facet_groups : dict[str, ndarray]
        Boundary group name -> edges, shape (K, 2) or (K, 3): end nodes then mid-node.
    node_sets : dict[str, ndarray]
        Group name -> sorted unique node indices of its edges (mid-nodes included).
    key : str
        Cache hash ('' if not cached).
    info : dict
        Free-form metadata: sizes, min_sicn (gmsh quality), source ('gmsh' or 'cache'), ...
    regions : dict[str, ndarray]
        Region name -> triangle indices (a gear: ``{"body": all}``; a housing: wall and cover,
        of different out-of-plane thickness). Not kept by the mesh cache.
    """

    points: np.ndarray
    triangles: np.ndarray
    order: int
    facet_groups: dict = field(default_factory=dict)
    node_sets: dict = field(default_factory=dict)
    key: str = ""
    info: dict = field(default_factory=dict)
    regions: dict = field(default_factory=dict)

    def __post_init__(self):
        self.points = np.ascontiguousarray(self.points, dtype=float)[:, :2]
        self.triangles = np.ascontiguousarray(self.triangles, dtype=np.int64)
        self.facet_groups = {k: np.asarray(v, dtype=np.int64).reshape(-1, self.order + 1)
                             for k, v in self.facet_groups.items()}
        if not self.node_sets:
            self.node_sets = {k: np.unique(v) for k, v in self.facet_groups.items()}

    @property
    def n_nodes(self) -> int:
        """Number of nodes (vertices + mid-nodes)."""
        return self.points.shape[0]

    @property
    def n_vertices(self) -> int:
        """Number of corner nodes (they are numbered first)."""
        return int(self.triangles[:, :3].max()) + 1

    @property
    def n_elements(self) -> int:
        """Number of triangles."""
        return self.triangles.shape[0]

    def corner_areas(self) -> np.ndarray:
        """Signed areas [m^2] of the straight triangles through the corner nodes."""
        p = self.points[self.triangles[:, :3]]
        d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        return 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])

    def min_angles(self) -> np.ndarray:
        """Smallest interior angle [deg] of each (straight-sided) triangle."""
        p = self.points[self.triangles[:, :3]]
        ang = []
        for i in range(3):
            a = p[:, (i + 1) % 3] - p[:, i]
            b = p[:, (i + 2) % 3] - p[:, i]
            nab = np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
            c = np.einsum("ij,ij->i", a, b) / nab
            ang.append(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))
        return np.min(ang, axis=0)

    def boundary_edges(self) -> np.ndarray:
        """Corner-node pairs (K, 2) of edges that belong to exactly one triangle."""
        t = self.triangles[:, :3]
        e = np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        es = np.sort(e, axis=1)
        _, idx, cnt = np.unique(es, axis=0, return_index=True, return_counts=True)
        return e[idx[cnt == 1]]

    def to_skfem(self):
        """Return the mesh as a scikit-fem ``MeshTri1``/``MeshTri2`` with named boundaries.

        ``mesh.boundaries[name]`` holds the skfem facet indices of each group in
        :attr:`facet_groups`. Vertex ``i`` of the skfem mesh is node ``i`` of this mesh.
        """
        from skfem import MeshTri1, MeshTri2

        nv = self.n_vertices
        if self.order == 1:
            m = MeshTri1(self.points[:nv].T.copy(), self.triangles.T.copy())
        else:
            m = MeshTri2(self.points.T.copy(), self.triangles.T.copy())
            # skfem keeps the vertices (numbered first here) in order
            assert np.allclose(m.p[:, :nv], self.points[:nv].T)
        lookup = FacetLookup(m.facets, nv)
        bnd = {name: lookup(e[:, 0], e[:, 1]) for name, e in self.facet_groups.items()}
        return m.with_boundaries(bnd)


class FacetLookup:
    """Map vertex pairs (a, b) to skfem facet indices (facets given as (2, Nf) vertex array)."""

    def __init__(self, facets: np.ndarray, n_vertices: int):
        f = np.sort(np.asarray(facets), axis=0).astype(np.int64)
        self._nv = int(max(n_vertices, f.max() + 1))
        keys = f[0] * self._nv + f[1]
        self._order = np.argsort(keys)
        self._keys = keys[self._order]

    def __call__(self, a, b) -> np.ndarray:
        a, b = np.asarray(a, np.int64), np.asarray(b, np.int64)
        k = np.minimum(a, b) * self._nv + np.maximum(a, b)
        pos = np.searchsorted(self._keys, k)
        pos = np.clip(pos, 0, len(self._keys) - 1)
        if np.any(self._keys[pos] != k):
            raise ValueError("edge not found among mesh facets")
        return self._order[pos].astype(np.int32)


# --------------------------------------------------------------------------------------------
# gmsh session
# --------------------------------------------------------------------------------------------
_GMSH_LOCK = threading.RLock()


class _GmshSession:
    """Context manager: initialise gmsh (quietly) if needed, a fresh model, clean finalize.

    gmsh keeps global state, so sessions are serialised with a process-wide lock. If gmsh was
    already initialised by the caller it is left initialised (only our model is removed).
    """

    _count = 0

    def __enter__(self):
        import gmsh

        _GMSH_LOCK.acquire()
        self.gmsh = gmsh
        self.owner = False
        try:
            self.owner = not gmsh.isInitialized()
            if self.owner:
                initialize_gmsh(gmsh)
            gmsh.option.setNumber("General.Terminal", 0)
            _GmshSession._count += 1
            self.name = f"flexgear_{os.getpid()}_{_GmshSession._count}"
            gmsh.model.add(self.name)
        except BaseException:
            try:
                if self.owner and gmsh.isInitialized():
                    gmsh.finalize()
            finally:
                _GMSH_LOCK.release()
            raise
        return gmsh

    def __exit__(self, *exc):
        gmsh = self.gmsh
        try:
            gmsh.model.setCurrent(self.name)
            gmsh.model.remove()
        finally:
            try:
                if self.owner:
                    gmsh.finalize()
            finally:
                _GMSH_LOCK.release()
        return False


def initialize_gmsh(gmsh) -> None:
    """``gmsh.initialize`` without Gmsh's changes to this process's signal handling: Python's
    Ctrl-C handler is kept (``interruptible=False``), and SIGPIPE, which Gmsh's library resets
    to its default action (end the process) where Python ignores it and raises BrokenPipeError,
    is ignored again. A batch that had meshed in its driver otherwise died of a write to a
    worker's closed pipe on Ctrl-C, without writing its summaries."""
    ignored = getattr(signal, "SIGPIPE", None) is not None and signal.getsignal(signal.SIGPIPE) == signal.SIG_IGN
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    if not ignored:  # no SIGPIPE (Windows), or a program that set its own disposition
        return
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    else:  # Python sets signals in the main thread only; the disposition is the process's
        import ctypes

        libc = ctypes.CDLL(None)
        libc.signal.restype = ctypes.c_void_p
        libc.signal.argtypes = (ctypes.c_int, ctypes.c_void_p)
        libc.signal(int(signal.SIGPIPE), ctypes.c_void_p(1))  # SIG_IGN


def _set_mesh_options(gmsh, order: int, h_min: float, h_max: float):
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeMin", h_min)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h_max)
    gmsh.option.setNumber("Mesh.Algorithm", 6)  # Frontal-Delaunay: good triangle shapes
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)  # mid-nodes on the true curves
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 0)
    gmsh.option.setNumber("General.NumThreads", 1)


def _add_circle(geo, c: Circle, h: float) -> list[int]:
    """Four arcs (< pi each, as the built-in kernel needs) forming a CCW circle."""
    centre = geo.addPoint(c.x, c.y, 0.0, h)
    pts = [geo.addPoint(c.x + c.radius * math.cos(a), c.y + c.radius * math.sin(a), 0.0, h)
           for a in (0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi)]
    return [geo.addCircleArc(pts[i], centre, pts[(i + 1) % 4]) for i in range(4)]


def _extract(gmsh, order: int, surfaces: Sequence[int], curve_groups: Mapping[str, Sequence[int]]):
    """Read nodes, triangles (of ``surfaces``, in turn) and the edges of each curve group from
    the current gmsh model; also the number of triangles of each surface."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    tags = np.asarray(tags, dtype=np.int64)
    xyz = np.asarray(coords).reshape(-1, 3)
    npe = 3 * order
    blocks = [np.asarray(gmsh.model.mesh.getElementsByType(_GMSH_TRI[order], s)[1], dtype=np.int64).reshape(-1, npe)
              for s in surfaces]
    tri_tags = np.vstack(blocks)
    # node numbering: corners first (in order of first appearance), then mid-nodes
    corner = _unique_stable(tri_tags[:, :3].ravel())
    if order == 2:
        mids = np.setdiff1d(_unique_stable(tri_tags.ravel()), corner, assume_unique=True)
    else:
        mids = np.empty(0, np.int64)
    used = np.concatenate([corner, mids])
    tag2idx = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    tag2idx[used] = np.arange(len(used))
    tag2row = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    tag2row[tags] = np.arange(len(tags))
    points = xyz[tag2row[used], :2]
    tri = tag2idx[tri_tags]
    groups = {}
    for name, curves in curve_groups.items():
        edges = []
        for c in curves:
            _, en = gmsh.model.mesh.getElementsByType(_GMSH_LINE[order], c)
            edges.append(np.asarray(en, dtype=np.int64).reshape(-1, order + 1))
        e = np.vstack(edges) if edges else np.empty((0, order + 1), np.int64)
        groups[name] = tag2idx[e]
    return points, tri, groups, [len(b) for b in blocks]


def _min_sicn(gmsh, order: int, surfaces: Sequence[int]) -> float:
    """Smallest gmsh signed inverse condition number of the surfaces' triangles (<= 0: invalid)."""
    return min(float(np.min(gmsh.model.mesh.getElementQualities(
        gmsh.model.mesh.getElementsByType(_GMSH_TRI[order], s)[0], "minSICN"))) for s in surfaces)


def _unique_stable(a: np.ndarray) -> np.ndarray:
    """Unique values of ``a`` in order of first appearance."""
    _, idx = np.unique(a, return_index=True)
    return a[np.sort(idx)]


def _orient_ccw(points, tri, order):
    p = points[tri[:, :3]]
    d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    neg = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) < 0
    if np.any(neg):
        perm = [0, 2, 1] if order == 1 else [0, 2, 1, 5, 4, 3]
        tri = tri.copy()
        tri[neg] = tri[neg][:, perm]
    return tri


def _mesh_loops(build, order: int, h_min: float, h_max: float, fields=None) -> GearMesh:
    """Run gmsh: ``build(geo) -> (surface_loops, curve_groups[, embedded_curves])``; optional
    ``fields(gmsh)``. Embedded curves lie inside the surface (their nodes are mesh nodes)."""
    def build_regions(geo):
        loops, groups, *embedded = build(geo)
        return {"body": loops}, groups, *embedded

    return mesh_regions(build_regions, order, h_min, h_max, fields)


def mesh_regions(build, order: int, h_min: float, h_max: float, fields=None) -> GearMesh:
    """Mesh plane regions with gmsh's built-in kernel; the mesher behind every mesh here.

    Parameters
    ----------
    build : callable
        ``build(geo) -> (regions, curve_groups[, embedded_curves])``: ``regions`` maps a region
        name to its boundary loops (lists of curve tags, the outer loop first, holes after), made
        with ``geo`` (``gmsh.model.geo``); regions that touch share their curves (the mesh is
        conforming). ``curve_groups`` maps a boundary group name to curve tags;
        ``embedded_curves`` lie inside the first region (their nodes are mesh nodes: a crack).
    order : int
        Triangle order, 1 or 2 (mid-nodes on the true curves).
    h_min, h_max : float
        Size bounds [m].
    fields : callable, optional
        ``fields(gmsh)`` sets the background size field.

    Returns
    -------
    GearMesh
        With ``regions`` (region name -> triangle indices, in the order given) and the
        boundary groups, read from the curves' and surfaces' own entities (no physical groups:
        nothing is written in gmsh's format).

    Raises
    ------
    GeometryError
        Inverted elements (min SICN <= 0 after the high-order optimisation).
    """
    with _GmshSession() as gmsh:
        geo = gmsh.model.geo
        loops, curve_groups, *embedded = build(geo)
        surfaces = {}
        for name, region in loops.items():
            cls = [geo.addCurveLoop(list(c)) for c in region]
            surfaces[name] = geo.addPlaneSurface(cls)
        geo.synchronize()
        if embedded and embedded[0]:
            gmsh.model.mesh.embed(1, list(embedded[0]), 2, next(iter(surfaces.values())))
        tags = list(surfaces.values())
        _set_mesh_options(gmsh, order, h_min, h_max)
        if fields is not None:
            fields(gmsh)
        gmsh.model.mesh.generate(2)
        if order == 2:
            gmsh.model.mesh.setOrder(2)
            if _min_sicn(gmsh, order, tags) <= 0.0:  # a curved element folded over
                gmsh.model.mesh.optimize("HighOrderElastic")
        min_sicn = _min_sicn(gmsh, order, tags)
        if min_sicn <= 0.0:
            raise GeometryError(f"mesh: invalid (inverted) elements, min SICN = {min_sicn:.3g}; "
                                "rule: SICN > 0 - use a finer level or order 1")
        points, tri, groups, counts = _extract(gmsh, order, tags, curve_groups)
    tri = _orient_ccw(points, tri, order)
    bounds = np.concatenate([[0], np.cumsum(counts)])
    regions = {name: np.arange(bounds[i], bounds[i + 1]) for i, name in enumerate(surfaces)}
    return GearMesh(points, tri, order, groups, info={"min_sicn": min_sicn, "source": "gmsh"}, regions=regions)


# --------------------------------------------------------------------------------------------
# generic polygon mesher
# --------------------------------------------------------------------------------------------
def mesh_polygon(outer, holes=(), *, h: float, order: int = 2, edge_names=None,
                 fine_edges=None, h_fine: float | None = None, fine_dist: float = 0.0,
                 grade_dist: float | None = None) -> GearMesh:
    """Mesh a planar domain bounded by a polygon or circle, with optional holes.

    Parameters
    ----------
    outer : array_like (N, 2) or Circle
        Outer boundary: a closed polygon (last point != first) [m] or a :class:`Circle`.
    holes : sequence of (array_like (N, 2) or Circle)
        Holes inside ``outer``.
    h : float
        Target element size [m].
    order : int
        Triangle order, 1 or 2.
    edge_names : dict[str, sequence of int], optional
        Extra boundary groups made of edges of a polygonal ``outer``; edge ``i`` joins point
        ``i`` to point ``i+1``. Always present: group ``"outer"`` (all of ``outer``) and
        ``"hole{j}"``.
    fine_edges : sequence of int, optional
        Edges of polygonal ``outer`` near which the size is ``h_fine`` (within ``fine_dist``
        [m], growing to ``h`` over ``grade_dist`` [m], default ``4*h``).

    Returns
    -------
    GearMesh
        Surface group "body" is implied; boundary groups as above. Not cached.
    """
    if not (h > 0):
        raise ConfigError(f"h = {h!r}: element size must be > 0 m")
    if order not in (1, 2):
        raise ConfigError(f"order = {order!r}: element order must be 1 or 2")
    edge_names = dict(edge_names or {})
    h_lo = min(h, h_fine) if h_fine else h

    def add_loop(geo, spec):
        if isinstance(spec, Circle):
            return _add_circle(geo, spec, h), None
        pts = np.asarray(spec, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 3:
            raise GeometryError(f"polygon shape {pts.shape}: need (N >= 3, 2) points")
        ptags = [geo.addPoint(x, y, 0.0, h) for x, y in pts]
        lines = [geo.addLine(ptags[i], ptags[(i + 1) % len(ptags)]) for i in range(len(ptags))]
        return lines, lines

    state = {}

    def build(geo):
        outer_curves, outer_lines = add_loop(geo, outer)
        groups = {"outer": outer_curves}
        loops = [outer_curves]
        for j, hole in enumerate(holes):
            hc, _ = add_loop(geo, hole)
            groups[f"hole{j}"] = hc
            loops.append(hc)
        for name, idx in edge_names.items():
            if outer_lines is None:
                raise ConfigError(f"edge_names[{name!r}]: only a polygonal outer boundary "
                                  "has edges")
            groups[name] = [outer_lines[i] for i in idx]
        state["lines"] = outer_lines
        return loops, groups

    def fields(gmsh):
        fm = gmsh.model.mesh.field
        if fine_edges and h_fine:
            d = fm.add("Distance")
            fm.setNumbers(d, "CurvesList", [state["lines"][i] for i in fine_edges])
            fm.setNumber(d, "Sampling", 200)
            f = fm.add("Threshold")
            fm.setNumber(f, "InField", d)
            fm.setNumber(f, "SizeMin", h_fine)
            fm.setNumber(f, "SizeMax", h)
            fm.setNumber(f, "DistMin", fine_dist)
            fm.setNumber(f, "DistMax", fine_dist + (grade_dist if grade_dist else 4 * h))
        else:
            f = fm.add("Constant")
            fm.setNumber(f, "VIn", h)
        fm.setAsBackgroundMesh(f)

    return _mesh_loops(build, order, 0.5 * h_lo, h, fields)


# --------------------------------------------------------------------------------------------
# gear mesher
# --------------------------------------------------------------------------------------------
def _gear_name(gear) -> str:
    return str(getattr(gear, "name", "gear") or "gear")


def _check_gear(gear, settings: MeshSettings, pts: np.ndarray):
    """Raise before gmsh runs if the body cannot be meshed sensibly."""
    name = _gear_name(gear)
    m = float(gear.module)
    r = np.hypot(pts[:, 0], pts[:, 1])
    if getattr(gear, "internal", False):
        rf = float(getattr(gear, "rf", r.max()))
        rf = max(rf, float(r.max()))
        rim_d = getattr(gear, "rim_diameter", None)
        if rim_d is None or not np.isfinite(rim_d):
            raise GeometryError(
                f"{name}.rim_diameter = {rim_d!r}: an internal gear needs an outer rim diameter "
                f"> root diameter {2 * rf:.6g} m + 2 x {settings.min_rim} module")
        thick = 0.5 * float(rim_d) - rf
        need = settings.min_rim * m
        if thick < need:
            raise GeometryError(
                f"{name}.rim_diameter = {rim_d!r} m: rim thickness (rim radius - root radius "
                f"{rf:.6g} m) = {thick:.6g} m is thinner than the minimum mesh.min_rim = "
                f"{settings.min_rim} module = {need:.6g} m; rule: rim_diameter >= "
                f"{2 * (rf + need):.6g} m")
    else:
        rf = float(getattr(gear, "rf", r.min()))
        rf = min(rf, float(r.min()))
        bore_d = getattr(gear, "bore_diameter", None)
        if bore_d is None or bore_d == 0:
            return
        if not (np.isfinite(bore_d) and bore_d > 0):
            raise GeometryError(f"{name}.bore_diameter = {bore_d!r}: must be > 0 m (or 0 / None "
                                "for a solid gear)")
        need = settings.min_ligament * m
        lig = rf - 0.5 * float(bore_d)
        if lig < need:
            raise GeometryError(
                f"{name}.bore_diameter = {bore_d!r} m: the bore leaves a ligament of {lig:.6g} m "
                f"below the root circle (root radius {rf:.6g} m); minimum mesh.min_ligament = "
                f"{settings.min_ligament} module = {need:.6g} m; rule: bore_diameter <= "
                f"{2 * (rf - need):.6g} m")


def _outline_arrays(gear):
    ol = gear.outline()
    pts = np.asarray(ol.points, dtype=float)
    kind = np.asarray(ol.kind, dtype=np.int64)
    tooth = np.asarray(ol.tooth, dtype=np.int64)
    side = np.asarray(ol.side, dtype=np.int64)
    n = len(pts)
    if n < 3 or pts.shape != (n, 2) or not (len(kind) == len(tooth) == len(side) == n):
        raise GeometryError(f"{_gear_name(gear)}.outline(): inconsistent arrays "
                            f"(points {pts.shape}, kind {kind.shape})")
    if not np.all(np.isfinite(pts)):
        raise GeometryError(f"{_gear_name(gear)}.outline(): non-finite points")
    # drop repeated points (also a closing point equal to the first)
    scale = float(np.max(np.abs(pts)))
    d = np.hypot(*(pts - np.roll(pts, 1, axis=0)).T)
    keep = d > 1e-10 * scale
    pts, kind, tooth, side = pts[keep], kind[keep], tooth[keep], side[keep]
    area = 0.5 * np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
    if area < 0:  # make CCW
        pts, kind, tooth, side = pts[::-1], kind[::-1], tooth[::-1], side[::-1]
    return pts, kind, tooth, side


def _group_of(kind, tooth, side):
    """Boundary group name of an outline point."""
    if kind == _FLANK:
        return f"tooth{tooth}_left" if side > 0 else f"tooth{tooth}_right"
    if kind in (_FILLET, _ROOT):
        return "root_fillets"
    return "tips"


def _outline_runs(kind, tooth, side, breaks=()):
    """Start indices and group names of maximal runs of points of one boundary group.

    Root land and fillets between two teeth form one curve (they join tangentially), so do
    the two halves of a tip; flanks are separate curves per tooth and side. ``breaks``: outline
    indices that start a curve of their own as well (a feature's points, :class:`MeshFeature`).
    """
    names = np.array([_group_of(k, t, s) for k, t, s in zip(kind, tooth, side)])
    starts = np.flatnonzero(names != np.roll(names, 1))
    if len(breaks):
        starts = np.union1d(starts, np.asarray(breaks, dtype=np.int64))
    if len(starts) < 2:  # one label only: cut into four pieces
        starts = np.linspace(0, len(names), 5)[:-1].astype(int)
    return starts, names[starts]


def cache_key(gear, settings: MeshSettings, outline_pts: np.ndarray | None = None,
              feature=None) -> tuple[str, dict]:
    """Return ``(sha256 hex, key dict)`` identifying the mesh of ``gear`` with ``settings`` (and
    ``feature``, a :class:`MeshFeature`, whose ``key()`` then enters the key)."""
    import gmsh

    if outline_pts is None:
        outline_pts = _outline_arrays(gear)[0]
    fp = hashlib.sha256(np.round(np.asarray(outline_pts, float), 12).tobytes()).hexdigest()
    key = {"format": FORMAT_VERSION, "geometry": gear_parameters(gear),
           "outline_sha256": fp, "n_outline": int(len(outline_pts)),
           "mesh": settings.key(), "gmsh": getattr(gmsh, "__version__", "?")}
    if feature is not None:
        key["feature"] = jsonable(feature.key())
    s = json.dumps(key, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(s.encode()).hexdigest(), json.loads(s)


def mesh_digest(gear, settings: MeshSettings | None = None, feature: MeshFeature | None = None) -> str:
    """The key (``GearMesh.key``) of the mesh that :func:`mesh_gear` makes of ``gear`` with
    ``settings`` (and ``feature``), without meshing [sha256 hex]."""
    return cache_key(gear, MeshSettings() if settings is None else settings, feature=feature)[0]


class MeshFeature:
    """Interface of an addition to a gear body's mesh (e.g. a root crack,
    :class:`flexgear.fe.crack.CrackFeature`), given to :func:`mesh_gear` as ``feature``.

    The gear mesher calls, in this order: :meth:`outline` (insert points into the toothed outline
    and name the indices that start a curve), :meth:`curves` (add curves embedded in the surface,
    returned as named boundary groups), :meth:`fields` (refine the size field) and
    :meth:`finish` (edit the mesh gmsh made, e.g. duplicate nodes). :meth:`key` enters the
    mesh cache key; ``size_min`` [m] is the smallest element size the feature asks for.
    """

    size_min: float = math.inf

    def key(self) -> dict:
        raise NotImplementedError

    def outline(self, pts, kind, tooth, side):
        """``(pts, kind, tooth, side, breaks)``: the outline arrays with the feature's points."""
        return pts, kind, tooth, side, ()

    def curves(self, geo, ptags, h: float) -> dict:
        """Add embedded curves with the gmsh ``geo`` kernel (``ptags``: outline point tags, ``h``:
        the tooth element size [m]); returns {group name: [curve tags]}."""
        return {}

    def fields(self, gmsh, background: int) -> int:
        """The size field to use instead of ``background`` (a gmsh field id)."""
        return background

    def finish(self, gm: GearMesh) -> GearMesh:
        """The mesh as the feature wants it (may be ``gm`` itself, edited)."""
        return gm


def _build_gear_mesh(gear, settings: MeshSettings, outline, feature: MeshFeature | None = None) -> GearMesh:
    pts, kind, tooth, side = outline
    breaks = ()
    if feature is not None:
        pts, kind, tooth, side, breaks = feature.outline(pts, kind, tooth, side)
    m = float(gear.module)
    h_tooth, h_body = settings.sizes(m)
    starts, run_names = _outline_runs(kind, tooth, side, breaks)
    n = len(pts)
    internal = bool(getattr(gear, "internal", False))

    def build(geo):
        ptags = [geo.addPoint(x, y, 0.0, h_tooth) for x, y in pts]
        groups: dict[str, list[int]] = {}
        curves = []
        for j, s in enumerate(starts):
            e = starts[(j + 1) % len(starts)]
            idx = list(range(s, e + 1)) if e > s else list(range(s, n)) + list(range(0, e + 1))
            tags = [ptags[i % n] for i in idx]
            c = geo.addSpline(tags) if len(tags) > 2 else geo.addLine(tags[0], tags[1])
            curves.append(c)
            groups.setdefault(str(run_names[j]), []).append(c)
        groups["outline"] = list(curves)
        if internal:
            rim = _add_circle(geo, Circle(0.0, 0.0, 0.5 * float(gear.rim_diameter)), h_body)
            groups["rim"] = rim
            loops = [rim, curves]
        else:
            loops = [curves]
            bore = getattr(gear, "bore_diameter", None)
            if bore:
                hub = _add_circle(geo, Circle(0.0, 0.0, 0.5 * float(bore)), h_body)
                groups["hub"] = hub
                loops.append(hub)
        build.curves = curves
        if feature is None:
            return loops, groups
        extra = feature.curves(geo, ptags, h_tooth)
        groups.update(extra)
        return loops, groups, [c for cs in extra.values() for c in cs]

    def fields(gmsh):
        fm = gmsh.model.mesh.field
        d = fm.add("Distance")
        fm.setNumbers(d, "CurvesList", build.curves)
        fm.setNumber(d, "Sampling", 40)
        t = fm.add("Threshold")
        fm.setNumber(t, "InField", d)
        fm.setNumber(t, "SizeMin", h_tooth)
        fm.setNumber(t, "SizeMax", h_body)
        fm.setNumber(t, "DistMin", DIST_FINE * m)
        fm.setNumber(t, "DistMax", (DIST_FINE + DIST_GRADE) * m)
        if feature is not None:
            t = feature.fields(gmsh, t)
        fm.setAsBackgroundMesh(t)

    h_min = 0.5 * h_tooth if feature is None else min(0.5 * h_tooth, feature.size_min)
    gm = _mesh_loops(build, settings.order, h_min, h_body, fields)
    gm.info.update({"h_tooth": h_tooth, "h_body": h_body, "gear": _gear_name(gear),
                    "level": settings.level})
    return gm if feature is None else feature.finish(gm)


class _UserCache:
    """Type of :data:`USER_CACHE`."""

    def __repr__(self):
        return "USER_CACHE"


USER_CACHE = _UserCache()
"""Default ``cache_dir`` of the meshing functions: the per-user mesh cache, :func:`mesh_cache_dir`."""


def mesh_cache_dir() -> Path:
    """The per-user mesh cache: ``meshes/`` in :func:`flexgear.files.user_cache_dir`
    (``$FLEXGEAR_CACHE_DIR/meshes`` if that variable is set, else e.g. ``~/.cache/flexgear/meshes``)."""
    return user_cache_dir() / "meshes"


def resolve_cache_dir(cache_dir):
    """``cache_dir`` as given, with :data:`USER_CACHE` replaced by :func:`mesh_cache_dir`."""
    return mesh_cache_dir() if cache_dir is USER_CACHE else cache_dir


def check_meshable(gear, settings: MeshSettings | None = None) -> None:
    """The checks :func:`mesh_gear` makes before gmsh runs (outline, bore ligament, ring rim),
    without meshing: lets a caller check every gear before meshing any.

    Raises
    ------
    ConfigError, GeometryError
    """
    settings = MeshSettings() if settings is None else settings
    if not isinstance(settings, MeshSettings):
        raise ConfigError(f"settings = {settings!r}: must be a flexgear.meshing.MeshSettings")
    _check_gear(gear, settings, _outline_arrays(gear)[0])


def mesh_gear(gear, settings: MeshSettings | None = None, cache_dir=USER_CACHE,
              feature: MeshFeature | None = None) -> GearMesh:
    """Mesh the body of ``gear`` (plane section), using/refreshing the on-disk cache.

    External gear: the closed tooth outline minus the bore circle (``bore_diameter``).
    Internal gear (``gear.internal``): the annulus between the rim circle (``rim_diameter``)
    and the toothed outline.

    Parameters
    ----------
    gear : flexgear.geometry.SpurGear
        Gear with ``outline()``, ``module`` [m], ``rf`` [m], ``bore_diameter`` /
        ``rim_diameter`` [m], ``internal``.
    settings : MeshSettings, optional
        Refinement level and order; default ``MeshSettings()`` (level 2, quadratic).
    cache_dir : str or PathLike or None
        Cache directory (created if needed); default the per-user cache
        (:func:`mesh_cache_dir`); ``None`` disables the cache.
    feature : MeshFeature, optional
        An addition to the body (a crack: :func:`flexgear.fe.crack.mesh_cracked_gear`); part
        of the cache key. ``None`` (default): the plain body.

    Returns
    -------
    GearMesh
        Boundary groups (a feature adds its own): ``"hub"`` (bore, external gears), ``"rim"`` (internal gears),
        ``"tooth{k}_left"`` / ``"tooth{k}_right"`` (flanks, side +1 / -1), ``"root_fillets"``
        (fillets and root arcs), ``"tips"``, ``"outline"`` (whole toothed outline). The
        surface is the physical group ``"body"`` (all triangles).

    Raises
    ------
    ConfigError, GeometryError
        Before gmsh runs: bad settings, a bore cutting into the minimum ligament below the
        root circle, a ring rim thinner than the minimum.
    """
    if settings is None:
        settings = MeshSettings()
    if not isinstance(settings, MeshSettings):
        raise ConfigError(f"settings = {settings!r}: must be a flexgear.meshing.MeshSettings")
    outline = _outline_arrays(gear)
    _check_gear(gear, settings, outline[0])
    digest, key = cache_key(gear, settings, outline[0], feature)
    cache_dir = resolve_cache_dir(cache_dir)
    with entry_lock(cache_dir, f"mesh-{digest}") if cache_dir is not None else contextlib.nullcontext():
        if cache_dir is not None:
            gm = load_cached(cache_dir, digest, key)
            if gm is not None:
                return gm
        t0 = time.perf_counter()
        gm = _build_gear_mesh(gear, settings, outline, feature)
        gm.key = digest
        gm.info["mesh_seconds"] = time.perf_counter() - t0
        if cache_dir is not None:
            write_cached(gm, cache_dir, digest, key)
    return gm


# --------------------------------------------------------------------------------------------
# cache files
# --------------------------------------------------------------------------------------------
def cache_paths(cache_dir, digest: str) -> tuple[Path, Path]:
    """Paths ``(mesh .vtu, sidecar .json)`` of a cache entry."""
    d = Path(cache_dir)
    return d / f"{digest}.vtu", d / f"{digest}.json"


def write_cached(gm: GearMesh, cache_dir, digest: str, key: dict) -> Path:
    """Write ``gm`` atomically to the cache (``.vtu`` via meshio, then the ``.json``)."""
    import meshio

    cache_dir = Path(cache_dir)
    cache_dir.mkdir(parents=True, exist_ok=True)
    vtu, side = cache_paths(cache_dir, digest)
    names = sorted(gm.facet_groups)
    lines = [gm.facet_groups[n] for n in names]
    gid = [np.full(len(e), i, dtype=np.int32) for i, e in enumerate(lines)]
    cells = [(_MESHIO_TRI[gm.order], gm.triangles)]
    cell_gid = [np.full(gm.n_elements, -1, dtype=np.int32)]
    if lines:
        cells.append((_MESHIO_LINE[gm.order], np.vstack(lines)))
        cell_gid.append(np.concatenate(gid))
    mesh = meshio.Mesh(np.column_stack([gm.points, np.zeros(gm.n_nodes)]), cells,
                       cell_data={"group_id": cell_gid})
    atomic_write(vtu, lambda tmp: meshio.write(tmp, mesh, file_format="vtu"))
    meta = {"hash": digest, "key": key, "vtu_sha256": sha256_file(vtu), "groups": names,
            "n_points": gm.n_nodes, "n_triangles": gm.n_elements, "order": gm.order,
            "info": jsonable(gm.info)}
    atomic_write_json(side, meta)
    return vtu


def load_cached(cache_dir, digest: str, key: dict) -> GearMesh | None:
    """Load a cache entry; ``None`` if it is missing, corrupt or stale (then it is removed)."""
    import meshio

    vtu, side = cache_paths(cache_dir, digest)
    if not side.exists() and not vtu.exists():
        return None
    try:
        meta = json.loads(side.read_text())
        if meta.get("hash") != digest or meta.get("key") != key:
            raise ValueError("stale cache entry (key mismatch)")
        if sha256_file(vtu) != meta["vtu_sha256"]:
            raise ValueError("corrupt cache entry (checksum mismatch)")
        mesh = meshio.read(vtu, file_format="vtu")
        order = int(meta["order"])
        tri_type, line_type = _MESHIO_TRI[order], _MESHIO_LINE[order]
        gids = mesh.cell_data["group_id"]
        tri = np.vstack([b.data for b in mesh.cells if b.type == tri_type])
        lines, lgid = [], []
        for b, g in zip(mesh.cells, gids):
            if b.type == line_type:
                lines.append(b.data)
                lgid.append(g)
        lines = np.vstack(lines) if lines else np.empty((0, order + 1), np.int64)
        lgid = np.concatenate(lgid) if lgid else np.empty(0, np.int64)
        groups = {name: lines[lgid == i] for i, name in enumerate(meta["groups"])}
        if mesh.points.shape[0] != meta["n_points"] or tri.shape[0] != meta["n_triangles"]:
            raise ValueError("corrupt cache entry (size mismatch)")
        info = dict(meta.get("info", {}))
        info["source"] = "cache"
        return GearMesh(mesh.points[:, :2], tri, order, groups, key=digest, info=info)
    except Exception as exc:  # noqa: BLE001 - any failure means: rebuild
        log.warning("mesh cache %s unusable (%s); rebuilding", vtu.name, exc)
        discard_files(side, vtu)
        return None
