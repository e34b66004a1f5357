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

from ..errors import ConfigError


@dataclass(frozen=True)
class RichardsonResult:
    """Result of :func:`richardson`. Arrays have shape (levels, ...) or (...) for the quantity.

    Attributes
    ----------
    values : ndarray
        Input values, coarse to fine, shape ``(n_levels, *q_shape)``.
    h : ndarray
        Element sizes, coarse to fine [m] (or any length unit; only ratios matter).
    order : ndarray
        Observed order p (NaN where the three finest values are not monotone) [-].
    extrapolated : ndarray
        Richardson value f0 (NaN where p is NaN).
    rel_error : ndarray
        |f_i - f0| / |f0| for every level, shape ``(n_levels, *q_shape)`` [-].
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
