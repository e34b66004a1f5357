"""Per-tooth changes of the contact laws: root cracks and faults over part of the face width, as a
:class:`~flexgear.dynamics.model.tables.ToothLawTable` for the force kernels. A rigid mesh's
IMPACT law takes a stiffness factor (and slices); the compliant law of a mesh with a flexible gear
a series compliance.

Root crack
    A crack leaves the outline as it is and makes its tooth more compliant. The pair of the
    cracked tooth follows F = kappa K delta^e with kappa(r) = rho(r)^e, rho the FE single-pair
    stiffness ratio k_cracked / k_healthy (:func:`flexgear.stiffness.crack.crack_ratio_table`) at
    the contact's roll angle on the cracked gear (r its distance from the gear's toothing centre;
    a ring's crack from the FE of the cracked ring with a planet, gear 2 of the planet-ring pair),
    taken at the mesh's nominal static force (:func:`nominal_mesh_force`). Since
    delta = (F / (kappa K))^(1/e), the pair's secant and tangent stiffness at any force scale by
    kappa^(1/e) = rho: the factor keeps the FE ratio at every load (the FE ratio itself changes
    with the load only through the Hertz term). It acts on contacts of the flank whose fillet the
    crack is in (their load opens it; the other flank's load closes it) and leaves the damping C.
    The choice against one factor per tooth or a series compliance: the theory page *Root crack*.

Root crack in a mesh with a flexible gear (compliant law)
    The compliant law (:mod:`flexgear.dynamics.flexible.compliant`) adds to the Hertz approach of
    the cracked tooth's contacts a series compliance c_s(r) [m/N]: ``h(F) + c_s F``, with
    c_s = 1 / k_partial - 1 / k_healthy from the same FE single-pair stiffnesses as the rigid
    factor (:func:`flexgear.stiffness.crack.crack_series_table`; k_partial = w k_cracked +
    (1 - w) k_healthy, slices in parallel), at the mesh's nominal static force and the flexible
    model's FE mesh level, order and formulation. Through the face width (w = 1) c_s is the
    cracked tooth's extra bulk compliance, independent of the load. It serves a crack of a rigid
    gear in such a mesh (the rigid tooth gains the crack's compliance) and a crack over part of
    the face width of a flexible gear (its FE body stays healthy: a plane body cannot hold a slit
    over part of its width); a flexible gear's crack through the face width is a slit in its FE
    body (:func:`flexgear.reduction.gear.reduce_gear`) and takes no table. A spall or chip over
    part of the face width takes the slices below in the compliant law too (a common approach,
    :func:`flexgear.dynamics.contact.laws.slice_approach`), on a healthy FE body.

Partial face width w < 1
    The faulty tooth is two slices in parallel with the same plane penetration: the faulty one of
    width w, the healthy one of width 1 - w, each with its share of K and C (the IMPACT law of the
    plane model is a force per face width times the width). A crack gives
    kappa = w rho^e + 1 - w; a spall or chip keeps the healthy outline in the contact tables
    (:func:`flexgear.gears.modified.tooth_outline` marks the points with ``width`` = 1 - w and
    ``recess``, the depth of the faulty slice below the outline), and the faulty slice's
    penetration is the outline's less the recess
    (:func:`flexgear.gears.modified.partial_width_force`).
"""
from __future__ import annotations

import math

import numpy as np

from ...config.mesh_damping import static_mesh_force
from ...errors import ConfigError
from ...gears.faults import Chip, Crack, Spall
from ...gears.geometry import FLANK, GearPair
from ...gears.modified import tooth_outline
from ...stiffness.crack import crack_ratio_table, crack_series_table
from .tables import ToothLawTable

#: Radii of a crack's factor table (the FE ratio is smooth along the path).
CRACK_RADII = 65


def flexible_gears(cfg) -> tuple:
    """Names of the flexible gears of ``cfg`` (empty for a rigid model)."""
    return tuple((getattr(cfg, "flexible", None) or {}).get("gears", ()))


def law_faults(cfg, body: str) -> list:
    """Faults of gear body ``body`` that change its teeth's contact laws (of non-zero size):
    cracks, and spalls and chips over part of the face width. Not a crack through the face width
    of a flexible gear: it is a slit in the gear's FE body."""
    flexible = flexible_gears(cfg)
    return [f for f in cfg.faults if f.body == body and not f.null
            and ((isinstance(f, Crack) and (f.gear not in flexible or f.width_fraction < 1.0))
                 or (isinstance(f, (Spall, Chip)) and f.width_fraction < 1.0))]


def nominal_mesh_force(cfg) -> float:
    """Static normal force [N] of a mesh at the final load torque
    (:func:`~flexgear.config.mesh_damping.static_mesh_force`)."""
    torque = cfg.load["torque"]
    return static_mesh_force(cfg, abs(float(torque if isinstance(torque, (int, float)) else torque[-1][1])))


def _crack_factor(cfg, pair: GearPair, which: int, f: Crack, e: float, load: float):
    """(radii [m], kappa) of crack ``f`` on gear ``which`` (1, 2) of ``pair``."""
    gear = pair.g1 if which == 1 else pair.g2
    roll, ratio = crack_ratio_table(pair, f.depth, f.angle, load, cracked=which, level=cfg.fe["level"],
                                    formulation=cfg.fe["formulation"], material=cfg.material)
    r_fe = gear.rb * np.sqrt(1.0 + roll**2)  # increasing with the roll angle
    r = np.linspace(r_fe[0], r_fe[-1], CRACK_RADII)
    rho = np.interp(r, r_fe, ratio)
    return r, f.width_fraction * rho**e + (1.0 - f.width_fraction)


def _crack_series(cfg, pair: GearPair, which: int, f: Crack, load: float):
    """(radii [m], series compliance [m/N]) of crack ``f`` on gear ``which`` (1, 2) of ``pair``
    in a mesh with the compliant law: from the FE at the flexible model's mesh settings."""
    from ..flexible.reductions import reduction_jobs

    gear = pair.g1 if which == 1 else pair.g2
    job = next(iter(reduction_jobs(cfg)[0].values()))  # the flexible bodies' mesh settings and material
    roll, series = crack_series_table(pair, f.depth, f.angle, load, cracked=which, width_fraction=f.width_fraction,
                                      settings=job["settings"], formulation=job["formulation"], material=job["material"])
    r_fe = gear.rb * np.sqrt(1.0 + roll**2)
    r = np.linspace(r_fe[0], r_fe[-1], CRACK_RADII)
    return r, np.interp(r, r_fe, series)


def _outline_slices(gear, tooth: int, side: int, faults, ds: float):
    """(radii [m], width, recess [m]) of the flank ``side`` of ``tooth`` with its partial faults,
    on a radius grid of a quarter outline spacing."""
    o = tooth_outline(gear, tooth, tuple(faults), None, ds=ds)
    sel = (o.side == side) & (o.kind == FLANK)
    rad = np.hypot(*o.points[sel].T)
    order = np.argsort(rad, kind="stable")
    rad, w, h = rad[order], o.width[sel][order], o.recess[sel][order]
    r = np.linspace(rad[0], rad[-1], max(2, int(math.ceil((rad[-1] - rad[0]) / (ds / 4))) + 1))
    return r, np.interp(r, rad, w), np.interp(r, rad, h)


def tooth_law_table(cfg, model) -> ToothLawTable | None:
    """The ToothLawTable of ``model`` (built from ``cfg``), None when no tooth's law changes (the
    model then packs the empty table and the kernel evaluates the plain law)."""
    if not any(law_faults(cfg, b.name) for b in model.bodies):
        return None
    load = nominal_mesh_force(cfg)
    flexible = flexible_gears(cfg)
    first, rows, tables = np.full((len(model.meshes), 2), -1, np.int64), [], []
    for m, mesh in enumerate(model.meshes):
        for g, ib in enumerate((mesh.a, mesh.b)):
            body = model.bodies[ib]
            faults = law_faults(cfg, body.name)
            if not faults:
                continue
            names = [body.attrs["gear"], model.bodies[mesh.b if g == 0 else mesh.a].attrs["gear"]]
            # the mesh's law: compliant with a flexible gear (flexgear.dynamics.flexible.reductions.make_flexible)
            compliant = any(n in flexible for n in names)
            gear = cfg.gears[names[0]]
            pair = GearPair(gear, cfg.gears[names[1]]) if g == 0 else GearPair(cfg.gears[names[1]], gear)
            row = np.full(2 * gear.z, -1, np.int64)
            for k, side in sorted({(f.tooth, f.flank) for f in faults}):
                here = [f for f in faults if f.tooth == k and f.flank == side]
                cracks = [f for f in here if isinstance(f, Crack)]
                name = f"faults[{cfg.faults.index(cracks[0])}] ({cracks[0].label()})" if cracks else ""
                if cracks and load <= 0.0:
                    raise ConfigError(f"{name}: load.torque = 0: the crack's stiffness ratio is taken from "
                                      "the FE at the static mesh force; rule: a crack needs a non-zero load torque")
                ds = cfg.contact["outline_spacing"] or gear.module / 200  # as the contact tables
                slices = _outline_slices(gear, k, side, [f for f in here if not isinstance(f, Crack)], ds) \
                    if len(here) > len(cracks) else None
                # the compliant law: cracks as series compliances (adding up), no factor; the
                # IMPACT law: cracks as stiffness factors (multiplying), no series compliance
                parts = [_crack_series(cfg, pair, g + 1, f, load) if compliant else
                         _crack_factor(cfg, pair, g + 1, f, mesh.e, load) for f in cracks]
                grid = slices[0] if slices is not None else parts[0][0]
                kappa, series = np.ones_like(grid), np.zeros_like(grid)
                for r, v in parts:
                    if compliant:
                        series = series + np.interp(grid, r, v)
                    else:
                        kappa = kappa * np.interp(grid, r, v)
                width, recess = (slices[1], slices[2]) if slices is not None else (np.ones_like(grid),
                                                                                    np.zeros_like(grid))
                row[2 * k + (0 if side > 0 else 1)] = len(tables)
                tables.append((grid, kappa, width, recess, series))
            first[m, g] = sum(len(x) for x in rows)
            rows.append(row)
    cat = lambda i: np.ascontiguousarray(np.concatenate([t[i] for t in tables]), float)  # noqa: E731
    count = np.array([len(t[0]) for t in tables], np.int64)
    return ToothLawTable(first=first, row=np.concatenate(rows), r0=np.array([t[0][0] for t in tables]),
                         dr=np.array([t[0][1] - t[0][0] for t in tables]), count=count,
                         start=np.concatenate([[0], np.cumsum(count)[:-1]]).astype(np.int64),
                         factor=cat(1), width=cat(2), recess=cat(3), series=cat(4))
