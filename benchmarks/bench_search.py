"""Benchmark of the tooth contact search alone (:func:`flexgear.dynamics.contact.search.mesh_search`,
the kernel behind :func:`~flexgear.dynamics.contact.search.mesh_contacts`).

Runs a preset for a short time, records the body poses of 400 further steps (the solver's own
time loop), then times the searches of all meshes at these poses: full searches only, local
searches only (each after the full search of its step, as in the run), and the run's pattern (a
full search every full_search_every(h)-th step, local ones between). Prints microseconds per call
of ``mesh_search`` (one mesh) and per step (all meshes), best of five timed loops, with the
load average.

``--save FILE`` / ``--compare FILE``: store, or compare bit for bit with a stored file, every
output of the searches along the trajectory (count, out_f, out_i, cache, ncache of every call,
full and local), to check that a faster search gives identical results.

Usage::

    python benchmarks/bench_search.py [--presets mercury_1a_flexible spur_pair_flexible]
                                      [--settle 0.005] [--save FILE | --compare FILE]
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numba as nb
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine_info import machine  # noqa: E402

from flexgear.config import load_config  # noqa: E402
from flexgear.config.loader import time_grid  # noqa: E402
from flexgear.dynamics.model.assembly import build_model  # noqa: E402
from flexgear.dynamics.contact.search import MAX_CONTACTS, mesh_pair, mesh_search  # noqa: E402
from flexgear.dynamics.integrator.simulation import COARSE_STRIDE, full_search_every, simulate  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_flexible import trajectory  # noqa: E402


@nb.njit
def _search(P, meshes, contact, out_f, out_i, cache, ncache, mode, full_every, reps):
    """Searches of every mesh at every pose of P. mode 0: full only; 1: a full search (not
    timed apart) then a local one, the local one repeated reps times; 2: the run's pattern."""
    nm = meshes.body_a.shape[0]
    for r in range(reps):
        for k in range(P.shape[0]):
            pose = P[k]
            for m in range(nm):
                a = meshes.body_a[m]
                b = meshes.body_b[m]
                local = False if mode == 0 else (True if mode == 1 else k % full_every != 0)
                mesh_search(pose[a], pose[b], mesh_pair(meshes, m), contact, out_f, out_i, local, cache[m], ncache[m])


@nb.njit
def _prime(P, meshes, contact, out_f, out_i, cache, ncache, k):
    """The full searches of step k (fills the caches for the local ones)."""
    pose = P[k]
    for m in range(meshes.body_a.shape[0]):
        a = meshes.body_a[m]
        b = meshes.body_b[m]
        mesh_search(pose[a], pose[b], mesh_pair(meshes, m), contact, out_f, out_i, False, cache[m], ncache[m])


@nb.njit
def _local_all(P, meshes, contact, out_f, out_i, cache, ncache, reps):
    """Local searches at every pose, each after its step's full search (only the local ones timed
    by difference is awkward, so: caches primed once per pose outside the repeated loop)."""
    nm = meshes.body_a.shape[0]
    for k in range(P.shape[0]):
        _prime(P, meshes, contact, out_f, out_i, cache, ncache, k)
        pose = P[k]
        for r in range(reps):
            for m in range(nm):
                a = meshes.body_a[m]
                b = meshes.body_b[m]
                mesh_search(pose[a], pose[b], mesh_pair(meshes, m), contact, out_f, out_i, True, cache[m], ncache[m])


@nb.njit
def _record(P, meshes, contact, full_every, counts, F, I, C, NC):
    """Every output of the run's search pattern plus a local search after every full one."""
    nm = meshes.body_a.shape[0]
    cache = np.zeros((nm, 4 * MAX_CONTACTS, 4), np.int64)
    ncache = np.zeros((nm, 1), np.int64)
    for k in range(P.shape[0]):
        pose = P[k]
        for m in range(nm):
            a = meshes.body_a[m]
            b = meshes.body_b[m]
            for rep in range(2):
                local = rep == 1 or k % full_every != 0
                out_f = np.full((MAX_CONTACTS, 5), -7.0)
                out_i = np.full((MAX_CONTACTS, 3), -7, np.int64)
                cnt = mesh_search(pose[a], pose[b], mesh_pair(meshes, m), contact, out_f, out_i, local, cache[m],
                                  ncache[m])
                counts[k, m, rep] = cnt
                F[k, m, rep] = out_f
                I[k, m, rep] = out_i
                C[k, m, rep] = cache[m]
                NC[k, m, rep] = ncache[m, 0]


def timed(fn, *args, reps=1):
    fn(*args, 1)  # compile
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        fn(*args, reps)
        best = min(best, time.perf_counter() - t0)
    return best / reps


def load() -> str:
    return f"load {os.getloadavg()[0]:.1f}"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--presets", nargs="+", default=["mercury_1a_flexible", "spur_pair_flexible", "mercury_1a"])
    p.add_argument("--settle", type=float, default=0.005, help="simulated time before the recorded steps [s]")
    p.add_argument("--steps", type=int, default=400)
    p.add_argument("--save", help="store the search outputs along the trajectories (.npz)")
    p.add_argument("--compare", help="compare the search outputs with a stored file (.npz)")
    a = p.parse_args(argv)
    print(machine())
    stored = {}
    ok = True
    for preset in a.presets:
        cfg = load_config(preset)
        h, _ = time_grid(cfg.simulation)
        model = build_model(cfg)
        nsteps = max(8, int(round(a.settle / h / 8)) * 8)
        r = simulate(model, nsteps * h, h, 8)
        km, work, Q, V, P, t0 = trajectory(model, r, h, steps=a.steps)
        meshes, contact = km.meshes, model.tables
        nm = meshes.body_a.shape[0]
        steps = P.shape[0]
        out_f = np.zeros((MAX_CONTACTS, 5))
        out_i = np.zeros((MAX_CONTACTS, 3), np.int64)
        cache = np.zeros((nm, 4 * MAX_CONTACTS, 4), np.int64)
        ncache = np.zeros((nm, 1), np.int64)
        full = timed(_search, P, meshes, contact, out_f, out_i, cache, ncache, 0, full_search_every(h))
        run_ = timed(_search, P, meshes, contact, out_f, out_i, cache, ncache, 2, full_search_every(h))
        both = timed(_local_all, P, meshes, contact, out_f, out_i, cache, ncache, reps=1)
        # local alone: (prime + 1 local) - (prime) with prime = full
        both9 = timed(_local_all, P, meshes, contact, out_f, out_i, cache, ncache, reps=9)
        local = (both9 * 9 - both) / 8
        calls = steps * nm
        print(f"{preset}: {nm} meshes, stride {COARSE_STRIDE}, {steps} poses ({load()})")
        print(f"  full search   {full / calls * 1e6:7.2f} us per call   {full / steps * 1e6:7.2f} us per step")
        print(f"  local search  {local / calls * 1e6:7.2f} us per call   {local / steps * 1e6:7.2f} us per step")
        print(f"  run pattern   {run_ / calls * 1e6:7.2f} us per call   {run_ / steps * 1e6:7.2f} us per step"
              f"  (1 full in {full_search_every(h)})")
        if a.save or a.compare:
            counts = np.zeros((steps, nm, 2), np.int64)
            F = np.zeros((steps, nm, 2, MAX_CONTACTS, 5))
            I = np.zeros((steps, nm, 2, MAX_CONTACTS, 3), np.int64)
            C = np.zeros((steps, nm, 2, 4 * MAX_CONTACTS, 4), np.int64)
            NC = np.zeros((steps, nm, 2), np.int64)
            _record(P, meshes, contact, full_search_every(h), counts, F, I, C, NC)
            rec = {"P": P, "counts": counts, "F": F, "I": I, "C": C, "NC": NC}
            for k, v in rec.items():
                stored[f"{preset}/{k}"] = v
            if a.compare:
                with np.load(a.compare) as ref:
                    for k, v in rec.items():
                        same = np.array_equal(ref[f"{preset}/{k}"], v)
                        ok &= same
                        if not same:
                            print(f"  DIFFERS: {k}")
                print(f"  outputs {'bit-identical' if ok else 'DIFFER'} ({int(counts.sum())} contacts)")
    if a.save:
        np.savez_compressed(a.save, **stored)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
