"""Condition monitoring as a diagnostic study uses it (a trial's findings): the cases of a batch's
own sweep, NA4's baselines named, the angle grid that would fold refused, a zero-size fault
left unmarked, teeth placed where they mesh whatever load a fault takes off them."""
import csv
import json

import numpy as np
import pytest

from flexgear.errors import ConfigError, FlexgearError
from flexgear.monitoring import MonitorSettings, monitor
from flexgear.monitoring.order import angle_grid, samples_per_revolution
from flexgear.monitoring.outputs import batch_cases, severity_table, write_severity

import monitoring_data as md


def _batch(tmp_path, cases, listed=None, noise=0.05, seed=7):
    """A batch directory of synthetic planetary records (md.write_planetary, 1 s; Gaussian noise
    ``noise`` on the top sensor), one case per (key, planet 1 fault depth); its summary.csv lists
    the keys ``listed`` (default all), as the sweep last run in the directory."""
    import h5py

    d = tmp_path / "batch"
    (d / "cases").mkdir(parents=True)
    rng = np.random.default_rng(seed)
    for key, sev in cases:
        md.write_planetary(d / "cases" / f"{key}.h5", duration=1.0, fault=sev)
        if noise:
            with h5py.File(d / "cases" / f"{key}.h5", "r+") as h5:
                x = h5["sensors/top/acceleration"]
                x[...] += noise * rng.standard_normal(x.shape)
        (d / "cases" / f"{key}.json").write_text(json.dumps({"status": "done",
                                                             "values": {"faults.planet1.depth": sev}}))
    with open(d / "summary.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "status", "faults_planet1_depth", "key", "file"])
        for i, (key, sev) in enumerate(cases):
            if listed is None or key in listed:
                w.writerow([i, "done", sev, key, f"cases/{key}.h5"])
    (d / "batch.json").write_text(json.dumps({"format": "flexgear-batch 1", "sweep": "sweep.toml"}))
    return d


def test_a_severity_table_takes_the_cases_its_summary_lists_and_names_na4s_baselines(tmp_path, capsys):
    """Case files another sweep left in the directory are not tabulated (a trial's second sweep
    into the same directory had every severity twice, noise-free cases normalised by a noisy
    healthy one); each case says how many healthy cases entered its NA4: the others at the
    healthy severity, none for the case itself; the command names the healthy severity."""
    from flexgear.app.cli import main

    d = _batch(tmp_path, [("a0", 0.0), ("a1", 0.0), ("b0", 1.0), ("b1", 2.0), ("old", 1.0)],
               listed={"a0", "a1", "b0", "b1"})
    assert [c.path.stem for c in batch_cases(d, "faults.planet1.depth")] == ["a0", "a1", "b0", "b1"]
    table = severity_table(d, "faults.planet1.depth", MonitorSettings(shafts=("planet1",)))
    assert table.severities == [0.0, 0.0, 1.0, 2.0]
    assert [r["planet1"] for r in table.baseline_records] == [1, 1, 2, 2]
    out = tmp_path / "sev"
    out.mkdir()
    write_severity(table, out)
    data = json.loads((out / "severity.json").read_text())
    assert [c["na4_baseline_records"] for c in data["cases"]] == [{"planet1": n} for n in (1, 1, 2, 2)]
    assert main(["monitor", str(d), "-o", str(tmp_path / "cli"), "--severity", "faults.planet1.depth",
                 "--shafts", "planet1"]) == 0
    assert "healthy cases, NA4's baseline: faults.planet1.depth = 0 (2 case(s))" in capsys.readouterr().out


@pytest.mark.parametrize("least", [0.0, 0.5])
def test_the_baseline_that_is_not_zero_or_not_used_is_named(tmp_path, capsys, least):
    """Without a case at 0 the least severity is the healthy one; a noise-free healthy residual
    (numerically zero: the sun's mesh order alone) gives NA4 no variance: the command says
    either, rather than tabulate silently against it."""
    import h5py

    from flexgear.app.cli import main

    d = _batch(tmp_path, [("c1", least), ("c2", 1.0)], noise=0.0)
    for key, bump in (("c1", least), ("c2", 1.0)):
        with h5py.File(d / "cases" / f"{key}.h5", "r+") as h5:  # the sun's mesh order, a bump once per sun turn
            rel = h5["bodies/sun/angle"][()] - h5["bodies/carrier/angle"][()]
            w = (rel - 1.0 + np.pi) % (2 * np.pi) - np.pi
            h5["sensors/top/acceleration"][...] = np.cos(24 * rel) + 0.2 * bump * np.exp(-0.5 * (w / 0.05) ** 2)
    assert main(["monitor", str(d), "-o", str(tmp_path / "cli"), "--severity", "faults.planet1.depth",
                 "--shafts", "sun"]) == 0
    said = capsys.readouterr().out
    assert ("- not zero: the least severity in the batch" in said) == (least != 0)
    assert ("NA4 is each case's own residual kurtosis" in said) == (least == 0)  # a faulty one has a variance


def test_a_batch_directory_without_severity_or_finished_cases_is_named(tmp_path, capsys):
    from flexgear.app.cli import main

    d = _batch(tmp_path, [("a0", 0.0)])
    assert main(["monitor", str(d), "-o", str(tmp_path / "m")]) == 2
    assert "is a batch directory: pass --severity KEY" in capsys.readouterr().err
    for p in (d / "cases").iterdir():
        p.unlink()
    with pytest.raises(FlexgearError, match="no case of its batch has finished yet; continue the batch with "
                                            "flexgear batch"):
        batch_cases(d, "faults.planet1.depth")


def test_an_angle_grid_coarser_than_the_record_is_refused():
    """Resampling onto a coarser angle grid than the record folds the lines above its Nyquist
    order into the average (a trial: a 2 mm crack's FM4 of 34 read 3.3 at 100 samples per
    revolution, no word said): refused with the least grid; a denser one is taken as given."""
    fs, speed = 10080.0, 10.0
    least = samples_per_revolution(fs, speed)
    assert least == 1008 and angle_grid(fs, speed, 24, None, "pinion") == 1008
    assert angle_grid(fs, speed, 24, 2016, "pinion") == 2016 and angle_grid(fs, speed, 24, 1008, "pinion") == 1008
    with pytest.raises(ConfigError, match=r"--samples-per-rev = 1007: coarser than the record for pinion, which "
                                          r"needs at least 1008 .* above order 503 would fold"):
        angle_grid(fs, speed, 24, 1007, "pinion")


def test_a_coarse_grid_would_have_folded_and_the_command_refuses_it(tmp_path):
    """The refusal protects a real loss: a line above the coarse grid's Nyquist order, resampled
    onto it, comes out at a false order with its full amplitude (what the refused grid would have
    averaged); monitor refuses that grid before any average."""
    from flexgear.monitoring.order import angular_resample, order_spectrum
    from flexgear.results.signals import line_amplitude

    fs, f_shaft = 10000.0, 10.0
    t = np.arange(int(fs)) / fs
    angle = 2 * np.pi * f_shaft * t
    x = np.cos(2 * np.pi * 3000.0 * t)  # order 300
    coarse = angular_resample(t, x, angle, 400)  # Nyquist order 200: folds to order 100
    orders, amp = order_spectrum(coarse)
    assert line_amplitude(orders, amp, 100.0) > 0.5
    md.write_planetary(tmp_path / "r.h5", duration=1.0)
    with pytest.raises(ConfigError, match="coarser than the record"):
        monitor(tmp_path / "r.h5", MonitorSettings(samples_per_rev=64))


def test_zero_size_fault_is_unmarked_and_teeth_stay_where_they_mesh(tmp_path):
    """A crack of depth 0 is the healthy model: its record says null and tsa.png marks no fault
    (a trial's healthy case was marked 'crack, tooth 0'). A tooth's angle is the middle of its
    loaded contact: a root crack, which takes load off its tooth, does not move it or its
    neighbours (the angle of the most loaded tooth had moved tooth 0 by 2.6 deg and tooth 1 by
    3.6 deg); the pinion's teeth stay a pitch apart. On a noise-free healthy run the residual
    panel says it is numerically zero instead of drawing autoscaled round-off; it has a unit."""
    import flexgear
    from flexgear.app.run import result_record
    from flexgear.config import loads_config, preset_path
    from flexgear.monitoring.figures import fig_tsa

    def crack(depth):
        cfg = loads_config(preset_path("spur_pair").read_text() + f"""
[[faults]]
kind = "crack"
gear = "pinion"
tooth = 0
flank = "left"
depth = {depth}
""")
        cfg.simulation.update(run_in=0.1, duration=0.3)
        return cfg

    cfg0, cfg1 = crack(0.0), crack(1.5e-3)
    assert json.loads(result_record(cfg0)["record"])["faults"][0]["null"] is True
    assert json.loads(result_record(cfg1)["record"])["faults"][0]["null"] is False
    reps = [monitor(flexgear.save(flexgear.run(c), tmp_path / f"r{i}.h5")) for i, c in enumerate((cfg0, cfg1))]
    healthy, cracked = (r.shafts["pinion"] for r in reps)
    assert healthy.fault_marks == [] and [m[:2] for m in cracked.fault_marks] == [(0, "crack")]
    pitch = 360.0 / 24
    a0, a1 = (np.degrees([sa.tooth_angles[k] for k in range(24)]) for sa in (healthy, cracked))
    gap = (a1 - a0 + 180.0) % 360.0 - 180.0
    assert np.max(np.abs(gap)) < 0.05 * pitch, gap
    spacing = np.abs((np.diff(a1) + 180.0) % 360.0 - 180.0)
    assert np.allclose(spacing, pitch, atol=0.05 * pitch), spacing
    fig = fig_tsa(reps[0])
    right = fig.axes[1]
    assert right.get_ylabel() and any("numerically zero" in t.get_text() for t in right.texts)
    # each axis names its quantity with the unit (a trial's tsa.png read "[N]" alone)
    assert fig.axes[0].get_ylabel() == "TSA [N]" and right.get_ylabel() == "Residual, difference [N]"
    assert not any("numerically zero" in t.get_text() for t in fig_tsa(reps[1]).axes[1].texts)


def test_the_indicators_do_not_depend_on_the_angle_grid(tmp_path):
    """FM4, NA4, M6A, M8A, kurtosis, crest factor and FM0 are the moments and peaks of the
    continuous waveforms (tsa.moment_grid), the same on the default grid and on one three or six
    times denser (1e-4: the resampling's round-off, measured 2e-5): the k-th power of a signal of
    orders <= Q holds orders <= k Q, which the default grid (about 2.5 Q samples per revolution)
    averaged with aliasing where a fault's impulse reaches the band's top (a trial: a crack's FM4 read 34.4 at the default grid, 38.0 at twice
    it). Here a sharp impulse once per sun turn over the sun's mesh tone."""
    import h5py

    from flexgear.monitoring import indicators as ind
    from flexgear.monitoring.tsa import moment_grid

    path = tmp_path / "r.h5"
    md.write_planetary(path, duration=1.0)
    with h5py.File(path, "r+") as h5:
        rel = h5["bodies/sun/angle"][()] - h5["bodies/carrier/angle"][()]
        w = (rel - 1.0 + np.pi) % (2 * np.pi) - np.pi
        h5["sensors/top/acceleration"][...] = np.cos(24 * rel) + 0.3 * np.exp(-0.5 * (w / 0.004) ** 2)
    settings = dict(shafts=("sun",))
    base = monitor(path, MonitorSettings(**settings)).shafts["sun"]
    d = base.signals.difference  # the sampled fourth moment on the default grid is off
    assert abs(ind.fm4(d) / ind.fm4(moment_grid(d, base.signals.max_order)) - 1) > 0.01
    for n in (3, 6):
        dense = monitor(path, MonitorSettings(**settings, samples_per_rev=n * base.samples_per_rev)).shafts["sun"]
        assert dense.signals.max_order == base.signals.max_order
        for name in ("kurtosis", "crest_factor", "fm0", "fm4", "na4", "m6a", "m8a"):
            assert dense.indicators[name] == pytest.approx(base.indicators[name], rel=1e-4), (n, name)
