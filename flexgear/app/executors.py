"""Where the cases of a batch run: in this process, in local worker processes, or on Dask.

Every executor has the same three steps: ``connect`` (reach the workers; errors here come
before anything is written), ``start`` (warm the workers up: load or compile the solver
once) and ``run`` (yield ``(task, outcome)`` as cases finish, in any order), then
``close``. The case function catches its own exceptions and returns a record, so an
outcome is that record, or a :class:`WorkerLost` when the process running the case died
(killed, out of memory, crashed).

- :class:`SerialExecutor`: one case after the other in the calling process (``--workers 1``).
- :class:`ProcessExecutor`: a pool of local processes, one per core by default. On Linux the
  workers are forked from the driver after it has loaded the compiled solver, so they start at
  once and share it; elsewhere they are spawned and load numba's on-disk cache. Each worker
  runs the solver single-threaded (the cores are the workers'), and a driver that has run the
  solver's parallel loops (:func:`flexgear.dynamics.threads.parallel_used`) spawns its workers
  instead: GNU OpenMP's threads do not survive a fork. A worker dies
  with the driver (``PR_SET_PDEATHSIG``, and a watchdog thread polling the parent). When a
  worker dies, the cases it may have been running are run again one at a time; the one that
  kills its worker again is reported lost and the others go on.
- :class:`DaskExecutor`: a ``dask.distributed`` cluster, at a scheduler address or a local
  cluster of N single-threaded worker processes.
"""
from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import multiprocessing
import os
import signal
import sys
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass

from ..errors import FlexgearError

CONNECT_TIMEOUT = 10.0  # s to reach a Dask scheduler
#: s a local Dask worker gets to stop after Ctrl-C before it is killed (a case in the compiled
#: solver does not stop on request; distributed's own wait is 4 s)
DASK_STOP_S = 0.5
POLL_S = 0.1  # s between two looks for a Ctrl-C while local workers run


class CtrlC:
    """Ctrl-C while a batch runs its cases. Python raises KeyboardInterrupt wherever the main
    thread is, also inside a weakref callback or a ``__del__``, which print it and go on: an
    interrupt lost there let the batch run to its end. This handler raises as Python's does and
    remembers the interrupt, and :meth:`check` raises it again where the executors look for it
    (every ``POLL_S`` seconds while waiting for local workers, after every case); such a
    swallowed interrupt is not printed (``sys.unraisablehook``). Inside :meth:`deferred` it is
    only remembered. A handler the caller installed is left alone, as is a thread other than the
    main one."""

    def __init__(self):
        self.pressed = False
        self._previous = None
        self._hook = None
        self._deferred = 0

    def __enter__(self):
        if (threading.current_thread() is threading.main_thread()
                and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
            self._previous = signal.signal(signal.SIGINT, self._handler)
            self._hook, sys.unraisablehook = sys.unraisablehook, self._unraisable
        return self

    def _handler(self, signum, frame):
        self.pressed = True
        if not self._deferred:
            raise KeyboardInterrupt

    def _unraisable(self, unraisable):
        if not (self.pressed and isinstance(unraisable.exc_value, KeyboardInterrupt)):
            self._hook(unraisable)  # anything but the interrupt remembered here

    @contextlib.contextmanager
    def deferred(self):
        """Ctrl-C meanwhile is remembered, not raised (:meth:`check` raises it afterwards): for
        writing a case's files and the summaries, which an interrupt inside leaves half done
        (xarray's netCDF writer then keeps its lock, and the next write waits for it forever)."""
        self._deferred += 1
        try:
            yield
        finally:
            self._deferred -= 1

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed since this guard was entered."""
        if self.pressed:
            raise KeyboardInterrupt

    def __exit__(self, *exc):
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            sys.unraisablehook = self._hook
            self._previous = self._hook = None
        return False


NO_CTRL_C = CtrlC()  # never entered: its check never raises


@dataclass
class WorkerLost:
    """Outcome of a case whose worker process died while running it."""

    message: str


# --------------------------------------------------------------------------- serial

class SerialExecutor:
    """Run the cases one after the other in this process."""

    name = "serial (this process)"
    workers = 1
    shares_files = True

    def connect(self):
        pass

    def start(self, warm_up=None):
        pass  # the first case loads the solver

    def run(self, fn, tasks, ctrl_c=NO_CTRL_C):
        for t in tasks:
            out = fn(t)
            ctrl_c.check()
            yield t, out

    def close(self):
        pass


# --------------------------------------------------------------------------- local processes

def _die_with_parent(parent_pid: int) -> None:
    """In a worker: exit when the driver exits, even when it is killed (SIGKILL)."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent_pid:  # the parent died before we got here
        os._exit(1)

    def watch():
        while True:
            time.sleep(1.0)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, name="flexgear-parent-watch", daemon=True).start()


def _init_worker(parent_pid: int, close_fds=()) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the driver's to handle
    for fd in close_fds:  # e.g. the batch directory's lock, which the driver alone holds
        try:
            os.close(fd)
        except OSError:
            pass
    _die_with_parent(parent_pid)
    from ..dynamics.threads import single_threaded

    single_threaded()  # one thread per worker: the pool has the cores


def start_method() -> str:
    """``fork`` on Linux (workers inherit the driver's loaded solver), else ``spawn``; ``spawn``
    too once this process has run the solver's parallel loops (GNU OpenMP, numba's threading
    layer, hangs in a child forked after a parallel region: :mod:`flexgear.dynamics.threads`;
    not ``forkserver``, whose workers are the server's children, not the driver's, which
    :func:`_die_with_parent` watches)."""
    from ..dynamics.threads import parallel_used

    if sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods() \
            and not parallel_used():
        return "fork"
    return "spawn"


class ProcessExecutor:
    """A pool of ``workers`` local processes (default: one per core)."""

    shares_files = True

    def __init__(self, workers: int | None = None):
        self.workers = workers or os.cpu_count() or 1
        self.method = start_method()
        self.close_in_workers = ()  # descriptors a forked worker closes at once
        self._pool = None

    @property
    def name(self) -> str:
        return f"{self.workers} local processes ({self.method})"

    def connect(self):
        pass

    def start(self, warm_up=None):
        """Warm the driver up (load or compile the solver) before the workers are made, so that
        forked workers inherit it and spawned ones find numba's cache on disk; single-threaded,
        so that the driver runs no parallel region and may still fork."""
        if warm_up is not None:
            from ..dynamics.threads import kernel_threads

            with kernel_threads(1):
                warm_up()

    def _new_pool(self, n):
        self.method = start_method()  # the driver may have run parallel loops since (then no fork)
        return ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context(self.method),
                                   initializer=_init_worker,
                                   initargs=(os.getpid(), self.close_in_workers if self.method == "fork" else ()))

    def run(self, fn, tasks, ctrl_c=NO_CTRL_C):
        queue = collections.deque(tasks)
        suspects = collections.deque()  # tasks in flight when a worker died: rerun alone
        inflight = {}
        try:
            while queue or suspects or inflight:
                if self._pool is None:
                    self._pool = self._new_pool(self.workers)
                if suspects:
                    if not inflight:
                        t = suspects.popleft()
                        inflight[self._pool.submit(fn, t)] = (t, True)
                else:
                    while queue and len(inflight) < self.workers:
                        t = queue.popleft()
                        inflight[self._pool.submit(fn, t)] = (t, False)
                done = ()
                while not done:
                    ctrl_c.check()
                    done, _ = wait(inflight, timeout=POLL_S, return_when=FIRST_COMPLETED)
                broken = []
                for f in done:
                    t, alone = inflight.pop(f)
                    try:
                        out = f.result()
                    except BrokenProcessPool:
                        broken.append((t, alone))
                        continue
                    yield t, out
                if not broken:
                    continue
                wait(inflight)  # every future of a broken pool completes at once
                for f, (t, alone) in list(inflight.items()):
                    try:
                        out = f.result()
                    except BrokenProcessPool:
                        broken.append((t, alone))
                    else:
                        yield t, out
                inflight.clear()
                self._kill_pool()
                for t, alone in broken:
                    if alone:
                        yield t, WorkerLost("the worker process running this case died (killed, out of memory "
                                            "or crashed), also when run alone")
                    else:
                        suspects.append(t)
        finally:
            if inflight:
                self._kill_pool()

    def _kill_pool(self):
        pool, self._pool = self._pool, None
        if pool is None:
            return
        procs = list((getattr(pool, "_processes", None) or {}).values())
        for p in procs:
            if p.is_alive():
                p.kill()
        for p in procs:  # dead before anyone cleans up after them (SIGKILL: a few ms)
            p.join(timeout=2.0)
        pool.shutdown(wait=False, cancel_futures=True)

    def close(self):
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None


# --------------------------------------------------------------------------- Dask

class DaskExecutor:
    """Cases as tasks on a ``dask.distributed`` cluster.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``).
    local_workers : int, optional
        Start a ``LocalCluster`` of this many single-threaded worker processes instead.
    processes : bool
        Local cluster only: worker processes (default) or threads in this process.
    """

    def __init__(self, scheduler: str | None = None, local_workers: int | None = None, processes: bool = True):
        if (scheduler is None) == (local_workers is None):
            raise FlexgearError("Dask: give a scheduler address or a number of local workers, not both")
        self.scheduler = scheduler
        self.local_workers = local_workers
        self.processes = processes
        self.client = None
        self.cluster = None
        self.workers = 0
        self._abandoned = False  # Ctrl-C left cases or the warm-up running on the workers
        self.shares_files = local_workers is not None
        self.name = (f"Dask scheduler {scheduler}" if scheduler else
                     f"Dask LocalCluster of {local_workers} {'processes' if processes else 'threads'}")

    def connect(self):
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise FlexgearError("Dask executors need dask.distributed: pip install 'flexgear[dask]' "
                                "(or pip install 'dask[distributed]')") from None
        if self.scheduler is not None:
            _check_scheduler_address(self.scheduler)  # a Client built from a bad one hung 20 s in its __del__
            try:
                self.client = Client(self.scheduler, timeout=CONNECT_TIMEOUT, set_as_default=False)
            except Exception as exc:  # OSError, TimeoutError, ValueError for a malformed address
                raise FlexgearError(f"--scheduler {self.scheduler}: cannot reach the Dask scheduler "
                                    f"({type(exc).__name__}: {exc}); start one (`dask scheduler`) or check "
                                    "the address") from None
        else:
            if isinstance(self.local_workers, bool) or not isinstance(self.local_workers, int) \
                    or self.local_workers < 1:
                raise FlexgearError(f"--dask-local {self.local_workers!r}: must be an integer >= 1")
            with _sigint_ignored():  # the worker processes inherit it: Ctrl-C is the driver's to handle
                self.cluster = LocalCluster(n_workers=self.local_workers, threads_per_worker=1,
                                            processes=self.processes, dashboard_address=None,
                                            # flexgear reports a failed case and a lost worker itself; a worker's
                                            # heartbeat to the scheduler the batch has stopped logs an ERROR
                                            silence_logs=logging.CRITICAL)
            self.client = Client(self.cluster, set_as_default=False)
        info = self.client.scheduler_info()
        self.workers = sum(w.get("nthreads", 1) for w in info.get("workers", {}).values())
        if self.workers == 0:
            self.close()
            raise FlexgearError(f"{self.name}: the cluster has no workers")

    def check_shared_directory(self, directory) -> None:
        """Whether every worker sees ``directory`` (then they write results there themselves;
        otherwise they send them back to the driver)."""
        probe = os.path.join(os.path.abspath(directory), f".probe-{os.getpid()}")
        with open(probe, "w"):
            pass
        try:
            seen = self.client.run(os.path.exists, probe)
            self.shares_files = bool(seen) and all(seen.values())
        finally:
            os.unlink(probe)

    def start(self, warm_up=None):
        """Load the solver on every worker (in parallel)."""
        if warm_up is not None:
            try:
                self.client.run(warm_up)
            except BaseException:  # Ctrl-C: the workers are still warming up
                self._abandon()
                raise

    def run(self, fn, tasks, ctrl_c=NO_CTRL_C):
        from distributed import as_completed

        futures = {}
        for t in tasks:
            futures[self.client.submit(fn, t, pure=False)] = t
        try:
            for f in as_completed(list(futures), loop=self.client.loop):
                t = futures.pop(f)
                try:
                    out = f.result()
                except Exception as exc:  # KilledWorker, CancelledError, lost connection
                    out = WorkerLost(f"the Dask worker running this case failed ({type(exc).__name__}: {exc})")
                f.release()
                ctrl_c.check()
                yield t, out
        finally:
            if futures:  # Ctrl-C: a local cluster's processes are stopped, other workers told to drop the cases
                if not self._abandon():
                    self.client.cancel(list(futures))

    def _abandon(self) -> bool:
        """After Ctrl-C: stop a local cluster's worker processes now (killed after
        :data:`DASK_STOP_S`), with distributed's log of it muted; False where there are none (a
        scheduler's workers, threads)."""
        self._abandoned = True
        if self.cluster is None or not self.processes:
            return False
        with _logger_muted("distributed"), contextlib.suppress(Exception):
            self.cluster.sync(_stop_workers, list(self.cluster.workers.values()), DASK_STOP_S)
        return True

    def close(self):
        """Disconnect; a local cluster is shut down (a Ctrl-C meanwhile would leave its
        processes and semaphores behind: it is ignored for the second this takes). After Ctrl-C
        (:meth:`_abandon`) distributed's log of the teardown is not shown: it only reports the
        workers it was told to stop."""
        quiet = self._abandoned and self.cluster is not None  # its workers stopped by _abandon
        with _sigint_ignored(), _logger_muted("distributed") if quiet else contextlib.nullcontext():
            if self.client is not None:
                self.client.close()
                self.client = None
            if self.cluster is not None:
                self.cluster.close()
                self.cluster = None


def _check_scheduler_address(address) -> None:
    """A Dask scheduler address ``[scheme://]host:port`` (port 1-65535 for tcp and tls), else a
    FlexgearError naming it, before any connection is tried."""
    from distributed.comm.addressing import parse_address, parse_host_port

    rule = "must be [tcp://]HOST:PORT, e.g. tcp://127.0.0.1:8786 (dask scheduler prints it)"
    try:
        scheme, loc = parse_address(str(address))
        if scheme in ("tcp", "tls"):
            host, port = parse_host_port(loc)
            if not host or not 0 < int(port) < 65536:
                raise ValueError(f"port {port} out of range 1-65535" if host else "no host")
    except (ValueError, TypeError) as exc:
        raise FlexgearError(f"--scheduler {address!r}: {exc}; {rule}") from None


@contextlib.contextmanager
def _sigint_ignored():
    """SIGINT ignored in this process meanwhile (main thread only; elsewhere nothing changes).
    A process started meanwhile inherits the ignored signal and Python keeps it ignored, so a
    terminal's Ctrl-C, sent to every process of the job, reaches the driver alone, which stops
    the workers (the local pool's do the same, :func:`_init_worker`); a Ctrl-C pressed meanwhile
    is lost."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def _logger_muted(name: str):
    """Logger ``name`` shows nothing meanwhile."""
    log = logging.getLogger(name)
    level = log.level
    log.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        log.setLevel(level)


async def _stop_workers(nannies, timeout: float) -> None:
    """Close local Dask workers (their nannies), killing each process still running after
    0.8 ``timeout`` s."""
    await asyncio.gather(*(n.close(timeout=timeout, reason="flexgear batch interrupted") for n in nannies),
                         return_exceptions=True)
