"""Named tables of arrays: the model as the compiled kernels of :mod:`flexgear.dynamics.integrator` see it.

Each concern is one :class:`typing.NamedTuple` of numpy arrays (and a few scalars), one array
per named quantity, its unit in the comment. Numba passes such a NamedTuple to
``@njit(cache=True)`` functions as a plain tuple typed by its fields, so the kernels compile
once and load from the disk cache in later processes (jitclass and structref arguments do not:
numba issues 6522, 9659, 10021). A kernel reads::

    forces(q, qd, t, model, contact, work, local)
    integrate(q, v, acc, t0, nsteps, model, compliant, contact, work, settings, records, stats)

========================  ====================================================================
table                     concern
========================  ====================================================================
:class:`BodyTable`        joints, supports, mass properties of the bodies (per body)
:class:`ProfileTable`     time profiles (prescribed speeds, applied torques), concatenated
:class:`MeshTable`        gear meshes: bodies, geometries, search band, IMPACT law (per mesh)
:class:`ToothLawTable`    per-tooth changes of the contact laws: cracks, partial face widths
:class:`FlexTable`        flexible bodies: modal coordinates, reduced matrices, mode shapes
:class:`KernelModel`      the four tables above: the model as the kernels see it
``ContactTables``         outlines and signed distance fields (:mod:`flexgear.gears.contact_tables`)
Workspace, Records, ...   the integrator's buffers (:mod:`flexgear.dynamics.integrator.buffers`)
========================  ====================================================================

Integers are int64 arrays, reals float64. An absent concern has zero-length arrays of the same
dtype and dimension (a rigid model passes an empty :class:`FlexTable`), so one compiled
signature serves every model.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np



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
    teeth: "ToothLawTable"  # per-tooth changes of the IMPACT law (empty: every tooth healthy)


class ToothLawTable(NamedTuple):
    """Per-tooth changes of the contact laws (:mod:`flexgear.dynamics.model.tooth_laws`): of the
    IMPACT law of rigid meshes and of the compliant law of meshes with a flexible gear.

    A contact of mesh m on flank s of tooth k of gear side g (0: gear A, 1: gear B) looks up the
    row ``row[first[m, g] + 2 k + si]`` (si = 0 for s = +1, 1 for s = -1; ``first[m, g] = -1``
    or row -1: healthy). A row is a function of the contact's distance r from the gear's
    toothing centre, tabulated on ``count`` radii from ``r0`` in steps ``dr`` (linear between,
    held beyond the ends) at ``start``:

    * ``factor``: the stiffness factor kappa of the law F = kappa K delta^e (a root crack: the FE
      pair stiffness ratio to the power e, over the cracked part of the face width);
    * ``width``: the fraction of the face width whose surface is the outline (1: whole width);
    * ``recess``: how far the rest of the face width lies below the outline along the normal [m]
      (a partial spall or chip: slices in parallel, :func:`flexgear.gears.modified.partial_width_force`);
    * ``series``: a compliance [m/N] in series with the compliant law's Hertz approach (a root
      crack in a mesh with a flexible gear: the FE pair's extra compliance of the cracked tooth,
      over the cracked part of the face width). 0 on every row of a rigid mesh.

    The IMPACT law reads ``factor``, ``width`` and ``recess`` (they are 1, 1, 0 on the rows of a
    mesh with a flexible gear); the compliant law reads ``series``. A model without such teeth has zero-length arrays (and ``first`` of shape (0, 2)).
    """

    first: np.ndarray  # (nm, 2) int: first row index in ``row`` of gear A / B of each mesh, -1: healthy gear
    row: np.ndarray  # (sum 2 z,) int: table of each (tooth, flank), -1: healthy
    r0: np.ndarray  # (nt,) float: first radius of each table [m]
    dr: np.ndarray  # (nt,) float: radius step [m]
    count: np.ndarray  # (nt,) int: radii of each table
    start: np.ndarray  # (nt,) int: offset of each table in factor / width / recess
    factor: np.ndarray  # (sum count,) float: stiffness factor kappa [-]
    width: np.ndarray  # (sum count,) float: face-width fraction of the outline's surface [-]
    recess: np.ndarray  # (sum count,) float: depth of the rest of the face below the outline [m]
    series: np.ndarray  # (sum count,) float: series compliance of the compliant law [m/N]


def empty_tooth_laws() -> ToothLawTable:
    """The tooth-law table of a model whose teeth all follow their mesh's law: zero-length arrays."""
    ints = ("row", "count", "start")
    return ToothLawTable(**{k: (np.zeros((0, 2), np.int64) if k == "first" else
                                np.zeros(0, np.int64) if k in ints else np.zeros(0))
                            for k in ToothLawTable._fields})


class FlexTable(NamedTuple):
    """Flexible bodies (nf of them): the compliance of their flanks at the contacts.

        A rigid model passes :func:`empty_flex` (zero-length arrays, same signature). Row f is body
        ``body[f]`` (``BodyTable.flex`` = f), a gear of ``teeth[f]`` teeth reduced by
        :func:`flexgear.reduction.gear.reduce_gear`. The flank compliance between flank point (tooth
        k, side s, radius r) and loaded point (l, s', r') [m/N] is::

            c = sum_i A_i(k, s, r) A_i(l, s', r') / omega_i^2   (condensed modes)
                + residual(k, s, r; l, s', r')                   (tables)

        ``A_i`` the normal flank displacement per unit (mass-normalised) modal coordinate; the
        residual tables hold the self term (near field removed) and the coupling with both flanks
        of every tooth at distance ``d = (k - l) mod z``, linear in the radius between the table
        radii (the coupling tables on every ``coupling_stride[f]``-th). See the theory page
        *Reduction and residual tables*.

        Layout (J = points[f], nq = condensed[f], z = teeth[f], P = period[f], Jc = (J - 1) /
        coupling_stride[f] + 1, si = 0 for side +1 (left flank), 1 for side -1):

        * ``radius[radius_offset[f] + j]`` [m], increasing;
        * ``shape[shape_offset[f] + ((k * 2 + si) * J + j) * nq + i] = A_i / omega_i``
          [m/sqrt(N m)]: the dot product of two rows is a compliance [m/N];
        * ``self_compliance[self_offset[f] + (c * 2 + si) * J + j]`` [m/N], tooth class c = k % P;
        * ``coupling[coupling_offset[f] + ((((c * 2 + so) * 2 + si) * z + d) * Jc + jo) * Jc + ji]``
          [m/N]: side so of tooth ``(c + d) mod z`` at coupling radius jo per newton on side si of
          tooth c at ji (block d = 0, so = si unused).

        Modes below ``[flexible] dynamic_cutoff`` are the ``modes[f] = m`` modal coordinates
        ``q[coordinate[f] : coordinate[f] + m]`` (after every rigid coordinate;
        :mod:`flexgear.dynamics.flexible.floating_frame`), with m x m row-major blocks
        ``stiffness`` (omega_i^2), ``mass`` (identity) and ``damping`` (2 zeta omega_i) from
        ``matrix_offset[f]``, and

        * ``dynamic_shape[dynamic_offset[f] + ((k * 2 + si) * J + j) * m + i] = A_i``
          [1/sqrt(kg)] (``shape`` then holds only the condensed modes);
        * ``frame_coupling[frame_offset[f] + d * m + i]``, d = 0, 1, 2 (frame x, y, theta): the
          reduced mass block ``R^T M Phi`` [sqrt(kg), sqrt(kg) m], body frame.

        Condensed modes carry ``condensed_omega`` (omega_i [rad/s]), ``condensed_damping``
        (2 zeta omega_i [1/s]) and ``condensed_coupling[3 * condensed_offset[f] + d * nq + i]`` =
        S_di, their mass coupling with the frame (as ``frame_coupling``; zero when the interface is
        not the frame, e.g. a ring held on its rim), for :mod:`flexgear.dynamics.flexible.condensed`.
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


class HousingTable(NamedTuple):
    """A housing coupled into the model (:mod:`flexgear.dynamics.model.housing`): its nh
    Craig-Bampton coordinates ``q[first : first + nh]`` (after every other coordinate, in a fixed
    frame) and the bearings seated in it. Link l moves the ground anchor of body ``link_body[l]``'s
    elastic bearing (and torsional spring to ground) by ``(dx, dy, dtheta) = link_rows[l] @ q_h``."""

    first: int  # index in q of the housing's first coordinate
    stiffness: np.ndarray  # (nh, nh) float: reduced stiffness with the foot springs [SI]
    damping: np.ndarray  # (nh, nh) float: modal damping of the housing on its feet [SI]
    mass: np.ndarray  # (nh, nh) float: reduced mass [SI]
    tangent_stiffness: np.ndarray  # (nh, nh) float: stiffness + G^T k G of every link: the constant housing block of Kt
    tangent_damping: np.ndarray  # (nh, nh) float: damping + G^T c G of every link: that of Ct
    link_body: np.ndarray  # (nl,) int: body whose ground bearing is seated in the housing
    link_rows: np.ndarray  # (nl, 3, nh) float: anchor displacement x, y [m] and rotation [rad] per coordinate
    #: the Newton matrix's housing block eliminated (:func:`~flexgear.dynamics.integrator.housing.housing_solve`),
    #: kept for the HHT coefficients in ``solver_key`` (both 0: not yet): A_hh^-1, A_hh^-1 A_hg, A_gh, A_gh A_hh^-1 A_hg
    solver_key: np.ndarray  # (2,) float: coefficients of Kt [s^2] and Ct [s] the four below hold for
    solver_inverse: np.ndarray  # (nh, nh) float
    solver_coupling: np.ndarray  # (nh, first) float
    solver_cross: np.ndarray  # (first, nh) float
    solver_correction: np.ndarray  # (first, first) float


class KernelModel(NamedTuple):
    """The model as the compiled kernels see it (:meth:`flexgear.dynamics.model.bodies.Model.pack`)."""

    bodies: BodyTable
    profiles: ProfileTable
    meshes: MeshTable
    flex: FlexTable
    #: ``flex`` again where a mesh has the compliant Hertz law, else None: the kernels of a model
    #: without one compile without the compliant contact problem (a rigid run compiles less)
    compliant: FlexTable | None
    #: the coupled housing (:class:`HousingTable`); without one :func:`empty_housing`, so that runs
    #: with and without a coupled housing share one compiled solver (the kernels skip it at run time)
    housing: HousingTable


def empty_housing() -> HousingTable:
    """The housing table of a model without a coupled housing: no coordinates, no links."""
    z = np.zeros((0, 0))
    return HousingTable(first=0, stiffness=z, damping=z, mass=z, tangent_stiffness=z, tangent_damping=z,
                        link_body=np.zeros(0, np.int64), link_rows=np.zeros((0, 3, 0)), solver_key=np.zeros(2),
                        solver_inverse=z, solver_coupling=z, solver_cross=z, solver_correction=z)


def empty_flex() -> FlexTable:
    """The flexible-body table of a rigid model: every array of length zero."""
    kinds = {"body": 0, "coordinate": 0, "modes": 0, "matrix_offset": 0, "teeth": 0, "period": 0, "points": 0,
             "condensed": 0, "radius_offset": 0, "shape_offset": 0, "self_offset": 0, "coupling_offset": 0,
             "dynamic_offset": 0, "frame_offset": 0, "coupling_stride": 0, "condensed_offset": 0}
    return FlexTable(**{k: (np.zeros(0, np.int64) if k in kinds else np.zeros(0)) for k in FlexTable._fields})
