"""Threads of the force evaluation (:mod:`flexgear.dynamics.threads`): the compliant meshes'
contact searches and the flexible bodies' flank rows in parallel loops give bit-identical
results; the thread count is checked; a batch still runs (spawned workers,
single-threaded) after the driver ran parallel loops; the OpenMP layer is the one in use."""
import numba
import numpy as np
import pytest

from flexgear.app.batch import run_batch
from flexgear.app.executors import ProcessExecutor
from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.integrator import simulation
from flexgear.dynamics.integrator.simulation import ThreadChoice, simulate
from flexgear.dynamics.threads import check_threads, parallel_used

PARALLEL = numba.config.NUMBA_NUM_THREADS > 1
needs_cores = pytest.mark.skipif(not PARALLEL, reason="numba has one thread on this machine")


@pytest.fixture(scope="module", params=["spur_pair_flexible", "mercury_1a_flexible"])
def flexible(request):
    """The flexible preset; MERCURY 1-A's gears at mesh level 0, whose reductions the modal tests
    share (the parallel loops are the same at every level)."""
    cfg = load_config(request.param)
    if request.param.startswith("mercury"):
        cfg.flexible["level"] = 0
    return build_model(cfg), cfg.simulation["step"]


def _records_equal(a, b):
    for name, x in a.records._asdict().items():
        assert np.array_equal(np.asarray(x), np.asarray(getattr(b.records, name))), name
    assert np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v)
    assert (a.steps, a.newton, a.rejected, a.linearised) == (b.steps, b.newton, b.rejected, b.linearised)


@needs_cores
def test_parallel_force_evaluation_is_bit_identical(flexible, monkeypatch):
    """0.002 s (320 steps): every record, the final state and the counters equal with one
    thread and two, in one chunk, and in chunks of 64 steps with the automatic choice between
    them (:class:`ThreadChoice`: 2, 1, then the faster, rechecked). (The chunk
    length itself changes the results in the last digits: compared at equal chunks.)"""
    model, h = flexible
    serial = simulate(model, 0.002, h, 8, threads=1)
    parallel = simulate(model, 0.002, h, 8, threads=2)
    assert parallel_used()
    assert numba.threading_layer() == "omp"
    _records_equal(serial, parallel)
    monkeypatch.setattr(simulation, "SpareCores", lambda: (lambda: 2.0))  # an idle machine: both timed
    _records_equal(simulate(model, 0.002, h, 8, threads=1, chunk_steps=64),
                   simulate(model, 0.002, h, 8, threads="auto", chunk_steps=64))


@needs_cores
def test_thread_choice_probes_both_then_keeps_the_faster():
    def choices(spare, serial_faster, chunks=45):
        pick = ThreadChoice(2, spare=lambda: spare)
        seen = []
        for _ in range(chunks):
            n = pick.next()
            seen.append(n)
            pick.timed(n, 1.0 if (n == 1) == serial_faster else 2.0)
        return seen

    seen = choices(2.0, serial_faster=True)
    assert seen[:2] == [2, 1]
    assert [i for i, n in enumerate(seen) if n == 2] == [0, 21, 41]  # rechecked every 20 chunks
    seen = choices(2.0, serial_faster=False)
    assert [i for i, n in enumerate(seen) if n == 1] == [1, 21, 41]
    assert set(choices(1.4, serial_faster=False)) == {1}  # no idle core for the second thread
    assert [ThreadChoice(1).next(), ThreadChoice(2, fixed=True, spare=lambda: 0.0).next()] == [1, 2]


@pytest.mark.parametrize("bad", [0, -2, 1.5, "2", True])
def test_thread_count_must_be_a_positive_integer(bad):
    with pytest.raises(ValueError, match="threads"):
        check_threads(bad)
    model = build_model(load_config("spur_pair"))
    with pytest.raises(ValueError, match="threads"):
        simulate(model, 1e-4, 2.5e-5, 1, threads=bad)


def _worker_threads(_):
    from threadpoolctl import threadpool_info

    blas = {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}
    return numba.get_num_threads(), blas


@needs_cores
def test_batch_after_parallel_loops_in_the_driver(tmp_path, monkeypatch):
    """After parallel regions in this process the pool spawns its workers (GNU OpenMP hangs in
    a forked child's parallel region), single-threaded: the kernels and BLAS, which their
    environment gives two threads; a batch runs to the end."""
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    cfg = load_config("spur_pair_flexible")
    model, h = build_model(cfg), cfg.simulation["step"]
    simulate(model, 5 * h, h, 1, threads=2)
    assert parallel_used()
    ex = ProcessExecutor(2)
    ex.start()
    try:
        assert [n for _, n in ex.run(_worker_threads, [0, 1])] == [(1, {1})] * 2
    finally:
        ex.close()
    assert ex.method == "spawn"
    p = tmp_path / "sweep.toml"
    p.write_text('base = "spur_pair"\n[set]\n"simulation.duration" = 0.01\n"simulation.run_in" = 0.0\n'
                 '[zip]\n"load.torque" = [150.0, 250.0]\n')
    r = run_batch(p, tmp_path / "out", workers=2, progress=False, log=lambda msg: None)
    assert (r.done, r.failed) == (2, 0)
