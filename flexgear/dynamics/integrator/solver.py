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

One-pass steps (``simulate(one_pass=...)``, on for models with flexible bodies). On the
flexible presets the first Newton correction of a step (median 1.8e-10 m of flank approach at
6.25 us) is above the tolerance (1e-10 m) in 96 % of the steps and the second is about 1e-5
of it: the iteration contracts quadratically, so the second force evaluation of almost every
step only confirms the first correction. A step is therefore accepted after one correction
d1 [m] (scaled as the tolerance) when

* the contraction estimates say that the next correction would be below ``tol``:
  ``max(rho d1, rho2 d1^2) < tol``, with rho [-] and rho2 [1/m] the largest ratios d2 / d1 and
  d2 / d1^2 seen on the steps that iterated (each sample decays by ``CONTRACTION_DECAY`` at
  the next one; a step with a full contact search, one in about ``CALIBRATE_STEPS``, iterates to give
  one; no one-pass step before the first sample of an :func:`integrate` call);
* the step is not a retry, the condensed modes are integrated (``condensation="integrated"``,
  the default; quasi-statically condensed, the mass matrix carries the flanks' inertia relief,
  which depends on the state), and
* the linearisation holds (:func:`linearised_acceptance`): no contact joins or leaves the
  active set within the correction's reach.

Everything the step records or carries forward (contact forces, depths and deflections, mesh
totals, body loads and drive torques, the condensed modes' loads and accelerations, the
generalised force the next step weights by alpha) is then moved from the evaluated iterate to
the corrected state with the evaluation's own tangent, and the body states are recorded at the
corrected state; so are those of a step whose iteration converged (the full iteration leaves
them at the last iterate, up to ``tol`` away; where the linearisation is refused such a step
evaluates once more unless its correction is below ``LAST_ITERATE`` x ``tol``). The errors are
of the order of the next correction. Against the full iteration converged to ``tol`` = 1e-13,
over 0.02 s of the flexible presets from the start at their 6.25 us step: mesh forces within
9e-5 (spur pair) and 2.4e-4 (MERCURY 1-A, its start transient ringing) of their RMS about the
mean, drive torques within 2e-6 and 7e-6, positions within 4e-11 m and angles within 4e-9 rad;
the full iteration at the default 1e-10 is off by 9e-4 and 0.12 in the mesh forces, 2e-4 and
4e-3 in the drive torques, 9e-9 m and 6e-7 rad (``tests/test_one_pass.py``). Evaluations per
step: 1.04 (spur pair) and 1.15 (MERCURY 1-A) against 1.92 and 1.99. A step that fails a
condition iterates as before. Rigid models keep the full iteration (their results are unchanged
to the bit).

The whole time loop (kinematics, contact search, assembly, Newton) runs in numba; Python
calls it in chunks to update the progress bar. The kernels take the model and their buffers as
named tables (:mod:`flexgear.dynamics.model.tables`)::

    forces(q, qd, t, model, contact, work, local)      kinematics, applied_torques,
                                                       torsional_supports, bearings,
                                                       tooth_contact, generalised_forces
    integrate(q, v, acc, t0, nsteps, model, contact,   predict, forces, newton_update,
              work, settings, records, stats)          record

Notes for kernel authors. Every array handed to a compiled function (also inside a table)
costs an atomic reference-count increment and decrement per call, so the kernels that run every
Newton iteration or step and create no arrays - :func:`forces` with everything it inlines,
:func:`~flexgear.dynamics.flexible.compliant.compliant_contacts`, the contact search, :func:`record` and
the other per-step writers - are compiled without reference counting (``_nrt=False``: they only
take views of their arguments, which outlive the call; a slice copy ``x[:] = y`` may allocate
there, so they copy element by element). With the one-pass steps above, that took the flexible
spur pair from 3.9 to 2.7 s per simulated second and the flexible MERCURY 1-A from 16.5 to 15 s
(bit-identical results; ``benchmarks/bench_flexible.py``).
The sub-kernels of :func:`forces` are ``inline="always"`` and take only the parts of the tables
they use (``work.bodies``, ``work.system``, ``work.contacts``; ``model.bodies``...). Numba's disk cache
of :func:`integrate` is keyed on this file only: after editing a kernel in another module
(:mod:`flexgear.dynamics.contact.search`), delete ``flexgear/dynamics/__pycache__/*.nb*`` or the cached time loop keeps
the old code.
"""
from __future__ import annotations

import math
import time as _time

import numba as nb

from ...kernels import kernel
import numpy as np

from ..model.bodies import ANGLE_PRESCRIBED, ANGLE_SPRING, BEARING, MAXC, Model
from ..flexible.joint import KNOWN
from ..contact.laws import LAW_HERTZ, hertz_line
from ..flexible.compliant import compliant_contacts
from ..flexible.flank import rigid_coordinates
from ..contact.laws import contact_load, impact_force, penetration_gradient, step
from ..contact.search import mesh_search
from ..flexible.floating_frame import modal_forces
from ..flexible.condensed import (INTEGRATED, STATIC, accept_condensed, frame_acceleration, frame_moves,
                                  mode_corrections, mode_frame_coupling, mode_inertia_load, start_condensed,
                                  static_condensed)
from .hht import hht_coefficients, predict
from ..model.tables import Settings, records as new_records, statistics as new_statistics, workspace
from ..threads import SpareCores, available_threads, check_threads, kernel_threads
from ...errors import DivergenceError

# a full contact search every FULL_SEARCH_INTERVAL of simulated time (full_search_every: 8 steps at
# the rigid presets' 25 us step, 32 at the flexible presets' 6.25 us); in between the contacts and
# the near-contacts within CACHE_SAMPLES samples are followed locally. A surface not followed would
# have to close 160 um in 200 us (0.8 m/s) to be missed for a step. The margin is a closing speed,
# so the interval is one of time, not of steps: 8 steps at any step gave the flexible presets 4 x
# the rigid baseline's margin for 4 x its full searches (on MERCURY 1-A about 6 % of a force
# evaluation; the same contacts over 0.12 s of both flexible presets either way).
FULL_SEARCH_INTERVAL = 200e-6  # s
# a full search scans every COARSE_STRIDE-th outline sample first (320 um at the default module/200
# spacing: the SDF is 1-Lipschitz, so a half tooth whose scanned samples all lie farther than
# half of that cannot touch), then refines around the nearest
COARSE_STRIDE = 32


def full_search_every(h: float) -> int:
    """Steps between two full contact searches at step ``h`` [s]: ``FULL_SEARCH_INTERVAL / h``
    rounded, at least 1 (8 at 25 us, 32 at 6.25 us)."""
    return max(1, int(round(FULL_SEARCH_INTERVAL / h)))


# one-pass steps (Settings.one_pass, :func:`linearised_acceptance`): an open compliant contact
# whose gap, less the change of its overlap, is below LINEAR_GAP times the Newton correction
# may close within the correction's reach (the flank deflection it gets from the other
# contacts' force change, C dF, is at most of the correction's order): the step iterates
LINEAR_GAP = 10.0
# the contraction estimates of the Newton iteration (second correction over the first, and over
# its square) keep the largest sample, decayed by this factor at each new sample (one every
# CALIBRATE_STEPS steps): a step that contracted badly holds one-pass steps back for a while
CONTRACTION_DECAY = 0.5
# a step with a full contact search, one in about CALIBRATE_STEPS steps (every
# max(1, CALIBRATE_STEPS // full_every)-th full search: 800 us at the flexible presets' 6.25 us,
# about 2.4 samples per sun-planet mesh period of MERCURY 1-A), always iterates to sample the
# contraction (one in 32 steps cost about 2 % more force evaluations on MERCURY 1-A)
CALIBRATE_STEPS = 128
# one-pass mode: a converged step that cannot move its records to the accepted state
# (linearised_acceptance refuses) evaluates once more unless its last correction is below
# LAST_ITERATE x tol (then its records are at an iterate that close to the accepted state)
LAST_ITERATE = 1e-3

#: ``simulate(condensation=...)``: the codes of :class:`~flexgear.dynamics.model.tables.Settings`
CONDENSATION = {"static": STATIC, "integrated": INTEGRATED}

# error codes returned by the kernel
OK, ERR_NEWTON, ERR_NAN, ERR_PENETRATION = 0, 1, 2, 3


@kernel(error_model="numpy")
def _profile(profiles, pid, t):
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
def _anchor(i, par, bodies, pose, vel):
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
def _anchor_jacobian(J, par, rx, ry, j):
    """Column j of the Jacobian of the anchor point (x, y) of a body on parent par."""
    if par < 0:
        return 0.0, 0.0
    return J[par, 0, j] - ry * J[par, 2, j], J[par, 1, j] + rx * J[par, 2, j]


# ---------------------------------------------------------------------------------------------
# Forces: kinematics, applied torques, supports, bearings, tooth contact, generalised forces


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
            w, a, integ = _profile(profiles, bodies.speed_profile[i], t)
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
            ax, ay, avx, avy, rx, ry = _anchor(i, par, bodies, pose, vel)
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


@kernel(error_model="numpy", inline="always")
def applied_torques(t, bodies, profiles, state):
    """Applied torques, each with its smooth ramp STEP(t; 0, 0, ramp, 1), into the body loads."""
    Fb = state.load
    for i in range(bodies.joint.shape[0]):
        tp = bodies.torque_profile[i]
        if tp >= 0:
            T, _, _ = _profile(profiles, tp, t)
            ramp = bodies.torque_ramp[i]
            if ramp > 0.0:
                T *= step(t, 0.0, 0.0, ramp, 1.0)
            Fb[i, 2] += T


@kernel(error_model="numpy", inline="always")
def torsional_supports(bodies, state, system):
    """Torsional spring-dampers (ANGLE_SPRING) to ground, or to the rotation of body
    ``torsion_parent`` (a shaft: twist = theta_i - theta_p - (theta0_i - theta0_p), reaction on
    the other body; the parent may be prescribed): body loads and tangent matrices."""
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    Fb = state.load
    Kt = system.stiffness
    Ct = system.damping
    n = system.rhs.shape[0]
    for i in range(bodies.joint.shape[0]):
        if bodies.rotation[i] == ANGLE_SPRING:
            ith = bodies.itheta[i]
            kt = bodies.torsional_stiffness[i]
            ct = bodies.torsional_damping[i]
            par = bodies.torsion_parent[i]
            if par < 0:
                Fb[i, 2] += -kt * (pose[i, 2] - bodies.theta0[i]) - ct * vel[i, 2]
                Kt[ith, ith] += kt
                Ct[ith, ith] += ct
                continue
            T = (-kt * (pose[i, 2] - pose[par, 2] - (bodies.theta0[i] - bodies.theta0[par]))
                 - ct * (vel[i, 2] - vel[par, 2]))
            Fb[i, 2] += T
            Fb[par, 2] -= T
            for a in range(n):
                da = J[i, 2, a] - J[par, 2, a]
                if da == 0.0:
                    continue
                for bb in range(n):
                    db = J[i, 2, bb] - J[par, 2, bb]
                    Kt[a, bb] += kt * da * db
                    Ct[a, bb] += ct * da * db


@kernel(error_model="numpy", inline="always")
def bearings(bodies, state, system):
    """Elastic bearings (BEARING) between each centre and its anchor: loads on the body and its
    parent, tangent matrices."""
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    Fb = state.load
    Kt = system.stiffness
    Ct = system.damping
    D = system.bearing_rows
    n = system.rhs.shape[0]
    for i in range(bodies.joint.shape[0]):
        if bodies.joint[i] == BEARING:
            par = bodies.parent[i]
            k = bodies.stiffness[i]
            c = bodies.damping[i]
            ax, ay, avx, avy, rx, ry = _anchor(i, par, bodies, pose, vel)
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


@kernel(error_model="numpy", inline="always")
def mesh_forces(m, meshes, contact, state, system, contacts, local):
    """Contacts of mesh m, their IMPACT forces, body loads and tangent matrices.

    Fills the mesh's rows of ``contacts`` (a ContactBuffers) and its totals (normal force sum,
    Fx, Fy on body b). Returns the largest penetration of the mesh [m] (0 without contact).
    """
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    Fb = state.load
    Kt = system.stiffness
    Ct = system.damping
    g = system.gradient
    out_f = contacts.found_f
    out_i = contacts.found_i
    c_force = contacts.force
    c_depth = contacts.depth
    c_x = contacts.x
    c_y = contacts.y
    c_nx = contacts.nx
    c_ny = contacts.ny
    c_ta = contacts.tooth_a
    c_tb = contacts.tooth_b
    c_sa = contacts.side_a
    n = system.rhs.shape[0]
    a = meshes.body_a[m]
    b = meshes.body_b[m]
    cnt = mesh_search(pose[a], pose[b], meshes.gear_a[m], meshes.gear_b[m], meshes.internal[m], contact,
                      meshes.ncand_a[m], meshes.ncand_b[m], meshes.stride[m], out_f, out_i, local,
                      contacts.search_cache[m], contacts.search_count[m])
    contacts.count[m] = cnt
    K = meshes.K[m]
    e = meshes.e[m]
    C = meshes.C[m]
    dd = meshes.d[m]
    deepest = 0.0
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
        # material velocities of the contact point on a and b
        vax = vel[a, 0] - vel[a, 2] * (py - pose[a, 1])
        vay = vel[a, 1] + vel[a, 2] * (px - pose[a, 0])
        vbx = vel[b, 0] - vel[b, 2] * (py - pose[b, 1])
        vby = vel[b, 1] + vel[b, 2] * (px - pose[b, 0])
        ddot = nx * (vbx - vax) + ny * (vby - vay)
        F, dF, cd = impact_force(depth, ddot, K, e, C, dd)
        c_force[m, c] = F
        c_depth[m, c] = depth
        c_x[m, c] = px
        c_y[m, c] = py
        c_nx[m, c] = nx
        c_ny[m, c] = ny
        c_ta[m, c] = out_i[c, 0]
        c_tb[m, c] = out_i[c, 1]
        c_sa[m, c] = out_i[c, 2]
        if F <= 0.0:
            continue
        sumF += F
        ma, mb = contact_load(Fb, pose, a, b, px, py, nx, ny, F)
        fxb -= F * nx
        fyb -= F * ny
        penetration_gradient(g, J, a, b, nx, ny, ma, mb, n)
        for r in range(n):
            if g[r] == 0.0:
                continue
            for s in range(n):
                Kt[r, s] += dF * g[r] * g[s]
                Ct[r, s] += cd * g[r] * g[s]
    contacts.mesh_force[m] = sumF
    contacts.mesh_fx[m] = fxb
    contacts.mesh_fy[m] = fyb
    return deepest


@kernel(error_model="numpy", inline="always")
def tooth_contact(meshes, flex, body_flex, contact, state, system, contacts, cst, local):
    """All meshes (:func:`mesh_forces`; the meshes with the compliant Hertz law, i.e. with a
    flexible gear, together in one contact problem:
    :func:`~flexgear.dynamics.flexible.compliant.compliant_contacts` with the FlexTable ``flex`` and the
    bodies' rows in it ``body_flex``); the largest penetration goes to
    ``contacts.max_depth[0]``. Returns the mesh with the largest penetration (-1: no
    contact)."""
    deepest = 0.0
    where = -1
    compliant = False
    for m in range(meshes.body_a.shape[0]):
        if meshes.law[m] == LAW_HERTZ:
            compliant = True
            continue
        dm = mesh_forces(m, meshes, contact, state, system, contacts, local)
        if dm > deepest:
            deepest = dm
            where = m
    if compliant:
        dm, wm = compliant_contacts(meshes, flex, body_flex, contact, state, system, contacts, cst, local)
        if dm > deepest:
            deepest = dm
            where = wm
    contacts.max_depth[0] = deepest
    return where


@kernel(error_model="numpy", inline="always")
def generalised_forces(bodies, state, system):
    """Generalised force rhs = J^T (F - M gamma) and mass matrix Mq = J^T M J from the body
    loads, Jacobians and convective accelerations."""
    J = state.jacobian
    gam = state.convective
    Fb = state.load
    rhs = system.rhs
    Mq = system.mass
    n = rhs.shape[0]
    for i in range(bodies.joint.shape[0]):
        mi = bodies.mass[i]
        Ii = bodies.inertia[i]
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


@kernel(error_model="numpy", _nrt=False)
def forces(q, qd, t, model, contact, work, local):
    """Generalised force (rhs = Q - J^T M gamma), mass matrix, tangent stiffness and damping.

    Parameters
    ----------
    q, qd : (n,) arrays
        Generalised coordinates and velocities [m, rad; m/s, rad/s].
    t : float
        Time [s].
    model : KernelModel
        Bodies, profiles, meshes, flexible bodies (:meth:`Model.pack`).
    contact : ContactTables
        Gear outlines and signed distance fields.
    work : Workspace
        Filled with poses, Jacobians, body loads (``work.bodies``), rhs, Mq, Kt, Ct
        (``work.system``), the contacts of every mesh and the mesh totals (``work.contacts``).
    local : bool
        The contact search only refines the half teeth that the last full search remembered
        (``work.contacts.search_cache``).

    Returns
    -------
    int
        The mesh with the largest penetration (its depth in ``work.contacts.max_depth[0]``),
        -1 if none.
    """
    bodies = model.bodies
    profiles = model.profiles
    state = work.bodies
    system = work.system
    kinematics(q, qd, t, bodies, profiles, state)
    coordinates = state.coordinates
    rates = state.rates
    for j in range(q.shape[0]):  # element by element: a slice copy may allocate (no NRT here)
        coordinates[j] = q[j]
        rates[j] = qd[j]
    state.load[:] = 0.0
    system.stiffness[:] = 0.0
    system.damping[:] = 0.0
    system.rhs[:] = 0.0
    system.inertia_load[:] = 0.0
    system.mass[:] = 0.0
    applied_torques(t, bodies, profiles, state)
    torsional_supports(bodies, state, system)
    bearings(bodies, state, system)
    where = tooth_contact(model.meshes, model.flex, bodies.flex, contact, state, system, work.contacts,
                          work.condensed, local)
    modal_forces(model.flex, state, system)
    generalised_forces(bodies, state, system)
    return where


# ---------------------------------------------------------------------------------------------
# Time integration: HHT coefficients, predictor, Newton, recording


@kernel(error_model="numpy")
def newton_update(Mq, Kt, Ct, rhs, rhs_n, inertia_load, a, alpha, beta, gamma_, hl, scale):
    """One Newton iteration on the end acceleration ``a`` of a step hl: the HHT residual
    R = Mq a + I - (1 + alpha) Q(t + hl) + alpha Q(t) (``rhs``, ``rhs_n``; I the inertia forces
    at the step's end outside the weighting, ``inertia_load``) with its tangent
    Mq + (1 + alpha) (beta hl^2 Kt + gamma hl Ct).

    Returns
    -------
    dq : float
        Largest position change beta hl^2 |da| of the iteration, in lengths (``scale``) [m].
    fin : bool
        All accelerations finite.
    """
    n = a.shape[0]
    R = Mq @ a + inertia_load - (1.0 + alpha) * rhs + alpha * rhs_n
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
    return dq, fin


@kernel(error_model="numpy", _nrt=False)
def record(k, rotation, inertia, state, contacts, out_every, records):
    """Write step k of the records: mesh totals, body states and drive torques (bodies with
    ``rotation`` ANGLE_PRESCRIBED, ``inertia`` [kg m^2]); every out_every steps the contact
    pairs."""
    pose = state.pose
    vel = state.vel
    gam = state.convective
    Fb = state.load
    mesh_force = contacts.mesh_force
    mesh_fx = contacts.mesh_fx
    mesh_fy = contacts.mesh_fy
    r_force = records.mesh_force
    r_fx = records.mesh_fx
    r_fy = records.mesh_fy
    r_x = records.x
    r_y = records.y
    r_theta = records.theta
    r_vx = records.vx
    r_vy = records.vy
    r_omega = records.omega
    r_torque = records.torque
    nm = mesh_force.shape[0]
    for m in range(nm):
        r_force[k, m] = mesh_force[m]
        r_fx[k, m] = mesh_fx[m]
        r_fy[k, m] = mesh_fy[m]
    for i in range(rotation.shape[0]):
        r_x[k, i] = pose[i, 0]
        r_y[k, i] = pose[i, 1]
        r_theta[k, i] = pose[i, 2]
        r_vx[k, i] = vel[i, 0]
        r_vy[k, i] = vel[i, 1]
        r_omega[k, i] = vel[i, 2]
        if rotation[i] == ANGLE_PRESCRIBED:
            r_torque[k, i] = inertia[i] * gam[i, 2] - Fb[i, 2]
        else:
            r_torque[k, i] = 0.0
    if (k + 1) % out_every == 0:
        o = (k + 1) // out_every - 1
        count = contacts.count
        c_force = contacts.force
        c_depth = contacts.depth
        c_ta = contacts.tooth_a
        c_tb = contacts.tooth_b
        c_sa = contacts.side_a
        p_force = records.pair_force
        p_depth = records.pair_depth
        p_ta = records.pair_tooth_a
        p_tb = records.pair_tooth_b
        p_sa = records.pair_side_a
        c_defl = contacts.deflection
        p_defl = records.pair_deflection
        for m in range(nm):
            for c in range(MAXC):
                if c < count[m]:
                    p_force[o, m, c] = c_force[m, c]
                    p_depth[o, m, c] = c_depth[m, c]
                    p_ta[o, m, c] = c_ta[m, c]
                    p_tb[o, m, c] = c_tb[m, c]
                    p_sa[o, m, c] = c_sa[m, c]
                    p_defl[o, m, c] = c_defl[m, c]
                else:
                    p_force[o, m, c] = 0.0
                    p_depth[o, m, c] = 0.0
                    p_ta[o, m, c] = -1
                    p_tb[o, m, c] = -1
                    p_sa[o, m, c] = 0
                    p_defl[o, m, c] = 0.0


@kernel(error_model="numpy", _nrt=False)
def record_condensed(o, flex, cst, state, integrated, out):
    """Write the condensed modes' coordinates eta_i of every flexible body into row o of
    ``out`` (``Records.condensed``, per mode at ``FlexTable.condensed_offset``) at a pair
    sample: integrated, their accepted state (``cst.position``); condensed quasi-statically,
    the static response the flank deflection of the last evaluation stands for, ``eta_i = (A_i
    . F + l_i) / omega_i^2`` with the frame's inertia load l_i (:mod:`flexgear.dynamics.flexible.condensed`) at the
    accelerations that evaluation used."""
    if out.shape[1] == 0:
        return
    if integrated:
        for j in range(out.shape[1]):
            out[o, j] = cst.position[j]
        return
    om = flex.condensed_omega
    W = flex.condensed_coupling
    vel = state.vel
    for f in range(flex.body.shape[0]):
        body = flex.body[f]
        nq = flex.condensed[f]
        o0 = flex.condensed_offset[f]
        ax, ay, ar = frame_acceleration(state.jacobian, state.accelerations, state.convective, body)
        cs = math.cos(state.pose[body, 2])
        sn = math.sin(state.pose[body, 2])
        w = vel[body, 2]
        for i in range(nq):
            j = o0 + i
            gx, gy, sr = mode_frame_coupling(W, o0, nq, i, cs, sn)
            ell = mode_inertia_load(gx, gy, sr, ax, ay, ar, w, vel[body, 0], vel[body, 1])
            out[o, j] = (cst.load[j] + ell) / (om[j] * om[j])


@kernel(error_model="numpy", _nrt=False)
def modal_drive_torque(k, acc, flex, rotation, records):
    """Add the modes' inertia reaction ``S_r . eta''`` (frame-mode coupling times the modal
    accelerations ``acc``) to the drive torque of a flexible body with prescribed rotation
    (step k): the drive supplies d/dt (J theta' + S_r eta')."""
    for f in range(flex.body.shape[0]):
        m = flex.modes[f]
        i = flex.body[f]
        if m == 0 or rotation[i] != ANGLE_PRESCRIBED:
            continue
        o = flex.frame_offset[f] + 2 * m
        c0 = flex.coordinate[f]
        for j in range(m):
            records.torque[k, i] += flex.frame_coupling[o + j] * acc[c0 + j]


@kernel(error_model="numpy", _nrt=False)
def condensed_drive_torque(k, flex, cst, rotation, records):
    """Add the integrated condensed modes' inertia reaction ``S_r . eta''`` (``cst``: the
    CondensedState) to the drive torque of a flexible body with prescribed rotation (step k),
    as :func:`modal_drive_torque` does for modal coordinates."""
    W = flex.condensed_coupling
    for f in range(flex.body.shape[0]):
        i = flex.body[f]
        if rotation[i] != ANGLE_PRESCRIBED:
            continue
        nq = flex.condensed[f]
        o = flex.condensed_offset[f]
        for j in range(nq):
            records.torque[k, i] += W[3 * o + 2 * nq + j] * cst.acceleration[o + j]


@kernel(error_model="numpy", _nrt=False)
def linearised_acceptance(a, da, dq, dv, dq_max, rhs_n, alpha, model, work):
    """Accept a step after one Newton correction: move everything the step records and carries
    forward from the evaluation at the iterate (q, v, a) - a in ``a`` after the correction ``da``
    - to the corrected state (q + dq, v + dv, a), dq = beta h^2 da [m, rad], dv = gamma h da,
    to first order in the correction (the error is of the order of the next Newton correction,
    like the records of a converged iteration). Returns False, with nothing the next step reads
    changed, when the linearisation does not hold: a contact joining or leaving the active set
    (an active compliant contact whose elastic force is within 10 |dF| of zero, an open one
    within ``LINEAR_GAP`` x ``dq_max`` of closing, a reported contact without force, an IMPACT
    or clipped force changing sign) or a non-finite tangent. The caller then iterates.

    Corrected (the contact buffers, body loads and condensed state of ``work``):

    * compliant contacts (:mod:`flexgear.dynamics.flexible.compliant`): the elastic forces by the contact tangent,
      ``dF_e = (C + diag h')^-1 (G + H) dq`` on the active set, the damping force by the rigid
      overlap and its rate (rigid columns of G), the rigid overlap (depth) by ``G dq`` and the
      elastic deflection by ``d depth - h'(F_e) dF_e``; IMPACT contacts by their law at the
      overlap and rate moved along their penetration gradient;
    * mesh totals and body loads (contact loads, torsional supports, bearings; the
      quadratic-velocity turning terms of the modes are left: a product of two small changes);
    * condensed modes, integrated in the contact solve (the only condensation this serves:
      quasi-statically condensed, the evaluation's mass matrix carries the flanks' inertia
      relief, which depends on the state): their contact load ``A_i . dF_e`` and their trial
      acceleration through that load and the frame's acceleration and velocity (``d eta''_i =
      ((1 + alpha) A_i . dF_e + d l_i) / D_i``), and so their inertia reaction;
    * the generalised force the next step weights by alpha, from the HHT residual at the
      corrected state, ``rhs = (Mq a + I + alpha rhs_n) / (1 + alpha)`` (exact up to the
      residual left by the correction, i.e. the next correction).

    Work arrays: ``work.linear`` (:class:`~flexgear.dynamics.model.tables.Linearisation`; the moved
    force and rigid overlap of every reported contact, both laws, are filled by the checks and
    applied by the corrections).
    """
    meshes = model.meshes
    flex = model.flex
    bodies = model.bodies
    state = work.bodies
    system = work.system
    contacts = work.contacts
    cst = work.condensed
    lin = work.linear
    u = lin.overlap_change
    dfe = lin.force_change
    ddepth = lin.depth_change
    force_new = lin.force
    depth_new = lin.depth
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    Fb = state.load
    g = system.gradient
    n = dq.shape[0]
    nr = rigid_coordinates(flex, n)
    nm = meshes.body_a.shape[0]
    # ---- checks (nothing written outside the work arrays)
    # IMPACT meshes: the law at the moved overlap and rate
    for m in range(nm):
        if meshes.law[m] == LAW_HERTZ:
            continue
        a_ = meshes.body_a[m]
        b_ = meshes.body_b[m]
        for c in range(contacts.count[m]):
            px = contacts.x[m, c]
            py = contacts.y[m, c]
            nx = contacts.nx[m, c]
            ny = contacts.ny[m, c]
            ma = (px - pose[a_, 0]) * ny - (py - pose[a_, 1]) * nx
            mb = (px - pose[b_, 0]) * ny - (py - pose[b_, 1]) * nx
            penetration_gradient(g, J, a_, b_, nx, ny, ma, mb, n)
            dd = 0.0
            dr_ = 0.0
            for j in range(n):
                dd += g[j] * dq[j]
                dr_ += g[j] * dv[j]
            vax = vel[a_, 0] - vel[a_, 2] * (py - pose[a_, 1])
            vay = vel[a_, 1] + vel[a_, 2] * (px - pose[a_, 0])
            vbx = vel[b_, 0] - vel[b_, 2] * (py - pose[b_, 1])
            vby = vel[b_, 1] + vel[b_, 2] * (px - pose[b_, 0])
            ddot = nx * (vbx - vax) + ny * (vby - vay)
            F1, _, _ = impact_force(contacts.depth[m, c] + dd, ddot + dr_, meshes.K[m], meshes.e[m], meshes.C[m],
                                    meshes.d[m])
            if (F1 > 0.0) != (contacts.force[m, c] > 0.0):
                return False
            force_new[m, c] = F1
            depth_new[m, c] = contacts.depth[m, c] + dd
    # compliant contacts: dF_e on the active set, the open contacts' gaps
    N = contacts.joint_count[0]
    G = system.contact_gradient
    H = system.inertia_gradient
    active = contacts.active
    idx = contacts.active_index
    Kc = contacts.contact_tangent
    Fe = contacts.elastic_force
    dr = contacts.overlap
    slot = contacts.joint_slot
    jf = contacts.joint_f
    jm = contacts.joint_mesh
    C = contacts.compliance
    na = 0
    for c in range(N):
        s_ = 0.0
        for j in range(n):
            s_ += (G[c, j] + H[c, j]) * dq[j]
        u[c] = s_
        dfe[c] = 0.0
        if active[c]:
            na += 1
    for p in range(na):
        s_ = 0.0
        for p2 in range(na):
            s_ += Kc[p, p2] * u[idx[p2]]
        c = idx[p]
        if not math.isfinite(s_) or Fe[c] - 10.0 * abs(s_) <= 0.0:
            return False
        dfe[c] = s_
    margin = LINEAR_GAP * dq_max
    for c in range(N):
        m = jm[c]
        if not active[c]:
            if slot[c] >= 0:
                return False  # a positive rigid overlap the flank deflection keeps open
            if contacts.compliance_known[c] == KNOWN:
                cf = 0.0
                for j in range(N):
                    cf += C[c, j] * Fe[j]
            else:
                cf = contacts.coupled_deflection[c]
            if cf - dr[c] - abs(u[c]) < margin:
                return False
            continue
        # the damping force's clipping must not change
        depth = jf[c, 0]
        ddep = 0.0
        drate = 0.0
        for j in range(nr):
            ddep += G[c, j] * dq[j]
            drate += G[c, j] * dv[j]
        sd = step(depth + ddep, 0.0, 0.0, meshes.d[m], meshes.C[m])
        F1 = Fe[c] + dfe[c] + sd * (contacts.overlap_rate[c] + drate)
        if (F1 > 0.0) != (contacts.force[m, slot[c]] > 0.0):
            return False
        ddepth[c] = ddep
        force_new[m, slot[c]] = max(F1, 0.0)
        depth_new[m, slot[c]] = depth + ddep
    # ---- corrections: the reported contacts of every mesh (a compliant mesh reports only
    # active contacts here: a reported open one was refused above), then the compliant
    # contacts' elastic deflection
    for m in range(nm):
        a_ = meshes.body_a[m]
        b_ = meshes.body_b[m]
        for c in range(contacts.count[m]):
            dF = force_new[m, c] - contacts.force[m, c]
            contacts.force[m, c] = force_new[m, c]
            contacts.depth[m, c] = depth_new[m, c]
            if dF != 0.0:
                nx = contacts.nx[m, c]
                ny = contacts.ny[m, c]
                contacts.mesh_force[m] += dF
                contacts.mesh_fx[m] -= dF * nx
                contacts.mesh_fy[m] -= dF * ny
                contact_load(Fb, pose, a_, b_, contacts.x[m, c], contacts.y[m, c], nx, ny, dF)
    hp = contacts.hertz
    for c in range(N):
        if active[c]:
            _, dh = hertz_line(Fe[c], hp[c, 0], hp[c, 1], hp[c, 2], hp[c, 3], hp[c, 4], hp[c, 5], hp[c, 6],
                               hp[c, 7], hp[c, 8])
            contacts.deflection[jm[c], slot[c]] += ddepth[c] - dh * dfe[c]
    # torsional supports and bearings (linear in q, q'; the anchors' turning left to second order)
    for i in range(bodies.joint.shape[0]):
        if bodies.rotation[i] == ANGLE_SPRING:
            par = bodies.torsion_parent[i]
            dth = 0.0
            dw = 0.0
            for j in range(n):
                jj = J[i, 2, j] - (J[par, 2, j] if par >= 0 else 0.0)
                dth += jj * dq[j]
                dw += jj * dv[j]
            dT = -bodies.torsional_stiffness[i] * dth - bodies.torsional_damping[i] * dw
            Fb[i, 2] += dT
            if par >= 0:
                Fb[par, 2] -= dT
        if bodies.joint[i] == BEARING:
            par = bodies.parent[i]
            ax, ay, _, _, rx, ry = _anchor(i, par, bodies, pose, vel)
            ex = 0.0
            ey = 0.0
            evx = 0.0
            evy = 0.0
            for j in range(n):
                jax, jay = _anchor_jacobian(J, par, rx, ry, j)
                ex += (J[i, 0, j] - jax) * dq[j]
                ey += (J[i, 1, j] - jay) * dq[j]
                evx += (J[i, 0, j] - jax) * dv[j]
                evy += (J[i, 1, j] - jay) * dv[j]
            dfx = -bodies.stiffness[i] * ex - bodies.damping[i] * evx
            dfy = -bodies.stiffness[i] * ey - bodies.damping[i] * evy
            Fb[i, 0] += dfx
            Fb[i, 1] += dfy
            if par >= 0:
                Fb[par, 0] -= dfx
                Fb[par, 1] -= dfy
                Fb[par, 2] -= (ax - pose[par, 0]) * dfy - (ay - pose[par, 1]) * dfx
    # condensed modes (evaluated only with a compliant mesh: compliant_contacts); dI, the
    # change of their reaction on the frames
    dI = lin.reaction
    dI[:] = 0.0
    dload_work = lin.modal_load
    om = flex.condensed_omega
    W = flex.condensed_coupling
    hertz = False
    for m in range(nm):
        if meshes.law[m] == LAW_HERTZ:
            hertz = True
    dynamic = hertz and cst.step[0] > 0.0
    gam = state.convective
    acc = state.accelerations
    for body in range(bodies.flex.shape[0]):
        f = bodies.flex[body]
        if f < 0 or not hertz:
            continue
        nk = contacts.body_count[f]
        nq = flex.condensed[f]
        o = flex.condensed_offset[f]
        bslot = contacts.body_slot[f]
        U = contacts.flank_modes[f]
        cs = math.cos(pose[body, 2])
        sn = math.sin(pose[body, 2])
        ax, ay, ar = frame_acceleration(J, acc, gam, body)
        dax = 0.0
        day = 0.0
        dar = 0.0
        dvx = 0.0
        dvy = 0.0
        dw = 0.0
        for j in range(n):
            dax += J[body, 0, j] * da[j]
            day += J[body, 1, j] * da[j]
            dar += J[body, 2, j] * da[j]
            dvx += J[body, 0, j] * dv[j]
            dvy += J[body, 1, j] * dv[j]
            dw += J[body, 2, j] * dv[j]
        w = vel[body, 2]
        # a frame that no coordinate moves (its Jacobian rows zero, so are dax ... dw; MERCURY
        # 1-A: the ring) keeps its modes' inertia load (dell = 0) and its reaction
        # changes in no row
        moving = frame_moves(J, body)
        px = 0.0
        py = 0.0
        pr = 0.0
        for i in range(nq):
            dload_work[i] = 0.0
        loaded = False
        for kk in range(nk):  # A . dF_e, contact by contact (rows of U contiguous; open contacts: 0)
            dfk = dfe[bslot[kk]]
            if dfk == 0.0:
                continue
            loaded = True
            Uk = U[kk]  # (a view indexed by the loop counter alone: contiguous loads)
            for i in range(nq):
                dload_work[i] += Uk[i] * dfk
        if not (loaded or moving):
            continue  # no change of the modes' load or trial acceleration
        px, py, pr = mode_corrections(nq, W[3 * o:3 * o + nq], W[3 * o + nq:3 * o + 2 * nq],
                                      W[3 * o + 2 * nq:3 * o + 3 * nq], om[o:o + nq], dload_work, cst.load[o:o + nq],
                                      cst.trial[o:o + nq], cst.divisor[o:o + nq], cs, sn, ax, ay, ar, dax, day, dar, w,
                                      dw, vel[body, 0], vel[body, 1], dvx, dvy, alpha, dynamic, moving)
        if dynamic and moving:
            for r in range(n):
                dI[r] += J[body, 0, r] * px + J[body, 1, r] * py + J[body, 2, r] * pr
    # the generalised force of the corrected state, from the HHT residual
    Mq = system.mass
    rhs = system.rhs
    il = system.inertia_load
    for r in range(n):
        s_ = il[r] + dI[r] + alpha * rhs_n[r]
        for j in range(n):
            s_ += Mq[r, j] * a[j]
        rhs[r] = s_ / (1.0 + alpha)
    return True


@kernel(error_model="numpy")
def _stop(stats, code, t, where):
    """Store an error (code, time [s], mesh) in the statistics and return its code."""
    stats.error_code[0] = code
    stats.error_time[0] = t
    stats.error_mesh[0] = where
    return code


@kernel(error_model="numpy")
def integrate(q, v, acc, t0, nsteps, model, contact, work, settings, records, stats):
    """Advance (q, v, acc) from t0 by nsteps steps of settings.h (halving a step whose Newton
    iteration fails, down to h/64), with the buffers ``work`` (a Workspace).

    Each step: predictor (:func:`predict`), forces (:func:`forces`, a full contact search in the
    first iteration every ``settings.full_every`` steps, local ones otherwise) and Newton
    updates (:func:`newton_update`) until the position change is below ``settings.tol``; then
    :func:`record`. ``records`` (a :class:`~flexgear.dynamics.model.tables.Records` window starting
    at this call's first step) receives every step, every out_every steps the contact pairs and
    the condensed modes' coordinates (:func:`record_condensed`).
    ``stats`` (:class:`~flexgear.dynamics.model.tables.Statistics`) counts steps and iterations and
    receives the error code, time and mesh. Returns the error code (0 = OK).

    With ``settings.one_pass`` a step without a full contact search and not retried is accepted
    after its first Newton correction d1 [m] (scaled as the tolerance) when ``max(rho d1, rho2
    d1^2) < settings.tol`` [m], rho [-] and rho2 [1/m] the largest contraction ratios d2 / d1
    and d2 / d1^2 of the steps that iterated (decayed by ``CONTRACTION_DECAY`` per new sample;
    a full contact search step, one in about ``CALIBRATE_STEPS`` steps, iterates to sample them; no one-pass
    step before the first sample of the call), and
    :func:`linearised_acceptance` finds the active set unchanged within the correction's reach;
    it then corrects the records and the carried state to first order in the correction
    (``stats.linearised`` counts these steps) and the body states are recorded at the accepted
    state. Otherwise the step iterates until the correction is below the tolerance, and its
    records and carried state are moved to the accepted state the same way when the
    linearisation holds.
    """
    n = q.shape[0]
    h = settings.h
    alpha = settings.alpha
    tol = settings.tol
    max_newton = settings.max_newton
    depth_limit = settings.depth_limit
    full_every = settings.full_every
    calibrate_every = max(1, CALIBRATE_STEPS // full_every)
    out_every = settings.out_every
    scale = settings.scale
    rotation = model.bodies.rotation
    inertia = model.bodies.inertia
    state = work.bodies
    system = work.system
    contacts = work.contacts
    rhs = system.rhs
    md = contacts.max_depth
    beta, gamma_ = hht_coefficients(alpha)
    rhs_n = np.zeros(n)
    # Condensed modes integrated in the contact solve (condensed.py): the frames' inertia load
    # on them is taken at the step's end, with the Newton iterate a (d a / dq = 1 / (beta h^2)),
    # and the forces at the start are those of the modes' accepted state (step 0). Condensed
    # quasi-statically, the inertia load acts like a mass too: in the HHT residual (1 + alpha)
    # F_n+1 - alpha F_n it must come out as the load of a_n+1, so each evaluation takes a_used =
    # (a + alpha a_used_n) / (1 + alpha); state.accelerations holds a_used of the last accepted
    # state (simulate sets it to acc before the first call)
    cst = work.condensed
    integrated = settings.condensation == INTEGRATED
    cst.alpha[0] = alpha
    cst.step[0] = 0.0
    a_used = state.accelerations.copy()
    state.acceleration_slope[0] = 0.0
    if integrated and cst.started[0] == 0:  # the first call: the modes start at their static response
        cst.mode[0] = STATIC
        forces(q, v, t0, model, contact, work, False)
        static_condensed(model.flex, cst)
    cst.mode[0] = settings.condensation
    forces(q, v, t0, model, contact, work, False)
    rhs_n[:] = rhs
    if integrated:
        start_condensed(model.flex, cst)
    t = t0
    qn = q.copy()
    vn = v.copy()
    an = acc.copy()
    a = np.zeros(n)
    qq = np.zeros(n)
    vv = np.zeros(n)
    since_full = 0
    retry = False
    # one pass (settings.one_pass): the contraction estimates (-1: no sample yet) and work arrays
    one_pass = settings.one_pass != 0 and integrated
    rho = -1.0
    rho2 = -1.0
    dq_first = 0.0
    full_step = False
    fulls = 0
    linear_record = False
    a0 = np.zeros(n)
    da = np.zeros(n)
    dqv = np.zeros(n)
    dvv = np.zeros(n)
    for k in range(nsteps):
        t_target = t0 + (k + 1) * h
        hl = h
        # a remainder below 1e-6 h is round-off of t (about 1e-16 t), not a step to take: a
        # sub-step of 1e-17 s would make HHT's acceleration jump
        while t < t_target - 1e-6 * h:
            if t + hl > t_target - 1e-6 * h:
                hl = t_target - t
            # Newton on the new acceleration
            a[:] = an
            conv = False
            fin = True
            it = 0
            where = -1
            linear = False
            while it < max_newton:
                it += 1
                predict(qn, vn, an, a, hl, beta, gamma_, qq, vv)
                full = it == 1 and (since_full >= full_every or retry)
                if full:
                    since_full = 0
                    full_step = fulls % calibrate_every == 0  # this step iterates: a contraction sample
                    fulls += 1
                elif it == 1:
                    full_step = False
                if integrated:
                    state.accelerations[:] = a
                    state.acceleration_slope[0] = 1.0 / (beta * hl * hl)
                    cst.step[0] = hl
                else:
                    for j in range(n):
                        state.accelerations[j] = (a[j] + alpha * a_used[j]) / (1.0 + alpha)
                    state.acceleration_slope[0] = 1.0 / ((1.0 + alpha) * beta * hl * hl)
                where = forces(qq, vv, t + hl, model, contact, work, not full)
                if one_pass:
                    a0[:] = a
                dq, fin = newton_update(system.mass, system.stiffness, system.damping, rhs, rhs_n, system.inertia_load, a,
                                        alpha, beta,
                                        gamma_, hl, scale)
                if not fin:
                    break
                if one_pass:
                    for j in range(n):  # the correction, for linearised_acceptance
                        da[j] = a[j] - a0[j]
                        dqv[j] = beta * hl * hl * da[j]
                        dvv[j] = gamma_ * hl * da[j]
                    if it == 1:
                        dq_first = dq
                    elif it == 2 and dq_first > 0.0:  # a sample of the contraction
                        r = dq / dq_first
                        rho = max(r, CONTRACTION_DECAY * rho)
                        rho2 = max(r / dq_first, CONTRACTION_DECAY * rho2)
                if dq < tol:
                    if one_pass:  # the records and the carried state at the accepted state too
                        linear = linearised_acceptance(a, da, dqv, dvv, dq, rhs_n, alpha, model, work)
                        if not linear and dq > LAST_ITERATE * tol and it < max_newton:
                            continue  # one more evaluation, at an iterate this close to the accepted state
                    conv = True
                    break
                if (one_pass and it == 1 and not full_step and not retry and rho >= 0.0
                        and max(rho * dq, rho2 * dq * dq) < tol):
                    if linearised_acceptance(a, da, dqv, dvv, dq, rhs_n, alpha, model, work):
                        conv = True
                        linear = True
                        stats.linearised[0] += 1
                        break
            stats.newton[0] += it
            if it > stats.max_iter[0]:
                stats.max_iter[0] = it
            if md[0] > depth_limit:
                return _stop(stats, ERR_PENETRATION, t + hl, where)
            if not conv:
                stats.rejected[0] += 1
                retry = True
                hl = 0.5 * hl
                if hl < h / 64.0:
                    return _stop(stats, ERR_NEWTON if fin else ERR_NAN, t, where)
                continue
            # accept: the state at t + hl; forces and records are those of the last Newton
            # evaluation (one pass: moved to the accepted state, linearised_acceptance; else up
            # to the tolerance from it)
            retry = False
            since_full += 1
            linear_record = linear
            predict(qn, vn, an, a, hl, beta, gamma_, qq, vv)
            for j in range(n):
                if not (math.isfinite(qq[j]) and math.isfinite(vv[j])):
                    return _stop(stats, ERR_NAN, t + hl, -1)
            if integrated and not accept_condensed(model.flex, cst, hl):
                return _stop(stats, ERR_NAN, t + hl, -1)
            qn[:] = qq
            vn[:] = vv
            an[:] = a
            a_used[:] = state.accelerations
            rhs_n[:] = rhs
            t += hl
            stats.steps[0] += 1
            if hl < h:
                hl = min(2.0 * hl, h)
        t = t_target  # no drift of t from summed sub-steps
        if linear_record:  # the records' poses and coordinates at the accepted state itself
            kinematics(qn, vn, t, model.bodies, model.profiles, state)
            state.coordinates[:] = qn
            state.rates[:] = vn
        record(k, rotation, inertia, state, contacts, out_every, records)
        nmod = records.modal.shape[1]
        for j in range(nmod):
            records.modal[k, j] = state.coordinates[n - nmod + j]
        if (k + 1) % out_every == 0:
            record_condensed((k + 1) // out_every - 1, model.flex, cst, state, integrated, records.condensed)
        modal_drive_torque(k, an, model.flex, rotation, records)
        if integrated:
            condensed_drive_torque(k, model.flex, cst, rotation, records)
    q[:] = qn
    v[:] = vn
    acc[:] = an
    return OK


# ---------------------------------------------------------------------------------------------
# Python entry points


def initial_acceleration(model: Model, arr=None, tables=None, q=None, v=None, stride=COARSE_STRIDE, t=0.0,
                         acceleration_slope=0.0):
    """Solve Mq a0 = rhs(q0, v0, t) (default: the model's initial state at t = 0).

    Parameters
    ----------
    model : Model
    arr : KernelModel, optional
        ``model.pack(stride)`` if given.
    tables : ContactTables, optional
        Default ``model.tables``.
    acceleration_slope : float
        d q'' / dq assumed in the tangent (:class:`~flexgear.dynamics.model.tables.BodyState`; the
        integrator's 1 / ((1 + alpha) beta h^2)). With 1, Kt includes ``-dQ/dq''`` of the frames' inertia
        load on condensed modes (:func:`~flexgear.dynamics.flexible.compliant.inertia_flank_value`); the
        accelerations themselves are taken as zero [1/s^2].

    Returns
    -------
    acc : (n,) array
        Generalised accelerations [m/s^2, rad/s^2].
    work : Workspace
        The force evaluation (poses, loads, matrices, contacts).
    """
    if arr is None:
        arr = model.pack(stride)
    if tables is None:
        tables = model.tables
    if q is None or v is None:
        q0, v0 = model.initial_state()
        q = q0 if q is None else q
        v = v0 if v is None else v
    q = np.asarray(q, float)
    v = np.asarray(v, float)
    work = model_workspace(model, arr, len(q))
    work.bodies.acceleration_slope[0] = float(acceleration_slope)
    forces(q, v, float(t), arr, tables, work, False)
    return np.linalg.solve(work.system.mass, work.system.rhs), work


def model_workspace(model: Model, arr, n: int):
    """Zeroed buffers (:func:`~flexgear.dynamics.model.tables.workspace`) sized for the model and its
    tables ``arr`` (KernelModel) with n coordinates."""
    return workspace(n, len(model.bodies), len(model.meshes), int(arr.flex.condensed.max(initial=0)),
                     int(np.count_nonzero(arr.meshes.law == LAW_HERTZ)), int(arr.flex.body.size),
                     int(arr.flex.condensed.sum()))


def evaluate(model: Model, q, v, t=0.0, stride=COARSE_STRIDE, acceleration_slope=0.0):
    """Forces and contacts of the model in state (q, v) at time t (for checks and tests;
    ``acceleration_slope``: see :func:`initial_acceleration`).

    Returns a dict with the body loads ``Fb`` (nb, 3), mesh totals ``mesh`` (nm, 3: normal force
    sum, Fx, Fy on body b), contact arrays ``cf`` (nm, MAXC, 6: force, depth, px, py, nx, ny),
    ``ci`` (nm, MAXC, 3: tooth a, tooth b, side a), counts ``count``, ``max_depth`` and the
    whole :class:`~flexgear.dynamics.model.tables.Workspace` as ``work``.
    """
    _, work = initial_acceleration(model, None, None, q, v, stride, t, acceleration_slope)
    b, s, c = work.bodies, work.system, work.contacts
    cf = np.stack([c.force, c.depth, c.x, c.y, c.nx, c.ny], axis=-1)
    ci = np.stack([c.tooth_a, c.tooth_b, c.side_a], axis=-1)
    mesh = np.stack([c.mesh_force, c.mesh_fx, c.mesh_fy], axis=-1)
    return dict(pose=b.pose, vel=b.vel, Fb=b.load, rhs=s.rhs, Mq=s.mass, Kt=s.stiffness, Ct=s.damping, cf=cf, ci=ci,
                count=c.count, mesh=mesh, max_depth=c.max_depth[0], work=work)


class Integration:
    """Result of :func:`simulate`: raw records on the integration grid plus statistics.

    ``mesh`` (nsteps, nm, 3: normal force sum, Fx, Fy on body b), ``body`` (nsteps, nb, 7: x,
    y, theta, vx, vy, omega, drive torque), ``pair_f`` (nout, nm, MAXC, 2: force, depth),
    ``pair_i`` (nout, nm, MAXC, 3: tooth a, tooth b, side a) stack the named ``records``.
    ``modal`` (nsteps, m) holds the modal coordinates in q at every step, ``condensed`` (nout,
    sum nq) the condensed modes' eta_i [sqrt(kg) m] at the pair samples (instantaneous; body
    f's at ``model.pack().flex.condensed_offset[f]``, in the order of ``model.flex``): with
    ``condensation`` "integrated" their state, with "static" their static response to the
    contact forces and the frame's inertia load (:func:`record_condensed`).
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)


def simulate(model: Model, t_end: float, h: float, out_every: int, alpha: float = -0.1, tol: float = 1e-10,
             max_newton: int = 12, stride: int = COARSE_STRIDE, chunk_steps: int = 2000, progress=None,
             depth_limit: float | None = None, full_every: int | None = None, q0=None,
             v0=None, condensation: str = "integrated", one_pass: bool | None = None,
             threads: int | None = None) -> Integration:
    """Integrate the model from 0 to t_end with step h (t_end/h steps, a multiple of out_every).

    Parameters
    ----------
    progress : callable(fraction) or None
        Called after every chunk with the simulated fraction done.
    depth_limit : float
        Penetration [m] beyond which the run is declared diverged (default: a quarter module of
        the first mesh's gears).
    full_every : int, optional
        Steps between two full contact searches (default: :func:`full_search_every` of h, a
        full search every 200 us of simulated time).
    q0, v0 : (n,) arrays, optional
        Initial coordinates and velocities (default: ``model.initial_state()``; e.g. an
        initial modal displacement for a free vibration).
    condensation : {"integrated", "static"}
        The flexible bodies' condensed modes: integrated inside the contact solve with their own
        inertia (:mod:`~flexgear.dynamics.flexible.condensed`; equivalent to modal coordinates at any
        step) or condensed quasi-statically (valid where the step cannot resolve them).
    one_pass : bool, optional
        Accept a step after its first Newton correction when the iteration's contraction
        shows that the next correction would be below ``tol``, with the records and the
        carried state corrected to first order (:func:`linearised_acceptance`; about one
        force evaluation per step instead of two). Default: on for a model with flexible
        bodies, off for a rigid one (whose results then stay those of the full iteration).
        Only with ``condensation="integrated"``; quasi-statically condensed, the evaluation's
        mass matrix carries the flanks' inertia relief, which the step would have to carry
        forward too, and the full iteration is kept.
    threads : int or "auto", optional
        Threads of the force evaluation (the compliant meshes' contact searches, the flexible
        bodies' flank rows, their parts of the joint compliance and of the open contacts'
        deflections run in parallel: :mod:`~flexgear.dynamics.threads`); 1 or None (default):
        serial; at most numba's ``NUMBA_NUM_THREADS``. The default is serial because a parallel
        chunk on a machine that becomes loaded can run 30-100 times slower (threads spinning for
        a time slice; measured: 384 s per simulated second instead of 13 on MERCURY 1-A
        flexible when another process started), and because on the 2-vCPU VM it was measured on
        even an idle machine gave 2 threads between 0.68 and 1.12 times the serial speed
        (``benchmarks/bench_flexible.py --threads 2``). ``"auto"``: chosen chunk by
        chunk up to numba's thread count (all cores; 1 in a batch worker) by :class:`ThreadChoice`: the
        first two chunks of ``chunk_steps`` steps timed with all threads and with one, then the
        faster, the other timed again every :data:`RECHECK_CHUNKS` chunks, and one thread
        while other processes keep the cores busy (on a loaded machine the threads wait for
        a time slice and a parallel step can take several times as long as a serial one). The
        results are bit-identical whatever the count and the choice (every sum is formed in
        one thread, in the serial order).

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
    if condensation not in CONDENSATION:
        raise ValueError(f"condensation = {condensation!r}: must be one of {sorted(CONDENSATION)}")
    threads = check_threads(threads)
    kmodel = model.pack(stride)
    tables = model.tables
    q, v = model.initial_state()
    if q0 is not None:
        q = np.array(q0, float).reshape(q.shape)
    if v0 is not None:
        v = np.array(v0, float).reshape(v.shape)
    n = len(q)
    nb_, nm = len(model.bodies), len(model.meshes)
    nsteps = int(round(t_end / h))
    nsteps -= nsteps % out_every
    if full_every is None:
        full_every = full_search_every(h)
    if int(full_every) < 1:
        raise ValueError(f"full_every = {full_every}: the steps between two full contact searches must be at least 1")
    if depth_limit is None:
        depth_limit = model.attrs.get("depth_limit", 5e-4)
    try:
        acc, _ = initial_acceleration(model, kmodel, tables, q, v, stride)
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
    modal = model.modal_coordinates()
    flex_of = {fb.body: fb for fb in model.flex}
    for body, c0, m in modal:  # flank displacement per unit modal coordinate
        scale[c0:c0 + m] = flex_of[body].modal_scale
    nmod = sum(m for _, _, m in modal)
    ncond = int(kmodel.flex.condensed.sum())
    settings = Settings(h=float(h), alpha=float(alpha), tol=float(tol), max_newton=int(max_newton),
                        depth_limit=float(depth_limit), full_every=int(full_every), out_every=int(out_every),
                        scale=scale, condensation=CONDENSATION[condensation],
                        one_pass=int(bool(model.flex) if one_pass is None else bool(one_pass)) * (condensation == "integrated"))
    rec = new_records(nsteps, nsteps // out_every, nb_, nm, nmod, ncond)
    stats = new_statistics()
    work = model_workspace(model, kmodel, n)
    work.bodies.accelerations[:] = acc  # the start's (see integrate)
    compile_seconds = 0.0
    if not integrate.signatures:  # compile (or load numba's disk cache) apart from the timed loop
        t0 = _time.perf_counter()
        integrate(q.copy(), v.copy(), acc.copy(), 0.0, 0, kmodel, tables, model_workspace(model, kmodel, n), settings,
                  rec.window(0, 0, out_every), new_statistics())
        compile_seconds = _time.perf_counter() - t0
    wall0 = _time.perf_counter()
    done = 0
    t = 0.0
    chunk = max(out_every, (chunk_steps // out_every) * out_every)
    # (threads only matter to the compliant meshes' evaluation: a model without any runs serial)
    auto = threads == "auto"
    pick = ThreadChoice(((available_threads() if auto else threads or 1) if np.any(kmodel.meshes.law == LAW_HERTZ)
                         else 1), fixed=not auto)
    while done < nsteps:
        k = min(chunk, nsteps - done)
        use = pick.next()
        work.contacts.threads[0] = use
        try:
            c0 = _time.perf_counter()
            with kernel_threads(use):
                code = integrate(q, v, acc, t, k, kmodel, tables, work, settings, rec.window(done, k, out_every),
                                 stats)
            pick.timed(use, (_time.perf_counter() - c0) / k)
        except np.linalg.LinAlgError:  # raised by the compiled solve on a non-finite Newton matrix
            raise DivergenceError(
                f"simulation diverged at t = {t:.6f} s (within the next {k * h:.3g} s) in the bodies' coordinates: "
                "the Newton matrix became non-finite (NaN/inf); check masses, inertias, loads and contact "
                "parameters for extreme values"
                + largest_modal_coordinate(model, work.bodies.coordinates, work.condensed.position)) from None
        if code != OK:
            tt = stats.error_time[0]
            wm = int(stats.error_mesh[0])
            where = f"mesh '{model.meshes[wm].name}'" if 0 <= wm < nm else "the bodies' coordinates"
            if code == ERR_PENETRATION:
                cause = (f"tooth penetration exceeded the limit {depth_limit*1e3:.3g} mm (the gears pass through "
                         "each other: load too high for the contact stiffness, or a step too large)")
            elif code == ERR_NAN:
                cause = "the state became non-finite (NaN/inf)"
            else:
                cause = (f"Newton's method did not converge in {max_newton} iterations even with the step "
                         f"reduced to {h/64:.3g} s")
            raise DivergenceError(f"simulation diverged at t = {tt:.6f} s in {where}: {cause}"
                                  + largest_modal_coordinate(model, work.bodies.coordinates, work.condensed.position))
        done += k
        t = done * h
        if progress is not None:
            progress(done / nsteps)
    wall = _time.perf_counter() - wall0
    return Integration(h=h, nsteps=nsteps, out_every=out_every,
                       mesh=np.stack([rec.mesh_force, rec.mesh_fx, rec.mesh_fy], axis=-1),
                       body=np.stack([rec.x, rec.y, rec.theta, rec.vx, rec.vy, rec.omega, rec.torque], axis=-1),
                       pair_f=np.stack([rec.pair_force, rec.pair_depth], axis=-1),
                       pair_i=np.stack([rec.pair_tooth_a, rec.pair_tooth_b, rec.pair_side_a], axis=-1),
                       records=rec, steps=int(stats.steps[0]), newton=int(stats.newton[0]),
                       rejected=int(stats.rejected[0]), max_iter=int(stats.max_iter[0]),
                       linearised=int(stats.linearised[0]), wall=wall,
                       compile_seconds=compile_seconds, q=q, v=v, modal=rec.modal, condensed=rec.condensed,
                       condensation=condensation)


#: chunks between two timings of the thread count not in use (:func:`simulate`)
RECHECK_CHUNKS = 20


class ThreadChoice:
    """The thread count of :func:`simulate`'s next chunk.

    ``fixed``: always that count. Otherwise (``most`` threads available, > 1) the first chunk
    runs with ``most`` threads and the second with one, then the faster of the two per step
    (wall time), the other timed again every :data:`RECHECK_CHUNKS` chunks; a chunk that would
    run on n > 1 threads runs on one unless the other processes left n - 1/2 cores idle during
    the last chunk (``spare``, default :class:`~flexgear.dynamics.threads.SpareCores`: threads
    waiting for a time slice make a parallel step several times slower than a serial one, and
    a chunk cannot be cut short). The results do not depend on the choice."""

    def __init__(self, most: int, fixed: bool = False, spare=None):
        self.most = max(1, min(int(most), int(nb.config.NUMBA_NUM_THREADS)))
        self.fixed = fixed
        self.spare = SpareCores() if spare is None else spare
        self.per_step = {}  # threads -> wall time per step of its last chunk [s]
        self.chunks = 0

    def next(self) -> int:
        """The thread count of the next chunk."""
        if self.fixed or self.most == 1:
            return self.most
        i = self.chunks
        self.chunks += 1
        if i == 0:
            want = self.most
        elif i == 1 or not self.per_step:
            want = 1
        else:
            best = min(self.per_step, key=self.per_step.get)
            want = best
            if (i - 1) % RECHECK_CHUNKS == 0:
                want = 1 if best != 1 else self.most
        if want > 1 and self.spare() < want - 0.5:
            return 1
        return want

    def timed(self, threads: int, per_step: float) -> None:
        """The wall time per step [s] of the chunk just run with ``threads``."""
        self.per_step[threads] = per_step


def largest_modal_coordinate(model: Model, q, condensed=None) -> str:
    """Text naming the flexible body and mode with the largest flank displacement among the
    modal coordinates in q and, if ``condensed`` (the condensed modes' eta_i, the
    :class:`~flexgear.dynamics.model.tables.CondensedState` ``position``, in the order of
    ``model.flex``) is given, among the condensed modes: body, mode number in the body's
    reduction, frequency, coordinate and flank displacement ('' for a model with neither)."""
    def largest(candidates):
        best = None
        for u, eta, freq, body, first in candidates:
            if u.size == 0:
                continue
            k = int(np.nanargmax(u)) if np.any(np.isfinite(u)) else 0
            if best is None or not u[k] <= best[0]:
                best = (u[k], body, first + k, float(eta[k]), float(freq[k]))
        return best

    flex_of = {fb.body: fb for fb in model.flex}
    modal = []
    for body, c0, m in model.modal_coordinates():
        eta = np.asarray(q[c0:c0 + m], float)
        modal.append((np.abs(eta) * flex_of[body].modal_scale, eta, flex_of[body].frequencies, body, 0))
    cond, o = [], 0
    for fb in model.flex if condensed is not None else ():
        nq = fb.shape.shape[3]
        if nq and fb.condensed_omega is not None:
            eta = np.asarray(condensed[o:o + nq], float)
            amax = np.abs(fb.shape).reshape(-1, nq).max(axis=0) * fb.condensed_omega  # largest |A_i| on the flanks
            cond.append((np.abs(eta) * amax, eta, fb.condensed_omega / (2.0 * np.pi), fb.body, fb.modes))
        o += nq
    text = ""
    for kind, best in (("modal coordinate", largest(modal)), ("condensed mode", largest(cond))):
        if best is not None:
            u, body, k, eta, f = best
            text += (f"; largest {kind}: body '{model.bodies[body].name}' mode {k + 1} ({f:.4g} Hz), "
                     f"eta = {eta:.4g} sqrt(kg) m, flank displacement up to {u * 1e6:.4g} um")
    return text


KERNELS = ("forces", "integrate")
"""The kernels Python calls directly (the others are compiled into them)."""


def compiled_cache_present() -> bool:
    """Whether numba's on-disk cache of the time loop exists (else the next run compiles it,
    which takes about 40 s on 2 cores)."""
    import os
    from pathlib import Path

    moved = os.environ.get("NUMBA_CACHE_DIR")  # numba then caches there only
    if moved:
        return all(any(Path(moved).glob(f"**/solver.{name}-*.nbi")) for name in KERNELS)
    here = Path(__file__).resolve().parent / "__pycache__"
    return all(any(here.glob(f"solver.{name}-*.nbi")) for name in KERNELS)
