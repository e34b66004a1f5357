"""Linearisation of a model about its loaded operating point: the linear system (mass matrix and
springs, :mod:`.system`) whose modes the modal analysis gives.

Three sources build such systems:

* :func:`linearise` - the rigid model (:mod:`flexgear.dynamics.model.assembly`) about its loaded
  operating point. The static equilibrium under the load torque is solved at positions spread
  over one mesh cycle (the driven body held at each position, the others free); each mesh's
  stiffness is the tangent of the IMPACT law, k = sum_c K e delta_c^(e-1) over its loaded tooth
  pairs, averaged over the cycle; its direction is the line of action of the loaded contacts.
  Bearings and supports enter with their stiffness. Speed effects (centripetal, gyroscopic)
  are left out, as in Lin & Parker's stationary analysis.
* :func:`linearise` of a flexible model (meshes with the compliant Hertz law of
  :mod:`flexgear.dynamics.flexible.compliant`, modal coordinates of :mod:`flexgear.dynamics.flexible.floating_frame`, elastic shafts): the same
  equilibria over a mesh cycle, but K is the solver's own tangent stiffness
  (:func:`~flexgear.dynamics.integrator.simulation.evaluate`), symmetrised and averaged over the cycle: the
  joint tangent (C + diag h')^-1 of all compliant contacts (so the coupling between meshes
  through a gear's rim is in it), bearings, shafts, the modal stiffness omega_i^2 and the
  modes' share of every contact's approach; M is the solver's Mq (the frame-mode inertia
  coupling included) plus -dQ/dq'' of the contact forces through the flanks' deflection under
  the gears' own inertia load (condensed modes, :func:`~flexgear.dynamics.flexible.compliant.inertia_flank_value`;
  symmetrised, ``attrs["inertia_relief_mass"]``): a gear the mesh accelerates is stiffer at
  its flanks than with its bore held (spur pair: the mesh mode 7.6 % higher). The condensed
  modes (between ``[flexible] dynamic_cutoff`` and ``cutoff``) enter as the solver integrates
  them (``condensation``, as in :func:`~flexgear.dynamics.integrator.simulation.simulate`): ``"integrated"``
  (the default) carries their own inertia, which is the same as having every mode a coordinate
  (:mod:`flexgear.dynamics.flexible.condensed`), so the linearisation makes each of them a modal coordinate
  (:func:`modes_as_coordinates`: the reduced model's modal mass, stiffness omega_i^2 and
  frame-mode coupling, their flank displacement in the contact tangent, no inertia relief
  left); ``"static"`` condenses them quasi-statically as above. Each matches a free vibration
  of the integrator with the same condensation; at one mesh position the static condensation
  puts the flexible spur pair's mesh mode 1.6 % below the integrated one, MERCURY 1-A's mesh
  modes 0.4-0.7 % below, and the coupled mode of a soft gear whose condensed modes the mesh
  excites (modulus x 0.01, modes at 3-10 kHz) 7 % above. The system carries these as explicit matrices
  (:attr:`LinearSystem.stiffness`, :attr:`LinearSystem.mass`); its springs then only split the
  strain energy: each mesh a spring along the line of action of its loaded drive-side contacts
  with the mesh's own stiffness (the other meshes' approaches held, fitted to the contact
  tangent: :func:`_mesh_decomposition`), each modal coordinate a spring omega_i^2; the part of K
  they leave (contact coupling between meshes, back-flank contacts) is the strain-energy entry
  :data:`COUPLING`. With ``free_drive`` the set's kinematic rotation is projected out of K (a
  tip-corner contact's moment arms off r_b1 : r_b2 resist it at some positions and drive it at
  others). Checked in ``tests/test_flexible_modal.py``: the spur pair's mesh mode against the
  FE loaded mesh's tangent stiffness with the static FE inertia relief (0.2-0.6 %), a shaft chain built by hand, a soft gear's
  coupled mode against a free vibration of the same model, MERCURY 1-A against Lin & Parker
  with the same mesh stiffnesses (the coupling between meshes moves the modes by up to 2 %).
* :mod:`flexgear.dynamics.lumped.planetary` - published lumped-parameter models set up from explicit
  parameters (Lin & Parker's planar planetary model).
"""
from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np

from ...errors import ConfigError
from ..contact.laws import LAW_HERTZ
from ..flexible.reductions import check_frame_inertia
from ..integrator.simulation import CONDENSATION, evaluate
from ..model.bodies import Model
from .equilibrium import (body_roles, contact_lost, cubic_step, drive_and_loads, equilibria, load_scale,
                          loaded_contacts, pose_jacobians, static_model, support_springs, valid_positions)
from .system import LinearSystem, Spring, symmetrise_planet_meshes
from .tangent import linearise_tangent


# =============================================================================================
# linearisation of the rigid model
# =============================================================================================


def modes_as_coordinates(model: Model) -> Model:
    """A copy of the flexible ``model`` with every condensed mode of its flexible bodies a modal
    coordinate (:mod:`flexgear.dynamics.flexible.floating_frame`), as with ``[flexible] dynamic_cutoff = cutoff``: the
    model whose linearisation is that of the condensed modes integrated in the contact solve
    (:mod:`flexgear.dynamics.flexible.condensed`: each mode's own inertia, its frame coupling S_i and its damping, exactly
    the equations of a modal coordinate).

    Condensed mode i of a body becomes a coordinate with unit modal mass, stiffness omega_i^2
    [1/s^2], damping 2 zeta omega_i [1/s], flank displacement A_i = ``shape`` x omega_i per unit
    coordinate [1/sqrt(kg)] and frame coupling S_i (zero where the interface is not the frame:
    a ring held on its rim or bolts, whose modes then carry no frame inertia, as when
    condensed); it follows the body's modal coordinates (ascending frequency). The residual
    tables (modes above the cutoff) stay. The model is returned unchanged when nothing is
    condensed.

    Raises
    ------
    ConfigError
        A body whose rigid mass or inertia is below what its modes carry (the mass matrix
        would be indefinite, :func:`~flexgear.dynamics.flexible.reductions.check_frame_inertia`).
    """
    if not any(fb.shape.shape[3] for fb in model.flex):
        return model
    bodies = [dataclasses.replace(b, attrs=dict(b.attrs)) for b in model.bodies]
    flex = []
    for fb in model.flex:
        nq = fb.shape.shape[3]
        if not nq:
            flex.append(fb)
            continue
        w = np.asarray(fb.condensed_omega, float)
        S = np.zeros((3, nq)) if fb.condensed_coupling is None else np.asarray(fb.condensed_coupling, float)
        damping = np.zeros(nq) if fb.condensed_damping is None else np.asarray(fb.condensed_damping, float)
        m0 = fb.modes

        def block(old, new):
            out = np.zeros((m0 + nq, m0 + nq))
            if m0:
                out[:m0, :m0] = old
            out[m0:, m0:] = new
            return out

        z, _, J, _ = fb.shape.shape
        shape = fb.shape * w  # A_i
        new = dataclasses.replace(
            fb, shape=np.zeros((z, 2, J, 0)),
            dynamic_shape=np.ascontiguousarray(shape if not m0 else np.concatenate([fb.dynamic_shape, shape], axis=3)),
            stiffness=block(fb.stiffness, np.diag(w * w)), mass=block(fb.mass, np.eye(nq)),
            damping=block(fb.damping, np.diag(damping)),
            frame_coupling=np.ascontiguousarray(S if not m0 else np.concatenate([fb.frame_coupling, S], axis=1)),
            frequencies=np.concatenate([fb.frequencies if m0 else np.zeros(0), w / (2 * math.pi)]),
            acceleration_shape=None if fb.acceleration_shape is None else np.zeros((z, 2, J, 3)),
            condensed_omega=np.zeros(0), condensed_damping=np.zeros(0), condensed_coupling=np.zeros((3, 0)),
            attrs=dict(fb.attrs, dynamic_modes=m0 + nq, condensed_modes=0))
        body = bodies[fb.body]
        body.attrs["mode_frequencies"] = [float(f) for f in new.frequencies]
        try:
            check_frame_inertia(body, new)
        except ConfigError as exc:
            raise ConfigError(f"linearisation with the condensed modes integrated (every mode a coordinate): {exc}; "
                              "or linearise with [flexible] condensation = 'static'") from exc
        flex.append(new)
    out = copy.copy(model)
    out.bodies, out.flex, out.attrs = bodies, flex, dict(model.attrs)
    return out


def linearise(model: Model, n_positions: int | None = None, free_drive: bool = False,
              load_time: float | None = None, condensation: str = "integrated") -> LinearSystem:
    """Linear system of the multi-body model about its loaded operating point (rigid: springs
    from the IMPACT tangent; flexible, :func:`is_flexible`: the solver's tangent, see the module
    docstring).

    Parameters
    ----------
    model : Model
        From :func:`flexgear.dynamics.model.assembly.build_model`.
    n_positions : int, optional
        Positions over one mesh cycle where the static equilibrium is solved and the mesh
        stiffness evaluated (default 8 N, or 24: a multiple of the planet count, so that every
        mesh sees the same phases).
    free_drive : bool
        False: the driven body's rotation is held (prescribed speed, as in the simulation).
        True: it is a free coordinate (reaction torque applied), so the set has a rigid-body
        rotation mode when nothing else holds it.
    load_time : float, optional
        Time [s] at which the load torque profiles are read (default: their last table time
        plus the ramp: the full load).
    condensation : {"integrated", "static"}
        How a flexible model's condensed modes enter, as in
        :func:`~flexgear.dynamics.integrator.simulation.simulate` (``[flexible] condensation``): integrated
        with their own inertia, i.e. each a modal coordinate (:func:`modes_as_coordinates`), or
        quasi-statically. No effect on a rigid model.

    Raises
    ------
    ConfigError
        ``condensation`` not one of the two, ``load.torque`` zero, no single driven body, a mesh without loaded contact at a
        position (contact lost), no static equilibrium at more than a quarter of the
        positions, or (flexible) a tangent stiffness that is not symmetric (forces not
        conservative at the operating point).
    """
    if condensation not in CONDENSATION:
        raise ConfigError(f"condensation = {condensation!r}: must be one of {', '.join(map(repr, sorted(CONDENSATION)))}")
    drive, torques = drive_and_loads(model, load_time)
    f_in, f_m = model.attrs["input_frequency"], model.attrs["mesh_frequency"]
    N = sum(1 for b in model.bodies if b.attrs.get("role") == "planet")
    if n_positions is None:
        n_positions = 8 * N if N else 24
    if n_positions < 1:
        raise ConfigError(f"n_positions = {n_positions}: must be >= 1")
    mesh_angle = 2 * math.pi * f_in / f_m  # drive rotation over one mesh cycle [rad]
    if is_flexible(model):
        condensed = sum(fb.shape.shape[3] for fb in model.flex)
        if condensation == "integrated":
            model = modes_as_coordinates(model)
        out = linearise_tangent(model, drive, torques, n_positions, free_drive, mesh_angle)
        out.attrs["condensation"] = condensation
        out.attrs["condensation_note"] = (
            "no condensed modes" if not condensed else
            f"the {condensed} condensed gear modes integrated with their own inertia (condensation = 'integrated'), "
            "linearised as modal coordinates" if condensation == "integrated" else
            f"the {condensed} condensed gear modes condensed quasi-statically (condensation = 'static')")
        return out
    scale = load_scale(model, torques)
    theta_d0 = model.bodies[drive].theta0
    cycle = {key: np.zeros((len(model.meshes), n_positions)) for key in ("k", "force", "depth", "count", "damping",
                                                                       "deflection")}
    ref = None
    approximate, skipped = [], []
    for j, dth, sm, q, ev, q_kin in equilibria(model, drive, torques, n_positions, mesh_angle, approximate,
                                                 skipped):
        pose, J = pose_jacobians(sm, q)
        for m, mesh in enumerate(model.meshes):
            cs = loaded_contacts(ev, sm, m, J, pose)
            if not cs:
                raise contact_lost(mesh, j, n_positions)
            cycle["k"][m, j] = sum(c[0] for c in cs)
            cycle["force"][m, j] = sum(c[2] for c in cs)
            cycle["depth"][m, j] = max(c[3] for c in cs)
            cycle["count"][m, j] = len(cs)
            g_j = sum(c[0] * c[1] for c in cs) / cycle["k"][m, j]
            cycle["deflection"][m, j] = g_j @ (q - q_kin)  # from the kinematic position
            cycle["damping"][m, j] = sum(mesh.C * cubic_step(c[3] / mesh.d) for c in cs)
        if ref is None:
            ref = (q, ev, j)
    valid = valid_positions(skipped, ref is not None, n_positions, scale)
    if not valid.all():  # fill skipped positions from their neighbours (periodic)
        x = np.arange(n_positions)
        for key, arr in cycle.items():
            for m in range(arr.shape[0]):
                arr[m, ~valid] = np.interp(x[~valid], x[valid], arr[m, valid], period=n_positions)
    k_mean = cycle["k"].mean(axis=1)
    q, ev, j_ref = ref
    theta_d0 = theta_d0 + mesh_angle * j_ref / n_positions
    reaction = -ev["Fb"][drive, 2]  # torque the drive must apply to hold the equilibrium
    if free_drive:
        sm = static_model(model, drive, theta_d0, torques, reaction)
        names = sm.coordinate_names()
        old = dict(zip(static_model(model, drive, theta_d0, torques, None).coordinate_names(), q))
        dn = f"{model.bodies[drive].name}.theta"
        q = np.array([old.get(nm, theta_d0) if nm != dn else theta_d0 for nm in names])
        ev = evaluate(sm, q, np.zeros_like(q))
    else:
        sm = static_model(model, drive, theta_d0, torques, None)
    pose, J = pose_jacobians(sm, q)
    springs = support_springs(sm, J, pose)
    mean_force, normals = {}, {}
    for m, mesh in enumerate(model.meshes):
        cs = loaded_contacts(ev, sm, m, J, pose)
        kc = np.array([c[0] for c in cs])
        g = sum(c[0] * c[1] for c in cs) / kc.sum()
        springs.append(Spring(mesh.name, "mesh", float(k_mean[m]), g))
        mean_force[mesh.name] = float(sum(c[2] for c in cs))
        nrm = sum(c[0] * np.array([c[4], c[5]]) for c in cs)
        normals[mesh.name] = nrm / np.linalg.norm(nrm)
    bodies = {b.name: (b.mass, b.inertia, J[i]) for i, b in enumerate(sm.bodies)}
    out = LinearSystem(
        dofs=sm.coordinate_names(), bodies=bodies, springs=springs, **body_roles(sm, pose),
        attrs={"source": "rigid model linearised about the loaded static equilibrium",
               "n_positions": n_positions, "mesh_stiffness": {m.name: float(k) for m, k in zip(model.meshes, k_mean)},
               "mesh_force": mean_force, "load_torques": {model.bodies[i].name: T for i, T in torques.items()},
               "drive_reaction_torque": float(reaction), "free_drive": free_drive, "q": q,
               "approximate_positions": approximate, "mesh_normal": normals, "cycle": cycle,
               "mesh_angle": mesh_angle, "drive": model.bodies[drive].name, "skipped_positions": skipped,
               "reference_position": j_ref})
    out.attrs["planet_asymmetry"] = symmetrise_planet_meshes(out)
    return out


# =============================================================================================
# linearisation of the flexible model: the solver's tangent
# =============================================================================================


def is_flexible(model: Model) -> bool:
    """Whether the model has compliant meshes (:mod:`flexgear.dynamics.flexible.compliant`) or modal coordinates: it is
    linearised with the solver's tangent (:func:`linearise_tangent`)."""
    return any(m.law == LAW_HERTZ for m in model.meshes) or bool(model.modal_coordinates())
