"""Faults and errors in the gears layer: ISO 1328-1:2013 tolerances and random pitch sequences,
the crack start point, modified outlines (zero-size identity, closed forms), rigid tooth offsets,
the plane representation of partial face-width faults."""
import math
import warnings

import numpy as np
import pytest
from scipy import stats

from flexgear.config import load_config
from flexgear.errors import GeometryError
from flexgear.gears.faults import (LEFT, RIGHT, Chip, Crack, Eccentricity, GearErrors, Missing, PitchErrors,
                                   ProfileErrors, Spall, check_crack, crack_direction, crack_path, crack_start,
                                   iso1328_class, iso1328_round, iso1328_tolerances, pitch_deviation_measures,
                                   random_pitch_deviations, roll_length, roll_radius)
from flexgear.gears.geometry import FLANK, ROOT, TIP, SpurGear
from flexgear.gears.modified import (ToothOffset, gear_outline, partial_width_force, tooth_offsets,
                                     tooth_outline)


@pytest.fixture(scope="module")
def gears():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return dict(load_config("mercury_1a").gears)


def mid_flank(g, frac):
    lo, hi = sorted((g.r_form, g.ra))
    return lo + frac * (hi - lo)


def polyline_distance(poly, q):
    """Distance of points q (n, 2) to the polyline poly (m, 2)."""
    a, b = poly[:-1], poly[1:]
    ab = b - a
    out = np.empty(len(q))
    for i, p in enumerate(q):
        t = np.clip(((p - a) * ab).sum(1) / (ab * ab).sum(1), 0, 1)
        out[i] = np.min(np.hypot(*(a + t[:, None] * ab - p).T))
    return out


def area(p):
    x, y = p[:, 0], p[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


# ============================================================================================
# ISO 1328-1:2013
# ============================================================================================
def test_iso1328_tolerances_by_hand():
    # m_n = 2 mm, z = 24: d = 48 mm, sqrt(d) = 6.9282; class 5 (q = 1), Eqs. (5)-(9), rounding 5.2.3
    g = SpurGear(z=24, module=2e-3, name="g")
    t = iso1328_tolerances(g, 5)
    assert t.single_pitch == pytest.approx(6.0e-6)  # 0.048 + 0.8 + 5 = 5.848 -> 6.0
    assert t.cumulative_pitch == pytest.approx(17e-6)  # 0.096 + 3.8105 + 1.4 + 12 = 17.31 -> 17
    assert t.profile_slope == pytest.approx(4.8e-6)  # 0.8 + 0.048 + 4 = 4.848 -> 4.8
    assert t.profile_form == pytest.approx(6.0e-6)  # 1.1 + 5 = 6.1 -> 6.0
    assert t.profile_total == pytest.approx(8.0e-6)  # hypot(4.848, 6.1) = 7.792 -> 8.0
    t7 = iso1328_tolerances(g, 7)  # q = 2
    assert t7.single_pitch == pytest.approx(12e-6)  # 11.696 -> 12
    assert t7.cumulative_pitch == pytest.approx(35e-6)  # 34.61 -> 35
    t1 = iso1328_tolerances(g, 1)  # q = 1/4
    assert t1.single_pitch == pytest.approx(1.5e-6)  # 1.462 -> 1.5
    assert t1.cumulative_pitch == pytest.approx(4.3e-6)  # 4.327 -> 4.3


def test_iso1328_rounding_and_scope():
    assert iso1328_round(10.4) == 10.0 and iso1328_round(10.6) == 11.0
    assert iso1328_round(7.3) == 7.5 and iso1328_round(7.2) == 7.0
    assert iso1328_round(4.86) == 4.9 and iso1328_round(4.84) == 4.8
    with pytest.raises(GeometryError, match="outside the scope of ISO 1328-1:2013.*m_n = 0.3 mm"):
        iso1328_tolerances(SpurGear(z=30, module=0.3e-3, face_width=0.01, name="g"), 6)
    with pytest.raises(GeometryError, match="class 12"):
        iso1328_tolerances(SpurGear(z=30, module=2e-3, name="g"), 12)


@pytest.mark.parametrize("z,grade", [(24, 6), (21, 4), (66, 8), (97, 2), (12, 11)])
def test_random_pitch_sequences_meet_their_class(z, grade):
    """Over many seeds: every sequence closes, meets f_pT and F_pT of its class and not those of the
    next finer class; the binding ratio is uniform on (u0, 1]; the once-per-revolution phase is
    uniform; the deviations have no bias; a seed reproduces its sequence."""
    g = SpurGear(z=z, module=2e-3, name="g")
    tol = iso1328_tolerances(g, grade)
    finer = iso1328_tolerances(g, grade - 1) if grade > 1 else None
    ratios, phases, all_f = [], [], []
    for seed in range(400):
        f = random_pitch_deviations(g, grade, seed)
        assert len(f) == z and abs(f.sum()) < 1e-18
        fp, Fp = pitch_deviation_measures(f)
        assert fp <= tol.single_pitch * (1 + 1e-12) and Fp <= tol.cumulative_pitch * (1 + 1e-12)
        assert iso1328_class(g, f) == grade
        if finer is not None:
            assert fp > finer.single_pitch or Fp > finer.cumulative_pitch
        ratios.append(max(fp / tol.single_pitch, Fp / tol.cumulative_pitch))
        F = np.concatenate([[0.0], np.cumsum(f[:-1])])
        phases.append(np.angle(np.sum(F * np.exp(-2j * np.pi * np.arange(z) / z))))
        all_f.append(f)
    assert np.array_equal(random_pitch_deviations(g, grade, 7), random_pitch_deviations(g, grade, 7))
    assert not np.array_equal(random_pitch_deviations(g, grade, 7), random_pitch_deviations(g, grade, 8))
    u0 = (max(finer.single_pitch / tol.single_pitch, finer.cumulative_pitch / tol.cumulative_pitch)
          if finer else 1 / math.sqrt(2))
    assert stats.kstest((np.array(ratios) - u0) / (1 - u0), "uniform").pvalue > 1e-3
    assert stats.kstest((np.array(phases) + np.pi) / (2 * np.pi), "uniform").pvalue > 1e-3
    # no bias: the mean of each deviation over the seeds is within 4 standard errors of zero
    A = np.array(all_f)
    se = A.std(0) / math.sqrt(len(A))
    assert np.all(np.abs(A.mean(0)) < 4.5 * se + 1e-15)


def test_records_are_plain_and_equal_for_equal_data():
    import json

    from flexgear.gears.faults import Errors, PinError, fault_record as record

    a = Crack(gear="planet", planet=2, tooth=4, flank=RIGHT, depth=1e-3, angle=0.6)
    assert json.loads(json.dumps(record(a))) == record(a) == record(Crack(**{k: v for k, v in record(a).items()
                                                                             if k != "kind"}))
    assert record(a)["kind"] == "crack" and record(a) != record(Crack(gear="planet", planet=3, tooth=4, flank=RIGHT,
                                                                      depth=1e-3, angle=0.6))
    e = Errors(gears={"sun": GearErrors(pitch=PitchErrors(deviations=(1e-6, -1e-6)))}, pins={"planet1": PinError()})
    assert json.loads(json.dumps(record(e))) == record(e)
    assert record(e)["gears"]["sun"]["pitch"]["deviations"] == [1e-6, -1e-6]


def test_pitch_errors_index_and_angles():
    g = SpurGear(z=6, module=2e-3, name="g")
    p = PitchErrors(deviations=(1e-6, -2e-6, 0.0, 3e-6, -1e-6, -1e-6))
    F = np.array([0, 1, -1, -1, 2, 1]) * 1e-6
    assert np.allclose(p.index_deviations(), F - F.mean(), atol=1e-20)
    assert np.allclose(p.angles(g), (F - F.mean()) / g.r, atol=1e-20)
    assert pitch_deviation_measures(p.deviations) == pytest.approx((3e-6, 3e-6))


# ============================================================================================
# crack
# ============================================================================================
@pytest.mark.parametrize("name", ["sun", "planet", "ring"])
@pytest.mark.parametrize("flank", [LEFT, RIGHT])
def test_crack_starts_at_the_critical_section(gears, name, flank):
    """ISO 6336-3: the fillet point whose tangent makes 30 deg (internal gears 60 deg) with the
    tooth centre line; measured on the generated outline, independently of the search."""
    g = gears[name]
    p, r = crack_start(g, flank)
    o = g.tooth_outline(g.module / 2000)
    j = int(np.argmin(np.hypot(*(o.points - p).T)))
    assert polyline_distance(o.points[j - 5:j + 6], p[None])[0] < 1e-8  # on the outline
    assert min(g.rf, g.r_form) < r < max(g.rf, g.r_form)  # on the fillet
    assert np.sign(p[1]) == flank
    t = o.points[j + 3] - o.points[j - 3]
    angle = math.degrees(math.atan2(abs(t[1]), abs(t[0])))
    assert angle == pytest.approx(60.0 if g.internal else 30.0, abs=0.5)


@pytest.mark.parametrize("name", ["sun", "ring"])
def test_crack_direction_and_limits(gears, name):
    g = gears[name]
    c = Crack(gear=name, tooth=0, flank=LEFT, depth=0.8e-3, angle=math.radians(45))
    p0, p1 = crack_path(g, c)
    d = (p1 - p0) / np.hypot(*(p1 - p0))
    centre_line = np.array([1.0, 0.0]) if not g.internal else np.array([-1.0, 0.0])
    assert math.degrees(math.acos(abs(d @ centre_line))) == pytest.approx(45.0)
    assert d @ centre_line < 0  # towards the root
    assert d[1] < 0  # towards the centre line from the left flank
    assert np.allclose(crack_direction(g, Crack(gear=name, tooth=0, flank=RIGHT, depth=1e-3, angle=c.angle)),
                       d * [1, -1])
    check_crack(g, c)
    with pytest.raises(GeometryError, match="leaves the tooth|ligament|neighbouring"):
        check_crack(g, Crack(gear=name, tooth=0, flank=LEFT, depth=12e-3, angle=math.radians(80)))
    check_crack(g, Crack(gear=name, tooth=0, flank=LEFT, depth=0.0, angle=math.radians(80)))  # zero size


# ============================================================================================
# zero size: bit for bit
# ============================================================================================
ZERO = [
    lambda n, g: Spall(gear=n, tooth=2, flank=LEFT, start_radius=mid_flank(g, 0.3), end_radius=mid_flank(g, 0.6),
                       depth=0.0),
    lambda n, g: Spall(gear=n, tooth=2, flank=RIGHT, start_radius=mid_flank(g, 0.3), end_radius=mid_flank(g, 0.6),
                       depth=50e-6, width_fraction=0.0),
    lambda n, g: Chip(gear=n, tooth=2, flank=LEFT, profile_size=0.0, tip_size=0.0),
    lambda n, g: Missing(gear=n, tooth=2, height_fraction=1.0),
    lambda n, g: Crack(gear=n, tooth=2, flank=LEFT, depth=1e-3, angle=0.7),  # a crack leaves the outline
]


@pytest.mark.parametrize("name", ["sun", "planet", "ring"])
def test_zero_size_faults_and_errors_give_the_healthy_outline_bit_for_bit(gears, name):
    g = gears[name]
    healthy = g.tooth_outline(g.module / 100)
    zero_errors = GearErrors(eccentricity=Eccentricity(magnitude=0.0, phase=1.0),
                             pitch=PitchErrors(deviations=(0.0,) * g.z), profile=ProfileErrors())
    for make in ZERO:
        o = tooth_outline(g, 2, [make(name, g)], zero_errors)
        assert o.points.tobytes() == healthy.points.tobytes()
        assert o.kind.tobytes() == healthy.kind.tobytes() and o.side.tobytes() == healthy.side.tobytes()
        assert o.healthy and np.all(o.width == 1) and np.all(o.recess == 0)
        assert o.offset.null
    whole = gear_outline(g, [make(name, g) for make in ZERO[:1]], zero_errors)
    ref = g.outline()
    for a in ("points", "tooth", "kind", "side"):
        assert getattr(whole, a).tobytes() == getattr(ref, a).tobytes()


# ============================================================================================
# modified outlines: closed forms
# ============================================================================================
def flank_points(o, side):
    sel = (o.kind == FLANK) & (o.side == side)
    return o.points[sel]


@pytest.mark.parametrize("name", ["sun", "ring"])
def test_spall_is_sunk_by_its_depth_between_its_radii(gears, name):
    g = gears[name]
    r1, r2, h = mid_flank(g, 0.3), mid_flank(g, 0.6), 40e-6
    healthy = g.tooth_outline(g.module / 100)
    o = tooth_outline(g, 4, [Spall(gear=name, tooth=4, flank=LEFT, start_radius=r1, end_radius=r2, depth=h)])
    # right flank untouched
    assert np.array_equal(flank_points(o, RIGHT), flank_points(healthy, RIGHT))
    p = flank_points(o, LEFT)
    r = np.hypot(*p.T)
    inside = (r > r1 + 1e-9) & (r < r2 - 1e-9)
    ref = flank_points(healthy, LEFT)
    d = polyline_distance(ref, p[inside])
    assert np.allclose(d, h, rtol=2e-3)  # the normal depth
    # material removed: depth x flank arc length between the radii (parallel involutes)
    L = roll_length(g, np.array([r1, r2]))
    arc = abs(L[1] ** 2 - L[0] ** 2) / (2 * g.rb)  # involute arc length = L^2 / (2 r_b)
    removed = (area(healthy.points) - area(o.points)) * (-1 if g.internal else 1)
    assert removed == pytest.approx(h * arc, rel=0.02)
    assert np.count_nonzero(o.modified) >= np.count_nonzero(inside)


@pytest.mark.parametrize("name", ["planet", "ring"])
def test_profile_errors_follow_the_iso_definitions(gears, name):
    """The normal offset of the modified flank against the roll length: its least-squares line
    spans f_Halpha over the profile, the residual's range is f_falpha (ISO 1328-1 definitions);
    tip relief C_a at the tip, nothing at its start, a quarter of it half way (parabolic)."""
    g = gears[name]
    healthy = g.tooth_outline(g.module / 200)
    ref = flank_points(healthy, LEFT)
    LF, La = roll_length(g, g.r_form), roll_length(g, g.ra)
    prof = ProfileErrors(slope=6e-6, form=4e-6, form_waves=2)
    o = tooth_outline(g, 0, [], GearErrors(profile=prof), ds=g.module / 200)
    p = flank_points(o, LEFT)
    r = np.hypot(*p.T)
    # signed normal offset: the distance to the healthy flank, positive where the point lies outside
    # the healthy tooth (at a larger polar angle than the healthy left flank at its radius)
    outside = np.arctan2(p[:, 1], p[:, 0]) > g.half_angle(r)
    delta = np.where(outside, 1.0, -1.0) * polyline_distance(ref, p)
    x = (roll_length(g, r) - LF) / (La - LF)
    order = np.argsort(x)
    xu = np.linspace(0.0, 1.0, 401)  # evaluated against the roll length, as ISO 1328-1 plots a profile
    du = np.interp(xu, x[order], delta[order])
    coef = np.polyfit(xu, du, 1)
    assert coef[0] == pytest.approx(prof.slope, rel=0.02)  # the line spans f_Halpha over x in [0, 1]
    resid = du - np.polyval(coef, xu)
    assert resid.max() - resid.min() == pytest.approx(prof.form, rel=0.02)
    assert np.allclose(delta, prof.offset(g, r), atol=2e-8)
    # tip relief, parabolic, from the middle of the profile
    rs = float(roll_radius(g, (LF + 0.5 * (La - LF)) / g.rb))
    tr = ProfileErrors(tip_relief=20e-6, tip_relief_start=rs, relief_shape="parabolic")
    assert float(tr.offset(g, g.ra)) == pytest.approx(-20e-6)
    assert float(tr.offset(g, rs)) == pytest.approx(0.0, abs=1e-15)
    assert float(tr.offset(g, roll_radius(g, (LF + 0.75 * (La - LF)) / g.rb))) == pytest.approx(-5e-6)
    o = tooth_outline(g, 0, [], GearErrors(profile=tr), ds=g.module / 200)
    corner = flank_points(o, LEFT)
    rc = np.hypot(*corner.T)
    tip_pt = corner[np.argmin(np.abs(rc - g.ra))]
    assert math.atan2(tip_pt[1], tip_pt[0]) == pytest.approx(float(g.half_angle(g.ra)) - 20e-6 / g.rb, abs=1e-9)
    # the outline stays a simple closed sequence: the tip land still reaches the tip centre
    assert np.isclose(np.hypot(*o.points[(len(o) + 1) // 2 - 1]), g.ra)


@pytest.mark.parametrize("name", ["sun", "ring"])
def test_chip_cuts_the_corner_along_a_chord(gears, name):
    g = gears[name]
    a, t = 1.0e-3, 0.3e-3
    healthy = g.tooth_outline(g.module / 100)
    o = tooth_outline(g, 1, [Chip(gear=name, tooth=1, flank=RIGHT, profile_size=a, tip_size=t)])
    changed = o.modified
    chord = o.points[changed]
    # the chord is straight
    u = (chord[-1] - chord[0]) / np.hypot(*(chord[-1] - chord[0]))
    assert np.abs((chord - chord[0]) @ np.array([-u[1], u[0]])).max() < 1e-12
    # its ends lie on the healthy outline at arc lengths a and t from the tip corner
    n = (len(healthy) + 1) // 2
    half = healthy.points[:n]
    s = np.concatenate([[0], np.cumsum(np.hypot(*np.diff(half, axis=0).T))])
    corner = np.nonzero(healthy.kind[:n] == FLANK)[0][-1]
    for end, target in ((chord[0], s[corner] - a), (chord[-1], s[corner] + t)):
        j = int(np.argmin(np.hypot(*(half - end).T)))
        assert polyline_distance(half, end[None])[0] < 1e-9
        assert np.interp(target, s, np.arange(n)) == pytest.approx(j, abs=1.0)
    # the left half is untouched
    assert np.array_equal(o.points[-(n - 1):], healthy.points[n:])


@pytest.mark.parametrize("name", ["sun", "ring"])
@pytest.mark.parametrize("eta", [0.0, 0.4])
def test_missing_tooth_is_cut_at_its_height(gears, name, eta):
    g = gears[name]
    o = tooth_outline(g, 3, [Missing(gear=name, tooth=3, height_fraction=eta)])
    r = np.hypot(*o.points.T)
    rc = g.rf + eta * (g.ra - g.rf)
    far = r.max() if not g.internal else r.min()
    assert far == pytest.approx(rc, abs=1e-12)
    healthy = g.tooth_outline(g.module / 100)
    assert np.array_equal(o.points[0], healthy.points[0]) and np.array_equal(o.points[-1], healthy.points[-1])
    if eta == 0.0:
        assert np.allclose(r, g.rf, atol=1e-12) and np.all(o.kind == ROOT)
    else:
        assert np.all(o.kind[np.isclose(r, rc, atol=1e-12)] == TIP)


def test_partial_width_faults_and_the_slicing_closed_form(gears):
    """A spall over part of the face width keeps the outline and marks width / recess; the plane
    law with two slices equals the face-width integral of a per-width line load over the pit's
    step depth profile, and has the closed-form limits (width 1: healthy; below the recess: the
    healthy law times the remaining width)."""
    g = gears["sun"]
    r1, r2, h, w = mid_flank(g, 0.3), mid_flank(g, 0.6), 30e-6, 0.4
    healthy = g.tooth_outline(g.module / 100)
    o = tooth_outline(g, 0, [Spall(gear="sun", tooth=0, flank=LEFT, start_radius=r1, end_radius=r2, depth=h,
                                   width_fraction=w)])
    assert np.allclose(polyline_distance(healthy.points, o.points), 0.0, atol=1e-12)
    band = o.width < 1
    rb = np.hypot(*o.points[band].T)
    assert np.all((rb >= r1 - 1e-9) & (rb <= r2 + 1e-9)) and np.all(o.side[band] == LEFT)
    assert np.allclose(o.width[band], 1 - w) and np.allclose(o.recess[band], h)
    K, e = 2.38e9, 1.3
    d = np.linspace(0, 80e-6, 161)
    F = partial_width_force(d, K, e, 1 - w, h)
    y = (np.arange(20000) + 0.5) / 20000  # across the face width
    depth = np.where(y < w, h, 0.0)
    F_slices = np.array([K * np.mean(np.maximum(di - depth, 0.0) ** e) for di in d])
    assert np.allclose(F, F_slices, rtol=1e-9, atol=1e-9)
    below = d < h
    assert np.allclose(F[below], (1 - w) * K * d[below] ** e)
    assert np.array_equal(partial_width_force(d, K, e, 1.0, 0.0), K * d**e)


# ============================================================================================
# rigid offsets
# ============================================================================================
def test_pitch_errors_and_eccentricity_move_the_teeth(gears):
    g = gears["sun"]
    f = random_pitch_deviations(g, 8, 3)
    errs = GearErrors(pitch=PitchErrors(deviations=tuple(f)), eccentricity=Eccentricity(magnitude=20e-6, phase=0.5))
    offs = tooth_offsets(g, errs)
    F = np.concatenate([[0.0], np.cumsum(f[:-1])])
    assert np.allclose([o.angle for o in offs], (F - F.mean()) / g.r, atol=1e-18)
    assert np.allclose(offs[5].shift, 20e-6 * np.array([math.cos(0.5), math.sin(0.5)]))
    whole = gear_outline(g, (), errs)
    # the tip centre of each tooth sits at its moved centre line, shifted by the eccentricity
    for k in (0, 5, 17):
        sel = (whole.tooth == k) & (whole.kind == TIP)
        tips = whole.points[sel] - offs[k].shift
        miss = np.angle(np.exp(1j * (np.arctan2(tips[:, 1], tips[:, 0]) - k * g.pitch_angle - offs[k].angle)))
        assert np.min(np.abs(miss)) < 1e-12  # the tip centre sample sits on the moved centre line
        assert abs(offs[k].angle) > 1e-6
    d = ToothOffset(1e-4, (1e-6, 0.0)).displacement([g.r, 0.0])
    assert d == pytest.approx([1e-6 + g.r * (math.cos(1e-4) - 1), g.r * math.sin(1e-4)])
    # sectors: no tooth's points cross into its neighbour's
    ang = np.unwrap(np.arctan2(*(whole.points - offs[0].shift)[:, ::-1].T))
    assert np.all(np.diff(ang) > -1e-9)
