"""Writing files safely: refuse to overwrite what a user saved, and never leave a partial file."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .errors import ResultExistsError


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


def atomic_write(path, write) -> Path:
    """Call ``write(tmp_path)`` on a temporary file beside ``path``, then move it onto ``path``
    (``os.replace``), so that readers see the old file or the complete new one."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path
