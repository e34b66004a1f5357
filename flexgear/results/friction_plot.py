"""Tooth friction of a run (``[lubrication]``) as researchers plot it: the friction force, the
pairs' sliding speeds and film thickness ratios over a few mesh periods, with the pitch-point
crossings, where the sliding and the friction reverse, marked
(:func:`~flexgear.results.friction_plot.fig_friction`; written by
:func:`~flexgear.results.plots.paper_figures` as ``friction_<mesh>.png``).
"""
from __future__ import annotations

import numpy as np

from ..style import COLUMN_WIDTH, MARK_COLOR, ZOOM_PERIODS, figure, styled

#: one line style per recorded contact slot (none red and dotted: the pitch-point marks are)
_PAIR_STYLES = [dict(color="k", linestyle="-"), dict(color="#1f5fa8", linestyle="--"),
                dict(color="#2e8b57", linestyle="-."), dict(color="#8e44ad", linestyle=(0, (5, 1, 1, 1)))]
#: [m] the least jump of a slot's contact position that is a handover to the next pair, not
#: the pair's motion between two samples (a handover jumps by about the path's length)
HANDOVER = 1e-3


def pitch_crossings(result, mesh: str) -> np.ndarray:
    """Times [s] where a recorded contact of ``mesh`` crosses the pitch point: its position
    ``contact_position`` changes sign within a slot between two samples without a handover
    (:data:`HANDOVER`), linearly interpolated; empty without tooth friction."""
    s = getattr(result.meshes[mesh], "contact_position", None)
    if s is None:
        return np.zeros(0)
    t = np.asarray(result.time, dtype=float)
    a, b = s[:-1], s[1:]
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(a) & np.isfinite(b) & (a * b < 0) & (np.abs(a - b) < HANDOVER)
    k, c = np.nonzero(ok)
    tc = t[k] + (t[k + 1] - t[k]) * a[k, c] / (a[k, c] - b[k, c])
    return np.unique(np.round(np.sort(tc), 9))


@styled
def fig_friction(result, mesh: str, periods: float = ZOOM_PERIODS, width: float = COLUMN_WIDTH):
    """Tooth friction of ``mesh`` over the first ``periods`` mesh periods of the record: (a) the
    friction force along the flank tangent, (b) each tooth pair's sliding speed and, with a
    lubricant, (c) each pair's film thickness ratio lambda with the bounds of mixed lubrication
    (1 and 3); the pitch-point crossings (:func:`pitch_crossings`) dotted in every panel: there
    the sliding speed and with it the friction change sign."""
    m = result.meshes[mesh]
    t = np.asarray(result.time, dtype=float)
    fm = float(result.attrs.get("mesh_frequency", 0.0))
    z0, z1 = (t[0], t[-1]) if not fm > 0 or (t[-1] - t[0]) * fm <= periods else (t[0], t[0] + periods / fm)
    keep = (t >= z0) & (t <= z1)
    film = getattr(m, "film_ratio", None)
    fig = figure(width, 4.4 if film is not None else 3.2)
    axes = fig.subplots(3 if film is not None else 2, 1, sharex=True)
    ms = 1e3 * t[keep]
    axes[0].plot(ms, m.friction_force[keep], color="k", lw=0.8)
    axes[0].set_ylabel("friction (N)")
    axes[0].set_title(f"(a) Friction force, {mesh} (dotted: pitch point)", loc="left")
    slots = [j for j in range(m.sliding_speed.shape[1]) if np.isfinite(m.sliding_speed[keep, j]).any()]
    position = m.contact_position[keep]

    def pair_line(values, j):  # a slot's record, broken where the slot passes to the next pair
        cut = np.nonzero(np.abs(np.diff(position[:, j])) >= HANDOVER)[0] + 1
        return np.insert(ms, cut, np.nan), np.insert(values[keep, j], cut, np.nan)

    for n, j in enumerate(slots):  # a line per recorded contact slot (a tooth pair while it is in mesh)
        axes[1].plot(*pair_line(m.sliding_speed, j), **_PAIR_STYLES[n % len(_PAIR_STYLES)], lw=0.8)
    axes[1].axhline(0.0, color="0.5", lw=0.4)
    axes[1].set_ylabel("sliding (m/s)")
    axes[1].set_title("(b) Sliding speed of each tooth pair", loc="left")
    if film is not None:
        for n, j in enumerate(slots):
            axes[2].plot(*pair_line(film, j), **_PAIR_STYLES[n % len(_PAIR_STYLES)], lw=0.8)
        top = float(np.nanmax(film[keep], initial=0.0))
        for bound in (1.0, 3.0):
            if bound < 1.5 * top:
                axes[2].axhline(bound, color="0.5", lw=0.4, ls="--")
        axes[2].set_ylim(0.0, None)
        axes[2].set_ylabel(r"$\lambda$ (-)")
        axes[2].set_title(r"(c) Film thickness ratio $\lambda$ (boundary below 1, mixed 1 to 3)", loc="left")
    for tc in pitch_crossings(result, mesh):
        if z0 <= tc <= z1:
            for ax in axes:
                ax.axvline(1e3 * tc, color=MARK_COLOR, ls=":", lw=0.6)
    axes[-1].set_xlabel("time (ms)")
    axes[-1].set_xlim(1e3 * z0, 1e3 * z1)
    return fig
