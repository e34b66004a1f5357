"""Regenerate the regression references in tests/data/reference/ (see tests/test_regression.py).

Run it at the commit whose behaviour is the reference (written per file in
tests/data/reference/SOURCE)::

    python tests/data/make_reference.py [PRESET ...]      (default: all of REFERENCES)
    python tests/data/make_reference.py --add-cpu [PRESET ...]   (default: the flexible ones)

Short runs of the presets with explicit contact tables and plain sampling, so that the files
change only when the integrator, the contact search or the model building change what they
compute. The flexible presets' kernels reassociate some sums (fastmath), whose rounding depends
on the vector width numba compiles for: their files record the CPU name and features numba
compiled for (:func:`compiled_for`), and the test compares them bit for bit only on that CPU.
Regenerating one removes the files other CPUs had of it (``PRESET@CPU.h5``: their results
changed too). ``--add-cpu`` writes this CPU's file of an unchanged reference, ``PRESET@CPU.h5``,
after checking that the run agrees with ``PRESET.h5`` within the test's round-off.
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
CONTACT = {"outline_spacing": 4.0e-5, "sdf_resolution": 1.0e-5}
RIGID = {"run_in": 0.02, "duration": 0.03, "antialias": False, "output_rate": 5000.0}
# 0.02 s at the flexible presets' 6.25 us step: 3200 steps, 100 full contact searches, 25
# one-pass calibration steps
FLEXIBLE = {"run_in": 0.005, "duration": 0.015, "antialias": False, "output_rate": 5000.0}
REFERENCES = {"spur_pair": RIGID, "mercury_1a": RIGID, "spur_pair_flexible": FLEXIBLE,
              "mercury_1a_flexible": FLEXIBLE}
#: FE mesh levels other than the preset's: MERCURY 1-A's bodies at level 0, whose reductions
#: the other tests share (the preset's level-2 ring is the costliest reduction of the suite, and
#: no other test of the default suite needs it); the spur pair keeps the preset's level 2, which
#: ``flexgear warm`` reduces anyway
LEVELS = {"mercury_1a_flexible": 0}


def reference_config(preset):
    cfg = load_config(preset)
    cfg.contact.update(CONTACT)
    cfg.simulation.update(REFERENCES[preset])
    if preset in LEVELS:
        cfg.flexible.update(level=LEVELS[preset])
    return cfg


def compiled_for() -> dict:
    """The CPU name and features numba compiles for (its configuration, else the host's)."""
    import llvmlite.binding as ll
    import numba

    return {"numba_cpu_name": numba.config.CPU_NAME or ll.get_host_cpu_name(),
            "numba_cpu_features": numba.config.CPU_FEATURES or ll.get_host_cpu_features().flatten()}


def source_lines() -> dict:
    path = HERE / "SOURCE"
    lines = path.read_text().split("\n") if path.exists() else []
    return dict(line.split(maxsplit=1) for line in lines if line.strip())


def add_cpu(presets) -> None:
    """Write this CPU's ``PRESET@CPU.h5`` of each flexible preset, if its run agrees with
    ``PRESET.h5`` within the regression test's ROUNDOFF (else the code changed: regenerate)."""
    import tempfile

    import h5py

    sys.path.insert(0, str(HERE.parent.parent))
    from test_regression import compare, reference_file

    cpu = compiled_for()
    for preset in presets:
        if not preset.endswith("_flexible"):
            sys.exit(f"{preset}: only the flexible references are per CPU")
        if reference_file(preset, cpu, HERE)[1]:
            print(preset, "already has this CPU's reference")
            continue
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "r.h5"
            save(run(reference_config(preset)), path)
            with h5py.File(HERE / f"{preset}.h5") as ref, h5py.File(path) as new:
                bad = compare(ref, new, exact=False)
            if bad:
                sys.exit(f"{preset}: differs from {preset}.h5 beyond the round-off ({bad}); regenerate instead")
            with h5py.File(path, "a") as f:
                f.attrs.update(cpu)
            out = HERE / f"{preset}@{cpu['numba_cpu_name']}.h5"
            out.write_bytes(path.read_bytes())
        print("wrote", out)


if __name__ == "__main__":
    HERE.mkdir(exist_ok=True)
    rev = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    sources = source_lines()
    args = sys.argv[1:]
    if args[:1] == ["--add-cpu"]:
        presets = args[1:] or [p for p in REFERENCES if p.endswith("_flexible")]
        add_cpu(presets)
        sources.update({p.name: rev for p in HERE.glob("*@*.h5") if p.name not in sources})
        (HERE / "SOURCE").write_text("".join(f"{k} {v}\n" for k, v in sorted(sources.items())))
        sys.exit(0)
    for preset in args or list(REFERENCES):
        res = run(reference_config(preset))
        path = HERE / f"{preset}.h5"
        save(res, path, overwrite=True)
        if preset.endswith("_flexible"):
            import h5py

            with h5py.File(path, "a") as f:
                f.attrs.update(compiled_for())
            for other in HERE.glob(f"{preset}@*.h5"):
                other.unlink()
                sources.pop(other.name, None)
        sources[path.name] = rev
        print("wrote", path)
    (HERE / "SOURCE").write_text("".join(f"{k} {v}\n" for k, v in sorted(sources.items())))
    sys.exit(0)
