"""A compliant contact whose total force is clipped at zero still loads the gear's modes.

The IMPACT damper acts between the rigid frames: a separating tooth pair's damper pull can
exceed its elastic force F_e, and the total force on the frames, F_e + damper, is then clipped
at zero. The flank deflection of the contact problem, the condensed modes
(:func:`flexgear.dynamics.flexible.condensed.condensed_response`) and the full-order reference
(:mod:`flexgear.dynamics.flexible.full_order`) all keep the elastic force F_e on the gear's
body; the modes as coordinates of the solver must too, or their equations differ from the
condensed modes' and the unloaded modes ring when the pair lets go (docs/theory/condensation.md,
*Clipped contacts*). With the paper's C (a mesh damping ratio of about 50) every pair that
leaves the mesh goes through such a state, so it decides whether the two formulations agree.
"""
import copy

import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.dynamics.flexible.full_order import reference_comparison

STEP = 2.5e-5  # s: the rigid presets' step (static_frequency = 48 kHz, below the cutoff)
T_END = 0.04  # s: load ramp 10 ms, then 7 mesh periods at 240 Hz


def paper_damping_config():
    """``spur_pair_flexible`` at mesh level 0 on fixed revolutes with the paper's contact damping,
    a 100 kHz cutoff and a 10 ms load ramp."""
    cfg = load_config("spur_pair_flexible")
    cfg.shafts = None
    cfg.flexible["level"] = 0
    cfg.flexible["cutoff"] = 100e3
    cfg.load["ramp"] = 0.01
    return cfg


@pytest.fixture(scope="module")
def paper_damping_runs():
    """:func:`paper_damping_config` with the condensed modes integrated (default) and with
    every mode a coordinate."""
    cfg = paper_damping_config()
    out = {}
    for label, dynamic in (("condensed", 2000.0), ("coordinates", 100e3)):
        c = copy.deepcopy(cfg)
        c.flexible["dynamic_cutoff"] = dynamic
        model = build_model(c)
        assert (sum(fb.modes for fb in model.flex) > 20) == (label == "coordinates")
        out[label] = simulate(model, T_END, STEP, 1, alpha=-0.1)
    return out


def test_the_runs_pass_through_clipped_contacts(paper_damping_runs):
    """Precondition of the next test: pairs with a positive Hertz approach (rigid overlap above
    the flank deflection: F_e > 0) and a zero total force occur, at every mesh period."""
    r = paper_damping_runs["condensed"]
    F, depth = r.pair_f[..., 0], r.pair_f[..., 1]
    defl = r.records.pair_deflection
    clipped = (F == 0.0) & (depth - defl > 1e-7)  # 0.1 um of Hertz approach: F_e of tens of N
    t = np.arange(1, F.shape[0] + 1) * STEP
    steps = np.flatnonzero(clipped.any(axis=(1, 2)) & (t > 0.015))
    assert steps.size > 0
    periods = np.unique(np.floor(t[steps] * 240.0))
    assert periods.size >= 5


def test_modes_as_coordinates_equal_condensed_modes_under_clipped_contacts(paper_damping_runs):
    """After the load ramp the two formulations give the same mesh force within 1e-3 of its
    peak (the tolerance of ``tests/test_condensed.py`` at a 5 % damping ratio, where no pair
    clips). With the modal coordinates unloaded while a pair is clipped they differed by up to
    1.2 kN (11 % of the force) for about 100 us after every pair's exit, the modes at 40-60 kHz
    ringing, and at the preset's 200 kHz cutoff the run diverged at 36 ms."""
    a = paper_damping_runs["condensed"].mesh[:, 0, 0]
    b = paper_damping_runs["coordinates"].mesh[:, 0, 0]
    t = np.arange(1, a.size + 1) * STEP
    after = t > 0.015
    peak = np.abs(b[after]).max()
    assert np.abs(a - b)[after].max() <= 1e-3 * peak


@pytest.mark.slow
def test_modes_as_coordinates_match_the_full_order_under_clipped_contacts():
    """The same model with every mode a coordinate against the full-order FE reference (which
    loads the FE flank dofs with F_e of every active contact), six mesh periods after the ramp:
    the force's mean, RMS and RMS about the mean within 2 % (the bar of
    ``tests/test_full_order.py``; measured 0.5 % about the mean; with the modes unloaded while
    clipped it was 88 % too high). About 1 min, most of it the full order's Python loop."""
    cfg = paper_damping_config()
    cfg.flexible["dynamic_cutoff"] = cfg.flexible["cutoff"]
    cfg.simulation.update(step=STEP, run_in=0.012)
    res = reference_comparison(cfg, cycles=6)
    for k in ("mean", "rms", "rms_ac"):
        assert abs(res["relative"][k]) < 0.02, (k, res["reduced"][k], res["full"][k])
