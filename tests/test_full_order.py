"""Full-order reference of the flexible spur pair (issue 8): the reduced model against both gears
as unreduced FE bodies (:mod:`flexgear.dynamics.flexible.full_order`).

The reference shares with the reduced model only the FE mesh, the contact search and law, and
the integrator; it has no modes, no quasi-static condensation and no flank tables. The fast
variant runs the coarsest mesh for a few mesh cycles after a short load ramp; the slow one the
preset's operating point for 24 mesh cycles (>= 20) after the preset's run-in. Both run at a 25
us step (STEP), the rigid presets', not the flexible preset's 6.25 us: the two models share the
step, so the comparison measures the reduction (``tests/test_step_spectrum.py`` checks the step),
and the full order's Python time loop would take four times as long.
"""
import copy
import math

import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.flexible.reductions import reduce_flexible_gears
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.dynamics.flexible.full_order import (FlankPatches, FullOrderModel, comparable_config,
                                                  reference_comparison, window_metrics)
from flexgear.errors import ConfigError
from flexgear.reduction.flank import flank_patch_loads

STEP = 2.5e-5  # s, both models (module docstring)


def config(level, **sim):
    cfg = load_config("spur_pair_flexible")
    cfg.shafts = None  # the reference compares the gears: both on fixed revolutes (as reference_comparison does)
    cfg.flexible["level"] = level
    cfg.simulation.update({"step": STEP, **sim})
    return cfg


def test_flank_patch_from_stored_quadrature_equals_the_reduction_patch():
    """The full-order model loads and observes a flank through exactly the patch of the
    reduction's tables (assembled there by scikit-fem per radius, here from stored quadrature)."""
    cfg = config(0)
    red = reduce_flexible_gears(cfg)["wheel"]
    fp = FlankPatches(red.body.model, red.gear)
    r = red.tables.radius
    radii = np.array([r[0] + 1e-7, 0.3 * r[0] + 0.7 * r[1], 0.5 * (r[0] + r[-1]), r[-1] - 1e-7])
    for tooth, side in ((0, 1), (7, -1), (20, 1)):
        F, *_ = flank_patch_loads(red.body.model, red.gear, tooth, side, radii)
        for j, rj in enumerate(radii):
            f = np.zeros(F.shape[0])
            f[fp.dofs[tooth, side]] = fp.load(tooth, side, rj)
            assert np.abs(f - F[:, j]).max() <= 1e-12 * np.abs(F[:, j]).max()
            assert f.sum() != 0.0


def test_rigid_gear_or_bad_window_is_refused_before_the_run():
    cfg = config(0)
    cfg.flexible["gears"] = ["pinion"]
    model = build_model(cfg)
    reds = reduce_flexible_gears(cfg)
    with pytest.raises(ConfigError, match="wheel.*must be flexible"):
        FullOrderModel(model, reds, cfg.simulation["step"], cfg.simulation["hht_alpha"])
    with pytest.raises(ConfigError, match="not a whole number"):
        window_metrics(np.ones(10000), 2.5e-5, 240.0, 20)  # 20 periods = 3333.3 steps
    with pytest.raises(ConfigError, match="only"):
        window_metrics(np.ones(100), 2.5e-5, 240.0, 24)


def test_window_metrics_of_a_known_signal():
    h, fm = 2.5e-5, 240.0
    t = np.arange(1, 4001) * h
    F = (1000.0 + 30.0 * np.cos(2 * math.pi * fm * t + 0.3) + 4.0 * np.sin(2 * math.pi * 7 * fm * t)
         + 6.0 * np.cos(2 * math.pi * 5500.0 * t))  # 5.5 kHz: above the band, between lines
    m = window_metrics(F, h, fm, 24)
    assert m["mean"] == pytest.approx(1000.0, rel=1e-12)
    assert m["rms_ac"] == pytest.approx(math.sqrt((30.0 ** 2 + 4.0 ** 2 + 6.0 ** 2) / 2), rel=1e-12)
    assert m["rms_band"] == pytest.approx(math.sqrt((30.0 ** 2 + 4.0 ** 2) / 2), rel=1e-12)
    assert m["lines"][0] == pytest.approx(30.0, rel=1e-12)
    assert m["lines"][6] == pytest.approx(4.0, rel=1e-12)
    assert m["line_hz"][-1] <= 5e3 and m["lines"].size == 20


def _within(res, bar, keys=("mean", "rms", "rms_ac"), f_max=5e3):
    """The bar of issue 8: force mean and RMS (total, about the mean) and every mesh-harmonic
    line up to f_max of the reduced model within ``bar`` of the full order."""
    rel = res["relative"]
    for k in keys:
        assert abs(rel[k]) < bar, (k, res["reduced"][k], res["full"][k])
    sel = res["full"]["line_hz"] <= f_max
    lines_f, lines_r = res["full"]["lines"][sel], res["reduced"]["lines"][sel]
    assert np.all(np.abs(lines_f - lines_r) < bar * lines_f), (lines_r, lines_f)


def test_the_comparison_leaves_out_the_blocks_the_full_order_model_lacks():
    """reference_comparison runs both models without [shafts] and [lubrication] (the full-order
    model has neither: a friction or film on the reduced side only would be compared with a
    model without) and says which it left out; the user's configuration keeps both."""
    from flexgear.config import loads_config, preset_path

    cfg = loads_config(preset_path("spur_pair_flexible").read_text()
                       + "\n[lubrication]\nfriction_coefficient = 0.05\n")
    said = []
    out = comparable_config(cfg, said.append)
    assert out.shafts is None and out.lubrication is None
    assert cfg.shafts and cfg.lubrication.friction_coefficient == 0.05
    assert [m.split(" left out")[0] for m in said] == ["full-order reference: [shafts]",
                                                     "full-order reference: [lubrication]"]
    assert comparable_config(out, said.append) is out and len(said) == 2


def test_reduced_matches_full_order_coarse_and_short():
    """Coarsest mesh, load ramp 2 ms, one mesh cycle of run-in and 3 compared: the reduced
    model's force mean and RMS within 2 % of the full order, and its mesh lines up to 2 kHz (in
    this short window after the ramp the lines above differ by more: see the slow variant)."""
    cfg = config(0, run_in=1 / 240)
    cfg.load["ramp"] = 0.002
    res = reference_comparison(cfg, cycles=3)
    _within(res, 0.02, f_max=2e3)


def light_damping(level):
    """``spur_pair_flexible`` on fixed revolutes with a 5 % mesh damping ratio instead of the
    paper's IMPACT C, 0.1 s of run-in (the load ramp takes 0.05 s).

    Why not the paper's C: it is a mesh damping ratio of about 50 and acts between the gear
    frames, i.e. on the bores. In the full order (and with the reduced model's modes integrated)
    it locks the light hub of each gear to the other gear while the rim vibrates on the hub's
    torsional stiffness: the hub's inertia, which modal truncation changes, then decides the
    response (the integrated-mode model rings at 15-20 kHz with 6x the full order's content).
    That is a property of where that damper acts, not of the reduction (with the preset's
    condensed modes under the paper's C the lines at 3.6-4.6 kHz differ by up to 4.8 %, level
    1); at a realistic damping the comparison measures the reduction.
    """
    cfg = load_config("spur_pair_flexible").use_damping_ratio(0.05)
    cfg.shafts = None
    cfg.flexible["level"] = level
    cfg.simulation.update(run_in=0.1, step=STEP)
    return cfg


@pytest.fixture(scope="module")
def preset_point():
    """Level 1, the preset's speed and load, a 25 us step, 24 mesh cycles (>= 20) after the
    run-in, every mode of the reduction below the cutoff (100 kHz) integrated as a coordinate
    (``dynamic_cutoff = cutoff``): the reduced model with the same dynamics as the full order
    below the cutoff, the residual flexibility above it condensed."""
    cfg = light_damping(1)
    cfg.flexible["cutoff"] = 100e3  # above static_frequency(25 us) = 48 kHz
    cfg.flexible["dynamic_cutoff"] = cfg.flexible["cutoff"]
    return cfg, reference_comparison(cfg, cycles=24)


@pytest.mark.slow
def test_reduced_model_matches_the_full_order_at_the_preset_operating_point(preset_point):
    """Force mean, RMS (total and about the mean) and every mesh line up to 5 kHz within 2 %
    of the full-order FE model (measured: RMS about the mean +0.15 %, lines within 1.94 %;
    level 1 because the preset's level 2 takes about twice as long:
    ``studies/full_order_reference.py``)."""
    _within(preset_point[1], 0.02)


@pytest.mark.slow
def test_condensed_modes_match_the_full_order_at_the_preset_operating_point(preset_point):
    """The preset's default, every mode condensed (dynamic_cutoff 2 kHz), against the same full
    order: force mean, RMS and RMS about the mean of the content up to 5 kHz, and every mesh
    line up to 5 kHz, within 2 % (measured: RMS in the band +0.18 %, lines within 0.99 %).

    The condensed modes respond quasi-statically to the contact forces and to the inertia load
    of their frame's acceleration (:func:`flexgear.dynamics.flexible.compliant.inertia_flank_value`);
    without the latter the RMS about the mean was 5.7 % low and the 3840 Hz line 2.35 % off.
    Their own inertia is left out: above the band, at the mesh resonance as the 25 us step
    renders it (7-8.6 kHz, lines of up to 4x the first), that moves the peak, so the RMS about
    the mean over the whole spectrum is 2.0 % below the full order's (+0.15 % with every mode
    integrated, the test above). At the flexible preset's 6.25 us step it matters below 5 kHz
    too: see the next test.
    """
    cfg, res = preset_point
    cfg = copy.deepcopy(cfg)
    cfg.flexible["dynamic_cutoff"] = 2000.0
    h = res["h"]
    r = simulate(build_model(cfg), res["t_end"], h, 1, alpha=cfg.simulation["hht_alpha"])
    m = window_metrics(r.mesh[:, 0, 0], h, res["f_mesh"], res["cycles"])
    full = res["full"]
    keys = ("mean", "rms", "rms_band")
    rel = {k: (full[k] - m[k]) / full[k] for k in keys}
    _within({"relative": rel, "reduced": m, "full": full}, 0.02, keys=keys)


@pytest.mark.slow
def test_integrated_condensed_modes_match_the_full_order_at_the_flexible_presets_step():
    """The comparison above at the flexible presets' 6.25 us step (the step the spectra up to 5
    kHz need, ``tests/test_step_spectrum.py``) and their 200 kHz cutoff: the full order's FE
    modes at 31-64 kHz are then partly resolved (omega h = 1.2 at 31 kHz), so the condensed
    modes must carry their own inertia: integrated in the contact solve (the default,
    :mod:`flexgear.dynamics.flexible.condensed`), force mean, RMS, RMS about the mean over the whole
    spectrum and every mesh line up to 5 kHz within 2 % of the full order (measured: lines within
    1.56 %, RMS about the mean 1.55 %; about 15 min: ``python studies/full_order_reference.py
    --level 1 --run-in 0.1 --damping-ratio 0.05 --step 6.25e-6``). Quasi-statically condensed
    they were up to 4.8 % off at 2.4-4.8 kHz and 21 % low in RMS about the mean; integrated with
    a 100 kHz cutoff, which leaves the 100-194 kHz modes that the step resolves to the static
    residual tables, 2.1 % (4080 Hz) and 3.2 %."""
    cfg = light_damping(1)
    cfg.simulation["step"] = 6.25e-6
    cfg.flexible["dynamic_cutoff"] = 2000.0
    assert cfg.flexible["condensation"] == "integrated" and cfg.flexible["cutoff"] == 200e3
    res = reference_comparison(cfg, cycles=24)
    _within(res, 0.02, keys=("mean", "rms", "rms_ac"))
