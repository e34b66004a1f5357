"""The one way flexgear declares a compiled kernel: ``@kernel(...)``, numba's ``njit`` with an
on-disk cache that concurrent processes can share.

numba's own cache numbers a kernel's compiled overloads in an index file; two processes that
compile different signatures of one kernel at once both take number 1, and the index of one
then points at the code of the other (numba issues 4807 and 10128): every later run crashes.
It also checks a kernel only against its own file, so a kernel that inlines code from another
module runs stale code after that module changes. The cache here instead

- names each compiled overload by a hash of its key (signature, target CPU, bytecode) and of
  the sources of every module the kernels are built from (:func:`source_digest`), so a file
  can only ever hold the code of its name, and a changed source is a miss, never stale code;
- writes a file atomically (temporary file, then rename) with a SHA-256 checksum of its
  payload, and uses it only if the name, the key, the digest and the checksum all match;
- compiles and loads under one inter-process lock (``filelock``), so a second process waits
  for the first's compilation and then loads it instead of compiling the same code again.

``numba.config.DISABLE_JIT`` leaves the functions as plain Python.
"""
from __future__ import annotations

import ast
import hashlib
import json
import os
import pickle
import sys
import time
import uuid
from pathlib import Path

import filelock
import llvmlite
import numba
import numpy as np
from numba.core import config as numba_config
from numba.core.caching import FunctionCache, InTreeCacheLocator, UserProvidedCacheLocator
from numba.core.registry import CPUDispatcher
from numba.core.serialize import dumps

PACKAGE_DIR = Path(__file__).resolve().parent
FORMAT = b"flexgear-kernel-cache 1\n"
LOCK_NAME = "flexgear-kernels.lock"
WAIT_NOTICE_S = 2.0  # tell the user after waiting this long for another process's compile
STALE_TMP_S = 3600.0  # temporary files older than this are left-overs of a killed process

#: Every dispatcher declared with ``@kernel``, in declaration order.
KERNELS: list = []
_digest: str | None = None
_locks: dict[str, filelock.FileLock] = {}


def _module_file(name: str) -> Path | None:
    """Source file of the flexgear module ``name`` (a module or a package's ``__init__``)."""
    rel = Path(*name.split(".")[1:])
    for p in (PACKAGE_DIR / rel.with_suffix(".py"), PACKAGE_DIR / rel / "__init__.py"):
        if p.is_file():
            return p
    return None


def _imported_modules(path: Path) -> set[str]:
    """flexgear modules imported by the file ``path`` (absolute and relative imports)."""
    base = ["flexgear", *path.relative_to(PACKAGE_DIR).parent.parts]  # the file's package
    found = set()
    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == "flexgear")
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                target = base[: len(base) - (node.level - 1)] + (node.module.split(".") if node.module else [])
            else:
                target = (node.module or "").split(".")
            if target[0] != "flexgear":
                continue
            mod = ".".join(target)
            found.add(mod)
            found.update(f"{mod}.{a.name}" for a in node.names if _module_file(f"{mod}.{a.name}"))
    return found


def kernel_sources(package_dir: Path = PACKAGE_DIR) -> list[Path]:
    """The files the compiled kernels are built from: every module that declares a kernel and,
    transitively, every flexgear module they import (constants and inlined kernels)."""
    files = {p for p in package_dir.rglob("*.py") if b"@kernel(" in p.read_bytes()}
    todo = list(files)
    while todo:
        for name in _imported_modules(todo.pop()):
            p = _module_file(name)
            if p is not None and p not in files:
                files.add(p)
                todo.append(p)
    return sorted(files)


def source_digest() -> str:
    """SHA-256 over the kernels' sources (:func:`kernel_sources`) and the versions of Python,
    numba, llvmlite and numpy: part of every cache file's name."""
    global _digest
    if _digest is None:
        h = hashlib.sha256()
        h.update(f"{sys.version}|{numba.__version__}|{llvmlite.__version__}|{np.__version__}".encode())
        for p in kernel_sources():
            h.update(p.relative_to(PACKAGE_DIR).as_posix().encode() + b"\0")
            h.update(p.read_bytes())
        _digest = h.hexdigest()
    return _digest


def lock_path(cache_path: str, locator) -> Path:
    """One lock for all kernels of this install that share a cache root (nested compiles take
    it once): the package's ``__pycache__``, ``NUMBA_CACHE_DIR``, or the cache folder itself."""
    if isinstance(locator, InTreeCacheLocator):
        return PACKAGE_DIR / "__pycache__" / LOCK_NAME
    if isinstance(locator, UserProvidedCacheLocator):
        return Path(numba_config.CACHE_DIR) / LOCK_NAME
    return Path(cache_path) / LOCK_NAME


def compile_lock(path: Path) -> filelock.FileLock:
    """The process's lock object for ``path``: re-entrant, shared by the process's threads (the
    threads exclude each other through numba's own compiler lock)."""
    key = str(path)
    if key not in _locks:
        path.parent.mkdir(parents=True, exist_ok=True)
        _locks[key] = filelock.FileLock(key, thread_local=False)
    return _locks[key]


class CacheFile:
    """Content-addressed, checksummed files of one kernel's compiled overloads."""

    def __init__(self, cache_path: str, filename_base: str):
        self.dir = Path(cache_path)
        self.base = filename_base

    def path(self, key) -> tuple[Path, str]:
        """File of ``key`` and the hash of the key that names it."""
        key_hash = hashlib.sha256(repr(key).encode()).hexdigest()
        return self.dir / f"{self.base}.{source_digest()[:16]}.{key_hash[:24]}.fgk", key_hash

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
            if (meta["key"] != key_hash or meta["digest"] != source_digest()
                    or meta["sha256"] != hashlib.sha256(payload).hexdigest()):
                return None
            return pickle.loads(payload)
        except Exception:  # damaged file: a miss; the compile that follows rewrites it
            return None

    def save(self, key, data) -> None:
        """Write ``data`` for ``key`` atomically; remove this kernel's files of other sources."""
        path, key_hash = self.path(key)
        payload = dumps(data)
        meta = {"key": key_hash, "digest": source_digest(), "sha256": hashlib.sha256(payload).hexdigest()}
        self.dir.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{path.name}.tmp.{uuid.uuid4().hex[:16]}")
        try:
            with open(tmp, "wb") as f:
                f.write(FORMAT + json.dumps(meta).encode() + b"\n" + payload)
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
        self.prune(keep_digest=source_digest()[:16])

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
        self._cache_file = CacheFile(self._cache_path, self._impl.filename_base)
        self.lock_path = lock_path(self._cache_path, self._impl.locator)


class KernelDispatcher(CPUDispatcher):
    """A CPU dispatcher that compiles and loads under the inter-process lock."""

    def enable_caching(self):
        self._cache = KernelCache(self.py_func)

    def compile(self, sig):
        if not isinstance(self._cache, KernelCache):
            return super().compile(sig)
        lock = compile_lock(self._cache.lock_path)
        try:
            lock.acquire(timeout=WAIT_NOTICE_S)
        except filelock.Timeout:
            print(f"flexgear: waiting for another process compiling the kernels (lock {lock.lock_file})",
                  file=sys.stderr, flush=True)
            lock.acquire()
        try:
            return super().compile(sig)
        finally:
            lock.release()


def kernel(**options):
    """Decorator: a numba ``njit`` kernel with the shared on-disk cache, registered in
    :data:`KERNELS`; ``options`` are numba's (``error_model``, ``inline``, ``fastmath``...)."""

    def declare(fn):
        if numba_config.DISABLE_JIT:
            return fn
        dispatcher = KernelDispatcher(py_func=fn, locals={}, targetoptions={"boundscheck": None, **options, "nopython": True})
        dispatcher.enable_caching()
        KERNELS.append(dispatcher)
        return dispatcher

    return declare
