"""The coupled housing's forces (:class:`~flexgear.dynamics.model.tables.HousingTable`): its
reduced stiffness, damping and mass, and the elastic bearings seated in it.

A seated bearing's spring-damper acts between the body's centre and its anchor moved by the
housing, ``f = -k (x - a0 - G q_h) - c (x' - G q_h')`` (G the link's rows; likewise a torsional
spring to ground about the anchor's rotation). :func:`~flexgear.dynamics.integrator.forces.bearings`
has already applied the ground part ``-k (x - a0) - c x'``; this adds the rest to the body and the
reaction ``-G^T f`` to the housing's coordinates, with the tangent terms of ``D = J_i - G``.

The Newton matrix's housing block is constant (the housing is linear and its seated bodies'
Jacobian rows are constant), so :func:`housing_solve` eliminates it once per step size: the
dense solve of each Newton iteration is the rest's alone.
"""
from __future__ import annotations

import numpy as np

from ...kernels import kernel
from ..model.bodies import ANGLE_SPRING


@kernel(error_model="numpy")
def housing_forces(housing, bodies, state, system):
    """Add the coupled housing to the body loads and ``system`` (rhs, Mq, Kt, Ct); nothing for
    the empty table of a model without one (:func:`~flexgear.dynamics.model.tables.empty_housing`). The
    housing block of Kt and Ct is the table's constant ``tangent_*`` (its own matrices and
    ``G^T k G`` of the links); the links add the rest, over the non-zero columns of the seated
    body's Jacobian row only."""
    if housing.stiffness.shape[0] == 0:
        return
    q = state.coordinates
    qd = state.rates
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    Fb = state.load
    rhs = system.rhs
    Mq = system.mass
    Kt = system.stiffness
    Ct = system.damping
    n = rhs.shape[0]
    h0 = housing.first
    nh = housing.stiffness.shape[0]
    for r in range(nh):
        acc = 0.0
        for s in range(nh):
            acc += housing.stiffness[r, s] * q[h0 + s] + housing.damping[r, s] * qd[h0 + s]
            Kt[h0 + r, h0 + s] += housing.tangent_stiffness[r, s]
            Ct[h0 + r, h0 + s] += housing.tangent_damping[r, s]
            Mq[h0 + r, h0 + s] += housing.mass[r, s]
        rhs[h0 + r] -= acc
    G = housing.link_rows
    for lk in range(housing.link_body.shape[0]):
        i = housing.link_body[lk]
        for d in range(3):
            if d < 2:
                k = bodies.stiffness[i]
                c = bodies.damping[i]
                rel = pose[i, d] - (bodies.pin_x[i] if d == 0 else bodies.pin_y[i])
            else:
                if bodies.rotation[i] != ANGLE_SPRING or bodies.torsion_parent[i] >= 0:
                    continue
                k = bodies.torsional_stiffness[i]
                c = bodies.torsional_damping[i]
                rel = pose[i, 2] - bodies.theta0[i]
            u = 0.0
            ud = 0.0
            for j in range(nh):
                u += G[lk, d, j] * q[h0 + j]
                ud += G[lk, d, j] * qd[h0 + j]
            Fb[i, d] += k * u + c * ud
            f = -k * (rel - u) - c * (vel[i, d] - ud)
            for j in range(nh):
                rhs[h0 + j] -= G[lk, d, j] * f
            for a in range(n):
                jd = J[i, d, a]
                if jd == 0.0:
                    continue
                for j in range(nh):
                    g = G[lk, d, j]
                    Kt[a, h0 + j] -= k * jd * g
                    Kt[h0 + j, a] -= k * jd * g
                    Ct[a, h0 + j] -= c * jd * g
                    Ct[h0 + j, a] -= c * jd * g


@kernel(error_model="numpy")
def housing_solve(system, b, ck, cc, housing):
    """``x`` of ``A x = b`` for the Newton matrix ``A = Mq + ck Kt + cc Ct`` of ``system`` (ck,
    cc: the HHT coefficients of a step, (1 + alpha) beta h^2 [s^2] and (1 + alpha) gamma h [s])
    with the housing's coordinates last, by the Schur complement of the housing block:
    ``(A_gg - A_gh A_hh^-1 A_hg) x_g = b_g - A_gh A_hh^-1 b_h``, then ``x_h = A_hh^-1 (b_h -
    A_hg x_g)``.

    The housing block and its coupling to the rest are constant for given coefficients (the
    housing is linear, its seated bodies sit on elastic bearings to ground, whose Jacobian rows
    are constant: :func:`~flexgear.dynamics.model.housing.couple_housing`), so ``A_hh^-1``,
    ``A_hh^-1 A_hg``, ``A_gh`` and ``A_gh A_hh^-1 A_hg`` are kept in the table and made again
    only when the coefficients change beyond round-off (1e-9 of them: the step's ``t_target - t``
    varies in its last bits; a Newton matrix that close leaves the converged step unchanged).
    Each iteration then forms and solves the rest's block alone."""
    h0 = housing.first
    Mq = system.mass
    Kt = system.stiffness
    Ct = system.damping
    n = b.shape[0]
    key = housing.solver_key
    if abs(key[0] - ck) > 1e-9 * ck or abs(key[1] - cc) > 1e-9 * cc:
        A = Mq + ck * Kt + cc * Ct
        inv = np.linalg.inv(np.ascontiguousarray(A[h0:, h0:]))
        X = inv @ np.ascontiguousarray(A[h0:, :h0])
        housing.solver_inverse[:, :] = inv
        housing.solver_coupling[:, :] = X
        housing.solver_cross[:, :] = A[:h0, h0:]
        housing.solver_correction[:, :] = np.ascontiguousarray(A[:h0, h0:]) @ X
        key[0] = ck
        key[1] = cc
    S = np.empty((h0, h0))
    for r in range(h0):
        for s in range(h0):
            S[r, s] = Mq[r, s] + ck * Kt[r, s] + cc * Ct[r, s] - housing.solver_correction[r, s]
    y = housing.solver_inverse @ np.ascontiguousarray(b[h0:])
    xg = np.linalg.solve(S, np.ascontiguousarray(b[:h0]) - housing.solver_cross @ y)
    x = np.empty(n)
    x[:h0] = xg
    x[h0:] = y - housing.solver_coupling @ xg
    return x
