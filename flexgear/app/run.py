"""A run is a pure function of its configuration: ``run(config) -> Result``.

The steps: validated configuration -> model (:mod:`flexgear.dynamics.model.assembly`) -> time integration
(:mod:`flexgear.dynamics.integrator`) on a uniform grid of step h dividing the output interval -> low-pass
and resampling to the output rate (:mod:`flexgear.results.decimation`: passband 0.8 x the output
Nyquist frequency, >= 60 dB above it) -> run-in discarded -> :class:`~flexgear.results.Result`
carrying the full configuration.

Tooth-pair slots (``pair_*``) are instantaneous samples at the output instants (integer tooth
indices cannot be filtered); the continuous signals are anti-aliased unless
``simulation.antialias = false`` (plain sampling, as ADAMS output).
"""
from __future__ import annotations

import functools
import json
import os
import platform
import sys
import time
import warnings

import numpy as np
import tomli_w

from .. import __version__
from ..dynamics.model.assembly import build_model
from ..config import Config, check_config, check_time_domain, config_document, load_config, ramp_note, time_grid
from ..config.faults import fault_frequencies
from ..gears.faults import fault_record
from ..results.decimation import decimate_many, passband_hz, settle_samples
from ..results.film import film_outputs
from ..results.noise import add_noise
from ..results.sensors import check_sensor_run, plan_sensors, record_sensors
from ..results.store import BodySignals, MeshSignals, Result
from ..dynamics.flexible.condensed import STATIC_SHARE, static_frequency
from ..dynamics.flexible.reductions import flexible_crack_note
from ..dynamics.integrator.friction import rigid_friction
from ..dynamics.integrator.simulation import simulate
from ..dynamics.threads import check_threads
from ..kernels import compile_seconds
from .console import LOADING_SOLVER, progress_bar, watched
from ..dynamics.lumped.friction import MAX_PAIRS, simulates_friction, squeeze_film_damped
from ..dynamics.lumped.faults import check_carried
from ..dynamics.lumped.model import build_lumped
from ..dynamics.lumped.time_loop import simulate_lumped
from ..dynamics.model.bodies import MAXC
from ..errors import ConfigError, user_stacklevel

#: Output samples simulated past the end, then dropped (filter edge).
TAIL_SAMPLES = 40
# (the anti-aliasing filter reaches about 22 output samples to each side, whatever the ratio of
# step rate to output rate; run() extends the tail should a filter ever reach further)


def resolved_toml(cfg: Config, step: float | None = None) -> str:
    """The configuration with every default filled in, as TOML text (SI values).

    ``step`` replaces ``simulation.step`` by the integration step a run used (see
    :func:`flexgear.config.time_grid`), so that the text reproduces the run.
    """
    doc = config_document(cfg)
    if step is not None:
        doc["simulation"] = dict(doc["simulation"], step=step)
    return tomli_w.dumps(doc)


#: the distributions whose versions a result records beside flexgear's (the numbers depend on them)
SOFTWARE = ("numpy", "scipy", "numba", "llvmlite", "scikit-fem", "gmsh", "h5py")


@functools.cache
def software_versions() -> str:
    """``"python 3.11.2; numpy 2.1.3; ..."``: Python's and :data:`SOFTWARE`'s versions, for a
    result's ``software`` attribute (read from the installed metadata, nothing imported)."""
    from importlib import metadata

    def version(name):
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            return "not installed"

    return "; ".join([f"python {platform.python_version()}"] + [f"{n} {version(n)}" for n in SOFTWARE])


def _say(text: str) -> None:
    """A phase message of a run on stderr, where its progress lines go (stdout stays the user's)."""
    print(text, file=sys.stderr, flush=True)


def run(config, progress=None, messages=None, model=None, threads=None) -> Result:
    """Simulate a configuration (a :class:`~flexgear.config.Config`, a path or a preset name).

    Parameters
    ----------
    progress : callable(fraction), bool or None
        Progress callback, called with the fraction of the integration done (the CLI passes a
        tqdm bar); ``True``: a bar of its own (``tqdm.auto``: a widget in a notebook, text in a
        terminal) with the phases of the wait (model, compile, reductions) written above it, and
        where stderr is a file or a pipe (a script's log) plain lines with the time left, as
        ``flexgear run`` writes them, the phases with them on stderr; ``None`` or ``False``: none
        (:func:`flexgear.run`, the package's entry point, turns ``None`` into ``True`` in an
        interactive session).
    messages : callable(str) or None
        Preprocessing messages (flexible gears: reductions computed or loaded from the cache).
    model : flexgear.dynamics.model.bodies.Model, optional
        A model built from this configuration (:func:`~flexgear.dynamics.model.assembly.build_model`)
        and then edited (e.g. a contact law per mesh, as ``studies/rigid_vs_flexible.py`` does);
        default: built here. The result's ``config_toml`` records the configuration, the mesh
        attributes the law each mesh used.
    threads : int or "auto", optional
        Threads of the flexible meshes' force evaluation (:func:`~flexgear.dynamics.integrator.simulation.simulate`;
        default serial). The results are bit-identical whatever the count.
    """
    check_threads(threads)  # before any long computation
    if not (progress is None or isinstance(progress, bool) or callable(progress)):
        raise TypeError(f"run(progress={progress!r}): must be None, a callable taking the fraction done (0-1), or "
                        "True for a progress bar")
    if not (messages is None or callable(messages)):
        raise TypeError(f"run(messages={messages!r}): must be None or a callable taking a message (str)")
    if isinstance(model, str):  # the model's kind is the configuration's: cfg.model
        raise TypeError(f"run(model={model!r}): must be None or a model built from the configuration "
                        f"(flexgear.dynamics.model.assembly.build_model); to choose the {model!r} model, set the "
                        f"configuration's model (cfg.model = {model!r}, or model = {model!r} in the file)")
    if progress is True and not watched():  # a log or a pipe: plain lines with the time left, as flexgear run's
        cfg = config if isinstance(config, Config) else load_config(config)
        lines, update = progress_bar(cfg.simulation["run_in"] + cfg.simulation["duration"])

        def tell(text):  # said once on stderr, as the lines, and repeated by them while nothing advances
            (_say if messages is None else messages)(text)
            lines.note(text)

        try:
            return run(cfg, update, tell, model, threads)
        finally:
            lines.close()
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=1000, desc="flexgear run",
                   bar_format="{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]")
        try:
            return run(config, lambda f: (setattr(bar, "n", round(1000 * f)), bar.refresh()),
                       bar.write if messages is None else messages, model, threads)
        finally:
            bar.close()
    progress = progress or None
    cfg = config if isinstance(config, Config) else load_config(config)
    cfg = check_config(cfg)  # a Config edited in Python meets the same rules as a file
    check_time_domain(cfg)
    check_sensor_run(cfg)
    sim = cfg.simulation
    # a synchronous grid needs a constant mesh frequency, not zero
    constant = isinstance(cfg.drive["speed_hz"], float) and cfg.mesh_frequency() != 0.0
    h, out_every = time_grid(sim, cfg.mesh_frequency() if constant else None)
    synchronous = sim["synchronous"] and constant
    sync = synchronous_note(cfg, h, out_every)
    rate = 1.0 / (out_every * h) if synchronous else sim["output_rate"]
    n_runin = int(round(sim["run_in"] * rate))
    n_keep = int(round(sim["duration"] * rate))
    check_record_size(cfg, n_runin + n_keep + TAIL_SAMPLES, out_every)  # before designing any filter
    tail = max(TAIL_SAMPLES, settle_samples(out_every) + 1) if sim["antialias"] else TAIL_SAMPLES
    n_out = n_runin + n_keep + tail
    t_end = n_out / rate
    check_record_size(cfg, n_out, out_every)
    # before the build
    short = "; ".join(x for x in (ramp_note(cfg), fault_period_note(cfg), flexible_crack_note(cfg)) if x)
    if short:
        warnings.warn(short, stacklevel=user_stacklevel())
    t_build, k_build = time.perf_counter(), compile_seconds()
    lumped = build_lumped(cfg) if cfg.model == "lumped" else None
    if lumped:
        check_carried(lumped)  # a fault that opens a loaded mesh: refused before any "simulating" line
    if model is not None and lumped:
        raise ConfigError("run(model=...): a prebuilt model is for the multi-body model, not model = 'lumped'")
    if model is None:
        model = lumped.model if lumped else build_model(cfg, progress=messages)
    t_build, k_build = time.perf_counter() - t_build, compile_seconds() - k_build
    if messages is not None:
        messages(build_message(t_build, k_build))
    check_record_size(cfg, n_out, out_every, model)  # every body, mesh and mode now known
    plan = plan_sensors(cfg, model, progress=messages)  # the housing reduced (cached) before the integration
    note = "; ".join(x for x in ("" if synchronous else step_note(sim, h, out_every), cutoff_note(cfg, h),
                                  "" if synchronous else sync) if x)
    if note:
        warnings.warn(note, stacklevel=user_stacklevel())
    if synchronous:  # asked for: recorded, not warned
        note = "; ".join(x for x in (note, sync) if x)
    note = "; ".join(x for x in (short, note) if x)
    if messages is not None and lumped:
        messages(solver_message(True, lumped.friction is not None))
    if lumped:
        integ = simulate_lumped(lumped, t_end, h, out_every, alpha=sim["hht_alpha"], max_newton=sim["max_newton"],
                                progress=progress)
    else:
        integ = simulate(model, t_end, h, out_every, alpha=sim["hht_alpha"], tol=sim["newton_tol"],
                         max_newton=sim["max_newton"], progress=progress, threads=threads,
                         condensation=cfg.flexible["condensation"] if cfg.flexible else "integrated",
                         friction=rigid_friction(cfg, model), on_solver=None if messages is None else
                         lambda state: messages(solver_message(False, state=state)))
    result = to_result(cfg, model, integ, n_runin, n_keep, synchronous=synchronous, sensors=plan,
                       extra={"build_seconds": t_build, "build_compile_seconds": k_build,
                              "compile_seconds": integ.compile_seconds})
    if note:
        notes = result.attrs["notes"]
        result.attrs["notes"] = note if notes == "none" else f"{notes}; {note}"
    return result


def _solver_entries(lumped: bool, friction: bool = False) -> tuple:
    from ..dynamics.integrator.simulation import ENTRY_KERNELS
    from ..dynamics.lumped.time_loop import integrate_lumped, integrate_lumped_friction

    if lumped:
        return (integrate_lumped_friction,) if friction else (integrate_lumped,)
    return ENTRY_KERNELS


def solver_ready(lumped: bool, friction: bool = False) -> bool:
    """Whether the time loop of the lumped (``friction``: its friction loop; else the multi-body)
    model is compiled in this process or in the kernel cache: a run then starts within seconds."""
    from ..kernels import is_cached

    return all(k.signatures or is_cached(k) for k in _solver_entries(lumped, friction))


def solver_message(lumped: bool, friction: bool = False, state: str | None = None) -> str:
    """The next phase in words, said before it starts: the time loop (of the lumped model:
    with ``friction``, its friction loop) compiled on its first run on this machine (minutes),
    loaded from the kernel cache (about a second), or ready in this process. ``state``: where
    the multi-body model's own loop comes from (:func:`flexgear.kernels.overload_state`, known
    once the model is built); without it, from whether the time loop's kernels are compiled or
    cached at all (:func:`solver_ready`)."""
    if state is None:
        state = ("compiled" if all(k.signatures for k in _solver_entries(lumped, friction))
                 else "cached" if solver_ready(lumped, friction) else "compile")
    if state == "compiled":
        return "simulating (solver compiled in this process)"
    if state == "cached":
        return f"{LOADING_SOLVER}, then simulating"
    return ("compiling the solver: "
            + ("its first run on this machine, a few seconds" if lumped else
               "the first run of this kind of model on this machine, 1 to 3 minutes on 2 cores")
            + " (cached for later runs; flexgear warm does it ahead), then simulating")


def build_message(seconds: float, compiling: float) -> str:
    """The model-building phase in words: its wall time and how much of it compiled (or loaded)
    the contact and table kernels; the rest is contact tables, reductions and assembly."""
    if compiling > 0.05:
        return (f"model built in {seconds:.1f} s ({compiling:.1f} s compiling or loading kernels, "
                f"{seconds - compiling:.1f} s contact tables, reductions and assembly)")
    return f"model built in {seconds:.1f} s (contact tables, reductions and assembly)"


def record_bytes(cfg: Config, n_out: int, out_every: int, model=None) -> int:
    """Memory [bytes] the solver's records of a run take (:func:`flexgear.dynamics.integrator.buffers.records`,
    8 bytes a value): every integration step's mesh signals (3 per mesh), body signals (7 per
    body), modal coordinates (and a coupled housing's, recorded with them) and tooth friction
    (lumped: 12 per mesh; rigid: 3 per mesh and 3 per contact slot at the output samples) and
    squeeze-film damping (1 per mesh; at the output samples rigid and flexible 1 per contact slot,
    lumped 1 per mesh), and every output sample's tooth-pair slots (6 per slot) and condensed modes' coordinates
    (``Records.condensed``: one per condensed mode of the flexible bodies, with either
    condensation; on flexible MERCURY 1-A 358 modes, 8 x 358 bytes a sample, 29 MB per simulated
    second at its 10 kHz output rate).

    With the ``model`` (:func:`~flexgear.dynamics.model.assembly.build_model`) the count is exact;
    without it, from the configuration alone, the gears and carrier only (no shaft motor or
    load bodies, no modal, housing or condensed coordinates: a lower bound)."""
    if model is not None:
        n_mesh, n_body = len(model.meshes), len(model.bodies)
        n_modal = sum(fb.modes for fb in model.flex) + (0 if model.housing is None else model.housing.n)
        n_condensed = sum(fb.shape.shape[3] for fb in model.flex)
    else:
        if cfg.kind == "spur":
            n_mesh, n_body = 1, 2
        else:
            n_planets = cfg.planetary["planets"]
            n_mesh, n_body = 2 * n_planets, n_planets + 3
        n_modal = n_condensed = 0
    steps = n_out * out_every
    # tooth friction: per step and mesh, lumped 3 values per pair slot and 3 totals, rigid 3 totals;
    # rigid also 3 values per contact slot at the output samples
    rubs = simulates_friction(cfg)
    squeeze = squeeze_film_damped(cfg)
    lumped = cfg.model == "lumped"
    n_friction = ((3 * MAX_PAIRS + 3) if lumped else 3) * n_mesh if rubs or (lumped and squeeze) else 0
    n_friction += n_mesh if squeeze else 0  # the films' power per step
    # per output sample: rigid 1 value per contact slot, lumped 1 per mesh (its slot 0)
    n_pairs = (6 + (3 if rubs and not lumped else 0) + (1 if squeeze and not lumped else 0)) * n_mesh * MAXC \
        + (n_mesh if squeeze and lumped else 0)
    return 8 * (steps * (3 * n_mesh + 7 * n_body + n_modal + n_friction) + n_out * (n_pairs + n_condensed))


def memory_bytes() -> int | None:
    """Physical memory of this machine [bytes], or None where it cannot be read."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def check_record_size(cfg: Config, n_out: int, out_every: int, model=None) -> None:
    """Refuse, before any work (and again with the built ``model``, before the integration), a
    run whose records (:func:`record_bytes`) would not fit in half the machine's memory."""
    need = record_bytes(cfg, n_out, out_every, model)
    have = memory_bytes() or 16 * 2**30
    if need > have / 2:
        sim = cfg.simulation
        n_condensed = sum(fb.shape.shape[3] for fb in model.flex) if model is not None else 0
        share = ""
        if n_condensed:
            part = 8 * n_out * n_condensed
            share = (f" ({part / 2**30:.3g} GiB of them the {n_condensed} condensed modes' coordinates at "
                     f"{n_out} output samples, Records.condensed)")
        raise ConfigError(
            f"simulation.step = {sim['step']!r} s with simulation.duration = {sim['duration']!r} s and run_in = "
            f"{sim['run_in']!r} s: {n_out * out_every:.3g} integration steps whose records need {need / 2**30:.3g} GiB"
            f"{share}, more than half of this machine's {have / 2**30:.3g} GiB; use a larger step or a shorter "
            "duration" + (", or a lower flexible.cutoff (fewer condensed modes)" if n_condensed else ""))


def step_note(sim: dict, h: float, out_every: int) -> str:
    """The message recorded when the integration step h differs from ``simulation.step``."""
    if abs(h - sim["step"]) <= 1e-9 * sim["step"]:
        return ""
    return (f"simulation.step = {sim['step']:.6g} s does not divide the output interval "
            f"1/output_rate = {1 / sim['output_rate']:.6g} s: integrated with h = {h:.6g} s "
            f"({out_every} steps per output sample); config_toml records this step")


def synchronous_note(cfg: Config, h: float, out_every: int) -> str:
    """The message recorded for ``simulation.synchronous`` (:func:`flexgear.config.time_grid`):
    the steps per mesh period and the output rate used, or why it was not applied (a speed
    table)."""
    sim = cfg.simulation
    if not sim["synchronous"]:
        return ""
    if not isinstance(cfg.drive["speed_hz"], float):
        return ("simulation.synchronous = true not applied: drive.speed_hz is a table, the mesh frequency changes "
                "during the run; the step divides the output interval instead")
    fm = cfg.mesh_frequency()
    if fm == 0.0:
        return ("simulation.synchronous = true not applied: drive.speed_hz = 0, the gears do not mesh; the step "
                "divides the output interval instead")
    return (f"simulation.synchronous: step h = {h:.6g} s, {round(1.0 / (fm * h))} steps per mesh period "
            f"(f_m = {fm:.6g} Hz), output at {1.0 / (out_every * h):.8g} Hz ({out_every} steps per sample; "
            f"output_rate = {sim['output_rate']:g} Hz asked)")


def cutoff_note(cfg: Config, h: float) -> str:
    """The message recorded when the flexible gears' mode cutoff leaves modes that the step h
    resolves to the reduction's static residual tables (below
    :func:`~flexgear.dynamics.flexible.condensed.static_frequency`)."""
    fx = cfg.flexible
    if not fx or fx["condensation"] != "integrated":
        return ""
    f = static_frequency(h, cfg.simulation["hht_alpha"])
    if fx["cutoff"] >= f:
        return ""
    return (f"flexible.cutoff = {fx['cutoff']:.6g} Hz is below {f:.4g} Hz, where a mode integrated with the step "
            f"{h:.4g} s responds within {STATIC_SHARE:.0%} of statically: the modes between are condensed into the "
            f"static residual tables though the step resolves them; set flexible.cutoff >= {f:.4g} Hz")


def fault_period_note(cfg) -> str:
    """The message recorded when ``simulation.duration`` is shorter than the period of a configured
    fault or error of nonzero size (:func:`~flexgear.config.faults.fault_frequencies`, at the mean
    speed): the record then holds the fault once or, by its phase, not at all, and the
    time-synchronous average and the fault indicators need several periods."""
    d = cfg.simulation["duration"]
    short = [(label, hz) for label, hz in fault_frequencies(cfg, healthy=False) if 0.0 < hz * d < 1.0]
    if not short:
        return ""
    what = ", ".join(f"{label} at {hz:.4g} Hz (period {1.0 / hz:.4g} s)" for label, hz in short)
    return (f"simulation.duration = {d:.6g} s is shorter than one period of {what}: the record holds the fault "
            f"once or, by its phase, not at all; simulation.duration >= {max(1.0 / hz for _, hz in short):.4g} s "
            "holds one period, several are better")


def result_record(cfg) -> dict | None:
    """The faults and errors of ``cfg`` for a result's ``/faults`` group (None without any):
    ``record``, JSON text ``{"faults": [...], "errors": {...} or null}`` of
    :func:`~flexgear.gears.faults.fault_record` (SI: m, rad; ``null`` true for a fault of zero size,
    which leaves the tooth healthy), and per configured fault and error
    its label and characteristic frequency [Hz] (:func:`~flexgear.config.faults.fault_frequencies`)."""
    if not cfg.faults and cfg.errors is None:
        return None
    rows = fault_frequencies(cfg)
    record = {"faults": [dict(fault_record(f), null=f.null) for f in cfg.faults],  # null: zero size, healthy
              "errors": None if cfg.errors is None else fault_record(cfg.errors)}
    return {"record": json.dumps(record, sort_keys=True), "labels": [r[0] for r in rows],
            "frequency_hz": [float(r[1]) for r in rows]}


def to_result(cfg: Config, model, integ, n_runin: int, n_keep: int, extra: dict | None = None,
              synchronous: bool = False, sensors=None) -> Result:
    """Assemble a :class:`~flexgear.results.Result` from the integration records.

    ``sensors``: a :class:`~flexgear.results.sensors.SensorPlan` (:func:`~flexgear.results.sensors.plan_sensors`)
    whose path models give the result's sensor signals, from the whole records (the housing at
    rest when the run starts, its start transient in the run-in).

    ``synchronous``: the run used the synchronous grid of ``simulation.synchronous``; the output
    rate is then that of the grid (recorded in the attributes), and ``config_toml`` keeps the
    step and output rate asked for, from which :func:`~flexgear.config.time_grid` gives the same
    grid again (otherwise it records the step used, see :func:`resolved_toml`)."""
    sim = cfg.simulation
    rate = 1.0 / (integ.out_every * integ.h) if synchronous else sim["output_rate"]
    aa = sim["antialias"]
    oe = integ.out_every
    # output sample j is at time (j + 1) / rate; start exactly at the end of the run-in
    first = max(n_runin - 1, 0)
    sl = slice(first, first + n_keep)
    steps = slice(first * oe, (first + n_keep) * oe)  # the steps of the output samples sl
    time_ = (np.arange(first, first + n_keep) + 1) / rate
    notes = list(model.attrs.get("notes", []))
    settle = settle_samples(oe) if aa else 0
    if first < settle:
        notes.append(f"the first {settle - first} output samples include the anti-aliasing filter's start-up "
                     f"(run_in {sim['run_in']:g} s < {settle / rate:g} s)")
    # every per-step record through the anti-aliasing filter at once, over the kept samples
    fr = getattr(integ, "friction", None)  # tooth friction (lumped: lumped.friction; rigid, flexible: integrator)
    dmp = getattr(integ, "damping", None)  # squeeze-film damping
    has_modal = getattr(integ, "modal", None) is not None and integ.modal.size > 0
    per_step = {"mesh": integ.mesh, "body": integ.body}
    if fr is not None:
        per_step.update(friction_force=fr["force"], friction_power=fr["power"])
    if dmp is not None:
        per_step["damping_power"] = dmp["power"]
    if has_modal:
        per_step["modal"] = integ.modal
    kept = dict(zip(per_step, decimate_many(list(per_step.values()), oe, aa, sl)))
    meshes = {}
    for m, mesh in enumerate(model.meshes):
        rec = kept["mesh"][:, m, :]
        pf = integ.pair_f[sl, m]
        pi = integ.pair_i[sl, m]
        a, b = model.bodies[mesh.a].name, model.bodies[mesh.b].name
        meshes[mesh.name] = MeshSignals(
            name=mesh.name, body_a=a, body_b=b, normal_force=rec[:, 0].copy(),
            force_global=np.ascontiguousarray(rec[:, 1:3]), pair_force=pf[:, :, 0].copy(),
            pair_tooth_a=pi[:, :, 0].copy(), pair_tooth_b=pi[:, :, 1].copy(),
            pair_side=pi[:, :, 2].astype(np.int8), penetration=pf[:, :, 1].copy(), attrs=dict(mesh.attrs),
            pair_deflection=(integ.records.pair_deflection[sl, m].copy() if mesh.attrs.get("flexible") else None))
        if fr is not None:
            sig = meshes[mesh.name]
            sig.friction_force = kept["friction_force"][:, m].copy()
            sig.friction_power = kept["friction_power"][:, m].copy()
            sig.sliding_speed = fr["sliding"][sl, m].copy()
            sig.contact_position = fr["position"][sl, m].copy()
            sig.pair_friction_force = fr["pair_force"][sl, m].copy()
            # the energies over the recorded window's steps, not means of the (filtered) samples
            sig.attrs["mesh_efficiency"] = float(1.0 - fr["power"][steps, m].sum() / fr["through"][steps, m].sum())
        elif cfg.lubrication is not None and not simulates_friction(cfg):  # a coefficient of 0: no friction loss
            meshes[mesh.name].attrs["mesh_efficiency"] = 1.0
        if dmp is not None:
            sig = meshes[mesh.name]
            sig.damping_power = kept["damping_power"][:, m].copy()
            sig.pair_damping_force = dmp["pair_force"][sl, m].copy()
    bodies = {}
    modal = {}
    if has_modal:
        rows = kept["modal"]
        nr = model.rigid_coordinates()
        modal = {b: np.ascontiguousarray(rows[:, c0 - nr:c0 - nr + m]) for b, c0, m in model.modal_coordinates()}
    condensed, condensed_hz = {}, {}  # instantaneous samples, as the pair slots
    cond = getattr(integ, "condensed", None)
    if cond is not None and cond.size:
        o = 0
        for fb in model.flex:
            nq = fb.shape.shape[3]
            if nq:
                condensed[fb.body] = np.ascontiguousarray(cond[sl, o:o + nq])
                condensed_hz[fb.body] = [float(w) / (2.0 * np.pi) for w in fb.condensed_omega]
            o += nq
    for i, body in enumerate(model.bodies):
        rec = kept["body"][:, i, :]
        attrs = {k: v for k, v in body.attrs.items() if v is not None}
        attrs.update(mass=body.mass, inertia=body.inertia)
        if i in condensed_hz:
            attrs["condensed_frequencies"] = condensed_hz[i]
        bodies[body.name] = BodySignals(
            name=body.name, position=np.ascontiguousarray(rec[:, 0:2]), angle=rec[:, 2].copy(),
            velocity=np.ascontiguousarray(rec[:, 3:5]), angular_velocity=rec[:, 5].copy(),
            torque=rec[:, 6].copy() if body.speed is not None else None, attrs=attrs,
            modal_coordinates=modal.get(i), condensed_coordinates=condensed.get(i))
    freq = {k: model.attrs[k] for k in ("input_frequency", "carrier_frequency", "mesh_frequency")}
    drive = bodies.get(cfg.drive["body"])
    if not isinstance(cfg.drive["speed_hz"], float) and drive is not None and drive.angular_velocity.size:
        # a speed table: the characteristic frequencies of the record (the means over its samples), not the table's
        f_in = np.abs(drive.angular_velocity) / (2 * np.pi)
        scale = float(f_in.mean()) / freq["input_frequency"] if freq["input_frequency"] else 1.0
        freq = {k: v * scale for k, v in freq.items()}
        if f_in.max() - f_in.min() > 1e-3 * f_in.mean():
            notes.append(f"drive speed {f_in.min():.4g} to {f_in.max():.4g} Hz over the record: input, carrier and "
                         "mesh frequencies are its means (a spectrum smears; for orders, flexgear monitor resamples "
                         "by angle)")
    attrs = {
        "title": cfg.title, "kind": cfg.kind, "model": "flexible" if cfg.flexible else cfg.model,
        "flexgear_version": __version__, "software": software_versions(), **freq, "output_rate": rate,
        "run_in": sim["run_in"],
        "duration": sim["duration"], "step": integ.h, "hht_alpha": sim["hht_alpha"], "antialias": aa,
        "solver_steps": integ.steps, "newton_iterations": integ.newton, "rejected_steps": integ.rejected,
        "max_newton_in_step": integ.max_iter, "wall_seconds": integ.wall,
        "machine": f"{platform.machine()} {platform.processor() or ''} {platform.system()}".strip(),
        "passband_hz": passband_hz(rate) if aa and oe > 1 else 0.5 * rate,
        "notes": "; ".join(notes) or "none",
    }
    if extra:
        attrs.update(extra)
    hrec = None if model.housing is None else integ.modal[:, integ.modal.shape[1] - model.housing.n:]
    signals, loads = ({}, {}) if sensors is None else record_sensors(sensors, cfg, model, integ.mesh, integ.body,
                                                                     integ.h, oe, aa, sl, rate, housing_rec=hrec)
    config_toml = resolved_toml(cfg, step=None if synchronous else integ.h)
    add_noise(signals, cfg.sensors, config_toml)  # measurement noise (sensors with noise_rms or snr_db)
    result = Result(time=time_, meshes=meshes, bodies=bodies, config_toml=config_toml,
                    attrs=attrs, sensors=signals, housing_loads=loads, faults=result_record(cfg))
    film_outputs(cfg, result)  # EHL film of the recorded contacts (runs with friction and a lubricant)
    return result
