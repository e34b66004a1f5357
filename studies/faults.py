"""Faulty gears: healthy against each fault kind at three severities, spur pair and MERCURY 1-A.

Runs batches (``flexgear.app.batch``) over the ``[[faults]]`` list (or the ``[errors]`` block) of
the presets ``spur_pair`` and ``mercury_1a``, one batch per set, fidelity and input kind, each with
its healthy case (every case with the mesh damping ratio 0.05 instead of the paper's C:
:func:`base_file`; the flexible groups on the presets ``spur_pair_flexible`` and
``mercury_1a_flexible``), then draws in the paper's style:

- ``<case group>_time.png``: transmission error (along the line of action, from the gears' angles
  as shaft encoders measure it: :func:`transmission_error`) and normal mesh force in a window of
  a few mesh periods around the faulty tooth's engagement, healthy and the three severities
  overlaid; the window is centred on the largest deviation of the most severe case from the
  healthy run (same time grid), which is where the faulty tooth meshes;
- ``<case group>_spectrum.png``: normal-force spectra, healthy and most severe, the fault
  frequencies (``/faults``) and mesh lines marked (``flexgear.results.plots.plot_spectrum``);

and ``report.md``: per case, RMS (about the mean), peak (largest deviation from the mean) and
kurtosis (Pearson, 3 for a Gaussian) of the transmission error and of the normal mesh force.

Fidelities. The rigid multi-body model simulates spalls, chips and missing teeth in the faulty
tooth's contact tables, cracks as a per-tooth factor of the contact law from the crack FE, and
every error. The lumped model runs every case it can, its mesh stiffness tables carrying the
faulty tooth's cycles and the errors. The flexible model runs every group whose fault it takes (all
of them: whole-width spalls, chips and missing teeth cut from the FE body, cracks of the
flexible gears (ring included) as slits, the pin error in the contact geometry), at the
flexible presets' FE mesh (with ``--quick``: level
0 and a 25 us step) and without the flexible presets' shafts (:func:`without_shafts`: on the
rigid presets' supports, so that the fidelities differ in their gears alone). The rigid and lumped
models' contact is the paper's IMPACT law, softer than the FE mesh (static approach on MERCURY
1-A about 2.8 um against the flexible model's 0.74 um, measured by a trial), so their
transmission errors are the larger; and a crack's factor on that law, rho^e, makes the pair rho
times as stiff at equal force but shares the load in double contact at equal approach in the ratio
rho^e, not rho: the rigid model's cracked tooth sheds 20-30 % more of its load than the
flexible model's on the same supports (docs, theory *Crack*). The lumped model refuses a missing tooth that opens the mesh (no contact
off the path of contact: nothing would stop the driven gear turning back; the report lists those
cases as not run, with the reason). Severities (tooth 0, loaded flank "left" unless said):

- spur pair (pinion tooth 0): missing down to height fractions 0.75, 0.5, 0; spall between the
  radii 23.5 and 24.5 mm, 10, 25, 50 um deep; chip of 0.5, 1.0, 1.5 mm along the profile and
  0.2, 0.4, 0.6 mm along the tip (half the tip land is 0.72 mm); crack 0.5, 1.0, 1.5 mm deep at
  45 deg;
- MERCURY 1-A: sun crack and planet 1 crack (as the pinion's), ring spall 25 um deep and 0.5, 1, 2 mm
  long around the radius 66 mm (deeper than the mesh approach, about 2 um: its length sets the
  severity), missing sun tooth (as the spur pair's), planet 1 pin error 0.5, 1, 2 um tangential
  (ahead; 10 um thinning on every gear of that group, healthy included, so that the set does not
  jam; 10 um and more unload planet 1 fully); each rigid, lumped and flexible.

The batches are resumable: running the study again continues them.

Usage::

    python studies/faults.py -o out/faults [--quick] [--only GROUP ...] [--workers N] [--overwrite]

Groups are named ``<set>_<fidelity>_<fault>`` (``spur_rigid_missing_pinion``, ...,
``mercury_lumped_pin_planet1``); ``--only`` runs a few of them (with ``--quick``: short records).

``--quick``: the spur pair, healthy against the missing tooth, the spall and the crack (rigid)
and the missing tooth (flexible, FE level 0 and a 25 us step), one pinion turn (0.1 s) after a
0.06 s run-in.
"""
from __future__ import annotations

import argparse
import dataclasses
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import tomli_w
from scipy.stats import kurtosis

from flexgear.app.batch import run_batch
from flexgear.app.console import markdown_table
from flexgear.config import load_config
from flexgear.config.faults import mesh_pairs
from flexgear.app.sweep import loads_sweep
from flexgear.config import preset_path
from flexgear.files import check_targets
from flexgear.results.plots import plot_spectrum
from flexgear.results.store import load
from flexgear.style import DOUBLE_WIDTH, figure, paper_style, save_figure
from flexgear.app.console import run_command

SEVERITIES = ("low", "medium", "high")
ZETA = 0.05  # mesh damping ratio of every case (see base_file)
PRESETS = {"spur": "spur_pair", "mercury": "mercury_1a"}
FIDELITIES = ("rigid", "lumped", "flexible")
#: the flexible groups' overrides with --quick (also with --only): the coarsest FE mesh, and the 25 us step of the
#: rigid presets (the mesh damping ratio ZETA damps the stiff flexible mesh mode the flexible
#: presets' 6.25 us step resolves; tests/test_flexible_faults.py runs so)
QUICK_FLEXIBLE = (("flexible.level", 0), ("flexible.cutoff", 100e3), ("flexible.dynamic_cutoff", 0.0),
                  ("simulation.step", 2.5e-5))
TITLES = {"spur": "spur pair 24/21", "mercury": "MERCURY 1-A"}


@dataclass(frozen=True)
class Group:
    """One fault kind on one set at one fidelity: three severities against the healthy case."""
    set: str
    fidelity: str          # "rigid" | "lumped" | "flexible"
    name: str              # e.g. "missing_sun"
    mesh: str              # the mesh shown
    what: str              # the description in the report
    faults: tuple = ()     # per severity: a list of [[faults]] tables
    errors: tuple = ()     # per severity: an [errors] table
    note: str = ""         # what the report says about this group's model
    extra: tuple = ()      # further (key, value) overrides of every case of the group, healthy included

    @property
    def key(self) -> str:
        return f"{self.set}_{self.fidelity}_{self.name}"

    @property
    def model(self) -> str:
        """The configuration's ``model``: a flexible group is the rigid multi-body model with the
        flexible preset's ``[flexible]`` gears."""
        return "rigid" if self.fidelity == "flexible" else self.fidelity

    @property
    def preset(self) -> str:
        return PRESETS[self.set] + ("_flexible" if self.fidelity == "flexible" else "")

    @property
    def axis(self) -> str:
        return "errors" if self.errors else "faults"

    @property
    def values(self) -> list:
        """The swept values: healthy first, then the three severities."""
        return [{}] + list(self.errors) if self.errors else [[]] + [list(f) for f in self.faults]


LUMPED_MISSING = (
    "Lumped model: where the missing tooth leaves no pair on the path of contact the mesh is open, and "
    "nothing would stop the load turning the driven gear back through the backlash: the lumped model has "
    "no contact off the path of contact (the early corner contact of the next tooth that stops it in the "
    "rigid model). It refuses such cases (listed above as not run); compare the rigid rows.")


#: MERCURY 1-A's ring spall: 25 um deep, its severity the length along the radius [m]. At the set's
#: light load the mesh approach is about 2 um, so any spall deeper than a few um takes the whole
#: spalled strip out of contact: depth no longer matters (25 and 50 um deep give the same run).
RING_SPALL_DEPTH = 25e-6
RING_SPALL_LENGTHS = (0.5e-3, 1.0e-3, 2.0e-3)

PIN_THINNING = 10e-6  # m per gear: normal backlash 2 x 10 um x cos(20 deg) = 19 um per mesh > 2 x 2 um
PIN_NOTE = (
    "Every case of this group (healthy included) has 10 um thinning on every gear: with the presets' zero "
    "backlash one planet's pin error cannot be taken up by the sun and carrier (they are set by the other "
    "planets), so the planet's back flanks close and the set jams with a preload (rigid model, 10 um: mean "
    "sun-planet forces 407 / 559 / 559 N against 237 N healthy). The errors are of the order of the static "
    "mesh approach (about 2 um at MERCURY 1-A's 237 N per mesh): from 10 um on, planet 1 carries nothing.")
LUMPED_PIN_NOTE = PIN_NOTE + (
    " Lumped model: with this backlash the set has two steady states at 30 Hz, teeth in contact or the planets "
    "rattling across the backlash (back-flank forces near -50 N on every sun-planet mesh). Both models rattle "
    "during the start-up ramp; the rigid model then settles into contact up to 1 um (at 2 um planet 1 touches "
    "its back flank, -14 N), the lumped model only below "
    "about 0.1 um (0.25 um and more stay rattling). Which state a run ends in depends on how it starts: compare "
    "the lumped rows with the rigid ones, and the mean forces with the statics (tests/test_faults_lumped.py).")


def tooth(gear: str, kind: str, planet: int | None = None, flank: str | None = "left", **kw) -> dict:
    d = {"kind": kind, "gear": gear, "tooth": 0}
    if planet is not None:
        d["planet"] = planet
    if flank is not None:
        d["flank"] = flank
    return d | kw


def missing(gear):
    return tuple([tooth(gear, "missing", flank=None, height_fraction=h)] for h in (0.75, 0.5, 0.0))


def spall(gear, r0, r1, planet=None):
    return tuple([tooth(gear, "spall", planet, start_radius=r0, end_radius=r1, depth=d)]
                 for d in (10e-6, 25e-6, 50e-6))


def spall_extent(gear, centre, depth=RING_SPALL_DEPTH):
    """Spalls ``depth`` deep centred on the radius ``centre`` [m], of the lengths RING_SPALL_LENGTHS
    along the radius: the severity of a spall deeper than the mesh approach is its extent."""
    return tuple([tooth(gear, "spall", start_radius=centre - w / 2, end_radius=centre + w / 2, depth=depth)]
                 for w in RING_SPALL_LENGTHS)


def chip(gear):
    return tuple([tooth(gear, "chip", profile_size=p, tip_size=t)]
                 for p, t in ((0.5e-3, 0.2e-3), (1.0e-3, 0.4e-3), (1.5e-3, 0.6e-3)))


def crack(gear, planet=None):
    return tuple([tooth(gear, "crack", planet, depth=d, angle_deg=45.0)] for d in (0.5e-3, 1.0e-3, 1.5e-3))


def pin_error(planet="planet1"):
    return tuple({"pin": {planet: {"tangential": t}}} for t in (0.5e-6, 1e-6, 2e-6))


def groups(quick: bool) -> list[Group]:
    spur_m, sun_m, ring_m = "pinion-wheel", "sun-planet1", "planet1-ring"
    out = []
    for fid in FIDELITIES:
        out += [Group("spur", fid, "missing_pinion", spur_m, "pinion tooth 0 missing to height 0.75 / 0.5 / 0",
                      faults=missing("pinion"), note=LUMPED_MISSING if fid == "lumped" else ""),
                Group("spur", fid, "spall_pinion", spur_m, "pinion tooth 0 spall 23.5-24.5 mm, 10 / 25 / 50 um deep",
                      faults=spall("pinion", 23.5e-3, 24.5e-3))]
    def spur_crack(fid):
        return Group("spur", fid, "crack_pinion", spur_m, "pinion tooth 0 root crack 0.5 / 1.0 / 1.5 mm, 45 deg",
                     faults=crack("pinion"))

    if quick:
        return out[:2] + [out[4], spur_crack("rigid")]
    out += [Group("spur", fid, "chip_pinion", spur_m, "pinion tooth 0 chip 0.5 / 1.0 / 1.5 mm (profile)",
                  faults=chip("pinion")) for fid in FIDELITIES]
    for fid in FIDELITIES:
        out += [spur_crack(fid),
                Group("mercury", fid, "crack_sun", sun_m, "sun tooth 0 root crack 0.5 / 1.0 / 1.5 mm, 45 deg",
                      faults=crack("sun")),
                Group("mercury", fid, "crack_planet", sun_m,
                      "planet 1 tooth 0 root crack (sun-side flank) 0.5 / 1.0 / 1.5 mm, 45 deg",
                      faults=crack("planet", planet=1))]
    for fid in FIDELITIES:
        out += [Group("mercury", fid, "spall_ring", ring_m,
                      "ring tooth 0 spall 25 um deep, 0.5 / 1 / 2 mm long (radii about 66 mm)",
                      faults=spall_extent("ring", 66.0e-3)),
                Group("mercury", fid, "missing_sun", sun_m, "sun tooth 0 missing to height 0.75 / 0.5 / 0",
                      faults=missing("sun"), note=LUMPED_MISSING if fid == "lumped" else ""),
                Group("mercury", fid, "pin_planet1", sun_m, "planet 1 pin 0.5 / 1 / 2 um ahead (tangential)",
                      errors=pin_error(), note=LUMPED_PIN_NOTE if fid == "lumped" else PIN_NOTE, extra=(("gear_defaults.thinning", PIN_THINNING),))]
    return out


def base_file(out: Path, set_name: str, preset: str | None = None) -> Path:
    """The set's preset with the mesh damping ratio ZETA instead of the paper's C (written to
    ``out``). The paper's C = 3000 N s/mm is a damping ratio of about 50 on the spur pair: with
    the contact losses of a missing tooth the lumped model's step diverges under it; gear-dynamics
    models put the mesh damping at a few percent of critical (``studies/rigid_vs_flexible.py``).
    All fidelities use the same ratio so that they compare. ``preset``: another preset of the set
    (default ``PRESETS[set_name]``; the flexible groups': ``Group.preset``)."""
    preset = preset or PRESETS[set_name]
    text = preset_path(preset).read_text()
    text, n = re.subn(r"^damping = .*$", f"damping_ratio = {ZETA}", text, count=1, flags=re.M)
    assert n == 1, preset
    if preset != PRESETS[set_name]:
        text = without_shafts(text)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"base_{preset}.toml"
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path.resolve()


def without_shafts(text: str) -> str:
    """A preset's text without its ``[shafts.*]`` tables: the flexible presets' shafts float the
    sun and change the planets' load sharing (a trial's 1 mm sun crack, flexible MERCURY 1-A: the
    cracked tooth shed 3.5 % of its load on the shafts, 5.8 % on the rigid preset's supports, the
    rigid model 7.0 %), so the flexible groups run on the rigid presets' supports and the three
    fidelities differ in their gears alone."""
    out, skip = ["# faults study: the preset without its [shafts] tables (the rigid preset's supports)\n"], False
    for line in text.splitlines(keepends=True):
        if line.startswith("["):
            skip = line.startswith("[shafts")
        if not skip:
            out.append(line)
    return "".join(out)


def sweep_text(g: Group, duration: float, run_in: float, base: Path | str | None = None) -> str:
    doc = {"title": f"faults study: {g.key}", "base": str(base or g.preset),
           "set": {"model": g.model, "simulation.duration": duration, "simulation.run_in": run_in} | dict(g.extra),
           "grid": {g.axis: g.values}}
    return tomli_w.dumps(doc)


def indicators(x: np.ndarray) -> tuple[float, float, float]:
    """RMS about the mean, peak deviation from the mean and Pearson kurtosis of a signal."""
    d = np.asarray(x, dtype=float) - np.mean(x)
    return float(np.sqrt(np.mean(d * d))), float(np.max(np.abs(d))), float(kurtosis(x, fisher=False))


CASES = ("healthy",) + SEVERITIES


def transmission_error(res, mesh: str, cfg) -> np.ndarray:
    """Transmission error of ``mesh`` along its line of action [m], mean removed, from the gears'
    angles relative to the carrier (``cfg``'s base radii r_b): r_b,a theta_a + r_b,b theta_b for
    an external pair, r_b,a theta_a - r_b,b theta_b for an internal one, constant for perfect
    rigid involutes. Unlike the contact's approach (``te_mean`` of the batch summary) it sees the
    material a fault removed: the gears turn on until another pair takes the load."""
    a, b, pair = mesh_pairs(cfg)[mesh]
    frame = res.bodies["carrier"].angle if "carrier" in res.bodies else 0.0
    angle = {n: (res.bodies[n].angle if n in res.bodies else 0.0) - frame for n in (a, b)}
    te = pair.g1.rb * angle[a] + (-1.0 if pair.internal else 1.0) * pair.g2.rb * angle[b]
    return te - np.mean(te)


def case_rows(g: Group, results: list, severities=CASES) -> list[dict]:
    rows = []
    cfg = load_config(g.preset)
    for sev, res in zip(severities, results):
        m = res.meshes[g.mesh]
        te = indicators(transmission_error(res, g.mesh, cfg) * 1e6)
        f = indicators(m.normal_force)
        rows.append({"group": g.key, "severity": sev, "te": te, "force": f})
    return rows


def fault_window(g: Group, results: list, periods: float = 3.0) -> tuple[float, float]:
    """A window of ``periods`` mesh periods each side of the most severe case's largest force
    deviation from the healthy case (where the faulty tooth meshes)."""
    healthy, worst = results[0], results[-1]
    a, b = worst.meshes[g.mesh].normal_force, healthy.meshes[g.mesh].normal_force
    n = min(a.size, b.size)
    t0 = worst.time[int(np.argmax(np.abs(a[:n] - b[:n])))]
    half = periods / worst.attrs["mesh_frequency"]
    return t0 - half, t0 + half


def fig_time(g: Group, results: list, severities=CASES):
    fig = figure(DOUBLE_WIDTH, 3.6)
    ax_te, ax_f = fig.subplots(2, 1, sharex=True)
    t0, t1 = fault_window(g, results)
    cfg = load_config(g.preset)
    for sev, res, style in zip(severities, results, ("k-", "-", "--", ":")):
        t = res.time
        sel = (t >= t0) & (t <= t1)
        m = res.meshes[g.mesh]
        ax_te.plot(1e3 * t[sel], 1e6 * transmission_error(res, g.mesh, cfg)[sel], style, lw=0.8, label=sev)
        ax_f.plot(1e3 * t[sel], m.normal_force[sel], style, lw=0.8, label=sev)
    ax_te.set_ylabel("TE along LoA (um, mean removed)")
    ax_f.set_ylabel(f"normal force {g.mesh} (N)")
    ax_f.set_xlabel("time (ms)")
    ax_te.set_title(f"{TITLES[g.set]}, {g.fidelity}: {g.what}")
    ax_te.legend(ncol=4)
    return fig


def fig_spectrum(g: Group, results: list, severities=CASES):
    fig = figure(DOUBLE_WIDTH, 4.0)
    top, bottom = fig.subplots(2, 1, sharex=True)
    fmax = 4.2 * results[0].attrs["mesh_frequency"]
    plot_spectrum(results[0], g.mesh, component="normal", fmax=fmax, ax=top, db=True)
    plot_spectrum(results[-1], g.mesh, component="normal", fmax=fmax, ax=bottom, db=True,
                  label_kinds=("mesh", "fault"))
    top.set_title(f"{TITLES[g.set]}, {g.fidelity}: healthy")
    bottom.set_title(f"{g.what}: {severities[len(results) - 1]}")
    return fig


def report_table(rows: list[dict]) -> str:
    return markdown_table(
        [[r["severity"], *(f"{v:.4g}" for v in r["te"]), *(f"{v:.4g}" for v in r["force"])] for r in rows],
        ["severity", "TE RMS um", "TE peak um", "TE kurtosis", "F RMS N", "F peak N", "F kurtosis"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", "--out", dest="output", default="out/faults")
    ap.add_argument("--quick", action="store_true",
                    help="spur pair, rigid missing tooth and spall, flexible missing tooth (FE level 0), 0.1 s")
    ap.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    ap.add_argument("--only", nargs="+", metavar="GROUP",
                    help="run only these case groups (e.g. mercury_rigid_missing_sun; default: all)")
    ap.add_argument("--overwrite", action="store_true", help="replace the figures and report")
    args = ap.parse_args(argv)
    out = Path(args.output)
    gs = groups(args.quick and not args.only)
    if args.only:  # any group, with --quick's short records if asked
        unknown = sorted(set(args.only) - {g.key for g in gs})
        if unknown:
            ap.error(f"--only {' '.join(unknown)}: no such group; groups: {', '.join(g.key for g in gs)}")
        gs = [g for g in gs if g.key in args.only]
    if args.quick:
        gs = [dataclasses.replace(g, extra=g.extra + QUICK_FLEXIBLE) if g.fidelity == "flexible" else g for g in gs]
    figures = [f"{g.key}_{k}.png" for g in gs for k in ("time", "spectrum")]
    check_targets([out / f for f in figures + ["report.md"]], args.overwrite)
    duration, run_in = (0.1, 0.06) if args.quick else (1.0, 0.2)
    bases = {(g.set, g.preset): base_file(out, g.set, g.preset) for g in gs}
    sweeps = [loads_sweep(sweep_text(g, duration, run_in, bases[g.set, g.preset]), source=f"faults study {g.key}")
              for g in gs]  # all validated before anything runs
    report = [f"# Faults study ({'quick: ' if args.quick else ''}{duration} s records after a {run_in} s run-in)", "",
              "TE: transmission error along the line of action from the gears' angles, mean removed (um; "
              "not the contact's approach, which cannot see the material a fault removes); F: normal mesh force "
              "(N). "
              "RMS about the mean, peak = largest deviation from the mean, kurtosis = Pearson's (3: Gaussian). "
              f"Presets with a mesh damping ratio of {ZETA} instead of the paper's C (the lumped mesh chatters "
              "under C = 3000 N s/mm).", "",
              "Fidelities: the rigid model runs spalls, chips and missing teeth (contact tables), cracks (a "
              "per-tooth factor of the contact law from the crack FE) and the pin errors; the lumped model runs "
              "every case that leaves a tooth pair on the path of contact; the flexible model (FE gears) runs them "
              "in the FE bodies and the contact tables, on the rigid presets' supports (the flexible presets "
              "without their shafts, which float the sun and change the planets' load sharing). The rigid and "
              "lumped models' IMPACT contact is softer than the FE mesh, so their TE is the larger, and a crack "
              "sheds 20-30 % more of the tooth's load there than in the flexible model (its factor rho^e on the "
              "contact law shares the load at equal approach in the ratio rho^e, the FE in the ratio rho): "
              "compare the fidelities' trends, not their levels.", ""]
    for g, sweep in zip(gs, sweeps):
        batch_dir = out / g.key
        r = run_batch(sweep, batch_dir, workers=args.workers)
        if r.failed or r.pending:
            print(f"{g.key}: {r.failed} case(s) failed; see {r.summary}", file=sys.stderr)
        recs = sorted(r.table.records(), key=lambda x: x["case"])
        report += [f"## {TITLES[g.set]}, {g.fidelity}: {g.what} (mesh {g.mesh})", ""]
        done = [x for x in recs if x["status"] == "done"]
        if len(done) < len(recs):
            report += ["Not run: " + "; ".join(f"{CASES[x['case']]}: {x['status']}"
                                              + (f" ({x['error']})" if x.get("error") else "")
                                              for x in recs if x["status"] != "done"), ""]
        if len(done) < 2 or done[0]["case"] != 0:  # nothing to compare with the healthy case
            continue
        results = [load(batch_dir / x["file"]) for x in done]
        severities = [CASES[x["case"]] for x in done]
        report += [report_table(case_rows(g, results, severities)), ""] + ([g.note, ""] if g.note else []) + \
            [f"Batch directory: `{batch_dir}`.", ""]
        with paper_style():
            save_figure(fig_time(g, results, severities), out / f"{g.key}_time.png", overwrite=args.overwrite)
            save_figure(fig_spectrum(g, results, severities), out / f"{g.key}_spectrum.png",
                        overwrite=args.overwrite)
    text = "\n".join(report)
    (out / "report.md").write_text(text)
    print(text)


if __name__ == "__main__":
    sys.exit(run_command(main, Path(__file__).stem))
