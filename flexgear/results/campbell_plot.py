"""Campbell diagram figure: natural frequencies (by mode type) against input speed, with the
mesh harmonics k f_m and their crossings: those planet phasing lets excite their mode marked,
the suppressed ones crossed out (:mod:`flexgear.dynamics.modal.campbell`)."""
from __future__ import annotations

import numpy as np

from ..config.faults import set_kinematics
from ..dynamics.modal.campbell import campbell_lines, modal_crossings
from ..style import COLUMN_WIDTH, figure, paper_style

TYPE_STYLE = {"rotational": ("C0", "-"), "translational": ("C1", "--"), "planet": ("C2", "-."), "-": ("0.3", "-")}


def fig_campbell(modal, mesh_ratio: float, speed_range, harmonics: int = 4, fmax: float | None = None,
                 operating: float | None = None, sun_teeth: int | None = None):
    """Campbell diagram of a :class:`~flexgear.dynamics.modal.system.ModalResult`.

    Parameters
    ----------
    mesh_ratio : float
        f_m / f_in (the mesh frequency in the carrier frame).
    sun_teeth : int, optional
        z_s of a planetary set: crossings that planet phasing suppresses
        (:func:`~flexgear.dynamics.modal.campbell.excites`) are crossed out in grey.
    speed_range : (float, float)
        Input speeds [Hz].
    operating : float, optional
        The input speed [Hz] the modes were linearised at, marked by a vertical line.

    Returns
    -------
    (Figure, list of Crossing)
    """
    lo, hi = speed_range
    speeds = np.linspace(0.0, hi, 200)
    cr = modal_crossings(modal, mesh_ratio, speed_range, harmonics, sun_teeth)
    top = fmax or 1.1 * max(max(modal.frequencies), harmonics * mesh_ratio * hi)
    with paper_style():
        fig = figure(COLUMN_WIDTH, 2.8)
        ax = fig.add_subplot(1, 1, 1)
        for label, f in campbell_lines(mesh_ratio, speeds, harmonics).items():
            ax.plot(speeds, f, color="0.2", lw=0.7)
            ax.annotate(f"${label}$", (speeds[-1], f[-1]), fontsize=6, xytext=(2, 0), textcoords="offset points",
                        va="center")
        seen = set()
        for fn, t in zip(modal.frequencies, modal.mode_type):
            if fn <= 0 or fn > top:
                continue
            c, ls = TYPE_STYLE.get(t, TYPE_STYLE["-"])
            ax.axhline(fn, color=c, ls=ls, lw=0.8,
                       label=None if t in seen else ("natural frequency" if t == "-" else t))  # '-': no type
            seen.add(t)
        for c in cr:
            if c.frequency > top:
                continue
            if c.excited:
                ax.plot(c.input_speed, c.frequency, "o", ms=2.5, mfc="none", color="k", mew=0.5)
            else:
                label = None if "suppressed" in seen else "crossing suppressed by planet phasing"
                ax.plot(c.input_speed, c.frequency, "x", ms=2.5, color="0.55", mew=0.5, label=label)
                seen.add("suppressed")
        if operating is not None:
            ax.axvline(operating, color="k", ls=":", lw=0.8, label="operating speed")
            seen.add("operating speed")
        ax.set_xlim(0, hi * 1.12)
        ax.set_ylim(0, top)
        ax.set_xlabel("input speed $f_{in}$ (Hz)")
        ax.set_ylabel("frequency (Hz)")
        if seen:
            ax.legend(loc="upper left")
    return fig, cr


def modal_campbell(modal, cfg, harmonics: int = 4):
    """The Campbell diagram that ``flexgear modal`` writes: the modes of ``modal``, linearised at
    the operating point of the gear-set configuration ``cfg``, against the input speed, from 0 to
    the larger of 1.5 times the operating speed (the mean input frequency, marked) and 1.25 times
    the speed where f_m meets the first elastic mode; the modes up to 1.1 times the highest
    harmonic's frequency at the top speed. Returns (Figure, list of Crossing)."""
    kin = set_kinematics(cfg, 1.0)  # per Hz of the input
    r_m = kin.mesh
    f_in = abs(cfg.input_frequency)
    elastic = [f for f in modal.frequencies if f > 0]
    hi = max(1.5 * f_in, 1.25 * min(elastic) / r_m if elastic else 0.0)
    if hi <= 0.0:
        hi = 1.0  # no elastic mode and the set at rest
    z_s = cfg.gears["sun"].z if cfg.kind == "planetary" else None
    return fig_campbell(modal, r_m, (0.02 * hi, hi), harmonics=harmonics, fmax=1.1 * harmonics * r_m * hi,
                        operating=f_in if f_in > 0 else None, sun_teeth=z_s)
