"""Several gear reductions at once, in worker processes that fill the reduction cache.

The reductions of different gears are independent, and one gear's is mostly SuperLU solves and
ARPACK's Lanczos iteration, which hold the GIL: threads would not overlap them, processes do.
:func:`reduce_in_workers` gives the gears that the cache lacks to up to :func:`reduction_workers`
fresh interpreters (``python -m flexgear.reduction.parallel``; a fresh interpreter re-runs none
of the caller's script, unlike multiprocessing's spawn, and inherits none of its threads, unlike
fork). Each worker runs :func:`~flexgear.reduction.gear.reduce_gear` on its gears, one after the
other, and writes them to the cache; the caller then loads every gear from the cache as usual,
so the results are those of a reduction in the caller's process, bit for bit (a reduction runs
its BLAS on one thread, :func:`~flexgear.fe.elasticity.single_threaded_blas`). The workers'
progress messages are passed on to the caller's ``progress`` as they come.

Assignment: longest first to the least loaded worker, by an estimated cost (the square of the
body's area in module squares: the dofs and the modes below a cutoff both grow with the area).
MERCURY 1-A on 2 cores: the ring (100,884 dofs, 163 modes) on one worker, sun and planet on the
other.

``FLEXGEAR_REDUCTION_WORKERS`` sets the number of workers (default: the CPU count; 1 reduces
in the caller's process, as does a run without a cache directory).
"""
from __future__ import annotations

import base64
import math
import os
import pickle
import subprocess
import sys
import threading
from pathlib import Path

from ..errors import ConfigError
from .gear import reduce_gear, reduction_cached

WORKERS_ENV = "FLEXGEAR_REDUCTION_WORKERS"


def reduction_workers() -> int:
    """Number of worker processes for gear reductions: ``$FLEXGEAR_REDUCTION_WORKERS``, else the
    CPU count [-].

    Raises
    ------
    ConfigError
        The variable is not an integer >= 1.
    """
    env = os.environ.get(WORKERS_ENV)
    if env is None or env.strip() == "":
        return max(1, os.cpu_count() or 1)
    try:
        n = int(env)
    except ValueError:
        n = 0
    if n < 1:
        raise ConfigError(f"{WORKERS_ENV} = {env!r}: must be an integer >= 1 (1: reduce in this process)")
    return n


def cost_estimate(gear) -> float:
    """Relative cost of reducing ``gear``: (body area / module^2)^2 [-]."""
    if gear.internal:  # from the tip circle (inside) to the rim
        area = math.pi * max((0.5 * gear.rim_diameter) ** 2 - gear.ra ** 2, 0.0)
    else:  # from the bore to the tip circle
        area = math.pi * max(gear.ra ** 2 - (0.5 * gear.bore_diameter) ** 2, 0.0)
    return (area / gear.module ** 2) ** 2


def assign(costs: dict, workers: int) -> list[list]:
    """Names grouped per worker: longest first to the least loaded worker."""
    groups = [[] for _ in range(workers)]
    load = [0.0] * workers
    for name in sorted(costs, key=lambda n: -costs[n]):
        i = min(range(workers), key=lambda k: load[k])
        groups[i].append(name)
        load[i] += costs[name]
    return [g for g in groups if g]


def _child_env(workers: int) -> dict:
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parents[2])  # the flexgear this process runs
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    # a reduction runs its BLAS on one thread (single_threaded_blas): a larger pool would only spin
    for var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env.setdefault(var, "1")
    env.setdefault("OMP_NUM_THREADS", str(max(1, (os.cpu_count() or 1) // workers)))
    return env


def _read(proc, say, lock, failures: dict) -> None:
    """Pass a worker's messages on as they come (one at a time), collect its failures."""
    for line in proc.stdout:
        line = line.rstrip("\n")
        if line.startswith("P "):
            with lock:
                say(line[2:])
        elif line.startswith("E "):
            name, data = line[2:].split(" ", 1)
            failures[name] = pickle.loads(base64.b64decode(data))


class Workers:
    """Worker processes reducing gears into the cache (:func:`start_workers`). Their progress
    messages go to ``progress`` as they come, from a reader thread per worker (one call at a
    time); :meth:`wait` waits for them and returns their failures, :meth:`close` stops them."""

    def __init__(self, groups: list, jobs: dict, cache_dir, progress=None):
        self.groups = groups
        self.procs, self.readers = [], []
        self.failures: dict = {}
        say = progress or (lambda s: None)
        lock = threading.Lock()
        env = _child_env(len(groups))
        try:
            for group in groups:
                p = subprocess.Popen([sys.executable, "-m", "flexgear.reduction.parallel"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, env=env, text=True)
                self.procs.append(p)
                p.stdin.write(base64.b64encode(pickle.dumps(([(n, jobs[n]) for n in group], str(cache_dir))))
                              .decode() + "\n")
                p.stdin.close()
                t = threading.Thread(target=_read, args=(p, say, lock, self.failures), daemon=True)
                t.start()
                self.readers.append(t)
        except BaseException:
            self.close()
            raise

    def wait(self) -> dict:
        """Wait for every worker.

        Returns
        -------
        dict
            Gear name -> exception raised by its reduction (the caller raises it as its own).
        """
        try:
            for t in self.readers:
                t.join()
            for p in self.procs:
                p.wait()
        finally:
            self.close()
        return dict(self.failures)

    def close(self) -> None:
        """Stop the workers still running (their unfinished gears are not cached)."""
        for p in self.procs:
            if p.poll() is None:
                p.kill()
                p.wait()


def start_workers(jobs: dict, cache_dir, progress=None, workers: int | None = None) -> Workers | None:
    """Start reducing the gears of ``jobs`` that the cache lacks in worker processes.

    Parameters
    ----------
    jobs : dict
        Gear name -> keyword arguments of :func:`~flexgear.reduction.gear.reduce_gear`
        (``gear`` included, ``cache_dir`` and ``progress`` excluded).
    cache_dir : path
        Reduction cache (None: nothing is started).
    progress : callable, optional
        ``progress(str)``: told which worker reduces which gears.
    workers : int, optional
        Default :func:`reduction_workers`.

    Returns
    -------
    Workers or None
        None when fewer than two gears are to be computed or one worker is asked for (the caller
        reduces them itself).
    """
    if cache_dir is None:
        return None
    workers = reduction_workers() if workers is None else int(workers)
    if workers < 2:
        return None
    pending = [n for n, kw in jobs.items() if not reduction_cached(**kw, cache_dir=cache_dir)]
    workers = min(workers, len(pending))
    if workers < 2:
        return None
    groups = assign({n: cost_estimate(jobs[n]["gear"]) for n in pending}, workers)
    if progress is not None:
        progress(f"reducing {', '.join(pending)} in {len(groups)} worker processes: "
                 + "; ".join(" then ".join(g) for g in groups))
    try:
        return Workers(groups, jobs, cache_dir, progress)
    except OSError as exc:  # no interpreter to start (embedded Python, process limits): reduce here
        if progress is not None:
            progress(f"worker processes could not start ({exc}); reducing in this process")
        return None


def reduce_in_workers(jobs: dict, cache_dir, progress=None, workers: int | None = None) -> dict:
    """:func:`start_workers` and :meth:`Workers.wait`: the gears that the cache lacks, reduced in
    worker processes into the cache; returns gear name -> exception of the failed ones."""
    w = start_workers(jobs, cache_dir, progress, workers)
    return {} if w is None else w.wait()


def _worker() -> int:
    """Worker process: reduce the gears read from stdin into the cache; messages on stdout."""
    proto = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)  # anything else printed goes to stderr
    sys.stdout = sys.stderr
    group, cache_dir = pickle.loads(base64.b64decode(sys.stdin.readline()))

    def say(msg):
        proto.write("P " + str(msg).replace("\n", " ") + "\n")

    for name, kw in group:
        try:
            reduce_gear(**kw, cache_dir=cache_dir, progress=say)
        except Exception as exc:  # noqa: BLE001 - handed to the caller, which raises it
            try:
                data = pickle.dumps(exc)
            except Exception:  # noqa: BLE001 - an exception that does not pickle
                data = pickle.dumps(RuntimeError(f"{type(exc).__name__}: {exc}"))
            proto.write(f"E {name} {base64.b64encode(data).decode()}\n")
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(_worker())
