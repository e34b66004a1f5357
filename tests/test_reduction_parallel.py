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
        for x, y in ((a.body.K, b.body.K), (a.body.M, b.body.M), (a.body.basis, b.body.basis), (a.modal, b.modal),
                     (a.tables.coupling, b.tables.coupling)):
            assert np.array_equal(x, y)  # the same computation, BLAS on one thread in both (single_threaded_blas)
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


def test_a_reduction_has_the_same_bits_with_any_blas_thread_count():
    """MERCURY 1-A's ring at mesh level 0 (cutoff 100 kHz, 33 table radii) reduced with two BLAS
    threads allowed and with one: the same bits (a threaded BLAS splits its sums by the thread
    count; a reduction runs its BLAS on one thread, single_threaded_blas), so a gear reduced on
    a machine with other cores, or in a worker given fewer threads, gives the same runs. Without
    single_threaded_blas around the reduction the two differ."""
    from threadpoolctl import threadpool_limits

    from flexgear.config import load_config
    from flexgear.dynamics.flexible.reductions import reduction_jobs

    cfg = load_config("mercury_1a_flexible")
    cfg.flexible["level"] = 0
    job = dict(reduction_jobs(cfg)[0]["ring"], cutoff=100e3, n_points=33)  # 100 kHz: above the first mode
    reds = []
    for threads in (2, 1):
        with threadpool_limits(limits=threads, user_api="blas"):
            reds.append(reduce_gear(**job, cache_dir=None))
    a, b = reds
    for x, y in ((a.body.basis, b.body.basis), (a.modal, b.modal), (a.tables.coupling, b.tables.coupling),
                 *((a.tables.self_residual[s], b.tables.self_residual[s]) for s in a.tables.self_residual)):
        assert np.array_equal(x, y)
