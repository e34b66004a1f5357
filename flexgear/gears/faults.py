"""Tooth faults and manufacturing / assembly errors as data (SI), and the ISO 1328-1:2013 tolerances.

A fault or error is a frozen dataclass; lengths in m, angles in rad. The configuration layer
(:mod:`flexgear.config.faults`) reads them from ``[[faults]]`` and ``[errors]``;
:mod:`flexgear.gears.modified` turns them into modified tooth outlines and per-tooth rigid
offsets, :mod:`flexgear.gears.kinematics` gives their characteristic frequencies.

Tooth numbering
    The numbers of the contact search and of the results' ``pair_tooth_a`` / ``pair_tooth_b``:
    tooth ``k`` (0 <= k < z) of a gear is centred on the polar angle ``theta + 2 pi k / z`` in the
    global frame, where ``theta`` is the body's angle (``/bodies/<name>/angle`` in a result): the
    teeth are counted counter-clockwise, seen from the front (z axis towards the viewer), from
    tooth 0, whose centre line is the body frame's x axis. Each planet is its own body
    (``planet1`` ... ``planetN``, numbered counter-clockwise from ``first_planet_angle_deg``) and
    counts its own teeth from 0.

Flanks
    ``LEFT = +1`` is the flank at positive polar angle from the tooth centre line (the
    counter-clockwise side of the tooth), ``RIGHT = -1`` the other one: the sign ``pair_side``
    records for gear a of a mesh. In an external mesh a's left flank meets b's left flank, in an
    internal mesh (planet-ring) a's left flank meets the ring's right flank
    (:func:`flexgear.gears.kinematics.mate_flank`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..errors import GeometryError
from .geometry import SpurGear

LEFT, RIGHT = 1, -1
FLANKS = {"left": LEFT, "right": RIGHT}
FLANK_NAMES = {LEFT: "left", RIGHT: "right"}

#: ISO 6336-3 critical section: the root fillet point whose tangent makes this angle with the
#: tooth centre line (external gears 30 deg, internal gears 60 deg); where a root crack starts.
CRITICAL_TANGENT_DEG = {False: 30.0, True: 60.0}
#: Smallest material ligament a crack tip leaves to the outline, the bore or the rim, in modules
#: (a crack closer to a free surface has broken the tooth; the FE mesh needs a few elements there).
CRACK_MIN_LIGAMENT = 0.05


# ============================================================================================
# tooth faults
# ============================================================================================
@dataclass(frozen=True, kw_only=True)
class ToothFault:
    """A local fault on one tooth of one gear body.

    Attributes
    ----------
    gear : str
        Gear name of the set (``pinion``, ``wheel``; ``sun``, ``planet``, ``ring``).
    tooth : int
        Tooth index, 0 <= tooth < z (numbering: module docstring).
    planet : int or None
        Which planet (1..N) for ``gear = "planet"``, else None.
    """

    kind: ClassVar[str] = ""
    gear: str
    tooth: int
    planet: int | None = None

    @property
    def body(self) -> str:
        """Name of the body that carries the fault (``planet2``, ``sun``, ...)."""
        return f"planet{self.planet}" if self.gear == "planet" else self.gear

    @property
    def null(self) -> bool:
        """True if the fault removes nothing (zero size): the tooth stays healthy."""
        raise NotImplementedError

    def label(self) -> str:
        """Short description for messages, e.g. ``crack on sun tooth 3, left flank``."""
        where = f"{self.body} tooth {self.tooth}"
        flank = getattr(self, "flank", None)
        return f"{self.kind} on {where}" + (f", {FLANK_NAMES.get(flank, flank)} flank" if flank is not None else "")


@dataclass(frozen=True, kw_only=True)
class Crack(ToothFault):
    """A straight root crack (the FE phase cuts it as a slit; the outline is unchanged).

    It starts on the root fillet of ``flank`` at the ISO 6336-3 critical section (the point
    whose fillet tangent makes 30 deg, internal gears 60 deg, with the tooth centre line:
    :func:`crack_start`), the point of largest root stress where fatigue cracks start, and
    runs ``depth`` [m] into the tooth at ``angle`` [rad] to the centre line, towards the centre
    line and the root (:func:`crack_path`). ``width_fraction`` is the part of the face width it
    crosses (1 = through the face width).
    """

    kind: ClassVar[str] = "crack"
    flank: int
    depth: float
    angle: float
    width_fraction: float = 1.0

    @property
    def null(self) -> bool:
        return self.depth == 0.0 or self.width_fraction == 0.0


@dataclass(frozen=True, kw_only=True)
class Spall(ToothFault):
    """Pitting: material removed from ``flank`` between the radii ``start_radius`` and
    ``end_radius`` [m] to the depth ``depth`` [m] (normal to the flank), over the fraction
    ``width_fraction`` of the face width (:func:`flexgear.gears.modified.tooth_outline`)."""

    kind: ClassVar[str] = "spall"
    flank: int
    start_radius: float
    end_radius: float
    depth: float
    width_fraction: float = 1.0

    @property
    def null(self) -> bool:
        return self.depth == 0.0 or self.width_fraction == 0.0 or self.start_radius == self.end_radius


@dataclass(frozen=True, kw_only=True)
class Chip(ToothFault):
    """The tip corner of ``flank`` cut off along a straight line from the flank point
    ``profile_size`` [m] below the corner (arc length along the outline) to the tip-land point
    ``tip_size`` [m] from the corner, over the fraction ``width_fraction`` of the face width."""

    kind: ClassVar[str] = "chip"
    flank: int
    profile_size: float
    tip_size: float
    width_fraction: float = 1.0

    @property
    def null(self) -> bool:
        return (self.profile_size == 0.0 and self.tip_size == 0.0) or self.width_fraction == 0.0


@dataclass(frozen=True, kw_only=True)
class Missing(ToothFault):
    """A broken tooth: everything above the fraction ``height_fraction`` of the tooth height
    (root circle = 0, tip circle = 1) removed, across the whole face width; 0 removes the tooth
    down to the root circle, 1 leaves it whole."""

    kind: ClassVar[str] = "missing"
    height_fraction: float = 0.0

    @property
    def null(self) -> bool:
        return self.height_fraction == 1.0


FAULT_KINDS = {c.kind: c for c in (Crack, Spall, Chip, Missing)}


# ============================================================================================
# manufacturing and assembly errors
# ============================================================================================
@dataclass(frozen=True, kw_only=True)
class Eccentricity:
    """Run-out of a gear: the toothing's centre lies ``magnitude`` [m] from the rotation axis, in
    the direction ``phase`` [rad] of the gear frame (counter-clockwise from tooth 0's centre line).
    Radial run-out F_r = 2 magnitude."""

    magnitude: float = 0.0
    phase: float = 0.0

    @property
    def null(self) -> bool:
        return self.magnitude == 0.0

    def shift(self) -> np.ndarray:
        """Offset (2,) [m] of the toothing's centre in the gear frame."""
        return np.array([self.magnitude * math.cos(self.phase), self.magnitude * math.sin(self.phase)])


@dataclass(frozen=True, kw_only=True)
class PinError:
    """Position error of a planet's carrier pin [m]: ``radial`` away from the carrier axis,
    ``tangential`` in the counter-clockwise direction of the carrier."""

    radial: float = 0.0
    tangential: float = 0.0

    @property
    def null(self) -> bool:
        return self.radial == 0.0 and self.tangential == 0.0


@dataclass(frozen=True, kw_only=True)
class PitchErrors:
    """Tooth spacing errors: ``deviations[j]`` is the single pitch deviation f_p,j+1 [m] (ISO
    1328-1), the actual minus the nominal arc length on the reference circle from tooth j to
    tooth j + 1 (mod z), counted counter-clockwise; they sum to zero (the circle closes). Drawn
    for an ISO 1328-1:2013 flank tolerance class ``grade`` with ``seed``
    (:func:`random_pitch_deviations`) or given (``grade`` and ``seed`` None). Each tooth is turned
    rigidly, both flanks alike (no thickness error): :meth:`angles`."""

    deviations: tuple = ()
    grade: int | None = None
    seed: int | None = None

    @property
    def null(self) -> bool:
        return not any(self.deviations)

    def index_deviations(self) -> np.ndarray:
        """Cumulative (index) deviations F_k [m] of teeth k = 0..z-1 on the reference circle,
        with mean zero (the errors do not turn the gear as a whole)."""
        f = np.asarray(self.deviations, float)
        F = np.concatenate([[0.0], np.cumsum(f[:-1])])
        return F - F.mean()

    def angles(self, gear: SpurGear) -> np.ndarray:
        """Angular offsets [rad] of the teeth, F_k / r (counter-clockwise positive)."""
        return self.index_deviations() / gear.r


@dataclass(frozen=True, kw_only=True)
class ProfileErrors:
    """Profile deviations and modifications of every tooth of a gear, both flanks, as a normal
    offset delta(L) of the involute (positive: material added) against the roll length L.

    The profile runs from the form circle (L_F) to the tip circle (L_a); x = (L - L_F)/(L_a - L_F)
    in [0, 1] (so also for a ring, whose tip is its smallest radius).

    Attributes
    ----------
    slope : float
        Profile slope deviation f_Halpha [m]: delta = slope (x - 1/2) (more material at the
        tip for slope > 0; unchanged at mid-profile).
    form : float
        Profile form deviation f_falpha [m] (>= 0), the range of a waviness
        delta = form/2 cos(2 pi form_waves x), which has no mean and no slope over the profile.
    form_waves : int
        Waves of the form deviation over the profile.
    tip_relief, root_relief : float
        Amounts C_a, C_f [m] (>= 0) of material removed at the tip circle / at the form circle.
    tip_relief_start, root_relief_start : float or None
        Radius [m] where the relief begins (tip: from there to the tip; root: from there down
        to the form circle).
    relief_shape : str
        ``"linear"`` or ``"parabolic"`` growth of the relief with the roll length from its start.
    """

    slope: float = 0.0
    form: float = 0.0
    form_waves: int = 1
    tip_relief: float = 0.0
    tip_relief_start: float | None = None
    root_relief: float = 0.0
    root_relief_start: float | None = None
    relief_shape: str = "linear"

    @property
    def null(self) -> bool:
        return self.slope == 0.0 and self.form == 0.0 and self.tip_relief == 0.0 and self.root_relief == 0.0

    def offset(self, gear: SpurGear, r) -> np.ndarray:
        """Normal offset delta [m] (material added > 0) of the involute at radii ``r`` [m]."""
        r = np.asarray(r, float)
        L = np.sqrt(np.maximum(r * r - gear.rb**2, 0.0))
        LF, La = roll_length(gear, gear.r_form), roll_length(gear, gear.ra)
        x = (L - LF) / (La - LF)
        d = np.zeros_like(L)
        if self.slope:
            d = d + self.slope * (x - 0.5)
        if self.form:
            d = d + 0.5 * self.form * np.cos(2 * math.pi * self.form_waves * x)
        p = 2 if self.relief_shape == "parabolic" else 1
        if self.tip_relief:
            xs = (roll_length(gear, self.tip_relief_start) - LF) / (La - LF)
            u = np.clip((x - xs) / (1.0 - xs), 0.0, None)
            d = d - self.tip_relief * u**p
        if self.root_relief:
            xs = (roll_length(gear, self.root_relief_start) - LF) / (La - LF)
            u = np.clip((xs - x) / xs, 0.0, None)
            d = d - self.root_relief * u**p
        return d


@dataclass(frozen=True)
class GearErrors:
    """The errors of one gear body (None: none of that kind)."""

    eccentricity: Eccentricity | None = None
    pitch: PitchErrors | None = None
    profile: ProfileErrors | None = None

    @property
    def null(self) -> bool:
        return all(e is None or e.null for e in (self.eccentricity, self.pitch, self.profile))


@dataclass(frozen=True)
class Errors:
    """Errors of a gear set: ``gears`` by body name (``sun``, ``planet2``, ``pinion``, ...) and
    ``pins`` by planet body name (``planet1`` ...)."""

    gears: dict = field(default_factory=dict)
    pins: dict = field(default_factory=dict)

    @property
    def null(self) -> bool:
        return all(g.null for g in self.gears.values()) and all(p.null for p in self.pins.values())


def fault_record(obj) -> dict:
    """A fault or error as a plain dictionary of JSON types (``kind`` first for a fault), for
    cache keys and result files: equal data give equal records."""
    if isinstance(obj, Errors):
        return {"gears": {b: fault_record(g) for b, g in sorted(obj.gears.items())},
                "pins": {b: fault_record(p) for b, p in sorted(obj.pins.items())}}
    if isinstance(obj, GearErrors):
        return {k: (None if v is None else fault_record(v)) for k, v in
                (("eccentricity", obj.eccentricity), ("pitch", obj.pitch), ("profile", obj.profile))}
    out = {"kind": obj.kind} if isinstance(obj, ToothFault) else {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        out[f.name] = list(v) if isinstance(v, tuple) else v
    return out


# ============================================================================================
# involute helpers
# ============================================================================================
def roll_length(gear: SpurGear, r):
    """Roll length L = sqrt(r^2 - r_b^2) [m] of the involute at radius r [m]; roll angle L / r_b."""
    r = np.asarray(r, float)
    L = np.sqrt(np.maximum(r * r - gear.rb**2, 0.0))
    return float(L) if L.ndim == 0 else L


def roll_radius(gear: SpurGear, roll_angle):
    """Radius [m] of the involute point at roll angle ``roll_angle`` [rad]: r_b sqrt(1 + xi^2)."""
    return gear.rb * np.sqrt(1.0 + np.asarray(roll_angle, float) ** 2)


# ============================================================================================
# cracks
# ============================================================================================
def crack_start(gear: SpurGear, flank: int = LEFT) -> tuple[np.ndarray, float]:
    """Start point of a root crack on tooth 0 (tooth frame, x along the centre line) [m] and its
    radius [m]: the ISO 6336-3 critical section, where the tangent to the generated root
    fillet makes 30 deg (internal gears 60 deg) with the tooth centre line."""
    lo, hi = sorted((gear.rf, gear.r_form))
    r = np.linspace(lo, hi, 4001)
    th = gear.half_angle(r)
    x, y = r * np.cos(th), r * np.sin(th)
    # angle between the fillet's tangent and the centre line (x axis), as lines, in [0, 90] deg
    tang = np.degrees(np.arctan2(np.abs(np.gradient(y)), np.abs(np.gradient(x))))
    target = CRITICAL_TANGENT_DEG[gear.internal]
    d = tang - target
    cross = np.nonzero(np.diff(np.sign(d)) != 0)[0]
    if not len(cross):
        raise GeometryError(f"{gear.name}: the root fillet has no point whose tangent makes {target:g} deg with "
                            "the tooth centre line (ISO 6336-3 critical section)")
    # the crossing nearest the form circle (the fillet turns from the root land to the flank)
    j = cross[-1] if not gear.internal else cross[0]
    t = d[j] / (d[j] - d[j + 1])
    p = np.array([x[j] + t * (x[j + 1] - x[j]), flank * (y[j] + t * (y[j + 1] - y[j]))])
    return p, float(math.hypot(*p))


def crack_direction(gear: SpurGear, crack: Crack) -> np.ndarray:
    """Unit vector (2,) of the crack path in the tooth frame: at ``crack.angle`` to the centre line,
    pointing towards the root and towards the centre line from the cracked flank."""
    u = 1.0 if not gear.internal else -1.0  # along the centre line, root -> tip
    return np.array([-math.cos(crack.angle) * u, -crack.flank * math.sin(crack.angle)])


def crack_path(gear: SpurGear, crack: Crack) -> tuple[np.ndarray, np.ndarray]:
    """Start and tip (2,) of a crack [m] in its tooth's frame (the tooth centre line along +x)."""
    p0, _ = crack_start(gear, crack.flank)
    return p0, p0 + crack.depth * crack_direction(gear, crack)


def inside_material(gear: SpurGear, points) -> np.ndarray:
    """True for points (n, 2) [m] of the gear frame that lie in the gear's material (teeth, rim;
    not in the bore of an external gear, not beyond the rim of a ring)."""
    p = np.atleast_2d(np.asarray(points, float))
    r = np.hypot(p[:, 0], p[:, 1])
    phi = np.arctan2(p[:, 1], p[:, 0])
    k = np.floor(phi / gear.pitch_angle + 0.5)
    phr = np.abs(phi - k * gear.pitch_angle)
    lo, hi = sorted((gear.rf, gear.ra))
    within = phr < gear.half_angle(np.clip(r, lo, hi))
    if gear.internal:
        return ((r > gear.rf) | ((r >= gear.ra) & within)) & (r < gear.rim_diameter / 2)
    return ((r < gear.rf) | ((r <= gear.ra) & within)) & (r > gear.bore_diameter / 2)


def _distance_to_outline(gear: SpurGear, point, skip_side: float = 0.0) -> float:
    """Distance [m] of a point (tooth-0 frame) to the toothed outline (three teeth around tooth 0),
    the bore of an external gear or the rim of a ring; ``skip_side`` +1 or -1: without tooth 0's
    outline on that side of its centre line (the surface a crack starts from)."""
    one = gear.tooth_outline(ds=gear.module / 400).points
    pts = []
    for k in (-1, 0, 1):
        a = k * gear.pitch_angle
        pk = one @ np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
        if k == 0 and skip_side:
            pk = np.where((pk[:, 1] * skip_side > 0)[:, None], np.nan, pk)  # no segment touches them
        pts.append(pk)
    poly = np.vstack(pts)
    a, b = poly[:-1], poly[1:]
    ab = b - a
    t = np.clip(((point - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0.0, 1.0)
    d = float(np.nanmin(np.hypot(*(a + t[:, None] * ab - point).T)))
    r = math.hypot(*point)
    edge = gear.rim_diameter / 2 - r if gear.internal else r - gear.bore_diameter / 2
    return min(d, edge)


def check_crack(gear: SpurGear, crack: Crack) -> None:
    """Raise GeometryError (naming the key) if the crack leaves its tooth: its path must stay in
    the material, its tip in the tooth's sector (|polar angle| <= pi/z from the centre line)
    with a ligament of at least CRACK_MIN_LIGAMENT modules to every free surface but the one it
    starts from (tooth 0's outline on the start's side of the centre line)."""
    if crack.null:
        return
    p0, p1 = crack_path(gear, crack)
    s = np.linspace(0.0, 1.0, 201)[1:]
    path = p0 + s[:, None] * (p1 - p0)
    m = gear.module
    if not inside_material(gear, path).all():
        raise GeometryError(f"depth = {crack.depth:.6g} m at angle_deg = {math.degrees(crack.angle):.6g}: the crack "
                            f"leaves the tooth (its path crosses a free surface); rule: the crack stays inside the "
                            f"material with a ligament >= {CRACK_MIN_LIGAMENT} module")
    phi = abs(math.atan2(p1[1], p1[0]))
    if phi > math.pi / gear.z:
        raise GeometryError(f"depth = {crack.depth:.6g} m at angle_deg = {math.degrees(crack.angle):.6g}: the crack tip "
                            f"lies under the neighbouring tooth ({math.degrees(phi):.4g} deg from the centre line > "
                            f"half a pitch {180 / gear.z:.4g} deg); rule: the crack stays in its tooth")
    lig = _distance_to_outline(gear, p1, skip_side=math.copysign(1.0, p0[1]))  # not the surface it starts from
    if lig < CRACK_MIN_LIGAMENT * m:
        raise GeometryError(f"depth = {crack.depth:.6g} m at angle_deg = {math.degrees(crack.angle):.6g}: the crack "
                            f"tip is {lig * 1e3:.4g} mm from the far free surface; rule: a ligament >= "
                            f"{CRACK_MIN_LIGAMENT} module = {CRACK_MIN_LIGAMENT * m * 1e3:.4g} mm remains (a deeper "
                            "crack has broken the tooth: use kind = 'missing')")


# ============================================================================================
# ISO 1328-1:2013 flank tolerances and random pitch deviations
# ============================================================================================
#: Flank tolerance classes of ISO 1328-1:2013 (1 finest ... 11 coarsest).
ISO1328_CLASSES = tuple(range(1, 12))


@dataclass(frozen=True)
class Iso1328Tolerances:
    """Flank tolerances of ISO 1328-1:2013 for one gear and class [m], rounded as the standard
    prescribes (> 10 um to 1 um, 5-10 um to 0.5 um, < 5 um to 0.1 um)."""

    grade: int
    single_pitch: float  # f_pT, Eq. (5)
    cumulative_pitch: float  # F_pT, Eq. (6)
    profile_slope: float  # f_HalphaT, Eq. (7)
    profile_form: float  # f_falphaT, Eq. (8)
    profile_total: float  # F_alphaT, Eq. (9)


def iso1328_round(value_um: float) -> float:
    """ISO 1328-1:2013 rounding of a tolerance in um: above 10 um to the nearest 1 um, from 5 to
    10 um to the nearest 0.5 um, below 5 um to the nearest 0.1 um (halves away from zero)."""
    def half_up(x):
        return math.floor(x + 0.5)

    if value_um > 10.0:
        return float(half_up(value_um))
    if value_um >= 5.0:
        return half_up(2.0 * value_um) / 2.0
    return half_up(10.0 * value_um) / 10.0


def iso1328_scope(gear: SpurGear, grade: int) -> str | None:
    """Why the ISO 1328-1:2013 formulas do not apply to ``gear`` (its Clause 1: 5 <= z <= 1000,
    5 mm <= d <= 15000 mm, 0.5 mm <= m_n <= 70 mm, 4 mm <= b <= 1200 mm; classes 1 to 11; the
    formulas are not to be extrapolated), or None if they do."""
    d, mn, b = gear.module * gear.z * 1e3, gear.module * 1e3, gear.face_width * 1e3
    bad = []
    if grade not in ISO1328_CLASSES:
        bad.append(f"class {grade!r} (1 to 11)")
    if not 5 <= gear.z <= 1000:
        bad.append(f"z = {gear.z} (5 to 1000)")
    if not 5.0 <= d <= 15000.0:
        bad.append(f"d = {d:.4g} mm (5 to 15000 mm)")
    if not 0.5 <= mn <= 70.0:
        bad.append(f"m_n = {mn:.4g} mm (0.5 to 70 mm)")
    if not 4.0 <= b <= 1200.0:
        bad.append(f"b = {b:.4g} mm (4 to 1200 mm)")
    return ", ".join(bad) if bad else None


def iso1328_tolerances(gear: SpurGear, grade: int) -> Iso1328Tolerances:
    """Flank tolerances [m] of ``gear`` for ISO 1328-1:2013 flank tolerance class ``grade``.

    With d = m z and m_n = m in mm and the class step factor q = sqrt(2)^(A - 5) (Eqs. 5-9)::

        f_pT = (0.001 d + 0.4 m_n + 5) q                      single pitch
        F_pT = (0.002 d + 0.55 sqrt(d) + 0.7 m_n + 12) q       total cumulative pitch
        f_HaT = (0.4 m_n + 0.001 d + 4) q                     profile slope
        f_faT = (0.55 m_n + 5) q                              profile form
        F_aT = sqrt(f_HaT^2 + f_faT^2)  (unrounded terms)     total profile

    in um, then rounded (:func:`iso1328_round`).

    Raises
    ------
    GeometryError
        Outside the standard's scope (:func:`iso1328_scope`).
    """
    why = iso1328_scope(gear, grade)
    if why:
        raise GeometryError(f"{gear.name}: outside the scope of ISO 1328-1:2013 ({why}); its tolerance formulas "
                            "are not extrapolated")
    d, mn = gear.module * gear.z * 1e3, gear.module * 1e3
    q = math.sqrt(2.0) ** (grade - 5)
    fpt = (0.001 * d + 0.4 * mn + 5.0) * q
    Fpt = (0.002 * d + 0.55 * math.sqrt(d) + 0.7 * mn + 12.0) * q
    fha = (0.4 * mn + 0.001 * d + 4.0) * q
    ffa = (0.55 * mn + 5.0) * q
    Fa = math.hypot(fha, ffa)
    um = 1e-6
    return Iso1328Tolerances(grade, iso1328_round(fpt) * um, iso1328_round(Fpt) * um, iso1328_round(fha) * um,
                             iso1328_round(ffa) * um, iso1328_round(Fa) * um)


def pitch_deviation_measures(deviations) -> tuple[float, float]:
    """(f_p, F_p) [m] of single pitch deviations: the largest single pitch deviation max |f_p,i| and
    the total cumulative pitch deviation F_p, the range of the index deviations (ISO 1328-1)."""
    f = np.asarray(deviations, float)
    F = np.concatenate([[0.0], np.cumsum(f[:-1])])
    return float(np.max(np.abs(f))), float(F.max() - F.min())


def iso1328_class(gear: SpurGear, deviations) -> int | None:
    """The finest ISO 1328-1:2013 class whose f_pT and F_pT the pitch deviations meet (None: not
    even class 11)."""
    fp, Fp = pitch_deviation_measures(deviations)
    for a in ISO1328_CLASSES:
        t = iso1328_tolerances(gear, a)
        if fp <= t.single_pitch * (1 + 1e-12) and Fp <= t.cumulative_pitch * (1 + 1e-12):
            return a
    return None


def random_pitch_deviations(gear: SpurGear, grade: int, seed: int) -> np.ndarray:
    """Single pitch deviations (z,) [m] of a gear of ISO 1328-1:2013 flank tolerance class
    ``grade``, drawn reproducibly from ``seed`` (numpy's PCG64 generator).

    The index deviations are the sum of the two components of measured pitch errors: a once-per-
    revolution sinusoid (run-out of the cutting set-up) of range F_pT and random phase, and a
    closed random walk of tooth-to-tooth errors (independent normal single pitch deviations with
    their mean removed, so that they sum to zero) scaled to a largest single pitch deviation of
    f_pT. The sum is then scaled by one factor so that the larger of f_p / f_pT and F_p / F_pT
    equals u, drawn uniformly from (u0, 1], u0 the ratio of class grade - 1's tolerance to class
    grade's (about 1/sqrt(2)): the gear meets class ``grade`` (f_p <= f_pT, F_p <= F_pT) and not
    the next finer one (:func:`iso1328_class` returns ``grade``).
    """
    tol = iso1328_tolerances(gear, grade)
    rng = np.random.default_rng(seed)
    z = gear.z
    k = np.arange(z)
    F1 = 0.5 * tol.cumulative_pitch * np.cos(2 * math.pi * k / z - rng.uniform(0.0, 2 * math.pi))
    e = rng.standard_normal(z)
    e -= e.mean()
    e *= tol.single_pitch / np.max(np.abs(e))
    f = np.diff(np.concatenate([F1, F1[:1]])) + e  # single pitch deviations of the sum
    f -= f.mean()  # exact closure against rounding
    fp, Fp = pitch_deviation_measures(f)
    if grade > 1:
        finer = iso1328_tolerances(gear, grade - 1)
        u0 = max(finer.single_pitch / tol.single_pitch, finer.cumulative_pitch / tol.cumulative_pitch)
    else:
        u0 = 1.0 / math.sqrt(2.0)
    u = 1.0 - rng.uniform(0.0, 1.0 - u0)  # in (u0, 1]
    return f * (u / max(fp / tol.single_pitch, Fp / tol.cumulative_pitch))
