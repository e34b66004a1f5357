"""The ADAMS IMPACT law, its STEP function and the unit conversion at the edge."""
import math
import warnings

import pytest

from flexgear.config import load_config, loads_config, preset_path
from flexgear.dynamics.contact.laws import impact_force, step, step_derivative
from flexgear.errors import ConfigError
from flexgear.units import impact_to_si


def test_step_matches_adams_definition():
    # STEP(x; x0, h0, x1, h1) = h0 + (h1 - h0) D^2 (3 - 2D)
    assert step(-1.0, 0.0, 2.0, 1.0, 5.0) == 2.0
    assert step(2.0, 0.0, 2.0, 1.0, 5.0) == 5.0
    assert step(0.5, 0.0, 2.0, 1.0, 5.0) == pytest.approx(3.5)  # symmetric midpoint
    D = 0.25
    assert step(0.25, 0.0, 0.0, 1.0, 1.0) == pytest.approx(D * D * (3 - 2 * D))
    # smooth: derivative vanishes at both ends and matches finite differences inside
    assert step_derivative(0.0, 0.0, 0.0, 1.0, 1.0) == 0.0
    assert step_derivative(1.0, 0.0, 0.0, 1.0, 1.0) == 0.0
    h = 1e-7
    for x in (0.1, 0.4, 0.9):
        fd = (step(x + h, 0, 0, 1, 1) - step(x - h, 0, 0, 1, 1)) / (2 * h)
        assert step_derivative(x, 0, 0, 1, 1) == pytest.approx(fd, rel=1e-6)


def test_impact_law():
    K, e, C, d = 2.0e9, 1.3, 3.0e6, 3e-4
    # no contact, no force
    assert impact_force(0.0, 1.0, K, e, C, d)[0] == 0.0
    assert impact_force(-1e-6, 1.0, K, e, C, d)[0] == 0.0
    # elastic part
    delta = 5e-6
    F, dF, c = impact_force(delta, 0.0, K, e, C, d)
    assert F == pytest.approx(K * delta**e)
    assert dF == pytest.approx(e * K * delta ** (e - 1))
    # damping rises smoothly from 0 at first touch to C at penetration d
    assert impact_force(1e-12, 1.0, K, e, C, d)[2] < 1e-6 * C
    assert impact_force(d, 1.0, K, e, C, d)[2] == pytest.approx(C)
    assert impact_force(2 * d, 1.0, K, e, C, d)[2] == pytest.approx(C)
    # the force never pulls: fast separation cannot make it negative
    assert impact_force(delta, -1e3, K, e, C, d)[0] == 0.0
    # with damping the force is larger while approaching than while separating
    assert impact_force(delta, 0.1, K, e, C, d)[0] > impact_force(delta, -0.01, K, e, C, d)[0]


def test_adams_n_mm_units_give_the_same_force_in_si():
    # ADAMS evaluates F[N] = K[N/mm^e] (delta[mm])^e + STEP * C[N s/mm] * ddelta[mm/s]
    Kmm, e, Cmm, dmm = 3e5, 1.3, 3000.0, 0.3
    K, e2, C, d = impact_to_si(Kmm, e, Cmm, dmm, "N-mm")
    assert e2 == e
    assert K == pytest.approx(3e5 * 1000**1.3)  # 2.38e9 N/m^1.3 (ADAMS evaluates the law in N-mm units: docs/paper_parameters.md)
    assert K == pytest.approx(2.383e9, rel=1e-3)
    assert C == pytest.approx(3e6) and d == pytest.approx(3e-4)
    for delta_mm, rate_mm in ((0.01, 0.0), (0.05, 20.0), (0.2, -3.0)):
        F_mm = Kmm * delta_mm**e + Cmm * step(delta_mm, 0, 0, dmm, 1.0) * rate_mm
        F_si = impact_force(delta_mm * 1e-3, rate_mm * 1e-3, K, e, C, d)[0]
        assert F_si == pytest.approx(max(F_mm, 0.0), rel=1e-12)


def test_unknown_unit_system_is_rejected():
    with pytest.raises(ConfigError, match="contact.units"):
        impact_to_si(1.0, 1.3, 1.0, 1.0, "lbf-in")


def test_presets_use_the_papers_adams_reading():
    cfg = load_config("mercury_1a")
    for pair in cfg.pairs.values():
        law = cfg.contact_law(pair)
        assert law.K == pytest.approx(3e5 * 1000**1.3) and law.e == 1.3
        assert law.C == pytest.approx(3e6) and law.d == pytest.approx(3e-4)


def test_eq5_stiffness_for_the_actual_pair_and_mixed_reading_is_announced():
    text = preset_path("mercury_1a").read_text().replace('stiffness = 3.0e5', 'stiffness = "eq5"')
    cfg = loads_config(text)
    sp, pr = cfg.pairs["sun-planet"], cfg.pairs["planet-ring"]
    with pytest.warns(UserWarning, match="exponent"):
        law = cfg.contact_law(sp)
    # Eq. (5): K = 4/3 sqrt(R) E*, R = 3.831 mm, E* = 1.1538e11 Pa -> 3.01e5 N/mm^1.5 (paper)
    K_mm = law.K / 1000**1.3
    assert K_mm == pytest.approx(3.01e5, rel=2e-3)
    # planet-ring: larger equivalent radius (internal mesh) -> stiffer, 4.99e5 N/mm^1.5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cfg.contact_law(pr).K / 1000**1.3 == pytest.approx(4.99e5, rel=2e-3)
    # the SI Hertz reading with e = 1.5 gives K in N/m^1.5 without any warning
    text_si = text.replace('units = "N-mm"', 'units = "SI"').replace("exponent = 1.3", "exponent = 1.5")
    text_si = text_si.replace("damping = 3000.0", "damping = 3.0e6").replace("penetration_depth = 0.3", "penetration_depth = 3e-4")
    cfg_si = loads_config(text_si)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        law_si = cfg_si.contact_law(sp)
    assert law_si.K == pytest.approx(4 / 3 * math.sqrt(sp.hertz_radius) * 1.1538e11, rel=1e-3)
    assert law_si.e == 1.5
