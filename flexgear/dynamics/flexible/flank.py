"""Flank compliance of a flexible gear at its contacts, from the tables of its reduction: the
condensed modes' flank displacements and the residual tables interpolated in the contact radius
(:class:`~flexgear.dynamics.model.tables.FlexTable`), and the modal coordinates' flank
displacement.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels import kernel


class ResidualTables(NamedTuple):
    """One flexible body's residual tables and counts (row f of a FlexTable, :func:`residual_tables`)."""

    teeth: int  # z
    period: int  # tooth classes of the residual tables
    points: int  # table radii J
    coarse: int  # coupling-table radii Jc = (J - 1) / coupling_stride + 1
    condensed: int  # condensed modes nq
    condensed_offset: int  # start of the body's condensed modes in the per-mode arrays
    coupling_offset: int  # start of the body's coupling tables in ``coupling``
    self_offset: int  # start of the body's self tables in ``self_compliance``
    coupling: np.ndarray  # FlexTable.coupling [m/N]
    self_compliance: np.ndarray  # FlexTable.self_compliance [m/N]


class FlankContacts(NamedTuple):
    """One flexible body's stacked contacts with their table cells and modal rows (row f of the
    ContactBuffers' per-body arrays, :func:`flank_contacts`)."""

    slot: np.ndarray  # (S,) int: stacked slot of each contact
    tooth: np.ndarray  # (S,) int: its tooth on the body
    side: np.ndarray  # (S,) int: its flank side (+1 / -1)
    radius: np.ndarray  # (S,) float: its radius [m]
    cell: np.ndarray  # (S,) int: flank table interval
    weight: np.ndarray  # (S,) float: its weight
    coupling_cell: np.ndarray  # (S,) int: coupling table interval
    coupling_weight: np.ndarray  # (S,) float: its weight
    modes: np.ndarray  # (S, modes) float: condensed modes' flank displacements A_i / omega_i [m/sqrt(N/m)]


class FlankPoint(NamedTuple):
    """A point on a body's flanks, found in its tables."""

    tooth: int  # tooth index
    side: int  # side index: 0 for side +1, 1 for side -1
    cell: int  # flank table interval
    weight: float  # weight in it
    coupling_cell: int  # coupling table interval
    coupling_weight: float  # weight in it


@kernel(error_model="numpy", inline="always")
def residual_tables(t, f):
    """ResidualTables of row f of ``t`` (a FlexTable, or a table with its field names)."""
    J = t.points[f]
    return ResidualTables(t.teeth[f], t.period[f], J, (J - 1) // t.coupling_stride[f] + 1, t.condensed[f],
                       t.condensed_offset[f], t.coupling_offset[f], t.self_offset[f], t.coupling, t.self_compliance)


@kernel(error_model="numpy", inline="always")
def flank_contacts(c, f):
    """FlankContacts of flexible body row f of ``c`` (ContactBuffers, or a table with its field names)."""
    return FlankContacts(c.body_slot[f], c.body_tooth[f], c.body_side[f], c.body_radius[f], c.flank_cell[f],
                         c.flank_weight[f], c.coupling_cell[f], c.coupling_weight[f], c.flank_modes[f])


@kernel(error_model="numpy", inline="always")
def contact_point(rows, i):
    """Contact i of ``rows`` (a FlankContacts) as a FlankPoint."""
    return FlankPoint(rows.tooth[i], 0 if rows.side[i] > 0 else 1, rows.cell[i], rows.weight[i], rows.coupling_cell[i],
                      rows.coupling_weight[i])



@kernel(error_model="numpy", inline="always")
def radius_cell(radius, o, J, r):
    """Table interval j0 and weight w (linear in r, clamped to the table ends; bisection, so
    any increasing table radii work: :func:`flexgear.reduction.flank.flank_tables` with ``radii``)."""
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
def flank_residual(tabs, a, b):
    """Residual part of :func:`flank_influence` between the displaced point ``a`` and the loaded
    point ``b`` (FlankPoints of a body with the tables ``tabs``, a ResidualTables) [m/N]: the self
    table for a contact with itself, the table of the tooth distance ``(a.tooth - b.tooth) mod z``
    and the two sides otherwise (bilinear in the radii), from the loaded tooth's class ``b.tooth
    % period``. Two different points of one flank get no residual term (the contact search gives
    one contact per flank of a tooth pair; their mutual near field would need the half-plane
    terms the self table removes). The cells are found once per contact by the caller: looking
    them up here, per pair, made the MERCURY 1-A step twice as slow."""
    z = tabs.teeth
    d = (a.tooth - b.tooth) % z
    cls = b.tooth % tabs.period
    if d == 0 and a.side == b.side:
        if a.tooth == b.tooth and a.cell == b.cell and a.weight == b.weight:
            return _self_term(tabs.self_compliance, tabs.self_offset + (cls * 2 + a.side) * tabs.points, a.cell,
                              a.weight)
        return 0.0
    Jc = tabs.coarse
    o = tabs.coupling_offset + (((cls * 2 + a.side) * 2 + b.side) * z + d) * Jc * Jc
    return _coupling_term(tabs.coupling, o, Jc, a.coupling_cell, a.coupling_weight, b.coupling_cell, b.coupling_weight)


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
    condensed quasi-statically plus the residual tables; see :class:`flexgear.dynamics.model.tables.FlexTable`)."""
    J = flex.points[f]
    nq = flex.condensed[f]
    ro = flex.radius_offset[f]
    ji, wi = radius_cell(flex.radius, ro, J, ri)
    jj, wj = radius_cell(flex.radius, ro, J, rj)
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
    a = FlankPoint(ki, ia, ji, wi, ci, ui)
    b = FlankPoint(kj, ib, jj, wj, cj, uj)
    return c + flank_residual(residual_tables(flex, f), a, b)


@kernel(error_model="numpy", inline="always")
def modal_products(U, cnt, nq, D, kap, ko):
    """``D[i, j] = D[j, i] = sum_m U[i, m] kap[ko + m] U[j, m]`` over the first nq columns, i, j <
    cnt (``kap``: the modes' weights, 1 for quasi-static condensation, :mod:`flexgear.dynamics.flexible.condensed`).

    Each sum runs over m in the order of a plain dot product; four of them (j .. j + 3) advance
    together, so that the additions are independent rather than one chain of dependent ones
    (the same numbers, with more instruction-level parallelism). Rows and weights are read through views
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
def contact_compliance(flex, f, rows, cnt, D, kap, ko):
    """``D[i, j]`` = :func:`flank_influence` of body f between its contacts i, j < cnt (``rows``, a
    FlankContacts: teeth, sides, radii) [m/N], each condensed mode m weighted by ``kap[ko + m]``
    (1: quasi-static, as :func:`flank_influence`; :mod:`flexgear.dynamics.flexible.condensed`).

    The same numbers, with the work shared: each contact's table cells are found once (into
    ``rows``), its modal flank displacements are interpolated once (row i of ``rows.modes``, which
    needs at least ``flex.condensed[f]`` columns; with fewer, every pair calls
    :func:`flank_influence`), and the modal part, a dot product of rows, once per pair of
    contacts (it is symmetric).
    """
    nq = flex.condensed[f]
    U = rows.modes
    if U.shape[1] < nq:
        for i in range(cnt):
            for j in range(cnt):
                D[i, j] = flank_influence(flex, f, rows.tooth[i], rows.side[i], rows.radius[i], rows.tooth[j],
                                          rows.side[j], rows.radius[j])
        return
    flank_cells(flex, f, rows, cnt)
    modal_products(U, cnt, nq, D, kap, ko)
    tabs = residual_tables(flex, f)
    for j in range(cnt):
        b = contact_point(rows, j)
        for i in range(cnt):
            D[i, j] += residual_pair(tabs, contact_point(rows, i), b)


@kernel(error_model="numpy", inline="always")
def flank_cells(t, f, rows, cnt):
    """Per contact i < cnt on flexible body f (``rows``, a FlankContacts: tooth, side, radius) its
    flank table cell and weight, coupling-table cell and weight and its condensed modes' flank
    displacements A_m / omega_m (row i of ``rows.modes``, at least ``t.condensed[f]`` columns),
    interpolated in the radius, into ``rows``; ``t``: the FlexTable (or a table with its names)."""
    nq = t.condensed[f]
    J = t.points[f]
    ro = t.radius_offset[f]
    so = t.shape_offset[f]
    S = t.shape
    table_radius = t.radius
    stride = t.coupling_stride[f]
    tooth = rows.tooth
    side = rows.side
    radius = rows.radius
    U = rows.modes
    for i in range(cnt):
        ji, wi = radius_cell(table_radius, ro, J, radius[i])
        rows.cell[i] = ji
        rows.weight[i] = wi
        rows.coupling_cell[i], rows.coupling_weight[i] = _coarse_cell(table_radius, ro, J, stride, ji, wi)
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
def residual_pair(tabs, a, b):
    """:func:`flank_residual` between a displaced point ``a`` and a loaded one ``b`` (FlankPoints
    with teeth in 0 .. z - 1) of a body with the tables ``tabs`` (a ResidualTables) [m/N], its
    integer work cut down for the inner loops of the joint compliance."""
    d = a.tooth - b.tooth
    if d < 0:
        d += tabs.teeth
    cls = b.tooth % tabs.period
    if d == 0 and a.side == b.side:
        if a.cell == b.cell and a.weight == b.weight:
            return _self_term(tabs.self_compliance, tabs.self_offset + (cls * 2 + a.side) * tabs.points, a.cell,
                              a.weight)
        return 0.0
    Jc = tabs.coarse
    o = tabs.coupling_offset + (((cls * 2 + a.side) * 2 + b.side) * tabs.teeth + d) * Jc * Jc
    return _coupling_term(tabs.coupling, o, Jc, a.coupling_cell, a.coupling_weight, b.coupling_cell, b.coupling_weight)


@kernel(error_model="numpy", inline="always")
def rigid_coordinates(flex, n):
    """Number of rigid-body coordinates among the n of q: the index of the first modal
    coordinate (they follow every rigid one, and a coupled housing's follow them), n without
    any (a housing's coordinates then count among the rigid ones: no contact reaches them)."""
    nr = n
    for f in range(flex.modes.shape[0]):
        if flex.modes[f] > 0 and flex.coordinate[f] < nr:
            nr = flex.coordinate[f]
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
    j, w = radius_cell(flex.radius, flex.radius_offset[f], J, r)
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
