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
    """Outlines and SDFs of the distinct gear geometries, packed for the compiled kernels.

    Geometry g's tooth-0 outline is ``outlines[out_off[g]:out_off[g + 1]]`` (gear frame, the
    tooth's centre line along +x); its SDF grid is ``sdf_grids[sdf_off[g]:sdf_off[g] +
    3 * sdf_rows[g] * sdf_columns[g]]`` reshaped to (3, sdf_rows[g], sdf_columns[g]): the planes of
    ``GearSDF.grid`` (:class:`~flexgear.gears.sdf.GearSDF`) (distance, normal x, normal y; rows: radius, columns: angle). Zero gears (e.g. a model without meshes) give zero-length arrays.
    """

    outlines: np.ndarray  # (sum N, 2) float: tooth-0 outline points [m]
    out_off: np.ndarray  # (ng + 1,) int: offsets of each geometry's outline in ``outlines``
    out_nh: np.ndarray  # (ng,) int: index of the tip centre point (end of the right half)
    out_ds: np.ndarray  # (ng,) float: largest outline sample spacing [m]
    out_tip: np.ndarray  # (ng,) int: first index of the tip region in the right half
    out_corner: np.ndarray  # (sum N,) bool: outline sample where the outline turns by more than CORNER_TURN
    sdf_grids: np.ndarray  # (sum 3 nr nphi,) float: GearSDF.grid planes (distance [m], normal x, y), flattened
    sdf_off: np.ndarray  # (ng,) int: offset of each grid in ``sdf_grids``
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


def pack_gears(gears: list[SpurGear], ds: float | None = None, sdf_resolution: float | None = None) -> ContactTables:
    """Outline samples and SDF grids of ``gears`` (distinct geometries), packed (no gears:
    empty tables).

    Parameters
    ----------
    ds : float, optional
        Outline sample spacing [m] (default module / 200, 10 um for m = 2 mm).
    sdf_resolution : float, optional
        SDF grid spacing [m] (default module / 200), see :func:`~flexgear.gears.sdf.build_sdf`.

    At the defaults the spur pair's mesh harmonics and peak force are converged to well within
    1 % (tests/test_contact_convergence.py).
    """
    outs, nh, dss, tips, grids, shapes, fl, zs, ras = [], [], [], [], [], [], [], [], []
    for g in gears:
        d = g.module / 200 if ds is None else ds
        o = g.tooth_outline(ds=d)
        n = len(o.points)
        outs.append(o.points)
        nh.append((n + 1) // 2)
        seg = np.hypot(*np.diff(o.points, axis=0).T)
        dss.append(seg.max())
        # tip region: within 0.4 m of the tip circle (tip land, tip corner, upper flank)
        rad = np.hypot(*o.points[: (n + 1) // 2].T)
        near = np.nonzero(np.abs(rad - g.ra) <= 0.4 * g.module)[0]
        tips.append(int(near[0]) if len(near) else 0)
        s = gear_sdf(g, sdf_resolution)
        grids.append(s.grid.ravel())
        shapes.append(s.grid.shape[1:])
        fl.append([s.r0, s.dr, s.phi0, s.dphi, s.pitch, 1.0 if s.internal else 0.0])
        zs.append(g.z)
        ras.append(g.ra)
    out_off = np.concatenate([[0], np.cumsum([len(o) for o in outs])]).astype(np.int64)
    sdf_off = np.concatenate([[0], np.cumsum([len(gr) for gr in grids])[:-1]]).astype(np.int64)[:len(gears)]
    shapes = np.array(shapes, np.int64).reshape(-1, 2)
    fl = np.array(fl, float).reshape(-1, 6)
    return ContactTables(
        outlines=np.ascontiguousarray(np.vstack(outs) if outs else np.zeros((0, 2))), out_off=out_off,
        out_nh=np.array(nh, np.int64), out_ds=np.array(dss, float), out_tip=np.array(tips, np.int64),
        out_corner=np.concatenate([corner_flags(o) for o in outs]) if outs else np.zeros(0, np.bool_),
        sdf_grids=np.concatenate(grids) if grids else np.zeros(0), sdf_off=sdf_off,
        sdf_rows=shapes[:, 0].copy(), sdf_columns=shapes[:, 1].copy(), sdf_r0=fl[:, 0].copy(),
        sdf_dr=fl[:, 1].copy(), sdf_phi0=fl[:, 2].copy(), sdf_dphi=fl[:, 3].copy(), sdf_pitch=fl[:, 4].copy(),
        sdf_internal=fl[:, 5] > 0.5, gear_z=np.array(zs, np.int64), gear_tip=np.array(ras, float),
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
