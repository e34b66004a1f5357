"""Tooth friction in the lumped model (``[lubrication]`` with ``model = "lumped"``).

Each mesh's normal force F (the spring of :mod:`~flexgear.dynamics.lumped.model`) is shared
equally by the tooth pairs on the path of contact, at s_j = s_0 + phi p_b + j p_b along the line
of action (s from the pitch point, positive towards gear a's tip; phi the mesh-cycle position,
:func:`contact_kinematics`). Pair j carries the friction force mu(v_s, u_e, w, R) F / n along
the flank tangent tau (perpendicular to the line of action) at its contact point P(s_j): on
gear a -mu N tau, on gear b +mu N tau, mu signed like the sliding speed
v_s = tau . (V_a(P) - V_b(P)) (:func:`flexgear.gears.tribology.friction_coefficient`: the
tanh regularisation of ``[lubrication] sliding_speed_scale``). Its generalised force is
-mu N h(s), h(s) = tau . (J_a(P) - J_b(P)) = h_0 + s h_1 the tangential counterpart of the mesh
gradient G: a force across the line of action on both centres and the moments mu N rho_a,
mu N rho_b with the friction arms rho = r_b tan(alpha_w) +- s, the distances of the contact from
the base tangent points (Vaishya & Singh 2001; He, Gunda & Singh 2007). v_s is the nominal
sliding speed plus h(s) . dq/dt; u_e, R and the arms are the nominal kinematics. Derivation and
limits: the theory page *Lumped model*, section *Tooth friction*.

With ``[lubrication] damping = "squeeze_film"`` the film's damping replaces the mesh damping of
the drive flank (:func:`film_damping`): c = sum_j c_sq(u_e, w_e, R) of the pairs at the elastic
load share w_e = k (delta - e) / (n L), as in the rigid model (the guide *Lubrication*).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ...config.faults import mesh_pairs
from ...errors import ConfigError
from ...gears.kinematics import contact_roll_range, flank_roll_angle, line_of_action
from ...gears.material import effective_modulus
from ...gears.tribology import (CONSTANT, FrictionParameters, coefficient_slopes_at, contact_constants,
                                friction_parameters, law_constants, squeeze_film_factor, squeeze_film_slopes)
from ...kernels import kernel
from .faults import nominal_poses

#: Tooth pairs a mesh can have on its path of contact at once (contact ratio below 3).
MAX_PAIRS = 3


@dataclass
class LumpedFriction:
    """Friction geometry of the lumped meshes (rows: meshes; ``n`` lumped coordinates).

    ``s0`` [m], ``rate`` [m per table period], ``pitch`` p_b, ``s_lo``, ``s_hi`` [m]: the pairs
    sit at s0 + rate phi + j p_b within [s_lo, s_hi]. ``h0``, ``h1`` (nm, n): h(s) = h0 + s h1.
    ``hd0``, ``hd1``: the same for the driven body's (removed) rotation [m/rad, 1/rad]. ``vn0``,
    ``vn1``, ``ue0``, ``ue1``: nominal sliding and entrainment speed [m/s] per rad/s of the drive,
    v = w (vn0 + vn1 s). ``ra0``, ``rb0`` [m], ``sigma`` (+1 external, -1 internal): arms
    rho_a = ra0 + s, rho_b = rb0 - sigma s. ``tau`` (nm, 2): the flank tangent at the reference
    position. ``width`` [m]: the face width in contact; ``params``: the friction law. ``film``
    (nm,): the squeeze-film factor [N s/m] of each mesh (:func:`~flexgear.gears.tribology.
    squeeze_film_factor`; 0: the mesh damping of [contact] or lumped.damping_ratio); ``rubs``:
    whether the teeth rub (False: a coefficient of 0, the squeeze film alone)."""

    params: FrictionParameters
    s0: np.ndarray
    rate: np.ndarray
    pitch: np.ndarray
    s_lo: np.ndarray
    s_hi: np.ndarray
    h0: np.ndarray
    h1: np.ndarray
    hd0: np.ndarray
    hd1: np.ndarray
    vn0: np.ndarray
    vn1: np.ndarray
    ue0: np.ndarray
    ue1: np.ndarray
    ra0: np.ndarray
    rb0: np.ndarray
    sigma: np.ndarray
    tau: np.ndarray
    width: np.ndarray
    through: np.ndarray  # (nm,) r_b,a |omega_a,rel| per rad/s of the drive: mesh power = F w through
    film: np.ndarray
    rubs: bool


class MeshFriction(NamedTuple):
    """The friction of the meshes as the time loop takes it (:class:`LumpedFriction` plus the
    drive speed at every step and the steps per output sample)."""

    params: FrictionParameters
    law: np.ndarray  # (nm, 2) the friction laws' constants (flexgear.gears.tribology.law_constants)
    speed: np.ndarray  # (steps + 1,) drive speed [rad/s]
    s0: np.ndarray
    rate: np.ndarray
    pitch: np.ndarray
    s_lo: np.ndarray
    s_hi: np.ndarray
    h0: np.ndarray
    h1: np.ndarray
    hd0: np.ndarray
    hd1: np.ndarray
    vn0: np.ndarray
    vn1: np.ndarray
    ue0: np.ndarray
    ue1: np.ndarray
    ra0: np.ndarray
    rb0: np.ndarray
    sigma: np.ndarray
    width: np.ndarray
    through: np.ndarray
    out_every: int  # steps per output sample (the pairs are recorded there)
    linear_tol: float  # the time loop's linearisation tolerance (time_loop.FRICTION_TOL)


class FrictionWork(NamedTuple):
    """The pairs of every mesh at one step (:func:`place_pairs`) and their friction at one state
    (:func:`friction_forces`); (nm, MAX_PAIRS) unless noted."""

    count: np.ndarray  # (nm,) int: pairs on the path of contact
    position: np.ndarray  # contact position s [m]
    nominal: np.ndarray  # nominal sliding speed [m/s]
    c0: np.ndarray  # the friction law's constants of the pair's u_e and R (contact_constants)
    c1: np.ndarray
    load: np.ndarray  # (nm,) normal force of each pair N = max(F, 0) / count [N]
    sliding: np.ndarray  # sliding speed [m/s]
    force: np.ndarray  # friction force mu N [N]
    dv: np.ndarray  # its slope d(mu N)/dv_s [N s/m]
    df: np.ndarray  # its slope d(mu N)/dF per unit mesh force F: (mu + w dmu/dw) / count [-]


class FrictionRecords(NamedTuple):
    """The friction time loop's records: LumpedRecords, per step the friction of each mesh and
    its part of the drive torque, at the output samples (every ``out_every`` steps) the pairs."""

    q: np.ndarray
    v: np.ndarray
    force: np.ndarray
    deflection: np.ndarray
    friction: np.ndarray  # (steps, nm) sum_j mu_j N_j [N]
    power: np.ndarray  # (steps, nm) sum_j mu_j N_j v_s,j [W]
    through: np.ndarray  # (steps, nm) |F| r_b,a |omega_a,rel| [W]
    torque: np.ndarray  # (steps,) the friction's part of the drive torque [N m]
    pair_force: np.ndarray  # (samples, nm, MAX_PAIRS) [N] (0: no pair)
    sliding: np.ndarray  # (samples, nm, MAX_PAIRS) [m/s] (nan: no pair)
    position: np.ndarray  # (samples, nm, MAX_PAIRS) [m] (nan: no pair)
    damping_power: np.ndarray  # (steps, nm) power the squeeze films dissipate [W] ((0, nm): no film)
    damping_force: np.ndarray  # (samples, nm) the squeeze film's part of the mesh force [N]


def friction_records_for(nsteps: int, out_every: int, nm: int, records, film: bool = False) -> FrictionRecords:
    """Zeroed :class:`FrictionRecords` of a run of ``nsteps`` steps sampled every ``out_every``
    around the LumpedRecords ``records`` (with ``film`` the squeeze film's records too); the
    pairs' sliding speeds and positions nan, which the slots of absent pairs keep."""
    ns = nsteps // out_every
    return FrictionRecords(*records, *(np.zeros((nsteps, nm)) for _ in range(3)), np.zeros(nsteps),
                           np.zeros((ns, nm, MAX_PAIRS)), *(np.full((ns, nm, MAX_PAIRS), np.nan) for _ in range(2)),
                           np.zeros((nsteps if film else 0, nm)), np.zeros((ns if film else 0, nm)))


def squeeze_film_damped(cfg) -> bool:
    """Whether ``cfg``'s ``[lubrication]`` replaces the mesh damping by the squeeze-film damping
    (``damping = "squeeze_film"``)."""
    return cfg.lubrication is not None and cfg.lubrication.damping == "squeeze_film"


def simulates_friction(cfg) -> bool:
    """Whether ``cfg``'s ``[lubrication]`` puts friction into the model (a constant coefficient of
    0 is the frictionless model, bit for bit)."""
    lub = cfg.lubrication
    return lub is not None and not (lub.friction_model == "constant" and lub.friction_coefficient == 0.0)


def friction_loop(cfg) -> bool:
    """Whether the lumped model of ``cfg`` has a :class:`LumpedFriction` (tooth friction or a
    squeeze film) and so runs the friction time loop, a kernel of its own."""
    return simulates_friction(cfg) or squeeze_film_damped(cfg)


def check_lumped_friction(cfg) -> None:
    """Raise ConfigError, before any long computation, for friction or a squeeze film the lumped
    model cannot take: explicit ``[lumped.parameters]`` (no tooth geometry, no path of contact)."""
    if ((simulates_friction(cfg) or squeeze_film_damped(cfg))
            and (cfg.lumped or {}).get("parameters") is not None):
        raise ConfigError("[lubrication] with [lumped.parameters]: the explicit parameters have no tooth geometry "
                          "to place the contacts, friction arms and films on; use the lumped model built from "
                          "[gears] (remove [lumped.parameters]) or drop [lubrication]")


def _cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _perp(a) -> np.ndarray:
    return np.array([-a[1], a[0]])


def build_friction(cfg, lm, full, T: np.ndarray, drive_dof: str) -> LumpedFriction | None:
    """The :class:`LumpedFriction` of the lumped model ``lm`` built from the linearised ``full``
    system (coordinates q_full = T q; ``drive_dof`` the driven rotation); None without friction
    and squeeze film."""
    if not friction_loop(cfg):
        return None
    rubs = simulates_friction(cfg)
    model = lm.model
    nm, n = lm.G.shape
    pairs = mesh_pairs(cfg)
    dofs = full.dofs
    jd = dofs.index(drive_dof)
    # body centres at the reference position (planets on the carrier at its reference angle)
    centre = {}
    for b in model.bodies:
        if b.parent < 0:
            centre[b.name] = np.asarray(b.pin, float)
        else:
            p = model.bodies[b.parent]
            th = lm.frame_angle if p.name == "carrier" else p.theta0
            c, s = math.cos(th), math.sin(th)
            centre[b.name] = centre[p.name] + np.array([c * b.pin[0] - s * b.pin[1], s * b.pin[0] + c * b.pin[1]])
    ratio = lm.ratio

    def turning(body):  # nominal angular velocity per rad/s of the drive (0: a held body)
        return ratio[dofs.index(f"{body}.theta")] if f"{body}.theta" in dofs else 0.0

    w_frame = turning("carrier")
    out = {k: np.zeros(nm) for k in ("s0", "rate", "pitch", "s_lo", "s_hi", "hd0", "hd1", "vn0", "vn1", "ue0",
                                     "ue1", "ra0", "rb0", "sigma", "width", "through")}
    h0, h1, tau = np.zeros((nm, n)), np.zeros((nm, n)), np.zeros((nm, 2))
    meshes = []
    for m, mesh in enumerate(model.meshes):
        an, bn, pair = pairs[mesh.name]
        meshes.append((model.bodies[mesh.a].attrs["gear"], model.bodies[mesh.b].attrs["gear"]))
        if (model.bodies[mesh.a].name, model.bodies[mesh.b].name) != (an, bn):
            raise ConfigError(f"mesh {mesh.name}: bodies {model.bodies[mesh.a].name}, {model.bodies[mesh.b].name} "
                              f"do not match the pair {an}, {bn}")
        rba, rbb, tw = pair.g1.rb, pair.g2.rb, math.tan(pair.alpha_w)
        sig = -1.0 if pair.internal else 1.0
        nv = np.asarray(lm.normals[m], float)
        Oa, Ob = centre[an], centre[bn]
        # the line of action: cross(n, P) = c, at distance r_b from both centres
        ca, cb = _cross(nv, Oa), _cross(nv, Ob)
        c = min((ca + rba, ca - rba), key=lambda x: abs(abs(x - cb) - rbb))
        Ta = Oa + (c - ca) * _perp(nv)
        Tb = Ob + (c - cb) * _perp(nv)
        es = (Tb - Ta) if not pair.internal else (Ta - Tb)
        es = es / np.linalg.norm(es)
        t = _perp(nv)
        Ja, Jb = full.bodies[an][2], full.bodies[bn][2]

        def h_full(s):
            P = Ta + (rba * tw + s) * es
            return t @ (Ja[:2] - Jb[:2]) + _cross(P - Oa, t) * Ja[2] - _cross(P - Ob, t) * Jb[2]

        g0, g1 = h_full(0.0), h_full(1.0) - h_full(0.0)
        h0[m], h1[m] = g0 @ T, g1 @ T
        out["hd0"][m], out["hd1"][m] = g0[jd], g1[jd]
        out["vn0"][m], out["vn1"][m] = g0 @ ratio, g1 @ ratio
        # entrainment speed: surface speeds along tau in the frame the centres stand still in
        wa = turning(an) - w_frame
        wb = turning(bn) - w_frame
        P0 = Ta + rba * tw * es
        ua0, ua1 = wa * _cross(P0 - Oa, t), wa * _cross(es, t)
        ub0, ub1 = wb * _cross(P0 - Ob, t), wb * _cross(es, t)
        out["ue0"][m], out["ue1"][m] = 0.5 * (ua0 + ub0), 0.5 * (ua1 + ub1)
        out["through"][m] = abs(wa) * rba
        tau[m] = t
        out["ra0"][m], out["rb0"][m], out["sigma"][m] = rba * tw, rbb * tw, sig
        out["width"][m] = pair.face_width
        out["pitch"][m] = pair.g1.pb
        (x0, x1), _ = contact_roll_range(pair)
        out["s_lo"][m], out["s_hi"][m] = rba * (x0 - tw), rba * (x1 - tw)
        out["s0"][m], out["rate"][m] = contact_kinematics(cfg, lm, m) * np.array([1.0, lm.cycles])
    e_star = effective_modulus(cfg.material, cfg.material)
    params = friction_parameters(cfg.lubrication, meshes, e_star)
    film = np.zeros(nm)
    if squeeze_film_damped(cfg):
        oil = cfg.lubrication.lubricant
        film = np.array([squeeze_film_factor(oil.viscosity, oil.pressure_viscosity, e_star, L) for L in out["width"]])
    return LumpedFriction(params=params, h0=h0, h1=h1, tau=tau, film=film, rubs=rubs, **out)


def contact_kinematics(cfg, lm, m: int) -> np.ndarray:
    """(s_0, ds/dphi) of mesh ``m``: the position [m] of a tooth pair on the path of contact of the
    initial state (the drive's rotation 0) and its rate per mesh cycle (+-p_b), from the
    engagement geometry of the rigid bodies (:func:`~flexgear.gears.kinematics.flank_roll_angle`)."""
    from ...config.faults import loaded_flanks

    model = lm.model
    mesh = model.meshes[m]
    an, bn, pair = mesh_pairs(cfg)[mesh.name]
    sa, _ = loaded_flanks(cfg)[mesh.name]
    dth = np.array([0.0, 0.25 * lm.mesh_angle])
    poses = nominal_poses(model, lm.drive, dth)
    xa, ya, tha = poses[an]
    xb, yb, _ = poses[bn]
    beta = np.arctan2(yb - ya, xb - xa) if not pair.internal else np.arctan2(ya - yb, xa - xb)
    ga, _ = line_of_action(pair, beta, sa)
    xi = flank_roll_angle(pair.g1, np.arange(pair.g1.z)[None, :], sa, tha[:, None], ga[:, None])
    (x0, x1), _ = contact_roll_range(pair)
    k = int(np.argmin(np.abs(xi[0] - 0.5 * (x0 + x1))))
    tw = math.tan(pair.alpha_w)
    s = pair.g1.rb * (xi[:, k] - tw)
    rate = (s[1] - s[0]) / 0.25
    pb = pair.g1.pb
    if abs(abs(rate) - pb) > 1e-6 * pb:
        raise ConfigError(f"mesh {mesh.name}: the contact moves {abs(rate):.6g} m per mesh cycle, not the base pitch "
                          f"{pb:.6g} m (inconsistent kinematics)")
    return np.array([s[0], math.copysign(pb, rate)])


def kernel_table(fr: LumpedFriction, speed: np.ndarray, out_every: int, linear_tol: float) -> MeshFriction:
    """The :class:`MeshFriction` of ``fr`` with the drive speed ``speed`` [rad/s] at every step,
    recording the pairs every ``out_every`` steps, linearised to ``linear_tol``."""
    return MeshFriction(fr.params, law_constants(fr.params), np.ascontiguousarray(speed, dtype=float), fr.s0,
                        fr.rate, fr.pitch, fr.s_lo, fr.s_hi, np.ascontiguousarray(fr.h0), np.ascontiguousarray(fr.h1),
                        fr.hd0, fr.hd1, fr.vn0, fr.vn1, fr.ue0, fr.ue1, fr.ra0, fr.rb0, fr.sigma, fr.width, fr.through,
                        int(out_every), float(linear_tol))


def pair_positions(fr: LumpedFriction, m: int, phase: np.ndarray) -> np.ndarray:
    """(len(phase), MAX_PAIRS) contact positions s [m] of mesh ``m`` at table positions
    ``phase`` (nan: no pair), as the time loop places them."""
    base = fr.s0[m] + fr.rate[m] * np.asarray(phase, float)
    j0 = np.ceil((fr.s_lo[m] - base) / fr.pitch[m])
    out = np.full((len(base), MAX_PAIRS), np.nan)
    for i in range(MAX_PAIRS):
        s = base + (j0 + i) * fr.pitch[m]
        out[:, i] = np.where(s <= fr.s_hi[m], s, np.nan)
    return out


@kernel(fastmath=True, _nrt=False, inline="always")
def rolling(fr, m, s, speed):
    """(u_e, R): the entrainment speed [m/s] at drive speed ``speed`` [rad/s] and the relative
    radius of curvature [m] (the arms rho_a, rho_b: 1/R = 1/rho_a + sigma/rho_b) of a pair of
    mesh ``m`` at contact position ``s`` [m], from the nominal kinematics."""
    ra = fr.ra0[m] + s
    rb = fr.rb0[m] - fr.sigma[m] * s
    return speed * (fr.ue0[m] + fr.ue1[m] * s), ra * rb / (rb + fr.sigma[m] * ra)


@kernel(fastmath=True, _nrt=False, inline="always")
def place_pairs(fr, phi, speed, work):
    """Put each mesh's tooth pairs at table position ``phi`` and drive speed ``speed`` [rad/s]
    into ``work`` (a FrictionWork): their count, contact positions, nominal sliding speeds and
    the friction law's constants of their entrainment speeds and radii (fixed through a step)."""
    for m in range(fr.pitch.shape[0]):
        pb = fr.pitch[m]
        base = fr.s0[m] + fr.rate[m] * phi
        j0 = math.ceil((fr.s_lo[m] - base) / pb)
        count = 0
        for i in range(work.position.shape[1]):
            s = base + (j0 + i) * pb
            if s > fr.s_hi[m]:
                break
            count += 1
            work.position[m, i] = s
            work.nominal[m, i] = speed * (fr.vn0[m] + fr.vn1[m] * s)
            if fr.params.model[m] == CONSTANT:
                work.c0[m, i] = fr.params.mu[m]
                work.c1[m, i] = 0.0
                continue
            ue, R = rolling(fr, m, s, speed)
            c0, c1 = contact_constants(fr.params, m, fr.law[m], ue, R)
            work.c0[m, i] = c0
            work.c1[m, i] = c1
        work.count[m] = count


class FilmTable(NamedTuple):
    """The squeeze films of the meshes as the friction time loop takes them (:func:`film_table`),
    and their state at the step's linearisation point (:func:`film_meshes`); (nm,) unless noted."""

    factor: np.ndarray  # squeeze-film factor [N s/m] (tribology.squeeze_film_factor; 0: no film)
    damp: np.ndarray  # the mesh damping the step takes [N s/m] (the film's, or the tables')
    kt: np.ndarray  # the mesh stiffness of the step's tangent [N/m]
    elastic: np.ndarray  # the elastic mesh force k (delta - e) the film was taken at [N]
    slope: np.ndarray  # the film damping's slope there, dc/dF_e [s/m]


def film_table(fr: LumpedFriction | None) -> FilmTable:
    """The :class:`FilmTable` of ``fr``'s squeeze films; without films every array has length 0
    (the friction time loop tests that at run time: one compiled loop for runs with and without)."""
    if fr is None or not np.any(fr.film > 0.0):
        return FilmTable(*(np.zeros(0) for _ in FilmTable._fields))
    nm = len(fr.film)
    return FilmTable(np.ascontiguousarray(fr.film, dtype=float), *(np.zeros(nm) for _ in range(4)))


@kernel(fastmath=True, _nrt=False, inline="always")
def film_damping(fr, film, m, Fe, speed, work):
    """(c, dc/dF_e): the squeeze-film damping [N s/m] of mesh ``m``'s drive flank, the sum of its
    pairs' coefficients (:func:`~flexgear.gears.tribology.squeeze_film_slopes` at each pair's
    entrainment speed and relative radius at drive speed ``speed`` [rad/s], its position from
    :func:`place_pairs` in ``work``) at the elastic load share w_e = F_e / (n L) of the elastic
    mesh force ``Fe`` [N], and its slope in F_e [s/m]. 0 where F_e <= 0: no film pressure
    without load."""
    count = work.count[m]
    if count == 0 or Fe <= 0.0:
        return 0.0, 0.0
    share = 1.0 / (count * fr.width[m])
    w = Fe * share
    c = 0.0
    dc = 0.0
    for i in range(count):
        ue, R = rolling(fr, m, work.position[m, i], speed)
        ci, _, dci = squeeze_film_slopes(film.factor[m], fr.params.v0[m], ue, w, R)
        c += ci
        dc += dci
    return c, dc * share


@kernel(fastmath=True, _nrt=False, inline="always")
def film_meshes(fr, film, system, q, v, kk, ee, cc, act, speed, work):
    """The mesh damping ``film.damp`` and tangent stiffness ``film.kt`` [N/m] the step takes at
    the state (q, v) and drive speed ``speed``: on a mesh with a squeeze film not on its back
    flank (``act`` >= 0) the film's damping c at the elastic force F_e = kk (delta - ee)
    (:func:`film_damping`; F_e and dc/dF_e kept in ``film``) and kt = kk (1 + d(delta)/dt
    dc/dF_e) (the film force c d(delta)/dt changes with the load); elsewhere the tables' damping
    ``cc`` and kk."""
    G = system.mesh_gradient
    n = q.shape[0]
    for m in range(G.shape[0]):
        film.damp[m] = cc[m]
        film.kt[m] = kk[m]
        if film.factor[m] == 0.0 or act[m] < 0:
            continue
        d = 0.0
        dd = 0.0
        for j in range(n):
            d += G[m, j] * q[j]
            dd += G[m, j] * v[j]
        Fe = kk[m] * (d - ee[m])
        c, dc = film_damping(fr, film, m, Fe, speed, work)
        film.elastic[m] = Fe
        film.slope[m] = dc
        film.damp[m] = c
        film.kt[m] = kk[m] * (1.0 + dd * dc)


@kernel(fastmath=True, _nrt=False, inline="always")
def linearised_film(film, system, v, kk, defl, act, F, fint, tol):
    """Carry the squeeze-film force of each film mesh in drive-flank contact (``act`` > 0), taken
    with the damping c_0 of the linearisation point (:func:`film_meshes`), to the state with
    velocities ``v`` and deflections ``defl`` along its tangent: add dc/dF_e (F_e - F_e0)
    d(delta)/dt to the mesh force ``F`` and its share to the internal force ``fint``. Returns
    whether every such F_e stayed within ``tol`` (relative) of F_e0; otherwise the step is
    linearised again at its solution."""
    G = system.mesh_gradient
    n = v.shape[0]
    within = True
    for m in range(G.shape[0]):
        if film.factor[m] == 0.0 or act[m] <= 0:
            continue
        Fe0 = film.elastic[m]
        dFe = kk[m] * defl[m] - Fe0
        if abs(dFe) > tol * abs(Fe0):
            within = False
        dd = 0.0
        for j in range(n):
            dd += G[m, j] * v[j]
        extra = film.slope[m] * dFe * dd
        if extra != 0.0:
            F[m] += extra
            for j in range(n):
                fint[j] += extra * G[m, j]
    return within


@kernel(fastmath=True, _nrt=False, inline="always")
def record_film(film, system, row, js, v, kk, F, defl, records):
    """Record step ``row``'s squeeze-film damping force F - kk defl of each film mesh in contact
    (0: open or on the back flank) and its power with the approach rate G v [W] in ``records``
    (a FrictionRecords window), the force also at output sample ``js`` (>= 0; -1: none)."""
    G = system.mesh_gradient
    n = v.shape[0]
    for m in range(G.shape[0]):
        if film.factor[m] == 0.0:
            continue
        fd = 0.0
        p = 0.0
        if F[m] > 0.0:
            fd = F[m] - kk[m] * defl[m]
            dd = 0.0
            for j in range(n):
                dd += G[m, j] * v[j]
            p = fd * dd
        records.damping_power[row, m] = p
        if js >= 0:
            records.damping_force[js, m] = fd


@kernel(fastmath=True, _nrt=False, inline="always")
def friction_forces(fr, v, F, fint, work):
    """Add the tooth friction (module docstring) of the pairs ``work`` holds (:func:`place_pairs`)
    at the velocities ``v`` and mesh forces F (a back-flank or open mesh carries none) to the
    internal force ``fint``; each pair's sliding speed, force and slopes into ``work``. Per mesh
    the pairs' h(s) = h0 + s h1 enter through h0 and h1 only: h0 . v, h1 . v once, fint += (sum f)
    h0 + (sum f s) h1."""
    h0 = fr.h0
    h1 = fr.h1
    n = v.shape[0]
    for m in range(h0.shape[0]):
        count = work.count[m]
        if count == 0:
            work.load[m] = 0.0
            continue
        a0 = 0.0
        a1 = 0.0
        for j in range(n):
            a0 += h0[m, j] * v[j]
            a1 += h1[m, j] * v[j]
        N = (F[m] if F[m] > 0.0 else 0.0) / count
        work.load[m] = N
        w = N / fr.width[m]
        ln_w = 0.0
        sqrt_w = 0.0
        if N > 0.0 and fr.params.model[m] != CONSTANT:
            ln_w = math.log(w)
            sqrt_w = math.sqrt(w)
        f0 = 0.0
        f1 = 0.0
        for i in range(count):
            s = work.position[m, i]
            vt = work.nominal[m, i] + a0 + s * a1
            work.sliding[m, i] = vt
            if N <= 0.0:
                work.force[m, i] = 0.0
                continue
            mu, dmu_v, dmu_w, _ = coefficient_slopes_at(fr.params, m, work.c0[m, i], work.c1[m, i], vt, w, ln_w,
                                                     sqrt_w)
            f = mu * N
            work.force[m, i] = f
            work.dv[m, i] = dmu_v * N
            work.df[m, i] = (mu + dmu_w * w) / count
            f0 += f
            f1 += f * s
        if f0 != 0.0 or f1 != 0.0:
            for j in range(n):
                fint[j] += f0 * h0[m, j] + f1 * h1[m, j]


@kernel(fastmath=True, _nrt=False, inline="always")
def linearised_friction(fr, dv, F, fint, work, tol):
    """Carry the friction :func:`friction_forces` put into ``work`` at a state x0 along its
    tangent to the state x0 + dx, and add it to the internal force ``fint``: each pair's sliding
    speed by h_j . dv (``dv`` the change of the velocities [m/s, rad/s]) and its force by
    d(mu N)/dv_s h_j . dv + d(mu N)/dF (F - F0) (``F`` the mesh forces at x0 + dx [N], F0 =
    count N0 those at x0). This is the friction the linearly implicit step solves with
    (:func:`~flexgear.dynamics.lumped.time_loop.integrate_lumped_friction`); a mesh that carried
    no friction at x0 (open, back flank, no pair) carries none.

    Returns whether every loaded pair stayed within ``tol`` of the scale its coefficient curves
    on (the linearisation's relative error is of the order of the square of the step):
    |d v_s| <= tol max(|v_s0|, v_0) and, for the load-dependent laws, |F - F0| <= tol F0."""
    h0 = fr.h0
    h1 = fr.h1
    n = dv.shape[0]
    within = True
    for m in range(h0.shape[0]):
        count = work.count[m]
        if count == 0:
            continue
        d0 = 0.0
        d1 = 0.0
        for j in range(n):
            d0 += h0[m, j] * dv[j]
            d1 += h1[m, j] * dv[j]
        N = work.load[m]
        if N <= 0.0:
            for i in range(count):
                work.sliding[m, i] += d0 + work.position[m, i] * d1
            continue
        dF = F[m] - N * count
        if fr.params.model[m] != CONSTANT and abs(dF) > tol * N * count:
            within = False
        v0 = tol * fr.params.v0[m]
        f0 = 0.0
        f1 = 0.0
        for i in range(count):
            s = work.position[m, i]
            dvs = d0 + s * d1
            vs = work.sliding[m, i]
            if abs(dvs) > max(tol * abs(vs), v0):
                within = False
            work.sliding[m, i] = vs + dvs
            f = work.force[m, i] + work.dv[m, i] * dvs + work.df[m, i] * dF
            work.force[m, i] = f
            f0 += f
            f1 += f * s
        for j in range(n):
            fint[j] += f0 * h0[m, j] + f1 * h1[m, j]
    return within


@kernel(fastmath=True, _nrt=False, inline="always")
def mesh_tangent(fr, system, kk, cc, act, sq, sv, work, A):
    """Add sq d/dq + sv d/dv of the meshes' forces, springs and friction, to the iteration
    matrix ``A`` (sq, sv: d q / d a and d v / d a of the step, times 1 + alpha): each mesh in
    contact (``act`` nonzero) F G, F = kk (G q - e) + cc G v (kk, cc: its stiffness and damping),
    and its pairs' friction sum_j f_j h_j from the slopes ``work`` holds
    (:func:`friction_forces`): f_j = mu_j N_j, N_j = F / count. Per mesh
    kc (G + u0 h0 + u1 h1) G^T, kc = sq kk + sv cc, u0 = sum_j df_j, u1 = sum_j df_j s_j (the
    friction tilts the mesh force off the line of action), and, where the coefficient changes
    with the sliding speed, sv sum_j dv_j h_j h_j^T = sv (h0 (a00 h0 + a01 h1)^T + h1 (a01 h0 +
    a11 h1)^T), a00, a01, a11 the sums of dv_j, dv_j s_j, dv_j s_j^2."""
    G = system.mesh_gradient
    h0 = fr.h0
    h1 = fr.h1
    n = G.shape[1]
    for m in range(G.shape[0]):
        if act[m] == 0:
            continue
        kc = sq * kk[m] + sv * cc[m]
        u0 = 0.0
        u1 = 0.0
        a00 = 0.0
        a01 = 0.0
        a11 = 0.0
        if work.load[m] > 0.0:
            for i in range(work.count[m]):
                s = work.position[m, i]
                d = work.dv[m, i]
                a00 += d
                a01 += d * s
                a11 += d * s * s
                u0 += work.df[m, i]
                u1 += work.df[m, i] * s
        for r in range(n):
            y = kc * (G[m, r] + u0 * h0[m, r] + u1 * h1[m, r])
            if y != 0.0:
                for c in range(n):
                    A[r, c] += y * G[m, c]
        if a00 != 0.0 or a01 != 0.0 or a11 != 0.0:
            for c in range(n):
                x0 = sv * (a00 * h0[m, c] + a01 * h1[m, c])
                x1 = sv * (a01 * h0[m, c] + a11 * h1[m, c])
                for r in range(n):
                    A[r, c] += h0[m, r] * x0 + h1[m, r] * x1


@kernel(fastmath=True, _nrt=False, inline="always")
def record_lumped_friction(fr, k, row, js, F, work, records):
    """Record the friction of step ``row`` (step index ``k`` of the run) in ``records`` (a
    FrictionRecords window starting at an output sample): each mesh's total, power, transmitted
    power and the drive torque, and, if the step is output sample ``js`` of the window (js >= 0;
    -1: none), the pairs on the path (the other slots keep :func:`friction_records_for`'s 0 and
    nan: no nan is stored in the fastmath loop, where it slowed every step)."""
    sp = fr.speed[k]
    torque = 0.0
    sample = js >= 0
    for m in range(fr.pitch.shape[0]):
        f0 = 0.0
        p = 0.0
        for i in range(work.count[m]):
            f = work.force[m, i]
            f0 += f
            p += f * work.sliding[m, i]
            torque += f * (fr.hd0[m] + fr.hd1[m] * work.position[m, i])
        records.friction[row, m] = f0
        records.power[row, m] = p
        records.through[row, m] = abs(F[m]) * abs(sp) * fr.through[m]
        if sample:
            for i in range(work.count[m]):
                records.pair_force[js, m, i] = work.force[m, i]
                records.sliding[js, m, i] = work.sliding[m, i]
                records.position[js, m, i] = work.position[m, i]
    records.torque[row] = torque


def friction_records(lm, records: FrictionRecords, body: np.ndarray) -> dict:
    """The friction outputs of a run, and its friction put into the per-step ``body`` record's
    drive torque in place (the friction in the meshes' Fx, Fy:
    :func:`~flexgear.dynamics.lumped.time_loop.simulate_lumped`, from ``force``).

    Returns a dict of per-step ``force`` (steps, nm): sum_j mu_j N_j [N], the force of body a on
    body b along the flank tangent, each pair's with the sign of its sliding speed (it changes sign at
    the pitch point); ``power`` (steps, nm): sum_j mu_j N_j v_s,j [W] >= 0, the power friction
    dissipates; ``through`` (steps, nm): |F| r_b,a |omega_a,rel| [W], the power the mesh
    transmits; and, at the output samples, ``sliding``, ``position`` and ``pair_force`` (nout,
    nm, MAX_PAIRS): each pair's sliding speed [m/s], contact position s [m] (nan: no pair) and
    friction force [N]."""
    force = records.friction
    body[:, lm.drive, 6] += records.torque
    return {"force": force, "power": records.power, "through": records.through, "sliding": records.sliding,
            "position": records.position, "pair_force": records.pair_force}
