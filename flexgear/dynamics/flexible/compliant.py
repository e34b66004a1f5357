"""Tooth contact on compliant flanks: line-contact Hertz plus the FE compliance of flexible gears.

For the meshes with ``LAW_HERTZ`` (every mesh with a flexible gear), the normal forces ``F_k``
of all their contacts, stacked in one problem, satisfy::

    delta_rigid_k = sum_l C_kl F_l + h_k(F_k)      for F_k > 0
    delta_rigid_k <= sum_l C_kl F_l                for F_k = 0

``delta_rigid_k`` the rigid overlap [m]; ``C_kl`` [m/N] the static flank compliance of the
flexible bodies carrying both contacts (:data:`FlexTable` of
:mod:`flexgear.dynamics.model.tables`: condensed modes plus residual tables, near field removed;
contacts of different meshes of one body couple through its rim, contacts on different bodies
never); ``h_k`` the 2D Hertz approach between the near-field reference depths
(:func:`flexgear.stiffness.hertz.hertz_approach`, plane strain) [m], plus the series compliance
of a cracked tooth's flank times F_k (:func:`~flexgear.dynamics.contact.laws.contact_approach`,
the mesh's :class:`~flexgear.dynamics.model.tables.ToothLawTable`; 0 on healthy teeth). Modal coordinates and the
condensed modes' response to the frame's acceleration are subtracted from ``delta_rigid_k``; the
IMPACT damper acts in parallel on the rigid approach, or with ``[lubrication] damping =
"squeeze_film"`` the film's c(u_e, F_e / L, R) d delta_rigid/dt
(:func:`~flexgear.dynamics.integrator.friction.film_coefficient`). Newton's method on the active set gives
the forces and the consistent tangent ``(C + diag h')^-1``; inside the integrator's Newton
iterations C is built only where the solve needs it
(:func:`~flexgear.dynamics.flexible.joint.solve_joint`). See the theory page *Compliant contact
and condensation*.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb

from ...kernels import kernel
import numpy as np

from ..contact.laws import LAW_HERTZ, contact_approach, contact_load, penetration_gradient, step, step_derivative
from ..contact.search import mesh_pair, mesh_search, toothing_centre
from ..contact.solve import active_set, lu_factor, lu_inverse
from ..contact.teeth import contact_slices
from .condensed import INTEGRATED, condensed_coefficients, condensed_response, frame_acceleration
from .flank import flank_cells, flank_contacts, flank_radius, flank_side, modal_flank, rigid_coordinates
from .joint import KNOWN, solve_joint
from ..integrator.friction import (contact_entrainment_row, film_coefficient, friction_load, friction_tangent,
                                   start_damping, start_friction)
from .sliding import tangential_flank


@kernel(error_model="numpy", _nrt=False)
def relief_reciprocity(G, c, u, slope, Mq):
    """Make the mass coupling of the inertia relief reciprocal: add to Mq the antisymmetric part
    that turns contact c's share ``X_c = G_c (x) u / slope`` into ``(X_c + X_c^T) / 2``; u is
    ``sum_q Kc[c, q] H[q]`` (the contact's row of dF/dq through the relief, summed with the
    tangent row in :func:`compliant_contacts`).

    Through :func:`inertia_flank_value` the contact forces depend on the accelerations, which is
    a mass ``X = G^T Kc R`` (R: the flank displacement per unit acceleration, ``H / slope``); it
    is not symmetric between bodies (gear A's flank relief against gear B's acceleration), and
    an unsymmetric mass splits a pair of equal frequencies into a growing and a decaying
    oscillation (MERCURY 1-A flexible, level 1, 5 % damping: pairs at 6.8 and 16.2 kHz, growth
    time 3.4 ms, seen as a 16 kHz oscillation building up at steps of 3 us and below). Its
    symmetric part keeps every mode's Rayleigh quotient (the frequencies, to first order) and the
    contact forces, and conserves energy."""
    n = u.shape[0]
    for r in range(n):
        gr = G[c, r]
        if gr == 0.0:
            continue
        for s in range(n):
            x = 0.5 * gr * (u[s] / slope)
            if x != 0.0:
                Mq[r, s] -= x
                Mq[s, r] += x


@kernel(error_model="numpy", inline="always")
def body_contacts(rows, body, f, N):
    """The stacked contacts (of N) on body ``body`` (FlexTable row f): their slots, tooth, flank
    side and radius on that body, in stacked order, into row f of ``rows`` (a BodyRows); returns
    their number."""
    body_a = rows.body_a
    body_b = rows.body_b
    jm = rows.joint_mesh
    ji = rows.joint_i
    slot = rows.body_slot[f]
    tooth = rows.body_tooth[f]
    bside = rows.body_side[f]
    brad = rows.body_radius[f]
    nk = 0
    for k in range(N):
        m = jm[k]
        if body_a[m] == body:
            slot[nk] = k
            tooth[nk] = ji[k, 0]
            bside[nk] = rows.flank_side_a[k]
            brad[nk] = rows.flank_radius_a[k]
            nk += 1
        elif body_b[m] == body:
            slot[nk] = k
            tooth[nk] = ji[k, 1]
            bside[nk] = rows.flank_side_b[k]
            brad[nk] = rows.flank_radius_b[k]
            nk += 1
    return nk


class MeshSearches(NamedTuple):
    """The contact searches of the compliant meshes (:func:`mesh_searches`): each mesh's search
    data (MeshTable) and its own result rows (ContactBuffers), under their sources' names."""

    body_a: np.ndarray  # (nm,) int
    body_b: np.ndarray  # (nm,) int
    gear_a: np.ndarray  # (nm,) int
    gear_b: np.ndarray  # (nm,) int
    internal: np.ndarray  # (nm,) bool
    ncand_a: np.ndarray  # (nm,) int
    ncand_b: np.ndarray  # (nm,) int
    stride: np.ndarray  # (nm,) int
    gap: np.ndarray  # (nm,) float [m]
    search_f: np.ndarray  # (nm, MAX_CONTACTS, 5) float: each mesh's found_f
    search_i: np.ndarray  # (nm, MAX_CONTACTS, 3) int: each mesh's found_i
    search_hits: np.ndarray  # (nm,) int: contacts found in each mesh
    search_cache: np.ndarray  # (nm, 4 MAX_CONTACTS, 4) int
    search_count: np.ndarray  # (nm, 1) int


@kernel(error_model="numpy", inline="always")
def mesh_searches(meshes, contacts):
    """The MeshSearches of a MeshTable and the ContactBuffers."""
    return MeshSearches(meshes.body_a, meshes.body_b, meshes.gear_a, meshes.gear_b, meshes.internal, meshes.ncand_a,
                        meshes.ncand_b, meshes.stride, meshes.gap, contacts.search_f, contacts.search_i,
                        contacts.search_hits, contacts.search_cache, contacts.search_count)


# the per-mesh and per-body tasks: functions of their own, called from the parallel loops (stores
# into the arrays of a tuple read inside a prange body itself are lost, numba issue 7135; a
# function called there writes them)
@kernel(error_model="numpy", _nrt=False)
def search_task(m, pose, searches, contact, local):
    """Contact search of mesh m (:func:`~flexgear.dynamics.contact.search.mesh_search`) into its
    own rows of ``searches`` (a MeshSearches): ``search_f[m]``, ``search_i[m]``, the count in
    ``search_hits[m]``, its search cache."""
    s = searches
    a = s.body_a[m]
    b = s.body_b[m]
    s.search_hits[m] = mesh_search(pose[a], pose[b], mesh_pair(s, m), contact, s.search_f[m], s.search_i[m], local,
                                   s.search_cache[m], s.search_count[m])


@kernel(error_model="numpy", parallel=True)
def search_parallel(order, ns, pose, searches, contact, local):
    """:func:`search_task` of the meshes ``order[:ns]`` in parallel threads (each writes only its
    mesh's rows)."""
    for p in nb.prange(ns):
        search_task(order[p], pose, searches, contact, local)


class BodyRows(NamedTuple):
    """What phase 2 of :func:`compliant_contacts` reads and writes per flexible body
    (:func:`body_rows`): the meshes' bodies (MeshTable), the stacked contacts and the per-body
    rows (ContactBuffers), the flank tables (FlexTable), the bodies' kinematics (BodyState) and
    the condensed modes' weights and history (CondensedState), under their sources' names."""

    body_a: np.ndarray  # (nm,) int
    body_b: np.ndarray  # (nm,) int
    joint_mesh: np.ndarray  # (S,) int
    joint_i: np.ndarray  # (S, 3) int
    joint_count: np.ndarray  # (1,) int
    flank_side_a: np.ndarray  # (S,) int
    flank_side_b: np.ndarray  # (S,) int
    flank_radius_a: np.ndarray  # (S,) float [m]
    flank_radius_b: np.ndarray  # (S,) float [m]
    body_slot: np.ndarray  # (nf, S) int
    body_tooth: np.ndarray  # (nf, S) int
    body_side: np.ndarray  # (nf, S) int
    body_radius: np.ndarray  # (nf, S) float [m]
    body_count: np.ndarray  # (nf,) int
    flank_cell: np.ndarray  # (nf, S) int
    flank_weight: np.ndarray  # (nf, S) float
    coupling_cell: np.ndarray  # (nf, S) int
    coupling_weight: np.ndarray  # (nf, S) float
    flank_modes: np.ndarray  # (nf, S, modes) float
    body_relief: np.ndarray  # (nf, S, 4) float
    condensed: np.ndarray  # (nf,) int
    points: np.ndarray  # (nf,) int
    radius_offset: np.ndarray  # (nf,) int
    shape_offset: np.ndarray  # (nf,) int
    shape: np.ndarray  # FlexTable.shape
    radius: np.ndarray  # FlexTable.radius: table radii [m]
    coupling_stride: np.ndarray  # (nf,) int
    condensed_offset: np.ndarray  # (nf,) int
    pose: np.ndarray  # (nb, 3) float
    jacobian: np.ndarray  # (nb, 3, n) float
    accelerations: np.ndarray  # (n,) float
    convective: np.ndarray  # (nb, 3) float
    vel: np.ndarray  # (nb, 3) float
    inertia_weight: np.ndarray  # (sum 3 nq,) float
    history: np.ndarray  # (sum nq,) float


@kernel(error_model="numpy", inline="always")
def body_rows(meshes, flex, state, contacts, cst):
    """The BodyRows of the tables of one force evaluation."""
    c = contacts
    return BodyRows(meshes.body_a, meshes.body_b, c.joint_mesh, c.joint_i, c.joint_count, c.flank_side_a,
                    c.flank_side_b, c.flank_radius_a, c.flank_radius_b, c.body_slot, c.body_tooth, c.body_side,
                    c.body_radius, c.body_count, c.flank_cell, c.flank_weight, c.coupling_cell, c.coupling_weight,
                    c.flank_modes, c.body_relief, flex.condensed, flex.points, flex.radius_offset, flex.shape_offset,
                    flex.shape, flex.radius, flex.coupling_stride, flex.condensed_offset, state.pose, state.jacobian,
                    state.accelerations, state.convective, state.vel, cst.inertia_weight, cst.history)


@kernel(error_model="numpy", _nrt=False)
def body_rows_task(body, body_flex, rows):
    """Phase 2 of :func:`compliant_contacts` for one body (``rows``, a BodyRows), up to its shared
    stores: its stacked contacts (:func:`body_contacts`, count in ``body_count[f]``), their table
    cells and modal rows (:func:`~flexgear.dynamics.flexible.flank.flank_cells`) and per contact
    ``body_relief[f, i]`` = the frame-inertia weights (tx, ty, tr) and the decrease of the overlap
    by the condensed modes' history and the frame's inertia load (:func:`inertia_flank_value`);
    row f = ``body_flex[body]`` (nothing for a rigid body). Writes only row f of its outputs: the
    overlaps and gradient rows, which a contact's two bodies share, are changed afterwards in
    body order (:func:`inertia_rows`)."""
    f = body_flex[body]
    if f < 0:
        return
    nk = body_contacts(rows, body, f, rows.joint_count[0])
    rows.body_count[f] = nk
    if nk == 0:
        return
    contacts = flank_contacts(rows, f)
    U = contacts.modes
    nq = rows.condensed[f]
    co = rows.condensed_offset[f]
    rel = rows.body_relief[f]
    # the contacts' cells and modal rows; their compliance entries in the contact solve
    flank_cells(rows, f, contacts, nk)
    cs = math.cos(rows.pose[body, 2])
    sn = math.sin(rows.pose[body, 2])
    ax, ay, ar = frame_acceleration(rows.jacobian, rows.accelerations, rows.convective, body)
    # per contact the sums over the modes of its flank row times the frame-inertia weights and
    # the history (views of the body's modes: contiguous vectors)
    iw = rows.inertia_weight
    relief_sums(U, nk, nq, iw[3 * co:3 * co + nq], iw[3 * co + nq:3 * co + 2 * nq], iw[3 * co + 2 * nq:3 * co + 3 * nq],
                rows.history[co:co + nq], rel)
    for i in range(nk):
        rel[i, 3] += inertia_flank_value(rel[i, 0], rel[i, 1], rel[i, 2], cs, sn, ax, ay, ar, rows.vel, body)


# reassociated sums (vectorised, in an order of the compiler's: the last digits differ from a
# plain dot product's); a function of its own, so that the flag reaches these loops only
@kernel(error_model="numpy", _nrt=False, fastmath={"reassoc", "contract"})
def relief_sums(U, nk, nq, wx, wy, wr, hv, rel):
    """``rel[i, 0:4]`` = the sums over the nq modes of contact i's flank row ``U[i]`` times the
    frame-inertia weights ``wx``, ``wy``, ``wr`` and the history ``hv`` (views of the body's
    modes), for the nk contacts of a body (:func:`body_rows_task`). The sums are reassociated,
    so the compiler vectorises them; they have no other evaluation that they would have to equal bit for bit."""
    for i in range(nk):
        Ui = U[i]
        tx = 0.0
        ty = 0.0
        tr = 0.0
        uh = 0.0
        for m in range(nq):
            u = Ui[m]
            tx += u * wx[m]
            ty += u * wy[m]
            tr += u * wr[m]
            uh += u * hv[m]
        rel[i, 0] = tx
        rel[i, 1] = ty
        rel[i, 2] = tr
        rel[i, 3] = uh


@kernel(error_model="numpy", parallel=True)
def body_rows_parallel(body_flex, rows):
    """:func:`body_rows_task` of every body in parallel threads (each writes only its FlexTable
    row's rows; the bodies' rows are distinct, ``body_flex`` maps a body to its own row)."""
    for body in nb.prange(body_flex.shape[0]):
        body_rows_task(np.int64(body), body_flex, rows)  # the serial loop's index type: one overload


@kernel(error_model="numpy", inline="always")
def inertia_flank_value(tx, ty, tr, cs, sn, ax, ay, ar, vel, body):
    """Normal displacement [m] of a flank point of body ``body`` from the inertia load of its frame's acceleration on the condensed modes (positive opens the contact).

        A condensed mode responds to the frame's acceleration as a modal coordinate does; its
        flank displacement per unit load is ``(tx, ty, tr) = sum_i (A_i / omega_i) S_i w_i`` (body
        frame) [m s^2, m s^2/rad], w_i = 1 / omega_i quasi-statically, kappa_i / ((1 + alpha)
        omega_i) integrated (:mod:`flexgear.dynamics.flexible.condensed`). Without it a free
        pinion's body compliance would act as if its hub carried the whole inertia. ``cs, sn``: the
        body's angle; ``ax, ay, ar``: the frame's acceleration (:func:`frame_acceleration`);
        ``vel``: body velocities (nb, 3). The derivative with q goes to :func:`inertia_rows`.
    """
    if tx == 0.0 and ty == 0.0 and tr == 0.0:
        return 0.0
    gx = cs * tx - sn * ty
    gy = sn * tx + cs * ty
    return -(gx * ax + gy * ay + tr * ar) + vel[body, 2] * (-gx * vel[body, 1] + gy * vel[body, 0])


@kernel(error_model="numpy", inline="always")
def inertia_rows(tx, ty, tr, cs, sn, Jb, body, slope, H, k):
    """The gradient rows of :func:`inertia_flank_value`: adds ``slope * T_g . J_body`` to row k of H."""
    if tx == 0.0 and ty == 0.0 and tr == 0.0:
        return
    gx = cs * tx - sn * ty
    gy = sn * tx + cs * ty
    if slope != 0.0:
        for c in range(H.shape[1]):
            H[k, c] += slope * (gx * Jb[body, 0, c] + gy * Jb[body, 1, c] + tr * Jb[body, 2, c])


@kernel(error_model="numpy", _nrt=False)
def compliant_contacts(meshes, flex, body_flex, contact, state, system, contacts, cst, friction, local):
    """Contacts of every compliant mesh solved as one contact problem: forces, body loads, tangent matrices.

        ``flex`` is the FlexTable, ``body_flex`` the bodies' rows in it (-1: rigid); ``state``,
        ``system``, ``contacts``, ``cst``, ``friction`` the parts of the Workspace (tooth friction
        on the meshes with ``friction.table.on[m]``: :func:`compliant_friction`). Three phases: (1) contact
        search per ``LAW_HERTZ`` mesh, with the rigid overlap less the modal flank displacement, its
        rate, the Hertz parameters, the flanks and the penetration-gradient row in stacked slots;
        (2) ``C_kl`` over all contacts on each flexible body and one joint solve
        (:func:`~flexgear.dynamics.flexible.joint.solve_joint`) with its tangent and the condensed
        modes' response (:func:`flexgear.dynamics.flexible.condensed.condensed_response`); (3) loads,
        mesh totals, records and tangent rows, cross-mesh terms included. Compiled with
        ``_nrt=False`` (it creates no arrays; it takes apart about a thousand table arrays per
        evaluation).

        Returns
        -------
        deepest : float
            The largest rigid overlap of the compliant meshes [m] (0 without contact).
        where : int
            Its mesh (-1: no contact).
    """
    pose = state.pose
    vel = state.vel
    J = state.jacobian
    Fb = state.load
    Kt = system.stiffness
    Ct = system.damping
    G = system.contact_gradient
    H = system.inertia_gradient
    jf = contacts.joint_f
    ji = contacts.joint_i
    jm = contacts.joint_mesh
    n = system.rhs.shape[0]
    C = contacts.compliance
    dr = contacts.overlap
    rate = contacts.overlap_rate
    hp = contacts.hertz
    Fe = contacts.elastic_force
    active = contacts.active
    side_a = contacts.flank_side_a
    side_b = contacts.flank_side_b
    rad_a = contacts.flank_radius_a
    rad_b = contacts.flank_radius_b
    slope = state.acceleration_slope[0]
    integrated = cst.mode[0] == INTEGRATED
    modes = flex.modes
    deepest = 0.0
    where = -1
    # phase 1: contact search of every compliant mesh, each into its own rows (in parallel
    # threads with contacts.threads > 1), then per contact the geometry, stacked in mesh order
    order = contacts.search_order
    ns = 0
    for m in range(meshes.body_a.shape[0]):
        if meshes.law[m] == LAW_HERTZ:
            order[ns] = m
            ns += 1
    hits = contacts.search_hits
    searches = mesh_searches(meshes, contacts)
    if contacts.threads[0] > 1 and ns > 1:
        search_parallel(order, ns, pose, searches, contact, local)
    else:
        for p in range(ns):
            search_task(order[p], pose, searches, contact, local)
    N = 0
    nprev = contacts.joint_count[0]  # the last evaluation's stacked contacts (for start_force)
    start = contacts.start_force
    for p in range(ns):
        m = order[p]
        a = meshes.body_a[m]
        b = meshes.body_b[m]
        cnt = hits[m]
        out_f = contacts.search_f[m]
        out_i = contacts.search_i[m]
        fa = body_flex[a]
        fbb = body_flex[b]
        zb = contact.gear_z[meshes.gear_b[m]]
        L = meshes.face_width[m]
        for c in range(cnt):
            k = N + c
            # the contact Newton's start (solve_joint): this slot's elastic force of the last
            # evaluation, if the slot held the same contact
            same = (k < nprev and jm[k] == m and ji[k, 0] == out_i[c, 0] and ji[k, 1] == out_i[c, 1]
                    and ji[k, 2] == out_i[c, 2])
            start[k] = Fe[k] if same else 0.0
            for j in range(5):
                jf[k, j] = out_f[c, j]
            for j in range(3):
                ji[k, j] = out_i[c, j]
            jm[k] = m
            if out_f[c, 0] > deepest:
                deepest = out_f[c, 0]
                where = m
            px = out_f[c, 1]
            py = out_f[c, 2]
            nx = out_f[c, 3]
            ny = out_f[c, 4]
            dr[k] = out_f[c, 0]
            vax = vel[a, 0] - vel[a, 2] * (py - pose[a, 1])
            vay = vel[a, 1] + vel[a, 2] * (px - pose[a, 0])
            vbx = vel[b, 0] - vel[b, 2] * (py - pose[b, 1])
            vby = vel[b, 1] + vel[b, 2] * (px - pose[b, 0])
            rate[k] = nx * (vbx - vax) + ny * (vby - vay)
            side_a[k] = out_i[c, 2]
            # flank radii from the toothing centres (an eccentric gear's teeth turn about its axis
            # off their centre; the flank tables are the teeth's, about the toothing centre)
            xa, ya = toothing_centre(contact, meshes.gear_a[m], pose[a, 0], pose[a, 1], pose[a, 2])
            xb, yb = toothing_centre(contact, meshes.gear_b[m], pose[b, 0], pose[b, 1], pose[b, 2])
            rad_a[k] = flank_radius(px, py, xa, ya)  # the search gave side_a
            side_b[k], rad_b[k] = flank_side(px, py, xb, yb, pose[b, 2], out_i[c, 1], zb)
            # relative radius of curvature of the two involutes at the contact radii
            ta = math.sqrt(max(rad_a[k] ** 2 - meshes.rb_a[m] ** 2, (0.05 * meshes.rb_a[m]) ** 2))
            tb = math.sqrt(max(rad_b[k] ** 2 - meshes.rb_b[m] ** 2, (0.05 * meshes.rb_b[m]) ** 2))
            if meshes.internal[m]:
                R = ta * tb / max(tb - ta, 0.05 * tb)
            else:
                R = ta * tb / (ta + tb)
            hp[k, 0] = R
            hp[k, 1] = L
            hp[k, 2] = meshes.hertz_a[m]
            hp[k, 3] = meshes.nu_a[m]
            hp[k, 4] = meshes.depth_a[m]
            hp[k, 5] = meshes.hertz_b[m]
            hp[k, 6] = meshes.nu_b[m]
            hp[k, 7] = meshes.depth_b[m]
            hp[k, 8] = meshes.e_star[m]
            # series compliance of a cracked tooth's flank and the face-width slices of a partial
            # spall or chip (per-tooth table lookups; 0.0 and whole widths on healthy teeth)
            contact_slices(meshes, m, out_i[c, 0], out_i[c, 1], side_a[k], rad_a[k], rad_b[k], hp, k)
            ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
            mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
            penetration_gradient(G[k], J, a, b, nx, ny, ma, mb, n)
            # modal coordinates: their flank displacement opens the rigid overlap (rows of G too);
            # so do the condensed modes' history and the frames' inertia load on them (phase 2,
            # its gradient in H)
            for j in range(n):
                H[k, j] = 0.0
            if fa >= 0 and modes[fa] > 0:
                dr[k] -= modal_flank(flex, fa, out_i[c, 0], side_a[k], rad_a[k], state.coordinates, G[k])
            if fbb >= 0 and modes[fbb] > 0:
                dr[k] -= modal_flank(flex, fbb, out_i[c, 1], side_b[k], rad_b[k], state.coordinates, G[k])
        N += cnt
    contacts.joint_count[0] = N
    nr = rigid_coordinates(flex, n)
    A = contacts.solve_matrix
    # phase 2: C over all stacked contacts, body by body (bodies, not FlexTable rows: bodies
    # sharing a reduction are still different bodies); D of one body built in A, free until
    # the contact solve; the condensed modes' history and inertia load on the overlaps
    for i in range(N):
        for j in range(N):
            C[i, j] = 0.0
    kap = cst.kappa
    condensed_coefficients(flex, cst)
    # per body (in parallel threads with contacts.threads > 1) its contacts, their cells and
    # modal rows and the frame-inertia terms, each into its own rows; then, one body after the
    # other in body order, the terms on the overlaps and gradient rows, which the two bodies of
    # a contact share (the sums in the serial order: the same numbers with any thread count)
    relief = contacts.body_relief
    rows = body_rows(meshes, flex, state, contacts, cst)
    if contacts.threads[0] > 1:
        body_rows_parallel(body_flex, rows)
    else:
        for body in range(body_flex.shape[0]):
            body_rows_task(body, body_flex, rows)
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f < 0:
            continue
        nk = contacts.body_count[f]
        if nk == 0:
            continue
        slot = contacts.body_slot[f]
        rel = relief[f]
        cs = math.cos(pose[body, 2])
        sn = math.sin(pose[body, 2])
        for i in range(nk):
            k = slot[i]
            inertia_rows(rel[i, 0], rel[i, 1], rel[i, 2], cs, sn, J, body, slope, H, k)
            dr[k] -= rel[i, 3]
    piv = contacts.pivots
    known = contacts.compliance_known
    if N > 0:
        # every entry of C outside the integrator's Newton iterations (statics, evaluate: C is
        # inspected), inside them only those the solve needs
        solve_joint(flex, body_flex, contacts, kap, N, slope == 0.0)
    # the condensed modes' generalised forces and, integrated, their accelerations and reaction
    condensed_response(flex, cst, body_flex, contacts, state, system)
    # tangent of the elastic forces on the joint active set: (C + diag h')^-1
    idx = contacts.active_index
    na_ = active_set(active, N, idx)
    Kc = contacts.contact_tangent
    if na_ > 0:
        for p in range(na_):
            i = idx[p]
            for q in range(na_):
                A[p, q] = C[i, idx[q]]
            _, dh = contact_approach(Fe[i], hp, i)
            A[p, p] += dh
        if lu_factor(A, piv, na_):
            lu_inverse(A, piv, Kc, na_)
        else:
            for p in range(na_):
                for q in range(na_):
                    Kc[p, q] = np.nan
    # phase 3: loads, records, mesh totals and tangent rows
    for m in range(meshes.body_a.shape[0]):
        if meshes.law[m] == LAW_HERTZ:
            contacts.count[m] = 0
            contacts.mesh_force[m] = 0.0
            contacts.mesh_fx[m] = 0.0
            contacts.mesh_fy[m] = 0.0
            if friction.table.on[m] != 0:
                start_friction(m, friction)
            if friction.table.squeeze[m] != 0:
                start_damping(m, friction)
    w = contacts.tangent_row
    u = contacts.relief_row
    p_c = -1
    for c in range(N):
        m = jm[c]
        a = meshes.body_a[m]
        b = meshes.body_b[m]
        Cmax = meshes.C[m]
        dd = meshes.d[m]
        depth = jf[c, 0]
        defl = depth - dr[c]  # modal coordinates' and frame inertia's part
        if known[c] == KNOWN:
            for j in range(N):
                defl += C[c, j] * Fe[j]
        else:
            defl += contacts.coupled_deflection[c]
        F = 0.0
        sd = 0.0  # dF/d(delta') [N s/m]: the damper's coefficient
        sk = 1.0  # dF/dF_e with the squeeze film: 1 + (dc/dw) d(delta)/dt / L
        fu = 0.0  # dF/du_e with the squeeze film: (dc/du_e) d(delta)/dt [N s/m]
        film = friction.table.squeeze[m] != 0
        if active[c]:
            p_c += 1  # idx[p_c] == c: the active set in stacked order
            if film:  # the squeeze film's damper instead of the IMPACT ramp, at the elastic load
                sd, dcu, dcw = film_coefficient(m, a, b, Fe[c], jf[c, 1], jf[c, 2], jf[c, 3], jf[c, 4], state, friction)
                F = Fe[c] + sd * rate[c]
                sk = 1.0 + dcw * rate[c] / friction.table.width[m]
                fu = dcu * rate[c]
            else:
                sd = step(depth, 0.0, 0.0, dd, Cmax)
                F = Fe[c] + sd * rate[c]
            if F < 0.0:
                F = 0.0
        if not active[c] and dr[c] <= 0.0:
            contacts.joint_slot[c] = -1
            continue  # a near contact that stays open: not reported
        px = jf[c, 1]
        py = jf[c, 2]
        nx = jf[c, 3]
        ny = jf[c, 4]
        kept = contacts.count[m]
        contacts.joint_slot[c] = kept
        contacts.force[m, kept] = F
        contacts.depth[m, kept] = depth
        contacts.deflection[m, kept] = defl
        contacts.x[m, kept] = px
        contacts.y[m, kept] = py
        contacts.nx[m, kept] = nx
        contacts.ny[m, kept] = ny
        contacts.tooth_a[m, kept] = ji[c, 0]
        contacts.tooth_b[m, kept] = ji[c, 1]
        contacts.side_a[m, kept] = ji[c, 2]
        contacts.count[m] = kept + 1
        if not active[c]:
            continue
        # the frames feel the total force F, clipped at 0 (none while the damper's pull on a
        # separating pair exceeds the elastic force); the modes the elastic force F_e, as the
        # condensed modes (condensed.condensed_response) and the contact's compliance do
        loaded = F > 0.0
        if film:  # the film's force (the elastic force's negative where the contact opens) and power
            fd = sd * rate[c] if loaded else -Fe[c]
            friction.damping[m, kept] = fd
            friction.damping_power[m] += fd * rate[c]
        if loaded:
            contacts.mesh_force[m] += F
            contact_load(Fb, pose, a, b, px, py, nx, ny, F)
            contacts.mesh_fx[m] -= F * nx
            contacts.mesh_fy[m] -= F * ny
        # the modes feel the elastic force A_i F_e; the damper acts between the rigid frames
        for r in range(nr, n):
            system.rhs[r] -= Fe[c] * G[c, r]
        # tangent: row c of dF/d(delta_rigid) (elastic coupling over every compliant mesh +
        # damping ramp) times the gradients
        damp_slope = 0.0 if film else step_derivative(depth, 0.0, 0.0, dd, Cmax) * rate[c]  # of the IMPACT ramp
        for j in range(n):  # the damping ramp depends on the rigid overlap: rigid columns
            w[j] = damp_slope * G[c, j] if j < nr else 0.0
        relief = False
        for j in range(n):
            u[j] = 0.0
        for q in range(na_):
            kq = Kc[p_c, q]
            if kq == 0.0:  # contacts on no common body (exact zeros of the block LU)
                continue
            l_ = idx[q]
            for j in range(n):
                hj = H[l_, j]
                w[j] += kq * (G[l_, j] + hj)
                if hj != 0.0:
                    u[j] += kq * hj
                    relief = True
        e = friction.roll_row
        if fu != 0.0 and loaded:  # e = d u_e / dq' of the contact (friction.squeeze_contact's)
            contact_entrainment_row(e, J, pose, a, b, friction.table.frame[m], jf[c, 1], jf[c, 2], jf[c, 3], jf[c, 4])
        if relief and not integrated and loaded:  # the quasi-static relief's mass made reciprocal
            relief_reciprocity(G, c, u, slope, system.mass)
        if relief and integrated and loaded:
            # the integrated modes' reaction on the frames through this contact's elastic force,
            # (1 + alpha) beta h^2 H_c^T dF_c/dq (condensed.condensed_response): the Newton
            # matrix's (G + H)^T Kc (G + H), reciprocal
            for r in range(nr):
                hr = H[c, r]
                if hr == 0.0:
                    continue
                for s in range(n):
                    Kt[r, s] += hr * (w[s] - damp_slope * G[c, s]) if s < nr else hr * w[s]
        for r in range(n):
            gr = G[c, r]
            if gr == 0.0:
                continue
            if r < nr:  # rigid rows: elastic + damping force (none while clipped)
                if not loaded:
                    continue
                for s in range(n):  # sk: the film's coefficient follows the elastic load (1 exactly without)
                    Kt[r, s] += gr * (sk * w[s])
                for s in range(nr):
                    Ct[r, s] += sd * gr * G[c, s]
                if fu != 0.0:  # and the entrainment speed: row e = d u_e / dq'
                    for s in range(n):
                        Ct[r, s] += fu * gr * e[s]
            else:  # modal rows: elastic force only
                for s in range(n):
                    Kt[r, s] += gr * (w[s] - damp_slope * G[c, s]) if s < nr else gr * w[s]
        if loaded and friction.table.on[m] != 0:  # friction f along t = (-ny, nx) on b
            f = compliant_friction(a, b, c, sd, sk, fu, w, state, system, contacts, friction, flex)
            contacts.mesh_fx[m] -= f * ny
            contacts.mesh_fy[m] += f * nx
    return deepest, where


@kernel(error_model="numpy", inline="always")
def compliant_friction(a, b, c, sd, sk, fu, w, state, system, contacts, friction, flex):
    """Tooth friction of stacked contact c (bodies a, b; its mesh ``contacts.joint_mesh[c]``, its
    reported slot ``contacts.joint_slot[c]``): the rigid model's
    :func:`~flexgear.dynamics.integrator.friction.friction_load` at the contact point from the
    floating frames' kinematics plus the flanks' elastic sliding speed from the modal rates, its
    generalised force on the modal coordinates, ``-f T`` on each gear
    (:mod:`flexgear.dynamics.flexible.sliding`), and its tangent with the compliant contact's
    normal force derivatives: ``sk w`` = dF/dq (``w`` every column: the elastic coupling over all
    compliant contacts, the condensed modes' relief, the IMPACT damper's ramp; ``sk`` = 1, with
    the squeeze film 1 + dc/dw d(delta)/dt / L), ``sd`` G[c, :nr] = dF/dq' (the damper on the
    rigid approach, the IMPACT ramp or the film's coefficient) and, with the film, ``fu`` = dF/du_e
    along the entrainment row; the sliding row -d v_s / dq' holds the modal
    rates' -T too. The condensed modes and residual tables are normal only (theory page
    *Compliant contact and condensation*, section *Tooth friction*). Returns f [N], the friction
    force on b along t."""
    tab = friction.table
    m = contacts.joint_mesh[c]
    kept = contacts.joint_slot[c]
    nr = rigid_coordinates(flex, w.shape[0])
    ve = 0.0
    row = friction.elastic_row[m, kept]  # length 0 without modal coordinates' tables
    if row.shape[0] > 0:  # T of both flanks, looked up once: d v_s / dq' at their modal coordinates
        off = tab.tangent_offset
        T = tab.tangent_shape
        for j in range(row.shape[0]):
            row[j] = 0.0
        ve = (tangential_flank(flex, off, T, a, contacts.joint_i[c, 0], contacts.flank_side_a[c],
                               contacts.flank_radius_a[c], state.rates, row)
              + tangential_flank(flex, off, T, b, contacts.joint_i[c, 1], contacts.flank_side_b[c],
                                 contacts.flank_radius_b[c], state.rates, row))
        friction.elastic[m, kept] = ve
    f, cF, cv, cu = friction_load(m, kept, a, b, ve, state, contacts, friction)  # cF = d f / d F
    hn = friction.slide_row
    for j in range(row.shape[0]):  # -T into the sliding row -d v_s / dq', the generalised force -f T
        if row[j] != 0.0:
            hn[j] -= row[j]
            system.rhs[j] -= f * row[j]
    if fu != 0.0:  # the squeeze film's normal force changes with u_e (friction.contact_friction)
        cu += cF * fu
    friction_tangent(system.stiffness, system.damping, hn, friction.roll_row, cF * sk, w, cF * sd,
                     system.contact_gradient[c], nr, cv, cu)
    return f
