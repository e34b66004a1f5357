"""Condensed modes integrated inside the contact solve (:mod:`flexgear.dynamics.flexible.condensed`).

Integrated, the condensed modes obey the equations of the modes as coordinates of the Newton
system, mode by mode: the same model with every mode a coordinate (``dynamic_cutoff = cutoff``)
must give the same forces, while the quasi-static condensation, at a step that begins to
resolve the modes, must not. The full-order comparison at the flexible presets' step is the
slow test of ``tests/test_full_order.py``.
"""
import copy
import math

import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.flexible.condensed import STATIC_SHARE, static_frequency
from flexgear.dynamics.integrator.hht import hht_coefficients
from flexgear.dynamics.integrator.simulation import simulate

STEP = 6.25e-6  # s, the flexible presets' step


def light_damping_level0():
    """``spur_pair_flexible`` at mesh level 0 on fixed revolutes with a 5 % mesh damping ratio
    (the paper's C locks the frames: ``tests/test_full_order.py::light_damping``)."""
    cfg = load_config("spur_pair_flexible").use_damping_ratio(0.05)
    cfg.shafts = None
    cfg.flexible["level"] = 0
    cfg.flexible["cutoff"] = 100e3
    return cfg


@pytest.fixture(scope="module")
def three_models():
    """Mesh force over 0.06 s (load ramp and 14 mesh periods) of the same reduction with the
    condensed modes integrated, with every mode a coordinate, and condensed quasi-statically."""
    cfg = light_damping_level0()
    out = {}
    for label, dynamic, condensation in [("integrated", 2000.0, "integrated"), ("coordinates", None, "integrated"),
                                         ("static", 2000.0, "static")]:
        c = copy.deepcopy(cfg)
        c.flexible["dynamic_cutoff"] = dynamic if dynamic is not None else c.flexible["cutoff"]
        model = build_model(c)
        if label == "coordinates":
            assert sum(fb.modes for fb in model.flex) > 20
        else:
            assert sum(fb.modes for fb in model.flex) == 0
        r = simulate(model, 0.06, STEP, 8, alpha=-0.1, condensation=condensation)
        out[label] = r.mesh[:, 0, 0]
    return out


def test_integrated_condensed_modes_equal_the_modes_as_coordinates(three_models):
    """Over the second half of the run (load ramp done), the integrated condensed modes give the
    modal coordinates' force within 1e-3 of its peak (measured 8e-5: the coordinates take the
    frame's convective acceleration into the HHT-weighted forces, the condensed modes at the
    step's end), the quasi-static condensation differs by more than 1e-2 (measured 3.7e-2, 11 %
    of the force's standard deviation), so the comparison can tell them apart."""
    a, b, s = three_models["integrated"], three_models["coordinates"], three_models["static"]
    half = slice(len(b) // 2, None)
    peak = np.abs(b[half]).max()
    assert np.abs(a - b)[half].max() <= 1e-3 * peak
    assert np.abs(s - b)[half].max() > 1e-2 * peak


def test_static_frequency_is_where_one_hht_step_gives_the_static_share():
    """An undamped unit-mass oscillator at rest, loaded by a unit force from the start of one
    HHT-alpha step (residual (1 + alpha)(k x - 1) at the end, -alpha (k x_0 - 0) = 0 at the
    start), moves by kappa / k in the step; at ``static_frequency`` kappa is STATIC_SHARE, and
    it tends to 1 for stiffer, 0 for softer oscillators."""
    h, alpha = STEP, -0.1
    beta, _ = hht_coefficients(alpha)

    def one_step(f_hz):
        k = (2 * math.pi * f_hz) ** 2
        # a + (1 + alpha)(k (beta h^2 a) - 1) = 0
        a = (1 + alpha) / (1 + (1 + alpha) * k * beta * h * h)
        return beta * h * h * a * k  # x / (1 / k)

    f = static_frequency(h, alpha)
    assert one_step(f) == pytest.approx(STATIC_SHARE, rel=1e-12)
    assert one_step(10 * f) > 0.999 and one_step(f / 100) < 0.01
    assert static_frequency(4 * h, alpha) == pytest.approx(f / 4)
