"""A gear's signed distance field placed at its pose: the lookups of the contact search.

The fields are tabulated over one angular pitch in the gear's frame (:mod:`flexgear.gears.sdf`);
a lookup turns a global point into the frame of the nearest tooth and interpolates bilinearly in
that tooth's table (a healthy gear has one table for every tooth; a faulty tooth and its
neighbours have their own: :mod:`flexgear.gears.contact_tables`).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels import kernel


class PlacedField(NamedTuple):
    """The signed distance field of gear Y in its current position (built inside the kernels
    from the :class:`~flexgear.gears.contact_tables.ContactTables` and the pose of Y; the fields
    of :class:`~flexgear.gears.sdf.GearSDF`)."""

    grid: np.ndarray  # (nt, 3, nr, nphi) per table: signed distance [m] (negative inside), normal x, y (GearSDF.grid)
    r0: float  # radius of the first row [m]
    dr: float  # row spacing [m]
    phi0: float  # angle of the first column [rad]
    dphi: float  # column spacing [rad]
    pitch: float  # angular pitch 2 pi / z [rad]
    internal: bool  # ring gear: material outside the toothed outline
    z: int  # number of teeth
    cx: float  # centre x [m]
    cy: float  # centre y [m]
    th: float  # rotation angle [rad]
    tip: float  # tip radius [m]: the material lies inside this circle (outside it for a ring gear)
    teeth: np.ndarray  # (z,) int: the table of each tooth in ``grid``
    angle: np.ndarray  # (z,) float: each tooth's turn from its nominal place (pitch errors) [rad]


@kernel(literal=True, error_model="numpy", inline="always")
def placed_field(tables, g, cx, cy, th):
    """The PlacedField of gear g of the ContactTables ``tables`` placed at (cx, cy) [m],
    turned by th [rad]."""
    nr = tables.sdf_rows[g]
    nphi = tables.sdf_columns[g]
    nt = tables.sdf_tables[g]
    o = tables.sdf_off[g]
    z = tables.gear_z[g]
    t0 = tables.tooth_off[g]
    grid = tables.sdf_grids[o:o + nt * 3 * nr * nphi].reshape((nt, 3, nr, nphi))
    return PlacedField(grid, tables.sdf_r0[g], tables.sdf_dr[g], tables.sdf_phi0[g], tables.sdf_dphi[g],
                       tables.sdf_pitch[g], tables.sdf_internal[g], z, cx, cy, th, tables.gear_tip[g],
                       tables.tooth_grid[t0:t0 + z], tables.tooth_angle[t0:t0 + z])


@kernel(literal=True, error_model="numpy", inline="always")
def _cell(Y, r, phi):
    """Grid cell and bilinear weights of the point at radius r, gear-frame angle phi of gear Y
    (a PlacedField).

    Returns (bound, i0, j0, a, b, k, phr, t): ``bound`` is nan inside the tabulated band, else a
    signed-distance bound with the right sign (the cell data are then unused); k is the tooth
    index (unreduced) of the nominal pitch sector, phr the angle from that tooth's centre line
    (turned by its pitch error) and t its table in ``Y.grid``.
    """
    grid = Y.grid
    r0 = Y.r0
    dr = Y.dr
    nr, nphi = grid.shape[2], grid.shape[3]
    rmax = r0 + dr * (nr - 1)
    if r <= r0:
        return ((r0 - r) + 1e-3 if Y.internal else -(r0 - r) - 1e-3), 0, 0, 0.0, 0.0, 0, 0.0, 0
    if r >= rmax:
        return (-(r - rmax) - 1e-3 if Y.internal else r - rmax + 1e-3), 0, 0, 0.0, 0.0, 0, 0.0, 0
    k = math.floor(phi / Y.pitch + 0.5)
    m = int(k) % Y.z
    phr = phi - k * Y.pitch - Y.angle[m]
    fi = (r - r0) / dr
    fj = (phr - Y.phi0) / Y.dphi
    i0 = min(int(fi), nr - 2)
    j0 = min(max(int(fj), 0), nphi - 2)
    return math.nan, i0, j0, fi - i0, fj - j0, int(k), phr, Y.teeth[m]


@kernel(literal=True, error_model="numpy", inline="always")
def tooth_turn(Y, k):
    """Angle [rad] of tooth k's (unreduced) frame of gear Y (a PlacedField): its rotation, its
    nominal place and its pitch error."""
    return Y.th + k * Y.pitch + Y.angle[k % Y.z]


@kernel(literal=True, error_model="numpy", inline="always")
def lookup_local(Y, px, py):
    """Signed distance of global point (px, py) to gear Y (a PlacedField), with its gradient in
    the frame of the nearest tooth (not yet turned to the global frame).

    Returns (f, ux, uy, k, phr, inside): ``inside`` is False far from the tooth band (f is then
    only a bound, see :func:`sdf_lookup`); k is the unreduced tooth index and phr the angle from
    that tooth's centre line. The gradient is turned to the global frame by the angle
    th + k pitch (:func:`turn_normal`), which the callers evaluate once per tooth.
    """
    dx = px - Y.cx
    dy = py - Y.cy
    return lookup_polar(Y, math.sqrt(dx * dx + dy * dy), math.atan2(dy, dx))


@kernel(literal=True, error_model="numpy", inline="always")
def lookup_polar(Y, r, psi):
    """:func:`lookup_local` of the point at radius r [m] and global polar angle psi [rad] about
    gear Y's centre (psi unused outside the tabulated band)."""
    bound, i0, j0, a, b, k, phr, t = _cell(Y, r, psi - Y.th)
    if not math.isnan(bound):
        return bound, 0.0, 0.0, 0, 0.0, False
    grid = Y.grid[t]
    w00 = (1 - a) * (1 - b)
    w10 = a * (1 - b)
    w01 = (1 - a) * b
    w11 = a * b
    f = w00 * grid[0, i0, j0] + w10 * grid[0, i0 + 1, j0] + w01 * grid[0, i0, j0 + 1] + w11 * grid[0, i0 + 1, j0 + 1]
    ux = w00 * grid[1, i0, j0] + w10 * grid[1, i0 + 1, j0] + w01 * grid[1, i0, j0 + 1] + w11 * grid[1, i0 + 1, j0 + 1]
    uy = w00 * grid[2, i0, j0] + w10 * grid[2, i0 + 1, j0] + w01 * grid[2, i0, j0 + 1] + w11 * grid[2, i0 + 1, j0 + 1]
    return f, ux, uy, k, phr, True


@kernel(literal=True, error_model="numpy", inline="always")
def turn_normal(ux, uy, c, s):
    """The tooth-frame gradient (ux, uy) turned by the angle with cosine c, sine s, and
    normalised (left as is when zero)."""
    gx = ux * c - uy * s
    gy = ux * s + uy * c
    g = math.sqrt(gx * gx + gy * gy)
    if g > 0.0:
        gx /= g
        gy /= g
    return gx, gy


@kernel(literal=True, error_model="numpy")
def sdf_lookup(Y, px, py):
    """Signed distance of global point (px, py) to gear Y (a PlacedField).

    Returns
    -------
    f : float
        Signed distance [m] (negative inside); far from the tooth band, a bound with the right
        sign (outside: > 0, inside: < 0) without the gradient.
    nx, ny : float
        Unit outward normal (gradient of f, interpolated from its tabulated exact values) in the
        global frame (0, 0 when f is only a bound).
    tooth : int
        Index of the nearest tooth (0..z-1).
    side : int
        +1 if the point lies at positive angle from that tooth's centre line, else -1.
    """
    f, ux, uy, k, phr, inside = lookup_local(Y, px, py)
    if not inside:
        return f, 0.0, 0.0, -1, 0
    # from the frame of tooth k (turned by th + k pitch) to the global frame
    a = tooth_turn(Y, k)
    gx, gy = turn_normal(ux, uy, math.cos(a), math.sin(a))
    side = 1 if phr >= 0.0 else -1
    return f, gx, gy, k % Y.z, side


@kernel(literal=True, error_model="numpy", inline="always")
def sdf_value(Y, px, py):
    """Signed distance only (no gradient): the fast path used while scanning."""
    f, _, _ = sdf_value_polar(Y, px, py)
    return f


@kernel(literal=True, error_model="numpy", inline="always")
def sdf_value_polar(Y, px, py):
    """:func:`sdf_value` and the point's radius r [m] and global polar angle psi [rad] about gear
    Y's centre (psi = 0 outside the tabulated band, where no atan2 is needed), from which
    :func:`lookup_polar` looks the point up again without the square root and arc tangent."""
    dx = px - Y.cx
    dy = py - Y.cy
    r = math.sqrt(dx * dx + dy * dy)
    f, _, psi = band_value(Y, dx, dy, r)
    return f, r, psi


@kernel(literal=True, error_model="numpy", inline="always")
def band_value(Y, dx, dy, r):
    """:func:`sdf_value` of gear Y (a PlacedField) at the point (dx, dy) [m] from its centre,
    at distance r = sqrt(dx^2 + dy^2) [m] from it, whether the point lies inside the tabulated
    band (else the value is only a bound), and its polar angle psi [rad] (0 outside the band)."""
    if r <= Y.r0 or r >= Y.r0 + Y.dr * (Y.grid.shape[2] - 1):  # outside the band: no atan2 needed
        bound, _, _, _, _, _, _, _ = _cell(Y, r, 0.0)
        return bound, False, 0.0
    psi = math.atan2(dy, dx)
    bound, i0, j0, a, b, _, _, t = _cell(Y, r, psi - Y.th)
    grid = Y.grid[t]
    return ((1 - a) * (1 - b) * grid[0, i0, j0] + a * (1 - b) * grid[0, i0 + 1, j0]
            + (1 - a) * b * grid[0, i0, j0 + 1] + a * b * grid[0, i0 + 1, j0 + 1]), True, psi
