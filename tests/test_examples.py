"""The scripts in examples/ run, and each gives one physical number that we check.

Each example computes its results at module level (plots only under ``__main__``), so importing
it runs it. The README's Python snippet is part of ``ex04_planetary_spectrum.py``, checked here
line for line, so it cannot rot.
"""
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import load_script

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def load_example(name):
    return load_script(EXAMPLES / f"{name}.py", name)


def test_ex01_spur_spectrum_lines_are_the_mesh_harmonics():
    ex = load_example("ex01_spur_spectrum")
    assert ex.mesh_frequency == pytest.approx(24 * 10.0)
    bin_hz = ex.f[1] - ex.f[0]
    got = sorted(p.freq for p in ex.peaks)
    assert np.allclose(got, [240.0, 480.0, 720.0, 960.0], atol=bin_hz)


def test_ex02_fe_pair_stiffness_lies_between_iso_c_prime_and_c_th():
    ex = load_example("ex02_tooth_compliance")
    assert ex.c_prime_iso < ex.c_single_fe < ex.c_th_iso


def test_ex03_fe_mass_equals_density_times_volume():
    ex = load_example("ex03_gear_modes")
    assert ex.fe_mass == pytest.approx(ex.outline_mass, rel=2e-3)   # curved boundary, P2 mesh
    assert np.all(np.diff(ex.freqs) >= 0) and ex.freqs[0] > 10e3    # clamped sun: tens of kHz


def test_ex04_sun_torque_obeys_statics():
    ex = load_example("ex04_planetary_spectrum")
    z_s, z_r = 24, 66
    assert ex.sun_torque == pytest.approx(60.0 * z_s / (z_s + z_r), rel=0.01)
    assert ex.fy.shape == (int(round(0.5 * ex.res.attrs["output_rate"])),)


def test_ex05_film_follows_the_viscosity_and_friction_reverses_at_the_pitch_point():
    """Dowson & Higginson: h_min ~ (eta u_e)^0.70 W^-0.13, so at the same speeds and nearly the
    same loads the films of the 90 and 40 degC runs differ by (eta_90 / eta_40)^0.70 (1 %);
    a tooth pair crosses the pitch point once per mesh period, and there the mesh's friction
    force changes sign, as the sliding does."""
    ex = load_example("ex05_oil_film")
    assert ex.film_ratio == pytest.approx(ex.film_ratio_expected, rel=0.01)
    res = ex.runs[40.0]
    periods = (res.time[-1] - res.time[0]) * res.attrs["mesh_frequency"]
    assert abs(len(ex.crossings) - periods) <= 1.0
    k = np.searchsorted(res.time, ex.crossings)
    f = ex.mesh[40.0].friction_force
    assert np.all(f[k - 1] * f[k] < 0.0)
    assert 0.9 < ex.efficiency[40.0] < 1.0 and 0.9 < ex.efficiency[90.0] < 1.0


def test_readme_python_snippet_is_the_example():
    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", readme, re.S)
    assert blocks, "README has no python block"
    example = (EXAMPLES / "ex04_planetary_spectrum.py").read_text()
    for line in blocks[0].strip().splitlines():
        assert line.rstrip() in example, f"README line not in ex04_planetary_spectrum.py: {line!r}"


def test_every_example_of_the_gallery_is_run_here():
    """The documentation's gallery (docs/conf.py: sphinx-gallery over examples/, the scripts
    matching its filename_pattern) shows only examples that a test in this file runs."""
    conf = (ROOT / "docs" / "conf.py").read_text()
    assert '"examples_dirs": str(ROOT / "examples")' in conf
    pattern = re.search(r'"filename_pattern": r"([^"]+)"', conf).group(1)
    gallery = {p.stem for p in EXAMPLES.glob("*.py") if re.search(pattern, "/" + p.name)}
    run_here = set(re.findall(r'load_example\("(\w+)"\)', Path(__file__).read_text()))
    assert gallery == {p.stem for p in EXAMPLES.glob("*.py")}, "every example is in the gallery"
    assert gallery <= run_here, f"gallery examples no test runs: {sorted(gallery - run_here)}"
