"""The compliant kernel's shared-work paths give the numbers of its plain per-pair definitions.

:func:`flexgear.dynamics.flexible.flank.contact_compliance` builds a body's flank compliance
between all its contacts with the work shared (cells found once per contact, four modal dot
products at a time, the residual tables' integer work hoisted); the definition is
:func:`~flexgear.dynamics.flexible.flank.flank_influence` of every pair (the path checked against
the full static FE in ``tests/test_flexible.py``). :func:`~flexgear.dynamics.contact.solve.solve_contacts`
solves each Newton step on the active set alone; its definition is the contact law itself.
"""
import math

import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.flexible.joint import FRESH, KNOWN, UNKNOWN, extend_compliance, open_deflection
from flexgear.dynamics.flexible.flank import (FlankContacts, contact_compliance, flank_cells, flank_influence,
                                              contact_point, residual_tables, residual_pair)
from flexgear.dynamics.contact.laws import HEALTHY_TERMS, HERTZ_COLUMNS, HERTZ_SERIES, hertz_line
from flexgear.dynamics.contact.solve import lu_factor, lu_inverse, lu_solve, solve_contacts
from flexgear.dynamics.contact.search import MAX_CONTACTS
from flexgear.gears.material import Material
from flexgear.stiffness.hertz import plane_constants


def flank_contacts(tooth, side, radius, modes, slot=None):
    """A body's contacts as a FlankContacts, with zeroed cells and the modal rows ``modes``."""
    S = modes.shape[0]
    pad = lambda a, dtype: np.concatenate([np.asarray(a, dtype), np.zeros(S - len(a), dtype)])  # noqa: E731
    return FlankContacts(pad(np.arange(len(tooth)) if slot is None else slot, np.int64), pad(tooth, np.int64),
                         pad(side, np.int64), pad(radius, float), np.zeros(S, np.int64), np.zeros(S),
                         np.zeros(S, np.int64), np.zeros(S), modes)


@pytest.fixture(scope="module")
def flex_table():
    """The FlexTable of the flexible spur pair (pinion row 0, wheel row 1)."""
    return build_model(load_config("spur_pair_flexible")).pack(32).flex


@pytest.mark.parametrize("f", [0, 1])
def test_contact_compliance_is_flank_influence_of_every_pair(flex_table, f):
    """Every entry of the shared-work matrix equals the per-pair definition (to round-off: the
    same operations in the same order), for contacts on teeth at every distance, both sides,
    two points on one flank, a repeated point, and radii off both ends of the tables."""
    flex = flex_table
    z = int(flex.teeth[f])
    o, J = int(flex.radius_offset[f]), int(flex.points[f])
    r0, r1 = flex.radius[o], flex.radius[o + J - 1]
    rng = np.random.default_rng(7)
    cnt = 13
    tooth = rng.integers(0, z, cnt)
    side = rng.choice([-1, 1], cnt)
    radius = rng.uniform(r0, r1, cnt)
    tooth[1], side[1], radius[1] = tooth[0], side[0], radius[0]  # the same point twice
    tooth[2], side[2] = tooth[0], side[0]  # another point of the same flank
    tooth[3], side[3] = tooth[0], -side[0]  # the tooth's other flank
    tooth[4], tooth[5] = 0, z - 1  # neighbours across the wrap of the tooth index
    radius[6], radius[7] = r0 - 1e-4, r1 + 1e-4  # clamped to the table ends
    S = 2 * MAX_CONTACTS
    D = np.full((S, S), np.nan)
    U = np.zeros((S, int(flex.condensed.max())))
    contact_compliance(flex, f, flank_contacts(tooth, side, radius, U), cnt, D, np.ones(U.shape[1]), 0)
    ref = np.array([[flank_influence(flex, f, tooth[i], side[i], radius[i], tooth[j], side[j], radius[j])
                     for j in range(cnt)] for i in range(cnt)])
    assert np.all(np.isfinite(D[:cnt, :cnt]))
    assert np.max(np.abs(D[:cnt, :cnt] - ref)) <= 1e-14 * np.max(np.abs(ref))
    assert D[0, 2] != 0.0 and D[0, 3] != 0.0


def test_active_set_solve_satisfies_the_law_with_many_open_contacts():
    """Newton on the active set alone: with most contacts open (near contacts of a flexible
    mesh), the closed ones satisfy delta = C F + h(F), the open ones keep a gap, F >= 0."""
    steel = Material(E=2.1e11, nu=0.3, rho=7850.0)
    E1, nu1 = plane_constants(steel, "plane_strain")
    n = 11
    hp = np.zeros((MAX_CONTACTS * 2, HERTZ_COLUMNS))
    hp[:, HERTZ_SERIES:] = HEALTHY_TERMS  # healthy teeth
    hp[:n, :9] = [0.006, 0.02, 1 / (math.pi * E1), nu1, 0.002, 1 / (math.pi * E1), nu1, 0.002, 0.5 * E1]
    rng = np.random.default_rng(3)
    B = rng.normal(size=(n, n)) * 0.2e-9
    C = np.zeros((2 * MAX_CONTACTS, 2 * MAX_CONTACTS))
    C[:n, :n] = B @ B.T + 2e-9 * np.eye(n)
    dr = np.zeros(2 * MAX_CONTACTS)
    dr[:n] = rng.uniform(-20e-6, 30e-6, n)
    F = np.zeros(2 * MAX_CONTACTS)
    active = np.zeros(2 * MAX_CONTACTS, bool)
    assert solve_contacts(C, dr, hp, F, active, n) > 0
    assert 0 < active[:n].sum() < n
    for i in range(n):
        gap = dr[i] - C[i, :n] @ F[:n]
        if active[i]:
            h, _ = hertz_line(F[i], *hp[i, :9])
            assert F[i] > 0.0
            assert gap - h == pytest.approx(0.0, abs=1e-14)
        else:
            assert F[i] == 0.0 and gap <= 0.0


@pytest.mark.parametrize("f", [0, 1])
def test_compliance_built_as_the_solve_needs_it_is_the_full_matrix(flex_table, f):
    """The joint solve inside the integrator builds C only between the contacts that are or
    become active (:func:`~flexgear.dynamics.flexible.joint.extend_compliance`, in two stages here:
    a first set, then contacts that join) and checks the others through the modal product
    ``U_k . (kappa U^T F)`` (:func:`~flexgear.dynamics.flexible.joint.open_deflection`). Against
    :func:`contact_compliance` of all pairs, with condensed modes weighted by an integrated
    step's kappa: the entries built are the same numbers up to the round-off of a dot product
    summed in another order (the solve's modal sums are reassociated, :func:`modal_row`: within
    ``2 nq eps sum_m |U_i,m kappa_m U_j,m|``, the bound of summation error), the others zero,
    and the open contacts' deflections ``sum_l C_kl F_l`` agree to round-off."""
    flex = flex_table
    z = int(flex.teeth[f])
    o, J = int(flex.radius_offset[f]), int(flex.points[f])
    nq = int(flex.condensed[f])
    ko = int(flex.condensed_offset[f])
    rng = np.random.default_rng(11)
    cnt = 13
    tooth = rng.integers(0, z, cnt)
    side = rng.choice([-1, 1], cnt)
    radius = rng.uniform(flex.radius[o], flex.radius[o + J - 1], cnt)
    tooth[1], side[1], radius[1] = tooth[0], side[0], radius[0]
    tooth[3], side[3] = tooth[0], -side[0]
    S = 2 * MAX_CONTACTS
    kap = np.zeros(int(flex.condensed.sum()))
    kap[ko:ko + nq] = rng.uniform(0.2, 1.0, nq)
    U = np.zeros((S, int(flex.condensed.max())))
    slot = rng.permutation(S)[:cnt]  # the stacked slots of the body's contacts
    rows = flank_contacts(tooth, side, radius, U, slot)
    D = np.zeros((S, S))
    contact_compliance(flex, f, rows, cnt, D, kap, ko)
    known = np.full(S, UNKNOWN, np.int64)
    C = np.zeros((S, S))
    for added in ([0, 2, 5, 6, 9], [3, 11]):
        known[slot[added]] = FRESH
        extend_compliance(flex, f, rows, cnt, kap, known, C, np.zeros(S, np.int64), np.zeros(S))
        known[known == FRESH] = KNOWN
    built = [0, 2, 3, 5, 6, 9, 11]
    Uk = U[:cnt, :nq] * np.sqrt(kap[ko:ko + nq])
    bound = 2 * nq * np.finfo(float).eps * (np.abs(Uk) @ np.abs(Uk).T)
    for i in range(cnt):
        for j in range(cnt):
            if i in built and j in built:
                assert abs(C[slot[i], slot[j]] - D[i, j]) <= bound[i, j], (i, j)
                assert C[slot[i], slot[j]] != 0.0
            else:
                assert C[slot[i], slot[j]] == 0.0
    active = np.zeros(S, bool)
    active[slot[[0, 5, 9, 11]]] = True
    F = np.zeros(S)
    F[active] = rng.uniform(50.0, 500.0, 4)
    out = np.zeros(S)
    open_deflection(flex, f, rows, cnt, kap, known, active, F, np.zeros(U.shape[1]), out)
    Fl = F[slot]
    for i in range(cnt):
        if i in built:
            assert out[slot[i]] == 0.0
        else:
            ref = D[i, :cnt] @ Fl
            assert out[slot[i]] == pytest.approx(ref, rel=1e-12, abs=1e-15 * abs(D[i, i]) * Fl.sum())


@pytest.mark.parametrize("unknown", [[1], [1, 4], [1, 4, 7], [1, 3, 4, 7, 8, 10, 12], [0, 1, 2, 3, 4, 6, 7, 8, 10]])
def test_open_deflection_is_the_one_at_a_time_sum(flex_table, unknown):
    """The open contacts' deflections, their modal dot products taken four or one at a time
    together (reassociated sums, :func:`~flexgear.dynamics.flexible.joint.open_modal`), are the plain
    sums up to the round-off of summing in another order (the bound ``2 nq eps sum_m |U_k,m
    z_m|``): per contact ``U_k . (kappa * U^T F)`` over the modes, then the residual entries
    times the active forces in contact order."""
    flex = flex_table
    f = 1
    z = int(flex.teeth[f])
    o, J = int(flex.radius_offset[f]), int(flex.points[f])
    nq = int(flex.condensed[f])
    ko = int(flex.condensed_offset[f])
    rng = np.random.default_rng(5)
    cnt = 13
    tooth = rng.integers(0, z, cnt)
    side = rng.choice([-1, 1], cnt)
    radius = rng.uniform(flex.radius[o], flex.radius[o + J - 1], cnt)
    S = 2 * MAX_CONTACTS
    kap = np.zeros(int(flex.condensed.sum()))
    kap[ko:ko + nq] = rng.uniform(0.2, 1.0, nq)
    U = np.zeros((S, int(flex.condensed.max())))
    slot = rng.permutation(S)[:cnt]
    rows = flank_contacts(tooth, side, radius, U, slot)
    contact_compliance(flex, f, rows, cnt, np.zeros((S, S)), kap, ko)
    known = np.full(S, KNOWN, np.int64)
    known[slot[unknown]] = UNKNOWN
    active = np.zeros(S, bool)
    on = [i for i in range(cnt) if i not in unknown][:4]
    active[slot[on]] = True
    F = np.zeros(S)
    F[active] = rng.uniform(50.0, 500.0, len(on))
    out = np.zeros(S)
    open_deflection(flex, f, rows, cnt, kap, known, active, F, np.zeros(U.shape[1]), out)
    zq = [0.0] * nq
    for j in range(cnt):
        if active[slot[j]]:
            for m in range(nq):
                zq[m] += float(U[j, m]) * float(F[slot[j]])
    zq = [zq[m] * float(kap[ko + m]) for m in range(nq)]
    for i in range(cnt):
        if i not in unknown:
            assert out[slot[i]] == 0.0
            continue
        g = 0.0
        size = 0.0
        for m in range(nq):
            g += float(U[i, m]) * zq[m]
            size += abs(float(U[i, m]) * zq[m])
        for j in range(cnt):
            if active[slot[j]]:
                g += residual_pair(residual_tables(flex, f), contact_point(rows, i), contact_point(rows, j)) * float(F[slot[j]])
        # (the residual terms added to either sum in the same order: a rounding each)
        assert abs(out[slot[i]] - g) <= np.finfo(float).eps * (2 * nq * size + 2 * cnt * abs(g)), i


@pytest.mark.parametrize("n", [1, 2, 5, 12])
def test_lu_inverse_is_the_solve_of_each_unit_vector(n):
    """The tangent's inverse, all columns together, is bit for bit :func:`lu_solve` of each unit
    vector, on a matrix with exact zeros (contacts on no common body) that needs pivoting; and
    it inverts the matrix."""
    rng = np.random.default_rng(n)
    M = rng.normal(size=(n, n)) * (rng.uniform(size=(n, n)) < 0.7)
    M += np.diag(rng.uniform(0.1, 0.5, n))
    S = 2 * MAX_CONTACTS
    A = np.zeros((S, S))
    A[:n, :n] = M
    piv = np.zeros(S, np.int64)
    assert lu_factor(A, piv, n)
    X = np.full((S, S), np.nan)
    lu_inverse(A, piv, X, n)
    for q in range(n):
        e = np.zeros(S)
        e[q] = 1.0
        lu_solve(A, piv, e, n)
        assert np.array_equal(X[:n, q], e[:n])
    assert np.max(np.abs(M @ X[:n, :n] - np.eye(n))) < 1e-10


@pytest.mark.parametrize("f", [0, 1])
def test_flank_cells_interpolate_the_shape_table(flex_table, f):
    """A contact's modal row is bit for bit ``(1 - w) S[j] + w S[j + 1]`` of the two table rows
    of its tooth, side and radius cell (read as contiguous rows), at table radii, between them
    and clamped at both ends."""
    flex = flex_table
    z = int(flex.teeth[f])
    o, J = int(flex.radius_offset[f]), int(flex.points[f])
    nq = int(flex.condensed[f])
    r0, r1 = flex.radius[o], flex.radius[o + J - 1]
    rng = np.random.default_rng(17)
    cnt = 9
    tooth = rng.integers(0, z, cnt)
    side = rng.choice([-1, 1], cnt)
    radius = rng.uniform(r0, r1, cnt)
    radius[0], radius[1], radius[2] = r0 - 1e-4, r1 + 1e-4, flex.radius[o + J // 2]
    S = 2 * MAX_CONTACTS
    U = np.full((S, int(flex.condensed.max())), np.nan)
    rows = flank_contacts(tooth, side, radius, U)
    flank_cells(flex, f, rows, cnt)
    for i in range(cnt):
        j, w = int(rows.cell[i]), rows.weight[i]
        assert 0 <= j < J - 1 and 0.0 <= w <= 1.0
        assert flex.radius[o + j] <= max(min(radius[i], r1), r0) <= flex.radius[o + j + 1]
        b = int(flex.shape_offset[f]) + ((int(tooth[i]) * 2 + (0 if side[i] > 0 else 1)) * J + j) * nq
        ref = (1.0 - w) * flex.shape[b:b + nq] + w * flex.shape[b + nq:b + 2 * nq]
        assert np.array_equal(U[i, :nq], ref)


@pytest.mark.parametrize("threads", [1, 2, 3, 8])
def test_body_groups_share_the_bodies_with_contacts_evenly(threads):
    """Every flexible body with contacts goes to exactly one of at most ``threads`` groups
    (bodies without contacts to none), and the largest-first greedy sharing keeps the busiest
    group within the largest body's work of the even share (MERCURY 1-A's sizes: a ring of 163
    modes, a sun of 54, three planets of 47)."""
    from flexgear.dynamics.flexible.joint import body_groups
    body_flex = np.array([-1, 0, 1, 2, 3, 4, -1])  # carrier and load rigid
    count = np.array([12, 9, 9, 0, 15])  # the third planet without contacts
    nq = np.array([54, 47, 47, 47, 163])
    group = np.zeros(5, np.int64)
    ng = body_groups(body_flex, count, nq, threads, group, np.zeros(5))
    busy = count > 0
    assert ng == (1 if threads == 1 else min(threads, busy.sum()))
    assert np.all(group[~busy] == (0 if ng == 1 else -1))
    assert np.all((group[busy] >= 0) & (group[busy] < ng))
    w = (nq + 8.0) * count
    loads = [w[group == g].sum() for g in range(ng)]
    assert sum(loads) == w.sum()
    assert max(loads) <= w.sum() / ng + w.max()
    if ng == 2:  # the ring (the most work) alone against the rest
        assert max(loads) == w[4] and np.sum(group == group[4]) == 1
