"""What a step of the integrator records: mesh totals, body states, drive torques, contact pairs,
the condensed modes and the rigid meshes' tooth friction (into the :class:`~flexgear.dynamics.integrator.buffers.Records`).
"""
from __future__ import annotations

import math

import numpy as np


from ...kernels import kernel
from ..flexible.condensed import frame_acceleration, mode_frame_coupling, mode_inertia_load
from ..model.bodies import ANGLE_PRESCRIBED, MAXC



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
def record_friction(k, friction, count, out_every, records):
    """Write step k of the rigid meshes' tooth friction and squeeze-film damping (``friction``,
    the FrictionBuffers of the last evaluation; ``count``: contacts of each mesh): the mesh
    totals, and every out_every steps each contact slot's force, sliding speed and position,
    and squeeze-film force. Nothing for what the run does not have (records with 0 rows; a
    frictionless model's ``friction`` None)."""
    if friction is None:
        return
    nm = friction.mesh_force.shape[0]
    if records.damping_power.shape[0] > 0:
        for m in range(nm):
            records.damping_power[k, m] = friction.damping_power[m]
        if (k + 1) % out_every == 0:
            o = (k + 1) // out_every - 1
            for m in range(nm):
                for c in range(MAXC):
                    records.pair_damping[o, m, c] = friction.damping[m, c] if c < count[m] else 0.0
    if records.friction_force.shape[0] == 0:
        return
    for m in range(nm):
        records.friction_force[k, m] = friction.mesh_force[m]
        records.friction_power[k, m] = friction.mesh_power[m]
        records.friction_through[k, m] = friction.mesh_through[m]
    if (k + 1) % out_every == 0:
        o = (k + 1) // out_every - 1
        for m in range(nm):
            for c in range(MAXC):
                if c < count[m]:
                    records.pair_friction[o, m, c] = friction.force[m, c]
                    records.pair_sliding[o, m, c] = friction.sliding[m, c]
                    records.pair_position[o, m, c] = friction.position[m, c]
                else:
                    records.pair_friction[o, m, c] = 0.0
                    records.pair_sliding[o, m, c] = np.nan
                    records.pair_position[o, m, c] = np.nan
