"""Console output shared by the CLI and the study scripts: Markdown tables and progress bars."""
from __future__ import annotations

import logging
import math
import os
import sys
import threading
import time
import warnings


def cell(value, scale: float = 1.0, fmt: str = ".4g", none: str = "-") -> str:
    """A table cell: ``value`` times ``scale`` formatted, ``none`` for None or a non-finite value."""
    return none if value is None or not math.isfinite(value) else f"{value * scale:{fmt}}"


def markdown_table(rows, headers) -> str:
    """A Markdown table (pipes, padded columns) of ``rows`` under ``headers``."""
    widths = [max([len(str(h))] + [len(str(r[i])) for r in rows]) for i, h in enumerate(headers)]
    line = "| " + " | ".join(str(h).ljust(w) for h, w in zip(headers, widths)) + " |"
    sep = "|" + "|".join("-" * (w + 2) for w in widths) + "|"
    body = ["| " + " | ".join(str(c).ljust(w) for c, w in zip(r, widths)) + " |" for r in rows]
    return "\n".join([line, sep, *body])


def watched(stream=None) -> bool:
    """Whether a person is likely watching ``stream`` (default stderr) as it is written: a
    terminal, or a Jupyter kernel (where tqdm draws a widget); not a pipe, a file or a log."""
    stream = sys.stderr if stream is None else stream
    try:
        if stream is not None and stream.isatty():
            return True
    except (AttributeError, ValueError):  # a replaced or closed stream
        pass
    shell = getattr(sys.modules.get("IPython"), "get_ipython", lambda: None)()
    return type(shell).__name__ == "ZMQInteractiveShell"


def progress_bar(total_s: float, stream=None, every_s: float = 10.0):
    """Progress over ``total_s`` simulated seconds; returns (bar, update(fraction)).

    On a terminal: a tqdm bar. Elsewhere (CI logs, pipes, files), where a bar would be hidden
    or garble the log: plain lines ``flexgear: 25 % (0.300/1.200 s simulated, 4 s elapsed,
    about 12 s left)``, one at the first update, then at most one per ``every_s`` wall seconds
    and one at the end. ``bar.close()`` ends either.
    """
    stream = sys.stderr if stream is None else stream
    isatty = getattr(stream, "isatty", None)
    if isatty is not None and isatty():
        from tqdm import tqdm

        bar = tqdm(total=round(total_s, 4), unit="s sim", bar_format="{l_bar}{bar}| {n:.3f}/{total:.3f} s "
                   "simulated [{elapsed}<{remaining}]", file=stream)

        def update(frac):
            bar.n = round(frac * total_s, 4)
            bar.refresh()

        return bar, update
    lines = ProgressLines(total_s, stream, every_s)
    return lines, lines.update


def time_left(elapsed_s: float, done: float) -> str:
    """``", about 1 min 20 s left"``: the rest of a task at the mean rate since it began to
    advance (``done`` of it, 0-1, in ``elapsed_s`` wall seconds), or ``""`` before it has."""
    if not (done > 0 and elapsed_s > 0) or done >= 1.0:
        return ""
    left = round(elapsed_s * (1.0 - done) / done)
    return f", about {left // 60} min {left % 60} s left" if left >= 60 else f", about {left} s left"


#: how a run says it loads the solver (:func:`flexgear.app.run.solver_message`); the lines say
#: "compiling" instead once the kernels report a compile (:func:`flexgear.kernels.compiling`)
LOADING_SOLVER = "loading the compiled solver from the kernel cache"


class RateClock:
    """Fraction done since the first advance and the wall time it took (for :func:`time_left`),
    so that a wait before the work starts (building the model, compiling) does not count."""

    def __init__(self):
        self.t0 = self.f0 = None

    def left(self, now: float, frac: float) -> str:
        if self.t0 is None:
            if frac > 0:
                self.t0, self.f0 = now, 0.0 if frac >= 1.0 else frac
            return ""
        if frac <= self.f0:
            return ""
        return time_left(now - self.t0, (frac - self.f0) / (1.0 - self.f0))


class ProgressLines:
    """Plain progress lines for a stream that is not a terminal (see :func:`progress_bar`).

    A line is printed at the start, at the first update, then at most every ``every_s`` wall
    seconds and at the end. While nothing advances (the model is built, the solver compiles on
    first use) a background thread repeats the current line every ``every_s`` seconds, so that a
    log never stays silent for long. Once the simulation advances, a line also estimates the
    wall time left at the mean rate since it began to advance.
    """

    def __init__(self, total_s: float, stream, every_s: float = 10.0):
        self.total_s, self.stream, self.every_s = total_s, stream, every_s
        self.start = time.perf_counter()
        self.last = None  # wall time of the last line
        self.finished = False
        self.frac = 0.0
        self.eta = ""
        self.doing = ""  # the phase before the first step (note), shown while nothing advances
        self.clock = RateClock()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        print(f"flexgear: simulating {total_s:.3f} s (progress every {every_s:g} s of wall time)", file=stream,
              flush=True)
        self.last_line = self.start
        if every_s > 0:
            threading.Thread(target=self._heartbeat, name="flexgear-progress", daemon=True).start()

    def update(self, frac: float) -> None:
        with self._lock:
            now = time.perf_counter()
            self.frac = frac
            self.eta = self.clock.left(now, frac)
            if self.finished:
                return
            if self.last is None or frac >= 1.0 or now - self.last >= self.every_s:
                self._line(now)
                self.last = now
                self.finished = frac >= 1.0

    def note(self, text: str) -> None:
        """The phase the wait is in (building, compiling), repeated by the lines at 0 %."""
        with self._lock:
            self.doing = text

    def _heartbeat(self) -> None:
        while not self._stop.wait(self.every_s):
            with self._lock:
                now = time.perf_counter()
                if self.finished:
                    return
                if now - self.last_line >= self.every_s:
                    self._line(now)

    def _line(self, now: float) -> None:
        self.last_line = now
        doing = f": {self.doing}" if self.doing and self.frac == 0.0 else ""
        if self.doing.startswith(LOADING_SOLVER) and doing and _compiling():  # the cache held another model's only
            doing = (": compiling the solver: not in the kernel cache, the first run of this kind of model on this "
                     "machine (1 to 3 minutes on 2 cores), then simulating")
        print(f"flexgear: {100 * self.frac:3.0f} % ({self.frac * self.total_s:.3f}/{self.total_s:.3f} s simulated, "
              f"{now - self.start:.0f} s elapsed{self.eta}){doing}", file=self.stream, flush=True)

    def close(self) -> None:
        self._stop.set()


def _compiling() -> bool:
    from ..kernels import compiling  # numba, only once a line is written

    return compiling()


def count_bar(total: int, unit: str, stream=None, every_s: float = 10.0):
    """Progress over ``total`` items (e.g. frames); returns (bar, update(fraction)) like
    :func:`progress_bar`: a tqdm bar on a terminal, else a plain line at most every ``every_s``
    wall seconds and at the end."""
    stream = sys.stderr if stream is None else stream
    isatty = getattr(stream, "isatty", None)
    if isatty is not None and isatty():
        from tqdm import tqdm

        bar = tqdm(total=total, unit=unit, file=stream)

        def update(frac):
            bar.n = round(frac * total)
            bar.refresh()

        return bar, update
    start = time.perf_counter()
    last = [None]
    clock = RateClock()

    def update(frac):
        now = time.perf_counter()
        left = clock.left(now, frac)
        if last[0] is None or frac >= 1.0 or now - last[0] >= every_s:
            last[0] = now
            print(f"flexgear: {100 * frac:3.0f} % ({round(frac * total)}/{total} {unit}s, {now - start:.0f} s elapsed"
                  f"{left})", file=stream, flush=True)

    class _Lines:
        def close(self):
            pass

    return _Lines(), update


def exit_at_once(status: int) -> None:
    """End an interrupted program now: flush its streams and logs, then exit without the
    interpreter's teardown, which frees the loaded solver's compiled code object by object
    (0.4 s of CPU, several seconds on a busy machine) while the user waits. Call it only when
    every file is written and closed and the worker processes are gone."""
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(status)


def run_command(call, prog: str = "flexgear", interactive: bool = True) -> int:
    """Run ``call()`` (returning an exit status or None) as a command: a flexgear error or a file
    system refusal is one line ``PROG: error: ...`` (status 2), not a traceback; Ctrl-C is
    ``PROG: interrupted`` (130, and with ``interactive`` the program ends at once); warnings
    print as ``PROG: warning: ...``. ``flexgear``'s commands and the studies' scripts end so."""
    from ..errors import FlexgearError

    def show(message, category, filename, lineno, file=None, line=None):
        print(f"{prog}: warning: {message}", file=sys.stderr if file is None else file, flush=True)

    shown, warnings.showwarning = warnings.showwarning, show
    try:
        status = call()
    except FlexgearError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a file system refusal (permissions, full disk): say what, without a traceback
        where = f" {exc.filename!r}" if exc.filename else ""
        print(f"{prog}: error:{where} {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted; nothing partial was written", file=sys.stderr)
        status = 130
    finally:
        warnings.showwarning = shown
    if status == 130 and interactive:  # the program itself (not a call from Python), interrupted
        exit_at_once(130)
    return status or 0
