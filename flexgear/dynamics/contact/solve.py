"""The joint solve of the compliant contacts: the forces F of contacts with a flank compliance C
and the Hertz line-contact law h, ``delta = C F + h(F)`` on the active set (F > 0) and
``delta <= C F`` off it, by Newton's method with complementarity checks; small dense LU.
"""
from __future__ import annotations

import numpy as np

from ...kernels import kernel
from .laws import contact_approach

#: Relative force tolerance of the contact solve (|dF| < FORCE_TOL max(F, 1 N)).
FORCE_TOL = 1e-11
#: Newton iterations of the contact solve per active set.
MAX_SOLVE = 60


@kernel(literal=True, error_model="numpy", fastmath=False, _nrt=False)
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


@kernel(literal=True, error_model="numpy", fastmath=False, _nrt=False)
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


@kernel(literal=True, error_model="numpy", _nrt=False)
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


@kernel(literal=True, error_model="numpy")
def solve_contacts(C, dr, hp, F, active, cnt):
    """:func:`solve_contacts_into` with its own work arrays (for tests and single calls)."""
    mc = C.shape[0]
    return solve_contacts_into(C, dr, hp, F, active, cnt, np.zeros((mc, mc)), np.zeros(mc), np.zeros(mc, np.int64),
                               np.zeros(mc, np.int64))


@kernel(literal=True, error_model="numpy", inline="always")
def active_set(active, cnt, idx):
    """The contacts of the active set in increasing order into ``idx``; returns their number."""
    na = 0
    for i in range(cnt):
        if active[i]:
            idx[na] = i
            na += 1
    return na


@kernel(literal=True, error_model="numpy", _nrt=False)
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
        Hertz parameters per contact: R, L, ka, na, da, kb, nb, db, E* (:func:`~.laws.hertz_line`) and the
        series compliance [m/N] (:func:`~.laws.contact_approach`).
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


@kernel(literal=True, error_model="numpy", _nrt=False)
def newton_active(C, dr, hp, F, active, cnt, A, rhs, piv, idx, total):
    """One round of :func:`solve_contacts_into`: Newton's method on the active set, from the
    forces in ``F`` (:func:`~flexgear.dynamics.flexible.joint.solve_joint`: the last evaluation's, near the root) and started
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
            _, d1 = contact_approach(1.0, hp, i)
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
            h, dh = contact_approach(F[i], hp, i)
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
