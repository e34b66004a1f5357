"""Flexible gears in the multi-body model: reductions -> flank compliance tables -> compliant meshes.

For each gear in ``[flexible] gears`` the cached Craig-Bampton reduction of
:func:`flexgear.reduction.gear.reduce_gear` becomes a
:class:`~flexgear.dynamics.model.bodies.FlexBody` of every body carrying that gear (the planets
share one), and every mesh with a flexible gear gets the compliant line-contact Hertz law of
:mod:`flexgear.dynamics.flexible.compliant`. The law changes because the paper's IMPACT law
stands for the whole tooth pair: in series with the FE compliance it would count the teeth twice;
the local Hertz approach is exactly what the FE tables leave out. The IMPACT damping stays.

Modes below ``[flexible] dynamic_cutoff`` are modal coordinates
(:mod:`flexgear.dynamics.flexible.floating_frame`); those up to ``cutoff`` are condensed
(integrated in the contact solve or quasi-static), the rest are in the residual tables. The
static compliance couples every contact on a body, across its meshes too
(:func:`cross_mesh_coupling`). Gears without backlash bend the back flank towards the mate, so
the flexible model searches the back-flank contacts the rigid outlines leave just open
(``search_gap``); mesh signals sum the magnitudes of all tooth pairs. See the theory pages
*Reduction and residual tables* and *Compliant contact and condensation*.
"""
from __future__ import annotations

import math

import numpy as np

from ...config.faults import loaded_flanks, mesh_pairs
from ...errors import ConfigError
from ...gears.faults import Crack
from ...fe.meshing import MeshSettings, mesh_cache_dir
from ...gears.material import Material
from ...reduction.flank import SIDES
from ...reduction.gear import reduce_gear
from ...reduction.parallel import reduce_in_workers, start_workers
from ...stiffness.compliance import DEFAULT_DEPTH
from ...stiffness.hertz import plane_constants
from ..model.bodies import FlexBody, Model
from ..contact.laws import LAW_HERTZ


def flex_body(body: int, red, dynamic_cutoff: float = 0.0, modal_damping: float = 0.0) -> FlexBody:
    """Flank compliance data of body ``body`` from a :class:`~flexgear.reduction.gear.GearReduction`:
    the modes below ``dynamic_cutoff`` [Hz] as modal coordinates (A_i, omega_i^2, damping ratio
    ``modal_damping``, the frame-mode mass coupling), the others condensed (A_i / omega_i, and
    their quasi-static response to the frame's acceleration, sum_i A_i S_i / omega_i^2, when the
    interface is the frame's x, y, theta), residual self tables and residual tables between
    every pair of flanks."""
    rb = red.body
    nq = rb.n_interface
    freq = np.asarray(rb.frequencies, float)
    omega = 2.0 * math.pi * freq
    nd = int(np.count_nonzero(freq < dynamic_cutoff))
    shape = np.ascontiguousarray(red.modal[..., nq + nd:] / omega[nd:])  # (z, 2, J, n_modes - nd)
    t = red.tables
    if list(SIDES) != [1, -1]:
        raise ConfigError(f"flank sides {SIDES}: the kernels expect (+1, -1)")
    self_c = np.stack([t.self_residual[s] for s in SIDES], axis=1)  # (P, 2, J)
    z = red.modal.shape[0]
    Jc = t.coupling_radius.size
    if t.coupling.shape != (self_c.shape[0], 2, 2, z, Jc, Jc) or \
            not np.array_equal(t.radius[::t.coupling_stride], t.coupling_radius):
        raise ConfigError(f"{red.gear.name}: flank tables of shape {t.coupling.shape}; expected every tooth "
                          f"distance and both pairs of sides, ({self_c.shape[0]}, 2, 2, {z}, Jc, Jc), on every "
                          "k-th table radius")
    w_c = omega[nd:]
    dyn = {"condensed_omega": w_c.copy(), "condensed_damping": 2.0 * modal_damping * w_c,
           "condensed_coupling": np.zeros((3, w_c.size))}
    if nq == 3:  # the frame's inertia load on the condensed modes (interface tied rigidly to the frame)
        S = np.ascontiguousarray(rb.M[:nq, nq + nd:])  # (3, n_condensed): S_i
        dyn["condensed_coupling"] = S
        dyn["acceleration_shape"] = np.ascontiguousarray(shape @ (S / w_c).T)  # (z, 2, J, 3)
    if nd:
        if nq != 3:
            raise ConfigError(f"[flexible] dynamic_cutoff = {dynamic_cutoff:g} Hz: {red.gear.name} has {nq} "
                              "interface coordinates; modal coordinates need the interface tied rigidly to the "
                              "body frame (x, y, theta)")
        sl = slice(nq, nq + nd)
        w = omega[:nd]
        dyn.update(dynamic_shape=np.ascontiguousarray(red.modal[..., sl]),
                   stiffness=np.ascontiguousarray(rb.K[sl, sl]), mass=np.ascontiguousarray(rb.M[sl, sl]),
                   damping=np.diag(2.0 * modal_damping * w), frame_coupling=np.ascontiguousarray(rb.M[:nq, sl]),
                   frequencies=freq[:nd].copy())
    return FlexBody(body=body, radius=np.asarray(t.radius, float), shape=shape, self_compliance=self_c,
                    coupling=np.ascontiguousarray(t.coupling, dtype=float),
                    attrs={"gear": red.gear.name, "modes": int(rb.n_modes), "depth": float(t.depth),
                           "dynamic_modes": nd, "condensed_modes": int(rb.n_modes) - nd,
                           "first_mode_hz": float(rb.frequencies[0]) if rb.n_modes else math.nan},
                    **dyn)


def reduction_jobs(cfg, cache_dir=None) -> tuple[dict, object]:
    """``(jobs, cache)``: the keyword arguments of
    :func:`~flexgear.reduction.gear.reduce_gear` per flexible gear of ``cfg`` and the cache
    directory (default the per-user cache)."""
    fx = cfg.flexible
    settings = MeshSettings(level=fx["level"], order=fx["order"])
    material = cfg.material
    if fx["modulus_scale"] != 1.0:
        material = Material(E=material.E * fx["modulus_scale"], nu=material.nu, rho=material.rho)
    cache = mesh_cache_dir() if cache_dir is None else cache_dir
    jobs = {name: dict(gear=cfg.gears[name], material=material, settings=settings, cutoff=fx["cutoff"],
                       formulation=fx["formulation"], support=fx["ring_support"], n_bolts=fx["bolts"],
                       n_points=fx["table_points"], coupling_points=fx["coupling_points"])
            for name in fx["gears"]}
    for name in list(jobs):
        for body, faults in body_faults(cfg, name).items():
            jobs[body] = dict(jobs[name], faults=faults)
    return jobs, cache


def body_faults(cfg, name: str) -> dict:
    """The tooth faults of non-zero size of the bodies of flexible gear ``name`` of ``cfg``, by
    body (``sun``; ``planet2``, ...): such a body gets a reduction of its own, which carries them
    (:func:`flexgear.reduction.gear.reduce_gear`); the healthy planets share the gear's. Not a
    fault over part of the face width: the body stays healthy and the fault enters the compliant
    law (a crack as a series compliance, a spall or chip as slices:
    :mod:`flexgear.dynamics.model.tooth_laws`). Not a crack on a flank no mesh loads, whose faces
    stay closed (:func:`closed_crack`)."""
    out = {}
    for f in getattr(cfg, "faults", ()):
        if f.gear == name and not f.null and getattr(f, "width_fraction", 1.0) == 1.0 and not closed_crack(cfg, f):
            out.setdefault(f.body, []).append(f)
    return {body: tuple(fs) for body, fs in out.items()}


def loaded_body_flanks(cfg) -> dict:
    """Body -> the set of its flanks (+1 left, -1 right) that carry the static load in one of its
    meshes (:func:`~flexgear.config.faults.loaded_flanks`): both for a planet (the sun on one, the
    ring on the other), one for the other gears."""
    pairs = mesh_pairs(cfg)
    out: dict = {}
    for mesh, (fa, fb) in loaded_flanks(cfg).items():
        a, b, _ = pairs[mesh]
        out.setdefault(a, set()).add(fa)
        out.setdefault(b, set()).add(fb)
    return out


def closed_crack(cfg, fault) -> bool:
    """Whether ``fault`` is a crack on the fillet of a flank that no mesh of its body loads: the
    bending closes its faces and the tooth is as stiff as a healthy one (the rigid and lumped
    models apply a crack on its loaded flank only; a flexible gear is reduced without it)."""
    return (isinstance(fault, Crack) and not fault.null
            and fault.flank not in loaded_body_flanks(cfg).get(fault.body, {fault.flank}))


def flexible_crack_note(cfg) -> str:
    """What the flexible model does with the cracks of flexible gears that differ from an open
    slit loaded on its own flank (docs/theory/crack.md, *Which flank*): a crack on a flank no mesh
    loads is left out (closed); a planet's crack is open also where its tooth's other flank
    meshes, where the faces would close. "" if neither."""
    if not cfg.flexible or cfg.model == "lumped":
        return ""
    gears = set(cfg.flexible["gears"])
    out = []
    for i, f in enumerate(cfg.faults):
        if not isinstance(f, Crack) or f.null or f.gear not in gears or f.width_fraction != 1.0:
            continue
        if closed_crack(cfg, f):
            out.append(f"faults[{i}] ({f.label()}) is on the fillet of a flank no mesh of {f.body} loads: its faces "
                       "stay closed, so the flexible gear is reduced without it (the healthy body, as the rigid and "
                       "lumped models leave it out)")
        elif len(loaded_body_flanks(cfg).get(f.body, ())) > 1:
            out.append(f"faults[{i}] ({f.label()}): the flexible planet's crack is an open slit without contact "
                       "between its faces, so it also softens the tooth while its other flank meshes, where the faces "
                       "would close: the flexible model overstates the crack in that mesh, where the rigid and "
                       "lumped models leave it out (docs/theory/crack.md, Which flank)")
    return "; ".join(out)


def body_reduction(reductions: dict, body_name: str, gear_name: str):
    """The reduction of a body: its own (a faulty body) or its gear's, or None (a rigid gear)."""
    return reductions.get(body_name, reductions.get(gear_name))


def start_flexible_reductions(cfg, progress=None, cache_dir=None):
    """Start the reductions of the flexible gears that the cache lacks in worker processes
    (:func:`flexgear.reduction.parallel.start_workers`): a handle for
    :func:`reduce_flexible_gears` (``started``), or None."""
    if not cfg.flexible:
        return None
    jobs, cache = reduction_jobs(cfg, cache_dir)
    return start_workers(jobs, cache, progress)


def reduce_flexible_gears(cfg, progress=None, cache_dir=None, started=None) -> dict:
    """Reductions of the flexible gears of ``cfg`` (``[flexible]``), by gear name, and of each
    faulty body by its name (:func:`body_reduction`). The gears
    that the cache lacks are reduced in worker processes (:mod:`flexgear.reduction.parallel`;
    ``started``: those that :func:`start_flexible_reductions` started), then all loaded.

    Raises
    ------
    ConfigError
        A cutoff below the first clamped mode of a gear (no mode to condense means the
        setting is a mistake: the cutoff must lie above the first mode).
    """
    fx = cfg.flexible
    if not fx:
        return {}
    say = progress or (lambda s: None)
    jobs, cache = reduction_jobs(cfg, cache_dir)
    if started is None:
        failed = reduce_in_workers(jobs, cache, say)  # the gears the cache lacks, in parallel, into the cache
    else:
        failed = started.wait()
    out = {}
    for name in jobs:
        try:
            if name in failed:
                raise failed[name]
            red = reduce_gear(**jobs[name], cache_dir=cache, progress=say)
        except ConfigError as exc:
            raise ConfigError(f"[flexible] gear {name!r}: {exc}") from exc
        if red.body.n_modes == 0:
            raise ConfigError(f"flexible.cutoff = {fx['cutoff']:g} Hz: below the first clamped mode of "
                              f"{name}; the cutoff must lie above it (default 100 kHz)")
        out[name] = red
    return out


def check_frame_inertia(body, fbody: FlexBody) -> None:
    """The rigid mass and inertia of ``body`` must exceed what its modal coordinates carry
    (``diag(m, m, J) - S M_eta^-1 S^T`` positive definite, S the frame-mode mass coupling), else
    the mass matrix is indefinite.

    Raises
    ------
    ConfigError
        Naming the body, its mass and inertia and the modes' share (e.g. an inertia set in the
        configuration below the FE gear's).
    """
    S = fbody.frame_coupling
    schur = np.diag([body.mass, body.mass, body.inertia]) - S @ np.linalg.solve(fbody.mass, S.T)
    if np.linalg.eigvalsh(0.5 * (schur + schur.T)).min() <= 0.0:
        share = S @ np.linalg.solve(fbody.mass, S.T)
        raise ConfigError(f"[flexible] dynamic_cutoff = {fbody.frequencies.max():.4g} Hz and above: body "
                          f"{body.name!r} has mass {body.mass:.4g} kg and inertia {body.inertia:.4g} kg m^2, but its "
                          f"{fbody.modes} modal coordinates carry {share[0, 0]:.4g} kg and {share[2, 2]:.4g} kg m^2 of "
                          "the FE gear's: the mass matrix would be indefinite; give the gear at least the FE mass "
                          "and inertia (gears.<name>.mass, inertia) or lower dynamic_cutoff")


def hertz_parameters(cfg, ga, gb, depth_a: float, depth_b: float) -> dict:
    """Constants of the line-contact Hertz law of a mesh (plane strain, the configuration's
    material for both gears; see :func:`~flexgear.dynamics.contact.laws.hertz_line`)."""
    E1, nu1 = plane_constants(cfg.material, "plane_strain")
    return {"face_width": min(ga.face_width, gb.face_width), "hertz_a": 1.0 / (math.pi * E1),
            "hertz_b": 1.0 / (math.pi * E1), "nu_a": nu1, "nu_b": nu1, "e_star": 0.5 * E1,
            "depth_a": depth_a, "depth_b": depth_b, "rb_a": ga.rb, "rb_b": gb.rb}


def make_flexible(model: Model, cfg, progress=None, reductions: dict | None = None,
                  hertz_meshes: str = "flexible", started=None) -> Model:
    """Attach the flexible gears of ``cfg`` to a rigid ``model`` (in place; returned).

    Parameters
    ----------
    reductions : dict, optional
        Gear (or faulty body) name -> GearReduction (default: :func:`reduce_flexible_gears`).
    hertz_meshes : {"flexible", "all"}
        Which meshes get the compliant Hertz law: those with a flexible gear (default) or all
        (a rigid model with the flexible model's contact law, for comparisons of healthy sets:
        the per-tooth crack tables, built for the default, give the rigid meshes a factor of the
        IMPACT law, which the compliant law does not read).
    started : optional
        Reductions already started (:func:`start_flexible_reductions`).
    """
    if reductions is None:
        reductions = reduce_flexible_gears(cfg, progress, started=started)
    gap = cfg.flexible["search_gap"] if cfg.flexible else 0.0
    flex = []
    depth = {}
    for i, b in enumerate(model.bodies):
        red = body_reduction(reductions, b.name, b.attrs.get("gear"))
        if red is not None:
            fbody = flex_body(i, red, cfg.flexible.get("dynamic_cutoff", 0.0), cfg.flexible.get("modal_damping", 0.0))
            flex.append(fbody)
            depth[i] = fbody.attrs["depth"]
            a = fbody.attrs
            b.attrs["flexible"] = (f"{a['dynamic_modes']} modes as coordinates, {a['condensed_modes']} condensed "
                                   f"(first {a['first_mode_hz']/1e3:.3g} kHz)")
            if fbody.modes:
                b.attrs["mode_frequencies"] = [float(f) for f in fbody.frequencies]
                check_frame_inertia(b, fbody)
    model.flex = flex
    notes = model.attrs.setdefault("notes", [])
    for mesh in model.meshes:
        fa, fb = mesh.a in depth, mesh.b in depth
        if not (fa or fb) and hertz_meshes != "all":
            continue
        ga = cfg.gears[model.bodies[mesh.a].attrs["gear"]]
        gb = cfg.gears[model.bodies[mesh.b].attrs["gear"]]
        mesh.law = LAW_HERTZ
        mesh.attrs["flexible"] = bool(fa or fb)
        mesh.gap = gap if (fa or fb) else 0.0
        mesh.hertz = hertz_parameters(cfg, ga, gb, depth.get(mesh.a, DEFAULT_DEPTH * ga.module),
                                      depth.get(mesh.b, DEFAULT_DEPTH * gb.module))
        mesh.attrs["law"] = ("line-contact Hertz (plane strain) + FE flank compliance"
                             if (fa or fb) else "line-contact Hertz (plane strain), rigid flanks")
        mesh.attrs["damping_on"] = "rigid approach rate (IMPACT STEP ramp, C and d as configured)"
    if flex:
        notes.append("flexible meshes use the line-contact Hertz law with the FE flank compliance "
                     "(the paper's IMPACT K stands for the whole tooth pair and would count the teeth twice); "
                     "the IMPACT damping acts on the rigid approach")
    return model


def cross_mesh_coupling(red, tooth_a: int, side_a: int, tooth_b: int, side_b: int) -> float:
    """Largest |static compliance| between flank points of two flanks of one reduction (the
    condensed modes plus the residual tables, at the table radii: what the solver uses),
    relative to the largest static self compliance of the first [-]: the size of the coupling
    through a body's rim, e.g. between a planet's sun-mesh and ring-mesh teeth, half a turn
    apart on opposite flanks.

    Raises
    ------
    ConfigError
        For the same flank twice (that is the self compliance).
    """
    t = red.tables
    z = red.modal.shape[0]
    if side_a not in SIDES or side_b not in SIDES:
        raise ConfigError(f"sides {side_a!r}, {side_b!r}: must be +1 or -1")
    d = (tooth_a - tooth_b) % z
    if d == 0 and side_a == side_b:
        raise ConfigError(f"tooth {tooth_a}, side {side_a} twice: that is the self compliance")
    nq = red.body.n_interface
    omega = 2.0 * math.pi * red.body.frequencies
    ia, ib = SIDES.index(side_a), SIDES.index(side_b)
    k = t.coupling_stride  # at the coupling tables' radii
    A = red.modal[tooth_a % z, ia][::k, nq:] / omega
    B = red.modal[tooth_b % z, ib][::k, nq:] / omega
    cross = A @ B.T + t.coupling[tooth_b % t.period, ia, ib, d]
    return float(np.abs(cross).max() / t.self_static[side_a][tooth_a % t.period].max())
