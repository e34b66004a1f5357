"""Cold and warm start of each preset: ``flexgear run`` in a fresh process, first with empty
caches (kernels, contact tables, reductions), then again with the caches it left.

Usage::

    python benchmarks/bench_cold_start.py [--presets spur_pair mercury_1a] [--duration 0.05]
    python benchmarks/bench_cold_start.py --readme      # README's first command (1 s, figures)

Each run gets its own empty ``NUMBA_CACHE_DIR`` and ``FLEXGEAR_CACHE_DIR``, so nothing the
developer's caches hold is used. Prints per preset and start: the process's wall time, and the
phases the run reports (model building, of which compiling kernels; solver compile; the
integration). The issue's bar: README's first command within 120 s after the install on the
2-core machine.
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from machine_info import machine

PHASES = {
    "build": r"model built in ([\d.]+) s",
    "build kernels": r"model built in [\d.]+ s \(([\d.]+) s compiling",
    "solver compile": r"plus ([\d.]+) s to compile the solver",
    "integration": r"; ([\d.]+) s wall for",
}


def one_run(preset: str, duration: float | None, caches: Path, out: Path, figures: bool) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(caches / "numba"), FLEXGEAR_CACHE_DIR=str(caches / "flexgear"),
               MPLBACKEND="Agg")
    cmd = [sys.executable, "-m", "flexgear.app.cli", "run", preset, "-o", str(out), "--overwrite"]
    if duration is not None:
        cmd += ["--duration", str(duration)]
    if not figures:
        cmd.append("--no-figures")
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{p.stderr[-3000:]}")
    text = p.stdout + p.stderr
    row = {"wall": wall}
    for name, pattern in PHASES.items():
        m = re.search(pattern, text)
        row[name] = float(m.group(1)) if m else 0.0
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--presets", nargs="+", default=["spur_pair", "mercury_1a"])
    ap.add_argument("--duration", type=float, default=0.05, help="simulated time kept [s] (default 0.05)")
    ap.add_argument("--readme", action="store_true", help="README's first command: mercury_1a, 1 s, with figures")
    args = ap.parse_args()
    presets, duration, figures = (["mercury_1a"], None, True) if args.readme else (args.presets, args.duration, False)
    print(machine())
    print(f"| preset | start | wall s | build s | of it kernels s | solver compile s | integration s |")
    print("|---|---|---|---|---|---|---|")
    for preset in presets:
        with tempfile.TemporaryDirectory(prefix="flexgear-cold-") as tmp:
            tmp = Path(tmp)
            for start in ("cold", "warm"):
                r = one_run(preset, duration, tmp, tmp / "out", figures)
                print(f"| {preset} | {start} | {r['wall']:.1f} | {r['build']:.1f} | {r['build kernels']:.1f} | "
                      f"{r['solver compile']:.1f} | {r['integration']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
