"""Campbell diagram figure: natural frequencies (by mode type) against input speed, with the
mesh harmonics and carrier sidebands, crossings marked."""
from __future__ import annotations

import numpy as np

from ..dynamics.modal.campbell import campbell_lines, crossings
from ..style import COLUMN_WIDTH, figure, paper_style

TYPE_STYLE = {"rotational": ("C0", "-"), "translational": ("C1", "--"), "planet": ("C2", "-."), "-": ("0.3", "-")}


def fig_campbell(modal, mesh_ratio: float, carrier_ratio: float, speed_range, harmonics: int = 4,
                 sidebands: int = 1, fmax: float | None = None):
    """Campbell diagram of a :class:`~flexgear.dynamics.modal.system.ModalResult`.

    Parameters
    ----------
    mesh_ratio, carrier_ratio : float
        f_m / f_in and f_a / f_in.
    speed_range : (float, float)
        Input speeds [Hz].

    Returns
    -------
    (Figure, list of Crossing)
    """
    lo, hi = speed_range
    speeds = np.linspace(0.0, hi, 200)
    cr = crossings(modal.frequencies, modal.mode_type, mesh_ratio, carrier_ratio, speed_range, harmonics,
                   sidebands)
    top = fmax or 1.1 * max(max(modal.frequencies), harmonics * mesh_ratio * hi)
    with paper_style():
        fig = figure(COLUMN_WIDTH, 2.8)
        ax = fig.add_subplot(1, 1, 1)
        for label, f in campbell_lines(mesh_ratio, carrier_ratio, speeds, harmonics, sidebands).items():
            main = "+" not in label and "-" not in label
            ax.plot(speeds, f, color="0.2" if main else "0.6", lw=0.7 if main else 0.4,
                    ls="-" if main else ":")
            if main:
                ax.annotate(f"${label.replace('f_m', 'f_m')}$", (speeds[-1], f[-1]), fontsize=6,
                            xytext=(2, 0), textcoords="offset points", va="center")
        seen = set()
        for fn, t in zip(modal.frequencies, modal.mode_type):
            if fn <= 0 or fn > top:
                continue
            c, ls = TYPE_STYLE.get(t, TYPE_STYLE["-"])
            ax.axhline(fn, color=c, ls=ls, lw=0.8, label=t if t not in seen else None)
            seen.add(t)
        for c in cr:
            if c.frequency <= top:
                ax.plot(c.input_speed, c.frequency, "o", ms=2.5, mfc="none", color="k", mew=0.5)
        ax.set_xlim(0, hi * 1.12)
        ax.set_ylim(0, top)
        ax.set_xlabel("input speed $f_{in}$ (Hz)")
        ax.set_ylabel("frequency (Hz)")
        if seen:
            ax.legend(loc="upper left")
    return fig, cr
