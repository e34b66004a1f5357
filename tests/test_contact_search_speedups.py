"""Checks of the shortcuts of the contact search (flexgear.dynamics.contact.search): the tabulated
corner flags against the outline's turning angle, the Lipschitz bound of the interpolated signed
distance on which the coarse scan's skipping rests, the skipping scan against the plain scan it
replaces, and the local search's walk handing its lookups to the refinement against the plain
walk and refinement."""
import math

import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.gears.sdf import CORNER_TURN
from flexgear.dynamics.contact.outline import PlacedOutline, outline_value, outline_value_polar
from flexgear.dynamics.contact.search import (LIPSCHITZ, LIPSCHITZ_MARGIN, MAX_CONTACTS, NO_TOOTH, UNKNOWN, HalfTooth,
                                              Probed, SearchJob, _coarse_scan, _finish, _min_scan, _refine_scan, _walk)
from flexgear.dynamics.contact.field import PlacedField, sdf_lookup
from flexgear.gears.contact_tables import corner_flags


@pytest.fixture(scope="module")
def tables():
    return build_model(load_config("mercury_1a")).tables  # sun, planet, ring


def _outline(t, g):
    return t.outlines[t.out_off[g]:t.out_off[g + 1]]


def _grid(t, g):
    nr, nphi = t.sdf_rows[g], t.sdf_columns[g]
    return t.sdf_grids[t.sdf_off[g]:t.sdf_off[g] + 3 * nr * nphi].reshape(1, 3, nr, nphi)


def _teeth(t, g):
    """Every tooth of gear g on its first table (the healthy gears of these tests)."""
    return np.zeros(int(t.gear_z[g]), np.int64)


def _angles(t, g):
    """No pitch errors."""
    return np.zeros(int(t.gear_z[g]))


def _placed_field(t, g, theta):
    """Gear g's signed-distance field placed at the origin, turned by theta [rad]."""
    return PlacedField(_grid(t, g), t.sdf_r0[g], t.sdf_dr[g], t.sdf_phi0[g], t.sdf_dphi[g], t.sdf_pitch[g],
                       bool(t.sdf_internal[g]), int(t.gear_z[g]), 0.0, 0.0, theta, float(t.gear_tip[g]), _teeth(t, g),
                       _angles(t, g))


def _placed_outline(t, g, x, y, both_sides):
    """Gear g's outline with its centre at (x, y) [m], not turned."""
    return PlacedOutline(_outline(t, g), t.out_corner[t.out_off[g]:t.out_off[g + 1]], int(t.out_nh[g]),
                         float(t.out_ds[g]), 0, float(t.sdf_pitch[g]), int(t.gear_z[g]), x, y, 0.0, both_sides)


def _band_distance(t, gx, gy):
    """Centre distance [m] at which gear gx's tooth band overlaps gear gy's (gy at the origin;
    outside an external gy, inside the ring)."""
    pts = _outline(t, gx)
    ry = t.sdf_r0[gy] + 0.5 * t.sdf_dr[gy] * (t.sdf_rows[gy] - 1)
    return ry + (-1 if t.sdf_internal[gy] else 1) * float(np.hypot(*pts[int(t.out_nh[gx]) - 1]))


def test_corner_flags_mark_the_samples_where_the_outline_turns_sharply(tables):
    for g in range(len(tables.gear_z)):
        pts = _outline(tables, g)
        u, w = np.diff(pts[:-1], axis=0), np.diff(pts[1:], axis=0)
        turn = np.abs(np.arctan2(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0], np.einsum("ij,ij->i", u, w)))
        flags = corner_flags(pts)
        assert not flags[0] and not flags[-1]
        assert np.array_equal(flags[1:-1], turn > CORNER_TURN)
        assert np.array_equal(tables.out_corner[tables.out_off[g]:tables.out_off[g + 1]], flags)
        # two tip corners per tooth outline (the tip land's ends) at least
        assert flags.sum() >= 2


def test_interpolated_signed_distance_obeys_the_lipschitz_bound(tables):
    rng = np.random.default_rng(1)
    for g in range(len(tables.gear_z)):
        t = tables
        grid = _grid(t, g)
        r0, dr = t.sdf_r0[g], t.sdf_dr[g]
        r1 = r0 + dr * (t.sdf_rows[g] - 1)
        field = PlacedField(grid, r0, dr, t.sdf_phi0[g], t.sdf_dphi[g], t.sdf_pitch[g], t.sdf_internal[g],
                            t.gear_z[g], 0.0, 0.0, 0.3, t.gear_tip[g], _teeth(t, g), _angles(t, g))
        worst = 0.0
        for _ in range(4000):
            r = rng.uniform(r0 + 1e-9, r1 - 1e-9)
            phi = rng.uniform(-math.pi, math.pi)
            step = rng.uniform(0.0, 5e-4)
            ang = rng.uniform(-math.pi, math.pi)
            p = (r * math.cos(phi), r * math.sin(phi))
            q = (p[0] + step * math.cos(ang), p[1] + step * math.sin(ang))
            if not r0 < math.hypot(*q) < r1:
                continue
            fp = sdf_lookup(field, *p)[0]
            fq = sdf_lookup(field, *q)[0]
            worst = max(worst, abs(fq - fp) / max(step, 1e-12))
            assert fq >= fp - LIPSCHITZ * step - LIPSCHITZ_MARGIN
        # the bound is not vacuous: the distance changes at about unit rate somewhere
        assert 0.8 < worst < LIPSCHITZ


def test_interpolated_signed_distance_is_bounded_by_the_tip_circle(tables):
    """The coarse scan's second bound: at radius r from a gear's centre the interpolated signed
    distance is at least r - ra (ra - r for the ring, whose material lies outside its tip
    circle) less a cell's diagonal and LIPSCHITZ_MARGIN, inside the tooth band and across it;
    and the bound is close (within a few cells) where the tips are."""
    rng = np.random.default_rng(4)
    t = tables
    for g in range(len(t.gear_z)):
        grid = _grid(t, g)
        r0, dr, dphi = t.sdf_r0[g], t.sdf_dr[g], t.sdf_dphi[g]
        r1 = r0 + dr * (t.sdf_rows[g] - 1)
        cell = dr + r1 * dphi
        ra, internal = float(t.gear_tip[g]), bool(t.sdf_internal[g])
        field = PlacedField(grid, r0, dr, t.sdf_phi0[g], t.sdf_dphi[g], t.sdf_pitch[g], internal, t.gear_z[g], 0.0,
                            0.0, 0.3, ra, _teeth(t, g), _angles(t, g))
        closest = np.inf
        for _ in range(20000):
            r = rng.uniform(r0 - 1e-4, r1 + 1e-4)
            phi = rng.uniform(-math.pi, math.pi)
            f = sdf_lookup(field, r * math.cos(phi), r * math.sin(phi))[0]
            bound = (ra - r if internal else r - ra) - cell
            assert f >= bound - LIPSCHITZ_MARGIN
            if bound > 0.0:
                closest = min(closest, f - bound)
        assert closest < 3 * cell


def test_skipping_coarse_scan_finds_what_the_plain_scan_finds_below_the_cap(tables):
    """Gear X (planet) turned about its centre against Y (sun or ring) at random angles: the
    skipping scan returns the plain scan's (value, sample) whenever the value is <= cap, and a
    value above cap otherwise."""
    rng = np.random.default_rng(2)
    t = tables
    gx = 1
    pts = _outline(t, gx)
    n = len(pts)
    nh = int(t.out_nh[gx])
    agree = above = 0
    for gy in (0, 2):
        # put the planet where its tooth band overlaps the other gear's band
        a_ = _band_distance(t, gx, gy)
        Y = _placed_field(t, gy, 0.0)
        for _ in range(300):
            X = _placed_outline(t, gx, a_ + rng.uniform(-3e-3, 3e-3), 0.0, True)
            # tooth 0 facing Y (toward the sun at the origin, away from the ring's centre), or not
            a = (math.pi if gy == 0 else 0.0) + rng.uniform(-0.6, 0.6)
            ca, sa = math.cos(a), math.sin(a)
            for lo, hi in ((0, nh - 1), (nh - 1, n - 1)):
                for stride in (8, 32):
                    cap = rng.choice([1e-5, 1.6e-4, 5e-4])
                    f0, j0, r0, p0 = _min_scan(lo, hi, stride, X, ca, sa, Y)
                    f1, j1, r1, p1 = _coarse_scan(lo, hi, stride, X, ca, sa, Y, cap)
                    if f0 <= cap:
                        # the same minimum, with the polar coordinates a fresh probe gives
                        assert (f1, j1, r1, p1) == (f0, j0, r0, p0)
                        assert (f0, r0, p0) == outline_value_polar(X, j0, ca, sa, Y)
                        agree += 1
                    else:
                        assert f1 > cap
                        above += 1
    assert agree > 20 and above > 20


def test_refinement_hands_finish_the_polar_coordinates_of_the_samples_it_probed(tables):
    """The full search's refinement returns, for its minimum and for the sample it starts
    from, the radius and polar angle about Y's centre of the two neighbours (and of the
    minimum) exactly where it probed them, equal to fresh probes; the minimum is the plain
    minimum over the samples it is to probe. Planet against sun and ring at random placements."""
    rng = np.random.default_rng(5)
    t = tables
    gx = 1
    pts = _outline(t, gx)
    n = len(pts)
    nh = int(t.out_nh[gx])
    checked = 0
    for gy in (0, 2):
        away = 1 if gy == 0 else -1
        a_ = _band_distance(t, gx, gy)
        Y = _placed_field(t, gy, rng.uniform(-0.1, 0.1))
        for _ in range(150):
            X = _placed_outline(t, gx, a_ + away * rng.uniform(-1e-3, 2e-3), rng.uniform(-1e-4, 1e-4), True)
            a = (math.pi if gy == 0 else 0.0) + rng.uniform(-0.3, 0.3)
            ca, sa = math.cos(a), math.sin(a)
            lo_h, hi_h = ((0, nh - 1), (nh - 1, n - 1))[int(rng.integers(2))]
            stride, sub = 32, 8
            jc = int(rng.integers(lo_h, hi_h + 1))
            s1, e1 = max(lo_h, jc - stride), min(lo_h + 10 * stride, jc + stride)
            lo, hi = max(lo_h, jc - sub), min(hi_h, jc + sub)
            best, ib, near, around = _refine_scan(lo, hi, 1, X, ca, sa, Y, Probed(lo_h, stride, s1, e1, sub), jc)
            probed = [i for i in range(lo, hi + 1)
                      if (i - lo_h) % stride != 0 and not (s1 <= i <= e1 and (i - s1) % sub == 0)]
            if not probed:
                continue
            values = [outline_value_polar(X, i, ca, sa, Y) for i in probed]
            k = int(np.argmin([v[0] for v in values]))
            assert (best, ib) == (values[k][0], probed[k])
            for tup, centre, slots in ((near, ib, (0, 1, 2)), (around, jc, (0, 2))):
                for slot in slots:
                    j = centre + slot - 1
                    r, psi = tup[2 * slot], tup[2 * slot + 1]
                    if j in probed:
                        assert (r, psi) == outline_value_polar(X, j, ca, sa, Y)[1:]
                        checked += 1
                    else:
                        assert r < 0.0
            assert around[2] < 0.0
    assert checked > 500


def _plain_walk(X, Y, ca, sa, j0, lo, hi):
    """The local search's walk as it was before it kept the polar coordinates: plain probes."""
    probe = lambda j: outline_value(X, j, ca, sa, Y)  # noqa: E731
    jb = min(max(j0, lo), hi)
    fb = probe(jb)
    for direction in (1, -1):
        moved = False
        while lo <= jb + direction <= hi:
            f = probe(jb + direction)
            if not f < fb:
                break
            fb, jb, moved = f, jb + direction, True
        if moved:
            break
    return jb, fb


def test_walk_hands_finish_the_lookups_it_made_and_finish_gives_the_same_contact(tables):
    """The local search's walk keeps the radius and polar angle of its minimum and of both
    neighbours for _finish: the same minimum as the plain walk, coordinates equal to fresh
    probes of those samples, and _finish from them gives bit for bit the contact (or near
    contact within the flexible meshes' search gap) that it gives looking every sample up
    itself. Planet against sun and ring at random placements around contact."""
    rng = np.random.default_rng(3)
    t = tables
    gx = 1
    pts = _outline(t, gx)
    n = len(pts)
    nh = int(t.out_nh[gx])
    gap = 5e-5  # the flexible presets' search_gap
    found = near = 0
    for gy in (0, 2):
        away = 1 if gy == 0 else -1  # the planet's centre moving this way leaves Y
        a_ = _band_distance(t, gx, gy)
        Y = _placed_field(t, gy, rng.uniform(-0.1, 0.1))
        for _ in range(1000):
            X = _placed_outline(t, gx, a_ + away * rng.uniform(-1e-3, 2e-3), rng.uniform(-1e-4, 1e-4),
                                bool(rng.integers(2)))
            a = (math.pi if gy == 0 else 0.0) + rng.uniform(-0.3, 0.3)
            ca, sa = math.cos(a), math.sin(a)
            for half, (lo, hi) in enumerate(((0, nh - 1), (nh - 1, n - 1))):
                j0 = int(rng.integers(lo - 5, hi + 6))
                jb, fb, known = _walk(X, Y, ca, sa, j0, lo, hi)
                assert (jb, fb) == _plain_walk(X, Y, ca, sa, j0, lo, hi)
                for row, j in enumerate((jb - 1, jb, jb + 1)):
                    if lo <= j <= hi:
                        f, r, psi = outline_value_polar(X, j, ca, sa, Y)
                        assert (known[2 * row], known[2 * row + 1]) == (r, psi)
                    else:
                        assert known[2 * row] < 0.0
                if fb >= gap:
                    continue
                res = []
                for kn in (known, UNKNOWN):
                    out_f = np.full((MAX_CONTACTS, 5), -7.0)
                    out_i = np.full((MAX_CONTACTS, 3), -7, np.int64)
                    job = SearchJob(out_f, out_i, np.zeros((4 * MAX_CONTACTS, 4), np.int64), np.zeros(1, np.int64),
                                    1, gap, False, 0)
                    memo = _finish(X, Y, HalfTooth(lo, hi, 0, half, ca, sa), jb, fb, 0, job, (NO_TOOTH, 1.0, 0.0), kn)
                    res.append((memo, out_f, out_i))
                assert res[0][0] == res[1][0]
                assert np.array_equal(res[0][1], res[1][1]) and np.array_equal(res[0][2], res[1][2])
                if res[0][0][0]:
                    found += 1
                    near += res[0][1][0, 0] < 0.0
    # both overlaps and near contacts inside the search gap were compared
    assert found > 1000 and near > 40
