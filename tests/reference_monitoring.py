"""An independent implementation of the monitoring's averages and indicators, for
``tests/test_monitoring_reference.py``: written from the literature (McFadden 1987 on the TSA;
Stewart 1977, Martin 1989, Zakrajsek et al. 1993 and Lebold et al. 2000 on the indicators) and
the definitions of the guide *Condition monitoring*, without reading ``flexgear.monitoring``.
Plain (unwindowed) averages of the shafts a result file records; numpy, scipy and h5py only.

Conventions, as the guide states them: 4x polyphase upsampling (257-tap Kaiser FIR, beta 10),
then a cubic spline at the instants (a cubic spline of time against angle) where the shaft's
angle reaches the grid of N points per whole revolution from angle 0; N the smallest multiple of
the tooth count with N f_min >= fs; amplitudes A(k) = 2 |rfft / N|; the mean removed and the
orders above passband / f_max zeroed; regular = mesh harmonics and shaft orders 1..2, residual =
TSA - regular, difference = residual without the orders k z -/+ 1; peaks and moments of the
continuous waveforms (the signal band-limited at kmax, interpolated exactly onto more than
8 kmax points per revolution, where its sampled moments up to the 8th are exact).
"""
from __future__ import annotations

import math

import h5py
import numpy as np
from scipy import signal as ss
from scipy.interpolate import CubicSpline

UP = 4
_FIR = ss.firwin(257, 1.0 / UP, window=("kaiser", 10.0))


def samples_per_rev(fs: float, fmin: float, z: int) -> int:
    return math.ceil(fs / (fmin * z) * (1 - 1e-9)) * z


def order_track(t, x, angle, n):
    """(revolutions, n) samples of x at n equal steps of each whole revolution of ``angle``."""
    xu = ss.resample_poly(x, UP, 1, window=_FIR.copy())
    tu = t[0] + (t[1] - t[0]) / UP * np.arange(len(xu))
    r0 = math.ceil(angle[0] / (2 * np.pi) - 1e-12)
    r1 = math.floor(angle[-1] / (2 * np.pi) + 1e-12)
    grid = (r0 + np.arange((r1 - r0) * n) / n) * 2 * np.pi
    return CubicSpline(tu, xu)(CubicSpline(angle, t)(grid)).reshape(r1 - r0, n)


def moment(x, k):
    return np.mean((x - x.mean()) ** k)


def signals(tsa, z, kmax, shaft_orders=2):
    """The conditioned TSA, its regular, residual and difference signals and amplitudes."""
    n = len(tsa)
    X = np.fft.rfft(tsa) / n
    k = np.arange(len(X))
    X[(k == 0) | (k > kmax)] = 0.0
    regular = ((k % z == 0) & (k > 0)) | ((k >= 1) & (k <= shaft_orders))
    side = (((k + 1) % z == 0) | ((k - 1) % z == 0)) & (k > 1) & ~regular
    inv = lambda Y: np.fft.irfft(Y * n, n=n)  # noqa: E731
    return {"tsa": inv(X), "regular": inv(np.where(regular, X, 0)), "residual": inv(np.where(regular, 0, X)),
            "difference": inv(np.where(regular | side, 0, X)), "amp": 2 * np.abs(X)}


def dense(x, kmax):
    """The periodic band-limited x on 8 kmax + 1 points (its zero-padded spectrum), or x if denser."""
    n = 8 * kmax + 1
    return x if len(x) >= n else np.fft.irfft(np.fft.rfft(x) * n / len(x), n=n)


def indicators(s, z, kmax, baseline_m2=(), sidebands=3):
    y, r, d, reg, amp = s["tsa"], s["residual"], s["difference"], s["regular"], s["amp"]
    rms = np.sqrt(np.mean(y ** 2))
    y, r, d = (dense(v, kmax) for v in (y, r, d))
    mesh = np.arange(z, min(kmax, len(amp) - 1) + 1, z)
    return {"rms": rms, "crest_factor": np.max(np.abs(y)) / rms, "kurtosis": moment(y, 4) / moment(y, 2) ** 2,
            "fm0": (y.max() - y.min()) / amp[mesh].sum(), "fm4": moment(d, 4) / moment(d, 2) ** 2,
            "na4": moment(r, 4) / np.mean([*baseline_m2, moment(r, 2)]) ** 2,
            # NA4* (Decker, Handschuh & Zakrajsek 1994): the healthy records' variance alone
            "na4_star": moment(r, 4) / np.mean(baseline_m2) ** 2 if len(baseline_m2) else None,
            "m6a": moment(d, 6) / moment(d, 2) ** 3, "m8a": moment(d, 8) / moment(d, 2) ** 4,
            "energy_ratio": np.sqrt(np.mean(d ** 2) / np.mean(reg ** 2)),
            **{name: (sum(amp[c - i] + amp[c + i] for i in range(1, sidebands + 1)) / amp[c]
                      # undefined: upper sidebands outside the band, or a mesh line within 10 x the floor
                      if c + sidebands <= kmax and amp[c] > 10 * floor(amp, z, kmax, sidebands) else None)
               for name, c in (("ser", z), ("ser2", 2 * z), ("ser3", 3 * z))}}


def floor(amp, z, kmax, sidebands):
    """The median amplitude of orders 1..kmax farther than ``sidebands`` from every mesh harmonic."""
    far = [k for k in range(1, kmax + 1) if min(k % z, z - k % z) > sidebands]
    return float(np.median([amp[k] for k in far]))


def shaft_averages(path, signal, shafts, kmax_of=None):
    """{shaft: (signals, z, kmax)} of the plain averages of ``shafts`` (angles relative to the
    carrier in a planetary set: the sun's, and the carrier's against the ring) of the signal at
    ``signal`` ("group/dataset" or "group/dataset:column"); ``kmax_of`` caps each shaft's band."""
    with h5py.File(path, "r") as f:
        t = f["time"][()]
        name, _, col = signal.partition(":")
        x = f[name][()]
        x = x[:, int(col)] if col else x
        pb = float(f.attrs["passband_hz"])
        b = f["bodies"]
        angles = {}
        for s in shafts:
            if "carrier" in b and s == "sun":
                angles[s] = (b["sun/angle"][()] - b["carrier/angle"][()], int(b["sun"].attrs["z"]))
            elif s == "carrier":
                ring = b["ring/angle"][()] if "ring/angle" in b else 0.0
                angles[s] = (b["carrier/angle"][()] - ring, int(b["ring"].attrs["z"]))
            else:
                angles[s] = (b[f"{s}/angle"][()], int(b[s].attrs["z"]))
    fs = 1.0 / np.median(np.diff(t))
    out = {}
    for s, (angle, z) in angles.items():
        a = np.sign(angle[-1] - angle[0]) * angle
        speed = np.gradient(a, t) / (2 * np.pi)
        kmax = math.floor(pb / speed.max())
        if kmax_of is not None:
            kmax = min(kmax, kmax_of[s])
        tsa = order_track(t, x - x.mean(), a, samples_per_rev(fs, speed.min(), z)).mean(axis=0)
        out[s] = (signals(tsa, z, kmax), z, kmax)
    return out
