"""Threads of the compiled force evaluation: numba's threading layer and the thread count.

The compliant meshes' force evaluation (:func:`~flexgear.dynamics.compliant.compliant_contacts`)
runs its per-mesh contact searches and its per-body flank rows in ``prange`` loops when the
workspace asks for more than one thread (``ContactBuffers.threads``, set by
:func:`~flexgear.dynamics.solver.simulate`); every sum is still formed in one thread in the
serial order, so the results are bit-identical whatever the thread count.

Threading layer: OpenMP where numba has it (GNU OpenMP on Linux wheels). A parallel loop there
costs about 1 us to launch; numba's fallback "workqueue" layer costs about 100 us, more than the
loops save, and TBB is rarely installed. A ``NUMBA_THREADING_LAYER`` set by the user is kept.

GNU OpenMP is not fork-safe: a process forked after the parent ran a parallel region hangs in
its own first parallel region. :func:`parallel_used` tells whether this process has run one
(through :func:`kernel_threads`); the batch executor then spawns its workers instead of
forking them, and every worker runs single-threaded
(:func:`~flexgear.app.executors.start_method`).
"""
from __future__ import annotations

import contextlib
import operator
import os

import numba

_PARALLEL_USED = False


def use_openmp() -> str:
    """Select numba's OpenMP threading layer if it loads and the user chose none; returns the
    configured layer name (numba's ``config.THREADING_LAYER``). Called once when
    :mod:`flexgear.dynamics` is imported, before any parallel loop runs."""
    if os.environ.get("NUMBA_THREADING_LAYER"):
        return numba.config.THREADING_LAYER
    try:
        from numba.np.ufunc import omppool  # noqa: F401  (the layer's library loads: libgomp / libomp)
    except ImportError:
        return numba.config.THREADING_LAYER
    numba.config.THREADING_LAYER = "omp"
    return "omp"


def check_threads(threads) -> int | None:
    """``threads`` as given to :func:`~flexgear.dynamics.solver.simulate`: None or an integer
    >= 1.

    Raises
    ------
    ValueError
        For anything else (0, a negative or a non-integer number), naming the parameter.
    """
    if threads is None:
        return None
    bad = ValueError(f"threads = {threads!r}: must be None (numba's thread count) or an integer >= 1")
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
    """Make the calling thread's kernels single-threaded (a batch worker: the cores are the
    workers')."""
    numba.set_num_threads(1)
