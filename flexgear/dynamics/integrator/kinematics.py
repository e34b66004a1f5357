"""Kinematics of the bodies: poses, velocities, pose Jacobians and convective accelerations from
the generalised coordinates, the joints and the prescribed speed profiles.
"""
from __future__ import annotations

import math


from ...kernels import kernel
from ..model.bodies import ANGLE_PRESCRIBED, BEARING



@kernel(error_model="numpy")
def profile_value(profiles, pid, t):
    """Value, slope and integral (from 0) of profile pid of ``profiles`` (a ProfileTable) at
    time t [s]."""
    prof_t = profiles.t
    prof_v = profiles.value
    prof_i = profiles.integral
    i0 = profiles.offset[pid]
    i1 = profiles.offset[pid + 1]
    n = i1 - i0
    if n == 1:
        v = prof_v[i0]
        return v, 0.0, v * t
    if t <= prof_t[i0]:
        v = prof_v[i0]
        return v, 0.0, v * (t - prof_t[i0]) + 0.0 + v * prof_t[i0]
    if t >= prof_t[i1 - 1]:
        v = prof_v[i1 - 1]
        return v, 0.0, prof_v[i0] * prof_t[i0] + prof_i[i1 - 1] + v * (t - prof_t[i1 - 1])
    k = i0
    while prof_t[k + 1] < t:
        k += 1
    dt = prof_t[k + 1] - prof_t[k]
    s = (prof_v[k + 1] - prof_v[k]) / dt
    v = prof_v[k] + s * (t - prof_t[k])
    integ = prof_v[i0] * prof_t[i0] + prof_i[k] + 0.5 * (prof_v[k] + v) * (t - prof_t[k])
    return v, s, integ


@kernel(error_model="numpy", inline="always")
def anchor(i, par, bodies, pose, vel):
    """Point ``pin`` of body i's parent (ground if par < 0): position, velocity and the arm
    (rx, ry) from the parent's centre, in the global frame."""
    if par < 0:
        return bodies.pin_x[i], bodies.pin_y[i], 0.0, 0.0, 0.0, 0.0
    c = math.cos(pose[par, 2])
    s = math.sin(pose[par, 2])
    rx = c * bodies.pin_x[i] - s * bodies.pin_y[i]
    ry = s * bodies.pin_x[i] + c * bodies.pin_y[i]
    w = vel[par, 2]
    return pose[par, 0] + rx, pose[par, 1] + ry, vel[par, 0] - w * ry, vel[par, 1] + w * rx, rx, ry


@kernel(error_model="numpy", inline="always")
def anchor_jacobian(J, par, rx, ry, j):
    """Column j of the Jacobian of the anchor point (x, y) of a body on parent par."""
    if par < 0:
        return 0.0, 0.0
    return J[par, 0, j] - ry * J[par, 2, j], J[par, 1, j] + rx * J[par, 2, j]


@kernel(error_model="numpy", inline="always")
def kinematics(q, qd, t, bodies, profiles, state):
    """Poses, velocities, Jacobians (nb, 3, n) and convective accelerations of all bodies
    (into ``state``, a BodyState)."""
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    gam = state.convective
    nb_ = bodies.joint.shape[0]
    J[:] = 0.0
    for i in range(nb_):
        jt = bodies.joint[i]
        rt = bodies.rotation[i]
        par = bodies.parent[i]
        ix = bodies.ix[i]
        iy = bodies.iy[i]
        ith = bodies.itheta[i]
        gam[i, 0] = 0.0
        gam[i, 1] = 0.0
        gam[i, 2] = 0.0
        # rotation
        if ith >= 0:
            pose[i, 2] = q[ith]
            vel[i, 2] = qd[ith]
            J[i, 2, ith] = 1.0
        elif rt == ANGLE_PRESCRIBED:
            w, a, integ = profile_value(profiles, bodies.speed_profile[i], t)
            pose[i, 2] = bodies.theta0[i] + integ
            vel[i, 2] = w
            gam[i, 2] = a
        else:
            pose[i, 2] = bodies.theta0[i]
            vel[i, 2] = 0.0
        # position
        if jt == BEARING:
            pose[i, 0] = q[ix]
            pose[i, 1] = q[iy]
            vel[i, 0] = qd[ix]
            vel[i, 1] = qd[iy]
            J[i, 0, ix] = 1.0
            J[i, 1, iy] = 1.0
        else:  # FIXED or REVOLUTE: the centre is the anchor point
            ax, ay, avx, avy, rx, ry = anchor(i, par, bodies, pose, vel)
            pose[i, 0] = ax
            pose[i, 1] = ay
            vel[i, 0] = avx
            vel[i, 1] = avy
            if par >= 0:
                for j in range(J.shape[2]):
                    J[i, 0, j], J[i, 1, j] = anchor_jacobian(J, par, rx, ry, j)
                w = vel[par, 2]
                gam[i, 0] = gam[par, 0] - ry * gam[par, 2] - w * w * rx
                gam[i, 1] = gam[par, 1] + rx * gam[par, 2] - w * w * ry
