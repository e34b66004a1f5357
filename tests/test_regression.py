"""Refactoring guard: short runs of the presets are bit-identical to the stored reference.

The reference files in ``tests/data/reference/`` were written by ``tests/data/make_reference.py``
at the commits named in ``SOURCE`` (explicit contact tables, plain sampling). A change that is
meant to change results (a new contact evaluation, a new integrator) regenerates them in the
same commit and says so; a refactoring must leave them untouched.

The flexible presets' kernels reassociate some sums (fastmath), whose rounding depends on the
vector width numba compiles for. Their references record the CPU name and features numba
compiled for, one file per CPU the project was developed on (``PRESET.h5``, and
``PRESET@CPU.h5`` added by ``make_reference.py --add-cpu``): on such a CPU the runs must be
bit-identical; on another one every float dataset must agree with ``PRESET.h5`` within
``ROUNDOFF`` times its RMS (integers, counters and shapes exactly).
"""
from pathlib import Path

import h5py
import numpy as np
import pytest

from flexgear.app.run import run
from conftest import load_script

DATA = Path(__file__).parent / "data"
#: relative agreement (of a dataset's RMS) of a flexible run compiled for another CPU: the
#: contact dynamics amplify the per-step rounding differences (a last-bit change of the load
#: torque alone grows to about 1e-9 over the 0.02 s run; AMD znver5 against Intel Emerald Rapids
#: differ by up to 1.2e-6, MERCURY 1-A's carrier angle); a physical change moves far more
ROUNDOFF = 1e-5


def _script():
    return load_script(DATA / "make_reference.py")


def _datasets(group, prefix=""):
    out = {}
    for k, v in group.items():
        if isinstance(v, h5py.Group):
            out.update(_datasets(v, f"{prefix}{k}/"))
        else:
            out[f"{prefix}{k}"] = v[()]
    return out


def _same_cpu(attrs, compiled):
    return all(k in attrs and str(attrs[k]) == v for k, v in compiled.items())


def compare(ref, new, exact):
    """The datasets of two result files that differ: all of them bit for bit (``exact``), else
    the float ones within ROUNDOFF of their RMS and the others exactly."""
    a, b = _datasets(ref), _datasets(new)
    assert sorted(a) == sorted(b)
    bad = []
    for k in a:
        assert a[k].dtype == b[k].dtype, k
        assert np.shape(a[k]) == np.shape(b[k]), k
        if exact or not np.issubdtype(a[k].dtype, np.floating):
            if not np.array_equal(a[k], b[k]):
                bad.append(k)
            continue
        x, y = np.asarray(a[k], float), np.asarray(b[k], float)
        if not np.array_equal(np.isfinite(x), np.isfinite(y)):
            bad.append(k)
            continue
        fin = np.isfinite(x)
        rms = np.sqrt(np.mean(x[fin] ** 2)) if fin.any() else 0.0
        if np.any(np.abs(x[fin] - y[fin]) > ROUNDOFF * rms):
            bad.append(k)
    return bad


def reference_file(preset: str, compiled: dict, directory: Path = DATA / "reference") -> tuple[Path, bool]:
    """(reference file, compare bit for bit) of ``preset`` on the CPU ``compiled`` describes."""
    main = directory / f"{preset}.h5"
    if not preset.endswith("_flexible"):
        return main, True
    for path in [main, *sorted(main.parent.glob(f"{preset}@*.h5"))]:
        with h5py.File(path) as f:
            if _same_cpu(f.attrs, compiled):
                return path, True
    return main, False


def check_against_reference(preset, tmp_path):
    from flexgear.results import save

    script = _script()
    res = run(script.reference_config(preset))
    path = tmp_path / "r.h5"
    save(res, path)
    ref_path, exact = reference_file(preset, script.compiled_for())
    with h5py.File(ref_path) as ref, h5py.File(path) as new:
        bad = compare(ref, new, exact)
        assert not bad, (f"{preset}: datasets differ from the reference "
                         f"({'bit for bit' if exact else f'beyond {ROUNDOFF:g} of their RMS'}): {bad}")
        for k in ("solver_steps", "newton_iterations", "rejected_steps", "step"):
            assert ref.attrs[k] == new.attrs[k], k


@pytest.mark.parametrize("preset", ["spur_pair", "mercury_1a"])
def test_short_runs_are_bit_identical_to_the_reference(preset, tmp_path):
    check_against_reference(preset, tmp_path)


@pytest.mark.parametrize("preset", ["spur_pair_flexible", "mercury_1a_flexible"])
def test_flexible_short_runs_match_the_reference(preset, tmp_path):
    check_against_reference(preset, tmp_path)


def test_the_comparison_sees_a_change_in_the_last_bit_and_beyond_the_roundoff(tmp_path):
    """Which wrong code passes: none that changes a float's last bit on the reference's CPU, nor
    one that changes a float by more than ROUNDOFF of its RMS, or an integer, elsewhere."""
    x = np.linspace(1.0, 2.0, 50)
    k = np.arange(50)
    rms = np.sqrt(np.mean(x ** 2))
    cases = {"same": (x, k), "last bit": (np.nextafter(x, 3.0), k),
             "roundoff": (x + 0.5 * ROUNDOFF * rms, k), "beyond": (x + 2 * ROUNDOFF * rms, k),
             "integer": (x, k + (k == 7))}
    with h5py.File(tmp_path / "ref.h5", "w") as ref:
        ref["g/x"], ref["k"] = x, k
        got = {}
        for name, (y, j) in cases.items():
            with h5py.File(tmp_path / f"{name}.h5", "w") as new:
                new["g/x"], new["k"] = y, j
                got[name] = (compare(ref, new, exact=True), compare(ref, new, exact=False))
    assert got["same"] == ([], [])
    assert got["last bit"] == (["g/x"], [])
    assert got["roundoff"] == (["g/x"], [])
    assert got["beyond"] == (["g/x"], ["g/x"])
    assert got["integer"] == (["k"], ["k"])
    compiled = _script().compiled_for()
    assert _same_cpu(compiled, compiled) and not _same_cpu({**compiled, "numba_cpu_name": "other"}, compiled)


def test_each_cpu_takes_its_own_reference_and_another_cpu_the_first_within_roundoff(tmp_path):
    """Which wrong code passes: none that compares a flexible run bit for bit with another CPU's
    file, or loosely with its own CPU's, or takes a file of another preset."""
    cpu = {name: {"numba_cpu_name": name, "numba_cpu_features": f"+{name}"} for name in "abc"}
    for stem, name in [("x_flexible", "a"), ("x_flexible@b", "b"), ("x_flexible_long@c", "c")]:
        with h5py.File(tmp_path / f"{stem}.h5", "w") as f:
            f.attrs.update(cpu[name])
    main = tmp_path / "x_flexible.h5"
    assert reference_file("x_flexible", cpu["a"], tmp_path) == (main, True)
    assert reference_file("x_flexible", cpu["b"], tmp_path) == (tmp_path / "x_flexible@b.h5", True)
    assert reference_file("x_flexible", cpu["c"], tmp_path) == (main, False)
    assert reference_file("x_flexible", {**cpu["b"], "numba_cpu_features": "+a"}, tmp_path) == (main, False)
