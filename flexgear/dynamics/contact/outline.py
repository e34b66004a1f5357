"""A gear's tooth outlines placed at its pose: the samples the contact search probes in the other
gear's signed distance field (:mod:`.field`). Every tooth of a healthy gear has the same outline;
a faulty tooth has its own (:mod:`flexgear.gears.contact_tables`), looked up by tooth.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels import kernel
from .field import lookup_local, lookup_polar, sdf_value, sdf_value_polar



class PlacedOutline(NamedTuple):
    """One tooth's outline samples of gear X in its current position, with the search data."""

    points: np.ndarray  # (N, 2) outline samples of the tooth in its own frame (as tooth 0 in the gear frame) [m]
    corner: np.ndarray  # (N,) bool: the outline turns by more than CORNER_TURN at the sample
    nh: int  # index of the tip centre sample (end of the right half)
    ds: float  # largest sample spacing [m]
    tip_from: int  # first sample of the tip region of the right half (0: scan the whole half)
    pitch: float  # angular pitch 2 pi / z [rad]
    z: int  # number of teeth
    cx: float  # centre x [m]
    cy: float  # centre y [m]
    th: float  # rotation angle [rad]
    is_a: bool  # X is gear A of the mesh (else gear B)


class GearOutlines(NamedTuple):
    """The outlines of gear X's teeth in its current position: the ContactTables' outline entries
    and the entry of each tooth (:func:`placed_tooth`)."""

    points: np.ndarray  # (sum N, 2) every entry's outline samples [m] (ContactTables.outlines)
    corner: np.ndarray  # (sum N,) bool (ContactTables.out_corner)
    off: np.ndarray  # (entries + 1,) int: entry e's samples are off[e]:off[e + 1]
    nh: np.ndarray  # (entries,) int: index of each entry's tip centre sample
    tip: np.ndarray  # (entries,) int: first sample of each entry's tip region
    cold: np.ndarray  # (entries,) bool: a full search scans the entry's halves afresh (ContactTables.out_cold)
    teeth: np.ndarray  # (z,) int: the entry of each tooth
    angle: np.ndarray  # (z,) float: each tooth's turn from its nominal place (pitch errors) [rad]
    ds: float  # largest sample spacing of the gear's entries [m]
    tips_only: bool  # scan each half from its tip region only (gear B of a mesh)
    pitch: float  # angular pitch 2 pi / z [rad]
    z: int  # number of teeth
    cx: float  # centre x [m]
    cy: float  # centre y [m]
    th: float  # rotation angle [rad]
    is_a: bool  # X is gear A of the mesh (else gear B)


@kernel(literal=True, error_model="numpy", inline="always")
def placed_outlines(tables, g, cx, cy, th, tips_only, is_a):
    """The GearOutlines of gear g of the ContactTables ``tables`` at (cx, cy) [m], turned by th
    [rad]: scanned from each entry's tip region (``tips_only``) or whole, as gear A (``is_a``) or B."""
    t0 = tables.tooth_off[g]
    z = tables.gear_z[g]
    return GearOutlines(tables.outlines, tables.out_corner, tables.out_off, tables.out_nh, tables.out_tip,
                        tables.out_cold, tables.tooth_entry[t0:t0 + z], tables.tooth_angle[t0:t0 + z], tables.out_ds[g],
                        tips_only, tables.sdf_pitch[g], z, cx, cy, th, is_a)


@kernel(literal=True, error_model="numpy", inline="always")
def placed_tooth(Xs, kk):
    """The PlacedOutline of tooth kk (unreduced index) of the GearOutlines ``Xs``: a per-tooth
    table lookup, views of the tables (no copy)."""
    e = Xs.teeth[kk % Xs.z]
    o0 = Xs.off[e]
    o1 = Xs.off[e + 1]
    return PlacedOutline(Xs.points[o0:o1], Xs.corner[o0:o1], Xs.nh[e], Xs.ds, Xs.tip[e] if Xs.tips_only else 0,
                         Xs.pitch, Xs.z, Xs.cx, Xs.cy, Xs.th, Xs.is_a)


@kernel(literal=True, error_model="numpy", inline="always")
def outline_value(X, j, ca, sa, Y):
    """Signed distance to gear Y (a PlacedField) of outline sample j of gear X's tooth (a
    PlacedOutline, the tooth turned by rotation ca, sa). (The search kernels are compiled
    without reference counting, so taking the tuples' fields in this innermost loop costs
    nothing.)"""
    outline = X.points
    px = X.cx + ca * outline[j, 0] - sa * outline[j, 1]
    py = X.cy + sa * outline[j, 0] + ca * outline[j, 1]
    return sdf_value(Y, px, py)


@kernel(literal=True, error_model="numpy", inline="always")
def outline_value_polar(X, j, ca, sa, Y):
    """:func:`outline_value` (the same value, the same operations) that also returns the sample's radius
    r and polar angle psi about gear Y's centre (psi = 0 outside the tabulated band, where it is
    not needed), from which :func:`_finish` looks the sample up again without the square root
    and arc tangent (:func:`lookup_polar`)."""
    outline = X.points
    px = X.cx + ca * outline[j, 0] - sa * outline[j, 1]
    py = X.cy + sa * outline[j, 0] + ca * outline[j, 1]
    return sdf_value_polar(Y, px, py)


@kernel(literal=True, error_model="numpy", inline="always")
def sample_lookup(X, j, r, psi, ca, sa, Y):
    """:func:`contact_at` at sample j itself (t = 0) from the sample's polar coordinates about
    gear Y's centre (from :func:`outline_value_polar`): the same results."""
    outline = X.points
    px = X.cx + ca * outline[j, 0] - sa * outline[j, 1]
    py = X.cy + sa * outline[j, 0] + ca * outline[j, 1]
    f, ux, uy, k, phr, inside = lookup_polar(Y, r, psi)
    return px, py, f, ux, uy, k, phr, inside


@kernel(literal=True, error_model="numpy", inline="always")
def outline_tangential(outline, j, side, ca, sa, nx, ny):
    """Component of the unit vector (nx, ny) along gear X's outline tangent at sample j (the
    tooth turned by rotation ca, sa): central difference for side = 0, else the one-sided
    tangent of the segment toward sample j + side (at a corner)."""
    j0 = j - 1 if side <= 0 else j
    j1 = j + 1 if side >= 0 else j
    tx = outline[j1, 0] - outline[j0, 0]
    ty = outline[j1, 1] - outline[j0, 1]
    return (nx * (ca * tx - sa * ty) + ny * (sa * tx + ca * ty)) / math.sqrt(tx * tx + ty * ty)


@kernel(literal=True, error_model="numpy", inline="always")
def contact_at(X, i_lo, i_hi, jb, t, ca, sa, Y):
    """Global point at fraction |t| <= 1 of the way from sample jb toward its neighbour (jb + 1
    for t > 0, jb - 1 for t < 0) on gear X's tooth, and the signed distance of gear Y there
    with its gradient in the frame of Y's nearest tooth k (:func:`lookup_local`):
    (px, py, f, ux, uy, k, phr, inside)."""
    outline = X.points
    jn = jb + 1 if t >= 0.0 else jb - 1
    if jn < i_lo or jn > i_hi:
        jn = jb
    at = abs(t)
    ox = (1 - at) * outline[jb, 0] + at * outline[jn, 0]
    oy = (1 - at) * outline[jb, 1] + at * outline[jn, 1]
    px = X.cx + ca * ox - sa * oy
    py = X.cy + sa * ox + ca * oy
    f, ux, uy, k, phr, inside = lookup_local(Y, px, py)
    return px, py, f, ux, uy, k, phr, inside
