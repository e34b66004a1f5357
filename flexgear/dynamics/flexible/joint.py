"""The joint flank compliance of the compliant contacts, built as their solve needs it: entries
between the contacts that are or become active, and the open contacts' deflections from the modes'
sums, each flexible body's part in its own rows (in parallel groups of bodies), added in body order.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from ...kernels import kernel
from ..contact.solve import DROPPED, newton_active
from .flank import residual_pair



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
