"""Shared fixtures: shortened runs of the two presets, computed once per test session."""
import importlib.util
import os
import re
import warnings
from pathlib import Path

# The session runs its tests in worker processes on every core (pytest-xdist) and compiles in
# more: a threaded BLAS in each would only oversubscribe the cores (OpenBLAS threads spin while
# they wait for work). Set before numpy loads; the results do not depend on it (a reduction runs
# its BLAS on one thread, flexgear.fe.elasticity.single_threaded_blas).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# Likewise the gear reductions run in the test's own process, not in a pool of fresh interpreters
# per model (flexgear.reduction.parallel; each pool's start and imports cost CPU the busy cores
# do not have: docs/performance.md); tests/test_reduction_parallel.py starts its pools itself.
os.environ.setdefault("FLEXGEAR_REDUCTION_WORKERS", "1")

import pytest  # noqa: E402

from flexgear.config import load_config  # noqa: E402
from flexgear.app.run import run  # noqa: E402


ROOT = Path(__file__).resolve().parents[1]


# --------------------------------------------------------------------------- session order
# A cold session spends minutes compiling the solver before the first simulation. The
# controlling process starts `flexgear warm` at once (one process: the rigid and lumped solvers,
# then the flexible one, which links the callees they share as compiled there, compiling them
# once), and the workers take the files in three phases: those that never simulate, then those
# that simulate rigid or lumped models, then those with flexible gears; so the compile overlaps
# the first phases, and a test that needs a kernel still compiling waits for it
# (the kernel cache's lock), never compiles it twice. In each phase the files that take longest
# go first (LONG, measured: 5-30 CPU-s each in a cold session, with the gear reductions they are
# the first to need), so that the session does not end with one worker busy and the other idle.
# pyproject.toml keeps this order (--no-loadscope-reorder: pytest-xdist would otherwise sort the
# files by their number of tests). The workers of a cold session run at a lower priority than the
# warm-up (WARMING_NICE; for the whole session, as a process cannot raise it back, but nothing
# competes once the warm-up ends), so the warm-up has a core to itself and the workers share the
# other: at the same priority each process ran slower (the session used 7-9 % more CPU), and the
# compile, which the later phases wait for, finished later.
SIMULATES = re.compile(r"(?<![\w.])run\(|flexgear\.run\(|simulate\(|build_model|build_lumped|spur_result|"
                       r"planetary_result|run_batch|mesh_contacts|integrate\(|load_script\(|"
                       r"flexgear\.app\.cli import main|tests/test_examples")
FLEXIBLE = re.compile(r"_flexible\b|\[flexible\]|[\"']flexible[\"']|reduce_flexible|\.flexible\b|flexible=")
NO_SOLVER = {"test_kernel_cache.py"}  # its simulations run in the slow tests only
LONG = {"test_crack.py", "test_kernel_cache.py", "test_stiffness.py", "test_reduction_parallel.py",
        "test_batch.py", "test_faults_lumped.py", "test_lumped_friction.py", "test_faults_rigid.py",
        "test_paper_acceptance.py", "test_sensor_paths.py", "test_rigid_crack.py",
        "test_flexible.py", "test_flexible_modal.py", "test_threads.py", "test_housing_coupled_planetary.py",
        "test_flexible_faults.py", "test_flexible_crack_series.py", "test_compliant_kernel.py",
        "test_table_convergence.py", "test_extended_contact.py", "test_deformed.py", "test_regression.py",
        "test_cross_mesh.py"}


def session_phase(path: Path) -> int:
    """0: the file never simulates; 1: it simulates rigid or lumped models; 2: flexible ones too."""
    text = path.read_text()
    if path.name in NO_SOLVER or not SIMULATES.search(text):
        return 0
    return 2 if FLEXIBLE.search(text) else 1


_warm = {}
WARMING = "FLEXGEAR_TESTS_WARMING"  # set for the workers of a session whose warm-up runs
#: the workers' niceness in a cold session: the warm-up takes a core and the workers share the
#: other; not 19, where a worker gets about 1.5 % of a core against another busy process (another
#: job on the machine), too little for the timeouts of the subprocesses its tests wait for
WARMING_NICE = 10


def pytest_sessionstart(session):
    import subprocess
    import sys
    import tempfile

    if os.environ.get("PYTEST_XDIST_WORKER") or session.config.getoption("collectonly", False):
        return
    from flexgear.dynamics.integrator.simulation import compiled_cache_present

    if compiled_cache_present():
        return
    if getattr(session.config.option, "numprocesses", None):  # the workers' shared cache (_private_cache_dir)
        cache = session.config._tmp_path_factory.getbasetemp() / "flexgear_cache"  # as pytest-xdist names it
        cache.mkdir(exist_ok=True)
    else:
        cache = _warm["cache"] = tempfile.mkdtemp(prefix="flexgear-warm-")  # contact tables: never the user's cache
    env = dict(os.environ, FLEXGEAR_CACHE_DIR=str(cache), MPLBACKEND="Agg")
    # the specialisations of the solver in one process, rigid (and lumped) first (session order),
    # the rigid one with friction (its friction code pruned from frictionless models) last
    os.environ[WARMING] = "1"  # for the workers, which pytest-xdist starts after this hook
    names = ("spur_pair", "spur_pair:lumped", "spur_pair_flexible", "spur_pair_friction")
    _warm["procs"] = [subprocess.Popen([sys.executable, "-m", "flexgear.app.cli", "warm", *names], env=env,
                                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]


def pytest_configure(config):
    if os.environ.get("PYTEST_XDIST_WORKER") and os.environ.get(WARMING) and hasattr(os, "nice"):
        os.nice(WARMING_NICE)  # lower the worker's priority below the warm-up's (session order, above)


def pytest_sessionfinish(session, exitstatus):
    import shutil

    os.environ.pop(WARMING, None)
    for proc in _warm.pop("procs", ()):  # kill does nothing to a process that has ended
        proc.kill()  # the kernel cache is written atomically: a killed compile leaves nothing half-written
        proc.wait()
    shutil.rmtree(_warm.pop("cache", ""), ignore_errors=True)


def pytest_collection_modifyitems(session, config, items):
    keys = {}

    def order(item):
        path = Path(str(item.fspath))
        if path not in keys:
            keys[path] = (session_phase(path), path.name not in LONG)
        return keys[path]

    items.sort(key=order)  # stable: each file's tests stay in their order
    for item in items:  # the long studies may take hours; the default one's bound is in pyproject.toml
        if item.get_closest_marker("slow") and not item.get_closest_marker("timeout"):
            item.add_marker(pytest.mark.timeout(6 * 3600))


def load_script(path, name=None):
    """Import a script that is not part of the package (a study, an example, a data generator)
    from its path, relative to the repository root or absolute."""
    path = ROOT / path
    spec = importlib.util.spec_from_file_location(name or path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def short(preset, duration, run_in=0.1, **sim):
    cfg = load_config(preset)
    cfg.simulation.update(duration=duration, run_in=run_in, **sim)
    return cfg


@pytest.fixture(scope="session")
def spur_result():
    return run(short("spur_pair", 0.25))


@pytest.fixture(scope="session")
def planetary_result():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run(short("mercury_1a", 0.5))


@pytest.fixture(scope="session", autouse=True)
def _private_cache_dir(tmp_path_factory):
    """Tests mesh into a cache of their own, never the user's (FLEXGEAR_CACHE_DIR); the worker
    processes of one session (pytest-xdist) share it, as the caches are safe for concurrent
    processes, so a flexible preset is meshed and reduced once per session."""
    import os

    old = os.environ.get("FLEXGEAR_CACHE_DIR")
    if os.environ.get("PYTEST_XDIST_WORKER"):  # basetemp .../pytest-N/popen-gwK: share .../pytest-N
        shared = tmp_path_factory.getbasetemp().parent / "flexgear_cache"
        shared.mkdir(exist_ok=True)
        os.environ["FLEXGEAR_CACHE_DIR"] = str(shared)
    else:
        os.environ["FLEXGEAR_CACHE_DIR"] = str(tmp_path_factory.mktemp("flexgear_cache"))
    yield
    if old is None:
        os.environ.pop("FLEXGEAR_CACHE_DIR", None)
    else:
        os.environ["FLEXGEAR_CACHE_DIR"] = old


def inertia_load_deflection(red):
    """Reference for the condensed modes' ``acceleration_shape`` of a reduced gear: a function
    (tooth, side +1 / -1, radius [m]) -> (3,) giving the normal displacement [m] of that flank
    point, read through the reduction's flank patch (positive along the contact force, i.e.
    opening the contact), per unit acceleration of the gear's frame (x, y [m/s^2], theta
    [rad/s^2]): the static FE solution ``K_ii u = -M_ir a`` with the interface held (the
    d'Alembert load of the frame's acceleration), a full sparse solve with no modes."""
    import numpy as np
    import scipy.sparse.linalg as sla

    from flexgear.dynamics.flexible.full_order import FlankPatches

    fm = red.body.model
    itf = red.body.interface
    inner = np.setdiff1d(np.arange(fm.ndofs), np.union1d(itf.boundary, itf.fixed))
    K = fm.K.tocsr()[inner][:, inner].tocsc()
    u = np.zeros((fm.ndofs, 3))
    u[inner] = sla.spsolve(K, -(fm.M.tocsr() @ fm.rigid_body_modes())[inner])
    patches = FlankPatches(fm, red.gear)
    return lambda tooth, side, radius: patches.load(tooth, side, radius) @ u[patches.dofs[tooth, side]]
