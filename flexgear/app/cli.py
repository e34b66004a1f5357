"""Command line: ``flexgear run | info | preset | mesh | modes | batch``.

``flexgear run CONFIG -o OUTDIR`` simulates a configuration (a TOML file or a built-in preset
name) with a progress bar, writes ``OUTDIR/results.h5`` and the paper-style figures, and
refuses to overwrite an existing result unless ``--overwrite`` is given.
"""
from __future__ import annotations

import argparse
import math
import shutil
import sys
import warnings
from pathlib import Path

from ..errors import FlexgearError, ResultExistsError
from .batch_command import add_batch_command
from .console import markdown_table, progress_bar


def _load(config):
    from ..config import load_config

    return load_config(config)


def info_text(cfg) -> str:
    """Derived gear data, pair data and characteristic frequencies as Markdown tables."""
    from ..dynamics.assembly import check_planetary
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
    for name, pair in cfg.pairs.items():
        law = cfg.contact_law(pair)
        prow.append([name, f"{pair.centre_distance*mm:.4f}", f"{math.degrees(pair.alpha_w):.4f}",
                     f"{pair.contact_ratio:.4f}", f"{pair.hertz_radius*mm:.4f}",
                     f"{pair.hertz_stiffness(e_star)*1e-3**1.5:.4g}", f"{law.K:.4g} N/m^{law.e:g}"])
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
        if isinstance(tload, float):
            rb = cfg.gears[cfg.load["body"]].rb
            frow.append(["static normal tooth force (N)", f"{tload/rb:.5g}"])
        notes = GearPair(cfg.gears["pinion"], cfg.gears["wheel"]).check()
    else:
        zs, zp, zr = (cfg.gears[n].z for n in ("sun", "planet", "ring"))
        fs = f_in if cfg.drive["body"] == "sun" else f_in * (zs + zr) / zs
        fc = fs * zs / (zs + zr)
        fm = zr * fc
        N = cfg.planetary["planets"]
        frow += [["sun rotation", f"{fs:.4g}"], ["carrier f_a", f"{fc:.4g}"],
                 ["planet spin relative to carrier", f"{(fs - fc)*zs/zp:.4g}"], ["gear mesh f_m", f"{fm:.4g}"],
                 ["2 f_m", f"{2*fm:.4g}"], ["3 f_m", f"{3*fm:.4g}"]]
        tl = cfg.load["torque"]
        if isinstance(tl, float) and cfg.load["body"] == "carrier":
            ts = tl / (1 + zr / zs)
            frow += [["sun torque at equilibrium (N m)", f"{ts:.4g}"],
                     ["normal tooth force per planet (N)", f"{ts/N/cfg.gears['sun'].rb:.5g}"]]
        notes = check_planetary(cfg)
    out += ["", "## Characteristic frequencies (Hz) and static loads", "", markdown_table(frow, ["quantity", "value"])]
    out += ["", "## Notes", ""] + ([f"- {n}" for n in notes] or ["- none"])
    return "\n".join(out)


def cmd_info(args):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = _load(args.config)
    print(info_text(cfg))


def cmd_preset(args):
    from ..config import PRESETS, preset_path

    if args.name is None:
        print("\n".join(PRESETS))
        return
    src = preset_path(args.name)
    if args.output is None:
        print(src.read_text(), end="")
        return
    dst = Path(args.output)
    if dst.exists() and not args.overwrite:
        raise ResultExistsError(f"{dst} exists; refusing to overwrite it (use --overwrite)")
    shutil.copyfile(src, dst)
    print(f"wrote {dst}")


def cmd_run(args):
    from ..results.plots import paper_figures
    from ..results.store import save
    from .run import run

    cfg = _load(args.config)
    if args.duration is not None:
        if not args.duration > 0:
            raise FlexgearError(f"--duration = {args.duration}: must be > 0 s")
        cfg.simulation["duration"] = float(args.duration)
    out = Path(args.output)
    target = out / "results.h5"
    if target.exists() and not args.overwrite:
        raise ResultExistsError(f"{target} exists; refusing to overwrite it (use --overwrite or another -o)")
    out.mkdir(parents=True, exist_ok=True)
    total = cfg.simulation["run_in"] + cfg.simulation["duration"]
    from ..dynamics.solver import compiled_cache_present

    if not compiled_cache_present():
        print("flexgear: compiling the solver on first use (about 40 s; cached for later runs)", file=sys.stderr)
    bar, update = progress_bar(total)
    try:
        result = run(cfg, progress=update)
    finally:
        bar.close()
    save(result, target, overwrite=args.overwrite)
    print(f"wrote {target}")
    if not args.no_figures:
        for p in paper_figures(result, out, overwrite=args.overwrite):
            print(f"wrote {p}")
    print(summary_text(result))


def summary_text(result) -> str:
    """Mean forces and solver statistics of a result."""
    a = result.attrs
    rows = [[name, f"{m.normal_force.mean():.5g}", f"{m.normal_force.std():.4g}"] for name, m in result.meshes.items()]
    sim_s = a["run_in"] + a["duration"]
    lines = [markdown_table(rows, ["mesh", "mean normal force N", "std N"]), "",
             f"solver: {a['solver_steps']} steps, {a['newton_iterations']} Newton iterations, "
             f"{a['rejected_steps']} rejected; {a['wall_seconds']:.2f} s wall for {sim_s:.3g} s simulated "
             f"({a['wall_seconds']/sim_s:.2f} s per simulated second)"]
    return "\n".join(lines)


def _fe_outputs(args, write, **kw):
    """Run an FE output writer (meshes or modes) for the configuration's gears."""
    from ..fe.meshing import MeshSettings

    cfg = _load(args.config)
    settings = MeshSettings(level=args.level if args.level is not None else cfg.fe["level"], order=cfg.fe["order"])
    for name in _gear_names(cfg, args.gear):
        for p in write(cfg.gears[name], cfg.material, settings, Path(args.output) / name, overwrite=args.overwrite,
                       **{k: cfg.fe[v] for k, v in kw.items()}):
            print(f"wrote {p}")


def cmd_mesh(args):
    from ..fe.output import write_mesh_outputs

    _fe_outputs(args, write_mesh_outputs)


def cmd_modes(args):
    from ..fe.output import write_mode_outputs

    _fe_outputs(args, write_mode_outputs, n_modes="n_modes", formulation="formulation")


def _gear_names(cfg, gear):
    if gear is None:
        return list(cfg.gears)
    if gear not in cfg.gears:
        raise FlexgearError(f"--gear {gear!r}: must be one of {', '.join(cfg.gears)}")
    return [gear]


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="flexgear", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="simulate a configuration; write results.h5 and figures")
    r.add_argument("config", help="TOML file or preset name (spur_pair, mercury_1a)")
    r.add_argument("-o", "--output", required=True, help="output directory")
    r.add_argument("--overwrite", action="store_true", help="replace an existing result in OUTDIR")
    r.add_argument("--duration", type=float, help="override simulation.duration [s]")
    r.add_argument("--no-figures", action="store_true", help="write results.h5 only")
    r.set_defaults(func=cmd_run)
    i = sub.add_parser("info", help="derived gear data and characteristic frequencies")
    i.add_argument("config")
    i.set_defaults(func=cmd_info)
    pr = sub.add_parser("preset", help="list the presets, print one, or copy it to a file to edit")
    pr.add_argument("name", nargs="?")
    pr.add_argument("-o", "--output")
    pr.add_argument("--overwrite", action="store_true")
    pr.set_defaults(func=cmd_preset)
    for name, func, text in (("mesh", cmd_mesh, "Gmsh meshes of the gear bodies (VTU, PNG)"),
                             ("modes", cmd_modes, "clamped-hub natural frequencies and mode shapes")):
        s = sub.add_parser(name, help=text)
        s.add_argument("config")
        s.add_argument("-o", "--output", default=f"out/{name}")
        s.add_argument("--gear", help="one gear only")
        s.add_argument("--level", type=int, help="mesh refinement level (overrides fe.level)")
        s.add_argument("--overwrite", action="store_true")
        s.set_defaults(func=func)
    add_batch_command(sub)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        status = args.func(args)
    except FlexgearError as exc:
        print(f"flexgear: error: {exc}", file=sys.stderr)
        return 2
    return status or 0


if __name__ == "__main__":
    sys.exit(main())
