"""Time-synchronous averages per shaft, planet-separation windows, and the regular, residual and
difference signals.

The time-synchronous average (TSA) of an angle-domain signal is the mean over its revolutions
at each angle: components synchronous with the shaft stay, the rest falls as 1/sqrt(revolutions).
For planets, McFadden's windows (J. Sound Vib. 144(1), 163-172, 1991; tapered, here Hann: J.
Vib. Acoust. 116(2), 179-187, 1994) take the signal only while a planet passes the sensor and
place it at the planet teeth then in mesh with the ring; :func:`windowed_average` divides by the
sum of the weights at every angle, so any window shape gives an unbiased average. Regular,
residual and difference signals follow Lebold et al. (Proc. 54th MFPT Meeting, 2000, 623-634).
Details and the choices made here: the guide page *Condition monitoring*.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.fft as sf

from .order import AngleSignal

__all__ = ["Average", "TSASignals", "PLANET_WINDOWS", "synchronous_average", "window_weights",
           "windowed_average", "tsa_signals", "tsa_amplitudes"]

#: Planet-separation window shapes: name -> weight at x = offset / half-width, |x| <= 1.
PLANET_WINDOWS = {
    "hann": lambda x: 0.5 * (1.0 + np.cos(np.pi * x)),
    "rectangular": lambda x: np.ones_like(x),
}


class Average(NamedTuple):
    """A synchronous average over one revolution.

    Attributes
    ----------
    values : ndarray, shape (N,)
        The average at the angles ``2 pi k / N`` of the revolution [unit of the signal].
    weight : ndarray, shape (N,)
        Sum of the weights that went into each angle: the number of revolutions for a plain
        average, the sum of the window weights for a windowed one.
    """

    values: np.ndarray
    weight: np.ndarray

    @property
    def averages(self) -> float:
        """The least number of (weighted) averages at any angle."""
        return float(np.min(self.weight))


def synchronous_average(sig: AngleSignal) -> Average:
    """Plain time-synchronous average: the mean over the revolutions of ``sig`` at each angle."""
    n = sig.samples_per_rev
    rows = sig.values[: sig.revolutions * n].reshape(sig.revolutions, n)
    return Average(rows.mean(axis=0), np.full(n, float(sig.revolutions)))


def window_weights(offset, half_width: float, kind: str = "hann") -> np.ndarray:
    """Planet-separation window weights at angular offsets from the pass.

    Parameters
    ----------
    offset : array_like
        Carrier angle of the planet minus the sensor's angle, wrapped to (-pi, pi] [rad].
    half_width : float
        Half the window's width [rad of carrier angle], > 0.
    kind : {"hann", "rectangular"}
        Window shape.

    Returns
    -------
    ndarray
        Weights in [0, 1], zero outside ``|offset| <= half_width``.
    """
    if kind not in PLANET_WINDOWS:
        raise ValueError(f"planet window {kind!r}: choose one of {', '.join(PLANET_WINDOWS)}")
    x = np.asarray(offset, dtype=float) / half_width
    inside = np.abs(x) <= 1.0
    w = np.zeros_like(x)
    w[inside] = PLANET_WINDOWS[kind](x[inside])
    return w


def windowed_average(sig: AngleSignal, weights) -> Average:
    """Weighted synchronous average: ``sum_r w x / sum_r w`` at each angle of the revolution.

    Parameters
    ----------
    sig : AngleSignal
        The signal against the shaft's angle.
    weights : array_like, shape like ``sig.values``
        Weight of every sample (the planet-separation window at its instant).

    Returns
    -------
    Average
        Angles that no window reached hold NaN in ``values`` and 0 in ``weight``; the caller
        checks ``weight`` before using the average.
    """
    n = sig.samples_per_rev
    m = sig.revolutions * n
    w = np.asarray(weights, dtype=float)[:m].reshape(-1, n)
    x = sig.values[:m].reshape(-1, n)
    total = w.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        values = np.where(total > 0, (w * x).sum(axis=0) / np.where(total > 0, total, 1.0), np.nan)
    return Average(values, total)


class TSASignals(NamedTuple):
    """A TSA split into the signals of Lebold et al. (2000), all mean-free, shape (N,).

    Attributes
    ----------
    tsa : ndarray
        The average, mean removed and limited to orders <= ``max_order``.
    regular : ndarray
        Its mesh harmonics ``k z`` and shaft orders ``1 .. shaft_orders``.
    residual : ndarray
        ``tsa - regular``.
    difference : ndarray
        The residual without the first-order sidebands ``k z +/- 1`` of the mesh harmonics.
    teeth : int
        Mesh order ``z`` (teeth meshing per revolution).
    max_order : int
        Highest order kept.
    """

    tsa: np.ndarray
    regular: np.ndarray
    residual: np.ndarray
    difference: np.ndarray
    teeth: int
    max_order: int


def tsa_signals(values, teeth: int, shaft_orders: int = 2, max_order: int | None = None) -> TSASignals:
    """Regular, residual and difference signals of a TSA.

    Parameters
    ----------
    values : array_like, shape (N,)
        The TSA over one revolution, N samples.
    teeth : int
        Mesh order ``z`` of the shaft (its tooth count; for a carrier, the ring's), >= 3.
    shaft_orders : int, optional
        Shaft orders 1..shaft_orders counted as regular (eccentricity, misalignment). Default 2.
    max_order : int, optional
        Orders above it are removed from every signal (the record's trustworthy band).
        Default: all below N/2.

    Returns
    -------
    TSASignals
    """
    x = np.asarray(values, dtype=float)
    n = x.size
    if teeth < 3:
        raise ValueError(f"tsa_signals: teeth = {teeth!r} must be >= 3")
    top = (n - 1) // 2 if max_order is None else min(int(max_order), (n - 1) // 2)
    spec = sf.rfft(x)
    orders = np.arange(spec.size)
    spec[(orders == 0) | (orders > top)] = 0.0
    mesh = (orders > 0) & (orders % teeth == 0)
    regular = mesh | ((orders >= 1) & (orders <= shaft_orders))
    side = (orders > 0) & ((orders % teeth == 1) | (orders % teeth == teeth - 1)) & ~regular

    def back(mask):
        return sf.irfft(np.where(mask, spec, 0.0), n=n)

    tsa = sf.irfft(spec, n=n)
    reg = back(regular)
    return TSASignals(tsa, reg, tsa - reg, back(~(regular | side)), int(teeth), int(top))


#: The highest moment an indicator takes (M8A): :func:`moment_grid`
MOMENT_ORDER = 8


def moment_grid(values, max_order: int) -> np.ndarray:
    """A one-revolution signal band-limited at ``max_order`` on a grid of more than
    MOMENT_ORDER x ``max_order`` samples (exact periodic interpolation: its spectrum zero-padded),
    where the sampled moments up to the 8th are those of the continuous waveform: the k-th power
    of orders <= Q holds orders <= k Q, which N samples average exactly only for N > k Q (the
    default grid, about 2.5 Q, aliased a crack's FM4 by 10 %); ``values`` itself where as dense."""
    x = np.asarray(values, dtype=float)
    n = MOMENT_ORDER * int(max_order) + 1
    if x.size >= n:
        return x
    return sf.irfft(sf.rfft(x), n) * (n / x.size)


def tsa_amplitudes(values) -> np.ndarray:
    """Amplitude of every order 0 .. N/2 of a one-revolution signal (exact on its bins: a line
    ``a cos(k angle)`` gives ``a`` at order ``k``) [unit of the signal]."""
    x = np.asarray(values, dtype=float)
    amp = np.abs(sf.rfft(x)) / x.size
    amp[1:(x.size + 1) // 2] *= 2.0
    return amp


def half_record_change(sig: AngleSignal, weights, residual, teeth: int, shaft_orders: int = 2,
                       max_order: int | None = None) -> float | None:
    """RMS of the difference between the residuals (:func:`tsa_signals`) of the record's first and
    second halves of revolutions over the RMS of the whole record's ``residual``: about 0 where
    everything the residual holds repeats with the shaft (a noise-free simulation's fault or
    error of that gear), of order 1 where content not synchronous with it leaks through the
    average. ``weights``: the planet windows (:func:`windowed_average`), None for a plain average.
    None where it cannot be told: fewer than 4 revolutions, or a half's windows not covering
    every angle."""
    n, half = sig.samples_per_rev, sig.revolutions // 2
    if half < 2:
        return None
    res = []
    for part in (slice(0, half * n), slice(half * n, 2 * half * n)):
        s = sig._replace(values=sig.values[part], times=sig.times[part])
        avg = synchronous_average(s) if weights is None else windowed_average(s, np.asarray(weights)[part])
        if not np.all(np.isfinite(avg.values)):
            return None
        res.append(tsa_signals(avg.values, teeth, shaft_orders, max_order).residual)
    return float(np.sqrt(np.mean((res[0] - res[1]) ** 2) / np.mean(np.asarray(residual) ** 2)))
