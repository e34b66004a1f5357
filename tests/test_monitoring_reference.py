"""flexgear's monitoring against an independent implementation of the same definitions
(``tests/reference_monitoring.py``, written from the literature and the guide without reading
``flexgear.monitoring``): every indicator of every plain shaft average within 1e-4, on a
simulated cracked spur pair and on a synthetic planetary record with noise, a faulty planet and a
healthy baseline for NA4 (measured at most 6e-6). The two differ in the round-off of the
resampling at the record's edge (a few 1e-5 where a revolution starts on the first sample)."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import monitoring_data as md
import reference_monitoring as ref
from flexgear.monitoring import MonitorSettings, monitor
from flexgear.monitoring.leaks import mostly_partner

INDICATORS = ("rms", "crest_factor", "kurtosis", "fm0", "fm4", "na4", "na4_star", "m6a", "m8a", "energy_ratio", "ser",
              "ser2", "ser3")


def _compare(report, mine, baseline_m2=None):
    for shaft, (sig, z, kmax) in mine.items():
        got = report.shafts[shaft]
        assert got.signals.max_order == kmax, shaft
        want = ref.indicators(sig, z, kmax, (baseline_m2 or {}).get(shaft, ()))
        for name in INDICATORS:
            if want[name] is None:  # outside the band, a mesh line in the floor, or no baseline for NA4*
                assert got.indicators[name] is None and ("band" in got.notes[name] or "median line"
                                                         in got.notes[name] or "baseline" in got.notes[name]), (
                    shaft, name)
            else:
                assert got.indicators[name] == pytest.approx(want[name], rel=1e-4), (shaft, name)


def test_a_cracked_spur_pair_as_an_independent_implementation_reads_it(tmp_path):
    import h5py

    import flexgear
    from flexgear.config import load_config
    from flexgear.gears.faults import Crack

    cfg = load_config("spur_pair")
    cfg.model = "lumped"
    cfg.contact["damping_ratio"] = 0.05
    cfg.contact.pop("damping", None)
    cfg.faults = (Crack(gear="pinion", tooth=3, flank="left", depth=1.5e-3, angle=math.radians(45)),)
    path = tmp_path / "spur.h5"
    flexgear.save(flexgear.run(cfg), path)
    report = monitor(path, MonitorSettings())
    mine = ref.shaft_averages(path, report.source.signal_path, ("pinion", "wheel"))
    assert report.shafts["pinion"].indicators["fm4"] > 4  # the crack is seen (3: Gaussian)
    _compare(report, mine)
    # 24 and 21 teeth, gcd 3: the pair meets the same teeth every 8 wheel (7 pinion) turns, so the pinion's
    # crack stays in the wheel's average at the wheel orders 7, 14, 28, ... (not 21 k): the
    # wheel's residual is mostly there, the pinion's (its own crack, broadband) is not
    for shaft, step, mine_share in (("wheel", 7, 0.5), ("pinion", 8, None)):
        sig, z, kmax = mine[shaft]
        power = np.abs(np.fft.rfft(sig["residual"])) ** 2
        k = np.arange(power.size)
        rest = (k > 2) & (k <= kmax) & (k % z != 0)
        share = power[rest & (k % step == 0)].sum() / power[rest].sum()
        got = report.shafts[shaft].partner_share
        assert got[0] == pytest.approx(share, rel=1e-6) and got[1] == pytest.approx(
            np.count_nonzero(rest & (k % step == 0)) / np.count_nonzero(rest)), shaft
        if mine_share:
            assert share > mine_share
    assert mostly_partner(report.shafts["wheel"].partner_share)
    assert not mostly_partner(report.shafts["pinion"].partner_share)
    # measurement noise (0.3 of the signal's RMS) hides the halves' difference, not this: it
    # dilutes the share (to about 0.47, 0.41 of the way from the broadband 0.10 to 1, which the
    # first threshold, half-way, missed) but not the pinion's impulses in the wheel's kurtosis
    # (about 4.9); the healthy set under the same noise reads the broadband share (within 0.05)
    healthy = tmp_path / "healthy.h5"
    cfg.faults = ()
    flexgear.save(flexgear.run(cfg), healthy)
    for p in (path, healthy):
        with h5py.File(p, "r+") as h5:
            x = h5[report.source.signal_path.split(":")[0]]
            x[...] += 0.3 * np.std(x[...]) * np.random.default_rng(3).standard_normal(x.shape)
    with pytest.warns(UserWarning, match=r"of the residual power of wheel lies at its orders 7, 14, \.\.\. .*"
                                         r"gcd\(21, 24\) = 3, so the pair meets the same teeth every 8 turns of wheel"):
        noisy = monitor(path, MonitorSettings())
    share, broad = noisy.shafts["wheel"].partner_share
    assert 0.3 < (share - broad) / (1 - broad) < 0.5 and noisy.shafts["wheel"].indicators["na4"] > 4
    assert not mostly_partner(noisy.shafts["pinion"].partner_share)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        calm = monitor(healthy, MonitorSettings())
    assert not [w for w in caught if "of the residual power of" in str(w.message)]
    for shaft in ("wheel", "pinion"):
        share, broad = calm.shafts[shaft].partner_share
        assert abs(share - broad) < 0.05 and not mostly_partner((share, broad)), shaft


def test_a_noisy_planetary_record_and_its_baseline_as_an_independent_implementation_reads_them(tmp_path):
    import h5py

    path, base = tmp_path / "faulty.h5", tmp_path / "healthy.h5"
    md.write_planetary(path, duration=1.0, fault=0.5)
    md.write_planetary(base, duration=1.0)
    rng = np.random.default_rng(7)
    for p in (path, base):
        with h5py.File(p, "r+") as h5:
            x = h5["sensors/top/acceleration"]
            x[...] += 0.05 * rng.standard_normal(x.shape)
    shafts = ("sun", "carrier")
    report = monitor(path, MonitorSettings(shafts=shafts), baseline=[base])
    signal = report.source.signal_path
    mine = ref.shaft_averages(path, signal, shafts)
    bands = {s: k for s, (_, _, k) in mine.items()}
    healthy = ref.shaft_averages(base, signal, shafts, bands)
    _compare(report, mine, {s: [ref.moment(sig["residual"], 2)] for s, (sig, _, _) in healthy.items()})
