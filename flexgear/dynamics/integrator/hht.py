"""HHT-alpha (Hilber-Hughes-Taylor) coefficients and the Newmark update, shared by the time loop
(:mod:`flexgear.dynamics.integrator.solver`) and the condensed modes integrated inside the contact solve (:mod:`flexgear.dynamics.flexible.condensed`).

With ``alpha`` in [-1/3, 0], ``beta = (1 - alpha)^2 / 4`` and ``gamma = 1/2 - alpha`` the scheme
is second-order accurate and unconditionally stable for linear systems; a step h from (q_n,
v_n, a_n) to the end acceleration a gives::

    q = q_n + h v_n + h^2 ((1/2 - beta) a_n + beta a)
    v = v_n + h ((1 - gamma) a_n + gamma a)

and the equations of motion are met as ``M a + (1 + alpha) (f(q, v) - Q) - alpha (f - Q)_n = 0``
(Hilber, Hughes & Taylor 1977).
"""
from __future__ import annotations

from ...kernels import kernel


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
