"""Threads of the compiled force evaluation: numba's threading layer and the thread count.

:func:`~flexgear.dynamics.flexible.compliant.compliant_contacts` runs its per-mesh searches and
per-body flank rows and compliance parts in ``prange`` loops when the workspace asks for more
than one thread (``ContactBuffers.threads``); every sum is still formed in one thread in serial
order, so results are bit-identical whatever the count.

The threading layer is OpenMP where numba has it (a parallel loop launches in about 1 us;
numba's "workqueue" fallback costs about 100 us, more than the loops save); a user's
``NUMBA_THREADING_LAYER`` is kept. Idle OpenMP threads spin :data:`SPIN_COUNT` times before they
sleep (``GOMP_SPINCOUNT``, unless the user set it or ``OMP_WAIT_POLICY``): a short spin makes the
threads wait for wake-ups, libgomp's default gains nothing. On a loaded machine the long spin
can make a parallel loop wait a time slice, hence serial runs by default and
:class:`~flexgear.dynamics.integrator.simulation.ThreadChoice`'s load check.

GNU OpenMP is not fork-safe (a process forked after a parallel region hangs in its own first
one): :func:`parallel_used` tells whether this process has run one, and the batch executor then
spawns its workers instead of forking them (:func:`~flexgear.app.executors.start_method`).
"""
from __future__ import annotations

import contextlib
import operator
import os
import time

import numba
from threadpoolctl import threadpool_limits

_PARALLEL_USED = False

#: GNU OpenMP's spin count before an idle thread sleeps (see the module's docstring)
SPIN_COUNT = 300000


def use_openmp() -> str:
    """Select numba's OpenMP threading layer if it loads and the user chose none; returns the
    configured layer name (numba's ``config.THREADING_LAYER``). Called once when
    :mod:`flexgear.dynamics` is imported, before any parallel loop runs."""
    if os.environ.get("NUMBA_THREADING_LAYER"):
        return numba.config.THREADING_LAYER
    if not (os.environ.get("OMP_WAIT_POLICY") or os.environ.get("GOMP_SPINCOUNT")):
        os.environ["GOMP_SPINCOUNT"] = str(SPIN_COUNT)  # read when libgomp loads (just below)
    try:
        from numba.np.ufunc import omppool  # noqa: F401  (the layer's library loads: libgomp / libomp)
    except ImportError:
        return numba.config.THREADING_LAYER
    numba.config.THREADING_LAYER = "omp"
    return "omp"


def check_threads(threads) -> int | None:
    """``threads`` as given to :func:`~flexgear.dynamics.integrator.simulation.simulate`: None, ``"auto"`` or an
    integer >= 1.

    Raises
    ------
    ValueError
        For anything else (0, a negative or a non-integer number), naming the parameter.
    """
    if threads is None or threads == "auto":
        return threads
    bad = ValueError(f"threads = {threads!r}: must be None (serial), 'auto' or an integer >= 1")
    if isinstance(threads, bool):
        raise bad
    try:
        n = operator.index(threads)
    except TypeError:
        raise bad from None
    if n < 1:
        raise bad
    return n


def available_threads() -> int:
    """Threads numba would use in this thread now (``numba.get_num_threads()``: all cores unless
    set lower, e.g. 1 in a batch worker)."""
    return int(numba.get_num_threads())


#: shortest interval over which :class:`SpareCores` measures the other processes' load [s]
MIN_SAMPLE = 0.02


class SpareCores:
    """Cores the machine's other processes left idle since the last call (a callable): the
    busy time of every core (Linux ``/proc/stat``) less this process's CPU time, per wall
    second, from the core count (over at least :data:`MIN_SAMPLE`; a call sooner: from the
    1-minute load average, less this process). Where ``/proc/stat`` cannot be read: the core
    count."""

    def __init__(self):
        self.cores = os.cpu_count() or 1
        self.last = self._sample()

    @staticmethod
    def _sample():
        try:
            with open("/proc/stat") as f:
                fields = f.readline().split()
            ticks = [int(x) for x in fields[1:]]
            busy = (sum(ticks[:8]) - ticks[3] - ticks[4]) / os.sysconf("SC_CLK_TCK")  # all but idle, iowait
        except (OSError, ValueError, IndexError, AttributeError):
            return None
        return time.perf_counter(), busy, time.process_time()

    def __call__(self) -> float:
        now = self._sample()
        if now is not None and self.last is not None and now[0] - self.last[0] < MIN_SAMPLE:
            try:  # too short to tell: the 1-minute load average less this running process
                return self.cores - max(os.getloadavg()[0] - 1.0, 0.0)
            except OSError:
                return float(self.cores)
        last, self.last = self.last, now
        if now is None or last is None or now[0] - last[0] <= 0.0:
            return float(self.cores)
        others = max((now[1] - last[1]) - (now[2] - last[2]), 0.0) / (now[0] - last[0])
        return self.cores - others


@contextlib.contextmanager
def kernel_threads(n: int):
    """Run the enclosed kernels with n threads (``numba.set_num_threads``), restored after; a
    count above 1 marks this process as having run parallel regions (:func:`parallel_used`)."""
    global _PARALLEL_USED
    n = max(1, min(int(n), int(numba.config.NUMBA_NUM_THREADS)))
    old = numba.get_num_threads()
    if n > 1:
        _PARALLEL_USED = True
    numba.set_num_threads(n)
    try:
        yield n
    finally:
        numba.set_num_threads(old)


def parallel_used() -> bool:
    """Whether this process has run the kernels with more than one thread (then it must not
    fork workers: GNU OpenMP's thread pool does not survive a fork)."""
    return _PARALLEL_USED


def single_threaded() -> None:
    """Make the calling thread's kernels and this process's BLAS single-threaded (a batch worker:
    the cores are the workers'; idle BLAS threads would spin on them)."""
    numba.set_num_threads(1)
    for var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):  # BLAS libraries loaded from now on
        os.environ[var] = "1"
    threadpool_limits(limits=1, user_api="blas")  # those already loaded
