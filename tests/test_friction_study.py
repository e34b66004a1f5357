"""The friction study (studies/friction.py) in its --quick form on the spur pair, and the
presets spur_pair_friction and mercury_1a_friction (issue 24)."""
import json
import runpy
import sys
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest

from flexgear.app.run import run
from flexgear.config import load_config
from flexgear.results.store import save

STUDY = Path(__file__).resolve().parents[1] / "studies" / "friction.py"


@pytest.mark.parametrize("preset, meshes", [("spur_pair_friction", ["pinion-wheel"]),
                                            ("mercury_1a_friction", ["sun-planet1", "planet1-ring"])])
def test_friction_presets_run_and_write_friction_and_film(preset, meshes, tmp_path):
    cfg = load_config(preset)
    assert cfg.lubrication is not None and cfg.lubrication.lubricant is not None
    cfg.simulation.update(run_in=0.06, duration=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = run(cfg)
    f = save(res, tmp_path / "results.h5")
    with h5py.File(f, "r") as h5:
        for mesh in meshes:
            g = h5[f"meshes/{mesh}"]
            for name in ("friction_force", "friction_power", "sliding_speed", "contact_position", "film_central",
                         "film_minimum", "film_ratio"):
                assert name in g, (mesh, name)
            assert 0.9 < g.attrs["mesh_efficiency"] < 1.0
            h = g["film_minimum"][()]
            assert np.isfinite(h).any() and np.all(h[np.isfinite(h)] > 0)
            assert np.all(np.abs(g["friction_force"][()]) > 0)


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("friction_study")
    argv = sys.argv
    sys.argv = ["friction.py", "-o", str(out), "--quick", "--sets", "spur"]
    try:
        with pytest.raises(SystemExit) as done:  # a study ends as a program: status 0
            runpy.run_path(str(STUDY), run_name="__main__")
        assert done.value.code == 0
    finally:
        sys.argv = argv
    return out, json.loads((out / "checks.json").read_text())


def test_quick_study_writes_its_figures_and_report(quick):
    out, _ = quick
    for f in ("efficiency.png", "force_spur.png", "spectrum_spur.png", "film_spur.png", "report.md"):
        assert (out / f).stat().st_size > 0, f


def test_quick_study_physics(quick):
    """Friction off: no friction outputs but the efficiency, 1, and no force across the line of action where the contact
    crosses the pitch point (one pair carries the load there, on the involutes: the normal force
    lies on the line of action; elsewhere the soft contact's tip corners add some). With friction
    the across-LOA force reverses at every pitch-point crossing (the sliding speed changes sign
    there: before and after differ by about 2 mu N), and the mesh efficiency falls as the constant
    coefficient grows."""
    _, checks = quick
    rec = checks["sets"]["spur"]
    off, const = rec["off/pinion-wheel"], rec["constant/pinion-wheel"]
    assert off["efficiency"] == 1.0 and off["film_central_pitch"] is None  # a coefficient of 0 loses nothing
    assert off["reversal"]["crossings"] >= 8
    assert off["reversal"]["at_max"] < 1e-3 * off["normal_mean"]
    for v in ("constant", "benedict_kelley", "xu"):
        r = rec[f"{v}/pinion-wheel"]
        assert r["reversal"]["crossings"] == off["reversal"]["crossings"], v
        assert r["reversal"]["reversed"] == 1.0, (v, r["reversal"])
        assert 0.9 < r["efficiency"] < 1.0, v
        assert 0.0 < r["film_central_pitch"] < 1e-5 and r["lambda_pitch"] > 0, v
    jump = np.abs(np.subtract(const["reversal"]["after"], const["reversal"]["before"]))
    assert np.allclose(jump, 2 * 0.05 * const["normal_mean"], rtol=0.1), jump
    eff = [r["efficiency"] for r in checks["efficiency"]["coefficient"]]
    mu = [r["mu"] for r in checks["efficiency"]["coefficient"]]
    assert mu == sorted(mu) and len(mu) == 3
    assert np.all(np.diff(eff) < 0), eff
    assert len(checks["efficiency"]["load_speed"]) == 4


def test_friction_figures_say_what_their_lines_and_axes_are():
    """The friction figure's sliding-speed panel (flexgear.results.friction_plot.fig_friction)
    has a legend for its alternating solid and dashed lines (successive tooth pairs), and every
    axis label of it and of the study's figures names a quantity with its unit in brackets or
    parentheses; the bottom axes of a column carry the x label."""
    import re

    from flexgear.results.friction_plot import fig_friction

    study = runpy.run_path(str(STUDY))
    cfg = load_config("spur_pair_friction")
    cfg.simulation.update(run_in=0.06, duration=0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = run(cfg)
    rows = [{"speed_hz": 10.0, "torque": t, "efficiency": e} for t, e in ((100.0, 0.985), (200.0, 0.99))]
    mus = [{"mu": mu, "efficiency": 1 - 0.2 * mu, "closed_form": 1 - 0.19 * mu} for mu in (0.02, 0.05)]
    figs = {"friction": fig_friction(res, "pinion-wheel"),
            "force": study["fig_force"]({"constant": res}, cfg, ["pinion-wheel"], "t"),
            "spectrum": study["fig_spectrum"]({"constant": res}, cfg, "pinion-wheel", ["pinion", "wheel"], "t", 2e3),
            "film": study["fig_film"]({"constant": res}, ["pinion-wheel"], "t"),
            "efficiency": study["fig_efficiency"](rows, mus)}
    unit = re.compile(r"\S.*[\[(][^\])]+[\])]\s*$", re.S)
    for name, fig in figs.items():
        for ax in fig.axes:
            assert unit.match(ax.get_ylabel()), (name, ax.get_ylabel())
            if ax.get_xlabel() or ax.get_subplotspec().is_last_row():
                assert unit.match(ax.get_xlabel().split(";")[0]), (name, ax.get_xlabel())
    sliding = figs["friction"].axes[1]
    legend = sliding.get_legend()
    assert legend is not None
    styles = {h.get_linestyle() for h in legend.legend_handles}
    assert styles == {"-", "--"}
    assert {line.get_linestyle() for line in sliding.get_lines() if len(line.get_xdata()) > 2} == {"-", "--"}
