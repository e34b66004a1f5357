"""The one way flexgear declares a compiled kernel: ``@kernel(...)``, numba's ``njit`` with an
on-disk cache that concurrent processes can share.

numba's own cache numbers a kernel's compiled overloads in an index file; two processes that
compile different signatures of one kernel at once both take number 1, and the index of one
then points at the code of the other (numba issues 4807 and 10128): every later run crashes.
It also checks a kernel only against its own file, so a kernel that inlines code from another
module runs stale code after that module changes. The cache here instead

- names each compiled overload by a hash of its key (signature with the field names of its
  tables, target CPU) and of everything it is compiled from (:func:`code_digest`: its
  bytecode, the constants it reads, the kernels it calls), so a file can only ever hold the
  code of its name, and a changed source or table layout is a miss, never stale code;
- writes a file atomically (temporary file, then rename) with a SHA-256 checksum of its
  payload, and uses it only if the name, the key, the digest and the checksum all match;
- compiles and loads each overload under an inter-process lock of its own (``filelock``), so a
  second process waits for the first's compilation of that overload and then loads it instead
  of compiling the same code again, while other kernels, and other signatures of the same
  kernel, load or compile meanwhile.

A caller is compiled against callees compiled in the same process, except callees whose whole
call tree is exact (no fastmath, no ``parallel=True``) inside a caller without fastmath, which it
may load from the disk cache (:meth:`KernelDispatcher.compile`), and a callee compiled with a
flag its caller passed down (numba's fastmath and error model, when the callee sets none) is not
saved as the callee's own code (:func:`inherits_other_results`): either way results do not
depend on which process filled the cache with what, and when.

``numba.config.DISABLE_JIT`` leaves the functions as plain Python.
"""
from __future__ import annotations

import contextlib
import gc
import hashlib
import json
import os
import pickle
import sys
import threading
import time
import types
import uuid
from pathlib import Path

import filelock
import llvmlite
import numba
import numpy as np
from numba.core import config as numba_config, sigutils, types as numba_types
from numba.core.caching import FunctionCache
from numba.core.compiler_lock import global_compiler_lock
from numba.core.dispatcher import Dispatcher
from numba.core.registry import CPUDispatcher
from numba.core.serialize import dumps

PACKAGE_DIR = Path(__file__).resolve().parent
FORMAT = b"flexgear-kernel-cache 1\n"
WAIT_NOTICE_S = 2.0  # tell the user after waiting this long for another process's compile
#: Python's cyclic garbage collector's thresholds while a kernel compiles (:func:`compile_gc`):
#: numba's typing and lowering allocate millions of short-lived objects, and with the default
#: thresholds (700, 10, 10) the collector keeps walking the interpreter's whole heap (cost in
#: docs/performance.md)
COMPILE_GC_THRESHOLD = (100000, 50, 100)
STALE_TMP_S = 3600.0  # temporary files older than this are left-overs of a killed process

#: Every dispatcher declared with ``@kernel``, in declaration order.
KERNELS: list = []
_digests: dict[int, str] = {}
_options: dict[int, str] = {}  # a kernel's compile options (fastmath, inline, ...) by id of its function
_inexact: set = set()  # ids of the functions of kernels compiled with fastmath or parallel=True
_exact: dict[int, bool] = {}  # exact_tree's answers by id of a kernel's function
_locks: dict[str, filelock.FileLock] = {}
_BASE = f"{sys.version}|{numba.__version__}|{llvmlite.__version__}|{np.__version__}"
_stack: list = []  # the kernels being compiled in this process, outermost first (callees compile inside)
_loaded: set = set()  # (id of a kernel, argument types) of overloads loaded from disk, not compiled here
_clock = {"seconds": 0.0, "waited": 0.0, "overloads": 0, "told": False,  # told: the wait notice, once
          "compiling": False}  # an outermost kernel missed the disk cache and compiles now


def compile_seconds() -> float:
    """Wall time [s] this process has spent compiling kernels or loading them from the disk
    cache (outermost calls only), including any wait for another process's compilation."""
    return _clock["seconds"]


def compiling() -> bool:
    """Whether this process is compiling a kernel now: the outermost kernel of the current call
    missed the disk cache (loading one takes about a second; compiling the solver minutes). For
    a progress line written while the solver is loaded or compiled, from another thread."""
    return _clock["compiling"]


def compile_counts() -> dict:
    """``{"seconds", "waited", "overloads"}``: time in compile calls, of it the wait for the
    lock [s], and the number of overloads compiled or loaded in this process."""
    return {k: _clock[k] for k in ("seconds", "waited", "overloads")}


def _stable_repr(value) -> str:
    """``repr`` that is the same in every process: a set's elements sorted (their iteration
    order follows the process's hash seed)."""
    if isinstance(value, (set, frozenset)):
        return "{" + ", ".join(sorted(_stable_repr(v) for v in value)) + "}"
    if isinstance(value, tuple):
        return "(" + ", ".join(_stable_repr(v) for v in value) + ")"
    return repr(value)


def _describe(value, seen: frozenset) -> str:
    """What a global referenced by a kernel contributes to its compiled code."""
    if isinstance(value, Dispatcher):
        return "kernel " + code_digest(value.py_func, seen)
    if isinstance(value, types.FunctionType):
        return "function " + code_digest(value, seen)
    if isinstance(value, types.ModuleType):
        return "module " + value.__name__
    if isinstance(value, (bool, int, float, complex, str, bytes, type(None), np.generic, np.dtype)):  # frozen constants
        return f"{type(value).__name__} {value!r}"
    if isinstance(value, tuple):
        return "(" + ", ".join(_describe(v, seen) for v in value) + ")"
    if isinstance(value, np.ndarray):  # numba freezes a global array into the code
        return f"array {value.dtype} {value.shape} {hashlib.sha256(value.tobytes()).hexdigest()}"
    if isinstance(value, type):  # a table's fields, a class's constants
        consts = sorted((k, v) for k, v in vars(value).items()
                        if not k.startswith("__") and isinstance(v, (bool, int, float, str, tuple)))
        return f"type {value.__module__}.{value.__qualname__} {getattr(value, '_fields', '')} {consts!r}"
    return f"object {type(value).__module__}.{type(value).__qualname__}"


def _walk_code(code, globs: dict, h, seen: frozenset) -> None:
    h.update(code.co_code)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            _walk_code(c, globs, h, seen)
        else:
            h.update(_stable_repr(c).encode())
    modules = [v for n in code.co_names if isinstance(v := globs.get(n), types.ModuleType)]
    for name in code.co_names:
        if name in globs:
            h.update(f"{name}={_describe(globs[name], seen)};".encode())
        for m in modules:  # module.attribute
            if name in vars(m) and not isinstance(vars(m)[name], types.ModuleType):
                h.update(f"{m.__name__}.{name}={_describe(vars(m)[name], seen)};".encode())


def code_digest(fn, seen: frozenset = frozenset()) -> str:
    """SHA-256 of what a kernel is compiled from: its bytecode and constants, the values of the
    globals it reads (constants, arrays, types) and, recursively, the kernels and functions it
    calls, plus the versions of Python, numba, llvmlite and numpy. numba itself checks only the
    kernel's own file; a constant or a callee in another module changes this digest."""
    key = id(fn)
    if key in _digests:
        return _digests[key]
    if key in seen:  # recursion: the cycle is described by its members' own code
        return f"cycle {fn.__module__}.{fn.__qualname__}"
    h = hashlib.sha256(_BASE.encode())
    h.update(f"{fn.__module__}.{fn.__qualname__}|{fn.__defaults__!r}|{_options.get(key, '')}".encode())
    _walk_code(fn.__code__, fn.__globals__, h, seen | {key})
    _digests[key] = h.hexdigest()
    return _digests[key]


def _called(code, globs: dict):
    """The kernels and plain functions a code object names (``f(...)`` or ``module.f(...)``)."""
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            yield from _called(c, globs)
    for name in code.co_names:
        value = globs.get(name)
        if isinstance(value, (Dispatcher, types.FunctionType)):
            yield value
        elif isinstance(value, types.ModuleType):
            for n in code.co_names:
                if isinstance(v := vars(value).get(n), (Dispatcher, types.FunctionType)):
                    yield v


def exact_tree(fn) -> bool:
    """Whether ``fn`` and every kernel and function it calls, recursively, compile without
    fastmath and without ``parallel=True``: code whose results IEEE arithmetic fixes whatever
    LLVM makes of it, so linking a copy that another process compiled changes no result."""
    key = id(fn)
    if key not in _exact:
        reached, todo = set(), [fn]
        while todo:  # every function reachable from fn (cycles included)
            f = todo.pop()
            if id(f) not in reached:
                reached.add(id(f))
                todo.extend(getattr(g, "py_func", g) for g in _called(f.__code__, f.__globals__))
        _exact[key] = not reached & _inexact
    return _exact[key]


def lock_path(cache_path: str, filename_base: str, args: tuple) -> Path:
    """The lock of one overload's cache file (a kernel, argument types ``args``), next to it. A
    lock per overload lets processes compile different kernels, or different signatures of one
    kernel (the rigid and flexible solvers), at once, and load a cached overload while another
    compiles; nested compiles take the callee's lock inside the caller's, and the call graph of
    overloads has no cycle, so no two processes can wait for each other."""
    digest = hashlib.sha256(key_text((args,)).encode()).hexdigest()[:16]
    return Path(cache_path) / f"{filename_base}.{digest}.lock"


def compile_lock(path: Path) -> filelock.FileLock:
    """The process's lock object for ``path``: re-entrant, shared by the process's threads (the
    threads exclude each other through numba's own compiler lock)."""
    key = str(path)
    if key not in _locks:
        path.parent.mkdir(parents=True, exist_ok=True)
        _locks[key] = filelock.FileLock(key, thread_local=False)
    return _locks[key]


def _table_fields(typ, out: list) -> None:
    """The classes and field names of the named tuples in a numba type, depth first."""
    if isinstance(typ, numba_types.BaseNamedTuple):
        cls = typ.instance_class
        out.append(f"{cls.__module__}.{cls.__qualname__}{tuple(cls._fields)!r}")
    if isinstance(typ, numba_types.BaseTuple):
        for t in typ.types:
            _table_fields(t, out)
    elif isinstance(typ, numba_types.Optional):
        _table_fields(typ.type, out)


def key_text(key) -> str:
    """The text a cache key is hashed from: numba's key (signature, target CPU, bytecode hash)
    plus the class and field names of every named tuple in the signature. numba names a named
    tuple's type by its class name and field types only, so two layouts of one table that differ
    in the order or names of same-typed fields would otherwise share a file, and a kernel that
    reads a field by name would load the code of the other layout."""
    fields: list = []
    for typ in key[0]:
        _table_fields(typ, fields)
    return repr(key) + "|" + ";".join(fields)


class CacheFile:
    """Content-addressed, checksummed files of one kernel's compiled overloads."""

    def __init__(self, cache_path: str, filename_base: str, digest=lambda: ""):
        self.dir = Path(cache_path)
        self.base = filename_base
        self.digest = digest  # the kernel's code digest (computed when first needed)

    def path(self, key) -> tuple[Path, str]:
        """File of ``key`` and the hash of the key that names it."""
        key_hash = hashlib.sha256(key_text(key).encode()).hexdigest()
        return self.dir / f"{self.base}.{self.digest()[:16]}.{key_hash[:24]}.fgk", key_hash

    def load(self, key):
        """The cached payload of ``key``, or None if absent, stale, foreign or damaged."""
        path, key_hash = self.path(key)
        try:
            raw = path.read_bytes()
        except OSError:
            return None
        try:
            if not raw.startswith(FORMAT):
                return None
            head, payload = raw[len(FORMAT):].split(b"\n", 1)
            meta = json.loads(head)
            if (meta["key"] != key_hash or meta["digest"] != self.digest()
                    or meta["sha256"] != hashlib.sha256(payload).hexdigest()):
                return None
            return pickle.loads(payload)
        except Exception:  # damaged file: a miss; the compile that follows rewrites it
            return None

    def save(self, key, data) -> None:
        """Write ``data`` for ``key`` atomically; remove this kernel's files of other sources."""
        path, key_hash = self.path(key)
        payload = dumps(data)
        meta = {"key": key_hash, "digest": self.digest(), "sha256": hashlib.sha256(payload).hexdigest()}
        self.dir.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{path.name}.tmp.{uuid.uuid4().hex[:16]}")
        try:
            with open(tmp, "wb") as f:
                f.write(FORMAT + json.dumps(meta).encode() + b"\n" + payload)
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
        self.prune(keep_digest=self.digest()[:16])

    def prune(self, keep_digest: str) -> None:
        """Remove this kernel's files built from other sources, numba's own index and data files
        of it, and temporary files a killed process left behind."""
        now = time.time()
        for p in self.dir.glob(f"{self.base}.*"):
            rest = p.name[len(self.base) + 1:].split(".")
            try:
                if rest[-1] == "fgk" and rest[0] != keep_digest:
                    p.unlink()
                elif rest[-1] in ("nbi", "nbc"):
                    p.unlink()
                elif "tmp" in rest and now - p.stat().st_mtime > STALE_TMP_S:
                    p.unlink()
            except OSError:
                pass

    def flush(self) -> None:
        """Nothing to reset: a recompiled overload overwrites its own file."""


class KernelCache(FunctionCache):
    """numba's function cache with :class:`CacheFile` in place of the numbered index."""

    def __init__(self, py_func):
        super().__init__(py_func)
        self._cache_file = CacheFile(self._cache_path, self._impl.filename_base, lambda: code_digest(py_func))
        self.lock_path = lambda args: lock_path(self._cache_path, self._impl.filename_base, args)
        self.fresh = False  # compile without loading (set by KernelDispatcher.compile)
        self.unsaved = False  # compiled with flags its caller passed down: not saved

    def load_overload(self, sig, target_context):
        got = None if self.fresh else super().load_overload(sig, target_context)
        if got is None and len(_stack) == 1:  # the outermost kernel compiles (:func:`compiling`)
            _clock["compiling"] = True
        return got

    def holds(self, sig, codegen) -> bool:
        """Whether the disk holds the overload ``sig`` (a tuple of argument types) built from the
        current code (a damaged file is found at load and recompiled)."""
        return self._cache_file.path(self._index_key(sig, codegen))[0].is_file()

    def save_overload(self, sig, data):
        """Save unless the compile took flags that change results from its caller
        (:func:`inherits_other_results`): its file is what a call of the kernel alone loads."""
        if not self.unsaved:
            super().save_overload(sig, data)


#: numba's flags a callee takes from its caller unless it sets them itself, that change results,
#: with the value a compile of the kernel alone takes (numba.core.cpu.CPUTargetOptions.finalize)
INHERITED = (("fastmath", False), ("error_model", "python"))


def inherits_other_results(dispatcher) -> bool:
    """Whether ``dispatcher``, compiled now inside the kernels on the compile stack, takes from
    them a flag that changes its results (:data:`INHERITED`: fastmath, error model) with another
    value than a compile of it alone: such a compile (the LU solve of the fastmath lumped friction
    loop, fastmath then, rounding otherwise than the solve compiled alone) is never saved."""
    for name, alone in INHERITED:
        if name in dispatcher.targetoptions:
            continue
        value = alone
        for caller in reversed(_stack):
            if name in caller.targetoptions:
                value = caller.targetoptions[name]
                break
        if _changes_results(name, value, alone):
            return True
    return False


def _changes_results(name: str, value, alone) -> bool:
    """Whether flag ``name`` of :data:`INHERITED` set to ``value`` compiles other results than
    its value ``alone`` (fastmath: True or a set of LLVM flags against none)."""
    return bool(value) != bool(alone) if name == "fastmath" else value != alone


def inherited_flag_conflicts(dispatchers=None) -> list[str]:
    """The kernels (``module.name: flag from caller``) that a kernel of ``dispatchers`` (default
    :data:`KERNELS`) calls, directly or through callees that set no value of their own, and that
    take from it a flag of :data:`INHERITED` with another value than a compile of them alone. numba keeps one
    overload per signature in a process: whichever compile came first would serve every
    caller and Python's calls (a fastmath LU solve compiled for the lumped friction loop,
    linked into a rigid solver compiled later in the same process). Such a kernel must set
    the flag itself. Callees inlined into their caller (``inline="always"``) are part of it."""
    dispatchers = KERNELS if dispatchers is None else dispatchers
    by_function = {id(d.py_func): d for d in dispatchers}
    found = set()
    for name, alone in INHERITED:
        for root in dispatchers:
            if not _changes_results(name, root.targetoptions.get(name, alone), alone):
                continue
            todo, seen = [root.py_func], set()
            while todo:
                fn = todo.pop()
                for callee in _called(fn.__code__, fn.__globals__):
                    d = by_function.get(id(getattr(callee, "py_func", callee)))
                    if d is None or id(d) in seen or name in d.targetoptions:
                        continue
                    seen.add(id(d))
                    if d.targetoptions.get("inline") != "always":
                        found.add(f"{d.py_func.__module__}.{d.py_func.__qualname__}: {name} from "
                                  f"{root.py_func.__qualname__}")
                    todo.append(d.py_func)
    return sorted(found)


class KernelDispatcher(CPUDispatcher):
    """A CPU dispatcher that compiles and loads under the inter-process lock."""

    def enable_caching(self):
        self._cache = KernelCache(self.py_func)

    keep_literals = False  # @kernel(literal=True)

    def get_call_template(self, args, kws):
        """A call from another kernel compiles the overload of the arguments' plain types: a
        constant argument (``forces(..., False)``, ``_stop(ERR_NAN, ...)``) would otherwise
        compile an overload of its literal value, apart from the one Python's calls use. Kernels
        declared with ``literal=True`` keep them (the contact search: its constants folded make
        MERCURY 1-A's runs about 4 % faster)."""
        if self.keep_literals:
            return super().get_call_template(args, kws)
        args = tuple(numba_types.unliteral(a) for a in args)
        kws = {k: numba_types.unliteral(v) for k, v in kws.items()}
        return super().get_call_template(args, kws)

    def compile(self, sig):
        """Compile or load the overload ``sig`` under its inter-process lock.

        A compile nested in a caller's (a callee) does not load from the disk cache, and a callee
        loaded earlier in this process is compiled afresh for the caller: the caller links the
        callee's code into its own and optimises them together, and linking code that another
        process compiled makes the caller's code depend on the cache's fill history. numba names
        functions by a per-process counter and the process's hash order of the fastmath flags,
        so a caller linking another process's copy of a callee can hold two copies of shared
        code under different names, optimised differently (the fastmath sums of the flexible
        model then round differently: runs not bit-identical to a serial build); and a
        ``parallel=True`` callee linked from a loaded copy crashes every process that loads the
        caller (numba issues 8578, 4807). The exception is a callee whose whole call tree is
        exact (:func:`exact_tree`) called from kernels without fastmath: IEEE arithmetic fixes
        its results however it is optimised, so it is loaded (the contact search, the laws and
        the records, shared by the rigid and flexible solvers). A warm run loads its outermost
        kernels, so nothing nested is compiled; a caller missing from the cache recompiles its
        other callees (cost in docs/performance.md). An outermost compile runs with the garbage
        collector's thresholds raised (:func:`compile_gc`)."""
        if not isinstance(self._cache, KernelCache):
            return super().compile(sig)
        if _stack:
            return self._compile_locked(sig)
        with compile_gc():
            return self._compile_locked(sig)

    def _compile_locked(self, sig):
        """:meth:`compile` of a kernel with the package's cache."""
        outer = not _stack
        t0 = time.perf_counter()
        try:
            args = tuple(sigutils.normalize_signature(sig)[0])
            lock = compile_lock(self._cache.lock_path(args))
            t_wait = time.perf_counter()
            try:
                lock.acquire(timeout=WAIT_NOTICE_S)
            except filelock.Timeout:
                if not _clock["told"]:
                    _clock["told"] = True
                    print(f"flexgear: waiting for another process compiling the kernels ({self.py_func.__qualname__}, "
                          f"lock {lock.lock_file})", file=sys.stderr, flush=True)
                lock.acquire()
            _clock["waited"] += time.perf_counter() - t_wait
            shared = exact_tree(self.py_func) and not any(id(k.py_func) in _inexact for k in _stack)
            own = bool(_stack) and not shared  # a callee compiled for its caller, never loaded
            if own and (id(self), args) in _loaded:  # loaded earlier: the caller gets its own compile
                self._compile_afresh(sig, args)
            self._cache.fresh = own and args not in self.overloads
            self._cache.unsaved = bool(_stack) and inherits_other_results(self)
            _stack.append(self)
            try:
                n, hits = len(self.overloads), sum(self._cache_hits.values())
                result = super().compile(sig)
                _clock["overloads"] += len(self.overloads) - n
                if sum(self._cache_hits.values()) > hits:
                    _loaded.add((id(self), args))
                return result
            finally:
                _stack.pop()
                self._cache.fresh = self._cache.unsaved = False
                lock.release()
        finally:
            if outer:
                _clock["seconds"] += time.perf_counter() - t0
                _clock["compiling"] = False

    def _compile_afresh(self, sig, args) -> None:
        """Compile ``args`` in this process in place of the overload loaded from the disk cache,
        for callers to link (Python's calls keep the loaded code, the same source); not saved,
        the file holds the same code."""
        _, return_type = sigutils.normalize_signature(sig)
        _stack.append(self)
        try:
            with global_compiler_lock:
                cres = self._compiler.compile(args, return_type)
                self.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
                self.overloads[args] = cres
        finally:
            _stack.pop()
        _loaded.discard((id(self), args))


_gc = {"depth": 0, "saved": None, "lock": threading.Lock()}  # compile_gc's blocks open in this process


@contextlib.contextmanager
def compile_gc():
    """Collect garbage less often while the block runs (each threshold at least
    :data:`COMPILE_GC_THRESHOLD`'s); the thresholds the process had, the user's included, come
    back when the last such block of the process ends (threads may overlap them). The collector
    stays on: a compile's reference cycles are still freed."""
    with _gc["lock"]:
        if _gc["depth"] == 0:
            _gc["saved"] = gc.get_threshold()
            gc.set_threshold(*(max(a, b) for a, b in zip(_gc["saved"], COMPILE_GC_THRESHOLD)))
        _gc["depth"] += 1
    try:
        yield
    finally:
        with _gc["lock"]:
            _gc["depth"] -= 1
            if _gc["depth"] == 0:
                gc.set_threshold(*_gc["saved"])


def lock_file(dispatcher, sig) -> Path | None:
    """The inter-process lock file of the compilation of a kernel's overload ``sig`` (argument
    types, as numba's signatures; None for a plain function)."""
    cache = getattr(dispatcher, "_cache", None)
    if not isinstance(cache, KernelCache):
        return None
    return cache.lock_path(tuple(sigutils.normalize_signature(sig)[0]))


def is_cached(dispatcher) -> bool:
    """Whether the on-disk cache holds a compiled overload of ``dispatcher`` built from its
    current code (else its first call compiles)."""
    cache = getattr(dispatcher, "_cache", None)
    if not isinstance(cache, KernelCache):
        return False
    cf = cache._cache_file
    return any(cf.dir.glob(f"{cf.base}.{cf.digest()[:16]}.*.fgk"))


def overload_state(dispatcher, args) -> str:
    """Where ``dispatcher`` called with ``args`` gets its code: ``"compiled"`` in this process
    (or plain Python, with numba's JIT disabled), ``"cached"`` on disk (loaded in about a
    second), or ``"compile"`` (the call compiles it first)."""
    if not isinstance(dispatcher, KernelDispatcher):
        return "compiled"
    types = tuple(dispatcher.typeof_pyval(a) for a in args)
    if types in dispatcher.overloads:
        return "compiled"
    cache = dispatcher._cache
    if isinstance(cache, KernelCache) and cache.holds(types, dispatcher.targetctx.codegen()):
        return "cached"
    return "compile"


def kernel(**options):
    """Decorator: a numba ``njit`` kernel with the shared on-disk cache, registered in
    :data:`KERNELS`; ``options`` are numba's (``error_model``, ``inline``, ``fastmath``...) and
    ``literal=True``: calls from other kernels compile overloads of their constant arguments."""

    def declare(fn):
        if numba_config.DISABLE_JIT:
            return fn
        _options[id(fn)] = _stable_repr(tuple(sorted(options.items())))
        if options.get("fastmath") or options.get("parallel"):
            _inexact.add(id(fn))
        numba_options = {k: v for k, v in options.items() if k != "literal"}
        dispatcher = KernelDispatcher(py_func=fn, locals={}, targetoptions={"boundscheck": None, **numba_options,
                                                                           "nopython": True})
        dispatcher.keep_literals = bool(options.get("literal", False))
        dispatcher.enable_caching()
        KERNELS.append(dispatcher)
        return dispatcher

    return declare
