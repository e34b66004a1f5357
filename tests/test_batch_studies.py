"""The batch studies run end to end in their --quick form (slow: a few minutes on 2 cores)."""
import runpy
import sys
from pathlib import Path

import pandas as pd
import pytest

from flexgear.config import load_config

STUDIES = Path(__file__).resolve().parents[1] / "studies"


@pytest.mark.slow
@pytest.mark.parametrize("script, figures", [
    ("speed_sweep.py", ["speed_forces.png", "speed_harmonics.png", "order_map_spur.png", "order_map_mercury.png"]),
    ("load_sweep.py", ["load_te.png", "load_contact_ratio.png"]),
])
def test_quick_study_writes_its_figures(tmp_path, monkeypatch, script, figures):
    monkeypatch.setattr(sys, "argv", [script, "-o", str(tmp_path), "--quick"])
    with pytest.raises(SystemExit) as done:  # a study ends as a program: status 0
        runpy.run_path(str(STUDIES / script), run_name="__main__")
    assert done.value.code == 0
    for f in figures + ["report.md"]:
        assert (tmp_path / f).stat().st_size > 0
    for s in ("spur", "mercury"):
        assert (pd.read_csv(tmp_path / s / "summary.csv").status == "done").all()


# ------------------------------------------------------------------------------- studies/faults.py
def _faults_study():
    return runpy.run_path(str(STUDIES / "faults.py"), run_name="faults_study")


def test_faults_study_covers_every_kind_and_validates_every_case(tmp_path):
    """The full study's batches: every fault kind (and the pin error) on the sets the issue names,
    at the three fidelities (rigid cracks: a per-tooth contact-law factor; flexible: the FE gears of
    the flexible presets), four cases each (healthy + three severities, the healthy one without
    faults or errors), every case a valid configuration that its model simulates (no run)."""
    ns = _faults_study()
    groups = ns["groups"](False)
    kinds = {(g.set, g.fidelity, g.name) for g in groups}
    for fid in ("rigid", "lumped", "flexible"):
        assert {("spur", fid, k) for k in ("missing_pinion", "spall_pinion", "chip_pinion")} <= kinds
        assert {("mercury", fid, k) for k in ("spall_ring", "missing_sun", "pin_planet1")} <= kinds
        assert {("spur", fid, "crack_pinion"), ("mercury", fid, "crack_sun"), ("mercury", fid, "crack_planet")} <= kinds
    for g in groups:
        base = ns["base_file"](tmp_path, g.set, g.preset)
        sweep = ns["loads_sweep"](ns["sweep_text"](g, 1.0, 0.2, base), source=g.key)
        assert len(sweep.cases) == 4
        assert not sweep.cases[0].data.get("faults") and not sweep.cases[0].data.get("errors")
        assert all(c.data["model"] == ("rigid" if g.fidelity == "flexible" else g.fidelity) for c in sweep.cases)
        assert all(bool(c.data.get("flexible")) == (g.fidelity == "flexible") for c in sweep.cases)
        assert all(c.data["contact"].get("damping_ratio") == 0.05 and "damping" not in c.data["contact"]
                   for c in sweep.cases)
    quick = ns["groups"](True)
    assert [g.key for g in quick] == ["spur_rigid_missing_pinion", "spur_rigid_spall_pinion",
                                      "spur_flexible_missing_pinion", "spur_rigid_crack_pinion"]
    # the flexible groups on the rigid presets' supports: no shafts (they float MERCURY 1-A's sun)
    for set_name, preset in (("spur", "spur_pair_flexible"), ("mercury", "mercury_1a_flexible")):
        assert "shafts" in load_config(preset).source_text
        flexible = load_config(ns["base_file"](tmp_path, set_name, preset))
        rigid = load_config(ns["base_file"](tmp_path, set_name))
        assert not flexible.shafts and flexible.supports == rigid.supports and flexible.flexible


def _report_rows(text: str, heading_part: str) -> dict:
    """{severity: [TE RMS, TE peak, TE kurtosis, F RMS, F peak, F kurtosis]} of one report section."""
    section = text.split(heading_part, 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells and cells[0] in ("healthy", "low", "medium", "high"):
            rows[cells[0]] = [float(c) for c in cells[1:]]
    return rows


@pytest.mark.slow
def test_quick_faults_study(tmp_path, monkeypatch):
    """The quick study (spur pair, rigid; the missing tooth also flexible): every case done and in
    the report; the healthy case's kurtosis is that of the spur_pair preset run directly with the
    same record and damping ratio; removing more of the pinion tooth (height 0.75, 0.5, 0) raises
    the peak and kurtosis of the mesh force (a larger unloading of the pair, then a loss of contact
    and an engagement impact: an impulsive signal), and the spall's deepest case departs from the
    healthy one, its transmission error peak growing with the depth; in the flexible model the whole missing tooth leaves one pair to carry the load,
    whose larger deflection raises the transmission error's peak."""
    import numpy as np
    from scipy.stats import kurtosis

    from flexgear.app.run import run
    from flexgear.config import loads_config, preset_path

    monkeypatch.setattr(sys, "argv", ["faults.py", "-o", str(tmp_path), "--quick", "--workers", "1"])
    with pytest.raises(SystemExit) as done:  # a study ends as a program: status 0
        runpy.run_path(str(STUDIES / "faults.py"), run_name="__main__")
    assert done.value.code == 0
    text = (tmp_path / "report.md").read_text()
    for key in ("spur_rigid_missing_pinion", "spur_rigid_spall_pinion", "spur_flexible_missing_pinion",
                "spur_rigid_crack_pinion"):
        assert (pd.read_csv(tmp_path / key / "summary.csv").status == "done").all()
        for f in ("time", "spectrum"):
            assert (tmp_path / f"{key}_{f}.png").stat().st_size > 0
    missing = _report_rows(text, "missing to height")
    spall = _report_rows(text, "spall 23.5-24.5 mm")
    assert set(missing) == set(spall) == {"healthy", "low", "medium", "high"}

    preset = preset_path("spur_pair").read_text()
    cfg = loads_config(preset.replace("duration = 1.0", "duration = 0.1").replace("run_in = 0.2", "run_in = 0.06"))
    healthy = run(cfg.use_damping_ratio(0.05))
    f = healthy.meshes["pinion-wheel"].normal_force
    assert missing["healthy"][5] == pytest.approx(kurtosis(f, fisher=False), rel=1e-3)
    assert spall["healthy"][5] == pytest.approx(kurtosis(f, fisher=False), rel=1e-3)

    # over the three severities; the 0.75 height cut's extra peak may stay below the healthy
    # record's largest one, which lies elsewhere, so healthy is compared with the whole tooth only
    peak = [missing[s][4] for s in ("low", "medium", "high")]
    kurt = [missing[s][5] for s in ("low", "medium", "high")]
    assert np.all(np.diff(peak) > 0), peak
    assert np.all(np.diff(kurt) > 0), kurt
    assert peak[-1] > missing["healthy"][4] and kurt[-1] > missing["healthy"][5]
    assert spall["high"][4] > spall["healthy"][4] and spall["high"][5] > spall["healthy"][5]
    # the transmission error from the gears' angles sees the lost material: its peak grows with the
    # spall's depth (the contact's approach had fallen, 27.1, 25.7, 24.7 um against 24.6 healthy)
    te_peak = [spall[s][1] for s in ("healthy", "low", "medium", "high")]
    assert np.all(np.diff(te_peak) > 0), te_peak
    flexible = _report_rows(text, "flexible: pinion tooth 0 missing to height")
    assert set(flexible) == {"healthy", "low", "medium", "high"}
    assert flexible["high"][1] > flexible["healthy"][1]
    # a deeper root crack softens the tooth more: the transmission error's peak grows with it
    crack = _report_rows(text, "pinion tooth 0 root crack")
    te_peak = [crack[s][1] for s in ("healthy", "low", "medium", "high")]
    assert np.all(np.diff(te_peak) > 0), te_peak
