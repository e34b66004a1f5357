"""Time integration: HHT-alpha (Hilber-Hughes-Taylor) with Newton iterations, compiled.

Equations of motion in the generalised coordinates q of :mod:`flexgear.bodies`::

    Mq(q) q'' = Q(q, q', t) - sum_b J_b^T M_b gamma_b

with J_b the Jacobian of body b's pose and gamma_b its convective acceleration. HHT-alpha
(alpha in [-1/3, 0], beta = (1 - alpha)^2 / 4, gamma = 1/2 - alpha) is second-order accurate,
unconditionally stable for linear systems and damps the high-frequency content that stiff,
switching tooth contact excites; it is the integrator ADAMS itself uses by default. Each step
is solved by Newton's method with the analytic tangent of the contact and bearing forces
(the geometric stiffness of the contact normals is left out: the iteration converges to the
same solution). A step whose Newton iteration does not converge is retried with half the step,
down to step/64; below that, or on a non-finite state or a penetration beyond the geometric
limit, the run stops with a :class:`~flexgear.errors.DivergenceError` that says when and where.

The whole time loop (kinematics, contact search, assembly, Newton) runs in numba; Python
calls it in chunks to update the progress bar.
"""
from __future__ import annotations

import math
import time as _time

import numba as nb
import numpy as np

from .bodies import ANGLE_PRESCRIBED, ANGLE_SPRING, BEARING, MAXC, Model
from .contact import impact_force, mesh_contacts, step
from ..errors import DivergenceError

# full contact search every this many steps (200 us at the default 25 us step); in between the
# contacts and the near-contacts within CACHE_SAMPLES samples are followed locally. A surface
# not followed would have to close 160 um in 200 us (0.8 m/s) to be missed for a step.
FULL_SEARCH_EVERY = 8

# error codes returned by the kernel
OK, ERR_NEWTON, ERR_NAN, ERR_PENETRATION = 0, 1, 2, 3


@nb.njit(cache=True)
def _profile(prof_t, prof_v, prof_i, off, pid, t):
    """Value, slope and integral (from 0) of profile pid at time t."""
    i0 = off[pid]
    i1 = off[pid + 1]
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


@nb.njit(cache=True, inline="always")
def _anchor(i, par, b_flt, pose, vel):
    """Point ``pin`` of body i's parent (ground if par < 0): position, velocity and the arm
    (rx, ry) from the parent's centre, in the global frame."""
    if par < 0:
        return b_flt[i, 2], b_flt[i, 3], 0.0, 0.0, 0.0, 0.0
    c = math.cos(pose[par, 2])
    s = math.sin(pose[par, 2])
    rx = c * b_flt[i, 2] - s * b_flt[i, 3]
    ry = s * b_flt[i, 2] + c * b_flt[i, 3]
    w = vel[par, 2]
    return pose[par, 0] + rx, pose[par, 1] + ry, vel[par, 0] - w * ry, vel[par, 1] + w * rx, rx, ry


@nb.njit(cache=True, inline="always")
def _anchor_jacobian(J, par, rx, ry, j):
    """Column j of the Jacobian of the anchor point (x, y) of a body on parent par."""
    if par < 0:
        return 0.0, 0.0
    return J[par, 0, j] - ry * J[par, 2, j], J[par, 1, j] + rx * J[par, 2, j]


@nb.njit(cache=True)
def kinematics(q, qd, t, b_int, b_flt, prof_t, prof_v, prof_i, prof_off, pose, vel, J, gam):
    """Poses, velocities, Jacobians (nb, 3, n) and convective accelerations of all bodies."""
    nb_ = b_int.shape[0]
    J[:] = 0.0
    for i in range(nb_):
        jt = b_int[i, 0]
        rt = b_int[i, 1]
        par = b_int[i, 2]
        ix = b_int[i, 3]
        iy = b_int[i, 4]
        ith = b_int[i, 5]
        gam[i, 0] = 0.0
        gam[i, 1] = 0.0
        gam[i, 2] = 0.0
        # rotation
        if ith >= 0:
            pose[i, 2] = q[ith]
            vel[i, 2] = qd[ith]
            J[i, 2, ith] = 1.0
        elif rt == ANGLE_PRESCRIBED:
            w, a, integ = _profile(prof_t, prof_v, prof_i, prof_off, b_int[i, 6], t)
            pose[i, 2] = b_flt[i, 4] + integ
            vel[i, 2] = w
            gam[i, 2] = a
        else:
            pose[i, 2] = b_flt[i, 4]
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
            ax, ay, avx, avy, rx, ry = _anchor(i, par, b_flt, pose, vel)
            pose[i, 0] = ax
            pose[i, 1] = ay
            vel[i, 0] = avx
            vel[i, 1] = avy
            if par >= 0:
                for j in range(J.shape[2]):
                    J[i, 0, j], J[i, 1, j] = _anchor_jacobian(J, par, rx, ry, j)
                w = vel[par, 2]
                gam[i, 0] = gam[par, 0] - ry * gam[par, 2] - w * w * rx
                gam[i, 1] = gam[par, 1] + rx * gam[par, 2] - w * w * ry


@nb.njit(cache=True)
def forces(q, qd, t, b_int, b_flt, prof_t, prof_v, prof_i, prof_off, m_int, m_flt,
           outlines, out_off, out_nh, out_ds, out_tip, sdf_grids, sdf_off, sdf_shape, sdf_f, gear_z, stride,
           pose, vel, J, gam, Fb, rhs, Mq, Kt, Ct, cf, ci, ccount, mesh_out, max_depth, local, cache, ncache):
    """Generalised force (rhs = Q - J^T M gamma), mass matrix, tangent stiffness and damping.

    Also fills the per-mesh contact arrays (cf: force, depth, px, py, nx, ny; ci: tooth a,
    tooth b, side a), the mesh totals mesh_out (normal force sum, Fx, Fy on body b) and the
    body loads Fb. With ``local`` the contact search only refines the half teeth that the
    last full search remembered (``cache``, ``ncache`` per mesh). Returns the mesh with the
    largest penetration (its depth in max_depth[0]).
    """
    n = q.shape[0]
    nb_ = b_int.shape[0]
    kinematics(q, qd, t, b_int, b_flt, prof_t, prof_v, prof_i, prof_off, pose, vel, J, gam)
    Fb[:] = 0.0
    Kt[:] = 0.0
    Ct[:] = 0.0
    rhs[:] = 0.0
    Mq[:] = 0.0
    D = np.zeros((2, n))
    for i in range(nb_):
        # applied torque with smooth ramp
        tp = b_int[i, 7]
        if tp >= 0:
            T, _, _ = _profile(prof_t, prof_v, prof_i, prof_off, tp, t)
            ramp = b_flt[i, 9]
            if ramp > 0.0:
                T *= step(t, 0.0, 0.0, ramp, 1.0)
            Fb[i, 2] += T
        # torsional support
        if b_int[i, 1] == ANGLE_SPRING:
            ith = b_int[i, 5]
            kt = b_flt[i, 7]
            ct = b_flt[i, 8]
            Fb[i, 2] += -kt * (pose[i, 2] - b_flt[i, 4]) - ct * vel[i, 2]
            Kt[ith, ith] += kt
            Ct[ith, ith] += ct
        # elastic bearing between the centre and its anchor
        if b_int[i, 0] == BEARING:
            par = b_int[i, 2]
            k = b_flt[i, 5]
            c = b_flt[i, 6]
            ax, ay, avx, avy, rx, ry = _anchor(i, par, b_flt, pose, vel)
            for j in range(n):
                jax, jay = _anchor_jacobian(J, par, rx, ry, j)
                D[0, j] = J[i, 0, j] - jax
                D[1, j] = J[i, 1, j] - jay
            fx = -k * (pose[i, 0] - ax) - c * (vel[i, 0] - avx)
            fy = -k * (pose[i, 1] - ay) - c * (vel[i, 1] - avy)
            Fb[i, 0] += fx
            Fb[i, 1] += fy
            if par >= 0:
                Fb[par, 0] -= fx
                Fb[par, 1] -= fy
                Fb[par, 2] -= (ax - pose[par, 0]) * fy - (ay - pose[par, 1]) * fx
            for a in range(n):
                for bb in range(n):
                    dd = D[0, a] * D[0, bb] + D[1, a] * D[1, bb]
                    Kt[a, bb] += k * dd
                    Ct[a, bb] += c * dd
    # tooth contact
    g = np.zeros(n)
    deepest = 0.0
    where = -1
    out_f = np.zeros((MAXC, 5))
    out_i = np.zeros((MAXC, 3), np.int64)
    for m in range(m_int.shape[0]):
        a = m_int[m, 0]
        b = m_int[m, 1]
        cnt = mesh_contacts(pose[a], pose[b], m_int[m, 2], m_int[m, 3], m_int[m, 4] == 1, outlines, out_off,
                            out_nh, out_ds, out_tip, sdf_grids, sdf_off, sdf_shape, sdf_f, gear_z, m_int[m, 5],
                            m_int[m, 6], stride, out_f, out_i, local, cache[m], ncache[m])
        ccount[m] = cnt
        K = m_flt[m, 0]
        e = m_flt[m, 1]
        C = m_flt[m, 2]
        dd = m_flt[m, 3]
        sumF = 0.0
        fxb = 0.0
        fyb = 0.0
        for c in range(cnt):
            depth = out_f[c, 0]
            px = out_f[c, 1]
            py = out_f[c, 2]
            nx = out_f[c, 3]
            ny = out_f[c, 4]
            if depth > deepest:
                deepest = depth
                where = m
            # material velocities of the contact point on a and b
            vax = vel[a, 0] - vel[a, 2] * (py - pose[a, 1])
            vay = vel[a, 1] + vel[a, 2] * (px - pose[a, 0])
            vbx = vel[b, 0] - vel[b, 2] * (py - pose[b, 1])
            vby = vel[b, 1] + vel[b, 2] * (px - pose[b, 0])
            ddot = nx * (vbx - vax) + ny * (vby - vay)
            F, dF, cd = impact_force(depth, ddot, K, e, C, dd)
            cf[m, c, 0] = F
            cf[m, c, 1] = depth
            cf[m, c, 2] = px
            cf[m, c, 3] = py
            cf[m, c, 4] = nx
            cf[m, c, 5] = ny
            ci[m, c, 0] = out_i[c, 0]
            ci[m, c, 1] = out_i[c, 1]
            ci[m, c, 2] = out_i[c, 2]
            if F <= 0.0:
                continue
            sumF += F
            ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
            mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
            Fb[a, 0] += F * nx
            Fb[a, 1] += F * ny
            Fb[a, 2] += F * ma
            Fb[b, 0] -= F * nx
            Fb[b, 1] -= F * ny
            Fb[b, 2] -= F * mb
            fxb -= F * nx
            fyb -= F * ny
            # gradient of the penetration w.r.t. q
            for j in range(n):
                g[j] = -(nx * J[a, 0, j] + ny * J[a, 1, j] + ma * J[a, 2, j]) + (
                    nx * J[b, 0, j] + ny * J[b, 1, j] + mb * J[b, 2, j])
            for r in range(n):
                if g[r] == 0.0:
                    continue
                for s in range(n):
                    Kt[r, s] += dF * g[r] * g[s]
                    Ct[r, s] += cd * g[r] * g[s]
        mesh_out[m, 0] = sumF
        mesh_out[m, 1] = fxb
        mesh_out[m, 2] = fyb
    # assemble the generalised quantities
    for i in range(nb_):
        mi = b_flt[i, 0]
        Ii = b_flt[i, 1]
        for r in range(n):
            jr0 = J[i, 0, r]
            jr1 = J[i, 1, r]
            jr2 = J[i, 2, r]
            if jr0 == 0.0 and jr1 == 0.0 and jr2 == 0.0:
                continue
            rhs[r] += jr0 * (Fb[i, 0] - mi * gam[i, 0]) + jr1 * (Fb[i, 1] - mi * gam[i, 1]) + jr2 * (
                Fb[i, 2] - Ii * gam[i, 2])
            for s in range(n):
                Mq[r, s] += mi * (jr0 * J[i, 0, s] + jr1 * J[i, 1, s]) + Ii * jr2 * J[i, 2, s]
    max_depth[0] = deepest
    return where


@nb.njit(cache=True)
def integrate(q, v, acc, t0, h, nsteps, out_every, alpha, tol, max_newton, scale, depth_limit, full_every,
              b_int, b_flt, prof_t, prof_v, prof_i, prof_off, m_int, m_flt,
              outlines, out_off, out_nh, out_ds, out_tip, sdf_grids, sdf_off, sdf_shape, sdf_f, gear_z, stride,
              rec_mesh, rec_body, rec_pair_f, rec_pair_i, stats):
    """Advance (q, v, acc) from t0 by nsteps steps of h (sub-stepping on Newton failure).

    Records after every step: rec_mesh (nsteps, nm, 3) normal force sum, Fx, Fy on body b;
    rec_body (nsteps, nb, 7) x, y, theta, vx, vy, omega, torque (drive torque of prescribed
    bodies, applied torque otherwise). Every out_every steps: rec_pair_f (nout, nm, MAXC, 2)
    force, depth; rec_pair_i (nout, nm, MAXC, 3) tooth a, tooth b, side a.
    stats: [steps, newton iterations, rejected steps, max iterations in a step, code, time, mesh].
    Returns the error code (0 = OK).
    """
    n = q.shape[0]
    nb_ = b_int.shape[0]
    nm = m_int.shape[0]
    beta = 0.25 * (1.0 - alpha) ** 2
    gamma_ = 0.5 - alpha
    pose = np.zeros((nb_, 3))
    vel = np.zeros((nb_, 3))
    J = np.zeros((nb_, 3, n))
    gam = np.zeros((nb_, 3))
    Fb = np.zeros((nb_, 3))
    rhs = np.zeros(n)
    Mq = np.zeros((n, n))
    Kt = np.zeros((n, n))
    Ct = np.zeros((n, n))
    cf = np.zeros((nm, MAXC, 6))
    ci = np.zeros((nm, MAXC, 3), np.int64)
    cc = np.zeros(nm, np.int64)
    mesh_out = np.zeros((nm, 3))
    md = np.zeros(1)
    cache = np.zeros((nm, 4 * MAXC, 4), np.int64)
    ncache = np.zeros((nm, 1), np.int64)
    rhs_n = np.zeros(n)
    # forces at the start
    forces(q, v, t0, b_int, b_flt, prof_t, prof_v, prof_i, prof_off, m_int, m_flt, outlines, out_off,
           out_nh, out_ds, out_tip, sdf_grids, sdf_off, sdf_shape, sdf_f, gear_z, stride, pose, vel, J, gam, Fb, rhs,
           Mq, Kt, Ct, cf, ci, cc, mesh_out, md, False, cache, ncache)
    rhs_n[:] = rhs
    t = t0
    qn = q.copy()
    vn = v.copy()
    an = acc.copy()
    a = np.zeros(n)
    qq = np.zeros(n)
    vv = np.zeros(n)
    since_full = 0
    retry = False
    for k in range(nsteps):
        t_target = t0 + (k + 1) * h
        hl = h
        while t < t_target - 1e-15 * h:
            if t + hl > t_target:
                hl = t_target - t
            # Newton on the new acceleration
            a[:] = an
            conv = False
            it = 0
            where = -1
            while it < max_newton:
                it += 1
                for j in range(n):
                    qq[j] = qn[j] + hl * vn[j] + hl * hl * ((0.5 - beta) * an[j] + beta * a[j])
                    vv[j] = vn[j] + hl * ((1.0 - gamma_) * an[j] + gamma_ * a[j])
                full = it == 1 and (since_full >= full_every or retry)
                if full:
                    since_full = 0
                where = forces(qq, vv, t + hl, b_int, b_flt, prof_t, prof_v, prof_i, prof_off, m_int, m_flt,
                               outlines, out_off, out_nh, out_ds, out_tip, sdf_grids, sdf_off, sdf_shape, sdf_f, gear_z,
                               stride, pose, vel, J, gam, Fb, rhs, Mq, Kt, Ct, cf, ci, cc, mesh_out, md, not full,
                               cache, ncache)
                R = Mq @ a - (1.0 + alpha) * rhs + alpha * rhs_n
                A = Mq + (1.0 + alpha) * (beta * hl * hl * Kt + gamma_ * hl * Ct)
                da = np.linalg.solve(A, -R)
                fin = True
                dq = 0.0
                for j in range(n):
                    a[j] += da[j]
                    if not math.isfinite(a[j]):
                        fin = False
                    x = abs(beta * hl * hl * da[j]) * scale[j]
                    if x > dq:
                        dq = x
                if not fin:
                    break
                if dq < tol:
                    conv = True
                    break
            stats[1] += it
            if it > stats[3]:
                stats[3] = it
            if md[0] > depth_limit:
                stats[4] = ERR_PENETRATION
                stats[5] = t + hl
                stats[6] = where
                return ERR_PENETRATION
            if not conv:
                stats[2] += 1
                retry = True
                hl = 0.5 * hl
                if hl < h / 64.0:
                    stats[4] = ERR_NEWTON if fin else ERR_NAN
                    stats[5] = t
                    stats[6] = where
                    return int(stats[4])
                continue
            # accept: the state at t + hl; forces and records are those of the last Newton
            # evaluation, which differs from the final state by less than the tolerance
            retry = False
            since_full += 1
            for j in range(n):
                qq[j] = qn[j] + hl * vn[j] + hl * hl * ((0.5 - beta) * an[j] + beta * a[j])
                vv[j] = vn[j] + hl * ((1.0 - gamma_) * an[j] + gamma_ * a[j])
            for j in range(n):
                if not (math.isfinite(qq[j]) and math.isfinite(vv[j])):
                    stats[4] = ERR_NAN
                    stats[5] = t + hl
                    stats[6] = -1
                    return ERR_NAN
            qn[:] = qq
            vn[:] = vv
            an[:] = a
            rhs_n[:] = rhs
            t += hl
            stats[0] += 1
            if hl < h:
                hl = min(2.0 * hl, h)
        # record
        for m in range(nm):
            rec_mesh[k, m, 0] = mesh_out[m, 0]
            rec_mesh[k, m, 1] = mesh_out[m, 1]
            rec_mesh[k, m, 2] = mesh_out[m, 2]
        for i in range(nb_):
            for c in range(3):
                rec_body[k, i, c] = pose[i, c]
                rec_body[k, i, 3 + c] = vel[i, c]
            if b_int[i, 1] == ANGLE_PRESCRIBED:
                rec_body[k, i, 6] = b_flt[i, 1] * gam[i, 2] - Fb[i, 2]
            else:
                rec_body[k, i, 6] = 0.0
        if (k + 1) % out_every == 0:
            o = (k + 1) // out_every - 1
            for m in range(nm):
                for c in range(MAXC):
                    if c < cc[m]:
                        rec_pair_f[o, m, c, 0] = cf[m, c, 0]
                        rec_pair_f[o, m, c, 1] = cf[m, c, 1]
                        rec_pair_i[o, m, c, 0] = ci[m, c, 0]
                        rec_pair_i[o, m, c, 1] = ci[m, c, 1]
                        rec_pair_i[o, m, c, 2] = ci[m, c, 2]
                    else:
                        rec_pair_f[o, m, c, 0] = 0.0
                        rec_pair_f[o, m, c, 1] = 0.0
                        rec_pair_i[o, m, c, 0] = -1
                        rec_pair_i[o, m, c, 1] = -1
                        rec_pair_i[o, m, c, 2] = 0
    q[:] = qn
    v[:] = vn
    acc[:] = an
    return OK


def initial_acceleration(model: Model, arr, tables, q, v, stride):
    """Solve Mq a0 = rhs(q0, v0, 0)."""
    n = len(q)
    nb_ = len(model.bodies)
    nm = len(model.meshes)
    bufs = _buffers(n, nb_, nm)
    forces(q, v, 0.0, arr["b_int"], arr["b_flt"], arr["prof_t"], arr["prof_v"], arr["prof_i"], arr["prof_off"],
           arr["m_int"], arr["m_flt"], tables.outlines, tables.out_off, tables.out_nh, tables.out_ds, tables.out_tip,
           tables.sdf_grids, tables.sdf_off, tables.sdf_shape, tables.sdf_f, tables.gear_z, stride, *bufs,
           False, np.zeros((nm, 4 * MAXC, 4), np.int64), np.zeros((nm, 1), np.int64))
    rhs, Mq = bufs[5], bufs[6]
    return np.linalg.solve(Mq, rhs), bufs


def _buffers(n, nb_, nm):
    return (np.zeros((nb_, 3)), np.zeros((nb_, 3)), np.zeros((nb_, 3, n)), np.zeros((nb_, 3)), np.zeros((nb_, 3)),
            np.zeros(n), np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n)), np.zeros((nm, MAXC, 6)),
            np.zeros((nm, MAXC, 3), np.int64), np.zeros(nm, np.int64), np.zeros((nm, 3)), np.zeros(1))


def evaluate(model: Model, q, v, t=0.0, stride=16):
    """Forces and contacts of the model in state (q, v) at time t (for checks and tests).

    Returns a dict with the body loads ``Fb`` (nb, 3), mesh totals ``mesh`` (nm, 3), contact
    arrays ``cf`` (nm, MAXC, 6: force, depth, px, py, nx, ny), ``ci`` and counts ``count``.
    """
    arr = model.pack()
    _, bufs = initial_acceleration(model, arr, model.tables, np.asarray(q, float), np.asarray(v, float), stride)
    pose, vel, J, gam, Fb, rhs, Mq, Kt, Ct, cf, ci, cc, mesh_out, md = bufs
    return dict(pose=pose, vel=vel, Fb=Fb, rhs=rhs, Mq=Mq, Kt=Kt, Ct=Ct, cf=cf, ci=ci, count=cc, mesh=mesh_out,
                max_depth=md[0])


class Integration:
    """Result of :func:`simulate`: raw records on the integration grid plus statistics."""

    def __init__(self, **kw):
        self.__dict__.update(kw)


def simulate(model: Model, t_end: float, h: float, out_every: int, alpha: float = -0.1, tol: float = 1e-10,
             max_newton: int = 12, stride: int = 16, chunk_steps: int = 2000, progress=None,
             depth_limit: float | None = None, full_every: int = FULL_SEARCH_EVERY) -> Integration:
    """Integrate the model from 0 to t_end with step h (t_end/h steps, a multiple of out_every).

    Parameters
    ----------
    progress : callable(fraction) or None
        Called after every chunk with the simulated fraction done.
    depth_limit : float
        Penetration [m] beyond which the run is declared diverged (default: a quarter module of
        the first mesh's gears).

    Raises
    ------
    DivergenceError
        With the simulated time, the mesh or coordinate and the cause.

    Notes
    -----
    The returned ``wall`` [s] times the integration only. The first call in a process compiles
    the time loop (or loads numba's disk cache) first; that time is ``compile_seconds`` (0 when
    the loop was already compiled in this process).
    """
    arr = model.pack()
    tables = model.tables
    q, v = model.initial_state()
    n = len(q)
    nb_, nm = len(model.bodies), len(model.meshes)
    nsteps = int(round(t_end / h))
    nsteps -= nsteps % out_every
    if depth_limit is None:
        depth_limit = model.attrs.get("depth_limit", 5e-4)
    try:
        acc, _ = initial_acceleration(model, arr, tables, q, v, stride)
    except np.linalg.LinAlgError:
        acc = np.full(n, np.nan)
    if not np.all(np.isfinite(acc)):
        raise DivergenceError(
            "simulation diverged at t = 0.000000 s in the bodies' coordinates: the initial accelerations are not "
            "finite (a singular mass matrix or non-finite forces: check masses, inertias, densities, loads and "
            "contact parameters for extreme values)")
    scale = np.ones(n)
    for i, name in enumerate(model.coordinate_names()):
        if name.endswith(".theta"):
            scale[i] = model.length_scale
    rec_mesh = np.zeros((nsteps, nm, 3))
    rec_body = np.zeros((nsteps, nb_, 7))
    nout = nsteps // out_every
    rec_pair_f = np.zeros((nout, nm, MAXC, 2))
    rec_pair_i = np.zeros((nout, nm, MAXC, 3), np.int64)
    stats = np.zeros(7)
    compile_seconds = 0.0
    if not integrate.signatures:  # compile (or load numba's disk cache) apart from the timed loop
        t0 = _time.perf_counter()
        integrate(q.copy(), v.copy(), acc.copy(), 0.0, h, 0, out_every, alpha, tol, max_newton, scale, depth_limit,
                  full_every, arr["b_int"], arr["b_flt"], arr["prof_t"], arr["prof_v"], arr["prof_i"],
                  arr["prof_off"], arr["m_int"], arr["m_flt"], tables.outlines, tables.out_off, tables.out_nh,
                  tables.out_ds, tables.out_tip, tables.sdf_grids, tables.sdf_off, tables.sdf_shape, tables.sdf_f,
                  tables.gear_z, stride, rec_mesh[:0], rec_body[:0], rec_pair_f[:0], rec_pair_i[:0], np.zeros(7))
        compile_seconds = _time.perf_counter() - t0
    wall0 = _time.perf_counter()
    done = 0
    t = 0.0
    chunk = max(out_every, (chunk_steps // out_every) * out_every)
    while done < nsteps:
        k = min(chunk, nsteps - done)
        o0 = done // out_every
        try:
            code = integrate(q, v, acc, t, h, k, out_every, alpha, tol, max_newton, scale, depth_limit, full_every,
                             arr["b_int"], arr["b_flt"], arr["prof_t"], arr["prof_v"], arr["prof_i"], arr["prof_off"],
                             arr["m_int"], arr["m_flt"], tables.outlines, tables.out_off, tables.out_nh, tables.out_ds,
                             tables.out_tip, tables.sdf_grids, tables.sdf_off, tables.sdf_shape, tables.sdf_f,
                             tables.gear_z, stride, rec_mesh[done:done + k], rec_body[done:done + k],
                             rec_pair_f[o0:o0 + k // out_every], rec_pair_i[o0:o0 + k // out_every], stats)
        except np.linalg.LinAlgError:  # raised by the compiled solve on a non-finite Newton matrix
            raise DivergenceError(
                f"simulation diverged at t = {t:.6f} s (within the next {k * h:.3g} s) in the bodies' coordinates: "
                "the Newton matrix became non-finite (NaN/inf); check masses, inertias, loads and contact "
                "parameters for extreme values") from None
        if code != OK:
            tt = stats[5]
            wm = int(stats[6])
            where = f"mesh '{model.meshes[wm].name}'" if 0 <= wm < nm else "the bodies' coordinates"
            if code == ERR_PENETRATION:
                cause = (f"tooth penetration exceeded the limit {depth_limit*1e3:.3g} mm (the gears pass through "
                         "each other: load too high for the contact stiffness, or a step too large)")
            elif code == ERR_NAN:
                cause = "the state became non-finite (NaN/inf)"
            else:
                cause = (f"Newton's method did not converge in {max_newton} iterations even with the step "
                         f"reduced to {h/64:.3g} s")
            raise DivergenceError(f"simulation diverged at t = {tt:.6f} s in {where}: {cause}")
        done += k
        t = done * h
        if progress is not None:
            progress(done / nsteps)
    wall = _time.perf_counter() - wall0
    return Integration(h=h, nsteps=nsteps, out_every=out_every, mesh=rec_mesh, body=rec_body, pair_f=rec_pair_f,
                       pair_i=rec_pair_i, steps=int(stats[0]), newton=int(stats[1]), rejected=int(stats[2]),
                       max_iter=int(stats[3]), wall=wall, compile_seconds=compile_seconds, q=q, v=v)


def compiled_cache_present() -> bool:
    """Whether numba's on-disk cache of the time loop exists (else the next run compiles it,
    which takes about 40 s on 2 cores)."""
    import os
    from pathlib import Path

    moved = os.environ.get("NUMBA_CACHE_DIR")  # numba then caches there only
    if moved:
        return any(Path(moved).glob("**/solver.integrate-*.nbi"))
    here = Path(__file__).resolve().parent / "__pycache__"
    return any(here.glob("solver.integrate-*.nbi"))

