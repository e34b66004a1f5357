"""Flank compliance of a flexible gear at its contacts, from the tables of its reduction: the
condensed modes' flank displacements and the residual tables interpolated in the contact radius
(:class:`~flexgear.dynamics.model.tables.FlexTable`), and the modal coordinates' flank
displacement.
"""
from __future__ import annotations

import math

from ...kernels import kernel



@kernel(error_model="numpy", inline="always")
def _radius_cell(radius, o, J, r):
    """Table interval j0 and weight w (linear in r, clamped to the table ends; bisection, so
    any increasing table radii work: ``flank_tables(radii=...)``)."""
    if r <= radius[o]:
        return 0, 0.0
    if r >= radius[o + J - 1]:
        return J - 2, 1.0
    lo = 0
    hi = J - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if radius[o + mid] <= r:
            lo = mid
        else:
            hi = mid
    return lo, (r - radius[o + lo]) / (radius[o + lo + 1] - radius[o + lo])


@kernel(error_model="numpy", inline="always")
def _coarse_cell(radius, o, J, k, j, w):
    """Cell and weight (linear in r) on the coupling tables' radii (every k-th of the J table
    radii ``radius[o:o + J]``; k = ``coupling_stride``) of the point in table cell j at weight w."""
    if k == 1:
        return j, w
    Jc = (J - 1) // k + 1
    r = radius[o + j] + w * (radius[o + j + 1] - radius[o + j])
    jc = min(j // k, Jc - 2)
    r0 = radius[o + jc * k]
    return jc, (r - r0) / (radius[o + (jc + 1) * k] - r0)


@kernel(error_model="numpy", inline="always")
def flank_residual(flex, f, ki, si, ji, wi, ci, ui, kj, sj, jj, wj, cj, uj):
    """Residual part of :func:`flank_influence` between points in table cells (ji, wi) and
    (jj, wj) of :func:`_radius_cell`, in the coupling tables' cells (ci, ui), (cj, uj) of
    :func:`_coarse_cell` [m/N]: the self table for a contact with itself, the table of the
    tooth distance ``(ki - kj) mod z`` and the two sides otherwise (bilinear in the radii), from
    the loaded tooth's class ``kj % period``. Two different points of one flank get no
    residual term (the contact search gives one contact per flank of a tooth pair; their
    mutual near field would need the half-plane terms the self table removes). The cells are
    found once per contact by the caller: looking them up here, per pair, made the MERCURY
    1-A step twice as slow."""
    z = flex.teeth[f]
    J = flex.points[f]
    ia = 0 if si > 0 else 1
    ib = 0 if sj > 0 else 1
    d = (ki - kj) % z
    cls = kj % flex.period[f]
    if d == 0 and ia == ib:
        if ki == kj and ji == jj and wi == wj:
            return _self_term(flex.self_compliance, flex.self_offset[f] + (cls * 2 + ia) * J, ji, wi)
        return 0.0
    Jc = (J - 1) // flex.coupling_stride[f] + 1
    o = flex.coupling_offset[f] + (((cls * 2 + ia) * 2 + ib) * z + d) * Jc * Jc
    return _coupling_term(flex.coupling, o, Jc, ci, ui, cj, uj)


@kernel(error_model="numpy", inline="always")
def _self_term(S, o, j, w):
    """Residual self compliance in table cell (j, w) of the self table at offset o of ``S``
    (``self_compliance``; o for body f, tooth class c, side index si: ``self_offset[f] + (c * 2 +
    si) * J``) [m/N]."""
    return (1.0 - w) * S[o + j] + w * S[o + j + 1]


@kernel(error_model="numpy", inline="always")
def _coupling_term(T, o, Jc, ci, ui, cj, uj):
    """Bilinear interpolation in the Jc x Jc coupling block at offset o of ``T`` between the
    displaced point in coupling cell (ci, ui) and the loaded one in (cj, uj) [m/N]."""
    return ((1.0 - ui) * (1.0 - uj) * T[o + ci * Jc + cj] + ui * (1.0 - uj) * T[o + (ci + 1) * Jc + cj]
            + (1.0 - ui) * uj * T[o + ci * Jc + cj + 1] + ui * uj * T[o + (ci + 1) * Jc + cj + 1])


@kernel(error_model="numpy", inline="always")
def flank_influence(flex, f, ki, si, ri, kj, sj, rj):
    """Static compliance of flexible body f between flank points: displacement of tooth ki, side
    si (+1 / -1) at radius ri per newton on tooth kj, side sj at radius rj [m/N] (modes
    condensed quasi-statically plus the residual tables; see :class:`flexgear.dynamics.model.tables.FlexTable`).
    (Inlined: a call that hands over the FlexTable costs a reference count per array, several
    times the work of the function.)"""
    J = flex.points[f]
    nq = flex.condensed[f]
    ro = flex.radius_offset[f]
    ji, wi = _radius_cell(flex.radius, ro, J, ri)
    jj, wj = _radius_cell(flex.radius, ro, J, rj)
    ia = 0 if si > 0 else 1
    ib = 0 if sj > 0 else 1
    S = flex.shape
    bi = flex.shape_offset[f] + ((ki * 2 + ia) * J + ji) * nq
    bj = flex.shape_offset[f] + ((kj * 2 + ib) * J + jj) * nq
    c = 0.0
    for m in range(nq):
        ai = (1.0 - wi) * S[bi + m] + wi * S[bi + nq + m]
        aj = (1.0 - wj) * S[bj + m] + wj * S[bj + nq + m]
        c += ai * aj
    k = flex.coupling_stride[f]
    ci, ui = _coarse_cell(flex.radius, ro, J, k, ji, wi)
    cj, uj = _coarse_cell(flex.radius, ro, J, k, jj, wj)
    return c + flank_residual(flex, f, ki, si, ji, wi, ci, ui, kj, sj, jj, wj, cj, uj)


@kernel(error_model="numpy", inline="always")
def modal_products(U, cnt, nq, D, kap, ko):
    """``D[i, j] = D[j, i] = sum_m U[i, m] kap[ko + m] U[j, m]`` over the first nq columns, i, j <
    cnt (``kap``: the modes' weights, 1 for quasi-static condensation, :mod:`flexgear.dynamics.flexible.condensed`).

    Each sum runs over m in the order of a plain dot product; four of them (j .. j + 3) advance
    together, so that the additions are independent rather than one chain of dependent ones
    (the same numbers, about three times faster). Rows and weights are read through views
    indexed by the loop counter alone (contiguous vector loads, see :func:`flank_cells`)."""
    kv = kap[ko:ko + nq]
    for i in range(cnt):
        Ui = U[i]
        j = i
        while j + 3 < cnt:
            U0 = U[j]
            U1 = U[j + 1]
            U2 = U[j + 2]
            U3 = U[j + 3]
            c0 = 0.0
            c1 = 0.0
            c2 = 0.0
            c3 = 0.0
            for m in range(nq):
                a = Ui[m] * kv[m]
                c0 += a * U0[m]
                c1 += a * U1[m]
                c2 += a * U2[m]
                c3 += a * U3[m]
            D[i, j] = c0
            D[j, i] = c0
            D[i, j + 1] = c1
            D[j + 1, i] = c1
            D[i, j + 2] = c2
            D[j + 2, i] = c2
            D[i, j + 3] = c3
            D[j + 3, i] = c3
            j += 4
        while j < cnt:
            Uj = U[j]
            c = 0.0
            for m in range(nq):
                c += Ui[m] * kv[m] * Uj[m]
            D[i, j] = c
            D[j, i] = c
            j += 1


@kernel(error_model="numpy", inline="always")
def contact_compliance(flex, f, tooth, side, radius, cnt, cell, weight, ccell, cweight, U, D, kap, ko):
    """``D[i, j]`` = :func:`flank_influence` of body f between contacts i, j < cnt on its teeth
    ``tooth[i]``, sides ``side[i]``, radii ``radius[i]`` [m/N], each condensed mode m weighted
    by ``kap[ko + m]`` (1: quasi-static, as :func:`flank_influence`; :mod:`flexgear.dynamics.flexible.condensed`).

    The same numbers, with the work shared: each contact's table cells are found once (``cell``,
    ``weight``; coupling tables ``ccell``, ``cweight``), its modal flank displacements are interpolated once (row i of ``U``, which
    needs at least ``flex.condensed[f]`` columns; with fewer, every pair calls
    :func:`flank_influence`), and the modal part, a dot product of rows, once per pair of
    contacts (it is symmetric).
    """
    nq = flex.condensed[f]
    if U.shape[1] < nq:
        for i in range(cnt):
            for j in range(cnt):
                D[i, j] = flank_influence(flex, f, tooth[i], side[i], radius[i], tooth[j], side[j], radius[j])
        return
    # the table's parts as plain arrays and numbers, once: a field of the table read inside the
    # loops below costs a reference count increment and decrement each time
    J = flex.points[f]
    stride = flex.coupling_stride[f]
    z = flex.teeth[f]
    period = flex.period[f]
    co = flex.coupling_offset[f]
    T = flex.coupling
    sc = flex.self_compliance
    sco = flex.self_offset[f]
    flank_rows(flex, f, tooth, side, radius, cnt, cell, weight, ccell, cweight, U)
    modal_products(U, cnt, nq, D, kap, ko)
    # residual part (:func:`flank_residual` with its integer work hoisted: :func:`residual_pair`)
    Jc = (J - 1) // stride + 1
    for j in range(cnt):
        kj = tooth[j]
        ib = 0 if side[j] > 0 else 1
        for i in range(cnt):
            D[i, j] += residual_pair(tooth[i], 0 if side[i] > 0 else 1, cell[i], weight[i], ccell[i], cweight[i], kj,
                                     ib, cell[j], weight[j], ccell[j], cweight[j], z, period, J, Jc, T, co, sc, sco)


@kernel(error_model="numpy", inline="always")
def flank_rows(flex, f, tooth, side, radius, cnt, cell, weight, ccell, cweight, U):
    """Per contact i < cnt on body f (tooth ``tooth[i]``, side ``side[i]``, radius ``radius[i]``):
    its flank table cell and weight (``cell``, ``weight``), coupling-table cell and weight
    (``ccell``, ``cweight``) and its condensed modes' flank displacements A_m / omega_m (row i of
    ``U``, at least ``flex.condensed[f]`` columns), interpolated in the radius."""
    flank_cells(flex.condensed[f], flex.points[f], flex.radius_offset[f], flex.shape_offset[f], flex.shape, flex.radius,
                flex.coupling_stride[f], tooth, side, radius, cnt, cell, weight, ccell, cweight, U)


@kernel(error_model="numpy", inline="always")
def flank_cells(nq, J, ro, so, S, table_radius, stride, tooth, side, radius, cnt, cell, weight, ccell, cweight, U):
    """:func:`flank_rows` with body f's parts of the FlexTable as numbers and arrays: nq
    condensed modes, J table radii from ``ro`` in ``table_radius``, mode shapes ``S`` from
    ``so``, coupling stride (see :func:`extend_entries`)."""
    for i in range(cnt):
        ji, wi = _radius_cell(table_radius, ro, J, radius[i])
        cell[i] = ji
        weight[i] = wi
        ccell[i], cweight[i] = _coarse_cell(table_radius, ro, J, stride, ji, wi)
        bi = so + ((tooth[i] * 2 + (0 if side[i] > 0 else 1)) * J + ji) * nq
        # the two table rows as views: indexed by the loop counter alone, which the compiler
        # knows is not negative, they are read as contiguous vectors (``S[bi + m]`` needs a
        # negative-index check per element, compiled into a gather)
        row0 = S[bi:bi + nq]
        row1 = S[bi + nq:bi + 2 * nq]
        Ui = U[i]
        for m in range(nq):
            Ui[m] = (1.0 - wi) * row0[m] + wi * row1[m]


@kernel(error_model="numpy", inline="always")
def residual_pair(ki, ia, ji, wi, ci, ui, kj, ib, jj, wj, cj, uj, z, period, J, Jc, T, co, sc, sco):
    """:func:`flank_residual` between a displaced point (tooth ki, side index ia, table cell (ji,
    wi), coupling cell (ci, ui)) and a loaded one (kj, ib, (jj, wj), (cj, uj)) of a body with z
    teeth, tooth period ``period``, J table radii, Jc coupling radii, coupling tables ``T`` from
    ``co`` and self tables ``sc`` from ``sco`` [m/N] (plain numbers and arrays: see
    :func:`contact_compliance`)."""
    d = ki - kj
    if d < 0:
        d += z
    cls = kj % period
    if d == 0 and ia == ib:
        if ji == jj and wi == wj:
            return _self_term(sc, sco + (cls * 2 + ia) * J, ji, wi)
        return 0.0
    o = co + (((cls * 2 + ia) * 2 + ib) * z + d) * Jc * Jc
    return _coupling_term(T, o, Jc, ci, ui, cj, uj)


@kernel(error_model="numpy", inline="always")
def rigid_coordinates(flex, n):
    """Number of rigid-body coordinates among n (the modal coordinates come last)."""
    nr = n
    for f in range(flex.modes.shape[0]):
        nr -= flex.modes[f]
    return nr


@kernel(error_model="numpy", inline="always")
def modal_flank(flex, f, k, s, r, q, g):
    """Normal displacement of tooth k, side s (+1 / -1), radius r of flexible body f due to its
    modal coordinates in q, sum_i A_i(k, s, r) q_i [m] (radius interpolation as in
    :func:`flank_influence`); adds -A_i to the penetration gradient row g at the modal
    coordinates (the displacement is along the contact force on that flank, so it opens the
    contact)."""
    m = flex.modes[f]
    if m == 0:
        return 0.0
    J = flex.points[f]
    j, w = _radius_cell(flex.radius, flex.radius_offset[f], J, r)
    ia = 0 if s > 0 else 1
    b = flex.dynamic_offset[f] + ((k * 2 + ia) * J + j) * m
    c0 = flex.coordinate[f]
    A = flex.dynamic_shape
    u = 0.0
    for i in range(m):
        ai = (1.0 - w) * A[b + i] + w * A[b + m + i]
        u += ai * q[c0 + i]
        g[c0 + i] -= ai
    return u


@kernel(error_model="numpy", inline="always")
def flank_side(px, py, cx, cy, th, k, z):
    """Side (+1: positive angle from the centre line) of tooth k of a gear at (cx, cy), turned
    by th, on which point (px, py) lies; and the point's radius."""
    dx = px - cx
    dy = py - cy
    phi = math.atan2(dy, dx) - th - k * 2.0 * math.pi / z
    phi = (phi + math.pi) % (2.0 * math.pi) - math.pi
    return (1 if phi >= 0.0 else -1), flank_radius(px, py, cx, cy)


@kernel(error_model="numpy", inline="always")
def flank_radius(px, py, cx, cy):
    """Distance of point (px, py) from a gear's centre (cx, cy) [m] (the radius of
    :func:`flank_side`, without its side)."""
    dx = px - cx
    dy = py - cy
    return math.sqrt(dx * dx + dy * dy)
