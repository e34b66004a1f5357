"""Modes, Campbell diagram and a stepped speed sweep of a gear set (lumped and rigid models), and
the tie-back of the simulated spectrum to the modes.

Usage::

    python studies/speed_sweep_modes.py -o out/sweep_modes [--config mercury_1a] [--quick]
        [--flexible auto|none|PRESET_OR_FILE]

Writes to the output directory:

* ``campbell.png`` and the crossings of the mesh harmonics with the natural frequencies of the
  set linearised at its operating point, each marked excited or suppressed by planet phasing
  (:func:`flexgear.dynamics.modal.campbell.excites`);
* ``sweep.png``: dynamic factor max(F)/mean(F) and the amplitude of the mesh harmonics of the
  first sun-planet (or pinion-wheel) mesh force against input speed, for the lumped model on a
  fine speed grid, the rigid model on a coarser one and the flexible model (the ``*_flexible``
  preset of the set, about 14 s of computing per simulated second for MERCURY 1-A) on a coarse
  grid of a few speeds, resonance peaks labelled by mode;
* ``report.md``: the modes (of the rigid set, and of the flexible set linearised with the
  solver's tangent, :func:`flexgear.dynamics.modal.linearise.linearise`), the crossings, the resonance
  peaks against each model's own linearised frequencies, and the tie-back table: the peaks of the rigid model's spectrum at the
  configuration's speed that are not mesh lines or sidebands, explained by the modes.

Each speed is a separate run of ``run_in + duration`` (steady state), so the peaks are those of
a stepped, slow sweep. ``--quick`` uses fewer speeds and shorter runs. ``--flexible auto`` (the
default) adds the flexible model of the configuration's preset (``mercury_1a`` ->
``mercury_1a_flexible``), ``none`` leaves it out.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import flexgear
from flexgear.app.console import markdown_table
from flexgear.config import PRESETS, load_config, loads_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.lumped.model import at_speed, build_lumped
from flexgear.dynamics.lumped.time_loop import simulate_lumped
from flexgear.dynamics.modal.analysis import integrated_frequency
from flexgear.dynamics.modal.campbell import modal_excites
from flexgear.dynamics.modal.linearise import linearise
from flexgear.dynamics.modal.system import modes
from flexgear.errors import DivergenceError
from flexgear.files import atomic_write, check_targets
from flexgear.app.run import time_grid
from flexgear.results.campbell_plot import fig_campbell
from flexgear.results.signals import amplitude_spectrum, find_peaks, line_amplitude, planetary_lines, spur_lines
from flexgear.style import COLUMN_WIDTH, figure, paper_style, save_figure
from flexgear.app.console import run_command

HARMONICS = 4
#: Peaks of a spectrum further than this below its largest peak are numerical noise (Newton
#: tolerance, round-off: -160 dB peaks were listed as "free vibration"), not tied back [dB].
NOISE_FLOOR_DB = -120.0


def mesh_metrics(force: np.ndarray, fs: float, f_mesh: float) -> dict:
    """Dynamic factor, RMS of the fluctuation and mesh-harmonic amplitudes of a mesh force."""
    f, A = amplitude_spectrum(force, fs)
    out = {"kv": float(force.max() / force.mean()), "rms": float(np.std(force)), "mean": float(force.mean())}
    tol = max(0.02 * f_mesh, 1.5 * (f[1] - f[0]))
    for k in range(1, HARMONICS + 1):
        out[f"h{k}"] = line_amplitude(f, A, k * f_mesh, tol_hz=tol) if k * f_mesh + tol < fs / 2 else np.nan
    return out


def lumped_sweep(lm, speeds, run_in, duration, h, out_every, mesh_index=0, alpha=-0.1):
    """Metrics of the lumped model's mesh force at every integration step (rate 1/h), with the
    step h [s] and HHT alpha of each run."""
    rows = []
    for s in speeds:
        m = at_speed(lm, s)
        try:
            integ = simulate_lumped(m, run_in + duration, h, out_every, alpha=alpha)
        except DivergenceError as exc:
            print(f"lumped model at {s:.2f} Hz: {exc}", file=sys.stderr)
            continue
        n0 = int(round(run_in / h))
        F = np.abs(integ.mesh[n0:, mesh_index, 0])
        rows.append(dict(speed=s, step=h, alpha=alpha, **mesh_metrics(F, 1.0 / h, m.model.attrs["mesh_frequency"])))
    return rows


def rigid_sweep(text, speeds, run_in, duration, mesh_name, label="rigid"):
    """Metrics of a multi-body model's mesh force (rigid, or flexible when ``text`` has a
    [flexible] block), output at 20 kHz (harmonics up to 10 kHz), with the integration step [s]
    and HHT alpha each run used (the flexible presets' 6.25 us, the rigid ones' 25 us)."""
    rows = []
    for s in speeds:
        cfg = loads_config(text)
        cfg.drive["speed_hz"] = float(s)
        cfg.simulation.update(run_in=run_in, duration=duration, output_rate=20000.0)
        try:
            res = flexgear.run(cfg)
        except DivergenceError as exc:
            print(f"{label} model at {s:.2f} Hz: {exc}", file=sys.stderr)
            continue
        F = res.meshes[mesh_name].normal_force
        rows.append(dict(speed=s, step=float(res.attrs["step"]), alpha=float(res.attrs["hht_alpha"]),
                         **mesh_metrics(F, res.fs, res.attrs["mesh_frequency"])))
    return rows


def resonance_peaks(rows, key, mesh_ratio, k):
    """Local maxima of ``key`` over speed (parabolic refinement): (speed, value, frequency k f_m)."""
    s = np.array([r["speed"] for r in rows])
    y = np.array([r[key] for r in rows])
    out = []
    for i in range(1, len(s) - 1):
        if y[i] > y[i - 1] and y[i] >= y[i + 1] and np.isfinite(y[i]):
            d = (y[i - 1] - y[i + 1]) / (2 * (y[i - 1] - 2 * y[i] + y[i + 1]))
            sp = s[i] + d * (s[i + 1] - s[i])
            out.append((float(sp), float(y[i]), float(k * mesh_ratio * sp)))
    return out


def excited_by(modal, k, sun_teeth):
    """Whether each mode of ``modal`` can respond to the k-th mesh harmonic (planet phasing,
    :func:`flexgear.dynamics.modal.campbell.modal_excites`); None (every mode) without a sun's
    tooth count (a spur pair)."""
    return None if sun_teeth is None else modal_excites(modal, k, sun_teeth)


def match_peaks(name, rows, modal, mesh_ratio, tol=0.05, sun_teeth=None):
    """Resonance peaks of each mesh harmonic's amplitude over speed (:func:`resonance_peaks`),
    each matched within ``tol`` to the mode of ``modal`` nearest as the run's own HHT-alpha
    integrator renders it (:func:`flexgear.dynamics.modal.analysis.integrated_frequency` at the
    step and alpha of the sweep point nearest the peak; the period grows with omega h), among
    the modes that harmonic excites (:func:`excited_by`: with equally spaced planets, a mode the
    phasing suppresses does not respond, however near). Returns (table rows, [(speed, k, mode
    number)] of the matched peaks)."""
    out, matched = [], []
    speeds = np.array([r["speed"] for r in rows])
    for k in range(1, HARMONICS + 1):
        excited = excited_by(modal, k, sun_teeth)
        for sp, _val, fk in resonance_peaks(rows, f"h{k}", mesh_ratio, k):
            row = rows[int(np.argmin(np.abs(speeds - sp)))]
            at_h = integrated_frequency(modal.frequencies, row["step"], row["alpha"])
            nm = nearest_mode(fk, modal, tol=tol, integrated=at_h, excited=excited)
            step = f"{row['step'] * 1e6:g}"
            if nm is None:
                if name == "flexible":  # few speeds: show every peak found
                    out.append([name, f"{k}f_m", f"{sp:.2f}", f"{fk:.0f}", "no excited mode within 5 %", "-", step,
                                "-", "-"])
                continue
            i, fn, t = nm
            fh = at_h[i - 1]
            out.append([name, f"{k}f_m", f"{sp:.2f}", f"{fk:.0f}", f"{i} ({t})", f"{fn:.0f}", step, f"{fh:.0f}",
                        f"{100*(fk-fh)/fh:+.1f}"])
            matched.append((sp, k, i))
    return out, matched


def nearest_mode(freq, modal, tol=0.05, integrated=None, excited=None):
    """The mode (number, f_n, type) nearest to ``freq`` within ``tol`` relative; with
    ``integrated`` (the modes' frequencies as the time integrator renders them,
    :func:`flexgear.dynamics.modal.analysis.integrated_frequency`) compared with those instead;
    with ``excited`` (a flag per mode, :func:`excited_by`) among the flagged modes only."""
    ref = modal.frequencies if integrated is None else np.asarray(integrated)
    best = None
    for i, (fn, t) in enumerate(zip(ref, modal.mode_type)):
        if excited is not None and not excited[i]:
            continue
        if fn > 0 and abs(freq - fn) <= tol * fn and (best is None or abs(freq - fn) < abs(freq - ref[best[0] - 1])):
            best = (i + 1, float(modal.frequencies[i]), t)
    return best


def tie_back(res, modal, mesh_name, component, n_peaks=30, tol_hz=None):
    """Peaks of a mesh force spectrum that are not on a mesh line or sideband, each with the
    explanations that fit it: an alias of a line above Nyquist, a free vibration at f_n, a
    modulation f_n +- k f_m. Peaks below :data:`NOISE_FLOOR_DB` re the largest are left out."""
    fs = res.fs
    m = res.meshes[mesh_name]
    x = m.normal_force if component == "normal" else m.force_global[:, 1]
    f, A = amplitude_spectrum(x, fs)
    fa, fm = res.attrs["carrier_frequency"], res.attrs["mesh_frequency"]
    df = f[1] - f[0]
    tol = tol_hz or 1.5 * df
    nh = int(fs / fm) + 2
    lines = (planetary_lines(fa, fm, n_harmonics=nh, n_sidebands=4) if fa > 0 else spur_lines(fm, nh))
    peaks = find_peaks(f, A, n_peaks, fmin=2 * df, min_separation_hz=2 * df, rel_floor=10 ** (NOISE_FLOOR_DB / 20))
    ref = max(p.amplitude for p in peaks)
    rows, on_lines = [], []

    def folded(x):  # where a frequency appears after sampling at fs
        x = abs(x) % fs
        return fs - x if x > fs / 2 else x

    for p in sorted(peaks, key=lambda p: p.freq):
        lab = next((ln.label for ln in lines if abs(ln.freq - p.freq) <= tol and ln.freq < fs / 2), None)
        if lab:
            on_lines.append((p, lab))
            continue
        expl = []
        for ln in lines:
            if ln.freq > fs / 2 and abs(p.freq - folded(ln.freq)) <= tol:
                expl.append(f"alias of {ln.label} ({ln.freq:.0f} Hz, above Nyquist; filter edge)")
                break
        for i, (fn, t) in enumerate(zip(modal.frequencies, modal.mode_type)):
            if fn <= 0 or fn > 1.1 * fs / 2:  # far above Nyquist the output filter removes it
                continue
            name = f"mode {i+1} ({t}, {fn:.0f} Hz)"
            if abs(p.freq - folded(fn)) <= 0.03 * fn:
                expl.append(f"free vibration of {name}" + (" (aliased at the filter edge)" if fn > fs / 2 else ""))
            for k in range(1, 4):
                for sgn in (-1, 1):
                    if fn + sgn * k * fm < fs / 2 and abs(p.freq - (fn + sgn * k * fm)) <= 0.01 * fn:
                        expl.append(f"{name} {'+' if sgn > 0 else '-'} {k if k > 1 else ''}f_m")
        rows.append([f"{p.freq:.1f}", f"{p.amplitude:.3g}", f"{20*math.log10(p.amplitude/ref):.0f}",
                     "; ".join(expl[:3]) or "unexplained"])
    return rows, on_lines


def ref_amp(res, mesh_name, component) -> float:
    """Largest spectral amplitude of a mesh force signal above 1 Hz (for relative thresholds)."""
    m = res.meshes[mesh_name]
    x = m.normal_force if component == "normal" else m.force_global[:, 1]
    f, A = amplitude_spectrum(x, res.fs)
    return float(A[f > 1.0].max())


def fig_sweep(lumped_rows, rigid_rows, peaks_labelled, key="kv", flexible_rows=()):
    with paper_style():
        fig = figure(COLUMN_WIDTH, 2.6)
        ax = fig.add_subplot(1, 1, 1)
        ax.plot([r["speed"] for r in lumped_rows], [r[key] for r in lumped_rows], "-", color="C0", label="lumped")
        if rigid_rows:
            ax.plot([r["speed"] for r in rigid_rows], [r[key] for r in rigid_rows], "o", ms=2.5, mfc="none",
                    color="C3", label="rigid")
        if flexible_rows:
            ax.plot([r["speed"] for r in flexible_rows], [r[key] for r in flexible_rows], "s--", ms=2.5, lw=0.6,
                    mfc="none", color="C2", label="flexible")
        for sp, val, text in peaks_labelled:
            ax.annotate(text, (sp, val), fontsize=5.5, xytext=(0, 6), textcoords="offset points", ha="center")
        ax.set_xlabel("input speed $f_{in}$ (Hz)")
        ax.set_ylabel("dynamic factor max(F)/mean(F)" if key == "kv" else key)
        ax.legend(loc="upper left")
    return fig


def flexible_preset(config: str, choice: str) -> str | None:
    """The flexible model to sweep: ``choice`` 'none' -> None; 'auto' -> the preset
    ``<config>_flexible`` when it exists; else ``choice`` itself (a preset name or a file)."""
    if choice == "none":
        return None
    if choice == "auto":
        name = f"{config}_flexible"
        return name if name in PRESETS else None
    return choice


def main(argv=None):
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("-o", "--output", "--out", dest="output", required=True)
    ap.add_argument("--config", default="mercury_1a")
    ap.add_argument("--quick", action="store_true", help="fewer speeds, shorter runs")
    ap.add_argument("--flexible", default="auto", help="flexible model: 'auto' (the configuration's *_flexible "
                    "preset, if any), 'none', or a preset name or file")
    ap.add_argument("--overwrite", action="store_true")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    out = Path(args.output)
    targets = [out / n for n in ("report.md", "campbell.png", "sweep.png")]
    check_targets(targets, args.overwrite)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    cfg = load_config(args.config)
    text = cfg.source_text
    model = build_model(cfg)
    modal = modes(linearise(model))
    f_in = model.attrs["input_frequency"]
    r_m = model.attrs["mesh_frequency"] / f_in
    mesh_name = model.meshes[0].name
    f1 = min(f for f in modal.frequencies if f > 0)
    hi = 1.25 * f1 / r_m
    lo = max(0.05 * hi, 2.0)
    z_s = cfg.gears["sun"].z if cfg.kind == "planetary" else None
    fig, cr = fig_campbell(modal, r_m, (lo, hi), harmonics=HARMONICS, sun_teeth=z_s)
    save_figure(fig, out / "campbell.png", overwrite=args.overwrite)
    # lumped: fine grid; rigid: a coarse grid and a fine one around the first mode's crossings
    lcfg = loads_config('model = "lumped"\n' + text)
    lm = build_lumped(lcfg)
    h, oe = time_grid(cfg.simulation)
    run_in, dur = (0.1, 0.1) if args.quick else (0.15, 0.25)
    n_l = 40 if args.quick else 120
    speeds_l = np.linspace(lo, hi, n_l)
    alpha = cfg.simulation["hht_alpha"]
    lumped_rows = lumped_sweep(lm, speeds_l, run_in, dur, h, oe, alpha=alpha)
    first = [c for c in cr if c.mode == int(np.argmax(modal.frequencies == f1)) + 1]
    fine = [] if args.quick else sorted({round(c.input_speed * x, 3) for c in first[:2] for x in
                                        np.linspace(0.94, 1.06, 7)})
    coarse = list(np.linspace(lo, hi, 6 if args.quick else 10))
    speeds_r = sorted(set(fine) | {round(s, 3) for s in coarse})
    rigid_rows = rigid_sweep(text, speeds_r, run_in, dur, mesh_name)
    flex_name = flexible_preset(args.config, args.flexible)
    speeds_f = [round(s, 3) for s in np.linspace(lo, hi, 4 if args.quick else 8)] if flex_name else []
    flexible_rows = (rigid_sweep(load_config(flex_name).source_text, speeds_f, run_in, dur, mesh_name, "flexible")
                     if flex_name else [])
    # the flexible set's own modes (the solver's tangent: compliant contacts, cross-mesh coupling)
    flex_modal = modes(linearise(build_model(load_config(flex_name)))) if flex_name else None
    # resonance peaks of the k-th harmonic amplitudes, against each model's own modes as its
    # HHT-alpha integrator renders them at the step each run used
    peak_rows, labelled = [], []
    for name, rows in (("lumped", lumped_rows), ("rigid", rigid_rows), ("flexible", flexible_rows)):
        if not rows:  # --flexible none: no flexible runs, no flexible modes
            continue
        table, matched = match_peaks(name, rows, flex_modal if name == "flexible" else modal, r_m, sun_teeth=z_s)
        peak_rows += table
        if name == "lumped":
            for sp, k, i in matched:
                kv = np.interp(sp, [r["speed"] for r in rows], [r["kv"] for r in rows])
                labelled.append((sp, kv, f"{k}$f_m$: mode {i}"))
    save_figure(fig_sweep(lumped_rows, rigid_rows, labelled, flexible_rows=flexible_rows), out / "sweep.png",
                overwrite=args.overwrite)
    # tie-back at the configuration's own speed (rigid model, as configured), and the same run
    # sampled at 20 kHz (lines up to 10 kHz unfolded)
    res = flexgear.run(cfg)
    tb_rows, on_lines = tie_back(res, modal, mesh_name, "normal")
    ring = next((m.name for m in model.meshes if m.name.endswith("-ring")), None)
    tb_ring, on_ring = tie_back(res, modal, ring, "y") if ring else ([], [])
    wide_cfg = loads_config(text)
    wide_cfg.simulation.update(output_rate=20000.0)
    wide = flexgear.run(wide_cfg)
    tb_wide, on_wide = tie_back(wide, modal, mesh_name, "normal", n_peaks=40)
    mrows, mh = modal.table()
    lines = [f"# Modes, Campbell diagram and speed sweep: {cfg.title}", "",
             f"Configuration `{args.config}`; input speed {f_in:g} Hz, mesh frequency {r_m*f_in:g} Hz. "
             f"Generated by `studies/speed_sweep_modes.py` in {time.perf_counter()-t0:.0f} s.", "",
             "## Modes of the set linearised at its operating point", "",
             markdown_table(mrows, mh), "",
             *([f"Flexible model (`{flex_name}`), linearised with the solver's tangent stiffness (compliant "
                "contacts solved jointly, coupling between meshes through the gear rims, elastic shafts):", "",
                markdown_table(*flex_modal.table()), ""] if flex_modal is not None else []),
             "## Crossings (Campbell diagram, `campbell.png`)", "",
             ("The mesh harmonics k f_m (the excitation in the carrier frame; the carrier sidebands k f_m +- f_a "
              "are what a fixed sensor hears of it, not crossings of their own). With equally spaced planets the "
              "k-th harmonic excites rotational modes only where k z_s / N is an integer, translational ones where "
              "(k z_s +- 1) / N is, planet modes otherwise (Parker 2000): the other crossings are suppressed."), "",
             markdown_table([[f"{c.input_speed:.2f}", c.label, c.mode, c.mode_type, f"{c.frequency:.0f}",
                              "yes" if c.excited else "no: suppressed by planet phasing"] for c in cr],
                            ["input speed Hz", "line", "mode", "type", "f_n Hz", "excited"]), "",
             "## Resonance peaks of the stepped speed sweep (`sweep.png`)", "",
             f"Amplitude of the k-th mesh harmonic of the `{mesh_name}` force against input speed; a peak at "
             "speed s is a resonance at k f_m(s), compared with the nearest linearised natural frequency among the "
             "modes that harmonic excites (a mode suppressed by planet phasing, above, does not respond to it).",
             "Lumped model: " + f"{len(speeds_l)} speeds; rigid model: {len(speeds_r)} speeds; "
             + (f"flexible model (`{flex_name}`): {len(speeds_f)} speeds, {len(flexible_rows)} finished "
                if flex_name else "flexible model: not run (`--flexible none`, or no flexible preset) ")
             + f"(run-in {run_in} s, {dur} s recorded each). On the coarse flexible grid a peak is only "
             "located to within the grid step. Each model's peaks are matched to the modes of its own "
             "linearisation within 5 % (lumped and rigid: the rigid set's; flexible: the flexible set's, above), "
             "as the HHT-alpha integrator renders them at the step h and alpha each run used (column "
             "`h us`: the flexible presets integrate at 6.25 us, the rigid ones at 25 us; `f_n at h`, "
             "`flexgear.dynamics.modal.analysis.integrated_frequency`: the period grows with omega h, an "
             "8.9 kHz mode runs at 7.6 kHz at 25 us, at 8.79 kHz at 6.25 us); the difference is against that.", "",
             markdown_table(peak_rows, ["model", "harmonic", "speed Hz", "k f_m Hz", "nearest mode", "f_n Hz",
                                        "h us", "f_n at h Hz", "difference %"]) if peak_rows else "(no peaks in range)",
             "",
             "Flexible model, every speed (dynamic factor, RMS of the fluctuation and mesh-harmonic amplitudes "
             "of the same force):", "",
             markdown_table([[f"{r['speed']:.2f}", f"{r['kv']:.3f}", f"{r['rms']:.3g}"]
                             + [f"{r[f'h{k}']:.3g}" for k in range(1, HARMONICS + 1)] for r in flexible_rows],
                            ["speed Hz", "max/mean", "RMS N"] + [f"{k}f_m N" for k in range(1, HARMONICS + 1)])
             if flexible_rows else "(not run)", "",
             "## Tie-back: peaks of the rigid model's spectrum that are not mesh lines", "",
             f"At the configured speed ({f_in:g} Hz), `{mesh_name}` normal force, {res.attrs['duration']:g} s, "
             f"sampled at {res.fs:g} Hz; peaks more than {-NOISE_FLOOR_DB:g} dB below the largest are numerical "
             "noise and left out. Mesh lines and sidebands found among the largest peaks: "
             + ", ".join(f"{lab} ({p.amplitude:.3g} N)" for p, lab in on_lines) + ".", "",
             markdown_table(tb_rows, ["f Hz", "amplitude N", "dB re largest", "explanation"]) if tb_rows else "none", ""]
    if ring:
        lines += [f"`{ring}` vertical force component:", "",
                  "Lines: " + ", ".join(f"{lab} ({p.amplitude:.3g} N)" for p, lab in on_ring) + ".", "",
                  markdown_table(tb_ring, ["f Hz", "amplitude N", "dB re largest", "explanation"]) if tb_ring
                  else "none", ""]
    lines += [f"The same run sampled at {wide.fs:g} Hz (`{mesh_name}` normal force): mesh lines "
              + ", ".join(f"{lab} ({p.amplitude:.3g} N)" for p, lab in on_wide) + ".", "",
              markdown_table(tb_wide, ["f Hz", "amplitude N", "dB re largest", "explanation"]) if tb_wide
              else "none", ""]
    # the same lines in the lumped model at the configured speed (three fidelities, one gear set)
    lres = flexgear.run(lcfg)
    fa_, fm_ = res.attrs["carrier_frequency"], res.attrs["mesh_frequency"]
    cmp_rows = []
    for label, comp in ((mesh_name, "normal"), (ring, "y")):
        if label is None:
            continue
        sig = {}
        for nm_, r_ in (("rigid", res), ("lumped", lres)):
            m_ = r_.meshes[label]
            x = m_.normal_force if comp == "normal" else m_.force_global[:, 1]
            sig[nm_] = amplitude_spectrum(x, r_.fs)
        f_r, A_r = sig["rigid"]
        for ln in (planetary_lines(fa_, fm_, n_harmonics=HARMONICS, n_sidebands=1) if fa_ > 0
                   else spur_lines(fm_, HARMONICS)):
            if ln.kind == "carrier" or ln.freq >= res.fs / 2:
                continue
            a_r = line_amplitude(f_r, A_r, ln.freq, tol_hz=0.5)
            a_l = line_amplitude(*sig["lumped"], ln.freq, tol_hz=0.5)
            if max(a_r, a_l) > 0.01 * ref_amp(res, label, comp):
                cmp_rows.append([label + (" F" if comp == "normal" else " F_y"), ln.label, f"{ln.freq:.0f}",
                                 f"{a_r:.3g}", f"{a_l:.3g}", f"{100 * (a_l - a_r) / a_r:+.0f}"])
    lines += ["## The same lines in the lumped model", "",
              "Amplitudes (N) at the configured speed, rigid model and lumped model (`contact` stiffness "
              f"source), {res.attrs['duration']:g} s each:", "",
              markdown_table(cmp_rows, ["signal", "line", "f Hz", "rigid", "lumped", "difference %"]), ""]
    # the lines near 4 f_m: amplification by the nearest mode
    fm = r_m * f_in
    if HARMONICS * fm < res.fs / 2:
        near = nearest_mode(HARMONICS * fm, modal, tol=0.5, excited=excited_by(modal, HARMONICS, z_s))
        if near:
            i, fn, t = near
            amp = 1 / abs(1 - (HARMONICS * fm / fn) ** 2)
            lines += [f"The {HARMONICS} f_m lines ({HARMONICS*fm:.0f} Hz and its carrier sidebands) lie "
                      f"{100*(fn-HARMONICS*fm)/fn:.0f} % below mode {i} ({t}, {fn:.0f} Hz; strain energy mostly in "
                      f"{modal.dominant_spring(i-1)[0]}): a single-mode amplification 1/|1 - (f/f_n)^2| = {amp:.1f} "
                      "of that harmonic of the mesh excitation, which is why they stand above the lower harmonics; "
                      "the sweep shows the same harmonic peaking where it meets the mode.", ""]
    text_out = "\n".join(lines)
    atomic_write(out / "report.md", lambda p: Path(p).write_text(text_out))
    print(text_out)
    return 0


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
