"""Where a cold compile goes: the CPU time of each kernel's compilation, excluding the kernels
it calls (which compile inside it), for a short run of each preset in a fresh process with an
empty kernel cache.

Usage::

    python benchmarks/bench_compile.py [--presets spur_pair mercury_1a] [--top 25]

Prints per preset the total compile CPU time and the kernels that take most of it, with their
number of overloads (specialisations). CPU time of the process, so a loaded machine stretches
the wall time but barely these figures.
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile
import time

from machine_info import machine


def child(preset: str, duration: float) -> None:
    import warnings

    from flexgear import kernels
    from flexgear.app.run import run
    from flexgear.config import load_config

    own = collections.defaultdict(float)
    count = collections.Counter()
    stack = []
    compile_ = kernels.KernelDispatcher.compile

    def timed(self, sig):
        name = f"{self.py_func.__module__.rsplit('.', 1)[-1]}.{self.py_func.__qualname__}"
        n = len(self.overloads)
        t0 = time.process_time()
        stack.append(0.0)
        try:
            return compile_(self, sig)
        finally:
            took = time.process_time() - t0
            inner = stack.pop()
            own[name] += took - inner
            count[name] += len(self.overloads) - n
            if stack:
                stack[-1] += took

    kernels.KernelDispatcher.compile = timed
    cfg = load_config(preset)
    cfg.simulation.update(duration=duration, run_in=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run(cfg)
    sigs = {f"{d.py_func.__module__.rsplit('.', 1)[-1]}.{d.py_func.__qualname__}": [
        "(" + ", ".join(str(a)[:60] for a in sig) + ")" for sig in d.signatures]
        for d in kernels.KERNELS if len(d.signatures) > 1}
    print(json.dumps({"own": own, "count": count, "signatures": sigs}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", nargs="+", default=["spur_pair", "mercury_1a"])
    ap.add_argument("--duration", type=float, default=0.01)
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--signatures", action="store_true", help="list the argument types of kernels compiled "
                    "more than once")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(args.child, args.duration)
    print(f"# compile CPU per kernel, cold cache, {machine()}")
    for preset in args.presets:
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, NUMBA_CACHE_DIR=f"{tmp}/numba", FLEXGEAR_CACHE_DIR=f"{tmp}/flexgear",
                       MPLBACKEND="Agg")
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, __file__, "--child", preset, "--duration", str(args.duration)],
                                 env=env, capture_output=True, text=True, check=True)
            wall = time.perf_counter() - t0
        data = json.loads(out.stdout.strip().splitlines()[-1])
        own, count = data["own"], data["count"]
        total = sum(own.values())
        print(f"\n{preset}: {total:.1f} CPU-s compiling {sum(count.values())} overloads of {len(own)} kernels "
              f"(process wall {wall:.1f} s)")
        for name, s in sorted(own.items(), key=lambda kv: -kv[1])[:args.top]:
            print(f"  {s:7.1f} s  {100 * s / total:5.1f} %  x{count[name]:<2d} {name}")
        if args.signatures:
            for name, sigs in data["signatures"].items():
                print(f"  {name}:", *(f"\n    {s}" for s in sigs))


if __name__ == "__main__":
    main()
