"""Faults and errors in the lumped model: each mesh's stiffness, offset and damping tables over
the period after which its faulty or erroneous teeth meet again.

A healthy lumped mesh is one spring with k(phi), e(phi), c(phi) over one mesh cycle
(:mod:`~flexgear.dynamics.lumped.model`). With faults or errors the tables span L mesh cycles,
L the least common multiple of the tooth counts of the gears whose teeth differ (a tooth of
gear g meets the same line of action again after z_g mesh cycles), and at each tabulated
position the mesh is split into the tooth pairs the rigid engagement geometry puts on the path
of contact (:func:`~flexgear.gears.kinematics.flank_roll_angle`), each with an equal share of
the healthy stiffness (exact for the IMPACT law on involutes: every pair on the path has the
same penetration) and the healthy offset. A pair is then changed by

* the errors, as a displacement along the line of action: the material its two flanks gain
  towards each other (eccentricity and pin error: the shift of the toothing projected on the
  line of action; pitch errors: s r_b times the tooth's angle; profile errors and relief: the
  normal offset at the contact radius) lowers its offset;
* a crack on the tension side of the loaded flank: its stiffness times the FE single-pair ratio
  k_cracked / k_healthy at the static mesh force (:func:`~flexgear.stiffness.crack.crack_pair_stiffness`,
  cached in the user cache), slices in parallel for a partial face width;
* a spall, chip or missing tooth: the contact length lost on the modified outline (no contact
  where the material is gone; a spall floor is an offset by its depth; a partial face width a
  slice of its width).

A pair (or slice) whose offset exceeds the mesh deflection at the static mesh force is left
out (active set). Derivation and sources: the theory page *Lumped model*, section *Faults and
errors*. Healthy meshes keep their tables (repeated L times).
"""
from __future__ import annotations

import dataclasses
import math
from functools import reduce

import numpy as np

from ...config.faults import chip_low_radius, loaded_flanks, mesh_pairs
from ...errors import ConfigError
from ...files import user_cache_dir
from ...gears.faults import Chip, Crack, GearErrors, Missing, PinError, Spall
from ...stiffness.crack import crack_ratio_table
from ...gears.kinematics import contact_roll_range, flank_roll_angle, line_of_action, mate_flank



def live_faults(cfg) -> tuple[list, object]:
    """(faults of non-zero size, errors or None if all of zero size)."""
    faults = [f for f in cfg.faults if not f.null]
    errors = cfg.errors if cfg.errors is not None and not cfg.errors.null else None
    return faults, errors


def check_lumped_faults(cfg) -> None:
    """Raise ConfigError, before any long computation, for faults the lumped model cannot take:
    any with explicit ``[lumped.parameters]`` (no tooth geometry)."""
    faults, errors = live_faults(cfg)
    if not faults and errors is None:
        return
    if (cfg.lumped or {}).get("parameters") is not None:
        raise ConfigError("[[faults]] / [errors] with [lumped.parameters]: the explicit parameters have no tooth "
                          "geometry to place a fault or an error on; use the lumped model built from [gears] "
                          "(remove [lumped.parameters])")


def period_cycles(cfg, faults, errors) -> int:
    """Mesh cycles L after which every mesh's faulty and erroneous teeth are back in place: the
    least common multiple of the tooth counts of the bodies with a tooth fault, an eccentricity
    or pitch errors (1 for profile and pin errors alone, which are the same on every tooth)."""
    bodies = {f.body: f.gear for f in faults}
    if errors is not None:
        for body, ge in errors.gears.items():
            if any(x is not None and not x.null for x in (ge.eccentricity, ge.pitch)):
                bodies[body] = body if not body.startswith("planet") else "planet"
    return reduce(math.lcm, (cfg.gears[g].z for g in bodies.values()), 1)


def nominal_poses(model, drive: int, dth: np.ndarray) -> dict:
    """Nominal (rigid, kinematic) poses of the bodies with the driven body turned by ``dth`` [rad]
    from the initial state: name -> (x, y, theta) arrays."""
    q0, v0 = model.initial_state()
    names = model.coordinate_names()
    w0 = model.bodies[drive].omega0
    out = {}
    for i, b in enumerate(model.bodies):
        nm = f"{b.name}.theta"
        if i == drive:
            th = b.theta0 + dth
        elif nm in names:
            j = names.index(nm)
            th = q0[j] + (v0[j] / w0 if w0 != 0 else 0.0) * dth
        else:
            th = np.full_like(dth, b.theta0)
        if b.parent < 0:
            x, y = np.full_like(dth, b.pin[0]), np.full_like(dth, b.pin[1])
        else:
            px, py, pth = out[model.bodies[b.parent].name]
            x = px + np.cos(pth) * b.pin[0] - np.sin(pth) * b.pin[1]
            y = py + np.sin(pth) * b.pin[0] + np.cos(pth) * b.pin[1]
        out[b.name] = (x, y, th)
    return out


def _rot(v, ang):
    """Vectors (2,) or (n, 2) turned counter-clockwise by angles ``ang`` (n,)."""
    c, s = np.cos(ang), np.sin(ang)
    v = np.broadcast_to(v, (len(ang), 2))
    return np.column_stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]])


class _Tooth:
    """What one gear body's flank brings to the pairs of one mesh: faults, pitch angles, profile."""

    def __init__(self, body, gear, side, faults, ge: GearErrors):
        self.gear, self.side = gear, side
        self.faults = [f for f in faults if f.body == body]
        self.pitch = ge.pitch.angles(gear) if ge.pitch is not None and not ge.pitch.null else None
        self.profile = ge.profile if ge.profile is not None and not ge.profile.null else None
        self.ecc = ge.eccentricity.shift() if ge.eccentricity is not None and not ge.eccentricity.null else None

    def material(self, k, r):
        """Normal offset [m] (material added) of flank ``side`` of tooth k at radius r: pitch and
        profile errors."""
        d = 0.0
        if self.pitch is not None:
            d += self.side * self.gear.rb * self.pitch[k]
        if self.profile is not None:
            d += float(self.profile.offset(self.gear, r))
        return d

    def beyond(self, r, r_cut) -> bool:
        """Whether radius r lies beyond r_cut towards the tip."""
        return (r - r_cut) * (self.gear.ra - self.gear.rf) > 0.0


def _slices(tooth: _Tooth, k: int, r: float, xi: float, crack_ratio) -> list:
    """(stiffness factor, extra offset [m]) slices of the pair that tooth k of ``tooth`` is in,
    contact at radius r and roll angle xi; [(1, 0)] for a healthy tooth, [] if no contact."""
    out = [(1.0, 0.0)]
    for f in tooth.faults:
        if f.tooth != k:
            continue
        if isinstance(f, Missing):
            if f.height_fraction == 0.0 or tooth.beyond(r, tooth.gear.rf + f.height_fraction * (tooth.gear.ra - tooth.gear.rf)):
                return []
        elif f.flank != tooth.side:
            continue  # a fault on the unloaded flank (a crack there is closed by the bending)
        elif isinstance(f, Crack):
            rho = crack_ratio(f, xi)
            out = [(s * (f.width_fraction * rho + 1.0 - f.width_fraction), d) for s, d in out]
        elif isinstance(f, Chip):
            if tooth.beyond(r, chip_low_radius(tooth.gear, f)):
                out = [(s * (1.0 - f.width_fraction), d) for s, d in out if f.width_fraction < 1.0]
        elif isinstance(f, Spall):
            lo, hi = sorted((f.start_radius, f.end_radius))
            if lo <= r <= hi:
                w = f.width_fraction
                out = [x for s, d in out for x in ((s * (1.0 - w), d), (s * w, d + f.depth)) if x[0] > 0.0]
    return out


def _crack_ratios(cfg, pair, which: int, faults, load: float) -> dict:
    """Crack -> (roll angles, k_cracked / k_healthy) along the path of the cracked gear (``which``
    = 1 or 2 of ``pair``) from the crack FE at the mesh force ``load`` [N]
    (:func:`~flexgear.stiffness.crack.crack_ratio_table`, cached in the user cache)."""
    load = float(f"{load:.4g}")  # meshes of one pair under nearly the same force share a table
    return {f: crack_ratio_table(pair, f.depth, f.angle, load, cracked=which, level=cfg.fe["level"],
                                 formulation=cfg.fe["formulation"], material=cfg.material,
                                 cache_dir=user_cache_dir())
            for f in faults if isinstance(f, Crack) and not f.null}


def apply_faults(cfg, lm, force: np.ndarray):
    """The lumped model ``lm`` with the faults and errors of ``cfg`` in its mesh tables
    (module docstring); ``force`` (nm, P) is each mesh's static force [N] over one mesh cycle.
    Returns ``lm`` itself when every fault and error has zero size."""
    faults, errors = live_faults(cfg)
    if not faults and errors is None:
        return lm
    model = lm.model
    nm, P = lm.k.shape
    L = period_cycles(cfg, faults, errors)
    n = P * L
    dth = lm.mesh_angle * np.arange(n) / P
    poses = nominal_poses(model, lm.drive, dth)
    carrier = next((b.name for b in model.bodies if b.name == "carrier"), None)
    rot = (poses[carrier][2] - lm.frame_angle) if carrier else np.zeros(n)
    k, e, c = np.tile(lm.k, L), np.tile(lm.e, L), np.tile(lm.c, L)
    pairs = mesh_pairs(cfg)
    flanks = loaded_flanks(cfg)
    gears_err = errors.gears if errors is not None else {}
    pins = errors.pins if errors is not None else {}
    touched = {f.body for f in faults} | {b for b, ge in gears_err.items() if not ge.null}
    touched |= {b for b, p in pins.items() if not p.null}
    for m, mesh in enumerate(model.meshes):
        an, bn, pair = pairs[mesh.name]
        if an not in touched and bn not in touched:
            continue
        sa, sb = flanks[mesh.name]
        ta = _Tooth(an, pair.g1, sa, faults, gears_err.get(an, GearErrors()))
        tb = _Tooth(bn, pair.g2, sb, faults, gears_err.get(bn, GearErrors()))
        # crack stiffness ratios from the FE at this mesh's mean static force
        ratios = {}
        for which, t in ((1, ta), (2, tb)):
            if any(isinstance(f, Crack) for f in t.faults):
                ratios.update(_crack_ratios(cfg, pair, which, t.faults, float(np.mean(force[m]))))

        def crack_ratio(f, xi):
            roll, rho = ratios[f]
            return float(np.interp(xi, roll, rho))

        # line of action from a to b (global) at every position; rigid shifts of both toothings
        nab = -_rot(lm.normals[m], rot)
        shift = np.zeros((n, 2))
        for t, body, sign in ((ta, an, 1.0), (tb, bn, -1.0)):
            if t.ecc is not None:
                shift += sign * _rot(t.ecc, poses[body][2])
            pe = pins.get(body, PinError())
            if not pe.null:
                x, y, _ = poses[body]
                psi = np.arctan2(y, x)
                er = np.column_stack([np.cos(psi), np.sin(psi)])
                et = np.column_stack([-np.sin(psi), np.cos(psi)])
                shift += sign * (pe.radial * er + pe.tangential * et)
        rigid = np.einsum("ij,ij->i", nab, shift)  # material gained along the line of action [m]
        # teeth on the path of contact
        xa, ya, tha = poses[an]
        xb, yb, thb = poses[bn]
        beta = np.arctan2(yb - ya, xb - xa) if not pair.internal else np.arctan2(ya - yb, xa - xb)
        ga, gb = line_of_action(pair, beta, sa)
        xi_a = flank_roll_angle(pair.g1, np.arange(pair.g1.z)[None, :], sa, tha[:, None], ga[:, None])
        xi_b = flank_roll_angle(pair.g2, np.arange(pair.g2.z)[None, :], mate_flank(sa, pair.internal), thb[:, None],
                                gb[:, None])
        (a0, a1), _ = contact_roll_range(pair)
        on = (xi_a >= a0) & (xi_a <= a1)
        tan_aw = math.tan(pair.alpha_w)
        rb1, rb2 = pair.g1.rb, pair.g2.rb
        for p in range(n):
            teeth = np.nonzero(on[p])[0]
            if not len(teeth):
                continue
            share = 1.0 / len(teeth)
            slices = []
            changed = False
            for ka in teeth:
                x1 = xi_a[p, ka]
                x2 = ((rb1 * x1 + (rb2 - rb1) * tan_aw) if pair.internal else ((rb1 + rb2) * tan_aw - rb1 * x1)) / rb2
                kb = int(np.argmin(np.abs(xi_b[p] - x2)))
                r1, r2 = rb1 * math.hypot(1.0, x1), rb2 * math.hypot(1.0, x2)
                gained = rigid[p] + ta.material(ka, r1) + tb.material(kb, r2)
                sl = _slices(ta, ka, r1, x1, crack_ratio)
                sl = [(s1 * s2, d1 + d2) for s1, d1 in sl for s2, d2 in _slices(tb, kb, r2, x2, crack_ratio)]
                changed |= gained != 0.0 or sl != [(1.0, 0.0)]
                slices += [(s * share, d - gained) for s, d in sl]
            if not changed:
                continue
            k[m, p], e[m, p], c[m, p] = _mesh_at(k[m, p], e[m, p], c[m, p], slices, force[m, p % P])
    healthy_k = np.tile(lm.k, L)
    gaps = {mesh.name: int(np.sum((k[m] == 0.0) & (healthy_k[m] > 0.0) & (np.tile(force[m], L) > 0.0))) / P
            for m, mesh in enumerate(model.meshes)}
    return dataclasses.replace(lm, k=k, e=e, c=c, cycles=L, gaps={name: g for name, g in gaps.items() if g > 0})


def check_carried(lm) -> None:
    """Raise ConfigError, before the time loop, when the faults leave a loaded mesh of ``lm``
    without any tooth pair in contact over part of its tables (``lm.gaps``: a missing, chipped
    or deeply spalled tooth where its pair would carry the mesh alone). The lumped model keeps
    its pairs on the nominal path of contact: nothing holds the load there, and the gears
    would swing through the backlash into the back flanks, where in the gear (and the rigid
    model) the next pair takes the load a few micrometres early."""
    if not lm.gaps:
        return
    name, gap = max(lm.gaps.items(), key=lambda kv: kv[1])
    raise ConfigError(f"model = 'lumped' with [[faults]]: mesh {name} has no tooth pair in contact over {gap:.3g} "
                      f"mesh cycles of every {lm.cycles} (a missing, chipped or spalled tooth where its pair would "
                      "carry the load alone); the lumped model, its pairs fixed on the nominal path of contact, "
                      "holds nothing there and its gears would swing through the backlash into the back flanks. "
                      "Use the rigid model (model = 'rigid': the next pair engages early on the real outlines), "
                      "or a fault that leaves the pair some contact")


def _mesh_at(k0: float, e0: float, c0: float, slices: list, F0: float):
    """Stiffness, offset and damping of a mesh whose healthy values are k0, e0, c0, made of
    ``slices`` (stiffness share, offset change [m]), at the static mesh force F0 [N]: slices
    whose offset exceeds the static deflection carry nothing (active set)."""
    ks = np.array([s for s, _ in slices]) * k0
    es = e0 + np.array([d for _, d in slices])
    on = ks > 0.0
    while on.any():
        d = (F0 + np.sum(ks[on] * es[on])) / np.sum(ks[on])
        drop = on & (es > d)
        if not drop.any():
            break
        on &= ~(es >= es[drop].max())
    if not on.any() or k0 <= 0.0:
        return 0.0, e0, 0.0
    kk = float(np.sum(ks[on]))
    ee = e0 if np.all(es[on] == e0) else float(np.sum(ks[on] * es[on]) / kk)
    return kk, ee, c0 * kk / k0
