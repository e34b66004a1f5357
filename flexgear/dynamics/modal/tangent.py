"""The linearisation of a flexible model: the solver's own tangent stiffness and mass, averaged over
a mesh cycle, and its split into mesh, modal and coupling springs for the strain energies.
"""
from __future__ import annotations

import math

import numpy as np

from ...errors import ConfigError
from ..integrator.simulation import evaluate
from ..model.bodies import Model
from .equilibrium import (body_roles, contact_lost, equilibria, load_scale, pose_jacobians, speed_ratio,
                          static_model, support_springs, valid_positions)
from .system import LinearSystem, Spring, modal_rotation, symmetrise_planet_meshes

#: Largest relative asymmetry of the solver's tangent stiffness that is symmetrised
#: (:func:`tangent_asymmetry`); beyond it the forces are not conservative at the operating
#: point and a modal analysis is refused. The flank tables' reciprocity (c_kl = c_lk) holds to
#: their interpolation, so the compliant tangent is symmetric to about 1e-5 in this measure.
TANGENT_ASYMMETRY = 1e-3


def tangent_asymmetry(K: np.ndarray) -> float:
    """max |K_ij - K_ji| / sqrt(|K_ii K_jj|) [-]: the asymmetry of a stiffness matrix relative
    to its diagonal, so that it does not depend on the coordinates' units (modal coordinates
    carry omega_i^2 up to 1.6e12 1/s^2 on the diagonal, contacts 1e8-1e9 N/m: relative to the
    largest entry an asymmetry of the contact terms would vanish)."""
    d = np.sqrt(np.abs(np.diag(K)))
    scale = np.maximum(np.outer(d, d), 1e-12 * max(float(d.max()) ** 2, 1e-300))
    return float((np.abs(K - K.T) / scale).max())


def _contact_gradients(ev, model: Model, m: int, J: np.ndarray, pose: np.ndarray):
    """Loaded contacts of mesh m: list of (g_c (n,) rigid approach per unit coordinate, F_c [N],
    depth [m], flank side of body a (+1 / -1))."""
    mesh = model.meshes[m]
    a, b = mesh.a, mesh.b
    out = []
    for c in range(int(ev["count"][m])):
        F, depth, px, py, nx, ny = ev["cf"][m, c]
        if F <= 0.0:
            continue
        ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
        mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
        g = -(nx * J[a, 0] + ny * J[a, 1] + ma * J[a, 2]) + (nx * J[b, 0] + ny * J[b, 1] + mb * J[b, 2])
        out.append((g, float(F), float(depth), int(ev["ci"][m, c, 2])))
    return out


def _modal_springs(model: Model) -> tuple[list[Spring], dict]:
    """Springs omega_i^2 of the modal coordinates (unit modal mass) and each flexible body's
    modal coordinate indices. An off-diagonal modal stiffness stays in the coupling."""
    n = len(model.coordinate_names())
    springs, rows = [], {}
    for body, c0, m in model.modal_coordinates():
        fb = next(f for f in model.flex if f.body == body)
        name = model.bodies[body].name
        rows[name] = list(range(c0, c0 + m))
        for k in range(m):
            g = np.zeros(n)
            g[c0 + k] = 1.0
            springs.append(Spring(f"{name} mode {k + 1} ({fb.frequencies[k]:.0f} Hz)", "gear mode",
                                  float(fb.stiffness[k, k]), g))
    return springs, rows


def _mesh_decomposition(K_c: np.ndarray, G: np.ndarray, rigid: np.ndarray, to_length: np.ndarray):
    """Per-mesh springs of a contact tangent K_c (n, n) with mesh gradients G (nm, n; rigid
    coordinates only): K_c ~ H^T S H, H = [G_R, A].

    S (nm, nm) [N/m] is G'^+T K_c' G'^+ on the rigid coordinates in lengths (angles times the
    model's length scale, so the pseudo-inverse does not mix units): S_mm is mesh m's stiffness
    along its line of action with the other meshes' approaches held, S_mn (m != n) the contact
    coupling between meshes (through a flexible body's rim). A (nm, n_modal) is the modal part
    of each mesh's approach, from K_c[R, E] = G_R^T S A. Returns S, H (nm, n) and the relative
    Frobenius residual of the fit."""
    R = rigid
    E = ~rigid
    S, Gp = _line_of_action(K_c[np.ix_(R, R)], G, rigid, to_length)
    H = np.zeros_like(G)
    H[:, R] = G[:, R]
    if E.any():
        B = Gp.T @ (K_c[np.ix_(R, E)] / to_length[R][:, None])
        H[:, E] = np.linalg.lstsq(S, B, rcond=None)[0]
    fit = H.T @ S @ H
    res = np.linalg.norm(K_c - fit) / max(np.linalg.norm(K_c), 1e-300)
    return S, H, float(res)


def _line_of_action(K_rr: np.ndarray, G: np.ndarray, rigid: np.ndarray, to_length: np.ndarray):
    """A stiffness K_rr on the rigid coordinates seen along the meshes' lines of action [N/m]:
    S = G'^+T K' G'^+ (nm, nm), the rigid coordinates in lengths (angles times the model's length
    scale, so the pseudo-inverse does not mix units), and G'^+."""
    Gp = np.linalg.pinv(G[:, rigid] / to_length[rigid])
    S = Gp.T @ (K_rr / np.outer(to_length[rigid], to_length[rigid])) @ Gp
    return 0.5 * (S + S.T), Gp


def _effective_mesh_stiffness(K_s: np.ndarray, G: np.ndarray, rigid: np.ndarray, to_length: np.ndarray):
    """Each mesh's effective (quasi-static) tangent stiffness along its line of action [N/m]: of
    K_s (n, n; K without the supports, bearings and shafts), the modal coordinates condensed
    statically (:func:`_condensed_stiffness`: the gears' tooth, rim and body compliance in series
    with the contact), the other meshes' approaches held, as S_mm of :func:`_mesh_decomposition`.
    This is the stiffness the FE loaded mesh gives (dF / dTE, c_gamma b); S_mm of a model with
    modal coordinates is only its contact spring."""
    return np.diag(_line_of_action(_condensed_stiffness(K_s, rigid), G, rigid, to_length)[0]).copy()


def _cyclic_mean(P: np.ndarray, A: np.ndarray, N: int) -> np.ndarray:
    """(1/N) sum_k P^k A P^-k: the part of A invariant under the planets' rotation (P orthogonal)."""
    out = np.zeros_like(A)
    Pk = np.eye(A.shape[0])
    for _ in range(N):
        out += Pk @ A @ Pk.T
        Pk = P @ Pk
    return out / N


def linearise_tangent(model: Model, drive: int, torques: dict, n_positions: int, free_drive: bool,
                       mesh_angle: float) -> LinearSystem:
    """:func:`linearise` for a model with compliant meshes or modal coordinates.

    At each equilibrium position over a mesh cycle the solver's tangent stiffness Kt
    (:func:`~flexgear.dynamics.integrator.simulation.evaluate`: bearings, shafts, the joint tangent of all
    compliant contacts with their coupling across meshes, the modal stiffness omega_i^2 and the
    modes' share of each contact's approach) is taken, symmetrised and averaged over the cycle;
    the mass matrix is the solver's Mq at the reference position (the frame-mode coupling of
    the modal coordinates included) plus ``-dQ/dq''`` of the contact forces through the condensed
    modes' deflection under the frames' inertia load (symmetrised). For the energy table each mesh gets a spring along the
    line of action of its loaded drive-side contacts, of stiffness S_mm from
    :func:`_mesh_decomposition` (averaged over the cycle); the gears' modes get springs
    omega_i^2 on their coordinates; the rest of K (contact coupling between meshes, back-flank
    contacts off the line of action) is the :data:`COUPLING` entry."""
    _, ratio = speed_ratio(model, drive)
    scale = load_scale(model, torques)
    theta_d0 = model.bodies[drive].theta0
    nm = len(model.meshes)
    keys = ("k", "force", "depth", "count", "back_force", "deflection", "k_effective")
    cycle = {key: np.zeros((nm, n_positions)) for key in keys}
    coupling = np.zeros((nm, nm, n_positions))
    K_sum, S_sum, n_valid, asym_max, fit_max = None, None, 0, 0.0, 0.0
    approximate, skipped = [], []
    ref = None
    for j, dth, sm, q, ev, q_kin in equilibria(model, drive, torques, n_positions, mesh_angle, approximate,
                                                 skipped):
        reaction = -ev["Fb"][drive, 2]  # torque the drive applies to hold the equilibrium
        held = {nme: i for i, nme in enumerate(sm.coordinate_names())}
        q_held = q
        if free_drive:  # the drive a coordinate, held by its reaction torque
            sm, q = _free_drive_state(model, drive, theta_d0 + dth, torques, sm, q, reaction)
            ev = evaluate(sm, q, np.zeros_like(q))
        Kt = ev["Kt"]
        asym = tangent_asymmetry(Kt)
        if asym > TANGENT_ASYMMETRY:
            raise ConfigError(f"the tangent stiffness at the operating point is not symmetric (relative asymmetry "
                              f"{asym:.3g} > {TANGENT_ASYMMETRY:g}): the forces are not conservative there, no modal "
                              "analysis")
        asym_max = max(asym_max, asym)
        K = 0.5 * (Kt + Kt.T)
        pose, J = pose_jacobians(sm, q)
        names = sm.coordinate_names()
        is_angle = np.array([nme.endswith(".theta") for nme in names])
        to_length = np.where(is_angle, model.length_scale, 1.0)
        rigid = np.arange(len(q)) < sm.rigid_coordinates()
        K_s = K - sum((s.k * np.outer(s.g, s.g) for s in support_springs(sm, J, pose)), np.zeros_like(K))
        K_c = K_s - sum((s.k * np.outer(s.g, s.g) for s in _modal_springs(sm)[0]), np.zeros_like(K))
        G = np.zeros((nm, len(q)))
        for m, mesh in enumerate(model.meshes):
            cs = _contact_gradients(ev, sm, m, J, pose)
            if not cs:
                raise contact_lost(mesh, j, n_positions)
            by_side = {sd: sum(F for _, F, _, s_ in cs if s_ == sd) for sd in (1, -1)}
            side = max(by_side, key=by_side.get)
            drive_side = [c for c in cs if c[3] == side]
            G[m] = sum(F * g for g, F, _, _ in drive_side) / by_side[side]
            cycle["force"][m, j] = by_side[side] - by_side[-side]
            cycle["back_force"][m, j] = by_side[-side]
            cycle["depth"][m, j] = max(d for _, _, d, _ in cs)
            cycle["count"][m, j] = len(cs)
            cols = [names.index(nme) for nme in held]
            cycle["deflection"][m, j] = G[m, cols] @ (q_held - q_kin)  # rigid approach from the kinematic position
        S, H, fit = _mesh_decomposition(K_c, G, rigid, to_length)
        fit_max = max(fit_max, fit)
        cycle["k"][:, j] = np.diag(S)
        cycle["k_effective"][:, j] = _effective_mesh_stiffness(K_s, G, rigid, to_length)
        coupling[:, :, j] = S
        K_sum = K if K_sum is None else K_sum + K
        S_sum = _condensed_stiffness(K, rigid) if S_sum is None else S_sum + _condensed_stiffness(K, rigid)
        n_valid += 1
        if ref is None:
            ref = (j, sm, q, ev, H, reaction)
    valid = valid_positions(skipped, ref is not None, n_positions, scale)
    k_mean = cycle["k"][:, valid].mean(axis=1)
    j_ref, sm, q, ev, H, reaction = ref
    K = K_sum / n_valid
    rigid = np.arange(len(q)) < sm.rigid_coordinates()
    if not rigid.all():
        # the modal coordinates' static condensation of the mean K is stiffer than the mean of
        # the condensed K (the Schur complement is concave in K: the contact moves along the
        # flanks and to the next tooth over the cycle, the mean spreads it). The rigid block is
        # corrected so that the quasi-static mesh stiffness is the cycle mean, as with static
        # condensation and in the rigid model (one position: no change)
        K[np.ix_(rigid, rigid)] += S_sum / n_valid - _condensed_stiffness(K, rigid)
    # the condensed modes' deflection under the frames' inertia load makes the contact forces
    # depend on the accelerations: -dQ/dq'' joins the mass (symmetrised: the Rayleigh quotient
    # of a mode is that of the unsymmetric term)
    M_inertia = evaluate(sm, q, np.zeros_like(q), acceleration_slope=1.0)["Kt"] - ev["Kt"]
    M = 0.5 * (ev["Mq"] + ev["Mq"].T + M_inertia + M_inertia.T)
    rigid_body_hz = 0.0
    if free_drive:
        # the kinematic rotation of the whole set (every angle at its speed ratio) is free: a
        # contact off the line of action (a tip corner) has moment arms off r_b1 : r_b2, which
        # resist it at one position and drive it at another; over a cycle they cancel. Project
        # it out of K (M-orthogonally); the frequency it had is kept in the attrs.
        names = sm.coordinate_names()
        held_ratio = dict(zip(model.coordinate_names(), ratio))
        r = np.array([1.0 if nme == f"{model.bodies[drive].name}.theta" else held_ratio.get(nme, 0.0)
                      for nme in names])
        Mr = M @ r
        rigid_body_hz = math.sqrt(max(r @ K @ r, 0.0) / (r @ Mr)) / (2 * math.pi)
        Q = np.eye(len(r)) - np.outer(r, Mr) / (r @ Mr)
        K = Q.T @ K @ Q
    pose, J = pose_jacobians(sm, q)
    modal, body_modes = _modal_springs(sm)
    springs = support_springs(sm, J, pose) + modal
    for m, mesh in enumerate(model.meshes):
        springs.append(Spring(mesh.name, "mesh", float(k_mean[m]), H[m].copy()))
    bodies = {b.name: (b.mass, b.inertia, J[i]) for i, b in enumerate(sm.bodies)}
    roles = body_roles(sm, pose)
    names = [mesh.name for mesh in model.meshes]
    out = LinearSystem(
        dofs=sm.coordinate_names(), bodies=bodies, springs=springs, **roles, stiffness=K, mass=M, body_modes=body_modes,
        attrs={"source": "flexible model linearised about the loaded static equilibrium (the solver's tangent "
                         "stiffness: compliant contacts solved jointly, modal coordinates)",
               "n_positions": n_positions, "mesh_stiffness": dict(zip(names, map(float, k_mean))),
               "effective_mesh_stiffness": dict(zip(names, map(float, cycle["k_effective"][:, valid].mean(axis=1)))),
               "mesh_coupling": {"meshes": names, "stiffness": coupling[:, :, valid].mean(axis=2)},
               "mesh_force": dict(zip(names, map(float, cycle["force"][:, valid].mean(axis=1)))),
               "load_torques": {model.bodies[i].name: T for i, T in torques.items()},
               "drive_reaction_torque": float(reaction),
               "free_drive": free_drive, "q": q, "approximate_positions": approximate, "cycle": cycle,
               "mesh_angle": mesh_angle, "drive": model.bodies[drive].name, "skipped_positions": skipped,
               "reference_position": j_ref, "tangent_asymmetry": asym_max, "mesh_fit_residual": fit_max,
               "rigid_body_frequency_removed": rigid_body_hz,
               "inertia_relief_mass": 0.5 * (M_inertia + M_inertia.T)})
    planets = set(roles["planets"])
    for fb in sm.flex:
        name = sm.bodies[fb.body].name
        if fb.modes and name not in planets and roles["planets"]:
            T = modal_rotation(fb, len(roles["planets"]))
            if T is not None:
                out.modal_rotation[name] = T
    asymmetry = symmetrise_planet_meshes(out)
    P = out.symmetry_operator()
    if P is not None:
        Np = len(roles["planets"])
        Ks, Ms = _cyclic_mean(P, K, Np), _cyclic_mean(P, M, Np)
        asymmetry = max(asymmetry, np.abs(Ks - K).max() / np.abs(K).max(), np.abs(Ms - M).max() / np.abs(M).max())
        out.stiffness, out.mass = Ks, Ms
    out.attrs["planet_asymmetry"] = float(asymmetry)
    return out


def _condensed_stiffness(K: np.ndarray, rigid: np.ndarray) -> np.ndarray:
    """Static condensation of the coordinates not in ``rigid`` (mask): K_rr - K_rm K_mm^-1 K_mr."""
    m = ~rigid
    if not m.any():
        return K[np.ix_(rigid, rigid)].copy()
    out = K[np.ix_(rigid, rigid)] - K[np.ix_(rigid, m)] @ np.linalg.solve(K[np.ix_(m, m)], K[np.ix_(m, rigid)])
    return 0.5 * (out + out.T)


def _free_drive_state(model: Model, drive: int, angle: float, torques: dict, held: Model, q: np.ndarray,
                      reaction: float):
    """The static model with the driven body free (held by the torque ``reaction``) and the
    coordinates q of the held model ``held`` extended by its angle."""
    sm = static_model(model, drive, angle, torques, reaction)
    old = dict(zip(held.coordinate_names(), q))
    dn = f"{model.bodies[drive].name}.theta"
    return sm, np.array([angle if nm == dn else old[nm] for nm in sm.coordinate_names()])
