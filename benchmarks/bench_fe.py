"""Benchmark of the FE pipeline for the sun gear at the default mesh level.

Sun gear of the MERCURY 1-A set (z = 24, m = 2 mm, x = 0, bore 20 mm, face width 20 mm),
steel (E = 2.1e11 Pa, nu = 0.3, rho = 7850 kg/m^3), plane stress, hub clamped.

Prints: mesh time (gmsh, cache empty), assembly time (K and M), 20 clamped-mode eigen-solve
time, cached reload time, peak memory (resident set size from ``resource.getrusage``, and the
Python/numpy heap peak from ``tracemalloc`` in a second, traced pass), and the machine.
Targets (issue 3, 2-core machine): mesh + assembly <= 10 s, 20 modes <= 15 s,
reload < 1 s, peak memory < 2 GB. ``--crack-depth`` meshes the sun with a root crack in tooth 0
(:func:`flexgear.fe.crack.mesh_cracked_gear`, 45 deg, 30 deg tangent start): the faulty gear.

Usage::

    python benchmarks/bench_fe.py [--level N] [--order 1|2] [--modes 20] [--no-tracemalloc]
                                  [--crack-depth M] [--check]

``--check`` exits with status 1 if a target is missed.
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import resource
import sys
import tempfile
import time
import tracemalloc

import numpy as np

from flexgear.fe.elasticity import assemble, clamped_modes
from flexgear.gears.geometry import SpurGear
from flexgear.gears.material import Material
from flexgear.fe.crack import mesh_cracked_gear, root_crack
from flexgear.fe.meshing import MeshSettings

TARGETS = {"mesh_assembly_s": 10.0, "modes_s": 15.0, "reload_s": 1.0, "memory_GB": 2.0}


def _rss_peak_bytes() -> int:
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r if sys.platform == "darwin" else r * 1024  # Linux reports KiB


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "?"


def run(level: int, order: int, n_modes: int, traced: bool, crack_depth: float = 0.0) -> dict:
    sun = SpurGear(z=24, module=2e-3, x=0.0, bore_diameter=0.02, face_width=0.02, name="sun")
    settings = MeshSettings(level=level, order=order)
    mat = Material(E=2.1e11, nu=0.3, rho=7850.0)
    out = {}
    crack = root_crack(sun, crack_depth, math.radians(45.0))

    def mesh(cache):
        return mesh_cracked_gear(sun, crack, settings, cache_dir=cache)

    with tempfile.TemporaryDirectory(prefix="flexgear_bench_") as cache:
        t0 = time.perf_counter()
        gm = mesh(cache)
        out["mesh_s"] = time.perf_counter() - t0
        assert gm.info["source"] == "gmsh"

        t0 = time.perf_counter()
        model = assemble(gm, mat, sun.face_width, "plane_stress")
        out["assembly_s"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        freqs, _ = clamped_modes(model, model.group_dofs("hub"), n_modes)
        out["modes_s"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        gm2 = mesh(cache)
        out["reload_s"] = time.perf_counter() - t0
        assert gm2.info["source"] == "cache"
        out["rss_GB"] = _rss_peak_bytes() / 1e9

        if traced:
            tracemalloc.start()
            m2 = assemble(gm2, mat, sun.face_width, "plane_stress")
            clamped_modes(m2, m2.group_dofs("hub"), n_modes)
            out["traced_GB"] = tracemalloc.get_traced_memory()[1] / 1e9
            tracemalloc.stop()
    out.update(nodes=gm.n_nodes, elements=gm.n_elements, dofs=model.ndofs,
               min_angle=float(gm.min_angles().min()), min_sicn=gm.info["min_sicn"],
               freqs=freqs)
    out["mesh_assembly_s"] = out["mesh_s"] + out["assembly_s"]
    out["memory_GB"] = max(out["rss_GB"], out.get("traced_GB", 0.0))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--level", type=int, default=MeshSettings().level)
    ap.add_argument("--order", type=int, default=MeshSettings().order)
    ap.add_argument("--modes", type=int, default=20)
    ap.add_argument("--no-tracemalloc", action="store_true")
    ap.add_argument("--crack-depth", type=float, default=0.0,
                    help="root crack in tooth 0 [m] (45 deg, 30 deg tangent start); 0: healthy")
    ap.add_argument("--check", action="store_true", help="exit 1 if a target is missed")
    a = ap.parse_args(argv)

    r = run(a.level, a.order, a.modes, not a.no_tracemalloc, a.crack_depth)
    crack = f", root crack {a.crack_depth * 1e3:g} mm in tooth 0" if a.crack_depth else ""
    print(f"flexgear FE benchmark: sun gear z=24, m=2 mm, bore 20 mm, face 20 mm, plane stress{crack}")
    print(f"machine : {platform.platform()}, Python {platform.python_version()}, "
          f"{os.cpu_count()} CPUs ({_cpu_model()})")
    print(f"mesh    : level {a.level}, order {a.order}: {r['elements']} triangles, "
          f"{r['nodes']} nodes, {r['dofs']} dofs; min angle {r['min_angle']:.1f} deg, "
          f"min SICN {r['min_sicn']:.2f}")
    rows = [
        ("mesh (gmsh, empty cache)", r["mesh_s"], "s", None),
        ("assembly (K, M)", r["assembly_s"], "s", None),
        ("mesh + assembly", r["mesh_assembly_s"], "s", "mesh_assembly_s"),
        (f"{a.modes} clamped modes (eigsh)", r["modes_s"], "s", "modes_s"),
        ("cached reload", r["reload_s"], "s", "reload_s"),
        ("peak RSS (getrusage)", r["rss_GB"], "GB", None),
    ]
    if "traced_GB" in r:
        rows.append(("peak traced heap (tracemalloc)", r["traced_GB"], "GB", None))
    rows.append(("peak memory", r["memory_GB"], "GB", "memory_GB"))
    ok = True
    for label, val, unit, key in rows:
        tgt = ""
        if key:
            good = val <= TARGETS[key] if key != "reload_s" else val < TARGETS[key]
            ok &= good
            tgt = f"  target {'<' if key == 'reload_s' else '<='} {TARGETS[key]:g} {unit}: " \
                  f"{'OK' if good else 'MISSED'}"
        print(f"  {label:32s} {val:9.3f} {unit}{tgt}")
    f = np.asarray(r["freqs"])
    print("first 10 clamped-hub frequencies [kHz]: " + " ".join(f"{x / 1e3:.3f}" for x in f[:10]))
    return 0 if (ok or not a.check) else 1


if __name__ == "__main__":
    raise SystemExit(main())
