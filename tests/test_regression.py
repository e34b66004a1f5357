"""Refactoring guard: short runs of both presets are bit-identical to the stored reference.

The reference files in ``tests/data/reference/`` were written by ``tests/data/make_reference.py``
at the commit named in ``SOURCE`` (explicit contact tables, plain sampling). A change that is
meant to change results (a new contact evaluation, a new integrator) regenerates them in the
same commit and says so; a refactoring must leave them untouched.
"""
from pathlib import Path

import h5py
import numpy as np
import pytest

from flexgear.app.run import run
from conftest import load_script

DATA = Path(__file__).parent / "data"


def _reference_config(preset):
    return load_script(DATA / "make_reference.py").reference_config(preset)


def _datasets(group, prefix=""):
    out = {}
    for k, v in group.items():
        if isinstance(v, h5py.Group):
            out.update(_datasets(v, f"{prefix}{k}/"))
        else:
            out[f"{prefix}{k}"] = v[()]
    return out


@pytest.mark.parametrize("preset", ["spur_pair", "mercury_1a"])
def test_short_runs_are_bit_identical_to_the_reference(preset, tmp_path):
    from flexgear.results import save

    res = run(_reference_config(preset))
    path = tmp_path / "r.h5"
    save(res, path)
    with h5py.File(DATA / "reference" / f"{preset}.h5") as ref, h5py.File(path) as new:
        a, b = _datasets(ref), _datasets(new)
        assert sorted(a) == sorted(b)
        for k in a:
            assert a[k].dtype == b[k].dtype, k
            assert np.array_equal(a[k], b[k]), f"{preset}: dataset {k} differs from the reference"
        for k in ("solver_steps", "newton_iterations", "rejected_steps", "step"):
            assert ref.attrs[k] == new.attrs[k], k
