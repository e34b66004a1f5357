"""One-pass steps: everything a step records and carries forward moved, to first order, from the
evaluated iterate to the state after its Newton correction (:func:`linearised_acceptance`).
"""
from __future__ import annotations

import math


from ...kernels import kernel
from ..contact.laws import LAW_HERTZ, contact_approach, contact_load, impact_force, penetration_gradient, step
from ..flexible.condensed import (FrameChange, FrameMotion, body_modes, frame_acceleration, frame_moves,
                                  mode_corrections)
from ..flexible.flank import rigid_coordinates
from ..flexible.joint import KNOWN
from ..model.bodies import ANGLE_SPRING, BEARING
from .friction import move_friction, moved_film_coefficient
from .kinematics import anchor, anchor_jacobian

# one-pass steps (Settings.one_pass, :func:`linearised_acceptance`): an open compliant contact
# whose gap, less the change of its overlap, is below LINEAR_GAP times the Newton correction
# may close within the correction's reach (the flank deflection it gets from the other
# contacts' force change, C dF, is at most of the correction's order): the step iterates
LINEAR_GAP = 10.0


@kernel(error_model="numpy", _nrt=False)
def linearised_acceptance(a, da, dq, dv, dq_max, rhs_n, alpha, model, work):
    """Accept a step after one Newton correction by moving its records to the corrected state to first order.

        Everything the step records and carries forward moves from the evaluation at the iterate
        (q, v, a) to (q + dq, v + dv, a), dq = beta h^2 da [m, rad], dv = gamma h da: compliant
        contacts through the tangent ``dF_e = (C + diag h')^-1 (G + H) dq`` (depth by ``G dq``,
        deflection by ``d depth - h'(F_e) dF_e``), IMPACT contacts by their law, the tooth friction
        at the moved forces and speeds (:func:`~flexgear.dynamics.integrator.friction.move_friction`),
        mesh totals and body loads (the quadratic-velocity terms of the modes, a product of two small changes, are
        left), the integrated condensed modes (``d eta''_i = ((1 + alpha) A_i . dF_e + d l_i) /
        D_i``) and the generalised force the next step weights by alpha,
        ``rhs = (Mq a + I + alpha rhs_n) / (1 + alpha)``. The error is of the order of the next
        correction.

        Returns False, with nothing the next step reads changed, when a contact would join or leave
        the active set (an active force within 10 |dF| of zero, an open contact within
        ``LINEAR_GAP`` x ``dq_max`` of closing, a reported contact without force, an IMPACT or
        clipped force changing sign) or the tangent is not finite. Work arrays: ``work.linear``
        (:class:`~flexgear.dynamics.integrator.buffers.Linearisation`).
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
    drates = lin.rate_change
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
    friction = work.friction
    # ---- checks (nothing written outside the work arrays)
    # IMPACT meshes: the law at the moved overlap and rate
    for m in range(nm):
        if meshes.law[m] == LAW_HERTZ:
            continue
        if friction.table.squeeze[m] != 0 and contacts.count[m] > 0:
            return False  # the squeeze film on a rigid mesh (friction.squeeze_contact): the step iterates
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
        if friction.table.squeeze[m] != 0:  # the film at the moved elastic force and entrainment speed
            sd = moved_film_coefficient(m, meshes.body_a[m], meshes.body_b[m], Fe[c] + dfe[c], jf[c, 1], jf[c, 2],
                                        jf[c, 3], jf[c, 4], dv, state, friction)
        else:
            sd = step(depth + ddep, 0.0, 0.0, meshes.d[m], meshes.C[m])
        F1 = Fe[c] + dfe[c] + sd * (contacts.overlap_rate[c] + drate)
        if (F1 > 0.0) != (contacts.force[m, slot[c]] > 0.0):
            return False
        ddepth[c] = ddep
        drates[c] = drate
        force_new[m, slot[c]] = max(F1, 0.0)
        depth_new[m, slot[c]] = depth + ddep
    # ---- corrections: the reported contacts of every mesh (a compliant mesh reports only
    # active contacts here: a reported open one was refused above), then the compliant
    # contacts' elastic deflection and squeeze films
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
            if friction.table.on[m] != 0:  # tooth friction at the moved force and speeds
                move_friction(m, c, a_, b_, dF, dv, state, contacts, friction)
    hp = contacts.hertz
    for c in range(N):
        if active[c]:
            m = jm[c]
            s_ = slot[c]
            _, dh = contact_approach(Fe[c], hp, c)
            contacts.deflection[m, s_] += ddepth[c] - dh * dfe[c]
            if friction.table.squeeze[m] != 0:  # the film's force (F - F_e) and power at the moved state
                r0 = contacts.overlap_rate[c]
                r1 = r0 + drates[c]  # the moved rate, as the check above took it
                fd = contacts.force[m, s_] - (Fe[c] + dfe[c])
                friction.damping_power[m] += fd * r1 - friction.damping[m, s_] * r0
                friction.damping[m, s_] = fd
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
            ax, ay, _, _, rx, ry = anchor(i, par, bodies, pose, vel)
            ex = 0.0
            ey = 0.0
            evx = 0.0
            evy = 0.0
            for j in range(n):
                jax, jay = anchor_jacobian(J, par, rx, ry, j)
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
        px, py, pr = mode_corrections(nq, body_modes(flex, cst, f), dload_work,
                                      FrameMotion(cs, sn, ax, ay, ar, w, vel[body, 0], vel[body, 1]),
                                      FrameChange(dax, day, dar, dw, dvx, dvy), alpha, dynamic, moving)
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
