"""A changed kernel source invalidates numba's cache of the whole dynamics package."""
import shutil

from flexgear.dynamics import kernel_cache


def test_stale_cache_files_are_deleted_when_a_source_changes(tmp_path):
    pkg = tmp_path / "dyn"
    pkg.mkdir()
    (pkg / "contact.py").write_text("x = 1\n")
    (pkg / "solver.py").write_text("y = 2\n")
    cache = pkg / "__pycache__"
    cache.mkdir()
    assert kernel_cache.invalidate_if_stale(pkg)          # first time: stamp written
    (cache / "solver.integrate-1.py311.nbi").write_text("index")
    (cache / "solver.integrate-1.py311.1.nbc").write_text("code")
    (cache / "solver.cpython-311.pyc").write_text("bytecode")
    assert not kernel_cache.invalidate_if_stale(pkg)      # unchanged sources: cache kept
    assert (cache / "solver.integrate-1.py311.nbi").exists()
    (pkg / "contact.py").write_text("x = 3\n")            # a dependency of integrate changes
    assert kernel_cache.invalidate_if_stale(pkg)
    assert not list(cache.glob("*.nb[ic]"))
    assert (cache / "solver.cpython-311.pyc").exists()    # nothing else is touched
    shutil.rmtree(pkg)


def test_the_installed_package_has_a_current_stamp():
    """Importing flexgear.dynamics stamped the package's cache with its current sources."""
    import os

    import pytest

    if os.environ.get("NUMBA_CACHE_DIR") or not os.access(kernel_cache.PACKAGE_DIR, os.W_OK):
        pytest.skip("numba keeps its own cache rules here (NUMBA_CACHE_DIR set or read-only package)")
    stamp = kernel_cache.PACKAGE_DIR / "__pycache__" / kernel_cache.STAMP_NAME
    assert stamp.read_text() == kernel_cache.source_digest()
