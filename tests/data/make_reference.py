"""Regenerate the regression references in tests/data/reference/ (see tests/test_regression.py).

Run it at the commit whose behaviour is the reference (written in tests/data/reference/SOURCE):
    python tests/data/make_reference.py
Short runs of both presets with explicit contact tables and plain sampling, so that the files
change only when the integrator, the contact search or the model building change what they
compute.
"""
import subprocess
import sys
from pathlib import Path

try:  # flexgear >= 0.2 layout
    from flexgear.app.run import run
    from flexgear.config import load_config
    from flexgear.results import save
except ImportError:  # 0.1.0 flat layout
    from flexgear.config import load_config
    from flexgear.results import save
    from flexgear.run import run

HERE = Path(__file__).parent / "reference"
OVERRIDES = {
    "contact": {"outline_spacing": 4.0e-5, "sdf_resolution": 1.0e-5},
    "simulation": {"run_in": 0.02, "duration": 0.03, "antialias": False, "output_rate": 5000.0},
}


def reference_config(preset):
    cfg = load_config(preset)
    for block, kv in OVERRIDES.items():
        getattr(cfg, block).update(kv)
    return cfg


if __name__ == "__main__":
    HERE.mkdir(exist_ok=True)
    for preset in ("spur_pair", "mercury_1a"):
        res = run(reference_config(preset))
        save(res, HERE / f"{preset}.h5", overwrite=True)
        print("wrote", HERE / f"{preset}.h5")
    rev = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    (HERE / "SOURCE").write_text(f"{rev}\n")
    sys.exit(0)
