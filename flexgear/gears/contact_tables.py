"""The contact search's tables of a gear set: each geometry's tooth outline samples and signed
distance field, packed into named arrays for the compiled kernels, and the band of candidate
teeth of a mesh. Depends on the geometry alone (built once per model, cached on disk).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..kernels import kernel
from .geometry import SpurGear
from .sdf import CORNER_TURN, gear_sdf



@kernel(error_model="numpy", inline="always")
def _is_corner(outline, j):
    """Whether the outline turns by more than CORNER_TURN at interior sample j."""
    ux = outline[j, 0] - outline[j - 1, 0]
    uy = outline[j, 1] - outline[j - 1, 1]
    wx = outline[j + 1, 0] - outline[j, 0]
    wy = outline[j + 1, 1] - outline[j, 1]
    return abs(math.atan2(ux * wy - uy * wx, ux * wx + uy * wy)) > CORNER_TURN


@kernel(error_model="numpy")
def corner_flags(outline):
    """Per outline sample, whether the outline turns there by more than CORNER_TURN (False at
    the two end samples); tabulated once by :func:`pack_gears` for the refinement."""
    n = outline.shape[0]
    out = np.zeros(n, np.bool_)
    for j in range(1, n - 1):
        out[j] = _is_corner(outline, j)
    return out


class ContactTables(NamedTuple):
    """Outlines and SDFs of the gears of a set, packed for the compiled kernels.

    A gear g is a geometry, or a body whose teeth differ from that geometry's (faults, profile
    errors): it has one or more *tables*, each an outline entry and an SDF grid, and every tooth
    k names its own: ``tooth_entry[tooth_off[g] + k]`` (outline entry) and
    ``tooth_grid[tooth_off[g] + k]`` (grid). A healthy gear has one table for all its teeth; a
    faulty tooth and its two neighbours have their own (the neighbours' fields see the faulty
    tooth). Entry e's outline is ``outlines[out_off[e]:out_off[e + 1]]`` (the tooth's own frame, its
    centre line along +x); gear g's entries 0..ng-1 are its first table's, the others follow. Gear
    g's SDF grids are ``sdf_grids[sdf_off[g]:sdf_off[g] + sdf_tables[g] * 3 * sdf_rows[g] *
    sdf_columns[g]]`` reshaped to (sdf_tables[g], 3, sdf_rows[g], sdf_columns[g]): the planes of
    ``GearSDF.grid`` (:class:`~flexgear.gears.sdf.GearSDF`) (distance, normal x, normal y; rows:
    radius, columns: angle). Zero gears (e.g. a model without meshes) give zero-length arrays.
    """

    outlines: np.ndarray  # (sum N, 2) float: outline points of every entry, tooth frame [m]
    out_off: np.ndarray  # (ne + 1,) int: offsets of each entry's outline in ``outlines``
    out_nh: np.ndarray  # (ne,) int: index of the tip centre point (end of the right half)
    out_ds: np.ndarray  # (ng,) float: largest outline sample spacing of the gear's entries [m]
    out_tip: np.ndarray  # (ne,) int: first index of the tip region in the right half (and from the end in the left)
    out_corner: np.ndarray  # (sum N,) bool: outline sample where the outline turns by more than CORNER_TURN
    out_cold: np.ndarray  # (ne,) bool: a full search scans the entry's halves afresh (a faulty tooth's outline)
    sdf_grids: np.ndarray  # (sum nt 3 nr nphi,) float: GearSDF.grid planes (distance [m], normal x, y), flattened
    sdf_off: np.ndarray  # (ng,) int: offset of each gear's grids in ``sdf_grids``
    sdf_tables: np.ndarray  # (ng,) int: number of grids nt of the gear
    sdf_rows: np.ndarray  # (ng,) int: grid rows nr (radii)
    sdf_columns: np.ndarray  # (ng,) int: grid columns nphi (angles)
    sdf_r0: np.ndarray  # (ng,) float: radius of the first row [m]
    sdf_dr: np.ndarray  # (ng,) float: row spacing [m]
    sdf_phi0: np.ndarray  # (ng,) float: angle of the first column, -pitch/2 [rad]
    sdf_dphi: np.ndarray  # (ng,) float: column spacing [rad]
    sdf_pitch: np.ndarray  # (ng,) float: angular pitch 2 pi / z [rad]
    sdf_internal: np.ndarray  # (ng,) bool: internal gear (material outside the toothed outline)
    gear_z: np.ndarray  # (ng,) int: number of teeth
    gear_tip: np.ndarray  # (ng,) float: tip radius ra [m] (of the toothed outline, also for a ring gear)
    gear_shift: np.ndarray  # (ng, 2) float: eccentricity: toothing centre from the rotation axis, gear frame [m]
    tooth_off: np.ndarray  # (ng,) int: offset of each gear's teeth in ``tooth_entry`` / ``tooth_grid``
    tooth_entry: np.ndarray  # (sum z,) int: outline entry of each tooth
    tooth_grid: np.ndarray  # (sum z,) int: SDF grid of each tooth (0 .. sdf_tables[g] - 1)
    tooth_angle: np.ndarray  # (sum z,) float: turn of each tooth from its nominal place (pitch errors) [rad]


def _entry(points: np.ndarray, nh: int, ra: float, module: float, cold: bool = False):
    """(points, nh, largest spacing, tip-region start, corner flags, cold) of an outline entry.

    ``cold``: a faulty tooth's outline, whose signed distance to the mate along a half tooth may
    have two minima (a spall's edge and its floor, a chip's corners): the full search scans it
    afresh instead of walking from the last minimum (see ``flexgear.dynamics.contact.search._scan``)."""
    seg = np.hypot(*np.diff(points, axis=0).T)
    # tip region: within 0.4 m of the tip circle (tip land, tip corner, upper flank); the right
    # half from its start, the left half from the end: the first such sample of either
    rad = np.hypot(*points.T)
    near_r = np.nonzero(np.abs(rad[:nh] - ra) <= 0.4 * module)[0]
    near_l = np.nonzero(np.abs(rad[nh - 1:][::-1] - ra) <= 0.4 * module)[0]
    tip = min(int(near_r[0]) if len(near_r) else 0, int(near_l[0]) if len(near_l) else 0)
    return points, nh, seg.max(), tip, corner_flags(points), cold


def pack_gears(gears: list[SpurGear], ds: float | None = None, sdf_resolution: float | None = None,
               faults: list | None = None) -> ContactTables:
    """Outline samples and SDF grids of ``gears``, packed (no gears: empty tables).

    Parameters
    ----------
    ds : float, optional
        Outline sample spacing [m] (default module / 200, 10 um for m = 2 mm).
    sdf_resolution : float, optional
        SDF grid spacing [m] (default module / 200), see :func:`~flexgear.gears.sdf.build_sdf`.
    faults : list, optional
        Per gear, None (healthy: the geometry's cached tables) or ``(faults, errors)``: the
        body's ToothFault tuple and GearErrors (or None). Profile errors change every tooth's
        table; a spall, chip or missing tooth (not of zero size) gives that tooth and its
        neighbours tables of their own (:func:`flexgear.gears.modified.tooth_outline`); an
        eccentricity gives ``gear_shift``, pitch errors ``tooth_angle`` (each tooth turned
        rigidly, :func:`flexgear.gears.modified.tooth_offsets`). Cracks and partial face widths do
        not enter these tables.

    At the defaults the spur pair's mesh harmonics and peak force are converged to well within
    1 % (tests/test_contact_convergence.py).
    """
    from .modified import faulty_teeth, tooth_offsets, tooth_outline
    from .sdf import tooth_sdf

    faults = [None] * len(gears) if faults is None else list(faults)
    base, extra, gear_ds, grids, shapes, fl, zs, ras, shifts, t_entry, t_grid, t_angle = ([] for _ in range(12))
    for gi, (g, spec) in enumerate(zip(gears, faults)):
        d = g.module / 200 if ds is None else ds
        fs, errs = spec if spec is not None else ((), None)
        prof = errs is not None and errs.profile is not None and not errs.profile.null
        outline_faults = tuple(f for f in fs if f.kind in ("spall", "chip", "missing") and not f.null)
        if prof:
            o = tooth_outline(g, 0, (), errs, ds=d)
            entries = [_entry(o.points, int(np.count_nonzero(o.side < 0)), g.ra, g.module)]
            fine = tooth_outline(g, 0, (), errs, ds=g.module / 400).points
            grid_list = [tooth_sdf(g, fine, fine, fine, sdf_resolution).grid]
        else:
            o = g.tooth_outline(ds=d)
            entries = [_entry(o.points, (len(o.points) + 1) // 2, g.ra, g.module)]
            fine = None
            grid_list = [gear_sdf(g, sdf_resolution).grid]
        own = faulty_teeth(outline_faults, g.z) if outline_faults else []
        entry_of = np.zeros(g.z, np.int64)  # local entry (0: the gear's first)
        for k in own:
            o = tooth_outline(g, k, outline_faults, errs, ds=d)
            entries.append(_entry(o.points, int(np.count_nonzero(o.side < 0)), g.ra, g.module, cold=not o.healthy))
            if fine is None:
                fine = g.tooth_outline(ds=g.module / 400).points

            def outline(j):
                j %= g.z
                if j in own or j == k:
                    return tooth_outline(g, j, outline_faults, errs, ds=g.module / 400).points
                return fine

            grid_list.append(tooth_sdf(g, outline(k - 1), outline(k), outline(k + 1), sdf_resolution).grid)
            entry_of[k] = len(entries) - 1
        base.append(entries[0])
        extra.append(entries[1:])
        gear_ds.append(max(e[2] for e in entries))
        grids.append(np.concatenate([gr.ravel() for gr in grid_list]))
        shapes.append(grid_list[0].shape[1:] + (len(grid_list),))
        s = gear_sdf(g, sdf_resolution)
        fl.append([s.r0, s.dr, s.phi0, s.dphi, s.pitch, 1.0 if s.internal else 0.0])
        zs.append(g.z)
        ras.append(g.ra)
        ecc = errs.eccentricity if errs is not None else None
        shifts.append(ecc.shift() if ecc is not None and not ecc.null else np.zeros(2))
        t_entry.append(entry_of)
        t_grid.append(entry_of.copy())
        pitch = errs.pitch if errs is not None else None
        t_angle.append(np.array([o.angle for o in tooth_offsets(g, errs)]) if pitch is not None and not pitch.null
                       else np.zeros(g.z))
    # global entry numbers: the gears' first entries, then the others gear by gear
    ng = len(gears)
    first = ng
    ordered = list(base)
    for gi in range(ng):
        local = t_entry[gi]
        glob = np.where(local == 0, gi, first + local - 1)
        t_entry[gi] = glob
        ordered += extra[gi]
        first += len(extra[gi])
    outs = [e[0] for e in ordered]
    out_off = np.concatenate([[0], np.cumsum([len(o) for o in outs])]).astype(np.int64)
    sdf_off = np.concatenate([[0], np.cumsum([len(gr) for gr in grids])[:-1]]).astype(np.int64)[:ng]
    shapes = np.array(shapes, np.int64).reshape(-1, 3)
    fl = np.array(fl, float).reshape(-1, 6)
    return ContactTables(
        outlines=np.ascontiguousarray(np.vstack(outs) if outs else np.zeros((0, 2))), out_off=out_off,
        out_nh=np.array([e[1] for e in ordered], np.int64), out_ds=np.array(gear_ds, float),
        out_tip=np.array([e[3] for e in ordered], np.int64),
        out_corner=np.concatenate([e[4] for e in ordered]) if outs else np.zeros(0, np.bool_),
        out_cold=np.array([e[5] for e in ordered], np.bool_),
        sdf_grids=np.concatenate(grids) if grids else np.zeros(0), sdf_off=sdf_off, sdf_tables=shapes[:, 2].copy(),
        sdf_rows=shapes[:, 0].copy(), sdf_columns=shapes[:, 1].copy(), sdf_r0=fl[:, 0].copy(),
        sdf_dr=fl[:, 1].copy(), sdf_phi0=fl[:, 2].copy(), sdf_dphi=fl[:, 3].copy(), sdf_pitch=fl[:, 4].copy(),
        sdf_internal=fl[:, 5] > 0.5, gear_z=np.array(zs, np.int64), gear_tip=np.array(ras, float),
        gear_shift=np.array(shifts, float).reshape(-1, 2),
        tooth_off=np.concatenate([[0], np.cumsum(zs)[:-1]]).astype(np.int64)[:ng],
        tooth_entry=np.concatenate(t_entry).astype(np.int64) if ng else np.zeros(0, np.int64),
        tooth_grid=np.concatenate(t_grid).astype(np.int64) if ng else np.zeros(0, np.int64),
        tooth_angle=np.concatenate(t_angle).astype(float) if ng else np.zeros(0),
    )


def candidate_teeth(gX: SpurGear, gY: SpurGear, centre_distance: float, internal_mesh: bool) -> int:
    """Half-width (in teeth) of the band of gear X's teeth that can reach gear Y.

    Samples X's tip circle and finds the largest angle from the facing direction at which it
    lies inside Y's tip circle (outside it for an internal Y): the corners of the lens where
    teeth can overlap, plus half a pitch.
    """
    a = centre_distance
    phi = np.linspace(-math.pi, math.pi, 20001)
    # X at origin; facing direction +x. Y's centre: external mesh (a, 0); X external in an
    # internal Y: Y centre at (-a, 0); X internal (ring) facing an external Y: Y at (a, 0).
    if internal_mesh and not gX.internal:
        cy = -a
    else:
        cy = a
    px, py = gX.ra * np.cos(phi), gX.ra * np.sin(phi)
    rY = np.hypot(px - cy, py)
    # X's tip circle where it lies inside Y's tip circle (outside it, for an internal Y)
    inside = rY > gY.ra if gY.internal else rY < gY.ra
    if not inside.any():
        return 1
    gamma = np.abs(phi[inside]).max()
    return int(math.ceil(gamma / gX.pitch_angle + 0.5))
