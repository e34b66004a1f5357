"""A gear's signed distance field placed at its pose: the lookups of the contact search.

The fields are tabulated over one angular pitch in the gear's frame (:mod:`flexgear.gears.sdf`);
a lookup turns a global point into the frame of the nearest tooth and interpolates bilinearly.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels import kernel



@kernel(error_model="numpy", inline="always")
def _cell(grid, r0, dr, phi0, dphi, pitch, internal, r, phi):
    """Grid cell and bilinear weights of the point at radius r, gear-frame angle phi.

    Returns (bound, i0, j0, a, b, k, phr): ``bound`` is nan inside the tabulated band, else a
    signed-distance bound with the right sign (the cell data are then unused); k is the tooth
    index (unreduced) and phr the angle from that tooth's centre line.
    """
    nr, nphi = grid.shape[1], grid.shape[2]
    rmax = r0 + dr * (nr - 1)
    if r <= r0:
        return ((r0 - r) + 1e-3 if internal else -(r0 - r) - 1e-3), 0, 0, 0.0, 0.0, 0, 0.0
    if r >= rmax:
        return (-(r - rmax) - 1e-3 if internal else r - rmax + 1e-3), 0, 0, 0.0, 0.0, 0, 0.0
    k = math.floor(phi / pitch + 0.5)
    phr = phi - k * pitch
    fi = (r - r0) / dr
    fj = (phr - phi0) / dphi
    i0 = min(int(fi), nr - 2)
    j0 = min(max(int(fj), 0), nphi - 2)
    return math.nan, i0, j0, fi - i0, fj - j0, int(k), phr


@kernel(error_model="numpy", inline="always")
def lookup_local(grid, r0, dr, phi0, dphi, pitch, internal, cx, cy, th, px, py):
    """Signed distance of global point (px, py) to a gear at (cx, cy) turned by th, with its
    gradient in the frame of the nearest tooth (not yet turned to the global frame).

    Returns (f, ux, uy, k, phr, inside): ``inside`` is False far from the tooth band (f is then
    only a bound, see :func:`sdf_lookup`); k is the unreduced tooth index and phr the angle from
    that tooth's centre line. The gradient is turned to the global frame by the angle
    th + k pitch (:func:`turn_normal`), which the callers evaluate once per tooth.
    """
    dx = px - cx
    dy = py - cy
    return lookup_polar(grid, r0, dr, phi0, dphi, pitch, internal, th, math.sqrt(dx * dx + dy * dy),
                         math.atan2(dy, dx))


@kernel(error_model="numpy", inline="always")
def lookup_polar(grid, r0, dr, phi0, dphi, pitch, internal, th, r, psi):
    """:func:`lookup_local` of the point at radius r [m] and global polar angle psi [rad] about
    the gear's centre (psi unused outside the tabulated band)."""
    bound, i0, j0, a, b, k, phr = _cell(grid, r0, dr, phi0, dphi, pitch, internal, r, psi - th)
    if not math.isnan(bound):
        return bound, 0.0, 0.0, 0, 0.0, False
    w00 = (1 - a) * (1 - b)
    w10 = a * (1 - b)
    w01 = (1 - a) * b
    w11 = a * b
    f = w00 * grid[0, i0, j0] + w10 * grid[0, i0 + 1, j0] + w01 * grid[0, i0, j0 + 1] + w11 * grid[0, i0 + 1, j0 + 1]
    ux = w00 * grid[1, i0, j0] + w10 * grid[1, i0 + 1, j0] + w01 * grid[1, i0, j0 + 1] + w11 * grid[1, i0 + 1, j0 + 1]
    uy = w00 * grid[2, i0, j0] + w10 * grid[2, i0 + 1, j0] + w01 * grid[2, i0, j0 + 1] + w11 * grid[2, i0 + 1, j0 + 1]
    return f, ux, uy, k, phr, True


@kernel(error_model="numpy", inline="always")
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


@kernel(error_model="numpy")
def sdf_lookup(grid, r0, dr, phi0, dphi, pitch, internal, z, cx, cy, th, px, py):
    """Signed distance of global point (px, py) to a gear at (cx, cy) turned by th.

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
    f, ux, uy, k, phr, inside = lookup_local(grid, r0, dr, phi0, dphi, pitch, internal, cx, cy, th, px, py)
    if not inside:
        return f, 0.0, 0.0, -1, 0
    # from the frame of tooth k (turned by th + k pitch) to the global frame
    gx, gy = turn_normal(ux, uy, math.cos(th + k * pitch), math.sin(th + k * pitch))
    side = 1 if phr >= 0.0 else -1
    return f, gx, gy, k % z, side


@kernel(error_model="numpy", inline="always")
def sdf_value(grid, r0, dr, phi0, dphi, pitch, internal, cx, cy, th, px, py):
    """Signed distance only (no gradient): the fast path used while scanning."""
    f, _, _ = sdf_value_polar(grid, r0, dr, phi0, dphi, pitch, internal, cx, cy, th, px, py)
    return f


@kernel(error_model="numpy", inline="always")
def sdf_value_polar(grid, r0, dr, phi0, dphi, pitch, internal, cx, cy, th, px, py):
    """:func:`sdf_value` and the point's radius r [m] and global polar angle psi [rad] about the
    gear's centre (psi = 0 outside the tabulated band, where no atan2 is needed), from which
    :func:`lookup_polar` looks the point up again without the square root and arc tangent."""
    dx = px - cx
    dy = py - cy
    r = math.sqrt(dx * dx + dy * dy)
    nr = grid.shape[1]
    if r <= r0 or r >= r0 + dr * (nr - 1):  # outside the band: no atan2 needed
        bound, _, _, _, _, _, _ = _cell(grid, r0, dr, phi0, dphi, pitch, internal, r, 0.0)
        return bound, r, 0.0
    psi = math.atan2(dy, dx)
    bound, i0, j0, a, b, _, _ = _cell(grid, r0, dr, phi0, dphi, pitch, internal, r, psi - th)
    return ((1 - a) * (1 - b) * grid[0, i0, j0] + a * (1 - b) * grid[0, i0 + 1, j0]
            + (1 - a) * b * grid[0, i0, j0 + 1] + a * b * grid[0, i0 + 1, j0 + 1]), r, psi


class PlacedField(NamedTuple):
    """The signed distance field of gear Y in its current position (built inside the kernels
    from :class:`ContactTables` and the pose of Y; the fields of :class:`GearSDF`)."""

    grid: np.ndarray  # (3, nr, nphi) signed distance [m] (negative inside), normal x, y (GearSDF.grid)
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


@kernel(error_model="numpy", inline="always")
def band_value(Y, dx, dy, r):
    """:func:`sdf_value` of gear Y (a PlacedField) at the point (dx, dy) [m] from its centre,
    at distance r = sqrt(dx^2 + dy^2) [m] from it, whether the point lies inside the tabulated
    band (else the value is only a bound), and its polar angle psi [rad] (0 outside the band,
    as from :func:`_polar_probe`)."""
    grid = Y.grid
    r0 = Y.r0
    dr = Y.dr
    nr = grid.shape[1]
    if r <= r0 or r >= r0 + dr * (nr - 1):  # outside the band: no atan2 needed
        bound, _, _, _, _, _, _ = _cell(grid, r0, dr, Y.phi0, Y.dphi, Y.pitch, Y.internal, r, 0.0)
        return bound, False, 0.0
    psi = math.atan2(dy, dx)
    bound, i0, j0, a, b, _, _ = _cell(grid, r0, dr, Y.phi0, Y.dphi, Y.pitch, Y.internal, r, psi - Y.th)
    return ((1 - a) * (1 - b) * grid[0, i0, j0] + a * (1 - b) * grid[0, i0 + 1, j0]
            + (1 - a) * b * grid[0, i0, j0 + 1] + a * b * grid[0, i0 + 1, j0 + 1]), True, psi


@kernel(error_model="numpy", inline="always")
def placed_field(sdf_grids, o, nr, nphi, r0, dr, phi0, dphi, pitch, internal, z, tip, cx, cy, th):
    """A PlacedField from one geometry's entries of the ContactTables (``o``: offset of its
    grid in ``sdf_grids``) placed at (cx, cy) [m], turned by th [rad]. (Entries, not the
    tables: every array of a table handed to a function costs a reference count.)"""
    grid = sdf_grids[o:o + 3 * nr * nphi].reshape((3, nr, nphi))
    return PlacedField(grid, r0, dr, phi0, dphi, pitch, internal, z, cx, cy, th, tip)
