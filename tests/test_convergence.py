"""Richardson extrapolation on analytic sequences, then mesh convergence of the gear FE models."""
import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.fe.convergence import errors_decrease, observed_order, richardson
from flexgear.stiffness.fe_convergence import gear_convergence
from flexgear.errors import ConfigError


@pytest.mark.parametrize("p", [1.0, 2.0, 3.0, 4.0])
@pytest.mark.parametrize("r", [2.0, 1.5, np.sqrt(2.0)])
def test_richardson_recovers_power_law(p, r):
    f0, c = 7.5, -3.2
    h = 0.1 * r ** -np.arange(4.0)
    f = f0 + c * h ** p
    res = richardson(f, ratio=r)  # h = r^-i: only ratios matter
    assert res.order == pytest.approx(p, rel=1e-8)
    assert res.extrapolated == pytest.approx(f0, rel=1e-10)
    assert np.allclose(res.rel_error, np.abs(c * h ** p) / f0, rtol=1e-6)
    assert errors_decrease(res.rel_error)
    assert res.monotone


def test_richardson_nonconstant_ratio_and_vectors():
    h = np.array([0.5, 0.3, 0.17, 0.1])
    f = np.stack([2.0 + h ** 2, 1.0 - 0.5 * h ** 1.3, 4.0 + 0.1 * h ** 3], axis=1)
    res = richardson(f, h=h)
    assert np.allclose(res.order, [2.0, 1.3, 3.0], rtol=1e-6)
    assert np.allclose(res.extrapolated, [2.0, 1.0, 4.0], rtol=1e-9)
    assert res.rel_error.shape == (4, 3)


def test_richardson_higher_order_term_is_small():
    # f = f0 + c h^2 + d h^3: observed order tends to 2; the extrapolation removes the h^2
    # term, so its error (O(h^3)) is an order of magnitude below the finest level's (O(h^2))
    h = 0.05 * 2.0 ** -np.arange(3.0)
    f = 1.0 + h ** 2 + h ** 3
    res = richardson(f, h=h)
    assert res.order == pytest.approx(2.0, abs=0.05)
    assert abs(res.extrapolated - 1.0) < 0.1 * abs(f[-1] - 1.0)
    # GCI bounds the true error of the finest level
    assert abs(f[-1] - 1.0) / 1.0 < res.gci


def test_oscillating_sequence_is_flagged():
    res = richardson([1.0, 1.1, 1.05], ratio=2.0)
    assert not res.monotone
    assert np.isnan(res.order) and np.isnan(res.extrapolated)


def test_bad_input():
    with pytest.raises(ConfigError):
        richardson([1.0, 2.0], ratio=2.0)
    with pytest.raises(ConfigError):
        richardson([1.0, 2.0, 3.0])
    with pytest.raises(ConfigError):
        richardson([1.0, 2.0, 3.0], h=[0.1, 0.2, 0.3])
    with pytest.raises(ConfigError):
        observed_order(1, 2, 3, 0.1, 0.2, 0.3)


# ------------------------------------------------------------------ gear FE models
@pytest.fixture(scope="module")
def cfg():
    return load_config("mercury_1a")


def test_sun_converges_on_coarse_levels(cfg, tmp_path):
    """Levels 0, 1, 2 of the sun: the errors against the Richardson values fall from level to
    level and the observed orders are positive, for the ten clamped-hub frequencies and the
    pitch-point tooth stiffness."""
    res = gear_convergence(cfg.gears["sun"], [0, 1, 2], material=cfg.material, cache_dir=tmp_path)
    assert np.all(res.freq_rich.monotone) and res.stiff_rich.monotone
    assert np.all(res.freq_rich.order > 0) and res.stiff_rich.order > 0
    assert np.all(errors_decrease(res.freq_rich.rel_error))
    assert errors_decrease(res.stiff_rich.rel_error)
    # a conforming displacement FE model is too stiff: frequencies and stiffness fall under
    # refinement
    assert np.all(np.diff(res.freqs, axis=0) < 0)
    assert np.all(np.diff(res.stiffness) < 0)


@pytest.mark.slow
def test_sun_default_level_is_converged(cfg, tmp_path):
    """Full check (levels 1-4): the default level 2 lies within 1 % (frequencies) and 2 %
    (tooth stiffness) of the Richardson-extrapolated values."""
    res = gear_convergence(cfg.gears["sun"], [1, 2, 3, 4], material=cfg.material, cache_dir=tmp_path)
    assert np.all(res.freq_rich.order > 0) and res.stiff_rich.order > 0
    assert np.all(errors_decrease(res.freq_rich.rel_error))
    assert errors_decrease(res.stiff_rich.rel_error)
    assert res.check(2, freq_tol=0.01, stiff_tol=0.02), res.level_errors(2)
