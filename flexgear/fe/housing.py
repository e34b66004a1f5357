"""The housing's plane FE model: Gmsh mesh of the wall and the cover, K and M by scikit-fem.

Pipeline position: ``gears.housing (geometry) -> fe.housing -> reduction.housing``.

Mesh sizes (``level`` 2 the default; sizes shrink by sqrt(2) per level)::

    h      = wall_thickness / 2 / sqrt(2)**(level - 2)       (everywhere: 2 elements through the wall)
    h_hole = min(h, pi d / 16 / sqrt(2)**(level - 2))          (on a hole of diameter d: 16 around it)

growing linearly from ``h_hole`` at a hole's edge to ``h`` one diameter away. Boundary groups:
``outer`` (the outer outline), ``foot<k>`` (the pad of foot k, a part of ``outer``), ``inner``
(the wall's inner outline: the cavity's edge without a cover, else the line between the two
regions), ``seat_<name>`` and ``bolt<k>`` (the holes' edges). Regions ``wall`` (out-of-plane
thickness ``depth``) and ``cover`` (``cover_thickness``).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from ..gears.housing import Housing
from .elasticity import FEModel, assemble
from .meshing import GearMesh, mesh_regions

#: holes' circumference in elements at level 2
HOLE_ELEMENTS = 16


def housing_sizes(housing: Housing) -> tuple[float, dict]:
    """``(h, {hole name: h_hole})`` [m] (module docstring)."""
    f = math.sqrt(2.0) ** (housing.level - 2)
    h = 0.5 * housing.wall_thickness / f
    return h, {name: min(h, math.pi * d / HOLE_ELEMENTS / f) for name, _, d in housing.holes()}


def mesh_housing(housing: Housing) -> GearMesh:
    """Mesh the housing (wall and cover regions, holes, foot pads); not cached here (the
    reduction's cache keeps the mesh it was built on).

    Raises
    ------
    ConfigError
        A level or order out of range.
    """
    if housing.level not in range(0, 6) or housing.order not in (1, 2):
        raise ConfigError(f"housing level = {housing.level!r}, order = {housing.order!r}: level in 0..5, order 1 or 2")
    h, h_holes = housing_sizes(housing)
    w = housing.foot_width
    breaks = [s + d for s in housing.feet for d in (-0.5 * w, 0.5 * w)]
    outer_pieces = housing.outline.pieces(breaks)
    inner_pieces = housing.inner.pieces([])
    holes = housing.holes()
    state = {}

    def build(geo):
        pts = {}

        def point(p, size):
            k = (round(float(p[0]), 12), round(float(p[1]), 12))
            if k not in pts:
                pts[k] = geo.addPoint(k[0], k[1], 0.0, size)
            return pts[k]

        def curve(part, size):
            a, b = point(part[1], size), point(part[2], size)
            if part[0] == "line":
                return geo.addLine(a, b)
            return geo.addCircleArc(a, point(part[3], size), b)

        groups = {"outer": []}
        for k, (s0, s1, parts) in enumerate(outer_pieces):
            tags = [curve(p, h) for p in parts]
            groups["outer"] += tags
            if housing.feet:
                foot = _foot_of(housing, 0.5 * (s0 + s1))
                if foot is not None:
                    groups[f"foot{foot}"] = tags
        inner = [curve(p, h) for _, _, parts in inner_pieces for p in parts]
        groups["inner"] = inner
        hole_loops = []
        for name, c, d in holes:
            hh = h_holes[name]
            r = 0.5 * d
            ring = [point(c + r * np.array([math.cos(a), math.sin(a)]), hh) for a in np.arange(4) * 0.5 * math.pi]
            centre = point(c, hh)
            loop = [geo.addCircleArc(ring[i], centre, ring[(i + 1) % 4]) for i in range(4)]
            groups[name] = loop
            hole_loops.append(loop)
        state["holes"] = [t for loop in hole_loops for t in loop]
        regions = {"wall": [groups["outer"], inner]}
        if housing.cover_thickness > 0:
            regions["cover"] = [inner] + hole_loops
        return regions, groups

    def fields(gmsh):
        fm = gmsh.model.mesh.field
        const = fm.add("Constant")
        fm.setNumber(const, "VIn", h)
        parts = [const]
        for (name, _, d), k in zip(holes, range(len(holes))):
            dist = fm.add("Distance")
            fm.setNumbers(dist, "CurvesList", state["holes"][4 * k:4 * k + 4])
            fm.setNumber(dist, "Sampling", 40)
            thr = fm.add("Threshold")
            fm.setNumber(thr, "InField", dist)
            fm.setNumber(thr, "SizeMin", h_holes[name])
            fm.setNumber(thr, "SizeMax", h)
            fm.setNumber(thr, "DistMin", 0.0)
            fm.setNumber(thr, "DistMax", d)
            parts.append(thr)
        mn = fm.add("Min")
        fm.setNumbers(mn, "FieldsList", parts)
        fm.setAsBackgroundMesh(mn)

    h_min = min([h] + list(h_holes.values()))
    gm = mesh_regions(build, housing.order, 0.5 * h_min, h, fields)
    gm.info.update({"h": h, "h_holes": h_holes, "level": housing.level})
    return gm


def _foot_of(housing: Housing, s: float) -> int | None:
    """The foot whose pad holds the outline point at arc length ``s`` [m], else None."""
    L = housing.outline.length
    for k, c in enumerate(housing.feet):
        d = (s - c + 0.5 * L) % L - 0.5 * L
        if abs(d) < 0.5 * housing.foot_width:
            return k
    return None


def housing_thickness(housing: Housing) -> dict:
    """Out-of-plane thickness of each region [m]."""
    t = {"wall": float(housing.depth)}
    if housing.cover_thickness > 0:
        t["cover"] = float(housing.cover_thickness)
    return t


def assemble_housing(housing: Housing, mesh: GearMesh | None = None) -> FEModel:
    """K [N/m] and M [kg] of the housing (``mesh`` default :func:`mesh_housing`)."""
    mesh = mesh_housing(housing) if mesh is None else mesh
    return assemble(mesh, housing.material, housing_thickness(housing), housing.formulation)
