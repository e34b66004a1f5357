"""Command line: run (progress, results, figures, no overwrite), info, preset."""
import warnings

import h5py
from flexgear.app.cli import main


def test_info_lists_derived_data_and_frequencies(capsys):
    assert main(["info", "mercury_1a"]) == 0
    out = capsys.readouterr().out
    assert "| carrier f_a" in out and "| 8 " in out
    assert "| gear mesh f_m" in out and "528" in out
    assert "1.5855" in out  # sun-planet contact ratio (ISO 21771)


def test_run_writes_results_and_figures_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "spur"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["run", "spur_pair", "-o", str(out), "--duration", "0.02"]) == 0
    h5 = out / "results.h5"
    assert h5.exists() and (out / "fig03_pinion_wheel_force.png").exists()
    with h5py.File(h5, "r") as f:
        assert f["meshes/pinion-wheel/normal_force"].shape == (100,)
        assert "kind = \"spur\"" in f.attrs["config_toml"]
    stamp = h5.stat().st_mtime_ns
    assert main(["run", "spur_pair", "-o", str(out), "--duration", "0.02"]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert h5.stat().st_mtime_ns == stamp  # the saved result is untouched


def test_bad_config_gives_a_clear_error(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('kind = "spur"\n[gears.pinion]\nteeth = 24\n[gears.wheel]\nteeth = 21\nmodule = -1.0\n')
    assert main(["run", str(bad), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "gears.wheel.module = -1.0: must be > 0" in err
    assert not (tmp_path / "o").exists()  # nothing ran, nothing was written


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
