"""studies/rigid_vs_flexible.py in its --quick form: the three models side by side obey the
physical relations the study reports on (spur pair in the default suite, MERCURY 1-A slow)."""
from pathlib import Path

import numpy as np
import pytest

from flexgear.dynamics.flexible.reductions import cross_mesh_coupling, reduce_flexible_gears
from conftest import load_script

STUDY = Path(__file__).resolve().parents[1] / "studies" / "rigid_vs_flexible.py"


def _study():
    return load_script(STUDY)


def _check(tmp_path, preset):
    mod = _study()
    studies, text = mod.execute(["--out", str(tmp_path), "--quick", "--presets", preset])
    s = studies[0]
    rim_coupling = {}
    if preset == "mercury":  # the sun's planet meshes load teeth a third of a turn apart
        cfg = s["flex_cfg"]
        sun = reduce_flexible_gears(cfg)["sun"]
        c = cross_mesh_coupling(sun, sun.gear.z // 3, 1, 0, 1)
        sun_meshes = [m for m in next(iter(s["metrics"].values())) if m.startswith("sun-")]
        rim_coupling = {m: (len(sun_meshes) - 1) * c for m in sun_meshes}
    for model in mod.MODELS:
        assert f"| {model}" in text
    for name in ("forces", "spectra", "te", "pair_loads", "deformed"):
        assert (tmp_path / f"{preset}_{name}.png").stat().st_size > 0
    assert (tmp_path / "report.md").read_text() == text
    # the fitted law reproduces the FE static TE at the fit loads (0.5 %)
    for fit in s["fits"].values():
        assert fit.max_rel_error < 5e-3
    for (model, damping), per_mesh in s["metrics"].items():
        for mesh, m in per_mesh.items():
            # the mean mesh force carries the static load T / r_b (within 2 % over the short record)
            assert m["mean"] == pytest.approx(m["W"], rel=0.02), (model, damping, mesh)
            # contact outside the theoretical path only adds contact: eps under load >= eps of the path
            eps = s["fits"][mod.pair_key(s["cfg"], mesh)].eps
            assert m["eps_load"] >= eps - 0.02, (model, damping, mesh)
            rim = rim_coupling.get(mesh, 0.0)
            if model in ("rigid (fitted)", "flexible") and not (model == "flexible" and rim):
                # mean TE = the FE's static TE of the single/double zones at the model's own
                # contact shares (5 %: the zones' inner shape differs from a power law)
                assert m["te_mean"] == pytest.approx(m["te_fe_load"], rel=0.05), (model, damping, mesh)
            if model == "flexible" and rim:
                # a sun mesh of the flexible model also deflects under the sun's other meshes
                # (through its rim), which the static FE of one pair leaves out: between the pair's
                # TE and that TE plus the other meshes' share, each at most c = the largest static
                # compliance between sun teeth a third of a turn apart over the largest self
                # compliance (modes + residual tables: the full FE's, tests/test_flexible.py)
                assert 0.95 * m["te_fe_load"] <= m["te_mean"] <= (1.0 + rim) * 1.05 * m["te_fe_load"], \
                    (model, damping, mesh, m["te_mean"] / m["te_fe_load"], rim)
                # contact ratio under load = the static FE's with contact outside the path (3 %)
                assert m["eps_load"] == pytest.approx(m["eps_fe_ext"], rel=0.03), (model, damping, mesh)
            if model == "flexible" and not rim:
                # the flexible model's mean TE = the static FE's with contact outside the path (3 %)
                assert m["te_mean"] == pytest.approx(m["te_fe_ext"], rel=0.03), (model, damping, mesh)
            if model == "rigid (paper)":
                # the paper's law is far softer than the real teeth (issue 8: 60-73 um vs ~30 um)
                assert m["te_mean"] > 1.5 * m["te_fe"]
    # each model has its own linearisation (the flexible one: the solver's tangent), over the
    # same coordinates; the modes below the first mesh mode are the elastic shafts' (with the
    # gears as inertias), which the mesh stiffness hardly changes: fitted and flexible within 2 %
    f_fit, f_flex = s["modal"]["rigid (fitted)"], s["modal"]["flexible"]
    assert len(f_fit) == len(f_flex)
    low = f_fit < 0.5 * f_fit.max()
    assert np.all(np.abs(f_flex[low] - f_fit[low]) <= 0.02 * f_fit[low])
    return mod, s


def test_quick_study_spur(tmp_path, capsys):
    _check(tmp_path, "spur")
    said = capsys.readouterr().out  # each case's phases before its wait (a first run compiles for minutes)
    for model in ("rigid (paper)", "flexible"):
        assert f"[spur] {model}, paper C: model built in" in said
        assert any(line.startswith(f"[spur] {model}, paper C: ") and "simulating" in line for line in said.splitlines())


@pytest.mark.slow
def test_quick_study_mercury(tmp_path):
    mod, s = _check(tmp_path, "mercury")
    assert (tmp_path / "mercury_planets.png").stat().st_size > 0
    for res in s["results"].values():
        shares = mod.planet_shares(res)
        assert np.mean([v.mean() for v in shares.values()]) == pytest.approx(1.0, abs=1e-9)
