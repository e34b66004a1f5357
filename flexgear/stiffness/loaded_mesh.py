"""Loaded mesh of a gear pair: load sharing between tooth pairs, static transmission error and mesh
stiffness from the FE influence coefficients and nonlinear Hertz contact (see
:mod:`flexgear.stiffness`, step 4).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from ..fe.meshing import USER_CACHE
from ..gears.material import Material
from .compliance import DEFAULT_DEPTH, DEFAULT_POSITIONS, DEFAULT_SPREAD, HERTZ_MODES, ToothCompliance, tooth_compliance, tooth_step
from .hertz import hertz_approach

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
                depth: float = DEFAULT_DEPTH, cache_dir=USER_CACHE, models=None,
                compliances=None) -> MeshStiffness:
    """Static transmission error and mesh stiffness of a pair over one mesh cycle.

    Parameters
    ----------
    pair : GearPair
        g1 external, g2 external or internal; both gears meshed and clamped (hub / rim).
    load : float
        Total normal tooth force along the line of action F [N] (the paper's spur check:
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
        Mesh cache directory; default the per-user cache (flexgear.fe.meshing.mesh_cache_dir), None: no cache.
    models : tuple(FEModel, FEModel), optional
        Pre-assembled models of g1 and g2.
    compliances : tuple(ToothCompliance, ToothCompliance), optional
        The tooth compliances of g1 and g2 on this pair's grid (``.c1``, ``.c2`` of an earlier
        result for the same pair, settings, formulation, n_positions, spread and depth): they
        do not depend on the load, so a load sweep computes them once.

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
    if compliances is not None:
        tc1, tc2 = compliances
        if len(tc1.bulk) != len(grid.s) or len(tc2.bulk) != len(grid.s):
            raise ConfigError(f"compliances: computed on {len(tc1.bulk)} / {len(tc2.bulk)} contact positions, "
                              f"the grid of pair {pair.name} with n_positions = {n_positions} has {len(grid.s)}")
    else:
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


