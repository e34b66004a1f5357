"""The lumped-parameter model in the time domain (``model = "lumped"``), on the rigid model's
geometry.

Building (:func:`build_lumped`). The rigid model of the configuration is linearised about its
loaded static equilibrium at positions over one mesh cycle (:func:`flexgear.dynamics.modal.modal.
linearise`): that gives the mass matrix, the bearing and support springs and, for every mesh,
its line of action (gradient g: mesh deflection per coordinate) and, per position, the IMPACT
tangent stiffness, the static force, the deflection from the kinematic position and the
contact damping. The coordinates q are deviations from the nominal (kinematic) motion, in the
frame of the reference position (the carrier frame for a planetary set); speed effects
(centripetal, gyroscopic) are left out. Each mesh is a spring along its line of action with a
time-varying stiffness k(phi) over the mesh cycle phi, from the chosen source:

* ``contact``: the IMPACT law's tangent at the static positions, with the offset
  e(phi) = delta_0(phi) - F_0(phi) / k(phi), so that the mesh force k (delta - e) reproduces the
  rigid model's static load and deflection (transmission error) and its small-vibration
  stiffness; the damping is the IMPACT damping at the static penetration;
* ``iso6336``: ISO 6336-1 c_gamma_alpha b as the mean, shaped by the number of tooth pairs in
  contact on the real outlines (so the contact ratio and phasing are the geometry's);
* ``fe``: the FE loaded mesh stiffness over one base pitch (:mod:`flexgear.stiffness.loaded_mesh`)
  at the static mesh force, aligned with the same tooth-pair pattern;
* ``constant``: one stiffness per pair.

Mesh phasing comes from the geometry: every mesh's stiffness series is taken at the same drive
positions, so the sequence of tooth pairs of each planet's meshes is the real one. Backlash and
contact loss: the drive flank carries k (delta - e) > 0 for delta > e, the back flank
k (delta + e + b) < 0 for delta < -e - b, none in between (b: backlash along the line of
action; e mirrors the soft start of the power law on the back flank). The mesh cycle position follows the
driven body's rotation: phi(t) = (Theta(t) - Theta(0)) / (its rotation per mesh cycle).

Integration (:func:`simulate_lumped`): HHT-alpha with Newton iterations on the piecewise-linear
forces, compiled with numba; the records have the rigid solver's layout, so runs, results,
signals, plots and studies work unchanged.
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass

import numpy as np

from ...kernels import kernel
from ..model.bodies import ANGLE_SPRING, BEARING, MAXC, Model, Profile
from ..modal.modal import LinearSystem, linearise
from ..integrator.simulation import Integration
from ...errors import ConfigError


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
    k, e, c : ndarray (nm, P)
        Mesh stiffness [N/m], offset [m] and damping [N s/m] at P positions over a mesh cycle.
    backlash : ndarray (nm,)
        [m] along the line of action.
    drive_arm : ndarray (nm,)
        Mesh deflection per unit rotation of the driven body (for its torque).
    normals : ndarray (nm, 2)
        Line-of-action unit vectors at the reference position (force on body a).
    source : str
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

    opts = cfg.lumped or {}
    if opts.get("parameters") is not None:
        return build_explicit_lumped(cfg)
    source = opts.get("mesh_stiffness", "contact")
    model = build_model(cfg)
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
    fe_cache = {}
    for m, mesh in enumerate(model.meshes):
        pair = _pair_name(cfg, model, mesh)
        if source == "contact":
            k[m] = cyc["k"][m]
            e[m] = cyc["deflection"][m] - cyc["force"][m] / cyc["k"][m]
            c[m] = cyc["damping"][m]
            continue
        count = cyc["count"][m]
        if source == "constant":
            k[m] = opts["constant_stiffness"][pair]
        elif source == "iso6336":
            k[m] = _iso_mean(cfg, model, mesh) * count / count.mean()
        elif source == "fe":
            if pair not in fe_cache:
                fe_cache[pair] = _fe_series(cfg, model, mesh, float(cyc["force"][m].mean()), P)
            k_fe, n_fe = fe_cache[pair]
            shift = int(np.argmax([np.dot(count - count.mean(), np.roll(n_fe - n_fe.mean(), s)) for s in range(P)]))
            k[m] = np.roll(k_fe, shift)
        else:
            raise ConfigError(f"lumped.mesh_stiffness = {source!r}: must be contact, iso6336, fe or constant")
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
    return LumpedModel(model=model, system=system, G=G, k=k, e=e, c=c, backlash=backlash, drive_arm=drive_arm,
                       normals=normals, source=source, reference_q=full.attrs["q"], drive=drive,
                       mesh_angle=full.attrs["mesh_angle"], ratio=ratio_full,
                       frame_angle=float(full.attrs["q"][full.dofs.index("carrier.theta")])
                       if "carrier.theta" in full.dofs else 0.0)


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
    model = build_model(cfg)
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


@kernel(fastmath=True)
def _tables_at(ktab, etab, ctab, phi, kk, ee, cc):
    """Mesh stiffness, offset and damping of every mesh at the mesh-cycle position phi (periodic,
    linear between the P tabulated positions)."""
    P = ktab.shape[1]
    x = phi * P
    f = math.floor(x)
    w = x - f
    i = int(f) % P
    j = (i + 1) % P
    for m in range(ktab.shape[0]):
        kk[m] = (1.0 - w) * ktab[m, i] + w * ktab[m, j]
        ee[m] = (1.0 - w) * etab[m, i] + w * etab[m, j]
        cc[m] = (1.0 - w) * ctab[m, i] + w * ctab[m, j]


@kernel(fastmath=True)
def _mesh_state(q, v, G, kk, ee, cc, backlash, Kb, Cb, fint, F, defl, active):
    """Mesh forces F, contact states (1 drive flank, -1 back flank, 0 open) and deflections
    beyond the offset for the mesh stiffness kk, offset ee and damping cc, and the internal
    force fint = Kb q + Cb v + sum F_m G_m."""
    n = q.shape[0]
    nm = G.shape[0]
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += Kb[i, j] * q[j] + Cb[i, j] * v[j]
        fint[i] = s
    for m in range(nm):
        d = 0.0
        dd = 0.0
        for j in range(n):
            d += G[m, j] * q[j]
            dd += G[m, j] * v[j]
        k = kk[m]
        e = ee[m]
        c = cc[m]
        f = 0.0
        act = 0
        if d > e:
            f = k * (d - e) + c * dd
            if f > 0.0:
                act = 1
            else:
                f = 0.0
        elif d < -e - backlash[m]:
            f = k * (d + e + backlash[m]) + c * dd
            if f < 0.0:
                act = -1
            else:
                f = 0.0
        F[m] = f
        defl[m] = d - e
        active[m] = act
        if f != 0.0:
            for i in range(n):
                fint[i] += f * G[m, i]


@kernel(fastmath=True)
def _solve_spd(A, b, x):
    """Solve A x = b for symmetric positive definite A (Cholesky, in place on A)."""
    n = A.shape[0]
    for j in range(n):
        s = A[j, j]
        for k in range(j):
            s -= A[j, k] * A[j, k]
        d = math.sqrt(s)
        A[j, j] = d
        for i in range(j + 1, n):
            s = A[i, j]
            for k in range(j):
                s -= A[i, k] * A[j, k]
            A[i, j] = s / d
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= A[i, k] * x[k]
        x[i] = s / A[i, i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, n):
            s -= A[k, i] * x[k]
        x[i] = s / A[i, i]


@kernel(fastmath=True)
def integrate_lumped(q, v, a, k0, nsteps, h, alpha, phi, fext, M, Kb, Cb, G, ktab, etab, ctab, backlash,
                     max_newton, rec_q, rec_v, rec_F, rec_d, stats):
    """Advance (q, v, a) by nsteps steps of h from step index k0 (HHT-alpha).

    The forces are linear for a given contact state of the meshes, so each iteration solves the
    step exactly for the assumed states (taken from the previous step) and checks them at the
    new state; a change repeats the step with the new states (up to max_newton times).

    phi (total steps + 1,): mesh-cycle position at each step time; fext (total + 1, n):
    external generalised force. Records per step: rec_q, rec_v (nsteps, n); rec_F, rec_d
    (nsteps, nm) mesh force and deflection beyond the offset. stats: [steps, iterations,
    max iterations in a step, steps whose contact states kept changing]."""
    n = q.shape[0]
    nm = G.shape[0]
    beta = 0.25 * (1.0 - alpha) ** 2
    gam = 0.5 - alpha
    fint = np.zeros(n)
    fint_n = np.zeros(n)
    A = np.zeros((n, n))
    Kt = np.zeros((n, n))
    Ct = np.zeros((n, n))
    b = np.zeros(n)
    an = np.zeros(n)
    qp = np.zeros(n)
    vp = np.zeros(n)
    qq = np.zeros(n)
    vv = np.zeros(n)
    F = np.zeros(nm)
    defl = np.zeros(nm)
    act = np.zeros(nm, np.int64)
    new = np.zeros(nm, np.int64)
    kk = np.zeros(nm)
    ee = np.zeros(nm)
    cc = np.zeros(nm)
    _tables_at(ktab, etab, ctab, phi[k0], kk, ee, cc)
    _mesh_state(q, v, G, kk, ee, cc, backlash, Kb, Cb, fint_n, F, defl, act)
    c1 = 1.0 + alpha
    for s in range(nsteps):
        k = k0 + s
        _tables_at(ktab, etab, ctab, phi[k + 1], kk, ee, cc)
        for i in range(n):
            qp[i] = q[i] + h * v[i] + h * h * (0.5 - beta) * a[i]
            vp[i] = v[i] + h * (1.0 - gam) * a[i]
        it = 0
        settled = False
        while it < max_newton:
            it += 1
            # tangent and constant term of the forces for the assumed contact states
            for i in range(n):
                for j in range(n):
                    Kt[i, j] = Kb[i, j]
                    Ct[i, j] = Cb[i, j]
                b[i] = c1 * fext[k + 1, i] - alpha * (fext[k, i] - fint_n[i])
            for m in range(nm):
                if act[m] == 0:
                    continue
                km = kk[m]
                cm = cc[m]
                off = ee[m]
                if act[m] < 0:
                    off = -off - backlash[m]
                for i in range(n):
                    gi = G[m, i]
                    if gi == 0.0:
                        continue
                    b[i] += c1 * km * off * gi
                    for j in range(n):
                        Kt[i, j] += km * gi * G[m, j]
                        Ct[i, j] += cm * gi * G[m, j]
            for i in range(n):
                s1 = 0.0
                for j in range(n):
                    s1 += Kt[i, j] * qp[j] + Ct[i, j] * vp[j]
                    A[i, j] = M[i, j] + c1 * (beta * h * h * Kt[i, j] + gam * h * Ct[i, j])
                b[i] -= c1 * s1
            _solve_spd(A, b, an)
            for i in range(n):
                qq[i] = qp[i] + beta * h * h * an[i]
                vv[i] = vp[i] + gam * h * an[i]
            _mesh_state(qq, vv, G, kk, ee, cc, backlash, Kb, Cb, fint, F, defl, new)
            settled = True
            for m in range(nm):
                if new[m] != act[m]:
                    settled = False
                act[m] = new[m]
            if settled:
                break
        stats[1] += it
        if it > stats[2]:
            stats[2] = it
        if not settled:
            stats[3] += 1
        for i in range(n):
            q[i] = qq[i]
            v[i] = vv[i]
            a[i] = an[i]
            fint_n[i] = fint[i]
            rec_q[s, i] = qq[i]
            rec_v[s, i] = vv[i]
        for j in range(nm):
            rec_F[s, j] = F[j]
            rec_d[s, j] = defl[j]
        stats[0] += 1
    return 0


# ---------------------------------------------------------------------------------------------


def _drive_angle(profile: Profile, t: np.ndarray):
    """Angle turned since t = 0 [rad], speed [rad/s] and acceleration [rad/s^2] of a speed profile."""
    w = profile(t)
    ang = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
    acc = np.gradient(w, t) if len(t) > 1 else np.zeros_like(t)
    return ang, w, acc


def _ramp(t, ramp):
    if ramp <= 0:
        return np.ones_like(t)
    x = np.clip(t / ramp, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def simulate_lumped(lm: LumpedModel, t_end: float, h: float, out_every: int, alpha: float = -0.1,
                    max_newton: int = 12, progress=None, chunk_steps: int = 20000) -> Integration:
    """Integrate the lumped model from 0 to t_end; records in the rigid solver's layout.

    Parameters
    ----------
    t_end, h : float
        End time and step [s] (t_end / h steps, a multiple of out_every).
    out_every : int
        Steps per output sample (tooth-pair slots are sampled there).
    alpha : float
        HHT-alpha parameter in [-1/3, 0].
    max_newton : int
        Contact-state iterations per step.
    progress : callable(fraction) or None
    """
    model, sysl = lm.model, lm.system
    n = sysl.n
    nm = len(model.meshes)
    nsteps = int(round(t_end / h))
    nsteps -= nsteps % out_every
    t = np.arange(nsteps + 1) * h
    drive = model.bodies[lm.drive]
    ang, w, acc = _drive_angle(drive.speed, t)
    phi = ang / lm.mesh_angle
    # external forces: applied torques (ramped) and the inertia of the nominal acceleration
    M = sysl.M
    fext = np.zeros((nsteps + 1, n))
    for i, b in enumerate(model.bodies):
        if b.torque is not None and i != lm.drive:
            T = b.torque(t) * _ramp(t, b.torque_ramp)
            fext += np.outer(T, sysl.bodies[b.name][2][2])
    Kb = np.zeros((n, n))
    Cb = np.zeros((n, n))
    for s in sysl.springs:
        if s.kind != "mesh":
            Kb += s.k * np.outer(s.g, s.g)
    for i, b in enumerate(model.bodies):  # bearing and support damping
        if b.name in sysl.bodies and (b.joint == BEARING or b.rotation == ANGLE_SPRING):
            J = sysl.bodies[b.name][2]
            Cb += b.damping * (J[:2].T @ J[:2]) + b.torsional_damping * np.outer(J[2], J[2])
    q = np.zeros(n)
    v = np.zeros(n)
    a = np.zeros(n)
    G = np.ascontiguousarray(lm.G)
    rec_q = np.zeros((nsteps, n))
    rec_v = np.zeros((nsteps, n))
    rec_F = np.zeros((nsteps, nm))
    rec_d = np.zeros((nsteps, nm))
    stats = np.zeros(4, np.int64)
    compile_seconds = 0.0
    if not integrate_lumped.signatures:  # compile (or load numba's disk cache) apart from the timing
        t0 = _time.perf_counter()
        integrate_lumped(q.copy(), v.copy(), a.copy(), 0, 0, h, alpha, phi, fext, M, Kb, Cb, G, lm.k, lm.e, lm.c,
                         lm.backlash, max_newton, rec_q[:0], rec_v[:0], rec_F[:0], rec_d[:0], np.zeros(4, np.int64))
        compile_seconds = _time.perf_counter() - t0
    wall0 = _time.perf_counter()
    done = 0
    chunk = max(out_every, (chunk_steps // out_every) * out_every)
    while done < nsteps:
        k = min(chunk, nsteps - done)
        integrate_lumped(q, v, a, done, k, h, alpha, phi, fext, M, Kb, Cb, G, lm.k, lm.e, lm.c, lm.backlash,
                         max_newton, rec_q[done:done + k], rec_v[done:done + k], rec_F[done:done + k],
                         rec_d[done:done + k], stats)
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            from ...errors import DivergenceError

            bad = ~(np.all(np.isfinite(rec_q[done:done + k]), axis=1) & np.all(np.isfinite(rec_F[done:done + k]), axis=1))
            i = int(np.argmax(bad)) if bad.any() else k - 1
            last = np.nan_to_num(rec_F[done + i - 1]) if done + i > 0 else np.zeros(nm)
            worst = model.meshes[int(np.argmax(np.abs(last)))].name if nm else "-"
            raise DivergenceError(f"lumped simulation diverged: non-finite state at t = {(done + i + 1) * h:.6f} s, "
                                  f"mesh {worst!r} carrying the largest force the step before "
                                  f"({np.max(np.abs(last)) if nm else 0.0:.3g} N). A contact damping far above "
                                  "critical with contact loss can do this: lower [contact] C or the step")
        done += k
        if progress is not None:
            progress(done / nsteps)
    wall = _time.perf_counter() - wall0
    tt = t[1:]
    body, mesh = _records(lm, tt, ang[1:], w[1:], acc[1:], rec_q, rec_v, rec_F)
    nout = nsteps // out_every
    pair_f = np.zeros((nout, nm, MAXC, 2))
    pair_i = np.full((nout, nm, MAXC, 3), -1, np.int64)
    pair_i[:, :, :, 2] = 0
    sel = slice(out_every - 1, nsteps, out_every)
    Fo, do = rec_F[sel], rec_d[sel]
    pair_f[:, :, 0, 0] = np.abs(Fo)
    pair_f[:, :, 0, 1] = np.where(Fo != 0.0, np.abs(do), 0.0)
    on = Fo != 0.0
    pair_i[:, :, 0, 0] = np.where(on, 0, -1)
    pair_i[:, :, 0, 1] = np.where(on, 0, -1)
    pair_i[:, :, 0, 2] = np.where(Fo > 0, 1, np.where(Fo < 0, -1, 0))
    return Integration(h=h, nsteps=nsteps, out_every=out_every, mesh=mesh, body=body, pair_f=pair_f, pair_i=pair_i,
                       steps=int(stats[0]), newton=int(stats[1]), rejected=int(stats[3]), max_iter=int(stats[2]),
                       wall=wall, q=q, v=v, lumped=True, compile_seconds=compile_seconds)


def _records(lm: LumpedModel, t, ang, w, acc, rec_q, rec_v, rec_F):
    """Per-step body poses (x, y, theta, vx, vy, omega, torque) and mesh totals (F, Fx, Fy on b)
    in the global frame: nominal motion plus the deviations."""
    model, sysl = lm.model, lm.system
    nb_ = len(model.bodies)
    ns = len(t)
    body = np.zeros((ns, nb_, 7))
    # nominal angles and rates: theta0 + ratio * drive angle
    q0, v0 = model.initial_state()
    names = model.coordinate_names()
    w0 = model.bodies[lm.drive].omega0
    theta = np.zeros((ns, nb_))
    omega = np.zeros((ns, nb_))
    for i, b in enumerate(model.bodies):
        nm_ = f"{b.name}.theta"
        if i == lm.drive:
            theta[:, i] = b.theta0 + ang
            omega[:, i] = w
        elif nm_ in names:
            r = v0[names.index(nm_)] / w0 if w0 != 0 else 0.0
            theta[:, i] = q0[names.index(nm_)] + r * ang
            omega[:, i] = r * w
        else:
            theta[:, i] = b.theta0
        if b.name in sysl.bodies:
            J = sysl.bodies[b.name][2]
            theta[:, i] += rec_q @ J[2]
            omega[:, i] += rec_v @ J[2]
    # frame rotation: the carrier's nominal turn (planetary), none for a spur pair
    ic = next((i for i, b in enumerate(model.bodies) if b.name == "carrier"), None)
    rot = (theta[:, ic] - lm.frame_angle) if ic is not None else np.zeros(ns)
    c, s = np.cos(rot), np.sin(rot)
    pos = np.zeros((ns, nb_, 2))
    vel = np.zeros((ns, nb_, 2))
    for i, b in enumerate(model.bodies):
        if b.parent < 0:
            anchor = np.broadcast_to(np.asarray(b.pin, float), (ns, 2)).copy()
            avel = np.zeros((ns, 2))
        else:
            p = b.parent
            cp, sp = np.cos(theta[:, p]), np.sin(theta[:, p])
            rx = cp * b.pin[0] - sp * b.pin[1]
            ry = sp * b.pin[0] + cp * b.pin[1]
            anchor = pos[:, p] + np.stack([rx, ry], axis=1)
            avel = vel[:, p] + omega[:, p, None] * np.stack([-ry, rx], axis=1)
        dev = np.zeros((ns, 2))
        dvel = np.zeros((ns, 2))
        if b.joint == BEARING and b.name in sysl.bodies:
            J = sysl.bodies[b.name][2]
            # translation of the centre relative to its anchor, in the reference frame, turned
            ux = rec_q @ J[0] - (0.0 if b.parent < 0 else rec_q @ _anchor_row(lm, i, 0))
            uy = rec_q @ J[1] - (0.0 if b.parent < 0 else rec_q @ _anchor_row(lm, i, 1))
            vx = rec_v @ J[0] - (0.0 if b.parent < 0 else rec_v @ _anchor_row(lm, i, 0))
            vy = rec_v @ J[1] - (0.0 if b.parent < 0 else rec_v @ _anchor_row(lm, i, 1))
            dev = np.stack([c * ux - s * uy, s * ux + c * uy], axis=1)
            dvel = np.stack([c * vx - s * vy, s * vx + c * vy], axis=1)
        pos[:, i] = anchor + dev
        vel[:, i] = avel + dvel
    body[:, :, 0:2] = pos
    body[:, :, 2] = theta
    body[:, :, 3:5] = vel
    body[:, :, 5] = omega
    db = model.bodies[lm.drive]
    body[:, lm.drive, 6] = rec_F @ lm.drive_arm + db.inertia * acc
    mesh = np.zeros((ns, len(model.meshes), 3))
    mesh[:, :, 0] = np.abs(rec_F)  # normal force on either flank (pair_side tells which)
    nx = c[:, None] * lm.normals[None, :, 0] - s[:, None] * lm.normals[None, :, 1]
    ny = s[:, None] * lm.normals[None, :, 0] + c[:, None] * lm.normals[None, :, 1]
    mesh[:, :, 1] = -rec_F * nx
    mesh[:, :, 2] = -rec_F * ny
    return body, mesh


def _anchor_row(lm: LumpedModel, i: int, axis: int) -> np.ndarray:
    """Row of the anchor point's Jacobian (global axis) of body i in the lumped coordinates."""
    model, sysl = lm.model, lm.system
    b = model.bodies[i]
    p = model.bodies[b.parent]
    Jp = sysl.bodies[p.name][2]
    th = p.theta0  # the reference position's parent angle
    cp, sp = math.cos(th), math.sin(th)
    rx = cp * b.pin[0] - sp * b.pin[1]
    ry = sp * b.pin[0] + cp * b.pin[1]
    return Jp[0] - ry * Jp[2] if axis == 0 else Jp[1] + rx * Jp[2]


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
