"""Gear reductions in worker processes, and the cache's basis read on first use (issue 8 part 8)."""
import numpy as np
import pytest

from flexgear.errors import ConfigError
from flexgear.fe.meshing import MeshSettings
from flexgear.gears.geometry import SpurGear
from flexgear.gears.material import Material
from flexgear.reduction.body import LazyBasisBody
from flexgear.reduction.gear import basis_path, reduce_gear, reduction_cached
from flexgear.reduction.parallel import WORKERS_ENV, assign, cost_estimate, reduce_in_workers, reduction_workers

STEEL = Material(E=2.1e11, nu=0.3, rho=7850.0)
SETTINGS = MeshSettings(level=0, order=1)


@pytest.fixture(scope="module")
def gears():
    return {"pinion": SpurGear(z=17, module=2e-3, bore_diameter=0.012, face_width=0.01, name="pinion"),
            "wheel": SpurGear(z=23, module=2e-3, bore_diameter=0.016, face_width=0.01, name="wheel")}


def jobs_of(gears, **kw):
    return {n: dict(gear=g, material=STEEL, settings=SETTINGS, cutoff=150e3, n_points=7, **kw)
            for n, g in gears.items()}


def test_workers_give_the_reduction_of_this_process(gears, tmp_path):
    jobs = jobs_of(gears)
    ref = {n: reduce_gear(**kw, cache_dir=None) for n, kw in jobs.items()}
    messages = []
    assert reduce_in_workers(jobs, tmp_path, messages.append, workers=2) == {}
    assert any("2 worker processes" in m for m in messages)
    for n in gears:  # the workers' own progress messages came through
        assert any(m.startswith(f"{n}: Craig-Bampton reduction") for m in messages)
        assert reduction_cached(**jobs[n], cache_dir=tmp_path)
    for n, kw in jobs.items():
        red = reduce_gear(**kw, cache_dir=tmp_path)
        assert red.info["source"] == "cache"
        a, b = ref[n], red
        assert np.array_equal(a.body.frequencies, b.body.frequencies)
        scale = np.abs(a.body.basis).max()
        for x, y, s in ((a.body.K, b.body.K, np.abs(a.body.K).max()), (a.body.M, b.body.M, 1.0),
                        (a.body.basis, b.body.basis, scale), (a.modal, b.modal, np.abs(a.modal).max()),
                        (a.tables.coupling, b.tables.coupling, np.abs(a.tables.coupling).max())):
            assert np.abs(x - y).max() <= 1e-12 * s  # the same computation, BLAS round-off at most
    # all cached: nothing to start
    messages.clear()
    assert reduce_in_workers(jobs, tmp_path, messages.append, workers=2) == {} and messages == []


def test_a_worker_failure_comes_back_as_the_exception(gears, tmp_path):
    jobs = jobs_of(gears)
    jobs["wheel"]["cutoff"] = 1e3  # below the first clamped mode
    failed = reduce_in_workers(jobs, tmp_path, workers=2)
    assert set(failed) == {"wheel"}
    assert isinstance(failed["wheel"], ConfigError) and "below the first fixed-interface mode" in str(failed["wheel"])
    assert reduction_cached(**jobs["pinion"], cache_dir=tmp_path)
    assert not reduction_cached(**jobs["wheel"], cache_dir=tmp_path)


def test_assignment_and_worker_count(gears, monkeypatch):
    assert assign({"ring": 10.0, "sun": 3.0, "planet": 2.0}, 2) == [["ring"], ["sun", "planet"]]
    assert assign({"a": 1.0, "b": 1.0}, 3) == [["a"], ["b"]]
    ring = SpurGear(z=66, module=2e-3, internal=True, rim_diameter=0.16, face_width=0.01, name="ring")
    assert cost_estimate(ring) > cost_estimate(gears["wheel"]) > cost_estimate(gears["pinion"])
    monkeypatch.setenv(WORKERS_ENV, "3")
    assert reduction_workers() == 3
    for bad in ("0", "two"):
        monkeypatch.setenv(WORKERS_ENV, bad)
        with pytest.raises(ConfigError, match=WORKERS_ENV):
            reduction_workers()
    monkeypatch.delenv(WORKERS_ENV)
    assert reduction_workers() >= 1


def test_cached_basis_is_read_on_first_use_and_checked(gears, tmp_path):
    g = gears["pinion"]
    kw = dict(material=STEEL, settings=SETTINGS, cutoff=150e3, n_points=7, cache_dir=tmp_path)
    a = reduce_gear(g, **kw)
    b = reduce_gear(g, **kw)
    assert isinstance(b.body, LazyBasisBody) and callable(b.body.__dict__["_basis"])
    assert np.array_equal(b.body.basis, a.body.basis)
    assert np.array_equal(b.body.residual.modes, a.body.basis[:, a.body.n_interface:])
    # a basis changed on disk (same size): refused when read, the entry removed, rebuilt next time
    c = reduce_gear(g, **kw)
    path = basis_path(tmp_path, c.key)
    data = bytearray(path.read_bytes())
    data[-8:] = bytes(8)
    path.write_bytes(bytes(data))
    with pytest.raises(ConfigError, match="corrupt"):
        c.body.basis  # noqa: B018
    assert not path.exists() and not reduction_cached(g, **kw)
    assert reduce_gear(g, **kw).info["source"] == "computed"
    # a truncated basis is found when the entry is loaded
    path.write_bytes(path.read_bytes()[:-100])
    assert reduce_gear(g, **kw).info["source"] == "computed"
