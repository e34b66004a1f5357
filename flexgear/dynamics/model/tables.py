"""Named tables of arrays: what the compiled kernels of :mod:`flexgear.dynamics.integrator.solver` take.

Each concern is one :class:`typing.NamedTuple` of numpy arrays (and a few scalars), one array
per named quantity, with its unit in the comment. Numba passes a NamedTuple of arrays to
``@njit(cache=True)`` functions as a plain tuple whose type is fixed by the field types, so
the kernels are compiled once and loaded from numba's on-disk cache by every later process
(jitclass and structref arguments are not: numba issues 6522, 9659, 10021). A kernel reads::

    forces(q, qd, t, model, contact, work, local)
    integrate(q, v, acc, t0, nsteps, model, contact, settings, records, stats)

========================  ====================================================================
table                     concern
========================  ====================================================================
:class:`BodyTable`        joints, supports, mass properties of the bodies (per body)
:class:`ProfileTable`     time profiles (prescribed speeds, applied torques), concatenated
:class:`MeshTable`        gear meshes: bodies, geometries, search band, IMPACT law (per mesh)
:class:`FlexTable`        flexible bodies: modal coordinates, reduced matrices, mode shapes
:class:`KernelModel`      the four tables above: the model as the kernels see it
``ContactTables``         outlines and signed distance fields (:mod:`flexgear.gears.contact_tables`)
:class:`Workspace`        buffers of one force evaluation: BodyState (poses, Jacobians, loads),
                          SystemMatrices (rhs, Mq, Kt, Ct), ContactBuffers (contacts, totals)
:class:`Records`          the time histories written by the integrator
:class:`Settings`         step, HHT parameter, Newton tolerance, limits
:class:`Statistics`       step and iteration counts, the error code and where it happened
========================  ====================================================================

Integer quantities (indices, codes, counts) are int64 arrays, real ones float64. A table
whose concern is absent has zero-length arrays of the same dtype and dimension (a model
without flexible bodies passes an empty :class:`FlexTable`), so one compiled signature
serves every model.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..contact.search import MAX_CONTACTS


class BodyTable(NamedTuple):
    """Per-body data (nb bodies, parents before children). Codes: see :mod:`flexgear.dynamics.model.bodies`."""

    joint: np.ndarray  # (nb,) int: FIXED, REVOLUTE or BEARING
    rotation: np.ndarray  # (nb,) int: ANGLE_FIXED, ANGLE_FREE, ANGLE_PRESCRIBED or ANGLE_SPRING
    parent: np.ndarray  # (nb,) int: parent body (-1: ground)
    ix: np.ndarray  # (nb,) int: coordinate of the centre's x (BEARING), else -1
    iy: np.ndarray  # (nb,) int: coordinate of the centre's y (BEARING), else -1
    itheta: np.ndarray  # (nb,) int: coordinate of the angle (ANGLE_FREE, ANGLE_SPRING), else -1
    speed_profile: np.ndarray  # (nb,) int: prescribed angular velocity profile, -1: none
    torque_profile: np.ndarray  # (nb,) int: applied torque profile, -1: none
    flex: np.ndarray  # (nb,) int: row of the body in the FlexTable, -1: rigid
    torsion_parent: np.ndarray  # (nb,) int: ANGLE_SPRING to this body's rotation (a shaft), -1: to ground
    mass: np.ndarray  # (nb,) float: mass [kg]
    inertia: np.ndarray  # (nb,) float: polar moment of inertia about the centre [kg m^2]
    pin_x: np.ndarray  # (nb,) float: joint / anchor point x, in the parent's frame [m]
    pin_y: np.ndarray  # (nb,) float: joint / anchor point y, in the parent's frame [m]
    theta0: np.ndarray  # (nb,) float: initial angle; fixed angle; rest angle of the torsional spring [rad]
    stiffness: np.ndarray  # (nb,) float: bearing stiffness in x and y [N/m]
    damping: np.ndarray  # (nb,) float: bearing damping [N s/m]
    torsional_stiffness: np.ndarray  # (nb,) float: [N m/rad]
    torsional_damping: np.ndarray  # (nb,) float: [N m s/rad]
    torque_ramp: np.ndarray  # (nb,) float: applied torque x STEP(t; 0, 0, torque_ramp, 1) [s]
    omega0: np.ndarray  # (nb,) float: initial angular velocity [rad/s]


class ProfileTable(NamedTuple):
    """Piecewise linear time profiles, concatenated: profile p has the nodes
    ``offset[p]:offset[p + 1]`` (one node: a constant); held constant outside its nodes."""

    t: np.ndarray  # (nodes,) float: node times [s]
    value: np.ndarray  # (nodes,) float: values at the nodes [rad/s or N m]
    integral: np.ndarray  # (nodes,) float: integral of the profile from its first node [rad or N m s]
    offset: np.ndarray  # (profiles + 1,) int


class MeshTable(NamedTuple):
    """Per gear mesh (nm meshes): gear A (external) on body_a, gear B on body_b."""

    body_a: np.ndarray  # (nm,) int
    body_b: np.ndarray  # (nm,) int
    gear_a: np.ndarray  # (nm,) int: geometry of gear A in the ContactTables
    gear_b: np.ndarray  # (nm,) int: geometry of gear B in the ContactTables
    internal: np.ndarray  # (nm,) bool: B is an internal gear
    ncand_a: np.ndarray  # (nm,) int: half-width of A's candidate band of teeth
    ncand_b: np.ndarray  # (nm,) int: half-width of B's candidate band of teeth
    stride: np.ndarray  # (nm,) int: coarse scan stride of the full contact search [outline samples]
    K: np.ndarray  # (nm,) float: IMPACT stiffness [N/m^e]
    e: np.ndarray  # (nm,) float: IMPACT force exponent [-]
    C: np.ndarray  # (nm,) float: IMPACT maximum damping [N s/m]
    d: np.ndarray  # (nm,) float: IMPACT penetration at full damping [m]
    law: np.ndarray  # (nm,) int: contact law, LAW_IMPACT (0) or LAW_HERTZ (1: line contact on compliant flanks)
    gap: np.ndarray  # (nm,) float: near contacts with a rigid gap up to this are reported too [m] (0: IMPACT)
    face_width: np.ndarray  # (nm,) float: contact length L of the Hertz law [m]
    hertz_a: np.ndarray  # (nm,) float: 1 / (pi E1) of gear A (plane strain) [1/Pa]
    hertz_b: np.ndarray  # (nm,) float: 1 / (pi E1) of gear B [1/Pa]
    nu_a: np.ndarray  # (nm,) float: nu1 of gear A (plane strain) [-]
    nu_b: np.ndarray  # (nm,) float: nu1 of gear B [-]
    e_star: np.ndarray  # (nm,) float: contact modulus E* [Pa]
    depth_a: np.ndarray  # (nm,) float: near-field reference depth of gear A [m]
    depth_b: np.ndarray  # (nm,) float: near-field reference depth of gear B [m]
    rb_a: np.ndarray  # (nm,) float: base radius of gear A [m] (radius of curvature of the flanks)
    rb_b: np.ndarray  # (nm,) float: base radius of gear B [m]


class FlexTable(NamedTuple):
    """Flexible bodies (nf of them): the compliance of their flanks at the contacts.

    A rigid model passes :func:`empty_flex` (every array of length zero); a model with flexible
    bodies passes the same dtypes and dimensions, so the compiled signature is the same. Row f
    describes body ``body[f]`` (whose ``BodyTable.flex`` is f), a gear with ``teeth[f]`` teeth
    reduced by :func:`flexgear.reduction.gear.reduce_gear` (bore, or ring rim/bolts, tied to the
    body frame).

    Every fixed-interface mode of the body is condensed quasi-statically here (at the presets'
    defaults the first clamped modes lie at 31-64 kHz, far above what a 25 us step resolves),
    so the flanks respond to the contact forces through a static compliance::

        c(k, s, r; l, s', r') = sum_i A_i(k, s, r) A_i(l, s', r') / omega_i^2     (modes)
                                + residual(k, s, r; l, s', r')                       (tables)

    between flank point (tooth k, side s, radius r) and the loaded point (tooth l, side s',
    radius r') [m/N]. ``A_i`` is the normal flank displacement per unit modal coordinate (mass
    normalised) and also the generalised force per newton; the residual part is the static
    compliance the modes miss, tabulated for every pair of flanks of the body: the loaded flank
    with itself (self, near field removed: it stays in the Hertz contact law) and with both
    flanks of every tooth at every distance ``d = (k - l) mod z`` (the other flank of the same
    tooth included), so that modes plus tables are the static FE compliance between any two
    flank points. Tables are linear in the radius between the ``points[f]`` table radii; the
    coupling tables (smooth fields) use every ``coupling_stride[f]``-th of them.

    Layout of the flat arrays (J = points[f], nq = condensed[f], z = teeth[f], P = period[f],
    Jc = (J - 1) / coupling_stride[f] + 1, side index si = 0 for side +1 (left flank), 1 for
    side -1):

    * ``radius[radius_offset[f] + j]`` [m], increasing;
    * ``shape[shape_offset[f] + ((k * 2 + si) * J + j) * nq + i] = A_i / omega_i`` [m/sqrt(N m)]
      for tooth k: the dot product of two such rows is a compliance [m/N];
    * ``self_compliance[self_offset[f] + (c * 2 + si) * J + j]`` [m/N] for tooth class c = k % P;
    * ``coupling[coupling_offset[f] + ((((c * 2 + so) * 2 + si) * z + d) * Jc + jo) * Jc + ji]``
      [m/N]: displacement of side index so of tooth ``(c + d) mod z`` at coupling radius jo
      (table radius ``jo * coupling_stride[f]``) per newton on side index si of tooth c at
      coupling radius ji (tooth class c, d = 0..z-1; the block d = 0, so = si is the raw
      residual of one flank, which the kernel does not use).

    Modes below ``[flexible] dynamic_cutoff`` are not condensed: they are the ``modes[f] = m``
    modal coordinates ``q[coordinate[f] : coordinate[f] + m]`` (after every rigid coordinate;
    see :mod:`flexgear.dynamics.flexible.floating_frame`), with the m x m blocks ``stiffness`` (omega_i^2), ``mass``
    (identity for mass-normalised modes) and ``damping`` (2 zeta omega_i) from
    ``matrix_offset[f]``, row-major, and

    * ``dynamic_shape[dynamic_offset[f] + ((k * 2 + si) * J + j) * m + i] = A_i`` [m per unit
      modal coordinate, 1/sqrt(kg)]: the normal flank displacement of the dynamic mode i (the
      ``shape`` rows then hold only the condensed modes);
    * ``frame_coupling[frame_offset[f] + d * m + i]`` for d = 0, 1, 2 (x, y, theta of the body
      frame): the reduced mass block ``R^T M Phi`` of the Craig-Bampton body [sqrt(kg),
      sqrt(kg) m], in the body frame.

    The condensed modes respond to the inertia load of the body frame's acceleration too, and,
    integrated inside the contact solve (:mod:`flexgear.dynamics.flexible.condensed`), to their own
    inertia; for that each body's condensed modes carry ``condensed_omega`` (omega_i [rad/s]),
    ``condensed_damping`` (2 zeta omega_i [1/s]) and ``condensed_coupling[3 *
    condensed_offset[f] + d * nq + i]`` = S_di, their mass coupling with the frame's x, y, theta
    (d = 0, 1, 2, body frame; the reduced mass block ``R^T M Phi`` [sqrt(kg), sqrt(kg) m]; zero
    for an interface that is not the frame, e.g. a ring held on its rim).
    """

    body: np.ndarray  # (nf,) int: body index in the BodyTable
    coordinate: np.ndarray  # (nf,) int: index in q of the first modal coordinate (-1: none)
    modes: np.ndarray  # (nf,) int: number of modal coordinates m kept in q
    matrix_offset: np.ndarray  # (nf,) int: start of the m x m blocks in stiffness / mass / damping
    stiffness: np.ndarray  # (sum m^2,) float: reduced stiffness blocks, row-major
    mass: np.ndarray  # (sum m^2,) float: reduced mass blocks, row-major
    damping: np.ndarray  # (sum m^2,) float: reduced damping blocks, row-major
    teeth: np.ndarray  # (nf,) int: number of teeth z
    period: np.ndarray  # (nf,) int: tooth classes of the residual tables (1: all teeth alike)
    points: np.ndarray  # (nf,) int: table radii J
    condensed: np.ndarray  # (nf,) int: modes condensed quasi-statically nq
    radius_offset: np.ndarray  # (nf,) int
    radius: np.ndarray  # (sum J,) float: table radii [m]
    shape_offset: np.ndarray  # (nf,) int
    shape: np.ndarray  # (sum z 2 J nq,) float: A_i / omega_i at the table radii [m / sqrt(N/m)]
    self_offset: np.ndarray  # (nf,) int
    self_compliance: np.ndarray  # (sum P 2 J,) float: residual self compliance [m/N]
    coupling_offset: np.ndarray  # (nf,) int
    coupling: np.ndarray  # (sum P 2 2 z Jc Jc,) float: residual compliance between flanks at every tooth distance [m/N]
    coupling_stride: np.ndarray  # (nf,) int: table radii per coupling-table interval
    dynamic_offset: np.ndarray  # (nf,) int
    dynamic_shape: np.ndarray  # (sum z 2 J m,) float: A_i of the modal coordinates [1/sqrt(kg)]
    frame_offset: np.ndarray  # (nf,) int
    frame_coupling: np.ndarray  # (sum 3 m,) float: R^T M Phi, rows x, y, theta [sqrt(kg), sqrt(kg) m]
    condensed_offset: np.ndarray  # (nf,) int: start of body f's condensed modes in the per-mode arrays
    condensed_omega: np.ndarray  # (sum nq,) float: circular frequency omega_i of each condensed mode [rad/s]
    condensed_damping: np.ndarray  # (sum nq,) float: its modal damping 2 zeta omega_i [1/s]
    condensed_coupling: np.ndarray  # (sum 3 nq,) float: its frame-mode mass coupling S_di, rows x, y, theta [sqrt(kg), sqrt(kg) m]


class KernelModel(NamedTuple):
    """The model as the compiled kernels see it (:meth:`flexgear.dynamics.model.bodies.Model.pack`)."""

    bodies: BodyTable
    profiles: ProfileTable
    meshes: MeshTable
    flex: FlexTable


class BodyState(NamedTuple):
    """Kinematics and loads of the bodies in one force evaluation (nb bodies, n coordinates).
    Rows are (x, y, theta) of each body."""

    pose: np.ndarray  # (nb, 3) float: x, y [m], angle [rad]
    vel: np.ndarray  # (nb, 3) float: vx, vy [m/s], angular velocity [rad/s]
    jacobian: np.ndarray  # (nb, 3, n) float: d(pose)/dq
    convective: np.ndarray  # (nb, 3) float: convective acceleration [m/s^2, rad/s^2]
    load: np.ndarray  # (nb, 3) float: force Fx, Fy [N] and torque [N m] on each body
    coordinates: np.ndarray  # (n,) float: q of the evaluation (modal coordinates for the flanks)
    rates: np.ndarray  # (n,) float: dq/dt of the evaluation
    accelerations: np.ndarray  # (n,) float: d2q/dt2 for the frames' inertia load on condensed modes (the integrator's iterate, HHT-weighted with static condensation; 0 outside it)
    acceleration_slope: np.ndarray  # (1,) float: d(accelerations)/dq in the integrator's step: 1 / (beta h^2) integrated, 1 / ((1 + alpha) beta h^2) static [1/s^2] (0 outside it)


class SystemMatrices(NamedTuple):
    """Generalised quantities of one force evaluation (n coordinates)."""

    rhs: np.ndarray  # (n,) float: generalised force Q - J^T M gamma [N, N m]
    inertia_load: np.ndarray  # (n,) float: inertia forces at the step's end outside the HHT weighting: the reaction of integrated condensed modes on their frames [N, N m]
    mass: np.ndarray  # (n, n) float: generalised mass matrix Mq
    stiffness: np.ndarray  # (n, n) float: tangent stiffness Kt = -dQ/dq
    damping: np.ndarray  # (n, n) float: tangent damping Ct = -dQ/dq'
    bearing_rows: np.ndarray  # (2, n) float: d(centre - anchor)/dq of the bearing being assembled
    gradient: np.ndarray  # (n,) float: d(penetration)/dq of the contact being assembled
    contact_gradient: np.ndarray  # (S, n) float: d(penetration)/dq of the compliant contacts (S: ContactBuffers)
    inertia_gradient: np.ndarray  # (S, n) float: d(penetration)/dq through the frames' inertia load on the condensed modes


class ContactBuffers(NamedTuple):
    """Tooth contacts of one force evaluation (nm meshes, MAX_CONTACTS slots per mesh; the
    compliant meshes' contacts also stacked in S slots for their joint solve)."""

    found_f: np.ndarray  # (MAX_CONTACTS, 5) float: one mesh's contacts from mesh_contacts
    found_i: np.ndarray  # (MAX_CONTACTS, 3) int: one mesh's tooth indices from mesh_contacts
    count: np.ndarray  # (nm,) int: contacts of each mesh
    force: np.ndarray  # (nm, MAX_CONTACTS) float: normal force [N]
    depth: np.ndarray  # (nm, MAX_CONTACTS) float: penetration [m]
    x: np.ndarray  # (nm, MAX_CONTACTS) float: contact point x [m]
    y: np.ndarray  # (nm, MAX_CONTACTS) float: contact point y [m]
    nx: np.ndarray  # (nm, MAX_CONTACTS) float: unit normal of the force on gear A, x
    ny: np.ndarray  # (nm, MAX_CONTACTS) float: unit normal of the force on gear A, y
    tooth_a: np.ndarray  # (nm, MAX_CONTACTS) int: tooth of gear A
    tooth_b: np.ndarray  # (nm, MAX_CONTACTS) int: tooth of gear B
    side_a: np.ndarray  # (nm, MAX_CONTACTS) int: flank side of gear A (+1 / -1)
    deflection: np.ndarray  # (nm, MAX_CONTACTS) float: elastic flank deflection of both gears [m]
    mesh_force: np.ndarray  # (nm,) float: sum of the normal forces [N]
    mesh_fx: np.ndarray  # (nm,) float: resultant x force on body b [N]
    mesh_fy: np.ndarray  # (nm,) float: resultant y force on body b [N]
    max_depth: np.ndarray  # (1,) float: largest penetration of the evaluation [m]
    search_cache: np.ndarray  # (nm, 4 MAX_CONTACTS, 4) int: half teeth near contact (see contact._scan)
    search_count: np.ndarray  # (nm, 1) int: entries of search_cache in use
    # the joint contact problem of every compliant mesh (compliant.compliant_contacts): S =
    # (number of LAW_HERTZ meshes) x MAX_CONTACTS stacked slots, reused evaluation after
    # evaluation so that a force evaluation allocates nothing
    joint_f: np.ndarray  # (S, 5) float: found_f rows of the stacked contacts (rigid overlap, point, normal)
    joint_i: np.ndarray  # (S, 3) int: found_i rows of the stacked contacts (tooth a, tooth b, side a)
    joint_mesh: np.ndarray  # (S,) int: mesh of each stacked contact
    joint_count: np.ndarray  # (1,) int: stacked contacts in use
    joint_slot: np.ndarray  # (S,) int: the stacked contact's slot in its mesh's rows (force, depth, ...; -1: not reported)
    overlap: np.ndarray  # (S,) float: rigid overlap of each contact less the modal flank displacement [m]
    overlap_rate: np.ndarray  # (S,) float: rate of the rigid overlap [m/s]
    compliance: np.ndarray  # (S, S) float: flank compliance between the contacts, all bodies [m/N]
    hertz: np.ndarray  # (S, 10) float: Hertz parameters of each contact (compliant.hertz_line)
    elastic_force: np.ndarray  # (S,) float: elastic contact force [N]
    active: np.ndarray  # (S,) bool: contact in the active set
    flank_side_a: np.ndarray  # (S,) int: flank side of gear A (+1 / -1)
    flank_side_b: np.ndarray  # (S,) int: flank side of gear B (+1 / -1)
    flank_radius_a: np.ndarray  # (S,) float: contact radius on gear A [m]
    flank_radius_b: np.ndarray  # (S,) float: contact radius on gear B [m]
    body_slot: np.ndarray  # (nf, S) int: the stacked contacts on each flexible body (row f: body_count[f] of them)
    body_tooth: np.ndarray  # (nf, S) int: their tooth on that body
    body_side: np.ndarray  # (nf, S) int: their flank side on that body (+1 / -1)
    body_radius: np.ndarray  # (nf, S) float: their contact radius on that body [m]
    body_count: np.ndarray  # (nf,) int: stacked contacts on each flexible body
    active_index: np.ndarray  # (S,) int: contacts of the active set, in order
    solve_matrix: np.ndarray  # (S, S) float: Newton matrix C + diag(h'), LU in place [m/N]
    solve_vector: np.ndarray  # (S,) float: Newton residual, then step [m, N]
    pivots: np.ndarray  # (S,) int: row interchanges of the LU
    contact_tangent: np.ndarray  # (S, S) float: (C + diag(h'))^-1 on the active set [N/m]
    tangent_row: np.ndarray  # (n,) float: one contact's row of dF/dq [N/m, N/rad]
    relief_row: np.ndarray  # (n,) float: one contact's row of dF/dq through the inertia relief (times 1 / slope: dF/dq'') [N/m, N/rad]
    flank_cell: np.ndarray  # (nf, S) int: flank table interval of each contact on each flexible body
    flank_weight: np.ndarray  # (nf, S) float: its interpolation weight [-]
    coupling_cell: np.ndarray  # (nf, S) int: interval of the coupling tables' radii (every k-th)
    coupling_weight: np.ndarray  # (nf, S) float: its interpolation weight [-]
    flank_modes: np.ndarray  # (nf, S, modes) float: condensed modal flank displacements A_i / omega_i of each flexible body's contacts [m/sqrt(N/m)]
    compliance_known: np.ndarray  # (S,) int: whether the entries of ``compliance`` between a contact and the others are computed (compliant.UNKNOWN, KNOWN, FRESH: being added)
    coupled_deflection: np.ndarray  # (S,) float: sum_l C_kl F_l of the contacts whose row is not computed [m]
    start_force: np.ndarray  # (S,) float: the contact Newton's start: the last evaluation's elastic force of the contact in this slot if the slot held the same contact (mesh, teeth, side), else 0 [N]
    # threads of the compliant meshes' evaluation (compliant.compliant_contacts): each mesh's
    # search and each body's flank rows into their own rows, stacked and summed in one thread
    threads: np.ndarray  # (1,) int: threads of the evaluation's parallel loops (1: serial; set by solver.simulate with numba's thread count)
    search_order: np.ndarray  # (nm,) int: the compliant meshes, in mesh order (first of them in use)
    search_hits: np.ndarray  # (nm,) int: contacts found in each mesh
    search_f: np.ndarray  # (nm, MAX_CONTACTS, 5) float: each mesh's found_f (rigid overlap, point, normal)
    search_i: np.ndarray  # (nm, MAX_CONTACTS, 3) int: each mesh's found_i (tooth a, tooth b, side a)
    body_relief: np.ndarray  # (nf, S, 4) float: per contact on each flexible body the frame-inertia flank displacement weights tx, ty, tr (body frame) and its overlap decrease [m s^2, m s^2 / rad, m]
    # the bodies' parts of the joint compliance and of the open deflections, each into its own rows
    # (compliant.joint_entries, open_deflections), in parallel groups of bodies
    body_entries: np.ndarray  # (nf, S, S) float: each body's part of C between its contacts (local indices) [m/N]
    body_cols: np.ndarray  # (nf, S) int: work array of each body's entries (columns)
    body_vals: np.ndarray  # (nf, S) float: work array of each body's entries (modal parts) [m/N]
    body_open: np.ndarray  # (nf, S) float: each body's part of the open contacts' deflections (local indices) [m]
    body_modal_work: np.ndarray  # (nf, modes) float: each body's condensed modes' weighted load (compliant.open_entries)
    body_group: np.ndarray  # (nf,) int: each body's group of the parallel loops (compliant.body_groups; -1: no contacts)
    group_load: np.ndarray  # (nf,) float: work array of compliant.body_groups


class CondensedState(NamedTuple):
    """The condensed modes of the flexible bodies (per mode, at ``FlexTable.condensed_offset``):
    their state at the last accepted step when they are integrated inside the contact solve
    (:mod:`flexgear.dynamics.flexible.condensed`), and the coefficients of the step being solved."""

    mode: np.ndarray  # (1,) int: 0 quasi-static condensation, 1 integrated in the contact solve
    step: np.ndarray  # (1,) float: the step h of the evaluation (0: the modes held at their accepted state) [s]
    alpha: np.ndarray  # (1,) float: HHT parameter of the step [-]
    started: np.ndarray  # (1,) int: 1 once the modes' state is set (the first integrator call sets it to the static response)
    position: np.ndarray  # (sum nq,) float: eta_i at the last accepted step [sqrt(kg) m]
    velocity: np.ndarray  # (sum nq,) float: eta_i' [sqrt(kg) m/s]
    acceleration: np.ndarray  # (sum nq,) float: eta_i'' [sqrt(kg) m/s^2]
    residual: np.ndarray  # (sum nq,) float: c_i eta_i' + omega_i^2 eta_i - A_i . F at the accepted step (HHT's alpha part) [sqrt(kg) m/s^2]
    trial: np.ndarray  # (sum nq,) float: eta_i'' at the end of the step, from the last evaluation [sqrt(kg) m/s^2]
    load: np.ndarray  # (sum nq,) float: generalised contact force A_i . F of the last evaluation [sqrt(kg) m/s^2]
    free: np.ndarray  # (sum nq,) float: the step's eta_i'' D_i before contact and frame loads [sqrt(kg) m/s^2]
    divisor: np.ndarray  # (sum nq,) float: D_i = 1 + (1 + alpha)(c_i gamma h + omega_i^2 beta h^2) [-]
    kappa: np.ndarray  # (sum nq,) float: weight of mode i in the step's flank compliance (1: static) [-]
    history: np.ndarray  # (sum nq,) float: omega_i times eta_i at the step's end without contact and frame loads [sqrt(N/m) sqrt(kg) m]
    inertia_weight: np.ndarray  # (sum 3 nq,) float: flank displacement weights of the frame's acceleration, S_di kappa_i / ((1 + alpha) omega_i) (static: S_di / omega_i) [sqrt(kg) s, sqrt(kg) m s]
    coefficient_key: np.ndarray  # (nf, 4) float: condensation, step and alpha of each body's kappa, divisor and inertia_weight; the step of its free response and history (NaN: none yet)


class Linearisation(NamedTuple):
    """Work arrays of a one-pass acceptance (solver.linearised_acceptance): the changes that
    move a force evaluation to the corrected state (S, nm and MAX_CONTACTS: ContactBuffers)."""

    overlap_change: np.ndarray  # (S,) float: change of each stacked compliant contact's overlap, (G + H) dq [m]
    force_change: np.ndarray  # (S,) float: change of its elastic force on the active set [N]
    depth_change: np.ndarray  # (S,) float: change of its rigid overlap, G dq [m]
    force: np.ndarray  # (nm, MAX_CONTACTS) float: moved force of every reported contact, both laws [N]
    depth: np.ndarray  # (nm, MAX_CONTACTS) float: its moved rigid overlap (penetration) [m]
    modal_load: np.ndarray  # (modes,) float: one body's condensed modes' contact load change over omega_i, A_i . dF_e / omega_i [sqrt(kg) m/s]
    reaction: np.ndarray  # (n,) float: change of the condensed modes' reaction on the frames [N, N m]


class Workspace(NamedTuple):
    """Buffers of one force evaluation, in parts so that each sub-kernel takes only the part it
    fills (every array handed to a compiled function costs a reference count)."""

    bodies: BodyState
    system: SystemMatrices
    contacts: ContactBuffers
    condensed: CondensedState
    linear: Linearisation


class Records(NamedTuple):
    """Time histories: one row per step (``nsteps``), pairs every out_every steps (``nout``)."""

    mesh_force: np.ndarray  # (nsteps, nm) float: sum of the normal forces [N]
    mesh_fx: np.ndarray  # (nsteps, nm) float: resultant x force on body b [N]
    mesh_fy: np.ndarray  # (nsteps, nm) float: resultant y force on body b [N]
    x: np.ndarray  # (nsteps, nb) float: centre x [m]
    y: np.ndarray  # (nsteps, nb) float: centre y [m]
    theta: np.ndarray  # (nsteps, nb) float: angle [rad]
    vx: np.ndarray  # (nsteps, nb) float: [m/s]
    vy: np.ndarray  # (nsteps, nb) float: [m/s]
    omega: np.ndarray  # (nsteps, nb) float: [rad/s]
    torque: np.ndarray  # (nsteps, nb) float: drive torque of a prescribed body [N m], else 0
    pair_force: np.ndarray  # (nout, nm, MAX_CONTACTS) float: normal force of each contact slot [N]
    pair_depth: np.ndarray  # (nout, nm, MAX_CONTACTS) float: penetration [m]
    pair_tooth_a: np.ndarray  # (nout, nm, MAX_CONTACTS) int: tooth of gear A (-1: empty slot)
    pair_tooth_b: np.ndarray  # (nout, nm, MAX_CONTACTS) int: tooth of gear B (-1: empty slot)
    pair_side_a: np.ndarray  # (nout, nm, MAX_CONTACTS) int: flank side of gear A (0: empty slot)
    pair_deflection: np.ndarray  # (nout, nm, MAX_CONTACTS) float: elastic flank deflection of both gears [m]
    modal: np.ndarray  # (nsteps, nmodal) float: modal coordinates of the flexible bodies [sqrt(kg) m]
    condensed: np.ndarray  # (nout, sum nq) float: condensed modes' eta_i at the pair samples (FlexTable.condensed_offset) [sqrt(kg) m]

    def window(self, k0: int, k: int, out_every: int) -> "Records":
        """Views of steps k0 .. k0 + k (k0 and k multiples of out_every)."""
        o0, no = k0 // out_every, k // out_every
        return Records(*[a[k0:k0 + k] for a in self[:10]], *[a[o0:o0 + no] for a in self[10:16]],
                       self.modal[k0:k0 + k], self.condensed[o0:o0 + no])


class Settings(NamedTuple):
    """Integrator settings."""

    h: float  # time step [s]
    alpha: float  # HHT parameter in [-1/3, 0] [-]
    tol: float  # Newton tolerance on the position increment [m]
    max_newton: int  # Newton iterations per step before the step is halved
    depth_limit: float  # penetration beyond which the run has diverged [m]
    full_every: int  # full contact search every this many steps
    out_every: int  # contact pairs recorded every this many steps
    scale: np.ndarray  # (n,) float: length per unit of each coordinate [m/m or m/rad]
    condensation: int  # condensed modes: 0 quasi-static, 1 integrated in the contact solve (CondensedState.mode)
    one_pass: int = 0  # 1: accept a step after one Newton correction when the contraction allows, records corrected to first order (solver.linearised_acceptance)


class Statistics(NamedTuple):
    """Counters of a run and, when it stops, the error code and where (arrays of length 1)."""

    steps: np.ndarray  # int: accepted steps (sub-steps included)
    newton: np.ndarray  # int: Newton iterations
    rejected: np.ndarray  # int: steps rejected and halved
    max_iter: np.ndarray  # int: most Newton iterations in one step
    linearised: np.ndarray  # int: steps accepted after one Newton correction (Settings.one_pass)
    error_code: np.ndarray  # int: 0 = OK, else the solver's ERR_* code
    error_time: np.ndarray  # float: simulated time of the error [s]
    error_mesh: np.ndarray  # int: mesh with the deepest penetration (-1: none / the coordinates)


def empty_flex() -> FlexTable:
    """The flexible-body table of a rigid model: every array of length zero."""
    kinds = {"body": 0, "coordinate": 0, "modes": 0, "matrix_offset": 0, "teeth": 0, "period": 0, "points": 0,
             "condensed": 0, "radius_offset": 0, "shape_offset": 0, "self_offset": 0, "coupling_offset": 0,
             "dynamic_offset": 0, "frame_offset": 0, "coupling_stride": 0, "condensed_offset": 0}
    return FlexTable(**{k: (np.zeros(0, np.int64) if k in kinds else np.zeros(0)) for k in FlexTable._fields})


def workspace(n: int, nb: int, nm: int, modes: int = 0, compliant: int | None = None, flexible: int = 0,
              condensed: int = 0) -> Workspace:
    """Zeroed buffers for n coordinates, nb bodies and nm meshes; ``modes``: the most condensed
    modes of a flexible body (``FlexTable.condensed``; with fewer the compliant meshes take a
    slower path); ``compliant``: the number of meshes with the compliant law (``LAW_HERTZ``),
    whose contacts are solved jointly in ``compliant * MAX_CONTACTS`` slots (default: nm);
    ``flexible``: the flexible bodies (rows of the FlexTable); ``condensed``: their condensed
    modes in all (the sum of ``FlexTable.condensed``)."""
    mc = MAX_CONTACTS
    S = mc * (nm if compliant is None else int(compliant))
    nq = int(condensed)
    nf = max(int(flexible), 1)
    return Workspace(
        bodies=BodyState(pose=np.zeros((nb, 3)), vel=np.zeros((nb, 3)), jacobian=np.zeros((nb, 3, n)),
                         convective=np.zeros((nb, 3)), load=np.zeros((nb, 3)), coordinates=np.zeros(n),
                         rates=np.zeros(n), accelerations=np.zeros(n), acceleration_slope=np.zeros(1)),
        system=SystemMatrices(rhs=np.zeros(n), inertia_load=np.zeros(n), mass=np.zeros((n, n)), stiffness=np.zeros((n, n)),
                              damping=np.zeros((n, n)), bearing_rows=np.zeros((2, n)), gradient=np.zeros(n),
                              contact_gradient=np.zeros((S, n)), inertia_gradient=np.zeros((S, n))),
        contacts=ContactBuffers(
            found_f=np.zeros((mc, 5)), found_i=np.zeros((mc, 3), np.int64), count=np.zeros(nm, np.int64),
            force=np.zeros((nm, mc)), depth=np.zeros((nm, mc)), x=np.zeros((nm, mc)), y=np.zeros((nm, mc)),
            nx=np.zeros((nm, mc)), ny=np.zeros((nm, mc)), tooth_a=np.zeros((nm, mc), np.int64),
            tooth_b=np.zeros((nm, mc), np.int64), side_a=np.zeros((nm, mc), np.int64),
            deflection=np.zeros((nm, mc)), mesh_force=np.zeros(nm),
            mesh_fx=np.zeros(nm), mesh_fy=np.zeros(nm), max_depth=np.zeros(1),
            search_cache=np.zeros((nm, 4 * mc, 4), np.int64), search_count=np.zeros((nm, 1), np.int64),
            joint_f=np.zeros((S, 5)), joint_i=np.zeros((S, 3), np.int64), joint_mesh=np.zeros(S, np.int64),
            joint_count=np.zeros(1, np.int64), joint_slot=np.zeros(S, np.int64),
            overlap=np.zeros(S), overlap_rate=np.zeros(S), compliance=np.zeros((S, S)), hertz=np.zeros((S, 10)),
            elastic_force=np.zeros(S), active=np.zeros(S, np.bool_), flank_side_a=np.zeros(S, np.int64),
            flank_side_b=np.zeros(S, np.int64), flank_radius_a=np.zeros(S), flank_radius_b=np.zeros(S),
            body_slot=np.zeros((nf, S), np.int64), body_tooth=np.zeros((nf, S), np.int64),
            body_side=np.zeros((nf, S), np.int64), body_radius=np.zeros((nf, S)), body_count=np.zeros(nf, np.int64),
            active_index=np.zeros(S, np.int64), solve_matrix=np.zeros((S, S)), solve_vector=np.zeros(S),
            pivots=np.zeros(S, np.int64), contact_tangent=np.zeros((S, S)), tangent_row=np.zeros(n), relief_row=np.zeros(n),
            flank_cell=np.zeros((nf, S), np.int64), flank_weight=np.zeros((nf, S)),
            coupling_cell=np.zeros((nf, S), np.int64), coupling_weight=np.zeros((nf, S)),
            flank_modes=np.zeros((nf, S, modes)), compliance_known=np.zeros(S, np.int64),
            coupled_deflection=np.zeros(S), start_force=np.zeros(S),
            threads=np.ones(1, np.int64), search_order=np.zeros(nm, np.int64), search_hits=np.zeros(nm, np.int64),
            search_f=np.zeros((nm, mc, 5)), search_i=np.zeros((nm, mc, 3), np.int64),
            body_relief=np.zeros((nf, S, 4)), body_entries=np.zeros((nf, S, S)), body_cols=np.zeros((nf, S), np.int64),
            body_vals=np.zeros((nf, S)), body_open=np.zeros((nf, S)), body_modal_work=np.zeros((nf, max(int(modes), 1))),
            body_group=np.zeros(nf, np.int64), group_load=np.zeros(nf)),
        condensed=CondensedState(
            mode=np.zeros(1, np.int64), step=np.zeros(1), alpha=np.zeros(1), started=np.zeros(1, np.int64),
            **{k: np.zeros(nq) for k in ("position", "velocity", "acceleration", "residual", "trial", "load", "free",
                                         "divisor", "kappa", "history")},
            inertia_weight=np.zeros(3 * nq), coefficient_key=np.full((nf, 4), np.nan)),
        linear=Linearisation(overlap_change=np.zeros(S), force_change=np.zeros(S), depth_change=np.zeros(S),
                             force=np.zeros((nm, mc)), depth=np.zeros((nm, mc)),
                             modal_load=np.zeros(max(int(modes), 1)), reaction=np.zeros(n)),
    )


def records(nsteps: int, nout: int, nb: int, nm: int, nmodal: int = 0, ncondensed: int = 0) -> Records:
    """Zeroed time histories (``nmodal`` modal coordinates, every step; ``ncondensed`` condensed
    modes, the sum of ``FlexTable.condensed``, at the nout pair samples only)."""
    mc = MAX_CONTACTS
    return Records(*[np.zeros((nsteps, nm)) for _ in range(3)], *[np.zeros((nsteps, nb)) for _ in range(7)],
                   np.zeros((nout, nm, mc)), np.zeros((nout, nm, mc)),
                   *[np.zeros((nout, nm, mc), np.int64) for _ in range(3)], np.zeros((nout, nm, mc)),
                   np.zeros((nsteps, nmodal)), np.zeros((nout, int(ncondensed))))


def statistics() -> Statistics:
    """Zeroed counters."""
    i = lambda: np.zeros(1, np.int64)  # noqa: E731
    return Statistics(steps=i(), newton=i(), rejected=i(), max_iter=i(), linearised=i(), error_code=i(), error_time=np.zeros(1),
                      error_mesh=i())
