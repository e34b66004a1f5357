"""Batch runs: sweep expansion, bad sweeps, executors giving identical results, failures,
resuming, the lock, a killed batch, and the metrics on signals of known content."""
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest

import flexgear
from flexgear.app.batch import BatchLock, BatchLockedError, CaseTask, execute_case, run_batch, stored_config
from flexgear.app.cli import main
from flexgear.app.metrics import DEFAULT_METRICS, approach, compute_metrics, line_or_nan
from flexgear.app.sweep import CaseLimitError, evaluate_expression, read_sweep
from flexgear.errors import ConfigError, FlexgearError
from flexgear.results.store import BodySignals, MeshSignals, Result, load

TINY = '[set]\n"simulation.duration" = 0.02\n"simulation.run_in" = 0.01\n'
QUIET = dict(progress=False, log=lambda msg: None)
TIMING_ATTRS = {"wall_seconds", "build_seconds", "case_run_seconds", "compile_seconds"}


def sweep_file(tmp_path, body, name="sweep.toml", base='"spur_pair"', tiny=True):
    p = tmp_path / name
    p.write_text(f"base = {base}\n" + (TINY if tiny else "") + body)
    return p


# --------------------------------------------------------------------------- expansion

def test_a_number_in_a_key_indexes_the_faults_of_the_base(tmp_path):
    """``faults.0.height_fraction`` sweeps the first [[faults]] entry of the base (the severity
    axis of a fault study); every other key of the fault is kept; an index the base does not have
    is an error naming the key, before any case runs."""
    s = read_sweep(sweep_file(tmp_path, '[grid]\n"faults.0.height_fraction" = [0.0, 0.5]\n',
                              base='"spur_pair_missing_tooth"'))
    assert [c.config.faults[0].height_fraction for c in s.cases] == [0.0, 0.5]
    assert all(c.config.faults[0].kind == "missing" and c.config.faults[0].gear == "pinion" and c.config.faults[0].tooth == 0
               and len(c.config.faults) == 1 for c in s.cases)
    with pytest.raises(ConfigError, match=r"faults\.1\.height_fraction: '1' is not an index"):
        read_sweep(sweep_file(tmp_path, '[grid]\n"faults.1.height_fraction" = [0.0, 0.5]\n',
                              base='"spur_pair_missing_tooth"'))
    with pytest.raises(ConfigError, match=r"faults\.0\.depth: the base configuration has no array of tables "
                       r"'faults' to index"):  # not the parser's "faults must be a list of tables"
        read_sweep(sweep_file(tmp_path, '[grid]\n"faults.0.depth" = [0.0, 1e-3]\n', name="nofaults.toml"))


@pytest.mark.parametrize("where", [TINY + 'contact = {damping_ratio = 0.05}\n',
                                   TINY + '"contact.damping_ratio" = 0.05\n',
                                   TINY + '[grid]\n"contact.damping_ratio" = [0.03, 0.05]\n'])
def test_a_damping_ratio_replaces_the_bases_damping_coefficient(tmp_path, where):
    """The mesh damping is a coefficient or a ratio, never both: a case that sets the ratio (the
    guides' advice for lumped and flexible studies) drops the base's coefficient, in [set] as in
    an axis (it was 'contact.damping = ... and contact.damping_ratio = ...: give one of them')."""
    s = read_sweep(sweep_file(tmp_path, where, base='"spur_pair_flexible"', tiny=False))
    assert all(c.config.contact.get("damping") is None and c.config.contact["damping_ratio"] in (0.03, 0.05)
               for c in s.cases)
    both = '"contact.damping_ratio" = 0.05\n"contact.damping" = 3.0\n'
    with pytest.raises(ConfigError, match="give one of them"):  # both given by the case: still an error
        read_sweep(sweep_file(tmp_path, both, name="both.toml", base='"spur_pair_flexible"'))


def test_a_base_with_the_lumped_suffix_sweeps_the_lumped_model_of_the_preset(tmp_path):
    """``base = "NAME:lumped"`` is the preset with ``model = "lumped"``, as ``flexgear run
    NAME:lumped`` reads it: the same key for the same case written either way."""
    s = read_sweep(sweep_file(tmp_path, '[grid]\nload.torque = [100.0, 200.0]\n', base='"spur_pair_friction:lumped"'))
    assert [c.config.model for c in s.cases] == ["lumped", "lumped"] and s.cases[0].config.lubrication is not None
    s2 = read_sweep(sweep_file(tmp_path, '[grid]\nload.torque = [100.0, 200.0]\nmodel = ["lumped"]\n',
                               name="other.toml", base='"spur_pair_friction"'))
    assert [c.key for c in s.cases] == [c.key for c in s2.cases]
    with pytest.raises(ConfigError, match=r"base = 'spur_pair:rigid': no such file .*optionally with ':lumped'"):
        read_sweep(sweep_file(tmp_path, '[grid]\nload.torque = [100.0]\n', base='"spur_pair:rigid"'))


def test_swept_columns_carry_the_units_of_their_configuration_keys(tmp_path):
    """columns.md and summary.nc name each swept column's unit as the configuration schema gives
    it (the key as written: degC, N m, Hz, m of a fault), not '-'."""
    from flexgear.app.summary import SummaryTable
    from flexgear.config import key_unit

    text = ('[grid]\nload.torque = [100.0, 200.0]\n"drive.speed_hz" = [5.0]\n'
            '"lubrication.oil_temperature_c" = [40.0, 90.0]\n')
    s = read_sweep(sweep_file(tmp_path, text, base='"spur_pair_friction"'))
    rows = {line.split("|")[1].strip(" `"): line.split("|")[2].strip() for line in
            SummaryTable(s).columns_text().splitlines()[2:]}
    assert rows["load_torque"] == "N m" and rows["drive_speed_hz"] == "Hz"
    assert rows["lubrication_oil_temperature_c"] == "degC"
    assert key_unit("faults.0.depth") == key_unit("gears.wheel.module") == "m"  # an array's index, a named table
    assert key_unit("lubrication") == key_unit("no.such.key") == ""


def test_grid_zip_and_derived_expand_in_order(tmp_path):
    s = read_sweep(sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [5.0, 10.0, 20.0]\nload.torque = [100.0, 200.0]\n'
                              '[zip]\n"contact.damping" = [1000.0, 2000.0]\n"contact.exponent" = [1.3, 1.4]\n'
                              '[derived]\n"load.ramp" = "load.torque / 1e4"\n'))
    assert s.shape == (3, 2, 2) and len(s.cases) == 12
    c = s.cases[7]  # C order: speed index 1, torque 1, zip 1
    assert c.position == (1, 1, 1)
    assert c.values == {"drive.speed_hz": 10.0, "load.torque": 200.0, "contact.damping": 2000.0,
                        "contact.exponent": 1.4, "load.ramp": 0.02}
    assert c.config.load["ramp"] == 0.02 and c.config.contact["damping"] == 2000.0
    assert c.data["simulation"]["duration"] == 0.02  # [set] applies to every case
    assert c.config.drive["speed_hz"] == 10.0
    assert len({x.key for x in s.cases}) == 12  # every case has its own configuration hash
    # the key hashes the full configuration, not the sweep: the same case written another way has the same key
    s2 = read_sweep(sweep_file(tmp_path, '[zip]\n"drive.speed_hz" = [10.0]\nload.torque = [200.0]\n'
                               '"contact.damping" = [2000.0]\n"contact.exponent" = [1.4]\n"load.ramp" = [0.02]\n',
                               name="other.toml"))
    assert s2.cases[0].config_toml == c.config_toml and s2.cases[0].key == c.key
    assert s2.cases[0].key != s.cases[6].key


def test_derived_list_and_axis_table(tmp_path):
    s = read_sweep(sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [5.0, 10.0]\nload.torque = [100.0, 200.0]\n'
                              '[derived]\n"contact.damping" = {axis = "drive.speed_hz", values = [1000.0, 2000.0]}\n'
                              '"load.ramp" = [0.01, 0.02, 0.03, 0.04]\n'))
    assert [c.values["contact.damping"] for c in s.cases] == [1000.0, 1000.0, 2000.0, 2000.0]
    assert [c.config.load["ramp"] for c in s.cases] == [0.01, 0.02, 0.03, 0.04]


@pytest.mark.parametrize("method", ["lhs", "random"])
def test_samples_are_reproducible_in_range_and_stratified(tmp_path, method):
    body = (f'[sample]\nmethod = "{method}"\nn = 8\nseed = 3\n[sample.ranges]\n"drive.speed_hz" = [5.0, 25.0]\n'
            '"contact.damping" = {min = 100.0, max = 10000.0, scale = "log"}\n')
    a = read_sweep(sweep_file(tmp_path, body))
    b = read_sweep(sweep_file(tmp_path, body, name="again.toml"))
    c = read_sweep(sweep_file(tmp_path, body.replace("seed = 3", "seed = 4"), name="other.toml"))
    va = np.array([[x.values["drive.speed_hz"], x.values["contact.damping"]] for x in a.cases])
    vb = np.array([[x.values["drive.speed_hz"], x.values["contact.damping"]] for x in b.cases])
    vc = np.array([[x.values["drive.speed_hz"], x.values["contact.damping"]] for x in c.cases])
    assert va.shape == (8, 2) and a.shape == (8,)
    assert np.array_equal(va, vb) and not np.array_equal(va, vc)
    assert np.all((va[:, 0] >= 5.0) & (va[:, 0] < 25.0)) and np.all((va[:, 1] >= 100.0) & (va[:, 1] < 1e4))
    if method == "lhs":  # one sample in each of the n equal strata of every coordinate (log for the damping)
        u = np.column_stack([(va[:, 0] - 5.0) / 20.0, np.log(va[:, 1] / 100.0) / np.log(100.0)])
        for j in range(2):
            assert sorted(np.floor(u[:, j] * 8).astype(int)) == list(range(8))


def test_expression_evaluator_is_arithmetic_only():
    vals = {"drive.speed_hz": 10.0, "gears.pinion.teeth": 24}
    look = vals.__getitem__
    assert evaluate_expression("2 * drive.speed_hz ** 2 + sqrt(16) - gears.pinion.teeth % 5", look) == 200.0
    assert evaluate_expression("round(drive.speed_hz / 3)", look) == 3
    for bad, why in [("__import__('os').system('echo hi')", "not allowed"), ("drive.speed_hz.__class__", "unknown name"),
                     ("open('x')", "not allowed"), ("[1, 2]", "only numbers"), ("lambda: 1", "only numbers"),
                     ("10 ** 10 ** 10", "too large"), ("1 / 0", "ZeroDivisionError"), ("drive.sped_hz", "unknown name"),
                     ("2 +", "not a valid expression"), ("'a' * 3", "not a number")]:
        with pytest.raises(ValueError, match=why):
            evaluate_expression(bad, look)


# --------------------------------------------------------------------------- bad sweeps

@pytest.mark.parametrize("body, message", [
    ('[grid]\n"contact.dampng" = [1.0, 2.0]\n', "case 0 (contact.dampng = 1.0): unknown key 'contact.dampng'; allowed in [contact]"),
    ('[grid]\n"drive.speed_hz" = [10.0, "fast"]\n', "case 1 (drive.speed_hz = 'fast'): drive.speed_hz = 'fast': must be a number"),
    ('[grid]\n"gears.pinion.teeth" = [24, 20.5]\n', "gears.pinion.teeth = 20.5: must be an integer"),
    ('[grid]\n"contact.damping" = [100.0, -1.0]\n', "contact.damping = -1.0: must be >= 0"),
    ('[grid]\n"drive.speed_hz" = []\n', "[grid] drive.speed_hz = []: an axis needs at least one value"),
    ('[grid]\n"drive.speed_hz" = 10.0\n', "an axis must be a list of values"),
    ('[zip]\n"drive.speed_hz" = [1.0, 2.0, 3.0]\n"load.torque" = [1.0, 2.0]\n',
     "[zip] lists must have equal lengths: drive.speed_hz has 3, load.torque has 2"),
    ('[sample]\nn = 4\n[sample.ranges]\n"drive.speed_hz" = [1.0, 2.0]\n', "sample.seed = None: must be given"),
    ('[sample]\nn = 4\nseed = 1\n[sample.ranges]\n"drive.speed_hz" = [2.0, 1.0]\n', "min must be < max"),
    ('[grid]\n"drive.speed_hz" = [1.0]\n[derived]\n"load.torque" = "os.system(1)"\n', "not allowed"),
    ('[grid]\n"drive.speed_hz" = [1.0, 2.0]\n[derived]\n"load.torque" = [1.0]\n', "one value per case; the sweep has 2"),
    ('[grid]\n"drive.speed_hz" = [1.0]\n[zip]\n"drive.speed_hz" = [2.0]\n', "'drive.speed_hz' is given twice"),
    ('[grid]\n"drive.speed_hz" = [10.0, 10.0]\n', "case 1 (drive.speed_hz = 10.0) and case 0 (drive.speed_hz = 10.0) have the same configuration"),
    ('[grd]\n"drive.speed_hz" = [1.0]\n', "unknown top-level key(s) 'grd'"),
])
def test_bad_sweep_is_refused_before_anything_runs(tmp_path, body, message):
    p = sweep_file(tmp_path, body)
    with pytest.raises(ConfigError) as err:
        run_batch(p, tmp_path / "out", workers=1, **QUIET)
    assert message in str(err.value) and str(p) in str(err.value)
    assert not (tmp_path / "out").exists()  # nothing written


def test_bad_planetary_case_is_refused_with_the_assembly_rule(tmp_path):
    p = sweep_file(tmp_path, '[grid]\n"gears.sun.teeth" = [24, 25]\n', base='"mercury_1a"')
    with pytest.raises(FlexgearError, match=r"case 1 \(gears.sun.teeth = 25\)"):
        read_sweep(p)


def test_case_limit_needs_yes(tmp_path, capsys):
    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [1.0, 2.0, 3.0]\n"load.torque" = [1.0, 2.0]\n')
    with pytest.raises(CaseLimitError, match="6 cases, more than the limit of 5; pass --yes"):
        read_sweep(p, max_cases=5)
    assert main(["batch", str(p), "-o", str(tmp_path / "o"), "--max-cases", "5"]) == 2
    assert "--yes" in capsys.readouterr().err and not (tmp_path / "o").exists()
    assert main(["batch", str(p), "-o", str(tmp_path / "o"), "--max-cases", "5", "--yes", "--dry-run"]) == 0
    assert capsys.readouterr().out.count("case ") == 6


def test_dry_run_lists_every_case_once_as_it_is_validated(tmp_path):
    """The size and axes come first, then every case once, each as soon as it is validated: a
    sweep of 10^6 cases streams its list instead of validating them all first; here the third
    case breaks a rule, after the first two were listed."""
    import io

    from flexgear.app.batch_command import dry_run

    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0, 12.0, "fast"]\n')
    out = io.StringIO()
    with pytest.raises(ConfigError, match=r"case 2 \(drive.speed_hz = 'fast'\)"):
        dry_run(p, None, out=out, err=io.StringIO())
    lines = out.getvalue().splitlines()
    assert lines[0] == "sweep: 3 cases, axes drive.speed_hz (3)"
    assert [line.split("  ", 1)[1] for line in lines[1:]] == ["case 0 (drive.speed_hz = 10.0)",
                                                             "case 1 (drive.speed_hz = 12.0)"]
    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0, 12.0]\n"load.torque" = [100.0, 200.0]\n')
    out = io.StringIO()
    assert dry_run(p, None, out=out, err=io.StringIO()) == 0
    keys = [c.key for c in read_sweep(p).cases]
    text = out.getvalue()
    assert len(text.splitlines()) == 5 and all(text.count(k) == 1 for k in keys)  # each case once
    seen = []
    read_sweep(p, progress=lambda done, total: seen.append((done, total)))
    assert seen == [(1, 4), (2, 4), (3, 4), (4, 4)]


def test_unreachable_scheduler_is_an_error_before_anything_is_written(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr("flexgear.app.executors.CONNECT_TIMEOUT", 1.0)
    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0]\n')
    with pytest.raises(FlexgearError, match="cannot reach the Dask scheduler"):
        run_batch(p, tmp_path / "out", scheduler="tcp://127.0.0.1:9", **QUIET)
    assert not (tmp_path / "out").exists()
    # a malformed address is named at once: a Dask Client built from one printed a traceback from
    # its __del__ after a 20 s wait (a trial)
    for bad, why in (("notanaddress", "missing port number"), ("", "missing port number"),
                     ("tcp://127.0.0.1:99999", "port 99999 out of range 1-65535"), ("tcp://:8786", "no host")):
        t0 = time.perf_counter()
        with pytest.raises(FlexgearError, match=rf"--scheduler '{re.escape(bad)}': {why}.*must be \[tcp://\]HOST:PORT"):
            run_batch(p, tmp_path / "out", scheduler=bad, **QUIET)
        assert time.perf_counter() - t0 < 5.0 and not (tmp_path / "out").exists()


def test_directory_of_something_else_is_refused(tmp_path):
    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0]\n')
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(FlexgearError, match="not a flexgear batch directory"):
        run_batch(p, tmp_path / "mine", workers=1, **QUIET)
    assert os.listdir(tmp_path / "mine") == ["notes.txt"]


# --------------------------------------------------------------------------- running

def test_failures_are_isolated_recorded_and_skipped_on_rerun(tmp_path, capsys):
    # the second torque makes the teeth pass through each other at once: DivergenceError
    p = sweep_file(tmp_path, '[zip]\n"load.torque" = [200.0, 1.0e6, 100.0]\n"load.ramp" = [0.05, 0.0, 0.05]\n')
    out = tmp_path / "out"
    assert main(["batch", str(p), "-o", str(out), "--workers", "2"]) == 1  # some case failed
    df = pd.read_csv(out / "summary.csv")
    assert list(df.status) == ["done", "failed", "done"]
    assert df.error[1].startswith("DivergenceError: simulation diverged at t = ")
    assert df.mean_force_pinion_wheel.notna().tolist() == [True, False, True]
    rec = json.loads((out / "cases" / f"{df.key[1]}.json").read_text())
    assert rec["status"] == "failed" and "Traceback" in rec["traceback"]
    assert not (out / "cases" / f"{df.key[1]}.h5").exists()
    stamps = {k: (out / "cases" / f"{k}.h5").stat().st_mtime_ns for k in df.key[[0, 2]]}
    r = run_batch(p, out, workers=1, **QUIET)  # rerun: nothing to do
    assert (r.ran, r.skipped, r.done, r.failed) == (0, 2, 2, 1)
    assert {k: (out / "cases" / f"{k}.h5").stat().st_mtime_ns for k in stamps} == stamps
    r = run_batch(p, out, workers=1, retry_failed=True, **QUIET)
    assert (r.ran, r.done, r.failed) == (1, 2, 1)
    assert "failed" in capsys.readouterr().err


def test_rerun_verifies_the_stored_configuration_not_the_file_name(tmp_path):
    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0, 12.0]\n')
    out = tmp_path / "out"
    first = run_batch(p, out, workers=1, **QUIET)
    k0, k1 = (c["key"] for c in first.table.records())
    before = pd.read_csv(out / "summary.csv")
    (out / "cases" / f"{k1}.h5").write_bytes((out / "cases" / f"{k0}.h5").read_bytes())  # wrong content
    (out / "cases" / f"{k1}.json").unlink()
    r = run_batch(p, out, workers=1, **QUIET)
    assert (r.ran, r.skipped) == (1, 1)
    assert list((out / "cases").glob(f"{k1}.h5.mismatch-*"))  # moved aside, not deleted
    cases = read_sweep(p).cases
    assert stored_config(out / "cases" / f"{k1}.h5") == cases[1].config_toml
    after = pd.read_csv(out / "summary.csv")
    cols = [c for c in before.columns if c != "wall_s"]
    pd.testing.assert_frame_equal(before[cols], after[cols])  # the rerun case gives the same numbers


def test_another_sweep_into_a_batch_directory_is_refused_and_an_extension_continues_it(tmp_path):
    """A sweep whose cases do not include every case the directory's summary lists would replace
    that summary (a trial's noisy sweep run into the directory of a noise-free one: both sweeps'
    case files were then tabulated together by the monitor): refused, naming the earlier sweep,
    with nothing written; a sweep that holds them all and more continues the directory."""
    first = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0, 12.0]\n', name="first.toml")
    other = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0, 14.0]\n', name="other.toml")
    more = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0, 12.0, 14.0]\n', name="more.toml")
    out = tmp_path / "out"
    run_batch(first, out, workers=1, **QUIET)
    saved = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    with pytest.raises(FlexgearError, match=r"holds the batch of \S*first\.toml, and 1 of its 2 cases are not "
                                            r"cases of \S*other\.toml \(another sweep, or the sweep or its base "
                                            r"edited since\)"):
        run_batch(other, out, workers=1, **QUIET)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == saved
    assert len(list((out / "cases").glob("*.h5"))) == 2
    r = run_batch(more, out, workers=1, **QUIET)
    assert (r.ran, r.skipped, r.done) == (1, 2, 3)
    assert list(pd.read_csv(out / "summary.csv").drive_speed_hz) == [10.0, 12.0, 14.0]


def test_a_case_without_a_shared_directory_sends_its_file_back(tmp_path):
    # what a Dask worker on another machine does: the driver writes the bytes
    case = read_sweep(sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0]\n')).cases[0]
    rec = execute_case(CaseTask(case.index, case.key, case.data, case.config_toml, None, DEFAULT_METRICS))
    assert rec["status"] == "done", rec["error"]
    (tmp_path / "r.h5").write_bytes(rec["payload"])
    res = load(tmp_path / "r.h5")
    assert res.config_toml == case.config_toml
    assert compute_metrics(res, DEFAULT_METRICS)[0] == rec["metrics"]


def test_a_case_whose_batch_has_ended_writes_nothing(tmp_path):
    """A case still running on an external Dask cluster when its batch was interrupted (Dask does
    not stop a running task) finished 40 s later and wrote its file into the ended batch's
    directory, where a rerun adopted it while running the same case again (a trial): a case
    writes into the batch's directory only while the batch holds it (its lock file)."""
    case = read_sweep(sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0]\n')).cases[0]
    cases = tmp_path / "out" / "cases"
    cases.mkdir(parents=True)
    task = CaseTask(case.index, case.key, case.data, case.config_toml, str(cases), DEFAULT_METRICS)
    rec = execute_case(task)
    assert rec["status"] == "failed" and "has ended" in rec["error"] and not list(cases.iterdir())
    lock = BatchLock(tmp_path / "out").acquire()
    try:
        assert execute_case(task)["status"] == "done" and (cases / f"{case.key}.h5").is_file()
    finally:
        lock.release()


def test_a_second_batch_on_the_same_directory_is_refused(tmp_path):
    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0]\n')
    out = tmp_path / "out"
    out.mkdir()
    with BatchLock(out):
        with pytest.raises(BatchLockedError, match=f"in use by another flexgear batch \\(pid {os.getpid()}"):
            run_batch(p, out, workers=1, **QUIET)
    assert not (out / "summary.csv").exists()
    assert run_batch(p, out, workers=1, **QUIET).done == 1  # free again


def test_the_lock_file_is_removed_when_a_batch_ends_normally_or_with_an_error(tmp_path, monkeypatch):
    import flexgear.app.batch as batch

    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [10.0]\n')
    out = tmp_path / "out"
    assert run_batch(p, out, workers=1, **QUIET).done == 1
    assert not (out / batch.LOCK_NAME).exists()

    def broken(*a, **k):
        raise RuntimeError("disk gone")

    monkeypatch.setattr(batch, "_scan", broken)
    with pytest.raises(RuntimeError, match="disk gone"):
        run_batch(p, out, workers=1, **QUIET)
    assert not (out / batch.LOCK_NAME).exists()


def test_a_lock_on_a_removed_lock_file_is_not_taken_for_the_lock(tmp_path, monkeypatch):
    """A process that opened the lock file just before its holder removed it, and then locks
    that orphaned file, holds nothing: it must open the path again, so that two batches never
    both think they hold the directory."""
    import flexgear.app.batch as batch

    a = BatchLock(tmp_path).acquire()
    stale = os.open(a.path, os.O_RDWR)  # opened while A holds the lock
    a.release()  # removes the file
    real_open, calls = os.open, []

    def open_stale_first(path, flags, mode=0o777):
        calls.append(path)
        return stale if len(calls) == 1 else real_open(path, flags, mode)

    monkeypatch.setattr(batch.os, "open", open_stale_first)
    b = BatchLock(tmp_path).acquire()
    monkeypatch.setattr(batch.os, "open", real_open)
    assert len(calls) == 2 and os.fstat(b.fd).st_ino == os.stat(b.path).st_ino
    with pytest.raises(BatchLockedError):
        BatchLock(tmp_path).acquire()
    b.release()
    assert not b.path.exists()


def test_summary_csv_and_array_agree(tmp_path):
    p = sweep_file(tmp_path, '[grid]\n"drive.speed_hz" = [8.0, 12.0]\n"load.torque" = [100.0, 200.0]\n'
                             '[derived]\n"load.ramp" = "load.torque / 1e5"\n')
    out = tmp_path / "out"
    run_batch(p, out, workers=1, **QUIET)
    df = pd.read_csv(out / "summary.csv")
    assert all(c.replace("_", "a").isalnum() and c[0].isalpha() for c in df.columns)  # MATLAB-valid names
    assert (df.status == "done").all() and list(df.drive_speed_hz) == [8.0, 8.0, 12.0, 12.0]
    xr = pytest.importorskip("xarray")
    with xr.open_dataset(out / "summary.nc", engine="h5netcdf") as ds:
        assert ds.rms_force_pinion_wheel.dims == ("drive_speed_hz", "load_torque")
        assert ds.rms_force_pinion_wheel.attrs["units"] == "N"
        v = ds.rms_force_pinion_wheel.sel(drive_speed_hz=12.0, load_torque=100.0).item()
        assert v == df.rms_force_pinion_wheel[2]
        assert ds.load_ramp.sel(drive_speed_hz=8.0).values.tolist() == [0.001, 0.002]  # ramped in during the run-in
        assert ds.drive_speed_hz.attrs["units"] == "Hz" and ds.load_torque.attrs["units"] == "N m"  # swept axes
    # the mean force balances the load torque: T / r_b of the wheel (spur pair, 21 teeth, m = 2 mm)
    rb = 21 * 2e-3 / 2 * math.cos(math.radians(20))
    assert np.allclose(df.mean_force_pinion_wheel, df.load_torque / rb, rtol=0.05)
    # summary metrics are those of the stored files
    res = load(out / df.file[3])
    values, _ = compute_metrics(res, DEFAULT_METRICS)
    assert values["peak_force_pinion_wheel"] == df.peak_force_pinion_wheel[3]


# --------------------------------------------------------------------------- metrics

def synthetic_result(fm, fa, amps, fs=5000.0, n=5000, F0=1000.0, pairs=None):
    t = np.arange(n) / fs + 0.2
    F = F0 + sum(a * np.cos(2 * np.pi * k * fm * t + 0.3 * k) for k, a in amps.items())
    fy = 0.5 * F + 7.0 * np.cos(2 * np.pi * (fm - fa) * t)
    K = 3
    pf = np.zeros((n, K))
    pen = np.zeros((n, K))
    count = pairs if pairs is not None else np.where(np.arange(n) % 10 < 6, 2, 1)  # 1.6 pairs on average
    for k in range(K):
        pf[:, k] = np.where(count > k, F / np.maximum(count, 1), 0.0)
        pen[:, k] = np.where(count > k, 1e-5 + 1e-6 * np.sin(2 * np.pi * fm * t), 0.0)
    mesh = MeshSignals("a-b", "a", "b", F, np.column_stack([0.3 * F, fy]), pf, np.full((n, K), -1),
                       np.full((n, K), -1), np.zeros((n, K), np.int8), pen)
    body = BodySignals("a", np.zeros((n, 2)), np.zeros(n), np.zeros((n, 2)), np.zeros(n), None)
    return Result(time=t, meshes={"a-b": mesh}, bodies={"a": body}, config_toml="",
                  attrs={"mesh_frequency": fm, "carrier_frequency": fa, "solver_steps": 10, "rejected_steps": 0})


def test_metrics_of_a_known_signal():
    res = synthetic_result(fm=243.7, fa=8.1, amps={1: 50.0, 2: 20.0, 3: 5.0})
    v, info = compute_metrics(res, DEFAULT_METRICS)
    F = res.meshes["a-b"].normal_force
    assert v["mean_force_a_b"] == pytest.approx(1000.0, rel=1e-3)
    assert v["rms_force_a_b"] == pytest.approx(math.sqrt(1000.0**2 + (50.0**2 + 20.0**2 + 5.0**2) / 2), rel=1e-3)
    assert v["dyn_rms_force_a_b"] == pytest.approx(math.sqrt((50.0**2 + 20.0**2 + 5.0**2) / 2), rel=1e-3)
    assert v["peak_force_a_b"] == F.max() and v["p2p_force_a_b"] == F.max() - F.min()
    assert v["dynamic_factor_a_b"] == pytest.approx(F.max() / F.mean())
    for k, a in {1: 50.0, 2: 20.0, 3: 5.0}.items():  # lines off the bins: zero-padding keeps them within 1 %
        assert v[f"amp_fm{k}_a_b"] == pytest.approx(a, rel=0.01)
    assert v["amp_fy_fm1_a_b"] == pytest.approx(25.0, rel=0.01)
    assert v["amp_fy_fm1_minus_fa_a_b"] == pytest.approx(7.0, rel=0.01)
    assert v["amp_fy_fm1_plus_fa_a_b"] < 0.1
    assert v["contact_pairs_mean_a_b"] == pytest.approx(1.6) and v["contact_pairs_min_a_b"] == 1
    assert v["te_mean_a_b"] == pytest.approx(1e-5, rel=1e-3) and v["te_p2p_a_b"] == pytest.approx(2e-6, rel=1e-2)
    assert info["amp_fm1_a_b"][0] == "N" and info["te_mean_a_b"][0] == "m"


def test_the_transmission_error_metrics_are_the_gears_approach():
    """te_mean and te_p2p read the approach along the line of action: for rigid gears on fixed
    axes r_b1 theta_1 + r_b2 theta_2, which the approach follows up to a constant (1 % of its
    peak-to-peak, measured 0.02 %; the spur preset, the
    record unfiltered at 40 kHz so that the angles are instantaneous as the contact slots are).
    The preset's ADAMS damper leaves a separating pair overlapping without force while the teeth
    change; the loaded pairs alone (the metric before a check from outside) read 29.6 um against
    the angles' 15.7 um."""
    cfg = flexgear.load_config("spur_pair")
    cfg.simulation.update(run_in=0.05, duration=0.05, antialias=False, output_rate=40000.0, synchronous=False)
    res = flexgear.run(cfg, progress=False)
    m = res.meshes["pinion-wheel"]
    assert np.any((m.penetration > 1e-6) & (m.pair_force == 0.0))  # a pair overlapping without force
    te = sum(cfg.gears[g].rb * res.bodies[g].angle for g in ("pinion", "wheel"))  # r_b1 w_1 + r_b2 w_2 = 0
    v, _ = compute_metrics(res, DEFAULT_METRICS)
    a = approach(m)
    assert v["te_p2p_pinion_wheel"] == np.ptp(a) and np.ptp(a - te) < 0.01 * np.ptp(a)  # equal up to a constant
    law = cfg.contact_law(cfg.pairs["pinion-wheel"])
    single = (cfg.load["torque"] / cfg.gears["wheel"].rb / law.K) ** (1.0 / law.e)  # one pair's static approach
    assert 0.5 * single < v["te_mean_pinion_wheel"] < single


def test_sensor_metrics_of_known_signals():
    """Per sensor signal (the measured one, not its noise-free copy): a sine of amplitude a on an
    offset has RMS a / sqrt 2, peak a and kurtosis 3/2, in the signal's unit; Gaussian noise a
    kurtosis of 3 (within 6 standard errors)."""
    from flexgear.results.store import SensorSignals

    res = synthetic_result(fm=243.7, fa=8.1, amps={1: 50.0})
    t = np.asarray(res.time)
    noise = np.random.default_rng(5).standard_normal(t.size)
    units = {"units": "m/s^2", "description": "test"}
    res.sensors = {"top": SensorSignals("top", {}, {"housing_path": 3.0 + 2.0 * np.sin(2 * np.pi * 97.0 * t),
                                                    "planet_pass": noise, "planet_pass_noise_free": 0 * noise},
                                        {"housing_path": units, "planet_pass": dict(units, units="N"),
                                         "planet_pass_noise_free": dict(units, units="N")})}
    v, info = compute_metrics(res, DEFAULT_METRICS)
    # (the closed forms of whole periods; the record ends within a period: 2e-3)
    assert v["sensor_rms_top_housing_path"] == pytest.approx(2.0 / math.sqrt(2), rel=2e-3)
    assert v["sensor_peak_top_housing_path"] == pytest.approx(2.0, rel=1e-3)
    assert v["sensor_kurtosis_top_housing_path"] == pytest.approx(1.5, rel=5e-3)
    assert v["sensor_kurtosis_top_planet_pass"] == pytest.approx(3.0, abs=6 * math.sqrt(24 / t.size))
    assert not any("noise_free" in k for k in v)
    assert info["sensor_rms_top_housing_path"][0] == "m/s^2" and info["sensor_peak_top_planet_pass"][0] == "N"
    assert info["sensor_kurtosis_top_planet_pass"][0] == "1"


def test_metrics_refuse_lines_the_record_cannot_resolve():
    short = synthetic_result(fm=243.7, fa=8.1, amps={1: 50.0}, n=400)  # 0.08 s: f_a needs 4 / 8.1 = 0.49 s
    v, _ = compute_metrics(short, DEFAULT_METRICS)
    assert math.isnan(v["amp_fy_fm1_minus_fa_a_b"]) and v["amp_fm1_a_b"] == pytest.approx(50.0, rel=0.02)
    assert math.isnan(line_or_nan(short, short.meshes["a-b"].normal_force, 2400.0, 243.7))  # above 0.4 fs
    spur = synthetic_result(fm=243.7, fa=0.0, amps={1: 50.0})
    v, _ = compute_metrics(spur, DEFAULT_METRICS)
    assert "amp_fy_fm1_a_b" not in v  # no carrier: no sideband columns


# --------------------------------------------------------------------------- kill and executors

def _ctrl_c_reaches_python():
    """Child ``preexec_fn``: SIGINT back to its default disposition, so that the child's Python
    installs its KeyboardInterrupt handler (a test runner started in the background of a shell
    without job control inherits SIGINT ignored, and Python then keeps it ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _children(pid):
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                if int((d / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                    out.append(int(d.name))
            except (OSError, IndexError, ValueError):
                pass
    return out


@pytest.mark.skipif(not Path("/proc").exists() or os.name != "posix", reason="needs /proc and SIGKILL")
def test_killed_batch_reruns_to_a_complete_consistent_summary(tmp_path):
    """SIGKILL once the summary lists two cases done: the summaries agree, the workers die, and
    the rerun completes the sweep. The summary is rewritten at most every 2 s, so the batch must
    outlast that with cases left: 12 cases of 2 s simulated (a warm case of 0.2 s ran all 8
    cases between two writes)."""
    n = 12
    speeds = ", ".join(f"{6.0 + i:.1f}" for i in range(n))
    p = sweep_file(tmp_path, '[set]\n"simulation.duration" = 2.0\n"simulation.run_in" = 0.01\n'
                             f'[grid]\n"drive.speed_hz" = [{speeds}]\n', tiny=False)
    out = tmp_path / "out"
    root = Path(flexgear.__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "flexgear.app.cli", "batch", str(p), "-o", str(out), "--workers", "2"],
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    t0 = time.time()
    done_at_kill = 0
    while time.time() - t0 < 300 and proc.poll() is None:  # a first compile under load can take 2 min
        if (out / "summary.csv").exists():
            done_at_kill = (pd.read_csv(out / "summary.csv").status == "done").sum()  # always a whole file
            if done_at_kill >= 2:
                break
        time.sleep(0.02)
    workers = _children(proc.pid)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert 2 <= done_at_kill < n, proc.stderr.read().decode()[-2000:]
    _assert_summaries_agree(out)  # written together, from one state
    deadline = time.time() + 10  # the workers die with the driver
    while time.time() < deadline and any(Path(f"/proc/{w}").exists() and "zombie" not in
                                         Path(f"/proc/{w}/status").read_text() for w in workers if
                                         Path(f"/proc/{w}/status").exists()):
        time.sleep(0.1)
    assert not [w for w in workers if Path(f"/proc/{w}/status").exists()
                and "zombie" not in Path(f"/proc/{w}/status").read_text()]
    r = run_batch(p, out, workers=2, **QUIET)
    assert r.done == n and r.failed == 0 and r.skipped >= done_at_kill and r.ran == n - r.skipped
    df = pd.read_csv(out / "summary.csv")
    assert len(df) == n and (df.status == "done").all() and df.key.is_unique
    cases = read_sweep(p).cases
    for row, case in zip(df.itertuples(), cases):
        res = load(out / row.file)  # every file whole
        assert res.config_toml == case.config_toml and row.key == case.key
        values, _ = compute_metrics(res, DEFAULT_METRICS)
        assert values["rms_force_pinion_wheel"] == row.rms_force_pinion_wheel
    left = [f.name for d in (out, out / "cases") for f in d.iterdir() if f.name.startswith(".")]
    assert left == []  # no temporary file left behind, nor the lock file


def _assert_summaries_agree(out):
    """summary.csv and summary.nc list the same cases as done, with the same files."""
    xr = pytest.importorskip("xarray")
    df = pd.read_csv(out / "summary.csv")
    with xr.open_dataset(out / "summary.nc", engine="h5netcdf") as ds:
        status = ds.status.values.ravel().tolist()
        files = ds.file.values.ravel().tolist()
    assert status == df.status.tolist()
    assert [f for f, st in zip(files, status) if st == "done"] == df.file[df.status == "done"].tolist()


@pytest.mark.skipif(os.name != "posix", reason="needs SIGINT")
def test_a_ctrl_c_that_python_swallows_still_stops_the_batch():
    """A SIGINT handled while the main thread runs a ``__del__`` (or a weakref callback): Python
    prints the KeyboardInterrupt and goes on, which once let a Ctrl-C'd batch run to its end.
    Inside :class:`CtrlC` the interrupt is remembered and :meth:`CtrlC.check` raises it; the
    local-process executor looks for it while waiting for a case; the handler is restored.
    The installed handler is called inside ``__del__`` as Python calls it on a SIGINT (the real
    signal: the Ctrl-C test below). In a process of its own: run inside the test runner's
    worker, this test (its pool forked and killed at once) twice took that worker down."""
    out = subprocess.run([sys.executable, "-c", SWALLOWED_CTRL_C], capture_output=True, text=True, timeout=120,
                         start_new_session=True, preexec_fn=_ctrl_c_reaches_python)
    words = out.stdout.split()
    assert out.returncode == 0 and words[:3] == ["remembered", "raised", "restored"], out.stdout + out.stderr[-2000:]
    assert words[3:6] == ["deferred-ran-through", "raised-after", "other-unraisable-shown"], out.stdout
    assert words[-1] == "interrupted" and float(words[-2]) < 5.0, out.stdout
    # the interrupt swallowed in __del__ is not printed; any other unraisable exception is
    assert "KeyboardInterrupt" not in out.stderr and "ValueError: not an interrupt" in out.stderr, out.stderr[-2000:]


SWALLOWED_CTRL_C = """
import signal, time
from flexgear.app.executors import CtrlC, ProcessExecutor

class Finaliser:
    def __del__(self):
        signal.getsignal(signal.SIGINT)(signal.SIGINT, None)

before = signal.getsignal(signal.SIGINT)
with CtrlC() as ctrl_c:
    Finaliser()  # collected at once: the interrupt is raised in __del__ and swallowed
    print("remembered" if ctrl_c.pressed else "lost")
    try:
        ctrl_c.check()
        print("not-raised")
    except KeyboardInterrupt:
        print("raised")
print("restored" if signal.getsignal(signal.SIGINT) is before else "not-restored")
with CtrlC() as ctrl_c:  # a Ctrl-C inside deferred() is remembered and raised after it
    try:
        with ctrl_c.deferred():
            signal.getsignal(signal.SIGINT)(signal.SIGINT, None)
            print("deferred-ran-through")
        ctrl_c.check()
    except KeyboardInterrupt:
        print("raised-after")

class Other:
    def __del__(self):
        raise ValueError("not an interrupt")

with CtrlC() as ctrl_c:
    ctrl_c.pressed = True
    Other()
    print("other-unraisable-shown")
with CtrlC() as ctrl_c:  # the executor's wait: the remembered Ctrl-C ends it within a poll
    ctrl_c.pressed = True
    ex = ProcessExecutor(1)
    t0 = time.perf_counter()
    try:
        next(ex.run(time.sleep, [30.0], ctrl_c))
    except KeyboardInterrupt:
        print(time.perf_counter() - t0, "interrupted")
    ex.close()
"""


@pytest.mark.skipif(not Path("/proc").exists() or os.name != "posix", reason="needs /proc and SIGINT")
def test_ctrl_c_stops_a_batch_at_once_and_leaves_only_whole_files(tmp_path):
    """SIGINT (Ctrl-C) while two workers run cases: the command exits with 130 within 4 s, with
    room for a loaded machine (it took 5-7 s: summary.nc's first import of xarray, then the
    interpreter freeing the solver), its workers are gone, no temporary file, no lock file, and
    the two summaries agree on the cases finished; the rerun completes the sweep."""
    p = sweep_file(tmp_path, '[set]\n"simulation.duration" = 3.0\n"simulation.run_in" = 0.01\n'
                             '[grid]\n"drive.speed_hz" = [6.0, 7.0, 8.0, 9.0, 10.0, 11.0]\n', tiny=False)
    out = tmp_path / "out"
    root = Path(flexgear.__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "flexgear.app.cli", "batch", str(p), "-o", str(out), "--workers",
                             "2"], env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            preexec_fn=_ctrl_c_reaches_python)
    t0 = time.time()
    workers = []
    while time.time() - t0 < 300 and proc.poll() is None:
        workers = _children(proc.pid)
        if len(workers) >= 2 and (out / "summary.csv").exists():
            break
        time.sleep(0.05)
    time.sleep(1.0)  # the cases under way
    t_int = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=60)
    took = time.perf_counter() - t_int
    err = proc.stderr.read().decode()
    assert proc.returncode == 130 and "interrupted" in err, err[-2000:]
    assert took < 4.0, f"{took:.2f} s from Ctrl-C to the end of the command"
    assert not [w for w in workers if Path(f"/proc/{w}/status").exists()
                and "zombie" not in Path(f"/proc/{w}/status").read_text()]
    left = [f.name for d in (out, out / "cases") for f in d.iterdir() if f.name.startswith(".")]
    assert left == []
    _assert_summaries_agree(out)
    for f in pd.read_csv(out / "summary.csv").file.dropna():
        load(out / f)  # whole
    assert run_batch(p, out, workers=2, **QUIET).done == 6



def _descendants(pid):
    out = _children(pid)
    for c in list(out):
        out += _descendants(c)
    return out


@pytest.mark.skipif(not Path("/proc").exists() or os.name != "posix", reason="needs /proc and SIGINT")
def test_ctrl_c_on_a_local_dask_cluster_stops_its_workers_at_once_and_quietly(tmp_path):
    """A terminal's Ctrl-C reaches every process of the job: the driver and the Dask workers of its
    LocalCluster. With cases under way it ends the command with 130 within 4 s, without a
    traceback or distributed's log of the teardown (the workers printed KeyboardInterrupt
    tracebacks, or after a 4 s wait 'still alive ... killing'), no process left, no temporary
    file, the summaries agreeing; the rerun completes the sweep from the files kept."""
    pytest.importorskip("distributed")
    p = sweep_file(tmp_path, '[set]\n"simulation.duration" = 3.0\n"simulation.run_in" = 0.01\n'
                             '[grid]\n"drive.speed_hz" = [6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0]\n', tiny=False)
    out = tmp_path / "out"
    root = Path(flexgear.__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "flexgear.app.cli", "batch", str(p), "-o", str(out),
                             "--dask-local", "2"], env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, preexec_fn=_ctrl_c_reaches_python, start_new_session=True)
    t0 = time.time()
    while time.time() - t0 < 300 and proc.poll() is None:
        if (out / "cases").is_dir() and any(f.suffix == ".h5" for f in (out / "cases").iterdir()):
            break  # the workers run cases
        time.sleep(0.05)
    workers = _descendants(proc.pid)
    t_int = time.perf_counter()
    os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the driver's process group
    try:
        proc.wait(timeout=60)
    except subprocess.TimeoutExpired:  # hung (it once waited forever for xarray's lock): leave nothing running
        os.killpg(proc.pid, signal.SIGKILL)
        raise
    took = time.perf_counter() - t_int
    err = proc.stderr.read().decode()
    assert proc.returncode == 130 and "interrupted" in err, err[-3000:]
    assert "Traceback" not in err and "distributed" not in err and "WARNING" not in err, err[-3000:]
    assert took < 4.0, f"{took:.2f} s from Ctrl-C to the end of the command"
    def alive():
        return {w: Path(f"/proc/{w}/cmdline").read_bytes().replace(b"\0", b" ")[:200] for w in workers
                if Path(f"/proc/{w}/status").exists() and "zombie" not in Path(f"/proc/{w}/status").read_text()}

    assert len(workers) >= 2
    t_end = time.time()  # multiprocessing's resource tracker ends when it reads the driver's pipe closed:
    while alive() and time.time() - t_end < 5.0:  # a moment after the driver; a live worker stays alive
        time.sleep(0.05)
    assert not alive(), alive()
    left = [f.name for d in (out, out / "cases") for f in d.iterdir() if f.name.startswith(".")]
    assert left == []
    _assert_summaries_agree(out)
    report = run_batch(p, out, workers=1, **QUIET)
    assert report.done == 8 and report.skipped >= 1

def _same_files(a, b):
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        attrs_a = {k: v for k, v in fa.attrs.items() if k not in TIMING_ATTRS}
        attrs_b = {k: v for k, v in fb.attrs.items() if k not in TIMING_ATTRS}
        assert attrs_a.keys() == attrs_b.keys()
        for k in attrs_a:
            assert np.array_equal(attrs_a[k], attrs_b[k]), k
        names = []
        fa.visit(names.append)
        for n in names:
            if isinstance(fa[n], h5py.Dataset):
                assert fa[n].dtype == fb[n].dtype and np.array_equal(fa[n][()], fb[n][()]), n


def test_serial_local_pool_and_dask_give_identical_results(tmp_path):
    pytest.importorskip("distributed")
    p = sweep_file(tmp_path, '[zip]\n"drive.speed_hz" = [8.0, 11.0, 14.0]\n"contact.damping" = [1000.0, 3000.0, 2000.0]\n')
    runs = {"serial": dict(workers=1), "pool": dict(workers=2),
            "dask": dict(dask_local=2, dask_processes=False)}  # a real LocalCluster, worker threads to stay fast
    tables = {}
    for name, kw in runs.items():
        r = run_batch(p, tmp_path / name, **kw, **QUIET)
        assert r.done == 3, name
        tables[name] = pd.read_csv(r.summary).drop(columns="wall_s")
    for name in ("pool", "dask"):
        pd.testing.assert_frame_equal(tables["serial"], tables[name], check_exact=True)
        for f in tables[name].file:
            _same_files(tmp_path / "serial" / f, tmp_path / name / f)


def test_a_plain_progress_line_counts_the_elapsed_time_from_the_batchs_start():
    """Without a terminal each finished case prints a line: its elapsed time counts from the
    batch's start, the solver's compile included (a trial's first batch read 'elapsed 0:00:15'
    after 1:34), and its ETA from the cases' own rate (the compile happens once)."""
    import io

    from flexgear.app.batch import BatchProgress

    stream = io.StringIO()
    bar = BatchProgress(4, stream=stream, started=time.perf_counter() - 95.0)
    bar.t0 -= 2.0  # the first case took 2 s
    bar.update("done")
    line = stream.getvalue().strip()
    assert line.startswith("flexgear batch: 1/4 run: 1 done, 0 failed, 3 remaining; elapsed 0:01:35, ETA 0:00:06")


def test_the_dynamic_factor_divides_by_the_static_load_when_the_back_flanks_strike():
    """A mesh that rattles: its force, signed by flank, swings below zero, so the back flanks
    strike (a zero-backlash spur pair at resonance). normal_force is the magnitude, whose mean
    counts the impacts as load (a trial: 26.3 kN against the torque's 10.1 kN, and a dynamic
    factor of 1.72 for a peak of 4.47 times the static load). The dynamic factor divides by the
    mean of the signed force; without back-flank contact it is peak over mean as before."""
    res = synthetic_result(fm=50.0, fa=0.0, amps={1: 1.0})
    n = res.time.size
    signed = 1000.0 + 2500.0 * np.cos(2 * np.pi * 50 * (res.time - res.time[0]))  # below zero for part of each period
    mesh = res.meshes["a-b"]
    mesh.normal_force = np.abs(signed)
    mesh.pair_force = np.column_stack([np.maximum(signed, 0.0), np.maximum(-signed, 0.0), np.zeros(n)])
    mesh.pair_side = np.column_stack([np.ones(n), -np.ones(n), np.zeros(n)]).astype(np.int8)
    v, _ = compute_metrics(res, DEFAULT_METRICS)
    assert v["mean_force_a_b"] == pytest.approx(np.abs(signed).mean()) and v["mean_force_a_b"] > 1500.0
    assert v["dynamic_factor_a_b"] == pytest.approx(3500.0 / 1000.0, rel=1e-9)
    mesh.pair_side = -mesh.pair_side  # the drive flank is the side that carries most, whichever sign it has
    assert compute_metrics(res, DEFAULT_METRICS)[0]["dynamic_factor_a_b"] == pytest.approx(3.5, rel=1e-9)


def test_a_rattling_lumped_spur_pairs_static_load_is_the_torques():
    """The lumped spur pair near its mesh resonance with a low damping ratio (300 Hz, zeta = 0.02,
    no backlash): the back flanks strike, the mean normal force (a magnitude) reads about 2.6
    times the torque's load T / r_b, and the static load the dynamic factor divides by is T / r_b
    within 10 % (the impacts sampled at the output rate: 6 % measured)."""
    from flexgear.app.metrics import static_force
    from flexgear.config import loads_config, preset_path

    cfg = loads_config('model = "lumped"\n' + preset_path("spur_pair").read_text()).use_damping_ratio(0.02)
    cfg.drive["speed_hz"] = 300.0
    cfg.simulation.update(duration=0.05, run_in=0.05, output_rate=50000.0, step=5e-6)
    mesh = flexgear.run(cfg).meshes["pinion-wheel"]
    load = cfg.load["torque"] / cfg.gears["wheel"].rb
    assert np.any(mesh.pair_side[:, 0] < 0) and mesh.normal_force.mean() > 2.0 * load
    assert static_force(mesh) == pytest.approx(load, rel=0.1)
