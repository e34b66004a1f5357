"""The loaded operating point of a model: static equilibria under the load torque at positions
over one mesh cycle (the driven body held), the bodies' pose Jacobians and the support springs.
"""
from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np

from ...errors import ConfigError
from ..integrator.simulation import COARSE_STRIDE, evaluate
from ..model.bodies import ANGLE_FREE, ANGLE_PRESCRIBED, ANGLE_SPRING, BEARING, Model, Profile
from .system import Spring

# a position where a contact switches on and off between Newton iterations (a tooth corner
# entering, found by the contact search only on one side of a threshold) has no exact
# equilibrium; the best state is kept if its force residual is below this fraction of the load
# (listed in the system's attrs), else the position is skipped; more than a quarter of the
# positions skipped is an error
APPROXIMATE_EQUILIBRIUM = 0.3


def pose_jacobians(model: Model, q: np.ndarray, angles: dict | None = None):
    """Poses (nb, 3) and pose Jacobians (nb, 3, n) of the bodies at coordinates q, mirroring the
    solver's kinematics. ``angles`` gives the angle of bodies whose rotation is not a coordinate
    (default: their ``theta0``)."""
    nb_ = len(model.bodies)
    n = len(q)
    pose = np.zeros((nb_, 3))
    J = np.zeros((nb_, 3, n))
    for i, (b, (ix, iy, ith)) in enumerate(zip(model.bodies, model.coordinate_indices())):
        if ith >= 0:
            pose[i, 2] = q[ith]
            J[i, 2, ith] = 1.0
        else:
            pose[i, 2] = (angles or {}).get(b.name, b.theta0)
        if ix >= 0:
            pose[i, 0], pose[i, 1] = q[ix], q[iy]
            J[i, 0, ix] = 1.0
            J[i, 1, iy] = 1.0
        else:
            pose[i, :2], J[i, :2] = _anchor(model, i, pose, J)
    return pose, J


def _anchor(model: Model, i: int, pose, J):
    """Position and Jacobian (2, n) of body i's anchor point (its pin on the parent or ground)."""
    b = model.bodies[i]
    par = b.parent
    if par < 0:
        return np.asarray(b.pin, float), np.zeros((2, J.shape[2]))
    c, s = math.cos(pose[par, 2]), math.sin(pose[par, 2])
    rx = c * b.pin[0] - s * b.pin[1]
    ry = s * b.pin[0] + c * b.pin[1]
    Ja = np.array([J[par, 0] - ry * J[par, 2], J[par, 1] + rx * J[par, 2]])
    return pose[par, :2] + np.array([rx, ry]), Ja


def static_model(model: Model, drive: int, angle: float, torques: dict, free_drive_torque: float | None):
    """A copy of the model for statics: the driven body held at ``angle`` (or free with the torque
    ``free_drive_torque``), constant load torques, no ramps, no initial speeds."""
    bodies = []
    for i, b in enumerate(model.bodies):
        nb = dataclasses.replace(b, omega0=0.0, torque_ramp=0.0, attrs=dict(b.attrs))
        if i == drive:
            nb.theta0 = angle
            if free_drive_torque is None:
                nb.rotation = ANGLE_PRESCRIBED
                nb.speed = Profile.make(0.0)
            else:
                nb.rotation = ANGLE_FREE
                nb.speed = None
                nb.torque = Profile.make(free_drive_torque)
        elif b.torque is not None:
            nb.torque = Profile.make(torques[i])
        if b.torsion_parent == drive >= 0:  # a shaft to the driven body: its rest twist stays
            nb.theta0 = b.theta0 + angle - model.bodies[drive].theta0
        bodies.append(nb)
    out = copy.copy(model)
    out.bodies = bodies
    return out


def _kinematic_state(model: Model, drive: int, dth: float, ratio: np.ndarray) -> np.ndarray:
    """Coordinates of the unloaded (kinematic) configuration with the driven body turned by dth:
    every angle advanced by its speed ratio, centres on bearings at their anchor points (exact
    on the carrier's circle, not extrapolated along the tangent)."""
    names = model.coordinate_names()
    rate = {}
    for i, b in enumerate(model.bodies):
        nm = f"{b.name}.theta"
        rate[i] = 1.0 if i == drive else (ratio[names.index(nm)] if nm in names else 0.0)
    turned = copy.copy(model)
    turned.bodies = [dataclasses.replace(b, theta0=b.theta0 + rate[i] * dth) for i, b in enumerate(model.bodies)]
    q, _ = turned.initial_state()
    return q


def _equilibrium(model: Model, q0: np.ndarray, load_scale: float, tol: float = 1e-9, max_iter: int = 200):
    """Static equilibrium rhs(q) = 0 by Newton's method on the contact tangent, with a step limit
    (2 um), a small regularisation while contacts are open, and backtracking on the residual.

    The residual is scaled to forces (torques divided by the model's length scale) and compared
    with ``load_scale`` [N]."""
    q = q0.copy()
    v = np.zeros_like(q)
    names = model.coordinate_names()
    is_angle = np.array([n.endswith(".theta") for n in names])
    L = model.length_scale
    to_force = np.where(is_angle, 1.0 / L, 1.0)
    to_length = np.where(is_angle, L, 1.0)
    dmax = 2e-6  # m of motion per iteration

    arr = model.pack(COARSE_STRIDE)  # one model, many evaluations

    def residual(x):
        ev_ = evaluate(model, x, v, arr=arr)
        return ev_, float(np.abs(ev_["rhs"] * to_force).max())

    ev, res = residual(q)
    best = (res, q, ev)
    stalled = 0
    for _ in range(max_iter):
        if res < tol * load_scale:
            return q, ev, res
        if res < best[0] * (1 - 1e-3):
            best, stalled = (res, q, ev), 0
        else:
            stalled += 1
        if stalled > 30:  # a contact appearing and vanishing between iterations (outline corner)
            break
        Kt = ev["Kt"]
        mu = 1e-6 * max(np.abs(np.diag(Kt) * to_force * to_force).max(), 1.0)
        A = Kt + mu * np.diag(1.0 / (to_force * to_force))
        dq = np.linalg.solve(A, ev["rhs"])
        move = np.abs(dq * to_length).max()
        if move > dmax:
            dq *= dmax / move
        lam = 1.0
        for _ in range(30):
            ev_t, res_t = residual(q + lam * dq)
            if res_t < res or move > dmax:  # limited steps move towards contact; accept them
                break
            lam *= 0.5
        q = q + lam * dq
        ev, res = ev_t, res_t
    if res < best[0]:
        best = (res, q, ev)
    return best[1], best[2], best[0]


def loaded_contacts(ev, model: Model, m: int, J: np.ndarray, pose: np.ndarray):
    """Loaded contacts of mesh m: list of (k_c [N/m], g_c (n,), F_c [N], depth [m], nx, ny)."""
    mesh = model.meshes[m]
    a, b = mesh.a, mesh.b
    out = []
    for c in range(int(ev["count"][m])):
        F, depth, px, py, nx, ny = ev["cf"][m, c]
        if F <= 0.0 or depth <= 0.0:
            continue
        ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
        mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
        g = -(nx * J[a, 0] + ny * J[a, 1] + ma * J[a, 2]) + (nx * J[b, 0] + ny * J[b, 1] + mb * J[b, 2])
        k = mesh.K * mesh.e * depth ** (mesh.e - 1.0)
        out.append((k, g, F, depth, nx, ny))
    return out


def cubic_step(x: float) -> float:
    """ADAMS STEP from 0 at x = 0 to 1 at x = 1 (cubic), clipped."""
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def support_springs(model: Model, J: np.ndarray, pose: np.ndarray) -> list[Spring]:
    out = []
    for i, b in enumerate(model.bodies):
        if b.joint == BEARING:
            _, Ja = _anchor(model, i, pose, J)
            kind = "bearing" if b.parent >= 0 or b.attrs.get("role") in ("planet",) else "support"
            kind = "support" if b.attrs.get("role") == "ring" else kind
            label = f"{b.name} bearing"
            if b.attrs.get("shaft"):  # the shaft's bending with its bearings (flexgear.dynamics.model.shafts)
                kind, label = "shaft", f"{b.attrs['shaft']} shaft bending"
            out.append(Spring(f"{label} x", kind, b.stiffness, J[i, 0] - Ja[0]))
            out.append(Spring(f"{label} y", kind, b.stiffness, J[i, 1] - Ja[1]))
        if b.rotation == ANGLE_SPRING and b.torsion_parent >= 0:  # a shaft (flexgear.dynamics.model.shafts)
            p = b.torsion_parent
            shaft = b.attrs.get("shaft") or model.bodies[p].attrs.get("shaft", "")
            out.append(Spring(f"{shaft} shaft torsion".lstrip(), "shaft", b.torsional_stiffness, J[i, 2] - J[p, 2]))
        elif b.rotation == ANGLE_SPRING:
            out.append(Spring(f"{b.name} torsion", "support", b.torsional_stiffness, J[i, 2].copy()))
    return out


def _shaft_twist(model: Model, drive: int, torques: dict, ratio: np.ndarray) -> np.ndarray:
    """Coordinate change of the shafts' static twist (:mod:`flexgear.dynamics.model.shafts`), a start for the
    equilibrium: the input shaft (a spring to the driven motor body) transmits the torque of
    the power balance T_in w_gear + sum T_load w_load = 0 at the nominal speeds and turns the
    whole set behind it by -T_in / k; an output shaft turns its load body by T_load / k."""
    index = model.coordinate_indices()
    out = np.zeros(len(ratio))
    for i, b in enumerate(model.bodies):
        p, ith = b.torsion_parent, index[i][2]
        if b.rotation != ANGLE_SPRING or p < 0 or ith < 0 or b.torsional_stiffness <= 0:
            continue
        if p == drive and b.omega0 != 0.0:
            t_in = -sum(T * model.bodies[j].omega0 for j, T in torques.items()) / b.omega0
            out += ratio / ratio[ith] * (-t_in / b.torsional_stiffness)
        elif i in torques:
            out[ith] += torques[i] / b.torsional_stiffness
    return out


def drive_and_loads(model: Model, load_time: float | None):
    drive = [i for i, b in enumerate(model.bodies) if b.speed is not None]
    if len(drive) != 1:
        raise ConfigError(f"linearisation needs exactly one driven body (prescribed speed), found {len(drive)}")
    torques = {}
    for i, b in enumerate(model.bodies):
        if b.torque is not None:
            t = load_time if load_time is not None else float(b.torque.t[-1]) + b.torque_ramp
            torques[i] = float(b.torque(t))
    if not torques or all(T == 0.0 for T in torques.values()):
        raise ConfigError("load.torque = 0: the linearisation point has no load (every tooth contact is "
                          "open, the mesh stiffness is zero); give a load torque > 0")
    return drive[0], torques


def equilibria(model: Model, drive: int, torques: dict, n_positions: int, mesh_angle: float,
                approximate: list, skipped: list):
    """Static equilibria at ``n_positions`` drive angles over one mesh cycle (the drive held at
    each, the others free), each from the last one turned on kinematically. Yields ``(j, dth,
    sm, q, ev, q_kin)`` for the positions found: index, drive rotation [rad], the held model,
    its coordinates and evaluation, and the kinematic (rigid, unloaded) state; appends (j,
    residual) to ``approximate`` (accepted) or ``skipped`` (residual above
    :data:`APPROXIMATE_EQUILIBRIUM` of the load). Shared by both linearisations."""
    q0, ratio = speed_ratio(model, drive)
    scale = load_scale(model, torques)
    theta_d0 = model.bodies[drive].theta0
    twist = _shaft_twist(model, drive, torques, ratio)
    q_prev = None
    for j in range(n_positions):
        dth = mesh_angle * j / n_positions
        sm = static_model(model, drive, theta_d0 + dth, torques, None)
        guess = (q0 + ratio * dth + twist) if q_prev is None else q_prev + ratio * (mesh_angle / n_positions)
        q, ev, res = _equilibrium(sm, guess, scale)
        if res > APPROXIMATE_EQUILIBRIUM * scale:
            skipped.append((j, res))
            q_prev = None
            continue
        if res >= 1e-9 * scale:
            approximate.append((j, res))
        q_prev = q
        yield j, dth, sm, q, ev, _kinematic_state(model, drive, dth, ratio)


def speed_ratio(model: Model, drive: int):
    """The initial coordinates and each coordinate's speed per unit drive speed (kinematic)."""
    q0, v0 = model.initial_state()
    w0 = model.bodies[drive].omega0
    return q0, (v0 / w0 if w0 != 0 else np.zeros_like(v0))


def load_scale(model: Model, torques: dict) -> float:
    """Largest applied torque over the model's length scale [N]: the equilibrium's force scale."""
    return max(abs(T) for T in torques.values()) / model.length_scale


def valid_positions(skipped: list, found: bool, n_positions: int, scale: float) -> np.ndarray:
    """Mask of the positions with an equilibrium; an error if more than a quarter (or all) failed."""
    if len(skipped) > n_positions // 4 or not found:
        raise ConfigError(f"static equilibrium not found at {len(skipped)} of {n_positions} positions over a mesh "
                          f"cycle (largest residual {max(r for _, r in skipped):.3g} N for a load of {scale:.3g} N): "
                          "a tooth contact appears and vanishes there; check load.torque and the supports")
    bad = {i for i, _ in skipped}
    return np.array([j not in bad for j in range(n_positions)])


def contact_lost(mesh, j: int, n_positions: int) -> ConfigError:
    return ConfigError(f"mesh '{mesh.name}' has no loaded tooth contact at the linearisation point "
                       f"(position {j} of {n_positions} over a mesh cycle): contact lost; increase load.torque")


def body_roles(sm: Model, pose: np.ndarray) -> dict:
    """Planets, their angles [rad] and the central members of a held model, for LinearSystem."""
    planets = [i for i, b in enumerate(sm.bodies) if b.attrs.get("role") == "planet"]
    return {"planets": [sm.bodies[i].name for i in planets],
            "planet_angles": np.array([math.atan2(pose[i, 1], pose[i, 0]) for i in planets]),
            "central": [b.name for b in sm.bodies if b.attrs.get("role", "").split(",")[0] in ("sun", "carrier", "ring")]}
