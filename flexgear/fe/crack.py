"""A root crack in a gear tooth: its geometry, checks, and the gear mesh with the crack as a slit.

A straight crack of length ``depth`` q [m] at ``angle`` nu (0 < nu <= 90 deg) to the tooth
centre line, through the face width, starting on the loaded flank's root fillet where the
fillet's tangent makes ``start_tangent`` with the centre line (default ISO 6336-3's critical
section: 30 deg on external gears, 60 deg on internal ones) or at ``start_radius``. It runs into
the body, from the tip side of the tooth towards its root and across towards the centre line:
towards the gear axis on an external gear, out towards the rim on an internal gear (whose teeth
point to the centre); nu is measured from the centre line's direction tip -> root. It opens under
the tooth load; with the other flank
loaded the slit's faces would overlap (no contact between them), overstating that flank's
compliance. :func:`mesh_cracked_gear` meshes the whole gear with the crack as an embedded curve,
refined at the tip, its face nodes duplicated except at the tip (groups ``"crack_body"`` and
``"crack_tooth"``, both in ``"outline"``); zero depth gives the healthy mesh. See the theory page
*Root crack*. Lengths in metres, angles in radians (messages print degrees).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import ConfigError, GeometryError
from ..gears.faults import CRITICAL_TANGENT_DEG
from ..gears.geometry import FILLET
from .meshing import (USER_CACHE, GearMesh, MeshFeature, MeshSettings, gear_parameters, mesh_digest,
                      mesh_gear)

#: ISO 6336-3 critical section of external gears: the fillet tangent at 30 deg to the centre line.
DEFAULT_START_TANGENT = math.radians(CRITICAL_TANGENT_DEG[False])
#: ISO 6336-3 critical section of internal gears: the fillet tangent at 60 deg to the centre line.
DEFAULT_START_TANGENT_INTERNAL = math.radians(CRITICAL_TANGENT_DEG[True])
#: Allowed crack angles to the tooth centre line: 0 < angle <= ANGLE_MAX.
ANGLE_MAX = 0.5 * math.pi
#: Smallest angle between the crack and the fillet surface at the start (no grazing slits).
MIN_SURFACE_ANGLE = math.radians(15.0)
#: Smallest ligament left between the crack tip and where the crack line leaves the body [modules].
MIN_LIGAMENT = 0.1
#: Shortest crack (other than 0, the healthy tooth) [modules].
MIN_DEPTH = 0.02
#: Element size at the crack tip relative to the tooth size h_tooth of the mesh level (at most
#: depth / TIP_PER_DEPTH), refine level 0: 40 um at the default level 2 of a 2 mm module.
TIP_SIZE = 0.08
#: Crack tip elements per crack length at least.
TIP_PER_DEPTH = 8
#: Growth of the element size away from the tip [m per m], refine level 0.
GRADING = 0.25
#: Bump when the crack mesh changes (part of the cache key).
CRACK_MESH_VERSION = 1


@dataclass(frozen=True)
class FilletCurve:
    """The root fillet of tooth 0's left flank, from the root land to the involute.

    Attributes
    ----------
    points : ndarray (N, 2)
        [m], gear frame, root end first.
    radius : ndarray (N,)
        [m]: growing from the root to the involute on an external gear, falling on an internal one.
    tangent : ndarray (N,)
        Angle between the fillet's tangent and the tooth centre line [rad]: near 90 deg at the
        root land, falling towards the involute.
    """

    points: np.ndarray
    radius: np.ndarray
    tangent: np.ndarray

    def at_tangent(self, angle: float) -> np.ndarray:
        """Point [m] where the tangent angle first (from the root) falls to ``angle`` [rad]."""
        t = self.tangent
        i = int(np.flatnonzero(t <= angle)[0])
        w = (t[i - 1] - angle) / (t[i - 1] - t[i])
        return (1 - w) * self.points[i - 1] + w * self.points[i]

    def at_radius(self, r: float) -> np.ndarray:
        """Point [m] at radius ``r`` [m] (the fillet's radius is monotone from root to involute)."""
        s = 1.0 if self.radius[-1] > self.radius[0] else -1.0
        i = int(np.flatnonzero(s * self.radius >= s * r)[0])
        w = (r - self.radius[i - 1]) / (self.radius[i] - self.radius[i - 1])
        return (1 - w) * self.points[i - 1] + w * self.points[i]

    def tangent_at(self, p) -> float:
        """Tangent angle [rad] at the fillet point nearest to ``p``."""
        i = int(np.argmin(np.hypot(*(self.points - np.asarray(p)).T)))
        return float(self.tangent[i])


def fillet_curve(gear) -> FilletCurve:
    """The left root fillet of tooth 0 of ``gear`` (external or internal), densely sampled (m / 400)."""
    m = gear.module
    ds = m / 400.0
    ol = gear.tooth_outline(ds)
    sel = (ol.kind == FILLET) & (ol.side > 0)
    p = ol.points[sel][::-1]  # the left side runs tip -> root; root end first
    if len(p) < 20:
        raise GeometryError(f"{gear.name}: the root fillet has too few points to place a crack")
    k = max(1, int(round(m / 100.0 / ds)))  # tangent from a chord of about m / 50
    lo = np.clip(np.arange(len(p)) - k, 0, len(p) - 1)
    hi = np.clip(np.arange(len(p)) + k, 0, len(p) - 1)
    t = p[hi] - p[lo]
    tangent = np.arctan2(np.abs(t[:, 1]), np.abs(t[:, 0]))
    return FilletCurve(points=p, radius=np.hypot(p[:, 0], p[:, 1]), tangent=tangent)


@dataclass(frozen=True)
class RootCrack:
    """A straight root crack (see the module docstring); make it with :func:`root_crack`.

    Attributes
    ----------
    gear : dict
        Geometry parameters of the gear it belongs to (:func:`flexgear.fe.meshing.gear_parameters`).
    tooth, side : int
        Tooth index (as the mesh's ``tooth{k}_left`` groups) and loaded flank (+1 left, -1 right).
    depth, angle : float
        Crack length q [m] and angle nu to the tooth centre line [rad].
    start_tangent, start_radius : float
        Fillet tangent angle [rad] and radius [m] at the start.
    start, tip : tuple (x, y)
        Start point on the fillet and crack tip [m], gear frame.
    exit_depth : float
        Length along the crack line from the start to where it would leave the body [m].
    name : str
        Prefix of messages (e.g. the fault's name in the configuration).
    """

    gear: dict
    tooth: int
    side: int
    depth: float
    angle: float
    start_tangent: float
    start_radius: float
    start: tuple
    tip: tuple
    exit_depth: float
    name: str = "crack"

    @property
    def direction(self) -> np.ndarray:
        """Unit vector from the start to the tip [-] (gear frame)."""
        return self._frame(_direction(self.angle, self.gear.get("internal", False)))

    @property
    def normal(self) -> np.ndarray:
        """Unit normal of the crack line pointing to the tooth (tip) side [-] (gear frame)."""
        s = -1.0 if self.gear.get("internal", False) else 1.0
        return self._frame(np.array([s * math.sin(self.angle), -math.cos(self.angle)]))

    def _frame(self, v):
        return _to_gear(v, self.tooth, self.side, int(self.gear["z"]))

    def key(self) -> dict:
        """What makes this crack's mesh (for cache keys)."""
        d = asdict(self)
        d.pop("name")
        return d


def _direction(angle: float, internal: bool) -> np.ndarray:
    """Unit vector of the crack in tooth 0's left-flank frame: at ``angle`` to the centre line's
    direction tip -> root (-x external, +x internal: into the body), towards the centre line (-y)."""
    return np.array([(1.0 if internal else -1.0) * math.cos(angle), -math.sin(angle)])


def _to_gear(v, tooth: int, side: int, z: int) -> np.ndarray:
    """Map a point/vector of tooth 0's left-flank frame to tooth ``tooth``, flank ``side``."""
    a = 2.0 * math.pi * tooth / z
    x, y = v[..., 0], side * v[..., 1]
    return np.stack([math.cos(a) * x - math.sin(a) * y, math.sin(a) * x + math.cos(a) * y], axis=-1)


def _number(name: str, what: str, v, rule: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
        raise ConfigError(f"{name}: {what} = {v!r}: must be a finite number ({rule})")
    return float(v)


def _ray_exit(origin, d, outline, circle: float, skip: float) -> float:
    """Distance along the ray origin + t d (t > skip) to the first crossing of the closed polygon
    ``outline`` or of the circle of radius ``circle`` about the axis (the bore of an external
    gear, the rim of an internal one; 0: none) [m] (inf if none)."""
    a = outline
    b = np.roll(outline, -1, axis=0)
    e = b - a
    den = d[0] * e[:, 1] - d[1] * e[:, 0]
    w = a - origin
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / den
        u = (w[:, 0] * d[1] - w[:, 1] * d[0]) / den
    hit = (np.abs(den) > 0) & (t > skip) & (u >= 0) & (u <= 1)
    best = float(np.min(t[hit])) if np.any(hit) else math.inf
    if circle > 0:  # |origin + t d| = R
        pb = float(origin @ d)
        disc = pb * pb - (float(origin @ origin) - circle ** 2)
        if disc >= 0:
            for t_ in (-pb - math.sqrt(disc), -pb + math.sqrt(disc)):
                if t_ > skip:
                    best = min(best, t_)
    return best


def root_crack(gear, depth: float, angle: float, *, tooth: int = 0, side: int = 1,
               start_tangent: float | None = None, start_radius: float | None = None,
               name: str = "crack") -> RootCrack:
    """Check and place a straight root crack in tooth ``tooth`` of an external or internal gear.

    Parameters
    ----------
    gear : SpurGear
        External or internal gear.
    depth : float
        Crack length q [m]; 0 is the healthy tooth, else at least ``MIN_DEPTH`` modules.
    angle : float
        Angle nu between the crack and the tooth centre line's direction tip -> root [rad],
        0 < nu <= 90 deg: the crack runs into the body (towards the axis of an external gear,
        towards the rim of an internal one) and towards the centre line.
    tooth : int
        Tooth index, 0 <= tooth < z (tooth k is centred on the polar angle 2 pi k / z).
    side : {1, -1}
        Flank whose fillet the crack starts on: +1 left (at larger polar angle), -1 right. The
        crack opens when that flank carries the load.
    start_tangent : float, optional
        Start where the fillet's tangent makes this angle with the centre line [rad]; default
        the ISO 6336-3 critical section, 30 deg external, 60 deg internal. Exclusive with
        ``start_radius``.
    start_radius : float, optional
        Start at this radius on the fillet [m].
    name : str
        Prefix of error messages (the fault's name in the configuration).

    Returns
    -------
    RootCrack

    Raises
    ------
    ConfigError
        Before any meshing: a parameter out of its range, a start point off the fillet, a crack
        that leaves the tooth (too deep for its angle) or ends too close to the outline; the
        message names the parameter, its value and the rule.
    """
    internal = bool(getattr(gear, "internal", False))
    z, m = int(gear.z), float(gear.module)
    if isinstance(tooth, bool) or not isinstance(tooth, (int, np.integer)) or not 0 <= tooth < z:
        raise ConfigError(f"{name}: tooth = {tooth!r}: must be a tooth index 0 <= tooth < z = {z} "
                          f"of {gear.name}")
    if side not in (1, -1) or isinstance(side, bool):
        raise ConfigError(f"{name}: side = {side!r}: must be +1 (left flank) or -1 (right flank)")
    depth = _number(name, "depth", depth, "crack length in m, >= 0")
    angle = _number(name, "angle", angle, "radians")
    if depth < 0:
        raise ConfigError(f"{name}: depth = {depth!r} m: must be >= 0 (0 = healthy tooth)")
    if not 0.0 < angle <= ANGLE_MAX + 1e-12:
        raise ConfigError(f"{name}: angle = {math.degrees(angle):.6g} deg: the angle between the "
                          f"crack and the tooth centre line must lie in (0, {math.degrees(ANGLE_MAX):g}] deg")
    if 0 < depth < MIN_DEPTH * m:
        raise ConfigError(f"{name}: depth = {depth*1e3:.4g} mm: a crack must be 0 (healthy) or at "
                          f"least {MIN_DEPTH} module = {MIN_DEPTH*m*1e3:.4g} mm long")
    fil = fillet_curve(gear)
    # keep the start a few outline spacings (m / 100) away from both ends of the fillet
    inner = slice(4 * max(1, len(fil.points) // 400), -4 * max(1, len(fil.points) // 400))
    t_lo, t_hi = float(fil.tangent[inner].min()), float(fil.tangent[inner].max())
    r_lo, r_hi = float(fil.radius[inner].min()), float(fil.radius[inner].max())
    if start_tangent is not None and start_radius is not None:
        raise ConfigError(f"{name}: start_tangent and start_radius both given: give one of them "
                          f"(or neither: the {60 if internal else 30} deg tangent point)")
    if start_radius is not None:
        r0 = _number(name, "start_radius", start_radius, "metres")
        if not r_lo < r0 < r_hi:
            raise ConfigError(f"{name}: start_radius = {r0*1e3:.6g} mm is off the root fillet of "
                              f"{gear.name}: it must lie in ({r_lo*1e3:.6g}, {r_hi*1e3:.6g}) mm "
                              "(between the root land and the involute flank)")
        p0 = fil.at_radius(r0)
    else:
        default = DEFAULT_START_TANGENT_INTERNAL if internal else DEFAULT_START_TANGENT
        tau = default if start_tangent is None else _number(
            name, "start_tangent", start_tangent, "radians")
        if not t_lo < tau < t_hi:
            raise ConfigError(f"{name}: start_tangent = {math.degrees(tau):.6g} deg is off the root "
                              f"fillet of {gear.name}: its tangent angle to the centre line runs "
                              f"from {math.degrees(t_hi):.4g} deg (root) to {math.degrees(t_lo):.4g} "
                              f"deg (involute); rule: {math.degrees(t_lo):.4g} < start_tangent < "
                              f"{math.degrees(t_hi):.4g} deg")
        p0 = fil.at_tangent(tau)
    tau0 = fil.tangent_at(p0)
    # angle between the crack and the fillet at the start; the fillet there runs along
    # (cos tau, -sin tau) (towards the flank), the crack along (-cos nu, -sin nu); on an internal
    # gear both mirrored in x: the same angle
    surf = math.acos(min(1.0, abs(math.cos(angle + tau0))))
    if surf < MIN_SURFACE_ANGLE:
        raise ConfigError(f"{name}: angle = {math.degrees(angle):.6g} deg makes {math.degrees(surf):.3g} "
                          f"deg with the fillet at the start (tangent {math.degrees(tau0):.4g} deg); rule: "
                          f"at least {math.degrees(MIN_SURFACE_ANGLE):g} deg (angle + tangent between "
                          f"{math.degrees(MIN_SURFACE_ANGLE):g} and {180 - math.degrees(MIN_SURFACE_ANGLE):g} deg)")
    d0 = _direction(angle, internal)
    outline = gear.outline().points
    circle = 0.5 * float((gear.rim_diameter if internal else getattr(gear, "bore_diameter", 0.0)) or 0.0)
    q_exit = _ray_exit(p0, d0, outline, circle, 1e-4 * m)
    q_max = q_exit - MIN_LIGAMENT * m
    if depth > q_max:
        raise ConfigError(f"{name}: depth = {depth*1e3:.4g} mm: a crack at angle "
                          f"{math.degrees(angle):.4g} deg from the fillet point at r = "
                          f"{np.hypot(*p0)*1e3:.5g} mm leaves the tooth {q_exit*1e3:.4g} mm from its "
                          f"start; rule: depth <= {q_max*1e3:.4g} mm (a ligament of {MIN_LIGAMENT} "
                          "module left)")
    tip0 = p0 + depth * d0
    half = math.pi / z
    if abs(math.atan2(tip0[1], tip0[0])) > half:
        limit = _sector_depth(p0, d0, half)
        raise ConfigError(f"{name}: depth = {depth*1e3:.4g} mm: at angle {math.degrees(angle):.4g} "
                          f"deg the crack passes below the neighbouring tooth space (polar angle "
                          f"beyond +-180/z = {math.degrees(half):.4g} deg from the tooth centre line); "
                          f"rule: depth <= {limit*1e3:.4g} mm, or a larger angle")
    return RootCrack(gear=gear_parameters(gear), tooth=int(tooth), side=int(side), depth=depth,
                     angle=angle, start_tangent=tau0, start_radius=float(np.hypot(*p0)),
                     start=tuple(float(v) for v in _to_gear(p0, tooth, side, z)),
                     tip=tuple(float(v) for v in _to_gear(tip0, tooth, side, z)),
                     exit_depth=float(q_exit), name=str(name))


def _sector_depth(p0, d0, half: float) -> float:
    """Length along p0 + t d0 to the radial line at polar angle -half [m]."""
    n = np.array([math.sin(-half), -math.cos(-half)])  # normal of the line y = x tan(-half)
    return float(-(p0 @ n) / (d0 @ n))


# ============================================================================================
# mesh
# ============================================================================================
@dataclass(frozen=True)
class CrackMesh:
    """Refinement around the crack tip.

    Parameters
    ----------
    tip_size : float
        Element size at the tip relative to the tooth element size of the mesh level (at most
        depth / ``TIP_PER_DEPTH``), at ``refine`` 0: the crack zone refines with the level.
    grading : float
        Growth of the size with the distance from the tip [m/m]; the refined zone ends where the
        size reaches the tooth size. Sizes proportional to the distance from the tip resolve the
        tip's r^(1/2) field with an error of order grading^4, whatever the tip size.
    refine : int
        Crack refinement level >= 0: the tip size halves per level (the convergence studies'
        parameter; the error of the tip elements falls as their size).
    """

    tip_size: float = TIP_SIZE
    grading: float = GRADING
    refine: int = 0

    def __post_init__(self):
        for nm in ("tip_size", "grading"):
            v = getattr(self, nm)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ConfigError(f"crack mesh {nm} = {v!r}: must be a number > 0")
        if isinstance(self.refine, bool) or not isinstance(self.refine, (int, np.integer)) or self.refine < 0:
            raise ConfigError(f"crack mesh refine = {self.refine!r}: must be an integer >= 0")

    def sizes(self, crack: RootCrack, h_tooth: float) -> tuple[float, float]:
        """(tip element size [m], grading [-]) for ``crack`` in a mesh of tooth size ``h_tooth`` [m]."""
        f = 2.0 ** -self.refine
        return min(self.tip_size * h_tooth, crack.depth / TIP_PER_DEPTH) * f, self.grading


class CrackFeature(MeshFeature):
    """The crack as a :class:`flexgear.fe.meshing.MeshFeature` of a gear body mesh."""

    def __init__(self, crack: RootCrack, h_tooth: float, crack_mesh: CrackMesh | None = None):
        self.crack = crack
        self.crack_mesh = CrackMesh() if crack_mesh is None else crack_mesh
        self.h_tip, self.grading = self.crack_mesh.sizes(crack, h_tooth)
        self.size_min = self.h_tip
        self._start_index = None
        self._tip_tag = None
        self._h = None

    def key(self) -> dict:
        return {"crack": self.crack.key(), "mesh": asdict(self.crack_mesh),
                "version": CRACK_MESH_VERSION}

    def place(self, pts, *arrays):
        """Insert the crack's start into the closed outline ``pts`` (N, 2) [m], in the segment
        nearest to it, dropping outline points closer than 0.3 spacings; ``arrays`` (per point)
        get the values of the split segment's first point. Returns ``(pts, arrays, index)``;
        :meth:`curves` starts the crack at ``index``."""
        p0 = np.asarray(self.crack.start)
        a, b = pts, np.roll(pts, -1, axis=0)
        e = b - a
        u = np.clip(np.einsum("ij,ij->i", p0 - a, e) / np.einsum("ij,ij->i", e, e), 0.0, 1.0)
        i = int(np.argmin(np.hypot(*(a + u[:, None] * e - p0).T)))
        spacing = float(np.median(np.hypot(*e.T)))
        j = i + 1
        pts = np.insert(pts, j, p0, axis=0)
        arrays = [np.insert(v, j, v[i]) for v in arrays]
        keep = np.hypot(*(pts - p0).T) >= 0.3 * spacing
        keep[j] = True
        self._start_index = int(np.count_nonzero(keep[:j]))
        return pts[keep], [v[keep] for v in arrays], self._start_index

    def outline(self, pts, kind, tooth, side):
        """Insert the start point into the fillet (:meth:`place`)."""
        pts, (kind, tooth, side), i = self.place(pts, kind, tooth, side)
        if kind[i] != FILLET or kind[(i + 1) % len(pts)] != FILLET or kind[i - 1] != FILLET:
            raise GeometryError(f"{self.crack.name}: the start point is not on a fillet of the outline")
        return pts, kind, tooth, side, (i,)

    def curves(self, geo, ptags, h):
        x, y = self.crack.tip
        self._tip_tag = geo.addPoint(x, y, 0.0, self.h_tip)
        self._h = h
        return {"crack": [geo.addLine(ptags[self._start_index], self._tip_tag)]}

    def fields(self, gmsh, background):
        fm = gmsh.model.mesh.field
        d = fm.add("Distance")
        fm.setNumbers(d, "PointsList", [self._tip_tag])
        t = fm.add("Threshold")
        fm.setNumber(t, "InField", d)
        fm.setNumber(t, "SizeMin", self.h_tip)
        fm.setNumber(t, "SizeMax", self._h)
        fm.setNumber(t, "DistMin", 0.0)
        fm.setNumber(t, "DistMax", max(self._h - self.h_tip, 0.0) / self.grading)
        fm.setNumber(t, "StopAtDistMax", 1)
        mn = fm.add("Min")
        fm.setNumbers(mn, "FieldsList", [background, t])
        return mn

    def finish(self, gm: GearMesh) -> GearMesh:
        out = split_crack(gm, self.crack)
        out.info.update({"crack": self.crack.key(), "h_crack_tip": self.h_tip,
                         "crack_grading": self.grading, "crack_refine": self.crack_mesh.refine})
        return out


def split_crack(gm: GearMesh, crack: RootCrack) -> GearMesh:
    """Duplicate the nodes of the embedded crack curve (group ``"crack"``) except its tip.

    The triangles on the tooth side of the crack line (``crack.normal``) take the copies, so the
    two faces share no node but the tip. Vertex nodes stay numbered before mid-nodes. Returns a
    new :class:`GearMesh` with groups ``"crack_body"`` and ``"crack_tooth"`` (also in
    ``"outline"``) in place of ``"crack"``.
    """
    groups = dict(gm.facet_groups)
    E = groups.pop("crack")
    P, T = gm.points, gm.triangles
    nv, N = gm.n_vertices, gm.n_nodes
    start, n = np.asarray(crack.start), crack.normal
    corners = np.unique(E[:, :2])
    tipnode = int(corners[np.argmin(np.hypot(*(P[corners] - np.asarray(crack.tip)).T))])
    if np.hypot(*(P[tipnode] - np.asarray(crack.tip))) > 1e-9 * max(1.0, np.abs(P).max()):
        raise GeometryError(f"{crack.name}: no mesh node at the crack tip")
    nodes = np.setdiff1d(np.unique(E), [tipnode])
    dc, dm = nodes[nodes < nv], nodes[nodes >= nv]
    old2new = np.arange(N)
    old2new[nv:] += len(dc)
    dup = np.full(N, -1, dtype=np.int64)
    dup[dc] = nv + np.arange(len(dc))
    dup[dm] = N + len(dc) + np.arange(len(dm))
    points = np.vstack([P[:nv], P[dc], P[nv:], P[dm]])

    def remap(cells, upper):
        out = old2new[cells]
        sub = cells[upper]
        d = dup[sub]
        out[upper] = np.where(d >= 0, d, old2new[sub])
        return out

    touch = np.isin(T, nodes).any(axis=1)
    side_t = (P[T[:, :3]].mean(axis=1) - start) @ n
    tri = remap(T, touch & (side_t > 0))
    new_groups = {}
    for name, e in groups.items():
        touch_e = np.isin(e, nodes).any(axis=1)
        side_e = (P[e[:, :2]].mean(axis=1) - start) @ n
        new_groups[name] = remap(e, touch_e & (side_e > 0))
    new_groups["crack_body"] = old2new[E]
    new_groups["crack_tooth"] = remap(E, np.ones(len(E), bool))[:, [1, 0] + list(range(2, E.shape[1]))]
    if "outline" in new_groups:
        new_groups["outline"] = np.vstack([new_groups["outline"], new_groups["crack_body"],
                                           new_groups["crack_tooth"]])
    return GearMesh(points, tri, gm.order, new_groups, key=gm.key, info=dict(gm.info))


def crack_node_pairs(gm: GearMesh) -> np.ndarray:
    """(K, 2) node pairs (body face, tooth face) at the same points of a cracked mesh's faces, the
    shared tip node left out."""
    a = np.setdiff1d(gm.node_sets["crack_body"], gm.node_sets["crack_tooth"])
    b = np.setdiff1d(gm.node_sets["crack_tooth"], gm.node_sets["crack_body"])
    if len(a) != len(b):
        raise GeometryError(f"crack faces have {len(a)} and {len(b)} unshared nodes")
    ia = np.lexsort(gm.points[a].T[::-1])
    ib = np.lexsort(gm.points[b].T[::-1])
    pairs = np.column_stack([a[ia], b[ib]])
    if not np.array_equal(gm.points[pairs[:, 0]], gm.points[pairs[:, 1]]):
        raise GeometryError("crack faces: unshared nodes do not come in coincident pairs")
    return pairs


def mesh_cracked_gear(gear, crack: RootCrack, settings: MeshSettings | None = None,
                      cache_dir=USER_CACHE, crack_mesh: CrackMesh | None = None) -> GearMesh:
    """Mesh the body of ``gear`` with ``crack`` as a slit (module docstring), cached as
    :func:`flexgear.fe.meshing.mesh_gear` (the crack and its refinement are part of the key).

    A crack of zero depth returns the healthy mesh of :func:`mesh_gear` (same key, same arrays).

    Raises
    ------
    ConfigError
        If ``crack`` was made for another gear.
    """
    settings, feature = _feature(gear, crack, settings, crack_mesh)
    return mesh_gear(gear, settings, cache_dir=cache_dir, feature=feature)


def cracked_mesh_digest(gear, crack: RootCrack, settings: MeshSettings | None = None,
                        crack_mesh: CrackMesh | None = None) -> str:
    """The key (``GearMesh.key``) of :func:`mesh_cracked_gear`'s mesh, without meshing (the
    healthy mesh's for a crack of zero depth): for caches built on the mesh [sha256 hex]."""
    return mesh_digest(gear, *_feature(gear, crack, settings, crack_mesh))


def _feature(gear, crack, settings, crack_mesh):
    """(settings, CrackFeature or None for zero depth), checked."""
    if crack.gear != gear_parameters(gear):
        raise ConfigError(f"{crack.name}: the crack was placed on another gear than {gear.name} "
                          "(root_crack(gear, ...) with this gear)")
    settings = MeshSettings() if settings is None else settings
    if not isinstance(settings, MeshSettings):
        raise ConfigError(f"settings = {settings!r}: must be a flexgear.fe.meshing.MeshSettings")
    if crack.depth == 0.0:
        return settings, None
    return settings, CrackFeature(crack, settings.sizes(float(gear.module))[0], crack_mesh)
