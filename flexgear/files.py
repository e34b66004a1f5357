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

from .errors import ResultExistsError

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


def check_output_directory(path) -> list[Path]:
    """Check that ``path`` can be (or is) an output directory: neither it nor a parent is a file.

    Returns
    -------
    list of Path
        The directories that do not exist yet, deepest first.

    Raises
    ------
    ResultExistsError
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
    return missing


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
    created = check_output_directory(path)
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
    """Raise :class:`ResultExistsError` if any of ``paths`` exists and ``overwrite`` is False."""
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
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, default_file_mode())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path


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


def discard_files(*paths) -> None:
    """Remove files that may or may not exist (an unusable cache entry); errors are ignored."""
    for p in paths:
        try:
            Path(p).unlink()
        except OSError:
            pass


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
