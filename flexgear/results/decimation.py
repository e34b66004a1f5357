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

The filter (scipy.signal.kaiserord + firwin) spans about 2 x 22 output samples. A run
therefore simulates :data:`~flexgear.app.run.TAIL_SAMPLES` output samples past the end, and the
run-in covers the start (:func:`settle_samples`). It is applied as
scipy.signal.resample_poly applies it (zero-padded ends, group delay removed), bit for bit,
by a compiled kernel that computes only the samples a result keeps, every channel of the
records in one pass (:func:`decimate_many`).
"""
from __future__ import annotations

import functools
import math

import numpy as np
from scipy.signal import firwin, kaiserord

from ..kernels import kernel

#: output samples :func:`decimate_many` computes from one copy of the records they reach (about
#: 33,000 records, 0.26 MB a channel, at 8 steps a sample), not a copy of the whole run's: a run
#: may hold records up to half the machine's memory (``flexgear.app.run.check_record_size``)
BLOCK_SAMPLES = 4096
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


@functools.lru_cache(maxsize=16)
def _placed_filter(out_every: int) -> tuple[np.ndarray, int]:
    """(taps, lead): :func:`antialias_filter` with the zeros scipy.signal.resample_poly puts in
    front of it so that output samples fall on input samples, and the number of leading output
    samples that resample_poly drops (the filter's group delay)."""
    taps = antialias_filter(out_every)
    half = (len(taps) - 1) // 2
    pad = out_every - half % out_every
    placed = np.concatenate([np.zeros(pad), taps])
    placed.setflags(write=False)
    return placed, (half + pad) // out_every


@kernel()
def _fir_decimate(x, taps, start, out_every, out):
    """out[j, c] = sum_k taps[k] x[start + j out_every - k, c] over the rows of x (zeros beyond),
    summed in the order of increasing row, as scipy.signal.upfirdn sums, so that the bits are
    the same; the channels of a row in the inner loop (contiguous: vectorised)."""
    n = x.shape[0]
    nt = taps.shape[0]
    nc = x.shape[1]
    for j in range(out.shape[0]):
        top = start + j * out_every
        lo = max(0, top - nt + 1)
        hi = min(top, n - 1)
        for c in range(nc):
            out[j, c] = 0.0
        for i in range(lo, hi + 1):
            t = taps[top - i]
            for c in range(nc):
                out[j, c] += x[i, c] * t


def decimate_many(records: list, out_every: int, antialias: bool = True, keep: slice = slice(None)) -> list:
    """:func:`decimate` of each array of ``records`` (first axis time, all of one length), its
    output samples ``keep`` only. Anti-aliased, the channels of all of them go through the
    filter together, over the records those samples reach: a few times faster than
    scipy.signal.resample_poly a channel at a time, with the same bits."""
    if out_every == 1:
        return [x[keep] for x in records]
    if not antialias:
        return [x[out_every - 1::out_every][keep] for x in records]
    n = max(len(records[0]) - (out_every - 1), 0)  # the records from time out_every h on
    first, stop, step = keep.indices((n - 1) // out_every + 1 if n else 0)
    if step != 1:
        raise ValueError(f"keep = {keep}: decimate_many keeps a range of output samples with step 1")
    count = max(stop - first, 0)
    taps, lead = _placed_filter(out_every)
    widths = [math.prod(np.shape(x)[1:]) for x in records]
    y = np.empty((count, sum(widths)))
    for b0 in range(0, count, BLOCK_SAMPLES):  # the records copied a block at a time: bounded memory
        b1 = min(count, b0 + BLOCK_SAMPLES)
        top = (first + lead + b0) * out_every  # the newest record sample first + b0 reaches
        r0 = min(max(0, top - len(taps) + 1), n)  # the block's samples reach the records r0 ... r1 - 1
        r1 = max(r0, min(n, top + (b1 - b0 - 1) * out_every + 1))
        rows = slice(out_every - 1 + r0, out_every - 1 + r1)
        block = np.concatenate([np.reshape(x[rows], (r1 - r0, w)) for x, w in zip(records, widths)], axis=1,
                               dtype=float)
        _fir_decimate(block, taps, top - r0, out_every, y[b0:b1])
    out, c = [], 0
    for r, w in zip(records, widths):
        out.append(np.ascontiguousarray(y[:, c:c + w]).reshape((count,) + np.shape(r)[1:]))
        c += w
    return out


def decimate(x: np.ndarray, out_every: int, antialias: bool = True, keep: slice = slice(None)) -> np.ndarray:
    """Resample records at times (k+1) h to samples at times (j+1) out_every h.

    Parameters
    ----------
    x : ndarray, shape (n, ...)
        Records at the step rate, first axis time; record k at time (k+1) h.
    out_every : int
        Steps per output sample.
    antialias : bool, optional
        Low-pass with :func:`antialias_filter` before resampling (default; the bits of
        scipy.signal.resample_poly with that filter); False takes every ``out_every``-th record
        (plain sampling, as ADAMS output).
    keep : slice, optional
        The output samples to return (step 1); anti-aliased, only those are computed.

    Returns
    -------
    ndarray, shape ((n - out_every) // out_every + 1, ...)
        Sample j at time (j+1) out_every h (of them those in ``keep``). The first and last
        :func:`settle_samples` samples include the filter's start-up (zero padding beyond the
        records).
    """
    return decimate_many([x], out_every, antialias, keep)[0]
