"""Cost of tooth friction and squeeze-film damping: CPU time of the same run with them off and
on, back to back, as a ratio (issue 24's bar: at most 1.15 x the run without).

Usage::

    python benchmarks/bench_friction.py [--duration 0.5] [--flexible-duration 0.4] [--lumped-duration 2]
        [--repeat 3] [--whole] [--presets spur_pair mercury_1a spur_pair_flexible spur_pair:lumped mercury_1a:lumped]

Per preset (spur_pair, mercury_1a: the rigid model; spur_pair_flexible: the flexible model as
the preset has it, ``--flexible-duration`` simulated): the integration's CPU time
(``time.process_time``, one solver thread) without ``[lubrication]``, with a constant coefficient
of 0.05, with the Xu et al. formula and with the squeeze-film damping alone
(``squeeze``: friction off, the IMPACT damper replaced) and with both (``xu+squeeze``), in turn
``repeat`` times, the order rotated each round (the kernels compiled first), the best of each,
its ratio to the run without and, for the squeeze film with friction, to the same friction with
the IMPACT damper (``vs``), and the Newton iterations per step (the film's damping differs from
the IMPACT damper's: the dynamics, and so the iterations, differ too). Timings on a loaded
machine vary; the ratio of runs taken back to back is the figure to read.

A preset with the suffix ``:lumped`` runs it with ``model = "lumped"`` (the spur pair with
``[contact] damping_ratio = 0.05`` instead of its ADAMS damper, as the guide *Lubrication*
advises for the lumped model) through :func:`~flexgear.dynamics.lumped.time_loop.simulate_lumped`
(``--lumped-duration`` simulated: a lumped step costs well under a microsecond), without
``[lubrication]``, with the constant coefficient, with the Xu et al. formula and with the squeeze
film (alone and with Xu et al.; the mesh damping ratio replaced by the film's); its
``newton/step`` counts the linear solves (the frictionless loop: one
per contact-state iteration). With ``--whole`` the lumped presets time whole runs instead
(:func:`flexgear.app.run.run` over the preset's duration: the model built, the integration, the
result with its filtered outputs; off, constant and Xu et al.), on which issue 24's bar is set.
"""
from __future__ import annotations

import argparse
import time
import warnings

from machine_info import machine
from flexgear.config import load_config, loads_config, preset_path
from flexgear.dynamics.integrator.friction import rigid_friction
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.dynamics.lumped.model import build_lumped
from flexgear.dynamics.lumped.time_loop import simulate_lumped
from flexgear.dynamics.model.assembly import build_model
from flexgear.app.run import run, time_grid

XU = 'friction_model = "xu"\niso_vg = 220\noil_temperature_c = 60.0\nroughness = 0.5e-6\n'
SQUEEZE = 'damping = "squeeze_film"\n'
LUBRICATION = {
    "constant": "friction_coefficient = 0.05\n",
    "xu": XU,
    "squeeze": SQUEEZE + "friction_coefficient = 0.0\niso_vg = 220\noil_temperature_c = 60.0\n",
    "xu+squeeze": XU + SQUEEZE,
}
#: the run each case is also compared with (besides the run without [lubrication])
SAME_WITHOUT = {"xu+squeeze": "xu"}
#: the lumped model's cases
LUMPED = ("constant", "xu", "squeeze", "xu+squeeze")


def lumped_config(preset: str, lubrication: str = ""):
    """The configuration of ``preset`` with ``model = "lumped"`` and the ``[lubrication]`` table
    ``lubrication`` (the spur pair's ADAMS damper, about 28 times critical on the lumped mesh,
    replaced by a damping ratio of 0.05)."""
    text = 'model = "lumped"\n' + preset_path(preset).read_text()
    cfg = loads_config(text + ("\n[lubrication]\n" + lubrication if lubrication else ""))
    return cfg.use_damping_ratio(0.05) if preset == "spur_pair" else cfg


def bench_lumped(preset: str, duration: float, repeat: int):
    """CPU time of the lumped runs of ``preset`` without and with friction (module docstring)."""
    models = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in ("off",) + LUMPED:
            models[name] = build_lumped(lumped_config(preset, LUBRICATION.get(name, "")))
    h, oe = time_grid(load_config(preset).simulation)
    for lm in models.values():  # compile (or load the cache)
        simulate_lumped(lm, 0.002, h, oe)
    return _rounds(models, repeat, lambda lm: simulate_lumped(lm, duration, h, oe))


def bench_lumped_runs(preset: str, repeat: int):
    """CPU time of whole lumped runs of ``preset`` (:func:`flexgear.app.run.run`: the model
    built, integrated over the preset's duration and its result assembled, the outputs
    filtered) without ``[lubrication]``, with the constant coefficient and with Xu et al.: the
    issue's bar is on these (each case run once first to compile or load its kernels)."""
    configs = {name: lumped_config(preset, LUBRICATION.get(name, "")) for name in ("off", "constant", "xu")}

    def whole(cfg):  # no solve counts: a run holds several integrations
        run(cfg)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for cfg in configs.values():
            whole(cfg)
        return _rounds(configs, repeat, whole)


def _rounds(cases: dict, repeat: int, run):
    """Best CPU time [s] of ``run(case)`` per case and its Newton iterations (linear solves) per
    step (None where ``run`` returns no Integration), the cases in turn ``repeat`` times, the
    order rotated each round (no case always runs first or last)."""
    best, newton = {}, {}
    names = list(cases)
    for r in range(repeat):
        for name in names[r % len(names):] + names[:r % len(names)]:
            c0 = time.process_time()
            integ = run(cases[name])
            best[name] = min(best.get(name, float("inf")), time.process_time() - c0)
            newton[name] = None if integ is None else integ.newton / integ.steps
    return best, newton


def bench(preset: str, duration: float, repeat: int):
    cfg = load_config(preset)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = build_model(cfg)
    h, oe = time_grid(cfg.simulation)
    tables = {"off": None}
    for name, lub in LUBRICATION.items():
        c = loads_config(preset_path(preset).read_text() + "\n[lubrication]\n" + lub)
        tables[name] = rigid_friction(c, model)
    cond = cfg.flexible["condensation"] if cfg.flexible else "integrated"
    for fr in tables.values():  # compile (or load the cache)
        simulate(model, 0.002, h, oe, friction=fr, threads=1, condensation=cond)
    return _rounds(tables, repeat,
                   lambda fr: simulate(model, duration, h, oe, friction=fr, threads=1, condensation=cond))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--duration", type=float, default=0.5, help="s simulated, rigid presets")
    p.add_argument("--flexible-duration", type=float, default=0.4, help="s simulated, flexible presets")
    p.add_argument("--lumped-duration", type=float, default=2.0, help="s simulated, lumped presets")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--whole", action="store_true",
                   help="lumped presets: time whole runs (model, integration, result) instead of the integration")
    p.add_argument("--presets", nargs="*", default=["spur_pair", "mercury_1a", "spur_pair_flexible",
                                                     "spur_pair:lumped", "mercury_1a:lumped"])
    args = p.parse_args()
    print(f"machine: {machine()}")
    print(f"{'preset':<18} {'case':<10} {'cpu s':>8} {'ratio':>6} {'vs':>14} {'newton/step':>11}")
    for preset in args.presets:
        duration = args.flexible_duration if preset.endswith("_flexible") else args.duration
        if preset.endswith(":lumped"):
            if args.whole:
                best, newton = bench_lumped_runs(preset.split(":")[0], args.repeat)
            else:
                best, newton = bench_lumped(preset.split(":")[0], args.lumped_duration, args.repeat)
        else:
            best, newton = bench(preset, duration, args.repeat)
        for name in best:
            ref = SAME_WITHOUT.get(name)
            vs = f"{best[name] / best[ref]:6.3f} ({ref})" if ref else ""
            solves = f"{'-':>11}" if newton[name] is None else f"{newton[name]:11.3f}"
            print(f"{preset:<18} {name:<10} {best[name]:8.3f} {best[name] / best['off']:6.3f} {vs:>14} {solves}")


if __name__ == "__main__":
    main()
