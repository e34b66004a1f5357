"""Using flexgear from Python (a notebook, a script) rather than the command line: the names on
the package, a Config edited in Python checked as strictly as a file, progress in a notebook,
results that compare and print briefly, files written where asked."""
import math
import re
import subprocess
import sys

import numpy as np
import pytest

import flexgear
from flexgear.config import check_config, load_config, loads_config, preset_path
from flexgear.errors import ConfigError
from flexgear.gears.faults import LEFT, Crack


def lumped(duration=0.05):
    cfg = load_config("spur_pair:lumped")
    cfg.simulation["duration"] = duration
    return cfg


def test_subpackages_and_save_are_on_the_package_in_a_fresh_process(tmp_path):
    """``flexgear.config``, ``flexgear.results``, ... without importing them first (the guides
    write ``flexgear.config.check_config(cfg)``), and ``flexgear.save`` beside ``flexgear.load``."""
    code = ("import flexgear\n"
            "assert callable(flexgear.config.check_config) and callable(flexgear.results.store.save)\n"
            "assert flexgear.save is not None and flexgear.monitoring.monitor\n"
            "try:\n    flexgear.nothing\nexcept AttributeError as e:\n    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "module 'flexgear' has no attribute 'nothing'" in out.stdout


def test_a_model_mistyped_in_python_is_refused_not_run_as_the_rigid_model():
    cfg = load_config("spur_pair")
    cfg.model = "lumpd"
    with pytest.raises(ConfigError, match=r"model = 'lumpd': must be one of 'rigid', 'lumped'"):
        check_config(cfg)


@pytest.mark.parametrize("faults, message", [
    ((Crack(gear="pinion", tooth=0, flank="up", depth=1e-3, angle=0.7),), r"faults\[0\].flank = 'up': must be LEFT"),
    ((Crack(gear="pinion", tooth=0, flank=LEFT, depth=1e-3, angle=45.0),),
     r"faults\[0\].angle = 45.0 rad \(2578.31 deg\): must lie in \(0, pi/2\]; Crack.angle is in radians"),
    (Crack(gear="pinion", tooth=0, flank=LEFT, depth=1e-3, angle=0.7), r"faults = Crack\(.*\): must be a tuple"),
    (({"kind": "crack", "gear": "pinion"},), r"faults\[0\] = \{'kind': 'crack'.*must be a fault object"),
])
def test_faults_set_in_python_are_named_when_wrong(faults, message):
    cfg = load_config("spur_pair")
    cfg.faults = faults
    with pytest.raises(ConfigError, match=message):
        check_config(cfg)


def test_faults_set_in_python_take_the_files_flank_names_and_numpy_integers():
    """``flank="left"`` as in the file, ``tooth=np.int64(3)`` as a loop over np.arange gives:
    the same configuration as LEFT and 3."""
    cfg = load_config("spur_pair")
    cfg.faults = (Crack(gear="pinion", tooth=np.int64(3), flank="left", depth=1e-3, angle=math.radians(45)),)
    got = check_config(cfg).faults[0]
    assert got == Crack(gear="pinion", tooth=3, flank=LEFT, depth=1e-3, angle=math.radians(45))
    assert type(got.tooth) is int


@pytest.mark.parametrize("value", ["yes", 1.5, [0.5]])
def test_a_progress_that_is_no_callable_is_refused_before_anything(value, monkeypatch):
    import flexgear.app.run as app_run

    monkeypatch.setattr(app_run, "build_lumped", lambda *a: pytest.fail("the model was built"))
    with pytest.raises(TypeError, match=r"run\(progress=.*\): must be None, a callable taking the fraction done"):
        flexgear.run(lumped(), progress=value)


def test_a_rigid_preset_switched_to_lumped_in_python_is_the_file_with_model_lumped():
    """cfg.model = "lumped" on a preset without [lumped] takes the [lumped] defaults, as the file
    with model = "lumped" does (the configuration document had failed on the missing table)."""
    cfg = load_config("mercury_1a")
    cfg.model = "lumped"
    got = check_config(cfg)
    want = loads_config('model = "lumped"\n' + preset_path("mercury_1a").read_text())
    assert got.model == "lumped" and got.lumped == want.lumped and got.lumped["dofs"] == "planar"


def test_a_model_kind_given_to_run_is_refused_with_where_it_goes(monkeypatch):
    """run(cfg, model="lumped") reads as choosing the lumped model; ``model`` is a built model."""
    import flexgear.app.run as app_run

    monkeypatch.setattr(app_run, "build_lumped", lambda *a: pytest.fail("the model was built"))
    with pytest.raises(TypeError, match=r"run\(model='lumped'\): must be None or a model built .*cfg.model = 'lumped'"):
        flexgear.run(lumped(), model="lumped")


def test_progress_true_shows_a_bar_and_the_phases(capsys):
    """``progress=True`` where stderr is no terminal (a script's log; here the captured
    streams): plain progress lines, the last at 100 %, no carriage returns (a tqdm bar's would
    garble the log), the phases of the wait said with them on stderr (a trial's script printed
    nothing at all; a later one found the phases on stdout, apart from the lines), stdout left
    to the user; False: nothing; the signals are the same (the run data, wall times among them,
    are not). In a terminal it is a bar (the next test)."""
    res = flexgear.run(lumped(), progress=True)
    got = capsys.readouterr()
    assert re.search(r"flexgear: 100 % \(([\d.]+)/\1 s simulated", got.err) and "\r" not in got.err, got.err
    assert "solver" in got.err and got.out == "", got
    quiet = flexgear.run(lumped(), progress=False)
    got = capsys.readouterr()
    assert got.err == got.out == "" and quiet.meshes == res.meshes and quiet.bodies == res.bodies


@pytest.mark.skipif(sys.platform == "win32", reason="needs a pseudo-terminal")
def test_an_interactive_session_shows_the_progress_bar_by_default():
    """A script run from a terminal waited silently (a trial's first flexible run: 305 s, the
    solver compiling): with ``progress`` not given the bar and the phases show where stderr is a
    terminal, and nothing where it is a pipe (a log, a batch, the test runner)."""
    import fcntl
    import os
    import pty
    import struct
    import termios

    script = ("import flexgear; c = flexgear.load_config('spur_pair:lumped'); "
              "c.simulation.update(run_in=0.01, duration=0.02); flexgear.run(c); print('done')")
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # 100 columns (tqdm's width)
    proc = subprocess.Popen([sys.executable, "-c", script], stdin=subprocess.DEVNULL, stdout=slave, stderr=slave)
    os.close(slave)
    seen = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # EIO: the child closed the terminal
            break
        if not chunk:
            break
        seen += chunk
    os.close(master)
    assert proc.wait(timeout=300) == 0
    text = seen.decode(errors="replace")
    assert "flexgear run: 100%" in text and "done" in text, text[-2000:]
    piped = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert piped.returncode == 0 and piped.stdout == "done\n" and "flexgear run" not in piped.stderr, piped.stderr


def test_results_compare_by_their_contents_and_print_briefly(tmp_path):
    """A result read back equals the one saved (arrays element by element, nan slots equal);
    one changed sample makes them differ; its repr is one line, not the arrays; save creates
    the directory it is asked to write into and refuses a directory as the file."""
    res = flexgear.run(lumped())
    back = flexgear.load(flexgear.save(res, tmp_path / "new" / "dir" / "results.h5"))
    assert back == res and not (back != res)
    back.meshes["pinion-wheel"].force_global[3, 1] += 1e-6
    assert back != res and back.meshes["pinion-wheel"] != res.meshes["pinion-wheel"]
    assert back.bodies == res.bodies
    text = repr(res)
    assert "\n" not in text and len(text) < 300 and "lumped spur" in text and "meshes ['pinion-wheel']" in text
    with pytest.raises(IsADirectoryError, match="a directory; give a file name"):
        flexgear.save(res, tmp_path / "new")
    with pytest.raises(TypeError):
        hash(res)


def test_monitor_takes_results_in_memory(tmp_path):
    """``monitor(res)`` and a Result as a baseline, as in a notebook loop: the same indicators as
    from the saved files, the report naming them as in memory."""
    from flexgear.monitoring import MonitorSettings, monitor
    from flexgear.results.store import save

    def noisy(seed):
        cfg = load_config("spur_pair_sensors:lumped")
        cfg.simulation["duration"] = 0.3
        cfg.sensors = tuple(__import__("dataclasses").replace(s, snr_db=20.0, noise_seed=seed) for s in cfg.sensors)
        return flexgear.run(cfg)

    res, base = noisy(1), noisy(2)
    settings = MonitorSettings(signal="sensors/side/housing_path", shafts=["pinion"])
    mem = monitor(res, settings, baseline=[base])
    disk = monitor(save(res, tmp_path / "r.h5"), settings, baseline=[save(base, tmp_path / "b.h5")])
    assert mem.shafts["pinion"].indicators == disk.shafts["pinion"].indicators
    assert mem.shafts["pinion"].indicators["na4"] is not None
    assert str(mem.source.path) == "<in-memory result>" and mem.baseline == ["<in-memory baseline 0>"]


def test_a_run_up_records_the_mean_frequencies_of_its_record():
    """A speed table from 10 to 30 Hz over 0.6 s, recorded from 0.2 s: the result's input and
    mesh frequencies (which the spectrum marks) are the means over the record, 23.33 Hz and
    24 x 23.33 Hz (the linear ramp's mean from 16.67 to 30 Hz), not the table's 20 Hz, and a note
    says the speed varies."""
    cfg = load_config("spur_pair:lumped").use_damping_ratio(0.05)
    cfg.simulation["duration"] = 0.4
    cfg.drive["speed_hz"] = [[0.0, 10.0], [0.6, 30.0]]
    res = flexgear.run(cfg)
    assert res.attrs["input_frequency"] == pytest.approx(70.0 / 3.0, rel=2e-3)
    assert res.attrs["mesh_frequency"] == pytest.approx(24 * res.attrs["input_frequency"], rel=1e-12)
    assert "drive speed 16.67 to 30 Hz over the record" in res.attrs["notes"]


def test_a_runs_warning_points_at_the_users_line():
    """A warning of flexgear.run names the caller's file and line, not flexgear's own wrapper
    (a trial's warnings all pointed at flexgear/__init__.py:49)."""
    import warnings

    import flexgear

    cfg = flexgear.load_config("spur_pair_missing_tooth")
    cfg.simulation.update(run_in=0.02, duration=0.02)  # shorter than the fault's period: a warning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        flexgear.run(cfg, progress=False)
    short = [w for w in caught if "shorter than one period" in str(w.message)]
    assert short and short[0].filename == __file__, [(w.filename, w.lineno) for w in caught]


def test_a_load_ramp_longer_than_the_run_in_is_warned_noted_and_listed_by_a_sweep(tmp_path):
    """With run_in shorter than [load] ramp the record starts while the load still rises (a
    trial's sweep read 0.876 T / r_b as the mean force of 0.03 s run-ins): the run warns before
    the build, naming both keys and the rising span, its notes keep it and its mean force is
    low; a sweep lists it among its warnings; run_in = ramp says nothing."""
    import warnings

    from flexgear.app.sweep import read_sweep

    cfg = load_config("spur_pair:lumped").use_damping_ratio(0.05)
    rb = cfg.gears["wheel"].rb
    means = {}
    for run_in in (0.01, 0.05):
        cfg.simulation.update(run_in=run_in, duration=0.02)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = flexgear.run(cfg, progress=False)
        said = [str(w.message) for w in caught if "load.ramp" in str(w.message)]
        means[run_in] = float(np.mean(res.meshes["pinion-wheel"].normal_force)) * rb / cfg.load["torque"]
        if run_in < 0.05:
            assert len(said) == 1 and re.search(r"load\.ramp = 0\.05 s outlasts simulation\.run_in = 0\.01 s: the "
                                                r"record's first 0\.04 s hold the load torque still rising", said[0])
            assert said[0] in res.attrs["notes"]
        else:
            assert said == [] and "load.ramp" not in res.attrs["notes"]
    assert means[0.01] < 0.9 and means[0.05] == pytest.approx(1.0, abs=0.01), means
    p = tmp_path / "sweep.toml"
    p.write_text('base = "spur_pair"\n[set]\n"simulation.run_in" = 0.03\n[grid]\n"drive.speed_hz" = [8.0, 9.0]\n')
    assert [w for w in read_sweep(p).warnings if "load.ramp" in w] == [
        "load.ramp = 0.05 s outlasts simulation.run_in = 0.03 s: the record's first 0.02 s hold the load torque still "
        "rising to its set value (its force and transmission error read low there); set run_in >= ramp"]


def test_a_result_records_the_software_that_made_it(tmp_path):
    """Besides flexgear's version a result names Python's and the numerical libraries' (a trial:
    bit-identity was claimed, but a result named flexgear's version alone), through a save."""
    import platform

    import numba
    import scipy

    res = flexgear.run(load_config("spur_pair:lumped").use_damping_ratio(0.05), progress=False)
    sw = res.attrs["software"]
    for part in (f"python {platform.python_version()}", f"numpy {np.__version__}", f"scipy {scipy.__version__}",
                 f"numba {numba.__version__}"):
        assert part in sw.split("; "), (part, sw)
    assert flexgear.load(flexgear.save(res, tmp_path / "r.h5")).attrs["software"] == sw
