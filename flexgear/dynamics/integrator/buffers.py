"""Buffers of the compiled integrator: what one force evaluation fills, what a run records, its
settings and counters (named tables of arrays, as :mod:`flexgear.dynamics.model.tables`).

========================  ====================================================================
table                     concern
========================  ====================================================================
:class:`Workspace`        buffers of one force evaluation: BodyState (poses, Jacobians, loads),
                          SystemMatrices (rhs, Mq, Kt, Ct), ContactBuffers (contacts, totals),
                          CondensedState (condensed modes), Linearisation (one-pass steps),
                          FrictionBuffers (tooth friction of the rigid meshes)
:class:`Records`          the time histories written by the integrator
:class:`Settings`         step, HHT parameter, Newton tolerance, limits
:class:`Statistics`       step and iteration counts, the error code and where it happened
========================  ====================================================================
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..contact.laws import HERTZ_COLUMNS
from ..contact.search import MAX_CONTACTS
from .friction import FrictionBuffers, friction_buffers



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
    search_cache: np.ndarray  # (nm, 4 MAX_CONTACTS, 4) int: half teeth near contact (see contact.search._scan)
    search_count: np.ndarray  # (nm, 1) int: entries of search_cache in use
    # the joint contact problem of every compliant mesh (flexible.compliant.compliant_contacts): S =
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
    hertz: np.ndarray  # (S, 14) float: Hertz parameters, series compliance [m/N], face-width slices of each contact (contact.laws.contact_approach)
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
    compliance_known: np.ndarray  # (S,) int: whether the entries of ``compliance`` between a contact and the others are computed (flexible.joint.UNKNOWN, KNOWN, FRESH: being added)
    coupled_deflection: np.ndarray  # (S,) float: sum_l C_kl F_l of the contacts whose row is not computed [m]
    start_force: np.ndarray  # (S,) float: the contact Newton's start: the last evaluation's elastic force of the contact in this slot if the slot held the same contact (mesh, teeth, side), else 0 [N]
    # threads of the compliant meshes' evaluation (flexible.compliant.compliant_contacts): each mesh's
    # search and each body's flank rows into their own rows, stacked and summed in one thread
    threads: np.ndarray  # (1,) int: threads of the evaluation's parallel loops (1: serial; set by integrator.simulation.simulate with numba's thread count)
    search_order: np.ndarray  # (nm,) int: the compliant meshes, in mesh order (first of them in use)
    search_hits: np.ndarray  # (nm,) int: contacts found in each mesh
    search_f: np.ndarray  # (nm, MAX_CONTACTS, 5) float: each mesh's found_f (rigid overlap, point, normal)
    search_i: np.ndarray  # (nm, MAX_CONTACTS, 3) int: each mesh's found_i (tooth a, tooth b, side a)
    body_relief: np.ndarray  # (nf, S, 4) float: per contact on each flexible body the frame-inertia flank displacement weights tx, ty, tr (body frame) and its overlap decrease [m s^2, m s^2 / rad, m]
    # the bodies' parts of the joint compliance and of the open deflections, each into its own rows
    # (flexible.joint.joint_entries, open_deflections), in parallel groups of bodies
    body_entries: np.ndarray  # (nf, S, S) float: each body's part of C between its contacts (local indices) [m/N]
    body_cols: np.ndarray  # (nf, S) int: work array of each body's entries (columns)
    body_vals: np.ndarray  # (nf, S) float: work array of each body's entries (modal parts) [m/N]
    body_open: np.ndarray  # (nf, S) float: each body's part of the open contacts' deflections (local indices) [m]
    body_modal_work: np.ndarray  # (nf, modes) float: each body's condensed modes' weighted load (flexible.joint.open_entries)
    body_group: np.ndarray  # (nf,) int: each body's group of the parallel loops (flexible.joint.body_groups; -1: no contacts)
    group_load: np.ndarray  # (nf,) float: work array of flexible.joint.body_groups


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
    """Work arrays of a one-pass acceptance (integrator.one_pass.linearised_acceptance): the changes that
    move a force evaluation to the corrected state (S, nm and MAX_CONTACTS: ContactBuffers)."""

    overlap_change: np.ndarray  # (S,) float: change of each stacked compliant contact's overlap, (G + H) dq [m]
    force_change: np.ndarray  # (S,) float: change of its elastic force on the active set [N]
    depth_change: np.ndarray  # (S,) float: change of its rigid overlap, G dq [m]
    rate_change: np.ndarray  # (S,) float: change of its rigid overlap's rate, G dv [m/s]
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
    friction: FrictionBuffers | None  # None: a rigid model without friction or squeeze film (pruned)


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
    # tooth friction of the rigid meshes (integrator.friction; 0 rows without friction)
    friction_force: np.ndarray  # (nsteps, nm) float: sum of the contacts' friction forces on body b along t [N]
    friction_power: np.ndarray  # (nsteps, nm) float: power the friction dissipates [W]
    friction_through: np.ndarray  # (nsteps, nm) float: power the normal forces carry through the mesh [W]
    pair_friction: np.ndarray  # (nout, nm, MAX_CONTACTS) float: friction force of each contact slot [N]
    pair_sliding: np.ndarray  # (nout, nm, MAX_CONTACTS) float: sliding speed [m/s] (nan: empty slot)
    pair_position: np.ndarray  # (nout, nm, MAX_CONTACTS) float: contact position from the pitch point [m] (nan: empty slot)
    # squeeze-film damping of the rigid meshes (integrator.friction; 0 rows with the IMPACT damper)
    damping_power: np.ndarray  # (nsteps, nm) float: power the squeeze films dissipate [W]
    pair_damping: np.ndarray  # (nout, nm, MAX_CONTACTS) float: squeeze-film force of each contact slot [N]

    def window(self, k0: int, k: int, out_every: int) -> "Records":
        """Views of steps k0 .. k0 + k (k0 and k multiples of out_every)."""
        o0, no = k0 // out_every, k // out_every
        per_step = ("mesh_force", "mesh_fx", "mesh_fy", "x", "y", "theta", "vx", "vy", "omega", "torque", "modal",
                    "friction_force", "friction_power", "friction_through", "damping_power")
        return Records(**{name: a[k0:k0 + k] if name in per_step else a[o0:o0 + no]
                          for name, a in zip(self._fields, self)})


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
    one_pass: int = 0  # 1: accept a step after one Newton correction when the contraction allows, records corrected to first order (integrator.one_pass.linearised_acceptance)


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


def workspace(n: int, nb: int, nm: int, modes: int = 0, compliant: int | None = None, flexible: int = 0,
              condensed: int = 0, friction=None) -> Workspace:
    """Zeroed buffers for n coordinates, nb bodies and nm meshes; ``modes``: the most condensed
    modes of a flexible body (``FlexTable.condensed``; with fewer the compliant meshes take a
    slower path); ``compliant``: the number of meshes with the compliant law (``LAW_HERTZ``),
    whose contacts are solved jointly in ``compliant * MAX_CONTACTS`` slots (default: nm);
    ``flexible``: the flexible bodies (rows of the FlexTable); ``condensed``: their condensed
    modes in all (the sum of ``FlexTable.condensed``); ``friction``: the RigidFriction of the
    meshes (:mod:`flexgear.dynamics.integrator.friction`; default frictionless: the workspace's
    ``friction`` is then None where no mesh is compliant, which the kernels' friction code tests,
    and frictionless buffers otherwise)."""
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
            overlap=np.zeros(S), overlap_rate=np.zeros(S), compliance=np.zeros((S, S)), hertz=np.zeros((S, HERTZ_COLUMNS)),
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
                             rate_change=np.zeros(S),
                             force=np.zeros((nm, mc)), depth=np.zeros((nm, mc)),
                             modal_load=np.zeros(max(int(modes), 1)), reaction=np.zeros(n)),
        friction=None if friction is None and compliant == 0 else friction_buffers(nm, n, friction),
    )


def records(nsteps: int, nout: int, nb: int, nm: int, nmodal: int = 0, ncondensed: int = 0,
            friction: bool = False, damping: bool = False) -> Records:
    """Zeroed time histories (``nmodal`` modal coordinates, every step; ``ncondensed`` condensed
    modes, the sum of ``FlexTable.condensed``, at the nout pair samples only; ``friction``: the
    rigid meshes' tooth friction, ``damping``: their squeeze-film damping, else their records
    have 0 rows)."""
    mc = MAX_CONTACTS
    fs, fo = (nsteps, nout) if friction else (0, 0)
    ds, do = (nsteps, nout) if damping else (0, 0)
    return Records(*[np.zeros((nsteps, nm)) for _ in range(3)], *[np.zeros((nsteps, nb)) for _ in range(7)],
                   np.zeros((nout, nm, mc)), np.zeros((nout, nm, mc)),
                   *[np.zeros((nout, nm, mc), np.int64) for _ in range(3)], np.zeros((nout, nm, mc)),
                   np.zeros((nsteps, nmodal)), np.zeros((nout, int(ncondensed))),
                   *[np.zeros((fs, nm)) for _ in range(3)], *[np.zeros((fo, nm, mc)) for _ in range(3)],
                   np.zeros((ds, nm)), np.zeros((do, nm, mc)))


def statistics() -> Statistics:
    """Zeroed counters."""
    i = lambda: np.zeros(1, np.int64)  # noqa: E731
    return Statistics(steps=i(), newton=i(), rejected=i(), max_iter=i(), linearised=i(), error_code=i(), error_time=np.zeros(1),
                      error_mesh=i())
