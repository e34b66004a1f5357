"""Benchmark of batch runs (issue targets on 2 cores):

1. speed-up of 2 local worker processes over 1 on a 20-case spur speed sweep (target >= 1.8x);
2. per-case overhead of the batch machinery, excluding the simulation (target < 0.2 s): the
   serial batch's time for running its cases minus the cases' own run time, per case, and
   against a plain loop of ``run`` + ``save``;
3. Dask (LocalCluster of 2 worker processes) against the local pool on the same sweep
   (target: < 10 % more time for running the cases; the cluster's start-up is reported apart).

Usage: ``python benchmarks/bench_batch.py [--cases 20] [--duration 1.0] [--no-dask]``.
Prints a Markdown table. The solver is loaded once before timing.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def sweep_text(n: int, duration: float) -> str:
    speeds = ", ".join(f"{5.0 + 25.0 * i / max(n - 1, 1):.6g}" for i in range(n))
    return (f'title = "bench"\nbase = "spur_pair"\n[set]\n"simulation.duration" = {duration}\n'
            f'"simulation.run_in" = 0.05\n[grid]\n"drive.speed_hz" = [{speeds}]\n')


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=20)
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per case after the run-in (default 1 s, the presets' duration)")
    ap.add_argument("--no-dask", action="store_true")
    args = ap.parse_args(argv)

    from flexgear.app.batch import run_batch, warm_up
    from flexgear.app.console import markdown_table
    from flexgear.app.run import run
    from flexgear.app.sweep import loads_sweep
    from flexgear.results.store import save

    tmp = Path(tempfile.mkdtemp(prefix="bench_batch_"))
    sweep = loads_sweep(sweep_text(args.cases, args.duration), source="bench.toml")
    warm_up(sweep.cases[0].data)
    quiet = dict(progress=False, log=lambda m: None)
    rows = []

    def batch(name, **kw):
        r = run_batch(sweep, tmp / name, **kw, **quiet)
        assert r.done == args.cases, f"{name}: {r.failed} failed"
        return r

    t = time.perf_counter()
    for c in sweep.cases:  # the same work without the batch machinery
        save(run(c.config), tmp / f"plain_{c.key}.h5")
    plain = time.perf_counter() - t
    serial = batch("serial", workers=1)
    sim = sum(r["wall_s"] for r in serial.table.records())
    overhead = (serial.cases_s - sim) / args.cases
    pool = batch("pool2", workers=2)
    speedup = serial.cases_s / pool.cases_s
    busy = sum(r["wall_s"] for r in pool.table.records()) / (2 * pool.cases_s)
    rows += [["plain loop run + save", f"{plain:.2f}", "", ""],
             ["serial batch (--workers 1)", f"{serial.cases_s:.2f}", f"{serial.wall_s:.2f}", ""],
             ["2 local processes (--workers 2)", f"{pool.cases_s:.2f}", f"{pool.wall_s:.2f}",
              f"speed-up {speedup:.2f}x (target >= 1.8)"]]
    if not args.no_dask:
        dask = batch("dask2", dask_local=2)
        extra = dask.cases_s / pool.cases_s - 1
        rows.append(["Dask LocalCluster, 2 processes (--dask-local 2)", f"{dask.cases_s:.2f}", f"{dask.wall_s:.2f}",
                     f"{100 * extra:+.1f} % against the local pool (target < 10 %)"])
    print(f"{args.cases} spur cases of {args.duration} s (+0.05 s run-in), {os.cpu_count()} cores\n")
    print(markdown_table(rows, ["executor", "running the cases s", "whole call s", "figure"]))
    print(f"\nworkers busy with cases {100 * busy:.0f} % of the pool's time (the speed-up on 2 idle cores is about "
          f"2 x this x the ratio of serial to pooled case times: {serial.cases_s / args.cases:.3f} s against "
          f"{sum(r['wall_s'] for r in pool.table.records()) / args.cases:.3f} s per case here)")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"load average during the benchmark: {load:.2f} (other processes on the machine slow the pool down)")
    print(f"\nper-case overhead of the batch machinery (serial batch minus the cases' run time): "
          f"{1e3 * overhead:.0f} ms (target < 200 ms); against the plain loop: "
          f"{1e3 * (serial.cases_s - plain) / args.cases:+.0f} ms per case")


if __name__ == "__main__":
    main()
