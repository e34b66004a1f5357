"""Modal coordinates of flexible bodies in the solver: the planar floating frame, linearised.

A flexible gear's modes below ``[flexible] dynamic_cutoff`` are coordinates ``eta``
(mass-normalised fixed-interface modes in the body frame; :class:`flexgear.dynamics.model.tables.FlexTable`).
A material point sits at ``r = r_c + R(theta) (X + Phi eta)``; the kinetic energy kept::

    T = 1/2 m |r_c'|^2 + 1/2 J theta'^2 + r_c'^T R(theta) S_t eta' + theta' S_r eta' + 1/2 eta'^T eta'

with ``[S_t; S_r] = R^T M Phi`` (:meth:`flexgear.reduction.body.ReducedBody.inertia_invariants`).
Lagrange's equations give the mass coupling ``Mq[eta, q] = (R S_t)^T J_xy + S_r J_theta``, the
load ``-(R S_t)^T gamma_xy - S_r gamma_theta`` of the frame's convective acceleration, the
quadratic-velocity terms of the turning coupling (E the 90-degree turn) and
``eta'' + D eta' + Omega^2 eta = sum A_i F``. Gyroscopic and centrifugal terms and the change of
the frame's inertia with eta are left out (small while gear speeds stay below omega_1 / 100);
the tangent leaves out the derivatives of the rotated coupling and of the quadratic-velocity
terms (Newton converges to the same solution). See the theory page *Compliant contact and
condensation*, section *Modes as coordinates*.
"""
from __future__ import annotations

import math

from ...kernels import kernel


@kernel(error_model="numpy", inline="always")
def modal_forces(flex, state, system):
    """Modal coordinates of the flexible bodies: their stiffness, damping and mass blocks, the
    frame-mode mass coupling, the convective and quadratic-velocity terms (see the module
    docstring) into ``system`` (rhs, Mq, Kt, Ct) and the body loads of ``state``. Call after
    the kinematics (``state`` poses, Jacobians, ``coordinates``, ``rates``) and before the
    generalised forces (which add J^T of the body loads)."""
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    gam = state.convective
    Fb = state.load
    q = state.coordinates
    qd = state.rates
    rhs = system.rhs
    Mq = system.mass
    Kt = system.stiffness
    Ct = system.damping
    n = rhs.shape[0]
    FC = flex.frame_coupling
    for f in range(flex.body.shape[0]):
        m = flex.modes[f]
        if m == 0:
            continue
        i = flex.body[f]
        c0 = flex.coordinate[f]
        mo = flex.matrix_offset[f]
        fo = flex.frame_offset[f]
        for k in range(m):
            r = c0 + k
            for l_ in range(m):
                kk = flex.stiffness[mo + k * m + l_]
                dd = flex.damping[mo + k * m + l_]
                rhs[r] -= kk * q[c0 + l_] + dd * qd[c0 + l_]
                Kt[r, c0 + l_] += kk
                Ct[r, c0 + l_] += dd
                Mq[r, c0 + l_] += flex.mass[mo + k * m + l_]
        cs = math.cos(pose[i, 2])
        sn = math.sin(pose[i, 2])
        w = vel[i, 2]
        px = 0.0
        py = 0.0
        for k in range(m):
            sx = FC[fo + k]
            sy = FC[fo + m + k]
            sr = FC[fo + 2 * m + k]
            gx = cs * sx - sn * sy
            gy = sn * sx + cs * sy
            r = c0 + k
            for s in range(n):
                u = J[i, 0, s] * gx + J[i, 1, s] * gy + J[i, 2, s] * sr
                if u != 0.0:
                    Mq[r, s] += u
                    Mq[s, r] += u
            rhs[r] -= gx * gam[i, 0] + gy * gam[i, 1] + sr * gam[i, 2]
            rhs[r] += w * (-gx * vel[i, 1] + gy * vel[i, 0])
            px += gx * qd[r]
            py += gy * qd[r]
        # p = R S_t eta' (global): force -w E p, torque r_c'^T E p on the frame
        Fb[i, 0] += w * py
        Fb[i, 1] -= w * px
        Fb[i, 2] += -vel[i, 0] * py + vel[i, 1] * px

