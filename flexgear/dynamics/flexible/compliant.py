"""Tooth contact on compliant flanks: line-contact Hertz plus the FE compliance of flexible gears.

For the meshes whose law is ``LAW_HERTZ`` (every mesh with a flexible gear, or a rigid mesh
given that law), the normal forces ``F_k`` of all their tooth-pair contacts k - the contacts
of every such mesh, stacked, in one problem - satisfy::

    delta_rigid_k = sum_l C_kl F_l + h_k(F_k)      for F_k > 0
    delta_rigid_k <= sum_l C_kl F_l                for F_k = 0

* ``delta_rigid_k`` - overlap of the rigid outlines at contact k in the bodies' frames (the
  penetration the contact search reports for the rigid model) [m];
* ``C_kl = sum over the flexible bodies B that carry both k and l of c^B_kl`` - static
  compliance of the flanks of body B at contact k per newton at contact l (:data:`FlexTable`
  of :mod:`flexgear.dynamics.model.tables`: the fixed-interface modes condensed quasi-statically, plus the residual
  tables between the two flanks, whatever their tooth distance and sides; the near field
  removed from the self term); zero for a rigid gear [m/N]. Contacts in different meshes of
  one body couple through its rim (the sun's teeth at the three planets, a planet's sun-side
  and ring-side teeth - opposite flanks of teeth about half a turn apart - the ring's teeth at
  the planets), and a tooth's two flanks couple through the tooth (back-flank contacts);
  contacts on different bodies never couple (the planets share their reduction, not their
  flanks);
* ``h_k(F)`` - 2D Hertz line-contact approach between points at the near-field reference
  depths of both gears (:func:`flexgear.stiffness.hertz.hertz_approach`, plane strain):
  the local part the FE tables leave out, so nothing is counted twice [m].

On MERCURY 1-A (level 1) the cross-mesh terms make the sun's flanks 6-8 % softer than its
meshes taken one by one. Modes plus tables are the static FE compliance at the table points
for every pair of flanks of a body (between teeth far apart the modes alone would misstate it:
sun teeth 120 deg apart 1.19 x, planet teeth half a turn apart 1.22-1.35 x, far teeth of a held
ring 0.5-0.8 % of the self compliance where FE gives ~1e-6), so the joint deflections follow
the static FE field of all of a body's loads at once up to the tables' linear interpolation in
the radius: over a run within 0.3 % on the sun meshes and 0.9 % on the planet-ring meshes
(``tests/test_cross_mesh.py``, ``tests/test_deformed.py``; with the far-tooth coupling from the
modes alone it was 1.9 % and 3.6 %). The tables come from the loaded tooth's class, so ``C``
is reciprocal up to the FE mesh's departure from cyclic symmetry (about 1e-4 of the self
compliance).

Modes kept as coordinates eta_i (:mod:`flexgear.dynamics.flexible.floating_frame`): ``delta_rigid_k`` is replaced by
``delta_rigid_k - sum_i A_i(k) eta_i`` over both gears (A_i: the mode's flank displacement
along the contact force on that flank, same radius interpolation as the tables); the
penetration-gradient row of the contact gets ``-A_i`` in the modal columns, so the consistent
tangent couples the modes; the modes receive the generalised force ``A_i F_k`` of the elastic
force (the work conjugate of their flank displacement; the damper below acts between the rigid
frames, as for condensed modes, so it dissipates and never feeds the modes).

The frames' acceleration loads the condensed modes as it loads modal coordinates: their
response, the flank's deflection under the gear's own inertia load (:func:`inertia_flank_value`,
the frame's acceleration from the integrator's Newton iterate), is subtracted from
``delta_rigid_k`` like the modal flank displacement; its derivative with q (through the step's
``d q''/dq``, :mod:`flexgear.dynamics.integrator.solver`) joins the tangent's columns. Quasi-statically condensed modes
respond statically; integrated ones (:mod:`flexgear.dynamics.flexible.condensed`, the default in the integrator) respond
with their own inertia within the step: each mode's term in ``C_kl`` is weighted by kappa_i,
their history adds to the flank displacement, and their reaction loads the frames. Outside the
integrator (statics, ``evaluate``) the condensation is quasi-static and the accelerations zero.

This is the loaded-mesh analysis of :func:`flexgear.stiffness.loaded_mesh.loaded_mesh` solved at
every force evaluation for the whole gear set at once (:func:`compliant_contacts`), on the
contacts the search finds (off the theoretical path too). The
IMPACT damping acts in parallel on the rigid approach: ``F_k += STEP(delta_rigid_k; 0, 0, d,
C) d(delta_rigid_k)/dt`` (a mesh damper across the whole tooth pair, as in lumped mesh
models), the total clipped at zero.

Solution: Newton's method on the active set (contacts with ``F_k > 0``), started from the
last evaluation's force of the same contact, or below the root for a contact without one (the
Hertz approach is concave in F, so the iterates approach the root from below, after at most
one iteration from above), with complementarity checks; the Jacobian ``C + diag(h')`` gives the consistent tangent
``dF/d delta_rigid = (C + diag(h'))^-1`` on the active set, which couples the contacts of
every compliant mesh that share a flexible body in the solver's tangent stiffness. Contacts
with no common body give exact zeros in it (and in the LU), which the assembly skips. Inside
the integrator's Newton iterations C is built only where the solve needs it
(:func:`solve_joint`: entries between active contacts, a contact's row when it joins, open
contacts' deflections from the modes' sums), with the same forces.
"""
from __future__ import annotations

import math

import numba as nb

from ...kernels import kernel
import numpy as np

from .condensed import INTEGRATED, condensed_coefficients, condensed_response, frame_acceleration
from ..contact.search import contact_load, mesh_search, penetration_gradient, step, step_derivative

LAW_IMPACT, LAW_HERTZ = 0, 1

#: Relative force tolerance of the contact solve (|dF| < FORCE_TOL max(F, 1 N)).
FORCE_TOL = 1e-11
#: Newton iterations of the contact solve per active set.
MAX_SOLVE = 60


@kernel(error_model="numpy")
def hertz_line(F, R, L, ka, na, da, kb, nb_, db, es):
    """2D Hertz line-contact approach between the reference depths and its derivative.

    ``h = P [ka (2 ln(2 da/a) - 1/2 - na) + kb (2 ln(2 db/a) - 1/2 - nb) + 1/(2 pi E*)]``,
    P = F / L, a = sqrt(4 P R / (pi E*)) (:func:`flexgear.stiffness.hertz.hertz_approach`).

    Parameters
    ----------
    F : float
        Normal force [N] (> 0).
    R : float
        Relative radius of curvature [m].
    L : float
        Contact length [m].
    ka, kb : float
        1 / (pi E1) of each body [1/Pa].
    na, nb_ : float
        nu1 of each body [-].
    da, db : float
        Reference depths [m].
    es : float
        Contact modulus E* [Pa].

    Returns
    -------
    h, dh/dF : float
        Approach [m] and compliance [m/N].
    """
    P = max(F, 1e-9) / L  # a force below 1 nN: evaluated at 1 nN (no log(0))
    a = math.sqrt(4.0 * P * R / (math.pi * es))
    la = math.log(2.0 * da / a)
    lb = math.log(2.0 * db / a)
    c0 = 1.0 / (2.0 * math.pi * es)
    h = P * (ka * (2.0 * la - 0.5 - na) + kb * (2.0 * lb - 0.5 - nb_) + c0)
    dh = (ka * (2.0 * la - 1.5 - na) + kb * (2.0 * lb - 1.5 - nb_) + c0) / L
    return h, dh


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


# reassociated sums (vectorised, in an order of the compiler's); a function of its own, so that
# the flags reach these loops only
@kernel(error_model="numpy", _nrt=False, fastmath={"reassoc", "contract"})
def modal_row(U, i, cols, nc, nq, kap, ko, out):
    """``out[p]`` = the modal part of :func:`modal_products` between contact i and contact
    ``cols[p]`` (p < nc, ``cols`` increasing): the pair (a, b), a <= b, sums ``(U[a, m] kap[ko +
    m]) U[b, m]`` over m, so that both entries of a pair get one value. Four columns advance
    together, rows and weights read through views (as in :func:`modal_products`), and the sums
    are reassociated, which lets the compiler vectorise them (MERCURY 1-A: the joint compliance
    entries of a step about 2x faster); they equal :func:`modal_products`' plain sums up to
    round-off (``tests/test_compliant_kernel.py``), which the integrator never compares."""
    Ui = U[i]
    kv = kap[ko:ko + nq]
    p = 0
    # columns below i: pair (j, i)
    while p + 3 < nc and cols[p + 3] < i:
        U0 = U[cols[p]]
        U1 = U[cols[p + 1]]
        U2 = U[cols[p + 2]]
        U3 = U[cols[p + 3]]
        c0 = 0.0
        c1 = 0.0
        c2 = 0.0
        c3 = 0.0
        for m in range(nq):
            u = Ui[m]
            k = kv[m]
            c0 += U0[m] * k * u
            c1 += U1[m] * k * u
            c2 += U2[m] * k * u
            c3 += U3[m] * k * u
        out[p] = c0
        out[p + 1] = c1
        out[p + 2] = c2
        out[p + 3] = c3
        p += 4
    while p < nc and cols[p] < i:
        Uj = U[cols[p]]
        c = 0.0
        for m in range(nq):
            c += Uj[m] * kv[m] * Ui[m]
        out[p] = c
        p += 1
    # columns from i on: pair (i, j)
    while p + 3 < nc:
        U0 = U[cols[p]]
        U1 = U[cols[p + 1]]
        U2 = U[cols[p + 2]]
        U3 = U[cols[p + 3]]
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
        out[p] = c0
        out[p + 1] = c1
        out[p + 2] = c2
        out[p + 3] = c3
        p += 4
    while p < nc:
        Uj = U[cols[p]]
        c = 0.0
        for m in range(nq):
            c += Ui[m] * kv[m] * Uj[m]
        out[p] = c
        p += 1


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


#: states of a contact's entries in the joint compliance (``ContactBuffers.compliance_known``)
UNKNOWN, KNOWN, FRESH = 0, 1, 2


@kernel(error_model="numpy", inline="always")
def extend_compliance(flex, f, nk, slot, tooth, side, cell, weight, ccell, cweight, U, kap, ko, known, C, cols, vals):
    """Add body f's flank compliance (:func:`contact_compliance`, the same numbers) to the joint
    compliance ``C`` between its contacts (local i < nk, stacked slot ``slot[i]``) whose entries
    are being added (``known[slot] == FRESH``) and those being added or already computed
    (``KNOWN``), both ways. ``cols`` (int) and ``vals`` (float) are work arrays of nk entries.
    Called body by body in the order of :func:`compliant_contacts`, so that each entry sums
    the bodies' parts in the same order. (:func:`extend_entries` into a body buffer, then
    :func:`add_entries`.)"""
    E = np.zeros((nk, nk))
    extend_entries(flex.condensed[f], flex.points[f], flex.coupling_stride[f], flex.teeth[f], flex.period[f],
                   flex.coupling_offset[f], flex.coupling, flex.self_compliance, flex.self_offset[f], nk, slot, tooth,
                   side, cell, weight, ccell, cweight, U, kap, ko, known, E, cols, vals)
    add_entries(nk, slot, known, E, C)


@kernel(error_model="numpy", inline="always")
def extend_entries(nq, J, stride, z, period, co, T, sc, sco, nk, slot, tooth, side, cell, weight, ccell, cweight, U,
                   kap, ko, known, E, cols, vals):
    """Body f's part of the entries that :func:`extend_compliance` adds, into ``E[i, j]`` (local
    indices i, j < nk; written only for the pairs being added, :func:`add_entries` adds them
    to the joint compliance), with body f's parts of the FlexTable as numbers and arrays: nq
    condensed modes, J table radii, coupling stride, z teeth, tooth period, coupling tables ``T``
    from ``co``, self tables ``sc`` from ``sco`` (every array of a table handed to a compiled
    function, inlined or not, costs a reference count per call). Writes nothing shared: the
    bodies can run in parallel threads (:func:`joint_entries`)."""
    Jc = (J - 1) // stride + 1
    for i in range(nk):
        si = slot[i]
        if known[si] != FRESH:
            continue
        nc = 0
        for j in range(nk):
            sj = slot[j]
            if known[sj] == KNOWN or (known[sj] == FRESH and j >= i):
                cols[nc] = j
                nc += 1
        modal_row(U, i, cols, nc, nq, kap, ko, vals)
        ki = tooth[i]
        ia = 0 if side[i] > 0 else 1
        for p in range(nc):
            j = cols[p]
            sj = slot[j]
            kj = tooth[j]
            ib = 0 if side[j] > 0 else 1
            E[i, j] = vals[p] + residual_pair(ki, ia, cell[i], weight[i], ccell[i], cweight[i], kj, ib, cell[j],
                                              weight[j], ccell[j], cweight[j], z, period, J, Jc, T, co, sc, sco)
            if j != i:
                E[j, i] = vals[p] + residual_pair(kj, ib, cell[j], weight[j], ccell[j], cweight[j], ki, ia,
                                                  cell[i], weight[i], ccell[i], cweight[i], z, period, J, Jc, T,
                                                  co, sc, sco)


@kernel(error_model="numpy", inline="always")
def add_entries(nk, slot, known, E, C):
    """Add a body's entries ``E`` (:func:`extend_entries`, local indices) to the joint
    compliance ``C`` (stacked slots ``slot``): the pairs between a contact being added
    (``FRESH``) and one being added after it or already computed (``KNOWN``), both ways.
    Called body by body in body order, so that each entry sums the bodies' parts in that order."""
    for i in range(nk):
        si = slot[i]
        if known[si] != FRESH:
            continue
        for j in range(nk):
            sj = slot[j]
            if known[sj] == KNOWN or (known[sj] == FRESH and j >= i):
                C[si, sj] += E[i, j]
                if j != i:
                    C[sj, si] += E[j, i]


@kernel(error_model="numpy", inline="always")
def open_deflection(flex, f, nk, slot, tooth, side, cell, weight, ccell, cweight, U, kap, ko, known, active, F, z_,
                    out):
    """Add body f's part of ``sum_l C_kl F_l`` (the active contacts' forces F) to ``out[k]`` for
    its contacts k whose entries are not computed (``known[k] == UNKNOWN``): the modal part as
    ``U_k . (kappa * U^T F)`` (O(modes) per contact instead of O(modes) per pair; equal to the
    entries' sum up to round-off), the residual part per active contact. ``z_`` is a work array
    of the body's condensed modes. (:func:`open_entries` into a body buffer, then
    :func:`add_open`.)"""
    P = np.zeros(nk)
    open_entries(flex.condensed[f], flex.points[f], flex.coupling_stride[f], flex.teeth[f], flex.period[f],
                 flex.coupling_offset[f], flex.coupling, flex.self_compliance, flex.self_offset[f], nk, slot, tooth, side,
                 cell, weight, ccell, cweight, U, kap, ko, known, active, F, z_, P)
    add_open(nk, slot, known, P, out)


@kernel(error_model="numpy", inline="always")
def open_entries(nq, J, stride, z, period, co, T, sc, sco, nk, slot, tooth, side, cell, weight, ccell, cweight, U, kap,
                 ko, known, active, F, z_, out):
    """Body f's part of :func:`open_deflection` into ``out[i]`` (local index i < nk, written for
    the contacts without entries; :func:`add_open` adds them to the stacked deflections), with
    body f's parts of the FlexTable as numbers and arrays (see :func:`extend_entries`). Writes
    nothing shared: the bodies can run in parallel threads (:func:`open_deflections`)."""
    Jc = (J - 1) // stride + 1
    kv = kap[ko:ko + nq]  # (rows and weights through views indexed by the loop counter, see modal_products)
    for m in range(nq):
        z_[m] = 0.0
    for j in range(nk):
        sj = slot[j]
        if active[sj]:
            Fj = F[sj]
            Uj = U[j]
            for m in range(nq):
                z_[m] += Uj[m] * Fj
    for m in range(nq):
        z_[m] *= kv[m]
    # the modal parts U_i . z of the contacts without entries (into out), then their residual parts
    open_modal(U, known, slot, nk, nq, z_, out)
    for i in range(nk):
        if known[slot[i]] == UNKNOWN:
            open_residual(nk, slot, tooth, side, cell, weight, ccell, cweight, active, F, i, out[i], z, period, J, Jc,
                          T, co, sc, sco, out)


# reassociated sums (vectorised, in an order of the compiler's); a function of its own, so that
# the flags reach these loops only
@kernel(error_model="numpy", _nrt=False, fastmath={"reassoc", "contract"})
def open_modal(U, known, slot, nk, nq, z_, out):
    """``out[i] = U_i . z_`` over the nq modes for the contacts i < nk (stacked slots ``slot``)
    whose entries are not computed (``known == UNKNOWN``): the modal part of their deflection
    (:func:`open_entries`). Four contacts advance together; the sums are reassociated, which
    lets the compiler vectorise them: they equal the plain sums up to round-off."""
    i0 = next_unknown(known, slot, nk, 0)
    while i0 < nk:
        i1 = next_unknown(known, slot, nk, i0 + 1)
        i2 = next_unknown(known, slot, nk, i1 + 1)
        i3 = next_unknown(known, slot, nk, i2 + 1)
        if i3 < nk:
            U0 = U[i0]
            U1 = U[i1]
            U2 = U[i2]
            U3 = U[i3]
            g0 = 0.0
            g1 = 0.0
            g2 = 0.0
            g3 = 0.0
            for m in range(nq):
                zm = z_[m]
                g0 += U0[m] * zm
                g1 += U1[m] * zm
                g2 += U2[m] * zm
                g3 += U3[m] * zm
            out[i0] = g0
            out[i1] = g1
            out[i2] = g2
            out[i3] = g3
            i0 = next_unknown(known, slot, nk, i3 + 1)
        else:
            U0 = U[i0]
            g0 = 0.0
            for m in range(nq):
                g0 += U0[m] * z_[m]
            out[i0] = g0
            i0 = i1


@kernel(error_model="numpy", inline="always")
def next_unknown(known, slot, nk, i):
    """The first local contact from i on (of nk; stacked slots ``slot``) whose entries are not
    computed (``known == UNKNOWN``); nk if none."""
    while i < nk and known[slot[i]] != UNKNOWN:
        i += 1
    return i


@kernel(error_model="numpy", inline="always")
def open_residual(nk, slot, tooth, side, cell, weight, ccell, cweight, active, F, i, g, z, period, J, Jc, T, co, sc,
                  sco, out):
    """Add the residual part of contact i's deflection under the active contacts' forces F to its
    modal part g; the sum into ``out[i]`` (:func:`open_entries`)."""
    ki = tooth[i]
    ia = 0 if side[i] > 0 else 1
    for j in range(nk):
        sj = slot[j]
        if not active[sj]:
            continue
        g += residual_pair(ki, ia, cell[i], weight[i], ccell[i], cweight[i], tooth[j], 0 if side[j] > 0 else 1,
                           cell[j], weight[j], ccell[j], cweight[j], z, period, J, Jc, T, co, sc, sco) * F[sj]
    out[i] = g


@kernel(error_model="numpy", inline="always")
def add_open(nk, slot, known, P, out):
    """Add a body's parts ``P`` (:func:`open_entries`, local indices) of the deflections of its
    contacts without entries (``UNKNOWN``) to ``out`` (stacked slots ``slot``); called body by
    body in body order."""
    for i in range(nk):
        if known[slot[i]] == UNKNOWN:
            out[slot[i]] += P[i]


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


@kernel(error_model="numpy", _nrt=False)
def relief_reciprocity(G, c, u, slope, Mq):
    """Make the mass coupling of the inertia relief reciprocal: add to Mq the antisymmetric part
    that turns contact c's share ``X_c = G_c (x) u / slope`` into ``(X_c + X_c^T) / 2``; u is
    ``sum_q Kc[c, q] H[q]`` (the contact's row of dF/dq through the relief, summed with the
    tangent row in :func:`compliant_contacts`).

    Through :func:`inertia_flank_value` the contact forces depend on the accelerations, which is
    a mass ``X = G^T Kc R`` (R: the flank displacement per unit acceleration, ``H / slope``); it
    is not symmetric between bodies (gear A's flank relief against gear B's acceleration), and
    an unsymmetric mass splits a pair of equal frequencies into a growing and a decaying
    oscillation (MERCURY 1-A flexible, level 1, 5 % damping: pairs at 6.8 and 16.2 kHz, growth
    time 3.4 ms, seen as a 16 kHz oscillation building up at steps of 3 us and below). Its
    symmetric part keeps every mode's Rayleigh quotient (the frequencies, to first order) and the
    contact forces, and conserves energy."""
    n = u.shape[0]
    for r in range(n):
        gr = G[c, r]
        if gr == 0.0:
            continue
        for s in range(n):
            x = 0.5 * gr * (u[s] / slope)
            if x != 0.0:
                Mq[r, s] -= x
                Mq[s, r] += x


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


@kernel(error_model="numpy", _nrt=False)
def lu_factor(A, piv, n):
    """LU factorisation with partial pivoting of the leading n x n block of A, in place
    (``P A = L U``: unit L below the diagonal, U on and above it; row k was swapped with row
    ``piv[k]``). For the few contacts of a gear set (up to MAX_CONTACTS per compliant mesh, about
    a dozen in use) this loop is several times faster than a LAPACK call through numba, which
    copies and checks its arguments.

    Returns
    -------
    bool
        False if a pivot is exactly zero (the matrix is singular).
    """
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                p = i
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
        d = A[k, k]
        for i in range(k + 1, n):
            f = A[i, k] / d
            A[i, k] = f
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    return True


@kernel(error_model="numpy", _nrt=False)
def lu_solve(A, piv, b, n):
    """Solve ``A x = b`` in place (b becomes x) with the factors of :func:`lu_factor`."""
    for k in range(n):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= A[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= A[i, j] * b[j]
        b[i] = s / A[i, i]


@kernel(error_model="numpy", _nrt=False)
def lu_inverse(A, piv, X, n):
    """The inverse of the matrix factorised by :func:`lu_factor` into the leading n x n block of
    X: column q is :func:`lu_solve` of the unit vector e_q, with the same operations in the
    same order for every column, the columns advancing together (independent additions
    instead of one chain per column)."""
    for p in range(n):
        for q in range(n):
            X[p, q] = 0.0
        X[p, p] = 1.0
    for k in range(n):
        p = piv[k]
        if p != k:
            for q in range(n):
                X[k, q], X[p, q] = X[p, q], X[k, q]
    for i in range(n):
        for j in range(i):
            a = A[i, j]
            for q in range(n):
                X[i, q] -= a * X[j, q]
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            a = A[i, j]
            for q in range(n):
                X[i, q] -= a * X[j, q]
        d = A[i, i]
        for q in range(n):
            X[i, q] = X[i, q] / d


@kernel(error_model="numpy")
def solve_contacts(C, dr, hp, F, active, cnt):
    """:func:`solve_contacts_into` with its own work arrays (for tests and single calls)."""
    mc = C.shape[0]
    return solve_contacts_into(C, dr, hp, F, active, cnt, np.zeros((mc, mc)), np.zeros(mc), np.zeros(mc, np.int64),
                               np.zeros(mc, np.int64))


@kernel(error_model="numpy", inline="always")
def active_set(active, cnt, idx):
    """The contacts of the active set in increasing order into ``idx``; returns their number."""
    na = 0
    for i in range(cnt):
        if active[i]:
            idx[na] = i
            na += 1
    return na


@kernel(error_model="numpy", _nrt=False)
def solve_contacts_into(C, dr, hp, F, active, cnt, A, rhs, piv, idx):
    """Forces of the compliant contact problem (see the module docstring).

    Each Newton step solves on the active set alone (``na`` rows, in stacked order): the same
    arithmetic as the full ``cnt`` x ``cnt`` system with identity rows for the inactive
    contacts (their rows and columns are zero off the diagonal, so partial pivoting never
    picks them and elimination never touches them), at (na / cnt)^3 of its cost.

    Parameters
    ----------
    C : (MAXC, MAXC) array
        Flank compliance [m/N] (MAXC: any number of slots >= cnt).
    dr : (MAXC,) array
        Rigid overlaps [m].
    hp : (MAXC, 10) array
        Hertz parameters per contact: R, L, ka, na, da, kb, nb, db, E* (:func:`hertz_line`).
    F : (MAXC,) array
        Out: forces [N].
    active : (MAXC,) bool array
        Out: contacts in the active set.
    cnt : int
        Number of contacts.
    A : (MAXC, MAXC) array, rhs : (MAXC,) array, piv : (MAXC,) int array, idx : (MAXC,) int array
        Work arrays: Newton matrix on the active set (factorised in place), residual and step,
        pivots, the active contacts.

    Returns
    -------
    int
        Newton iterations (negative if the solve did not converge; the forces are NaN if the
        Newton matrix was singular).
    """
    for i in range(cnt):
        F[i] = 0.0
        active[i] = dr[i] > 0.0
    total = 0
    for _round in range(2 * cnt + 2):
        status, total = newton_active(C, dr, hp, F, active, cnt, A, rhs, piv, idx, total)
        if status < 0:
            return -total
        if status == DROPPED:
            continue
        # complementarity: an inactive contact whose flank is pushed into its mate joins
        joined = False
        for i in range(cnt):
            if active[i]:
                continue
            gap = dr[i]
            for j in range(cnt):
                if active[j]:
                    gap -= C[i, j] * F[j]
            if gap > 0.0:
                active[i] = True
                F[i] = 0.0
                joined = True
        if not joined:
            return total
    return -total


#: outcomes of :func:`newton_active`
CONVERGED, DROPPED, STALLED, SINGULAR = 0, 1, -1, -2


@kernel(error_model="numpy", _nrt=False)
def newton_active(C, dr, hp, F, active, cnt, A, rhs, piv, idx, total):
    """One round of :func:`solve_contacts_into`: Newton's method on the active set, from the
    forces in ``F`` (:func:`solve_joint`: the last evaluation's, near the root) and started
    below the root for the contacts without one (F <= 0: they just joined), until it converges
    or a contact's force drops to zero (that contact leaves the active set). The Hertz approach
    is concave in F, so an iteration from above the root lands below it and the iterates then
    approach it from below. Only the entries of C between active contacts are read.

    Returns
    -------
    status : int
        CONVERGED, DROPPED, STALLED (no convergence in MAX_SOLVE iterations) or SINGULAR (the
        Newton matrix; the forces set to NaN).
    total : int
        ``total`` plus the Newton iterations of the round.
    """
    # start below the root: the tangent at 1 N overestimates the Hertz compliance... of a
    # concave approach, so F0 = delta / (C_ii + h'(1 N)) lies under the solution
    for i in range(cnt):
        if active[i] and F[i] <= 0.0:
            _, d1 = hertz_line(1.0, hp[i, 0], hp[i, 1], hp[i, 2], hp[i, 3], hp[i, 4], hp[i, 5], hp[i, 6],
                               hp[i, 7], hp[i, 8])
            F[i] = max(dr[i], 1e-12) / (C[i, i] + d1)
    na = active_set(active, cnt, idx)
    for _it in range(MAX_SOLVE):
        total += 1
        fmax = 1.0
        for p in range(na):
            if F[idx[p]] > fmax:
                fmax = F[idx[p]]
        for p in range(na):
            i = idx[p]
            h, dh = hertz_line(F[i], hp[i, 0], hp[i, 1], hp[i, 2], hp[i, 3], hp[i, 4], hp[i, 5], hp[i, 6],
                               hp[i, 7], hp[i, 8])
            r = dr[i] - h
            for q in range(na):
                j = idx[q]
                r -= C[i, j] * F[j]
                A[p, q] = C[i, j]
            A[p, p] += dh
            rhs[p] = r
        if not lu_factor(A, piv, na):
            for i in range(cnt):
                F[i] = np.nan
            return SINGULAR, total
        lu_solve(A, piv, rhs, na)
        dF = rhs
        big = 0.0
        dropped = False
        for p in range(na):
            i = idx[p]
            F[i] += dF[p]
            if abs(dF[p]) > big:
                big = abs(dF[p])
            if F[i] <= 0.0:
                F[i] = 0.0
                active[i] = False
                dropped = True
        if dropped:
            return DROPPED, total
        if big < FORCE_TOL * fmax:
            return CONVERGED, total
    return STALLED, total


@kernel(error_model="numpy", inline="always")
def solve_joint(C, dr, hp, F, active, cnt, A, rhs, piv, idx, full, flex, body_flex, contacts, kap):
    """:func:`solve_contacts_into` on the stacked contacts of :func:`compliant_contacts` with
    the joint compliance C built as the solve needs it (the same forces up to round-off).

    With ``full`` every entry of C is computed first. Otherwise (inside the integrator's
    Newton iterations, where it is the cost that grows with the condensed modes: nk^2 nq / 2 per
    body) C starts with the entries between the contacts that start active (positive overlap)
    and gains a contact's row and column when it joins (:func:`extend_compliance`; about a dozen
    of MERCURY 1-A's 27 stacked contacts are active, the rest are back flanks and approaching
    teeth); the complementarity check of a contact without computed entries takes its flank
    deflection ``sum_l C_kl F_l`` from :func:`open_deflection` (O(modes) per contact), which is
    left in ``contacts.coupled_deflection`` for the records. ``contacts.compliance_known``
    says which contacts have their entries (KNOWN) at the end.

    Returns
    -------
    int
        As :func:`solve_contacts_into`.
    """
    known = contacts.compliance_known
    # the tables' parts as plain arrays, once (a table handed to a helper costs a reference
    # count per array and call)
    count = contacts.body_count
    slot = contacts.body_slot
    tooth = contacts.body_tooth
    side = contacts.body_side
    cell = contacts.flank_cell
    weight = contacts.flank_weight
    ccell = contacts.coupling_cell
    cweight = contacts.coupling_weight
    U = contacts.flank_modes
    Z = contacts.body_modal_work
    P = contacts.body_open
    E = contacts.body_entries
    bcols = contacts.body_cols
    bvals = contacts.body_vals
    group = contacts.body_group
    cd = contacts.coupled_deflection
    nq = flex.condensed
    J = flex.points
    stride = flex.coupling_stride
    z = flex.teeth
    period = flex.period
    co = flex.coupling_offset
    T = flex.coupling
    sc = flex.self_compliance
    sco = flex.self_offset
    qo = flex.condensed_offset
    start = contacts.start_force
    for i in range(cnt):
        active[i] = dr[i] > 0.0
        # started from the last evaluation's force of the same contact (compliant_contacts; the
        # forces change little from one evaluation to the next: about half the Newton
        # iterations), else from below the root (newton_active)
        F[i] = start[i] if active[i] else 0.0
        known[i] = UNKNOWN
    # the bodies' parts of C and of the open deflections in up to contacts.threads parallel groups
    ng = body_groups(body_flex, count, nq, contacts.threads[0], group, contacts.group_load)
    total = 0
    result = 0
    done = False
    for _round in range(2 * cnt + 2):
        fresh = False
        for i in range(cnt):
            if known[i] == UNKNOWN and (full or active[i]):
                known[i] = FRESH
                fresh = True
        if fresh:
            joint_entries(body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z, period,
                          co, T, sc, sco, qo, kap, known, C, E, bcols, bvals, ng, group)
            for i in range(cnt):
                if known[i] == FRESH:
                    known[i] = KNOWN
        status, total = newton_active(C, dr, hp, F, active, cnt, A, rhs, piv, idx, total)
        if status < 0:
            result = -total
            break
        if status == DROPPED:
            continue
        # complementarity: an inactive contact whose flank is pushed into its mate joins
        open_deflections(body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z, period,
                         co, T, sc, sco, qo, kap, known, active, F, cnt, Z, P, cd, ng, group)
        joined = False
        for i in range(cnt):
            if active[i]:
                continue
            gap = dr[i]
            if known[i] == KNOWN:
                for j in range(cnt):
                    if active[j]:
                        gap -= C[i, j] * F[j]
            else:
                gap -= cd[i]
            if gap > 0.0:
                active[i] = True
                F[i] = 0.0
                joined = True
        if not joined:
            result = total
            done = True
            break
    if not done:
        if result == 0:
            result = -total
        open_deflections(body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z, period,
                         co, T, sc, sco, qo, kap, known, active, F, cnt, Z, P, cd, ng, group)
    return result


@kernel(error_model="numpy", inline="always")
def body_groups(body_flex, count, nq, threads, group, load):
    """Share the flexible bodies with contacts among at most ``threads`` groups of about equal
    work (largest first, each to the least loaded group; work ~ (modes + 8) x contacts):
    ``group[f]`` for FlexTable row f (-1: no contacts), ``load`` a work array of nf entries.
    Returns the number of groups (1: all in group 0, run in this thread)."""
    nf = group.shape[0]
    busy = 0
    for f in range(nf):
        group[f] = -1
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f >= 0 and count[f] > 0:
            busy += 1
    ng = min(threads, busy)
    if ng <= 1:
        for f in range(nf):
            group[f] = 0
        return 1
    for g in range(ng):
        load[g] = 0.0
    for _ in range(busy):
        best = -1
        bw = -1.0
        for f in range(nf):
            if group[f] < 0 and count[f] > 0:
                w = (nq[f] + 8.0) * count[f]
                if w > bw:
                    bw = w
                    best = f
        g0 = 0
        for g in range(1, ng):
            if load[g] < load[g0]:
                g0 = g
        group[best] = g0
        load[g0] += bw
    return ng


# the per-body tasks: functions of their own, called from the parallel loops (stores into the
# arrays of a tuple handed to a prange body were lost with numba 0.68; see search_task)
@kernel(error_model="numpy", _nrt=False)
def entries_task(g, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z,
                 period, co, T, sc, sco, qo, kap, known, E, cols, vals):
    """:func:`extend_entries` of the bodies of group g into their own buffers ``E[f]`` (work
    arrays ``cols[f]``, ``vals[f]``)."""
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f < 0 or group[f] != g:
            continue
        nk = count[f]
        if nk == 0:
            continue
        extend_entries(nq[f], J[f], stride[f], z[f], period[f], co[f], T, sc, sco[f], nk, slot[f], tooth[f], side[f],
                       cell[f], weight[f], ccell[f], cweight[f], U[f], kap, qo[f], known, E[f], cols[f], vals[f])


@kernel(error_model="numpy", parallel=True)
def entries_parallel(ng, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride,
                     z, period, co, T, sc, sco, qo, kap, known, E, cols, vals):
    """:func:`entries_task` of the ng groups in parallel threads (each writes only its bodies' rows)."""
    for g in nb.prange(ng):
        entries_task(g, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z,
                     period, co, T, sc, sco, qo, kap, known, E, cols, vals)


@kernel(error_model="numpy", _nrt=False)
def open_task(g, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z, period,
              co, T, sc, sco, qo, kap, known, active, F, Z, P):
    """:func:`open_entries` of the bodies of group g into their own buffers ``P[f]`` (work array
    ``Z[f]``)."""
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f < 0 or group[f] != g:
            continue
        nk = count[f]
        if nk == 0:
            continue
        open_entries(nq[f], J[f], stride[f], z[f], period[f], co[f], T, sc, sco[f], nk, slot[f], tooth[f], side[f],
                     cell[f], weight[f], ccell[f], cweight[f], U[f], kap, qo[f], known, active, F, Z[f], P[f])


@kernel(error_model="numpy", parallel=True)
def open_parallel(ng, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z,
                  period, co, T, sc, sco, qo, kap, known, active, F, Z, P):
    """:func:`open_task` of the ng groups in parallel threads (each writes only its bodies' rows)."""
    for g in nb.prange(ng):
        open_task(g, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z,
                  period, co, T, sc, sco, qo, kap, known, active, F, Z, P)


@kernel(error_model="numpy", inline="always")
def joint_entries(body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z, period, co, T,
                  sc, sco, qo, kap, known, C, E, cols, vals, ng, group):
    """:func:`extend_compliance` of every flexible body, from the parts of the ContactBuffers
    (``count``: body_count, ``slot``: body_slot, ... ``U``: flank_modes; ``E``, ``cols``,
    ``vals``: body_entries, body_cols, body_vals) and of the FlexTable (``nq``: condensed,
    ``J``: points, ``stride``: coupling_stride, ``z``: teeth, ``period``, ``co``:
    coupling_offset, ``T``: coupling, ``sc``: self_compliance, ``sco``: self_offset, ``qo``:
    condensed_offset) that :func:`solve_joint` reads once. Each body's part into its own buffer,
    the ng groups of bodies (:func:`body_groups`) in parallel threads if ng > 1; then the parts
    added to C in body order (the same numbers with any number of threads)."""
    if ng > 1:
        entries_parallel(ng, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride,
                         z, period, co, T, sc, sco, qo, kap, known, E, cols, vals)
    else:
        entries_task(0, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z,
                     period, co, T, sc, sco, qo, kap, known, E, cols, vals)
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f >= 0 and count[f] > 0:
            add_entries(count[f], slot[f], known, E[f], C)


@kernel(error_model="numpy", inline="always")
def open_deflections(body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z, period, co,
                     T, sc, sco, qo, kap, known, active, F, cnt, Z, P, cd, ng, group):
    """``cd[k] = sum_l C_kl F_l`` (``contacts.coupled_deflection``) for the contacts k < cnt
    without computed entries (:func:`open_deflection` of every flexible body; the arguments as
    :func:`joint_entries`, ``Z``, ``P``: contacts.body_modal_work, body_open): each body's part
    into its own buffer, the groups in parallel threads if ng > 1, then added in body order."""
    for i in range(cnt):
        cd[i] = 0.0
    if ng > 1:
        open_parallel(ng, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z,
                      period, co, T, sc, sco, qo, kap, known, active, F, Z, P)
    else:
        open_task(0, group, body_flex, count, slot, tooth, side, cell, weight, ccell, cweight, U, nq, J, stride, z,
                  period, co, T, sc, sco, qo, kap, known, active, F, Z, P)
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f >= 0 and count[f] > 0:
            add_open(count[f], slot[f], known, P[f], cd)


@kernel(error_model="numpy", inline="always")
def body_contacts(body_a, body_b, body, jm, ji, side_a, side_b, rad_a, rad_b, N, slot, tooth, bside, brad):
    """The stacked contacts (of N) on body ``body``: their slots, tooth, flank side and radius on
    that body, in stacked order; returns their number (``body_a``, ``body_b``: the meshes'
    bodies, :class:`flexgear.dynamics.model.tables.MeshTable`)."""
    nk = 0
    for k in range(N):
        m = jm[k]
        if body_a[m] == body:
            slot[nk] = k
            tooth[nk] = ji[k, 0]
            bside[nk] = side_a[k]
            brad[nk] = rad_a[k]
            nk += 1
        elif body_b[m] == body:
            slot[nk] = k
            tooth[nk] = ji[k, 1]
            bside[nk] = side_b[k]
            brad[nk] = rad_b[k]
            nk += 1
    return nk


@kernel(error_model="numpy", _nrt=False)
def search_task(m, pose, body_a, body_b, gear_a, gear_b, internal, ncand_a, ncand_b, stride, gap, contact, local,
                found_f, found_i, hits, cache, ncache):
    """Contact search of mesh m (:func:`~flexgear.dynamics.contact.search.mesh_search`) into its own rows: ``found_f[m]``,
    ``found_i[m]``, the count in ``hits[m]``, its search cache ``cache[m]``, ``ncache[m]``
    (the ContactBuffers' ``search_f``, ``search_i``, ``search_hits``, ``search_cache``,
    ``search_count``; the mesh's parts of the MeshTable as arrays).

    A function of its own, called from the parallel loop of :func:`search_parallel`: stores into
    the arrays of a tuple handed to a ``prange`` body were lost (numba 0.68), and a loop handed
    the whole ContactBuffers took tens of seconds more to compile."""
    a = body_a[m]
    b = body_b[m]
    hits[m] = mesh_search(pose[a], pose[b], gear_a[m], gear_b[m], internal[m], contact, ncand_a[m], ncand_b[m],
                          stride[m], found_f[m], found_i[m], local, cache[m], ncache[m], gap[m])


@kernel(error_model="numpy", parallel=True)
def search_parallel(order, ns, pose, body_a, body_b, gear_a, gear_b, internal, ncand_a, ncand_b, stride, gap, contact,
                    local, found_f, found_i, hits, cache, ncache):
    """:func:`search_task` of the meshes ``order[:ns]`` in parallel threads (each writes only its
    mesh's rows)."""
    for p in nb.prange(ns):
        search_task(order[p], pose, body_a, body_b, gear_a, gear_b, internal, ncand_a, ncand_b, stride, gap, contact,
                    local, found_f, found_i, hits, cache, ncache)


@kernel(error_model="numpy", _nrt=False)
def body_rows_task(body, body_flex, N, body_a, body_b, jm, ji, side_a, side_b, rad_a, rad_b, body_slot, body_tooth,
                   body_side, body_radius, body_count, condensed, points, radius_offset, shape_offset, f_shape,
                   f_radius, coupling_stride, condensed_offset, flank_cell, flank_weight, coupling_cell,
                   coupling_weight, flank_modes, pose, Jb, acc, gam, vel, iw, hist, relief):
    """Phase 2 of :func:`compliant_contacts` for one body, up to its shared stores: its stacked
    contacts (:func:`body_contacts`, count in ``body_count[f]``), their table cells and modal
    rows (:func:`flank_cells`) and per contact ``relief[f, i]`` = the frame-inertia weights
    (tx, ty, tr) and the decrease of the overlap by the condensed modes' history and the
    frame's inertia load (:func:`inertia_flank_value`); row f = ``body_flex[body]``
    (nothing for a rigid body). Writes only row f of its outputs: the overlaps and gradient
    rows, which a contact's two bodies share, are changed afterwards in body order
    (:func:`inertia_rows`). The arguments are the ContactBuffers' and FlexTable's arrays of the
    same names (``Jb``: the pose Jacobians, ``iw``, ``hist``: the CondensedState's
    ``inertia_weight``, ``history``)."""
    f = body_flex[body]
    if f < 0:
        return
    slot = body_slot[f]
    tooth = body_tooth[f]
    bside = body_side[f]
    brad = body_radius[f]
    nk = body_contacts(body_a, body_b, body, jm, ji, side_a, side_b, rad_a, rad_b, N, slot, tooth, bside, brad)
    body_count[f] = nk
    if nk == 0:
        return
    U = flank_modes[f]
    nq = condensed[f]
    co = condensed_offset[f]
    rel = relief[f]
    # the contacts' cells and modal rows; their compliance entries in the contact solve
    flank_cells(nq, points[f], radius_offset[f], shape_offset[f], f_shape, f_radius, coupling_stride[f], tooth, bside,
                brad, nk, flank_cell[f], flank_weight[f], coupling_cell[f], coupling_weight[f], U)
    cs = math.cos(pose[body, 2])
    sn = math.sin(pose[body, 2])
    ax, ay, ar = frame_acceleration(Jb, acc, gam, body)
    # per contact the sums over the modes of its flank row times the frame-inertia weights and
    # the history (views of the body's modes: contiguous vectors)
    relief_sums(U, nk, nq, iw[3 * co:3 * co + nq], iw[3 * co + nq:3 * co + 2 * nq], iw[3 * co + 2 * nq:3 * co + 3 * nq],
                hist[co:co + nq], rel)
    for i in range(nk):
        rel[i, 3] += inertia_flank_value(rel[i, 0], rel[i, 1], rel[i, 2], cs, sn, ax, ay, ar, vel, body)


# reassociated sums (vectorised, in an order of the compiler's: the last digits differ from a
# plain dot product's); a function of its own, so that the flag reaches these loops only
@kernel(error_model="numpy", _nrt=False, fastmath={"reassoc", "contract"})
def relief_sums(U, nk, nq, wx, wy, wr, hv, rel):
    """``rel[i, 0:4]`` = the sums over the nq modes of contact i's flank row ``U[i]`` times the
    frame-inertia weights ``wx``, ``wy``, ``wr`` and the history ``hv`` (views of the body's
    modes), for the nk contacts of a body (:func:`body_rows_task`). The sums are reassociated,
    so the compiler vectorises them (on MERCURY 1-A 1.1 instead of 3.1 us per evaluation); they
    have no other evaluation that they would have to equal bit for bit."""
    for i in range(nk):
        Ui = U[i]
        tx = 0.0
        ty = 0.0
        tr = 0.0
        uh = 0.0
        for m in range(nq):
            u = Ui[m]
            tx += u * wx[m]
            ty += u * wy[m]
            tr += u * wr[m]
            uh += u * hv[m]
        rel[i, 0] = tx
        rel[i, 1] = ty
        rel[i, 2] = tr
        rel[i, 3] = uh


@kernel(error_model="numpy", parallel=True)
def body_rows_parallel(body_flex, N, body_a, body_b, jm, ji, side_a, side_b, rad_a, rad_b, body_slot, body_tooth,
                       body_side, body_radius, body_count, condensed, points, radius_offset, shape_offset, f_shape,
                       f_radius, coupling_stride, condensed_offset, flank_cell, flank_weight, coupling_cell,
                       coupling_weight, flank_modes, pose, Jb, acc, gam, vel, iw, hist, relief):
    """:func:`body_rows_task` of every body in parallel threads (each writes only its FlexTable
    row's rows; the bodies' rows are distinct, ``body_flex`` maps a body to its own row)."""
    for body in nb.prange(body_flex.shape[0]):
        body_rows_task(body, body_flex, N, body_a, body_b, jm, ji, side_a, side_b, rad_a, rad_b, body_slot, body_tooth,
                       body_side, body_radius, body_count, condensed, points, radius_offset, shape_offset, f_shape,
                       f_radius, coupling_stride, condensed_offset, flank_cell, flank_weight, coupling_cell,
                       coupling_weight, flank_modes, pose, Jb, acc, gam, vel, iw, hist, relief)


@kernel(error_model="numpy", inline="always")
def inertia_flank_value(tx, ty, tr, cs, sn, ax, ay, ar, vel, body):
    """Normal displacement of a flank point of flexible body ``body`` due to the inertia load of
    its frame's acceleration on the condensed modes [m] (positive opens the contact).

    A condensed mode i responds to everything that loads it: the contact forces (the
    compliance :func:`flank_influence`) and, as a modal coordinate does (:mod:`flexgear.dynamics.flexible.floating_frame`),
    the frame's acceleration and turning, ``l_i = -S_i . R^T a_frame + theta' S_i . R^T E^T
    v_frame`` with ``a_frame = J_body q'' + gamma``. Its flank displacement per unit of that load
    is ``(tx, ty, tr) = sum_i (A_i / omega_i) S_i w_i`` at the point (body frame), with w_i = 1 /
    omega_i for quasi-static condensation (the flank's deflection under the gear's own inertia
    load, a rim lagging its hub) and kappa_i / ((1 + alpha) omega_i) for modes integrated in the
    contact solve (:mod:`flexgear.dynamics.flexible.condensed`). Left out, a free pinion's body compliance would act as if
    its hub carried the whole inertia (on the spur pair, level 1, 5 % damping, 25 us: force RMS
    about the mean 5.7 % below the full-order FE; with it within 1 %, ``tests/test_full_order.py``).

    Its derivative with q, ``+d(-u)/dq = slope * T_g . J_body`` (slope = d q'' / dq of the
    integrator's step), goes to the contact's row of H in :func:`inertia_rows`. ``tx, ty, tr``:
    the flank displacement per unit frame acceleration x, y, theta (body frame) [m s^2, m s^2 /
    rad]; ``cs, sn``: the body's angle; ``ax, ay, ar``: the frame's acceleration
    (:func:`frame_acceleration`); ``vel``: body velocities (nb, 3)."""
    if tx == 0.0 and ty == 0.0 and tr == 0.0:
        return 0.0
    gx = cs * tx - sn * ty
    gy = sn * tx + cs * ty
    return -(gx * ax + gy * ay + tr * ar) + vel[body, 2] * (-gx * vel[body, 1] + gy * vel[body, 0])


@kernel(error_model="numpy", inline="always")
def inertia_rows(tx, ty, tr, cs, sn, Jb, body, slope, H, k):
    """The gradient rows of :func:`inertia_flank_value`: adds ``slope * T_g . J_body`` to row k of H."""
    if tx == 0.0 and ty == 0.0 and tr == 0.0:
        return
    gx = cs * tx - sn * ty
    gy = sn * tx + cs * ty
    if slope != 0.0:
        for c in range(H.shape[1]):
            H[k, c] += slope * (gx * Jb[body, 0, c] + gy * Jb[body, 1, c] + tr * Jb[body, 2, c])


@kernel(error_model="numpy", _nrt=False)
def compliant_contacts(meshes, flex, body_flex, contact, state, system, contacts, cst, local):
    """Contacts of every mesh with the compliant Hertz law, solved as one contact problem:
    forces, body loads, tangent matrices.

    ``flex`` is the FlexTable, ``body_flex`` the bodies' rows in it (-1: rigid); ``state``,
    ``system``, ``contacts``, ``cst`` the parts of the Workspace. Three phases:

    1. every ``LAW_HERTZ`` mesh: contact search, and per contact the rigid overlap less the
       modal flank displacement, its rate, the Hertz parameters, the flank (tooth, side,
       radius) on each gear and the penetration-gradient row, in stacked slots;
    2. ``C_kl``: for every flexible body, the flank compliance between all stacked contacts
       on it, whatever their mesh (a body's meshes couple through its rim; contacts on
       different bodies, e.g. two planets, do not), and the condensed modes' flank displacement
       under the frame's inertia load and, integrated, their history (:mod:`flexgear.dynamics.flexible.condensed`); one
       joint solve of the contact problem (:func:`solve_joint`: inside the integrator's Newton
       iterations only the entries of C between contacts that are or become active) and its
       tangent ``(C + diag h')^-1`` on the joint active set; the condensed modes' response
       (:func:`flexgear.dynamics.flexible.condensed.condensed_response`);
    3. per contact the loads, the mesh totals and records (depth = rigid overlap, force =
       elastic + damping force, deflection = elastic flank deflection of both gears, from the
       loads of every mesh) and the tangent rows, cross-mesh terms included.

    Compiled without reference counting (``_nrt=False``, as :func:`~flexgear.dynamics.integrator.solver.forces`
    and the contact search): it creates no arrays, and the tables' arrays it takes apart (about
    a thousand per evaluation on MERCURY 1-A) then cost no atomic increment and decrement each.

    Returns
    -------
    deepest : float
        The largest rigid overlap of the compliant meshes [m] (0 without contact).
    where : int
        Its mesh (-1: no contact).
    """
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    Fb = state.load
    Kt = system.stiffness
    Ct = system.damping
    G = system.contact_gradient
    H = system.inertia_gradient
    jf = contacts.joint_f
    ji = contacts.joint_i
    jm = contacts.joint_mesh
    n = system.rhs.shape[0]
    C = contacts.compliance
    dr = contacts.overlap
    rate = contacts.overlap_rate
    hp = contacts.hertz
    Fe = contacts.elastic_force
    active = contacts.active
    side_a = contacts.flank_side_a
    side_b = contacts.flank_side_b
    rad_a = contacts.flank_radius_a
    rad_b = contacts.flank_radius_b
    acc = state.accelerations
    gam = state.convective
    slope = state.acceleration_slope[0]
    integrated = cst.mode[0] == INTEGRATED
    modes = flex.modes
    deepest = 0.0
    where = -1
    # phase 1: contact search of every compliant mesh, each into its own rows (in parallel
    # threads with contacts.threads > 1), then per contact the geometry, stacked in mesh order
    order = contacts.search_order
    ns = 0
    for m in range(meshes.body_a.shape[0]):
        if meshes.law[m] == LAW_HERTZ:
            order[ns] = m
            ns += 1
    hits = contacts.search_hits
    if contacts.threads[0] > 1 and ns > 1:
        search_parallel(order, ns, pose, meshes.body_a, meshes.body_b, meshes.gear_a, meshes.gear_b, meshes.internal,
                        meshes.ncand_a, meshes.ncand_b, meshes.stride, meshes.gap, contact, local, contacts.search_f,
                        contacts.search_i, hits, contacts.search_cache, contacts.search_count)
    else:
        for p in range(ns):
            search_task(order[p], pose, meshes.body_a, meshes.body_b, meshes.gear_a, meshes.gear_b, meshes.internal,
                        meshes.ncand_a, meshes.ncand_b, meshes.stride, meshes.gap, contact, local, contacts.search_f,
                        contacts.search_i, hits, contacts.search_cache, contacts.search_count)
    N = 0
    nprev = contacts.joint_count[0]  # the last evaluation's stacked contacts (for start_force)
    start = contacts.start_force
    for p in range(ns):
        m = order[p]
        a = meshes.body_a[m]
        b = meshes.body_b[m]
        cnt = hits[m]
        out_f = contacts.search_f[m]
        out_i = contacts.search_i[m]
        fa = body_flex[a]
        fbb = body_flex[b]
        zb = contact.gear_z[meshes.gear_b[m]]
        L = meshes.face_width[m]
        for c in range(cnt):
            k = N + c
            # the contact Newton's start (solve_joint): this slot's elastic force of the last
            # evaluation, if the slot held the same contact
            same = (k < nprev and jm[k] == m and ji[k, 0] == out_i[c, 0] and ji[k, 1] == out_i[c, 1]
                    and ji[k, 2] == out_i[c, 2])
            start[k] = Fe[k] if same else 0.0
            for j in range(5):
                jf[k, j] = out_f[c, j]
            for j in range(3):
                ji[k, j] = out_i[c, j]
            jm[k] = m
            if out_f[c, 0] > deepest:
                deepest = out_f[c, 0]
                where = m
            px = out_f[c, 1]
            py = out_f[c, 2]
            nx = out_f[c, 3]
            ny = out_f[c, 4]
            dr[k] = out_f[c, 0]
            vax = vel[a, 0] - vel[a, 2] * (py - pose[a, 1])
            vay = vel[a, 1] + vel[a, 2] * (px - pose[a, 0])
            vbx = vel[b, 0] - vel[b, 2] * (py - pose[b, 1])
            vby = vel[b, 1] + vel[b, 2] * (px - pose[b, 0])
            rate[k] = nx * (vbx - vax) + ny * (vby - vay)
            side_a[k] = out_i[c, 2]
            rad_a[k] = flank_radius(px, py, pose[a, 0], pose[a, 1])  # the search gave side_a
            side_b[k], rad_b[k] = flank_side(px, py, pose[b, 0], pose[b, 1], pose[b, 2], out_i[c, 1], zb)
            # relative radius of curvature of the two involutes at the contact radii
            ta = math.sqrt(max(rad_a[k] ** 2 - meshes.rb_a[m] ** 2, (0.05 * meshes.rb_a[m]) ** 2))
            tb = math.sqrt(max(rad_b[k] ** 2 - meshes.rb_b[m] ** 2, (0.05 * meshes.rb_b[m]) ** 2))
            if meshes.internal[m]:
                R = ta * tb / max(tb - ta, 0.05 * tb)
            else:
                R = ta * tb / (ta + tb)
            hp[k, 0] = R
            hp[k, 1] = L
            hp[k, 2] = meshes.hertz_a[m]
            hp[k, 3] = meshes.nu_a[m]
            hp[k, 4] = meshes.depth_a[m]
            hp[k, 5] = meshes.hertz_b[m]
            hp[k, 6] = meshes.nu_b[m]
            hp[k, 7] = meshes.depth_b[m]
            hp[k, 8] = meshes.e_star[m]
            ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
            mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
            penetration_gradient(G[k], J, a, b, nx, ny, ma, mb, n)
            # modal coordinates: their flank displacement opens the rigid overlap (rows of G too);
            # so do the condensed modes' history and the frames' inertia load on them (phase 2,
            # its gradient in H)
            for j in range(n):
                H[k, j] = 0.0
            if fa >= 0 and modes[fa] > 0:
                dr[k] -= modal_flank(flex, fa, out_i[c, 0], side_a[k], rad_a[k], state.coordinates, G[k])
            if fbb >= 0 and modes[fbb] > 0:
                dr[k] -= modal_flank(flex, fbb, out_i[c, 1], side_b[k], rad_b[k], state.coordinates, G[k])
        N += cnt
    contacts.joint_count[0] = N
    nr = rigid_coordinates(flex, n)
    A = contacts.solve_matrix
    # phase 2: C over all stacked contacts, body by body (bodies, not FlexTable rows: bodies
    # sharing a reduction are still different bodies); D of one body built in A, free until
    # the contact solve; the condensed modes' history and inertia load on the overlaps
    for i in range(N):
        for j in range(N):
            C[i, j] = 0.0
    kap = cst.kappa
    hist = cst.history
    iw = cst.inertia_weight
    condensed_coefficients(flex, cst)
    # per body (in parallel threads with contacts.threads > 1) its contacts, their cells and
    # modal rows and the frame-inertia terms, each into its own rows; then, one body after the
    # other in body order, the terms on the overlaps and gradient rows, which the two bodies of
    # a contact share (the sums in the serial order: the same numbers with any thread count)
    relief = contacts.body_relief
    if contacts.threads[0] > 1:
        body_rows_parallel(body_flex, N, meshes.body_a, meshes.body_b, jm, ji, side_a, side_b, rad_a, rad_b,
                           contacts.body_slot, contacts.body_tooth, contacts.body_side, contacts.body_radius,
                           contacts.body_count, flex.condensed, flex.points, flex.radius_offset, flex.shape_offset,
                           flex.shape, flex.radius, flex.coupling_stride, flex.condensed_offset, contacts.flank_cell,
                           contacts.flank_weight, contacts.coupling_cell, contacts.coupling_weight, contacts.flank_modes,
                           pose, J, acc, gam, vel, iw, hist, relief)
    else:
        for body in range(body_flex.shape[0]):
            body_rows_task(body, body_flex, N, meshes.body_a, meshes.body_b, jm, ji, side_a, side_b, rad_a, rad_b,
                           contacts.body_slot, contacts.body_tooth, contacts.body_side, contacts.body_radius,
                           contacts.body_count, flex.condensed, flex.points, flex.radius_offset, flex.shape_offset,
                           flex.shape, flex.radius, flex.coupling_stride, flex.condensed_offset, contacts.flank_cell,
                           contacts.flank_weight, contacts.coupling_cell, contacts.coupling_weight, contacts.flank_modes,
                           pose, J, acc, gam, vel, iw, hist, relief)
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f < 0:
            continue
        nk = contacts.body_count[f]
        if nk == 0:
            continue
        slot = contacts.body_slot[f]
        rel = relief[f]
        cs = math.cos(pose[body, 2])
        sn = math.sin(pose[body, 2])
        for i in range(nk):
            k = slot[i]
            inertia_rows(rel[i, 0], rel[i, 1], rel[i, 2], cs, sn, J, body, slope, H, k)
            dr[k] -= rel[i, 3]
    piv = contacts.pivots
    known = contacts.compliance_known
    if N > 0:
        # every entry of C outside the integrator's Newton iterations (statics, evaluate: C is
        # inspected), inside them only those the solve needs
        solve_joint(C, dr, hp, Fe, active, N, A, contacts.solve_vector, piv, contacts.active_index, slope == 0.0,
                    flex, body_flex, contacts, kap)
    # the condensed modes' generalised forces and, integrated, their accelerations and reaction
    condensed_response(flex, cst, body_flex, contacts.flank_modes, contacts.body_slot, contacts.body_count, Fe, pose, acc,
                       gam, vel, J, system.inertia_load, Kt, Fb)
    # tangent of the elastic forces on the joint active set: (C + diag h')^-1
    idx = contacts.active_index
    na_ = active_set(active, N, idx)
    Kc = contacts.contact_tangent
    if na_ > 0:
        for p in range(na_):
            i = idx[p]
            for q in range(na_):
                A[p, q] = C[i, idx[q]]
            _, dh = hertz_line(Fe[i], hp[i, 0], hp[i, 1], hp[i, 2], hp[i, 3], hp[i, 4], hp[i, 5], hp[i, 6],
                               hp[i, 7], hp[i, 8])
            A[p, p] += dh
        if lu_factor(A, piv, na_):
            lu_inverse(A, piv, Kc, na_)
        else:
            for p in range(na_):
                for q in range(na_):
                    Kc[p, q] = np.nan
    # phase 3: loads, records, mesh totals and tangent rows
    for m in range(meshes.body_a.shape[0]):
        if meshes.law[m] == LAW_HERTZ:
            contacts.count[m] = 0
            contacts.mesh_force[m] = 0.0
            contacts.mesh_fx[m] = 0.0
            contacts.mesh_fy[m] = 0.0
    w = contacts.tangent_row
    u = contacts.relief_row
    p_c = -1
    for c in range(N):
        m = jm[c]
        a = meshes.body_a[m]
        b = meshes.body_b[m]
        Cmax = meshes.C[m]
        dd = meshes.d[m]
        depth = jf[c, 0]
        defl = depth - dr[c]  # modal coordinates' and frame inertia's part
        if known[c] == KNOWN:
            for j in range(N):
                defl += C[c, j] * Fe[j]
        else:
            defl += contacts.coupled_deflection[c]
        F = 0.0
        sd = 0.0
        if active[c]:
            p_c += 1  # idx[p_c] == c: the active set in stacked order
            sd = step(depth, 0.0, 0.0, dd, Cmax)
            F = Fe[c] + sd * rate[c]
            if F < 0.0:
                F = 0.0
        if not active[c] and dr[c] <= 0.0:
            contacts.joint_slot[c] = -1
            continue  # a near contact that stays open: not reported
        px = jf[c, 1]
        py = jf[c, 2]
        nx = jf[c, 3]
        ny = jf[c, 4]
        kept = contacts.count[m]
        contacts.joint_slot[c] = kept
        contacts.force[m, kept] = F
        contacts.depth[m, kept] = depth
        contacts.deflection[m, kept] = defl
        contacts.x[m, kept] = px
        contacts.y[m, kept] = py
        contacts.nx[m, kept] = nx
        contacts.ny[m, kept] = ny
        contacts.tooth_a[m, kept] = ji[c, 0]
        contacts.tooth_b[m, kept] = ji[c, 1]
        contacts.side_a[m, kept] = ji[c, 2]
        contacts.count[m] = kept + 1
        if F <= 0.0:
            continue
        contacts.mesh_force[m] += F
        contact_load(Fb, pose, a, b, px, py, nx, ny, F)
        contacts.mesh_fx[m] -= F * nx
        contacts.mesh_fy[m] -= F * ny
        # the modes feel the elastic force A_i F_e; the damper acts between the rigid frames
        for r in range(nr, n):
            system.rhs[r] -= Fe[c] * G[c, r]
        # tangent: row c of dF/d(delta_rigid) (elastic coupling over every compliant mesh +
        # damping ramp) times the gradients
        damp_slope = step_derivative(depth, 0.0, 0.0, dd, Cmax) * rate[c]  # dF/d(delta) of the damping ramp
        for j in range(n):  # the damping ramp depends on the rigid overlap: rigid columns
            w[j] = damp_slope * G[c, j] if j < nr else 0.0
        relief = False
        for j in range(n):
            u[j] = 0.0
        for q in range(na_):
            kq = Kc[p_c, q]
            if kq == 0.0:  # contacts on no common body (exact zeros of the block LU)
                continue
            l_ = idx[q]
            for j in range(n):
                hj = H[l_, j]
                w[j] += kq * (G[l_, j] + hj)
                if hj != 0.0:
                    u[j] += kq * hj
                    relief = True
        if relief and not integrated:  # the quasi-static relief's mass made reciprocal
            relief_reciprocity(G, c, u, slope, system.mass)
        if relief and integrated:
            # the integrated modes' reaction on the frames through this contact's elastic force,
            # (1 + alpha) beta h^2 H_c^T dF_c/dq (condensed.condensed_response): the Newton
            # matrix's (G + H)^T Kc (G + H), reciprocal
            for r in range(nr):
                hr = H[c, r]
                if hr == 0.0:
                    continue
                for s in range(n):
                    Kt[r, s] += hr * (w[s] - damp_slope * G[c, s]) if s < nr else hr * w[s]
        for r in range(n):
            gr = G[c, r]
            if gr == 0.0:
                continue
            if r < nr:  # rigid rows: elastic + damping force
                for s in range(n):
                    Kt[r, s] += gr * w[s]
                for s in range(nr):
                    Ct[r, s] += sd * gr * G[c, s]
            else:  # modal rows: elastic force only
                for s in range(n):
                    Kt[r, s] += gr * (w[s] - damp_slope * G[c, s]) if s < nr else gr * w[s]
    return deepest, where
