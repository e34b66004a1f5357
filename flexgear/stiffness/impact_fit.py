"""An ADAMS IMPACT contact law fitted to the FE loaded-mesh transmission error.

The paper's rigid law (K = 3e5 N/mm^1.3) is softer than the real tooth pair; this module keeps
the rigid model and refits K and e so that the rigid mesh deflects statically as the FE mesh
does: least squares in log of the zone-weighted mean static transmission error over several
loads. Derivation: the theory page *Contact law and search*, section *Fitting the law to the
FE mesh*.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.optimize

from ..errors import ConfigError
from ..fe.meshing import USER_CACHE
from .compliance import DEFAULT_POSITIONS
from .loaded_mesh import MeshStiffness, loaded_mesh

EXPONENT_BOUNDS = (0.8, 2.0)  # search range of the fitted exponent e [-]


def contact_shares(eps: float) -> list[tuple[int, float]]:
    """Time shares ``[(n0, 1 - (eps - n0)), (n0 + 1, eps - n0)]`` of the numbers of tooth pairs in contact over one mesh cycle, n0 = floor(eps), contact ratio ``eps`` >= 1."""
    if not eps >= 1.0:
        raise ConfigError(f"contact ratio eps = {eps!r}: must be >= 1")
    n0 = int(math.floor(eps))
    frac = eps - n0
    return [(n0, 1.0 - frac), (n0 + 1, frac)]


def rigid_static_te(load, K: float, e: float, eps: float):
    """Mean static transmission error ``sum_n share_n (F / (n K))^(1/e)`` [m] of a rigid IMPACT mesh.

        ``load`` F [N] (float or array), ``K`` [N/m^e], ``e`` [-], contact ratio ``eps`` [-].
    """
    F = np.asarray(load, float)
    out = sum(share * (F / (n * K)) ** (1.0 / e) for n, share in contact_shares(eps) if share > 0)
    return float(out) if np.ndim(out) == 0 else out


def zone_pairs(ms: MeshStiffness) -> np.ndarray:
    """Number of tooth pairs on the usable path at each mesh position of ``ms`` (geometric,
    whether loaded or not), shape (N,)."""
    J, n = len(ms.grid.s), ms.grid.n
    return np.array([len(range(k, J, n)) for k in range(len(ms.te))])


def zone_mean_te(ms: MeshStiffness, eps: float | None = None) -> float:
    """Mean static transmission error [m] of an FE loaded mesh with exact zone weights.

        The TE is averaged within each zone (same number of pairs on the usable path) and the zones
        are weighted by :func:`contact_shares` of ``ms.grid.eps_alpha``, or of ``eps`` when given
        (e.g. a dynamic model's contact ratio under load).
    """
    pairs = zone_pairs(ms)
    total = 0.0
    eps = ms.grid.eps_alpha if eps is None else eps
    if int(math.floor(eps)) != int(math.floor(ms.grid.eps_alpha)):
        raise ConfigError(f"eps = {eps!r}: the FE grid of pair {ms.pair.name} has zones of "
                          f"{int(math.floor(ms.grid.eps_alpha))} and {int(math.floor(ms.grid.eps_alpha)) + 1} pairs only")
    for n, share in contact_shares(eps):
        if share <= 0:
            continue
        sel = pairs == n
        if not np.any(sel):
            raise ConfigError(f"pair {ms.pair.name}: no grid position with {n} pairs on the path "
                              f"(eps = {ms.grid.eps_alpha:.4f}, {ms.grid.n} positions per pitch); refine n_positions")
        total += share * float(np.mean(ms.te[sel]))
    return total


def fit_impact_to_te(loads, te, eps: float, exponent: float | None = None) -> tuple[float, float]:
    """K and e of the IMPACT law whose rigid mean static TE matches ``te`` at ``loads``.

    Parameters
    ----------
    loads : array_like (L,)
        Mesh normal forces [N], > 0.
    te : array_like (L,)
        Mean static transmission errors to match [m], > 0.
    eps : float
        Contact ratio of the mesh [-].
    exponent : float, optional
        Keep e fixed at this value and fit K alone. Default: fit both (needs two distinct loads).

    Returns
    -------
    (K [N/m^e], e [-])
        Least squares in log(te) (relative errors weigh the same at every load).

    Raises
    ------
    ConfigError
        Non-positive or mismatched loads / TE, too few loads for a free exponent.
    """
    F = np.asarray(loads, float)
    te = np.asarray(te, float)
    if F.ndim != 1 or F.shape != te.shape or F.size == 0:
        raise ConfigError(f"loads and te: need two 1-D arrays of the same length, got {F.shape} and {te.shape}")
    if not (np.all(F > 0) and np.all(te > 0) and np.all(np.isfinite(F)) and np.all(np.isfinite(te))):
        raise ConfigError(f"loads = {F.tolist()} N, te = {te.tolist()} m: must be finite and > 0")
    if exponent is None and np.unique(F).size < 2:
        raise ConfigError(f"loads = {F.tolist()} N: fitting K and e needs at least two distinct loads "
                          "(or give the exponent)")
    if exponent is not None and not exponent > 0:
        raise ConfigError(f"exponent = {exponent!r}: must be > 0")

    def k_for(e):
        g = rigid_static_te(1.0, 1.0, e, eps)  # g(e, eps) for F = K = 1
        logK = float(np.mean(np.log(F) + e * (np.log(g) - np.log(te))))
        return math.exp(logK)

    def cost(e):
        r = np.log(rigid_static_te(F, k_for(e), e, eps)) - np.log(te)
        return float(np.sum(r * r))

    if exponent is not None:
        return k_for(exponent), float(exponent)
    res = scipy.optimize.minimize_scalar(cost, bounds=EXPONENT_BOUNDS, method="bounded",
                                         options={"xatol": 1e-10})
    e = float(res.x)
    if min(e - EXPONENT_BOUNDS[0], EXPONENT_BOUNDS[1] - e) < 1e-6:
        raise ConfigError(f"fitted exponent e = {e:.4g} at the bound of {EXPONENT_BOUNDS}: the TE against load "
                          "is not a power law there; fix the exponent")
    return k_for(e), e


@dataclass
class ImpactFit:
    """An IMPACT law fitted to the FE loaded-mesh transmission error of a pair.

    Attributes
    ----------
    pair : GearPair
    K : float
        Fitted stiffness [N/m^e] (SI; :attr:`K_n_mm` in the paper's N-mm reading).
    e : float
        Fitted exponent [-].
    eps : float
        Contact ratio of the usable path used for both models [-].
    loads : ndarray (L,)
        Fit loads [N].
    te_fe : ndarray (L,)
        FE zone-weighted mean static TE at the loads [m] (:func:`zone_mean_te`).
    te_fit : ndarray (L,)
        The fitted rigid law's mean static TE at the loads [m] (:func:`rigid_static_te`).
    fe : list of MeshStiffness
        The FE loaded meshes, one per load.
    """

    pair: object
    K: float
    e: float
    eps: float
    loads: np.ndarray
    te_fe: np.ndarray
    te_fit: np.ndarray
    fe: list = field(repr=False, default_factory=list)

    @property
    def K_n_mm(self) -> float:
        """K in N/mm^e (ADAMS's N-mm units, as the paper's 3e5)."""
        return self.K * 1e-3 ** self.e

    @property
    def max_rel_error(self) -> float:
        """Largest relative error of the fitted mean TE against the FE over the loads [-]."""
        return float(np.max(np.abs(self.te_fit / self.te_fe - 1.0)))

    def tangent_stiffness(self, load: float) -> float:
        """Tangent stiffness dF/d delta [N/m] of one tooth pair of the fitted law carrying ``load`` [N]."""
        return self.e * load / (load / self.K) ** (1.0 / self.e)


def fit_impact_law(pair, loads, *, settings=None, material=None, formulation: str = "plane_strain",
                   hertz: str = "plane_strain", exponent: float | None = None,
                   n_positions: int = DEFAULT_POSITIONS, cache_dir=USER_CACHE) -> ImpactFit:
    """Fit an IMPACT law to the FE loaded-mesh transmission error of ``pair`` over ``loads``.

    Parameters
    ----------
    pair : GearPair
    loads : array_like (L,)
        Mesh normal forces [N] to fit at (e.g. 0.5 .. 1.5 x the static mesh force).
    settings : MeshSettings, optional
        FE mesh of both gears (use the flexible model's level for a like-for-like comparison).
    material : Material, optional
    formulation, hertz : str
        As :func:`~flexgear.stiffness.loaded_mesh.loaded_mesh` (default plane strain, as the
        flexible presets).
    exponent : float, optional
        Fix e and fit K alone.
    n_positions : int
        Mesh positions per base pitch of the FE grid.
    cache_dir : path or None
        Mesh cache.

    Returns
    -------
    ImpactFit
    """
    F = np.asarray(loads, float)
    if F.ndim != 1 or F.size == 0 or not np.all(F > 0):
        raise ConfigError(f"loads = {np.atleast_1d(F).tolist()} N: need a 1-D list of loads > 0")
    fe, tc = [], None
    for load in F:
        ms = loaded_mesh(pair, float(load), settings=settings, material=material, formulation=formulation,
                         hertz=hertz, n_positions=n_positions, cache_dir=cache_dir, compliances=tc)
        tc = (ms.c1, ms.c2)
        fe.append(ms)
    eps = fe[0].grid.eps_alpha
    te_fe = np.array([zone_mean_te(ms) for ms in fe])
    K, e = fit_impact_to_te(F, te_fe, eps, exponent)
    return ImpactFit(pair=pair, K=K, e=e, eps=eps, loads=F, te_fe=te_fe,
                     te_fit=np.asarray(rigid_static_te(F, K, e, eps)), fe=fe)
