"""Planar bodies, joints, supports and gear meshes: the model the solver integrates.

A body has a planar pose (x, y, theta). Its centre is placed by its joint:

* ``FIXED`` - welded to ground at ``pin``;
* ``REVOLUTE`` - ideal revolute joint at ``pin`` on ground (``parent = -1``) or on a parent body
  (``pin`` in the parent's frame, e.g. a planet on its carrier pin);
* ``BEARING`` - elastic bearing: the centre is free (two coordinates) and tied to the anchor
  point (ground ``pin`` or a parent's pin) by a linear spring-damper in x and y.

Its rotation is ``ANGLE_FIXED``, ``ANGLE_FREE`` (a coordinate), ``ANGLE_PRESCRIBED`` (a speed
profile) or ``ANGLE_SPRING`` (a coordinate with a torsional spring-damper to ground, or to
another body's rotation: a shaft, :mod:`flexgear.dynamics.model.shafts`).

Coordinates are absolute angles and absolute positions, so the mass matrix of rigid bodies is
constant and the centripetal terms of bodies on a rotating carrier come from the kinematics.
A flexible body's modal coordinates follow all rigid ones (:meth:`Model.modal_coordinates`),
so the joints and a rigid model's numbering are unchanged.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..contact.search import MAX_CONTACTS
from ...gears.contact_tables import ContactTables
from ..contact.laws import LAW_HERTZ, LAW_IMPACT
from .tables import (BodyTable, FlexTable, KernelModel, MeshTable, ProfileTable, ToothLawTable, empty_flex,
                     empty_housing, empty_tooth_laws)
from ...errors import ConfigError

FIXED, REVOLUTE, BEARING = 0, 1, 2
ANGLE_FIXED, ANGLE_FREE, ANGLE_PRESCRIBED, ANGLE_SPRING = 0, 1, 2, 3


@dataclass
class Profile:
    """A time profile: constant or piecewise linear through (t, value) points, held constant
    outside the table."""

    t: np.ndarray
    v: np.ndarray

    @classmethod
    def make(cls, spec, scale: float = 1.0) -> "Profile":
        if isinstance(spec, (int, float)):
            return cls(np.array([0.0]), np.array([float(spec) * scale]))
        pts = np.asarray(spec, dtype=float)
        return cls(pts[:, 0].copy(), pts[:, 1] * scale)

    def __call__(self, t):
        return np.interp(t, self.t, self.v)


@dataclass
class Body:
    """A rigid planar body.

    Parameters
    ----------
    name : str
    mass : float
        [kg]
    inertia : float
        Polar moment of inertia about the centre [kg m^2].
    joint : int
        FIXED, REVOLUTE or BEARING.
    parent : int
        Index of the parent body (-1: ground). Parents precede children.
    pin : (2,) array
        Joint / anchor point [m], in the parent's frame (global for ground).
    rotation : int
        ANGLE_FIXED, ANGLE_FREE, ANGLE_PRESCRIBED or ANGLE_SPRING.
    theta0, omega0 : float
        Initial angle [rad] and angular velocity [rad/s].
    speed : Profile or None
        Prescribed angular velocity [rad/s] (ANGLE_PRESCRIBED).
    torque : Profile or None
        Applied torque [N m], counter-clockwise positive.
    torque_ramp : float
        The applied torque is multiplied by STEP(t; 0, 0, torque_ramp, 1) [s].
    stiffness, damping : float
        Bearing spring [N/m] and damper [N s/m] (BEARING).
    torsional_stiffness, torsional_damping : float
        [N m/rad], [N m s/rad] (ANGLE_SPRING).
    torsion_parent : int
        ANGLE_SPRING: the spring ties the angle to this body's angle (a shaft between two
        bodies, or to a prescribed motor body) instead of to ground (-1).
    gear : int
        Index of the gear geometry in the contact tables (-1: not a gear).
    attrs : dict
        Extra information carried to the results (tooth count, role).
    """

    name: str
    mass: float
    inertia: float
    joint: int = REVOLUTE
    parent: int = -1
    pin: tuple = (0.0, 0.0)
    rotation: int = ANGLE_FREE
    theta0: float = 0.0
    omega0: float = 0.0
    speed: Profile | None = None
    torque: Profile | None = None
    torque_ramp: float = 0.0
    stiffness: float = 0.0
    damping: float = 0.0
    torsional_stiffness: float = 0.0
    torsional_damping: float = 0.0
    torsion_parent: int = -1
    gear: int = -1
    attrs: dict = field(default_factory=dict)


@dataclass
class MeshingPair:
    """A gear mesh between body ``a`` (external gear) and body ``b``, with the IMPACT law (SI)."""

    name: str
    a: int
    b: int
    internal: bool
    K: float
    e: float
    C: float
    d: float
    ncand_a: int
    ncand_b: int
    attrs: dict = field(default_factory=dict)
    law: int = LAW_IMPACT  # LAW_IMPACT or LAW_HERTZ (:mod:`flexgear.dynamics.contact.laws`)
    gap: float = 0.0  # near-contact margin of the contact search [m]
    hertz: dict = field(default_factory=dict)  # LAW_HERTZ: face_width, hertz_a/b, nu_a/b, e_star, depth_a/b, rb_a/b


@dataclass
class FlexBody:
    """Flank compliance data of a flexible body (see :class:`~flexgear.dynamics.model.tables.FlexTable`).

    Attributes
    ----------
    body : int
        Body index.
    radius : ndarray (J,)
        Table radii [m].
    shape : ndarray (z, 2, J, nq)
        Normal flank displacement per unit modal coordinate divided by the mode's circular
        frequency, A_i / omega_i, sides (+1, -1) [m / sqrt(N/m)].
    self_compliance : ndarray (P, 2, J)
        Residual self compliance per tooth class, near field removed [m/N].
    coupling : ndarray (P, 2, 2, z, Jc, Jc)
        Residual compliance from a loaded flank (class, side) to both flanks of every tooth at
        distance d = 0..z-1 [m/N] (:class:`~flexgear.reduction.flank.FlankTables`, FlexTable),
        at every :attr:`coupling_stride`-th table radius.
    dynamic_shape : ndarray (z, 2, J, m)
        Normal flank displacement A_i per unit modal coordinate of the m modes kept as
        coordinates in q [1/sqrt(kg)] (m = 0: every mode condensed).
    stiffness, mass, damping : ndarray (m, m)
        Reduced matrices of the modal coordinates [1/s^2, -, 1/s].
    frame_coupling : ndarray (3, m)
        Mass coupling R^T M Phi of the body frame's x, y, theta with the modal coordinates, in
        the body frame [sqrt(kg), sqrt(kg) m].
    frequencies : ndarray (m,)
        Frequencies of the modal coordinates [Hz].
    acceleration_shape : ndarray (z, 2, J, 3)
        Quasi-static normal flank displacement of the condensed modes per unit acceleration of
        the body frame (x, y, theta, in the body frame), ``sum_i (A_i / omega_i^2) S_i`` with
        S_i the frame-mode mass coupling of condensed mode i; the displacement under the frame's
        acceleration a is ``-acceleration_shape . a`` (the gear's own inertia load) [m per m/s^2,
        m per rad/s^2]. None: zero.
    condensed_omega : ndarray (nq,)
        Circular frequencies omega_i of the condensed modes [rad/s].
    condensed_damping : ndarray (nq,)
        Their modal damping 2 zeta omega_i [1/s].
    condensed_coupling : ndarray (3, nq)
        Their mass coupling S_i with the body frame's x, y, theta, in the body frame [sqrt(kg),
        sqrt(kg) m] (zero where the interface is not the frame: a ring held on its rim or bolts).
    """

    body: int
    radius: np.ndarray
    shape: np.ndarray
    self_compliance: np.ndarray
    coupling: np.ndarray
    attrs: dict = field(default_factory=dict)
    dynamic_shape: np.ndarray | None = None
    stiffness: np.ndarray | None = None
    mass: np.ndarray | None = None
    damping: np.ndarray | None = None
    frame_coupling: np.ndarray | None = None
    frequencies: np.ndarray | None = None
    acceleration_shape: np.ndarray | None = None
    condensed_omega: np.ndarray | None = None
    condensed_damping: np.ndarray | None = None
    condensed_coupling: np.ndarray | None = None

    @property
    def coupling_stride(self) -> int:
        """Table radii per interval of the coupling tables, (J - 1) / (Jc - 1)."""
        return (self.radius.size - 1) // (self.coupling.shape[-1] - 1)

    @property
    def modes(self) -> int:
        """Number of modal coordinates kept in q."""
        return 0 if self.dynamic_shape is None else int(self.dynamic_shape.shape[3])

    @property
    def modal_scale(self) -> np.ndarray:
        """Largest flank displacement per unit modal coordinate of each mode [m per sqrt(kg) m]
        (the length scale of the coordinate in the Newton test)."""
        if not self.modes:
            return np.zeros(0)
        return np.abs(self.dynamic_shape).reshape(-1, self.modes).max(axis=0)


def pack_flex(flex: list[FlexBody], first: int = 0) -> FlexTable:
    """The FlexTable of flexible bodies (empty list: :func:`~flexgear.dynamics.model.tables.empty_flex`);
    their modal coordinates are numbered from ``first`` (the number of rigid coordinates)."""
    if not flex:
        return empty_flex()
    ints = lambda v: np.array(v, np.int64)  # noqa: E731
    offs = lambda arrs: ints(np.concatenate([[0], np.cumsum([a.size for a in arrs])[:-1]]))  # noqa: E731
    cat = lambda arrs: np.ascontiguousarray(np.concatenate([np.asarray(a, float).ravel() for a in arrs]))  # noqa: E731
    modes = [f.modes for f in flex]
    start = first + np.concatenate([[0], np.cumsum(modes)[:-1]])
    blocks = {k: [np.zeros((0, 0)) if f.modes == 0 else getattr(f, k) for f in flex]
              for k in ("stiffness", "mass", "damping")}
    dyn = [np.zeros(0) if f.modes == 0 else f.dynamic_shape for f in flex]
    frame = [np.zeros(0) if f.modes == 0 else f.frame_coupling for f in flex]
    nq = [f.shape.shape[3] for f in flex]
    for f, k in zip(flex, nq):
        if f.condensed_omega is None or f.condensed_omega.shape != (k,):
            raise ConfigError(f"flexible body {f.body}: {k} condensed modes but condensed_omega "
                              f"{None if f.condensed_omega is None else f.condensed_omega.shape}")
    per_mode = lambda name: cat([np.zeros(k) if getattr(f, name) is None else getattr(f, name)  # noqa: E731
                                 for f, k in zip(flex, nq)])
    coupling = cat([np.zeros((3, k)) if f.condensed_coupling is None else f.condensed_coupling
                    for f, k in zip(flex, nq)])
    return FlexTable(
        body=ints([f.body for f in flex]), coordinate=ints([s if m else -1 for s, m in zip(start, modes)]),
        modes=ints(modes), matrix_offset=offs(blocks["stiffness"]), stiffness=cat(blocks["stiffness"]),
        mass=cat(blocks["mass"]), damping=cat(blocks["damping"]),
        dynamic_offset=offs(dyn), dynamic_shape=cat(dyn), frame_offset=offs(frame), frame_coupling=cat(frame),
        teeth=ints([f.shape.shape[0] for f in flex]), period=ints([f.self_compliance.shape[0] for f in flex]),
        points=ints([f.radius.size for f in flex]), condensed=ints([f.shape.shape[3] for f in flex]),
        radius_offset=offs([f.radius for f in flex]), radius=cat([f.radius for f in flex]),
        shape_offset=offs([f.shape for f in flex]), shape=cat([f.shape for f in flex]),
        self_offset=offs([f.self_compliance for f in flex]), self_compliance=cat([f.self_compliance for f in flex]),
        coupling_offset=offs([f.coupling for f in flex]), coupling=cat([f.coupling for f in flex]),
        coupling_stride=ints([f.coupling_stride for f in flex]),
        condensed_offset=ints(np.concatenate([[0], np.cumsum(nq)[:-1]])), condensed_omega=per_mode("condensed_omega"),
        condensed_damping=per_mode("condensed_damping"), condensed_coupling=coupling)


@dataclass
class Model:
    """Bodies, meshes and the packed gear tables; ``pack()`` gives the solver's named tables."""

    bodies: list[Body]
    meshes: list[MeshingPair]
    tables: ContactTables
    length_scale: float  # m, converts rotations to lengths in the Newton convergence test
    attrs: dict = field(default_factory=dict)
    flex: list = field(default_factory=list)  # FlexBody of the flexible bodies
    tooth_laws: ToothLawTable | None = None  # per-tooth IMPACT law changes (cracks, partial widths); None: none
    housing: object | None = None  # HousingCoupling (flexgear.dynamics.model.housing): coordinates after all others

    def housing_first(self) -> int:
        """Index in q of the coupled housing's first coordinate (the count of all others)."""
        return self.rigid_coordinates() + sum(m for _, _, m in self.modal_coordinates())

    def pack(self, stride: int = 16) -> KernelModel:
        """The model as named tables for the compiled kernels (rigid models: an empty
        :class:`~flexgear.dynamics.model.tables.FlexTable`).

        Parameters
        ----------
        stride : int
            Coarse scan stride of the full contact search [outline samples].
        """
        nb = len(self.bodies)
        ints = {k: np.full(nb, -1, np.int64) for k in ("joint", "rotation", "parent", "ix", "iy", "itheta",
                                                        "speed_profile", "torque_profile", "flex",
                                                        "torsion_parent")}
        flts = {k: np.zeros(nb) for k in ("mass", "inertia", "pin_x", "pin_y", "theta0", "stiffness", "damping",
                                          "torsional_stiffness", "torsional_damping", "torque_ramp", "omega0")}
        prof_t, prof_v, prof_off = [], [], [0]

        def add_profile(p: Profile | None) -> int:
            if p is None:
                return -1
            prof_t.append(p.t)
            prof_v.append(p.v)
            prof_off.append(prof_off[-1] + len(p.t))
            return len(prof_off) - 2

        index = self.coordinate_indices()
        for i, b in enumerate(self.bodies):
            if b.parent >= i:
                raise ConfigError(f"body {b.name}: parent index {b.parent} must precede the body")
            ix, iy, ith = index[i]
            for k, val in (("joint", b.joint), ("rotation", b.rotation), ("parent", b.parent), ("ix", ix),
                           ("iy", iy), ("itheta", ith), ("speed_profile", add_profile(b.speed)),
                           ("torque_profile", add_profile(b.torque)), ("torsion_parent", b.torsion_parent)):
                ints[k][i] = val
            for k, val in (("mass", b.mass), ("inertia", b.inertia), ("pin_x", b.pin[0]), ("pin_y", b.pin[1]),
                           ("theta0", b.theta0), ("stiffness", b.stiffness), ("damping", b.damping),
                           ("torsional_stiffness", b.torsional_stiffness),
                           ("torsional_damping", b.torsional_damping), ("torque_ramp", b.torque_ramp),
                           ("omega0", b.omega0)):
                flts[k][i] = val
        # cumulative integrals of the profiles at their nodes (for prescribed angles)
        prof_i = []
        for t, v in zip(prof_t, prof_v):
            ci = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))]) if len(t) > 1 else np.zeros(1)
            prof_i.append(ci)
        cat = (lambda xs: np.concatenate(xs) if xs else np.zeros(1))
        ms = self.meshes
        gear = [b.gear for b in self.bodies]
        meshes = MeshTable(
            body_a=np.array([m.a for m in ms], np.int64), body_b=np.array([m.b for m in ms], np.int64),
            gear_a=np.array([gear[m.a] for m in ms], np.int64), gear_b=np.array([gear[m.b] for m in ms], np.int64),
            internal=np.array([bool(m.internal) for m in ms], bool),
            ncand_a=np.array([m.ncand_a for m in ms], np.int64), ncand_b=np.array([m.ncand_b for m in ms], np.int64),
            stride=np.full(len(ms), stride, np.int64), K=np.array([m.K for m in ms], float),
            e=np.array([m.e for m in ms], float), C=np.array([m.C for m in ms], float),
            d=np.array([m.d for m in ms], float), law=np.array([m.law for m in ms], np.int64),
            gap=np.array([m.gap for m in ms], float),
            **{k: np.array([m.hertz.get(k, 0.0) for m in ms], float) for k in HERTZ_FIELDS},
            teeth=self.tooth_laws if self.tooth_laws is not None else empty_tooth_laws())
        for row, fb in enumerate(self.flex):
            ints["flex"][fb.body] = row
        flex = pack_flex(self.flex, self.rigid_coordinates())
        return KernelModel(bodies=BodyTable(**ints, **flts),
                           profiles=ProfileTable(t=cat(prof_t), value=cat(prof_v), integral=cat(prof_i),
                                                 offset=np.array(prof_off, np.int64)),
                           meshes=meshes, flex=flex, compliant=flex if (meshes.law == LAW_HERTZ).any() else None,
                           housing=empty_housing() if self.housing is None
                           else self.housing.table(self.housing_first(), self.bodies))

    def coordinate_indices(self) -> list[tuple[int, int, int]]:
        """Per body, the indices (ix, iy, itheta) of its generalised coordinates in q, -1 where
        the quantity is not a coordinate: a BEARING centre has x and y, a free or spring-held
        rotation has theta, in body order."""
        out, n = [], 0
        for b in self.bodies:
            ix = iy = ith = -1
            if b.joint == BEARING:
                ix, iy = n, n + 1
                n += 2
            if b.rotation in (ANGLE_FREE, ANGLE_SPRING):
                ith = n
                n += 1
            out.append((ix, iy, ith))
        return out

    def rigid_coordinates(self) -> int:
        """Number of rigid-body coordinates (the modal coordinates of flexible bodies follow)."""
        return sum((ix >= 0) + (iy >= 0) + (ith >= 0) for ix, iy, ith in self.coordinate_indices())

    def modal_coordinates(self) -> list[tuple[int, int, int]]:
        """Per flexible body with modal coordinates: (body, first index in q, count), in the
        order of ``flex`` after all rigid coordinates."""
        out, n = [], self.rigid_coordinates()
        for fb in self.flex:
            if fb.modes:
                out.append((fb.body, n, fb.modes))
                n += fb.modes
        return out

    def coordinate_names(self) -> list[str]:
        names = []
        for b, (ix, _, ith) in zip(self.bodies, self.coordinate_indices()):
            if ix >= 0:
                names += [f"{b.name}.x", f"{b.name}.y"]
            if ith >= 0:
                names.append(f"{b.name}.theta")
        for body, _, m in self.modal_coordinates():
            names += [f"{self.bodies[body].name}.eta{k + 1}" for k in range(m)]
        return names + ([] if self.housing is None else list(self.housing.names))

    def initial_state(self):
        """Generalised coordinates and velocities at t = 0 from the bodies' initial data."""
        q, v = [], []
        for b in self.bodies:
            if b.joint == BEARING:
                anchor = np.asarray(b.pin, float)
                if b.parent >= 0:
                    p = self.bodies[b.parent]
                    c, s = math.cos(p.theta0), math.sin(p.theta0)
                    anchor = np.asarray(p.pin, float) + np.array([c * b.pin[0] - s * b.pin[1],
                                                                   s * b.pin[0] + c * b.pin[1]])
                    vel = p.omega0 * np.array([-(anchor[1] - p.pin[1]), anchor[0] - p.pin[0]])
                else:
                    vel = np.zeros(2)
                q += list(anchor)
                v += list(vel)
            if b.rotation in (ANGLE_FREE, ANGLE_SPRING):
                q.append(b.theta0)
                v.append(b.omega0)
        nmod = sum(m for _, _, m in self.modal_coordinates())  # undeformed, at rest in the frame
        nmod += 0 if self.housing is None else self.housing.n  # the housing undeformed, at rest
        return np.array(q + [0.0] * nmod, float), np.array(v + [0.0] * nmod, float)


MAXC = MAX_CONTACTS
HERTZ_FIELDS = ("face_width", "hertz_a", "hertz_b", "nu_a", "nu_b", "e_star", "depth_a", "depth_b", "rb_a", "rb_b")
