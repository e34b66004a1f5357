"""Batch runs: ``flexgear batch SWEEP.toml -o DIR`` runs every case of a sweep and tabulates them.

The sweep file (:mod:`flexgear.app.sweep`) is expanded and every case validated before anything
runs. The cases then run on an executor (:mod:`flexgear.app.executors`): local processes, one
per core (default), this process (``--workers 1``), or Dask (``--scheduler ADDRESS``,
``--dask-local N``). A case is ``flexgear.app.run.run(config)``, its metrics
(:mod:`flexgear.app.metrics`) and ``flexgear.results.store.save``; the result is the same on
every executor.

The batch directory::

    DIR/batch.json            what the directory holds (sweep, axes, columns, version)
    DIR/sweep.toml            the sweep file of the last invocation
    DIR/summary.csv           one row per case, rewritten (atomically) as cases finish
    DIR/summary.nc            the same as arrays over the sweep's axes, always written with the CSV
                              from the same state (at most every SUMMARY_EVERY_S, and at the end)
    DIR/columns.md            the summary's columns: unit and meaning
    DIR/cases/<key>.h5        the result of a case; <key> hashes its full configuration
    DIR/cases/<key>.json      the case's record: status, metrics, error and traceback
    DIR/.flexgear-batch.lock  held while a batch runs in DIR (removed when it ends)

Rerunning the same command continues: a case whose result file holds its exact configuration
is finished and not run again (its metrics are read back, or recomputed from the file); a failed
case stays failed unless ``--retry-failed``. Every file is written to a temporary name and
moved into place, so killing the batch at any moment loses only the cases in flight. Ctrl-C
kills the workers at once, removes what they were writing and writes the summaries of the
cases finished. A second batch on the same DIR is refused while the first runs.
"""
from __future__ import annotations

import copy
import functools
import json
import os
import socket
import sys
import tempfile
import time
import traceback
import warnings
from dataclasses import dataclass
from pathlib import Path

from .. import __version__
from ..config import parse_config
from ..errors import FlexgearError
from ..files import atomic_write, check_output_directory, csv_column
from .executors import CtrlC, DaskExecutor, ProcessExecutor, SerialExecutor, WorkerLost
from .metrics import DEFAULT_METRICS, compute_metrics
from .run import resolved_toml, run
from .summary import SummaryTable
from .sweep import DEFAULT_MAX_CASES, Sweep, read_sweep

#: The batch directory's lock file, present while a batch runs there.
LOCK_NAME = ".flexgear-batch.lock"
SUMMARY_EVERY_S = 2.0  # the summaries are rewritten at most this often while cases finish
MARKER = "batch.json"
RECORD_FORMAT = "flexgear-batch-case 1"


class BatchLockedError(FlexgearError):
    """Another batch is running in the same directory."""


# --------------------------------------------------------------------------- one case (worker side)

@dataclass(frozen=True)
class CaseTask:
    """What a worker needs to run one case (picklable).

    Attributes
    ----------
    index : int
        Case index (for messages).
    key : str
        Configuration hash: the result is ``<out_dir>/<key>.h5``.
    data : dict
        The case's configuration as a TOML dictionary.
    config_toml : str
        Its full configuration after defaults, as the driver read it.
    out_dir : str or None
        Where to write the result; None: send the file's bytes back.
    metrics : tuple of Metric
        The summary metrics.
    """

    index: int
    key: str
    data: dict
    config_toml: str
    out_dir: str | None
    metrics: tuple


def stored_config(path) -> str | None:
    """The ``config_toml`` a result file holds, or None if it cannot be read."""
    import h5py

    try:
        with h5py.File(path, "r") as h5:
            v = h5.attrs["config_toml"]
            return v.decode() if isinstance(v, bytes) else str(v)
    except Exception:
        return None


def execute_case(task: CaseTask) -> dict:
    """Run one case: validate, simulate, compute the metrics, save the result.

    Never raises for a failing case: the record's ``status`` is ``"failed"`` with the error and
    traceback. Returns the record (a dict; ``payload`` holds the file's bytes when
    ``task.out_dir`` is None).
    """
    from ..results.store import save

    t0 = time.perf_counter()
    rec = {"key": task.key, "worker": f"{socket.gethostname()}:{os.getpid()}"}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cfg = parse_config(copy.deepcopy(task.data), source=f"case {task.index}")
            if resolved_toml(cfg) != task.config_toml:
                raise FlexgearError("the worker reads this case's configuration differently from the driver "
                                    "(different flexgear versions on driver and workers?)")
            t_run = time.perf_counter()
            result = run(cfg)
            run_s = time.perf_counter() - t_run
        result.attrs["case_run_seconds"] = run_s
        values, info = compute_metrics(result, task.metrics)
        if task.out_dir is not None:
            path = Path(task.out_dir) / f"{task.key}.h5"
            if not (path.parent.parent / LOCK_NAME).exists():  # a task a Dask cluster ran on after Ctrl-C
                raise FlexgearError(f"the batch that sent this case has ended (interrupted?): {path.name} is not "
                                    "written into its directory")
            try:
                save(result, path)
            except FileExistsError:  # written meanwhile by an earlier attempt at this very case
                if stored_config(path) != task.config_toml:
                    raise
        else:
            with tempfile.TemporaryDirectory() as d:
                rec["payload"] = save(result, Path(d) / "r.h5").read_bytes()
        rec.update(status="done", metrics=values, columns={k: list(v) for k, v in info.items()}, wall_s=run_s,
                   error=None, traceback=None)
    except Exception as exc:
        rec.update(status="failed", metrics={}, columns={}, wall_s=time.perf_counter() - t0,
                   error=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc())
    return rec


def warm_up(data: dict) -> None:
    """Load (or compile, the first time) the solver by a very short run of a case; errors are
    left to the case itself."""
    data = copy.deepcopy(data)
    sim = data.setdefault("simulation", {})
    rate = sim.get("output_rate", 5000.0)
    sim.update(duration=4.0 / rate if isinstance(rate, (int, float)) and rate > 0 else 1e-3, run_in=0.0)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            run(parse_config(data))
    except Exception:
        pass


# --------------------------------------------------------------------------- lock

class BatchLock:
    """An exclusive lock on a batch directory (``flock`` on :data:`LOCK_NAME`), released when
    the process ends, even killed. A normal release removes the file; since another process may
    have opened it just before, :meth:`acquire` keeps a lock only on the file that is still at
    the path (else it opens the path again)."""

    def __init__(self, directory):
        self.path = Path(directory) / LOCK_NAME
        self.fd = None

    def acquire(self):
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
            try:
                _lock_fd(fd)
            except OSError:
                try:
                    who = os.read(fd, 400).decode(errors="replace").strip() or "unknown process"
                finally:
                    os.close(fd)
                raise BatchLockedError(f"{str(self.path.parent)!r} is in use by another flexgear batch ({who}); "
                                       "wait for it to finish, or write to another directory (-o)") from None
            try:
                current = os.stat(self.path).st_ino
            except FileNotFoundError:
                current = None
            if current == os.fstat(fd).st_ino:
                break
            os.close(fd)  # its holder removed that file as we opened it: lock the one at the path
        os.ftruncate(fd, 0)
        os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}, started "
                     f"{time.strftime('%Y-%m-%d %H:%M:%S')}".encode())
        self.fd = fd
        return self

    def release(self):
        """Remove the lock file, then release the lock (closing the descriptor)."""
        if self.fd is not None:
            try:
                if os.stat(self.path).st_ino == os.fstat(self.fd).st_ino:
                    os.unlink(self.path)
            except OSError:
                pass
            os.close(self.fd)
            self.fd = None

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()


def _lock_fd(fd):
    if os.name == "nt":
        import msvcrt

        msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
    else:
        import fcntl

        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # forked workers close their copy (executors)


# --------------------------------------------------------------------------- progress

class BatchProgress:
    """Cases done / failed / remaining and an ETA: a tqdm bar on a terminal, else a plain line
    per finished case (at most one a second, and the last). ``started``: when the batch began
    (``time.perf_counter``; default now), from which a plain line's elapsed time counts, the
    solver's compile included; the ETA comes from the cases' own rate."""

    def __init__(self, total: int, stream=None, enabled: bool = True, started: float | None = None):
        self.total = total
        self.done = self.failed = 0
        self.stream = stream or sys.stderr
        self.t0 = time.perf_counter()
        self.started = self.t0 if started is None else started
        self.enabled = enabled and total > 0
        self.bar = None
        self._last = 0.0
        if self.enabled and hasattr(self.stream, "isatty") and self.stream.isatty():
            from tqdm import tqdm

            class Bar(tqdm):
                monitor_interval = 0  # no monitor thread (workers may be forked later)

            self.bar = Bar(total=total, unit="case", file=self.stream, dynamic_ncols=True,
                           bar_format="{l_bar}{bar}| {n}/{total} [{elapsed}<{remaining}] {postfix}")
            self.bar.set_postfix_str(self._counts())

    def _counts(self) -> str:
        return f"{self.done} done, {self.failed} failed, {self.total - self.done - self.failed} remaining"

    def eta(self) -> float:
        """Seconds left at the mean rate so far (inf before the first case)."""
        n = self.done + self.failed
        if n == 0:
            return float("inf")
        return (time.perf_counter() - self.t0) / n * (self.total - n)

    def update(self, status: str):
        if status == "done":
            self.done += 1
        else:
            self.failed += 1
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.set_postfix_str(self._counts(), refresh=False)
            self.bar.update(1)
            return
        now = time.perf_counter()
        n = self.done + self.failed
        if now - self._last >= 1.0 or n == self.total:
            self._last = now
            print(f"flexgear batch: {n}/{self.total} run: {self._counts()}; elapsed {_hms(now - self.started)}, "
                  f"ETA {_hms(self.eta())}", file=self.stream, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _validation_progress(log, every_s: float = 10.0):
    """``progress(done, total)`` for validating the cases of a large sweep: a line at most every
    ``every_s`` seconds, so that a sweep that takes minutes to validate does not look stuck."""
    t0 = time.perf_counter()
    last = [t0]

    def progress(done: int, total: int) -> None:
        now = time.perf_counter()
        if now - last[0] >= every_s and done < total:
            last[0] = now
            log(f"flexgear batch: validating the cases: {done}/{total}, elapsed {_hms(now - t0)}, "
                f"ETA {_hms((now - t0) / done * (total - done))}")

    return progress


def _hms(s: float) -> str:
    if s == float("inf"):
        return "?"
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


# --------------------------------------------------------------------------- the batch

@dataclass
class BatchReport:
    """What a batch did. ``done``, ``failed``, ``pending``: cases in each state at the end;
    ``ran``: cases run by this invocation; ``skipped``: finished cases found on disk; ``wall_s``:
    seconds of the whole call, ``cases_s`` of running the cases (after validation, connecting and
    warming up the workers)."""

    directory: Path
    cases: int
    done: int
    failed: int
    pending: int
    ran: int
    skipped: int
    wall_s: float
    cases_s: float
    executor: str
    summary: Path
    table: SummaryTable


def make_executor(workers=None, scheduler=None, dask_local=None, dask_processes=True):
    """The executor for the command-line options (see :mod:`flexgear.app.executors`)."""
    if scheduler is not None and dask_local is not None:
        raise FlexgearError("give either --scheduler or --dask-local, not both")
    if workers is not None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise FlexgearError(f"--workers {workers!r}: must be an integer >= 1")
        if scheduler is not None or dask_local is not None:
            raise FlexgearError("--workers applies to local processes; with Dask the cluster's workers run "
                                "the cases (drop --workers)")
    if scheduler is not None or dask_local is not None:
        return DaskExecutor(scheduler=scheduler, local_workers=dask_local, processes=dask_processes)
    if workers == 1:
        return SerialExecutor()
    return ProcessExecutor(workers)


def _check_directory(out: Path):
    if out.exists() and not out.is_dir():
        raise FlexgearError(f"-o {str(out)!r} is a file; give a directory")
    ours = {MARKER, LOCK_NAME, "cases"}
    if out.is_dir() and any(p.name not in ours for p in out.iterdir()) and not (out / MARKER).exists():
        raise FlexgearError(f"-o {str(out)!r} exists, is not empty and is not a flexgear batch directory "
                            f"(no {MARKER}); refusing to write into it: choose another directory")
    check_output_directory(out)  # can be created and written: a real write, undone


def _check_same_sweep(out: Path, sweep: Sweep):
    """Refuse a sweep that would replace the summaries of another sweep run in ``out``: every
    case the directory's summary lists must be a case of ``sweep`` (the same sweep, or one that
    extends it, e.g. by a grid value, continues the directory; its finished cases are reused)."""
    earlier = csv_column(out / "summary.csv", "key")
    if not earlier:
        return
    ours = {c.key for c in sweep.cases}
    lost = [k for k in earlier if k not in ours]
    if lost:
        try:
            was = json.loads((out / MARKER).read_text()).get("sweep") or "another sweep"
        except (OSError, ValueError, AttributeError):
            was = "another sweep"
        raise FlexgearError(
            f"-o {str(out)!r} holds the batch of {was}, and {len(lost)} of its {len(earlier)} cases are not cases of "
            f"{sweep.source or 'this sweep'} (another sweep, or the sweep or its base edited since): running it there "
            "would replace the directory's summary.csv, summary.nc and sweep.toml; run it in another directory (a "
            "sweep that holds all of the directory's cases, e.g. with one more grid value, continues it)")


def _clean_temporaries(out: Path):
    """Remove the temporary files a killed batch left (we hold the lock): hidden files in
    ``cases/`` and the temporary copies of the batch's own files in ``DIR``."""
    own = tuple(f".{Path(n).stem}." for n in ("summary.csv", MARKER, "sweep.toml", "columns.md"))
    for p in list(out.glob(".*")) + list((out / "cases").glob(".*")):
        if p.is_file() and p.name != LOCK_NAME and (p.parent.name == "cases" or p.name.startswith(own)):
            p.unlink()


def _metric_names(metrics) -> list[str]:
    return [f"{m.name}:{getattr(m.func, '__module__', '')}.{getattr(m.func, '__qualname__', repr(m.func))}"
            for m in metrics]


def _write_record(path: Path, rec: dict):
    text = json.dumps(rec, indent=1)
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def _read_record(path: Path) -> dict | None:
    try:
        rec = json.loads(path.read_text())
        return rec if rec.get("format") == RECORD_FORMAT else None
    except (OSError, ValueError):
        return None


def _scan(sweep: Sweep, cases_dir: Path, table: SummaryTable, metrics, retry_failed: bool, log) -> list:
    """Fill ``table`` from the files of earlier runs; return the cases to run."""
    from ..results.store import load

    names = _metric_names(metrics)
    todo = []
    for case in sweep.cases:
        h5, js = cases_dir / f"{case.key}.h5", cases_dir / f"{case.key}.json"
        rec = _read_record(js) if js.exists() else None
        if rec is not None and rec.get("config_toml") != case.config_toml:
            rec = None
        if h5.exists():
            if stored_config(h5) == case.config_toml:
                if rec is None or rec.get("status") != "done" or rec.get("metric_names") != names:
                    result = load(h5)
                    values, info = compute_metrics(result, metrics)
                    rec = _record(case, {"status": "done", "metrics": values, "columns": {k: list(v) for k, v in
                                                                                       info.items()},
                                         "wall_s": result.attrs.get("case_run_seconds"), "error": None,
                                         "traceback": None, "worker": "recomputed from the result file"}, names)
                    _write_record(js, rec)
                table.set(case.index, "done", rec["metrics"], rec["columns"], rec["wall_s"],
                          file=f"cases/{h5.name}")
                continue
            aside = h5.with_name(f"{h5.name}.mismatch-{time.strftime('%Y%m%d-%H%M%S')}")
            os.replace(h5, aside)
            log(f"flexgear batch: {h5} does not hold {case.label()}'s configuration; moved it to {aside.name}")
        if rec is not None and rec.get("status") == "failed" and not retry_failed:
            table.set(case.index, "failed", wall_s=rec.get("wall_s"), error=rec.get("error"))
            continue
        todo.append(case)
    return todo


def _record(case, outcome: dict, names) -> dict:
    rec = {"format": RECORD_FORMAT, "key": case.key, "case": case.index, "values": case.values}
    rec.update({k: v for k, v in outcome.items() if k != "payload"})
    rec.update(config_toml=case.config_toml, metric_names=names, flexgear_version=__version__)
    return rec


def _metadata(sweep: Sweep, table: SummaryTable, executor_name: str) -> dict:
    return {"format": "flexgear-batch 1", "flexgear_version": __version__, "title": sweep.title,
            "sweep": sweep.source, "base": sweep.base, "cases": len(sweep.cases), "shape": list(sweep.shape),
            "axes": [{"kind": a.kind, "name": a.name, "keys": list(a.keys), "points": [list(p) for p in a.points]}
                     for a in sweep.axes],
            "derived": sweep.derived, "executor": executor_name,
            "columns": {c: list(table.info[c]) for c in table.columns}}


def run_batch(sweep, out_dir, *, workers: int | None = None, scheduler: str | None = None,
              dask_local: int | None = None, dask_processes: bool = True, retry_failed: bool = False,
              max_cases: int | None = DEFAULT_MAX_CASES, metrics=DEFAULT_METRICS,
              progress: bool = True, log=None) -> BatchReport:
    """Run (or continue) a batch.

    Parameters
    ----------
    sweep : str, Path or Sweep
        The sweep file, or an expanded :class:`~flexgear.app.sweep.Sweep`.
    out_dir : str or Path
        The batch directory (created; an existing one is continued).
    workers : int, optional
        Local worker processes (default: one per core); 1 runs the cases in this process.
    scheduler : str, optional
        Dask scheduler address; the cases run on its cluster.
    dask_local : int, optional
        Start a Dask ``LocalCluster`` of this many single-threaded workers
        (``dask_processes=False``: threads of this process).
    retry_failed : bool
        Run the cases that failed before again.
    max_cases : int or None
        Refuse a sweep of more than ``max_cases`` cases (None: no limit; the CLI's ``--yes``).
    metrics : sequence of Metric
        Summary columns (default :data:`flexgear.app.metrics.DEFAULT_METRICS`).
    progress : bool
        Show progress on stderr.
    log : callable(str), optional
        Where messages go (default: print to stderr).

    Returns
    -------
    BatchReport

    Raises
    ------
    ConfigError
        For a bad sweep or case (before anything runs or is written).
    FlexgearError
        Unreachable scheduler, bad options, a directory that is not a batch's.
    BatchLockedError
        Another batch is running in ``out_dir``.
    """
    log = log or (lambda msg: print(msg, file=sys.stderr, flush=True))
    t_start = time.perf_counter()
    metrics = tuple(metrics)
    executor = make_executor(workers, scheduler, dask_local, dask_processes)
    if not isinstance(sweep, Sweep):
        sweep = read_sweep(sweep, max_cases=max_cases, progress=_validation_progress(log) if progress else None)
    elif max_cases is not None and len(sweep.cases) > max_cases:
        raise FlexgearError(f"the sweep has {len(sweep.cases)} cases, more than the limit of {max_cases}; pass "
                            "--yes to run them all (or raise --max-cases)")
    for w in sweep.warnings:
        log(f"flexgear batch: warning: {w}")
    out = Path(out_dir)
    _check_directory(out)
    table = SummaryTable(sweep)
    executor.connect()
    lock = None
    try:
        out.mkdir(parents=True, exist_ok=True)
        lock = BatchLock(out).acquire()
        _check_same_sweep(out, sweep)
        if isinstance(executor, ProcessExecutor):
            executor.close_in_workers = (lock.fd,)
        atomic_write(out / MARKER, lambda tmp: Path(tmp).write_text(json.dumps(_metadata(sweep, table,
                                                                                         executor.name), indent=1)))
        (out / "cases").mkdir(exist_ok=True)
        _clean_temporaries(out)
        if isinstance(executor, DaskExecutor) and not executor.shares_files:
            executor.check_shared_directory(out / "cases")
        atomic_write(out / "sweep.toml", lambda tmp: Path(tmp).write_text(sweep.text))
        todo = _scan(sweep, out / "cases", table, metrics, retry_failed, log)
        skipped = table.count("done")
        summary = out / "summary.csv"
        summaries = _Summaries(out, table, log)
        summaries.write()  # both files from the state found on disk (and xarray imported now, not at Ctrl-C)
        log(f"flexgear batch: {len(sweep.cases)} cases: {skipped} finished before, {table.count('failed')} failed "
            f"before{' (not retried; --retry-failed runs them again)' if table.count('failed') else ''}, "
            f"{len(todo)} to run on {executor.name}")
        ran = 0
        cases_s = 0.0
        if todo:
            from ..dynamics.lumped.friction import friction_loop
            from .run import solver_ready

            kinds, seen = set(), set()
            for c in todo:  # the time loops the cases take: one case parsed per [lubrication] table swept
                lumped = c.data.get("model") == "lumped"
                key = lumped and json.dumps(c.data.get("lubrication"), sort_keys=True, default=str)
                if key in seen:
                    continue
                seen.add(key)
                try:
                    kinds.add((lumped, lumped and friction_loop(parse_config(copy.deepcopy(c.data)))))
                except Exception:  # a case whose configuration fails says so itself
                    kinds.add((lumped, False))
            ready = all(solver_ready(*kind) for kind in kinds)
            if not ready:
                log("flexgear batch: compiling the solver once (a few minutes; cached for every later case)")
            if not isinstance(executor, SerialExecutor):
                warm = functools.partial(warm_up, todo[0].data)
                if not ready and isinstance(executor, DaskExecutor):
                    warm()  # compile here once; the workers then load numba's cache
                executor.start(warm)
            out_cases = str((out / "cases").resolve()) if executor.shares_files else None
            tasks = [CaseTask(c.index, c.key, c.data, c.config_toml, out_cases, metrics) for c in todo]
            names = _metric_names(metrics)
            bar = BatchProgress(len(tasks), enabled=progress, started=t_start)
            t_cases = time.perf_counter()
            with CtrlC() as ctrl_c:
                outcomes = executor.run(execute_case, tasks, ctrl_c)
                try:
                    for task, outcome in outcomes:
                        case = sweep.cases[task.index]
                        if isinstance(outcome, WorkerLost):
                            outcome = {"status": "failed", "metrics": {}, "columns": {}, "wall_s": None,
                                       "error": f"WorkerLost: {outcome.message}", "traceback": None}
                        with ctrl_c.deferred():  # the case's files and the summaries whole
                            payload = outcome.get("payload")
                            h5 = out / "cases" / f"{case.key}.h5"
                            if payload is not None:
                                atomic_write(h5, lambda tmp: Path(tmp).write_bytes(payload))
                            _write_record(out / "cases" / f"{case.key}.json", _record(case, outcome, names))
                            done = outcome["status"] == "done"
                            table.set(case.index, outcome["status"], outcome["metrics"], outcome["columns"],
                                      outcome["wall_s"], outcome["error"], file=f"cases/{h5.name}" if done else None)
                            summaries.write(every=SUMMARY_EVERY_S)
                            ran += 1
                            bar.update(outcome["status"])
                        ctrl_c.check()  # pressed while the case was recorded
                except KeyboardInterrupt:
                    with ctrl_c.deferred():  # a second Ctrl-C here would leave the summaries half written
                        outcomes.close()  # kill the workers now
                        _clean_temporaries(out)  # the files they were writing
                        _finish(out, sweep, table, executor.name, summaries)
                    raise
                finally:
                    outcomes.close()
                    bar.close()
                    cases_s = time.perf_counter() - t_cases
        _finish(out, sweep, table, executor.name, summaries)
    finally:
        try:
            executor.close()
        finally:
            if lock is not None:
                lock.release()
    report = BatchReport(directory=out, cases=len(sweep.cases), done=table.count("done"),
                         failed=table.count("failed"), pending=table.count("pending"), ran=ran, skipped=skipped,
                         wall_s=time.perf_counter() - t_start, cases_s=cases_s, executor=executor.name,
                         summary=summary, table=table)
    log(f"flexgear batch: {report.done} done, {report.failed} failed, {report.pending} pending "
        f"({report.ran} run now, {report.skipped} finished before) in {_hms(report.wall_s)}; summary: {summary}")
    for r in table.records():
        if r["status"] == "failed":
            log(f"  failed: {sweep.cases[r['case']].label()}: {r['error']}")
    return report


class _Summaries:
    """``summary.csv`` and ``summary.nc`` of a batch, always written together from one state
    (:meth:`SummaryTable.write_both`): at the start, at most every ``every`` seconds as cases
    finish, and at the end or on an interrupt."""

    def __init__(self, out: Path, table: SummaryTable, log):
        self.out, self.table, self.log = out, table, log
        self.last = None
        self.warned = False

    def write(self, every: float = 0.0) -> None:
        now = time.perf_counter()
        if self.last is not None and now - self.last < every:
            return
        self.last = now
        if not self.table.write_both(self.out / "summary.csv", self.out / "summary.nc") and not self.warned:
            self.warned = True
            self.log("flexgear batch: summary.nc not written (xarray or h5netcdf missing); pip install xarray h5netcdf")


def _finish(out: Path, sweep: Sweep, table: SummaryTable, executor_name: str, summaries: _Summaries):
    atomic_write(out / "columns.md", lambda tmp: Path(tmp).write_text(table.columns_text()))
    atomic_write(out / MARKER, lambda tmp: Path(tmp).write_text(json.dumps(_metadata(sweep, table, executor_name),
                                                                           indent=1)))
    summaries.write()
