"""One force evaluation: the generalised force, mass matrix and tangent matrices of the model at
(q, q', t) - applied torques, torsional supports, bearings, tooth contact (IMPACT meshes here,
compliant meshes in :mod:`flexgear.dynamics.flexible.compliant`), modal forces.
"""
from __future__ import annotations

import math

from ...kernels import kernel
from ..contact.laws import LAW_HERTZ, contact_load, impact_force, penetration_gradient, step
from ..contact.search import mesh_pair, mesh_search, toothing_centre
from ..contact.teeth import tooth_law
from ..flexible.compliant import compliant_contacts
from ..flexible.floating_frame import modal_forces
from ..model.bodies import ANGLE_SPRING, BEARING
from .friction import contact_friction, squeeze_contact, start_damping, start_friction
from .housing import housing_forces
from .kinematics import anchor, anchor_jacobian, kinematics, profile_value



@kernel(error_model="numpy", inline="always")
def applied_torques(t, bodies, profiles, state):
    """Applied torques, each with its smooth ramp STEP(t; 0, 0, ramp, 1), into the body loads."""
    Fb = state.load
    for i in range(bodies.joint.shape[0]):
        tp = bodies.torque_profile[i]
        if tp >= 0:
            T, _, _ = profile_value(profiles, tp, t)
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
            ax, ay, avx, avy, rx, ry = anchor(i, par, bodies, pose, vel)
            for j in range(n):
                jax, jay = anchor_jacobian(J, par, rx, ry, j)
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
                if D[0, a] == 0.0 and D[1, a] == 0.0:  # adds zeros (Kt, Ct never hold -0.0): skipped
                    continue
                for bb in range(n):
                    dd = D[0, a] * D[0, bb] + D[1, a] * D[1, bb]
                    Kt[a, bb] += k * dd
                    Ct[a, bb] += c * dd


@kernel(error_model="numpy", inline="always")
def tooth_force(m, depth, ddot, px, py, ta, tb, sa, meshes, contact, pose):
    """IMPACT force, dF/ddelta and dF/ddelta_dot of a contact of mesh m at (px, py) between tooth
    ta of gear A (flank sa) and tooth tb of gear B: the mesh's law, with the per-tooth changes of
    ``meshes.teeth`` where it has any (a crack's stiffness factor on K; a partial face width as
    slices in parallel, each with its share of K and C and its penetration less its recess).
    Meshes without such teeth evaluate the plain law."""
    K = meshes.K[m]
    e = meshes.e[m]
    C = meshes.C[m]
    dd = meshes.d[m]
    teeth = meshes.teeth
    if teeth.first.shape[0] == 0 or (teeth.first[m, 0] < 0 and teeth.first[m, 1] < 0):
        return impact_force(depth, ddot, K, e, C, dd)
    a = meshes.body_a[m]
    b = meshes.body_b[m]
    xa, ya = toothing_centre(contact, meshes.gear_a[m], pose[a, 0], pose[a, 1], pose[a, 2])
    xb, yb = toothing_centre(contact, meshes.gear_b[m], pose[b, 0], pose[b, 1], pose[b, 2])
    ka, wa, ha = tooth_law(teeth, m, 0, ta, sa, math.hypot(px - xa, py - ya))
    kb, wb, hb = tooth_law(teeth, m, 1, tb, -sa if meshes.internal[m] else sa, math.hypot(px - xb, py - yb))
    F = 0.0
    dF = 0.0
    cd = 0.0
    for i in range(4):  # slices: the outline's and the recessed part of A's face width times B's
        w = (wa if i % 2 == 0 else 1.0 - wa) * (wb if i < 2 else 1.0 - wb)
        if w <= 0.0:
            continue
        h = (0.0 if i % 2 == 0 else ha) + (0.0 if i < 2 else hb)
        Fi, dFi, cdi = impact_force(depth - h, ddot, K * ka * kb * w, e, C * w, dd)
        F += Fi
        dF += dFi
        cd += cdi
    return F, dF, cd


@kernel(error_model="numpy", inline="always")
def mesh_forces(m, meshes, contact, state, system, contacts, friction, local):
    """Contacts of mesh m, their IMPACT forces, body loads and tangent matrices.

    Fills the mesh's rows of ``contacts`` (a ContactBuffers) and its totals (normal force sum,
    Fx, Fy on body b, friction included); with tooth friction on the mesh
    (``friction.table.on[m]``) each contact's friction (:func:`~.friction.contact_friction`);
    with the squeeze-film damping (``friction.table.squeeze[m]``) the IMPACT damper replaced by
    the film's (:func:`~.friction.squeeze_contact`). ``friction`` is None in a model without
    tooth friction, squeeze film or compliant mesh (:func:`~.buffers.workspace`): numba then
    prunes that code at compile time, so a frictionless rigid model compiles without it
    (docs/performance.md, *Cold start*): inlined into :func:`tooth_contact`, ``friction`` is
    that kernel's argument passed straight through, which numba's branch pruning, run again
    after inlining, resolves (pass it on unchanged, or the frictionless model fails to compile).
    Returns the largest penetration of the mesh [m] (0 without contact).
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
    cnt = mesh_search(pose[a], pose[b], mesh_pair(meshes, m), contact, out_f, out_i, local, contacts.search_cache[m],
                      contacts.search_count[m])
    contacts.count[m] = cnt
    deepest = 0.0
    sumF = 0.0
    fxb = 0.0
    fyb = 0.0
    rubs = False
    squeeze = False
    if friction is not None:  # None: a frictionless model, whose kernels numba compiles without it
        rubs = friction.table.on[m] != 0
        if rubs:
            start_friction(m, friction)
        squeeze = friction.table.squeeze[m] != 0
        if squeeze:
            start_damping(m, friction)
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
        c_depth[m, c] = depth
        c_x[m, c] = px
        c_y[m, c] = py
        c_nx[m, c] = nx
        c_ny[m, c] = ny
        c_ta[m, c] = out_i[c, 0]
        c_tb[m, c] = out_i[c, 1]
        c_sa[m, c] = out_i[c, 2]
        fu = 0.0
        if squeeze:  # the law's elastic part (no damper at a zero rate), then the film's damping
            Fe, dFe, _ = tooth_force(m, depth, 0.0, px, py, out_i[c, 0], out_i[c, 1], out_i[c, 2], meshes, contact,
                                     pose)
            F, dF, cd = Fe, dFe, 0.0
            if friction is not None:
                F, dF, cd, fu = squeeze_contact(m, c, a, b, Fe, dFe, ddot, state, contacts, friction)
        else:
            F, dF, cd = tooth_force(m, depth, ddot, px, py, out_i[c, 0], out_i[c, 1], out_i[c, 2], meshes, contact,
                                    pose)
        c_force[m, c] = F
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
        if friction is not None:
            if fu != 0.0:  # the squeeze film's coefficient changes with the entrainment speed: row e
                e = friction.roll_row
                for r in range(n):
                    if g[r] == 0.0:
                        continue
                    for s in range(n):
                        Ct[r, s] += fu * g[r] * e[s]
            if rubs:  # friction f along t = (-ny, nx) on b
                f = contact_friction(m, c, a, b, dF, cd, fu, state, system, contacts, friction)
                fxb -= f * ny
                fyb += f * nx
    contacts.mesh_force[m] = sumF
    contacts.mesh_fx[m] = fxb
    contacts.mesh_fy[m] = fyb
    return deepest


@kernel(error_model="numpy")
def tooth_contact(meshes, compliant, body_flex, contact, state, system, contacts, cst, friction, local):
    """All meshes (:func:`mesh_forces`; the meshes with the compliant Hertz law, i.e. with a
    flexible gear, together in one contact problem:
    :func:`~flexgear.dynamics.flexible.compliant.compliant_contacts` with the FlexTable
    ``compliant`` and the bodies' rows in it ``body_flex``); the largest penetration goes to
    ``contacts.max_depth[0]``. Returns the mesh with the largest penetration (-1: no contact).

    ``compliant`` is None in a model without a compliant mesh: numba then prunes the compliant
    branch at compile time (an argument tested against None), so a rigid model's kernels do not
    compile the compliant contact problem. Not inlined, for that pruning to act."""
    deepest = 0.0
    where = -1
    for m in range(meshes.body_a.shape[0]):
        if meshes.law[m] == LAW_HERTZ:
            continue
        dm = mesh_forces(m, meshes, contact, state, system, contacts, friction, local)
        if dm > deepest:
            deepest = dm
            where = m
    if compliant is not None:
        dm, wm = compliant_contacts(meshes, compliant, body_flex, contact, state, system, contacts, cst, friction,
                                    local)
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
    housing_forces(model.housing, bodies, state, system)
    where = tooth_contact(model.meshes, model.compliant, bodies.flex, contact, state, system, work.contacts,
                          work.condensed, work.friction, local)
    modal_forces(model.flex, state, system)
    generalised_forces(bodies, state, system)
    return where
