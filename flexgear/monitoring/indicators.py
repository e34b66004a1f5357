"""Condition indicators of gear vibration: RMS, crest factor, kurtosis, FM0, FM4, NA4, M6A, M8A,
energy ratio and sideband energy ratio.

Each function is the published definition, on the signal it names (raw record, TSA, residual
or difference signal: :mod:`flexgear.monitoring.tsa`); :data:`INDICATORS` holds the unit, the
definition and the source of each, and ``docs/guide/monitoring.md`` the derivations and analytic
values. Normalised moments are computed with :func:`scipy.stats.moment` (central moments with
the 1/N normalisation the definitions use).
"""
from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np
import scipy.stats as st

from .tsa import tsa_amplitudes

__all__ = ["Indicator", "INDICATORS", "rms", "crest_factor", "kurtosis", "fm0", "fm4", "na4", "na4_star", "m6a",
           "m8a", "energy_ratio", "sideband_energy_ratio"]

LEBOLD = ("Lebold, McClintic, Campbell, Byington & Maynard 2000, Review of vibration analysis methods for "
          "gearbox diagnostics and prognostics, Proc. 54th MFPT Meeting, pp. 623-634")
HANNA = ("Hanna, Hatch, Kalb, Weiss & Luo 2011, Detection of wind turbine gear tooth defects using sideband "
         "energy ratio, China Wind Power 2011")
ZAKRAJSEK = ("Zakrajsek, Townsend & Decker 1993, An analysis of gear fault detection methods as applied to "
             "pitting fatigue failure data, NASA TM-105950")
DECKER = ("Decker, Handschuh & Zakrajsek 1994, An enhancement to the NA4 gear vibration diagnostic parameter, "
          "NASA TM-106553")


class Indicator(NamedTuple):
    """What an indicator is: name, unit (``signal`` = the unit of the analysed signal), the
    signal it is computed on, its definition and its source."""

    name: str
    unit: str
    on: str
    definition: str
    source: str


#: Every indicator by name, with its definition, unit and source.
INDICATORS: dict[str, Indicator] = {i.name: i for i in (
    Indicator("rms", "signal", "TSA", "sqrt(mean(x^2))", LEBOLD),
    Indicator("crest_factor", "1", "TSA", "max|x| / rms(x)", LEBOLD),
    Indicator("kurtosis", "1", "TSA", "m4 / m2^2, m_k = mean((x - mean x)^k)", LEBOLD),
    Indicator("fm0", "1", "TSA", "(max x - min x) / sum_k A(k z), mesh harmonics k z in the band "
              "(Stewart 1977)", LEBOLD),
    Indicator("fm4", "1", "difference", "m4 / m2^2 of the difference signal d (Stewart 1977)", ZAKRAJSEK),
    Indicator("na4", "1", "residual", "m4(r) / [(1/M) sum_j m2(r_j)]^2 over the records j = 1..M: the "
              "healthy baseline records and this one last (M = 1 without a baseline)", ZAKRAJSEK),
    Indicator("na4_star", "1", "residual", "m4(r) / [(1/M) sum_j m2(r_j)]^2 over the healthy baseline records "
              "j = 1..M alone (NA4*): it grows with the fault's variance and does not depend on M; undefined "
              "without a baseline", DECKER),
    Indicator("m6a", "1", "difference", "m6 / m2^3 of the difference signal (Martin 1989)", ZAKRAJSEK),
    Indicator("m8a", "1", "difference", "m8 / m2^4 of the difference signal (Martin 1989)", ZAKRAJSEK),
    Indicator("energy_ratio", "1", "difference, regular", "rms(d) / rms(regular signal) (Swansson 1980)",
              LEBOLD),
    Indicator("ser", "1", "TSA", "sum of the amplitudes of the first 3 sidebands on each side of the first "
              "mesh harmonic, at shaft orders z -/+ i, divided by the amplitude at z", HANNA),
    Indicator("ser2", "1", "TSA", "the same at the second mesh harmonic: orders 2 z -/+ i over the amplitude "
              "at 2 z", HANNA),
    Indicator("ser3", "1", "TSA", "the same at the third mesh harmonic: orders 3 z -/+ i over the amplitude "
              "at 3 z", HANNA),
)}


def _mean_free(x, name: str) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 2 or not np.all(np.isfinite(x)):
        raise ValueError(f"{name}: need a finite 1-D signal of at least 2 samples, got shape {x.shape}")
    return x


def _normalised_moment(x, k: int, name: str) -> float:
    x = _mean_free(x, name)
    m2 = st.moment(x, order=2)
    if not m2 > 0:
        raise ValueError(f"{name}: the signal is constant (zero variance); the indicator is undefined")
    return float(st.moment(x, order=k) / m2 ** (k // 2))


#: A residual or difference signal below this fraction of the TSA's RMS holds only the angular
#: resampling's round-off (about 1e-5 of a line): its normalised moments are left undefined.
NUMERICAL_FLOOR = 1e-4


def numerically_zero(x, tsa) -> bool:
    """Whether the signal ``x`` derived from the average ``tsa`` holds only round-off."""
    return rms(x) <= NUMERICAL_FLOOR * rms(tsa)


def rms(x) -> float:
    """Root mean square ``sqrt(mean(x^2))`` [unit of x] (of x as given, mean included)."""
    x = _mean_free(x, "rms")
    return float(np.sqrt(np.mean(x * x)))


def crest_factor(x) -> float:
    """``max|x| / rms(x)`` [-]: sqrt(2) for a sine, sqrt(P) for one unit impulse per P samples."""
    r = rms(x)
    if not r > 0:
        raise ValueError("crest_factor: the signal is zero")
    return float(np.max(np.abs(x)) / r)


def kurtosis(x) -> float:
    """Normalised fourth central moment ``m4 / m2^2`` [-]: 3 for Gaussian noise, 1.5 for a sine
    (Pearson's kurtosis, :func:`scipy.stats.kurtosis` with ``fisher=False``)."""
    _normalised_moment(x, 2, "kurtosis")
    return float(st.kurtosis(np.asarray(x, dtype=float), fisher=False, bias=True))


#: A mesh line below this fraction of the TSA's RMS is absent for FM0 and SER, which divide by
#: it: a ratio to round-off would read as a huge indicator.
LINE_FLOOR = 1e-4


def fm0(tsa, teeth: int, max_order: int | None = None) -> float:
    """FM0 = peak-to-peak of the TSA / sum of its mesh-harmonic amplitudes [-] (Stewart 1977):
    2 for a pure mesh tone.

    Parameters
    ----------
    tsa : array_like, shape (N,)
        One revolution.
    teeth : int
        Mesh order z.
    max_order : int, optional
        Highest order counted (the record's band). Default N/2.
    """
    x = _mean_free(tsa, "fm0")
    amp = tsa_amplitudes(x)
    top = amp.size - 1 if max_order is None else min(int(max_order), amp.size - 1)
    harm = amp[teeth: top + 1: teeth]
    if harm.size == 0 or not np.sum(harm) > LINE_FLOOR * rms(x):
        raise ValueError(f"fm0: no mesh harmonic (order {teeth}) within order {top} above {LINE_FLOOR:g} of the "
                         "TSA's RMS (a force turning with the carrier puts its mesh lines on sidebands)")
    return float(np.ptp(x) / np.sum(harm))


def fm4(difference) -> float:
    """FM4 = kurtosis of the difference signal [-] (3 when it is Gaussian)."""
    return _normalised_moment(difference, 4, "fm4")


def m6a(difference) -> float:
    """M6A = ``m6 / m2^3`` of the difference signal [-] (15 for Gaussian, 2.5 for a sine)."""
    return _normalised_moment(difference, 6, "m6a")


def m8a(difference) -> float:
    """M8A = ``m8 / m2^4`` of the difference signal [-] (105 for Gaussian, 35/8 for a sine)."""
    return _normalised_moment(difference, 8, "m8a")


def na4(residual, baseline: Sequence = ()) -> float:
    """NA4 = ``m4(r) / [mean_j m2(r_j)]^2`` [-] over the run ensemble (Zakrajsek et al. 1993).

    Parameters
    ----------
    residual : array_like
        The residual signal of this record.
    baseline : sequence of array_like or float, optional
        The residual signals of the earlier (healthy) records, or their variances ``m2``.
        Without a baseline NA4 is the residual's kurtosis.
    """
    r = _mean_free(residual, "na4")
    mean_m2 = float(np.mean(_variances(baseline, "na4") + [float(st.moment(r, order=2))]))
    if not mean_m2 > 0:
        raise ValueError("na4: the residual signals are zero")
    return float(st.moment(r, order=4) / mean_m2 ** 2)


def na4_star(residual, baseline: Sequence) -> float:
    """NA4* = ``m4(r) / [mean_j m2(r_j)]^2`` [-] over the healthy baseline records alone
    (Decker, Handschuh & Zakrajsek 1994): NA4 whose normalising variance is the gear's in good
    condition, so that it keeps growing with the damage and does not depend on how many
    healthy records there are (NA4's ensemble holds the current record too: once the fault
    dominates, NA4 tends to M^2 times the residual's kurtosis).

    Parameters
    ----------
    residual : array_like
        The residual signal of this record.
    baseline : sequence of array_like or float
        The residual signals of the healthy records, or their variances ``m2``: at least one.
    """
    r = _mean_free(residual, "na4_star")
    if not len(baseline):
        raise ValueError("na4_star: needs a healthy baseline (--baseline): NA4* is normalised by its residual "
                         "variance")
    mean_m2 = float(np.mean(_variances(baseline, "na4_star")))
    if not mean_m2 > 0:
        raise ValueError("na4_star: the baseline's residual signals are zero")
    return float(st.moment(r, order=4) / mean_m2 ** 2)


def _variances(baseline, name: str) -> list[float]:
    """The variances m2 of baseline residual signals, or the variances given."""
    return [float(b) if np.ndim(b) == 0 else float(st.moment(_mean_free(b, f"{name} baseline"), order=2))
            for b in baseline]


def energy_ratio(difference, regular) -> float:
    """Energy ratio ``rms(d) / rms(regular)`` [-] (Swansson 1980)."""
    den = rms(regular)
    if not den > 0:
        raise ValueError("energy_ratio: the regular signal is zero")
    return rms(difference) / den


#: An SER's mesh line must stand this many times above the TSA's median line (its noise floor):
#: below, its sidebands' sum reads mostly noise (about 2 x sidebands / SER_FLOOR of it, 0.6 for 3).
SER_FLOOR = 10.0


def sideband_energy_ratio(tsa, teeth: int, harmonic: int = 1, sidebands: int = 3,
                          max_order: int | None = None) -> float:
    """SER = sum of the sideband amplitudes at orders ``h z -/+ i`` (i = 1..sidebands) over the
    amplitude at ``h z`` [-] (Hanna et al. 2011: three sidebands a side at the shaft's speed, at
    each of the first mesh harmonics; a housing sensor often hears the higher ones better).

    Parameters
    ----------
    tsa : array_like, shape (N,)
        One revolution of the shaft (its orders are the shaft's harmonics).
    teeth : int
        Mesh order z.
    harmonic : int, optional
        Mesh harmonic h. Default 1.
    sidebands : int, optional
        Sidebands on each side. Default 3.
    max_order : int, optional
        Highest order the TSA holds (the record's band): the upper sidebands must lie within it.
        Default N/2.

    Undefined (ValueError) where the mesh line is absent, or stands less than :data:`SER_FLOOR`
    times above the TSA's median line away from the mesh harmonics and their sidebands: a
    sideband of noise alone would then make up much of the ratio.
    """
    amp = tsa_amplitudes(_mean_free(tsa, "ser"))
    name = "ser" if harmonic == 1 else f"ser{harmonic}"
    c = harmonic * teeth
    top = amp.size - 1 if max_order is None else min(int(max_order), amp.size - 1)
    if c + sidebands > top or c - sidebands < 1:
        raise ValueError(f"{name}: orders {c} -/+ {sidebands} do not fit in the TSA's band (orders 1 to {top})")
    if not amp[c] > LINE_FLOOR * np.sqrt(0.5 * np.sum(amp ** 2)):
        raise ValueError(f"{name}: no line at the mesh order {c} above {LINE_FLOOR:g} of the TSA's RMS (a force "
                         "turning with the carrier puts its mesh lines on sidebands)")
    k = np.arange(1, top + 1)
    far = np.minimum(k % teeth, teeth - k % teeth) > sidebands  # from every mesh harmonic (and order 0)
    floor = float(np.median(amp[k[far]])) if far.any() else 0.0
    if not amp[c] > SER_FLOOR * floor:
        raise ValueError(f"{name}: the mesh line at order {c} ({amp[c]:.3g}) stands less than {SER_FLOOR:g} times "
                         f"above the TSA's median line ({floor:.3g}: noise, or what the average leaves of other "
                         f"content): its {2 * sidebands} sidebands would read that floor, about "
                         f"{2 * sidebands * floor / amp[c]:.2g}")
    i = np.arange(1, sidebands + 1)
    return float((amp[c - i].sum() + amp[c + i].sum()) / amp[c])
