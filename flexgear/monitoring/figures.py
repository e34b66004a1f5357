"""Figures of condition monitoring, as researchers publish them.

- :func:`fig_tsa`: per shaft, the time-synchronous average against its angle, the teeth in mesh
  numbered on the top axis (carrier: where each planet passes the sensor), and the residual and
  difference signals;
- :func:`fig_order_spectra`: the whole record against the reference shaft's orders and every
  shaft's TSA spectrum, mesh orders and sidebands marked;
- :func:`fig_envelope`: the envelope spectrum of the band, shaft orders marked;
- :func:`fig_severity`: indicators against fault severity (several results).

Built on :mod:`flexgear.style` (Agg canvas, no pyplot, journal sizes).
"""
from __future__ import annotations

import numpy as np

from ..style import DOUBLE_WIDTH, MARK_COLOR, figure, styled, unit_label
from ..config import key_unit
from .indicators import INDICATORS, numerically_zero

__all__ = ["MONITOR_FIGURES", "fig_tsa", "fig_order_spectra", "fig_envelope", "fig_severity"]

#: File names written by the command, in order.
MONITOR_FIGURES = ("tsa.png", "order_spectra.png", "envelope_spectrum.png")

_MARK = {"mesh": dict(color="#c0392b", linestyle="--", linewidth=0.5),
         "sideband": dict(color="#1f5fa8", linestyle=":", linewidth=0.5),
         "shaft": dict(color="#2e8b57", linestyle="-.", linewidth=0.5),
         "planet": dict(color="#8e44ad", linestyle="-.", linewidth=0.5)}


def _unit(report) -> str:
    return unit_label(report.source.units) or "-"


def _deg(n: int) -> np.ndarray:
    return np.arange(n) * 360.0 / n


def _label(sa) -> str:
    s = sa.shaft
    rel = f" rel. to {s.reference}" if s.reference else ""
    avg = f"averages {sa.average.averages:.3g}"
    win = f", planet windows of {sa.window_teeth} teeth" if s.windowed else ""
    return f"{s.name}{rel}: {avg}{win}"


def _tooth_marks(sa) -> tuple[list, list, str]:
    """(angles [deg], labels, axis title) of the top axis: the teeth numbered at the angles where
    the recorded contacts put them in mesh; the carrier: where each planet passes the measuring
    angle (the sensor's, or --sensor-angle); without recorded contacts, unlabelled tooth pitches."""
    if sa.shaft.name == "carrier" and sa.planet_angles:
        return ([np.degrees(a) for a in sa.planet_angles.values()],
                [p.replace("planet", "P") for p in sa.planet_angles], "planet passing the measuring angle")
    if sa.tooth_angles:
        items = sorted(sa.tooth_angles.items(), key=lambda kv: kv[1])
        return [np.degrees(a) for _, a in items], [str(k) for k, _ in items], f"tooth in mesh on {sa.shaft.tooth_mesh}"
    return list(_deg(sa.shaft.mesh_order)), [], "tooth pitches"


def tooth_angle(angles: dict, tooth: int, z: int) -> float | None:
    """Angle [deg] at which ``tooth`` meshes, from the recorded ``angles`` {tooth: rad} of the
    others where it has none (a missing tooth never meshes): the teeth lie a pitch 2 pi / z
    apart, in the sense the record shows; None without recorded teeth."""
    if tooth in angles:
        return float(np.degrees(angles[tooth]))
    if not angles:
        return None
    k = np.array(list(angles), dtype=float)
    a = np.array(list(angles.values()))
    best = None
    for sense in (1.0, -1.0):
        phase = np.exp(1j * (a + sense * k * 2.0 * np.pi / z))  # the same for every tooth in the right sense
        spread = 1.0 - abs(phase.mean())
        if best is None or spread < best[0]:
            best = (spread, sense, np.angle(phase.mean()))
    _, sense, origin = best
    return float(np.degrees(np.mod(origin - sense * tooth * 2.0 * np.pi / z, 2.0 * np.pi)))


def _angle_axes(ax, sa, labelled: bool) -> None:
    """Shaft-angle axes, 0-360 deg; ``labelled``: the teeth (or planets) numbered on a top axis."""
    where, labels, title = _tooth_marks(sa)
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 60))
    if sa.shaft.name == "carrier":
        for a in where:
            ax.axvline(a, **_MARK["planet"], zorder=0.5)
    if labelled:
        top = ax.secondary_xaxis("top")
        step = max(1, -(-len(where) // 24))
        top.set_xticks(where[::step], labels[::step] if labels else [], fontsize=5)
        top.tick_params(length=2, pad=1)
        top.set_xlabel(title, fontsize=5.5, labelpad=1)


def _grid(nrow: int, ncol: int = 1, height_each: float = 0.95, gap: float = 0.6, top: float = 0.3):
    """nrow x ncol panels with fixed margins [in] (no constrained layout: with many panels and tick
    labels it costs more than the drawing itself)."""
    bottom, left, right = 0.4, 0.55, 0.1
    height = top + bottom + nrow * height_each + (nrow - 1) * gap
    fig = figure(DOUBLE_WIDTH, height, layout=None)
    grid = dict(left=left / DOUBLE_WIDTH, right=1 - right / DOUBLE_WIDTH, top=1 - top / height,
                bottom=bottom / height, hspace=gap / height_each, wspace=0.22)
    return fig, fig.subplots(nrow, ncol, squeeze=False, gridspec_kw=grid)


@styled
def fig_tsa(report):
    """Per shaft (rows): the time-synchronous average (left, teeth numbered on top) and the
    residual and difference signals (right), against the shaft's angle [deg]."""
    fig, axes = _grid(len(report.shafts), 2, top=0.55)
    unit = _unit(report)
    for (left, right), sa in zip(axes, report.shafts.values()):
        ang = _deg(sa.samples_per_rev)
        left.plot(ang, sa.signals.tsa, color="k", linewidth=0.5)
        for tooth, kind, mesh, angles in sa.fault_marks:  # where a recorded fault's flank meshes
            a = tooth_angle(angles, tooth, sa.shaft.mesh_order)
            if a is not None:
                for ax in (left, right):
                    ax.axvline(a, color=MARK_COLOR, linestyle="--", linewidth=0.6, zorder=0.5)
                where = "" if mesh == sa.shaft.tooth_mesh else f" (in mesh on {mesh})"
                gear = "ring " if sa.shaft.name == "carrier" else ""  # the carrier's marks: the ring's teeth
                left.text(a, 0.97, f" {gear}{kind}, tooth {tooth}{where} ", transform=left.get_xaxis_transform(),
                          fontsize=5, color=MARK_COLOR, ha="right" if a > 180.0 else "left", va="top")  # in the panel
        left.set_ylabel(f"TSA [{unit}]")
        left.set_title(_label(sa), loc="left", fontsize=6, pad=13)
        _angle_axes(left, sa, True)
        right.plot(ang, sa.signals.residual, color="k", linewidth=0.5, label="residual")
        right.plot(ang, sa.signals.difference, color="#c0392b", linewidth=0.4, label="difference")
        right.set_ylabel(f"Residual, difference [{unit}]")
        zero = [n for n in ("residual", "difference") if numerically_zero(getattr(sa.signals, n), sa.signals.tsa)]
        if zero:  # autoscaled round-off would look like events
            right.text(0.01, 0.97, f"{' and '.join(zero)} numerically zero: round-off of the resampling",
                       transform=right.transAxes, fontsize=5, va="top", ha="left")
        _angle_axes(right, sa, False)
    axes[0, 1].legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=2, borderaxespad=0.2)
    for ax in axes[-1]:
        ax.set_xlabel("Shaft angle [deg] (in its direction of rotation)")
    fig.suptitle(f"Time-synchronous averages of {report.source.signal_path} (left), their residual and "
                 "difference signals (right)", fontsize=7, y=1 - 0.12 / fig.get_figheight())
    return fig


def _mark(ax, marks, top: float, labels: bool = True, alpha: float = 1.0) -> None:
    """Vertical marker lines (one collection per kind) up to 82 % of the panel, labels above."""
    from matplotlib.transforms import blended_transform_factory

    tr = blended_transform_factory(ax.transData, ax.transAxes)
    for kind, style in _MARK.items():
        at = [o for o, _, k in marks if k == kind and 0 < o <= top]
        if at:
            ax.vlines(at, 0.0, 0.82, transform=tr, colors=style["color"], linestyles=style["linestyle"],
                      linewidths=style["linewidth"], alpha=alpha, zorder=0.5)
    if labels:
        for order, label, kind in marks:
            if label and 0 < order <= top:
                ax.text(order, 0.84, label, transform=tr, rotation=90, fontsize=5, ha="center", va="bottom",
                        color=_MARK[kind]["color"])


def _spectrum(ax, orders, amp, top: float, unit: str) -> None:
    """Amplitude in dB re 1 unit of the signal over orders (0, top], 80 dB below the largest line."""
    from ..results.signals import db

    sel = (orders > 0) & (orders <= top)
    y = db(amp[sel])
    ax.plot(orders[sel], y, color="k", linewidth=0.5)
    hi = float(np.max(y))
    ax.set_ylim(hi - 80.0, hi + 20.0)
    ax.set_xlim(0, top)
    ax.set_ylabel(f"Amplitude [dB re 1 {unit}]")


@styled
def fig_order_spectra(report):
    """The record's order spectrum against the reference shaft, and each shaft's TSA spectrum,
    with mesh orders (k z), their sidebands and the other shafts' orders marked."""
    from .tsa import tsa_amplitudes

    fig, axes = _grid(1 + len(report.shafts), height_each=0.85, gap=0.5)
    axes = axes[:, 0]
    o = report.orders
    _spectrum(axes[0], o.orders, o.amplitude, o.max_order, _unit(report))
    _mark(axes[0], [m for m in o.marks if m[2] in ("mesh", "sideband")], o.max_order)
    axes[0].set_title(f"Whole record against {o.reference} orders (Hann window)", loc="left", fontsize=6.5)
    for ax, sa in zip(axes[1:], report.shafts.values()):
        amp = tsa_amplitudes(sa.signals.tsa)
        top = sa.signals.max_order
        _spectrum(ax, np.arange(amp.size, dtype=float), amp, top, _unit(report))
        z = sa.shaft.mesh_order
        marks = [(float(k * z), f"{k}z" if k > 1 else "z", "mesh") for k in range(1, top // z + 1)]
        marks += [(float(k * z + j), "", "sideband") for k in range(1, top // z + 1) for j in (-1, 1)]
        _mark(ax, marks, top)
        ax.set_title(f"TSA spectrum, {_label(sa)} (z = {z})", loc="left", fontsize=6.5)
    axes[-1].set_xlabel("Order [1/rev]")
    from matplotlib.lines import Line2D

    keys = {"mesh": "mesh orders k z", "sideband": "sidebands k z -/+ 1 (top panel: to -/+ 3)"}
    axes[0].legend([Line2D([], [], **_MARK[k]) for k in keys], list(keys.values()), loc="lower right",
                   bbox_to_anchor=(1.0, 1.0), ncol=2, fontsize=5, handlelength=2.5, borderaxespad=0.2)
    return fig


@styled
def fig_envelope(report):
    """Envelope spectrum of the band against the reference shaft's orders, shaft orders marked."""
    e = report.envelope
    fig, axes = _grid(1, height_each=1.6, top=0.45)
    ax = axes[0, 0]
    top = min(e.max_order, 12.0 * max((m[0] for m in e.marks), default=1.0))
    _spectrum(ax, e.orders, e.amplitude, top, _unit(report))
    _mark(ax, e.marks, top, labels=False)
    _mark(ax, [(k * o, "", kind) for o, _, kind in e.marks for k in (2, 3)], top, alpha=0.5)  # harmonics
    key = ", ".join(f"{label} {order:.4g}" for order, label, _ in sorted(e.marks))
    ax.text(0.0, 1.02, f"orders marked (2nd, 3rd faint): {key}", transform=ax.transAxes, ha="left", va="bottom",
            fontsize=5)  # above the panel: a key inside it hid the lines near the top right
    ax.set_xlabel(f"Order of the {e.reference} [1/rev]")
    ax.set_title(f"Envelope spectrum of the band {e.band_hz[0]:.0f}-{e.band_hz[1]:.0f} Hz "
                 f"(zero-phase Butterworth band-pass, Hilbert envelope)", loc="left", fontsize=6.5, pad=10)
    return fig


@styled
def fig_severity(table, indicators=tuple(INDICATORS)):
    """Indicators against fault severity: one panel per indicator, one line per shaft, every
    panel over the batch's whole severity range (an undefined value, such as FM4 of a
    noise-free healthy case, leaves a gap, not a shorter axis)."""
    ncol = 3
    nrow = -(-len(indicators) // ncol)
    fig = figure(DOUBLE_WIDTH, 1.55 * nrow + 0.4)
    axes = fig.subplots(nrow, ncol, squeeze=False).ravel()
    styles = ["-o", "--s", ":^", "-.v", "-D", "--x"]
    x = np.asarray(table.severities, dtype=float)
    pad = 0.04 * (np.ptp(x) or max(abs(x[0]), 1.0))
    unit = key_unit(table.key)
    levels, where = np.unique(x, return_inverse=True)
    repeats = levels.size < x.size  # repeated measurements of a severity: each case a mark, a line through the means
    for ax, name in zip(axes, indicators):
        if all(v is None for shaft in table.shafts for v in table.values(shaft, name)):
            ax.text(0.5, 0.5, "undefined in every case\n(a case's indicators.json\nsays why)", ha="center",
                    va="center", fontsize=6, color="0.4", transform=ax.transAxes)
        for j, shaft in enumerate(table.shafts):
            y = np.array([np.nan if v is None else v for v in table.values(shaft, name)], dtype=float)
            style = styles[j % len(styles)]
            if not repeats:
                ax.plot(x, y, style, markersize=2.5, linewidth=0.6, label=shaft)
                continue
            with np.errstate(invalid="ignore"):
                mean = np.array([np.nanmean(y[where == i]) if np.isfinite(y[where == i]).any() else np.nan
                                 for i in range(levels.size)])
            line, = ax.plot(levels, mean, style[:-1] or "-", linewidth=0.6, label=shaft)
            ax.plot(x, y, style[-1], markersize=2.0, linestyle="none", color=line.get_color(), alpha=0.6)
        ax.set_xlim(x.min() - pad, x.max() + pad)
        ind_unit = table.units.get(name, "1")
        ax.set_title(name.replace("_", " ") + ("" if ind_unit == "1" else f" [{ind_unit}]"), fontsize=6.5, loc="left")
        ax.set_xlabel(table.key + (f" [{unit}]" if unit else ""), fontsize=6)
    for ax in axes[len(indicators):]:
        ax.set_visible(False)
    axes[0].legend(fontsize=5.5)
    each = f"; marks: each of {x.size} cases, lines: means over the repeats" if repeats else ""
    fig.suptitle(f"Indicators against {table.key} ({table.signal}{each})", fontsize=7.5)
    return fig
