"""HHT-alpha (Hilber-Hughes-Taylor) coefficients and the Newmark update, shared by the time loop
(:mod:`flexgear.dynamics.integrator.time_loop`) and the condensed modes integrated inside the contact solve
(:mod:`flexgear.dynamics.flexible.condensed`); one Newton iteration of a step.

With ``alpha`` in [-1/3, 0], ``beta = (1 - alpha)^2 / 4`` and ``gamma = 1/2 - alpha`` the scheme
is second-order accurate and unconditionally stable for linear systems; a step h from (q_n,
v_n, a_n) to the end acceleration a gives::

    q = q_n + h v_n + h^2 ((1/2 - beta) a_n + beta a)
    v = v_n + h ((1 - gamma) a_n + gamma a)

and the equations of motion are met as ``M a + (1 + alpha) (f(q, v) - Q) - alpha (f - Q)_n = 0``
(Hilber, Hughes & Taylor 1977).
"""
from __future__ import annotations

import math

import numpy as np

from ...kernels import kernel
from .housing import housing_solve


@kernel(error_model="numpy")
def hht_coefficients(alpha):
    """Newmark beta and gamma of HHT-alpha: beta = (1 - alpha)^2 / 4, gamma = 1/2 - alpha."""
    beta = 0.25 * (1.0 - alpha) ** 2
    gamma_ = 0.5 - alpha
    return beta, gamma_


@kernel(error_model="numpy", _nrt=False)
def predict(qn, vn, an, a, hl, beta, gamma_, qq, vv):
    """Newmark update: position qq and velocity vv at the end of a step hl from (qn, vn, an)
    with the end acceleration a."""
    for j in range(qn.shape[0]):
        qq[j] = qn[j] + hl * vn[j] + hl * hl * ((0.5 - beta) * an[j] + beta * a[j])
        vv[j] = vn[j] + hl * ((1.0 - gamma_) * an[j] + gamma_ * a[j])


@kernel(error_model="numpy")
def newton_update(system, rhs_n, a, alpha, beta, gamma_, hl, scale, housing):
    """One Newton iteration on the end acceleration ``a`` of a step hl: the HHT residual
    R = Mq a + I - (1 + alpha) Q(t + hl) + alpha Q(t) (``system.rhs``, ``rhs_n``; I the inertia
    forces at the step's end outside the weighting, ``system.inertia_load``) with its tangent
    Mq + (1 + alpha) (beta hl^2 Kt + gamma hl Ct) (``system``'s matrices). A coupled ``housing``
    (one with coordinates) is eliminated from the solve by its Schur complement
    (:func:`~flexgear.dynamics.integrator.housing.housing_solve`).

    Returns
    -------
    dq : float
        Largest position change beta hl^2 |da| of the iteration, in lengths (``scale``) [m].
    fin : bool
        All accelerations finite.
    """
    n = a.shape[0]
    Mq = system.mass
    R = Mq @ a + system.inertia_load - (1.0 + alpha) * system.rhs + alpha * rhs_n
    if housing.stiffness.shape[0] == 0:  # no coupled housing
        A = Mq + (1.0 + alpha) * (beta * hl * hl * system.stiffness + gamma_ * hl * system.damping)
        da = np.linalg.solve(A, -R)
    else:
        da = housing_solve(system, -R, (1.0 + alpha) * beta * hl * hl, (1.0 + alpha) * gamma_ * hl, housing)
    fin = True
    dq = 0.0
    for j in range(n):
        a[j] += da[j]
        if not math.isfinite(a[j]):
            fin = False
        x = abs(beta * hl * hl * da[j]) * scale[j]
        if x > dq:
            dq = x
    return dq, fin
