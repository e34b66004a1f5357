"""Rigid against flexible gears: three models of both presets side by side, two mesh dampings.

Models, all built from the flexible preset's configuration (``spur_pair_flexible``,
``mercury_1a_flexible``) so that anything else the preset holds (supports, shafts, ...) is the
same in all three:

1. **rigid (paper)** - the ``[flexible]`` block removed: rigid gears, the paper's ADAMS IMPACT
   law (K = 3e5 N/mm^1.3, e = 1.3): the rigid preset (``spur_pair``, ``mercury_1a``) plus the
   flexible preset's elastic shafts;
2. **rigid (fitted)** - the same rigid model with an IMPACT law per mesh fitted to the FE
   loaded-mesh transmission error (:func:`flexgear.stiffness.impact_fit.fit_impact_law`, same
   FE mesh level and formulation as the flexible model, loads 0.5-1.5 x the static mesh
   force): what a multi-body user would do next;
3. **flexible** - the preset itself: Craig-Bampton gears with compliant flanks and the
   line-contact Hertz law.

Each with two mesh dampings: **paper C** (C = 3000 N s/mm, d = 0.3 mm: a mesh damping ratio of
~50, heavily overdamped) and **zeta** (``--zeta``, default 0.05 of critical: C = 2 zeta
sqrt(k m_e) / STEP(delta_0 / d) at each mesh's static operating point,
:mod:`flexgear.config.mesh_damping`, with k and delta_0 of the model's own stiffness: the paper
law for model 1, the fitted law for models 2 and 3, the fitted law standing for the flexible
mesh's stiffness since the flexible model's damper acts on the same rigid approach).
Why 0.05: gear-dynamics models put the mesh's viscous damping at a few percent of critical
(0.03-0.1 is the range usually assumed, :mod:`flexgear.config.mesh_damping`); damping derived
from the lubricant film (Li & Kahraman, "A spur gear mesh interface damping model based on
elastohydrodynamic contact behaviour", https://www.semanticscholar.org/paper/491233c16bd29a2c122d0c692c060333bf72870f)
is what such a ratio stands for. The paper's C is not in that range: ~50 on the spur pair, and
at MERCURY's light mesh load (236 N, a few um of penetration on the STEP ramp) 0.28 with the
paper's law and 0.01 with the fitted one (report table).

Writes to ``--out``, per preset (``spur``, ``mercury``):

* ``<p>_forces.png`` - mesh normal forces overlaid; ``<p>_spectra.png`` - their spectra;
* ``<p>_te.png`` - transmission error (approach of the loaded pairs along the line of action)
  with the FE static mean; ``<p>_pair_loads.png`` - load sharing between tooth pairs;
* ``mercury_planets.png`` - load sharing between the planets;
* ``report.md`` - the table (mean, peak-to-peak and RMS force, mesh-line and sideband
  amplitudes, dynamic factor, contact ratio under load, mean TE), the fitted laws and every
  spectral line present in one model and not in another, attributed to a mesh harmonic /
  sideband / combination or to the nearest natural frequency of the linearised model
  (:func:`flexgear.dynamics.modal.linearise.linearise`; the flexible model's own linearisation: the
  solver's tangent with the compliant contacts solved jointly, so the coupling between meshes
  through the gear rims is in it; the gears' clamped frequencies from the reductions are
  listed).

Definitions: dynamic factor K_v = max dynamic mesh force / static mesh force W (the ISO 6336
K_v analogue; W = T / r_b per mesh, :func:`flexgear.config.mesh_damping.operating_point`);
contact ratio under load = mean number of loaded tooth pairs (1 + the time share of two-pair
contact when at most two pairs carry load), from the per-pair force slots.

Usage::

    python studies/rigid_vs_flexible.py --out out/rvf [--duration 1.0] [--quick] [--overwrite]

``--quick`` (tests): very short runs, FE level 0 for the fit and the flexible gears.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

from flexgear.app.console import markdown_table
from flexgear.app.run import run
from flexgear.config import load_config, time_grid
from flexgear.config.mesh_damping import damping_from_ratio, operating_point, ratio_from_damping
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.modal.analysis import integrated_frequency
from flexgear.dynamics.modal.linearise import linearise
from flexgear.dynamics.modal.system import modes
from flexgear.fe.meshing import MeshSettings
from flexgear.files import check_targets
from flexgear.results.signals import amplitude_spectrum, find_peaks, line_amplitude
from flexgear.stiffness.impact_fit import fit_impact_law, zone_mean_te
from flexgear.stiffness.loaded_mesh import loaded_mesh
from flexgear.style import DOUBLE_WIDTH, figure, paper_style, save_figure
from flexgear.app.console import run_command

PRESETS = {"spur": "spur_pair_flexible", "mercury": "mercury_1a_flexible"}
MODELS = ("rigid (paper)", "rigid (fitted)", "flexible")
DAMPINGS = ("paper C", "zeta")
FIT_LOADS = (0.5, 0.75, 1.0, 1.25, 1.5)  # x the static mesh force W
OUTPUT_RATE = 10000.0  # Hz: trustworthy band to 4 kHz (README)
LINE_FLOOR = 2e-3  # spectral lines below this fraction of W are not reported
NEW_LINE_RATIO = 0.1  # a line is new if the other model has < 10 % (-20 dB) of it there
SIDEBAND_ORDERS = 3
MODE_TOLERANCE = 0.05  # a line within 5 % of a natural frequency is attributed to it
MODES_SHOWN_HZ = 20e3  # natural frequencies listed in the report up to this


# ============================================================================ configurations
def configurations(flex_name: str, duration: float, run_in: float, level: int | None = None):
    """(rigid config, flexible config) from the flexible preset: the rigid one is the same
    configuration with the ``[flexible]`` block removed (so it keeps whatever else the preset
    holds)."""
    flex = load_config(flex_name)
    flex.simulation.update(duration=duration, run_in=run_in, output_rate=OUTPUT_RATE)
    if level is not None:
        flex.flexible["level"] = level
    return dataclasses.replace(flex, flexible=None), flex


def pair_key(cfg, mesh_name: str) -> str:
    """Name of the distinct pair (``cfg.pairs``) a mesh of the model belongs to."""
    if cfg.kind == "spur":
        return "pinion-wheel"
    return "sun-planet" if mesh_name.startswith("sun-") else "planet-ring"


def fit_laws(flex_cfg, loads_rel=FIT_LOADS) -> dict:
    """Fitted IMPACT law per distinct pair (:class:`~flexgear.stiffness.impact_fit.ImpactFit`),
    at the flexible model's FE level and formulation."""
    fx = flex_cfg.flexible
    fits = {}
    for name, pair in flex_cfg.pairs.items():
        W, _ = operating_point(flex_cfg, pair)
        fits[name] = fit_impact_law(pair, W * np.asarray(loads_rel), settings=MeshSettings(level=fx["level"]),
                                    material=flex_cfg.material, formulation=fx["formulation"])
    return fits


def zeta_damping(cfg, laws: dict | None, zeta: float) -> dict:
    """IMPACT C [N s/m] per pair giving the mesh damping ratio ``zeta`` with the stiffness of
    ``laws`` (pair -> (K, e); None: the configuration's law)."""
    out = {}
    for name, pair in cfg.pairs.items():
        W, m_e = operating_point(cfg, pair)
        law = cfg.contact_law(pair)
        K, e = (law.K, law.e) if laws is None else laws[name]
        out[name] = damping_from_ratio(zeta, W, K, e, law.d, m_e)
    return out


def make_model(cfg, laws: dict | None = None, damping: dict | None = None):
    """The model of ``cfg`` with the IMPACT K, e (``laws``: pair -> (K, e)) and C (``damping``:
    pair -> C) replaced per mesh; the mesh attributes record the values used."""
    model = build_model(cfg)
    for mesh in model.meshes:
        key = pair_key(cfg, mesh.name)
        if laws is not None:
            mesh.K, mesh.e = laws[key]
            mesh.attrs.update(K=mesh.K, e=mesh.e, stiffness_reading=f"fitted to the FE loaded-mesh TE ({key})")
        if damping is not None:
            mesh.C = damping[key]
            mesh.attrs.update(C=mesh.C, damping_reading=f"C = {mesh.C:.5g} N s/m from a mesh damping ratio")
    return model


def deformed_snapshot(result, path: Path, at_time: float, scale: float = 200.0, overwrite: bool = False):
    """Deformed-shape snapshot of a flexible result (to be wired to
    ``flexgear.results.deformed.plot_deformed(result, time, scale, ax=None)`` once it exists).

    Returns the written path, or None when that function is not available yet (the study
    does not compute deformations itself).
    """
    try:
        from flexgear.results.deformed import plot_deformed  # noqa: F401  (written by another helper)
    except ImportError:
        return None
    with paper_style():
        fig = figure(DOUBLE_WIDTH, DOUBLE_WIDTH)
        ax = fig.subplots()
        plot_deformed(result, at_time, scale, ax=ax)
        return save_figure(fig, path, overwrite=overwrite)


# ============================================================================ signals
def transmission_error(mesh) -> np.ndarray:
    """Approach of the loaded pairs along the line of action [m] per sample (rigid models: the
    IMPACT penetration; flexible: the rigid overlap, elastic flank deflection included)."""
    loaded = mesh.pair_force > 0
    return np.where(loaded, mesh.penetration, -np.inf).max(axis=1)


def side_frequency(cfg, res) -> float:
    """The modulating frequency of the sidebands [Hz]: the carrier (planetary) or the input
    shaft (spur)."""
    return res.attrs["carrier_frequency"] if cfg.kind == "planetary" else res.attrs["input_frequency"]


def mesh_metrics(cfg, res, mesh_name: str) -> dict:
    """Force statistics, line amplitudes, dynamic factor and loaded contact ratio of a mesh."""
    m = res.meshes[mesh_name]
    W, _ = operating_point(cfg, cfg.pairs[pair_key(cfg, mesh_name)])
    F = m.normal_force
    f, A = amplitude_spectrum(F, res.attrs["output_rate"])
    fm, fs = res.attrs["mesh_frequency"], side_frequency(cfg, res)
    df = f[1] - f[0]
    tol = 0.6 * df
    loaded = (m.pair_force > 0).sum(axis=1)
    te = transmission_error(m)
    # the ground-frame vertical component (the paper's signal): the planets carry the mesh around,
    # which modulates it at the carrier frequency (sidebands that the scalar mesh force lacks)
    fy, Ay = amplitude_spectrum(m.force_global[:, 1], res.attrs["output_rate"])
    band = (f > 0.5 * fm) & (f <= res.attrs["passband_hz"])
    top = int(np.argmax(np.where(band, A, 0.0)))
    return {"W": W, "mean": F.mean(), "pp": np.ptp(F), "rms": F.std(), "f_m": line_amplitude(f, A, fm, tol),
            "2f_m": line_amplitude(f, A, 2 * fm, tol),
            "f_m-f_s": line_amplitude(f, A, fm - fs, tol) if fs >= df else math.nan,
            "f_m+f_s": line_amplitude(f, A, fm + fs, tol) if fs >= df else math.nan,
            "Fy f_m-f_s": line_amplitude(fy, Ay, fm - fs, tol) if fs >= df else math.nan,
            "Fy f_m+f_s": line_amplitude(fy, Ay, fm + fs, tol) if fs >= df else math.nan,
            "top": (f[top] / fm, A[top]),
            "Kv": F.max() / W, "pair_max": m.pair_force.max() / W, "two_pair": float(np.mean(loaded >= 2)),
            "eps_load": float(loaded.mean()), "te_mean": float(np.mean(te[np.isfinite(te)])),
            "spectrum": (f, A)}


def planet_shares(res) -> dict:
    """Instantaneous load share of each planet (sun-planet force / mean of them) [-]."""
    names = sorted(n for n in res.meshes if n.startswith("sun-"))
    F = np.stack([res.meshes[n].normal_force for n in names])
    share = F / F.mean(axis=0)
    return {n.split("-")[1]: s for n, s in zip(names, share)}


# ============================================================================ spectral lines
def mesh_line_label(f0: float, fm: float, fs: float, sym: str, tol: float, n_harm: int = 12,
                    max_order: int = SIDEBAND_ORDERS) -> str | None:
    """``k f_m +- j f_s`` (|j| <= max_order) within ``tol`` of ``f0``, or None."""
    best = None
    for k in range(0, n_harm + 1):
        for j in range(-max_order, max_order + 1):
            if k == 0 and j <= 0:
                continue
            fr = k * fm + j * fs
            if abs(fr - f0) <= tol and (best is None or abs(fr - f0) < best[0]):
                km = "" if k == 0 else (f"{k}f_m" if k > 1 else "f_m")
                js = "" if j == 0 else f"{'+' if j > 0 and k else ('-' if j < 0 else '')}{abs(j) if abs(j) > 1 else ''}{sym}"
                best = (abs(fr - f0), f"{km}{js}")
    return None if best is None else best[1]


def attribute_line(f0: float, fm: float, fs: float, sym: str, tol: float, mode_freqs) -> str:
    """What explains a spectral line at ``f0``, first match of:

    1. a mesh harmonic or sideband ``k f_m +- j f_s`` (j <= 3), with the nearest natural
       frequency of the linearised model (what amplifies it);
    2. a half-order mesh harmonic ``(2k+1) f_m / 2 +- j f_s`` (j <= 3): period doubling;
    3. a natural frequency within MODE_TOLERANCE, or ``f_n +- k f_m`` within ``tol``;
    4. a higher-order combination ``k f_m +- j f_s`` (the set is periodic with 1/f_s, so
       every steady line is one), else "unexplained"; both with the nearest mode.
    """
    freqs = [x for x in mode_freqs if x > 0]
    near = min(freqs, key=lambda fn: abs(f0 - fn)) if freqs else None
    near_txt = "" if near is None else f"; nearest mode {near:.0f} Hz ({100 * (f0 / near - 1):+.1f} %)"
    lab = mesh_line_label(f0, fm, fs, sym, tol)
    if lab:
        return lab + near_txt
    k2 = round(2 * f0 / fm)
    for kk in (k2 - 1, k2, k2 + 1):
        if kk % 2 == 1:
            for j in range(-SIDEBAND_ORDERS, SIDEBAND_ORDERS + 1):
                if abs(kk * fm / 2 + j * fs - f0) <= tol:
                    js = "" if j == 0 else f"{'+' if j > 0 else '-'}{abs(j) if abs(j) > 1 else ''}{sym}"
                    return f"{kk}f_m/2{js} (half order){near_txt}"
    if near is not None and abs(f0 / near - 1) <= MODE_TOLERANCE:
        return f"mode {near:.0f} Hz ({100 * (f0 / near - 1):+.1f} %)"
    for fn in sorted(freqs, key=lambda x: abs(f0 - x)):
        for k in range(1, 8):
            for sgn in (-1, 1):
                if abs(fn + sgn * k * fm - f0) <= tol:
                    return f"mode {fn:.0f} Hz {'+' if sgn > 0 else '-'} {k if k > 1 else ''}f_m"
    lab = mesh_line_label(f0, fm, fs, sym, tol, max_order=max(SIDEBAND_ORDERS, int(fm / (2 * fs)) + 1))
    if lab:
        return f"{lab} (combination){near_txt}"
    return f"unexplained{near_txt}"


def new_lines(spec_a, spec_b, W: float, fmax: float, fmin: float = 20.0) -> list:
    """Lines of spectrum b (f, A) above LINE_FLOOR W that spectrum a does not have (a has less
    than NEW_LINE_RATIO of b's amplitude within +- 2 bins)."""
    fa, Aa = spec_a
    fb, Ab = spec_b
    df = fb[1] - fb[0]
    out = []
    for p in find_peaks(fb, Ab, 40, fmin=fmin, fmax=fmax, min_separation_hz=3 * df, min_amplitude=LINE_FLOOR * W):
        there = line_amplitude(fa, Aa, p.freq, 2.5 * df)
        if there < NEW_LINE_RATIO * p.amplitude:
            out.append((p.freq, p.amplitude, there))
    return sorted(out)


# ============================================================================ study
def study_preset(key: str, duration: float, run_in: float, zeta: float, level=None, loads_rel=FIT_LOADS,
                 say=print) -> dict:
    """Run the six cases of one preset; returns configs, fits, results, metrics, modes."""
    rigid_cfg, flex_cfg = configurations(PRESETS[key], duration, run_in, level)
    t0 = time.perf_counter()
    fits = fit_laws(flex_cfg, loads_rel)
    say(f"[{key}] FE fit of the IMPACT law: {time.perf_counter() - t0:.1f} s")
    fitted = {n: (f.K, f.e) for n, f in fits.items()}
    damp = {"paper C": {m: None for m in MODELS},
            "zeta": {"rigid (paper)": zeta_damping(rigid_cfg, None, zeta),
                     "rigid (fitted)": zeta_damping(rigid_cfg, fitted, zeta),
                     "flexible": zeta_damping(rigid_cfg, fitted, zeta)}}
    results, wall = {}, {}
    for dname in DAMPINGS:
        for mname in MODELS:
            cfg = flex_cfg if mname == "flexible" else rigid_cfg
            laws = fitted if mname == "rigid (fitted)" else None
            t0 = time.perf_counter()
            model = make_model(cfg, laws, damp[dname][mname])
            results[(mname, dname)] = run(cfg, model=model,  # its phases said (a first run compiles minutes)
                                          messages=lambda m, case=f"[{key}] {mname}, {dname}": say(f"{case}: {m}"))
            wall[(mname, dname)] = time.perf_counter() - t0
            say(f"[{key}] {mname}, {dname}: {wall[(mname, dname)]:.1f} s wall")
    model_flex = build_model(flex_cfg)
    # the flexible model linearised as it is integrated (condensed modes with their own inertia:
    # every gear mode a coordinate); its modes from the gears' first clamped mode up are the
    # gears' own (listed below as clamped modes), far above the band
    flex_f = modes(linearise(model_flex, condensation=flex_cfg.flexible["condensation"])).frequencies
    modal = {"rigid (paper)": modes(linearise(make_model(rigid_cfg))).frequencies,
             "rigid (fitted)": modes(linearise(make_model(rigid_cfg, fitted))).frequencies,
             "flexible": flex_f[flex_f < min(fb.attrs["first_mode_hz"] for fb in model_flex.flex)]}
    # the modes as the HHT-alpha integrator renders them at the runs' step (what the spectra show)
    h, _ = time_grid(flex_cfg.simulation)
    alpha = flex_cfg.simulation["hht_alpha"]
    modal_at_h = {name: integrated_frequency(f, h, alpha) for name, f in modal.items()}
    clamped = {}
    for fb in model_flex.flex:
        clamped[fb.attrs["gear"]] = fb.attrs["first_mode_hz"]
    # the static FE reference with contact outside the path (what the dynamic models also have)
    fx = flex_cfg.flexible
    fe_ext = {name: loaded_mesh(pair, operating_point(flex_cfg, pair)[0], settings=MeshSettings(level=fx["level"]),
                                material=flex_cfg.material, formulation=fx["formulation"], extended=True)
              for name, pair in flex_cfg.pairs.items()}
    metrics = {k: {mesh: mesh_metrics(rigid_cfg, r, mesh) for mesh in r.meshes} for k, r in results.items()}
    for per_mesh in metrics.values():
        for mesh, m in per_mesh.items():
            fit = fits[pair_key(rigid_cfg, mesh)]
            fe = fit.fe[int(np.argmin(np.abs(fit.loads - m["W"])))]
            lo = math.floor(fe.grid.eps_alpha)
            m["te_fe"] = zone_mean_te(fe)
            m["te_fe_load"] = zone_mean_te(fe, min(max(m["eps_load"], lo), lo + 1 - 1e-9))
            ext = fe_ext[pair_key(rigid_cfg, mesh)]
            m["te_fe_ext"], m["eps_fe_ext"] = float(np.mean(ext.te)), float(np.mean(ext.n_pairs))
    return {"key": key, "cfg": rigid_cfg, "flex_cfg": flex_cfg, "fits": fits, "results": results,
            "metrics": metrics, "modal": modal, "modal_at_h": modal_at_h, "step": (h, alpha), "clamped": clamped,
            "damping": damp, "wall": wall}


def shown_meshes(res) -> list:
    meshes = list(res.meshes)
    return meshes[:1] if len(meshes) < 3 else [meshes[0], meshes[len(meshes) // 2]]


def write_figures(s: dict, out: Path, overwrite: bool) -> list:
    key, results = s["key"], s["results"]
    any_res = results[(MODELS[0], DAMPINGS[0])]
    shown = shown_meshes(any_res)
    fm = any_res.attrs["mesh_frequency"]
    written = []
    with paper_style():
        # forces overlaid
        fig = figure(DOUBLE_WIDTH, 2.0 * len(shown) * len(DAMPINGS))
        axs = fig.subplots(len(shown) * len(DAMPINGS), 1, squeeze=False)[:, 0]
        for i, (dname, mesh) in enumerate([(d, m) for d in DAMPINGS for m in shown]):
            for mname in MODELS:
                r = results[(mname, dname)]
                sel = r.time < r.time[0] + 6 / fm
                axs[i].plot(r.time[sel], r.meshes[mesh].normal_force[sel], lw=0.7, label=mname)
            axs[i].set_ylabel(f"normal force [N]\n{mesh}, {dname}")
            axs[i].legend(loc="upper right", fontsize=6)
        axs[-1].set_xlabel("time [s]")
        written.append(save_figure(fig, out / f"{key}_forces.png", overwrite=overwrite))
        # spectra
        fig = figure(DOUBLE_WIDTH, 2.0 * len(shown) * len(DAMPINGS))
        axs = fig.subplots(len(shown) * len(DAMPINGS), 1, squeeze=False)[:, 0]
        for i, (dname, mesh) in enumerate([(d, m) for d in DAMPINGS for m in shown]):
            for mname in MODELS:
                f, A = s["metrics"][(mname, dname)][mesh]["spectrum"]
                band = f <= results[(mname, dname)].attrs["passband_hz"]
                axs[i].semilogy(f[band], A[band] + 1e-12, lw=0.6, alpha=0.8, label=mname)
            W = s["metrics"][(MODELS[0], dname)][mesh]["W"]
            axs[i].set_ylim(1e-5 * W, None)  # lines below 10 ppm of the static force are not of interest
            axs[i].set_ylabel(f"normal force amplitude [N]\n{mesh}, {dname}")
            axs[i].legend(loc="upper right", fontsize=6)
        axs[-1].set_xlabel("frequency [Hz]")
        written.append(save_figure(fig, out / f"{key}_spectra.png", overwrite=overwrite))
        # transmission error
        mesh = shown[0]
        fit = s["fits"][pair_key(s["cfg"], mesh)]
        W = s["metrics"][(MODELS[0], DAMPINGS[0])][mesh]["W"]
        fig = figure(DOUBLE_WIDTH, 2.2 * len(DAMPINGS))
        axs = fig.subplots(len(DAMPINGS), 1, squeeze=False)[:, 0]
        for ax, dname in zip(axs, DAMPINGS):
            for mname in MODELS:
                r = results[(mname, dname)]
                sel = r.time < r.time[0] + 4 / fm
                ax.plot(r.time[sel], transmission_error(r.meshes[mesh])[sel] * 1e6, lw=0.7, label=mname)
            fe = fit.fe[int(np.argmin(np.abs(fit.loads - W)))]
            ax.axhline(zone_mean_te(fe) * 1e6, color="k", ls="--", lw=0.6, label=f"FE static mean ({fe.load:.4g} N)")
            ax.set_ylabel(f"{mesh} TE [um]\n{dname}")
            ax.legend(loc="upper right", fontsize=6)
        axs[-1].set_xlabel("time [s]")
        written.append(save_figure(fig, out / f"{key}_te.png", overwrite=overwrite))
        # load sharing between tooth pairs
        fig = figure(DOUBLE_WIDTH, 1.6 * len(MODELS))
        axs = fig.subplots(len(MODELS), len(DAMPINGS), squeeze=False, sharey=True)
        for i, mname in enumerate(MODELS):
            for j, dname in enumerate(DAMPINGS):
                r = results[(mname, dname)]
                sel = r.time < r.time[0] + 3 / fm
                pf = r.meshes[mesh].pair_force[sel]
                axs[i, j].plot(r.time[sel], np.sort(pf, axis=1)[:, ::-1][:, :3], lw=0.7)
                axs[i, j].set_title(f"{mname}, {dname}", fontsize=7)
            axs[i, 0].set_ylabel("pair load [N]")
        axs[-1, 0].set_xlabel("time [s]")
        axs[-1, 1].set_xlabel("time [s]")
        written.append(save_figure(fig, out / f"{key}_pair_loads.png", overwrite=overwrite))
        # load sharing between planets
        if s["cfg"].kind == "planetary":
            fig = figure(DOUBLE_WIDTH, 1.6 * len(MODELS))
            axs = fig.subplots(len(MODELS), len(DAMPINGS), squeeze=False, sharey=True)
            for i, mname in enumerate(MODELS):
                for j, dname in enumerate(DAMPINGS):
                    r = results[(mname, dname)]
                    sel = r.time < r.time[0] + 2 / r.attrs["carrier_frequency"] / s["cfg"].planetary["planets"]
                    for p, share in planet_shares(r).items():
                        axs[i, j].plot(r.time[sel], share[sel], lw=0.6, label=p)
                    axs[i, j].set_title(f"{mname}, {dname}", fontsize=7)
                axs[i, 0].set_ylabel("load share [-]")
            axs[0, 0].legend(loc="upper right", fontsize=6)
            written.append(save_figure(fig, out / f"{key}_planets.png", overwrite=overwrite))
    return written


def line_table(s: dict) -> list:
    """Rows: spectral lines present in one model and absent in another, with their attribution."""
    rows = []
    cfg = s["cfg"]
    any_res = s["results"][(MODELS[0], DAMPINGS[0])]
    fm, fs = any_res.attrs["mesh_frequency"], side_frequency(cfg, any_res)
    sym = "f_a" if cfg.kind == "planetary" else "f_1"
    fmax = any_res.attrs["passband_hz"]
    comparisons = (("rigid (paper)", "rigid (fitted)"), ("rigid (paper)", "flexible"), ("rigid (fitted)", "flexible"),
                   ("flexible", "rigid (fitted)"), ("rigid (fitted)", "rigid (paper)"))
    for mesh in shown_meshes(any_res):
        for dname in DAMPINGS:
            for a, b in comparisons:
                ma, mb = s["metrics"][(a, dname)][mesh], s["metrics"][(b, dname)][mesh]
                f = mb["spectrum"][0]
                tol = 1.5 * (f[1] - f[0])
                for f0, amp, there in new_lines(ma["spectrum"], mb["spectrum"], mb["W"], fmax):
                    rows.append([mesh, dname, b, a, f"{f0:.1f}", f"{amp:.3g}", f"{there:.2g}",
                                 attribute_line(f0, fm, fs, sym, tol, s["modal_at_h"][b])])
    return rows


def report(studies: list, args, wall: float) -> str:
    head = ["preset", "mesh", "damping", "model", "mean F [N]", "mean/W", "p-p [N]", "RMS [N]", "f_m [N]",
            "2f_m [N]", "f_m-f_s [N]", "f_m+f_s [N]", "F_y f_m-f_s [N]", "F_y f_m+f_s [N]", "largest line [f_m, N]", "K_v", "max pair/W", "2-pair share", "eps_load",
            "mean TE [um]", "FE TE at eps_load [um]", "FE ext. TE [um]", "FE ext. eps"]
    rows, fits, lines, modal_rows = [], [], [], []
    for s in studies:
        key = s["key"]
        meshes = shown_meshes(s["results"][(MODELS[0], DAMPINGS[0])])
        for mesh in meshes:
            for dname in DAMPINGS:
                for mname in MODELS:
                    m = s["metrics"][(mname, dname)][mesh]
                    rows.append([key, mesh, dname, mname, f"{m['mean']:.1f}", f"{m['mean'] / m['W']:.4f}",
                                 f"{m['pp']:.1f}", f"{m['rms']:.2f}", f"{m['f_m']:.2f}", f"{m['2f_m']:.2f}",
                                 f"{m['f_m-f_s']:.3g}", f"{m['f_m+f_s']:.3g}", f"{m['Fy f_m-f_s']:.3g}",
                                 f"{m['Fy f_m+f_s']:.3g}", f"{m['top'][0]:.2f}: {m['top'][1]:.3g}", f"{m['Kv']:.3f}",
                                 f"{m['pair_max']:.3f}", f"{m['two_pair']:.3f}", f"{m['eps_load']:.3f}",
                                 f"{m['te_mean'] * 1e6:.2f}", f"{m['te_fe_load'] * 1e6:.2f}",
                                 f"{m['te_fe_ext'] * 1e6:.2f}", f"{m['eps_fe_ext']:.3f}"])
        for name, fit in s["fits"].items():
            W, m_e = operating_point(s["cfg"], s["cfg"].pairs[name])
            law = s["cfg"].contact_law(s["cfg"].pairs[name])
            z_paper = ratio_from_damping(law.C, W, law.K, law.e, law.d, m_e)
            z_fit = ratio_from_damping(law.C, W, fit.K, fit.e, law.d, m_e)
            fits.append([key, name, f"{W:.5g}", f"{fit.K:.4g}", f"{fit.K_n_mm:.4g}", f"{fit.e:.4f}",
                         f"{fit.eps:.4f}", f"{fit.max_rel_error * 100:.3f}",
                         f"{zone_mean_te(fit.fe[int(np.argmin(np.abs(fit.loads - W)))]) * 1e6:.2f}",
                         f"{law.e * W / (W / law.K) ** (1 / law.e):.4g}", f"{fit.tangent_stiffness(W):.4g}",
                         f"{s['damping']['zeta']['rigid (paper)'][name]:.4g}",
                         f"{s['damping']['zeta']['rigid (fitted)'][name]:.4g}", f"{z_paper:.3g}", f"{z_fit:.3g}"])
        for r in line_table(s):
            lines.append([key] + r)
        for mname, fr in s["modal"].items():
            el = [f"{x:.0f}" for x in fr if 0 < x < MODES_SHOWN_HZ]
            modal_rows.append([key, mname, ", ".join(el) or "-"])
        h, alpha = s["step"]
        for mname, fr in s["modal_at_h"].items():
            el = [f"{x:.0f}" for x in fr[s["modal"][mname] < MODES_SHOWN_HZ] if x > 0]
            modal_rows.append([key, f"{mname}, as integrated (h = {h * 1e6:g} us, alpha = {alpha:g})",
                               ", ".join(el) or "-"])
        if s["clamped"]:
            modal_rows.append([key, "flexible: first clamped gear modes",
                               ", ".join(f"{g} {f:.0f}" for g, f in s["clamped"].items())])
    planets = []
    for s in studies:
        if s["cfg"].kind != "planetary":
            continue
        for dname in DAMPINGS:
            for mname in MODELS:
                sh = planet_shares(s["results"][(mname, dname)])
                planets.append([s["key"], dname, mname] + [f"{v.mean():.4f} ({np.ptp(v):.3f})" for v in sh.values()])
    cmd = (f"python studies/rigid_vs_flexible.py --out {args.out} --duration {args.duration} --run-in {args.run_in} "
           f"--zeta {args.zeta}" + (" --quick" if args.quick else "") + f" --presets {' '.join(args.presets)}")
    txt = ["# Rigid vs flexible gears: three models, two mesh dampings\n", f"`{cmd}` ({wall:.0f} s wall)\n",
           "Models (all from the flexible preset's configuration, its elastic shafts included): **rigid (paper)** = IMPACT K = 3e5 N/mm^1.3, "
           "e = 1.3; **rigid (fitted)** = IMPACT law per mesh fitted to the FE loaded-mesh transmission error "
           f"(mesh level and formulation of the flexible model, loads {', '.join(map(str, FIT_LOADS))} x W); "
           "**flexible** = Craig-Bampton gears, compliant flanks, line-contact Hertz.\n",
           f"Dampings: **paper C** = 3000 N s/mm, d = 0.3 mm; **zeta** = a mesh damping ratio of {args.zeta} of "
           "critical at each mesh's static operating point (C below; the flexible model uses the fitted model's C: "
           "the fitted law stands for its mesh stiffness and its damper acts on the same rigid approach).\n",
           "Definitions: W = static mesh force (T / r_b per mesh); K_v = max F / W (dynamic factor, ISO 6336 "
           "K_v analogue); max pair/W = largest single tooth-pair load / W; 2-pair share = time share with two or "
           "more loaded pairs; eps_load = mean number of loaded pairs (contact ratio under load); TE = approach "
           "of the loaded pairs along the line of action (rigid: IMPACT penetration; flexible: rigid overlap, "
           "elastic deflection included); FE TE at eps_load = the FE static TE of the single- and double-pair zones weighted by the model's own loaded contact shares (the FE's theoretical path has no contact outside it); FE ext. TE / eps = the FE static loaded mesh at W with contact outside the path (`loaded_mesh(..., extended=True)`: mean TE and mean number of loaded pairs), the static reference for the dynamic models, which all engage early and release late under load; f_s = input shaft (spur, f_1) or carrier (planetary, f_a) frequency; f_m +- f_s of the scalar mesh force and of its ground-frame vertical component F_y (the paper's signal: the carrier sidebands come from the planets carrying the mesh around, the scalar force of ideal gears has none); largest line = the largest spectral line above f_m/2 in the trustworthy band, in multiples of f_m, and its amplitude. "
           "Amplitudes: Hann-windowed single-sided spectrum of the whole record.\n",
           "## Fitted IMPACT laws\n",
           markdown_table(fits, ["preset", "pair", "W [N]", "K [N/m^e]", "K [N/mm^e]", "e", "eps", "max fit err [%]",
                                 "FE mean TE at W [um]", "paper k_t at W [N/m]", "fitted k_t at W [N/m]",
                                 "C zeta paper [N s/m]", "C zeta fitted [N s/m]", "paper C: zeta (paper law)",
                                 "paper C: zeta (fitted law)"]) + "\n",
           "k_t = tangent stiffness of one tooth pair's law at W. The last two columns: the mesh damping ratio that the paper's C = 3000 N s/mm amounts to at W with each law (STEP ramp over d = 0.3 mm: at MERCURY's light load the penetration is a few um, so the paper's C acts only weakly there). Fit error: the fitted rigid law's mean static TE "
           "against the FE's (zone-weighted) at the fit loads.\n",
           "## Forces\n", markdown_table(rows, head) + "\n"]
    if planets:
        txt += ["## Load sharing between planets\n",
                "Mean load share of each planet (sun-planet force / mean of the planets) and, in brackets, its "
                "peak-to-peak over the record.\n",
                markdown_table(planets, ["preset", "damping", "model"] + [f"planet {i + 1}" for i in range(len(planets[0]) - 3)]) + "\n"]
    txt += ["## Natural frequencies (linearised, < 20 kHz) and clamped gear modes\n",
            markdown_table(modal_rows, ["preset", "model", "frequencies [Hz]"]) + "\n",
            "Each model is linearised about its own loaded equilibrium over a mesh cycle "
            "(`flexgear.dynamics.modal.linearise.linearise`); the flexible model with the solver's tangent stiffness "
            "(compliant contacts solved jointly, so the coupling between meshes through the gear rims is in it). "
            "The gears' first clamped modes (from the reductions) lie far above the trustworthy band. "
            "'As integrated': the frequency at which the HHT-alpha integrator makes each mode oscillate at the "
            "runs' step (`flexgear.dynamics.modal.analysis.integrated_frequency`; the period grows with omega h), "
            "which is what the spectra show and what the lines below are attributed to.\n",
            "## Spectral lines present in one model and not in another\n",
            f"Lines of model B above {LINE_FLOOR:g} W where model A has less than {NEW_LINE_RATIO:g} x B's amplitude "
            "(+-2 bins), up to the trustworthy band's edge; attribution (first match, "
            "within 1.5 bins): mesh harmonic / sideband k f_m +- j f_s (j <= 3), half-order harmonic (2k+1) f_m/2 +- "
            "j f_s (period doubling), a natural frequency of B's own linearisation (as integrated) within 5 % or f_n +- k f_m, a higher-order combination k f_m +- j f_s; the nearest mode is given with "
            "each (what amplifies the line).\n",
            markdown_table(lines, ["preset", "mesh", "damping", "B (has it)", "A (lacks it)", "f [Hz]", "B amp [N]",
                                   "A amp [N]", "explained by"]) if lines else "None above the threshold.\n", "\n"]
    return "\n".join(txt)


def execute(argv=None) -> tuple[list, str]:
    """Parse ``argv``, run the study, write the figures and report.md; returns (studies, report)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("-o", "--out", "--output", dest="out", required=True, type=Path, help="output directory")
    p.add_argument("--duration", type=float, default=1.0, help="simulated time after the run-in [s]")
    p.add_argument("--run-in", type=float, default=0.2, help="run-in [s]")
    p.add_argument("--zeta", type=float, default=0.05, help="mesh damping ratio of the 'zeta' runs [-]")
    p.add_argument("--presets", nargs="+", default=list(PRESETS), choices=list(PRESETS), help="gear sets compared")
    p.add_argument("--quick", action="store_true",
                   help="a smoke test: at most 0.05 s after at most 0.1 s of run-in, the flexible gears at FE level 0")
    p.add_argument("--overwrite", action="store_true", help="replace the figures and report.md of an earlier run")
    a = p.parse_args(argv)
    if a.quick:
        a.duration, a.run_in = min(a.duration, 0.05), min(a.run_in, 0.1)
    if not (a.duration > 0 and a.run_in >= 0 and a.zeta > 0):
        raise SystemExit(f"--duration {a.duration}, --run-in {a.run_in}, --zeta {a.zeta}: need duration > 0, "
                         "run-in >= 0, zeta > 0")
    a.out.mkdir(parents=True, exist_ok=True)
    names = ["forces", "spectra", "te", "pair_loads"]
    targets = [a.out / "report.md"] + [a.out / f"{k}_{n}.png" for k in a.presets for n in names]
    targets += [a.out / "mercury_planets.png"] if "mercury" in a.presets else []
    targets += [a.out / f"{k}_deformed.png" for k in a.presets]
    check_targets(targets, a.overwrite)
    t0 = time.perf_counter()
    studies = [study_preset(k, a.duration, a.run_in, a.zeta, level=0 if a.quick else None) for k in a.presets]
    for s in studies:
        write_figures(s, a.out, a.overwrite)
        flex = s["results"][("flexible", "paper C")]
        deformed_snapshot(flex, a.out / f"{s['key']}_deformed.png", float(flex.time[0]), overwrite=a.overwrite)
    text = report(studies, a, time.perf_counter() - t0)
    (a.out / "report.md").write_text(text)
    return studies, text


def main(argv=None) -> int:
    print(execute(argv)[1])
    return 0


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
