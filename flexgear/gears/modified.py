"""Modified tooth outlines: faults (spall, chip, missing tooth) and profile errors (slope, form,
tip and root relief) applied to the generated outline, and the per-tooth rigid offsets of pitch
errors and eccentricity.

A healthy tooth's outline is :meth:`~flexgear.gears.geometry.SpurGear.tooth_outline` (tooth 0's frame: centre line along
+x; points counter-clockwise from mid-space at -pi/z to mid-space at +pi/z, the right half
first, both halves sharing the tip centre point). :func:`tooth_outline` returns the same sampling
with the tooth's modifications, as a :class:`ToothOutline`; with no modification (or only zero-
size ones) its arrays are those of the healthy outline, bit for bit.

How the modifications are drawn
    * A normal offset delta of an involute (material added > 0) is the same involute turned by
      delta / r_b about the gear axis (parallel involutes), so profile errors and a spall's
      floor turn flank points at constant radius by delta(r) / r_b. The tip land keeps its radius
      and is stretched to the moved corner; the profile errors' offset at the form circle is
      carried down the fillet, fading linearly to zero at the root circle (no step).
    * Spall: the flank between its radii is sunk by its depth, with walls along the circles at
      both ends (sampled at the outline's spacing).
    * Chip: the outline between the flank point ``profile_size`` below the tip corner and the tip
      point ``tip_size`` from it (arc lengths along the outline) becomes the straight chord.
    * Missing tooth: everything beyond the cut circle (root circle + height_fraction x tooth
      height) becomes an arc of that circle (``TIP`` kind; ``ROOT`` when cut to the root circle).

Partial face width (plane model)
    A spall or chip over the fraction w < 1 of the face width leaves the outline (the outermost
    material across the face width) unchanged and marks the affected points with
    ``width = 1 - w`` (the fraction of the face width whose surface is the outline) and
    ``recess`` (how far the rest of the face lies below it, along the normal). The contact law of
    such a point is the slicing method with two slices (:func:`partial_width_force`): the healthy
    band carries the law scaled by its width, the faulted band the same law shifted by the recess.
    It is exact for a fault of uniform depth across its part of the face width and a law that is
    additive along the face width, as the plane model's force per face width is.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import GeometryError
from .faults import Chip, Crack, GearErrors, Missing, ProfileErrors, Spall
from .geometry import FILLET, FLANK, ROOT, TIP, Outline, SpurGear


@dataclass
class ToothOutline:
    """One tooth's outline in its own frame, sampled as :meth:`~flexgear.gears.geometry.SpurGear.tooth_outline`.

    Attributes
    ----------
    points : ndarray (N, 2)
        Outline points [m] (centre line along +x), counter-clockwise from mid-space at -pi/z to
        mid-space at +pi/z; the right half (``side`` -1) runs to the tip centre, the left half on.
    kind, side : ndarray (N,) of int
        As :class:`~flexgear.gears.geometry.Outline` (``ROOT``, ``FILLET``, ``FLANK``, ``TIP``;
        -1 right, +1 left).
    width : ndarray (N,)
        Fraction of the face width whose surface is this outline point (1 healthy).
    recess : ndarray (N,)
        Depth [m] below the point, along the outline's normal, of the rest (1 - width) of the
        face width (0 where width = 1).
    modified : ndarray (N,) of bool
        Points that differ from the healthy outline (moved, inserted, or partial width).
    tooth : int
        Tooth index.
    offset : ToothOffset
        The tooth's rigid offset (pitch error, eccentricity), not applied to ``points``.
    """

    points: np.ndarray
    kind: np.ndarray
    side: np.ndarray
    width: np.ndarray
    recess: np.ndarray
    modified: np.ndarray
    tooth: int = 0
    offset: "ToothOffset" = field(default_factory=lambda: ToothOffset())

    def __len__(self):
        return len(self.points)

    @property
    def healthy(self) -> bool:
        """True if the outline is the healthy one (no point modified)."""
        return not self.modified.any()

    def placed(self, gear: SpurGear) -> np.ndarray:
        """The points (N, 2) [m] in the gear frame: turned to the tooth's place 2 pi k / z and by
        its offset angle, and shifted by its offset (:class:`ToothOffset`)."""
        return self.offset.place(self.points, self.tooth * gear.pitch_angle)


@dataclass(frozen=True)
class ToothOffset:
    """Rigid offset of a tooth: a point p of the tooth's frame lies at R(2 pi k/z + angle) p + shift
    in the gear frame (R: counter-clockwise rotation)."""

    angle: float = 0.0  # rad, counter-clockwise, from the pitch errors
    shift: tuple = (0.0, 0.0)  # m, gear frame, from the eccentricity

    @property
    def null(self) -> bool:
        return self.angle == 0.0 and self.shift[0] == 0.0 and self.shift[1] == 0.0

    def place(self, points: np.ndarray, nominal: float) -> np.ndarray:
        """Points (n, 2) of the tooth's frame in the gear frame, the tooth's nominal angle
        ``nominal`` [rad] plus the offset."""
        a = nominal + self.angle
        c, s = math.cos(a), math.sin(a)
        out = points @ np.array([[c, s], [-s, c]])
        if self.shift[0] or self.shift[1]:
            out = out + np.asarray(self.shift, float)
        return out

    def displacement(self, point, nominal: float = 0.0) -> np.ndarray:
        """Displacement (2,) [m] of the gear-frame point ``point`` of a tooth at the nominal angle
        ``nominal`` caused by the offset: R(angle) p + shift - p. Its component along a mesh's line
        of action is the error the mesh sees there."""
        p = np.asarray(point, float)
        c, s = math.cos(self.angle), math.sin(self.angle)
        return np.array([c * p[0] - s * p[1], s * p[0] + c * p[1]]) + np.asarray(self.shift, float) - p


def tooth_offsets(gear: SpurGear, errors: GearErrors | None) -> list[ToothOffset]:
    """The rigid offsets of the z teeth of ``gear`` (pitch errors and eccentricity)."""
    z = gear.z
    angles = np.zeros(z)
    shift = (0.0, 0.0)
    if errors is not None and errors.pitch is not None and not errors.pitch.null:
        if len(errors.pitch.deviations) != z:
            raise GeometryError(f"{gear.name}: {len(errors.pitch.deviations)} pitch deviations for {z} teeth")
        angles = errors.pitch.angles(gear)
    if errors is not None and errors.eccentricity is not None and not errors.eccentricity.null:
        shift = tuple(float(v) for v in errors.eccentricity.shift())
    return [ToothOffset(float(a), shift) for a in angles]


# --------------------------------------------------------------------------------------------
# half-tooth operations. A half is "left-like": the left half, or the right half mirrored
# (y -> -y), ordered from the space centre (polar angle +pi/z) to the tip centre (angle 0).
class _Half:
    def __init__(self, pts, kind):
        self.p = np.array(pts, float)
        self.kind = np.array(kind)
        n = len(self.p)
        self.width = np.ones(n)
        self.recess = np.zeros(n)
        self.mod = np.zeros(n, bool)

    @property
    def r(self):
        return np.hypot(self.p[:, 0], self.p[:, 1])

    def insert(self, i, pts, kind, width=None, recess=None, mod=True):
        """Insert points before index i."""
        m = len(pts)
        self.p = np.insert(self.p, i, pts, axis=0)
        self.kind = np.insert(self.kind, i, np.full(m, kind))
        self.width = np.insert(self.width, i, np.ones(m) if width is None else width)
        self.recess = np.insert(self.recess, i, np.zeros(m) if recess is None else recess)
        self.mod = np.insert(self.mod, i, np.full(m, mod))

    def dedupe(self):
        """Drop points that repeat their predecessor (inserted at a sample)."""
        keep = np.concatenate([[True], np.hypot(*np.diff(self.p, axis=0).T) > 1e-15])
        if not keep.all():
            self.p, self.kind, self.width = self.p[keep], self.kind[keep], self.width[keep]
            self.recess, self.mod = self.recess[keep], self.mod[keep]

    def cut(self, i, j, pts, kind):
        """Replace points i..j-1 by ``pts`` (all modified)."""
        self.p = np.concatenate([self.p[:i], pts, self.p[j:]])
        self.kind = np.concatenate([self.kind[:i], np.full(len(pts), kind), self.kind[j:]])
        self.width = np.concatenate([self.width[:i], np.ones(len(pts)), self.width[j:]])
        self.recess = np.concatenate([self.recess[:i], np.zeros(len(pts)), self.recess[j:]])
        self.mod = np.concatenate([self.mod[:i], np.ones(len(pts), bool), self.mod[j:]])


def _turn(p, a):
    """Points (n, 2) turned counter-clockwise by angles a (n,) about the origin."""
    c, s = np.cos(a), np.sin(a)
    return np.column_stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]])


def _arc(radius, t0, t1, ds):
    """Points of the circle of ``radius`` from polar angle t0 to t1, spacing <= ds (both ends)."""
    n = max(2, int(math.ceil(abs(t1 - t0) * radius / ds)) + 1)
    t = np.linspace(t0, t1, n)
    return np.column_stack([radius * np.cos(t), radius * np.sin(t)])


def _index_at(r, value):
    """Fractional index (i + fraction) where the monotonic sequence r reaches ``value``."""
    idx = np.arange(len(r), dtype=float)
    if r[-1] < r[0]:
        return float(np.interp(-value, -r, idx))
    return float(np.interp(value, r, idx))


def _at(p, t):
    """The point at fractional index t of the polyline p (exactly a sample at whole t)."""
    i = min(int(math.floor(t)), len(p) - 2)
    f = t - i
    if f == 0.0:
        return p[i].copy()
    if f == 1.0:
        return p[i + 1].copy()
    return p[i] + f * (p[i + 1] - p[i])


def _profile(h: _Half, gear: SpurGear, prof: ProfileErrors):
    """Turn flank points by delta(r)/r_b, carry the form-circle offset down the fillet, stretch
    the tip land to the moved corner."""
    r = h.r
    fl = h.kind == FLANK
    d = np.zeros(len(r))
    d[fl] = prof.offset(gear, r[fl])
    dF = float(prof.offset(gear, gear.r_form))
    fil = h.kind == FILLET
    if dF != 0.0 and fil.any():
        d[fil] = dF * np.clip((r[fil] - gear.rf) / (gear.r_form - gear.rf), 0.0, 1.0)
    tip = np.nonzero(h.kind == TIP)[0]
    corner = int(np.nonzero(fl)[0][-1])
    th_c = math.atan2(h.p[corner, 1], h.p[corner, 0])
    a = d / gear.rb
    if len(tip) and a[corner] != 0.0:
        th = np.arctan2(h.p[tip, 1], h.p[tip, 0])
        a[tip] = th * (a[corner] / th_c)  # stretch the tip land: angle th -> th (th_c + a_c) / th_c
    move = a != 0.0
    h.p[move] = _turn(h.p[move], a[move])
    h.mod |= move


def _wall(p, a, ds):
    """Points of the circular wall from p turned by 0 to a [rad] about the gear axis, spacing <= ds
    (both ends)."""
    n = max(1, int(math.ceil(abs(a) * math.hypot(*p) / ds)))
    return _turn(np.repeat(p[None, :], n + 1, axis=0), np.linspace(0.0, a, n + 1))


def _spall(h: _Half, gear: SpurGear, f: Spall, ds: float):
    r = h.r
    fl = np.nonzero(h.kind == FLANK)[0]
    i0, i1 = fl[0], fl[-1] + 1
    rs = r[i0:i1]
    ta, tb = sorted((_index_at(rs, f.start_radius), _index_at(rs, f.end_radius)))
    ta, tb = ta + i0, tb + i0
    ja, jb = int(math.floor(ta)) + 1, int(math.floor(tb)) + 1  # points strictly inside: ja..jb-1
    pa, pb = _at(h.p, ta), _at(h.p, tb)
    if f.width_fraction == 1.0:
        a = -f.depth / gear.rb
        h.p[ja:jb] = _turn(h.p[ja:jb], np.full(jb - ja, a))
        h.mod[ja:jb] = True
        h.insert(jb, _wall(pb, a, ds)[::-1], FLANK)
        h.insert(ja, _wall(pa, a, ds), FLANK)
    else:
        w = 1.0 - f.width_fraction
        h.width[ja:jb] = w
        h.recess[ja:jb] = f.depth
        h.mod[ja:jb] = True
        h.insert(jb, [pb], FLANK, width=[w], recess=[f.depth])
        h.insert(ja, [pa], FLANK, width=[w], recess=[f.depth])


def _chip(h: _Half, f: Chip, ds: float):
    corner = int(np.nonzero(h.kind == FLANK)[0][-1])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(h.p, axis=0).T))])
    s1, s2 = s[corner] - f.profile_size, s[corner] + f.tip_size
    t1 = float(np.interp(s1, s, np.arange(len(s))))
    t2 = float(np.interp(s2, s, np.arange(len(s))))
    p1, p2 = _at(h.p, t1), _at(h.p, t2)
    j1, j2 = int(math.floor(t1)) + 1, min(int(math.ceil(t2)), len(h.p) - 1)  # replaced: j1..j2-1
    j2 = max(j2, j1)
    if f.width_fraction == 1.0:
        n = max(2, int(math.ceil(math.hypot(*(p2 - p1)) / ds)) + 1)
        chord = p1 + np.linspace(0.0, 1.0, n)[:, None] * (p2 - p1)
        chord[-1] = p2
        h.cut(j1, j2, chord, FLANK)
    else:
        t = (p2 - p1) / max(math.hypot(*(p2 - p1)), 1e-300)
        nrm = np.array([-t[1], t[0]])
        depth = np.abs((h.p[j1:j2] - p1) @ nrm)
        h.width[j1:j2] = 1.0 - f.width_fraction
        h.recess[j1:j2] = depth
        h.mod[j1:j2] = True


def _missing(h: _Half, gear: SpurGear, f: Missing, ds: float):
    if f.height_fraction == 0.0:
        arc = _arc(gear.rf, math.pi / gear.z, 0.0, ds)
        h.cut(0, len(h.p), arc, ROOT)
        return
    rc = gear.rf + f.height_fraction * (gear.ra - gear.rf)
    r = h.r
    t = _index_at(r, rc)
    pc = _at(h.p, t)
    j = int(math.floor(t)) + 1
    arc = _arc(rc, math.atan2(pc[1], pc[0]), 0.0, ds)
    h.cut(j, len(h.p), arc, TIP)


# --------------------------------------------------------------------------------------------
def _healthy(one: Outline, tooth: int, offset: "ToothOffset") -> ToothOutline:
    n = len(one.points)
    return ToothOutline(points=one.points, kind=one.kind, side=one.side, width=np.ones(n), recess=np.zeros(n),
                        modified=np.zeros(n, bool), tooth=tooth, offset=offset)


def tooth_outline(gear: SpurGear, tooth: int = 0, faults=(), errors: GearErrors | None = None,
                  ds: float | None = None, offset: ToothOffset | None = None) -> ToothOutline:
    """The outline of tooth ``tooth`` of ``gear`` with its faults and the gear's profile errors.

    Parameters
    ----------
    gear : SpurGear
    tooth : int
        Tooth index (the outline is in that tooth's own frame).
    faults : sequence of ToothFault
        Faults of this gear body; those on other teeth are ignored; cracks leave the outline as
        it is (the FE phase cuts them).
    errors : GearErrors, optional
        The body's errors: the profile errors shape every tooth; pitch errors and eccentricity
        give ``offset`` (:func:`tooth_offsets`) unless it is given.
    ds : float, optional
        Largest sample spacing [m] (default module / 100, as :meth:`~flexgear.gears.geometry.SpurGear.tooth_outline`).
    """
    ds = gear.module / 100 if ds is None else ds
    one = gear.tooth_outline(ds)
    if offset is None:
        offset = tooth_offsets(gear, errors)[tooth] if errors is not None else ToothOffset()
    mine = [f for f in faults if f.tooth == tooth and not f.null and not isinstance(f, Crack)]
    prof = errors.profile if errors is not None and errors.profile is not None and not errors.profile.null else None
    if not mine and prof is None:
        return _healthy(one, tooth, offset)
    n = len(one.points)
    nh = (n + 1) // 2
    halves = {}
    for side, idx in ((-1, np.arange(nh)), (1, np.arange(n - 1, nh - 2, -1))):
        p = one.points[idx].copy()
        p[:, 1] *= side
        halves[side] = _Half(p, one.kind[idx])
    for side, h in halves.items():
        if prof is not None:
            _profile(h, gear, prof)
        for f in mine:
            if getattr(f, "flank", None) != side:
                continue
            if isinstance(f, Spall):
                _spall(h, gear, f, ds)
            elif isinstance(f, Chip):
                _chip(h, f, ds)
        for f in mine:
            if isinstance(f, Missing):
                _missing(h, gear, f, ds)
        h.dedupe()
    right, left = halves[-1], halves[1]
    rp = right.p.copy()
    rp[:, 1] *= -1
    pts = np.vstack([rp, left.p[::-1][1:]])

    def join(a, b):
        return np.concatenate([a, b[::-1][1:]])

    side = np.concatenate([-np.ones(len(rp), int), np.ones(len(left.p) - 1, int)])
    return ToothOutline(points=pts, kind=join(right.kind, left.kind), side=side, width=join(right.width, left.width),
                        recess=join(right.recess, left.recess), modified=join(right.mod, left.mod), tooth=tooth,
                        offset=offset)


def faulty_teeth(faults, z: int | None = None) -> list[int]:
    """Sorted tooth indices whose outline a fault changes (cracks included: they change the
    tooth's compliance); with ``z``, also their neighbours (tooth +- 1 mod z), which the later
    phases give their own tables too."""
    teeth = {f.tooth for f in faults if not f.null}
    if z is not None:
        teeth |= {(k + d) % z for k in list(teeth) for d in (-1, 1)}
    return sorted(teeth)


@dataclass
class GearOutline(Outline):
    """A whole gear's outline (:class:`~flexgear.gears.geometry.Outline`) with the tooth outlines'
    ``width``, ``recess`` and ``modified`` arrays."""

    width: np.ndarray = None
    recess: np.ndarray = None
    modified: np.ndarray = None


def gear_outline(gear: SpurGear, faults=(), errors: GearErrors | None = None, ds: float | None = None) -> GearOutline:
    """The whole gear's toothed outline in the gear frame (closed polygon, counter-clockwise, last
    point != first), as :meth:`~flexgear.gears.geometry.SpurGear.outline` with the faults, profile errors and rigid tooth
    offsets applied: what an FE mesh of the faulty gear is built on. With pitch errors the root
    lands of neighbouring teeth meet half way between their (moved) centre lines."""
    offs = tooth_offsets(gear, errors) if errors is not None else [ToothOffset()] * gear.z
    turned = any(o.angle != 0.0 for o in offs)
    P, T, K, S, W, R, M = [], [], [], [], [], [], []
    pitch = gear.pitch_angle
    for k in range(gear.z):
        o = tooth_outline(gear, k, faults, errors, ds, offset=ToothOffset(offs[k].angle))
        n1 = len(o.points) - 1  # the last point is the next tooth's first
        p = o.offset.place(o.points[:n1], k * pitch)
        arrays = [o.kind[:n1], o.side[:n1], o.width[:n1], o.recess[:n1], o.modified[:n1] | (offs[k].angle != 0.0)]
        if turned:  # trim the root lands to the sector between the neighbours' centre lines
            ca = k * pitch + offs[k].angle
            lo = ca - 0.5 * (pitch + offs[k].angle - offs[k - 1].angle)
            hi = ca + 0.5 * (pitch + offs[(k + 1) % gear.z].angle - offs[k].angle)
            ang = ca + np.angle(np.exp(1j * (np.arctan2(p[:, 1], p[:, 0]) - ca)))
            sel = (ang >= lo) & (ang < hi)
            p = np.vstack([[gear.rf * math.cos(lo), gear.rf * math.sin(lo)], p[sel]])
            first = (ROOT, -1, 1.0, 0.0, True)
            arrays = [np.concatenate([[v], a[sel]]) for v, a in zip(first, arrays)]
        P.append(p)
        T.append(np.full(len(p), k))
        for lst, a in zip((K, S, W, R, M), arrays):
            lst.append(a)
    pts = np.vstack(P)
    shift = offs[0].shift if offs else (0.0, 0.0)
    if shift[0] or shift[1]:
        pts = pts + np.asarray(shift, float)
    return GearOutline(pts, np.concatenate(T), np.concatenate(K), np.concatenate(S), width=np.concatenate(W),
                       recess=np.concatenate(R), modified=np.concatenate(M))


#: Fault kinds that remove material from the outline (and so from a flexible gear's FE body).
OUTLINE_FAULTS = ("spall", "chip", "missing")


class FaultyGear:
    """A gear whose outline carries its tooth faults: what the FE mesh of a faulty flexible gear is
    built on (:func:`flexgear.fe.meshing.mesh_gear` reads ``outline()``).

    ``outline()`` is :func:`gear_outline` with ``faults`` (spall, chip, missing tooth across the
    whole face width); every other attribute is the wrapped gear's. The outline's fingerprint
    enters the mesh's cache key, so a faulty and a healthy gear never share a mesh.
    """

    def __init__(self, gear: SpurGear, faults=()):
        self.gear = gear
        self.faults = tuple(faults)

    def __getattr__(self, name):
        if name.startswith("__") or name in ("gear", "faults"):
            raise AttributeError(name)
        return getattr(self.gear, name)

    def outline(self, ds: float | None = None) -> GearOutline:
        """The whole gear's outline with the faults (:func:`gear_outline`)."""
        return gear_outline(self.gear, self.faults, ds=ds)


def partial_width_force(delta, K: float, e: float, width, recess):
    """Contact force [N] of the plane model at an outline point with a partial face-width fault:
    the slicing method with two slices of the law F = K delta^e (K for the whole face width),
    F = K [width delta_+^e + (1 - width) (delta - recess)_+^e] for the penetration ``delta`` [m]
    at the outline; width = 1 gives the healthy law."""
    d = np.asarray(delta, float)
    w = np.asarray(width, float)
    h = np.asarray(recess, float)
    return K * (w * np.maximum(d, 0.0) ** e + (1.0 - w) * np.maximum(d - h, 0.0) ** e)
