"""Richardson extrapolation on analytic sequences, then mesh convergence of the gear FE models."""
import numpy as np
import pytest

from flexgear.convergence import errors_decrease, observed_order, richardson
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
