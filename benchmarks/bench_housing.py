"""Benchmark of the housing reduction (issue 23, "Speed": at most 30 s uncached, under 1 s cached).

For the default housings of the presets (``[housing]`` with every default: MERCURY 1-A and the
spur pair), prints the wall and CPU time of

* ``uncached``: mesh (Gmsh), K and M (scikit-fem), Craig-Bampton with the modal truncation
  augmentation, and writing the cache entry, into an empty cache directory;
* ``cached``: loading that entry, both files' SHA-256 verified (best of ``--repeat``);
* ``path``: building the transfer path (modes of the housing on its feet) and applying it to a
  1 s record at 10 kHz of every input channel;
* ``coupled``: the spur pair on elastic bearings, a run with the housing coupled into the solver
  (``coupled = true``) and the two sensors against the same run without housing and sensors,
  back to back (solver wall time of each and their ratio; issue 23's bar: 1.3x);
* ``flexible``: the flexible spur pair preset (gears on their shafts) with the housing and the two
  sensors, through the one-way path and coupled, against the same run without housing and
  sensors: CPU time of the whole run and the solver's wall time, back to back, and their ratios
  (issue 23's bar: 1.3x);
* ``planetary``: MERCURY 1-A with its coupled housing (``mercury_1a_coupled_sensors``) against
  the same run with ``coupled = false`` (the one-way path model): CPU time of the whole run
  and the solver's wall time, and their ratios.

The load average is printed: on a shared machine the CPU time is the steadier figure.

Usage::

    python benchmarks/bench_housing.py [--repeat 3] [--duration 0.2] [--coupled-only | --planetary-only | --flexible-only]
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

from flexgear.config.loader import loads_config, preset_path
from flexgear.reduction.housing import reduce_housing
from flexgear.reduction.paths import TransferPath

SENSORS = '\n[housing]\n\n[[sensors]]\nname = "top"\nangle_deg = 90.0\n\n[[sensors]]\nname = "side"\nangle_deg = 0.0\n'


def timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


BEARINGS = ('pinion = "revolute"\nwheel = "revolute"',
            'pinion = {stiffness = 5.0e8, damping = 2.0e3}\nwheel = {stiffness = 5.0e8, damping = 2.0e3}')


def build_model_with(text: str):
    """The model of a configuration text with its coupled housing in it."""
    from flexgear.dynamics.model.assembly import build_model
    from flexgear.results.sensors import plan_sensors

    cfg = loads_config(text)
    model = build_model(cfg)
    plan_sensors(cfg, model)
    return model


def coupled_ratio(duration: float, cutoff: float | None = None) -> None:
    """The solver's wall time of a spur pair run with and without the coupled housing (module
    docstring); ``cutoff`` [Hz]: the housing's (default its default), fewer modes, fewer coordinates."""
    from flexgear.app.run import run

    base = preset_path("spur_pair").read_text().replace(*BEARINGS)
    base = base.replace("duration = 1.0", f"duration = {duration}").replace("run_in = 0.2", "run_in = 0.05")
    with_h = base + SENSORS.replace("[housing]\n", "[housing]\ncoupled = true\n"
                                    + ("" if cutoff is None else f"cutoff = {cutoff}\n"))
    run(loads_config(with_h))  # kernels of both compiled or loaded before timing
    run(loads_config(base))
    walls = {}
    for name, text in (("without", base), ("coupled", with_h), ("without", base), ("coupled", with_h)):
        res = run(loads_config(text))
        walls[name] = min(walls.get(name, float("inf")), res.attrs["wall_seconds"])
    n = len(build_model_with(with_h).coordinate_names())
    print(f"spur_pair coupled housing (cutoff {'default' if cutoff is None else f'{cutoff:g} Hz'}, {n} coordinates "
          f"in all), 2 sensors, {duration} s kept: solver {walls['coupled']:.2f} s wall against "
          f"{walls['without']:.2f} s without: {walls['coupled'] / walls['without']:.2f}x (best of 2, back to back)")


def planetary_coupled_ratio(duration: float) -> None:
    """MERCURY 1-A with its housing coupled (preset ``mercury_1a_coupled_sensors``) against the
    same set, supports and sensors with ``coupled = false`` (the one-way housing path and the
    planet-pass window after the run): CPU time of the whole run and the solver's wall time,
    back to back, best of 2 (module docstring)."""
    from flexgear.app.run import run

    coupled = preset_path("mercury_1a_coupled_sensors").read_text()
    coupled = coupled.replace("duration = 1.0", f"duration = {duration}")
    one_way = coupled.replace("coupled = true ", "coupled = false ")
    assert one_way != coupled
    run(loads_config(coupled))  # kernels compiled or loaded, housing reduced, before timing
    run(loads_config(one_way))
    cpu, walls = {}, {}
    for name, text in (("one_way", one_way), ("coupled", coupled), ("one_way", one_way), ("coupled", coupled)):
        res, _, c = timed(lambda: run(loads_config(text)))
        cpu[name] = min(cpu.get(name, float("inf")), c)
        walls[name] = min(walls.get(name, float("inf")), res.attrs["wall_seconds"])
    n = len(build_model_with(coupled).coordinate_names())
    print(f"mercury_1a coupled housing ({n} coordinates in all), 2 sensors, {duration} s kept + 0.2 s run-in: "
          f"run {cpu['coupled']:.2f} s CPU against {cpu['one_way']:.2f} s with the one-way path: "
          f"{cpu['coupled'] / cpu['one_way']:.2f}x; solver {walls['coupled']:.2f} s against {walls['one_way']:.2f} s "
          f"wall: {walls['coupled'] / walls['one_way']:.2f}x (best of 2, back to back)")


def flexible_coupled_ratio(duration: float) -> None:
    """The flexible spur pair preset with its housing and two sensors, through the one-way path
    and coupled, against the same run without housing and sensors (module docstring)."""
    from flexgear.app.run import run

    base = preset_path("spur_pair_flexible").read_text()
    base = base.replace("duration = 1.0", f"duration = {duration}").replace("run_in = 0.2", "run_in = 0.02")
    texts = {"without": base, "one_way": base + SENSORS,
             "coupled": base + SENSORS.replace("[housing]\n", "[housing]\ncoupled = true\n")}
    for text in texts.values():  # kernels compiled or loaded, gears and housing reduced, before timing
        run(loads_config(text))
    cpu, walls = {}, {}
    for _ in range(2):
        for name, text in texts.items():
            res, _, c = timed(lambda: run(loads_config(text)))
            cpu[name] = min(cpu.get(name, float("inf")), c)
            walls[name] = min(walls.get(name, float("inf")), res.attrs["wall_seconds"])
    for name in ("one_way", "coupled"):
        print(f"spur_pair_flexible, housing ({name}), 2 sensors, {duration} s kept + 0.02 s run-in: run "
              f"{cpu[name]:.2f} s CPU against {cpu['without']:.2f} s without: {cpu[name] / cpu['without']:.2f}x; "
              f"solver {walls[name]:.2f} s against {walls['without']:.2f} s wall: "
              f"{walls[name] / walls['without']:.2f}x (best of 2, back to back)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--duration", type=float, default=0.2, help="kept seconds of the coupled runs")
    ap.add_argument("--coupled-only", action="store_true", help="only the coupled-run ratio")
    ap.add_argument("--planetary-only", action="store_true", help="only the coupled planetary run's ratio")
    ap.add_argument("--flexible-only", action="store_true", help="only the coupled flexible run's ratio")
    args = ap.parse_args(argv)
    if args.flexible_only:
        flexible_coupled_ratio(args.duration)
        return
    if args.planetary_only:
        planetary_coupled_ratio(args.duration)
        return
    if args.coupled_only:
        for cutoff in (None, 12e3):
            coupled_ratio(args.duration, cutoff)
        planetary_coupled_ratio(args.duration)
        flexible_coupled_ratio(args.duration)
        return
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    for preset in ("mercury_1a", "spur_pair"):
        cfg = loads_config(preset_path(preset).read_text() + SENSORS)
        with tempfile.TemporaryDirectory() as cache:
            red, wall, cpu = timed(lambda: reduce_housing(cfg.housing, cache_dir=cache))
            b = red.body
            print(f"{preset}: {red.info['ndofs']} dofs, {b.n_interface} interface coordinates, "
                  f"{b.n_modes - b.info['augmentation_vectors']} modes to {cfg.housing.cutoff / 1e3:.0f} kHz + "
                  f"{b.info['augmentation_vectors']} augmentation vectors = {b.n} coordinates")
            print(f"  uncached: {wall:6.2f} s wall, {cpu:6.2f} s CPU (mesh {red.info['mesh_seconds']:.2f} s, "
                  f"assembly {red.info['assemble_seconds']:.2f} s, reduction {red.info['reduce_seconds']:.2f} s)")
            best = min(timed(lambda: reduce_housing(cfg.housing, cache_dir=cache))[1:] for _ in range(args.repeat))
            print(f"  cached:   {best[0]:6.3f} s wall, {best[1]:6.3f} s CPU (best of {args.repeat})")
            path, w1, c1 = timed(lambda: TransferPath(red, cfg.sensors))
            rng = np.random.default_rng(0)
            F = rng.standard_normal((10000, len(path.channels)))
            _, w2, c2 = timed(lambda: path.response(F, 10000.0))
            print(f"  path:     {w1:6.3f} s to build, {w2:6.3f} s wall / {c2:6.3f} s CPU for 1 s at 10 kHz "
                  f"({len(path.channels)} channels, {len(path.sensors)} sensors)")
    for cutoff in (None, 12e3):
        coupled_ratio(args.duration, cutoff)
    planetary_coupled_ratio(args.duration)


if __name__ == "__main__":
    main()
