"""Speed of this checkout against another revision, from one run: the claim "no slower".

Usage::

    python benchmarks/bench_revisions.py --base 7a96e1b [--repeat 3] [--presets spur_pair mercury_1a]
    python benchmarks/bench_revisions.py --base-tree /path/to/other/checkout

Both trees run the same workload through the API both revisions have (``flexgear.load_config``,
``flexgear.run``) in fresh processes, alternating base and this checkout so that a change of the
machine's load hits both: each preset for ``--duration`` simulated seconds after a warm-up run
that compiles (or loads) the kernels. Prints per preset the median wall time per simulated
second of each tree (the result's ``wall_seconds``: integration only, compile excluded) and
the fastest run, their ratios (on a shared VM the fastest is the steadier figure), and whether the mesh forces of the two trees are bit-identical.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from machine_info import machine

HERE = Path(__file__).resolve().parents[1]
PRESETS = ["spur_pair", "mercury_1a", "spur_pair_flexible", "mercury_1a_flexible", "spur_pair:lumped"]
DURATION = {"spur_pair": 2.0, "mercury_1a": 0.5, "spur_pair_flexible": 0.2, "mercury_1a_flexible": 0.1,
            "spur_pair:lumped": 5.0}

WORKER = r'''
import hashlib, json, sys, tomllib, warnings
warnings.simplefilter("ignore")
import flexgear
from flexgear.config import parse_config, preset_path
name, duration = sys.argv[1], float(sys.argv[2])
base, _, model = name.partition(":")
data = tomllib.loads(preset_path(base).read_text())
if model:
    data["model"] = model
data.setdefault("simulation", {}).update(duration=duration, run_in=0.02, antialias=False, output_rate=10000.0)
from flexgear.config import loader
if "synchronous" in loader.SIM_KEYS:  # the same plain grid in both trees
    data["simulation"]["synchronous"] = False
res = flexgear.run(parse_config(data, source=name))
h = hashlib.sha256()
for m in sorted(res.meshes):
    h.update(res.meshes[m].normal_force.tobytes())
print(json.dumps({"wall": res.attrs["wall_seconds"], "simulated": duration + 0.02, "forces": h.hexdigest()}))
'''


def one(tree: Path, preset: str, duration: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([sys.executable, "-c", WORKER, preset, str(duration)], env=env, capture_output=True,
                       text=True, cwd=tempfile.gettempdir())
    if p.returncode:
        raise SystemExit(f"{tree}: {preset} failed:\n{p.stderr[-3000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--base", help="git revision to compare with (checked out in a temporary worktree)")
    ap.add_argument("--base-tree", type=Path, help="an existing checkout of the base instead")
    ap.add_argument("--presets", nargs="+", default=PRESETS, help="presets; NAME:lumped for a lumped model")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--duration", type=float, help="simulated time per run [s] (default: per preset)")
    args = ap.parse_args()
    if not (args.base or args.base_tree):
        ap.error("give --base REV or --base-tree PATH")
    tmp = None
    base = args.base_tree
    if base is None:
        tmp = Path(tempfile.mkdtemp(prefix="flexgear-base-")) / "tree"
        subprocess.run(["git", "-C", str(HERE), "worktree", "add", "--detach", str(tmp), args.base], check=True,
                       capture_output=True)
        base = tmp
    try:
        print(machine())
        print(f"base {base} against {HERE}; wall s per simulated second, median (fastest) of {args.repeat}")
        print("| preset | base | this | this / base, median | this / base, fastest | forces bit-identical |")
        print("|---|---|---|---|---|---|")
        for preset in args.presets:
            d = args.duration or DURATION.get(preset, 0.1)
            for tree in (base, HERE):  # warm-up: compile or load the kernels, fill the caches
                one(tree, preset, 0.005)
            runs = {base: [], HERE: []}
            for _ in range(args.repeat):
                for tree in (base, HERE):
                    runs[tree].append(one(tree, preset, d))
            med = {t: statistics.median(r["wall"] / r["simulated"] for r in rs) for t, rs in runs.items()}
            low = {t: min(r["wall"] / r["simulated"] for r in rs) for t, rs in runs.items()}
            same = runs[base][0]["forces"] == runs[HERE][0]["forces"]
            print(f"| {preset} | {med[base]:.3f} ({low[base]:.3f}) | {med[HERE]:.3f} ({low[HERE]:.3f}) | "
                  f"{med[HERE] / med[base]:.3f} | {low[HERE] / low[base]:.3f} | {'yes' if same else 'no'} |", flush=True)
    finally:
        if tmp is not None:
            subprocess.run(["git", "-C", str(HERE), "worktree", "remove", "--force", str(tmp)], capture_output=True)


if __name__ == "__main__":
    main()
