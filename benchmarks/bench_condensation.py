"""Condensed modes (integrated / static) against every Craig-Bampton mode as a solver coordinate
on the flexible spur pair (level 0): mesh force difference, static force, spectrum.

python benchmarks/bench_condensation.py --step 25e-6 --variants integrated,coordinates,static
"""
import argparse
import copy
import time

import numpy as np

from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.integrator.simulation import simulate

p = argparse.ArgumentParser()
p.add_argument("--step", type=float, default=25e-6)
p.add_argument("--run-in", type=float, default=0.06)
p.add_argument("--duration", type=float, default=0.04)
p.add_argument("--variants", default="integrated,coordinates")
p.add_argument("--cutoff", type=float, default=None)
p.add_argument("--dynamic", type=float, default=None, help="dynamic_cutoff of the condensed variants")
p.add_argument("--damping", type=float, default=None, help="modal_damping")
p.add_argument("--zeta", type=float, default=None, help="mesh damping ratio instead of the paper's C")
p.add_argument("--speed", type=float, default=None)
p.add_argument("--ramp", type=float, default=None)
p.add_argument("--no-shafts", action="store_true")
p.add_argument("--one-pass", default="default", choices=["default", "on", "off"])
p.add_argument("--alpha", type=float, default=-0.1)
p.add_argument("--level", type=int, default=0)
p.add_argument("--save", default=None)
a = p.parse_args()

cfg = load_config("spur_pair_flexible")
if a.zeta is not None:
    cfg.use_damping_ratio(a.zeta)
if a.no_shafts:
    cfg.shafts = None
cfg.flexible["level"] = a.level
if a.cutoff:
    cfg.flexible["cutoff"] = a.cutoff
if a.damping is not None:
    cfg.flexible["modal_damping"] = a.damping
if a.speed is not None:
    cfg.drive["speed_hz"] = a.speed
if a.ramp is not None:
    cfg.load["ramp"] = a.ramp
gw = cfg.gears["wheel"]
rb = gw.rb
T = cfg.load["torque"]
T = float(T) if np.isscalar(T) else float(np.asarray(T)[-1, 1])
op = {"default": None, "on": True, "off": False}[a.one_pass]
h = a.step
t_end = a.run_in + a.duration
out = {}
for v in a.variants.split(","):
    c = copy.deepcopy(cfg)
    cond = "static" if v == "static" else "integrated"
    if v == "coordinates":
        c.flexible["dynamic_cutoff"] = c.flexible["cutoff"]
    elif a.dynamic is not None:
        c.flexible["dynamic_cutoff"] = a.dynamic
    model = build_model(c)
    nm = sum(fb.modes for fb in model.flex)
    t0 = time.time()
    r = simulate(model, t_end, h, 1, alpha=a.alpha, condensation=cond, one_pass=op)
    f = r.mesh[:, 0, 0]
    n0 = int(round(a.run_in / h))
    out[v] = f[n0:]
    print(f"{v:12s} modes as coords {nm:4d}  newton/step {r.newton / r.steps:5.3f}  wall {time.time() - t0:6.1f} s  mean {f[n0:].mean():9.2f} N  std {f[n0:].std():8.2f} N",
          flush=True)
if rb:
    print(f"T / r_b2 = {T / rb:.2f} N  (T {T} N m, r_b2 {rb * 1e3:.4f} mm)")
ref = a.variants.split(",")[-1] if "coordinates" not in out else "coordinates"
b = out[ref]
fs = 1.0 / h
for v, x in out.items():
    if v == ref:
        continue
    d = x - b
    rel = np.sqrt(np.mean(d ** 2)) / b.std()
    print(f"{v} - {ref}: RMS diff / std = {rel:.4f}  mean diff {d.mean():.2f} N  max|d| {np.abs(d).max():.1f} N")
    D = np.abs(np.fft.rfft((d - d.mean()) * np.hanning(len(d))))
    fr = np.fft.rfftfreq(len(d), h)
    top = np.argsort(D)[::-1]
    picked = []
    for i in top:
        if all(abs(fr[i] - fr[j]) > 3 * fs / len(d) for j in picked):
            picked.append(i)
        if len(picked) == 6:
            break
    print("   dominant lines of the difference [Hz (rel amp)]: " +
          ", ".join(f"{fr[i]:.0f} ({D[i] / D[top[0]]:.2f})" for i in picked))
if a.save:
    np.savez(a.save, h=h, **out)
