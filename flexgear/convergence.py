"""Mesh-convergence bookkeeping: observed order, Richardson extrapolation, relative errors.

For a quantity that converges as f(h) = f0 + c h^p (+ higher order), three solutions on meshes
of sizes h1 > h2 > h3 with constant ratio r = h1/h2 = h2/h3 give

    p   = ln((f1 - f2) / (f2 - f3)) / ln r          (observed order)
    f0 ~= f3 + (f3 - f2) / (r^p - 1)                (Richardson extrapolation)

When the ratio is not constant, p solves (f1 - f2)/(f2 - f3) = (h1^p - h2^p)/(h2^p - h3^p)
(root-found here). With more than three levels the three finest are used for p and f0 and
the relative error of every level, |f_i - f0| / |f0|, is reported. The grid convergence index
(Roache), GCI = F_s |(f3 - f2)/f3| / (r^p - 1) with safety factor F_s = 1.25, is an error band
on the finest solution.

If (f1 - f2)/(f2 - f3) <= 0 the sequence is oscillating (not in the asymptotic range): p and
f0 are NaN and ``monotone`` is False. Vector quantities (e.g. ten natural frequencies) are
handled component-wise.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .errors import ConfigError


@dataclass(frozen=True)
class RichardsonResult:
    """Result of :func:`richardson`. Arrays have shape (levels, ...) or (...) for the quantity.

    Attributes
    ----------
    values : ndarray
        Input values, coarse to fine, shape (n_levels, *q_shape).
    h : ndarray
        Element sizes, coarse to fine [m] (or any length unit; only ratios matter).
    order : ndarray
        Observed order p (NaN where the three finest values are not monotone) [-].
    extrapolated : ndarray
        Richardson value f0 (NaN where p is NaN).
    rel_error : ndarray
        |f_i - f0| / |f0| for every level, shape (n_levels, *q_shape) [-].
    gci : ndarray
        Grid convergence index of the finest level (F_s = 1.25) [-].
    monotone : ndarray of bool
        True where the three finest values converge monotonically.
    """

    values: np.ndarray
    h: np.ndarray
    order: np.ndarray
    extrapolated: np.ndarray
    rel_error: np.ndarray
    gci: np.ndarray
    monotone: np.ndarray


def observed_order(f1, f2, f3, h1: float, h2: float, h3: float):
    """Observed order of convergence p from three solutions (coarse f1 to fine f3).

    Parameters
    ----------
    f1, f2, f3 : float or array_like
        Values on meshes of size h1 > h2 > h3.
    h1, h2, h3 : float
        Element sizes (any consistent length unit).

    Returns
    -------
    ndarray
        p [-]; NaN where (f1 - f2)/(f2 - f3) <= 0 (oscillatory) or undefined.
    """
    f1, f2, f3 = (np.asarray(v, dtype=float) for v in (f1, f2, f3))
    if not h1 > h2 > h3 > 0:
        raise ConfigError(f"h = ({h1}, {h2}, {h3}): element sizes must decrease and be > 0")
    with np.errstate(divide="ignore", invalid="ignore"):
        R = (f1 - f2) / (f2 - f3)
    R = np.atleast_1d(R)
    p = np.full(R.shape, np.nan)
    r21, r32 = h1 / h2, h2 / h3
    const = abs(r21 - r32) < 1e-9 * r21
    for i, Ri in np.ndenumerate(R):
        if not np.isfinite(Ri) or Ri <= 0:
            continue
        if const:
            p[i] = np.log(Ri) / np.log(r21)
            continue

        def g(q, Ri=Ri):
            return (h1 ** q - h2 ** q) - Ri * (h2 ** q - h3 ** q)

        # bracket the root on a wide range of orders
        lo, hi = 1e-6, 20.0
        try:
            p[i] = brentq(g, lo, hi)
        except ValueError:
            p[i] = np.nan
    return p.reshape(np.shape(f1)) if np.ndim(f1) else p[0]


def richardson(values, h=None, ratio: float | None = None, safety: float = 1.25) -> RichardsonResult:
    """Observed order, Richardson extrapolation and relative errors from >= 3 mesh levels.

    Parameters
    ----------
    values : array_like, shape (n_levels, ...)
        The quantity on each level, coarse to fine (scalar or vector per level).
    h : array_like, shape (n_levels,), optional
        Element size of each level, decreasing. Give either ``h`` or ``ratio``.
    ratio : float, optional
        Constant refinement ratio r = h_i / h_{i+1} > 1 (then h = r^-i).
    safety : float
        Safety factor F_s of the grid convergence index.

    Returns
    -------
    RichardsonResult

    Examples
    --------
    >>> hs = np.array([0.4, 0.2, 0.1])
    >>> res = richardson(3.0 + 2.0 * hs ** 2, h=hs)
    >>> round(float(res.order), 6), round(float(res.extrapolated), 9)
    (2.0, 3.0)
    """
    f = np.asarray(values, dtype=float)
    n = f.shape[0]
    if n < 3:
        raise ConfigError(f"{n} refinement levels given: Richardson extrapolation needs >= 3")
    if h is None:
        if ratio is None or not ratio > 1.0:
            raise ConfigError(f"ratio = {ratio!r}: give element sizes h or a ratio > 1")
        h = ratio ** -np.arange(n, dtype=float)
    h = np.asarray(h, dtype=float)
    if h.shape != (n,):
        raise ConfigError(f"h has shape {h.shape}, expected ({n},)")
    if np.any(np.diff(h) >= 0) or np.any(h <= 0):
        raise ConfigError(f"h = {h.tolist()}: element sizes must be > 0 and strictly decreasing")
    f1, f2, f3 = f[-3], f[-2], f[-1]
    h1, h2, h3 = h[-3], h[-2], h[-1]
    p = np.asarray(observed_order(f1, f2, f3, h1, h2, h3), dtype=float)
    r = h2 / h3
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        rp = r ** p
        f0 = f3 + (f3 - f2) / (rp - 1.0)
        rel = np.abs(f - f0) / np.abs(f0)
        gci = safety * np.abs((f3 - f2) / f3) / (rp - 1.0)
    mono = np.isfinite(p)
    return RichardsonResult(values=f, h=h, order=p, extrapolated=f0, rel_error=rel, gci=gci,
                            monotone=mono)


def errors_decrease(rel_error) -> np.ndarray:
    """True where the relative error decreases strictly from level to level.

    Parameters
    ----------
    rel_error : array_like, shape (n_levels, ...)
        Relative errors, coarse to fine.
    """
    e = np.asarray(rel_error, dtype=float)
    return np.all(np.diff(e, axis=0) < 0, axis=0)


# ============================================================================================
# mesh convergence of the gear FE models
# ============================================================================================
@dataclass
class GearConvergence:
    """Clamped natural frequencies and pitch-point tooth stiffness of one gear on several levels.

    Attributes
    ----------
    name : str
        Gear name.
    levels : ndarray (L,) of int
        Mesh refinement levels, coarse to fine.
    h : ndarray (L,)
        Element size on the teeth, h_tooth [m].
    ndofs : ndarray (L,) of int
    freqs : ndarray (L, n_modes)
        Natural frequencies with the hub (external) or outer rim (ring) clamped [Hz].
    stiffness : ndarray (L,)
        Tooth stiffness at the pitch point, 1 / c_bulk [N/m] (see :mod:`flexgear.stiffness`).
    seconds : ndarray (L,)
        Wall time per level (mesh, assembly, eigen-solve, static solve) [s].
    freq_rich, stiff_rich : RichardsonResult
        Observed order, Richardson value and relative errors.
    clamp : str
        Boundary group held fixed.
    """

    name: str
    levels: np.ndarray
    h: np.ndarray
    ndofs: np.ndarray
    freqs: np.ndarray
    stiffness: np.ndarray
    seconds: np.ndarray
    freq_rich: RichardsonResult
    stiff_rich: RichardsonResult
    clamp: str

    def level_errors(self, level: int) -> tuple[float, float]:
        """(max relative frequency error over the modes, stiffness error) of ``level`` [-]."""
        i = int(np.flatnonzero(self.levels == level)[0])
        return float(np.max(self.freq_rich.rel_error[i])), float(self.stiff_rich.rel_error[i])

    def check(self, level: int, freq_tol: float = 0.01, stiff_tol: float = 0.02) -> bool:
        """True if ``level`` is within the tolerances of the Richardson values (and all orders
        are finite, i.e. the finest three levels converge monotonically)."""
        fe, se = self.level_errors(level)
        finite = bool(np.all(self.freq_rich.monotone) and np.all(self.stiff_rich.monotone))
        return finite and fe <= freq_tol and se <= stiff_tol


def gear_convergence(gear, levels, *, order: int = 2, n_modes: int = 10, material=None,
                     formulation: str = "plane_stress", cache_dir="meshes/cache",
                     log=None) -> GearConvergence:
    """Refine the mesh of ``gear`` over ``levels`` and track modes and tooth stiffness.

    Parameters
    ----------
    gear : SpurGear
        External gears are clamped at the bore ("hub"), internal gears at the outer rim ("rim").
    levels : sequence of int
        At least three refinement levels (see :class:`flexgear.meshing.MeshSettings`),
        increasing.
    order : int
        Element order (1 or 2).
    n_modes : int
        Number of clamped natural frequencies.
    material : Material, optional
    formulation : {"plane_stress", "plane_strain"}
    cache_dir : path or None
        Mesh cache.
    log : callable, optional
        ``log(str)`` progress messages.

    Returns
    -------
    GearConvergence
    """
    import time

    from .fe import clamped_modes
    from .material import Material
    from .meshing import MeshSettings
    from .stiffness import build_model, clamp_group, pitch_point_compliance

    levels = [int(v) for v in levels]
    if len(levels) < 3 or any(b <= a for a, b in zip(levels, levels[1:])):
        raise ConfigError(f"levels = {levels}: need >= 3 strictly increasing refinement levels")
    material = Material() if material is None else material
    clamp = clamp_group(gear)
    H, N, Fq, K, T = [], [], [], [], []
    for lv in levels:
        t0 = time.perf_counter()
        model, gm = build_model(gear, MeshSettings(level=lv, order=order), material, formulation,
                                cache_dir)
        f, _ = clamped_modes(model, model.group_dofs(clamp), n_modes)
        c = pitch_point_compliance(gear, model=model)
        H.append(gm.info["h_tooth"])
        N.append(model.ndofs)
        Fq.append(f)
        K.append(1.0 / c)
        T.append(time.perf_counter() - t0)
        if log:
            log(f"{gear.name} level {lv}: {model.ndofs} dofs, f1 = {f[0]:.2f} Hz, "
                f"k_tooth = {1/c:.5g} N/m, {T[-1]:.1f} s")
    H = np.array(H)
    Fq, K = np.array(Fq), np.array(K)
    return GearConvergence(name=gear.name, levels=np.array(levels), h=H, ndofs=np.array(N),
                           freqs=Fq, stiffness=K, seconds=np.array(T),
                           freq_rich=richardson(Fq, h=H), stiff_rich=richardson(K, h=H),
                           clamp=clamp)
