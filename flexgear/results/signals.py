"""Signal analysis for simulated gear signals: amplitude spectra, peaks and characteristic lines.

Conventions
-----------
- :func:`amplitude_spectrum` returns a single-sided *amplitude* spectrum: a sinusoid
  ``a cos(2 pi f0 t)`` gives a line of height ``a`` (in the unit of ``x``, e.g. N) at ``f0``.
  The window's coherent gain is divided out (scaling by the sum of the window). With the
  rectangular window this is exact for a sinusoid on a bin; other windows are exact on a bin too
  (periodic windows) and lose at most their scalloping loss between bins (hann -1.4 dB,
  flattop < 0.02 dB).
- Frequencies in Hz, amplitudes in the unit of the signal.
- Characteristic lines (:class:`Line`) of a planetary set: carrier frequency ``f_a``, mesh
  frequency ``f_m`` and its harmonics ``k f_m``, sidebands ``k f_m +/- j f_a``.
"""
from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np
import scipy.signal as _ss

__all__ = [
    "WINDOWS",
    "Peak",
    "Line",
    "amplitude_spectrum",
    "find_peaks",
    "line_amplitude",
    "db",
    "band_rms",
    "planetary_lines",
    "spur_lines",
    "lines_in_band",
]

#: Window names accepted by :func:`amplitude_spectrum` (mapped to scipy.signal.get_window).
WINDOWS: dict[str, str] = {
    "rectangular": "boxcar",
    "hann": "hann",
    "hamming": "hamming",
    "blackman": "blackman",
    "flattop": "flattop",
}
_WINDOW_ALIASES = {"rect": "rectangular", "boxcar": "rectangular", "none": "rectangular",
                   "hanning": "hann"}


class Peak(NamedTuple):
    """A spectral peak: frequency [Hz] and amplitude [unit of the signal]."""

    freq: float
    amplitude: float


class Line(NamedTuple):
    """A characteristic frequency line.

    Attributes
    ----------
    freq : float
        Frequency [Hz].
    label : str
        Label, e.g. ``"f_a"``, ``"f_m"``, ``"2f_m"``, ``"f_m-2f_a"``.
    kind : str
        ``"carrier"``, ``"mesh"`` or ``"sideband"``.
    """

    freq: float
    label: str
    kind: str


def _window(window, n: int) -> np.ndarray:
    """Periodic (DFT-even) window of length ``n`` from a name, or a given array."""
    if isinstance(window, str) or window is None:
        key = "rectangular" if window is None else window.strip().lower()
        key = _WINDOW_ALIASES.get(key, key)
        if key not in WINDOWS:
            raise ValueError(f"unknown window {window!r}; choose one of "
                             f"{', '.join(sorted(WINDOWS))}")
        return _ss.get_window(WINDOWS[key], n, fftbins=True)
    w = np.asarray(window, dtype=float)
    if w.shape != (n,):
        raise ValueError(f"window array must have the signal's length {n}, got shape {w.shape}")
    if not np.sum(w) > 0:
        raise ValueError("window array must have a positive sum")
    return w


def _detrend(x: np.ndarray, detrend) -> np.ndarray:
    if detrend in (None, False, "none"):
        return x
    if detrend == "mean":
        return x - np.mean(x, axis=-1, keepdims=True)
    if detrend == "linear":
        return _ss.detrend(x, axis=-1, type="linear")
    raise ValueError(f"unknown detrend {detrend!r}; choose 'mean', 'linear' or None")


def amplitude_spectrum(x, fs: float, window="hann", detrend="mean", nfft: int | None = None):
    """Single-sided amplitude spectrum with amplitude-correct scaling.

    Parameters
    ----------
    x : array_like, shape (..., N)
        Signal, sampled uniformly; the spectrum is taken along the last axis.
    fs : float
        Sampling rate [Hz].
    window : str or array_like, optional
        ``"rectangular"``, ``"hann"`` (default), ``"hamming"``, ``"blackman"``, ``"flattop"``
        (periodic windows from :func:`scipy.signal.get_window`), or an array of length N.
    detrend : {"mean", "linear", None}, optional
        Remove the mean (default) or a straight line before windowing, or nothing.
    nfft : int, optional
        FFT length >= N; the windowed signal is zero-padded to it (finer bin spacing
        ``fs/nfft``, the same physical resolution ``fs/N``). Default N.

    Returns
    -------
    f : ndarray, shape (nfft//2 + 1,)
        Frequencies [Hz], spacing ``fs/nfft``.
    A : ndarray, shape (..., nfft//2 + 1)
        Amplitude [unit of ``x``]: ``|X_k| / sum(w)``, doubled except at DC and Nyquist, so a
        sinusoid of amplitude ``a`` on a bin gives ``A = a`` there.

    Raises
    ------
    ValueError
        For an unknown window or detrend, ``fs <= 0``, fewer than 2 samples or ``nfft < N``.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] < 2:
        raise ValueError(f"amplitude_spectrum: need at least 2 samples, got shape {x.shape}")
    if not (np.isfinite(fs) and fs > 0):
        raise ValueError(f"amplitude_spectrum: fs must be positive, got {fs!r}")
    n = x.shape[-1]
    nfft = n if nfft is None else int(nfft)
    if nfft < n:
        raise ValueError(f"amplitude_spectrum: nfft={nfft} is shorter than the signal ({n})")
    w = _window(window, n)
    xw = _detrend(x, detrend) * w
    amp = np.abs(np.fft.rfft(xw, n=nfft, axis=-1)) / np.sum(w)
    if nfft % 2 == 0:
        amp[..., 1:-1] *= 2.0
    else:
        amp[..., 1:] *= 2.0
    return np.fft.rfftfreq(nfft, d=1.0 / fs), amp


def find_peaks(f, A, n: int, fmin: float = 0.0, fmax: float | None = None,
               min_separation_hz: float = 0.0, min_amplitude: float = 0.0,
               rel_floor: float = 1e-9) -> list[Peak]:
    """The ``n`` largest local maxima of a spectrum, sorted by amplitude (largest first).

    Parameters
    ----------
    f : array_like, shape (M,)
        Frequencies [Hz], increasing, uniformly spaced.
    A : array_like, shape (M,)
        Amplitudes.
    n : int
        Number of peaks wanted (fewer are returned if there are fewer maxima).
    fmin, fmax : float, optional
        Only peaks with ``fmin <= f <= fmax`` [Hz]. Defaults 0 and the last frequency.
        ``fmin`` > 0 skips the DC region.
    min_separation_hz : float, optional
        Minimum distance between returned peaks [Hz]; of two closer maxima the larger is
        kept. Default 0 (every local maximum).
    min_amplitude : float, optional
        Ignore maxima below this amplitude. Default 0.
    rel_floor : float, optional
        Ignore maxima below ``rel_floor`` times the largest amplitude in the band (round-off
        ripple of an exact, noise-free signal). Default 1e-9 (-180 dB).

    Returns
    -------
    list of Peak
        ``(freq, amplitude)`` named tuples.
    """
    f = np.asarray(f, dtype=float)
    A = np.asarray(A, dtype=float)
    if f.ndim != 1 or A.shape != f.shape:
        raise ValueError(f"find_peaks: f and A must be 1-D of equal length, got {f.shape}, "
                         f"{A.shape}")
    if n < 1 or f.size < 3:
        return []
    df = (f[-1] - f[0]) / (f.size - 1)
    distance = None
    if min_separation_hz > 0:
        distance = max(1, int(np.ceil(min_separation_hz / df - 1e-9)))
    idx, _ = _ss.find_peaks(A, distance=distance)
    fmax = f[-1] if fmax is None else fmax
    keep = (f[idx] >= fmin) & (f[idx] <= fmax) & (A[idx] >= min_amplitude)
    idx = idx[keep]
    if idx.size:
        band = (f >= fmin) & (f <= fmax)
        idx = idx[A[idx] >= rel_floor * np.max(A[band])]
    idx = idx[np.argsort(-A[idx], kind="stable")][:n]
    return [Peak(float(f[i]), float(A[i])) for i in idx]


def line_amplitude(f, A, f0: float, tol_hz: float | None = None) -> float:
    """Largest amplitude within ``f0 +/- tol_hz``.

    Parameters
    ----------
    f, A : array_like, shape (M,)
        Spectrum (frequencies [Hz], amplitudes).
    f0 : float
        Line frequency [Hz].
    tol_hz : float, optional
        Half-width of the search band [Hz]. Default one bin spacing.

    Returns
    -------
    float
        The maximum of ``A`` over the band.

    Raises
    ------
    ValueError
        If no bin lies in the band.
    """
    f = np.asarray(f, dtype=float)
    A = np.asarray(A, dtype=float)
    if tol_hz is None:
        tol_hz = (f[-1] - f[0]) / (f.size - 1)
    sel = np.abs(f - f0) <= tol_hz * (1 + 1e-12)
    if not np.any(sel):
        raise ValueError(f"line_amplitude: no frequency bin within {f0} +/- {tol_hz} Hz "
                         f"(spectrum covers {f[0]} .. {f[-1]} Hz)")
    return float(np.max(A[sel]))


def db(a, ref: float = 1.0):
    """Amplitude in decibels, ``20 log10(|a| / ref)``.

    Parameters
    ----------
    a : array_like or float
        Amplitude(s); zeros give a large negative number (floored at the smallest positive
        float), never ``-inf``.
    ref : float, optional
        Reference amplitude (> 0), same unit as ``a``. Default 1.

    Returns
    -------
    ndarray or float
        Level [dB re ``ref``].
    """
    if not ref > 0:
        raise ValueError(f"db: ref must be positive, got {ref!r}")
    a = np.maximum(np.abs(np.asarray(a, dtype=float)), np.finfo(float).tiny)
    out = 20.0 * np.log10(a / ref)
    return float(out) if out.ndim == 0 else out


def band_rms(x, fs: float, f_lo: float, f_hi: float, detrend="mean") -> float:
    """RMS of the part of a signal between ``f_lo`` and ``f_hi`` (Parseval, no window).

    Parameters
    ----------
    x : array_like, shape (N,)
        Signal.
    fs : float
        Sampling rate [Hz].
    f_lo, f_hi : float
        Band edges [Hz], inclusive; ``0`` and ``fs/2`` cover the whole signal (then the
        result equals the RMS of the detrended signal).
    detrend : {"mean", "linear", None}, optional
        As in :func:`amplitude_spectrum`.

    Returns
    -------
    float
        RMS [unit of ``x``].
    """
    x = _detrend(np.asarray(x, dtype=float), detrend)
    if x.ndim != 1 or x.size < 2:
        raise ValueError(f"band_rms: x must be 1-D with at least 2 samples, got {x.shape}")
    if f_hi < f_lo:
        raise ValueError(f"band_rms: f_hi={f_hi} Hz is below f_lo={f_lo} Hz")
    n = x.size
    X = np.fft.rfft(x)
    p = np.abs(X) ** 2 / n**2
    p[1:] *= 2.0
    if n % 2 == 0:
        p[-1] /= 2.0
    f = np.fft.rfftfreq(n, 1.0 / fs)
    sel = (f >= f_lo) & (f <= f_hi)
    return float(np.sqrt(np.sum(p[sel])))


def _mult(k: int, sym: str) -> str:
    return sym if k == 1 else f"{k}{sym}"


def planetary_lines(f_carrier: float, f_mesh: float, n_harmonics: int = 3,
                    n_sidebands: int = 3, n_carrier_harmonics: int = 1) -> list[Line]:
    """Characteristic lines of a planetary gear set, sorted by frequency.

    Parameters
    ----------
    f_carrier : float
        Carrier rotation frequency ``f_a`` [Hz] (relative to the ring).
    f_mesh : float
        Mesh frequency ``f_m`` [Hz].
    n_harmonics : int, optional
        Mesh harmonics ``k f_m``, k = 1..n_harmonics. Default 3.
    n_sidebands : int, optional
        Sidebands ``k f_m +/- j f_a``, j = 1..n_sidebands, around every harmonic. Default 3.
    n_carrier_harmonics : int, optional
        Carrier harmonics ``j f_a``, j = 1..n. Default 1.

    Returns
    -------
    list of Line
        Kinds ``"carrier"`` (labels ``f_a``, ``2f_a``), ``"mesh"`` (``f_m``, ``2f_m``) and
        ``"sideband"`` (``f_m-f_a``, ``2f_m+3f_a``); lines at or below 0 Hz are left out.
    """
    if not (f_carrier > 0 and f_mesh > 0):
        raise ValueError(f"planetary_lines: frequencies must be positive, got "
                         f"f_carrier={f_carrier!r}, f_mesh={f_mesh!r}")
    lines = [Line(j * f_carrier, _mult(j, "f_a"), "carrier")
             for j in range(1, n_carrier_harmonics + 1)]
    for k in range(1, n_harmonics + 1):
        fm = _mult(k, "f_m")
        lines.append(Line(k * f_mesh, fm, "mesh"))
        for j in range(1, n_sidebands + 1):
            fa = _mult(j, "f_a")
            for sign in (-1, 1):
                fr = k * f_mesh + sign * j * f_carrier
                if fr > 0:
                    lines.append(Line(fr, f"{fm}{'+' if sign > 0 else '-'}{fa}", "sideband"))
    return sorted(lines, key=lambda ln: ln.freq)


def spur_lines(f_mesh: float, n_harmonics: int = 4) -> list[Line]:
    """Mesh-harmonic lines ``k f_m`` of a fixed-axis gear pair.

    Parameters
    ----------
    f_mesh : float
        Mesh frequency ``f_m = z f_rot`` [Hz].
    n_harmonics : int, optional
        Number of harmonics. Default 4.

    Returns
    -------
    list of Line
        Kind ``"mesh"``, labels ``f_m``, ``2f_m``, ...
    """
    if not f_mesh > 0:
        raise ValueError(f"spur_lines: f_mesh must be positive, got {f_mesh!r}")
    return [Line(k * f_mesh, _mult(k, "f_m"), "mesh") for k in range(1, n_harmonics + 1)]


def lines_in_band(lines: Sequence[Line], fmin: float, fmax: float) -> list[Line]:
    """The lines with ``fmin <= freq <= fmax`` [Hz]."""
    return [ln for ln in lines if fmin <= ln.freq <= fmax]
