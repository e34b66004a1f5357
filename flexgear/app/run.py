"""A run is a pure function of its configuration: ``run(config) -> Result``.

The steps: validated configuration -> model (:mod:`flexgear.assembly`) -> time integration
(:mod:`flexgear.solver`) on a uniform grid of step h dividing the output interval -> low-pass
(polyphase FIR, scipy.signal.resample_poly) and resampling to the output rate -> run-in
discarded -> :class:`~flexgear.results.Result` carrying the full configuration.

Tooth-pair slots (``pair_*``) are instantaneous samples at the output instants (integer tooth
indices cannot be filtered); the continuous signals are anti-aliased unless
``simulation.antialias = false`` (plain sampling, as ADAMS output).
"""
from __future__ import annotations

import math
import platform
import time

import numpy as np
import tomli_w
from scipy.signal import resample_poly

from .. import __version__
from ..dynamics.assembly import build_model
from ..config import Config, load_config
from ..results.store import BodySignals, MeshSignals, Result
from ..dynamics.solver import simulate
from ..dynamics.lumped_solver import build_lumped, simulate_lumped

TAIL_SAMPLES = 40  # output samples simulated past the end, then dropped (filter edge)


def resolved_toml(cfg: Config) -> str:
    """The configuration with every default filled in, as TOML text (SI values)."""
    def clean(d):
        if isinstance(d, dict):
            return {k: clean(v) for k, v in d.items() if v is not None}
        return d

    gears = {}
    for name, g in cfg.gears.items():
        gd = {"teeth": g.z, "module": g.module, "pressure_angle_deg": math.degrees(g.pressure_angle),
              "profile_shift": g.x, "addendum": g.ha, "dedendum": g.hf, "tool_tip_radius": g.rho_f,
              "face_width": g.face_width, "thinning": g.thinning, "internal": g.internal}
        if g.internal:
            gd.update(rim_diameter=g.rim_diameter, cutter_teeth=g.cutter_teeth)
        else:
            gd["bore_diameter"] = g.bore_diameter
        m, J = cfg.gear_mass[name]
        if m is not None:
            gd["mass"] = m
        if J is not None:
            gd["inertia"] = J
        gears[name] = gd
    doc = {"title": cfg.title, "kind": cfg.kind, **({"model": "lumped", "lumped": cfg.lumped} if cfg.model == "lumped" else {}),
           "material": {"E": cfg.material.E, "nu": cfg.material.nu, "density": cfg.material.rho},
           "gears": gears}
    if cfg.planetary:
        doc["planetary"] = cfg.planetary
    if cfg.spur:
        doc["spur"] = cfg.spur
    doc.update(supports=cfg.supports, drive=cfg.drive, load=cfg.load, contact=cfg.contact, simulation=cfg.simulation,
               fe=cfg.fe)
    return tomli_w.dumps(clean(doc))


def time_grid(sim: dict) -> tuple[float, int]:
    """Integration step h [s] (<= simulation.step, dividing the output interval) and steps per
    output sample."""
    out_dt = 1.0 / sim["output_rate"]
    out_every = max(1, int(math.ceil(out_dt / sim["step"] - 1e-9)))
    return out_dt / out_every, out_every


def run(config, progress=None) -> Result:
    """Simulate a configuration (a :class:`~flexgear.config.Config`, a path or a preset name).

    Parameters
    ----------
    progress : callable(fraction) or None
        Progress callback (the CLI passes a tqdm bar).
    """
    cfg = config if isinstance(config, Config) else load_config(config)
    sim = cfg.simulation
    t_build = time.perf_counter()
    lumped = build_lumped(cfg) if cfg.model == "lumped" else None
    model = lumped.model if lumped else build_model(cfg)
    t_build = time.perf_counter() - t_build
    h, out_every = time_grid(sim)
    rate = sim["output_rate"]
    n_runin = int(round(sim["run_in"] * rate))
    n_keep = int(round(sim["duration"] * rate))
    n_out = n_runin + n_keep + TAIL_SAMPLES
    t_end = n_out / rate
    if lumped:
        integ = simulate_lumped(lumped, t_end, h, out_every, alpha=sim["hht_alpha"], max_newton=sim["max_newton"],
                                progress=progress)
    else:
        integ = simulate(model, t_end, h, out_every, alpha=sim["hht_alpha"], tol=sim["newton_tol"],
                         max_newton=sim["max_newton"], progress=progress)
    return to_result(cfg, model, integ, n_runin, n_keep, extra={"build_seconds": t_build})


def _decimate(x: np.ndarray, out_every: int, antialias: bool) -> np.ndarray:
    """From records at times (k+1) h to samples at times (j+1) out_every h."""
    x = x[out_every - 1:]
    if out_every == 1:
        return x
    if not antialias:
        return x[::out_every]
    y = resample_poly(x, 1, out_every, axis=0)
    return y[: (len(x) - 1) // out_every + 1]


def to_result(cfg: Config, model, integ, n_runin: int, n_keep: int, extra: dict | None = None) -> Result:
    """Assemble a :class:`Result` from the integration records."""
    sim = cfg.simulation
    rate = sim["output_rate"]
    aa = sim["antialias"]
    oe = integ.out_every
    # output sample j is at time (j + 1) / rate; start exactly at the end of the run-in
    first = max(n_runin - 1, 0)
    sl = slice(first, first + n_keep)
    time_ = (np.arange(first, first + n_keep) + 1) / rate
    meshes = {}
    for m, mesh in enumerate(model.meshes):
        rec = _decimate(integ.mesh[:, m, :], oe, aa)[sl]
        pf = integ.pair_f[sl, m]
        pi = integ.pair_i[sl, m]
        a, b = model.bodies[mesh.a].name, model.bodies[mesh.b].name
        meshes[mesh.name] = MeshSignals(
            name=mesh.name, body_a=a, body_b=b, normal_force=rec[:, 0].copy(),
            force_global=np.ascontiguousarray(rec[:, 1:3]), pair_force=pf[:, :, 0].copy(),
            pair_tooth_a=pi[:, :, 0].copy(), pair_tooth_b=pi[:, :, 1].copy(),
            pair_side=pi[:, :, 2].astype(np.int8), penetration=pf[:, :, 1].copy(), attrs=dict(mesh.attrs))
    bodies = {}
    for i, body in enumerate(model.bodies):
        rec = _decimate(integ.body[:, i, :], oe, aa)[sl]
        attrs = {k: v for k, v in body.attrs.items() if v is not None}
        attrs.update(mass=body.mass, inertia=body.inertia)
        bodies[body.name] = BodySignals(
            name=body.name, position=np.ascontiguousarray(rec[:, 0:2]), angle=rec[:, 2].copy(),
            velocity=np.ascontiguousarray(rec[:, 3:5]), angular_velocity=rec[:, 5].copy(),
            torque=rec[:, 6].copy() if body.speed is not None else None, attrs=attrs)
    attrs = {
        "title": cfg.title, "kind": cfg.kind, "model": cfg.model, "flexgear_version": __version__,
        "input_frequency": model.attrs["input_frequency"], "carrier_frequency": model.attrs["carrier_frequency"],
        "mesh_frequency": model.attrs["mesh_frequency"], "output_rate": rate, "run_in": sim["run_in"],
        "duration": sim["duration"], "step": integ.h, "hht_alpha": sim["hht_alpha"], "antialias": aa,
        "solver_steps": integ.steps, "newton_iterations": integ.newton, "rejected_steps": integ.rejected,
        "max_newton_in_step": integ.max_iter, "wall_seconds": integ.wall,
        "machine": f"{platform.machine()} {platform.processor() or ''} {platform.system()}".strip(),
        "notes": "; ".join(model.attrs.get("notes", [])) or "none",
    }
    if extra:
        attrs.update(extra)
    return Result(time=time_, meshes=meshes, bodies=bodies, config_toml=resolved_toml(cfg), attrs=attrs)
