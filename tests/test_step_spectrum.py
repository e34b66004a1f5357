"""Convergence of the flexible presets' integration step in the frequency domain (issue 8: "show
that the step stays converged with the added stiffness"; converged means every discretisation,
each shown by a test that can fail).

Why the flexible presets need a smaller step than the rigid ones: their mesh modes are stiff
(spur pair: 14.9 kHz with the shafts, 9.3 kHz with the pinion held; flexible MERCURY 1-A: an
8.9 kHz rotational mode) and HHT-alpha renders a mode of angular frequency omega at a lower
frequency, the period error growing as (omega h)^2 / 12
(:func:`flexgear.dynamics.modal.analysis.integrated_frequency`: at 25 us the 8.9 kHz mode runs at 7.6
kHz, at 6.25 us at 8.8 kHz). The dynamic amplification of the mesh lines a few kHz below such a
mode then depends on the step. The time-domain checks (``tests/test_flexible.py``) bound the
force within 1 % of its mean; the lines at 3-5 kHz are 1-3 % of the first line, so they need a
check of their own.

Measure: the mesh normal force over a whole number of mesh periods after the run-in, on the
integration grid (:func:`flexgear.dynamics.flexible.full_order.window_metrics`); every mesh-harmonic line
up to 5 kHz against the run with half the step, relative to the line itself, and for lines
below a tenth of the band's largest line (-20 dB: a cancellation line like the spur pair's 7th
under the paper's C has a few mN) relative to that tenth. The Newton tolerance is tightened to
1e-12 m: the force recorded at a step is that of the last Newton evaluation, up to the mesh
stiffness times the tolerance from the accepted state (4e8 N/m x 1e-10 m = 0.04 N at the
solver's default), a noise that would blur lines of a few N by 1-2 % between runs.

``studies/step_spectrum.py`` prints the whole table (both presets, both dampings, 25 to 1.5625
us) with the observed order.
"""

import numpy as np
import pytest

from conftest import load_script
from flexgear.config.loader import time_grid
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.flexible.full_order import window_metrics
from flexgear.dynamics.integrator.simulation import simulate

BAR = 0.02  # every line within 2 % of the run with half the step (issue 8's bar for lines to 5 kHz)
STUDY = load_script("studies/step_spectrum.py")
FLOOR = STUDY.FLOOR  # lines below this fraction of the band's largest line are held to BAR x FLOOR x largest
TOL = 1e-12  # m, Newton tolerance (see the module docstring)
OLD_STEP = 2.5e-5  # s: the step the flexible presets had, the rigid presets' step


def preset(name, damping="paper", level=None):
    """The preset with the paper's IMPACT C or (``damping="ratio"``) a 5 % mesh damping ratio
    (the study's :func:`preset_config`)."""
    return STUDY.preset_config(name, damping, level)


def lines(cfg, model, h, cycles, meshes=(0,)):
    """Mesh-harmonic lines up to 5 kHz [N] of the last ``cycles`` mesh periods, per mesh index."""
    fm = cfg.mesh_frequency()
    r = simulate(model, cfg.simulation["run_in"] + cycles / fm, h, 1, alpha=cfg.simulation["hht_alpha"], tol=TOL)
    return np.array([window_metrics(r.mesh[:, k, 0], h, fm, cycles)["lines"] for k in meshes])


line_error = STUDY.line_error  # relative to each line, or to FLOOR x the largest line if larger


def change_ratio(a, b, c):
    """Largest line change between runs a -> b over b -> c, for steps h, h/2, h/4: about 4 for
    a second-order integrator."""
    return np.abs(a - b).max() / np.abs(b - c).max()


def test_preset_step_is_used_as_given():
    """The flexible presets' step divides the output interval, so :func:`time_grid` uses it as
    given: the step the tests below check is the step a run takes."""
    for name in ("spur_pair_flexible", "mercury_1a_flexible"):
        cfg = preset(name)
        h, every = time_grid(cfg.simulation)
        assert h == cfg.simulation["step"]
        assert every * h == pytest.approx(1.0 / cfg.simulation["output_rate"], rel=1e-12)


def runs(cfg, factors, cycles, meshes=(0,), extra=()):
    """Lines at the preset's step h times each factor, and at the steps in ``extra`` [s]; keyed
    by the factor, the extra ones by their step."""
    model = build_model(cfg)
    h = cfg.simulation["step"]
    out = {k: lines(cfg, model, k * h, cycles, meshes) for k in factors}
    for step in extra:
        same = [k for k in factors if abs(k * h - step) < 1e-12]
        out[step] = out[same[0]] if same else lines(cfg, model, step, cycles, meshes)
    return out


@pytest.fixture(scope="module")
def spur_level0():
    """The flexible spur pair (shafts included, the paper's C) at FE level 0, 0.1 s of run-in
    (the load ramp takes 0.05 s) and 12 mesh periods, at 4, 2, 1 and 1/2 times the preset's
    step and at the old 25 us (a few seconds)."""
    cfg = preset("spur_pair_flexible", level=0)
    cfg.simulation["run_in"] = 0.1
    return runs(cfg, (4, 2, 1, 0.5), 12, extra=(OLD_STEP,))


def test_mesh_lines_are_converged_at_the_preset_step(spur_level0):
    """Fast variant: every line up to 5 kHz at the preset's step within 2 % of half that step
    (measured 0.7 %), while the old 25 us step is off by more than twice the bar on a line
    that carries > 2 % of the first line's amplitude (measured 14 % at 3120 Hz, a line of 3 %)."""
    L = spur_level0
    ref = L[0.5][0]
    assert line_error(L[1][0], ref).max() < BAR
    old = line_error(L[OLD_STEP][0], ref)
    real = ref >= 0.02 * ref[0]
    assert old[real].max() > 2 * BAR, old


def test_mesh_lines_converge_at_second_order(spur_level0):
    """HHT-alpha is second order: halving the step divides the largest line change by about 4
    (measured 3.4 and 4.2 for 4h -> 2h -> h -> h/2); required between 2^1.5 and 2^2.5."""
    L = spur_level0
    for a, b, c in ((4, 2, 1), (2, 1, 0.5)):
        assert 2 ** 1.5 < change_ratio(L[a], L[b], L[c]) < 2 ** 2.5, (a, b, c)


# ------------------------------------------------------------------------------- slow: presets
@pytest.mark.slow
@pytest.mark.parametrize("damping", ["paper", "ratio"])
def test_spur_pair_preset_lines_are_converged_at_its_step(damping):
    """``spur_pair_flexible`` at its level (2), shafts included, the preset's 0.2 s run-in, 21
    mesh periods: every line up to 5 kHz at the preset's step within 2 % of half the step
    (measured against 1.5625 us: 1.0 % with the paper's C, 0.4 % with 5 % damping; 10 us: 2.8
    and 1.0 %; 25 us: 15 and 7 %), the old 25 us beyond the bar, and second-order convergence
    from 4h down to h/2."""
    L = runs(preset("spur_pair_flexible", damping), (4, 2, 1, 0.5), 21, extra=(OLD_STEP,))
    assert line_error(L[1], L[0.5]).max() < BAR
    assert line_error(L[OLD_STEP], L[0.5]).max() > BAR
    for a, b, c in ((4, 2, 1), (2, 1, 0.5)):
        assert 2 ** 1.5 < change_ratio(L[a], L[b], L[c]) < 2 ** 2.5, (a, b, c)


@pytest.fixture(scope="module")
def mercury():
    """``mercury_1a_flexible`` at its level (2), the paper's C, the preset's 0.2 s run-in, 33 mesh
    periods (a whole number of steps at 25 us ... h/2), a sun-planet and a planet-ring mesh."""
    return runs(preset("mercury_1a_flexible"), (1, 0.5), 33, meshes=(0, 3), extra=(OLD_STEP,))


@pytest.mark.slow
def test_mercury_preset_step_cuts_the_line_error_of_the_old_step(mercury):
    """The preset's step brings MERCURY 1-A's lines up to 5 kHz at least twice as close to the
    run with half the step as the old 25 us (level 1, against 1.5625 us: 30 and 40 % at 25 us,
    14 and 14 % at 6.25 us for the two meshes)."""
    for k in range(2):
        new = line_error(mercury[1][k], mercury[0.5][k]).max()
        old = line_error(mercury[OLD_STEP][k], mercury[0.5][k]).max()
        assert new < 0.5 * old, (k, new, old)


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "measured at level 1: the lines up to 5 kHz of flexible MERCURY 1-A are 0.1-2.5 N (<= 1 % of the "
    "236 N mean; the mesh force's dynamic part, about 60-70 N RMS, is forced at 9.5 and 15-20 kHz, next to "
    "modes up to 19.7 kHz); at 6.25 us they are 14 % (up to 0.07 N) off the 1.5625 us run, at 3.125 us "
    "2.7 %, and they do not converge at a steady rate (orders 0.3-1.8 between 25 and 3.125 us)"))
def test_mercury_preset_lines_are_converged_at_its_step(mercury):
    """The spur pair's bar on ``mercury_1a_flexible``: every line up to 5 kHz at the preset's
    step within 2 % of half the step."""
    assert line_error(mercury[1], mercury[0.5]).max() < BAR
