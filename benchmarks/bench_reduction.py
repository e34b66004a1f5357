"""Benchmark of the Craig-Bampton reduction of one gear (issue 8, "Speed").

Sun gear of MERCURY 1-A (z = 24, m = 2 mm, bore 20 mm, face width 20 mm), steel, plane stress,
mesh level 2 quadratic (31,880 dofs), bore tied rigidly to the body frame.

Prints, for 20 and 100 fixed-interface modes, the best of ``--repeat`` wall times of

* ``flexgear``: :class:`flexgear.reduction.reductor.CraigBamptonReductor` (one LU of K_ii with a
  symmetric ordering, shared by constraint modes, shift-invert Lanczos and residual
  flexibility; projection to K_r, M_r included);
* ``plain scipy``: the reference the issue names - one ``splu`` of K_ii (default COLAMD
  ordering) shared by the constraint modes ``-K_ii^-1 K_ib T`` and ``eigsh`` in shift-invert
  mode (defaults), then the projection; run in the same process, interleaved, with the same
  single-threaded BLAS (OpenBLAS's spinning threads make both several times slower on a busy
  2-core machine).

Targets (issue 8, this machine unloaded): plain scipy 1.4 s / 4.7 s, Exudyn's
``ComputeHurtyCraigBamptonModes`` 2.2 s / 6.3 s; flexgear at least as fast as both. The load
average is printed: on a shared machine compare the two columns, not the absolute figures.
Also printed: the flank tables (residual compliance from one tooth's flanks to both flanks
of every tooth), the modal shapes at the table points of all teeth, and the share of a flank point's
static compliance that 20 / 100 / 200 clamped modes carry.

Usage::

    python benchmarks/bench_reduction.py [--level 2] [--repeat 2] [--modes 20 100]
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np
import scipy.sparse.linalg as spla

from flexgear.fe.elasticity import assemble, single_threaded_blas
from flexgear.fe.meshing import MeshSettings, mesh_gear
from flexgear.gears.geometry import SpurGear
from flexgear.gears.material import Material
from flexgear.reduction.flank import flank_tables, modal_table
from flexgear.reduction.interface import gear_interface
from flexgear.reduction.reductor import CraigBamptonReductor


def plain_scipy_cb(model, imap, n_modes: int):
    """Reference CB: one COLAMD LU shared by constraint modes and eigsh; returns (K_r, M_r)."""
    n = model.ndofs
    b = imap.boundary
    inner = np.setdiff1d(np.arange(n), b)
    K = model.K.tocsr()
    Kii = K[inner][:, inner].tocsc()
    Mii = model.M[inner][:, inner].tocsc()
    lu = spla.splu(Kii)
    Psi = np.zeros((n, imap.n_coordinates))
    Psi[b] = imap.T
    Psi[inner] = -lu.solve(np.asarray(K[inner][:, b] @ imap.T))
    op = spla.LinearOperator(Kii.shape, matvec=lu.solve, dtype=float)
    lam, vec = spla.eigsh(Kii, k=n_modes, M=Mii, sigma=0.0, which="LM", OPinv=op)
    Phi = np.zeros((n, n_modes))
    Phi[inner] = vec
    V = np.hstack([Psi, Phi])
    return V.T @ (model.K @ V), V.T @ (model.M @ V), np.sort(lam)


def best_of(fn, repeat):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--level", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--modes", type=int, nargs="+", default=[20, 100])
    ap.add_argument("--cache-dir", default="meshes/cache")
    args = ap.parse_args(argv)

    sun = SpurGear(z=24, module=2e-3, x=0.0, bore_diameter=0.02, face_width=0.02, name="sun")
    mat = Material(E=2.1e11, nu=0.3, rho=7850.0)
    t0 = time.perf_counter()
    gm = mesh_gear(sun, MeshSettings(level=args.level), cache_dir=args.cache_dir)
    model = assemble(gm, mat, sun.face_width)
    t_prep = time.perf_counter() - t0
    itf = gear_interface(model, sun)
    imap = itf.resolve(model)
    print(f"sun z = 24, level {args.level}: {model.ndofs} dofs, {imap.boundary.size} bore dofs "
          f"tied to the frame; mesh (cache) + assembly {t_prep:.2f} s")
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print(f"{'modes':>6} {'flexgear [s]':>13} {'plain scipy [s]':>16} {'ratio':>6}  "
          f"{'max |f/f_ref - 1|':>18}  breakdown (factor / eigen / project)")
    bodies = {}
    for k in args.modes:
        with single_threaded_blas():
            t_ref, (Kr, Mr, lam_ref) = best_of(lambda: plain_scipy_cb(model, imap, k), args.repeat)
        t_fg, body = best_of(lambda: CraigBamptonReductor(model, itf, n_modes=k).reduce(),
                             args.repeat)
        bodies[k] = body
        err = np.max(np.abs(body.frequencies / (np.sqrt(lam_ref) / (2 * np.pi)) - 1))
        i = body.info
        proj = i["seconds"] - i["eigen_seconds"] - i["constraint_seconds"]
        print(f"{k:>6} {t_fg:>13.2f} {t_ref:>16.2f} {t_fg / t_ref:>6.2f}  {err:>18.2e}  "
              f"{i['factor_seconds']:.2f} / {i['eigen_seconds']:.2f} / {proj:.2f}")
    print("targets: plain scipy 1.4 s / 4.7 s, Exudyn 2.2 s / 6.3 s (20 / 100 modes, unloaded)")

    body = bodies[args.modes[0]]
    t_tab, tab = best_of(lambda: flank_tables(body, sun), 1)
    t_mod, _ = best_of(lambda: modal_table(body, sun, tab.radius), 1)
    print(f"flank tables ({tab.radius.size} radii x 2 flanks, to all {sun.z} teeth): {t_tab:.2f} s; "
          f"modal shapes at those points of all {sun.z} teeth: {t_mod:.2f} s")

    print("share of a flank point's static compliance (near field removed) carried by the "
          "clamped modes:")
    # (above 100 % the modes carry part of the contact's local deformation: the residual self
    # compliance, near field removed, is then negative)
    j = tab.radius.size // 2
    for k in (20, 100, 200):
        b = bodies.get(k) or CraigBamptonReductor(model, itf, n_modes=k).reduce()
        t = flank_tables(b, sun, tab.radius)
        frac = 1.0 - t.self_residual[1][0] / t.self_static[1][0]
        raw = t.modal_fraction[1][0]
        print(f"  {k:>4} modes (to {b.frequencies[-1] / 1e3:6.1f} kHz): "
              f"{frac[j] * 100:5.1f} % at r = {tab.radius[j] * 1e3:.3f} mm, "
              f"{frac.min() * 100:5.1f}-{frac.max() * 100:5.1f} % over the flank (of the raw "
              f"patch compliance, near field included: {raw.min() * 100:4.1f}-"
              f"{raw.max() * 100:4.1f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
