"""Issue acceptance with the presets unchanged, 1 s after the run-in: studies/paper_rigid.py
checks every expected value (mesh harmonics, forces, carrier frequency, planet circle, load
sharing, sidebands and the suppressed mesh line) and exits non-zero if one misses."""
from pathlib import Path

import pytest
from conftest import load_script


def test_paper_rigid_study_meets_every_expectation(tmp_path):
    path = Path(__file__).resolve().parents[1] / "studies" / "paper_rigid.py"
    mod = load_script(path)
    assert mod.main(["-o", str(tmp_path), "--duration", "1.0"]) == 0
    report = (tmp_path / "report.md").read_text()
    assert "| NO" not in report
    for fig in ("fig03_pinion_wheel_force.png", "fig04_pinion_wheel_spectrum.png"):
        assert (tmp_path / "spur_pair" / fig).stat().st_size > 10_000
    for fig in ("fig07_planet_positions.png", "fig09_planet1_ring_spectrum.png", "fig10_ring_forces_all_planets.png",
                "fig12_sun_planet1_spectrum.png"):
        assert (tmp_path / "mercury_1a" / fig).stat().st_size > 10_000
    for run in ("spur_pair_zeta0.05", "mercury_1a_zeta0.05"):
        assert (tmp_path / run / "results.h5").exists()
    assert (tmp_path / "damping_comparison.png").stat().st_size > 10_000
    for heading in ("## Contact damping", "## What the model does not reproduce", "three times smaller",
                    "even modulations bigger", "heavily overdamped"):
        assert heading in report
    with pytest.raises(Exception, match="exists"):
        mod.main(["-o", str(tmp_path), "--duration", "1.0"])  # never overwrites a saved study
