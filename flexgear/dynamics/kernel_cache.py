"""Keep numba's on-disk cache of the compiled kernels consistent with their sources.

Numba checks a cached kernel only against the file that defines it: ``solver.integrate``
compiled with the contact code of an older ``contact.py`` is reused after ``contact.py``
changed (an editable install, a local edit), silently running the old contact evaluation.
:func:`invalidate_if_stale` keeps a digest of every source file of this package next to the
cache and deletes the package's cache files (``*.nbi``, ``*.nbc``) when the digest changes.
It runs once when :mod:`flexgear.dynamics` is imported; with ``NUMBA_CACHE_DIR`` set, or where
the cache folder cannot be written, it does nothing (numba then keeps its own rules).
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
STAMP_NAME = "kernel_sources.sha256"


def source_digest(package_dir: Path = PACKAGE_DIR) -> str:
    """SHA-256 over the names and contents of the package's ``*.py`` files."""
    h = hashlib.sha256()
    for p in sorted(package_dir.glob("*.py")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def invalidate_if_stale(package_dir: Path = PACKAGE_DIR) -> bool:
    """Delete the package's numba cache files if any source changed since they were written.

    Returns
    -------
    bool
        True if cache files were deleted (or there were none and the stamp was new).
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return False
    cache = package_dir / "__pycache__"
    stamp = cache / STAMP_NAME
    digest = source_digest(package_dir)
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for p in list(cache.glob("*.nbi")) + list(cache.glob("*.nbc")):
            p.unlink(missing_ok=True)
        tmp = cache / f".{STAMP_NAME}.{os.getpid()}"
        tmp.write_text(digest)
        os.replace(tmp, stamp)
    except OSError:
        return False
    return True
