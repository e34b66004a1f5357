"""Writing files safely: refuse to overwrite what a user saved, never leave a partial file or an
empty output directory; the per-user cache directory."""
from __future__ import annotations

import hashlib
import json
import os
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .errors import FlexgearError, ResultExistsError

CACHE_ENV = "FLEXGEAR_CACHE_DIR"


def user_cache_dir() -> Path:
    """flexgear's per-user cache directory (not created here).

    ``$FLEXGEAR_CACHE_DIR`` if set; otherwise the platform's user cache:
    ``$XDG_CACHE_HOME/flexgear`` or ``~/.cache/flexgear`` (Linux and other Unix),
    ``~/Library/Caches/flexgear`` (macOS), ``%LOCALAPPDATA%\\flexgear\\Cache`` (Windows).
    """
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env).expanduser()
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or str(Path.home() / "AppData" / "Local")
        return Path(base) / "flexgear" / "Cache"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "flexgear"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg and Path(xdg).is_absolute() else Path.home() / ".cache"
    return base / "flexgear"


def check_output_directory(path, probe: bool = True) -> list[Path]:
    """Check that ``path`` can be (or is) an output directory: neither it nor a parent is a
    file, and (``probe``) the directories can be created and a file written in it, tried for
    real (:func:`probe_directory`) and undone, so that a command refuses before any long work.

    Returns
    -------
    list of Path
        The directories that do not exist yet, deepest first.

    Raises
    ------
    ResultExistsError
        A part of the path is a file.
    FlexgearError
        The directory cannot be created or written (the message says which and why).
    """
    path = Path(path)
    missing = []
    for p in (path, *path.parents):
        if p.exists():
            if not p.is_dir():
                raise ResultExistsError(f"output directory {str(path)!r}: {str(p)!r} exists and is not a "
                                        "directory; choose another path")
            break
        missing.append(p)
    if probe:
        probe_directory(path, missing)
    return missing


def probe_directory(path, missing=()) -> None:
    """Create the ``missing`` directories (deepest first, as :func:`check_output_directory`
    lists them), write and remove a small file in ``path``, then remove the directories created
    here: what a file system refuses (read-only, ``/proc``, permissions, full) is found before
    any work, and nothing stays behind.

    Raises
    ------
    FlexgearError
        Naming the directory that could not be created or written, and the system's reason.
    """
    path = Path(path)
    created = []
    try:
        for p in reversed(list(missing)):
            try:
                p.mkdir()
            except FileExistsError:
                continue
            except OSError as exc:
                raise FlexgearError(f"output directory {str(path)!r}: cannot create {str(p)!r} "
                                    f"({exc.strerror or exc}); choose a writable location") from None
            created.append(p)
        try:
            fd, tmp = tempfile.mkstemp(prefix=".flexgear-write-probe-", dir=path)
            try:
                os.write(fd, b"flexgear")
            finally:
                os.close(fd)
                os.unlink(tmp)
        except OSError as exc:
            raise FlexgearError(f"output directory {str(path)!r}: cannot write a file there "
                                f"({exc.strerror or exc}); choose a writable location") from None
    finally:
        for p in reversed(created):  # deepest first
            try:
                p.rmdir()
            except OSError:
                pass


@contextmanager
def output_directory(path):
    """Create the output directory ``path`` (with its parents) for the block that writes into
    it; if the block raises, remove the directories created here that are still empty.

    Raises
    ------
    ResultExistsError
        If ``path`` or one of its parents exists and is not a directory (checked first).
    """
    path = Path(path)
    created = check_output_directory(path, probe=False)
    path.mkdir(parents=True, exist_ok=True)
    try:
        yield path
    except BaseException:
        for p in created:  # deepest first
            try:
                p.rmdir()
            except OSError:  # not empty (complete files were written) or gone
                break
        raise


def check_targets(paths, overwrite: bool) -> None:
    """Raise :class:`~flexgear.errors.ResultExistsError` if any of ``paths`` exists and ``overwrite`` is False."""
    for p in paths:
        if Path(p).exists() and not overwrite:
            raise ResultExistsError(f"{str(p)!r} already exists; refusing to overwrite it "
                                    "(pass overwrite=True, command line --overwrite)")


def _umask() -> int:
    um = os.umask(0)
    os.umask(um)
    return um


def default_file_mode() -> int:
    """Permission bits of a new file as ``open()`` would create it: 0o666 less the umask
    (0o644 with the usual umask 022). ``tempfile`` creates 0o600 files; a file written through
    a temporary one gets these bits before it is moved into place."""
    return 0o666 & ~_umask()


def atomic_write(path, write) -> Path:
    """Call ``write(tmp_path)`` on a temporary file beside ``path``, then move it onto ``path``
    (``os.replace``), so that readers see the old file or the complete new one."""
    return atomic_write_together([(path, write)])[0]


def atomic_write_together(writes) -> list[Path]:
    """Write several files from one state: call every ``write(tmp_path)`` of ``writes`` (pairs
    ``(path, write)``) on a temporary file beside its path first, then move them all into place
    one right after the other, so that readers see every file old or every file new except for
    the instant between two renames (the slow part, writing, comes before the first)."""
    tmps = []
    try:
        for path, write in writes:
            path = Path(path)
            fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
            os.close(fd)
            tmps.append((tmp, path))
            write(tmp)
            os.chmod(tmp, default_file_mode())
        for tmp, path in tmps:
            os.replace(tmp, path)
    finally:
        for tmp, _ in tmps:
            if os.path.exists(tmp):
                os.unlink(tmp)
    return [path for _, path in tmps]


def sha256_file(path) -> str:
    """SHA-256 hex digest of a file's contents (cache checksums)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def atomic_write_json(path, data) -> Path:
    """Write ``data`` as JSON (sorted keys) through :func:`atomic_write`."""
    def write(tmp):
        with open(tmp, "w") as fh:
            json.dump(data, fh, sort_keys=True, indent=1)

    return atomic_write(path, write)


def atomic_write_arrays(path, arrays) -> Path:
    """Write numpy arrays through :func:`atomic_write`: a dict as an uncompressed ``.npz``
    (``numpy.savez``), a single array as ``.npy`` (``numpy.save``)."""
    import numpy as np

    def write(tmp):
        with open(tmp, "wb") as fh:
            if isinstance(arrays, dict):
                np.savez(fh, **arrays)
            else:
                np.save(fh, arrays)

    return atomic_write(path, write)


def entry_lock(cache_dir, name: str):
    """The inter-process lock of one multi-file cache entry, ``<cache_dir>/<name>.lock``
    (``filelock``): a process holds it while it loads, builds and writes the entry, so that no
    other reads an entry half written (and removes it as damaged, under the writer's feet), and
    a second process waits for the build instead of repeating it."""
    import filelock

    Path(cache_dir).mkdir(parents=True, exist_ok=True)
    return filelock.FileLock(str(Path(cache_dir) / f"{name}.lock"))


def discard_files(*paths) -> None:
    """Remove files that may or may not exist (an unusable cache entry); errors are ignored."""
    for p in paths:
        try:
            Path(p).unlink()
        except OSError:
            pass


def csv_column(path, name: str) -> list[str] | None:
    """The non-empty fields of column ``name`` of the CSV file ``path`` (header line first),
    or None if the file is missing, unreadable or has no such column."""
    import csv

    try:
        with open(path, newline="") as f:
            return [row[name] for row in csv.DictReader(f) if row.get(name)]
    except (OSError, KeyError, csv.Error, UnicodeDecodeError):
        return None


def jsonable(v):
    """``v`` with numpy scalars and arrays, tuples and dict keys turned into plain JSON values
    (other objects by their ``repr``)."""
    if isinstance(v, (np.floating, float)):
        return float(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (np.bool_,)):
        return bool(v)
    if isinstance(v, np.ndarray):
        return [jsonable(x) for x in v.tolist()]
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if v is None or isinstance(v, (bool, int, str)):
        return v
    return repr(v)


def read_cached_arrays(npz, side, key: dict) -> dict:
    """Arrays of a cache entry written by :func:`write_cached_arrays`: the ``.npz`` ``npz`` and its
    ``.json`` sidecar ``side``, whose key must equal ``key`` and whose checksum the ``.npz`` must
    match. Raises OSError or ValueError otherwise (the caller drops and recomputes the entry)."""
    meta = json.loads(Path(side).read_text())
    if meta.get("key") != key:
        raise ValueError("stale cache entry (key mismatch)")
    if sha256_file(npz) != meta["npz_sha256"]:
        raise ValueError("corrupt cache entry (checksum mismatch)")
    with np.load(npz) as z:
        return {k: np.array(z[k]) for k in z.files}


def write_cached_arrays(npz, side, key: dict, arrays: dict) -> None:
    """Write a cache entry atomically: the arrays as ``npz``, then the sidecar ``side`` with the
    key and the ``.npz``'s checksum (a reader that finds the sidecar finds the complete ``.npz``)."""
    Path(npz).parent.mkdir(parents=True, exist_ok=True)
    atomic_write_arrays(npz, arrays)
    atomic_write_json(side, {"key": key, "npz_sha256": sha256_file(npz)})
