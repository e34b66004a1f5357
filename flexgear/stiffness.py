"""Tooth and mesh stiffness of spur gears from plane finite elements plus Hertzian contact.

Pipeline position: ``geometry -> meshing -> fe -> stiffness``. Compared with ISO 6336-1 in
:mod:`flexgear.iso6336`; the command ``python -m flexgear.stiffness`` prints the comparison
for the MERCURY 1-A sun-planet and planet-ring pairs.

Method
------
**1. Tooth compliance (one gear, FE).** The gear body is meshed (:func:`flexgear.meshing.mesh_gear`),
clamped at its bore (``"hub"``, external gears) or at its outer rim (``"rim"``, the ring) and
loaded on the left flank of tooth 0 at a contact point P of radius r, normal to the flank (the
normal of an involute lies along the line of action). A point load in 2D gives a displacement
that grows like ln(1/h) under refinement, so the load is *spread* over a smooth patch of the
flank centred on P::

    p(s) ~ (1 - s^2/w^2)^2   for |s| < w      (s: arc length along the involute from P)

with half-width ``w = spread * m`` (default 0.5 m), normalised to a unit resultant. The
displacement is measured work-conjugately, as the p-weighted mean of the normal displacement
over the same patch (``u_P = f_P . u`` with ``f_P`` the load vector), which makes the influence
matrix symmetric (Maxwell-Betti).

**2. Near field separated analytically.** The FE response to the patch load contains the
half-plane (Flamant) near field of that patch, which depends on w (logarithmically). It is
subtracted in closed form: for a pressure distribution p on a straight half-plane boundary
(Young's modulus and Poisson's ratio of the formulation, ``E1, nu1``: plane stress E, nu; plane
strain E/(1-nu^2), nu/(1-nu)), the p-weighted mean normal displacement of the loaded surface
relative to the point at depth d below the patch centre is, per unit resultant F [N] on a body
of thickness L::

    u_loc = 1/(pi E1 L) * [ 2 (ln d - J) - (1 + nu1) ],    J = int int p^ p^ ln|s - t| ds dt

(p^ = p/F normalised; derived from Flamant's displacement field; J = ln(w/2) - 1/4 for the
elliptical Hertz pressure, computed numerically for the patch, also when the patch is clipped at
the end of the flank). The remainder ``c_bulk = c_FE - u_loc`` (tooth bending, shear, rim and
body deformation up to the reference depth) does not depend on w for w small against the tooth
(checked by a test) and converges under mesh refinement.

**3. Hertzian contact, nonlinear.** Two teeth pressed together by F (per thickness P = F/L)
carry the elliptical Hertz pressure of half-width ``a = sqrt(4 P R / (pi E*))``, R the relative
radius of curvature of the involutes at the contact (rho_i = distance of the contact from the
base tangent point; R = rho1 rho2/(rho1 + rho2), internal rho1 rho2/(rho2 - rho1)). Using the
same weighted-mean displacement for the contact and the half-plane solution above with J of the
ellipse, the approach of the two reference points (depth d_i in each tooth) is, exactly for
2D Hertz line contact (the conformity condition adds a^2 / (8 R))::

    delta_H(F) = sum_i P/(pi E1_i) [2 ln(2 d_i / a) - 1/2 - nu1_i] + P / (2 pi E*)

(Weber/Johnson form; nonlinear in F through a ~ sqrt(F)). The contact zone is narrow against
the face width, so the Hertz term is taken in **plane strain** (``hertz="plane_strain"``) while
the FE body may be plane stress (the project default): the region within depth d = m of the
contact is treated as plane strain. ``hertz="same"`` uses the FE formulation (then d cancels
exactly); for the MERCURY pairs the two choices differ by 2-3 % in c'.

**4. Loaded mesh.** For a :class:`~flexgear.geometry.GearPair`, contact positions are measured
along the line of action by s (from the pitch point, positive towards the tip of gear 1),
s in [-g_f, g_a]; pairs in contact at one instant are s, s + p_b, s + 2 p_b, ... within that
path (perfect involutes, no modifications, no contact outside the theoretical path). Each gear
is solved once per pair: unit patch loads on tooth 0 at all grid points, displacements read on
teeth -1, 0, +1 give the influence matrices, including the coupling between neighbouring
loaded teeth of the same gear. The static transmission error (along the line of action) delta
and the pair loads F_k follow from compatibility and equilibrium::

    delta = sum_l [C1_kl + C2_kl] F_l + delta_H,k(F_k)  for every loaded pair k,   sum_k F_k = F

solved by iterating on the secant Hertz compliance (a pair that would pull is unloaded).
Mesh stiffness k(s) = F / delta [N/m] (secant); single-pair stiffness k'(s) = F / (C1_kk +
C2_kk + delta_H(F)/F) for one pair carrying the whole load. ISO's c' is compared with
max_s k'(s) / b and c_gamma_alpha with the mean of k over one mesh cycle, divided by b.

All quantities SI: m, N, N/m; compliances m/N; stiffness per face width N/m^2.
"""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from .errors import ConfigError
from .material import Material

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
# closed forms: plane constants, half-plane near field, Hertz line contact
# ============================================================================================
def plane_constants(material: Material, formulation: str) -> tuple[float, float]:
    """In-plane elastic constants ``(E1, nu1)`` of a 2D formulation.

    Plane stress: (E, nu); plane strain: (E/(1 - nu^2), nu/(1 - nu)). With them plane strain
    and plane stress share the same equations.

    Parameters
    ----------
    material : Material
        E [Pa], nu [-].
    formulation : {"plane_stress", "plane_strain"}
    """
    E, nu = material.E, material.nu
    if formulation == "plane_stress":
        return E, nu
    if formulation == "plane_strain":
        return E / (1.0 - nu ** 2), nu / (1.0 - nu)
    raise ConfigError(f"formulation = {formulation!r}: must be 'plane_stress' or 'plane_strain'")


def contact_modulus(m1: Material, m2: Material, formulation: str = "plane_strain") -> float:
    """Contact modulus E* [Pa], 1/E* = 1/E1_1 + 1/E1_2 (plane strain: the Hertz E*)."""
    return 1.0 / (1.0 / plane_constants(m1, formulation)[0] + 1.0 / plane_constants(m2, formulation)[0])


def hertz_half_width(F: float, R: float, thickness: float, e_star: float) -> float:
    """Half-width of the 2D Hertz contact a = sqrt(4 F R / (pi L E*)) [m].

    Parameters
    ----------
    F : float
        Normal force [N].
    R : float
        Relative radius of curvature [m].
    thickness : float
        Contact length L (face width) [m].
    e_star : float
        Contact modulus E* [Pa].
    """
    return math.sqrt(4.0 * F * R / (math.pi * thickness * e_star))


def _biweight(xi):
    return np.clip(1.0 - xi * xi, 0.0, None) ** 2


def _panel_log_integrals(edges: np.ndarray) -> np.ndarray:
    """I_ij = int_{panel i} int_{panel j} ln|s - t| dt ds (exact), panels given by edges."""
    def G(x):
        ax = np.abs(x)
        with np.errstate(divide="ignore", invalid="ignore"):
            v = 0.5 * x * x * np.log(ax) - 0.75 * x * x
        return np.where(ax > 0, v, 0.0)

    a, b = edges[:-1, None], edges[1:, None]
    c, d = edges[None, :-1], edges[None, 1:]
    return G(b - c) - G(a - c) - G(b - d) + G(a - d)


@lru_cache(maxsize=4096)
def log_self_energy(lo: float = -1.0, hi: float = 1.0, shape: str = "biweight", n: int = 400) -> float:
    """J = int int p^(s) p^(t) ln|s - t| ds dt of a unit-half-width patch clipped to [lo, hi].

    Parameters
    ----------
    lo, hi : float
        Support of the (clipped) patch in units of the half-width, -1 <= lo < hi <= 1.
    shape : {"biweight", "ellipse"}
        p ~ (1 - xi^2)^2 (the FE patch) or sqrt(1 - xi^2) (Hertz).
    n : int
        Number of panels (piecewise-constant density, exact panel log integrals).

    Returns
    -------
    float
        J [-] (for a half-width w add ln w). Unclipped ellipse: ln(1/2) - 1/4.
    """
    lo, hi = max(-1.0, lo), min(1.0, hi)
    if not hi > lo:
        raise ConfigError(f"patch support [{lo}, {hi}] is empty")
    edges = np.linspace(lo, hi, n + 1)
    # panel weights: exact integrals of the density over each panel
    if shape == "biweight":
        def prim(x):
            return x - 2.0 * x ** 3 / 3.0 + x ** 5 / 5.0
    elif shape == "ellipse":
        def prim(x):
            x = np.clip(x, -1.0, 1.0)
            return 0.5 * (x * np.sqrt(1.0 - x * x) + np.arcsin(x))
    else:
        raise ConfigError(f"shape = {shape!r}: must be 'biweight' or 'ellipse'")
    q = np.diff(prim(edges))
    q = q / q.sum()
    h = np.diff(edges)
    dens = q / h
    return float(dens @ _panel_log_integrals(edges) @ dens)


def halfplane_compliance(w: float, depth: float, material: Material, thickness: float,
                         formulation: str = "plane_stress", lo: float = -1.0, hi: float = 1.0,
                         shape: str = "biweight") -> float:
    """Near-field compliance of a patch load on a half-plane [m/N].

    p-weighted mean normal displacement of the loaded boundary, relative to the point at depth
    ``depth`` below the patch centre, per newton of resultant:
    ``1/(pi E1 L) [2 (ln d - J - ln w) - (1 + nu1)]``.

    Parameters
    ----------
    w : float
        Patch half-width [m].
    depth : float
        Reference depth d [m].
    material : Material
    thickness : float
        Body thickness L [m].
    formulation : {"plane_stress", "plane_strain"}
    lo, hi : float
        Clipped support in units of w (see :func:`log_self_energy`).
    shape : {"biweight", "ellipse"}
    """
    E1, nu1 = plane_constants(material, formulation)
    J = log_self_energy(float(lo), float(hi), shape) + math.log(w)
    return (2.0 * (math.log(depth) - J) - (1.0 + nu1)) / (math.pi * E1 * thickness)


def hertz_approach(F, R: float, thickness: float, m1: Material, m2: Material, depth1: float,
                   depth2: float, formulation: str = "plane_strain"):
    """Approach of two bodies in 2D Hertz line contact, between points at depths d1, d2 [m].

    ``delta = sum_i P/(pi E1_i) [2 ln(2 d_i / a) - 1/2 - nu1_i] + P/(2 pi E*)`` with P = F/L and
    a the Hertz half-width; consistent with :func:`halfplane_compliance` (weighted-mean
    displacements) and with Johnson's centre-line result.

    Parameters
    ----------
    F : float or ndarray
        Normal force [N] (>= 0).
    R : float
        Relative radius of curvature [m].
    thickness : float
        Contact length L [m].
    m1, m2 : Material
    depth1, depth2 : float
        Reference depths [m].
    formulation : {"plane_strain", "plane_stress"}
    """
    F = np.asarray(F, dtype=float)
    E1a, nua = plane_constants(m1, formulation)
    E1b, nub = plane_constants(m2, formulation)
    es = 1.0 / (1.0 / E1a + 1.0 / E1b)
    P = F / thickness
    out = np.zeros_like(P)
    pos = P > 0
    a = np.sqrt(4.0 * P[pos] * R / (math.pi * es))
    out[pos] = (P[pos] / (math.pi * E1a) * (2.0 * np.log(2.0 * depth1 / a) - 0.5 - nua)
                + P[pos] / (math.pi * E1b) * (2.0 * np.log(2.0 * depth2 / a) - 0.5 - nub)
                + P[pos] / (2.0 * math.pi * es))
    return out if out.ndim else float(out)


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
    """FE compliance of tooth 0's left flank at contact radii r_j, and its coupling to teeth +-1.

    Attributes
    ----------
    gear : SpurGear
    radius : ndarray (J,)
        Contact radii [m].
    roll : ndarray (J,)
        Roll angles tan(alpha_y) at the contact [rad].
    spread : ndarray (J,)
        Patch half-width used at each point [m].
    raw : ndarray (J,)
        FE compliance with the patch load, f_j . K^-1 f_j [m/N].
    near_field : ndarray (J,)
        Half-plane near field of the same patch (subtracted) [m/N].
    bulk : ndarray (J,)
        raw - near_field: tooth + body compliance to the reference depth [m/N].
    coupling : dict[int, ndarray (J, J)]
        coupling[d][i, j] = displacement of tooth d at point i per newton at tooth 0, point j
        [m/N] (d = -1, 0, 1; d = 0 off-diagonal terms are on the same tooth).
    depth : float
        Reference depth d [m].
    formulation : str
    thickness : float
        Face width [m].
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
    def stiffness_per_width(self) -> np.ndarray:
        """Bulk tooth stiffness per face width 1/(c_bulk L) [N/m^2]."""
        return 1.0 / (self.bulk * self.thickness)


def _flank_range(model, facets, gear):
    """Arc-length range [S_lo, S_hi] of the flank facets (involute arc from the base circle)."""
    nodes = np.unique(model.mesh.facets[:, facets])
    r = np.hypot(*model.mesh.p[:, nodes])
    S = involute_arc(gear, r)
    return float(S.min()), float(S.max())


def flank_patch_load(fb, rb: float, Sc: float, w: float, thickness: float, dim: int, what: str):
    """Load vector of a unit-resultant normal pressure patch on a flank.

    The pressure is a biweight in the involute arc length s (roll distance from the base
    circle) centred at ``Sc`` with half-width ``w`` [m], scaled so that its resultant over the
    facets of ``fb`` (thickness [m] in 2D, 1 in 3D) is 1 N, pointing into the body.
    """
    from skfem import Functional, LinearForm

    def pfun(x):
        s = (x[0] ** 2 + x[1] ** 2 - rb * rb) / (2.0 * rb) - Sc
        return _biweight(s / w)

    tot = Functional(lambda v: pfun(v.x)).assemble(fb) * thickness
    if not tot > 0:
        raise ConfigError(f"{what}: the load patch has no support on the meshed flank")

    @LinearForm
    def load(v, wq):
        p = pfun(wq.x) / tot
        return -thickness * p * sum(wq.n[i] * v[i] for i in range(dim))

    return load.assemble(fb)


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


class _Solver:
    """Clamped stiffness factorised once (sparse LU); solves for many right-hand sides."""

    def __init__(self, model, fixed):
        import scipy.sparse.linalg as spla

        from .fe import _free

        self.model = model
        self.free = _free(model.ndofs, fixed)
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


def build_model(gear, settings=None, material: Material | None = None,
                formulation: str = "plane_stress", cache_dir="meshes/cache"):
    """Mesh and assemble ``gear`` (thickness = its face width); returns (FEModel, GearMesh)."""
    from .fe import assemble
    from .meshing import MeshSettings, mesh_gear

    settings = MeshSettings() if settings is None else settings
    material = Material() if material is None else material
    gm = mesh_gear(gear, settings, cache_dir=cache_dir)
    model = assemble(gm, material, gear.face_width, formulation)
    return model, gm


def tooth_compliance(gear, radii, *, settings=None, material: Material | None = None,
                     formulation: str = "plane_stress", spread: float = DEFAULT_SPREAD,
                     min_spread: float = MIN_SPREAD, depth: float = DEFAULT_DEPTH,
                     neighbours: bool = True, cache_dir="meshes/cache", model=None) -> ToothCompliance:
    """Static FE compliance of one tooth along its flank, hub (or ring rim) clamped.

    Parameters
    ----------
    gear : SpurGear
        The gear; its face width is the plane-model thickness.
    radii : array_like
        Contact radii on the involute flank [m] (e.g. from :func:`roll_angle` grid or a pair's
        path of contact).
    settings : MeshSettings, optional
        Mesh level/order (default: level 2, quadratic).
    material : Material, optional
        Steel defaults.
    formulation : {"plane_stress", "plane_strain"}
    spread : float
        Patch half-width in modules (w = spread m).
    min_spread : float
        Smallest half-width (modules) where the patch meets the end of the flank.
    depth : float
        Reference depth of the near field in modules (d = depth m).
    neighbours : bool
        Also compute the coupling to teeth -1 and +1.
    cache_dir : path or None
        Mesh cache.
    model : FEModel, optional
        A model already assembled for ``gear`` (skips meshing/assembly).

    Returns
    -------
    ToothCompliance
    """
    import time

    t0 = time.perf_counter()
    material = Material() if material is None else material
    if model is None:
        model, gm = build_model(gear, settings, material, formulation, cache_dir)
        info = {"level": gm.info.get("level"), "h_tooth": gm.info.get("h_tooth")}
    else:
        info = {}
    m = gear.module
    radii = np.atleast_1d(np.asarray(radii, float))
    fixed = model.group_dofs(clamp_group(gear))
    solver = _Solver(model, fixed)
    F0, widths, lo, hi = _patch_loads(model, gear, 0, radii, spread * m, min_spread * m)
    U0 = solver.solve(F0)
    coupling = {0: F0.T @ U0}
    if neighbours:
        for d in (-1, 1):
            Fd, *_ = _patch_loads(model, gear, d, radii, spread * m, min_spread * m)
            coupling[d] = Fd.T @ U0
    raw = np.diag(coupling[0]).copy()
    L = model.thickness
    near = np.array([halfplane_compliance(w, depth * m, material, L, model.formulation, a, b)
                     for w, a, b in zip(widths, lo, hi)])
    info.update({"ndofs": model.ndofs, "seconds": time.perf_counter() - t0})
    return ToothCompliance(gear=gear, radius=radii, roll=roll_angle(gear, radii), spread=widths,
                           raw=raw, near_field=near, bulk=raw - near, coupling=coupling,
                           depth=depth * m, formulation=model.formulation, thickness=L, info=info)


def pitch_point_compliance(gear, *, settings=None, material=None, formulation="plane_stress",
                           spread=DEFAULT_SPREAD, depth=DEFAULT_DEPTH, cache_dir="meshes/cache",
                           model=None) -> float:
    """Bulk tooth compliance at the reference (pitch) circle [m/N] (see :func:`tooth_compliance`)."""
    tc = tooth_compliance(gear, [gear.r], settings=settings, material=material,
                          formulation=formulation, spread=spread, depth=depth,
                          neighbours=False, cache_dir=cache_dir, model=model)
    return float(tc.bulk[0])


# ============================================================================================
# loaded mesh of a pair
# ============================================================================================
@dataclass
class PairGrid:
    """Contact positions along the line of action of a pair on a uniform grid.

    Attributes
    ----------
    s : ndarray (J,)
        Positions from the pitch point towards the tip of gear 1 [m], spacing p_b / n, from the
        start to the end of the usable path of contact.
    n : int
        Grid points per base pitch.
    r1, r2 : ndarray (J,)
        Contact radii on gear 1 and gear 2 [m].
    R : ndarray (J,)
        Relative radius of curvature [m].
    limits : tuple(float, float)
        Usable path [s_start, s_end] [m]: the tip-circle path (-g_f, g_a) of ISO 21771,
        shortened where it would reach below a gear's form circle (contact on the fillet).
    eps_alpha : float
        Contact ratio of the usable path, (s_end - s_start) / p_b [-].
    notes : list of str
        Why the path was shortened, if it was.
    """

    s: np.ndarray
    n: int
    r1: np.ndarray
    r2: np.ndarray
    R: np.ndarray
    limits: tuple
    eps_alpha: float
    notes: list


def usable_path(pair) -> tuple[float, float, list]:
    """Path of contact on the involutes of both gears: (s_start, s_end, notes) [m].

    ISO 21771's path runs between the tip circles, (-g_f, g_a) from the pitch point. Where a tip
    would meet the mate below the mate's form circle (the end of its involute), the path ends
    at the form circle instead (no involute contact exists there; with perfect, unmodified
    flanks this is the interference the geometry check reports).
    """
    g1, g2 = pair.g1, pair.g2
    tw = math.tan(pair.alpha_w)
    gf, ga = pair.path_of_contact
    lo, hi, notes = -gf, ga, []
    t_form1 = math.sqrt(max(g1.r_form ** 2 - g1.rb ** 2, 0.0))
    s1 = t_form1 - g1.rb * tw  # gear 1 at its form circle
    if s1 > lo:
        notes.append(f"{g2.name} tip would contact {g1.name} below its form circle "
                     f"({g1.r_form*1e3:.4g} mm): path start moved by {(s1-lo)*1e3:.3g} mm")
        lo = s1
    t_form2 = math.sqrt(max(g2.r_form ** 2 - g2.rb ** 2, 0.0))
    s2 = (t_form2 - g2.rb * tw) if pair.internal else (g2.rb * tw - t_form2)
    if s2 < hi:
        notes.append(f"{g1.name} tip would contact {g2.name} beyond its form circle "
                     f"({g2.r_form*1e3:.4g} mm): path end moved by {(hi-s2)*1e3:.3g} mm")
        hi = s2
    return lo, hi, notes


def pair_grid(pair, n: int = DEFAULT_POSITIONS) -> PairGrid:
    """Uniform grid of contact positions over the usable path of contact of ``pair``."""
    g1, g2 = pair.g1, pair.g2
    lo, hi, notes = usable_path(pair)
    pb = g1.pb
    step = pb / n
    J = int(math.floor((hi - lo) / step + 1e-9)) + 1
    s = lo + step * np.arange(J)
    t1 = g1.rb * math.tan(pair.alpha_w) + s
    t2 = g2.rb * math.tan(pair.alpha_w) + (s if pair.internal else -s)
    r1, r2 = np.hypot(g1.rb, t1), np.hypot(g2.rb, t2)
    R = t1 * t2 / (t2 - t1) if pair.internal else t1 * t2 / (t1 + t2)
    return PairGrid(s=s, n=n, r1=r1, r2=r2, R=R, limits=(lo, hi), eps_alpha=(hi - lo) / pb,
                    notes=notes)


@dataclass
class MeshStiffness:
    """Quasi-static loaded mesh of a pair over one mesh cycle.

    Attributes
    ----------
    pair : GearPair
    grid : PairGrid
    load : float
        Total normal load F [N].
    s : ndarray (N,)
        Mesh position (first pair's contact position) over one base pitch [m].
    roll1 : ndarray (N,)
        Rotation of gear 1 from the first position [rad] (s / r_b1).
    n_pairs : ndarray (N,) int
        Pairs in contact.
    pair_loads : ndarray (N, 3)
        Load of the pairs at s, s + p_b, s + 2 p_b [N] (0 if not in contact).
    te : ndarray (N,)
        Static transmission error along the line of action [m].
    k_mesh : ndarray (N,)
        Mesh stiffness F / te [N/m].
    k_single : ndarray (J,)
        Single-pair stiffness over the whole path (grid points) [N/m].
    c1, c2 : ToothCompliance
        FE data of the two gears.
    hertz : str
        Hertz formulation used.
    """

    pair: object
    grid: PairGrid
    load: float
    s: np.ndarray
    roll1: np.ndarray
    n_pairs: np.ndarray
    pair_loads: np.ndarray
    te: np.ndarray
    k_mesh: np.ndarray
    k_single: np.ndarray
    c1: ToothCompliance
    c2: ToothCompliance
    hertz: str

    @property
    def face_width(self) -> float:
        """Common face width b = min(b1, b2) [m]."""
        return min(self.pair.g1.face_width, self.pair.g2.face_width)

    @property
    def c_gamma(self) -> float:
        """Mean mesh stiffness per face width over one mesh cycle [N/m^2] (compare c_gamma_alpha)."""
        return float(np.mean(self.k_mesh)) / self.face_width

    @property
    def c_single(self) -> float:
        """Maximum single-pair stiffness per face width [N/m^2] (compare ISO c')."""
        return float(np.max(self.k_single)) / self.face_width

    @property
    def te_peak_to_peak(self) -> float:
        """Peak-to-peak static transmission error [m]."""
        return float(np.ptp(self.te))


def _pair_compliance(tc1: ToothCompliance, tc2: ToothCompliance, idx, sig1: int, sig2: int):
    """Elastic compliance matrix (both gears, bulk) of the contacts at grid indices ``idx``
    (consecutive pairs one base pitch apart, idx[k] = idx[0] + k n)."""
    n = len(idx)
    C = np.zeros((n, n))
    for a in range(n):
        for b in range(n):
            if a == b:
                C[a, a] = tc1.bulk[idx[a]] + tc2.bulk[idx[a]]
                continue
            for tc, sig in ((tc1, sig1), (tc2, sig2)):
                d = sig * (a - b)  # tooth of contact a relative to the loaded tooth (contact b)
                if abs(d) > 1:
                    raise ConfigError("more than two teeth apart: contact ratio >= 3 not supported")
                C[a, b] += tc.coupling[d][idx[a], idx[b]]
    return C


def _share(C, hertz_fn, F: float, tol: float = 1e-10, max_iter: int = 100):
    """Solve delta = C F_k + h_k(F_k), sum F_k = F, F_k >= 0 (secant iteration, active set)."""
    n = C.shape[0]
    active = np.ones(n, bool)
    Fk = np.full(n, F / n)
    for _ in range(n + 1):
        idx = np.flatnonzero(active)
        f = Fk[idx].copy()
        f[f <= 0] = F / len(idx)
        for _it in range(max_iter):
            h = np.array([hertz_fn(i, fi) / fi for i, fi in zip(idx, f)])
            A = np.zeros((len(idx) + 1, len(idx) + 1))
            A[:-1, :-1] = C[np.ix_(idx, idx)] + np.diag(h)
            A[:-1, -1] = -1.0
            A[-1, :-1] = 1.0
            rhs = np.zeros(len(idx) + 1)
            rhs[-1] = F
            sol = np.linalg.solve(A, rhs)
            fnew, delta = sol[:-1], sol[-1]
            if np.any(fnew <= 0):
                break
            done = np.max(np.abs(fnew - f)) < tol * F
            f = fnew
            if done:
                break
        if np.all(fnew > 0):
            Fk = np.zeros(n)
            Fk[idx] = fnew
            return Fk, float(delta)
        worst = idx[np.argmin(fnew)]
        active[worst] = False
        Fk = np.zeros(n)
        Fk[idx] = np.maximum(fnew, 0)
    raise RuntimeError("load sharing did not converge")


def loaded_mesh(pair, load: float, *, settings=None, material: Material | None = None,
                formulation: str = "plane_stress", hertz: str = "plane_strain",
                n_positions: int = DEFAULT_POSITIONS, spread: float = DEFAULT_SPREAD,
                depth: float = DEFAULT_DEPTH, cache_dir="meshes/cache", models=None) -> MeshStiffness:
    """Static transmission error and mesh stiffness of a pair over one mesh cycle.

    Parameters
    ----------
    pair : GearPair
        g1 external, g2 external or internal; both gears meshed and clamped (hub / rim).
    load : float
        Total normal tooth force along the line of action F [N] (REFERENCE spur check:
        200 N m / r_b = 10.14 kN).
    settings : MeshSettings, optional
    material : Material, optional
        Both gears (steel defaults).
    formulation : {"plane_stress", "plane_strain"}
        FE formulation of the bodies.
    hertz : {"plane_strain", "plane_stress", "same"}
        Formulation of the Hertz near field ("same": as the FE).
    n_positions : int
        Mesh positions per base pitch (grid spacing p_b / n).
    spread, depth : float
        Patch half-width and reference depth, in modules.
    cache_dir : path or None
        Mesh cache.
    models : tuple(FEModel, FEModel), optional
        Pre-assembled models of g1 and g2.

    Returns
    -------
    MeshStiffness
    """
    if not load > 0:
        raise ConfigError(f"load = {load!r}: must be > 0 N")
    if hertz not in HERTZ_MODES:
        raise ConfigError(f"hertz = {hertz!r}: must be one of {HERTZ_MODES}")
    material = Material() if material is None else material
    g1, g2 = pair.g1, pair.g2
    grid = pair_grid(pair, n_positions)
    m1, m2 = (None, None) if models is None else models
    tc1 = tooth_compliance(g1, grid.r1, settings=settings, material=material,
                           formulation=formulation, spread=spread, depth=depth,
                           cache_dir=cache_dir, model=m1)
    tc2 = tooth_compliance(g2, grid.r2, settings=settings, material=material,
                           formulation=formulation, spread=spread, depth=depth,
                           cache_dir=cache_dir, model=m2)
    hform = formulation if hertz == "same" else hertz
    L = min(g1.face_width, g2.face_width)

    def hertz_fn(j, F):
        return hertz_approach(F, grid.R[j], L, material, material, tc1.depth, tc2.depth, hform)

    # tooth index step per +p_b along s: gear 1 radius grows with s; external gear 2 shrinks,
    # internal gear 2 grows
    sig1 = tooth_step(g1)
    sig2 = tooth_step(g2) * (1 if pair.internal else -1)
    n, J = grid.n, len(grid.s)
    k_single = np.array([load / ((tc1.bulk[j] + tc2.bulk[j]) * load + hertz_fn(j, load))
                         for j in range(J)])
    npos = min(n, J)
    te = np.zeros(npos)
    loads = np.zeros((npos, 3))
    npairs = np.zeros(npos, int)
    for k in range(npos):
        idx = list(range(k, J, n))
        if len(idx) > 3:
            raise ConfigError(f"pair {pair.name}: more than three pairs in contact are not supported")
        C = _pair_compliance(tc1, tc2, idx, sig1, sig2)
        Fk, delta = _share(C, lambda i, F: hertz_fn(idx[i], F), load)
        te[k] = delta
        loads[k, :len(idx)] = Fk
        npairs[k] = int(np.count_nonzero(Fk > 0))
    s = grid.s[:npos]
    return MeshStiffness(pair=pair, grid=grid, load=load, s=s, roll1=(s - s[0]) / g1.rb,
                         n_pairs=npairs, pair_loads=loads, te=te, k_mesh=load / te,
                         k_single=k_single, c1=tc1, c2=tc2, hertz=hertz)


# ============================================================================================
# ISO comparison
# ============================================================================================
@dataclass
class IsoComparison:
    """FE mesh stiffness against ISO 6336-1 for one pair (per face width, N/m^2).

    Attributes
    ----------
    name : str
    fe : MeshStiffness
    iso : flexgear.iso6336.PairStiffness
        ISO values with eps_alpha from the tip circles (ISO 21771, as ISO 6336 prescribes).
    iso_usable : flexgear.iso6336.PairStiffness
        ISO values with the contact ratio of the usable (involute) path the FE model uses.
    """

    name: str
    fe: MeshStiffness
    iso: object
    iso_usable: object

    @property
    def ratio_single(self) -> float:
        """FE max single-pair stiffness / ISO c' [-]."""
        return self.fe.c_single / self.iso.c_prime

    @property
    def ratio_mesh(self) -> float:
        """FE mean mesh stiffness / ISO c_gamma_alpha (tip-circle eps_alpha) [-]."""
        return self.fe.c_gamma / self.iso.c_gamma_alpha

    @property
    def ratio_mesh_usable(self) -> float:
        """FE mean mesh stiffness / ISO c_gamma_alpha with the usable-path eps_alpha [-]."""
        return self.fe.c_gamma / self.iso_usable.c_gamma_alpha

    def summary(self) -> str:
        """Text summary in ISO units."""
        from .iso6336 import to_iso_units as iso

        fe, i, u = self.fe, self.iso, self.iso_usable
        lines = [
            f"{self.name}: F = {fe.load/1e3:.4g} kN, eps_alpha = {i.eps_alpha:.3f} (tip circles), "
            f"{fe.grid.eps_alpha:.3f} (usable involute path, FE)",
            f"  c'      FE {iso(fe.c_single):6.2f}  ISO {iso(i.c_prime):6.2f} N/(mm um)"
            f"  FE/ISO {self.ratio_single:.3f}   (ISO c'_th {iso(i.single.c_th):.2f})",
            f"  c_gamma FE {iso(fe.c_gamma):6.2f}  ISO {iso(i.c_gamma_alpha):6.2f} N/(mm um)"
            f"  FE/ISO {self.ratio_mesh:.3f}   (ISO with usable eps: {iso(u.c_gamma_alpha):.2f}, "
            f"FE/ISO {self.ratio_mesh_usable:.3f})",
            f"  static TE mean {np.mean(fe.te)*1e6:.3f} um, peak-to-peak "
            f"{fe.te_peak_to_peak*1e6:.3f} um; pairs in contact {sorted(set(fe.n_pairs.tolist()))}",
        ]
        line_load = fe.load * math.cos(fe.pair.alpha_w) / fe.face_width  # F_t / b, K_A = 1
        if line_load < 1e5:
            low = (line_load / 1e5) ** 0.25
            lines.append(f"  note: F_t/b = {line_load/1e3:.3g} N/mm < 100 N/mm: ISO would reduce c' and "
                         f"c_gamma by ({line_load/1e3:.3g}/100)^0.25 = {low:.3f} (empirical low-load rule; "
                         f"not applied above)")
        lines += [f"  note: {n}" for n in fe.grid.notes]
        return "\n".join(lines)


def compare_iso(pair, load: float, name: str | None = None, **kw) -> IsoComparison:
    """Loaded-mesh FE stiffness of ``pair`` and ISO 6336-1 c', c_gamma_alpha for the same pair.

    Parameters
    ----------
    pair : GearPair
    load : float
        Normal tooth force [N].
    name : str, optional
    **kw
        Passed to :func:`loaded_mesh`.
    """
    from .iso6336 import pair_stiffness

    g1, g2 = pair.g1, pair.g2
    b = min(g1.face_width, g2.face_width)
    fe = loaded_mesh(pair, load, **kw)

    def iso(eps):
        return pair_stiffness(g1.z, g2.z, g1.module, b, internal=pair.internal,
                              alpha=g1.pressure_angle, x1=g1.x, x2=g2.x, ha=g1.ha, hf=g1.hf,
                              eps_alpha=eps)

    return IsoComparison(name or pair.name, fe, iso(pair.contact_ratio), iso(fe.grid.eps_alpha))


def plot_mesh(results, path) -> None:
    """PNG of single-pair and mesh stiffness and static TE versus gear-1 roll angle."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .iso6336 import to_iso_units as iso

    fig, axs = plt.subplots(2, 1, figsize=(7, 7), sharex=False)
    for res in results:
        fe = res.fe
        g1 = fe.pair.g1
        xi = roll_angle(g1, fe.grid.r1)
        b = fe.face_width
        line, = axs[0].plot(np.degrees(xi), iso(fe.k_single / b), "--", label=f"{res.name} single pair")
        xi_m = roll_angle(g1, fe.grid.r1[: len(fe.s)])
        axs[0].plot(np.degrees(xi_m), iso(fe.k_mesh / b), "-", color=line.get_color(),
                    label=f"{res.name} mesh")
        axs[0].axhline(iso(res.iso.c_prime), color=line.get_color(), ls=":", lw=0.8)
        axs[0].axhline(iso(res.iso.c_gamma_alpha), color=line.get_color(), ls="-.", lw=0.8)
        axs[1].plot(np.degrees(xi_m), fe.te * 1e6, color=line.get_color(), label=res.name)
    axs[0].set_xlabel("roll angle of gear 1 at the contact [deg]")
    axs[0].set_ylabel("stiffness per face width [N/(mm um)]")
    axs[0].legend(fontsize=7)
    axs[0].set_title("FE + Hertz (lines) vs ISO 6336-1 c' (dotted), c_gamma (dash-dot)", fontsize=9)
    axs[1].set_xlabel("roll angle of gear 1, first pair [deg]")
    axs[1].set_ylabel("static transmission error [um]")
    axs[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def mercury_pairs(preset: str = "mercury_1a"):
    """The MERCURY 1-A sun-planet and planet-ring pairs and material from the preset."""
    from .config import load_config

    cfg = load_config(preset)
    return cfg.pairs, cfg.material


def main(argv=None) -> int:
    """``python -m flexgear.stiffness``: FE/ISO stiffness ratios of the MERCURY 1-A pairs."""
    from .meshing import MeshSettings

    ap = argparse.ArgumentParser(prog="python -m flexgear.stiffness", description=main.__doc__)
    ap.add_argument("--level", type=int, default=2, help="mesh refinement level (default 2)")
    ap.add_argument("--order", type=int, default=2, help="element order 1 or 2 (default 2)")
    ap.add_argument("--load", type=float, default=None,
                    help="normal tooth force [N] (default: 200 N m / r_b of the planet = 10.14 kN)")
    ap.add_argument("--formulation", default="plane_stress", choices=("plane_stress", "plane_strain"))
    ap.add_argument("--hertz", default="plane_strain", choices=HERTZ_MODES)
    ap.add_argument("--positions", type=int, default=DEFAULT_POSITIONS)
    ap.add_argument("--plot", default=None, help="write a PNG of stiffness and TE vs roll angle")
    ap.add_argument("--cache-dir", default="meshes/cache")
    a = ap.parse_args(argv)
    pairs, material = mercury_pairs()
    settings = MeshSettings(level=a.level, order=a.order)
    load = a.load if a.load is not None else 200.0 / pairs["sun-planet"].g2.rb
    out = []
    for name, pair in pairs.items():
        res = compare_iso(pair, load, name=name, settings=settings, material=material,
                          formulation=a.formulation, hertz=a.hertz, n_positions=a.positions,
                          cache_dir=a.cache_dir)
        print(res.summary())
        out.append(res)
    if a.plot:
        plot_mesh(out, a.plot)
        print(f"wrote {a.plot}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
