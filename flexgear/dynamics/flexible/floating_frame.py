"""Modal coordinates of flexible bodies in the solver: the planar floating frame, linearised.

A flexible gear's modes below ``[flexible] dynamic_cutoff`` are generalised coordinates
``eta`` (mass-normalised fixed-interface modes of the Craig-Bampton body, expressed in the body
frame, which is the rigid body's pose x, y, theta; see :class:`flexgear.dynamics.model.tables.FlexTable`). A material
point sits at ``r = r_c + R(theta) (X + Phi eta)``. Kinetic energy kept::

    T = 1/2 m |r_c'|^2 + 1/2 J theta'^2 + r_c'^T R(theta) S_t eta' + theta' S_r eta' + 1/2 eta'^T eta'

with ``[S_t; S_r] = R^T M Phi`` the off-diagonal block of the reduced mass matrix (frame x, y,
theta against the modes; :meth:`flexgear.reduction.body.ReducedBody.inertia_invariants`).
Lagrange's equations of this T (so the model is conservative: the free-vibration test of
``tests/test_flexible_modes.py`` checks the energy) give

* the mass matrix coupling ``Mq[eta, q] = (R S_t)^T J_xy + S_r J_theta`` (and its transpose),
  with the body's pose Jacobian J; the frame's convective acceleration ``gamma`` (a prescribed
  rotation, a planet on its carrier) loads the modes with ``-(R S_t)^T gamma_xy - S_r gamma_theta``;
* the quadratic-velocity terms of the turning coupling: ``+theta' (R S_t)^T E r_c'`` on the
  modes, ``-theta' E R S_t eta'`` on the frame's force and ``+r_c'^T E R S_t eta'`` on its
  torque (E: the 90-degree turn);
* ``eta'' + D eta' + Omega^2 eta = sum_contacts A_i F`` (stiffness omega_i^2, damping
  2 zeta omega_i).

Left out (linearised about the undeformed body): the gyroscopic ``2 theta' G eta'`` with
``G = Phi^T M E Phi``, the centrifugal softening ``-theta'^2 eta``, ``theta'' G eta``, the
centrifugal load ``theta'^2 Phi^T M X`` and the change of the frame's inertia with eta. Against
the modal stiffness they scale with ``theta' / omega_1`` (gyroscopic) and ``(theta' /
omega_1)^2`` (centrifugal): the presets' fastest gear (MERCURY 1-A sun, 30 Hz; spur pinion
10 Hz) against their first clamped modes (31-64 kHz; a ring on bolts 26 kHz) gives 1e-3 and 1e-6; with the softest mode
that a 25 us step can resolve (2 kHz) 1.5e-2 and 2e-4. The centrifugal expansion
``rho Omega^2 r^3 / E`` is 2e-11 m on the sun (tip radius 26 mm) at 30 Hz. So the terms stay below 1 % of the
modal stiffness for gear speeds up to omega_1 / 100 (gyroscopic: 260 Hz = 16,000 rpm for a
26 kHz first mode, 20 Hz for a 2 kHz one) and the neglected centrifugal part up to omega_1 / 10.
The tangent leaves out the derivatives of the rotated coupling with theta and of the
quadratic-velocity terms (Newton converges to the same solution).
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

