"""Tooth friction of a run (``[lubrication]``) as researchers plot it: the friction force, the
pairs' sliding speeds and film thickness ratios over a few mesh periods, each pair followed
through the solver's contact slots (:func:`~flexgear.results.friction_plot.pair_tracks`), with
the pitch-point crossings, where the sliding and the friction reverse, marked
(:func:`~flexgear.results.friction_plot.fig_friction`; written by
:func:`~flexgear.results.plots.paper_figures` as ``friction_<mesh>.png``).
"""
from __future__ import annotations

import numpy as np

from ..style import COLUMN_WIDTH, MARK_COLOR, ZOOM_PERIODS, figure, styled

#: line styles of successive tooth pairs, alternating (none red and dotted: the pitch-point marks are)
_PAIR_STYLES = [dict(color="k", linestyle="-"), dict(color="#1f5fa8", linestyle="--")]
#: [m] the least jump of a slot's contact position that is a handover to the next pair, not
#: the pair's motion between two samples (a handover jumps by about the path's length)
HANDOVER = 1e-3


def pitch_crossings(result, mesh: str) -> np.ndarray:
    """Times [s] where a recorded tooth pair of ``mesh`` crosses the pitch point: its contact
    position ``contact_position`` changes sign between two of its samples (the pair followed
    through the slots, :func:`pair_tracks`), linearly interpolated; empty without tooth friction."""
    s = getattr(result.meshes[mesh], "contact_position", None)
    if s is None:
        return np.zeros(0)
    return _crossings(np.asarray(result.time, dtype=float), s, pair_tracks(s))


def _crossings(t: np.ndarray, s: np.ndarray, tracks) -> np.ndarray:
    """Times [s] where the tracked pairs' positions ``s`` change sign, linearly interpolated."""
    out = []
    for track in tracks:
        k, c = track[:, 0], track[:, 1]
        a, b = s[k[:-1], c[:-1]], s[k[1:], c[1:]]
        i = np.nonzero(a * b < 0)[0]
        out.append(t[k[i]] + (t[k[i + 1]] - t[k[i]]) * a[i] / (a[i] - b[i]))
    return np.unique(np.round(np.sort(np.concatenate(out)), 9)) if out else np.zeros(0)


#: samples a tooth pair may miss in the record (unloaded for an instant, as by the impact of
#: the next pair's entry) and still be followed as the same pair
MAX_GAP = 3


def pair_tracks(position: np.ndarray) -> list[np.ndarray]:
    """Each tooth pair's samples in the record of contact slots ``position`` (n, S) [m] (nan: no
    loaded pair): a list, in order of entry (positions grow along the path), of (k, 2) int
    arrays of (sample, slot). A pair keeps on at the contact position nearest to where its
    motion leads, within :data:`HANDOVER`, whichever slot holds it then (a solver's slots shift
    as pairs enter and leave), across up to :data:`MAX_GAP` samples without it."""
    tracks, live = [], {}  # live: track index -> (sample, position, position change per sample)
    for k, row in enumerate(position):
        free = [j for j in range(row.size) if np.isfinite(row[j])]
        for i, (k0, s0, ds) in sorted(live.items(), key=lambda kv: kv[1][1]):
            if k - k0 > MAX_GAP + 1:
                del live[i]
                continue
            guess = s0 + ds * (k - k0)
            near = [j for j in free if abs(row[j] - guess) < HANDOVER]
            if near:
                j = min(near, key=lambda j: abs(row[j] - guess))
                free.remove(j)
                tracks[i].append((k, j))
                live[i] = (k, row[j], (row[j] - s0) / (k - k0) if len(tracks[i]) > 1 else 0.0)
        for j in sorted(free, key=lambda j: -row[j]):  # pairs entering, the one furthest along first
            tracks.append([(k, j)])
            live[len(tracks) - 1] = (k, row[j], 0.0)
    return [np.array(tr, dtype=int) for tr in tracks]


def _track_line(ms, values, track):
    """(x, y) of a pair's track, broken (nan) where it misses samples."""
    k = track[:, 0]
    x, y = ms[k], values[k, track[:, 1]]
    cut = np.nonzero(np.diff(k) > 1)[0] + 1
    return np.insert(x, cut, np.nan), np.insert(y, cut, np.nan)


@styled
def fig_friction(result, mesh: str, periods: float = ZOOM_PERIODS, width: float = COLUMN_WIDTH):
    """Tooth friction of ``mesh`` over the first ``periods`` mesh periods of the record: (a) the
    friction force along the flank tangent, (b) each tooth pair's sliding speed and, with a
    lubricant, (c) each pair's film thickness ratio lambda with the bounds of mixed lubrication
    (1 and 3; nan, no line, at a tip-corner contact off the involutes: :mod:`flexgear.results.film`);
    successive tooth pairs alternate solid and dashed lines in (b) and (c) (the legend says so), so
    that two pairs in contact at once are told apart; the pitch-point crossings
    (:func:`pitch_crossings`) dotted in every panel: there the sliding speed and with it the
    friction change sign."""
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
    axes[0].set_ylabel("Friction force\n[N]")
    axes[0].set_title(f"(a) Friction force, {mesh} (dotted: pitch point)", loc="left")
    position = m.contact_position[keep]
    tracks = pair_tracks(position)  # of the window only, not the whole record
    for n, track in enumerate(tracks):  # one line per tooth pair, its style kept through slot changes
        style = _PAIR_STYLES[n % 2]
        axes[1].plot(*_track_line(ms, m.sliding_speed[keep], track), **style, lw=0.8,
                     label=("pair $k$", "pair $k$+1")[n] if n < 2 else None)
    axes[1].axhline(0.0, color="0.5", lw=0.4)
    if len(tracks) > 1:  # what the alternating solid and dashed lines are
        axes[1].legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=2, fontsize="x-small", frameon=False,
                       handlelength=2.2, borderaxespad=0.1, columnspacing=1.0)
    axes[1].set_ylabel("Sliding speed\n$v_s$ [m/s]")
    axes[1].set_title("(b) Sliding speed of each tooth pair", loc="left")
    if film is not None:
        for n, track in enumerate(tracks):
            axes[2].plot(*_track_line(ms, film[keep], track), **_PAIR_STYLES[n % 2], lw=0.8)
        top = float(np.nanmax(film[keep], initial=0.0))
        for bound in (1.0, 3.0):
            if bound < 1.5 * top:
                axes[2].axhline(bound, color="0.5", lw=0.4, ls="--")
        axes[2].set_ylim(0.0, None)
        axes[2].set_ylabel(r"$\lambda$ [-]")
        axes[2].set_title(r"(c) Film thickness ratio $\lambda$ (boundary below 1, mixed 1 to 3)", loc="left")
    for tc in _crossings(t[keep], position, tracks):
        for ax in axes:
            ax.axvline(1e3 * tc, color=MARK_COLOR, ls=":", lw=0.6)
    axes[-1].set_xlabel("Time $t$ [ms]")
    axes[-1].set_xlim(1e3 * z0, 1e3 * z1)
    return fig
