"""The batch studies run end to end in their --quick form (slow: a few minutes on 2 cores)."""
import runpy
import sys
from pathlib import Path

import pandas as pd
import pytest

STUDIES = Path(__file__).resolve().parents[1] / "studies"


@pytest.mark.slow
@pytest.mark.parametrize("script, figures", [
    ("speed_sweep.py", ["speed_forces.png", "speed_harmonics.png", "order_map_spur.png", "order_map_mercury.png"]),
    ("load_sweep.py", ["load_te.png", "load_contact_ratio.png"]),
])
def test_quick_study_writes_its_figures(tmp_path, monkeypatch, script, figures):
    monkeypatch.setattr(sys, "argv", [script, "-o", str(tmp_path), "--quick"])
    runpy.run_path(str(STUDIES / script), run_name="__main__")
    for f in figures + ["report.md"]:
        assert (tmp_path / f).stat().st_size > 0
    for s in ("spur", "mercury"):
        assert (pd.read_csv(tmp_path / s / "summary.csv").status == "done").all()
