"""Command line: ``flexgear run | info | preset | mesh | modes | modal | deform | batch``.

``flexgear run CONFIG -o OUTDIR`` simulates a configuration (a TOML file or a built-in preset
name) with a progress bar (plain progress lines when stderr is not a terminal), writes
``OUTDIR/results.h5`` and the paper-style figures, and refuses to overwrite an existing result
unless ``--overwrite`` is given. Every command checks its input and its output files before
any work, and a failed command leaves no partial file or empty directory behind.
"""
from __future__ import annotations

import argparse
import math
import shutil
import sys
import time
import warnings
from pathlib import Path

from .. import __version__
from ..config import PARAMETER_SETS, PRESETS
from ..errors import FlexgearError, ResultExistsError
from ..files import atomic_write, check_output_directory, check_targets, output_directory, probe_directory
from .batch_command import add_batch_command
from .monitor_command import add_monitor_command
from .console import cell, count_bar, markdown_table, progress_bar, run_command
from .warm import DEFAULT_CONFIGS

PRESET_NAMES = PRESETS + PARAMETER_SETS  # names `flexgear preset` lists and copies


def _load(config):
    from ..config import load_config

    return load_config(config)


def _need_gears(cfg, command: str) -> None:
    """A lumped parameter set as printed has no gears: refuse the commands that need them."""
    if not cfg.gears:
        raise FlexgearError(f"flexgear {command}: {cfg.source or 'the configuration'} is a lumped parameter set "
                            "without [gears] (no gear data to show, mesh or run); use `flexgear modal`")


def _lubrication_info(cfg, e_star: float, static) -> list[str]:
    """The ``[lubrication]`` section of :func:`info_text`: the lubricant and, with ``static`` =
    (load [N], {pair: gear 1's speed [rad/s]}) the static load of a constant load torque (None
    otherwise), per pair the loss factor, the efficiency with equal load sharing and the pitch
    point's film (:func:`~flexgear.gears.lubrication.nominal_lubrication`)."""
    from ..gears.lubrication import nominal_lubrication
    from ..gears.tribology import friction_law

    lub = cfg.lubrication
    oil = lub.lubricant
    law = (f"constant mu = {lub.friction_coefficient:g}" if lub.friction_model == "constant"
           else {"benedict_kelley": "Benedict & Kelley (1961)", "xu": "Xu et al. (2007)"}.get(lub.friction_model,
                                                                                               lub.friction_model))
    head = [f"friction coefficient: {law}; regularised over v0 = {lub.sliding_speed_scale:g} m/s"]
    if oil is not None:
        grade = f"ISO VG {oil.iso_vg} at {oil.temperature_c:g} degC: " if oil.iso_vg is not None else ""
        head.append(f"lubricant: {grade}eta_0 = {oil.viscosity:.4g} Pa s (nu = {oil.kinematic_viscosity * 1e6:.4g} "
                    f"mm^2/s), alpha = {oil.pressure_viscosity:.3g} 1/Pa, density {oil.density:g} kg/m^3")

    title = ("## Lubrication at the static load (rigid involutes, the load shared equally by the pairs in contact; "
             "film at the pitch point)")
    if static is None:
        return [title, ""] + [f"- {line}" for line in head] + [
            "- no static load to evaluate the meshes at: the load torque is not a constant (a table), or a "
            "planetary set's load is not on the carrier"]
    load, omega1 = static
    rows = []
    for name, pair in cfg.pairs.items():
        rq = lub.mesh_roughness(pair.g1.name, pair.g2.name)
        nom = nominal_lubrication(pair, friction_law(lub, pair.g1.name, pair.g2.name, e_star), oil, rq, e_star,
                                  load, omega1[name])
        rows.append([name, cell(nom.loss_factor), cell(nom.efficiency, 100.0, ".3f"), cell(nom.pitch_load),
                     cell(nom.film_central, 1e6), cell(nom.film_minimum, 1e6), cell(nom.film_ratio)])
    what = ("- efficiency: the closed form over the ISO 21771 path of contact of rigid involutes (1 - mu H_V, "
            "Ohlendorf, for a constant coefficient; otherwise the friction power along that path with the pairs "
            "sharing the load equally), not a run's.")
    if cfg.model == "lumped":
        what += " A lumped run's pairs stay on that path: its efficiency differs by the dynamics only."
    else:
        what += (" A run's contact is softer: the loaded tip corners touch beyond the path (the rigid model's IMPACT "
                 "law, the flexible model's compliant teeth), where the sliding is fastest, so a run loses more "
                 "(spur_pair with mu = 0.05: 98.80 % run, 99.06 % here). Guide *Lubrication*, *Mesh losses and "
                 "efficiency*.")
    return ([title, ""] + [f"- {line}" for line in head]
             + ["", markdown_table(rows, ["pair", "H_V", "efficiency %", "w N/m", "h_c um", "h_min um", "lambda"]),
                "", what])


def info_text(cfg) -> str:
    """Derived gear data, pair data and characteristic frequencies as Markdown tables."""
    from ..dynamics.model.assembly import check_planetary
    from ..gears.geometry import GearPair
    from ..gears.material import effective_modulus

    mm = 1e3
    rows = []
    for name, g in cfg.gears.items():
        m, J = g.mass_properties(cfg.material.rho)
        wk = f"{g.base_tangent_length(g.base_tangent_span)*mm:.4f} (k={g.base_tangent_span})" if not g.internal else "-"
        rows.append([name, g.z, "internal" if g.internal else "external", f"{g.r*2*mm:.3f}", f"{g.rb*2*mm:.3f}",
                     f"{g.ra*2*mm:.3f}", f"{g.rf*2*mm:.3f}", f"{g.r_form*2*mm:.3f}", f"{g.pb*mm:.4f}",
                     f"{g.s*mm:.4f}", f"{g.tip_thickness*mm:.4f}", wk, "yes" if g.undercut else "no",
                     f"{m:.4g}", f"{J:.4g}"])
    out = [f"# {cfg.title}", "", "## Gears (diameters in mm)", "",
           markdown_table(rows, ["gear", "z", "type", "d", "d_b", "d_a", "d_f", "d_Ff (form)", "p_b", "s",
                         "s_a", "W_k", "undercut", "mass kg", "J kg m^2"])]
    e_star = effective_modulus(cfg.material, cfg.material)
    prow = []
    flexible = set((cfg.flexible or {}).get("gears", ())) if cfg.model == "rigid" else set()
    for name, pair in cfg.pairs.items():
        law = cfg.contact_law(pair)
        # a mesh with a flexible gear has the compliant FE contact (line-contact Hertz on the FE flank
        # compliance), not the IMPACT law's K
        used = ("- (compliant FE contact)" if {pair.g1.name, pair.g2.name} & flexible
                else f"{law.K:.4g} N/m^{law.e:g}")
        prow.append([name, f"{pair.centre_distance*mm:.4f}", f"{math.degrees(pair.alpha_w):.4f}",
                     f"{pair.contact_ratio:.4f}", f"{pair.hertz_radius*mm:.4f}",
                     f"{pair.hertz_stiffness(e_star)*1e-3**1.5:.4g}", used])
    out += ["", "## Pairs (ISO 21771)", "",
            markdown_table(prow, ["pair", "a_w mm", "alpha_w deg", "eps_alpha", "R (Eq. 5) mm", "K Eq. 5 N/mm^1.5",
                          "K used (SI)"])]
    f_in = cfg.input_frequency
    frow = []
    if cfg.kind == "spur":
        zin = cfg.gears[cfg.drive["body"]].z
        fm = zin * f_in
        frow += [["input rotation", f"{f_in:.4g}"], ["gear mesh f_m", f"{fm:.4g}"]]
        frow += [[f"{k} f_m", f"{k*fm:.4g}"] for k in (2, 3, 4)]
        tload = cfg.load["torque"]
        static = None  # (normal tooth force [N], {pair: gear 1's angular velocity [rad/s]}) at the static load
        if isinstance(tload, float):
            rb = cfg.gears[cfg.load["body"]].rb
            frow.append(["static normal tooth force (N)", f"{tload/rb:.5g}"])
            static = (tload / rb, {name: 2 * math.pi * fm / pair.g1.z for name, pair in cfg.pairs.items()})
        notes = GearPair(cfg.gears["pinion"], cfg.gears["wheel"]).check()
    else:
        zs, zp, zr = (cfg.gears[n].z for n in ("sun", "planet", "ring"))
        fs = f_in if cfg.drive["body"] == "sun" else f_in * (zs + zr) / zs
        fc = fs * zs / (zs + zr)
        fm = zr * fc
        N = cfg.planetary["planets"]
        fp = (fs - fc) * zs / zp  # the planets spin against the sun relative to the carrier
        frow += [["sun rotation", f"{fs:.4g}"], ["carrier f_a", f"{fc:.4g}"],
                 ["planet spin relative to carrier (against the sun)", f"{fp:.4g}"],
                 ["planet rotation, absolute (signed as the sun's)", f"{fc - fp:.4g}"],
                 ["planet pass N f_a (the planets passing a fixed point)", f"{N * fc:.4g}"],
                 ["gear mesh f_m", f"{fm:.4g}"], ["2 f_m", f"{2*fm:.4g}"], ["3 f_m", f"{3*fm:.4g}"]]
        tl = cfg.load["torque"]
        static = None
        if isinstance(tl, float) and cfg.load["body"] == "carrier":
            ts = tl / (1 + zr / zs)
            frow += [["sun torque at equilibrium (N m)", f"{ts:.4g}"],
                     ["normal tooth force per planet (N)", f"{ts/N/cfg.gears['sun'].rb:.5g}"]]
            # gear 1 of each pair (the sun, the planet) relative to the carrier: f_m / z
            static = (ts / N / cfg.gears["sun"].rb, {name: 2 * math.pi * fm / pair.g1.z
                                                     for name, pair in cfg.pairs.items()})
        notes = check_planetary(cfg)
    from ..config.faults import characteristic_fault_frequencies, fault_frequencies, loaded_flanks

    frow += [[f"{what}: {formula}", f"{hz:.4g}"] for what, formula, hz in characteristic_fault_frequencies(cfg)]
    out += ["", "## Characteristic frequencies (Hz) and static loads", "", markdown_table(frow, ["quantity", "value"])]
    names = {1: "left", -1: "right"}
    lrow = [[mesh, names[a], names[b]] for mesh, (a, b) in loaded_flanks(cfg).items()]
    out += ["", "## Loaded flanks (tooth k centred at body angle + 2 pi k / z, counted counter-clockwise; left = "
            "the tooth's counter-clockwise side)", "", markdown_table(lrow, ["mesh", "gear a", "gear b"])]
    if cfg.faults or cfg.errors is not None:
        freqs = fault_frequencies(cfg)
        out += ["", "## Faults and errors: characteristic frequencies (Hz)", "",
                markdown_table([[what, f"{hz:.4g}"] for what, hz in freqs], ["fault / error", "Hz"]) if freqs else
                "none: every fault and error given has size 0 (the healthy set)"]
        pitch = _pitch_rows(cfg)
        if pitch:
            out += ["", "## Pitch deviations (ISO 1328-1:2013, um)", "",
                    markdown_table(pitch, ["gear", "f_p", "F_p", "class met", "f_pT", "F_pT", "deviations"])]
    if cfg.lubrication is not None:
        out += ["", *_lubrication_info(cfg, e_star, static)]
    if getattr(cfg, "shafts", None):
        from ..dynamics.model.shafts import shaft_properties

        srow = []
        for name in cfg.shafts:
            p = shaft_properties(cfg, name)
            srow.append([name, p.body, f"{p.torsional_stiffness:.5g}",
                         "-" if p.lateral_stiffness is None else f"{p.lateral_stiffness:.5g}",
                         f"{p.polar_inertia:.4g}", f"{p.bending_mass:.4g}",
                         f"{p.load_inertia:.4g}" if name == "output" else "-"])
        out += ["", "## Shafts", "", markdown_table(srow, ["shaft", "body", "k_t (N m/rad)", "k_lat (N/m)",
                                                           "J_s (kg m^2)", "bending mass (kg)", "load J (kg m^2)"])]
    out += ["", "## Notes", ""] + ([f"- {n}" for n in notes] or ["- none"])
    return "\n".join(out)


def _pitch_rows(cfg) -> list:
    """Each gear's pitch deviations against ISO 1328-1:2013: the largest single and the total
    cumulative pitch deviation, the finest class they meet and that class's tolerances [um]."""
    from ..gears.faults import iso1328_class, iso1328_tolerances, pitch_deviation_measures

    rows = []
    for body, ge in (cfg.errors.gears.items() if cfg.errors is not None else ()):
        if ge.pitch is None or ge.pitch.null:
            continue
        gear = cfg.gears[body.rstrip("0123456789")]  # planet2 -> planet
        fp, Fp = pitch_deviation_measures(ge.pitch.deviations)
        a = iso1328_class(gear, ge.pitch.deviations)
        t = iso1328_tolerances(gear, a) if a is not None else None
        tol = ["-", "-"] if t is None else [f"{t.single_pitch * 1e6:g}", f"{t.cumulative_pitch * 1e6:g}"]
        rows.append([body, f"{fp * 1e6:.3g}", f"{Fp * 1e6:.3g}", "coarser than 11" if a is None else a, *tol,
                     "given" if ge.pitch.grade is None else f"drawn for class {ge.pitch.grade}, seed {ge.pitch.seed}"])
    return rows


def cmd_info(args):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = _load(args.config)
    _need_gears(cfg, "info")
    text = info_text(cfg)
    if args.output is None:
        print(text)
        return
    dst = Path(args.output)
    _check_file_target(dst, args.overwrite)
    atomic_write(dst, lambda p: Path(p).write_text(text + "\n"))
    print(f"wrote {dst}")


def _check_file_target(dst: Path, overwrite: bool) -> None:
    """A file to write: not a directory, not an existing file unless ``overwrite``, in a
    directory that exists and takes a file."""
    if dst.is_dir():
        raise ResultExistsError(f"-o {dst}: is a directory; give a file name")
    if dst.exists() and not overwrite:
        raise ResultExistsError(f"-o {dst}: exists; refusing to overwrite it (use --overwrite)")
    if not dst.parent.is_dir():
        raise FlexgearError(f"-o {dst}: directory {str(dst.parent)!r} does not exist")
    probe_directory(dst.parent)  # a real write, undone: refused now rather than after the work


def cmd_preset(args):
    from ..config import preset_path

    if args.name is None:
        print("\n".join(PRESET_NAMES))
        return
    src = preset_path(args.name)
    if args.output is None:
        print(src.read_text(), end="")
        return
    dst = Path(args.output)
    _check_file_target(dst, args.overwrite)
    atomic_write(dst, lambda p: shutil.copyfile(src, p))
    print(f"wrote {dst}")


def cmd_run(args):
    from ..config import check_config, check_time_domain
    from ..dynamics.lumped.friction import simulates_friction
    from ..results.plots import paper_figure_names, paper_figures
    from ..results.store import save
    from .run import run

    cfg = _load(args.config)
    check_time_domain(cfg)
    if args.duration is not None:
        if not args.duration > 0:
            raise FlexgearError(f"--duration = {args.duration}: must be > 0 s")
        cfg.simulation["duration"] = float(args.duration)
    cfg = check_config(cfg)
    if args.print_config:
        from .run import resolved_toml

        print(resolved_toml(cfg), end="")
        return 0
    if args.output is None:
        raise FlexgearError("flexgear run: -o/--output OUTDIR is required (the directory for results.h5 and the "
                            "figures), unless --print-config")
    # every check before any work: nothing is computed or written if one fails
    out = Path(args.output)
    target = out / "results.h5"
    figures = [] if args.no_figures else paper_figure_names(cfg.kind, simulates_friction(cfg),
                                                            [sensor.name for sensor in cfg.sensors])
    targets = [target] + [out / n for n in figures]
    check_output_directory(out)
    existing = [str(p) for p in targets if p.exists()]
    if existing and not args.overwrite:
        raise ResultExistsError(f"{', '.join(existing)} exist{'s' if len(existing) == 1 else ''}; refusing to "
                                "overwrite (use --overwrite or another -o)")
    total = cfg.simulation["run_in"] + cfg.simulation["duration"]
    bar, update = progress_bar(total)

    def tell(text):  # said once, and repeated by plain progress lines while nothing advances
        say(text)
        getattr(bar, "note", lambda _: None)(text)

    try:
        # every phase named: reductions computed or loaded, model built (kernels, tables), solver compiled
        result = run(cfg, progress=update, messages=tell)
    finally:
        bar.close()
    with output_directory(out):
        save(result, target, overwrite=args.overwrite)
        print(f"wrote {target}")
        if not args.no_figures:
            for p in paper_figures(result, out, overwrite=args.overwrite):
                print(f"wrote {p}")
    print(summary_text(result))


def summary_text(result) -> str:
    """Mean forces, sensor levels and solver statistics of a result."""
    a = result.attrs
    rows = [[name, f"{m.normal_force.mean():.5g}", f"{m.normal_force.std():.4g}"] for name, m in result.meshes.items()]
    sim_s = a["run_in"] + a["duration"]
    comp = a.get("compile_seconds", 0.0)
    build = a.get("build_seconds")
    lines = [markdown_table(rows, ["mesh", "mean normal force N", "std N"]), ""]
    rubbing = {name: m for name, m in result.meshes.items()
               if getattr(m, "friction_force", None) is not None or getattr(m, "damping_power", None) is not None}
    if rubbing:  # tooth friction or squeeze films ([lubrication]): the batch summary's columns
        from .metrics import (film_damping_loss, friction_loss, mesh_efficiency, min_film, min_film_ratio,
                              rms_friction_force)

        frows = [[name, cell(mesh_efficiency(result, m), 100.0, ".3f"), cell(friction_loss(result, m)),
                  cell(rms_friction_force(result, m)), cell(min_film(result, m), 1e6, ".3g"),
                  cell(min_film_ratio(result, m), 1.0, ".3g")] for name, m in rubbing.items()]
        heads = ["mesh", "efficiency %", "friction loss W", "friction force rms N", "min film um", "min lambda"]
        if any(getattr(m, "damping_power", None) is not None for m in rubbing.values()):
            for row, m in zip(frows, rubbing.values()):
                row.insert(3, cell(film_damping_loss(result, m)))
            heads.insert(3, "film damping W")
        lines += [markdown_table(frows, heads), ""]
        corners = {name: m.attrs["film_corner_contacts"] for name, m in rubbing.items()
                   if m.attrs.get("film_corner_contacts")}
        if corners:  # tip corners off the involutes: no line-contact film (flexgear.results.film)
            lines += ["min film and lambda: of the contacts on the involutes (the path of contact); left out, "
                      "tip-corner contacts outside it (output samples x slots): "
                      + ", ".join(f"{name} {n}" for name, n in corners.items())
                      + " (guide Lubrication, Film thickness outputs)", ""]
    sensors = getattr(result, "sensors", None) or {}  # a stand-in result may have none
    if sensors:
        srows = [[f"{name}/{path}", s.signal_attrs[path]["units"], f"{y.std():.4g}"]
                 for name, s in sensors.items() for path, y in s.signals.items()]
        lines += [markdown_table(srows, ["sensor signal", "units", "rms about the mean"]), ""]
    lines.append(f"solver: {a['solver_steps']} steps, {a['newton_iterations']} Newton iterations, "
                 f"{a['rejected_steps']} rejected; {_seconds(a['wall_seconds'])} s wall for {sim_s:.3g} s simulated "
                 f"({_seconds(a['wall_seconds'] / sim_s)} s per simulated second)"
                 + (f"; plus {comp:.1f} s to compile the solver (first run) or load its cache" if comp > 0.05 else "")
                 + (f"; model built in {build:.1f} s" if build is not None else ""))
    if a.get("notes", "none") != "none":
        lines.append(f"notes: {a['notes']}")
    return "\n".join(lines)


def _seconds(x: float) -> str:
    """A time [s] to 0.01 s, or to two significant digits below 0.1 s (a short lumped run's
    integration takes milliseconds: not "0.00 s")."""
    return f"{x:.2f}" if x >= 0.1 else f"{x:.2g}"


def _fe_outputs(args, write, paths, **kw):
    """Run an FE output writer (meshes or modes) for the configuration's gears, after checking
    every gear (output files, meshability) first. A flexible gear is meshed as the flexible
    model meshes it (``[flexible]`` level, order and formulation), the others by ``[fe]``."""
    from ..fe.meshing import MeshSettings, check_meshable

    cfg = _load(args.config)
    _need_gears(cfg, "mesh / modes")
    fx = cfg.flexible or {}

    def table(name):  # the table a gear's FE model follows
        return fx if name in fx.get("gears", ()) else cfg.fe

    def settings(name):
        t = table(name)
        return MeshSettings(level=args.level if args.level is not None else t["level"], order=t["order"])

    names = _gear_names(cfg, args.gear)
    out = Path(args.output)
    check_output_directory(out)
    check_targets([p for n in names for p in paths(cfg.gears[n], out / n)], args.overwrite)
    for n in names:
        check_meshable(cfg.gears[n], settings(n))
    with output_directory(out):
        for name in names:
            if table(name) is fx:
                say(f"{name}: meshed as the flexible model meshes it ([flexible] level {settings(name).level}, "
                    f"order {fx['order']}, {fx['formulation']})")
            with output_directory(out / name):  # a writer failing midway leaves no empty folder
                for p in write(cfg.gears[name], cfg.material, settings(name), out / name, overwrite=args.overwrite,
                               **{k: table(name).get(v, cfg.fe[v]) for k, v in kw.items()}):
                    print(f"wrote {p}")


def cmd_mesh(args):
    from ..fe.output import mesh_output_paths, write_mesh_outputs

    _fe_outputs(args, write_mesh_outputs, mesh_output_paths)


def cmd_modes(args):
    from ..fe.output import mode_output_paths, write_mode_outputs

    _fe_outputs(args, write_mode_outputs, mode_output_paths, n_modes="n_modes", formulation="formulation")


def cmd_modal(args):
    from ..dynamics.modal.analysis import MODAL_OUTPUTS, modal_analysis, needs_model, write_modal_outputs
    from ..dynamics.model.assembly import build_model
    from ..kernels import compile_seconds
    from .run import build_message

    cfg = _load(args.config)
    if args.positions is not None and args.positions < 1:
        raise FlexgearError(f"--positions = {args.positions}: must be >= 1")
    out = Path(args.output)
    check_output_directory(out)
    figure = out / "campbell.png" if cfg.gears else None  # a gear set's kinematics; a lumped parameter set has none
    check_targets([out / n for n in MODAL_OUTPUTS] + ([figure] if figure else []), args.overwrite)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = None
        if needs_model(cfg):  # every phase named, as flexgear run does: reductions, kernels, linearisation
            t_build, k_build = time.perf_counter(), compile_seconds()
            model = build_model(cfg, progress=say)
            say(build_message(time.perf_counter() - t_build, compile_seconds() - k_build))
        result = modal_analysis(cfg, n_positions=args.positions, free_drive=args.free_drive, messages=say,
                                model=model)
    with output_directory(out):
        for p in write_modal_outputs(result, out, title=cfg.title, overwrite=args.overwrite, cfg=cfg):
            print(f"wrote {p}")
        if figure:
            from ..results.campbell_plot import modal_campbell
            from ..style import save_figure

            print(f"wrote {save_figure(modal_campbell(result, cfg)[0], figure, overwrite=args.overwrite)}")
    note = result.system.attrs.get("condensation_note")
    if note:
        print(f"condensed modes: {note}")
    if result.system.attrs.get("housing"):
        print(f"{result.system.attrs['housing']}: included (the seated supports act against it, not ground)")
    rows, headers = result.table()
    print(markdown_table(rows, headers))


def cmd_deform(args):
    from ..results.deformed import DeformedGears, deformed_series_paths, frame_indices, load_result

    if not (math.isfinite(args.scale) and args.scale > 0):
        raise FlexgearError(f"--scale = {args.scale}: the displacement scale must be a finite number > 0")
    if args.every < 1:
        raise FlexgearError(f"--every = {args.every}: must be an integer >= 1")
    result = load_result(args.result)
    idx = frame_indices(result.time, args.window, args.every, name="--window")
    out = Path(args.output)
    paths = deformed_series_paths(out, idx.size)
    check_output_directory(out)
    existing = [str(p) for p in paths if p.exists()]
    if existing and not args.overwrite:
        raise ResultExistsError(f"{existing[0]} and {len(existing) - 1} more exist; refusing to overwrite (use "
                                "--overwrite or another -o)" if len(existing) > 1 else
                                f"{existing[0]} exists; refusing to overwrite (use --overwrite or another -o)")
    gears = DeformedGears(result, progress=say)
    from ..results.deformed import write_deformed_series

    bar, update = count_bar(idx.size, "frame")
    try:
        written = write_deformed_series(result, out, args.window, args.scale, args.every, overwrite=args.overwrite,
                                        gears=gears, progress=update)
    finally:
        bar.close()
    print(f"wrote {written[0]} ({len(written) - 1} frames, {written[1].name} .. {written[-1].name}; "
          f"geometry deflections x {args.scale:g}, point data 'displacement' true)")


def _gear_names(cfg, gear):
    if gear is None:
        return list(cfg.gears)
    if gear not in cfg.gears:
        raise FlexgearError(f"--gear {gear!r}: must be one of {', '.join(cfg.gears)}")
    return [gear]


def say(text: str) -> None:
    """A progress message of a command on stderr."""
    print(f"flexgear: {text}", file=sys.stderr, flush=True)


CONFIG_HELP = (f"a TOML configuration file, or a built-in preset name: {', '.join(PRESETS)}; NAME:lumped "
               "for its lumped model (e.g. spur_pair_friction:lumped)")
MODAL_CONFIG_HELP = f"{CONFIG_HELP}; or a lumped parameter set: {', '.join(PARAMETER_SETS)}"
OVERWRITE_HELP = "replace existing output files (default: refuse, and write nothing)"


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="flexgear", description="Vibration of spur and planetary gears: involute "
                                "geometry, ADAMS IMPACT tooth contact, multi-body dynamics, FE meshes and modes.",
                                epilog="Run 'flexgear COMMAND -h' for a command's arguments and defaults.")
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND", title="commands")
    r = sub.add_parser("run", help="simulate a configuration; write results.h5 and figures",
                       description="Simulate a configuration and write OUTDIR/results.h5 and the paper-style "
                       "figures (spur pair: Figs. 3-4; planetary: Figs. 7-12). Every check (configuration, "
                       "existing files) runs before the simulation; a failed run writes nothing.")
    r.add_argument("config", metavar="CONFIG", help=CONFIG_HELP)
    r.add_argument("-o", "--output", metavar="OUTDIR",
                   help="output directory (required, unless --print-config; created if missing)")
    r.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    r.add_argument("--duration", type=float, metavar="SECONDS",
                   help="override simulation.duration: simulated time kept, > 0 s (default: the configuration's "
                   "value, 1 s in the presets); the run simulates simulation.run_in (0.2 s in the presets) "
                   "before it and discards that start-up")
    r.add_argument("--no-figures", action="store_true", help="write results.h5 only (default: also the figures)")
    r.add_argument("--print-config", action="store_true",
                   help="print the configuration with every default filled in (SI, TOML; what results.h5 records) "
                   "and stop, simulating nothing")
    r.set_defaults(func=cmd_run)
    i = sub.add_parser("info", help="derived gear data and characteristic frequencies",
                       description="Derived gear and pair data (ISO 21771), characteristic frequencies and static "
                       "loads of a configuration, as Markdown tables.")
    i.add_argument("config", metavar="CONFIG", help=CONFIG_HELP)
    i.add_argument("-o", "--output", metavar="FILE", help="write the tables to FILE (default: print them)")
    i.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    i.set_defaults(func=cmd_info)
    pr = sub.add_parser("preset", help="list the presets, print one, or copy it to a file to edit",
                        description="Without NAME: list the built-in presets. With NAME: print it, or copy it "
                        "to FILE with -o.")
    pr.add_argument("name", nargs="?", metavar="NAME", choices=PRESET_NAMES,
                    help="preset to print or copy: spur_pair, mercury_1a, ...; lin_parker_1999 is a lumped parameter "
                    "set (default: list them)")
    pr.add_argument("-o", "--output", metavar="FILE", help="copy the preset to FILE (default: print it)")
    pr.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    pr.set_defaults(func=cmd_preset)
    for name, func, text in (("mesh", cmd_mesh, "Gmsh meshes of the gear bodies (VTU, PNG)"),
                             ("modes", cmd_modes, "clamped-hub natural frequencies and mode shapes (VTU, PNG, "
                              "CSV, Markdown)")):
        s = sub.add_parser(name, help=text, description=f"{text}, one subdirectory OUTDIR/<gear> per gear. "
                           "Every gear is checked (files, bore and rim sizes) before any is meshed.")
        s.add_argument("config", metavar="CONFIG", help=CONFIG_HELP)
        s.add_argument("-o", "--output", metavar="OUTDIR", default=f"out/{name}",
                       help="output directory (default: %(default)s)")
        s.add_argument("--gear", metavar="GEAR", help="one gear only: pinion or wheel (spur pair), sun, planet or "
                       "ring (planetary) (default: every gear)")
        s.add_argument("--level", type=int, choices=range(6), metavar="LEVEL",
                       help="mesh refinement level 0-5, element size / sqrt(2) per level (default: the "
                       "configuration's: a flexible gear's [flexible] level, the others' fe.level; both 2 by default)")
        s.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
        s.set_defaults(func=func)
    m = sub.add_parser("modal", help="natural frequencies and modes of the set linearised at its loaded operating point")
    m.add_argument("config", metavar="CONFIG", help=MODAL_CONFIG_HELP)
    m.add_argument("-o", "--output", default="out/modal", help="output directory for modes.md, modes.json and, "
                   "for a gear set, campbell.png (the modes against the input speed, the operating speed marked; "
                   "default out/modal)")
    m.add_argument("--positions", type=int, metavar="COUNT", help="number of static equilibrium positions over one "
                   "mesh cycle whose mesh stiffnesses are averaged (default: 8 per planet, 24 for a spur pair)")
    m.add_argument("--free-drive", action="store_true", help="free the driven body's rotation (rigid-body mode)")
    m.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    m.set_defaults(func=cmd_modal)
    d = sub.add_parser("deform", help="deformed gears of a flexible result over a time window (ParaView series)",
                       description="Full FE displacement fields of the flexible gears (static FE solution under the "
                       "recorded contact loads plus the rigid motion; rigid gears undeformed) at every output "
                       "sample of a window: OUTDIR/deformed.pvd (open it in ParaView) and one deformed_NNNN.vtu "
                       "per frame, all gears in one grid, point data 'displacement' (true, m), "
                       "'displacement_magnitude' and 'body', cell data 'von_mises' and 'strain_energy_density'.")
    d.add_argument("result", metavar="RESULT", help="a results.h5 of a flexible run, or its directory")
    d.add_argument("-o", "--output", metavar="OUTDIR", required=True, help="output directory (created if missing)")
    d.add_argument("--window", nargs=2, type=float, metavar=("T0", "T1"), required=True,
                   help="first and last time [s], within the recorded span (after the run-in)")
    d.add_argument("--scale", type=float, required=True, metavar="S",
                   help="factor on the elastic displacements for the drawn geometry (> 0; e.g. 200)")
    d.add_argument("--every", type=int, default=1, metavar="N", help="every N-th output sample (default 1)")
    d.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    d.set_defaults(func=cmd_deform)
    w = sub.add_parser("warm", help="compile the kernels and fill the caches ahead of the first runs",
                       description="Compile the kernels and build the contact tables (and the reductions of "
                       "flexible gears) of each configuration with a run a few samples long, so that later runs, "
                       "e.g. on the nodes of a cluster sharing the install, start warm. NAME:lumped warms a "
                       "configuration's lumped model. Prints the time of each phase.")
    w.add_argument("config", nargs="*", metavar="CONFIG",
                   help=f"{CONFIG_HELP} (default: {' '.join(DEFAULT_CONFIGS)})")
    w.set_defaults(func=cmd_warm)
    add_batch_command(sub)
    add_monitor_command(sub)
    return p


def cmd_warm(args):
    from .warm import warm

    names = args.config or list(DEFAULT_CONFIGS)
    t0 = time.perf_counter()
    rows = [[t.config, f"{t.total:.1f}", f"{t.build - t.build_kernels:.1f}", f"{t.build_kernels:.1f}",
             f"{t.solver_kernels:.1f}"]
            for t in warm(names, messages=say)]
    print(markdown_table(rows, ["configuration", "total s", "tables, reductions s", "model kernels s",
                                "solver kernels s"]))
    print(f"caches warm after {time.perf_counter() - t0:.1f} s")


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    return run_command(lambda: args.func(args), interactive=argv is None)


if __name__ == "__main__":
    sys.exit(main())
