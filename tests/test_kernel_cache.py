"""The compiled kernels' on-disk cache: safe under concurrent first runs, never stale, never
damaged code (flexgear.kernels)."""
import contextlib
import gc
import os
import subprocess
import sys
import json
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest

from flexgear import kernels
from flexgear.dynamics.integrator import hht


def cache_file_class():
    """The cache-file class the package's kernels write through."""
    return type(hht.predict._cache._cache_file)


class Key(tuple):
    """A cache key as numba builds it: (signature, target, code hashes)."""


def test_every_kernel_uses_the_shared_cache():
    import flexgear.dynamics.integrator.simulation  # noqa: F401  (declares most kernels)

    assert kernels.KERNELS
    for d in kernels.KERNELS:
        assert isinstance(d._cache, kernels.KernelCache), d.py_func.__qualname__


def test_an_outer_compile_collects_garbage_less_often_and_gives_the_thresholds_back(monkeypatch):
    """While a kernel compiles (or loads) outermost, each of Python's collector thresholds is at
    least COMPILE_GC_THRESHOLD's (numba's typing allocates millions of short-lived objects);
    afterwards (when the last of overlapping blocks ends), also after an error, the process has
    its own thresholds again, a user's higher one untouched. Which wrong code passes: none that
    leaves the raised thresholds behind, gives them back while another compile runs, lowers a
    higher one, or compiles with the defaults."""
    old = gc.get_threshold()
    seen = []
    real = kernels.compile_gc

    @contextlib.contextmanager
    def recording():
        with real():
            seen.append(gc.get_threshold())
            yield

    try:
        mine = (500, 200, 5)
        gc.set_threshold(*mine)
        raised = tuple(max(a, b) for a, b in zip(mine, kernels.COMPILE_GC_THRESHOLD))
        assert raised[0] > mine[0] and raised[1] == mine[1]
        with kernels.compile_gc():
            assert gc.get_threshold() == raised and gc.isenabled()
            with kernels.compile_gc():  # another thread's compile overlapping this one
                pass
            assert gc.get_threshold() == raised  # given back only when the last block ends
        assert gc.get_threshold() == mine
        with pytest.raises(RuntimeError), kernels.compile_gc():
            raise RuntimeError("a failed compile")
        assert gc.get_threshold() == mine
        monkeypatch.setattr(kernels, "compile_gc", recording)
        assert hht.hht_coefficients(np.float32(-0.25)) == pytest.approx((0.390625, 0.75))  # a new signature
        assert seen == [raised]  # one outer compile, with the raised thresholds
        assert gc.get_threshold() == mine
    finally:
        gc.set_threshold(*old)


def test_racing_saves_of_two_signatures_never_mix_their_code(tmp_path, monkeypatch):
    """Two processes saving different overloads of one kernel at once. numba's numbered index
    breaks when the file replacements interleave as index A, index B, data B, data A: the index
    then maps B's signature to A's code (numba issues 4807, 10128), and the next run crashes.
    The replacements are forced into that order here; the cache must give each key its own
    data or nothing."""
    cls = cache_file_class()
    if cls is getattr(kernels, "CacheFile", None):
        files = {w: kernels.CacheFile(str(tmp_path), "kern-1.py311", lambda: "d" * 64) for w in "AB"}
    else:  # numba's own index file (the package before the fix)
        files = {w: cls(cache_path=str(tmp_path), filename_base="kern-1.py311", source_stamp="s") for w in "AB"}
    schedule = [("A", "index"), ("B", "index"), ("B", "data"), ("A", "data")]
    done = [threading.Event() for _ in schedule]
    arrived = {w: threading.Event() for w in "AB"}
    real_replace = os.replace

    def forced_replace(src, dst, *args, **kw):
        me = threading.current_thread().name
        if not arrived[me].is_set():  # both have read the index before either writes
            arrived[me].set()
            arrived["B" if me == "A" else "A"].wait(timeout=2)
        kind = "index" if str(dst).endswith(".nbi") else "data"
        mine = [i for i, (w, _) in enumerate(schedule) if w == me and not done[i].is_set()]
        pos = next(i for i in mine if schedule[i][1] == kind)
        for i in mine:
            if i < pos:
                done[i].set()  # this writer has no such step: never wait for it
        for i in range(pos):
            done[i].wait(timeout=2)
        real_replace(src, dst, *args, **kw)
        done[pos].set()

    monkeypatch.setattr(os, "replace", forced_replace)
    key = {"A": Key(("int64", "cpu", "code")), "B": Key(("float64", "cpu", "code"))}
    data = {"A": ("code of A",), "B": ("code of B",)}
    threads = [threading.Thread(target=files[w].save, args=(key[w], data[w]), name=w) for w in "AB"]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=20)
    monkeypatch.setattr(os, "replace", real_replace)
    for w in "AB":
        got = files[w].load(key[w])
        assert got is None or got == data[w], f"the cache gives signature {w} the code {got!r}"


def test_a_damaged_or_foreign_file_is_never_used(tmp_path):
    digest = ["d" * 64]
    cf = kernels.CacheFile(str(tmp_path), "kern-1.py311", lambda: digest[0])
    ka, kb = Key(("int64",)), Key(("float64",))
    cf.save(ka, ("payload A", 1.0))
    assert cf.load(ka) == ("payload A", 1.0)
    pa, pb = cf.path(ka)[0], cf.path(kb)[0]
    assert pa != pb
    pb.write_bytes(pa.read_bytes())          # A's code under B's name: refused
    assert cf.load(kb) is None
    raw = pa.read_bytes()
    pa.write_bytes(raw[:-5])                  # truncated: refused
    assert cf.load(ka) is None
    pa.write_bytes(raw[:-1] + bytes([raw[-1] ^ 1]))  # one bit flipped: refused
    assert cf.load(ka) is None
    pa.write_bytes(b"garbage")
    assert cf.load(ka) is None
    cf.save(ka, ("payload A", 1.0))           # a miss recompiles and rewrites it
    assert cf.load(ka) == ("payload A", 1.0)
    good = pa.read_bytes()
    digest[0] = "0" * 64                      # the kernel's code changed: another name ...
    assert cf.load(ka) is None
    cf.path(ka)[0].write_bytes(good)          # ... and the old file under the new name is refused
    assert cf.load(ka) is None


def test_files_of_other_sources_are_pruned(tmp_path):
    digest = ["d" * 64]
    cf = kernels.CacheFile(str(tmp_path), "kern-1.py311", lambda: digest[0])
    k = Key(("int64",))
    cf.save(k, ("old",))
    old = cf.path(k)[0]
    (tmp_path / "kern-1.py311.nbi").write_bytes(b"numba index")
    (tmp_path / "kern-1.py311.1.nbc").write_bytes(b"numba data")
    (tmp_path / "other-1.py311.nbi").write_bytes(b"not ours")
    digest[0] = "f" * 64
    cf.save(k, ("new",))
    assert not old.exists()
    assert cf.load(k) == ("new",)
    assert not (tmp_path / "kern-1.py311.nbi").exists() and not (tmp_path / "kern-1.py311.1.nbc").exists()
    assert (tmp_path / "other-1.py311.nbi").exists()


def digest_of(tmp_path, name, sources):
    """code_digest of kmain.f with the modules ``sources`` (name -> text) on the path."""
    import importlib

    d = tmp_path / name
    d.mkdir()
    for mod, text in sources.items():
        (d / f"{mod}.py").write_text(textwrap.dedent(text))
    sys.path.insert(0, str(d))
    try:
        for mod in sources:
            sys.modules.pop(mod, None)
        return kernels.code_digest(importlib.import_module("kmain").f.py_func)
    finally:
        sys.path.remove(str(d))
        for mod in sources:
            sys.modules.pop(mod, None)


MAIN = """
    from flexgear.kernels import kernel
    from kdep import SCALE, g
    import kdep

    @kernel()
    def f(x):
        return g(x) * SCALE + kdep.OFFSET
"""
DEP = """
    import numpy as np
    from flexgear.kernels import kernel
    SCALE = {scale}
    OFFSET = {offset}

    @kernel({opts})
    def g(x):
        return x + {inc}

    def unrelated():
        return {unrelated}
"""


def test_the_digest_follows_what_a_kernel_is_compiled_from(tmp_path):
    """numba checks a cached kernel only against its own file; the digest in the cache name also
    changes with a constant it imports, a kernel it calls in another module (its code or its
    compile options), and a constant read as module.attribute, and not with code the kernel does
    not use."""
    base = dict(scale=2.0, offset=1, inc=1, unrelated=0, opts="")

    def digest(tag, **change):
        return digest_of(tmp_path, tag, {"kmain": MAIN, "kdep": DEP.format(**(base | change))})

    ref = digest("ref")
    assert digest("same") == ref
    assert digest("unrelated", unrelated=5) == ref
    assert digest("scale", scale=3.0) != ref
    assert digest("offset", offset=2) != ref
    assert digest("callee", inc=2) != ref
    assert digest("options", opts="fastmath=True") != ref  # a callee compiled with other flags
    assert digest("np1", offset="np.int64(1)") != digest("np2", offset="np.int64(2)")  # a numpy scalar


SET_KERNELS = textwrap.dedent('''
    from flexgear.kernels import kernel

    @kernel(fastmath={"reassoc", "contract", "arcp", "nsz"})
    def option_set(x):
        return x

    @kernel()
    def constant_set(k):
        return k in {"alpha", "beta", "gamma", "delta"}  # a frozenset constant of strings
''')


def test_every_kernels_digest_is_the_same_in_every_process(tmp_path):
    """A cached kernel is found again only if its digest is: two fresh processes with different
    hash seeds (the order of a set of strings differs between them: a fastmath option set, a
    frozenset constant) give every kernel the same digest, the package's and two made for it."""
    (tmp_path / "ksets.py").write_text(SET_KERNELS)
    script = ("import sys, json, flexgear.dynamics.integrator.simulation, flexgear.dynamics.lumped.time_loop, "
              f"flexgear.gears.tribology\nsys.path.insert(0, {str(tmp_path)!r})\nimport ksets\n"
              "from flexgear import kernels\n"
              "print(json.dumps({f'{d.py_func.__module__}.{d.py_func.__qualname__}': "
              "kernels.code_digest(d.py_func) for d in kernels.KERNELS}))")
    runs = [json.loads(subprocess.run([sys.executable, "-c", script], env=dict(os.environ, PYTHONHASHSEED=seed),
                                      capture_output=True, text=True, check=True).stdout) for seed in "123"]
    assert len(runs[0]) > 100 and "ksets.constant_set" in runs[0]
    assert [k for k in runs[0] if not runs[0][k] == runs[1].get(k) == runs[2].get(k)] == []


KERNEL_MODULE = textwrap.dedent('''
    import numpy as np
    from flexgear.kernels import kernel

    @kernel(error_model="numpy")
    def affine(x, a):
        return a * x + 1

    @kernel(error_model="numpy")
    def total(v):
        s = v.ravel()[0] * 0
        for e in v.ravel():
            s += e * e
        return affine(s, 2)
''')

WORKER = textwrap.dedent('''
    import sys, json
    import numpy as np
    sys.path.insert(0, sys.argv[1])
    import kmod
    kind = sys.argv[2]
    args = {"int": (np.int64(3), np.int64(5)), "float": (2.5, 0.5), "complex": (1 + 2j, 3j),
            "i1": np.arange(7), "f2": np.linspace(0.0, 1.0, 12).reshape(3, 4)}
    out = []
    for k in kind.split(","):
        a = args[k]
        r = kmod.affine(*a) if isinstance(a, tuple) else kmod.total(a)
        out.append(str(r))
    hits = sum(sum(d.stats.cache_hits.values()) for d in (kmod.affine, kmod.total))
    misses = sum(sum(d.stats.cache_misses.values()) for d in (kmod.affine, kmod.total))
    from flexgear.kernels import compile_counts
    signatures = sum(len(d.signatures) for d in (kmod.affine, kmod.total))
    print(json.dumps({"out": out, "hits": hits, "misses": misses, "counts": compile_counts(),
                      "signatures": signatures}))
''')

EXPECTED = {"int": str(3 * 5 + 1), "float": str(2.5 * 0.5 + 1), "complex": str((1 + 2j) * 3j + 1),
            "i1": str(2 * int((np.arange(7) ** 2).sum()) + 1),
            "f2": str(2 * float((np.linspace(0.0, 1.0, 12) ** 2).sum()) + 1)}


def run_workers(src, cache, kinds):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    procs = [subprocess.Popen([sys.executable, "-c", WORKER, str(src), k], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for k in kinds]
    results = []
    for p in procs:
        out, err = p.communicate(timeout=600)
        assert p.returncode == 0, f"worker crashed (exit {p.returncode}):\n{err[-2000:]}"
        results.append(json.loads(out.strip().splitlines()[-1]))
    return results


def test_concurrent_first_runs_with_different_specialisations(tmp_path):
    """Processes that compile different signatures of the same kernels at once on an empty
    cache, then every signature again: no crash, the right results, loaded from the cache."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "kmod.py").write_text(KERNEL_MODULE)
    kinds = ["int,i1", "float", "complex,i1"]
    cache = tmp_path / "cache"
    first = run_workers(src, cache, kinds)
    for k, r in zip(kinds, first):
        assert r["out"] == [EXPECTED[x] for x in k.split(",")]
    every = "int,float,complex,i1,f2"
    again = run_workers(src, cache, [every, every])
    for r in again:
        assert r["out"] == [EXPECTED[x] for x in every.split(",")]
    # f2 (total of a 2-D array, and affine(float, int) inside it) is new: compiled once, by one
    # process, while the other waits for the lock and then loads it
    assert sum(r["misses"] for r in again) == 2
    # every overload compiled or loaded is counted once, nested ones too (total(f2) calls
    # affine(float, int)); the time is the outermost calls' (not more than the process ran)
    assert all(r["counts"]["overloads"] == r["signatures"] > 0 for r in first + again)
    assert all(0 < r["counts"]["seconds"] and r["counts"]["waited"] <= r["counts"]["seconds"] for r in first + again)
    assert not list(Path(cache).rglob("*.tmp.*")), "no temporary file is left behind"


STATE = textwrap.dedent('''
    import sys, json
    import numpy as np
    sys.path.insert(0, sys.argv[1])
    import kmod
    from flexgear.kernels import overload_state
    before = [overload_state(kmod.affine, a) for a in ((2.5, 0.5), (np.int64(3), np.int64(5)))]
    kmod.affine(2.5, 0.5)
    after = overload_state(kmod.affine, (2.5, 0.5))
    print(json.dumps({"before": before, "after": after}))
''')


def test_a_run_can_tell_before_the_call_whether_its_overload_compiles_loads_or_is_ready(tmp_path):
    """What `flexgear run` says before its wait: an overload neither in the process nor on disk
    compiles; once compiled it is ready in that process and cached for the next one, while
    another signature of the same kernel still compiles (a rigid run with friction, or a
    flexible one, is another overload of the same time loop)."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "kmod.py").write_text(KERNEL_MODULE)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    runs = [json.loads(subprocess.run([sys.executable, "-c", STATE, str(src)], env=env, capture_output=True,
                                      text=True, check=True, timeout=600).stdout) for _ in range(2)]
    assert runs[0] == {"before": ["compile", "compile"], "after": "compiled"}
    assert runs[1] == {"before": ["cached", "compile"], "after": "compiled"}


HOLDER = textwrap.dedent('''
    import sys
    sys.path.insert(0, sys.argv[1])
    import kmod
    from numba import types
    from flexgear import kernels
    sig = tuple(getattr(types, t) for t in sys.argv[3].split(","))
    lock = kernels.compile_lock(kernels.lock_file(getattr(kmod, sys.argv[2]), sig))
    lock.acquire()
    print("held", flush=True)
    sys.stdin.read()  # until the test closes it
    lock.release()
''')


def test_a_waiting_process_loads_what_the_first_compiled(tmp_path):
    """While another process holds a kernel's compile lock, a process that needs that kernel
    waits, then loads instead of compiling; one that needs only another kernel does not wait."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "kmod.py").write_text(KERNEL_MODULE)
    cache = tmp_path / "cache"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    run_workers(src, cache, ["float"])  # affine(float, float) compiled and cached
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(src), "affine", "int64,int64"], env=env,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        files = set(cache.rglob("*.fgk"))
        p = subprocess.Popen([sys.executable, "-c", WORKER, str(src), "int"], env=env, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        notice = p.stderr.readline()  # blocks until the worker reports that it waits
        assert "waiting for another process compiling the kernels (affine" in notice, notice
        assert set(cache.rglob("*.fgk")) == files, "nothing is compiled while the lock is held"
    finally:
        holder.stdin.close()
        holder.wait(timeout=60)
    out, err = p.communicate(timeout=600)
    assert p.returncode == 0 and EXPECTED["int"] in out, err
    first = json.loads(out.strip().splitlines()[-1])
    assert first["misses"] == 1 and first["counts"]["waited"] > 1.0  # compiled once, after the wait


def test_a_held_lock_of_one_signature_does_not_stop_another_signature_compiling(tmp_path):
    """The rigid and flexible solvers are two signatures of the same kernels: a process that
    compiles one signature (its lock held) does not hold up another that compiles a different
    one. A lock per kernel serialised them (a test session's flexible warm-up waited for the
    whole rigid compile)."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "kmod.py").write_text(KERNEL_MODULE)
    cache = tmp_path / "cache"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(src), "affine", "int64,int64"], env=env,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        p = subprocess.Popen([sys.executable, "-c", WORKER, str(src), "float"], env=env, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        try:
            out, err = p.communicate(timeout=120)  # with the other signature's lock shared: waits until killed
        except subprocess.TimeoutExpired:
            p.kill()
            out, err = p.communicate()
        assert p.returncode == 0, err[-2000:]
        r = json.loads(out.strip().splitlines()[-1])
        assert r["out"] == [EXPECTED["float"]] and r["misses"] == 1 and r["counts"]["waited"] < 1.0
    finally:
        holder.stdin.close()
        holder.wait(timeout=60)


def test_a_held_lock_of_one_kernel_does_not_stop_another_from_loading(tmp_path):
    """A process compiling one kernel (its lock held) does not hold up another process loading
    a different, cached kernel: with one global lock a long compile stopped every other process
    of a batch or a test session from even loading its kernels."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "kmod.py").write_text(KERNEL_MODULE)
    cache = tmp_path / "cache"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    run_workers(src, cache, ["i1"])  # total(int array) and affine(int, int) cached
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(src), "affine", "int64,int64"], env=env,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        (r,) = run_workers(src, cache, ["i1"])  # total loads its cached code (affine inside it)
        assert r["out"] == [EXPECTED["i1"]] and r["misses"] == 0 and r["counts"]["waited"] < 1.0
    finally:
        holder.stdin.close()
        holder.wait(timeout=60)


@pytest.mark.slow
def test_two_models_compiled_at_once_on_an_empty_cache_equal_a_serial_build(tmp_path):
    """Two presets with different specialisations of the shared kernels (rigid and flexible
    spur pair), first run at once on an empty cache, then each again: all equal a serial build."""
    script = textwrap.dedent('''
        import sys, numpy as np, flexgear
        cfg = flexgear.load_config(sys.argv[1]); cfg.simulation["duration"] = 0.01; cfg.simulation["run_in"] = 0.0
        r = flexgear.run(cfg)
        np.save(sys.argv[2], r.meshes["pinion-wheel"].normal_force)
    ''')
    presets = ["spur_pair", "spur_pair_flexible"]

    def batch(cache, tag, together):
        env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), FLEXGEAR_CACHE_DIR=str(tmp_path / "fg"))
        cmds = [[sys.executable, "-c", script, p, str(tmp_path / f"{tag}-{p}.npy")] for p in presets]
        if together:
            procs = [subprocess.Popen(c, env=env, stderr=subprocess.PIPE, text=True) for c in cmds]
            for p in procs:
                _, err = p.communicate(timeout=3600)
                assert p.returncode == 0, err[-2000:]
        else:
            for c in cmds:
                subprocess.run(c, env=env, check=True, capture_output=True, timeout=3600)

    batch(tmp_path / "serial", "serial", together=False)
    batch(tmp_path / "shared", "first", together=True)
    batch(tmp_path / "shared", "again", together=True)
    for p in presets:
        ref = np.load(tmp_path / f"serial-{p}.npy")
        for tag in ("first", "again"):
            assert np.array_equal(np.load(tmp_path / f"{tag}-{p}.npy"), ref), (tag, p)


PARALLEL_MODULE = textwrap.dedent('''
    import numba as nb
    from flexgear.kernels import kernel

    @kernel(error_model="numpy", parallel=True)
    def scale_all(x):
        for i in nb.prange(x.shape[0]):
            x[i] = 2.0 * x[i] + 1.0

    @kernel(error_model="numpy", _nrt=False)
    def middle(x):
        scale_all(x)
        s = 0.0
        for i in range(x.shape[0]):
            s += x[i]
        return s

    @kernel(error_model="numpy")
    def outer(x):
        return middle(x) + 1.0
''')

PARALLEL_STEP = textwrap.dedent('''
    import sys, json
    import numpy as np, numba
    sys.path.insert(0, sys.argv[1])
    import pmod
    out = None
    for step in sys.argv[2].split(","):
        x = np.arange(8.0)
        if step == "compile-middle":
            pmod.middle.compile((numba.typeof(x),))
        else:
            out = getattr(pmod, step)(x)
    print(json.dumps({"out": out, "misses": {k: sum(getattr(pmod, k).stats.cache_misses.values())
                                            for k in ("scale_all", "middle", "outer")}}))
''')


@pytest.mark.parametrize("first", ["compile-middle", "middle"])
def test_a_caller_compiled_after_its_parallel_callee_was_cached_is_safe_to_load(tmp_path, first):
    """A kernel calling a parallel=True kernel (through another) is compiled in one process;
    another process then compiles its caller, the callee taken from the disk cache
    (``compile-middle``) or loaded and run there first (``middle``); a third process loads that
    caller and runs it. numba alone leaves a cached caller that crashes every later process
    (numba issues 8578, 4807): the caller must be compiled with its callees compiled
    afresh in its process, a loaded one too (not counted as a miss), and then saved."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "pmod.py").write_text(PARALLEL_MODULE)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    expected = float((2.0 * np.arange(8.0) + 1.0).sum() + 1.0)
    runs = []
    for steps in ("compile-middle", "outer", "outer") if first == "compile-middle" else ("middle", "middle,outer", "outer"):
        p = subprocess.run([sys.executable, "-c", PARALLEL_STEP, str(src), steps], env=env, capture_output=True,
                           text=True, timeout=600)
        assert p.returncode == 0, f"{steps}: exit {p.returncode}\n{p.stderr[-2000:]}"
        runs.append(json.loads(p.stdout.strip().splitlines()[-1]))
    assert runs[1]["out"] == expected and runs[2]["out"] == expected
    if first == "compile-middle":  # middle compiled afresh inside outer, outer saved and then loaded
        assert runs[1]["misses"] == {"scale_all": 1, "middle": 1, "outer": 1}
        assert runs[2]["misses"] == {"scale_all": 0, "middle": 0, "outer": 0}
    else:  # middle loaded and run before outer was compiled: compiled again for outer, outer saved
        assert runs[1]["misses"] == {"scale_all": 1, "middle": 0, "outer": 1}
        assert runs[2]["misses"] == {"scale_all": 0, "middle": 0, "outer": 0}


TABLE_MODULE = """
    from collections import namedtuple
    from flexgear.kernels import kernel

    @kernel()
    def first(t):
        return t.x

    T = namedtuple("T", {fields!r})
"""


def test_a_table_whose_same_typed_fields_were_reordered_is_a_miss(tmp_path, monkeypatch):
    """numba names a named tuple's type by its class name and field types: swapping two fields of
    one type keeps the kernel's bytecode and that name. The cache key also holds the field names,
    so the kernel compiled for the old layout is not loaded for the new one."""
    import importlib

    import numba

    monkeypatch.setattr(numba.config, "CACHE_DIR", "")  # the cache beside the module, also under NUMBA_CACHE_DIR
    sys.path.insert(0, str(tmp_path))
    try:
        for fields in ("x y", "y x"):
            (tmp_path / "ktable.py").write_text(textwrap.dedent(TABLE_MODULE.format(fields=fields)))
            sys.modules.pop("ktable", None)
            importlib.invalidate_caches()
            mod = importlib.import_module("ktable")
            assert mod.first(mod.T(x=1.0, y=2.0)) == 1.0, fields
        assert len(list((tmp_path / "__pycache__").glob("ktable.first-*.fgk"))) == 2
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("ktable", None)


FASTMATH_MODULE = textwrap.dedent('''
    from flexgear.kernels import kernel

    @kernel(error_model="numpy", _nrt=False, fastmath={"reassoc", "contract"})
    def dot(a, b, n):
        s = 0.0
        for i in range(n):
            s += a[i] * b[i]
        return s

    @kernel(error_model="numpy", _nrt=False)
    def outer(a, b):
        t = 0.0
        for k in range(a.shape[0] - 8):
            t += dot(a[k:], b, 8) * 1e-3 + dot(a, b[k:], 5)
        return t
''')

FASTMATH_STEP = textwrap.dedent('''
    import sys, json
    import numpy as np
    sys.path.insert(0, sys.argv[1])
    import fmod
    a = np.sin(np.arange(40.0) * 0.7) * 1e3 + 1.0 / 3.0
    b = np.cos(np.arange(40.0) * 1.3) / 7.0
    out = {}
    for step in sys.argv[2].split(","):
        if step == "dot":
            out["dot"] = fmod.dot(a, b, 40)
        else:
            out["outer"] = fmod.outer(a, b)
            cres = fmod.outer.overloads[fmod.outer.signatures[0]]
            out["ir"] = cres.library.get_llvm_str()  # empty if outer was loaded
    out["misses"] = {k: sum(getattr(fmod, k).stats.cache_misses.values()) for k in ("dot", "outer")}
    print(json.dumps(out))
''')


def fmod_steps(tmp_path, module: str):
    """``step(cache, steps)``: run FASTMATH_STEP's steps on ``module`` (as fmod) in a fresh
    process with the numba cache ``tmp_path / cache`` and a fixed hash seed; its JSON output."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "fmod.py").write_text(module)

    def step(cache, steps):
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / cache), PYTHONHASHSEED="1")
        p = subprocess.run([sys.executable, "-c", FASTMATH_STEP, str(src), steps], env=env, capture_output=True,
                           text=True, timeout=600, check=False)
        assert p.returncode == 0, f"{steps}: exit {p.returncode}\n{p.stderr[-2000:]}"
        return json.loads(p.stdout.strip().splitlines()[-1])

    return step


@pytest.mark.parametrize("fill", ["nested", "earlier"])
def test_a_caller_compiled_after_its_callee_was_cached_equals_a_serial_build(tmp_path, fill):
    """A fastmath kernel is compiled and cached by one process; another compiles its caller, the
    callee taken from the disk cache inside the caller's compile (``nested``) or loaded by a call
    of its own first (``earlier``). The caller's code must be the serial build's, symbol for
    symbol: it links its callees' code into its own, and a copy compiled by another process
    (other function numbers, another hash order of the fastmath flags) made the flexible
    model's fastmath sums round differently after some fill orders of a shared cache. Which
    wrong code passes: none that links a callee loaded from the disk cache into a new caller."""
    step = fmod_steps(tmp_path, FASTMATH_MODULE)
    serial = step("serial", "outer")
    step("shared", "dot")
    dirty = step("shared", "outer" if fill == "nested" else "dot,outer")
    assert dirty["misses"]["outer"] == 1 and "dot" in dirty["ir"]
    assert dirty["outer"] == serial["outer"]
    assert dirty["ir"] == serial["ir"], "the caller's code differs from the serial build's"
    again = step("shared", "outer")  # saved: loaded, nothing compiled
    assert again["misses"] == {"dot": 0, "outer": 0} and again["outer"] == serial["outer"]


@pytest.mark.parametrize("flags", ["inherited", "own"])
def test_a_callee_compiled_with_its_callers_flags_is_not_saved_as_its_own(tmp_path, flags):
    """A process compiles a caller only; a later process calls the callee alone. ``inherited``:
    the callee sets no fastmath and the caller does, so numba compiled it fastmath for the caller
    (flags a callee does not set are its caller's): that compile is not saved, the later process
    compiles the callee (a miss) and gets the serial build's value. ``own``: the callee sets its
    own flags, its compile for the caller is its own code, saved and loaded. The caller is saved
    and loaded either way. Which wrong code passes: none that saves a compile under inherited
    flags as the kernel's own (the lumped friction loop's LU solve, saved so, rounded otherwise
    than the solve compiled alone: tests/test_compliant_kernel.py's bit-for-bit check of the LU
    inverse failed after that fill order), nor one that never saves a callee."""
    fast = ', fastmath={"reassoc", "contract"}'
    module = FASTMATH_MODULE
    if flags == "inherited":  # the fastmath moves from the callee to its caller
        dot, outer = FASTMATH_MODULE.split("\n\n@kernel")[1:]
        module = ("from flexgear.kernels import kernel\n\n@kernel" + dot.replace(fast, "")
                  + "\n\n@kernel" + outer.replace("_nrt=False)", f"_nrt=False{fast})"))
        assert module.count("fastmath") == 1 and "def dot" in module and "def outer" in module
    step = fmod_steps(tmp_path, module)
    serial = step("serial", "dot")
    first = step("shared", "outer")
    assert first["misses"] == {"dot": 1, "outer": 1}
    alone = step("shared", "dot,outer")
    assert alone["misses"] == {"dot": int(flags == "inherited"), "outer": 0}
    assert alone["dot"] == serial["dot"] and alone["outer"] == first["outer"]


@pytest.mark.parametrize("caller", ["exact", "fastmath"])
def test_an_exact_callee_is_loaded_only_into_a_caller_without_fastmath(tmp_path, caller):
    """A callee free of fastmath and parallel loops (and so is all it calls) is loaded from the
    disk cache inside a caller free of fastmath: IEEE arithmetic fixes its results whatever the
    caller's module makes of it, so the contact search compiles once for the rigid and flexible
    solvers. Inside a fastmath caller it is compiled afresh, as a fastmath callee always is.
    Which wrong code passes: none that compiles every callee afresh (the first case) or loads
    one into fastmath code (the second)."""
    fast = ', fastmath={"reassoc", "contract"}' if caller == "fastmath" else ""
    dot, outer = FASTMATH_MODULE.split("\n\n@kernel")[1:]
    module = ("from flexgear.kernels import kernel\n\n@kernel" + dot.replace(', fastmath={"reassoc", "contract"}', "")
              + "\n\n@kernel" + outer.replace("_nrt=False)", f"_nrt=False{fast})"))
    assert module.count("fastmath") == (caller == "fastmath") and "def dot" in module and "def outer" in module
    step = fmod_steps(tmp_path, module)
    serial = step("serial", "outer")
    step("shared", "dot")
    shared = step("shared", "outer")
    assert shared["misses"] == {"dot": int(caller == "fastmath"), "outer": 1}
    assert shared["outer"] == serial["outer"]


def test_exact_tree_follows_every_call():
    """Which kernels may be loaded inside a caller: the contact search and the Hertz law are
    exact all the way down; the force kernel is not (it calls the flexible contact solve, whose
    sums are fastmath), nor is the lumped time loop (fastmath itself)."""
    import flexgear.dynamics.integrator.simulation  # noqa: F401  (declares most kernels)
    from flexgear.dynamics.contact import laws, search
    from flexgear.dynamics.flexible import compliant
    from flexgear.dynamics.integrator import forces
    from flexgear.dynamics.lumped import time_loop

    assert kernels.exact_tree(search.mesh_search.py_func) and kernels.exact_tree(laws.hertz_force.py_func)
    assert not kernels.exact_tree(compliant.compliant_contacts.py_func)
    assert not kernels.exact_tree(forces.forces.py_func) and not kernels.exact_tree(time_loop.integrate_lumped.py_func)


@pytest.mark.parametrize("callee", ["inherits", "inline", "own"])
def test_a_kernel_taking_result_flags_from_a_caller_must_set_its_own(tmp_path, monkeypatch, callee):
    """numba keeps one overload per signature in a process, so a callee that takes fastmath from
    one caller serves every later caller and Python's calls with that code: the lumped friction
    loop (fastmath) compiling the LU solve first would make a rigid solver compiled later in the
    same process, and the cache it saves, round otherwise than a serial build. The rule: such a
    callee sets its flags itself. Toy module: ``dot`` without flags under a fastmath ``outer`` is
    reported (``inherits``); inlined into it, or with its own fastmath, it is not. Which wrong
    code passes: none that misses a callee compiled under other flags, or reports one that
    cannot be (the second and third cases)."""
    dot, outer = FASTMATH_MODULE.split("\n\n@kernel")[1:]
    dot = dot.replace('_nrt=False, fastmath={"reassoc", "contract"})',
                      {"inherits": "_nrt=False)", "inline": '_nrt=False, inline="always")',
                       "own": "_nrt=False, fastmath=False)"}[callee])
    outer = outer.replace("_nrt=False)", "_nrt=False, fastmath=True)")
    (tmp_path / "flagmod.py").write_text("from flexgear.kernels import kernel\n\n@kernel" + dot + "\n\n@kernel" + outer)
    monkeypatch.setattr(kernels, "KERNELS", [])
    monkeypatch.syspath_prepend(str(tmp_path))
    import flagmod  # noqa: F401  (declares the two kernels)

    assert len(kernels.KERNELS) == 2
    expected = ["flagmod.dot: fastmath from outer"] if callee == "inherits" else []
    assert kernels.inherited_flag_conflicts() == expected
    sys.modules.pop("flagmod")


def test_no_kernel_of_the_package_takes_result_flags_from_a_caller():
    """:func:`flexgear.kernels.inherited_flag_conflicts` over every kernel of the package (the
    LU solve and the squeeze film's damping under the fastmath lumped loops, the lumped mesh
    tables under its numpy error model, set their own). Fails if one of them loses its flag."""
    import importlib
    import pkgutil

    import flexgear

    for module in pkgutil.walk_packages(flexgear.__path__, "flexgear."):
        importlib.import_module(module.name)
    assert kernels.inherited_flag_conflicts() == []


COMPILING_PROBE = """
import sys, threading, time
sys.path.insert(0, sys.argv[1])
from flexgear.kernels import compiling
seen, done = [], threading.Event()

def poll():
    while not done.is_set():
        seen.append(compiling())
        time.sleep(0.0005)

t = threading.Thread(target=poll)
t.start()
import kmain
kmain.f(1.0)
done.set()
t.join()
print(any(seen), compiling())
"""


def test_compiling_says_whether_the_kernel_compiles_or_loads(tmp_path):
    """flexgear.kernels.compiling(), which the plain progress lines read while the solver is
    loaded or compiled (a run cannot tell ahead whether the cache holds this model's solver, or
    another's only): True while a kernel that missed the disk cache compiles, never while one is
    loaded from it, and False once the call returns."""
    d = tmp_path / "mods"
    d.mkdir()
    (d / "kmain.py").write_text(textwrap.dedent(MAIN))
    (d / "kdep.py").write_text(textwrap.dedent(DEP.format(scale=2.0, offset=0.5, opts="", inc=1.0, unrelated=0)))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    said = [subprocess.run([sys.executable, "-c", COMPILING_PROBE, str(d)], env=env, capture_output=True, text=True,
                           timeout=300) for _ in range(2)]
    assert [p.stdout.split() for p in said] == [["True", "False"], ["False", "False"]], [p.stderr[-1500:] for p in said]
