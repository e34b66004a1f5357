"""The housing coupled into the multi-body model (``[housing] coupled = true``).

The reduced housing (:func:`flexgear.reduction.housing.reduce_housing`) becomes one more body
whose coordinates are its Craig-Bampton coordinates ``q_h`` (patch frames, then fixed-interface
modes and augmentation vectors) in a fixed frame, placed after every other coordinate of q:

* its stiffness is the reduced ``K`` plus the foot springs to ground
  (:meth:`~flexgear.reduction.housing.HousingReduction.ground_stiffness`), its mass the reduced
  ``M``, its damping modal, ``C = M Phi diag(2 zeta omega) Phi^T M`` over the modes of the
  housing on its feet (zeta the housing's ``damping_ratio``, as in the one-way path);
* the elastic bearing of each shaft a seat carries (``supports.<shaft>`` a table) acts between
  the body's centre and the seat patch's centre instead of ground;
* a planetary set's sun and carrier bearings (their shafts coaxial, one seat) act on the
  central seat; the ring, on an elastic support with a torsional stiffness, is bolted in: its
  bearing and torsional spring act against the bolt circle's rigid motion ``(E^T E)^-1 E^T q_h``
  (:meth:`~flexgear.reduction.housing.HousingReduction.ring_coupling`), which shares its load
  over the bolts as the one-way path does.

Bearings seated in the housing must be elastic: a rigid (revolute or fixed) joint has no spring
through which the housing could move the shaft. Small displacements: the springs act on the
patches' undeformed centres.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ...errors import ConfigError
from ...fe.elasticity import single_threaded_blas
from .bodies import ANGLE_SPRING, BEARING
from .tables import HousingTable


@dataclass
class HousingCoupling:
    """The housing as the model holds it (module docstring): matrices [SI] of its ``n``
    coordinates, the seated bodies and their anchor rows (3, n), the coordinates' names and
    their length scales [m per unit] for the Newton test."""

    reduction: object  # HousingReduction
    stiffness: np.ndarray
    damping: np.ndarray
    mass: np.ndarray
    links: list  # (body index, (3, n) rows)
    names: list
    scale: np.ndarray

    @property
    def n(self) -> int:
        return self.stiffness.shape[0]

    def link_springs(self, bodies) -> np.ndarray:
        """(nl, 2, 3) stiffness [N/m, N m/rad] (row 0) and damping [N s/m, N m s/rad] (row 1) of
        each link's spring-damper in x, y and rotation (rotation: a torsional spring to ground,
        else 0), from the model's ``bodies``."""
        out = np.zeros((len(self.links), 2, 3))
        for lk, (i, _) in enumerate(self.links):
            b = bodies[i]
            out[lk, :, :2] = np.array([[b.stiffness], [b.damping]])
            if b.rotation == ANGLE_SPRING and b.torsion_parent < 0:
                out[lk, :, 2] = (b.torsional_stiffness, b.torsional_damping)
        return out

    def table(self, first: int, bodies) -> HousingTable:
        """The kernels' table, the housing's coordinates from q[first] (``bodies``: the model's,
        for the links' springs). Its tangent blocks are constant: the housing's own matrices
        plus ``G^T k G`` of every link."""
        n, first = self.n, int(first)
        springs = self.link_springs(bodies)
        Kh, Ch = self.stiffness.copy(), self.damping.copy()
        for lk, (_, G) in enumerate(self.links):
            Kh += G.T @ (springs[lk, 0][:, None] * G)
            Ch += G.T @ (springs[lk, 1][:, None] * G)
        return HousingTable(first=first, stiffness=self.stiffness, damping=self.damping, mass=self.mass,
                            tangent_stiffness=np.ascontiguousarray(Kh), tangent_damping=np.ascontiguousarray(Ch),
                            link_body=np.array([i for i, _ in self.links], np.int64),
                            link_rows=np.ascontiguousarray(np.array([g for _, g in self.links]).reshape(
                                len(self.links), 3, n)),
                            solver_key=np.zeros(2), solver_inverse=np.zeros((n, n)),
                            solver_coupling=np.zeros((n, first)), solver_cross=np.zeros((first, n)),
                            solver_correction=np.zeros((first, first)))


def _seated(model, name: str, key: str):
    index = {b.name: i for i, b in enumerate(model.bodies)}
    if name not in index:
        raise ConfigError(f"housing.coupled = true: the housing carries {name!r}, which the model does not have")
    i = index[name]
    b = model.bodies[i]
    if b.joint != BEARING or b.parent >= 0:
        raise ConfigError(f"housing.coupled = true: {key} of {name!r} must be an elastic bearing on ground (a table "
                          "with stiffness and damping) to seat in the housing; a rigid joint cannot move with it")
    return i


def couple_housing(model, red) -> HousingCoupling:
    """Put the reduced housing ``red`` into ``model`` (``model.housing``) with every shaft its
    seats carry and the ring on its bolts; raises ConfigError (naming the support) for a shaft
    or ring without an elastic bearing, before anything runs."""
    n = red.n
    links = []
    for p in red.role("seat"):
        for shaft in p.shafts:
            i = _seated(model, shaft, f"supports.{shaft}")
            b = model.bodies[i]
            if np.hypot(b.pin[0] - p.centre[0], b.pin[1] - p.centre[1]) > 1e-9:
                raise ConfigError(f"housing.coupled = true: {shaft!r} turns about {b.pin}, not about its seat's "
                                  f"centre {p.centre}")
            G = np.zeros((3, n))
            G[0, p.coordinates[0]] = G[1, p.coordinates[1]] = G[2, p.coordinates[2]] = 1.0
            links.append((i, G))
    if red.role("bolt"):
        i = _seated(model, "ring", "supports.ring")
        if model.bodies[i].rotation != ANGLE_SPRING:
            raise ConfigError("housing.coupled = true: supports.ring needs a torsional_stiffness; the ring's reaction "
                              "torque reaches the housing through its bolts only by that spring")
        links.append((i, bolt_anchor_rows(red, tuple(model.bodies[i].pin))))
    K = red.body.K + red.ground_stiffness()
    M = red.body.M
    K, M = 0.5 * (K + K.T), 0.5 * (M + M.T)
    with single_threaded_blas():  # the same bits in any process (a batch's driver or its workers)
        w2, Phi = sla.eigh(K, M)
        if w2[0] <= 0:
            raise ConfigError("housing.coupled = true: the housing on its feet has a mode at 0 Hz (no foot): give feet")
        MP = M @ Phi
        C = MP @ np.diag(2.0 * red.housing.damping_ratio * np.sqrt(w2)) @ MP.T
    scale = np.maximum(np.abs(red.body.basis).max(axis=0), 1e-12)
    h = HousingCoupling(red, np.ascontiguousarray(K), np.ascontiguousarray(C), np.ascontiguousarray(M), links,
                        [f"housing.{x}" for x in red.body.names], scale)
    model.housing = h
    return h


def bolt_anchor_rows(red, centre=(0.0, 0.0)) -> np.ndarray:
    """(3, n) rows ``(E^T E)^-1 E^T``: the bolt circle's rigid motion ``(u_x, u_y, theta)`` about
    ``centre`` that fits the housing's bolt patches best (least squares; exact when they move
    rigidly), E = :meth:`~flexgear.reduction.housing.HousingReduction.ring_coupling`. Its
    transpose shares a ring's load over the bolts as the one-way path's
    :func:`~flexgear.reduction.paths.housing_inputs` does."""
    E = red.ring_coupling(centre)
    return np.linalg.solve(E.T @ E, E.T)


def foot_reactions(red, q_h) -> np.ndarray:
    """(n_t, n_feet, 2) forces [N] the ground puts on each foot, from housing coordinates
    ``q_h`` (n_t, n): ``-k_f (u_x, u_y)`` of the foot's patch."""
    q_h = np.atleast_2d(q_h)
    feet = red.role("foot")
    out = np.zeros((q_h.shape[0], len(feet), 2))
    for k, p in enumerate(feet):
        out[:, k, 0] = -red.housing.foot_stiffness * q_h[:, p.coordinates[0]]
        out[:, k, 1] = -red.housing.foot_stiffness * q_h[:, p.coordinates[1]]
    return out


def ground_moment(red, q_h, centre=(0.0, 0.0)) -> np.ndarray:
    """(n_t,) moment [N m] of the feet's ground reactions about ``centre`` (at the feet's
    undeformed centres)."""
    F = foot_reactions(red, q_h)
    c = np.array([p.centre for p in red.role("foot")]) - np.asarray(centre, float)
    return np.sum(c[None, :, 0] * F[:, :, 1] - c[None, :, 1] * F[:, :, 0], axis=1)
