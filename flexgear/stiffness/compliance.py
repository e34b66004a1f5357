"""Static FE compliance of one tooth along its flank (influence coefficients), with the near field
of the patch load separated in closed form (see :mod:`flexgear.stiffness`, steps 1-2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..errors import ConfigError
from ..fe.loads import flank_patch_load
from ..fe.meshing import USER_CACHE
from ..gears.material import Material
from .hertz import halfplane_compliance

#: Default patch half-width in modules (w = DEFAULT_SPREAD * m).
DEFAULT_SPREAD = 0.5
#: Smallest patch half-width near the ends of the flank, in modules.
MIN_SPREAD = 0.1
#: Default reference depth of the near field, in modules (d = DEFAULT_DEPTH * m).
DEFAULT_DEPTH = 1.0
#: Mesh positions per base pitch in the loaded-mesh analysis.
DEFAULT_POSITIONS = 24

HERTZ_MODES = ("plane_strain", "plane_stress", "same")


# ============================================================================================
# involute flank helpers
# ============================================================================================
def involute_arc(gear, r):
    """Arc length of the involute from the base circle to radius r, (r^2 - r_b^2)/(2 r_b) [m]."""
    r = np.asarray(r, dtype=float)
    return (r * r - gear.rb ** 2) / (2.0 * gear.rb)


def roll_angle(gear, r):
    """Roll angle xi = tan(alpha_y) = sqrt(r^2 - r_b^2) / r_b of the involute at radius r [rad]."""
    r = np.asarray(r, dtype=float)
    return np.sqrt(np.clip(r * r - gear.rb ** 2, 0.0, None)) / gear.rb


def flank_point(gear, r: float, tooth: int = 0):
    """Point on the left flank (side +1) of ``tooth`` at radius r and the unit normal into the tooth.

    Returns
    -------
    point : ndarray (2,)
        [m] in the gear frame.
    normal : ndarray (2,)
        Unit normal pointing into the tooth material (the direction of a contact force).
    """
    def pt(rr):
        phi = 2.0 * math.pi * tooth / gear.z + float(gear.involute_half_angle(rr))
        return np.array([rr * math.cos(phi), rr * math.sin(phi)])

    p = pt(r)
    dr = 1e-7 * gear.module
    t = pt(r + dr) - pt(r - dr)
    n = np.array([-t[1], t[0]]) / np.hypot(*t)
    e_phi = np.array([-p[1], p[0]]) / np.hypot(*p)
    if n @ e_phi > 0:  # the tooth lies at smaller polar angle than its left flank
        n = -n
    return p, n


def tooth_step(gear) -> int:
    """Tooth-index change between two left-flank contacts one base pitch apart on the same line of
    action, going to the larger radius: +1 for external, -1 for internal gears."""
    return -1 if gear.internal else 1


# ============================================================================================
# FE influence coefficients of one gear
# ============================================================================================
@dataclass
class ToothCompliance:
    """FE compliance of tooth 0's left flank at contact radii r_j, coupled to teeth -N ... N (:attr:`reach`).

        Attributes
        ----------
        gear : SpurGear
        radius, roll, spread : ndarray (J,)
            Contact radii [m], roll angles tan(alpha_y) [rad], patch half-widths [m].
        raw : ndarray (J,)
            FE compliance with the patch load, f_j . K^-1 f_j [m/N].
        near_field : ndarray (J,)
            Half-plane near field of the same patch (subtracted) [m/N].
        bulk : ndarray (J,)
            raw - near_field: tooth + body compliance to the reference depth [m/N].
        coupling : dict[int, ndarray (J, J)]
            coupling[d][i, j]: displacement of tooth d at point i per newton at tooth 0, point j [m/N].
        depth, thickness : float
            Reference depth, face width [m].
        formulation : str
        info : dict
            Mesh and solver data (n_dofs, level, h_tooth, seconds).
    """

    gear: object
    radius: np.ndarray
    roll: np.ndarray
    spread: np.ndarray
    raw: np.ndarray
    near_field: np.ndarray
    bulk: np.ndarray
    coupling: dict
    depth: float
    formulation: str
    thickness: float
    info: dict = field(default_factory=dict)

    @property
    def reach(self) -> int:
        """Largest tooth distance N with a coupling table (0: the loaded tooth only)."""
        return max(abs(d) for d in self.coupling)

    @property
    def stiffness_per_width(self) -> np.ndarray:
        """Bulk tooth stiffness per face width 1/(c_bulk L) [N/m^2]."""
        return 1.0 / (self.bulk * self.thickness)


def _flank_range(model, facets, gear):
    """Arc-length range [S_lo, S_hi] of the flank facets (involute arc from the base circle)."""
    nodes = np.unique(model.mesh.facets[:, facets])
    r = np.hypot(*model.mesh.p[:, nodes])
    S = involute_arc(gear, r)
    return float(S.min()), float(S.max())



def _patch_loads(model, gear, tooth: int, radii, spread: float, min_spread: float):
    """Unit-resultant biweight patch loads on the left flank of ``tooth`` at ``radii``.

    Returns (F (ndofs, J), widths (J,), lo (J,), hi (J,)) with lo/hi the clipped support in
    units of each width.
    """
    from skfem import FacetBasis

    name = f"tooth{tooth % gear.z}_left"
    if name not in model.mesh.boundaries:
        raise ConfigError(f"mesh of {gear.name} has no boundary {name!r}")
    facets = model.mesh.boundaries[name]
    S_lo, S_hi = _flank_range(model, facets, gear)
    fb = FacetBasis(model.mesh, model.basis.elem, facets=facets, intorder=8)
    L = model.thickness
    rb = gear.rb
    cols, widths, los, his = [], [], [], []
    for r in np.atleast_1d(radii):
        Sc = float(involute_arc(gear, r))
        if not (S_lo - 1e-9 <= Sc <= S_hi + 1e-9):
            raise ConfigError(
                f"{gear.name}: contact radius {r*1e3:.4g} mm lies off the involute flank "
                f"(arc {Sc*1e3:.4g} mm not in [{S_lo*1e3:.4g}, {S_hi*1e3:.4g}] mm)")
        w = min(spread, max(min_spread, min(Sc - S_lo, S_hi - Sc)))
        lo, hi = max(-1.0, (S_lo - Sc) / w), min(1.0, (S_hi - Sc) / w)
        cols.append(flank_patch_load(fb, rb, Sc, w, L, 2, f"{gear.name}: patch at r = {r*1e3:.4g} mm"))
        widths.append(w)
        los.append(lo)
        his.append(hi)
    return np.column_stack(cols), np.array(widths), np.array(los), np.array(his)


class _ClampedSolver:
    """Clamped stiffness factorised once (sparse LU); solves for many right-hand sides."""

    def __init__(self, model, fixed):
        import scipy.sparse.linalg as spla

        from ..fe.elasticity import free_dofs

        self.model = model
        self.free = free_dofs(model.ndofs, fixed)
        Kff = model.K[self.free][:, self.free].tocsc()
        self.lu = spla.splu(Kff, permc_spec="COLAMD")

    def solve(self, F):
        F = np.asarray(F, float)
        U = np.zeros_like(F)
        U[self.free] = self.lu.solve(np.ascontiguousarray(F[self.free]))
        return U


def clamp_group(gear) -> str:
    """Boundary held fixed: ``"rim"`` (outer rim) for internal gears, ``"hub"`` (bore) otherwise."""
    return "rim" if gear.internal else "hub"


def tooth_fe_model(gear, settings=None, material: Material | None = None,
                formulation: str = "plane_stress", cache_dir=USER_CACHE):
    """Mesh and assemble ``gear`` (thickness = its face width); returns (FEModel, GearMesh)."""
    from ..fe.elasticity import assemble
    from ..fe.meshing import MeshSettings, mesh_gear

    settings = MeshSettings() if settings is None else settings
    material = Material() if material is None else material
    gm = mesh_gear(gear, settings, cache_dir=cache_dir)
    model = assemble(gm, material, gear.face_width, formulation)
    return model, gm


def tooth_compliance(gear, radii, *, settings=None, material: Material | None = None,
                     formulation: str = "plane_stress", spread: float = DEFAULT_SPREAD,
                     min_spread: float = MIN_SPREAD, depth: float = DEFAULT_DEPTH,
                     neighbours: bool | int = True, cache_dir=USER_CACHE, model=None) -> ToothCompliance:
    """Static FE compliance of one tooth along its flank, hub (or ring rim) clamped.

        Parameters
        ----------
        gear : SpurGear
            Its face width is the plane-model thickness.
        radii : array_like
            Contact radii on the involute flank [m].
        settings : MeshSettings, optional
            Mesh level/order (default: level 2, quadratic).
        material : Material, optional
            Steel defaults.
        formulation : {"plane_stress", "plane_strain"}
        spread, min_spread, depth : float
            Patch half-width, its smallest value at the end of the flank, and reference depth of the
            near field, in modules.
        neighbours : bool or int
            Coupling sampled on teeth -N ... N (``True``: 1); at most (z - 1) // 2, so that no tooth
            is reached from both sides.
        cache_dir : path or None
            Mesh cache directory (default the per-user cache; None: no cache).
        model : FEModel, optional
            A model already assembled for ``gear``.

        Returns
        -------
        ToothCompliance
    """
    import time

    t0 = time.perf_counter()
    reach = coupling_reach(gear, neighbours)
    material = Material() if material is None else material
    if model is None:
        model, gm = tooth_fe_model(gear, settings, material, formulation, cache_dir)
        info = {"level": gm.info.get("level"), "h_tooth": gm.info.get("h_tooth")}
    else:
        info = {}
    m = gear.module
    radii = np.atleast_1d(np.asarray(radii, float))
    fixed = model.group_dofs(clamp_group(gear))
    solver = _ClampedSolver(model, fixed)
    F0, widths, lo, hi = _patch_loads(model, gear, 0, radii, spread * m, min_spread * m)
    U0 = solver.solve(F0)
    # the patch loads touch a few flank dofs: sample the field through sparse columns
    coupling = {0: np.asarray(sp.csc_matrix(F0).T @ U0)}
    for d in range(-reach, reach + 1):
        if d != 0:
            Fd, *_ = _patch_loads(model, gear, d, radii, spread * m, min_spread * m)
            coupling[d] = np.asarray(sp.csc_matrix(Fd).T @ U0)
    raw = np.diag(coupling[0]).copy()
    L = model.thickness
    near = np.array([halfplane_compliance(w, depth * m, material, L, model.formulation, a, b)
                     for w, a, b in zip(widths, lo, hi)])
    info.update({"ndofs": model.ndofs, "seconds": time.perf_counter() - t0})
    return ToothCompliance(gear=gear, radius=radii, roll=roll_angle(gear, radii), spread=widths,
                           raw=raw, near_field=near, bulk=raw - near, coupling=coupling,
                           depth=depth * m, formulation=model.formulation, thickness=L, info=info)


def coupling_reach(gear, neighbours) -> int:
    """Tooth distance N of the coupling tables asked for by ``neighbours`` (see
    :func:`tooth_compliance`): True -> 1, False -> 0, an int N with 0 <= N <= (z - 1) // 2."""
    if isinstance(neighbours, (bool, np.bool_)):
        return int(bool(neighbours))
    if not isinstance(neighbours, (int, np.integer)) or not 0 <= neighbours <= (gear.z - 1) // 2:
        raise ConfigError(f"{gear.name}: neighbours = {neighbours!r}: must be True, False or a tooth "
                          f"distance N with 0 <= N <= (z - 1) // 2 = {(gear.z - 1) // 2}")
    return int(neighbours)


def pitch_point_compliance(gear, *, settings=None, material=None, formulation="plane_stress",
                           spread=DEFAULT_SPREAD, depth=DEFAULT_DEPTH, cache_dir=USER_CACHE,
                           model=None) -> float:
    """Bulk tooth compliance at the reference (pitch) circle [m/N] (see :func:`tooth_compliance`)."""
    tc = tooth_compliance(gear, [gear.r], settings=settings, material=material,
                          formulation=formulation, spread=spread, depth=depth,
                          neighbours=False, cache_dir=cache_dir, model=model)
    return float(tc.bulk[0])


