"""The coupled housing's forces (:class:`~flexgear.dynamics.model.tables.HousingTable`): its
reduced stiffness, damping and mass, and the elastic bearings seated in it.

A seated bearing's spring-damper acts between the body's centre and its anchor moved by the
housing, ``f = -k (x - a0 - G q_h) - c (x' - G q_h')`` (G the link's rows; likewise a torsional
spring to ground about the anchor's rotation). :func:`~flexgear.dynamics.integrator.forces.bearings`
has already applied the ground part ``-k (x - a0) - c x'``; this adds the rest to the body and the
reaction ``-G^T f`` to the housing's coordinates, with the tangent terms of ``D = J_i - G``.
"""
from __future__ import annotations

from ...kernels import kernel
from ..model.bodies import ANGLE_SPRING


@kernel(error_model="numpy")
def housing_forces(housing, bodies, state, system):
    """Add the coupled housing to the body loads and ``system`` (rhs, Mq, Kt, Ct); nothing when
    ``housing`` is None (numba prunes the body at compile time: not inlined for that)."""
    if housing is None:
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
        for s in range(nh):
            kk = housing.stiffness[r, s]
            cc = housing.damping[r, s]
            rhs[h0 + r] -= kk * q[h0 + s] + cc * qd[h0 + s]
            Kt[h0 + r, h0 + s] += kk
            Ct[h0 + r, h0 + s] += cc
            Mq[h0 + r, h0 + s] += housing.mass[r, s]
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
                g = G[lk, d, j]
                if g == 0.0:
                    continue
                rhs[h0 + j] -= g * f
                for a in range(n):
                    jd = J[i, d, a]
                    if jd != 0.0:
                        Kt[a, h0 + j] -= k * jd * g
                        Kt[h0 + j, a] -= k * jd * g
                        Ct[a, h0 + j] -= c * jd * g
                        Ct[h0 + j, a] -= c * jd * g
                for s in range(nh):
                    Kt[h0 + j, h0 + s] += k * g * G[lk, d, s]
                    Ct[h0 + j, h0 + s] += c * g * G[lk, d, s]
