"""Anti-aliased decimation from the integration step rate to the output rate.

The solver records every continuous signal at its step rate f_h = 1/h (40 kHz at the default
25 us step); a result is written at the output rate f_out (5 kHz), ``out_every = f_h / f_out``
steps per output sample. Content between f_out/2 and f_h/2 (the 5th mesh harmonic of MERCURY
1-A and its carrier sidebands, 2632 / 2648 Hz, are 70 N lines) would fold back into
[0, f_out/2] by plain sampling. Before resampling, a linear-phase low-pass FIR removes it:

* passband 0 ... 0.8 f_out/2 (the *trustworthy band*, :func:`passband_hz`): gain 1 within
  0.1 % (Kaiser-window design, passband deviation = stopband level);
* transition band 0.8 ... 1.0 f_out/2: lines there are attenuated, not trustworthy;
* stopband from f_out/2 upwards: at least 60 dB down (designed for 70 dB, measured 69-70 dB),
  so whatever folds into the output spectrum is at least 60 dB below its source.

The filter (scipy.signal.kaiserord + firwin, applied by scipy.signal.resample_poly, which
removes its group delay) spans about 2 x 22 output samples. A run therefore simulates
:data:`~flexgear.app.run.TAIL_SAMPLES` output samples past the end, and the run-in covers the
start (:func:`settle_samples`).
"""
from __future__ import annotations

import functools
import math

import numpy as np
from scipy.signal import firwin, kaiserord, resample_poly

PASSBAND_FRACTION = 0.8  # trustworthy band as a fraction of the output Nyquist frequency
STOPBAND_DB = 60.0  # guaranteed attenuation above the output Nyquist frequency [dB]
#: Kaiser design attenuation [dB] (margin over STOPBAND_DB for the finite length).
DESIGN_DB = 70.0


def passband_hz(output_rate: float) -> float:
    """Upper edge [Hz] of the trustworthy band of a result at ``output_rate`` [Hz]:
    0.8 x the output Nyquist frequency (2000 Hz at 5 kHz)."""
    return PASSBAND_FRACTION * 0.5 * output_rate


@functools.lru_cache(maxsize=16)
def antialias_filter(out_every: int) -> np.ndarray:
    """Low-pass FIR taps for decimation by ``out_every`` (odd length, linear phase).

    Frequencies normalised to the input Nyquist frequency: passband edge 0.8/out_every,
    stopband edge 1/out_every (the output Nyquist frequency), Kaiser window for
    :data:`DESIGN_DB` dB; cut-off in the middle of the transition band; unit gain at 0 Hz.
    """
    if out_every < 2:
        raise ValueError(f"out_every = {out_every}: decimation needs at least 2 input samples per output")
    f_pass, f_stop = PASSBAND_FRACTION / out_every, 1.0 / out_every
    n, beta = kaiserord(DESIGN_DB, f_stop - f_pass)
    n |= 1  # odd: a type-I filter whose delay is a whole number of samples
    taps = firwin(n, 0.5 * (f_pass + f_stop), window=("kaiser", beta))
    taps.setflags(write=False)
    return taps


def settle_samples(out_every: int) -> int:
    """Output samples on each side of a sample that the filter reaches (half its length)."""
    if out_every < 2:
        return 0
    return int(math.ceil((len(antialias_filter(out_every)) // 2) / out_every))


def decimate(x: np.ndarray, out_every: int, antialias: bool = True) -> np.ndarray:
    """Resample records at times (k+1) h to samples at times (j+1) out_every h.

    Parameters
    ----------
    x : ndarray, shape (n, ...)
        Records at the step rate, first axis time; record k at time (k+1) h.
    out_every : int
        Steps per output sample.
    antialias : bool, optional
        Low-pass with :func:`antialias_filter` before resampling (default); False takes every
        ``out_every``-th record (plain sampling, as ADAMS output).

    Returns
    -------
    ndarray, shape ((n - out_every) // out_every + 1, ...)
        Sample j at time (j+1) out_every h. The first and last :func:`settle_samples` samples
        include the filter's start-up (zero padding beyond the records).
    """
    x = x[out_every - 1:]
    if out_every == 1:
        return x
    if not antialias:
        return x[::out_every]
    y = resample_poly(x, 1, out_every, axis=0, window=antialias_filter(out_every))
    return y[: (len(x) - 1) // out_every + 1]
