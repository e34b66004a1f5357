"""The scripts in benchmarks/ run to the end and print what they promise.

No other test runs them, so an internal change can break one unnoticed (bench_flexible.py
crashed for weeks after ``newton_update``'s signature changed). Each ``bench_*.py`` runs here
as a user would (a fresh process from the repository root, ``MPLBACKEND=Agg``, the session's
``FLEXGEAR_CACHE_DIR``) with the smallest arguments that still take it through all its code
paths, and its output is checked for its own table headers and rows, each row with finite
numbers (a benchmark that prints ``nan`` or an empty row is as broken as one that crashes).
Timings are never checked: the machine may be loaded.

The runs are ``slow`` (minutes: the benchmarks compile their own kernels, and two of them
compile the package's from empty caches by design). The default suite only checks, without
spawning anything, that every ``benchmarks/bench_*.py`` has its arguments here, so a new
benchmark cannot be left out.
"""
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"

#: a finite decimal number as the benchmarks print them (never nan or inf)
N = r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?"
#: a positive one with one decimal (not 0.0)
NZ = r"(?!0\.0 )\d+\.\d"
#: [s] allowed on top of each case's own time: the kernels it loads may not be compiled yet (a
#: fresh clone's first slow session compiles the solver's specialisations, minutes on 2 cores)
COLD_KERNELS = 600

#: per script: the argument lists of its runs, in order ("{tmp}": the test's temporary
#: directory), the time allowed for all of them with the kernels compiled [s] (several times
#: what they took on the loaded 2-core VM), and the patterns (regular expressions,
#: one line each) its standard output must hold.
BENCHES = {
    "bench_batch": {
        "runs": [["--cases", "2", "--duration", "0.01"]],  # with the Dask LocalCluster
        "timeout": 120,
        "expect": [r"^2 spur cases of 0\.01 s",
                r"^\| executor +\| running the cases s +\| whole call s +\| figure",
                rf"^\| plain loop run \+ save +\| {N} ",
                rf"^\| serial batch \(--workers 1\) +\| {N} +\| {N} ",
                rf"^\| 2 local processes \(--workers 2\) +\| {N} +\| {N} +\| speed-up {N}x",
                rf"^\| Dask LocalCluster, 2 processes \(--dask-local 2\) +\| {N} +\| {N} +\| {N} % against",
                rf"^per-case overhead of the batch machinery .*: {N} ms .*: {N} ms per case"]},
    "bench_decimation": {
        "runs": [["--presets", "spur_pair", "spur_pair+friction", "--repeat", "1"]],
        "timeout": 120,
        "expect": [r"^preset +channels +steps +before ms/s +now ms/s +ratio$",
                   rf"^spur_pair +17 +\d+ +{N} +{N} +{N}$",
                   rf"^spur_pair\+friction +19 +\d+ +{N} +{N} +{N}$"]},
    "bench_cold_start": {
        "runs": [["--presets", "spur_pair", "--duration", "0.001"]],
        "timeout": 600,
        "expect": [r"^\| preset \| start \| wall s \| build s \| of it kernels s \| solver compile s \| integration s \|",
                # the cold run's model build and solver compile are read from its messages: 0.0 when
                # bench_cold_start.PHASES no longer match what `flexgear run` prints
                rf"^\| spur_pair \| cold \| {N} \| {NZ} \| {N} \| {NZ} \| {N} \|$",
                rf"^\| spur_pair \| warm \| {N} \| {N} \| {N} \| {N} \| {N} \|$"]},
    "bench_compile": {
        "runs": [["--presets", "spur_pair", "--duration", "0.001", "--top", "3", "--signatures"]],
        "timeout": 600,
        "expect": [r"^# compile CPU per kernel, cold cache",
                rf"^spur_pair: {N} CPU-s compiling \d+ overloads of \d+ kernels \(process wall {N} s\)",
                rf"^ +{N} s +{N} % +x\d+ +\w"]},
    "bench_condensation": {
        "runs": [["--run-in", "0.002", "--duration", "0.004", "--variants", "integrated,static,coordinates",
               "--save", "{tmp}/condensation.npz"]],
        "timeout": 120,
        "expect": [*(rf"^{v} +modes as coords +\d+ +newton/step +{N} +wall +{N} s +mean +{N} N +std +{N} N"
                  for v in ("integrated", "static", "coordinates")),
                rf"^T / r_b2 = {N} N",
                *(rf"^{v} - coordinates: RMS diff / std = {N} +mean diff {N} N +max\|d\| {N} N" for v in ("integrated", "static")),
                rf"^ +dominant lines of the difference \[Hz \(rel amp\)\]: {N} \({N}\)"]},
    "bench_faults": {
        "runs": [["--duration", "0.002", "--level", "0", "--faults", "missing", "eccentricity", "--repeat", "1", "--cpu"]],
        "timeout": 120,
        "expect": [r"^\| fidelity \| fault \| healthy s/s \| faulted s/s \| ratio \| target \| load \|",
                *(rf"^\| {fid} \| {fault} \| {N} \| {N} \| {N} \| <= {N} \| load {N} \|$"
                  for fid in ("lumped", "rigid", "flexible") for fault in ("missing", "eccentricity")),
                rf"^largest ratio {N}",
                rf"^ +missing: uncached {N} s, cached {N} s",
                r"^ +eccentricity: the FE body stays nominal"]},
    "bench_fe": {
        "runs": [["--level", "0", "--modes", "4"]],
        "timeout": 60,
        "expect": [r"^flexgear FE benchmark: sun gear z=24",
                rf"^mesh +: level 0, order \d: \d+ triangles, \d+ nodes, \d+ dofs; min angle {N} deg",
                *(rf"^ +{re.escape(label)} +{N} (s|GB)" for label in (
                    "mesh (gmsh, empty cache)", "assembly (K, M)", "4 clamped modes (eigsh)", "cached reload",
                    "peak traced heap (tracemalloc)", "peak memory")),
                rf"^first 10 clamped-hub frequencies \[kHz\]: {N} {N} {N} {N}$"]},
    "bench_flexible": {
        "runs": [["--duration", "0.002", "--level", "0", "--presets", "spur_pair", "--threads", "2"]],
        "timeout": 300,
        "expect": [r"^spur_pair_flexible:$",
                rf"^ +preprocessing uncached {N} s",
                rf"^ +preprocessing cached {N} s",
                rf"^ +model build in this process {N} s .*; \d+ generalised coordinates",
                r"^ +(pinion|wheel) \(x1\): \d+ FE dofs -> \d+ interface coordinates \+ \d+ fixed-interface modes",
                rf"^ +wall per simulated second at h = {N} us: flexible {N} s .*rigid {N} s .*ratio {N}",
                rf"^ +flexible on 2 threads: {N} s per simulated second",
                rf"^ +Newton iterations per step: flexible {N}, rigid {N}",
                *(rf"^ +{part} +{N} us" for part in ("contact search", "compliance", "Newton", "rest"))]},
    "bench_friction": {
        "runs": [["--duration", "0.004", "--flexible-duration", "0.002", "--lumped-duration", "0.1", "--repeat", "1",
               "--presets", "spur_pair", "spur_pair_flexible", "spur_pair:lumped"],
                 ["--whole", "--repeat", "1", "--presets", "spur_pair:lumped"]],
        "timeout": 120,
        "expect": [r"^preset +case +cpu s +ratio +vs +newton/step",
                *(rf"^spur_pair +{case} +{N} +{N} +{N}$" for case in ("off", "constant", "xu", "squeeze")),
                rf"^spur_pair +xu\+squeeze +{N} +{N} +{N} \(xu\) +{N}$",
                *(rf"^spur_pair_flexible +{case} +{N} +{N} +{N}$" for case in ("off", "constant", "xu")),
                *(rf"^spur_pair:lumped +{case} +{N} +{N} +{N}$" for case in ("off", "constant", "xu", "squeeze")),
                rf"^spur_pair:lumped +xu\+squeeze +{N} +{N} +{N} \(xu\) +{N}$",
                *(rf"^spur_pair:lumped +{case} +{N} +{N} +-$" for case in ("off", "constant", "xu"))]},
    "bench_housing": {
        "runs": [["--repeat", "1", "--duration", "0.002"], ["--flexible-only", "--duration", "0.002"]],
        "timeout": 300,
        "expect": [rf"^(mercury_1a|spur_pair): \d+ dofs, \d+ interface coordinates, \d+ modes to {N} kHz",
                rf"^ +uncached: +{N} s wall, +{N} s CPU",
                rf"^ +cached: +{N} s wall, +{N} s CPU",
                rf"^ +path: +{N} s to build, +{N} s wall / +{N} s CPU",
                (rf"^spur_pair coupled housing \(cutoff default, \d+ coordinates .*: solver {N} s wall against {N} s "
                rf"without: {N}x"),
                r"^spur_pair coupled housing \(cutoff 12000 Hz,",
                (rf"^mercury_1a coupled housing \(\d+ coordinates in all\).*: run {N} s CPU against {N} s .*: {N}x; "
                rf"solver {N} s against {N} s wall: {N}x"),
                *(rf"^spur_pair_flexible, housing \({w}\), 2 sensors, .*: run {N} s CPU against {N} s without: {N}x; "
                  rf"solver {N} s against {N} s wall: {N}x" for w in ("one_way", "coupled"))]},
    "bench_lumped": {
        "runs": [["--duration", "0.01"]],
        "timeout": 60,
        "expect": [r"^\| model +\| wall s per simulated s \| steps \| iterations \|",
                *(rf"^\| {m} +\| {N} \| \d+ \| \d+ \|$" for m in ("rigid", "lumped")),
                rf"^lumped is {N} x faster than rigid",
                rf"^lumped model build .*: {N} s",
                rf"^modal analysis of the rigid set \(\d+ modes, \d+ positions\): {N} s"]},
    "bench_monitor": {
        "runs": [["--repeat", "1"]],  # simulates the 1 s of MERCURY 1-A it times the command on: no shorter option
        "timeout": 120,
        "expect": [r"^result: MERCURY 1-A, 1 s, \d+ samples",
                rf"^flexgear monitor \(fresh process\): wall best {N} s of 1 \({N}\), CPU {N} s",
                rf"^ +imports alone .*: wall {N}, CPU {N} s",
                rf"^ +CPU in process: read {N} s, analysis {N} s, indicators and figures {N} s"]},
    "bench_reduction": {
        "runs": [["--level", "0", "--repeat", "1", "--modes", "20", "--cache-dir", "{tmp}/meshes"]],
        "timeout": 120,
        "expect": [r"^sun z = 24, level 0: \d+ dofs, \d+ bore dofs",
                r"^ +modes +flexgear \[s\] +plain scipy \[s\] +ratio",
                rf"^ +20 +{N} +{N} +{N} +{N} +{N} / {N} / {N}$",
                rf"^flank tables \(\d+ radii x 2 flanks, to all 24 teeth\): {N} s; modal shapes .*: {N} s",
                *(rf"^ +{k} modes \(to +{N} kHz\): +{N} % at r = {N} mm, +{N}- *{N} % over the flank" for k in (20, 100, 200))]},
    "bench_revisions": {
        "runs": [["--base-tree", str(ROOT), "--presets", "spur_pair", "--repeat", "1", "--duration", "0.005"]],
        "timeout": 120,
        "expect": [r"^\| preset \| base \| this \| this / base, median \| this / base, fastest \| forces bit-identical \|",
                # the same tree twice: the forces must be identical
                rf"^\| spur_pair \| {N} \({N}\) \| {N} \({N}\) \| {N} \| {N} \| yes \|$"]},
    "bench_rigid": {
        "runs": [["--duration", "0.01"]],
        "timeout": 60,
        "expect": [r"^preset +build s +jit s +wall s/sim s +steps +newton +newton/step +rejected +step us",
                *(rf"^{p} +{N} +{N} +{N} +\d+ +\d+ +{N} +\d+ +{N}$" for p in ("spur_pair", "mercury_1a"))]},
    "bench_search": {
        "runs": [["--presets", "spur_pair_flexible", "mercury_1a", "--steps", "16", "--settle", "0.0005",
               "--save", "{tmp}/search.npz"],
              ["--presets", "spur_pair_flexible", "mercury_1a", "--steps", "16", "--settle", "0.0005",
               "--compare", "{tmp}/search.npz"]],
        "timeout": 300,
        "expect": [*(rf"^{p}: \d+ meshes, stride \d+, 16 poses" for p in ("spur_pair_flexible", "mercury_1a")),
                *(rf"^ +{s} search +{N} us per call +{N} us per step" for s in ("full", "local")),
                rf"^ +run pattern +{N} us per call +{N} us per step",
                # the second run compares the searches of the same code with the first's
                r"^ +outputs bit-identical \(\d+ contacts\)"]},
}


def test_every_benchmark_is_smoke_tested():
    """Every benchmarks/bench_*.py has its arguments in BENCHES (and no entry is stale)."""
    scripts = {p.stem for p in BENCHMARKS.glob("bench_*.py")}
    assert scripts, f"no benchmark found in {BENCHMARKS}"
    assert not scripts - set(BENCHES), "benchmarks with no smoke test: give them arguments in BENCHES"
    assert not set(BENCHES) - scripts, "BENCHES names scripts that are gone"


def run_script(name: str, args: list, timeout: float) -> tuple[int, str, str]:
    """Runs benchmarks/NAME.py with ``args`` from the repository root; its process group is
    killed at ``timeout`` [s] (the benchmarks start processes of their own)."""
    env = dict(os.environ, MPLBACKEND="Agg", FLEXGEAR_CACHE_DIR=os.environ["FLEXGEAR_CACHE_DIR"])
    proc = subprocess.Popen([sys.executable, str(BENCHMARKS / f"{name}.py"), *args], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        pytest.fail(f"{name} {' '.join(args)}: still running after {timeout:.0f} s\n{out[-3000:]}\n{err[-3000:]}")
    return proc.returncode, out, err


@pytest.mark.slow
@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.timeout(c["timeout"] + COLD_KERNELS + 60)) for n, c in BENCHES.items()])
def test_benchmark_runs(name, tmp_path):
    """The benchmark runs to exit status 0 and prints its headers and rows with finite numbers
    (catches: a crash after an internal change, a row or section no longer printed, a figure
    that became nan or inf)."""
    case = BENCHES[name]
    out = ""
    left = case["timeout"] + COLD_KERNELS
    for args in case["runs"]:
        args = [a.format(tmp=tmp_path) for a in args]
        t0 = time.monotonic()
        code, stdout, stderr = run_script(name, args, left)
        left -= time.monotonic() - t0
        print(f"$ python benchmarks/{name}.py {' '.join(args)}\n{stdout}")
        assert code == 0, f"{name} {' '.join(args)}: exit status {code}\n{stdout[-3000:]}\n{stderr[-5000:]}"
        out += stdout
    missing = [p for p in case["expect"] if not re.search(p, out, re.MULTILINE)]
    assert not missing, f"{name}: no line matches {missing}\n{out[-5000:]}"
    bad = re.findall(r"^.*\b(?:nan|inf)\b.*$", out, re.MULTILINE | re.IGNORECASE)
    assert not bad, f"{name}: a figure is not finite: {bad}"
