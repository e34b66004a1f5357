"""From a configuration to a model: assembly rules, mesh phasing, bodies, supports, meshes.

Assembly rules (checked before anything runs; each error names the rule and the values):

* sun-planet and planet-ring centre distances agree (so tooth counts and shifts fit together);
* N planets can be equally spaced: (z_s + z_r) / N is an integer;
* neighbouring planets' tip circles do not overlap: 2 a sin(pi/N) > 2 r_a,planet;
* teeth are not pointed (checked by :class:`~flexgear.geometry.SpurGear`); undercut is reported.

Mesh phasing. For an external pair with gear A at the origin and gear B in the direction beta,
the phases Phi_A = z_A (theta_A - beta) / 2 pi and Phi_B = z_B (theta_B - beta - pi) / 2 pi
(mod 1; 0 when a tooth points along the centre line) satisfy Phi_A + Phi_B = 1/2 in every
centred (zero-load, backlash-centred) position. For a planet in a ring (direction psi from the
ring centre) Phi_P - Phi_R = 1/2 with Phi = z (theta - psi) / 2 pi. The initial angles are
chosen so; the sun angles that each planet requires must coincide, which is the assembly
condition written in angles.
"""
from __future__ import annotations

import math
import warnings

from .tooth_laws import tooth_law_table
from .bodies import (ANGLE_FIXED, ANGLE_FREE, ANGLE_PRESCRIBED, ANGLE_SPRING, BEARING, FIXED, REVOLUTE, Body,
                     MeshingPair, Model, Profile)
from ...config import Config
from ...gears.contact_tables import candidate_teeth, pack_gears
from ...errors import GeometryError, user_stacklevel
from ...gears.geometry import GearPair


def _frac(x: float) -> float:
    return x - math.floor(x)


def check_planetary(cfg: Config) -> list[str]:
    """Planetary assembly rules; raises GeometryError, returns notes (undercut, fillet contact)."""
    s, p, r = cfg.gears["sun"], cfg.gears["planet"], cfg.gears["ring"]
    N = cfg.planetary["planets"]
    sp, pr = GearPair(s, p), GearPair(p, r)
    a1, a2 = sp.centre_distance, pr.centre_distance
    if abs(a1 - a2) > 1e-6:
        raise GeometryError(
            f"planetary set does not fit: sun-planet centre distance {a1*1e3:.4f} mm differs from planet-ring "
            f"{a2*1e3:.4f} mm (z_s = {s.z}, z_p = {p.z}, z_r = {r.z}, x = {s.x}, {p.x}, {r.x}; for unshifted "
            f"gears z_r = z_s + 2 z_p is required)"
        )
    if (s.z + r.z) % N:
        raise GeometryError(
            f"{N} planets cannot be equally spaced: (z_s + z_r)/N = ({s.z} + {r.z})/{N} = {(s.z + r.z)/N:.4g} "
            "is not an integer"
        )
    gap = 2 * a1 * math.sin(math.pi / N) - 2 * p.ra if N > 1 else math.inf
    if gap <= 0:
        raise GeometryError(
            f"neighbouring planets overlap: tip circles of diameter {2*p.ra*1e3:.4g} mm on a {a1*1e3:.4g} mm "
            f"radius, {N} planets: centre spacing {2*a1*math.sin(math.pi/N)*1e3:.4g} mm <= tip diameter"
        )
    notes = sp.check() + pr.check()
    for g in (s, p):
        if g.undercut:
            notes.append(f"{g.name} ({g.z} teeth, x = {g.x}) is undercut by the generating rack")
    return notes


def _support(body: Body, spec, what: str):
    """Apply a support specification ('revolute', 'fixed' or an elastic table) to ``body``."""
    if isinstance(spec, dict):
        body.joint = BEARING
        body.stiffness = spec["stiffness"]
        body.damping = spec["damping"]
        if spec.get("torsional_stiffness") is not None:
            if body.rotation != ANGLE_FIXED:
                raise GeometryError(f"supports.{what}.torsional_stiffness applies only to a non-rotating body")
            body.rotation = ANGLE_SPRING
            body.torsional_stiffness = spec["torsional_stiffness"]
            body.torsional_damping = spec["torsional_damping"]
    elif spec == "fixed":
        body.joint = FIXED
    else:
        body.joint = REVOLUTE


def _gear_body(cfg: Config, name: str, body_name: str, gear_index: int, **kw) -> Body:
    g = cfg.gears[name]
    m, J = g.mass_properties(cfg.material.rho)
    mo, Jo = cfg.gear_mass[name]
    return Body(name=body_name, mass=mo if mo is not None else m, inertia=Jo if Jo is not None else J, gear=gear_index,
                attrs={"z": g.z, "gear": name, "mass_source": "given" if mo else "outline x face width x density"},
                **kw)


def fault_spec(cfg: Config, body: str):
    """``(faults, errors)`` of gear body ``body`` for :func:`~flexgear.gears.contact_tables.pack_gears`,
    or None when its contact tables are the healthy geometry's: no spall, chip or missing tooth
    of non-zero size across the whole face width, no profile or pitch errors, no eccentricity (a
    zero-size fault gives the healthy model, bit for bit). A spall or chip over part of the face
    width keeps the healthy outline (the outermost material); it enters the tooth's contact law
    (:mod:`~flexgear.dynamics.model.tooth_laws`)."""
    fs = tuple(f for f in cfg.faults if f.body == body and not f.null and f.kind in ("spall", "chip", "missing")
               and getattr(f, "width_fraction", 1.0) == 1.0)
    ge = cfg.errors.gears.get(body) if cfg.errors is not None else None
    live = ge is not None and any(e is not None and not e.null for e in (ge.profile, ge.eccentricity, ge.pitch))
    return (fs, ge) if fs or live else None


def _torque_profile(spec, sense: float) -> Profile:
    """Resisting torque: applied against the body's nominal rotation sense."""
    return Profile.make(spec, scale=-sense)


def build_model(cfg: Config, progress=None, reductions: dict | None = None) -> Model:
    """The multi-body model of a validated configuration (shafts of ``[shafts]``:
    :func:`flexgear.dynamics.model.shafts.attach_shafts`; flexible gears of ``[flexible]`` reduced
    or loaded from the cache, with ``progress(str)`` messages, or taken from ``reductions``
    (gear name -> GearReduction) when the caller holds them already:
    :func:`flexgear.dynamics.flexible.reductions.make_flexible`)."""
    started = None
    if getattr(cfg, "flexible", None) and reductions is None:
        from ..flexible.reductions import start_flexible_reductions

        # the reductions the cache lacks run in worker processes while the rigid model is built
        started = start_flexible_reductions(cfg, progress)
    try:
        c = cfg.contact
        ds = c["outline_spacing"]
        if cfg.kind == "spur":
            model = _build_spur(cfg, ds)
        else:
            model = _build_planetary(cfg, ds)
        model.tooth_laws = tooth_law_table(cfg, model)
        if getattr(cfg, "shafts", None):
            from .shafts import attach_shafts

            attach_shafts(model, cfg)
        if getattr(cfg, "flexible", None):
            from ..flexible.reductions import make_flexible

            make_flexible(model, cfg, progress, reductions=reductions, started=started)
    finally:
        if started is not None:
            started.close()
    return model


def _mesh(cfg: Config, name, ia, ib, ga, gb, pair: GearPair, a_dist: float) -> MeshingPair:
    law = cfg.contact_law(pair)
    return MeshingPair(name=name, a=ia, b=ib, internal=pair.internal, K=law.K, e=law.e, C=law.C, d=law.d,
                ncand_a=candidate_teeth(ga, gb, a_dist, pair.internal),
                ncand_b=candidate_teeth(gb, ga, a_dist, pair.internal),
                attrs={"z_a": ga.z, "z_b": gb.z, "kind": "internal" if pair.internal else "external",
                       "K": law.K, "e": law.e, "C": law.C, "d": law.d, "law": "ADAMS IMPACT",
                       "stiffness_reading": law.reading, "damping_ratio": law.zeta,
                       "damping_reading": law.damping_reading, "centre_distance": a_dist,
                       "contact_ratio": pair.contact_ratio})


def _build_spur(cfg: Config, ds) -> Model:
    g1, g2 = cfg.gears["pinion"], cfg.gears["wheel"]
    pair = GearPair(g1, g2)
    a = cfg.spur["centre_distance"] or pair.centre_distance
    beta = math.radians(cfg.spur["line_of_centres_deg"])
    tables = pack_gears([g1, g2], ds=ds, sdf_resolution=cfg.contact["sdf_resolution"],
                        faults=[fault_spec(cfg, "pinion"), fault_spec(cfg, "wheel")])
    drive, load = cfg.drive, cfg.load
    w_in = Profile.make(drive["speed_hz"], 2 * math.pi)
    names = {"pinion": 0, "wheel": 1}
    ratio = -g1.z / g2.z
    sense = {"pinion": 1.0, "wheel": -1.0}
    if drive["body"] == "wheel":
        sense = {"wheel": 1.0, "pinion": -1.0}
    w0 = float(w_in(0.0))
    th1 = 0.0
    phi_a = _frac(g1.z * (th1 - beta) / (2 * math.pi))
    th2 = beta + math.pi + 2 * math.pi * (0.5 - phi_a) / g2.z
    b1 = _gear_body(cfg, "pinion", "pinion", 0, pin=(0.0, 0.0), theta0=th1)
    b2 = _gear_body(cfg, "wheel", "wheel", 1, pin=(a * math.cos(beta), a * math.sin(beta)), theta0=th2)
    bodies = [b1, b2]
    for b in bodies:
        b.attrs["role"] = "driven (prescribed speed)" if b.name == drive["body"] else "loaded"
    db = bodies[names[drive["body"]]]
    db.rotation = ANGLE_PRESCRIBED
    db.speed = w_in
    if drive["body"] == "pinion":
        b1.omega0, b2.omega0 = w0, w0 * ratio
    else:
        b2.omega0, b1.omega0 = w0, w0 / ratio
    lb = bodies[names[load["body"]]]
    lb.torque = _torque_profile(load["torque"], sense[load["body"]])
    lb.torque_ramp = load["ramp"]
    for nm_, b in names.items():
        _support(bodies[b], cfg.supports[nm_], nm_)
    mesh = _mesh(cfg, "pinion-wheel", 0, 1, g1, g2, pair, a)
    model = Model(bodies=bodies, meshes=[mesh], tables=tables, length_scale=g1.rb,
                  attrs={"depth_limit": 0.25 * g1.module, "notes": pair.check(),
                         "input_frequency": cfg.input_frequency, "carrier_frequency": 0.0,
                         "mesh_frequency": g1.z * cfg.input_frequency if drive["body"] == "pinion"
                         else g2.z * cfg.input_frequency})
    return model


def _build_planetary(cfg: Config, ds) -> Model:
    notes = check_planetary(cfg)
    for n in notes:
        warnings.warn(n, stacklevel=user_stacklevel())
    s, p, r = cfg.gears["sun"], cfg.gears["planet"], cfg.gears["ring"]
    pc = cfg.planetary
    N = pc["planets"]
    a = GearPair(s, p).centre_distance
    # a planet whose tables differ from the healthy planet's is a gear of its own (index 3, 4, ...)
    specs = [fault_spec(cfg, "sun"), None, fault_spec(cfg, "ring")]
    planet_gear, geoms = {}, [s, p, r]
    for k in range(1, N + 1):
        spec = fault_spec(cfg, f"planet{k}")
        planet_gear[k] = 1 if spec is None else len(geoms)
        if spec is not None:
            geoms.append(p)
            specs.append(spec)
    tables = pack_gears(geoms, ds=ds, sdf_resolution=cfg.contact["sdf_resolution"], faults=specs)
    drive, load = cfg.drive, cfg.load
    zs, zp, zr = s.z, p.z, r.z
    # kinematics with the ring fixed: carrier/sun = zs/(zs+zr)
    w_in = Profile.make(drive["speed_hz"], 2 * math.pi)
    w0 = float(w_in(0.0))
    if drive["body"] == "sun":
        ws, wc = w0, w0 * zs / (zs + zr)
    elif drive["body"] == "carrier":
        wc, ws = w0, w0 * (zs + zr) / zs
    else:
        raise GeometryError(f"drive.body = {drive['body']!r}: with a fixed ring, drive the sun or the carrier")
    wp = wc - (ws - wc) * zs / zp
    th_r = 0.0
    psi0 = math.radians(pc["first_planet_angle_deg"])
    bodies = []
    # order: sun, carrier, planets, ring (parents first)
    sun = _gear_body(cfg, "sun", "sun", 0, pin=(0.0, 0.0))
    carrier = Body(name="carrier", mass=pc["carrier_mass"], inertia=pc["carrier_inertia"], joint=REVOLUTE,
                   rotation=ANGLE_FREE, theta0=0.0, omega0=wc, attrs={"role": "carrier", "z": 0})
    bodies += [sun, carrier]
    th_sun = []
    for k in range(N):
        psi = psi0 + 2 * math.pi * k / N
        phi_r = _frac(zr * (th_r - psi) / (2 * math.pi))
        th_p = psi + 2 * math.pi * (phi_r + 0.5) / zp
        phi_b = _frac(zp * (th_p - psi - math.pi) / (2 * math.pi))
        th_sun.append(psi + 2 * math.pi * (0.5 - phi_b) / zs)
        pin = (a * math.cos(psi), a * math.sin(psi))
        pe = cfg.errors.pins.get(f"planet{k + 1}") if cfg.errors is not None else None
        if pe is not None and not pe.null:  # carrier pin position error: radial out, tangential ahead
            pin = ((a + pe.radial) * math.cos(psi) - pe.tangential * math.sin(psi),
                   (a + pe.radial) * math.sin(psi) + pe.tangential * math.cos(psi))
        pl = _gear_body(cfg, "planet", f"planet{k + 1}", planet_gear[k + 1], parent=1, pin=pin, theta0=th_p, omega0=wp)
        pl.attrs["role"] = "planet"
        pl.attrs["pin_angle"] = psi
        _support(pl, cfg.supports["planets"], "planets")
        bodies.append(pl)
    # all planets must ask for the same sun angle (mod the sun's pitch)
    pitch_s = 2 * math.pi / zs
    ref = th_sun[0]
    for k, th in enumerate(th_sun[1:], start=2):
        d = (th - ref) / pitch_s
        if abs(d - round(d)) > 1e-6:
            raise GeometryError(f"planet {k} cannot mesh with the sun and ring at its equally spaced position "
                                f"(phase mismatch {abs(d - round(d)):.3f} pitch)")
    sun.theta0 = ref
    sun.omega0 = ws
    ring = _gear_body(cfg, "ring", "ring", 2, pin=(0.0, 0.0), theta0=th_r, rotation=ANGLE_FIXED)
    ring.attrs["role"] = "ring"
    _support(ring, cfg.supports["ring"], "ring")
    bodies.append(ring)
    _support(sun, cfg.supports["sun"], "sun")
    _support(carrier, cfg.supports.get("carrier", "revolute"), "carrier")
    sun.attrs["role"] = "sun"
    idx = {b.name: i for i, b in enumerate(bodies)}
    db = bodies[idx[drive["body"]]]
    db.rotation = ANGLE_PRESCRIBED
    db.speed = w_in
    db.attrs["role"] += ", driven (prescribed speed)"
    lb = bodies[idx[load["body"]]]
    if load["body"] == "ring":
        raise GeometryError("load.body = 'ring': the ring is fixed; load the carrier or the sun")
    lb.torque = _torque_profile(load["torque"], 1.0 if (ws if load["body"] == "sun" else wc) > 0 else -1.0)
    lb.torque_ramp = load["ramp"]
    sp, pr = GearPair(s, p), GearPair(p, r)
    meshes = []
    for k in range(N):
        ip = idx[f"planet{k + 1}"]
        meshes.append(_mesh(cfg, f"sun-planet{k + 1}", idx["sun"], ip, s, p, sp, a))
    for k in range(N):
        ip = idx[f"planet{k + 1}"]
        meshes.append(_mesh(cfg, f"planet{k + 1}-ring", ip, idx["ring"], p, r, pr, a))
    f_in = cfg.input_frequency
    f_s = f_in if drive["body"] == "sun" else f_in * (zs + zr) / zs
    f_c = f_s * zs / (zs + zr)
    return Model(bodies=bodies, meshes=meshes, tables=tables, length_scale=s.rb,
                 attrs={"depth_limit": 0.25 * s.module, "notes": notes, "input_frequency": f_in,
                        "carrier_frequency": f_c, "mesh_frequency": zr * f_c, "planet_pin_radius": a})
