"""Modal analysis of a configuration (``flexgear modal``): its modes, the report files, and the
frequency at which a simulation shows a mode.

A simulation shows a mode where its HHT-alpha step puts it, not at f_n:
:func:`integrated_frequency` (at 25 us an 8.9 kHz mode rings at 7.6 kHz, at the flexible
presets' 6.25 us at 8.79 kHz), so spectral peaks are matched to those values.
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ...errors import ConfigError
from .linearise import default_positions, is_flexible, linearise
from .system import UNCLASSIFIED, ModalResult, modes



def integrated_frequency(frequency, h: float, alpha: float):
    """Frequency [Hz] at which the solver's HHT-alpha integrator (:mod:`flexgear.dynamics.integrator.time_loop`, step h [s],
    alpha in [-1/3, 0], beta = (1 - alpha)^2 / 4, gamma = 1/2 - alpha) makes an undamped mode of
    natural frequency ``frequency`` [Hz] oscillate: arg(lambda) / (2 pi h) of the complex
    eigenvalue pair of the scheme's amplification matrix for x'' + omega^2 x = 0. The period
    grows with omega h (alpha = 0: exactly (2 / h) atan(omega h / 2)); at the rigid presets' 25 us
    step with alpha = -0.1 a 6.4 kHz mode runs at 5.82 kHz and an 8.9 kHz one at 7.60 kHz (at the
    flexible presets' 6.25 us: 8.79 kHz), so
    spectral peaks of simulations are matched to these values, not to the modes' own.
    Array input gives an array; 0 Hz stays 0."""
    if not (-1.0 / 3.0 - 1e-12 <= alpha <= 0.0) or not h > 0:
        raise ConfigError(f"integrated_frequency: h = {h!r} must be > 0 and alpha = {alpha!r} in [-1/3, 0]")
    beta, gamma = 0.25 * (1.0 - alpha) ** 2, 0.5 - alpha
    f = np.atleast_1d(np.asarray(frequency, float))
    out = np.zeros_like(f)
    for i, fi in enumerate(f):
        if fi <= 0:
            continue
        w2 = (2 * math.pi * fi) ** 2
        A = np.zeros((3, 3))
        for j, (x0, v0, a0) in enumerate(np.eye(3)):  # one step from each unit state (x, v, a)
            pred = x0 + h * v0 + h * h * (0.5 - beta) * a0
            a1 = (-(1 + alpha) * w2 * pred + alpha * w2 * x0) / (1 + (1 + alpha) * w2 * h * h * beta)
            A[:, j] = (pred + h * h * beta * a1, v0 + h * ((1 - gamma) * a0 + gamma * a1), a1)
        lam = np.linalg.eigvals(A)
        out[i] = abs(np.angle(lam[np.argmax(np.abs(lam.imag))])) / (2 * math.pi * h)
    return out if np.ndim(frequency) else float(out[0])


def needs_model(cfg) -> bool:
    """Whether :func:`modal_analysis` of ``cfg`` linearises a multi-body model (built with
    :func:`flexgear.dynamics.model.assembly.build_model`), not the lumped model of explicit
    parameters (``[lumped.parameters]``).

    Raises
    ------
    ConfigError
        ``housing.coupled = true`` with ``model = "lumped"``."""
    if cfg.housing is not None and cfg.housing.coupled and cfg.model == "lumped":
        raise ConfigError("housing.coupled = true with model = lumped: the housing couples into the multi-body "
                          "model only, rigid or flexible (set coupled = false: the modal analysis then leaves the "
                          "housing out)")
    return not (cfg.model == "lumped" and (cfg.lumped or {}).get("parameters") is not None)


def modal_analysis(cfg, n_positions: int | None = None, free_drive: bool = False, messages=None,
                   model=None) -> ModalResult:
    """Modal analysis of a configuration's multi-body model (rigid, or flexible with a
    ``[flexible]`` block, its condensed modes as ``[flexible] condensation`` says) about its
    loaded operating point; with explicit lumped parameters (``[lumped.parameters]``), of the
    lumped model they define. A coupled housing (``[housing] coupled = true``, rigid or flexible
    gears) joins the system (:func:`~.housing.couple_system`).

    Parameters
    ----------
    messages : callable(str), optional
        Told each phase as it starts or ends (reductions computed or loaded, the linearisation
        and its time), as :func:`flexgear.app.run.run` tells its own.
    model : Model, optional
        The configuration's multi-body model, already built (:func:`needs_model`).
    """
    from ...kernels import compile_seconds
    from ..model.assembly import build_model

    coupled = cfg.housing is not None and cfg.housing.coupled
    if not needs_model(cfg):
        from ..lumped.planetary import explicit_parameters, planetary_system

        return modes(planetary_system(explicit_parameters(cfg, free_drive=free_drive)))

    tell = messages or (lambda _text: None)
    condensation = cfg.flexible["condensation"] if cfg.flexible else "integrated"
    model = build_model(cfg, progress=messages) if model is None else model
    housing = None
    if coupled:
        from ...reduction.housing import USER_CACHE, reduce_housing
        from ..model.housing import couple_housing

        housing = couple_housing(model, reduce_housing(cfg.housing, cache_dir=USER_CACHE, progress=messages))
        model.housing = None  # the set linearised on ground, then the housing takes ground's place
    n = default_positions(model) if n_positions is None else n_positions
    tell(f"linearising about the loaded static equilibrium: {n} positions over a mesh cycle"
         + (", the solver's tangent stiffness" if is_flexible(model) else "")
         + " (a first run on this machine compiles the kernels it needs first)")
    t0, k0 = time.perf_counter(), compile_seconds()
    system = linearise(model, n_positions=n, free_drive=free_drive, condensation=condensation)
    dt, dk = time.perf_counter() - t0, compile_seconds() - k0
    tell(f"linearised in {dt:.1f} s" + (f" ({dk:.1f} s of it compiling or loading kernels)" if dk > 0.05 else "")
         + f"; solving for the modes of {system.n} coordinate{'s' if system.n != 1 else ''}")
    if not coupled:
        if cfg.model == "lumped":  # the lumped model is this linearisation (flexgear.dynamics.lumped.model)
            system = _lumped_meshes(cfg, model, system)
            system.attrs["source"] = f"lumped model: the {system.attrs.get('source', 'rigid model linearised')}"
        return modes(system)
    from .housing import couple_system

    model.housing = housing
    return modes(couple_system(system, model))


def _lumped_meshes(cfg, model, system):
    """The linearised system with the lumped model's mesh springs: the mean over the mesh cycle of
    ``[lumped] mesh_stiffness`` (iso6336, fe, constant; the contact law's tangent, the
    linearisation's own, is kept)."""
    from ..lumped.model import source_stiffness

    series = source_stiffness(cfg, model, system.attrs["cycle"])
    if series is None:
        return system
    k = {name: float(np.mean(v)) for name, v in series.items()}
    springs = [dataclasses.replace(sp, k=k[sp.name]) if sp.kind == "mesh" else sp for sp in system.springs]
    attrs = dict(system.attrs, mesh_stiffness=k, mesh_stiffness_source=cfg.lumped["mesh_stiffness"])
    return dataclasses.replace(system, springs=springs, attrs=attrs)


MODAL_OUTPUTS = ("modes.md", "modes.json")


def modal_operating_point(result: ModalResult) -> dict:
    """Where the modes were linearised (JSON types): the load torques [N m] per body, the drive's
    reaction torque [N m], the equilibrium positions over a mesh cycle, whether the drive was
    free, the condensation of a flexible model; keys absent for a lumped parameter set."""
    a = result.system.attrs
    out = {"load_torques_Nm": {k: float(v) for k, v in a.get("load_torques", {}).items()},
           "drive_reaction_torque_Nm": a.get("drive_reaction_torque"), "positions": a.get("n_positions"),
           "free_drive": a.get("free_drive"), "condensation": a.get("condensation")}
    return {k: (float(v) if isinstance(v, np.floating) else v) for k, v in out.items() if v not in (None, {})}


def provenance(cfg) -> dict:
    """The flexgear version and the configuration with every default filled in (TOML text), as
    ``results.h5`` records them (``flexgear_version``, ``config_toml``)."""
    import tomli_w

    from ... import __version__
    from ...config import config_document

    return {"flexgear_version": __version__, "config_toml": tomli_w.dumps(config_document(cfg))}


def report_markdown(result: ModalResult, title: str = "", cfg=None) -> str:
    """A Markdown report: modes table, mesh stiffnesses and the operating point; with ``cfg``, the
    flexgear version and the configuration (:func:`provenance`)."""
    def table(rows, headers):
        w = [max(len(str(h)), *(len(str(r[i])) for r in rows)) if rows else len(str(h)) for i, h in enumerate(headers)]
        out = ["| " + " | ".join(str(h).ljust(x) for h, x in zip(headers, w)) + " |",
               "|" + "|".join("-" * (x + 2) for x in w) + "|"]
        out += ["| " + " | ".join(str(c).ljust(x) for c, x in zip(r, w)) + " |" for r in rows]
        return "\n".join(out)

    sysl = result.system
    rows, headers = result.table()
    note = sysl.attrs.get("condensation_note")
    out = [f"# Modal analysis{': ' + title if title else ''}", "", sysl.attrs.get("source", ""), "",
           *([f"Condensed modes: {note}.", ""] if note else []),
           *([f"{sysl.attrs['housing']}: the set's seated supports act against it, not ground; its own strain "
              "energy is the 'coupling' share, and the feet break the cyclic symmetry (modes unclassified).", ""]
             if sysl.attrs.get("housing") else []),
           f"Coordinates: {', '.join(sysl.dofs)}", "", table(rows, headers), ""]
    accidental = [r[0] for r in rows if "accidental" in str(r[3])]
    if accidental:
        out += [(f"Modes {', '.join(map(str, accidental))}: an accidental degeneracy, modes of different types "
                 "(or more of one type than Lin & Parker's multiplicity) at one frequency; their shapes are any "
                 "combination of the group's, so their types and energy shares are not those of one mode."), ""]
    op = modal_operating_point(result)
    if op:
        out += ["## Operating point", "",
                table([[OPERATING_LABELS.get(k, k), json_text(v)] for k, v in op.items()], ["quantity", "value"]), ""]
    out += mesh_stiffness_section(sysl.attrs, table)
    cpl = sysl.attrs.get("mesh_coupling")
    if cpl is not None:
        names, S = cpl["meshes"], cpl["stiffness"]
        out += ["## Stiffness between meshes (flexible model)", "",
                "S[m, n] = force change of mesh m per unit approach of mesh n, the other meshes held [N/m] "
                "(diagonal: each mesh's own stiffness; off the diagonal: the contact coupling through the "
                "gears' rims), mean over the cycle.", "",
                table([[a] + [f"{v:.4g}" for v in row] for a, row in zip(names, S)], ["mesh"] + names), ""]
    if sysl.planets and not sysl.attrs.get("housing"):
        N = len(sysl.planets)
        out += [f"Mode types for {N} equally spaced planets (Lin & Parker): rotational (multiplicity 1), "
                + ("translational (2), planet (N - 3)" if sysl.has_central_translation()
                   else "planet (N - 1; the central members have no translational coordinate)") + ".", ""]
    if cfg is not None:
        prov = provenance(cfg)
        out += ["## Version and configuration", "",
                (f"flexgear {prov['flexgear_version']}; the configuration, every default filled in (as "
                 "results.h5 records it):"), "", "```toml", prov["config_toml"].rstrip(), "```", ""]
    return "\n".join(out)


#: Row names of the report's operating-point table.
OPERATING_LABELS = {"load_torques_Nm": "load torque (N m)", "drive_reaction_torque_Nm": "drive torque holding it (N m)",
                    "positions": "equilibrium positions over a mesh cycle", "free_drive": "drive free",
                    "condensation": "condensed gear modes"}


def json_text(value) -> str:
    """A value of :func:`modal_operating_point` as table text."""
    if isinstance(value, dict):
        return ", ".join(f"{k} {v:.6g}" for k, v in value.items())
    return f"{value:.6g}" if isinstance(value, float) else str(value)


#: What the ``mesh_stiffness`` of a flexible linearisation is (report and ``modes.json``).
CONTACT_SPRING = ("the tangent dF/d(approach) of the contact between the reduced flanks along the line of action, "
                  "the gears' modal coordinates held: the contact and residual spring only (the gears' tooth, rim "
                  "and body compliance is in their modes); it splits the modes' strain energy")
#: What the ``effective_mesh_stiffness`` of a flexible linearisation is.
EFFECTIVE_MESH = ("the quasi-static mesh stiffness along the line of action, the gears' modal coordinates condensed "
                  "statically (contact and gear compliance in series): the stiffness of a rigid or lumped model's "
                  "mesh and of the FE loaded mesh (dF/dTE, c_gamma b)")


def mesh_stiffness_section(attrs: dict, table) -> list:
    """Lines of the report's mesh-stiffness table: for a rigid (or lumped) linearisation the IMPACT
    tangent, for a flexible one the contact spring between the reduced flanks and the effective
    mesh stiffness (:data:`CONTACT_SPRING`, :data:`EFFECTIVE_MESH`), each [N/m], mean over the
    mesh cycle; ``table(rows, headers)`` formats a Markdown table."""
    ks = attrs.get("mesh_stiffness")
    if not ks:
        return []
    fm = attrs.get("mesh_force", {})
    force = {k: f"{fm[k]:.5g}" if k in fm else "-" for k in ks}
    eff = attrs.get("effective_mesh_stiffness")
    if eff is None:
        source = attrs.get("mesh_stiffness_source")
        return ["## Mesh stiffness at the operating point", "",
                (f"Mesh stiffness: the lumped model's, [lumped] mesh_stiffness = {source!r}, mean over the mesh "
                 "cycle." if source else "Mesh stiffness: the contact law's tangent dF/d(approach) summed over the "
                 "loaded tooth pairs, along their line of action (rigid bodies), mean over the mesh cycle."), "",
                table([[k, f"{v:.5g}", force[k]] for k, v in ks.items()],
                      ["mesh", "mesh stiffness N/m", "normal force N"]), ""]
    return ["## Mesh stiffness at the operating point (flexible model)", "",
            f"Effective mesh stiffness: {EFFECTIVE_MESH}.", "",
            f"Contact spring between the reduced flanks: {CONTACT_SPRING}.", "",
            "Both are mean values over the mesh cycle.", "",
            table([[k, f"{eff.get(k, float('nan')):.5g}", f"{v:.5g}", force[k]] for k, v in ks.items()],
                  ["mesh", "effective mesh stiffness N/m", "contact spring between reduced flanks N/m",
                   "normal force N"]), ""]


def write_modal_outputs(result: ModalResult, outdir, title: str = "", overwrite: bool = False, cfg=None) -> list:
    """Write ``modes.md`` (report) and ``modes.json`` (frequencies, shapes, energies, the operating
    point; with the configuration ``cfg``, the flexgear version and the configuration,
    :func:`provenance`) to outdir."""
    import json
    from pathlib import Path

    from ...files import atomic_write, check_targets

    outdir = Path(outdir)
    targets = [outdir / name for name in MODAL_OUTPUTS]
    check_targets(targets, overwrite)
    outdir.mkdir(parents=True, exist_ok=True)
    sysl = result.system
    data = {"title": title, "units": {"frequencies": "Hz", "shapes": "mass-normalised, per coordinate"},
            "dofs": sysl.dofs, "frequencies": result.frequencies.tolist(), "mode_type": result.mode_type,
            "multiplicity": result.multiplicity.tolist(),
            "type_purity": [None if t == UNCLASSIFIED else float(p)
                            for t, p in zip(result.mode_type, result.type_purity)],
            "operating_point": modal_operating_point(result), **(provenance(cfg) if cfg is not None else {}),
            "shapes": result.shapes.T.tolist(),
            "strain_energy_fraction": {k: v.tolist() for k, v in result.strain_energy.items()},
            "kinetic_energy_fraction": {k: v.tolist() for k, v in result.kinetic_energy.items()},
            "mesh_stiffness": sysl.attrs.get("mesh_stiffness", {})}
    if sysl.attrs.get("effective_mesh_stiffness") is not None:
        data["effective_mesh_stiffness"] = sysl.attrs["effective_mesh_stiffness"]
        data["units"].update(mesh_stiffness=f"N/m: {CONTACT_SPRING}", effective_mesh_stiffness=f"N/m: {EFFECTIVE_MESH}")
    elif data["mesh_stiffness"]:
        source = sysl.attrs.get("mesh_stiffness_source")
        data["units"]["mesh_stiffness"] = (
            f"N/m: the lumped model's, [lumped] mesh_stiffness = {source!r}" if source
            else "N/m: the contact law's tangent along the line of action (rigid bodies)")
    if sysl.attrs.get("condensation") is not None:
        data["condensation"] = {"mode": sysl.attrs["condensation"], "note": sysl.attrs["condensation_note"]}
    if sysl.attrs.get("mesh_coupling") is not None:
        data["mesh_coupling"] = {"meshes": sysl.attrs["mesh_coupling"]["meshes"],
                                 "stiffness": np.asarray(sysl.attrs["mesh_coupling"]["stiffness"]).tolist()}
    text = report_markdown(result, title, cfg)
    atomic_write(targets[0], lambda p: Path(p).write_text(text))
    atomic_write(targets[1], lambda p: Path(p).write_text(json.dumps(data, indent=1)))
    return targets
