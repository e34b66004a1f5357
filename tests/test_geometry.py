"""Independent verification of flexgear.geometry (ISO 21771 / DIN 3960 spur gear geometry).

Every expectation is derived in this file from a closed form (ISO 21771) or from an independent
numerical construction (brute-force envelopes of the generating tools, caliper measurements on
the generated outline, two outlines placed in mesh); no number printed by the code under test is
used as a reference value. Lengths in metres, angles in radians.
"""
import math
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar
from matplotlib.path import Path as MplPath
from scipy.spatial import cKDTree

from flexgear.errors import GeometryError
from flexgear.gears.geometry import FILLET, FLANK, ROOT, TIP, GearPair, SpurGear, inv_inverse

M = 2e-3
A20 = math.radians(20.0)
RING_RIM = 0.16


# ============================================================================ independent helpers
def invf(a):
    return np.tan(a) - a


def ext(z, x=0.0, **kw):
    kw.setdefault("module", M)
    return SpurGear(z=z, x=x, **kw)


def ring(z=66, x=0.0, **kw):
    kw.setdefault("module", M)
    kw.setdefault("rim_diameter", RING_RIM)
    return SpurGear(z=z, x=x, internal=True, **kw)


def iso_half_angle(z, m, a, x, thinning, r, internal=False):
    """ISO 21771 half tooth angle at radius r >= r_b: s_y = d_y (s/d +- (inv a - inv a_y))."""
    d = m * z
    s = m * (math.pi / 2 + 2 * x * math.tan(a)) - thinning
    ay = np.arccos(m * z * math.cos(a) / 2 / np.asarray(r, float))
    sgn = -1.0 if internal else 1.0
    return s / d + sgn * (invf(a) - invf(ay))


def polar(p):
    return np.hypot(p[:, 0], p[:, 1]), np.arctan2(p[:, 1], p[:, 0])


def circle_crossings(pts, R):
    """Polar angles where the closed-or-open polyline pts crosses the circle of radius R (exact
    segment/circle intersection)."""
    p0, p1 = pts[:-1], pts[1:]
    d = p1 - p0
    A = (d * d).sum(1)
    B = 2 * (p0 * d).sum(1)
    C = (p0 * p0).sum(1) - R * R
    disc = B * B - 4 * A * C
    out = []
    for sgn in (-1.0, 1.0):
        with np.errstate(invalid="ignore"):
            t = (-B + sgn * np.sqrt(disc)) / (2 * A)
        ok = (disc >= 0) & (t >= 0) & (t < 1)
        q = p0[ok] + t[ok, None] * d[ok]
        out.extend(np.arctan2(q[:, 1], q[:, 0]).tolist())
    return np.array(sorted(set(np.round(out, 15))))


def tooth_half_angles_from_outline(g, R, ds=None):
    """(left, right) polar angles of tooth 0 at radius R measured on the generated outline."""
    o = g.tooth_outline(ds if ds is not None else g.module / 400)
    left = circle_crossings(o.points[o.side == 1], R)
    right = circle_crossings(o.points[o.side == -1], R)
    assert len(left) == 1 and len(right) == 1, (left, right)
    return left[0], right[0]


def seg_self_intersections(P):
    """Number of proper crossings between non-adjacent edges of the closed polygon P."""
    a = P
    b = np.roll(P, -1, axis=0)
    n = len(P)

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    count = 0
    chunk = 400
    for i0 in range(0, n, chunk):
        ai, bi = a[i0:i0 + chunk, None, :], b[i0:i0 + chunk, None, :]
        aj, bj = a[None, :, :], b[None, :, :]
        o1 = orient(ai, bi, aj)
        o2 = orient(ai, bi, bj)
        o3 = orient(aj, bj, ai)
        o4 = orient(aj, bj, bi)
        cross = (o1 * o2 < 0) & (o3 * o4 < 0)
        I = np.arange(i0, min(i0 + chunk, n))[:, None]
        J = np.arange(n)[None, :]
        adj = (np.abs(I - J) <= 1) | (np.abs(I - J) == n - 1)
        count += int(np.count_nonzero(cross & ~adj))
    return count // 2


def signed_area(P):
    x, y = P[:, 0], P[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


# ---------------------------------------------------------------- brute-force rack envelope
def rack_envelope_half_angle(g, R):
    """Half tooth angle at radius R of an external gear cut by the ISO basic rack (tip rounding
    rho_f m, addendum hf m, datum shifted by x m, tooth thickness reduced by the thinning), found by
    brute force: the smallest polar angle on the circle R that the rolling rack tooth ever covers.
    The rounded rack tooth is the core polygon (rack tooth shrunk by rho) dilated by rho."""
    m, a, z = g.module, g.pressure_angle, g.z
    r, p, rho = m * z / 2, math.pi * m, g.rho_f * m
    C = (m * (math.pi / 2 + 2 * g.x * math.tan(a)) - g.thinning) / 2  # gear half thickness at v = 0
    vc = (g.x - g.hf) * m + rho
    k0 = p / 2 - C - rho / math.cos(a)
    W0 = k0 + vc * math.tan(a)
    d = (math.sin(a), math.cos(a))

    def f(t, phi):
        v = R * np.cos(t + phi) - r          # rack coordinates: v radial from the reference line,
        u = R * np.sin(t + phi) - r * phi    # u along the rack; rack tooth centres at u = p/2 + k p
        W = np.abs(u - p / 2 - p * np.round((u - p / 2) / p))
        inside = (v >= vc) & (W <= k0 + v * math.tan(a))
        dseg = np.where(W <= W0, np.abs(v - vc), np.hypot(W - W0, v - vc))
        qx, qy = W - W0, v - vc
        tp = np.maximum(0.0, qx * d[0] + qy * d[1])
        dray = np.hypot(qx - tp * d[0], qy - tp * d[1])
        return np.where(inside, 0.0, np.minimum(dseg, dray)) - rho

    return _envelope_bisect(f, math.pi / z, 0.7, 4001)


def _envelope_bisect(f, half, span, n):
    def fmin(t):
        phis = -t + np.linspace(-span, span, n)
        v = f(t, phis)
        i = int(np.argmin(v))
        res = minimize_scalar(lambda ph: float(f(t, np.array([ph]))[0]),
                              bounds=(phis[max(i - 1, 0)], phis[min(i + 1, n - 1)]), method="bounded",
                              options={"xatol": 1e-14})
        return min(float(res.fun), float(v[i]))

    return brentq(fmin, 0.0, half, xtol=1e-14)


# ---------------------------------------------------------------- brute-force pinion cutter envelope
class PinionCutter:
    """An independent pinion-type cutter: z0 teeth, tooth thickness s0 at r0 = m z0/2, tip radius
    ra0, tip rounding rho. Cutter frame: a space centred on +x, tooth centres at (2k+1) pi / z0."""

    def __init__(self, z0, m, a, s0, ra0, rho):
        self.z0, self.m, self.a, self.s0, self.ra0, self.rho = z0, m, a, s0, ra0, rho
        self.r0 = m * z0 / 2
        self.rb0 = self.r0 * math.cos(a)
        rq = ra0 - rho
        # the centre of the rounding lies on the flank involute offset inwards by rho, i.e. on the
        # same involute turned by rho / r_b0 towards the tooth centre
        psiQ = float(self.psi(rq)) - rho / self.rb0
        assert psiQ > 0, "rounding does not fit on this cutter"
        self.Q = np.array([rq * math.cos(psiQ), rq * math.sin(psiQ)])
        # outward flank normal at the tangent point = gradient of (polar angle - psi(radius))
        h = 1e-9

        def F(px, py):
            return math.atan2(py, px) - float(self.psi(math.hypot(px, py)))

        gx = (F(self.Q[0] + h, self.Q[1]) - F(self.Q[0] - h, self.Q[1])) / (2 * h)
        gy = (F(self.Q[0], self.Q[1] + h) - F(self.Q[0], self.Q[1] - h)) / (2 * h)
        self.n_fl = np.array([gx, gy]) / math.hypot(gx, gy)
        self.n_tip = self.Q / np.linalg.norm(self.Q)

    def psi(self, rq):
        rq = np.maximum(rq, self.rb0)
        return self.s0 / (2 * self.r0) + invf(self.a) - invf(np.arccos(self.rb0 / rq))

    def value(self, px, py):
        """< 0 inside the cutter's material."""
        rq = np.hypot(px, py)
        lam = np.arctan2(py, px)
        pa = 2 * math.pi / self.z0
        W = np.abs((lam - pa / 2) - pa * np.round((lam - pa / 2) / pa))
        sharp = np.minimum((self.psi(rq) - W) * rq, self.ra0 - rq)
        X, Y = rq * np.cos(W), rq * np.sin(W)
        dx, dy = X - self.Q[0], Y - self.Q[1]
        dq = np.hypot(dx, dy)
        in_sector = (self.n_tip[0] * dy - self.n_tip[1] * dx >= 0) & (dx * self.n_fl[1] - dy * self.n_fl[0] >= 0)
        return np.where(in_sector & (dq > self.rho), dq - self.rho, -sharp)


def ring_envelope_half_angle(g, R):
    """Half tooth angle at radius R of an internal gear cut by a consistent pinion cutter: the
    cutter's reference circle rolls on the ring's (centre distance r - r0), its tooth thickness is
    the ring's space width there (p - s), its tip reaches the ring's root circle r + (hf - x) m."""
    m, a, z, z0 = g.module, g.pressure_angle, g.z, g.cutter_teeth
    r, r0 = m * z / 2, m * z0 / 2
    s = m * (math.pi / 2 + 2 * g.x * math.tan(a)) - g.thinning
    rf = r + (g.hf - g.x) * m
    a0 = r - r0
    cut = PinionCutter(z0, m, a, math.pi * m - s, rf - a0, g.rho_f * m)

    def f(t, phi):
        phi0 = phi * z / z0  # same sense of rotation, pitch circles roll
        X, Y = R * np.cos(t + phi) - a0, R * np.sin(t + phi)
        c, s_ = np.cos(phi0), np.sin(phi0)
        return cut.value(c * X + s_ * Y, -s_ * X + c * Y)

    return _envelope_bisect(f, math.pi / z, 0.5, 8001)


# ---------------------------------------------------------------- two outlines in mesh
def _slice(g, teeth, ds):
    """Teeth -teeth..teeth of g's outline (tooth 0 centred on +x), as an open polyline."""
    one = g.tooth_outline(ds).points
    parts = []
    for j in range(-teeth, teeth + 1):
        c, s = math.cos(j * g.pitch_angle), math.sin(j * g.pitch_angle)
        parts.append((one if j == teeth else one[:-1]) @ np.array([[c, s], [-s, c]]))
    return np.vstack(parts)


def _place(P, angle, centre):
    c, s = math.cos(angle), math.sin(angle)
    return P @ np.array([[c, s], [-s, c]]) + np.asarray(centre)


def _inside(poly, pts):
    """Point in polygon (poly closed implicitly)."""
    return MplPath(poly).contains_points(pts)


def _dist_to_polyline(line, pts, k=6):
    """Distance of each point to the open polyline `line` (nearest segments found through the k
    nearest vertices; exact for a densely sampled smooth polyline)."""
    _, idx = cKDTree(line).query(pts, k=k)
    best = np.full(len(pts), np.inf)
    for i0 in (idx - 1, idx):
        i0 = np.clip(i0, 0, len(line) - 2)
        a, b = line[i0], line[i0 + 1]
        d = b - a
        q = pts[:, None, :] - a
        t = np.clip((q * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-300), 0, 1)
        dist = np.hypot(q[..., 0] - t * d[..., 0], q[..., 1] - t * d[..., 1]).min(axis=1)
        best = np.minimum(best, dist)
    return best


def _signed_gap(line_a, centre_a, pts, material_inside):
    """Signed distance of pts to body A (polyline line_a about centre_a): negative inside A's material."""
    d = _dist_to_polyline(line_a, pts)
    inside = _inside(np.vstack([line_a, centre_a]), pts)
    in_mat = inside if material_inside else ~inside
    return np.where(in_mat, -d, d)


def mesh_gap(pair, a, rot2=0.0, ds=None, zone=None, rot1=0.0):
    """Smallest signed normal gap [m] between the two generated outlines with centre distance a
    (negative = overlap). Gear 1 at the origin with a space on +x; gear 2 (external) at (a, 0)
    turned by pi so that its tooth 0 enters that space, or (internal) at (-a, 0) with its tooth 0
    on +x; rot1, rot2 turn the gears further about their own centres (CCW). Symmetric about the x
    axis for rot1 = rot2 = 0."""
    g1, g2 = pair.g1, pair.g2
    ds = ds if ds is not None else g1.module / 200
    zone = zone if zone is not None else 3 * g1.module
    L1 = _place(_slice(g1, 2, ds), math.pi / g1.z + rot1, (0, 0))
    if g2.internal:
        c2 = np.array([-a, 0.0])
        L2 = _place(_slice(g2, 2, ds), rot2, c2)
    else:
        c2 = np.array([a, 0.0])
        L2 = _place(_slice(g2, 2, ds), math.pi + rot2, c2)
    rp = a * g1.z / abs(g1.z + (-g2.z if g2.internal else g2.z))
    P = np.array([rp, 0.0])
    b1 = L1[np.hypot(*(L1 - P).T) < zone]
    b2 = L2[np.hypot(*(L2 - P).T) < zone]
    s21 = _signed_gap(L1, np.zeros(2), b2, True)
    s12 = _signed_gap(L2, c2, b1, not g2.internal)  # ring material lies outside its outline
    return float(min(s21.min(), s12.min()))


def iso_alpha_w(z1, z2s, x1, x2, a=A20):
    """inv(a_w) = inv(a) + 2 tan(a) (x1 + x2) / (z1 + z2), z2 < 0 for internal (ISO 21771)."""
    target = float(invf(a)) + 2 * math.tan(a) * (x1 + x2) / (z1 + z2s)
    return brentq(lambda t: math.tan(t) - t - target, 1e-6, math.radians(60), xtol=1e-15)


# ============================================================================ basic radii, pitch
@pytest.mark.parametrize("z,x", [(24, 0.0), (21, 0.0), (24, 0.3), (30, -0.25), (17, 0.5)])
def test_external_radii_closed_form(z, x):
    g = ext(z, x, ha=1.0, hf=1.25)
    m, a = M, A20
    assert g.r == pytest.approx(m * z / 2, rel=1e-14)
    assert g.rb == pytest.approx(m * z * math.cos(a) / 2, rel=1e-14)
    assert g.ra == pytest.approx(m * z / 2 + (1.0 + x) * m, rel=1e-14)
    assert g.rf == pytest.approx(m * z / 2 - (1.25 - x) * m, rel=1e-14)
    assert g.p == pytest.approx(math.pi * m, rel=1e-14)
    assert g.pb == pytest.approx(math.pi * m * math.cos(a), rel=1e-14)
    # base pitch = base circle circumference / z
    assert g.pb == pytest.approx(2 * math.pi * g.rb / z, rel=1e-14)
    assert g.pitch_angle == pytest.approx(2 * math.pi / z)


@pytest.mark.parametrize("x", [0.0, 0.1, -0.2])
def test_internal_radii_closed_form(x):
    """ISO 21771 with z < 0: d_a = d + 2 x m + 2 h_a m, d_f = d + 2 x m - 2 h_f m (signed d) -> for
    an internal gear |r_a| = r - (h_a + x) m, |r_f| = r + (h_f - x) m."""
    g = ring(66, x, ha=1.0, hf=1.25)
    r = M * 66 / 2
    assert g.r == pytest.approx(r)
    assert g.rb == pytest.approx(r * math.cos(A20))
    assert g.ra == pytest.approx(r - (1.0 + x) * M)
    assert g.rf == pytest.approx(r + (1.25 - x) * M)
    assert g.ra < g.r < g.rf
    assert g.pb == pytest.approx(math.pi * M * math.cos(A20))


@pytest.mark.parametrize("x,thin", [(0.0, 0.0), (0.3, 0.0), (-0.2, 4e-5), (0.5, 1e-4)])
def test_reference_thickness(x, thin):
    g = ext(24, x, thinning=thin)
    assert g.s == pytest.approx(M * (math.pi / 2 + 2 * x * math.tan(A20)) - thin, rel=1e-14)
    # measured on the generated outline at the reference circle
    left, right = tooth_half_angles_from_outline(g, g.r)
    assert g.r * (left - right) == pytest.approx(g.s, abs=2e-9)
    assert left == pytest.approx(-right, abs=1e-12)


# ============================================================================ thickness at radius
@pytest.mark.parametrize("kind,x,thin", [("ext", 0.0, 0.0), ("ext", 0.4, 0.0), ("ext", -0.3, 5e-5),
                                         ("int", 0.0, 0.0), ("int", 0.0, 6e-5)])
def test_thickness_at_radius_on_outline(kind, x, thin):
    """s_y = d_y (s/d + inv a - inv a_y) (external), d_y (s/d - inv a + inv a_y) (internal), checked
    against the angular width of the generated outline at several radii of the flank."""
    g = ext(24, x, thinning=thin) if kind == "ext" else ring(66, x, thinning=thin)
    lo, hi = sorted((g.r_form, g.ra))
    for R in np.linspace(lo, hi, 9)[1:-1]:
        expected = 2 * R * iso_half_angle(g.z, M, A20, x, thin, R, internal=g.internal)
        left, right = tooth_half_angles_from_outline(g, R)
        assert R * (left - right) == pytest.approx(expected, abs=2e-9), R
        assert float(g.thickness(R)) == pytest.approx(expected, abs=1e-9)
        assert float(g.half_angle(R)) == pytest.approx(expected / (2 * R), abs=1e-10)


def test_tip_thickness_and_thickness_range():
    g = ext(24, 0.3)
    ra = g.ra
    assert g.tip_thickness == pytest.approx(2 * ra * iso_half_angle(24, M, A20, 0.3, 0.0, ra), rel=1e-12)
    with pytest.raises(GeometryError):
        g.thickness(g.ra * 1.01)
    with pytest.raises(GeometryError):
        g.thickness(g.rf * 0.99)


# ============================================================================ base tangent length
@pytest.mark.parametrize("z,x,thin", [(24, 0.0, 0.0), (21, 0.0, 0.0), (35, 0.3, 0.0), (24, -0.2, 5e-5)])
def test_base_tangent_length(z, x, thin):
    g = ext(z, x, thinning=thin)
    k = g.base_tangent_span
    assert k == max(1, round(z * 20.0 / 180.0 + 0.5))
    a = A20
    # ISO 21771 closed form, thinning acts along the base tangent as thinning * cos(a)
    W_iso = M * math.cos(a) * (math.pi * (k - 0.5) + z * float(invf(a))) + 2 * x * M * math.sin(a) - thin * math.cos(a)
    assert g.base_tangent_length(k) == pytest.approx(W_iso, rel=1e-13)

    o = g.outline(ds=M / 200)
    # (1) involute start angles: every flank point (rho, theta) lies on the involute that leaves the
    # base circle at theta +- inv(a_y); W_k = r_b * (difference of the outer flanks' start angles)
    rr, th = polar(o.points)
    ay = np.arccos(np.clip(g.rb / rr, -1, 1))
    fl = o.kind == FLANK
    left = fl & (o.tooth == k - 1) & (o.side == 1)
    right = fl & (o.tooth == 0) & (o.side == -1)
    beta_l = np.unwrap(th[left] + invf(ay[left]))
    beta_r = th[right] - invf(ay[right])
    assert g.rb * np.ptp(beta_l) < 1e-9 and g.rb * np.ptp(beta_r) < 1e-9
    W_start = g.rb * (beta_l.mean() - beta_r.mean())
    assert W_start == pytest.approx(W_iso, abs=1e-9)
    # (2) caliper: two parallel jaws normal to the span's symmetry line
    phic = (k - 1) * math.pi / z
    n = np.array([-math.sin(phic), math.cos(phic)])
    span = (o.tooth >= 0) & (o.tooth <= k - 1) & (rr >= g.r_form)  # the jaws reach into the spaces
    proj = o.points[span] @ n
    W_cal = proj.max() - proj.min()
    assert W_cal == pytest.approx(W_iso, abs=5e-9)  # vertices of a 10 um polyline: ~1 nm per jaw
    assert o.kind[span][np.argmax(proj)] == FLANK and o.kind[span][np.argmin(proj)] == FLANK
    # the caliper touches at r = sqrt(rb^2 + (W/2)^2), which must lie on the involute part
    assert g.r_form < math.hypot(g.rb, W_iso / 2) < g.ra


def test_base_tangent_length_errors():
    with pytest.raises(GeometryError):
        ring().base_tangent_length(3)
    with pytest.raises(GeometryError):
        ext(24).base_tangent_length(0)
    with pytest.raises(GeometryError):
        ext(24).base_tangent_length(24)


# ============================================================================ outline structure
@pytest.mark.parametrize("which", ["ext24", "ext21s", "ring66"])
def test_outline_closed_ccw_simple(which):
    g = {"ext24": lambda: ext(24), "ext21s": lambda: ext(21, 0.4, thinning=3e-5), "ring66": lambda: ring(66)}[which]()
    ds = g.module / 4
    o = g.outline(ds=ds)
    P = o.points
    assert len(o) == len(P) == len(o.tooth) == len(o.kind) == len(o.side)
    # closed polygon whose last point is not repeated; spacing at most ds (also across the seam)
    steps = np.hypot(*(np.roll(P, -1, axis=0) - P).T)
    assert steps.max() <= ds * (1 + 1e-9)
    assert steps.min() > 0
    # CCW about the gear centre: positive signed area, polar angle increases monotonically
    assert signed_area(P) > 0
    _, th = polar(P)
    dth = np.diff(np.unwrap(th))
    assert np.all(dth >= -1e-12)
    assert np.unwrap(th)[-1] - np.unwrap(th)[0] == pytest.approx(2 * math.pi, abs=2 * math.pi / g.z)
    assert seg_self_intersections(P) == 0
    # a fine single tooth, closed through the gear centre, has no self-intersection either
    one = g.tooth_outline(g.module / 100).points
    assert seg_self_intersections(np.vstack([one, [[0.0, 0.0]]])) == 0


@pytest.mark.parametrize("ds", [None, M / 1000])
def test_outline_spacing_at_most_ds(ds):
    g = ext(24)
    o = g.outline(ds)
    steps = np.hypot(*(np.roll(o.points, -1, axis=0) - o.points).T)
    assert steps.max() <= (ds or g.module / 100) * (1 + 1e-9)


@pytest.mark.parametrize("internal", [False, True])
def test_outline_labels(internal):
    g = ring(66) if internal else ext(24, 0.2)
    o = g.outline(ds=g.module / 50)
    rr, th = polar(o.points)
    for k in (0, 1, g.z // 2, g.z - 1):
        sel = o.tooth == k
        kinds = o.kind[sel]
        # per tooth, CCW: root, fillet, flank, tip, flank, fillet, root
        runs = [kinds[0]] + [b for a_, b in zip(kinds[:-1], kinds[1:]) if b != a_]
        assert runs == [ROOT, FILLET, FLANK, TIP, FLANK, FILLET, ROOT]
        tip = sel & (o.kind == TIP)
        centre = 2 * math.pi * k / g.z
        rel = np.angle(np.exp(1j * (th[sel] - centre)))
        # tooth k spans [-pi/z, pi/z] about its centre line
        assert np.all(np.abs(rel) <= math.pi / g.z + 1e-9)
        # side +1 at positive polar angle from the centre line, -1 at negative
        s = o.side[sel]
        assert np.all(rel[s == 1] >= -1e-12) and np.all(rel[s == -1] <= 1e-12)
        # tip points at the tip circle and symmetric about the centre line
        assert np.allclose(rr[tip], g.ra, rtol=0, atol=1e-12)
        assert np.mean(rel[o.kind[sel] == TIP]) == pytest.approx(0.0, abs=1e-3 / g.z)
        assert np.allclose(rr[sel & (o.kind == ROOT)], g.rf, rtol=0, atol=1e-12)


def test_outline_tooth_outline_consistency():
    g = ext(24, 0.1)
    one = g.tooth_outline(M / 50)
    P = one.points
    assert polar(P[:1])[1][0] == pytest.approx(-math.pi / 24, abs=1e-12)
    assert polar(P[-1:])[1][0] == pytest.approx(math.pi / 24, abs=1e-12)
    # mirror symmetric about the tooth centre line
    mirrored = P[::-1] * np.array([1, -1])
    assert np.allclose(mirrored, P, atol=1e-12)
    whole = g.outline(M / 50)
    assert len(whole) == 24 * (len(one) - 1)
    with pytest.raises(GeometryError):
        g.tooth_outline(ds=0.0)


# ============================================================================ involute and fillet
@pytest.mark.parametrize("kind,x,thin", [("ext", 0.0, 0.0), ("ext", 0.35, 2e-5), ("ext", -0.3, 0.0),
                                         ("int", 0.0, 0.0)])
def test_flank_points_on_exact_involute(kind, x, thin):
    """Distance of every FLANK point from the parametric involute
    P(tau) = r_b [cos(b0 - tau) + tau sin(b0 - tau), sin(b0 - tau) - tau cos(b0 - tau)] < 1e-7 m."""
    g = ext(24, x, thinning=thin) if kind == "ext" else ring(66, x, thinning=thin)
    o = g.tooth_outline(g.module / 100)
    s = M * (math.pi / 2 + 2 * x * math.tan(A20)) - thin
    for side in (1, -1):
        pts = o.points[(o.kind == FLANK) & (o.side == side)] * np.array([1, side])  # mirror right flank
        rr = np.hypot(pts[:, 0], pts[:, 1])
        tau = np.sqrt(np.maximum(rr**2 / g.rb**2 - 1, 0))
        if g.internal:
            b0 = s / (2 * g.r) - float(invf(A20))
            ang = b0 + tau - np.arctan(tau)
        else:
            b0 = s / (2 * g.r) + float(invf(A20))
            ang = b0 - tau + np.arctan(tau)
        # P(tau) in closed form (same for both unwinding senses up to the sign of tau)
        sg = 1 if g.internal else -1
        px = g.rb * (np.cos(b0 + sg * tau) + sg * tau * np.sin(b0 + sg * tau))
        py = g.rb * (np.sin(b0 + sg * tau) - sg * tau * np.cos(b0 + sg * tau))
        assert np.allclose(np.arctan2(py, px), ang, atol=1e-12)
        dist = np.hypot(pts[:, 0] - px, pts[:, 1] - py)
        assert dist.max() < 1e-7
        assert len(pts) > 20


@pytest.mark.parametrize("z,x,thin", [(24, 0.0, 0.0), (24, 0.3, 0.0), (40, -0.2, 3e-5), (21, 0.0, 0.0)])
def test_rack_fillet_matches_bruteforce_envelope(z, x, thin):
    """The generated root (rack tip rounding trochoid) agrees with a brute-force envelope of the
    rolling rounded rack to 0.01 um at radii across the fillet."""
    g = ext(z, x, thinning=thin)
    for R in np.linspace(g.rf + 0.03 * M, g.r_form, 5):
        e = rack_envelope_half_angle(g, R)
        assert float(g.half_angle(R)) * R == pytest.approx(e * R, abs=1e-8), R
        left, right = tooth_half_angles_from_outline(g, R, ds=M / 1000)
        assert left * R == pytest.approx(e * R, abs=1e-8)
        assert -right * R == pytest.approx(e * R, abs=1e-8)


@pytest.mark.parametrize("z,x", [(24, 0.0), (24, 0.3), (24, -0.3), (40, 0.5), (21, 0.0)])
def test_form_radius_iso(z, x):
    """d_Ff = sqrt(d_b^2 + (d sin a - 2 (h_aP0 - x m)/sin a)^2), h_aP0 = (h_f - rho_f (1 - sin a)) m."""
    g = ext(z, x)
    haP0 = (1.25 - 0.38 * (1 - math.sin(A20))) * M
    dFf = math.sqrt((M * z * math.cos(A20)) ** 2 + (M * z * math.sin(A20) - 2 * (haP0 - x * M) / math.sin(A20)) ** 2)
    assert g.r_form == pytest.approx(dFf / 2, abs=1e-9)
    # the first flank point of the outline sits at the form radius, the last fillet point as well
    ds = M / 100
    o = g.tooth_outline(ds)
    rr, _ = polar(o.points)
    assert rr[o.kind == FILLET].max() == pytest.approx(dFf / 2, abs=1e-9)
    assert dFf / 2 < rr[o.kind == FLANK].min() < dFf / 2 + 2 * ds  # (see test_outline_spacing_at_most_ds)
    assert g.r_form > g.rb


def _junction_check(g):
    """Check, on tooth 0's left side, that the last fillet point lies on the exact involute (ISO
    closed form) at the form radius and that the outline's tangents on both sides of it agree with
    the involute's tangent there (which makes the angle a_y with the radius vector, because the
    involute's normal is the base-circle tangent)."""
    ds = g.module / 2000
    o = g.tooth_outline(ds)
    sel = o.side == 1
    P, K = o.points[sel][::-1], o.kind[sel][::-1]  # left side from the space centre towards the tip
    j = int(np.nonzero(K == FILLET)[0][-1])
    i = int(np.nonzero(K == FLANK)[0][0])
    assert i == j + 1
    pf = P[j]
    R = math.hypot(*pf)
    assert R == pytest.approx(g.r_form, abs=1e-9)
    th = math.atan2(pf[1], pf[0])
    psi = float(iso_half_angle(g.z, g.module, g.pressure_angle, g.x, g.thinning, R, internal=g.internal))
    assert R * abs(th - psi) < 1e-8, f"fillet end off the involute by {R * (th - psi) * 1e6:.3f} um"
    ay = math.acos(g.rb / R)
    rhat = pf / R
    for v in (P[j] - P[j - 3], P[i + 3] - P[j]):
        v = v / np.linalg.norm(v)
        assert math.degrees(abs(math.acos(abs(float(v @ rhat))) - ay)) < 0.3


@pytest.mark.parametrize("which", ["ext24", "ext24x", "ext40n", "ring66", "ring66t"])
def test_fillet_meets_involute_tangentially(which):
    g = {"ext24": lambda: ext(24), "ext24x": lambda: ext(24, 0.3), "ext40n": lambda: ext(40, -0.2, thinning=3e-5),
         "ring66": lambda: ring(66), "ring66t": lambda: ring(66, thinning=5e-5)}[which]()
    _junction_check(g)


@pytest.mark.parametrize("x", [0.1, -0.1])
def test_internal_shifted_fillet_meets_involute(x):
    _junction_check(ring(66, x))


@pytest.mark.parametrize("x,thin,z0", [(0.0, 0.0, 18), (0.0, 5e-5, 24)])
def test_ring_fillet_matches_bruteforce_pinion_cutter(x, thin, z0):
    g = ring(66, x, thinning=thin, cutter_teeth=z0)
    for R in np.linspace(g.rf - 0.03 * M, g.r_form, 4):
        e = ring_envelope_half_angle(g, R)
        assert float(g.half_angle(R)) * R == pytest.approx(e * R, abs=1e-8), R


def test_ring_shifted_fillet_matches_bruteforce_pinion_cutter():
    g = ring(66, 0.1)
    for R in np.linspace(g.rf - 0.03 * M, g.r_form, 3)[:-1]:
        e = ring_envelope_half_angle(g, R)
        assert float(g.half_angle(R)) * R == pytest.approx(e * R, abs=1e-8), R


@pytest.mark.parametrize("x", [0.2, 0.3])
def test_ring_positive_shift_can_be_generated(x):
    # a consistent cutter (thickness p - s, tip radius r0 + (hf - x) m, rolling at r - r0) has room
    # for the 0.25 m rounding: the independent construction succeeds
    m = M
    s = m * (math.pi / 2 + 2 * x * math.tan(A20))
    PinionCutter(18, m, A20, math.pi * m - s, 18 * m / 2 + (1.25 - x) * m, 0.25 * m)
    g = ring(66, x)
    assert g.rf > g.r_form > g.ra


@pytest.mark.parametrize("z,x", [(24, 0.0), (24, 0.3), (40, -0.2)])
def test_fillet_reaches_root_and_curvature(z, x):
    g = ext(z, x)
    rho = g.rho_f * g.module
    ds = g.module / 400
    o = g.tooth_outline(ds)
    rr, _ = polar(o.points)
    assert rr.min() == pytest.approx(g.rf, abs=1e-12)
    assert np.allclose(rr[o.kind == ROOT], g.rf, rtol=0, atol=1e-12)
    left = o.side == 1
    P, K = o.points[left][::-1], o.kind[left][::-1]  # space centre -> tip
    j = int(np.nonzero(K == FILLET)[0][0])
    assert K[j - 1] == ROOT and np.hypot(*(P[j] - P[j - 1])) <= ds * (1 + 1e-9)
    fil = P[K == FILLET]
    assert g.rf < np.hypot(*fil.T).min() < g.rf + ds
    # radius of curvature of the trochoid envelope >= tool tip radius (circumcircles of triples)
    k = 5
    p0, p1, p2 = fil[:-2 * k], fil[k:-k], fil[2 * k:]
    a_ = np.hypot(*(p1 - p0).T)
    b_ = np.hypot(*(p2 - p1).T)
    c_ = np.hypot(*(p2 - p0).T)
    cr = np.abs((p1 - p0)[:, 0] * (p2 - p0)[:, 1] - (p1 - p0)[:, 1] * (p2 - p0)[:, 0])
    Rc = a_ * b_ * c_ / (2 * cr)
    assert Rc.min() >= rho * (1 - 1e-3)
    # and the fillet is concave towards the space (material on the inner side): it turns the
    # same way all along
    crs = (p1 - p0)[:, 0] * (p2 - p1)[:, 1] - (p1 - p0)[:, 1] * (p2 - p1)[:, 0]
    assert np.all(crs > 0) or np.all(crs < 0)


@pytest.mark.parametrize("z,x", [(24, 0.0), (24, 0.3), (30, 0.0)])
def test_fillet_outside_extended_involute(z, x):
    """No undercut: between the base circle and the form radius the tooth is thicker than the
    involute extended below the form radius."""
    g = ext(z, x)
    assert not g.undercut
    lo = max(g.rb, g.rf)
    for R in np.linspace(lo, g.r_form, 7)[:-1]:
        left, right = tooth_half_angles_from_outline(g, R, ds=M / 400)
        inv_half = iso_half_angle(z, M, A20, x, 0.0, R)
        assert left >= inv_half - 1e-12 and -right >= inv_half - 1e-12


# ============================================================================ undercut
@pytest.mark.parametrize("z,x,expected", [(12, 0.0, True), (24, 0.0, False), (14, 0.0, True), (12, 0.5, False),
                                          (21, 0.0, False), (17, 0.0, True), (17, 0.02, False)])
def test_undercut_flag(z, x, expected):
    # no undercut while the end of the rack's straight flank (h_aP0 - x m below the reference line)
    # stays outside the interference point: x >= h_aP0* - z sin^2(a) / 2
    haP0 = 1.25 - 0.38 * (1 - math.sin(A20))
    assert (x < haP0 - z * math.sin(A20) ** 2 / 2) == expected
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = ext(z, x)
    assert g.undercut is expected
    assert ring(66).undercut is False


def test_undercut_outline_not_thicker_than_generated():
    g = ext(12, 0.0)
    assert g.undercut
    for R in np.linspace(g.rb, g.r_form, 6)[1:]:
        e = rack_envelope_half_angle(g, R)
        assert float(g.half_angle(R)) * R <= e * R + 1e-8, R


# ============================================================================ pair: ISO formulas
@pytest.mark.parametrize("z1,z2,x1,x2,internal", [(24, 21, 0.0, 0.0, False), (24, 21, 0.3, -0.1, False),
                                                  (17, 40, 0.5, 0.2, False), (21, 66, 0.0, 0.0, True),
                                                  (21, 66, 0.3, 0.0, True), (21, 66, 0.2, -0.2, True)])
def test_pair_alpha_w_and_centre_distance_iso(z1, z2, x1, x2, internal):
    g1 = ext(z1, x1)
    g2 = ring(z2, x2) if internal else ext(z2, x2)
    pair = GearPair(g1, g2)
    z2s = -z2 if internal else z2
    aw = iso_alpha_w(z1, z2s, x1, x2)
    assert pair.alpha_w == pytest.approx(aw, abs=1e-12)
    a_w = abs((z1 + z2s) * M * math.cos(A20) / (2 * math.cos(aw)))
    assert pair.centre_distance == pytest.approx(a_w, rel=1e-12)
    # and the identity a_w cos(a_w) = |r_b2 +- r_b1|
    assert pair.centre_distance * math.cos(pair.alpha_w) == pytest.approx(abs(g2.rb + (-1 if internal else 1) * g1.rb), rel=1e-12)
    assert pair.ratio == pytest.approx(z2 / z1)
    if x1 == x2 == 0:
        assert pair.centre_distance == pytest.approx(45e-3 if z1 + z2 in (45, 87) else 0, rel=1e-12)


def test_inv_inverse():
    for a in np.radians([0.5, 5, 14.5, 20, 25, 31, 40, 55]):
        assert inv_inverse(float(invf(a))) == pytest.approx(a, abs=1e-13)
    assert inv_inverse(0.0) == 0.0
    with pytest.raises(ValueError):
        inv_inverse(-1e-3)


@pytest.mark.parametrize("z1,z2,x1,x2,internal", [(24, 21, 0.0, 0.0, False), (24, 21, 0.3, -0.1, False),
                                                  (21, 66, 0.0, 0.0, True), (21, 66, 0.3, 0.0, True)])
def test_zero_backlash_at_centre_distance(z1, z2, x1, x2, internal):
    """Two generated outlines placed at pair.centre_distance touch on both flanks (zero backlash):
    the symmetric placement has a zero gap, turning gear 2 either way makes them overlap, and the
    gap grows as sin(a_w) times the centre distance change (the working pressure angle)."""
    g1 = ext(z1, x1, name="p")
    g2 = ring(z2, x2, name="r") if internal else ext(z2, x2, name="w")
    pair = GearPair(g1, g2)
    a = pair.centre_distance
    gap0 = mesh_gap(pair, a)
    assert abs(gap0) < 1e-6
    assert abs(gap0) < 5e-8  # in fact to the discretisation of the outlines
    d = 1e-6 / g2.rb
    assert mesh_gap(pair, a, rot2=+d) < -0.5e-6 * math.cos(0.5)
    assert mesh_gap(pair, a, rot2=-d) < -0.5e-6 * math.cos(0.5)
    da = 20e-6 * (-1 if internal else 1)  # open the mesh by 20 um
    gap1 = mesh_gap(pair, a + da)
    slope = (gap1 - gap0) / abs(da)
    assert slope == pytest.approx(math.sin(pair.alpha_w), rel=0.01)
    a_zero = a - (gap0 / slope) * (1 if not internal else -1)
    assert a_zero == pytest.approx(a, abs=3e-7)


@pytest.mark.parametrize("internal", [False, True])
def test_backlash_from_thinning(internal):
    """With thinnings t1, t2 the normal backlash is (t1 + t2) cos(a) and the circumferential backlash
    on the working pitch circle t1 r_w1/r_1 + t2 r_w2/r_2 (involutes: exact, not only first order)."""
    t1, t2 = 20e-6, 30e-6
    g1 = ext(21, 0.3, thinning=t1)
    # (ring addendum 0.9 m: with 1.0 m its tip corner reaches the pinion's fillet, see
    # test_reference_planet_ring_fillet_interference, and would limit the gap instead of the flanks)
    g2 = ring(66, 0.0, thinning=t2, ha=0.9) if internal else ext(24, -0.1, thinning=t2)
    pair = GearPair(g1, g2)
    assert pair.check() == []
    a = pair.centre_distance
    # thinning is a tolerance: it does not change the centre distance
    assert a == pytest.approx(GearPair(ext(21, 0.3), ring(66, ha=0.9) if internal else ext(24, -0.1)).centre_distance)
    gap = mesh_gap(pair, a)
    jn = (t1 + t2) * math.cos(A20)
    assert 2 * gap == pytest.approx(jn, abs=1e-7)
    # rotate gear 2 until one flank closes: half of the circumferential backlash
    # the gap closes linearly with the rotation of gear 2 (the flank moves by r_b2 * angle along the
    # line of action); find the closing angle from two measured points and verify it
    f1, f2 = 0.5 * gap / g2.rb, 0.9 * gap / g2.rb
    m1, m2 = mesh_gap(pair, a, rot2=f1), mesh_gap(pair, a, rot2=f2)
    phi = f1 - m1 * (f2 - f1) / (m2 - m1)
    assert abs(mesh_gap(pair, a, rot2=phi)) < 2e-8
    zs = -g2.z if internal else g2.z
    rw1 = a * g1.z / abs(g1.z + zs)
    rw2 = a * g2.z / abs(g1.z + zs)
    jt = 2 * phi * rw2
    assert jt == pytest.approx(t1 * rw1 / g1.r + t2 * rw2 / g2.r, rel=0.01)
    assert jt == pytest.approx(jn / math.cos(pair.alpha_w), rel=0.01)


def _rolling_gaps(pair, n=15):
    g1, g2 = pair.g1, pair.g2
    sense = 1.0 if g2.internal else -1.0  # internal gears turn in the same sense as the pinion
    out = []
    for th1 in np.linspace(-0.5, 0.5, n) * g1.pitch_angle:
        out.append(mesh_gap(pair, pair.centre_distance, rot1=th1, rot2=sense * th1 * g1.z / g2.z))
    return np.array(out)


@pytest.mark.parametrize("which", ["24/21", "24/21 shifted", "21/66 shifted, ring ha 0.9"])
def test_conjugate_rolling_without_backlash_or_overlap(which):
    """Roll the two generated outlines through one pitch at the working centre distance (angles in
    the ratio z2 / z1): the flanks stay in contact (gap 0) without any overlap anywhere."""
    pair = {"24/21": lambda: GearPair(ext(24), ext(21)),
            "24/21 shifted": lambda: GearPair(ext(24, 0.3), ext(21, -0.1)),
            "21/66 shifted, ring ha 0.9": lambda: GearPair(ext(21, 0.3), ring(66, ha=0.9))}[which]()
    assert pair.check() == []
    gaps = _rolling_gaps(pair)
    assert np.abs(gaps).max() < 5e-8


def test_reference_planet_ring_fillet_interference():
    """The paper's planet-ring mesh (21/66, x = 0, ring h_a = 1.0 m, planet cut by the 0.38 m
    rack) is not free of interference: the ring's tip reaches below the planet's form radius
    (19.738 mm < 19.779 mm, ISO closed forms) and, rolling the generated outlines, the ring's tip
    corner cuts into the planet's fillet. check() must at least report it."""
    pair = GearPair(ext(21, name="planet"), ring(66, name="ring"))
    notes = pair.check()
    assert any("planet" in n and "fillet" in n for n in notes)
    gaps = _rolling_gaps(pair, n=21)
    assert gaps.min() < -10e-6  # ~22 um overlap at some mesh positions
    assert gaps.max() < 5e-8


# ============================================================================ contact ratio
def _line_of_action_path(pair):
    """Length of the path of contact from a geometric construction: the common tangent of the base
    circles through the pitch region, clipped by the tip circles (inside both tips for an external
    pair; inside the pinion tip and outside the ring tip for an internal pair)."""
    g1, g2, a = pair.g1, pair.g2, pair.centre_distance
    O1 = np.zeros(2)
    O2 = np.array([-a, 0.0]) if g2.internal else np.array([a, 0.0])
    # line {p : n.p = c}: distance rb1 from O1, rb2 from O2 (opposite sides for an external pair,
    # same side for an internal pair)
    sgn = 1.0 if g2.internal else -1.0

    def res(gam):
        n = np.array([math.cos(gam), math.sin(gam)])
        c = -g1.rb  # n.O1 - c = rb1
        return n @ O2 - c - sgn * g2.rb

    gam = brentq(res, 1e-6, math.pi - 1e-6)
    n = np.array([math.cos(gam), math.sin(gam)])
    c = -g1.rb
    t = np.array([-n[1], n[0]])
    base = c * n

    def chord(O, R):
        s0 = (O - base) @ t
        h2 = R * R - np.sum((base + s0 * t - O) ** 2)
        h = math.sqrt(h2)
        return s0 - h, s0 + h

    lo1, hi1 = chord(O1, g1.ra)
    lo2, hi2 = chord(O2, g2.ra)
    # pitch point (on the line of centres)
    sP = (np.array([pair.centre_distance * g1.z / abs(g1.z + (-g2.z if g2.internal else g2.z)), 0.0]) - base) @ t
    if not g2.internal:
        lo, hi = max(lo1, lo2), min(hi1, hi2)
    elif sP >= hi2:  # internal: part of [lo1, hi1] outside (lo2, hi2) that contains the pitch point
        lo, hi = max(lo1, hi2), hi1
    else:
        lo, hi = lo1, min(hi1, lo2)
    return hi - lo, sP, (lo, hi)


@pytest.mark.parametrize("internal,expected", [(False, 1.586), (True, 1.932)])
def test_contact_ratio_reference_pairs(internal, expected):
    pair = GearPair(ext(24 if not internal else 21), ring(66) if internal else ext(21))
    a, aw = A20, A20
    g1, g2 = pair.g1, pair.g2
    if internal:
        g = math.sqrt(g1.ra**2 - g1.rb**2) - math.sqrt(g2.ra**2 - g2.rb**2) + pair.centre_distance * math.sin(aw)
    else:
        g = math.sqrt(g1.ra**2 - g1.rb**2) + math.sqrt(g2.ra**2 - g2.rb**2) - pair.centre_distance * math.sin(aw)
    eps = g / (math.pi * M * math.cos(a))
    assert round(eps, 3) == expected
    assert pair.contact_ratio == pytest.approx(eps, rel=1e-12)
    L, _, _ = _line_of_action_path(pair)
    assert L / g1.pb == pytest.approx(eps, rel=1e-9)
    gf, ga = pair.path_of_contact
    assert gf + ga == pytest.approx(L, rel=1e-9)
    # lowest active point of the pinion flank (start of approach), from the construction:
    # the approach ends gf before the pitch point, i.e. rb1 tan(a_w) - gf from T1
    gf_own = L - (math.sqrt(g1.ra**2 - g1.rb**2) - g1.rb * math.tan(aw))
    r_low1 = math.hypot(g1.rb, g1.rb * math.tan(aw) - gf_own)
    haP0 = (1.25 - 0.38 * (1 - math.sin(A20))) * M
    r_form1 = math.hypot(g1.rb, g1.r * math.sin(A20) - haP0 / math.sin(A20))
    notes = pair.check()
    if internal:
        # 21/66: the ring tip reaches below the planet's form radius (19.738 mm < 19.779 mm):
        # a real fillet contact the check must report
        assert r_low1 < r_form1
        assert len(notes) == 1 and "fillet" in notes[0] and f"{r_low1 * 1e3:.4g}" in notes[0]
    else:
        assert r_low1 > r_form1
        assert notes == []


@pytest.mark.parametrize("z1,z2,x1,x2,internal", [(24, 21, 0.3, -0.1, False), (17, 40, 0.5, 0.2, False),
                                                  (21, 66, 0.3, 0.0, True)])
def test_contact_ratio_shifted_geometric(z1, z2, x1, x2, internal):
    g1 = ext(z1, x1)
    g2 = ring(z2, x2) if internal else ext(z2, x2)
    pair = GearPair(g1, g2)
    L, sP, (lo, hi) = _line_of_action_path(pair)
    assert pair.contact_ratio == pytest.approx(L / (math.pi * M * math.cos(A20)), rel=1e-9)
    # approach / recess split about the pitch point; recess ends at the pinion's tip circle
    assert lo < sP < hi
    gf, ga = pair.path_of_contact
    assert sorted((gf, ga)) == pytest.approx(sorted((sP - lo, hi - sP)), abs=1e-12)
    assert ga == pytest.approx(math.sqrt(g1.ra**2 - g1.rb**2) - g1.rb * math.tan(pair.alpha_w), rel=1e-12)


# ============================================================================ Hertz radius
@pytest.mark.parametrize("internal,R_mm,K", [(False, 3.831, 3.01e5), (True, 10.534, 4.99e5)])
def test_hertz_radius_reference(internal, R_mm, K):
    pair = GearPair(ext(21), ring(66)) if internal else GearPair(ext(24), ext(21))
    assert round(pair.hertz_radius * 1e3, 3) == R_mm
    z1, z2 = (21, 66) if internal else (24, 21)
    Rc = (M / 2) * z1 * z2 / ((z2 - z1) if internal else (z1 + z2)) * math.sin(A20)
    assert pair.hertz_radius == pytest.approx(Rc, rel=1e-12)
    E_star = 2.1e11 / (2 * (1 - 0.3**2))
    assert E_star == pytest.approx(1.1538e11, rel=1e-4)
    k_si = pair.hertz_stiffness(E_star)
    assert k_si == pytest.approx(4 / 3 * math.sqrt(Rc) * E_star, rel=1e-12)
    # N/m^1.5 -> N/mm^1.5
    assert k_si / 1000**1.5 == pytest.approx(K, rel=2e-3)


@pytest.mark.parametrize("internal", [False, True])
def test_hertz_radius_shifted_from_pitch_point(internal):
    """Radii of curvature of the flanks at the working pitch point: rho_i = sqrt(r_wi^2 - r_bi^2)."""
    g1 = ext(21, 0.3)
    g2 = ring(66, 0.0) if internal else ext(24, -0.1)
    pair = GearPair(g1, g2)
    a = pair.centre_distance
    zs = -g2.z if internal else g2.z
    rw1, rw2 = a * g1.z / abs(g1.z + zs), a * g2.z / abs(g1.z + zs)
    r1, r2 = math.sqrt(rw1**2 - g1.rb**2), math.sqrt(rw2**2 - g2.rb**2)
    R = r1 * r2 / (r2 - r1) if internal else r1 * r2 / (r1 + r2)
    assert pair.hertz_radius == pytest.approx(R, rel=1e-9)


# ============================================================================ mass properties
@pytest.mark.parametrize("internal", [False, True])
def test_mass_between_annuli(internal):
    rho_m, b = 7850.0, 0.02
    if internal:
        g = ring(66, face_width=b)
        Ro = RING_RIM / 2
        lo_m = rho_m * b * math.pi * (Ro**2 - g.rf**2)
        hi_m = rho_m * b * math.pi * (Ro**2 - g.ra**2)
        lo_j = rho_m * b * math.pi * (Ro**4 - g.rf**4) / 2
        hi_j = rho_m * b * math.pi * (Ro**4 - g.ra**4) / 2
    else:
        rbo = 0.01
        g = ext(24, face_width=b, bore_diameter=2 * rbo)
        lo_m = rho_m * b * math.pi * (g.rf**2 - rbo**2)
        hi_m = rho_m * b * math.pi * (g.ra**2 - rbo**2)
        lo_j = rho_m * b * math.pi * (g.rf**4 - rbo**4) / 2
        hi_j = rho_m * b * math.pi * (g.ra**4 - rbo**4) / 2
    mass, J = g.mass_properties(rho_m)
    assert lo_m < mass < hi_m
    assert lo_j < J < hi_j
    # independent: area of the toothed outline by the shoelace formula of this file
    P = g.outline(g.module / 20).points
    A_out = signed_area(P)
    A = (math.pi * RING_RIM**2 / 4 - A_out) if internal else (A_out - math.pi * 0.01**2)
    assert mass == pytest.approx(rho_m * b * A, rel=1e-9)
    # and the same area from the tooth thickness: teeth band = z * integral of s_y dr (substitution
    # r = r_root +- u^2 for the square-root behaviour of the fillet at the root circle)
    lo, hi = sorted((g.rf, g.ra))
    u = np.linspace(0, math.sqrt(hi - lo), 20001)
    if internal:
        band = g.z * np.trapezoid(g.thickness(g.rf - u**2) * 2 * u, u)
    else:
        band = g.z * np.trapezoid(g.thickness(g.rf + u**2) * 2 * u, u)
    if internal:
        A_th = math.pi * (RING_RIM**2 / 4 - g.rf**2) + band
    else:
        A_th = math.pi * (g.rf**2 - 0.01**2) + band
    fine_mass, _ = g.mass_properties(rho_m, ds=g.module / 400)
    assert fine_mass == pytest.approx(rho_m * b * A_th, rel=2e-6)


def test_inertia_tends_to_reference_annulus():
    rho_m, b = 7850.0, 0.01
    errs, zs = [], (40, 80, 160, 320)
    for z in zs:
        g = ext(z, face_width=b)
        _, J = g.mass_properties(rho_m, ds=g.module / 5)
        J_ref = rho_m * b * math.pi * g.r**4 / 2
        errs.append(abs(J / J_ref - 1))
    assert all(e2 < e1 for e1, e2 in zip(errs[:-1], errs[1:]))
    assert errs[-1] < 2e-3
    # O(1/z): z * error settles
    assert zs[-1] * errs[-1] == pytest.approx(zs[-2] * errs[-2], rel=0.1)


# ============================================================================ errors
def test_pointed_teeth():
    with pytest.raises(GeometryError, match=r"(?s)pinion.*pointed"):
        SpurGear(z=10, module=M, x=1.0, name="pinion")
    # nearly pointed (s_a < 0.2 m) warns; check with the closed form
    x = 0.7
    ra = M * 12 / 2 + (1 + x) * M
    sa = 2 * ra * iso_half_angle(12, M, A20, x, 0.0, ra)
    assert 0 < sa < 0.2 * M
    with pytest.warns(UserWarning, match="tip thickness"):
        SpurGear(z=12, module=M, x=x)


def test_size_errors():
    with pytest.raises(GeometryError, match="bore"):
        ext(24, bore_diameter=2 * (M * 12 - 1.25 * M) + 1e-4, name="sun")
    with pytest.raises(GeometryError, match="module"):
        SpurGear(z=24, module=-2e-3)
    with pytest.raises(GeometryError, match="module"):
        SpurGear(z=24, module=0.0)
    with pytest.raises(GeometryError, match="face_width"):
        ext(24, face_width=-0.01)
    with pytest.raises(GeometryError, match="thinning"):
        ext(24, thinning=-1e-6)
    with pytest.raises(GeometryError, match="bore"):
        ext(24, bore_diameter=-0.01)
    with pytest.raises(GeometryError):
        ext(24, ha=-1.0)
    with pytest.raises(GeometryError):
        ext(24, hf=0.0)
    with pytest.raises(GeometryError):
        ext(24, rho_f=-0.1)
    with pytest.raises(GeometryError):
        SpurGear(z=24.0, module=M)
    with pytest.raises(GeometryError):
        SpurGear(z=3, module=M)
    with pytest.raises(GeometryError):
        SpurGear(z=24, module=M, pressure_angle=math.radians(50))


def test_internal_gear_errors():
    rf = M * 66 / 2 + 1.25 * M
    with pytest.raises(GeometryError, match="rim_diameter"):
        ring(66, rim_diameter=2 * rf - 1e-4, name="ring")
    with pytest.raises(GeometryError, match="rim_diameter"):
        ring(66, rim_diameter=None)
    with pytest.raises(GeometryError, match="rim_diameter"):
        ring(66, rim_diameter=-0.1)
    with pytest.raises(GeometryError, match="cutter_teeth"):
        ring(66, cutter_teeth=63)
    with pytest.raises(GeometryError, match="cutter_teeth"):
        ring(66, cutter_teeth=5)


def test_pair_errors():
    with pytest.raises(GeometryError, match="modules differ"):
        GearPair(ext(24, name="a"), SpurGear(z=21, module=2.5e-3, name="b"))
    with pytest.raises(GeometryError, match="pressure angle"):
        GearPair(ext(24), SpurGear(z=21, module=M, pressure_angle=math.radians(25)))
    with pytest.raises(GeometryError, match="first gear must be external"):
        GearPair(ring(66), ext(21))
    with pytest.raises(GeometryError):
        GearPair(ext(62), ring(66))
    # contact ratio < 1: ha = 0.5 on both gears; ISO closed form says eps ~ 0.87
    g1, g2 = ext(24, ha=0.5), ext(21, ha=0.5)
    pair = GearPair(g1, g2)
    eps = (math.sqrt(g1.ra**2 - g1.rb**2) + math.sqrt(g2.ra**2 - g2.rb**2) - pair.centre_distance * math.sin(A20)) / g1.pb
    assert eps < 1
    assert pair.contact_ratio == pytest.approx(eps, rel=1e-12)
    with pytest.raises(GeometryError, match="contact ratio"):
        pair.check()


def test_pair_interference_small_gear_driven():
    """The 60-tooth gear's tip (approach, g2) reaches past the 12-tooth pinion's interference point
    T1 (distance r_b1 tan a_w from the pitch point): an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        small, big = ext(12, name="small"), ext(60, name="big")
    pair = GearPair(small, big)
    gf, _ = pair.path_of_contact
    T1 = small.rb * math.tan(pair.alpha_w)
    assert gf > T1
    assert math.sqrt(big.ra**2 - big.rb**2) - big.rb * math.tan(pair.alpha_w) > T1
    with pytest.raises(GeometryError, match="interference"):
        pair.check()


def test_pair_interference_checked_symmetrically():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        small, big = ext(12, name="small"), ext(60, name="big")
    pair = GearPair(big, small)
    _, ga = pair.path_of_contact
    assert ga > small.rb * math.tan(pair.alpha_w)  # big's tip passes small's interference point
    with pytest.raises(GeometryError, match="interference"):
        pair.check()
