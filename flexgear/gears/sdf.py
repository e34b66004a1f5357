"""Signed distance field of a gear's outline over one pitch, and its on-disk cache.

Each gear's outline (involute flanks, trochoid fillets, tip and root lands, from
:mod:`flexgear.gears.geometry`) is turned once into a signed distance field (negative inside the
material) tabulated on a polar grid over one angular pitch (the teeth are identical, so the
field is periodic); the contact search (:mod:`flexgear.dynamics.contact.search`) looks the
other gear's outline samples up in it.
"""
from __future__ import annotations

import functools
import hashlib
import json
import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ..files import atomic_write, atomic_write_json, discard_files, entry_lock, sha256_file, user_cache_dir
from .geometry import SpurGear, gear_parameters

log = logging.getLogger(__name__)

# an outline sample is a corner when the outline turns there by more than this [rad]: the tip
# corner turns by 90 deg minus the pressure angle at the tip (about 60 deg for a standard tooth,
# more than 30 deg up to pointed teeth), smooth parts by ds / rho (0.03 rad at ds = m/100 on the
# m = 2 mm, rho = 0.38 m fillet)
CORNER_TURN = 0.35


@dataclass
class GearSDF:
    """Signed distance to a gear's outline on a polar grid over one pitch (tooth 0 frame).

    Attributes
    ----------
    grid : ndarray (3, nr, nphi)
        Planes: signed distance f [m] (negative inside the material), then the x and y
        components of its gradient (the unit outward normal of the nearest outline point) in the
        tooth-0 frame. The gradient is tabulated from the exact nearest points, not differenced
        from f: bilinear interpolation then gives the normal to O(h^2 / rho^2) (1e-5 rad at
        h = 10 um, rho = 3 mm) instead of the O(h / rho) (3e-3 rad) of the gradient of the
        bilinear f, which through the damping term (C times the normal velocity, to which the
        sliding velocity contributes through a tilted normal) made the force jitter by 1-2 %.
    r0, dr : float
        Radius of the first row and row spacing [m].
    phi0, dphi : float
        Angle of the first column (-pi/z) and column spacing [rad]; the last column is +pi/z.
    pitch : float
        2 pi / z [rad].
    internal : bool
        Material outside the toothed outline (ring gear).
    """

    grid: np.ndarray
    r0: float
    dr: float
    phi0: float
    dphi: float
    pitch: float
    internal: bool
    z: int


def _polyline_distance(points: np.ndarray, query: np.ndarray) -> tuple[np.ndarray, ...]:
    """Unsigned distance from query points to an open polyline (nearest vertex, then its two
    adjacent segments exactly).

    Returns
    -------
    dist : (N,) distance [m]
    foot : (N, 2) nearest point of the polyline
    seg : (N,) int, index of the segment holding it
    t : (N,) its position on that segment (0 at points[seg], 1 at points[seg + 1])
    """
    tree = cKDTree(points)
    _, idx = tree.query(query, workers=-1)  # each query alone: the same result on any number of workers
    best = np.full(len(query), np.inf)
    foot = np.empty_like(query)
    seg = np.zeros(len(query), np.int64)
    where = np.zeros(len(query))
    for off in (-1, 0):
        i0 = np.clip(idx + off, 0, len(points) - 2)
        a, b = points[i0], points[i0 + 1]
        ab = b - a
        t = np.einsum("ij,ij->i", query - a, ab) / np.einsum("ij,ij->i", ab, ab)
        t = np.clip(t, 0.0, 1.0)
        proj = a + t[:, None] * ab
        d = np.hypot(*(query - proj).T)
        closer = d < best
        best = np.where(closer, d, best)
        foot[closer] = proj[closer]
        seg[closer] = i0[closer]
        where[closer] = t[closer]
    return best, foot, seg, where


def _outline_normal(poly: np.ndarray, seg: np.ndarray, t: np.ndarray, internal: bool) -> np.ndarray:
    """Unit outward normal of the material at points of a polyline sampling a smooth outline.

    The normal is interpolated linearly along each segment between vertex normals (the mean of
    the two segments' normals; at a corner vertex, turning by more than CORNER_TURN, each
    segment keeps its own). A segment's own normal would jump by ds / rho from one segment to
    the next (2e-3 rad at ds = 5 um, rho = 3 mm); the interpolated one follows the smooth curve
    to O((ds / rho)^2). The polyline runs counter-clockwise about the gear centre: the material
    of an external gear is on its left, of an internal gear on its right.
    """
    tan = np.diff(poly, axis=0)
    tan /= np.hypot(*tan.T)[:, None]
    nseg = np.column_stack([tan[:, 1], -tan[:, 0]]) * (-1.0 if internal else 1.0)
    turn = np.abs(np.arctan2(tan[:-1, 0] * tan[1:, 1] - tan[:-1, 1] * tan[1:, 0], np.einsum("ij,ij->i", tan[:-1], tan[1:])))
    smooth = turn <= CORNER_TURN  # interior vertices 1 .. n-2
    mean = nseg[:-1] + nseg[1:]
    mean /= np.hypot(*mean.T)[:, None]
    n_start = nseg.copy()  # normal of segment i at its first vertex
    n_end = nseg.copy()  # ... at its last vertex
    n_start[1:][smooth] = mean[smooth]
    n_end[:-1][smooth] = mean[smooth]
    n = (1.0 - t)[:, None] * n_start[seg] + t[:, None] * n_end[seg]
    return n / np.hypot(*n.T)[:, None]


def build_sdf(gear: SpurGear, resolution: float | None = None) -> GearSDF:
    """Tabulate the signed distance to ``gear``'s outline.

    Parameters
    ----------
    gear : SpurGear
    resolution : float, optional
        Grid spacing [m] in radius and arc length (default module / 200, 10 um for m = 2 mm).
        Bilinear interpolation error ~ h^2 / (8 rho) with rho >= the fillet radius: < 20 nm;
        for the tabulated normal ~ h^2 / (8 rho^2).
    """
    R, P, q, grid = _polar_grid(gear, resolution)
    one = gear.tooth_outline(ds=gear.module / 400)
    poly = _three_teeth(gear, one.points, one.points, one.points)
    lo, hi = min(gear.rf, gear.ra), max(gear.rf, gear.ra)
    # inside test from the generated half-tooth angle (single valued in r)
    half = gear.half_angle(np.clip(R, lo, hi))
    within = np.abs(P) < half
    if gear.internal:
        inside = (R > gear.rf) | ((R >= gear.ra) & within)
    else:
        inside = (R < gear.rf) | ((R <= gear.ra) & within)
    return _field(gear, poly, q, R, inside, grid)


def build_tooth_sdf(gear: SpurGear, before: np.ndarray, tooth: np.ndarray, after: np.ndarray,
                    resolution: float | None = None) -> GearSDF:
    """:func:`build_sdf` of one tooth's pitch sector for modified outlines (a faulty tooth or a
    neighbour of one): ``tooth`` is the sector's tooth outline, ``before`` / ``after`` those of
    the teeth at -pitch / +pitch, each in its own tooth frame and sampled as
    :meth:`~flexgear.gears.geometry.SpurGear.tooth_outline` (:func:`flexgear.gears.modified.tooth_outline`).
    The grid is the healthy one's; inside and outside from the parity of the outline's crossings
    of the radial ray outward from each node (the outline need not be single valued in r)."""
    R, P, q, grid = _polar_grid(gear, resolution)
    poly = _three_teeth(gear, before, tooth, after)
    inside = _inside_by_crossings(poly, R[:, 0], P[0], gear.internal)
    return _field(gear, poly, q, R, inside, grid)


def _polar_grid(gear: SpurGear, resolution):
    """The field's polar grid over one pitch: (R, P) node radii and angles (nr, nphi), the nodes
    (nr nphi, 2) and (r0, dr, phi0, dphi)."""
    m = gear.module
    h = m / 200 if resolution is None else resolution
    lo, hi = min(gear.rf, gear.ra), max(gear.rf, gear.ra)
    margin = 0.3 * m
    r0, r1 = lo - margin, hi + margin
    nr = int(math.ceil((r1 - r0) / h)) + 1
    pitch = gear.pitch_angle
    nphi = int(math.ceil(pitch * r1 / h)) + 1
    rs = r0 + (r1 - r0) * np.arange(nr) / (nr - 1)
    phis = -pitch / 2 + pitch * np.arange(nphi) / (nphi - 1)
    R, P = np.meshgrid(rs, phis, indexing="ij")
    q = np.column_stack([(R * np.cos(P)).ravel(), (R * np.sin(P)).ravel()])
    return R, P, q, (r0, (r1 - r0) / (nr - 1), -pitch / 2, pitch / (nphi - 1))


def _three_teeth(gear: SpurGear, before, tooth, after) -> np.ndarray:
    """The outlines of three consecutive teeth (each in its own frame) as one polyline in the
    middle tooth's frame, repeated points dropped."""
    pitch = gear.pitch_angle
    pts = []
    for k, one in zip((-1, 0, 1), (before, tooth, after)):
        a = k * pitch
        c, s = math.cos(a), math.sin(a)
        pts.append(one @ np.array([[c, s], [-s, c]]))
    poly = np.vstack(pts)
    keep = np.concatenate([[True], np.hypot(*np.diff(poly, axis=0).T) > 1e-12])
    return poly[keep]


def _inside_by_crossings(poly: np.ndarray, rs: np.ndarray, phis: np.ndarray, internal: bool) -> np.ndarray:
    """Material flags (nr, nphi) of the polar grid nodes (radii rs, angles phis) from the parity of
    the crossings of ``poly`` with the ray from each node radially outward: the ray of an
    external gear ends outside the material, a ring's in its rim. A segment spans the angles
    [min, max) of its ends, so a ray through a vertex counts once where the outline passes it
    and zero or two times where it turns back."""
    ang = np.arctan2(poly[:, 1], poly[:, 0])
    a0, a1 = ang[:-1], ang[1:]
    lo, hi = np.minimum(a0, a1), np.maximum(a0, a1)
    j0 = np.searchsorted(phis, lo, "left")
    j1 = np.searchsorted(phis, hi, "left")
    odd = np.zeros((len(rs), len(phis)), bool)
    for i in np.nonzero(j1 > j0)[0]:
        p0, d = poly[i], poly[i + 1] - poly[i]
        for j in range(j0[i], j1[i]):
            u = np.array([math.cos(phis[j]), math.sin(phis[j])])
            t = -(u[0] * p0[1] - u[1] * p0[0]) / (u[0] * d[1] - u[1] * d[0])
            rc = math.hypot(*(p0 + t * d))
            odd[:, j] ^= rs < rc
    return ~odd if internal else odd


def _field(gear: SpurGear, poly: np.ndarray, q: np.ndarray, R: np.ndarray, inside: np.ndarray, grid) -> GearSDF:
    """The GearSDF of the outline polyline ``poly`` at the grid nodes ``q`` (material flags
    ``inside``)."""
    dist, foot, seg, tseg = _polyline_distance(poly, q)
    dist = dist.reshape(R.shape)
    f = np.where(inside, -dist, dist)
    # gradient of f: the outward normal of the outline at the nearest point; where that point is
    # a corner vertex (the fan of directions outside the tip corner, the ridge inside), the unit
    # vector from it, pointing out of the material
    g = _outline_normal(poly, seg, tseg, gear.internal)
    tan = np.diff(poly, axis=0)
    ang = np.arctan2(tan[:, 1], tan[:, 0])
    corner = np.zeros(len(poly), bool)
    corner[1:-1] = np.abs((np.diff(ang) + np.pi) % (2 * np.pi) - np.pi) > CORNER_TURN
    at_corner = ((tseg <= 0.0) & corner[seg]) | ((tseg >= 1.0) & corner[seg + 1])
    sign = np.where(inside, -1.0, 1.0).ravel()
    d = np.maximum(dist.ravel(), 1e-300)
    fan = at_corner & (dist.ravel() > 1e-9)
    g[fan] = (sign[fan, None] * (q[fan] - foot[fan]) / d[fan, None])
    out = np.stack([f, g[:, 0].reshape(R.shape), g[:, 1].reshape(R.shape)])
    r0, dr, phi0, dphi = grid
    return GearSDF(grid=np.ascontiguousarray(out), r0=r0, dr=dr, phi0=phi0, dphi=dphi, pitch=gear.pitch_angle,
                   internal=gear.internal, z=gear.z)


#: Bump when the content of a cached signed distance field changes (invalidates old entries).
SDF_FORMAT = 1


def sdf_cache_key(gear: SpurGear, resolution: float | None) -> tuple[str, dict]:
    """``(sha256 hex, key dict)`` of a gear's signed distance field: the geometry parameters, the
    grid spacing, :data:`SDF_FORMAT`, the source of the functions that build the field and of
    the outline generation (:mod:`flexgear.gears.geometry`), and the numpy / scipy versions, so
    that a change of any of them rebuilds the field."""
    import inspect

    import scipy

    from . import geometry

    code = hashlib.sha256()
    for fn in (build_sdf, _polar_grid, _three_teeth, _field, _polyline_distance, _outline_normal):
        code.update(inspect.getsource(fn).encode())
    code.update(repr(CORNER_TURN).encode())
    code.update(Path(geometry.__file__).read_bytes())
    key = {"format": SDF_FORMAT, "geometry": gear_parameters(gear),
           "resolution": None if resolution is None else float(resolution), "code": code.hexdigest(),
           "numpy": np.__version__, "scipy": scipy.__version__}
    text = json.dumps(key, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest(), json.loads(text)


def load_sdf(cache_dir, digest: str, key: dict) -> GearSDF | None:
    """A cached field; ``None`` if missing, stale or corrupt (then it is removed)."""
    npz, side = Path(cache_dir) / f"sdf-{digest}.npz", Path(cache_dir) / f"sdf-{digest}.json"
    if not side.exists() and not npz.exists():
        return None
    try:
        meta = json.loads(side.read_text())
        if meta.get("key") != key:
            raise ValueError("stale cache entry (key mismatch)")
        if sha256_file(npz) != meta["npz_sha256"]:
            raise ValueError("corrupt cache entry (checksum mismatch)")
        with np.load(npz) as z:
            grid = np.ascontiguousarray(z["grid"])
        return GearSDF(grid=grid, r0=meta["r0"], dr=meta["dr"], phi0=meta["phi0"], dphi=meta["dphi"],
                       pitch=meta["pitch"], internal=bool(meta["internal"]), z=int(meta["z"]))
    except Exception as exc:  # noqa: BLE001 - any failure means: rebuild
        log.warning("signed distance cache %s unusable (%s); rebuilding", npz.name, exc)
        discard_files(side, npz)
        return None


def write_sdf(cache_dir, digest: str, key: dict, sdf: GearSDF) -> None:
    """Write a field atomically (the ``.npz``, then the ``.json`` with its checksum); a cache
    that cannot be written is skipped."""
    cache_dir = Path(cache_dir)
    npz, side = cache_dir / f"sdf-{digest}.npz", cache_dir / f"sdf-{digest}.json"

    def write(tmp):
        with open(tmp, "wb") as fh:
            np.savez(fh, grid=sdf.grid)

    try:
        cache_dir.mkdir(parents=True, exist_ok=True)
        atomic_write(npz, write)
        atomic_write_json(side, {"key": key, "npz_sha256": sha256_file(npz), "r0": sdf.r0, "dr": sdf.dr,
                                 "phi0": sdf.phi0, "dphi": sdf.dphi, "pitch": sdf.pitch,
                                 "internal": bool(sdf.internal), "z": int(sdf.z)})
    except OSError as exc:
        log.warning("signed distance cache not written (%s)", exc)


def sdf_cache_dir() -> Path:
    """The per-user cache of signed distance fields: ``sdf/`` in
    :func:`flexgear.files.user_cache_dir`."""
    return user_cache_dir() / "sdf"


@functools.lru_cache(maxsize=32)
def gear_sdf(gear: SpurGear, resolution: float | None) -> GearSDF:
    """:func:`build_sdf`, memoised per gear geometry (gears are immutable) and cached on disk in
    :func:`sdf_cache_dir` (keyed by :func:`sdf_cache_key`; a stale or corrupt entry is rebuilt):
    the fields are most of a rigid model's build time (about 0.5 s per gear)."""
    digest, key = sdf_cache_key(gear, resolution)
    cache = sdf_cache_dir()
    with entry_lock(cache, f"sdf-{digest}"):
        sdf = load_sdf(cache, digest, key)
        if sdf is None:
            sdf = build_sdf(gear, resolution)
            write_sdf(cache, digest, key, sdf)
    return sdf


def tooth_sdf(gear: SpurGear, before: np.ndarray, tooth: np.ndarray, after: np.ndarray,
              resolution: float | None) -> GearSDF:
    """:func:`build_tooth_sdf`, cached on disk in :func:`sdf_cache_dir` as :func:`gear_sdf` is,
    keyed by the healthy field's key, the three outlines' samples and the source of the
    functions that tell inside from outside: a faulty gear's fields are built once."""
    import inspect

    digest, key = sdf_cache_key(gear, resolution)
    h = hashlib.sha256(digest.encode())
    for fn in (build_tooth_sdf, _inside_by_crossings):
        h.update(inspect.getsource(fn).encode())
    for pts in (before, tooth, after):
        h.update(np.ascontiguousarray(pts, float).tobytes())
    key = {**key, "tooth": h.hexdigest()}
    digest = hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()
    cache = sdf_cache_dir()
    with entry_lock(cache, f"sdf-{digest}"):
        sdf = load_sdf(cache, digest, key)
        if sdf is None:
            sdf = build_tooth_sdf(gear, before, tooth, after, resolution)
            write_sdf(cache, digest, key, sdf)
    return sdf
