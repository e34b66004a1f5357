"""Involute spur gear geometry (ISO 21771 definitions), generated tooth outlines.

Everything downstream (contact, FE meshes, masses, frequencies) is derived from the
:class:`SpurGear` objects defined here. All lengths are in metres, angles in radians.

Conventions
-----------
* Tooth ``k`` of a gear is centred on the polar angle ``2 pi k / z`` of the gear frame.
* The "left" flank of a tooth (``side = +1``) is the one at positive polar angle from the
  tooth centre line, the "right" flank (``side = -1``) the one at negative angle.
* Internal gears follow ISO 21771's signed convention internally (``z < 0`` in the pair
  formulas); a positive profile shift ``x`` of an internal gear moves its profile towards the
  gear axis, i.e. makes its teeth thicker and its tip and root diameters smaller.
* The root is the trochoid cut by the generating tool: the basic rack (tip radius
  ``rho_f * m``) for external gears, a pinion-type cutter of ``cutter_teeth`` teeth with the
  same tip radius for internal gears. The envelope of the tool's tip rounding is computed
  from the generating motion (the cutting point's normal passes through the instantaneous
  centre of the relative motion).
"""
from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import GeometryError, user_stacklevel
from ..files import jsonable

ROOT, FILLET, FLANK, TIP = 0, 1, 2, 3


def inv(alpha):
    """Involute function inv(alpha) = tan(alpha) - alpha."""
    return np.tan(alpha) - alpha


def inv_inverse(value: float) -> float:
    """Solve inv(alpha) = value for alpha in [0, pi/2) by Newton's method."""
    if value < 0:
        raise ValueError(f"inv_inverse: value {value} < 0 has no pressure angle")
    a = (3.0 * value) ** (1.0 / 3.0) if value > 0 else 0.0
    for _ in range(50):
        f = math.tan(a) - a - value
        d = math.tan(a) ** 2
        if d == 0:
            break
        step = f / d
        a -= step
        if abs(step) < 1e-15:
            break
    return a


@dataclass
class Outline:
    """A sampled tooth outline.

    Attributes
    ----------
    points : ndarray (N, 2)
        Points [m] in the gear frame, ordered counter-clockwise about the gear centre.
    tooth : ndarray (N,) of int
        Index of the tooth each point belongs to.
    kind : ndarray (N,) of int
        ``ROOT`` (root circle land), ``FILLET`` (trochoid), ``FLANK`` (involute) or ``TIP``.
    side : ndarray (N,) of int
        +1 left flank side, -1 right flank side (0 never occurs; tip points take the side of the
        half tooth they belong to).
    """

    points: np.ndarray
    tooth: np.ndarray
    kind: np.ndarray
    side: np.ndarray

    def __len__(self):
        return len(self.points)


def _check_positive(name, value):
    if not (isinstance(value, (int, float, np.floating, np.integer)) and value > 0):
        raise GeometryError(f"{name} = {value!r}: must be a number > 0")


@dataclass(frozen=True)
class SpurGear:
    """An involute spur gear, external or internal.

    Parameters
    ----------
    z : int
        Number of teeth (positive also for internal gears; see ``internal``).
    module : float
        Module m [m].
    pressure_angle : float
        Reference pressure angle alpha [rad] (default 20 deg).
    x : float
        Profile shift coefficient [-].
    ha : float
        Addendum coefficient h_a* [-] (tip: r_a = r + (ha + x) m, external).
    hf : float
        Dedendum coefficient h_f* [-] (root: r_f = r - (hf - x) m, external); also the tool
        addendum that cuts the root.
    rho_f : float, optional
        Tip radius coefficient of the generating tool rho_fP* [-]. Default 0.38 (ISO 53 profile A
        rack) for external gears, 0.25 for internal gears (a 0.38 m rounding does not fit on the
        tip of a pinion cutter with a 1.25 m addendum).
    face_width : float
        Face width b [m].
    thinning : float
        Backlash allowance: reduction of the circular tooth thickness at the reference circle [m].
    internal : bool
        True for an internal (ring) gear.
    bore_diameter : float
        Bore (hub) diameter of an external gear [m]; 0 for a solid gear.
    rim_diameter : float or None
        Outer diameter of an internal gear's rim [m].
    cutter_teeth : int
        Teeth of the pinion-type cutter that generates an internal gear.
    name : str
        Name used in messages.
    """

    z: int
    module: float
    pressure_angle: float = math.radians(20.0)
    x: float = 0.0
    ha: float = 1.0
    hf: float = 1.25
    rho_f: float | None = None
    face_width: float = 0.02
    thinning: float = 0.0
    internal: bool = False
    bore_diameter: float = 0.0
    rim_diameter: float | None = None
    cutter_teeth: int = 18
    name: str = "gear"

    def __post_init__(self):
        n = self.name
        if self.rho_f is None:  # ISO 53 profile A rack: 0.38; pinion cutters carry a smaller rounding
            object.__setattr__(self, "rho_f", 0.25 if self.internal else 0.38)
        if not isinstance(self.z, (int, np.integer)) or isinstance(self.z, bool):
            raise GeometryError(f"{n}.z = {self.z!r}: number of teeth must be an integer")
        zmin = 4
        if self.z < zmin:
            raise GeometryError(f"{n}.z = {self.z}: number of teeth must be >= {zmin}")
        _check_positive(f"{n}.module", self.module)
        _check_positive(f"{n}.face_width", self.face_width)
        if not (0 < self.pressure_angle < math.radians(45)):
            raise GeometryError(
                f"{n}.pressure_angle = {math.degrees(self.pressure_angle):.3g} deg: must lie in (0, 45) deg"
            )
        _check_positive(f"{n}.ha", self.ha)
        _check_positive(f"{n}.hf", self.hf)
        if self.rho_f < 0:
            raise GeometryError(f"{n}.rho_f = {self.rho_f}: tool tip radius coefficient must be >= 0")
        if self.thinning < 0:
            raise GeometryError(f"{n}.thinning = {self.thinning}: backlash allowance must be >= 0 m")
        if self.hf <= self.ha and not self.internal:
            pass  # allowed (no clearance), unusual
        if self.internal:
            if self.rim_diameter is None:
                raise GeometryError(f"{n}.rim_diameter is required for an internal gear")
            _check_positive(f"{n}.rim_diameter", self.rim_diameter)
            if self.rim_diameter / 2 <= self.rf:
                raise GeometryError(
                    f"{n}.rim_diameter = {self.rim_diameter*1e3:.4g} mm: must exceed the root diameter "
                    f"{2*self.rf*1e3:.4g} mm"
                )
            if not isinstance(self.cutter_teeth, (int, np.integer)) or self.cutter_teeth < 8:
                raise GeometryError(f"{n}.cutter_teeth = {self.cutter_teeth!r}: must be an integer >= 8")
            if self.cutter_teeth >= self.z - 4:
                raise GeometryError(
                    f"{n}.cutter_teeth = {self.cutter_teeth}: a pinion cutter must have fewer teeth than "
                    f"the internal gear minus 4 (z = {self.z})"
                )
            if self.ra <= self.rb:
                raise GeometryError(
                    f"{n}: tip radius {self.ra*1e3:.4g} mm lies inside the base circle "
                    f"{self.rb*1e3:.4g} mm of the internal gear (rule: r_a > r_b); reduce ha or increase x"
                )
        else:
            if self.bore_diameter < 0:
                raise GeometryError(f"{n}.bore_diameter = {self.bore_diameter}: must be >= 0")
            if self.bore_diameter / 2 >= self.rf:
                raise GeometryError(
                    f"{n}.bore_diameter = {self.bore_diameter*1e3:.4g} mm: the bore cuts the root circle "
                    f"(root diameter {2*self.rf*1e3:.4g} mm)"
                )
        sa = self.tip_thickness
        if sa <= 0:
            raise GeometryError(
                f"{n}: pointed teeth: tip thickness s_a = {sa*1e3:.4g} mm <= 0 "
                f"(z = {self.z}, x = {self.x}, ha = {self.ha}); reduce ha or x"
            )
        if sa < 0.2 * self.module:
            warnings.warn(
                f"{n}: tip thickness s_a = {sa*1e3:.3g} mm is below 0.2 m = {0.2*self.module*1e3:.3g} mm "
                "(nearly pointed teeth)",
                stacklevel=user_stacklevel(),
            )

    # ------------------------------------------------------------------ basic radii
    @property
    def sign(self) -> int:
        """+1 for external, -1 for internal gears (ISO 21771 sign of z)."""
        return -1 if self.internal else 1

    @property
    def r(self) -> float:
        """Reference radius r = m z / 2 [m]."""
        return self.module * self.z / 2.0

    @property
    def rb(self) -> float:
        """Base radius r_b = r cos(alpha) [m]."""
        return self.r * math.cos(self.pressure_angle)

    @property
    def ra(self) -> float:
        """Tip radius [m]: r + (ha + x) m external, r - (ha + x) m internal (ISO 21771)."""
        return self.r + self.sign * (self.ha + self.x) * self.module

    @property
    def rf(self) -> float:
        """Root radius [m]: r - (hf - x) m external, r + (hf - x) m internal."""
        return self.r - self.sign * (self.hf - self.x) * self.module

    @property
    def p(self) -> float:
        """Reference pitch p = pi m [m]."""
        return math.pi * self.module

    @property
    def pb(self) -> float:
        """Base pitch p_b = pi m cos(alpha) [m]."""
        return self.p * math.cos(self.pressure_angle)

    @property
    def pitch_angle(self) -> float:
        """Angular pitch 2 pi / z [rad]."""
        return 2.0 * math.pi / self.z

    @property
    def s(self) -> float:
        """Circular tooth thickness at the reference circle [m], m (pi/2 + 2 x tan(alpha)) - thinning."""
        return self.module * (math.pi / 2 + 2 * self.x * math.tan(self.pressure_angle)) - self.thinning

    # ------------------------------------------------------------------ involute thickness
    def involute_half_angle(self, r):
        """Half tooth angle of the involute flank at radius r >= r_b [rad] (ISO 21771).

        External: psi = s/(2 r_ref) + inv(alpha) - inv(alpha_y); internal:
        psi = s/(2 r_ref) - inv(alpha) + inv(alpha_y), with cos(alpha_y) = r_b / r.
        """
        r = np.asarray(r, dtype=float)
        ay = np.arccos(np.clip(self.rb / r, -1.0, 1.0))
        a = self.pressure_angle
        return self.s / (2 * self.r) + self.sign * (inv(a) - inv(ay))

    @property
    def tip_thickness(self) -> float:
        """Circular tooth thickness at the tip circle s_a [m] (involute)."""
        return float(2 * self.ra * self.involute_half_angle(self.ra))

    def half_angle(self, r):
        """Half tooth angle [rad] of the generated outline at radius r (root to tip)."""
        prof = self._profile
        r = np.asarray(r, dtype=float)
        return np.interp(r, prof["r"], prof["theta"]) if not self.internal else np.interp(
            r, prof["r"][::-1], prof["theta"][::-1]
        )

    def thickness(self, r):
        """Circular tooth thickness s_y = 2 r psi(r) at radius r [m] (involute and fillet)."""
        r = np.asarray(r, dtype=float)
        lo, hi = sorted((self.rf, self.ra))
        if np.any((r < lo - 1e-12) | (r > hi + 1e-12)):
            raise GeometryError(
                f"{self.name}.thickness: radius outside the tooth [{lo*1e3:.4g}, {hi*1e3:.4g}] mm"
            )
        return 2 * r * self.half_angle(r)

    def base_tangent_length(self, k: int) -> float:
        """Base tangent length W_k over k teeth [m] (ISO 21771, spur, external gears).

        W_k = m cos(alpha) [pi (k - 0.5) + z inv(alpha)] + 2 x m sin(alpha) - thinning cos(alpha).
        """
        if self.internal:
            raise GeometryError(f"{self.name}: base tangent length is defined here for external gears")
        if not (1 <= k < self.z):
            raise GeometryError(f"{self.name}: base tangent span k = {k} must satisfy 1 <= k < z = {self.z}")
        a, m = self.pressure_angle, self.module
        return (m * math.cos(a) * (math.pi * (k - 0.5) + self.z * inv(a)) + 2 * self.x * m * math.sin(a)
                - self.thinning * math.cos(a))

    @property
    def base_tangent_span(self) -> int:
        """Usual number of spanned teeth k = round(z alpha / pi + 0.5) (at least 1)."""
        return max(1, int(round(self.z * self.pressure_angle / math.pi + 0.5)))

    # ------------------------------------------------------------------ generation
    @cached_property
    def _profile(self):
        """Half-tooth boundary (left side) as arrays r, theta with segment kinds.

        Returns a dict with dense arrays ordered from the space centre (root) to the tip centre.
        """
        if self.internal:
            fil = self._fillet_pinion_cutter()
        else:
            fil = self._fillet_rack()
        return self._assemble_profile(fil)

    def _fillet_rack(self):
        """Trochoid cut by the basic rack's tip rounding (external gear), left side of tooth 0."""
        m, a, r = self.module, self.pressure_angle, self.r
        rho = self.rho_f * m
        C = self.s / 2  # flank line u + v tan(a) = C  (u tangential, v radial from reference circle)
        vt = (self.x - self.hf) * m  # tool tip line
        vc = vt + rho
        uc = C - vc * math.tan(a) + rho / math.cos(a)
        half_space = self.p / 2
        if uc > half_space:
            rho_max = (half_space - C + vt * math.tan(a)) / (1 / math.cos(a) - math.tan(a))
            raise GeometryError(
                f"{self.name}.rho_f = {self.rho_f}: the tool tip rounding does not fit on the basic rack's "
                f"tip land (largest that fits: {rho_max / m:.3f}); reduce rho_f"
            )
        # cutting direction (u, v) = normalize(uc + r phi, vc); scan phi
        phi_b = -uc / r
        phi_t = (vc / math.tan(a) - uc) / r
        phis = np.linspace(phi_b, phi_t, 1500)
        du = uc + r * phis
        dv = np.full_like(phis, vc)
        nrm = np.hypot(du, dv)
        du, dv = du / nrm, dv / nrm
        pu, pv = uc + rho * du, vc + rho * dv
        # map rack (u, v) at roll phi into the gear frame: R(-phi) [r + v, u + r phi]
        X, Y = r + pv, pu + r * phis
        c, s_ = np.cos(phis), np.sin(phis)
        gx, gy = c * X + s_ * Y, -s_ * X + c * Y
        rr = np.hypot(gx, gy)
        th = np.arctan2(gy, gx)
        return rr, th, uc / r  # root land ends at polar angle uc/r

    def _fillet_pinion_cutter(self):
        """Trochoid cut by a pinion-type cutter's tip rounding (internal gear), left side of tooth 0."""
        m, a = self.module, self.pressure_angle
        z, z0 = self.z, self.cutter_teeth
        rho = self.rho_f * m
        r0 = m * z0 / 2.0
        rb0 = r0 * math.cos(a)
        s0 = self.p - self.s  # cutter tooth = internal gear's space (thinning widens the space)
        a0 = self.r - r0  # centre distance of generation (the shift is in s0 and the tip reach)
        ra0 = self.rf - a0  # cutter tip radius reaches the internal root circle
        # generating pitch radius of the cutter for centre distance a0 (ratio z/z0 fixed)
        rw0 = a0 * z0 / (z - z0)
        thc = math.pi / z0  # cutter tooth centre in the cutter frame (space on +x at phi0 = 0)
        lam_flank = thc - s0 / (2 * r0) - float(inv(a))  # right flank of that cutter tooth

        def lam(px, py):
            rq = np.hypot(px, py)
            return np.arctan2(py, px) - inv(np.arccos(np.clip(rb0 / rq, -1, 1)))

        rq = ra0 - rho
        if rq <= rb0:
            raise GeometryError(
                f"{self.name}: pinion cutter ({z0} teeth) tip rounding centre falls inside its base circle; "
                "use more cutter teeth or a smaller rho_f"
            )
        thq = lam_flank + rho / rb0 + float(inv(math.acos(rb0 / rq)))
        if thq > thc:
            raise GeometryError(
                f"{self.name}.rho_f = {self.rho_f}: the tip rounding does not fit on the tip of the "
                f"{z0}-tooth pinion cutter (its centre passes the tooth centre line); reduce rho_f "
                "or raise cutter_teeth"
            )
        Cx, Cy = rq * math.cos(thq), rq * math.sin(thq)
        # inward normal of the flank at C: grad(lambda), numerically
        h = 1e-9
        gx = (lam(Cx + h, Cy) - lam(Cx - h, Cy)) / (2 * h)
        gy = (lam(Cx, Cy + h) - lam(Cx, Cy - h)) / (2 * h)
        g = math.hypot(gx, gy)
        d_flank = -np.array([gx, gy]) / g
        d_tip = np.array([Cx, Cy]) / rq
        ang_f = math.atan2(d_tip[0] * d_flank[1] - d_tip[1] * d_flank[0], d_tip @ d_flank)
        # scan cutter rotation phi0; instantaneous centre in the cutter frame
        phi0_b = -thq
        span = 1.2 * math.pi / z0 + 0.6
        phi0 = np.linspace(phi0_b - span, phi0_b + span, 20001)
        Ix, Iy = rw0 * np.cos(phi0), -rw0 * np.sin(phi0)
        dx, dy = Cx - Ix, Cy - Iy
        dn = np.hypot(dx, dy)
        dx, dy = dx / dn, dy / dn
        ang = np.arctan2(d_tip[0] * dy - d_tip[1] * dx, d_tip[0] * dx + d_tip[1] * dy)
        keep = (np.sign(ang) == np.sign(ang_f)) & (np.abs(ang) <= abs(ang_f)) | (np.abs(ang) < 1e-15)
        idx = np.nonzero(keep)[0]
        if len(idx) < 10:
            raise GeometryError(f"{self.name}: pinion cutter generation failed (no cutting range)")
        # keep the contiguous range containing the bottom point
        ib = int(np.argmin(np.abs(phi0 - phi0_b)))
        lo = hi = ib
        while lo - 1 >= 0 and keep[lo - 1]:
            lo -= 1
        while hi + 1 < len(keep) and keep[hi + 1]:
            hi += 1
        sl = slice(lo, hi + 1)
        pcx, pcy = Cx + rho * dx[sl], Cy + rho * dy[sl]
        ph0 = phi0[sl]
        phi = ph0 * z0 / z
        # cutter frame -> internal gear frame: R(-phi) O0 + R(phi0 - phi) P
        rel = ph0 - phi
        px = a0 * np.cos(-phi) + np.cos(rel) * pcx - np.sin(rel) * pcy
        py = a0 * np.sin(-phi) + np.sin(rel) * pcx + np.cos(rel) * pcy
        rr = np.hypot(px, py)
        th = np.arctan2(py, px)
        # the root land ends where the tip circle's cutting point leaves: polar angle at the bottom
        th_root = th[np.argmax(rr)] if len(rr) else math.pi / z
        order = np.argsort(rr)
        return rr[order], th[order], th_root

    def _assemble_profile(self, fil):
        """Join root land, trochoid fillet and involute into one half-tooth boundary.

        The involute exists only where the tool's straight (rack) or involute (cutter) flank
        generates it, i.e. beyond the point where the tip rounding's trochoid meets it
        tangentially (radius r_T). Undercut is reported (:attr:`undercut`), and its outline is
        approximated by a radial line from the trochoid end to the base circle.
        """
        rr_f, th_f, th_root = fil
        ext = not self.internal
        order = np.argsort(rr_f)
        rr_f, th_f = rr_f[order], th_f[order]
        if ext:
            r_T = float(rr_f[-1])
            if self.undercut:
                # the fillet crosses the involute above the base circle: the tool's flank has
                # cut the tooth there, so the fillet ends at the crossing and the involute starts
                sel = rr_f >= self.rb
                if np.count_nonzero(sel) >= 2:
                    diff = th_f[sel] - self.involute_half_angle(rr_f[sel])
                    cross = np.nonzero(np.diff(np.sign(diff)) != 0)[0]
                    if len(cross):
                        j = cross[-1]
                        r1, r2 = rr_f[sel][j], rr_f[sel][j + 1]
                        d1, d2 = diff[j], diff[j + 1]
                        r_T = float(r1 - d1 * (r2 - r1) / (d2 - d1))
                        keep = rr_f < r_T
                        rr_f, th_f = rr_f[keep], th_f[keep]
            r_inv0 = max(r_T, self.rb)
            if self.ra <= r_inv0:
                raise GeometryError(
                    f"{self.name}: no involute flank: tip radius {self.ra*1e3:.4g} mm <= form radius "
                    f"{r_inv0*1e3:.4g} mm"
                )
            r_inv = np.linspace(r_inv0, self.ra, 2001)
            rad = np.concatenate([rr_f, r_inv])
            th = np.concatenate([th_f, self.involute_half_angle(r_inv)])
            kinds = np.concatenate([np.full(len(rr_f), FILLET), np.full(len(r_inv), FLANK)])
            r_form = r_inv0
        else:
            r_T = float(rr_f[0])
            if r_T <= self.ra:
                raise GeometryError(
                    f"{self.name}: no involute flank: form radius {r_T*1e3:.4g} mm <= tip radius "
                    f"{self.ra*1e3:.4g} mm"
                )
            r_inv = np.linspace(r_T, self.ra, 2001)  # root side -> tip (decreasing radius)
            rad = np.concatenate([rr_f[::-1], r_inv])
            th = np.concatenate([th_f[::-1], self.involute_half_angle(r_inv)])
            kinds = np.concatenate([np.full(len(rr_f), FILLET), np.full(len(r_inv), FLANK)])
            r_form = r_T
        # drop the duplicated junction point
        keep = np.ones(len(rad), bool)
        keep[len(rr_f)] = not np.isclose(rad[len(rr_f)], rad[len(rr_f) - 1], rtol=0, atol=1e-12)
        return {"r": rad[keep], "theta": th[keep], "kind": kinds[keep], "r_form": float(r_form),
                "theta_root": float(th_root)}

    def _form_radius_nominal(self) -> float:
        """Form radius from the rack's straight flank end (ISO 21771), external gears [m]."""
        a, m = self.pressure_angle, self.module
        haP0 = (self.hf - self.rho_f * (1 - math.sin(a))) * m
        q = self.r * math.sin(a) - (haP0 - self.x * m) / math.sin(a)
        return math.sqrt(self.rb**2 + max(q, 0.0) ** 2) if q > 0 else self.rb

    @property
    def r_form(self) -> float:
        """Form radius: where the generated involute flank begins [m]."""
        return self._profile["r_form"]

    @property
    def undercut(self) -> bool:
        """True if the generating tool undercuts the involute flank (external gears)."""
        if self.internal:
            return False
        a = self.pressure_angle
        haP0 = self.hf - self.rho_f * (1 - math.sin(a))
        return self.x < haP0 - self.z * math.sin(a) ** 2 / 2

    # ------------------------------------------------------------------ outlines
    def tooth_outline(self, ds: float | None = None) -> Outline:
        """One tooth (index 0) from mid-space at -pi/z to mid-space at +pi/z, counter-clockwise.

        Parameters
        ----------
        ds : float, optional
            Maximum spacing of the points along the outline [m] (default m/100).
        """
        ds = self.module / 100 if ds is None else ds
        if not ds > 0:
            raise GeometryError(f"{self.name}: outline spacing ds = {ds!r} must be > 0")
        prof = self._profile
        segs = []  # each (points(N,2), kind) along the left half from space centre to tip centre

        def arc(radius, t0, t1, kind):
            n = max(2, int(math.ceil(abs(t1 - t0) * radius / ds)) + 1)
            t = np.linspace(t0, t1, n)
            return np.column_stack([radius * np.cos(t), radius * np.sin(t)]), np.full(n, kind)

        def resample(rad, th, kind):
            xy = np.column_stack([rad * np.cos(th), rad * np.sin(th)])
            L = np.concatenate([[0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
            n = max(2, int(math.ceil(L[-1] / ds)) + 1)
            s = np.linspace(0, L[-1], n)
            return np.column_stack([np.interp(s, L, xy[:, 0]), np.interp(s, L, xy[:, 1])]), np.full(n, kind)

        half = math.pi / self.z
        rad, th, kinds = prof["r"], prof["theta"], prof["kind"]
        # root land from the space centre to the fillet start
        segs.append(arc(self.rf, half, th[0], ROOT))
        fil = kinds == FILLET
        if np.count_nonzero(fil) >= 2:
            segs.append(resample(rad[fil], th[fil], FILLET))
        fl = kinds == FLANK
        segs.append(resample(rad[fl], th[fl], FLANK))
        segs.append(arc(self.ra, th[-1], 0.0, TIP))
        pts, kd = [], []
        for i, (p, k) in enumerate(segs):
            if i > 0 and np.hypot(*(p[0] - pts[-1][-1])) < 1e-12:
                p, k = p[1:], k[1:]  # drop a duplicated junction point
            pts.append(p)
            kd.append(k)
        left = np.vstack(pts)
        left_kind = np.concatenate(kd)
        # left half runs space centre (+half) -> tip centre (0). The whole tooth, counter-clockwise
        # about the gear centre, is the mirrored left half (-half -> 0) followed by the left half
        # reversed (0 -> +half).
        mirrored = left.copy()
        mirrored[:, 1] *= -1
        pts = np.vstack([mirrored, left[::-1][1:]])
        kind = np.concatenate([left_kind, left_kind[::-1][1:]])
        side = np.concatenate([-np.ones(len(left), int), np.ones(len(left) - 1, int)])
        return Outline(points=pts, tooth=np.zeros(len(pts), int), kind=kind, side=side)

    def outline(self, ds: float | None = None) -> Outline:
        """The whole gear's toothed outline, closed polygon (last point != first), CCW.

        For an internal gear the material lies outside this polygon (up to the rim).
        """
        one = self.tooth_outline(ds)
        n1 = len(one) - 1  # drop the last point (it equals the next tooth's first point)
        P, T, K, S = [], [], [], []
        for k in range(self.z):
            a = k * self.pitch_angle
            c, s = math.cos(a), math.sin(a)
            p = one.points[:n1] @ np.array([[c, s], [-s, c]])
            P.append(p)
            T.append(np.full(n1, k))
            K.append(one.kind[:n1])
            S.append(one.side[:n1])
        return Outline(np.vstack(P), np.concatenate(T), np.concatenate(K), np.concatenate(S))

    # ------------------------------------------------------------------ mass properties
    def mass_properties(self, density: float, ds: float | None = None) -> tuple[float, float]:
        """Mass [kg] and polar moment of inertia about the axis [kg m^2] from the outline.

        External: toothed outline minus the bore; internal: rim disc minus the toothed outline.
        """
        pts = self.outline(ds if ds is not None else self.module / 20).points
        x, y = pts[:, 0], pts[:, 1]
        xn, yn = np.roll(x, -1), np.roll(y, -1)
        cr = x * yn - xn * y
        area = 0.5 * cr.sum()
        jz = (cr * (x * x + x * xn + xn * xn + y * y + y * yn + yn * yn)).sum() / 12.0
        if self.internal:
            R = self.rim_diameter / 2
            area = math.pi * R**2 - area
            jz = math.pi * R**4 / 2 - jz
        else:
            rb_ = self.bore_diameter / 2
            area -= math.pi * rb_**2
            jz -= math.pi * rb_**4 / 2
        b = self.face_width
        return density * area * b, density * jz * b


@dataclass(frozen=True)
class GearPair:
    """A meshing pair: ``g1`` external, ``g2`` external or internal (ISO 21771, spur).

    The working centre distance follows from the profile shifts for zero backlash (thinning is a
    tolerance and leaves it unchanged).
    """

    g1: SpurGear
    g2: SpurGear

    def __post_init__(self):
        if self.g1.internal:
            raise GeometryError(f"pair {self.g1.name}-{self.g2.name}: the first gear must be external")
        if not math.isclose(self.g1.module, self.g2.module, rel_tol=1e-9):
            raise GeometryError(
                f"pair {self.name}: modules differ ({self.g1.module*1e3:g} mm vs {self.g2.module*1e3:g} mm); "
                "meshing gears need the same module"
            )
        if not math.isclose(self.g1.pressure_angle, self.g2.pressure_angle, rel_tol=1e-9):
            raise GeometryError(f"pair {self.name}: pressure angles differ; meshing gears need the same")
        if self.g2.internal and self.g2.z - self.g1.z < 5:
            raise GeometryError(
                f"pair {self.name}: internal gear z = {self.g2.z} and pinion z = {self.g1.z} differ by "
                f"{self.g2.z - self.g1.z} < 5 teeth (tip interference)"
            )

    @property
    def name(self) -> str:
        return f"{self.g1.name}-{self.g2.name}"

    @property
    def internal(self) -> bool:
        return self.g2.internal

    @property
    def _z2s(self) -> int:
        return -self.g2.z if self.internal else self.g2.z

    @property
    def alpha_w(self) -> float:
        """Working transverse pressure angle [rad]: inv(a_w) = inv(a) + 2 tan(a) (x1 + x2)/(z1 + z2)."""
        a = self.g1.pressure_angle
        v = float(inv(a)) + 2 * math.tan(a) * (self.g1.x + self.g2.x) / (self.g1.z + self._z2s)
        return inv_inverse(v)

    @property
    def centre_distance(self) -> float:
        """Working centre distance |a_w| [m] = |z1 + z2| m cos(a) / (2 cos(a_w))."""
        m, a = self.g1.module, self.g1.pressure_angle
        return abs(self.g1.z + self._z2s) * m * math.cos(a) / (2 * math.cos(self.alpha_w))

    @property
    def ratio(self) -> float:
        """Gear ratio u = z2 / z1 (positive)."""
        return self.g2.z / self.g1.z

    @property
    def path_of_contact(self) -> tuple[float, float]:
        """Approach and recess lengths along the line of action [m], (g_f, g_a), measured from the
        pitch point; their sum is the length of the path of contact g_alpha.

        g_a (recess, tip of g1) = sqrt(ra1^2 - rb1^2) - rb1 tan(a_w);
        g_f (approach, tip of g2) = sqrt(ra2^2 - rb2^2) - rb2 tan(a_w) (external) or
        rb2 tan(a_w) - sqrt(ra2^2 - rb2^2) (internal).
        """
        g1, g2, aw = self.g1, self.g2, self.alpha_w
        ga = math.sqrt(g1.ra**2 - g1.rb**2) - g1.rb * math.tan(aw)
        t2 = math.sqrt(max(g2.ra**2 - g2.rb**2, 0.0))
        gf = (t2 - g2.rb * math.tan(aw)) if not self.internal else (g2.rb * math.tan(aw) - t2)
        return gf, ga

    @property
    def face_width(self) -> float:
        """Common face width b [m]: the narrower of the two gears' (the length of the contact lines)."""
        return min(self.g1.face_width, self.g2.face_width)

    @property
    def contact_ratio(self) -> float:
        """Transverse contact ratio eps_alpha = g_alpha / p_b (ISO 21771)."""
        gf, ga = self.path_of_contact
        return (gf + ga) / self.g1.pb

    @property
    def hertz_radius(self) -> float:
        """Equivalent radius of curvature at the pitch point R [m] (paper Eq. 5).

        rho_i = r_bi tan(a_w); external R = rho1 rho2/(rho1 + rho2), internal rho1 rho2/(rho2 - rho1).
        """
        t = math.tan(self.alpha_w)
        r1, r2 = self.g1.rb * t, self.g2.rb * t
        return r1 * r2 / (r2 - r1) if self.internal else r1 * r2 / (r1 + r2)

    def hertz_stiffness(self, e_star: float) -> float:
        """K = 4/3 sqrt(R) E* [N/m^1.5] (paper Eq. 5, cylinders in contact)."""
        return 4.0 / 3.0 * math.sqrt(self.hertz_radius) * e_star

    def check(self) -> list[str]:
        """Geometric checks of the pair; raises GeometryError, returns warnings (as text)."""
        notes = []
        g1, g2, aw = self.g1, self.g2, self.alpha_w
        gf, ga = self.path_of_contact
        # the contact path must stay within the involute parts of both flanks
        T1 = g1.rb * math.tan(aw)  # interference point distance from the pitch point on g1's side
        if self.internal:
            T2_inner = T1  # g2 approach limited by the pinion's tangent point (same side)
            if gf > T2_inner + 1e-12:
                raise GeometryError(
                    f"pair {self.name}: tip of {g2.name} reaches past the interference point of "
                    f"{g1.name} (approach {gf*1e3:.4g} mm > {T2_inner*1e3:.4g} mm)"
                )
        else:
            if gf > T1 + 1e-12:
                raise GeometryError(
                    f"pair {self.name}: tip of {g2.name} reaches past the interference point of "
                    f"{g1.name} (approach {gf*1e3:.4g} mm > {T1*1e3:.4g} mm)"
                )
            T2 = g2.rb * math.tan(aw)
            if ga > T2 + 1e-12:
                raise GeometryError(
                    f"pair {self.name}: tip of {g1.name} reaches past the interference point of "
                    f"{g2.name} (recess {ga*1e3:.4g} mm > {T2*1e3:.4g} mm)"
                )
        # form radii: the active flanks must be involute
        t2 = g2.rb * math.tan(aw)
        rA2 = math.hypot(g2.rb, t2 + ga) if self.internal else math.hypot(g2.rb, t2 - ga)
        if (self.internal and rA2 > g2.r_form + 1e-9) or (not self.internal and rA2 < g2.r_form - 1e-9):
            notes.append(
                f"pair {self.name}: {g2.name} active flank reaches r = {rA2*1e3:.4g} mm beyond its form "
                f"radius {g2.r_form*1e3:.4g} mm (contact on the fillet)"
            )
        rA1 = math.hypot(g1.rb, g1.rb * math.tan(aw) - gf)  # g1's lowest active radius
        if rA1 < g1.r_form - 1e-9:
            notes.append(
                f"pair {self.name}: {g1.name} active flank starts at r = {rA1*1e3:.4g} mm below its form "
                f"radius {g1.r_form*1e3:.4g} mm (contact on the fillet)"
            )
        if self.contact_ratio < 1.0:
            raise GeometryError(
                f"pair {self.name}: transverse contact ratio {self.contact_ratio:.3f} < 1 (rule: eps_alpha >= 1)"
            )
        # tip clearance: a tip circle must not cut the mating root circle (the gears would jam)
        a = self.centre_distance
        if self.internal:
            gaps = ((g1, g2, g2.rf - a - g1.ra), (g2, g1, g2.ra - a - g1.rf))
        else:
            gaps = ((g1, g2, a - g1.ra - g2.rf), (g2, g1, a - g2.ra - g1.rf))
        for tip, root, c in gaps:
            if c < -1e-12:
                raise GeometryError(
                    f"pair {self.name}: the tip circle of {tip.name} cuts the root circle of {root.name} "
                    f"(tip clearance {c*1e3:.4g} mm < 0 at centre distance {a*1e3:.4g} mm); reduce "
                    f"{tip.name}'s addendum or increase {root.name}'s dedendum")
        return notes


_GEAR_PARAMS = ("z", "module", "pressure_angle", "x", "ha", "hf", "rho_f", "face_width",
                "thinning", "internal", "bore_diameter", "rim_diameter", "cutter_teeth")


def gear_parameters(gear) -> dict:
    """Geometry parameters of ``gear`` that define its body (the name is left out) [SI]."""
    if dataclasses.is_dataclass(gear):
        d = {f.name: getattr(gear, f.name) for f in dataclasses.fields(gear)}
    else:
        d = {k: getattr(gear, k) for k in _GEAR_PARAMS if hasattr(gear, k)}
    d.pop("name", None)
    return jsonable(d)
