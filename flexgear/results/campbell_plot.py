"""Campbell diagram figure: natural frequencies (by mode type) against input speed, with the
mesh harmonics k f_m and their crossings: those planet phasing lets excite their mode marked,
the suppressed ones crossed out (:mod:`flexgear.dynamics.modal.campbell`)."""
from __future__ import annotations

import numpy as np

from ..config.faults import set_kinematics
from ..dynamics.modal.campbell import campbell_lines, modal_crossings
from ..style import COLUMN_WIDTH, figure, paper_style

TYPE_STYLE = {"rotational": ("C0", "-"), "translational": ("C1", "--"), "planet": ("C2", "-."), "-": ("0.3", "-")}
#: Marker at the right end of each mode line, by type: near-coincident lines of different types
#: stay apart there even where one is drawn over the other.
TYPE_MARKER = {"rotational": "o", "translational": "s", "planet": "^", "-": "D"}
#: Least vertical distance between two mode labels [points]: closer ones are moved apart, each
#: joined to its line by a leader.
LABEL_GAP_PT = 7.0
#: Least share of a mode's strain energy in the mesh springs for it to count as a mesh mode
#: (:func:`mesh_modes`; the flexible spur pair's mesh mode holds 28 % in its contact spring).
MESH_SHARE = 0.2


def mode_groups(modal, top: float) -> list[tuple[list[int], float, str]]:
    """The elastic modes up to ``top`` [Hz], those of one frequency (a degenerate pair or more,
    ``ModalResult.multiplicity``) together: list of (1-based mode numbers, frequency [Hz],
    type)."""
    out, i, f = [], 0, modal.frequencies
    while i < len(f):
        n = max(int(modal.multiplicity[i]), 1)
        if 0 < f[i] <= top:
            out.append((list(range(i + 1, i + n + 1)), float(f[i]), modal.mode_type[i]))
        i += n
    return out


def spread_labels(y, gap: float) -> np.ndarray:
    """Label positions as close to ``y`` (ascending) as they can be with at least ``gap`` between
    neighbours (same units): pushed up from below, then the stack shifted down by its mean
    displacement so that it stays centred on its lines."""
    y = np.asarray(y, float)
    out = y.copy()
    for k in range(1, len(out)):
        out[k] = max(out[k], out[k - 1] + gap)
    # groups of labels that touch share one shift: their mean displacement
    start = 0
    for k in range(1, len(out) + 1):
        if k == len(out) or out[k] - out[k - 1] > gap + 1e-12 * max(abs(gap), 1.0):
            shift = np.mean(out[start:k] - y[start:k])
            out[start:k] -= shift
            start = k
    if len(out):
        out[0] = max(out[0], 0.5 * gap)  # not below the axis
    for k in range(1, len(out)):  # the shift may close a gap to the group below
        out[k] = max(out[k], out[k - 1] + gap)
    return out


def fig_campbell(modal, mesh_ratio: float, speed_range, harmonics: int = 4, fmax: float | None = None,
                 operating: float | None = None, sun_teeth: int | None = None):
    """Campbell diagram of a :class:`~flexgear.dynamics.modal.system.ModalResult`: each mode a
    line (colour and dash by type, end marker by type, a degenerate group one line) labelled at
    its right end with its number(s) and frequency, labels of close lines moved apart.

    Parameters
    ----------
    mesh_ratio : float
        f_m / f_in (the mesh frequency in the carrier frame).
    speed_range : (float, float)
        Input speeds [Hz].
    fmax : float, optional
        Top of the frequency axis [Hz] (default: 1.1 times the highest mode or harmonic).
    operating : float, optional
        The input speed [Hz] the modes were linearised at, marked by a vertical line.
    sun_teeth : int, optional
        z_s of a planetary set: crossings that planet phasing suppresses
        (:func:`~flexgear.dynamics.modal.campbell.excites`) are crossed out in grey.

    Returns
    -------
    (Figure, list of Crossing)
    """
    lo, hi = speed_range
    speeds = np.linspace(0.0, hi, 200)
    cr = modal_crossings(modal, mesh_ratio, speed_range, harmonics, sun_teeth)
    top = fmax or 1.1 * max(max(modal.frequencies), harmonics * mesh_ratio * hi)
    height = 3.1  # the legend above the axes
    with paper_style():
        fig = figure(COLUMN_WIDTH, height)
        ax = fig.add_subplot(1, 1, 1)
        for label, f in campbell_lines(mesh_ratio, speeds, harmonics).items():
            ax.plot(speeds, f, color="0.2", lw=0.7)
            ax.annotate(f"${label}$", (speeds[-1], f[-1]), fontsize=6, xytext=(2, 0), textcoords="offset points",
                        va="center", annotation_clip=True)
        seen = set()
        groups = mode_groups(modal, top)
        x_end, x_label = 1.14 * hi, 1.2 * hi
        # the axes are about 0.75 of the figure's height: LABEL_GAP_PT in frequency units
        gap = top * LABEL_GAP_PT / (72.0 * 0.75 * height)
        ys = spread_labels([g[1] for g in groups], gap)
        for (numbers, fn, t), y in zip(groups, ys):
            c, ls = TYPE_STYLE.get(t, TYPE_STYLE["-"])
            # dashed types drawn over solid ones: a near-coincident dashed line stays visible
            ax.plot([0.0, x_end], [fn, fn], color=c, ls=ls, lw=0.8, zorder=2.0 if ls == "-" else 2.2,
                    label=None if t in seen else ("natural frequency" if t == "-" else t))  # '-': no type
            ax.plot([x_end], [fn], TYPE_MARKER.get(t, "D"), color=c, ms=2.5, zorder=2.3)
            seen.add(t)
            ax.plot([x_end, x_label], [fn, y], color=c, lw=0.4, zorder=2.3)
            name = ", ".join(map(str, numbers))
            ax.annotate(f"{name}: {fn:.1f} Hz", (x_label, y), xytext=(1, 0), textcoords="offset points",
                        fontsize=5, va="center", color=c, gid=f"mode-label {name}")
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
        ax.set_xlim(0, hi * 1.55)
        ax.set_ylim(0, top)
        ax.set_xlabel("input speed $f_{in}$ (Hz)")
        ax.set_ylabel("frequency (Hz)")
        if seen:
            ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=2, frameon=False,
                      borderaxespad=0.0)  # above the axes, off the lines
    return fig, cr


def mesh_modes(modal, share: float = MESH_SHARE) -> list[float]:
    """Frequencies [Hz] of the elastic modes with at least ``share`` of their strain energy in the
    mesh springs (for a flexible model the contact springs between the reduced flanks); if none
    has, the one with the largest share."""
    meshes = {s.name for s in modal.system.springs if s.kind == "mesh"}
    if not meshes:
        return []
    e = sum(np.asarray(modal.strain_energy[name]) for name in meshes if name in modal.strain_energy)
    elastic = np.flatnonzero(modal.frequencies > 0)
    if not elastic.size:
        return []
    chosen = [float(modal.frequencies[i]) for i in elastic if e[i] >= share]
    return chosen or [float(modal.frequencies[elastic[np.argmax(e[elastic])]])]


def modal_campbell(modal, cfg, harmonics: int = 4):
    """The Campbell diagram that ``flexgear modal`` writes: the modes of ``modal``, linearised at
    the operating point of the gear-set configuration ``cfg``, against the input speed.

    The frequency axis reaches 1.25 times the highest mesh mode (:func:`mesh_modes`: the modes
    the mesh excites most; in a flexible model the shaft and load modes come lower and the gear
    modes higher), and at least 1.1 times the highest harmonic at 1.5 times the operating speed;
    the speed axis is where the highest harmonic reaches that top, and at least 1.5 times the
    operating speed (the mean input frequency, marked). So every mode on the diagram is
    crossed by the highest harmonic, and the mesh modes by every harmonic that reaches them.
    Returns (Figure, list of Crossing)."""
    kin = set_kinematics(cfg, 1.0)  # per Hz of the input
    r_m = kin.mesh
    f_in = abs(cfg.input_frequency)
    meshes = mesh_modes(modal)
    top = max(1.25 * max(meshes) if meshes else 0.0, 1.1 * harmonics * r_m * 1.5 * f_in)
    if top <= 0.0:
        top = 1.1 * harmonics * r_m  # no elastic mode and the set at rest: 1 Hz
    hi = max(1.5 * f_in, top / (1.1 * harmonics * r_m))
    z_s = cfg.gears["sun"].z if cfg.kind == "planetary" else None
    return fig_campbell(modal, r_m, (0.02 * hi, hi), harmonics=harmonics, fmax=top,
                        operating=f_in if f_in > 0 else None, sun_teeth=z_s)
