"""Files a user gets: permissions as for any file they create, the per-user cache, no empty
output directories after a failure."""
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from flexgear.errors import ResultExistsError
from flexgear.files import output_directory, user_cache_dir


def _mode(p) -> int:
    return stat.S_IMODE(os.stat(p).st_mode)


@pytest.fixture
def umask():
    old = os.umask(0o022)
    os.umask(old)

    def set_(m):
        os.umask(m)

    yield set_
    os.umask(old)


def _result():
    from flexgear.results.store import BodySignals, MeshSignals, Result

    n = 4
    mesh = MeshSignals(name="pinion-wheel", body_a="pinion", body_b="wheel", normal_force=np.ones(n),
                       force_global=np.ones((n, 2)), pair_force=np.ones((n, 1)), pair_tooth_a=np.zeros((n, 1), int),
                       pair_tooth_b=np.zeros((n, 1), int), pair_side=np.ones((n, 1), np.int8),
                       penetration=np.zeros((n, 1)))
    body = BodySignals(name="pinion", position=np.zeros((n, 2)), angle=np.zeros(n), velocity=np.zeros((n, 2)),
                       angular_velocity=np.zeros(n), torque=None)
    return Result(time=np.arange(n) / 5000.0, meshes={"pinion-wheel": mesh}, bodies={"pinion": body},
                  config_toml='kind = "spur"\n', attrs={})


@pytest.mark.parametrize("mask, expected", [(0o022, 0o644), (0o027, 0o640)])
def test_results_file_mode_follows_the_umask_like_other_files(tmp_path, umask, mask, expected):
    from flexgear.results.store import save

    umask(mask)
    h5 = save(_result(), tmp_path / "results.h5")
    other = tmp_path / "plain.txt"
    other.write_text("x")
    assert _mode(h5) == expected == _mode(other)  # not tempfile's 0600


def test_user_cache_dir_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("FLEXGEAR_CACHE_DIR", str(tmp_path / "mine"))
    assert user_cache_dir() == tmp_path / "mine"
    monkeypatch.delenv("FLEXGEAR_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    if os.name == "posix" and os.uname().sysname == "Linux":
        assert user_cache_dir() == tmp_path / "xdg" / "flexgear"
        monkeypatch.delenv("XDG_CACHE_HOME")
        assert user_cache_dir() == Path.home() / ".cache" / "flexgear"


def test_meshes_are_cached_per_user_not_in_the_current_directory(monkeypatch, tmp_path):
    from flexgear.config import load_config
    from flexgear.fe.meshing import MeshSettings, mesh_cache_dir, mesh_gear

    cache = tmp_path / "cache"
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.setenv("FLEXGEAR_CACHE_DIR", str(cache))
    monkeypatch.chdir(work)
    sun = load_config("mercury_1a").gears["sun"]
    gm = mesh_gear(sun, MeshSettings(level=0))
    assert mesh_cache_dir() == cache / "meshes"
    # the entry and its inter-process lock (files.entry_lock)
    assert sorted(p.suffix for p in (cache / "meshes").iterdir()) == [".json", ".lock", ".vtu"]
    assert list(work.iterdir()) == []  # nothing relative to where the user stands
    assert mesh_gear(sun, MeshSettings(level=0)).info.get("source") == "cache"
    assert gm.n_elements > 0


def test_output_directory_removes_only_what_it_created_and_left_empty(tmp_path):
    with pytest.raises(RuntimeError):
        with output_directory(tmp_path / "a" / "b" / "c"):
            raise RuntimeError("failed before writing")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "a").mkdir()
    with pytest.raises(RuntimeError):
        with output_directory(tmp_path / "a" / "b") as out:
            (out / "complete.txt").write_text("a complete file")
            raise RuntimeError("failed after writing one file")
    assert (tmp_path / "a" / "b" / "complete.txt").exists()  # complete files are kept
    (tmp_path / "f").write_text("mine")
    with pytest.raises(ResultExistsError, match="exists and is not a directory"):
        with output_directory(tmp_path / "f" / "sub"):
            pass
    assert (tmp_path / "f").read_text() == "mine"


def test_discard_files_removes_what_exists_and_ignores_the_rest(tmp_path):
    from flexgear.files import discard_files

    a, b = tmp_path / "a.json", tmp_path / "b.npz"
    a.write_text("{}")
    discard_files(a, b)  # b never existed
    assert not a.exists() and not b.exists()
