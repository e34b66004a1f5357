"""The gearbox housing as a plane body, and the sensors on it: geometry only (no FE).

The housing is seen along the gear axis, in the plane of the gears, as one plane body of two
regions (``docs/guide/housing.md``):

* the **wall** (shell): between the outer :class:`HousingOutline` and the same outline offset inwards
  by ``wall_thickness``; out-of-plane thickness ``depth`` (the axial length of the wall);
* the **cover**: inside the wall, the two end covers seen together; out-of-plane thickness
  ``cover_thickness``, with the bores of the bearing seats and the holes of the ring gear's
  bolts.

The gears lie in front of the cover (another axial plane), so they may overlap it in the plane;
they must not cross the wall. Feet are pads of the outer outline held to ground by springs.

Everything here is SI (m, rad). Angles are counter-clockwise from +x about the body's centre.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from .material import Material

OUTLINES = ("circle", "rounded_rectangle")
SENSOR_BODIES = ("housing", "ring")
QUANTITIES = ("acceleration", "velocity", "displacement")
#: time derivative of the displacement that each quantity is
QUANTITY_ORDER = {"displacement": 0, "velocity": 1, "acceleration": 2}
QUANTITY_UNITS = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}
DIRECTIONS = ("radial", "tangential", "x", "y")
#: planet-pass windows (:func:`flexgear.reduction.paths.planet_pass_window`)
WINDOWS = ("hann", "rectangular")
#: grey cast iron EN-GJL-250 (EN 1561): E 103-118 GPa, nu 0.26, 7250 kg/m^3
CAST_IRON = Material(E=1.1e11, nu=0.26, rho=7250.0)


@dataclass(frozen=True)
class HousingOutline:
    """A closed convex outline: a rounded rectangle (a circle is one with ``width = height =
    2 corner_radius``), counter-clockwise.

    Parameters
    ----------
    centre : (float, float)
        Centre [m].
    width, height : float
        Extent along x and y [m].
    corner_radius : float
        Radius of the four corners [m], 0 <= r <= min(width, height) / 2.
    """

    centre: tuple
    width: float
    height: float
    corner_radius: float

    @classmethod
    def circle(cls, centre, diameter: float) -> "HousingOutline":
        """A circle of ``diameter`` [m] about ``centre``."""
        return cls((float(centre[0]), float(centre[1])), float(diameter), float(diameter), 0.5 * float(diameter))

    @property
    def is_circle(self) -> bool:
        return self.width == self.height and 2.0 * self.corner_radius == self.width

    @property
    def kind(self) -> str:
        return "circle" if self.is_circle else "rounded_rectangle"

    def offset(self, d: float) -> "HousingOutline":
        """The outline moved outwards by ``d`` [m] (inwards for d < 0); a corner radius that
        would turn negative becomes 0 (a sharp corner)."""
        return HousingOutline(self.centre, self.width + 2 * d, self.height + 2 * d, max(self.corner_radius + d, 0.0))

    def sdf(self, p) -> np.ndarray:
        """Signed distance [m] of points ``p`` (..., 2) to the outline: < 0 inside, exact."""
        p = np.asarray(p, float)
        r = self.corner_radius
        q = np.abs(p - np.asarray(self.centre)) - (0.5 * np.array([self.width, self.height]) - r)
        outside = np.hypot(np.maximum(q[..., 0], 0.0), np.maximum(q[..., 1], 0.0))
        inside = np.minimum(np.maximum(q[..., 0], q[..., 1]), 0.0)
        return outside + inside - r

    def contains_circle(self, centre, radius: float) -> float:
        """Clearance [m] between a circle and the outline: >= 0 if the circle lies inside."""
        return float(-self.sdf(centre) - radius)

    def point_at_angle(self, angle: float) -> np.ndarray:
        """The outline's point on the ray from the centre at ``angle`` [rad]."""
        u = np.array([math.cos(angle), math.sin(angle)])
        c = np.asarray(self.centre, float)
        hw, hh, r = 0.5 * self.width, 0.5 * self.height, self.corner_radius
        with np.errstate(divide="ignore"):
            t = float(np.min(np.array([hw, hh]) / np.abs(u)))  # the flat side it reaches first
        p = t * u
        cc = np.sign(u) * np.array([hw - r, hh - r])
        if r > 0 and abs(p[0]) > hw - r and abs(p[1]) > hh - r:  # beyond a flat side: on a corner arc
            b = float(u @ cc)
            t = b + math.sqrt(max(b * b - float(cc @ cc) + r * r, 0.0))
        return c + t * u

    def segments(self) -> list:
        """The outline as lines and arcs, counter-clockwise from its point at angle 0.

        Each item is ``("line", a, b)`` or ``("arc", a, b, centre, radius, angle_a, angle_b)``
        (points as arrays [m], angles [rad], angle_b > angle_a, each arc a quarter at most).
        Zero-length lines (a circle's) are left out.
        """
        cx, cy = self.centre
        hw, hh, r = 0.5 * self.width, 0.5 * self.height, self.corner_radius
        ax, ay = hw - r, hh - r  # corner centres at (+-ax, +-ay)
        out = []

        def line(a, b):
            if math.hypot(b[0] - a[0], b[1] - a[1]) > 1e-12 * (1 + hw + hh):
                out.append(("line", np.array(a, float), np.array(b, float)))

        def arc(ccx, ccy, t0):
            if r <= 0:
                return
            c = np.array([cx + ccx, cy + ccy])
            a = c + r * np.array([math.cos(t0), math.sin(t0)])
            b = c + r * np.array([math.cos(t0 + 0.5 * math.pi), math.sin(t0 + 0.5 * math.pi)])
            out.append(("arc", a, b, c, r, t0, t0 + 0.5 * math.pi))

        line((cx + hw, cy), (cx + hw, cy + ay))
        arc(ax, ay, 0.0)
        line((cx + ax, cy + hh), (cx - ax, cy + hh))
        arc(-ax, ay, 0.5 * math.pi)
        line((cx - hw, cy + ay), (cx - hw, cy - ay))
        arc(-ax, -ay, math.pi)
        line((cx - ax, cy - hh), (cx + ax, cy - hh))
        arc(ax, -ay, 1.5 * math.pi)
        line((cx + hw, cy - ay), (cx + hw, cy))
        return out

    @property
    def length(self) -> float:
        """Perimeter [m]."""
        return sum(_seg_length(s) for s in self.segments())

    def locate(self, p) -> tuple[float, float]:
        """``(s, distance)``: arc length [m] (from the point at angle 0, counter-clockwise) of
        the outline point nearest to ``p``, and the distance to it [m]."""
        p = np.asarray(p, float)
        s0, best = 0.0, (math.inf, 0.0)
        for seg in self.segments():
            L = _seg_length(seg)
            if seg[0] == "line":
                a, b = seg[1], seg[2]
                t = float(np.clip((p - a) @ (b - a) / (L * L), 0.0, 1.0))
                q, sl = a + t * (b - a), t * L
            else:
                _, a, b, c, r, t0, t1 = seg
                ang = math.atan2(p[1] - c[1], p[0] - c[0])
                ang = t0 + (ang - t0) % (2 * math.pi)
                if ang > t1:  # outside the arc's span: nearer end
                    ang = t1 if (ang - t1) < (t0 + 2 * math.pi - ang) else t0
                q, sl = c + r * np.array([math.cos(ang), math.sin(ang)]), r * (ang - t0)
            d = float(np.hypot(*(p - q)))
            if d < best[0]:
                best = (d, s0 + sl)
            s0 += L
        return best[1], best[0]

    def point_at(self, s: float) -> np.ndarray:
        """The point at arc length ``s`` [m] (modulo the perimeter)."""
        s = s % self.length
        for seg in self.segments():
            L = _seg_length(seg)
            if s <= L:
                return _seg_point(seg, s)
            s -= L
        return _seg_point(self.segments()[-1], _seg_length(self.segments()[-1]))

    def pieces(self, breaks) -> list:
        """The outline cut at the arc lengths ``breaks`` [m]: a list of ``(s_start, s_end,
        parts)``, one per interval between consecutive breaks (from the first break round to
        it again; ``s_end`` may exceed the perimeter), ``parts`` the line and arc pieces of
        :meth:`segments` inside it (same item layout). No breaks: one interval from 0."""
        segs = self.segments()
        lengths = np.array([_seg_length(s) for s in segs])
        total = float(lengths.sum())
        starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        tol = 1e-9 * total
        cuts = sorted({float(b) % total for b in breaks}) or [0.0]
        points = []
        for v in sorted(set(cuts) | set(starts.tolist())):
            if not points or v - points[-1] > tol:
                points.append(v)
        if total - points[-1] <= tol:
            points.pop()
        k0 = int(np.argmin([abs(v - cuts[0]) for v in points]))
        walk = points[k0:] + [v + total for v in points[:k0]]
        walk.append(walk[0] + total)
        out = []
        for p, q in zip(walk[:-1], walk[1:]):
            if min(abs(p % total - c) for c in cuts) <= tol or min(abs(p % total - c - total) for c in cuts) <= tol:
                out.append([p, q, []])
            mid = (0.5 * (p + q)) % total
            j = int(np.searchsorted(starts, mid, side="right") - 1)
            a = mid - 0.5 * (q - p) - starts[j]
            out[-1][1] = q
            out[-1][2].append(_sub_segment(segs[j], max(a, 0.0), min(a + (q - p), lengths[j])))
        return [tuple(g) for g in out]

    def key(self) -> dict:
        return {"centre": [float(self.centre[0]), float(self.centre[1])], "width": float(self.width),
                "height": float(self.height), "corner_radius": float(self.corner_radius)}


def _seg_length(seg) -> float:
    if seg[0] == "line":
        return float(np.hypot(*(seg[2] - seg[1])))
    return seg[4] * (seg[6] - seg[5])


def _seg_point(seg, s: float) -> np.ndarray:
    if seg[0] == "line":
        a, b = seg[1], seg[2]
        return a + (b - a) * (s / _seg_length(seg))
    _, a, b, c, r, t0, t1 = seg
    t = t0 + s / r
    return c + r * np.array([math.cos(t), math.sin(t)])


def _sub_segment(seg, a: float, b: float):
    """The part of a segment between arc lengths a < b (from its start)."""
    if seg[0] == "line":
        return ("line", _seg_point(seg, a), _seg_point(seg, b))
    _, _, _, c, r, t0, _ = seg
    return ("arc", _seg_point(seg, a), _seg_point(seg, b), c, r, t0 + a / r, t0 + b / r)


@dataclass(frozen=True)
class Seat:
    """A bearing seat: a bore in the cover for the shafts named in ``shafts`` (coaxial shafts,
    the sun's and the carrier's, share one seat in the plane), centre [m], bore diameter [m]."""

    name: str
    shafts: tuple
    centre: tuple
    diameter: float


@dataclass(frozen=True)
class RingBolts:
    """The bolts that hold the ring gear to the cover: ``count`` holes of ``hole_diameter`` [m]
    equally spaced on the circle of ``circle_diameter`` [m] about ``centre``, the first at
    angle 0 (as the ring's bolted support, :func:`flexgear.reduction.interface.gear_interface`,
    so that ring bolt k and housing bolt k coincide)."""

    count: int
    circle_diameter: float
    hole_diameter: float
    centre: tuple = (0.0, 0.0)

    def positions(self) -> np.ndarray:
        """(count, 2) bolt centres [m]."""
        a = 2.0 * np.pi * np.arange(self.count) / self.count
        R = 0.5 * self.circle_diameter
        return np.column_stack([self.centre[0] + R * np.cos(a), self.centre[1] + R * np.sin(a)])


@dataclass(frozen=True)
class Housing:
    """A gearbox housing (see module docstring). Lengths [m], stiffness [N/m].

    Attributes
    ----------
    outline : HousingOutline
        Outer outline.
    wall_thickness : float
        Wall thickness (the inner outline is the outer one offset by it).
    depth : float
        Axial length of the wall: its out-of-plane thickness.
    cover_thickness : float
        Out-of-plane thickness of the cover region (both end covers); 0: no cover (a ring;
        then no seats and no bolts).
    seats : tuple of Seat
    bolts : RingBolts or None
    feet : tuple of float
        Arc lengths on the outer outline of the foot pads' centres [m].
    foot_angles_deg : tuple of float or None
        The angles the feet were given by [deg] (for writing the configuration back), or None.
    foot_points_given : tuple of (float, float) or None
        The points the feet were given by [m] (likewise), or None.
    foot_width : float
        Length of each foot pad along the outline.
    foot_stiffness : float
        Ground stiffness of each foot in x and in y [N/m] (applied outside the reduction).
    material : Material
    damping_ratio : float
        Modal damping ratio of the housing's modes on its feet [-].
    level, order : int
        Mesh refinement (sizes shrink by sqrt(2) per level) and element order.
    cutoff : float
        Fixed-interface modes kept by the Craig-Bampton reduction [Hz].
    formulation : str
        Plane elasticity formulation (plane stress: thin walls).
    coupled : bool
        The housing is a body of the multi-body model (:mod:`flexgear.dynamics.model.housing`),
        not only a one-way path (not part of the mesh key).
    """

    outline: HousingOutline
    wall_thickness: float
    depth: float
    cover_thickness: float
    seats: tuple = ()
    bolts: RingBolts | None = None
    feet: tuple = ()
    foot_angles_deg: tuple | None = None
    foot_points_given: tuple | None = None
    foot_width: float = 0.02
    foot_stiffness: float = 1e8
    material: Material = field(default=CAST_IRON)
    damping_ratio: float = 0.02
    level: int = 2
    order: int = 2
    cutoff: float = 20e3
    formulation: str = "plane_stress"
    coupled: bool = False

    @property
    def inner(self) -> HousingOutline:
        """The wall's inner outline."""
        return self.outline.offset(-self.wall_thickness)

    @property
    def centre(self) -> np.ndarray:
        return np.asarray(self.outline.centre, float)

    def holes(self) -> list:
        """``(group name, centre (2,), diameter)`` of every hole in the cover: seats, then bolts."""
        out = [(f"seat_{s.name}", np.asarray(s.centre, float), float(s.diameter)) for s in self.seats]
        if self.bolts is not None:
            out += [(f"bolt{k}", c, float(self.bolts.hole_diameter)) for k, c in enumerate(self.bolts.positions())]
        return out

    def foot_points(self) -> np.ndarray:
        """(n_feet, 2) centres of the foot pads [m]."""
        return np.array([self.outline.point_at(s) for s in self.feet]).reshape(-1, 2)

    def contains(self, p, tol: float = 0.0) -> bool:
        """Whether point ``p`` lies in the body (wall or cover, not in a hole), within ``tol`` [m]."""
        p = np.asarray(p, float)
        if self.outline.sdf(p) > tol:
            return False
        if self.cover_thickness <= 0 and self.inner.sdf(p) < -tol:
            return False
        return all(np.hypot(*(p - c)) >= 0.5 * d - tol for _, c, d in self.holes())

    def mesh_key(self) -> dict:
        """Everything that changes the mesh and the reduced model (a reduction cache key part):
        geometry, material, mesh and reduction settings; not the foot stiffness nor the damping,
        which act outside the reduction."""
        return {"outline": self.outline.key(), "wall_thickness": float(self.wall_thickness),
                "depth": float(self.depth), "cover_thickness": float(self.cover_thickness),
                "seats": [{"name": s.name, "shafts": list(s.shafts), "centre": [float(c) for c in s.centre],
                           "diameter": float(s.diameter)} for s in self.seats],
                "bolts": None if self.bolts is None else {
                    "count": int(self.bolts.count), "circle_diameter": float(self.bolts.circle_diameter),
                    "hole_diameter": float(self.bolts.hole_diameter),
                    "centre": [float(c) for c in self.bolts.centre]},
                "feet": [float(s) for s in self.feet], "foot_width": float(self.foot_width),
                "material": {"E": float(self.material.E), "nu": float(self.material.nu),
                             "rho": float(self.material.rho)},
                "level": int(self.level), "order": int(self.order), "cutoff": float(self.cutoff),
                "formulation": self.formulation}

    def check(self, ring=None, gears=(), path: str = "housing") -> None:
        """Raise ConfigError for a housing that cannot be built: a wall as thick as the outline,
        holes outside the cover or overlapping, bolts off the ring's rim, a ring it does not
        enclose, a gear it collides with, feet off the outline or overlapping.

        Parameters
        ----------
        ring : (centre (2,), root radius, rim radius) or None
            The ring gear the bolts hold (planetary sets) [m].
        gears : sequence of (name, centre (2,), tip radius)
            External gears that turn inside the wall [m].
        path : str
            Prefix of the keys named in the messages.
        """
        o, t = self.outline, self.wall_thickness
        if not 0 < t < 0.5 * min(o.width, o.height):
            raise ConfigError(f"{path}.wall_thickness = {t!r} m: must be > 0 and less than half the outline's "
                              f"smaller extent ({0.5 * min(o.width, o.height):.6g} m)")
        inner = self.inner
        if ring is not None:
            c, r_root, r_rim = ring
            gap = inner.contains_circle(c, r_rim)
            if gap < 0:
                raise ConfigError(f"{path}: the wall's inner outline (outline offset inwards by wall_thickness = "
                                  f"{t:.6g} m) does not enclose the ring gear's rim (diameter {2 * r_rim:.6g} m, "
                                  f"it crosses by {-gap * 1e3:.4g} mm); enlarge the outline or thin the wall")
        for name, c, ra in gears:
            gap = inner.contains_circle(c, ra)
            if gap < 0:
                raise ConfigError(f"{path}: the wall collides with gear {name!r} (tip circle diameter {2 * ra:.6g} m "
                                  f"at ({c[0]:.6g}, {c[1]:.6g}) m crosses the wall's inner outline by "
                                  f"{-gap * 1e3:.4g} mm); enlarge the outline or thin the wall")
        holes = self.holes()
        if holes and self.cover_thickness <= 0:
            raise ConfigError(f"{path}.cover_thickness = {self.cover_thickness!r} m: seats and bolts sit in the "
                              "cover; give a cover thickness > 0")
        if self.bolts is not None:
            b = self.bolts
            if b.count < 3:
                raise ConfigError(f"{path}.bolts = {b.count!r}: the ring needs at least 3 bolts")
            chord = b.circle_diameter * math.sin(math.pi / b.count)
            if chord <= b.hole_diameter:
                raise ConfigError(f"{path}.bolts = {b.count}: bolt holes of {b.hole_diameter * 1e3:.4g} mm on a "
                                  f"{b.circle_diameter * 1e3:.4g} mm circle overlap (pitch {chord * 1e3:.4g} mm); "
                                  "fewer bolts, a larger bolt circle or a smaller bolt_diameter")
            if ring is not None:
                _, r_root, r_rim = ring
                R, h = 0.5 * b.circle_diameter, 0.5 * b.hole_diameter
                if not (r_root < R - h and R + h < r_rim):
                    raise ConfigError(f"{path}.bolt_circle_diameter = {b.circle_diameter:.6g} m: the bolt holes "
                                      f"(diameter {b.hole_diameter:.6g} m) must lie in the ring's rim, between its "
                                      f"root circle ({2 * r_root:.6g} m) and its rim ({2 * r_rim:.6g} m)")
        for name, c, d in holes:
            key = f"{path}.seat_diameter" if name.startswith("seat") else f"{path}.bolt_diameter"
            if not d > 0:
                raise ConfigError(f"{key} = {d!r} m: must be > 0")
            lig = inner.contains_circle(c, 0.5 * d)
            if lig < 0.25 * d:
                raise ConfigError(f"{key} = {d:.6g} m: hole {name} at ({c[0]:.6g}, {c[1]:.6g}) m must lie inside the "
                                  f"cover with a ligament of at least a quarter of its diameter to the wall's inner "
                                  f"outline ({lig * 1e3:.4g} mm < {0.25 * d * 1e3:.4g} mm)")
        for i in range(len(holes)):
            for j in range(i + 1, len(holes)):
                (ni, ci, di), (nj, cj, dj) = holes[i], holes[j]
                gap = float(np.hypot(*(ci - cj))) - 0.5 * (di + dj)
                if gap < 0.25 * min(di, dj) and not (ni.startswith("bolt") and nj.startswith("bolt")
                                                      and gap > 0):
                    raise ConfigError(f"{path}: holes {ni} and {nj} overlap or leave a ligament below a quarter of "
                                      f"the smaller diameter ({gap * 1e3:.4g} mm); move the seats or bolts "
                                      f"({path}.seat_diameter, {path}.bolt_circle_diameter, {path}.bolt_diameter)")
        w = self.foot_width
        L = o.length
        if self.feet and not 0 < w < L / (2 * len(self.feet)):
            raise ConfigError(f"{path}.foot_width = {w!r} m: must be > 0 and below the outline's perimeter over "
                              f"twice the number of feet ({L / (2 * len(self.feet)):.6g} m)")
        s = sorted(x % L for x in self.feet)
        for a, b in zip(s, s[1:] + [s[0] + L] if s else []):
            if len(s) > 1 and b - a < w:
                raise ConfigError(f"{path}: foot pads at arc lengths {a:.6g} and {b % L:.6g} m overlap "
                                  f"(foot_width = {w:.6g} m)")


def foot_positions(outline: HousingOutline, points=None, angles=None, path: str = "housing", tol: float | None = None):
    """Arc lengths [m] of feet given as points on the outline or as angles [rad] from its centre.

    Raises
    ------
    ConfigError
        A point farther than ``tol`` (default 1e-6 of the outline's size) from the outline.
    """
    if points is not None:
        tol = 1e-6 * max(outline.width, outline.height) if tol is None else tol
        out = []
        for k, p in enumerate(points):
            s, d = outline.locate(p)
            if d > tol:
                raise ConfigError(f"{path}.foot_points[{k}] = [{p[0]:.6g}, {p[1]:.6g}] m: off the outline by "
                                  f"{d * 1e3:.4g} mm; a foot lies on the outer outline (or give "
                                  f"{path}.foot_angles_deg)")
            out.append(s)
        return tuple(out)
    return tuple(outline.locate(outline.point_at_angle(a))[0] for a in (angles or ()))


# --------------------------------------------------------------------------------------------
# sensors
# --------------------------------------------------------------------------------------------
#: a sensor's measurement-noise settings (written to a result only where set)
NOISE_KEYS = ("noise_rms", "snr_db", "noise_seed")


@dataclass(frozen=True)
class Sensor:
    """An accelerometer (or velocity / displacement pick-up) on a body.

    Attributes
    ----------
    name : str
    body : str
        ``"housing"`` or ``"ring"``.
    point : (float, float)
        Where it sits [m] (given, or on the body's outer rim at ``angle_deg``).
    direction : (float, float)
        Unit vector of the measured component.
    quantity : str
        ``"acceleration"``, ``"velocity"`` or ``"displacement"``.
    angle_deg : float or None
        The rim angle it was placed by [deg] (as given), else None.
    direction_label : str or None
        ``radial``, ``tangential`` (about the body's centre), ``x`` or ``y`` as given; None if
        the direction was given by ``direction_deg`` [deg, counter-clockwise from +x].
    window, window_width_deg : str, float
        The planet-pass path model's window (``hann`` or ``rectangular``) and its angular width
        [deg] (``docs/guide/housing.md``).
    noise_rms, snr_db, noise_seed : float, float, int or None
        Measurement noise added to the recorded signals: white Gaussian noise of RMS
        ``noise_rms`` [the quantity's unit], or at a signal-to-noise ratio ``snr_db`` [dB], drawn
        from ``noise_seed`` (None: derived from the configuration); all None: none
        (:mod:`flexgear.results.noise`).
    """

    name: str
    body: str
    point: tuple
    direction: tuple
    quantity: str = "acceleration"
    angle_deg: float | None = None
    direction_label: str | None = "radial"
    direction_deg: float | None = None
    window: str = "hann"
    window_width_deg: float = 360.0
    noise_rms: float | None = None
    snr_db: float | None = None
    noise_seed: int | None = None

    @property
    def noisy(self) -> bool:
        """Whether the sensor adds measurement noise to its signals."""
        return self.noise_rms is not None or self.snr_db is not None

    @property
    def units(self) -> str:
        return QUANTITY_UNITS[self.quantity]

    def definition(self) -> dict:
        """The sensor's definition as plain values (for a result file's attributes)."""
        return {"name": self.name, "body": self.body, "point": [float(v) for v in self.point],
                "direction": [float(v) for v in self.direction], "quantity": self.quantity,
                "units": self.units, "angle_deg": self.angle_deg, "direction_label": self.direction_label,
                "direction_deg": self.direction_deg, "window": self.window,
                "window_width_deg": self.window_width_deg,
                **{k: getattr(self, k) for k in NOISE_KEYS if getattr(self, k) is not None}}


def sensor_direction(label: str | None, angle: float | None, point, centre) -> tuple[float, float]:
    """Unit vector of a sensor direction: ``label`` (radial / tangential about ``centre``, x, y)
    or ``angle`` [rad] counter-clockwise from +x."""
    if angle is not None:
        return (math.cos(angle), math.sin(angle))
    if label in ("x", "y"):
        return (1.0, 0.0) if label == "x" else (0.0, 1.0)
    d = np.asarray(point, float) - np.asarray(centre, float)
    n = float(np.hypot(*d))
    if n == 0:
        raise ConfigError(f"direction = {label!r} at the body's centre: radial and tangential are undefined there; "
                          "give x, y or direction_deg")
    e = d / n
    return (float(e[0]), float(e[1])) if label == "radial" else (float(-e[1]), float(e[0]))


def check_sensor_names(sensors) -> None:
    """Raise ConfigError for two sensors of one name."""
    seen = set()
    for i, s in enumerate(sensors):
        if s.name in seen:
            raise ConfigError(f"sensors[{i}].name = {s.name!r}: a sensor of that name exists already; names are "
                              "unique (they name /sensors/<name> in the results)")
        seen.add(s.name)
