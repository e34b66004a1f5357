"""The lumped-parameter model of a configuration (``model = "lumped"``); its time loop is :mod:`~flexgear.dynamics.lumped.time_loop`.

:func:`build_lumped` linearises the rigid model about its loaded static equilibrium at
positions over one mesh cycle (:func:`~flexgear.dynamics.modal.linearise.linearise`): mass
matrix, bearing and support springs and, per mesh, its line of action and, per position, the
stiffness, static force, deflection and contact damping. Coordinates are deviations from the
nominal motion (carrier frame for a planetary set), without speed effects. Each mesh is a spring
with a stiffness k(phi) over the mesh cycle from ``contact`` (IMPACT tangent with the offset
e = delta_0 - F_0 / k), ``iso6336``, ``fe`` or ``constant``, taken at the same drive positions
for every mesh (the geometry's phasing), with backlash and contact loss on both flanks. See the
theory page *Lumped model*.
"""
from __future__ import annotations

import math
import dataclasses
import warnings
from dataclasses import dataclass, field

import numpy as np

from ...errors import ConfigError, user_stacklevel
from ..modal.linearise import linearise
from ..modal.system import LinearSystem
from ..model.bodies import BEARING, Model, Profile
from .faults import apply_faults, check_lumped_faults

#: a lumped mesh damped above this ratio (from [contact] C) is warned about: it chatters at contact loss
OVERDAMPED = 10.0


@dataclass
class LumpedModel:
    """A lumped model ready to integrate.

    Attributes
    ----------
    model : Model
        The rigid model (bodies, meshes, attributes; names of the results).
    system : LinearSystem
        Linearised system in the lumped coordinates (deviations from the nominal motion).
    G : ndarray (nm, n)
        Mesh gradients (deflection per coordinate).
    k, e, c : ndarray (nm, P cycles)
        Mesh stiffness [N/m], offset [m] and damping [N s/m] at P positions per mesh cycle.
    backlash : ndarray (nm,)
        [m] along the line of action.
    drive_arm : ndarray (nm,)
        Mesh deflection per unit rotation of the driven body (for its torque).
    normals : ndarray (nm, 2)
        Line-of-action unit vectors at the reference position (force on body a).
    source : str
    friction : LumpedFriction or None
        Tooth friction of ``[lubrication]`` (:mod:`~flexgear.dynamics.lumped.friction`); None:
        frictionless.
    cycles : int
        Mesh cycles the tables span (1 healthy; with faults or errors the period after which the
        faulty teeth meet again, :mod:`~flexgear.dynamics.lumped.faults`).
    gaps : dict
        {mesh name: mesh cycles of the tables' span} where the faults leave a loaded mesh without
        any tooth pair in contact (:func:`~flexgear.dynamics.lumped.faults.check_carried`).
    """

    model: Model
    system: LinearSystem
    G: np.ndarray
    k: np.ndarray
    e: np.ndarray
    c: np.ndarray
    backlash: np.ndarray
    drive_arm: np.ndarray
    normals: np.ndarray
    source: str
    reference_q: np.ndarray
    drive: int
    mesh_angle: float
    ratio: np.ndarray
    frame_angle: float = 0.0
    cycles: int = 1
    friction: object = None
    gaps: dict = field(default_factory=dict)


def _reduce(system: LinearSystem, T: np.ndarray, dofs: list) -> LinearSystem:
    """The system in coordinates q_full = T q (columns: the kept coordinates ``dofs``); springs
    left without deflection are dropped."""
    bodies = {k: (m, i, J @ T) for k, (m, i, J) in system.bodies.items()}
    springs = [type(s)(s.name, s.kind, s.k, s.g @ T) for s in system.springs if np.any(s.g @ T != 0.0)]
    return LinearSystem(dofs=list(dofs), bodies=bodies, springs=springs, planets=system.planets,
                        planet_angles=system.planet_angles, central=system.central, attrs=system.attrs)


def _reduction(model: Model, full: LinearSystem, drive_dof: str, rotational: bool):
    """T (n_full, n_kept) and the kept coordinate names: the driven body's rotation removed; with
    ``rotational``, the translations removed too, those of bodies on a parent's pin (planets on
    the carrier) slaved to the pin so that they still move with the parent's rotation."""
    dofs = full.dofs
    keep = [d for d in dofs if d != drive_dof and (not rotational or d.endswith(".theta"))]
    col = {d: j for j, d in enumerate(keep)}
    T = np.zeros((len(dofs), len(keep)))
    for i, d in enumerate(dofs):
        if d in col:
            T[i, col[d]] = 1.0
    if rotational:
        for b in model.bodies:
            if b.joint != BEARING or b.parent < 0 or f"{b.name}.x" not in dofs:
                continue
            p = model.bodies[b.parent]
            Jp = full.bodies[p.name][2] @ T  # parent pose per kept coordinate
            th = full.attrs["q"][dofs.index(f"{p.name}.theta")] if f"{p.name}.theta" in dofs else p.theta0
            rx = math.cos(th) * b.pin[0] - math.sin(th) * b.pin[1]
            ry = math.sin(th) * b.pin[0] + math.cos(th) * b.pin[1]
            T[dofs.index(f"{b.name}.x")] = Jp[0] - ry * Jp[2]
            T[dofs.index(f"{b.name}.y")] = Jp[1] + rx * Jp[2]
    return T, keep


def _default_backlash(cfg, model: Model, mesh) -> float:
    """(thinning_a + thinning_b) cos(alpha_w): the circular thinning along the line of action."""
    from ...gears.geometry import GearPair

    ga = cfg.gears[model.bodies[mesh.a].attrs["gear"]]
    gb = cfg.gears[model.bodies[mesh.b].attrs["gear"]]
    return (ga.thinning + gb.thinning) * math.cos(GearPair(ga, gb).alpha_w)


def _pair_name(cfg, model: Model, mesh) -> str:
    if cfg.kind == "spur":
        return "pinion-wheel"
    return "sun-planet" if mesh.name.startswith("sun-") else "planet-ring"


def _equivalent_mass(system: LinearSystem, g: np.ndarray) -> float:
    """Mass seen along a mesh's line of action, 1 / (g^T M^-1 g) [kg]."""
    return 1.0 / float(g @ np.linalg.solve(system.M, g))


def _align(pattern: np.ndarray, series: np.ndarray) -> np.ndarray:
    """``series`` shifted circularly to best match ``pattern`` (same length)."""
    p = pattern - pattern.mean()
    s = series - series.mean()
    scores = [float(np.dot(p, np.roll(s, k))) for k in range(len(s))]
    return np.roll(series, int(np.argmax(scores)))


def build_lumped(cfg) -> LumpedModel:
    """The lumped model of a validated configuration with ``model = "lumped"``."""
    from ..model.assembly import build_model

    from .friction import build_friction, check_lumped_friction

    opts = cfg.lumped or {}
    check_lumped_faults(cfg)
    check_lumped_friction(cfg)
    if opts.get("parameters") is not None:
        return build_explicit_lumped(cfg)
    source = opts.get("mesh_stiffness", "contact")
    model = build_model(dataclasses.replace(cfg, faults=(), errors=None))  # healthy: faults enter below
    full = linearise(model, n_positions=opts.get("positions", 48), free_drive=True)
    drive = next(i for i, b in enumerate(model.bodies) if b.speed is not None)
    dname = f"{model.bodies[drive].name}.theta"
    T, kept = _reduction(model, full, dname, opts.get("dofs", "planar") == "rotational")
    system = _reduce(full, T, kept)
    meshes = [s for s in full.springs if s.kind == "mesh"]
    nm = len(model.meshes)
    G = np.array([s.g @ T for s in meshes])
    drive_arm = np.array([s.g[full.dofs.index(dname)] for s in meshes])
    cyc = full.attrs["cycle"]
    P = cyc["k"].shape[1]
    k = np.zeros((nm, P))
    e = np.zeros((nm, P))
    c = np.zeros((nm, P))
    zeta = opts.get("damping_ratio", 0.03)
    series = source_stiffness(cfg, model, cyc)
    if series is not None and cfg.contact.get("damping_ratio") is not None:
        warnings.warn(f"[contact] damping_ratio = {cfg.contact['damping_ratio']:g} damps the contact law; with "
                      f"[lumped] mesh_stiffness = {source!r} the lumped meshes take [lumped] damping_ratio = {zeta:g}",
                      stacklevel=user_stacklevel())
    for m, mesh in enumerate(model.meshes):
        if series is None:
            k[m] = cyc["k"][m]
            e[m] = cyc["deflection"][m] - cyc["force"][m] / cyc["k"][m]
            c[m] = cyc["damping"][m]
            ratio = c[m].mean() / (2.0 * math.sqrt(k[m].mean() * _equivalent_mass(system, G[m]))) if np.any(G[m]) \
                else 0.0
            if ratio > OVERDAMPED:
                warnings.warn(f"mesh {mesh.name}: [contact] C gives the lumped mesh a damping ratio of {ratio:.3g} at "
                              "its static load; the lumped model's linear mesh keeps so strong a damper through "
                              "contact loss, where it chatters and can diverge (the spur preset at 1.5 times its "
                              "torque); for a lumped study give [contact] damping_ratio (e.g. 0.05) instead of C",
                              stacklevel=user_stacklevel())
            continue
        k[m] = series[mesh.name]
        m_eq = _equivalent_mass(system, G[m]) if np.any(G[m]) else 0.0
        c[m] = 2 * zeta * np.sqrt(k[m] * m_eq)
    bl = opts.get("backlash")
    backlash = np.array([bl if bl is not None else _default_backlash(cfg, model, mesh) for mesh in model.meshes])
    normals = np.array([full.attrs["mesh_normal"][mesh.name] for mesh in model.meshes])
    q0, v0 = model.initial_state()
    w0 = model.bodies[drive].omega0
    names0 = model.coordinate_names()
    ratio_full = np.array([v0[names0.index(d)] / w0 if d in names0 and w0 != 0 else (1.0 if d == dname else 0.0)
                           for d in full.dofs])
    lm = LumpedModel(model=model, system=system, G=G, k=k, e=e, c=c, backlash=backlash, drive_arm=drive_arm,
                     normals=normals, source=source, reference_q=full.attrs["q"], drive=drive,
                     mesh_angle=full.attrs["mesh_angle"], ratio=ratio_full,
                     frame_angle=float(full.attrs["q"][full.dofs.index("carrier.theta")])
                     if "carrier.theta" in full.dofs else 0.0)
    lm = apply_faults(cfg, lm, cyc["force"])
    lm.friction = build_friction(cfg, lm, full, T, dname)
    return lm


def build_explicit_lumped(cfg) -> LumpedModel:
    """The lumped model of a configuration with ``[gears]`` and ``[lumped.parameters]``: the gear
    set gives the kinematics (speeds, mesh frequency, body and mesh names of the results), the
    explicit parameters (:func:`flexgear.dynamics.lumped.planetary.explicit_parameters`) the masses,
    inertias, radii, pressure angles and the constant mesh stiffnesses; the supports are those
    of ``[supports]``. Each mesh is a spring of constant stiffness on the drive flank and, past
    the backlash, on the back flank; its damping follows ``lumped.damping_ratio``."""
    from ..model.assembly import build_model
    from .planetary import explicit_parameters, planetary_system

    opts = cfg.lumped
    if not cfg.gears:
        raise ConfigError("[lumped.parameters] without [gears]: a time-domain run needs the tooth counts (input, "
                          "carrier and mesh frequencies, mesh phasing); add [gears], [drive], [load] and "
                          "[simulation] as in the presets, or use `flexgear modal` for the parameter set alone")
    model = build_model(dataclasses.replace(cfg, faults=(), errors=None))  # healthy: faults enter below
    p = explicit_parameters(cfg, free_drive=True)
    drive = next(i for i, b in enumerate(model.bodies) if b.speed is not None)
    dname = f"{model.bodies[drive].name}.theta"
    if opts.get("dofs", "planar") == "rotational":  # planets on their pins, central members not translating
        p.rigid_pins = True
        p.held |= {f"{c}.{x}" for c in ("sun", "ring", "carrier") for x in "xy"}
    full = planetary_system(p)
    kept = [d for d in full.dofs if d != dname]
    T = np.zeros((len(full.dofs), len(kept)))
    for j, d in enumerate(kept):
        T[full.dofs.index(d), j] = 1.0
    system = _reduce(full, T, kept)
    by_name = {sp.name: sp for sp in full.springs if sp.kind == "mesh"}
    meshes = [by_name[mesh.name] for mesh in model.meshes]
    G = np.array([sp.g @ T for sp in meshes])
    drive_arm = np.array([sp.g[full.dofs.index(dname)] if dname in full.dofs else 0.0 for sp in meshes])
    k = np.array([[sp.k] for sp in meshes])
    c = np.array([[2 * opts["damping_ratio"] * math.sqrt(sp.k * _equivalent_mass(system, g))] if np.any(g) else [0.0]
                  for sp, g in zip(meshes, G)])
    bl = opts.get("backlash")
    backlash = np.array([bl if bl is not None else _default_backlash(cfg, model, mesh) for mesh in model.meshes])
    psi = p.angles()
    normals = []
    for mesh in model.meshes:  # unit vector of the force on body a (sun-planet: the sun; planet-ring: the planet)
        n = int(mesh.name.split("planet")[1].split("-")[0]) - 1
        er, et = np.array([math.cos(psi[n]), math.sin(psi[n])]), np.array([-math.sin(psi[n]), math.cos(psi[n])])
        if mesh.name.startswith("sun-"):
            normals.append(-(math.sin(p.alpha_sun) * er + math.cos(p.alpha_sun) * et))
        else:
            normals.append(-(math.sin(p.alpha_ring) * er - math.cos(p.alpha_ring) * et))
    q0, v0 = model.initial_state()
    names0 = model.coordinate_names()
    w0 = model.bodies[drive].omega0
    ratio = np.array([v0[names0.index(d)] / w0 if d in names0 and w0 != 0 else (1.0 if d == dname else 0.0)
                      for d in full.dofs])
    ic = next(i for i, b in enumerate(model.bodies) if b.name == "carrier")
    return LumpedModel(model=model, system=system, G=G, k=k, e=np.zeros_like(k), c=c, backlash=backlash,
                       drive_arm=drive_arm, normals=np.array(normals), source="explicit parameters (constant)",
                       reference_q=np.zeros(len(full.dofs)), drive=drive,
                       mesh_angle=2 * math.pi * model.attrs["input_frequency"] / model.attrs["mesh_frequency"],
                       ratio=ratio, frame_angle=model.bodies[ic].theta0)


def source_stiffness(cfg, model: Model, cycle: dict) -> dict | None:
    """Each mesh's stiffness [N/m] at the linearisation's positions over the mesh cycle
    (``cycle``: its ``count`` of pairs in contact and ``force``) from ``[lumped]
    mesh_stiffness`` = iso6336, fe or constant, by mesh name; None for ``contact`` (the
    linearisation's own tangent). The lumped model's springs, and its modal analysis's."""
    opts = cfg.lumped or {}
    source = opts.get("mesh_stiffness", "contact")
    if source == "contact":
        return None
    P = cycle["count"].shape[1]
    out, fe_cache = {}, {}
    for m, mesh in enumerate(model.meshes):
        pair = _pair_name(cfg, model, mesh)
        count = cycle["count"][m]
        if source == "constant":
            out[mesh.name] = np.full(P, float(opts["constant_stiffness"][pair]))
        elif source == "iso6336":
            out[mesh.name] = _iso_mean(cfg, model, mesh) * count / count.mean()
        elif source == "fe":
            if pair not in fe_cache:
                fe_cache[pair] = _fe_series(cfg, model, mesh, float(cycle["force"][m].mean()), P)
            k_fe, n_fe = fe_cache[pair]
            shift = int(np.argmax([np.dot(count - count.mean(), np.roll(n_fe - n_fe.mean(), s)) for s in range(P)]))
            out[mesh.name] = np.roll(k_fe, shift)
        else:
            raise ConfigError(f"lumped.mesh_stiffness = {source!r}: must be contact, iso6336, fe or constant")
    return out


def _iso_mean(cfg, model, mesh) -> float:
    from ...stiffness.iso6336 import pair_stiffness

    ga = cfg.gears[model.bodies[mesh.a].attrs["gear"]]
    gb = cfg.gears[model.bodies[mesh.b].attrs["gear"]]
    ps = pair_stiffness(ga.z, gb.z, ga.module, min(ga.face_width, gb.face_width), internal=gb.internal,
                        alpha=ga.pressure_angle, x1=ga.x, x2=gb.x, ha=ga.ha, hf=ga.hf)
    return ps.k_mesh


def _fe_series(cfg, model, mesh, force: float, P: int):
    """FE mesh stiffness and pairs in contact over one mesh cycle, resampled to P positions."""
    from ...gears.geometry import GearPair
    from ...stiffness.loaded_mesh import loaded_mesh

    ga = cfg.gears[model.bodies[mesh.a].attrs["gear"]]
    gb = cfg.gears[model.bodies[mesh.b].attrs["gear"]]
    ms = loaded_mesh(GearPair(ga, gb), force, material=cfg.material, formulation=cfg.fe["formulation"])
    x = np.arange(len(ms.k_mesh)) / len(ms.k_mesh)
    xp = np.arange(P) / P
    kk = np.interp(xp, x, ms.k_mesh, period=1.0)
    npairs = np.interp(xp, x, ms.n_pairs.astype(float), period=1.0)
    return kk, npairs


# ---------------------------------------------------------------------------------------------
# compiled time loop


# ---------------------------------------------------------------------------------------------


def at_speed(lm: LumpedModel, input_frequency: float) -> LumpedModel:
    """The same lumped model driven at a constant ``input_frequency`` [Hz] (speed sweeps: the
    static positions, stiffness and phasing do not depend on speed). Initial speeds of all
    bodies and the model's characteristic frequencies are scaled with it."""
    import copy
    import dataclasses

    if not input_frequency > 0:
        raise ConfigError(f"input_frequency = {input_frequency!r}: must be > 0 Hz")
    old = lm.model.attrs["input_frequency"]
    s = input_frequency / old
    model = copy.copy(lm.model)
    model.bodies = [dataclasses.replace(b, omega0=b.omega0 * s) for b in lm.model.bodies]
    d = model.bodies[lm.drive]
    d.speed = Profile.make(2 * math.pi * input_frequency * (1.0 if d.omega0 >= 0 else -1.0))
    model.attrs = dict(lm.model.attrs, input_frequency=input_frequency,
                       carrier_frequency=lm.model.attrs["carrier_frequency"] * s,
                       mesh_frequency=lm.model.attrs["mesh_frequency"] * s)
    return dataclasses.replace(lm, model=model)
