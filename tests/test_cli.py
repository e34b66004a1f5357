"""Command line: run (progress, results, figures, no overwrite), info, preset."""
import warnings

import pytest
from pathlib import Path

import h5py
from flexgear.app.cli import main


def test_info_lists_derived_data_and_frequencies(capsys):
    assert main(["info", "mercury_1a"]) == 0
    out = capsys.readouterr().out
    assert "| carrier f_a" in out and "| 8 " in out
    assert "| gear mesh f_m" in out and "528" in out
    assert "1.5855" in out  # sun-planet contact ratio (ISO 21771)
    # sun 30 Hz, carrier 30 * 24 / 90 = 8 Hz: each planet spins 22 * 24 / 21 = 25.14 Hz against the sun
    # relative to the carrier, 8 - 25.14 = -17.14 Hz absolute; three planets pass a point at 24 Hz
    rows = {r[0].strip(): r[1].strip() for r in (line.strip("|").split("|") for line in out.splitlines())
            if len(r) == 2}
    assert rows["planet spin relative to carrier (against the sun)"] == "25.14"
    assert rows["planet rotation, absolute (signed as the sun's)"] == "-17.14"
    assert rows["planet pass N f_a (the planets passing a fixed point)"] == "24"


def test_run_writes_results_and_figures_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "spur"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["run", "spur_pair", "-o", str(out), "--duration", "0.02"]) == 0
    h5 = out / "results.h5"
    assert h5.exists() and (out / "fig03_pinion_wheel_force.png").exists()
    said = capsys.readouterr()
    assert "flexgear: model built in" in said.err  # every phase of the wait is named
    assert "model built in" in said.out  # and summed up
    with h5py.File(h5, "r") as f:
        assert f["meshes/pinion-wheel/normal_force"].shape == (round(0.02 * f.attrs["output_rate"]),)
        assert "kind = \"spur\"" in f.attrs["config_toml"]
    stamp = h5.stat().st_mtime_ns
    assert main(["run", "spur_pair", "-o", str(out), "--duration", "0.02"]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert h5.stat().st_mtime_ns == stamp  # the saved result is untouched


def test_run_of_a_preset_with_the_lumped_suffix_runs_and_records_its_lumped_model(tmp_path, capsys):
    out = tmp_path / "lumped"
    assert main(["run", "spur_pair:lumped", "-o", str(out), "--duration", "0.02", "--no-figures"]) == 0
    with h5py.File(out / "results.h5", "r") as f:
        assert f.attrs["model"] == "lumped"
        assert 'model = "lumped"' in f.attrs["config_toml"]  # a rerun of the stored document is lumped too


def test_print_config_prints_every_default_and_runs_nothing(tmp_path, capsys, monkeypatch):
    """``run --print-config`` (the configuration guide's): the configuration with every default,
    which reads back to the same configuration, with --duration applied; no -o needed, nothing
    simulated; without it -o is required (exit 2, named)."""
    import flexgear.app.run as app_run
    from flexgear.config import config_document, load_config, loads_config

    monkeypatch.setattr(app_run, "run", lambda *a, **k: pytest.fail("simulated"))
    assert main(["run", "mercury_1a_sensors", "--print-config", "--duration", "0.3"]) == 0
    text = capsys.readouterr().out
    expected = load_config("mercury_1a_sensors")
    expected.simulation["duration"] = 0.3
    assert config_document(loads_config(text)) == config_document(expected)
    assert "[[sensors]]" in text and "duration = 0.3" in text
    assert main(["run", "spur_pair"]) == 2
    assert "-o/--output OUTDIR is required" in capsys.readouterr().err


def test_a_warning_prints_as_the_commands_own_line(tmp_path, capsys):
    """A warning during a command is one line ``flexgear: warning: ...``, without Python's source
    file, line number and code line (the lumped spur preset's overdamped mesh warns)."""
    assert main(["run", "spur_pair:lumped", "-o", str(tmp_path / "w"), "--duration", "0.02", "--no-figures"]) == 0
    err = capsys.readouterr().err
    line = next(x for x in err.splitlines() if "damping ratio of" in x)
    assert line.startswith("flexgear: warning: mesh pinion-wheel:")
    assert "UserWarning" not in err and ".py:" not in err


def test_bad_config_gives_a_clear_error(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('kind = "spur"\n[gears.pinion]\nteeth = 24\n[gears.wheel]\nteeth = 21\nmodule = -1.0\n')
    assert main(["run", str(bad), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "gears.wheel.module = -1.0: must be > 0" in err
    assert not (tmp_path / "o").exists()  # nothing ran, nothing was written


def test_modes_of_a_flexible_gear_are_those_of_its_flexible_mesh(tmp_path, capsys):
    """A gear of [flexible] is meshed by [flexible]'s level, order and formulation (the FE model
    the flexible run reduces), not [fe]'s: ``modes`` writes the clamped frequencies of that model,
    and says so; the rigid gear of the same file follows [fe]."""
    import csv

    from flexgear.config import load_config
    from flexgear.fe.meshing import MeshSettings
    from flexgear.fe.output import clamped_gear_modes

    text = (load_config("spur_pair").source_text + '\n[flexible]\ngears = ["pinion"]\nlevel = 0\n'
            'formulation = "plane_strain"\n')
    path = tmp_path / "flex.toml"
    path.write_text(text + '\n[fe]\nlevel = 0\nformulation = "plane_stress"\nn_modes = 3\n')
    assert main(["modes", str(path), "-o", str(tmp_path / "m")]) == 0
    assert "pinion: meshed as the flexible model meshes it ([flexible] level 0, order 2, plane_strain)" in \
        capsys.readouterr().err
    cfg = load_config(str(path))
    for gear, formulation in (("pinion", "plane_strain"), ("wheel", "plane_stress")):
        with open(tmp_path / "m" / gear / f"{gear}_modes.csv") as fh:
            got = [float(r["frequency_Hz"]) for r in csv.DictReader(fh)]
        _, _, want, _ = clamped_gear_modes(cfg.gears[gear], cfg.material, MeshSettings(level=0), 3,
                                           formulation=formulation, cache_dir=tmp_path / "c")
        assert got == pytest.approx(list(want), rel=1e-9), gear


def test_preset_copy_refuses_to_overwrite(tmp_path):
    dst = tmp_path / "my.toml"
    assert main(["preset", "mercury_1a", "-o", str(dst)]) == 0
    dst.write_text("# my edits\n")
    assert main(["preset", "mercury_1a", "-o", str(dst)]) == 2
    assert dst.read_text() == "# my edits\n"


def test_mesh_and_modes_commands(tmp_path, capsys):
    out = tmp_path / "fe"
    assert main(["modes", "mercury_1a", "-o", str(out), "--gear", "sun", "--level", "0"]) == 0
    table = (out / "sun" / "sun_modes.md").read_text()
    assert table.count("\n| ") >= 10  # ten clamped-hub frequencies
    assert main(["mesh", "mercury_1a", "-o", str(out), "--gear", "ring", "--level", "0"]) == 0
    assert (out / "ring" / "ring_mesh.vtu").stat().st_size > 0
    assert main(["modes", "mercury_1a", "-o", str(out), "--gear", "sun", "--level", "0"]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert main(["mesh", "mercury_1a", "-o", str(out), "--gear", "moon"]) == 2


# ---------------------------------------------------------------- checks before work, clean failures
def test_version_and_help_for_every_argument(capsys):
    import argparse

    import pytest

    from flexgear import __version__
    from flexgear.app.cli import build_parser

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.strip() == f"flexgear {__version__}"
    parser = build_parser()
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sp in subs.choices.items():
        flags = {opt for a in sp._actions for opt in a.option_strings}
        assert "-o" in flags or name == "warm", f"{name}: no -o"  # warm fills caches only, writes no output
        for a in sp._actions:
            assert a.help, f"{name} {a.dest}: no help"
    helps = {n: " ".join(sp.format_help().split()) for n, sp in subs.choices.items()}
    assert "0-5" in helps["mesh"] and "sun, planet" in helps["modes"] and "spur_pair, mercury_1a" in helps["run"]
    from flexgear.config import PARAMETER_SETS, PRESETS

    for name in ("run", "info", "mesh", "modes", "modal"):  # every preset a command takes, from the one list
        assert all(p in helps[name] for p in PRESETS), name
    assert all(p in helps["modal"] for p in PARAMETER_SETS)
    # --duration: the run-in is simulated on top of it, and the help says so
    assert "run_in (0.2 s in the presets) before it" in helps["run"]


def test_run_with_output_naming_a_file_or_a_bad_config_path_fails_cleanly(tmp_path, capsys):
    f = tmp_path / "afile"
    f.write_text("mine")
    assert main(["run", "spur_pair", "-o", str(f)]) == 2
    assert "exists and is not a directory" in capsys.readouterr().err
    assert main(["run", "spur_pair", "-o", str(f / "sub")]) == 2  # refused before running, too
    assert "exists and is not a directory" in capsys.readouterr().err
    assert f.read_text() == "mine"
    assert main(["run", str(tmp_path), "-o", str(tmp_path / "o")]) == 2
    assert "is a directory" in capsys.readouterr().err
    binary = tmp_path / "b.toml"
    binary.write_bytes(bytes(range(256)) * 8)
    assert main(["info", str(binary)]) == 2
    assert "not a text (UTF-8 TOML) file" in capsys.readouterr().err
    assert main(["preset", "spur_pair", "-o", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_run_refuses_an_existing_figure_before_running(tmp_path, capsys, monkeypatch):
    import flexgear.app.run as run_module

    def must_not_run(*a, **k):
        raise AssertionError("the simulation ran although an output figure exists")

    monkeypatch.setattr(run_module, "run", must_not_run)
    out = tmp_path / "o"
    out.mkdir()
    (out / "fig04_pinion_wheel_spectrum.png").write_bytes(b"mine")
    assert main(["run", "spur_pair", "-o", str(out)]) == 2
    assert "fig04_pinion_wheel_spectrum.png exists; refusing to overwrite" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["fig04_pinion_wheel_spectrum.png"]  # no results.h5


def test_a_failed_run_leaves_no_output_directory(tmp_path, capsys, monkeypatch):
    import flexgear.app.run as run_module
    from flexgear.errors import DivergenceError

    def diverge(cfg, progress=None, messages=None):
        progress(0.5)
        raise DivergenceError("simulation diverged at t = 0.1 s in mesh 'pinion-wheel': test")

    monkeypatch.setattr(run_module, "run", diverge)
    out = tmp_path / "a" / "b"
    assert main(["run", "spur_pair", "-o", str(out)]) == 2
    assert "diverged" in capsys.readouterr().err
    assert not (tmp_path / "a").exists()


def test_modes_and_mesh_check_every_gear_before_meshing_any(tmp_path, capsys):
    out = tmp_path / "fe"
    (out / "ring").mkdir(parents=True)
    (out / "ring" / "ring_modes.csv").write_text("mine")
    assert main(["modes", "mercury_1a", "-o", str(out), "--level", "0"]) == 2
    assert "ring_modes.csv" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["ring"]  # sun and planet were not computed
    # a ring rim thinner than one module: refused before the sun and the planet are meshed
    from flexgear.config import preset_path

    text = preset_path("mercury_1a").read_text()
    assert "rim_diameter = 0.160" in text
    cfg = tmp_path / "thin_rim.toml"
    cfg.write_text(text.replace("rim_diameter = 0.160", "rim_diameter = 0.138"))
    out2 = tmp_path / "fe2"
    assert main(["mesh", str(cfg), "-o", str(out2), "--level", "0"]) == 2
    assert "ring.rim_diameter" in capsys.readouterr().err
    assert not out2.exists()


def test_progress_lines_without_a_terminal():
    import io

    from flexgear.app.console import progress_bar

    stream = io.StringIO()
    bar, update = progress_bar(1.2, stream=stream, every_s=0.0)
    for f in (0.25, 0.5, 1.0, 1.0):
        update(f)
    bar.close()
    lines = stream.getvalue().splitlines()
    assert lines[0].startswith("flexgear: simulating 1.200 s")  # at once: a log shows the run started
    assert [line.split(" elapsed")[0] for line in lines[1:]] == [
        f"flexgear: {p:3d} % ({p * 0.012:.3f}/1.200 s simulated, 0 s" for p in (25, 50, 100)]


def test_progress_lines_estimate_the_time_left_from_the_rate_since_the_simulation_advanced(monkeypatch):
    """A plain line says how long the rest takes at the mean rate since the first advance: the
    40 s of compiling before it do not count. 25 % at t = 40 s, 50 % at t = 50 s: 25 % per 10 s,
    so 20 s for the remaining 50 %; 75 % at t = 60 s: 10 s; at the end nothing is left."""
    import io

    import flexgear.app.console as console

    clock = iter([0.0, 40.0, 50.0, 60.0, 70.0])
    monkeypatch.setattr(console.time, "perf_counter", lambda: next(clock))
    stream = io.StringIO()
    lines = console.ProgressLines(1.2, stream, every_s=0.0)
    for f in (0.25, 0.5, 0.75, 1.0):
        lines.update(f)
    out = stream.getvalue().splitlines()
    assert out[1] == "flexgear:  25 % (0.300/1.200 s simulated, 40 s elapsed)"  # no rate known yet
    assert out[2] == "flexgear:  50 % (0.600/1.200 s simulated, 50 s elapsed, about 20 s left)"
    assert out[3] == "flexgear:  75 % (0.900/1.200 s simulated, 60 s elapsed, about 10 s left)"
    assert out[4] == "flexgear: 100 % (1.200/1.200 s simulated, 70 s elapsed)"
    assert console.time_left(30.0, 0.2) == ", about 2 min 0 s left"


def test_summary_reports_compile_time_apart_from_the_simulation():
    from types import SimpleNamespace

    import numpy as np

    from flexgear.app.cli import summary_text

    mesh = SimpleNamespace(normal_force=np.array([1.0, 3.0]))
    attrs = dict(run_in=0.2, duration=1.0, solver_steps=48000, newton_iterations=96000, rejected_steps=0,
                 wall_seconds=2.4, compile_seconds=41.0, notes="none")
    text = summary_text(SimpleNamespace(meshes={"pinion-wheel": mesh}, attrs=attrs))
    assert "2.40 s wall for 1.2 s simulated (2.00 s per simulated second)" in text
    assert "plus 41.0 s to compile the solver" in text
    attrs["compile_seconds"] = 0.0
    assert "compile" not in summary_text(SimpleNamespace(meshes={"pinion-wheel": mesh}, attrs=attrs))
    attrs["wall_seconds"] = 0.0031  # a short lumped run: milliseconds, not "0.00 s"
    assert "0.0031 s wall for 1.2 s simulated (0.0026 s per simulated second)" in summary_text(
        SimpleNamespace(meshes={"pinion-wheel": mesh}, attrs=attrs))


def test_progress_lines_keep_a_log_alive_while_nothing_advances():
    import io
    import time

    from flexgear.app.console import ProgressLines

    stream = io.StringIO()
    lines = ProgressLines(1.0, stream, every_s=0.05)
    time.sleep(0.3)  # e.g. the solver compiling: no update arrives
    lines.note("compiling the solver")  # the phase, as the run says it, repeated while nothing advances
    time.sleep(0.2)
    lines.update(0.5)
    time.sleep(0.2)
    lines.close()
    out = stream.getvalue().splitlines()
    waiting = [line for line in out[1:] if line.startswith("flexgear:   0 % (0.000/1.000 s simulated")]
    assert len(waiting) >= 3 and waiting[-1].endswith("elapsed): compiling the solver")
    assert not any("compiling" in line for line in out[1:] if not line.startswith("flexgear:   0 %"))


def test_progress_lines_say_compiling_when_the_solver_said_to_load_compiles(monkeypatch):
    """A run says "loading" when the cache holds a solver of its kind of model (rigid or
    flexible: it cannot tell which ahead); the lines repeated while it waits say "compiling" once
    the kernels report a compile (flexgear.kernels.compiling, tested in test_kernel_cache)."""
    import io

    from flexgear.app import console

    for compiling, said in ((False, "elapsed): loading the compiled solver"), (True, "elapsed): compiling the solver")):
        monkeypatch.setattr(console, "_compiling", lambda compiling=compiling: compiling)
        stream = io.StringIO()
        lines = console.ProgressLines(1.0, stream, every_s=0.0)
        lines.note("loading the compiled solver from the kernel cache, then simulating")
        lines.update(0.0)
        lines.close()
        assert said in stream.getvalue().splitlines()[-1]


def test_a_rigid_run_says_whether_its_own_kind_of_solver_is_compiled_before_it_waits(monkeypatch):
    """Once its model is built a multi-body run asks for its own overload of the time loop: the
    rigid solver the session's warm-up cached is loaded (or ready) without a hedge about other
    kinds of model; one that is not on disk is said to compile, before the wait."""
    import flexgear
    from flexgear.config import load_config
    from flexgear.dynamics.integrator import simulation

    cfg = load_config("spur_pair")
    cfg.simulation.update(run_in=0.0, duration=0.01)
    said = []
    flexgear.run(cfg, progress=False, messages=said.append)
    solver = [m for m in said if m.endswith("then simulating") or m.startswith("simulating")]
    # no hedge about other kinds of model (the old message added one to every cached run)
    assert solver in (["loading the compiled solver from the kernel cache, then simulating"],
                      ["simulating (solver compiled in this process)"]), solver
    monkeypatch.setattr(simulation, "overload_state", lambda kernel, args: "compile")
    said.clear()
    flexgear.run(cfg, progress=False, messages=said.append)
    assert [m for m in said if m.startswith("compiling the solver")] == [
        "compiling the solver: the first run of this kind of model on this machine, 1 to 3 minutes on 2 cores (cached "
        "for later runs; flexgear warm does it ahead), then simulating"]


def test_a_run_says_whether_it_compiles_or_loads_the_solver_before_it_waits(monkeypatch):
    """Said before the wait: the rigid solver the session's warm-up compiled is loaded (or ready),
    a kernel neither compiled in this process nor cached is compiled first."""
    import flexgear.kernels as kernels
    from flexgear.app.run import solver_message, solver_ready
    from flexgear.dynamics.lumped import time_loop

    assert solver_message(lumped=False).startswith(("loading the compiled solver", "simulating (solver compiled"))

    class Fresh:
        signatures = []

    monkeypatch.setattr(time_loop, "integrate_lumped", Fresh())
    monkeypatch.setattr(kernels, "is_cached", lambda k: False if isinstance(k, Fresh) else True)
    assert solver_message(lumped=True).startswith("compiling the solver: its first run on this machine, a few seconds")
    assert not solver_ready(lumped=True) and solver_ready(lumped=False)  # what a batch says before its cases
    # a lumped run with friction takes its own loop: loaded while the frictionless one is not cached
    assert solver_message(lumped=True, friction=True).startswith(("loading the compiled solver", "simulating"))
    monkeypatch.setattr(time_loop, "integrate_lumped_friction", Fresh())
    assert solver_message(lumped=True, friction=True).startswith("compiling the solver")


def test_a_lumped_run_with_friction_or_a_squeeze_film_names_the_friction_loop():
    """Which lumped time loop a configuration takes: the friction loop with friction or a squeeze
    film, the frictionless one with neither or a zero coefficient (the frictionless model)."""
    from flexgear.config import loads_config, preset_path
    from flexgear.dynamics.lumped.friction import friction_loop as lumped_friction_loop

    base = 'model = "lumped"\n' + preset_path("spur_pair").read_text() + "\n"
    assert not lumped_friction_loop(loads_config(base))
    assert lumped_friction_loop(loads_config(base + "[lubrication]\nfriction_coefficient = 0.05\n"))
    assert not lumped_friction_loop(loads_config(base + "[lubrication]\nfriction_coefficient = 0.0\n"))
    squeeze = ('[lubrication]\nfriction_coefficient = 0.0\ndamping = "squeeze_film"\niso_vg = 220\n'
               'oil_temperature_c = 60.0\n')
    assert lumped_friction_loop(loads_config(base + squeeze))


def test_a_writer_failing_midway_leaves_no_empty_gear_folder(tmp_path, capsys, monkeypatch):
    """The first gear's files are kept; the gear whose writer failed leaves no empty folder."""
    import flexgear.fe.output as output

    real = output.write_mesh_outputs
    calls = []

    def fail_on_second(gear, material, settings, outdir, **kw):
        calls.append(gear.name)
        if len(calls) == 2:
            outdir.mkdir(parents=True, exist_ok=True)
            raise RuntimeError("writer failed")
        return real(gear, material, settings, outdir, **kw)

    monkeypatch.setattr(output, "write_mesh_outputs", fail_on_second)
    out = tmp_path / "fe"
    try:
        main(["mesh", "spur_pair", "-o", str(out), "--level", "0"])
    except RuntimeError:
        pass
    assert len(calls) == 2
    assert sorted(p.name for p in out.iterdir()) == [calls[0]]
    assert any((out / calls[0]).iterdir())



def test_run_checks_threads_before_any_work():
    """``run(threads=...)`` (the solver's thread count, :mod:`flexgear.dynamics.threads`) meets
    the rule of ``simulate`` before the model is built: 0 is an error naming the parameter."""
    import pytest
    from flexgear.app.run import run

    with pytest.raises(ValueError, match="threads = 0: must be None"):
        run("spur_pair", threads=0)


def test_an_output_directory_that_cannot_be_written_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    """``-o /proc/flexout`` (a directory the system refuses to create) and ``-o /proc`` (one that
    takes no file): every command with -o refuses at once, with the reason, before simulating,
    meshing or solving anything, and leaves no probe behind. Root bypasses permission bits, so
    the refusal comes from /proc."""
    import os

    import pytest

    import flexgear.app.batch as batch_module
    import flexgear.app.run as run_module
    import flexgear.dynamics.modal.analysis as modal_module
    import flexgear.fe.meshing as meshing

    if not os.path.isdir("/proc/self"):
        pytest.skip("needs Linux /proc")

    def must_not_run(*a, **k):
        raise AssertionError("work started before the output directory was checked")

    # the batch binds run at its import: patched there too (imported above, not first during the
    # patch, which would leave its run patched for every later test in this process)
    for mod, name in ((run_module, "run"), (batch_module, "run"), (modal_module, "modal_analysis"),
                      (meshing, "mesh_gear")):
        monkeypatch.setattr(mod, name, must_not_run)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('base = "spur_pair"\n[grid]\n"drive.speed_hz" = [10.0]\n')
    from flexgear.results.store import save
    from test_results import make_result

    result = save(make_result(), tmp_path / "results.h5")
    t0, t1 = (float(x) for x in make_result().time[[0, 3]])
    commands = {
        "run": ["run", "spur_pair"], "modal": ["modal", "mercury_1a"], "mesh": ["mesh", "mercury_1a"],
        "modes": ["modes", "mercury_1a"], "batch": ["batch", str(sweep), "--workers", "1"],
        "deform": ["deform", str(result), "--window", str(t0), str(t1), "--scale", "100"],
    }
    for name, argv in commands.items():
        cases = [("/proc/flexout/sub", "cannot create '/proc/flexout'")]
        if name != "batch":  # batch refuses /proc earlier: not empty and not a batch directory
            cases.append(("/proc", "cannot write a file there"))
        for out, why in cases:
            assert main(argv + ["-o", out]) == 2, (name, out)
            err = capsys.readouterr().err
            assert f"output directory '{out}'" in err and why in err, (name, out, err)
    for name in ("info", "preset"):
        assert main([name, "spur_pair", "-o", "/proc/spur.toml"]) == 2
        assert "output directory '/proc': cannot write a file there" in capsys.readouterr().err
    assert not any(p.name.startswith(".flexgear-write-probe") for p in Path("/proc").iterdir())


def test_warm_refuses_a_bad_name_before_any_work(capsys, monkeypatch):
    import flexgear.app.warm as warm_module

    def must_not_run(*a, **k):
        raise AssertionError("warmed before every name was checked")

    monkeypatch.setattr(warm_module, "warm_config", must_not_run)
    assert main(["warm", "spur_pair", "no_such_preset"]) == 2
    assert "'no_such_preset' not found" in capsys.readouterr().err
    assert main(["warm", "spur_pair:flexible"]) == 2
    assert "'spur_pair:flexible' not found" in capsys.readouterr().err


def test_warm_runs_each_configuration_a_few_samples_and_reports_its_phases(capsys, monkeypatch):
    """``flexgear warm spur_pair spur_pair:lumped`` runs each configuration, in order, for four
    output samples without run-in (the lumped one as the lumped model), leaves the lumped time
    loop in the disk cache, and tables each phase's time."""
    import flexgear.app.run as run_module
    from flexgear.dynamics.lumped.time_loop import integrate_lumped
    from flexgear.kernels import is_cached

    real, seen = run_module.run, []

    def recorded(cfg, **kw):
        seen.append((cfg.model, cfg.simulation["run_in"], cfg.simulation["duration"] * cfg.simulation["output_rate"]))
        return real(cfg, **kw)

    monkeypatch.setattr(run_module, "run", recorded)
    assert main(["warm", "spur_pair", "spur_pair:lumped"]) == 0
    assert seen == [("rigid", 0.0, pytest.approx(4.0)), ("lumped", 0.0, pytest.approx(4.0))]
    said = capsys.readouterr()
    assert "warning" not in said.err  # the lumped spur pair's damping ratio: for its real runs to say
    out = said.out
    assert "| spur_pair:lumped |" in out and "solver kernels s" in out and "caches warm after" in out
    assert is_cached(integrate_lumped)
