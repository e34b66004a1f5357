"""Tooth friction and squeeze-film damping of the meshes: the friction force of every contact the
contact search finds, its loads on both bodies and its Newton tangent (``[lubrication]`` with the
rigid model; the flexible model's compliant contacts take :func:`friction_load` and
:func:`friction_tangent` with their own normal-force derivatives,
:func:`flexgear.dynamics.flexible.compliant.compliant_friction`); with ``damping =
"squeeze_film"`` the damping term of each rigid (IMPACT) contact's normal force
(:func:`squeeze_contact`).

At a contact point P with normal n (of the force on gear a) and flank tangent t = (-n_y, n_x),
the sliding speed is v_s = t . (V_a(P) - V_b(P)) and the entrainment speed u_e = t .
(V_a(P) + V_b(P)) / 2 - t . V_f(P), both from the bodies' kinematics (f: the frame the gear
centres are pinned to, the carrier; the ground for a spur pair). The friction force
f = mu(v_s, u_e, w, R) F (:func:`flexgear.gears.tribology.friction_coefficient_slopes`, signed
like v_s; w = F / face width, R from the involutes' radii of curvature rho = |(P - O) . n|)
acts at P: -f t on gear a, +f t on gear b, with their moments (arms (P - O) x t = +-rho). Its
Newton tangent: d f / dq = (mu + w dmu/dw) dF/dq, d f / dq' = (mu + w dmu/dw) dF/dq' +
F (dmu/dv_s h + dmu/du_e e), h = d v_s / dq', e = d u_e / dq' (the changes of P, n and the arms
with q are left out, as in the normal contact's tangent). Derivation: the theory page
*Contact law and search*, section *Tooth friction*. In the flexible model v_s also holds the
flanks' elastic velocity from the modal rates and the friction loads the modal coordinates
(:mod:`flexgear.dynamics.flexible.sliding`; the table's ``tangent_offset``, ``tangent_shape``).

Squeeze film: the normal force of a contact is F = F_e + c(u_e, w_e, R) d delta/dt, F_e the
elastic part of the mesh's law (the IMPACT law without its damper), w_e = F_e / face width, c
the squeeze-film coefficient at the central film thickness
(:func:`flexgear.gears.tribology.squeeze_film_slopes`); 0 where F <= 0, as the IMPACT law.
Tangent: dF/d delta = dF_e/d delta + (dc/dw) (dF_e/d delta) / L d delta/dt, dF/d delta' = c,
dF/du_e = (dc/du_e) d delta/dt (row e). Derivation: the theory page *Contact law and search*,
section *Squeeze-film damping*. The compliant contacts of the flexible model take the same
coefficient (:func:`film_coefficient`) at their elastic force
(:func:`flexgear.dynamics.flexible.compliant.compliant_contacts`).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...gears.tribology import (FrictionParameters, friction_coefficient_slopes, friction_parameters,
                                law_constants, squeeze_film_factor, squeeze_film_slopes)
from ...kernels import kernel
from ..contact.laws import contact_load, penetration_gradient
from ..contact.search import MAX_CONTACTS
from ..lumped.friction import simulates_friction, squeeze_film_damped


class RigidFriction(NamedTuple):
    """The friction and squeeze-film damping of the meshes as the force kernel takes them (one row
    per mesh)."""

    params: FrictionParameters  # the friction law (and lubricant) of every mesh
    law: np.ndarray  # (nm, 2) float: the friction laws' constants (flexgear.gears.tribology.law_constants)
    on: np.ndarray  # (nm,) int: 1 friction on this mesh, 0 frictionless (nothing computed)
    squeeze: np.ndarray  # (nm,) int: 1 squeeze-film damping instead of the IMPACT damper, 0 the IMPACT law
    film_factor: np.ndarray  # (nm,) float: K of the film coefficient (tribology.squeeze_film_factor) [N s/m]
    width: np.ndarray  # (nm,) float: face width in contact [m] (w = F / width)
    sigma: np.ndarray  # (nm,) float: +1 external, -1 internal mesh (R = rho_a rho_b / |rho_b + sigma rho_a|)
    frame: np.ndarray  # (nm,) int: body the gear centres are pinned to (-1: the ground)
    pitch_radius: np.ndarray  # (nm,) float: operating pitch radius of gear a [m] (contact position)
    tangent_offset: np.ndarray  # (nf,) int: start of FlexTable row f's table in tangent_shape (-1: none)
    tangent_shape: np.ndarray  # (sum z 2 J m,) float: T_i of the modal coordinates [1/sqrt(kg)] (flexible.sliding)


class FrictionBuffers(NamedTuple):
    """The friction table and what one force evaluation fills (nm meshes, MAX_CONTACTS slots,
    n coordinates)."""

    table: RigidFriction
    force: np.ndarray  # (nm, MAX_CONTACTS) float: friction force f of each contact [N] (0: none)
    sliding: np.ndarray  # (nm, MAX_CONTACTS) float: sliding speed v_s [m/s] (nan: no contact)
    position: np.ndarray  # (nm, MAX_CONTACTS) float: contact position from the pitch point [m] (nan: no contact)
    mesh_force: np.ndarray  # (nm,) float: sum of the contacts' f [N]
    mesh_power: np.ndarray  # (nm,) float: power the friction dissipates, sum f v_s [W]
    mesh_through: np.ndarray  # (nm,) float: power the normal forces carry through the mesh [W]
    slide_row: np.ndarray  # (n,) float: -h = -d v_s / dq' of the contact being assembled
    roll_row: np.ndarray  # (n,) float: e = d u_e / dq' of the contact being assembled
    damping: np.ndarray  # (nm, MAX_CONTACTS) float: squeeze-film force of each contact [N] (0: none)
    damping_power: np.ndarray  # (nm,) float: power the squeeze films dissipate [W]
    elastic: np.ndarray  # (nm, MAX_CONTACTS) float: the flanks' elastic part of v_s [m/s] (flexible.sliding)
    elastic_row: np.ndarray  # (nm, MAX_CONTACTS, n or 0) float: its gradient d v_s / dq' at the modal coordinates


def friction_buffers(nm: int, n: int, table: RigidFriction | None = None) -> FrictionBuffers:
    """Zeroed buffers; without ``table`` every mesh frictionless (the arrays of a table with
    nm rows, all off: the same compiled types with and without friction)."""
    if table is None:
        table = frictionless_table(nm)
    mc = MAX_CONTACTS
    elastic = n if np.any(table.tangent_offset >= 0) else 0
    return FrictionBuffers(table=table, force=np.zeros((nm, mc)), sliding=np.full((nm, mc), np.nan),
                           position=np.full((nm, mc), np.nan), mesh_force=np.zeros(nm), mesh_power=np.zeros(nm),
                           mesh_through=np.zeros(nm), slide_row=np.zeros(n), roll_row=np.zeros(n),
                           damping=np.zeros((nm, mc)), damping_power=np.zeros(nm), elastic=np.zeros((nm, mc)),
                           elastic_row=np.zeros((nm, mc, elastic)))


def frictionless_table(nm: int) -> RigidFriction:
    """A :class:`RigidFriction` of nm frictionless meshes."""
    z = np.zeros(nm)
    params = FrictionParameters(model=np.zeros(nm, np.int64), mu=z.copy(), v0=np.ones(nm), eta=z.copy(),
                                alpha=z.copy(), e_star=np.ones(nm), roughness=z.copy(), xu=np.zeros((nm, 9)))
    return RigidFriction(params=params, law=np.zeros((nm, 2)), on=np.zeros(nm, np.int64),
                         squeeze=np.zeros(nm, np.int64), film_factor=z.copy(), width=np.ones(nm), sigma=np.ones(nm),
                         frame=np.full(nm, -1, np.int64), pitch_radius=z.copy(), tangent_offset=np.zeros(0, np.int64),
                         tangent_shape=np.zeros(0))


def rigid_friction(cfg, model) -> RigidFriction | None:
    """The :class:`RigidFriction` of ``model`` (built from ``cfg``) under ``cfg.lubrication``;
    None without friction and squeeze-film damping (no block, or a constant coefficient of 0
    with the IMPACT damper: the frictionless model, bit for bit)."""
    from ...config.faults import mesh_pairs
    from ...gears.material import effective_modulus
    rubs = simulates_friction(cfg)
    squeeze = squeeze_film_damped(cfg)
    if not (rubs or squeeze):
        return None
    pairs = mesh_pairs(cfg)
    names = [b.name for b in model.bodies]
    frame = names.index("carrier") if "carrier" in names else -1
    nm = len(model.meshes)
    width, sigma, radius, meshes = np.zeros(nm), np.ones(nm), np.zeros(nm), []
    for m, mesh in enumerate(model.meshes):
        an, bn, pair = pairs[mesh.name]
        if (names[mesh.a], names[mesh.b]) != (an, bn) or pair.g1.internal:
            raise ValueError(f"mesh {mesh.name}: bodies {names[mesh.a]}, {names[mesh.b]} do not match the pair "
                             f"{an}, {bn} (gear a external)")
        meshes.append((model.bodies[mesh.a].attrs["gear"], model.bodies[mesh.b].attrs["gear"]))
        width[m] = pair.face_width
        sigma[m] = -1.0 if pair.internal else 1.0
        radius[m] = pair.g1.rb / math.cos(pair.alpha_w)
    e_star = effective_modulus(cfg.material, cfg.material)
    params = friction_parameters(cfg.lubrication, meshes, e_star)
    oil = cfg.lubrication.lubricant
    film = np.array([squeeze_film_factor(oil.viscosity, oil.pressure_viscosity, e_star, L) if squeeze else 0.0
                     for L in width])
    offset, shape = np.zeros(0, np.int64), np.zeros(0)
    if rubs and any(fb.modes for fb in model.flex):  # the modal coordinates' tangential flank shapes
        from ..flexible.sliding import tangential_shapes

        offset, shape = tangential_shapes(cfg, model)
    return RigidFriction(params=params, law=law_constants(params), on=np.full(nm, int(rubs), np.int64),
                         squeeze=np.full(nm, int(squeeze), np.int64), film_factor=film, width=width, sigma=sigma,
                         frame=np.full(nm, frame, np.int64), pitch_radius=radius, tangent_offset=offset,
                         tangent_shape=shape)


@kernel(error_model="numpy", inline="always")
def tangential_speed(pose, vel, i, px, py, tx, ty):
    """t . V_i(P): the velocity of body i's material point at P along the direction (tx, ty)
    (the flank tangent, or the normal) [m/s] (0 for i = -1, the ground)."""
    if i < 0:
        return 0.0
    return tx * vel[i, 0] + ty * vel[i, 1] + vel[i, 2] * ((px - pose[i, 0]) * ty - (py - pose[i, 1]) * tx)


@kernel(error_model="numpy", inline="always")
def contact_axes(contacts, m, c):
    """Point (px, py) [m], normal (nx, ny) (of the force on gear a) and flank tangent (tx, ty) =
    (-ny, nx) of contact c of mesh m."""
    nx = contacts.nx[m, c]
    ny = contacts.ny[m, c]
    return contacts.x[m, c], contacts.y[m, c], nx, ny, -ny, nx


@kernel(error_model="numpy", inline="always")
def contact_relative_radius(pose, a, b, px, py, nx, ny, sigma):
    """R = rho_a rho_b / |rho_b + sigma rho_a| [m] from the involutes' radii of curvature at P,
    rho_i = |(P - O_i) . n| (sigma: +1 external, -1 internal mesh)."""
    rho_a = abs((px - pose[a, 0]) * nx + (py - pose[a, 1]) * ny)
    rho_b = abs((px - pose[b, 0]) * nx + (py - pose[b, 1]) * ny)
    return rho_a * rho_b / max(abs(rho_b + sigma * rho_a), 1e-12)


@kernel(error_model="numpy", inline="always")
def friction_tangent(Kt, Ct, hn, e, kq, dq_row, kv, dv_row, nv, cv, cu):
    """The friction's tangent, Q = f hn (hn = -d v_s / dq'; e = d u_e / dq'): Kt -= hn (kq
    dq_row)^T, d f / dq = kq dq_row; Ct -= hn (kv dv_row - cv hn + cu e)^T, d f / dq' with
    dv_row's first nv entries (the others 0), cv = F d mu / d v_s, cu = F d mu / d u_e."""
    n = hn.shape[0]
    for r in range(n):
        hr = hn[r]
        if hr == 0.0:
            continue
        for s in range(n):
            Kt[r, s] -= hr * kq * dq_row[s]
            ds = dv_row[s] if s < nv else 0.0
            Ct[r, s] -= hr * (kv * ds - cv * hn[s] + cu * e[s])


@kernel(error_model="numpy", inline="always")
def moved_speed(pose, vel, J, dv, i, px, py, tx, ty):
    """:func:`tangential_speed` of body i at P with the velocities changed by J dv (dv: a change
    of the generalised velocities) [m/s]."""
    u = tangential_speed(pose, vel, i, px, py, tx, ty)
    if i < 0:
        return u
    arm = (px - pose[i, 0]) * ty - (py - pose[i, 1]) * tx
    for j in range(dv.shape[0]):
        u += dv[j] * (tx * J[i, 0, j] + ty * J[i, 1, j] + arm * J[i, 2, j])
    return u


@kernel(error_model="numpy", inline="always")
def move_friction(m, c, a, b, dF, dv, state, contacts, friction):
    """Contact c of mesh m's friction moved with a step accepted after one Newton correction
    (:func:`~flexgear.dynamics.integrator.one_pass.linearised_acceptance`): its normal force
    already changed by dF in ``contacts``, the velocities by dv, the contact point held (as the
    normal force's correction holds it). The friction force at the moved speeds and force, its
    change applied to the body loads and mesh totals, and the outputs."""
    tab = friction.table
    F = contacts.force[m, c]
    F0 = F - dF
    f0 = friction.force[m, c]
    if F <= 0.0 and F0 <= 0.0:
        return
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    px, py, nx, ny, tx, ty = contact_axes(contacts, m, c)
    fr_ = tab.frame[m]
    vs, ue, R = moved_contact_speeds(tab, m, a, b, px, py, nx, ny, dv, state)
    if friction.elastic_row.shape[2] > 0 and F0 > 0.0:  # the flanks' elastic sliding (flexible.sliding)
        ve = friction.elastic[m, c]
        row = friction.elastic_row[m, c]
        for j in range(row.shape[0]):
            ve += row[j] * dv[j]
        vs += ve
    f = 0.0
    if F > 0.0:
        f = friction_coefficient_slopes(tab.params, tab.law[m], m, vs, ue, F / tab.width[m], R)[0] * F
    df = f - f0
    contact_load(state.load, pose, a, b, px, py, tx, ty, -df)
    contacts.mesh_fx[m] -= df * ny
    contacts.mesh_fy[m] += df * nx
    friction.mesh_force[m] += df
    friction.mesh_power[m] += f * vs - f0 * friction.sliding[m, c]
    ra0 = tangential_speed(pose, vel, a, px, py, nx, ny) - tangential_speed(pose, vel, fr_, px, py, nx, ny)
    ra1 = moved_speed(pose, vel, J, dv, a, px, py, nx, ny) - moved_speed(pose, vel, J, dv, fr_, px, py, nx, ny)
    friction.mesh_through[m] += max(F, 0.0) * abs(ra1) - max(F0, 0.0) * abs(ra0)
    friction.force[m, c] = f
    friction.sliding[m, c] = vs


@kernel(error_model="numpy", inline="always")
def start_friction(m, friction):
    """Clear mesh m's friction outputs before its contacts are assembled."""
    for c in range(friction.force.shape[1]):
        friction.force[m, c] = 0.0
        friction.sliding[m, c] = np.nan
        friction.position[m, c] = np.nan
        friction.elastic[m, c] = 0.0
    friction.mesh_force[m] = 0.0
    friction.mesh_power[m] = 0.0
    friction.mesh_through[m] = 0.0


@kernel(error_model="numpy", inline="always")
def contact_speeds(tab, m, a, b, px, py, nx, ny, pose, vel):
    """(v_s, u_e, R) of the contact of mesh m (bodies a, b) at (px, py) with normal (nx, ny):
    sliding and entrainment speed [m/s] along the flank tangent t = (-n_y, n_x) and the
    involutes' relative radius of curvature [m] (module docstring)."""
    tx = -ny
    ty = nx
    fr_ = tab.frame[m]
    ua = tangential_speed(pose, vel, a, px, py, tx, ty)
    ub = tangential_speed(pose, vel, b, px, py, tx, ty)
    uf = tangential_speed(pose, vel, fr_, px, py, tx, ty)
    vs = ua - ub
    ue = 0.5 * (ua + ub) - uf
    return vs, ue, contact_relative_radius(pose, a, b, px, py, nx, ny, tab.sigma[m])


@kernel(error_model="numpy", inline="always")
def moved_contact_speeds(tab, m, a, b, px, py, nx, ny, dv, state):
    """:func:`contact_speeds` with the velocities changed by J dv (a step accepted after one
    Newton correction, :func:`~flexgear.dynamics.integrator.one_pass.linearised_acceptance`; the
    contact point held)."""
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    tx = -ny
    ty = nx
    ua = moved_speed(pose, vel, J, dv, a, px, py, tx, ty)
    ub = moved_speed(pose, vel, J, dv, b, px, py, tx, ty)
    uf = moved_speed(pose, vel, J, dv, tab.frame[m], px, py, tx, ty)
    return ua - ub, 0.5 * (ua + ub) - uf, contact_relative_radius(pose, a, b, px, py, nx, ny, tab.sigma[m])


@kernel(error_model="numpy", inline="always")
def entrainment_row(e, J, pose, a, b, f, px, py, tx, ty, ma, mb):
    """e = d u_e / dq' into ``e`` (n,): the entrainment speed's gradient of a contact at (px, py)
    between bodies a and b with flank tangent (tx, ty) and tangential arms ma, mb, relative to
    frame body f (-1: the ground)."""
    mf = 0.0
    if f >= 0:
        mf = (px - pose[f, 0]) * ty - (py - pose[f, 1]) * tx
    for j in range(e.shape[0]):
        ga = tx * J[a, 0, j] + ty * J[a, 1, j] + ma * J[a, 2, j]
        gb = tx * J[b, 0, j] + ty * J[b, 1, j] + mb * J[b, 2, j]
        gf = 0.0
        if f >= 0:
            gf = tx * J[f, 0, j] + ty * J[f, 1, j] + mf * J[f, 2, j]
        e[j] = 0.5 * (ga + gb) - gf


@kernel(error_model="numpy", inline="always")
def contact_entrainment_row(e, J, pose, a, b, f, px, py, nx, ny):
    """:func:`entrainment_row` of a contact at (px, py) with normal (nx, ny): its flank tangent
    t = (-n_y, n_x) and the tangential arms from the poses of bodies a and b."""
    tx = -ny
    ty = nx
    ma = (px - pose[a, 0]) * ty - (py - pose[a, 1]) * tx
    mb = (px - pose[b, 0]) * ty - (py - pose[b, 1]) * tx
    entrainment_row(e, J, pose, a, b, f, px, py, tx, ty, ma, mb)


@kernel(error_model="numpy", inline="always")
def start_damping(m, friction):
    """Clear mesh m's squeeze-film outputs before its contacts are assembled."""
    for c in range(friction.damping.shape[1]):
        friction.damping[m, c] = 0.0
    friction.damping_power[m] = 0.0


@kernel(error_model="numpy", inline="always")
def film_coefficient(m, a, b, Fe, px, py, nx, ny, state, friction):
    """(c [N s/m], dc/du_e [N s^2/m^2], dc/dw [s]) of the squeeze film of a contact of mesh m
    (bodies a, b) at (px, py) with normal (nx, ny) carrying the elastic force ``Fe`` [N]: at its
    entrainment speed and relative radius (:func:`contact_speeds`) and its load per face width
    w = Fe / width (:func:`flexgear.gears.tribology.squeeze_film_slopes`); the rigid contact's
    (:func:`squeeze_contact`) and the compliant one's
    (:func:`flexgear.dynamics.flexible.compliant.compliant_contacts`)."""
    tab = friction.table
    _, ue, R = contact_speeds(tab, m, a, b, px, py, nx, ny, state.pose, state.vel)
    return squeeze_film_slopes(tab.film_factor[m], tab.params.v0[m], ue, Fe / tab.width[m], R)


@kernel(error_model="numpy", inline="always")
def moved_film_coefficient(m, a, b, Fe, px, py, nx, ny, dv, state, friction):
    """c [N s/m] of :func:`film_coefficient` with the velocities changed by J dv (a step accepted
    after one Newton correction, :func:`~flexgear.dynamics.integrator.one_pass.linearised_acceptance`;
    ``Fe`` the moved elastic force, the contact point held)."""
    tab = friction.table
    _, ue, R = moved_contact_speeds(tab, m, a, b, px, py, nx, ny, dv, state)
    c, _, _ = squeeze_film_slopes(tab.film_factor[m], tab.params.v0[m], ue, Fe / tab.width[m], R)
    return c


@kernel(error_model="numpy", inline="always")
def squeeze_contact(m, c, a, b, Fe, dFe, ddot, state, contacts, friction):
    """Normal force of contact c of mesh m (bodies a, b; its point and normal already in
    ``contacts``) with the squeeze-film damper: F_e, dF_e = dF_e/d delta the elastic part of the
    mesh's law, ddot the penetration rate [m/s] (module docstring). Records the damping force
    F - F_e and its power in ``friction``; with a damping force leaves e = d u_e / dq' in
    ``friction.roll_row``. Returns (F, dF/d delta, dF/d delta', dF/du_e), zeros where F <= 0."""
    if Fe <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    tab = friction.table
    pose = state.pose
    px = contacts.x[m, c]
    py = contacts.y[m, c]
    nx = contacts.nx[m, c]
    ny = contacts.ny[m, c]
    L = tab.width[m]
    cs, dc_u, dc_w = film_coefficient(m, a, b, Fe, px, py, nx, ny, state, friction)
    fd = cs * ddot
    F = Fe + fd
    if F <= 0.0:  # the film does not pull the flanks together (as the IMPACT law): the contact opens
        friction.damping[m, c] = -Fe
        friction.damping_power[m] -= Fe * ddot
        return 0.0, 0.0, 0.0, 0.0
    friction.damping[m, c] = fd
    friction.damping_power[m] += fd * ddot
    contact_entrainment_row(friction.roll_row, state.jacobian, pose, a, b, tab.frame[m], px, py, nx, ny)
    return F, dFe + dc_w * dFe / L * ddot, cs, dc_u * ddot


@kernel(error_model="numpy", inline="always")
def friction_load(m, c, a, b, ve, state, contacts, friction):
    """Friction of contact c of mesh m (bodies a, b; its normal force F, point and normal already
    in ``contacts``) from the bodies' kinematics, ``ve`` [m/s] added to the sliding speed (the
    flanks' elastic part, :mod:`flexgear.dynamics.flexible.sliding`; 0 rigid): its loads on both
    bodies, the contact's and the mesh's outputs and the rows ``friction.slide_row`` = -d v_s / dq', ``friction.roll_row``
    = d u_e / dq' (module docstring). Returns (f [N], the friction force on b along t; d f / d F;
    F d mu / d v_s [N s/m]; F d mu / d u_e [N s/m]), what a tangent needs besides the normal
    force's own derivatives (:func:`contact_friction`; the compliant contact's in
    :mod:`flexgear.dynamics.flexible.compliant`)."""
    tab = friction.table
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    hn = friction.slide_row
    e = friction.roll_row
    n = hn.shape[0]
    F = contacts.force[m, c]
    px, py, nx, ny, tx, ty = contact_axes(contacts, m, c)
    fr_ = tab.frame[m]
    vs, ue, R = contact_speeds(tab, m, a, b, px, py, nx, ny, pose, vel)
    if ve != 0.0:
        vs += ve
    w = F / tab.width[m]
    mu, dmu_v, dmu_u, dmu_w = friction_coefficient_slopes(tab.params, tab.law[m], m, vs, ue, w, R)
    f = mu * F
    ma, mb = contact_load(state.load, pose, a, b, px, py, tx, ty, -f)
    # the outputs: the contact's force, sliding speed and position from the pitch point C
    # (on the line of centres at r_w,a from O_a; beyond O_a for an internal mesh), positive
    # towards the tip of gear a
    friction.force[m, c] = f
    friction.sliding[m, c] = vs
    dx = pose[b, 0] - pose[a, 0]
    dy = pose[b, 1] - pose[a, 1]
    k = tab.sigma[m] * tab.pitch_radius[m] / math.sqrt(dx * dx + dy * dy)
    ex = px - pose[a, 0] - k * dx
    ey = py - pose[a, 1] - k * dy
    ra = math.sqrt((px - pose[a, 0]) ** 2 + (py - pose[a, 1]) ** 2)
    friction.position[m, c] = math.copysign(math.sqrt(ex * ex + ey * ey), ra - tab.pitch_radius[m])
    friction.mesh_force[m] += f
    friction.mesh_power[m] += f * vs
    # power the normal force carries out of gear a, relative to the frame
    ra_n = tangential_speed(pose, vel, a, px, py, nx, ny) - tangential_speed(pose, vel, fr_, px, py, nx, ny)
    friction.mesh_through[m] += F * abs(ra_n)
    # tangent: Q = f hn (hn = -h = -d v_s / dq'), Kt = -dQ/dq, Ct = -dQ/dq'
    penetration_gradient(hn, J, a, b, tx, ty, ma, mb, n)
    entrainment_row(e, J, pose, a, b, fr_, px, py, tx, ty, ma, mb)
    return f, mu + dmu_w * w, dmu_v * F, dmu_u * F


@kernel(error_model="numpy", inline="always")
def contact_friction(m, c, a, b, dF, cd, fu, state, system, contacts, friction):
    """Friction of contact c of mesh m of the IMPACT law (:func:`friction_load`; its penetration
    gradient in ``system.gradient``; dF, cd, fu: d F / d delta, d F / d delta', d F / d u_e, the
    last non-zero with the squeeze film): loads, outputs and tangent matrices. Returns f [N], the
    friction force on b along t."""
    g = system.gradient
    f, cF, cv, cu = friction_load(m, c, a, b, 0.0, state, contacts, friction)  # cF = d f / d F
    if fu != 0.0:  # the squeeze film's normal force changes with u_e
        cu += cF * fu
    friction_tangent(system.stiffness, system.damping, friction.slide_row, friction.roll_row, cF * dF, g, cF * cd, g,
                     g.shape[0], cv, cu)
    return f
