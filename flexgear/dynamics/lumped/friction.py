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
from ...gears.tribology import FrictionParameters, friction_coefficient_slopes, friction_parameters
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
    position. ``width`` [m]: the face width in contact; ``params``: the friction law."""

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


class MeshFriction(NamedTuple):
    """The friction of the meshes as the time loop takes it (:class:`LumpedFriction` plus the
    drive speed at every step)."""

    params: FrictionParameters
    speed: np.ndarray  # (steps + 1,) drive speed [rad/s]
    s0: np.ndarray
    rate: np.ndarray
    pitch: np.ndarray
    s_lo: np.ndarray
    s_hi: np.ndarray
    h0: np.ndarray
    h1: np.ndarray
    vn0: np.ndarray
    vn1: np.ndarray
    ue0: np.ndarray
    ue1: np.ndarray
    ra0: np.ndarray
    rb0: np.ndarray
    sigma: np.ndarray
    width: np.ndarray


class FrictionWork(NamedTuple):
    """Scratch and per-step outputs of :func:`friction_forces`."""

    h: np.ndarray  # (n,) h(s) of one pair
    force: np.ndarray  # (nm, MAX_PAIRS) friction force mu N of each pair [N] (0: no pair)
    sliding: np.ndarray  # (nm, MAX_PAIRS) sliding speed [m/s] (nan: no pair)
    position: np.ndarray  # (nm, MAX_PAIRS) contact position s [m] (nan: no pair)


class FrictionRecords(NamedTuple):
    """The friction time loop's records, one row per step (LumpedRecords plus the pairs)."""

    q: np.ndarray
    v: np.ndarray
    force: np.ndarray
    deflection: np.ndarray
    friction: np.ndarray  # (steps, nm, MAX_PAIRS) [N]
    sliding: np.ndarray  # (steps, nm, MAX_PAIRS) [m/s]
    position: np.ndarray  # (steps, nm, MAX_PAIRS) [m]


def simulates_friction(cfg) -> bool:
    """Whether ``cfg``'s ``[lubrication]`` puts friction into the model (a constant coefficient of
    0 is the frictionless model, bit for bit)."""
    lub = cfg.lubrication
    return lub is not None and not (lub.friction_model == "constant" and lub.friction_coefficient == 0.0)


def check_lumped_friction(cfg) -> None:
    """Raise ConfigError, before any long computation, for friction the lumped model cannot take:
    explicit ``[lumped.parameters]`` (no tooth geometry, no path of contact) and the squeeze-film
    damping (the lumped mesh damping is ``lumped.damping_ratio`` or the IMPACT damping)."""
    lub = cfg.lubrication
    if lub is None:
        return
    if lub.damping != "impact":
        raise ConfigError(f"lubrication.damping = {lub.damping!r} with model = 'lumped': the lumped model takes "
                          "its mesh damping from [contact] or lumped.damping_ratio; use damping = 'impact'")
    if simulates_friction(cfg) and (cfg.lumped or {}).get("parameters") is not None:
        raise ConfigError("[lubrication] with [lumped.parameters]: the explicit parameters have no tooth geometry "
                          "to place the contacts and friction arms on; use the lumped model built from [gears] "
                          "(remove [lumped.parameters]) or drop [lubrication]")


def _cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _perp(a) -> np.ndarray:
    return np.array([-a[1], a[0]])


def build_friction(cfg, lm, full, T: np.ndarray, drive_dof: str) -> LumpedFriction | None:
    """The :class:`LumpedFriction` of the lumped model ``lm`` built from the linearised ``full``
    system (coordinates q_full = T q; ``drive_dof`` the driven rotation); None without friction."""
    if not simulates_friction(cfg):
        return None
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
    return LumpedFriction(params=params, h0=h0, h1=h1, tau=tau, **out)


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


def kernel_table(fr: LumpedFriction, speed: np.ndarray) -> MeshFriction:
    """The :class:`MeshFriction` of ``fr`` with the drive speed ``speed`` [rad/s] at every step."""
    return MeshFriction(fr.params, np.ascontiguousarray(speed, dtype=float), fr.s0, fr.rate, fr.pitch, fr.s_lo,
                        fr.s_hi, np.ascontiguousarray(fr.h0), np.ascontiguousarray(fr.h1), fr.vn0, fr.vn1, fr.ue0,
                        fr.ue1, fr.ra0, fr.rb0, fr.sigma, fr.width)


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


@kernel(fastmath=True, _nrt=False)
def add_friction(fr, system, phi, speed, q, v, F, kk, cc, fint, work, tangent_out):
    """Add each mesh's tooth friction (module docstring) at table position ``phi`` and drive speed
    ``speed`` [rad/s] for the mesh forces F (kk, cc: stiffness and damping of the meshes in
    contact; a back-flank or open mesh carries no friction) to the internal force ``fint``, and
    record every pair's force, sliding speed and position in ``work`` (a FrictionWork).
    ``tangent_out`` = (Kt, Ct) (n, n): their derivatives d/dq and d/dv are added (a 0-row Kt:
    none)."""
    G = system.mesh_gradient
    Kt, Ct = tangent_out
    tangent = Kt.shape[0] > 0
    n = q.shape[0]
    nm = G.shape[0]
    h = work.h
    for m in range(nm):
        for i in range(work.force.shape[1]):
            work.force[m, i] = 0.0
            work.sliding[m, i] = np.nan
            work.position[m, i] = np.nan
        pb = fr.pitch[m]
        base = fr.s0[m] + fr.rate[m] * phi
        j0 = math.ceil((fr.s_lo[m] - base) / pb)
        count = 0
        for i in range(work.force.shape[1]):
            if base + (j0 + i) * pb <= fr.s_hi[m]:
                count += 1
        if count == 0:
            continue
        Fm = F[m] if F[m] > 0.0 else 0.0
        share = 1.0 / count
        N = share * Fm
        w = N / fr.width[m]
        for i in range(count):
            s = base + (j0 + i) * pb
            vt = speed * (fr.vn0[m] + fr.vn1[m] * s)
            for j in range(n):
                h[j] = fr.h0[m, j] + s * fr.h1[m, j]
                vt += h[j] * v[j]
            work.sliding[m, i] = vt
            work.position[m, i] = s
            if N <= 0.0:
                continue
            ue = speed * (fr.ue0[m] + fr.ue1[m] * s)
            ra = fr.ra0[m] + s
            rb = fr.rb0[m] - fr.sigma[m] * s
            R = ra * rb / (rb + fr.sigma[m] * ra)
            mu, dmu_v, dmu_u, dmu_w = friction_coefficient_slopes(fr.params, m, vt, ue, w, R)
            f = mu * N
            work.force[m, i] = f
            for j in range(n):
                fint[j] += f * h[j]
            if not tangent:
                continue
            cv = dmu_v * N  # d f / d v_s
            cf = share * (mu + dmu_w * w)  # d f / d F_m
            ck = cf * kk[m]
            cd = cf * cc[m]
            for a in range(n):
                ha = h[a]
                if ha == 0.0:
                    continue
                for b in range(n):
                    Ct[a, b] += ha * (cv * h[b] + cd * G[m, b])
                    Kt[a, b] += ha * ck * G[m, b]
    return 0


def friction_records(lm, records: FrictionRecords, speed: np.ndarray, body: np.ndarray, mesh: np.ndarray,
                     out_every: int) -> dict:
    """The friction outputs of a run, and its friction put into the per-step ``body`` (drive
    torque) and ``mesh`` (Fx, Fy on body b) records in place.

    Returns a dict of per-step ``force`` (steps, nm): sum_j mu_j N_j [N], the force of body a on
    body b along the flank tangent, positive in the direction a slides on b (it changes sign at
    the pitch point); ``power`` (steps, nm): sum_j mu_j N_j v_s,j [W] >= 0, the power friction
    dissipates; ``through`` (steps, nm): |F| r_b,a |omega_a,rel| [W], the power the mesh
    transmits; and, at the output samples, ``sliding``, ``position`` and ``pair_force`` (nout,
    nm, MAX_PAIRS): each pair's sliding speed [m/s], contact position s [m] (nan: no pair) and
    friction force [N]."""
    fr = lm.friction
    f, vs, s = records.friction, records.sliding, records.position
    on = np.isfinite(s)
    s0 = np.where(on, s, 0.0)
    force = f.sum(axis=2)
    power = np.where(on, f * vs, 0.0).sum(axis=2)
    body[:, lm.drive, 6] += np.sum(f * (fr.hd0[None, :, None] + fr.hd1[None, :, None] * s0), axis=(1, 2))
    ic = next((i for i, b in enumerate(lm.model.bodies) if b.name == "carrier"), None)
    rot = body[:, ic, 2] - lm.frame_angle if ic is not None else np.zeros(len(force))
    c, sn = np.cos(rot)[:, None], np.sin(rot)[:, None]
    tx, ty = fr.tau[None, :, 0], fr.tau[None, :, 1]
    mesh[:, :, 1] += force * (c * tx - sn * ty)
    mesh[:, :, 2] += force * (sn * tx + c * ty)
    through = np.abs(records.force) * np.abs(speed)[:, None] * fr.through[None, :]
    sel = slice(out_every - 1, len(force), out_every)
    return {"force": force, "power": power, "through": through, "sliding": vs[sel].copy(),
            "position": s[sel].copy(), "pair_force": f[sel].copy()}
