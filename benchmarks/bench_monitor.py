"""Wall time of ``flexgear monitor`` on a 1 s result.

Usage::

    python benchmarks/bench_monitor.py [--result PATH] [--repeat 3]

Without ``--result`` it first simulates 1 s of rigid MERCURY 1-A (not timed) into a temporary
directory. Prints the wall time of the whole command in a fresh process (interpreter start,
imports, analysis, files and figures; the best of ``--repeat`` runs) with the CPU time that
process used (user + system: on a shared machine the better measure of its own cost), and, in
this process, the CPU time of its parts: reading the file, the analysis (order tracking,
averages, indicators, spectra), and writing the indicators and the figures; and, back to back
with each run, a process that only imports what the command needs (Python, scipy.signal,
matplotlib: a floor no analysis can go below). Target: the command under 2 s.
"""
from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from machine_info import machine


IMPORTS = ("import flexgear.app.cli, flexgear.monitoring.analysis, matplotlib.figure, "
           "matplotlib.backends.backend_agg, PIL.PngImagePlugin")


def simulate(directory: Path) -> Path:
    import flexgear
    from flexgear.results.store import save

    cfg = flexgear.load_config("mercury_1a")
    cfg.simulation["duration"] = 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return save(flexgear.run(cfg), directory / "results.h5")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--result", type=Path, help="a 1 s results.h5 (default: simulate MERCURY 1-A)")
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args()
    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        h5 = args.result or simulate(d)
        def child(cmd):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            subprocess.run([sys.executable, *cmd], check=True, capture_output=True)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            return time.perf_counter() - t0, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime

        walls, cpus, floor = [], [], []
        for i in range(args.repeat):  # the command and, back to back, a process that only imports what it needs
            w, c = child(["-m", "flexgear.app.cli", "monitor", str(h5), "-o", str(d / f"cmd{i}")])
            walls.append(w)
            cpus.append(c)
            floor.append(child(["-c", IMPORTS]))
        from flexgear.monitoring.analysis import monitor
        from flexgear.monitoring.outputs import write_report
        from flexgear.monitoring.source import read_input

        t0 = time.process_time()
        inp = read_input(h5)
        t_read = time.process_time() - t0
        t0 = time.process_time()
        rep = monitor(h5)
        t_analysis = time.process_time() - t0 - t_read
        (d / "parts").mkdir()
        t0 = time.process_time()
        write_report(rep, d / "parts")
        t_write = time.process_time() - t0
    n = inp.time.size
    print(f"result: {h5.name if args.result else 'MERCURY 1-A, 1 s'}, {n} samples, signal {inp.signal_path}, "
          f"shafts {', '.join(rep.shafts)}")
    print(f"flexgear monitor (fresh process): wall best {min(walls):.2f} s of {args.repeat} "
          f"({', '.join(f'{w:.2f}' for w in walls)}), CPU {', '.join(f'{c:.2f}' for c in cpus)} s; target < 2 s")
    print(f"  imports alone (python, scipy.signal, matplotlib; fresh process, back to back): wall "
          f"{', '.join(f'{w:.2f}' for w, _ in floor)}, CPU {', '.join(f'{c:.2f}' for _, c in floor)} s")
    print(f"  CPU in process: read {t_read:.3f} s, analysis {t_analysis:.3f} s, indicators and figures {t_write:.3f} s")


if __name__ == "__main__":
    main()
