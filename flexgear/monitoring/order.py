"""Angular resampling (computed order tracking) from recorded shaft angles, and order spectra.

A simulation records every shaft's angle, so no tachometer is needed: the signal is resampled
at equal increments of a shaft's angle (Fyfe & Munck 1997, "Analysis of computed order
tracking", *Mech. Syst. Signal Process.* 11(2) 187-205), which turns lines that move with the
speed into fixed orders (cycles per revolution), also under a speed ramp. Fyfe & Munck found
the interpolation to be the main source of error after the reference timing (here exact), and
higher-order interpolation far better than linear; the signal is therefore first upsampled by a
polyphase FIR (:func:`scipy.signal.resample_poly`) and then interpolated by a cubic spline at
the instants of the angle grid, so that the spline acts on a signal sampled far above its band.
The angle grid is chosen at least as dense in time as the record even at the lowest speed
(:func:`samples_per_revolution`), so that no line of the record folds in the angle domain.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.signal as ss
from scipy.interpolate import make_interp_spline

from ..errors import ConfigError
from ..results.signals import amplitude_spectrum

__all__ = ["AngleSignal", "samples_per_revolution", "angle_grid", "angular_resample", "order_spectrum"]

UPSAMPLE = 4  # polyphase upsampling before the spline: lines at 0.4 fs sit at 0.1 of the new rate
#: The upsampling low-pass: 32 taps per phase, Kaiser beta = 10 (lines up to 0.88 x Nyquist keep
#: their amplitude within 2e-5; scipy's default design loses 0.4 % at 0.8 x Nyquist).
UPSAMPLE_FILTER = ss.firwin(2 * 32 * UPSAMPLE + 1, 1.0 / UPSAMPLE, window=("kaiser", 10.0))
TWO_PI = 2.0 * np.pi


class AngleSignal(NamedTuple):
    """A signal sampled at equal increments of a shaft angle, over whole revolutions.

    Attributes
    ----------
    values : ndarray, shape (revolutions * samples_per_rev,)
        The signal at the angles ``angle0 + 2 pi k / samples_per_rev`` [unit of the signal].
    samples_per_rev : int
        Samples per revolution.
    angle0 : float
        Angle of the first sample [rad], a whole number of revolutions, measured in the shaft's
        direction of rotation (the recorded angle times ``direction``).
    direction : int
        +1 if the recorded angle increases (counter-clockwise rotation), -1 otherwise.
    times : ndarray, shape like ``values``
        Instant of every sample [s].
    """

    values: np.ndarray
    samples_per_rev: int
    angle0: float
    direction: int
    times: np.ndarray

    @property
    def revolutions(self) -> int:
        """Number of whole revolutions held."""
        return self.values.size // self.samples_per_rev


def samples_per_revolution(fs: float, min_speed_hz: float, multiple: int = 1) -> int:
    """Samples per revolution for angular resampling without folding.

    The smallest multiple of ``multiple`` (e.g. the gear's tooth count, so that tooth pitches
    fall on samples) that is at least ``fs / min_speed_hz``: at the lowest shaft speed the angle
    grid is then as dense in time as the record, so every line the record holds stays below the
    angle domain's Nyquist order.

    Parameters
    ----------
    fs : float
        Sampling rate of the record [Hz].
    min_speed_hz : float
        Lowest shaft speed over the record [rev/s], > 0.
    multiple : int, optional
        The result is a multiple of it. Default 1.
    """
    if not (min_speed_hz > 0 and fs > 0):
        raise ValueError(f"samples_per_revolution: fs = {fs!r} Hz and min_speed_hz = {min_speed_hz!r} rev/s "
                         "must be > 0")
    multiple = max(1, int(multiple))
    return int(np.ceil(fs / min_speed_hz / multiple * (1.0 - 1e-9))) * multiple  # a speed's round-off adds no pitch


def angle_grid(fs: float, min_speed_hz: float, multiple: int, requested: int | None, name: str) -> int:
    """Samples per revolution of shaft ``name``'s angle grid: ``requested`` (``--samples-per-rev``),
    refused where it is coarser than the record at the shaft's lowest speed (the record's lines
    above the grid's Nyquist order would fold: :func:`angular_resample` applies no anti-alias
    filter), or by default :func:`samples_per_revolution` with ``multiple`` (its mesh order)."""
    if requested is None:
        return samples_per_revolution(fs, min_speed_hz, multiple)
    least = samples_per_revolution(fs, min_speed_hz)
    if requested < least:
        raise ConfigError(f"--samples-per-rev = {requested}: coarser than the record for {name}, which needs at least "
                          f"{least} ({fs:g} Hz at its lowest {min_speed_hz:.4g} rev/s): the record's lines above order "
                          f"{requested // 2} would fold into its average; give >= {least}, or leave it out (default: "
                          f"the smallest multiple of its mesh order {multiple} at least that)")
    return int(requested)


def _monotone(angle: np.ndarray, name: str) -> tuple[np.ndarray, int]:
    """The angle made increasing (times the direction of rotation) and the direction."""
    d = np.diff(angle)
    direction = 1 if angle[-1] >= angle[0] else -1
    a = direction * angle
    if not np.all(direction * d > 0):
        i = int(np.argmax(direction * d <= 0))
        raise ValueError(f"{name}: the angle must change monotonically for order tracking; it stands still or "
                         f"reverses between samples {i} and {i + 1}")
    return a, direction


def angular_resample(t, x, angle, samples_per_rev: int, name: str = "shaft") -> AngleSignal:
    """Resample ``x(t)`` at equal increments of ``angle(t)`` over the whole revolutions recorded.

    Parameters
    ----------
    t : array_like, shape (n,)
        Uniformly spaced sample instants [s].
    x : array_like, shape (n,)
        Signal [any unit].
    angle : array_like, shape (n,)
        Unwrapped shaft angle at the same instants [rad]; either direction, monotonic.
    samples_per_rev : int
        Samples per revolution of the result (see :func:`samples_per_revolution`).
    name : str, optional
        The shaft's name, for messages.

    Returns
    -------
    AngleSignal
        The samples over every whole revolution (angles multiple of 2 pi) inside the record.

    Raises
    ------
    ValueError
        Arrays of different lengths, time not uniform, an angle that stands still or reverses,
        or less than one whole revolution in the record.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    angle = np.asarray(angle, dtype=float)
    if not (t.ndim == x.ndim == angle.ndim == 1 and t.size == x.size == angle.size and t.size >= 4):
        raise ValueError(f"{name}: time, signal and angle must be 1-D of one length >= 4, got shapes {t.shape}, "
                         f"{x.shape}, {angle.shape}")
    dt = np.diff(t)
    if not (np.all(dt > 0) and np.ptp(dt) <= 1e-6 * dt.mean()):
        raise ValueError(f"{name}: the time samples must be uniformly spaced (spacing {dt.min():.6g} .. "
                         f"{dt.max():.6g} s)")
    n_rev = int(samples_per_rev)
    if n_rev < 4:
        raise ValueError(f"{name}: samples_per_rev = {samples_per_rev!r} must be >= 4")
    a, direction = _monotone(angle, name)
    r0 = int(np.ceil(a[0] / TWO_PI - 1e-12))
    r1 = int(np.floor(a[-1] / TWO_PI + 1e-12))
    if r1 - r0 < 1:
        raise ValueError(f"{name}: the record holds {(a[-1] - a[0]) / TWO_PI:.3g} revolutions, less than one "
                         "whole revolution; record a longer run")
    grid = TWO_PI * (r0 + np.arange((r1 - r0) * n_rev) / n_rev)
    times = make_interp_spline(a, t, k=3)(grid)
    x_up = ss.resample_poly(x, UPSAMPLE, 1, window=UPSAMPLE_FILTER, padtype="line")
    t_up = t[0] + np.arange(x_up.size) * (dt.mean() / UPSAMPLE)
    values = make_interp_spline(t_up, x_up, k=3)(np.clip(times, t[0], t[-1]))
    return AngleSignal(values, n_rev, TWO_PI * r0, direction, times)


def order_spectrum(sig: AngleSignal, window: str = "hann"):
    """Amplitude spectrum over orders (cycles per revolution) of an angle-domain signal.

    The whole record is one block: the order resolution is ``1 / revolutions``. Amplitudes as
    :func:`flexgear.results.signals.amplitude_spectrum` (a line ``a cos(k angle)`` gives ``a``
    at order ``k``).

    Returns
    -------
    orders : ndarray
        Orders [1/rev].
    amplitude : ndarray
        Amplitudes [unit of the signal].
    """
    return amplitude_spectrum(sig.values, float(sig.samples_per_rev), window=window)
