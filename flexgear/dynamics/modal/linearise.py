"""Linearisation of a model about its loaded operating point: the linear system (:mod:`.system`) whose modes the modal analysis gives.

* :func:`linearise` of a rigid model: static equilibria at positions over one mesh cycle, each
  mesh a spring with the IMPACT tangent averaged over the cycle along its line of action;
  bearings and supports with their stiffness; no speed effects (Lin & Parker).
* :func:`linearise` of a flexible model: K is the solver's own tangent stiffness
  (:func:`~flexgear.dynamics.integrator.simulation.evaluate`), symmetrised and averaged; M the
  solver's mass matrix. Integrated condensed modes become modal coordinates
  (:func:`modes_as_coordinates`); statically condensed ones add the inertia relief mass
  (``attrs["inertia_relief_mass"]``). The springs only split the strain energy (each mesh fitted
  to the contact tangent, :func:`_mesh_decomposition`; the rest is :data:`COUPLING`). With
  ``free_drive`` the set's kinematic rotation is projected out of K.
* :mod:`flexgear.dynamics.lumped.planetary`: Lin & Parker's planar model from explicit
  parameters.

See the theory page *Linearisation and modal analysis*.
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
    """A copy of the flexible ``model`` with every condensed mode a modal coordinate (as ``dynamic_cutoff = cutoff``).

        Its linearisation is that of the condensed modes integrated in the contact solve. Mode i
        gets unit modal mass, stiffness omega_i^2 [1/s^2], damping 2 zeta omega_i [1/s], flank
        displacement A_i = ``shape`` x omega_i [1/sqrt(kg)] and frame coupling S_i (zero where the
        interface is not the frame); it follows the body's modal coordinates. The residual tables
        stay; the model is returned unchanged when nothing is condensed.

        Raises
        ------
        ConfigError
            A body whose rigid mass or inertia is below what its modes carry
            (:func:`~flexgear.dynamics.flexible.reductions.check_frame_inertia`).
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


def default_positions(model: Model) -> int:
    """Equilibrium positions over one mesh cycle that :func:`linearise` takes by default: 8 N for
    N planets (a multiple of N, so that every mesh sees the same phases), 24 for a spur pair."""
    N = sum(1 for b in model.bodies if b.attrs.get("role") == "planet")
    return 8 * N if N else 24


def linearise(model: Model, n_positions: int | None = None, free_drive: bool = False,
              load_time: float | None = None, condensation: str = "integrated") -> LinearSystem:
    """Linear system of the multi-body model about its loaded operating point (module docstring).

        Parameters
        ----------
        model : Model
            From :func:`flexgear.dynamics.model.assembly.build_model`.
        n_positions : int, optional
            Positions over one mesh cycle (default 8 N, or 24: a multiple of the planet count, so
            that every mesh sees the same phases).
        free_drive : bool
            True: the driven body's rotation is a free coordinate (reaction torque applied);
            False: held, as in the simulation.
        load_time : float, optional
            Time [s] at which the load torque profiles are read (default: full load).
        condensation : {"integrated", "static"}
            How a flexible model's condensed modes enter (as in
            :func:`~flexgear.dynamics.integrator.simulation.simulate`).

        Raises
        ------
        ConfigError
            Unknown ``condensation``, zero ``load.torque``, no single driven body, a mesh without
            loaded contact at a position, no static equilibrium at more than a quarter of the
            positions, or (flexible) a non-symmetric tangent stiffness.
    """
    if condensation not in CONDENSATION:
        raise ConfigError(f"condensation = {condensation!r}: must be one of {', '.join(map(repr, sorted(CONDENSATION)))}")
    drive, torques = drive_and_loads(model, load_time)
    f_in, f_m = model.attrs["input_frequency"], model.attrs["mesh_frequency"]
    if n_positions is None:
        n_positions = default_positions(model)
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
