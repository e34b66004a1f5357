"""Contact search of one mesh on the real tooth outlines.

For a gear pair, the outline samples of every tooth of one gear that can reach the other gear are
looked up in the other gear's signed distance field (:mod:`.field`), and vice versa; per half
tooth the deepest point (coarse scan, local refinement, interpolation between samples) gives the
penetration, the contact point and the normal (the field's gradient). Both outlines are used in
their current positions, so this covers involute contact on the line of action, tip and corner
contact off it, contact on the fillet and back-flank contact, for external and internal meshes.
A contact is reported as (depth, point, normal, tooth indices) in the global frame.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels import kernel
from .field import band_value, placed_field, tooth_turn, turn_normal
from .outline import (contact_at, outline_tangential, outline_value, outline_value_polar, placed_outlines, sample_lookup,
                      placed_tooth)

MAX_CONTACTS = 8  # tooth-pair contact slots per mesh
# half teeth closer than this many outline samples (160 um at the default m/200 spacing) are
# followed between full searches; the solver's full search interval must be short enough that
# no surface closes that gap in between (see integrator.simulation.FULL_SEARCH_INTERVAL)
CACHE_SAMPLES = 16.0


class MeshPair(NamedTuple):
    """One mesh as its contact search sees it (a row of the :class:`~flexgear.dynamics.model.tables.MeshTable`)."""

    gear_a: int  # geometry of gear A (external) in the ContactTables
    gear_b: int  # geometry of gear B
    internal: bool  # B is an internal gear
    ncand_a: int  # half-width (in teeth) of A's candidate band (candidate_teeth)
    ncand_b: int  # half-width of B's candidate band
    stride: int  # coarse scan stride of a full search [outline samples]
    gap: float  # near contacts apart by less than this are reported too, with a negative depth [m] (0: overlaps only)


class SearchJob(NamedTuple):
    """One mesh search: where its contacts go, its cache of half teeth and how it scans."""

    found_f: np.ndarray  # (MAX_CONTACTS, 5) float: depth, point x, y, normal of the force on A x, y [m]
    found_i: np.ndarray  # (MAX_CONTACTS, 3) int: tooth of A, tooth of B, side of A
    cache: np.ndarray  # (4 MAX_CONTACTS, 4) int: half teeth near contact (xIsA, tooth, half, sample)
    cache_count: np.ndarray  # (1,) int: rows of ``cache`` written by this search
    stride: int  # coarse scan stride [outline samples]
    gap: float  # near-contact margin [m] (MeshPair.gap)
    local: bool  # only follow the cached half teeth
    base: int  # full search: first row of the previous search's half teeth in ``cache``


class HalfTooth(NamedTuple):
    """Half tooth of gear X being refined: its sample range and the tooth's turn."""

    lo: int  # first sample of the half's range
    hi: int  # last sample
    tooth: int  # tooth index (unreduced)
    half: int  # 0: right half, 1: left half
    ca: float  # cosine of the tooth's angle
    sa: float  # sine of the tooth's angle


class Probed(NamedTuple):
    """Samples of a half tooth already probed, which a refinement need not probe again."""

    i0: int  # the coarse scan's samples i0 + k stride (stride = 0: none)
    stride: int
    s1: int  # the first refinement's samples s1 + k sub <= e1 (e1 < s1: none)
    e1: int
    sub: int


@kernel(literal=True, error_model="numpy", inline="always")
def mesh_pair(meshes, m):
    """Row m of a MeshTable as a MeshPair."""
    return MeshPair(meshes.gear_a[m], meshes.gear_b[m], meshes.internal[m], meshes.ncand_a[m], meshes.ncand_b[m],
                    meshes.stride[m], meshes.gap[m])


# no tooth index: the memo of the turn of Y's tooth frame is empty
NO_TOOTH = 1 << 62
# polar coordinates (radius, angle) of the samples around jb for _finish: none known
UNKNOWN = (-1.0, 0.0, -1.0, 0.0, -1.0, 0.0)


# not inline: inlined into every caller it made the first compile of the force kernels take
# over 10 min instead of about 1 min (numba inlines at the IR level); no reference counting,
# see mesh_search
@kernel(literal=True, error_model="numpy", _nrt=False)
def _finish(X, Y, tooth, jb, fb, count, job, memo, known):
    """Refine around sample jb (value fb) of ``tooth`` (a HalfTooth) of X (a PlacedOutline) against Y (a PlacedField) and merge the contact into the job's list.

        A near contact with a gap up to ``job.gap`` [m] counts too (negative depth). On a smooth
        part of X the deepest point is where Y's normal is perpendicular to X's tangent: two
        involutes are nearly parallel, so a parabola through the sampled depths would misplace it
        by micrometres (and the damping's normal velocity with it); the zero of the normal's
        tangential component, interpolated between jb and the neighbour where it changes sign, is
        used instead. At X's tip corner the corner sample is kept unless the depth still grows into
        a segment. Where the normal does not change sign (Y's corner pressed into X's flank) the
        sample is kept. The depth is the signed distance at that point (at most the chord sag
        ds^2 / (8 rho) lost).

        ``memo`` = (mk, mc, ms): the last tooth of Y turned to the global frame and its cosine and
        sine (mk = NO_TOOTH: none), returned updated with the count. ``known``: (r, psi) [m, rad] of
        samples jb - 1, jb, jb + 1 about Y's centre as probed by the caller (negative radius:
        :data:`UNKNOWN`), reused without recomputing.
    """
    i_lo, i_hi, kk, half, ca, sa = tooth
    out_f = job.found_f
    out_i = job.found_i
    gap = job.gap
    mk, mc, ms = memo
    outline = X.points
    corners = X.corner
    pitch = Y.pitch
    z = Y.z
    thY = Y.th
    if known[2] >= 0.0:
        px, py, f, ux, uy, k, phr, inside = sample_lookup(X, jb, known[2], known[3], ca, sa, Y)
    else:
        px, py, f, ux, uy, k, phr, inside = contact_at(X, i_lo, i_hi, jb, 0.0, ca, sa, Y)
    nx = 0.0
    ny = 0.0
    toothY = -1
    sideY = 0
    if inside:
        if k != mk:
            mk = k
            ang = tooth_turn(Y, k)
            mc = math.cos(ang)
            ms = math.sin(ang)
        nx, ny = turn_normal(ux, uy, mc, ms)
        toothY = k % z
        sideY = 1 if phr >= 0.0 else -1
    npts = outline.shape[0]
    if toothY >= 0 and 1 <= jb <= npts - 2:
        corner = corners[jb]
        for d in (-1, 1):
            # the depth grows from jb toward jb + d where the tangential component h of Y's
            # normal along the outline (in index order) has the sign of -d
            hb = outline_tangential(outline, jb, d if corner else 0, ca, sa, nx, ny)
            jn = jb + d
            if hb * d >= 0.0 or jn < i_lo or jn > i_hi or jn < 1 or jn > npts - 2 or corners[jn]:
                continue
            rn = known[0] if d < 0 else known[4]
            if rn >= 0.0:
                pn = known[1] if d < 0 else known[5]
                _, _, _, vx, vy, kn, _, inside_n = sample_lookup(X, jn, rn, pn, ca, sa, Y)
            else:
                _, _, _, vx, vy, kn, _, inside_n = contact_at(X, i_lo, i_hi, jn, 0.0, ca, sa, Y)
            mx = 0.0
            my = 0.0
            if inside_n:
                if kn != mk:
                    mk = kn
                    ang = tooth_turn(Y, kn)
                    mc = math.cos(ang)
                    ms = math.sin(ang)
                mx, my = turn_normal(vx, vy, mc, ms)
            hn = outline_tangential(outline, jn, 0, ca, sa, mx, my)
            if hn * hb < 0.0:
                t = hb / (hb - hn) * d
                qx, qy, g, wx, wy, kq, phq, inside_q = contact_at(X, i_lo, i_hi, jb, t, ca, sa, Y)
                if inside_q:
                    if kq != mk:
                        mk = kq
                        ang = tooth_turn(Y, kq)
                        mc = math.cos(ang)
                        ms = math.sin(ang)
                    nx, ny = turn_normal(wx, wy, mc, ms)
                    px, py, f = qx, qy, g
                    toothY = kq % z
                    sideY = 1 if phq >= 0.0 else -1
                break
    depth = -f
    if depth <= -gap or toothY < 0:
        return count, (mk, mc, ms)
    toothX = kk % X.z
    sideX = -1 if half == 0 else 1
    if X.is_a:
        ta, tb, sa_ = toothX, toothY, sideX
        nAx, nAy = nx, ny
    else:
        ta, tb, sa_ = toothY, toothX, sideY
        nAx, nAy = -nx, -ny
    # merge with an existing contact of the same tooth pair and flank side
    slot = -1
    for c in range(count):
        if out_i[c, 0] == ta and out_i[c, 1] == tb and out_i[c, 2] == sa_:
            slot = c
            break
    if slot >= 0:
        if depth <= out_f[slot, 0]:
            return count, (mk, mc, ms)
    else:
        if count >= out_f.shape[0]:
            sm = 0
            for c in range(1, count):
                if out_f[c, 0] < out_f[sm, 0]:
                    sm = c
            if depth <= out_f[sm, 0]:
                return count, (mk, mc, ms)
            slot = sm
        else:
            slot = count
            count += 1
    out_f[slot, 0] = depth
    out_f[slot, 1] = px
    out_f[slot, 2] = py
    out_f[slot, 3] = nAx
    out_f[slot, 4] = nAy
    out_i[slot, 0] = ta
    out_i[slot, 1] = tb
    out_i[slot, 2] = sa_
    return count, (mk, mc, ms)


@kernel(literal=True, error_model="numpy", inline="always")
def _half_range(half, nh, npts, tip_from):
    """Sample index range of a half tooth (0: right, 1: left), restricted to the tip region
    from ``tip_from`` (0: the whole half)."""
    if half == 0:
        return tip_from, nh - 1
    return nh - 1, npts - 1 - tip_from


@kernel(literal=True, error_model="numpy", inline="always")
def _min_scan(lo, hi, step, X, ca, sa, Y):
    """Smallest signed distance (and its first sample, its radius and polar angle about Y's
    centre as :func:`outline_value_polar` gives them) over samples lo, lo + step, ... <= hi of gear X's
    tooth (a PlacedOutline, turned by rotation ca, sa) against gear Y (a PlacedField):
    :func:`_refine_scan` with no sample known."""
    best, ib, near, _ = _refine_scan(lo, hi, step, X, ca, sa, Y, Probed(lo, 0, 0, -1, 1), -2)
    return best, ib, near[2], near[3]


# a function, not inlined: called twice by _scan (compile time, see _scan)
@kernel(literal=True, error_model="numpy", _nrt=False)
def _refine_scan(lo, hi, step, X, ca, sa, Y, probed, jc):
    """The smallest signed distance over samples lo, lo + step, ... <= hi, skipping the samples in ``probed``.

        The known samples (coarse scan, first refinement) are all at least the best value fb so
        far, so skipping them does not change the outcome (a better sample only if f2 < fb).

        Returns
        -------
        best, ib : float, int
            The smallest value found and its first sample (1e30, lo: none probed).
        near : tuple
            (r, psi) [m, rad] of samples ib - 1, ib, ib + 1 for :func:`_finish` (negative radius:
            not probed).
        around : tuple
            The same for the samples jc - 1 and jc + 1 (the middle pair unset, r = -1).
    """
    i0, stride, s1, e1, sub = probed
    best = 1e30
    ib = lo
    rm, pm, rc, pc, rp, pp = UNKNOWN  # samples ib - 1, ib, ib + 1
    qm, am, qp, ap = -1.0, 0.0, -1.0, 0.0  # samples jc - 1, jc + 1
    il = lo - 2  # the last sample probed, its radius and angle
    rl = -1.0
    pl = 0.0
    i = lo
    while i <= hi:
        if (stride == 0 or (i - i0) % stride != 0) and not (s1 <= i <= e1 and (i - s1) % sub == 0):
            f, r, p = outline_value_polar(X, i, ca, sa, Y)
            if i == ib + 1:
                rp, pp = r, p
            if i == jc - 1:
                qm, am = r, p
            elif i == jc + 1:
                qp, ap = r, p
            if f < best:
                best = f
                ib = i
                rc, pc = r, p
                rp, pp = -1.0, 0.0
                if il == i - 1:
                    rm, pm = rl, pl
                else:
                    rm, pm = -1.0, 0.0
            il, rl, pl = i, r, p
        i += step
    return best, ib, (rm, pm, rc, pc, rp, pp), (qm, am, -1.0, 0.0, qp, ap)


# The coarse scan skips samples whose signed distance is certified to exceed what it looks for.
# The tabulated distances are exact at the grid nodes (1-Lipschitz: |f difference| <= the
# distance of two nodes, dr radially, at most r_i dphi along row i). In a cell (rows i, i + 1,
# the point at r = r_i + a dr) the bilinear interpolant in (r, phi) has a radial derivative
# of at most 1 and an arc-length derivative (1/r) df/dphi of at most
# ((1 - a) r_i + a r_(i+1)) dphi / (r dphi) = 1, so a gradient of at most sqrt(2), and it is
# continuous from cell to cell: f(q) >= f(p) - LIPSCHITZ |path from p to q| - LIPSCHITZ_MARGIN
# (the margin covering rounding, the interpolant's extrapolation by rounding at the pitch
# seam, and the chord sag of the outline polygon against the inside test, all nanometres);
# samples i and j of an outline are joined by a path at most |i - j| ds long.
LIPSCHITZ = 1.5
LIPSCHITZ_MARGIN = 1e-6  # m


@kernel(literal=True, error_model="numpy", inline="always")
def _coarse_scan(lo, hi, step, X, ca, sa, Y, cap):
    """:func:`_min_scan` that skips samples certified to exceed ``cap`` > 0 (the result is exact whenever it is <= cap).

        Returns (value, sample, its radius and polar angle about Y's centre; -1, 0: none
        evaluated). Two bounds certify a sample: the SDF is Lipschitz (LIPSCHITZ) from the anchor
        of the largest certified value (a sample in the band, or outside it away from Y's material,
        less a cell's diagonal), and Y's tip circle (material lies inside it, outside for a ring),
        checked before the arc tangent and interpolation. The caller keeps cap < 1 mm -
        LIPSCHITZ_MARGIN, so samples beyond the band on the far side exceed it.
    """
    outline = X.points
    cxX = X.cx
    cyX = X.cy
    cxY = Y.cx
    cyY = Y.cy
    internal = Y.internal
    tip = Y.tip
    lip_ds = LIPSCHITZ * X.ds
    rmax = Y.r0 + Y.dr * (Y.grid.shape[2] - 1)
    cell = Y.dr + rmax * Y.dphi  # longer than the diagonal of any cell
    best = 1e30
    ib = lo
    rb = -1.0  # radius and polar angle of sample ib about Y's centre (r < 0: none)
    pb = 0.0
    fa = -1e30  # value at the anchor sample ia (none yet)
    ia = lo
    i = lo
    while i <= hi:
        if fa - LIPSCHITZ_MARGIN - lip_ds * (i - ia) >= cap:
            i += step
            continue
        px = cxX + ca * outline[i, 0] - sa * outline[i, 1]
        py = cyX + sa * outline[i, 0] + ca * outline[i, 1]
        dx = px - cxY
        dy = py - cyY
        r = math.sqrt(dx * dx + dy * dy)
        # lower bound of the value from Y's tip circle: the distance to the material less a cell
        lb = (tip - r if internal else r - tip) - cell
        if lb - LIPSCHITZ_MARGIN >= cap:  # certified above cap: not evaluated, an anchor
            if lb > fa - lip_ds * (i - ia):
                fa = lb
                ia = i
            i += step
            continue
        f, inband, psi = band_value(Y, dx, dy, r)
        if f < best:
            best = f
            ib = i
            rb = r
            pb = psi
        if inband:
            fa = f
            ia = i
        elif lb > fa - lip_ds * (i - ia):  # outside the band: the bound from the tip circle
            fa = lb
            ia = i
        i += step
    return best, ib, rb, pb


# a function, not inlined (compile time, see _scan); no reference counting, see mesh_search
@kernel(literal=True, error_model="numpy", _nrt=False)
def _walk(X, Y, ca, sa, j0, i_lo, i_hi):
    """Walk downhill along gear X's tooth outline (a PlacedOutline, the tooth turned by rotation
    ca, sa) in the signed distance of gear Y (a PlacedField) from sample j0 (clipped to
    [i_lo, i_hi]) to the nearest local minimum: first toward higher indices, else lower.

    Returns
    -------
    jb, fb : int, float
        The sample of the local minimum and its signed distance [m].
    known : tuple
        (r, psi of sample jb - 1, the same of jb, of jb + 1) [m, rad], their radius and polar
        angle about Y's centre (:func:`outline_value_polar`) for :func:`_finish`; a negative radius
        where a neighbour lies outside [i_lo, i_hi] (the walk probes both neighbours inside it:
        the one it came from and the one that stopped it).
    """
    jb = min(max(j0, i_lo), i_hi)
    fb, rc, pc = outline_value_polar(X, jb, ca, sa, Y)
    rm, pm, rp, pp = -1.0, 0.0, -1.0, 0.0  # samples jb - 1, jb + 1 (r < 0: not probed)
    for direction in (1, -1):
        moved = False
        while True:
            j = jb + direction
            if j < i_lo or j > i_hi:
                break
            f, r, p = outline_value_polar(X, j, ca, sa, Y)
            if f < fb:  # step on: the old jb becomes the neighbour behind, the one ahead is unknown
                if direction > 0:
                    rm, pm, rp, pp = rc, pc, -1.0, 0.0
                else:
                    rm, pm, rp, pp = -1.0, 0.0, rc, pc
                fb, rc, pc = f, r, p
                jb = j
                moved = True
            else:
                if direction > 0:
                    rp, pp = r, p
                else:
                    rm, pm = r, p
                break
        if moved:
            break
    return jb, fb, (rm, pm, rc, pc, rp, pp)


# not inline: inlined into every caller it made the first compile of the force kernels take
# over 10 min instead of about 1 min (numba inlines at the IR level); no reference counting,
# see mesh_search
@kernel(literal=True, error_model="numpy", inline="always")
def _tip_corner(corner, half, i_lo, i_hi):
    """The corner sample of a half tooth nearest its tip centre (the tip corner: the first sample
    flagged in ``corner`` going from the tip centre toward the root), -1 if none (a pointed
    tooth). The tip centre is the last sample of the right half (half 0), the first of the left."""
    if half == 0:
        for j in range(i_hi - 1, i_lo, -1):
            if corner[j]:
                return j
    else:
        for j in range(i_lo + 1, i_hi):
            if corner[j]:
                return j
    return -1


@kernel(literal=True, error_model="numpy", inline="always")
def _key_order(row_a, row_k, row_h, x_is_a, kk, half):
    """Order of the cache row (row_a: xIsA, row_k: tooth, row_h: half) against the half tooth
    (x_is_a, kk, half) in the order in which a full search visits the half teeth (gear A's
    first, then by tooth, then right half before left): -1 before it, 0 the same half tooth, 1
    after it."""
    ra = 0 if row_a == 1 else 1
    xa = 0 if x_is_a else 1
    if ra != xa:
        return -1 if ra < xa else 1
    if row_k != kk:
        return -1 if row_k < kk else 1
    if row_h != half:
        return -1 if row_h < half else 1
    return 0


# The warm start of a full search (_scan with local = False, a half tooth the previous full
# search cached, see mesh_search): the half tooth's sampled signed distance f is walked downhill
# from its cached sample (_walk, as the local searches between full searches do) instead of
# the coarse scan and its two refinements. The result is the cold one (the same sample, value,
# cache row and contact) whenever f is strictly unimodal over the half's samples (one local
# minimum, at g):
#  - the walk ends at g, from any start;
#  - the coarse scan's smallest value is the smaller of f at the two coarse samples (i_lo +
#    n stride) bracketing g, g_lo <= g < g_lo + stride (its skipped samples exceed the cap, and
#    on either side of g the nearest coarse sample is the smallest): the cold search refines
#    iff that value <= thresh, which the warm start decides by probing g_lo and g_lo + stride,
#    or without probing when the Lipschitz bound from g certifies the nearer one <= thresh;
#  - refining, the coarse minimum c is g_lo or g_lo + stride, within stride of g, so g lies in
#    the first refinement's window [c - stride, c + stride]; its smallest sample j1 (with c, the
#    samples at most sub apart) is next to g: |g - j1| <= sub, so the last refinement, every
#    sample of [j1 - sub, j1 + sub], ends at g;
#  - g >= the cache threshold (a half tooth leaving contact): the cold search neither caches it
#    nor reports a contact (its result is >= f(g)), nor does the warm one.
# f is not unimodal over a whole half: the tip corner, where f has a kink, is often a local
# minimum besides a flank point (a walk from a random sample ends at the wrong one in most full
# searches). The probes a warm start makes besides the walk's test the unimodality, and a sample
# below the walk's minimum sends the half to the cold search: the half's tip corner (unless the
# walk has probed it), and the two coarse samples around the minimum when it is at the tip
# corner or at an end of the half (where a deeper flank minimum apart from it is not seen by
# the walk) or when they are probed anyway. A second minimum elsewhere is not detected: a
# minimum the walk sits at stays the result while another, apart from it, becomes deeper (the
# blind spot of the local searches between two full searches, which the cold full search
# closed every FULL_SEARCH_INTERVAL); tests/test_full_search_warm.py checks that the warm search
# gives the cold one's results. A faulty tooth's outline (ContactTables.out_cold: a spall's edge
# and floor, a chip's corners are minima apart from each other) is scanned cold at every full
# search, so the deeper minimum takes over within a full-search interval.
@kernel(literal=True, error_model="numpy", _nrt=False)
def _scan(Xs, Y, ncand, beta, count, job):
    """Scan gear X's teeth (a GearOutlines; each tooth's outline a per-tooth lookup) against the SDF of gear Y (a PlacedField) and append the contacts to the job (a SearchJob).

        ``found_f``: depth, px, py, nAx, nAy (unit normal of the force on gear A); ``found_i``:
        tooth_a, tooth_b, side_a; appended after the first ``count``. Full search: candidate teeth
        around the facing direction ``beta``, each half scanned coarsely (every ``stride``-th point;
        the SDF is 1-Lipschitz, so a half whose samples all exceed stride*ds/2 cannot penetrate),
        then refined; halves near contact are remembered in ``job.cache`` (xIsA, tooth, half,
        sample). Local search: only the cached halves, each followed downhill to the nearest local
        minimum. ``job.gap`` [m]: near contacts are reported with a negative depth. ``X.tip_from``
        limits the scan to the tip region (the scan of B against A only has to find B's tip
        corners). ``job.base``: rows from there hold the previous full search's halves, walked
        downhill instead of scanned unless this search overwrote them.
    """
    stride = job.stride
    local = job.local
    cache = job.cache
    ncache = job.cache_count
    gap = job.gap
    base = job.base
    ds = Xs.ds
    thX = Xs.th
    pitchX = Xs.pitch
    xIsA = Xs.is_a
    # memo of the turn of Y's tooth frames for _finish (NO_TOOTH: empty); np.int64, not the
    # literal constant: _finish compiles once, not once more for the literal memo
    memo = (np.int64(NO_TOOTH), 1.0, 0.0)
    if local:
        xk = NO_TOOTH  # the tooth of X whose turn ca, sa and outline are known
        ca = 1.0
        sa = 0.0
        X = placed_tooth(Xs, 0)
        for e in range(ncache[0]):
            if (cache[e, 0] == 1) != xIsA:
                continue
            kk = cache[e, 1]
            half = cache[e, 2]
            j0 = cache[e, 3]
            if kk != xk:  # the two halves of a tooth follow each other in the cache
                xk = kk
                a = thX + kk * pitchX + Xs.angle[kk % Xs.z]
                ca = math.cos(a)
                sa = math.sin(a)
                X = placed_tooth(Xs, kk)
            i_lo, i_hi = _half_range(half, X.nh, X.points.shape[0], X.tip_from)
            jb, fb, known = _walk(X, Y, ca, sa, j0, i_lo, i_hi)
            cache[e, 3] = jb
            if fb < gap:
                count, memo = _finish(X, Y, HalfTooth(i_lo, i_hi, kk, half, ca, sa), jb, fb, count, job, memo,
                                      known)
        return count
    kc = int(math.floor((beta - thX) / pitchX + 0.5))
    thresh = 0.5 * stride * ds + 1e-9 + gap
    keep = CACHE_SAMPLES * ds + gap  # the cache threshold
    # the certified skipping of the coarse scan needs the bound outside the band (1 mm) above thresh
    skip = thresh < 1e-3 - LIPSCHITZ_MARGIN
    p = base  # the next row of the previous search's half teeth
    nrows = cache.shape[0]
    entry = -1  # the outline entry whose tip corners are known
    tipc0 = -1
    tipc1 = -1
    for kk in range(kc - ncand, kc + ncand + 1):
        a = thX + kk * pitchX + Xs.angle[kk % Xs.z]
        ca = math.cos(a)
        sa = math.sin(a)
        X = placed_tooth(Xs, kk)
        nh = X.nh
        npts = X.points.shape[0]
        tip_from = X.tip_from
        if Xs.teeth[kk % Xs.z] != entry:
            # the tip corners of the two halves of this tooth's outline (shared by the teeth of an entry)
            entry = Xs.teeth[kk % Xs.z]
            lo0, hi0 = _half_range(0, nh, npts, tip_from)
            lo1, hi1 = _half_range(1, nh, npts, tip_from)
            tipc0 = _tip_corner(X.corner, 0, lo0, hi0)
            tipc1 = _tip_corner(X.corner, 1, lo1, hi1)
        for half in range(2):
            i_lo, i_hi = _half_range(half, nh, npts, tip_from)
            # the previous search's row of this half tooth (rows below ncache[0]: overwritten)
            j0 = -1
            while p < nrows:
                if p < ncache[0]:
                    p += 1
                    continue
                order = _key_order(cache[p, 0], cache[p, 1], cache[p, 2], xIsA, kk, half)
                if order < 0:
                    p += 1
                    continue
                if order == 0:
                    j0 = cache[p, 3]
                    p += 1
                break
            warm = False
            if j0 >= 0 and not Xs.cold[entry]:
                # warm start (see the comment above _scan)
                jb, fb, known = _walk(X, Y, ca, sa, j0, i_lo, i_hi)
                warm = True
                jt = tipc0 if half == 0 else tipc1
                js = min(max(j0, i_lo), i_hi)
                # at the tip corner or an end of the half, where the walk stops at a kink or a
                # bound, a deeper flank minimum may lie apart: the two coarse samples around jb
                # are probed then
                special = jb == jt or jb == i_lo or jb == i_hi
                # the tip corner, unless the walk has probed it (its path from j0 to jb and the
                # two neighbours of jb: none below fb)
                if jt >= 0 and not min(js, jb) - 1 <= jt <= max(js, jb) + 1 and outline_value(X, jt, ca, sa, Y) < fb:
                    warm = False  # a second minimum, deeper: scan the half
                if warm and (fb < keep or special):
                    # does the cold search refine: a coarse sample <= thresh, of the two around jb?
                    # Certified without probing when the Lipschitz bound from jb (see LIPSCHITZ)
                    # puts the nearer one, dmin samples away, at most at thresh: the outline
                    # between them lies within dmin ds of sample jb (radius rj about Y's
                    # centre), inside the tabulated band when rj is dmin ds inside it
                    g_lo = i_lo + ((jb - i_lo) // stride) * stride
                    g_hi = g_lo + stride
                    dmin = min(jb - g_lo, g_hi - jb) if g_hi <= i_hi else jb - g_lo
                    rj = known[2]
                    reach = dmin * ds
                    if special or not (fb + LIPSCHITZ * reach + LIPSCHITZ_MARGIN <= thresh and Y.r0 < rj - reach
                                       and rj + reach < Y.r0 + Y.dr * (Y.grid.shape[2] - 1)):
                        f_lo = outline_value(X, g_lo, ca, sa, Y)
                        f_hi = outline_value(X, g_hi, ca, sa, Y) if g_hi <= i_hi else 1e30
                        if f_lo < fb or f_hi < fb:
                            warm = False  # not unimodal: scan the half
                        elif fb < keep and min(f_lo, f_hi) > thresh:
                            continue  # the cold search does not refine it: neither cached nor reported
                if warm and fb >= keep:
                    continue  # leaving contact: neither cached nor reported
            if not warm:
                if skip:
                    fb, jb, rb, pb = _coarse_scan(i_lo, i_hi, stride, X, ca, sa, Y, thresh)
                else:
                    fb, jb, rb, pb = _min_scan(i_lo, i_hi, stride, X, ca, sa, Y)
                if fb > thresh:
                    continue
                # refine around the best sample: every stride/4-th sample, then every sample
                # (the samples of the coarse scan and of the first refinement are not probed again:
                # none of them is below fb, see _refine_scan)
                sub = stride // 4 if stride >= 4 else 1
                s1 = max(i_lo, jb - stride)
                e1 = min(i_hi, jb + stride)
                f2, j2, near, _ = _refine_scan(s1, e1, sub, X, ca, sa, Y, Probed(i_lo, stride, 0, -1, 1), -2)
                if f2 < fb:
                    fb, jb, rb, pb = f2, j2, near[2], near[3]
                # the last refinement probes the neighbours of its minimum (of the sample jb it
                # starts from, when it finds nothing deeper): their polar coordinates go to _finish
                f2, j2, near, around = _refine_scan(max(i_lo, jb - sub), min(i_hi, jb + sub), 1, X, ca, sa, Y,
                                                    Probed(i_lo, stride, s1, e1, sub), jb)
                if f2 < fb:
                    fb, jb = f2, j2
                    known = near
                else:
                    known = (around[0], around[1], rb, pb, around[4], around[5])
            # remember half teeth close to contact for the local searches until the next full one
            if fb < keep and ncache[0] < cache.shape[0]:
                e = ncache[0]
                cache[e, 0] = 1 if xIsA else 0
                cache[e, 1] = kk
                cache[e, 2] = half
                cache[e, 3] = jb
                ncache[0] += 1
            if fb >= gap:
                continue
            count, memo = _finish(X, Y, HalfTooth(i_lo, i_hi, kk, half, ca, sa), jb, fb, count, job, memo, known)
    return count


@kernel(literal=True, error_model="numpy")
def mesh_contacts(pose_a, pose_b, pair, tables, found_f, found_i, local=False, cache=None, ncache=None):
    """All tooth-pair contacts of one mesh between gear A (external) and gear B.

    Parameters
    ----------
    pose_a, pose_b : (3,) arrays
        x [m], y [m], angle [rad] of the two gears.
    pair : MeshPair
        The mesh: geometries of A and B in ``tables``, internal B, candidate bands
        (:func:`~flexgear.gears.contact_tables.candidate_teeth`), coarse scan stride, near-contact
        margin ``gap`` [m] (contacts whose rigid outlines are apart by less are reported with a
        negative depth; 0: overlaps only).
    tables : ContactTables
        Outline samples and signed distance fields of the gear geometries.
    found_f, found_i : arrays (MAX_CONTACTS, 5) float and (MAX_CONTACTS, 3) int
        Filled with depth, point, normal of the force on A; tooth of A, tooth of B, side of A.
    local : bool
        Only refine the half teeth remembered in ``cache`` by the last full search.
    cache, ncache : int arrays (4 * MAX_CONTACTS, 4) and (1,)
        Half teeth near contact (filled by a full search). A full search starts from the half
        teeth the previous one left in them (see :func:`_scan`); ``ncache[0] = 0`` before it
        makes it search from scratch (the same results along the presets' trajectories).

    Returns
    -------
    int
        Number of contacts.

    The force kernels call :func:`mesh_search` (the same with the cache arrays required), which
    is compiled without reference counting.
    """
    if cache is None:
        cache = np.zeros((4 * MAX_CONTACTS, 4), np.int64)
        ncache = np.zeros(1, np.int64)
    return mesh_search(pose_a, pose_b, pair, tables, found_f, found_i, local, cache, ncache)


@kernel(literal=True, error_model="numpy", inline="always")
def toothing_centre(tables, g, cx, cy, th):
    """Centre [m] of gear g's toothing at the pose (cx, cy, th): the rotation axis moved by the
    gear's eccentricity (``tables.gear_shift``, gear frame); the axis itself without one."""
    ex, ey = tables.gear_shift[g, 0], tables.gear_shift[g, 1]
    if ex != 0.0 or ey != 0.0:
        c = math.cos(th)
        s = math.sin(th)
        return cx + (c * ex - s * ey), cy + (s * ex + c * ey)
    return cx, cy


# Compiled without reference counting (_nrt=False), as are _scan and _finish: they create no
# arrays, only views of their arguments, which outlive the call. With it, every array passed to
# a compiled function or taken from a tuple costs an atomic increment and decrement (about 60
# per local search of a mesh).
@kernel(literal=True, error_model="numpy", _nrt=False)
def mesh_search(pose_a, pose_b, pair, tables, found_f, found_i, local, cache, ncache):
    """:func:`mesh_contacts` with the search cache ``cache``, ``ncache`` given (arrays, not
    None); what the force kernels call."""
    base = cache.shape[0]
    if not local:
        # the previous full search's half teeth (as the local searches left them) move to the
        # last rows, where _scan warm-starts from them while it writes its own from row 0
        nold = min(max(ncache[0], 0), cache.shape[0])
        base = cache.shape[0] - nold
        for e in range(nold - 1, -1, -1):
            for c in range(4):
                cache[base + e, c] = cache[e, c]
        ncache[0] = 0
    cxA, cyA, thA = pose_a[0], pose_a[1], pose_a[2]
    cxB, cyB, thB = pose_b[0], pose_b[1], pose_b[2]
    if local:  # the facing directions only centre the candidate teeth of a full search
        betaA = 0.0
        betaB = 0.0
    elif pair.internal:
        beta = math.atan2(cyA - cyB, cxA - cxB)
        betaA = beta
        betaB = beta
    else:
        betaA = math.atan2(cyB - cyA, cxB - cxA)
        betaB = betaA + math.pi
    gA = pair.gear_a
    gB = pair.gear_b
    cxA, cyA = toothing_centre(tables, gA, cxA, cyA, thA)
    cxB, cyB = toothing_centre(tables, gB, cxB, cyB, thB)
    fieldA = placed_field(tables, gA, cxA, cyA, thA)
    fieldB = placed_field(tables, gB, cxB, cyB, thB)
    # the scan of B only looks for B's tip corners (every other contact is found scanning A)
    outlineA = placed_outlines(tables, gA, cxA, cyA, thA, False, True)
    outlineB = placed_outlines(tables, gB, cxB, cyB, thB, True, False)
    job = SearchJob(found_f, found_i, cache, ncache, pair.stride, pair.gap, local, base)
    count = np.int64(0)  # not the literal 0: _scan and _finish compile once each
    count = _scan(outlineA, fieldB, pair.ncand_a, betaA, count, job)
    count = _scan(outlineB, fieldA, pair.ncand_b, betaB, count, job)
    return count
