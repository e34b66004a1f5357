"""The joint flank compliance of the compliant contacts, built as their solve needs it: entries
between the contacts that are or become active, and the open contacts' deflections from the modes'
sums, each flexible body's part in its own rows (in parallel groups of bodies), added in body order.
"""
from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np

from ...kernels import kernel
from ..contact.solve import DROPPED, newton_active
from .flank import flank_contacts, contact_point, residual_tables, residual_pair

#: states of a contact's entries in the joint compliance (``ContactBuffers.compliance_known``)
UNKNOWN, KNOWN, FRESH = 0, 1, 2


class JointWork(NamedTuple):
    """What the per-body tasks of the joint compliance read and write (:func:`joint_work`): the
    flexible bodies' contact rows and buffers and the contacts' state (ContactBuffers), the
    bodies' residual tables (FlexTable) and the condensed modes' weights kappa_i
    (CondensedState). The fields keep their sources' names and units."""

    body_group: np.ndarray  # (nf,) int: each body's group of the parallel loops (-1: no contacts)
    body_count: np.ndarray  # (nf,) int
    body_slot: np.ndarray  # (nf, S) int
    body_tooth: np.ndarray  # (nf, S) int
    body_side: np.ndarray  # (nf, S) int
    body_radius: np.ndarray  # (nf, S) float
    flank_cell: np.ndarray  # (nf, S) int
    flank_weight: np.ndarray  # (nf, S) float
    coupling_cell: np.ndarray  # (nf, S) int
    coupling_weight: np.ndarray  # (nf, S) float
    flank_modes: np.ndarray  # (nf, S, modes) float
    body_entries: np.ndarray  # (nf, S, S) float: each body's part of C between its contacts
    body_cols: np.ndarray  # (nf, S) int: work array
    body_vals: np.ndarray  # (nf, S) float: work array
    body_open: np.ndarray  # (nf, S) float: each body's part of the open contacts' deflections
    body_modal_work: np.ndarray  # (nf, modes) float: work array
    compliance_known: np.ndarray  # (S,) int: UNKNOWN, KNOWN or FRESH
    active: np.ndarray  # (S,) bool
    elastic_force: np.ndarray  # (S,) float [N]
    condensed: np.ndarray  # (nf,) int
    points: np.ndarray  # (nf,) int
    coupling_stride: np.ndarray  # (nf,) int
    teeth: np.ndarray  # (nf,) int
    period: np.ndarray  # (nf,) int
    coupling_offset: np.ndarray  # (nf,) int
    coupling: np.ndarray  # (sum P 2 2 z Jc Jc,) float [m/N]
    self_offset: np.ndarray  # (nf,) int
    self_compliance: np.ndarray  # (sum P 2 J,) float [m/N]
    condensed_offset: np.ndarray  # (nf,) int
    kappa: np.ndarray  # (sum nq,) float: the condensed modes' weights [-]


@kernel(error_model="numpy", inline="always")
def joint_work(flex, contacts, kap):
    """The JointWork of the FlexTable ``flex``, the ContactBuffers ``contacts`` and the modes'
    weights ``kap``."""
    c = contacts
    return JointWork(c.body_group, c.body_count, c.body_slot, c.body_tooth, c.body_side, c.body_radius, c.flank_cell,
                     c.flank_weight, c.coupling_cell, c.coupling_weight, c.flank_modes, c.body_entries, c.body_cols,
                     c.body_vals, c.body_open, c.body_modal_work, c.compliance_known, c.active, c.elastic_force,
                     flex.condensed, flex.points, flex.coupling_stride, flex.teeth, flex.period, flex.coupling_offset,
                     flex.coupling, flex.self_offset, flex.self_compliance, flex.condensed_offset, kap)


# reassociated sums (vectorised, in an order of the compiler's); a function of its own, so that
# the flags reach these loops only
@kernel(error_model="numpy", _nrt=False, fastmath={"reassoc", "contract"})
def modal_row(U, i, cols, nc, nq, kap, ko, out):
    """``out[p]`` = the modal part of :func:`modal_products` between contact i and contact
    ``cols[p]`` (p < nc, ``cols`` increasing): the pair (a, b), a <= b, sums ``(U[a, m] kap[ko +
    m]) U[b, m]`` over m, so that both entries of a pair get one value. Four columns advance
    together, rows and weights read through views (as in :func:`modal_products`), and the sums
    are reassociated, which lets the compiler vectorise them; they equal :func:`modal_products`'
    plain sums up to round-off, which the integrator never compares."""
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
def extend_compliance(flex, f, rows, nk, kap, known, C, cols, vals):
    """Add body f's flank compliance (:func:`~flexgear.dynamics.flexible.flank.contact_compliance`,
    the same numbers) to the joint compliance ``C`` between its contacts (``rows``, a
    FlankContacts: local i < nk, stacked slot ``rows.slot[i]``) whose entries are being added
    (``known[slot] == FRESH``) and those being added or already computed (``KNOWN``), both ways.
    ``cols`` (int) and ``vals`` (float) are work arrays of nk entries. Called body by body in the
    order of :func:`~flexgear.dynamics.flexible.compliant.compliant_contacts`, so that each entry
    sums the bodies' parts in the same order. (:func:`extend_entries` into a body buffer, then
    :func:`add_entries`.)"""
    E = np.zeros((nk, nk))
    extend_entries(residual_tables(flex, f), rows, nk, kap, known, E, cols, vals)
    add_entries(nk, rows.slot, known, E, C)


@kernel(error_model="numpy", inline="always")
def extend_entries(tabs, rows, nk, kap, known, E, cols, vals):
    """Body f's part of the entries that :func:`extend_compliance` adds, into ``E[i, j]`` (local
    indices i, j < nk of ``rows``; written only for the pairs being added, :func:`add_entries`
    adds them to the joint compliance), with the body's tables ``tabs`` (a ResidualTables). Writes
    nothing shared: the bodies can run in parallel threads (:func:`joint_entries`)."""
    nq = tabs.condensed
    ko = tabs.condensed_offset
    slot = rows.slot
    U = rows.modes
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
        a = contact_point(rows, i)
        for p in range(nc):
            j = cols[p]
            b = contact_point(rows, j)
            E[i, j] = vals[p] + residual_pair(tabs, a, b)
            if j != i:
                E[j, i] = vals[p] + residual_pair(tabs, b, a)


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
def open_deflection(flex, f, rows, nk, kap, known, active, F, z_, out):
    """Add body f's part of ``sum_l C_kl F_l`` (the active contacts' forces F) to ``out[k]`` for
    its contacts k (``rows``, a FlankContacts) whose entries are not computed (``known[k] ==
    UNKNOWN``): the modal part as ``U_k . (kappa * U^T F)`` (O(modes) per contact instead of
    O(modes) per pair; equal to the entries' sum up to round-off), the residual part per active
    contact. ``z_`` is a work array of the body's condensed modes. (:func:`open_entries` into a
    body buffer, then :func:`add_open`.)"""
    P = np.zeros(nk)
    open_entries(residual_tables(flex, f), rows, nk, kap, known, active, F, z_, P)
    add_open(nk, rows.slot, known, P, out)


@kernel(error_model="numpy", inline="always")
def open_entries(tabs, rows, nk, kap, known, active, F, z_, out):
    """Body f's part of :func:`open_deflection` into ``out[i]`` (local index i < nk, written for
    the contacts without entries; :func:`add_open` adds them to the stacked deflections), with
    the body's tables ``tabs`` (a ResidualTables). Writes nothing shared: the bodies can run in
    parallel threads (:func:`open_deflections`)."""
    nq = tabs.condensed
    ko = tabs.condensed_offset
    slot = rows.slot
    U = rows.modes
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
            open_residual(tabs, rows, nk, active, F, i, out)


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
def open_residual(tabs, rows, nk, active, F, i, out):
    """Add the residual part of contact i's deflection under the active contacts' forces F to its
    modal part in ``out[i]`` (:func:`open_entries`)."""
    slot = rows.slot
    a = contact_point(rows, i)
    g = out[i]
    for j in range(nk):
        sj = slot[j]
        if not active[sj]:
            continue
        g += residual_pair(tabs, a, contact_point(rows, j)) * F[sj]
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
def solve_joint(flex, body_flex, contacts, kap, cnt, full):
    """:func:`~flexgear.dynamics.contact.solve.solve_contacts_into` on the cnt stacked contacts of
    :func:`~flexgear.dynamics.flexible.compliant.compliant_contacts` (the ContactBuffers
    ``contacts``: overlaps, Hertz parameters, forces, active set, LU work) with the joint
    compliance built as the solve needs it (the same forces up to round-off), each condensed mode
    weighted by ``kap`` (CondensedState.kappa).

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
        As :func:`~flexgear.dynamics.contact.solve.solve_contacts_into`.
    """
    C = contacts.compliance
    dr = contacts.overlap
    hp = contacts.hertz
    F = contacts.elastic_force
    active = contacts.active
    A = contacts.solve_matrix
    rhs = contacts.solve_vector
    piv = contacts.pivots
    idx = contacts.active_index
    known = contacts.compliance_known
    cd = contacts.coupled_deflection
    start = contacts.start_force
    work = joint_work(flex, contacts, kap)
    for i in range(cnt):
        active[i] = dr[i] > 0.0
        # started from the last evaluation's force of the same contact (compliant_contacts; the
        # forces change little from one evaluation to the next: about half the Newton
        # iterations), else from below the root (newton_active)
        F[i] = start[i] if active[i] else 0.0
        known[i] = UNKNOWN
    # the bodies' parts of C and of the open deflections in up to contacts.threads parallel groups
    ng = body_groups(body_flex, contacts.body_count, flex.condensed, contacts.threads[0], contacts.body_group,
                     contacts.group_load)
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
            joint_entries(body_flex, work, C, ng)
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
        open_deflections(body_flex, work, cnt, cd, ng)
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
        open_deflections(body_flex, work, cnt, cd, ng)
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
# arrays of a tuple read inside a prange body itself are lost, numba issue 7135; a function
# called there writes them)
@kernel(error_model="numpy", _nrt=False)
def entries_task(g, body_flex, work):
    """:func:`extend_entries` of the bodies of group g (``work.body_group``) into their own
    buffers ``work.body_entries[f]`` (a JointWork)."""
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f < 0 or work.body_group[f] != g:
            continue
        nk = work.body_count[f]
        if nk == 0:
            continue
        extend_entries(residual_tables(work, f), flank_contacts(work, f), nk, work.kappa, work.compliance_known,
                       work.body_entries[f], work.body_cols[f], work.body_vals[f])


@kernel(error_model="numpy", parallel=True)
def entries_parallel(ng, body_flex, work):
    """:func:`entries_task` of the ng groups in parallel threads (each writes only its bodies' rows)."""
    for g in nb.prange(ng):
        entries_task(np.int64(g), body_flex, work)  # the serial call's index type: one overload


@kernel(error_model="numpy", _nrt=False)
def open_task(g, body_flex, work):
    """:func:`open_entries` of the bodies of group g (``work.body_group``) into their own buffers
    ``work.body_open[f]`` (a JointWork)."""
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f < 0 or work.body_group[f] != g:
            continue
        nk = work.body_count[f]
        if nk == 0:
            continue
        open_entries(residual_tables(work, f), flank_contacts(work, f), nk, work.kappa, work.compliance_known, work.active,
                     work.elastic_force, work.body_modal_work[f], work.body_open[f])


@kernel(error_model="numpy", parallel=True)
def open_parallel(ng, body_flex, work):
    """:func:`open_task` of the ng groups in parallel threads (each writes only its bodies' rows)."""
    for g in nb.prange(ng):
        open_task(np.int64(g), body_flex, work)  # the serial call's index type: one overload


@kernel(error_model="numpy", inline="always")
def joint_entries(body_flex, work, C, ng):
    """:func:`extend_compliance` of every flexible body (a JointWork ``work``): each body's part
    into its own buffer, the ng groups of bodies (:func:`body_groups`) in parallel threads if ng
    > 1; then the parts added to C in body order (the same numbers with any number of threads)."""
    if ng > 1:
        entries_parallel(ng, body_flex, work)
    else:
        entries_task(0, body_flex, work)
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f >= 0 and work.body_count[f] > 0:
            add_entries(work.body_count[f], work.body_slot[f], work.compliance_known, work.body_entries[f], C)


@kernel(error_model="numpy", inline="always")
def open_deflections(body_flex, work, cnt, cd, ng):
    """``cd[k] = sum_l C_kl F_l`` (``contacts.coupled_deflection``) for the contacts k < cnt
    without computed entries (:func:`open_deflection` of every flexible body, a JointWork
    ``work``): each body's part into its own buffer, the groups in parallel threads if ng > 1,
    then added in body order."""
    for i in range(cnt):
        cd[i] = 0.0
    if ng > 1:
        open_parallel(ng, body_flex, work)
    else:
        open_task(0, body_flex, work)
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f >= 0 and work.body_count[f] > 0:
            add_open(work.body_count[f], work.body_slot[f], work.compliance_known, work.body_open[f], cd)
