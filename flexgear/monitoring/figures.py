"""Figures of condition monitoring, as researchers publish them.

- :func:`fig_tsa`: the time-synchronous average of every shaft against its angle, the teeth in
  mesh numbered on the top axis (carrier: where each planet passes the sensor);
- :func:`fig_residual`: the residual and difference signals of every shaft;
- :func:`fig_order_spectra`: the whole record against the reference shaft's orders and every
  shaft's TSA spectrum, mesh orders and sidebands marked;
- :func:`fig_envelope`: the envelope spectrum of the band, shaft orders marked;
- :func:`fig_severity`: indicators against fault severity (several results).

Built on :mod:`flexgear.style` (Agg canvas, no pyplot, journal sizes).
"""
from __future__ import annotations

import numpy as np

from ..style import DOUBLE_WIDTH, figure, styled

__all__ = ["MONITOR_FIGURES", "fig_tsa", "fig_residual", "fig_order_spectra", "fig_envelope", "fig_severity"]

#: File names written by the command, in order.
MONITOR_FIGURES = ("tsa.png", "residual.png", "order_spectra.png", "envelope_spectrum.png")

_MARK = {"mesh": dict(color="#c0392b", linestyle="--", linewidth=0.5),
         "sideband": dict(color="#1f5fa8", linestyle=":", linewidth=0.5),
         "shaft": dict(color="#2e8b57", linestyle="-.", linewidth=0.5),
         "planet": dict(color="#8e44ad", linestyle="-.", linewidth=0.5)}


def _unit(report) -> str:
    return report.source.units or "-"


def _deg(n: int) -> np.ndarray:
    return np.arange(n) * 360.0 / n


def _label(sa) -> str:
    s = sa.shaft
    rel = f" rel. to {s.reference}" if s.reference else ""
    avg = f"averages {sa.average.averages:.3g}"
    win = f", planet windows of {sa.window_teeth} teeth" if s.windowed else ""
    return f"{s.name}{rel}: {avg}{win}"


def _teeth_axis(ax, sa) -> None:
    """Top axis: tooth numbers at the angles they mesh (carrier: planet passes)."""
    top = ax.secondary_xaxis("top")
    if sa.shaft.name == "carrier" and sa.planet_angles:
        ang = {p: np.degrees(a) for p, a in sa.planet_angles.items()}
        top.set_xticks(list(ang.values()), [p.replace("planet", "P") for p in ang], fontsize=5.5)
        for a in ang.values():
            ax.axvline(a, **_MARK["planet"], zorder=0.5)
        top.set_xlabel("planet passing the sensor", fontsize=6)
    elif sa.tooth_angles:
        items = sorted(sa.tooth_angles.items(), key=lambda kv: kv[1])
        step = max(1, len(items) // 24)
        top.set_xticks([np.degrees(a) for _, a in items[::step]], [str(k) for k, _ in items[::step]], fontsize=5)
        top.set_xlabel(f"tooth in mesh on {sa.shaft.tooth_mesh}", fontsize=6)
    else:
        z = sa.shaft.mesh_order
        top.set_xticks(_deg(z)[:: max(1, z // 24)], [])
        top.set_xlabel("tooth pitches", fontsize=6)
    top.tick_params(length=2, pad=1)


def _panels(n: int, height_each: float = 1.25):
    fig = figure(DOUBLE_WIDTH, 0.5 + height_each * n)
    return fig, fig.subplots(n, 1, squeeze=False)[:, 0]


@styled
def fig_tsa(report):
    """Time-synchronous average of every shaft against its angle [deg], teeth numbered on top."""
    fig, axes = _panels(len(report.shafts))
    for ax, sa in zip(axes, report.shafts.values()):
        ang = _deg(sa.samples_per_rev)
        ax.plot(ang, sa.signals.tsa, color="k", linewidth=0.5)
        ax.set_xlim(0, 360)
        ax.set_ylabel(f"TSA [{_unit(report)}]")
        ax.set_title(_label(sa), loc="left", fontsize=6.5)
        _teeth_axis(ax, sa)
    axes[-1].set_xlabel("Shaft angle [deg] (in its direction of rotation)")
    fig.suptitle(f"Time-synchronous averages of {report.source.signal_path}", fontsize=8)
    return fig


@styled
def fig_residual(report):
    """Residual and difference signals of every shaft against its angle [deg]."""
    fig, axes = _panels(len(report.shafts))
    for ax, sa in zip(axes, report.shafts.values()):
        ang = _deg(sa.samples_per_rev)
        ax.plot(ang, sa.signals.residual, color="k", linewidth=0.5, label="residual")
        ax.plot(ang, sa.signals.difference, color="#c0392b", linewidth=0.4, label="difference")
        ax.set_xlim(0, 360)
        ax.set_ylabel(f"[{_unit(report)}]")
        ax.set_title(_label(sa), loc="left", fontsize=6.5)
        _teeth_axis(ax, sa)
    axes[0].legend(loc="upper right", ncol=2)
    axes[-1].set_xlabel("Shaft angle [deg] (in its direction of rotation)")
    fig.suptitle("Residual (TSA without mesh harmonics and shaft orders) and difference signals "
                 "(also without first-order sidebands)", fontsize=7)
    return fig


def _mark(ax, marks, top: float, labels: bool = True) -> None:
    from matplotlib.transforms import blended_transform_factory

    tr = blended_transform_factory(ax.transData, ax.transAxes)
    for order, label, kind in marks:
        if 0 < order <= top:
            ax.axvline(order, ymax=0.82, zorder=0.5, **_MARK[kind])
            if labels and label:
                ax.text(order, 0.84, label, transform=tr, rotation=90, fontsize=5, ha="center", va="bottom",
                        color=_MARK[kind]["color"])


def _spectrum(ax, orders, amp, top: float, unit: str) -> None:
    sel = (orders > 0) & (orders <= top)
    y = np.maximum(amp[sel], np.max(amp[sel]) * 1e-6 if np.any(amp[sel] > 0) else 1e-30)
    ax.semilogy(orders[sel], y, color="k", linewidth=0.5)
    lo, hi = float(np.min(y)), float(np.max(y))
    ax.set_ylim(max(lo, hi * 1e-5), hi * 30)
    ax.set_xlim(0, top)
    ax.set_ylabel(f"Amplitude [{unit}]")


@styled
def fig_order_spectra(report):
    """The record's order spectrum against the reference shaft, and each shaft's TSA spectrum,
    with mesh orders (k z), their sidebands and the other shafts' orders marked."""
    from .tsa import tsa_amplitudes

    fig, axes = _panels(1 + len(report.shafts), 1.15)
    o = report.orders
    _spectrum(axes[0], o.orders, o.amplitude, o.max_order, _unit(report))
    _mark(axes[0], o.marks, o.max_order)
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
    return fig


@styled
def fig_envelope(report):
    """Envelope spectrum of the band against the reference shaft's orders, shaft orders marked."""
    e = report.envelope
    fig = figure(DOUBLE_WIDTH, 2.4)
    ax = fig.add_subplot()
    top = min(e.max_order, 12.0 * max((m[0] for m in e.marks), default=1.0))
    _spectrum(ax, e.orders, e.amplitude, top, _unit(report))
    _mark(ax, e.marks, top)
    for order, label, kind in e.marks:  # the second and third harmonics of each, unlabelled
        for k in (2, 3):
            ax.axvline(k * order, ymax=0.82, zorder=0.4, alpha=0.5, **_MARK[kind])
    ax.set_xlabel(f"Order of the {e.reference} [1/rev]")
    ax.set_title(f"Envelope spectrum of the band {e.band_hz[0]:.0f}-{e.band_hz[1]:.0f} Hz "
                 f"(zero-phase Butterworth band-pass, Hilbert envelope)", loc="left", fontsize=6.5)
    return fig


@styled
def fig_severity(table, indicators=("rms", "kurtosis", "fm0", "fm4", "na4", "m6a", "m8a", "energy_ratio", "ser")):
    """Indicators against fault severity: one panel per indicator, one line per shaft."""
    ncol = 3
    nrow = -(-len(indicators) // ncol)
    fig = figure(DOUBLE_WIDTH, 1.55 * nrow + 0.4)
    axes = fig.subplots(nrow, ncol, squeeze=False).ravel()
    styles = ["-o", "--s", ":^", "-.v", "-D", "--x"]
    x = np.asarray(table.severities, dtype=float)
    for ax, name in zip(axes, indicators):
        for j, shaft in enumerate(table.shafts):
            y = np.array([np.nan if v is None else v for v in table.values(shaft, name)], dtype=float)
            ax.plot(x, y, styles[j % len(styles)], markersize=2.5, linewidth=0.6, label=shaft)
        unit = table.units.get(name, "1")
        ax.set_title(name.replace("_", " ") + ("" if unit == "1" else f" [{unit}]"), fontsize=6.5, loc="left")
        ax.set_xlabel(table.key, fontsize=6)
    for ax in axes[len(indicators):]:
        ax.set_visible(False)
    axes[0].legend(fontsize=5.5)
    fig.suptitle(f"Indicators against {table.key} ({table.signal})", fontsize=7.5)
    return fig
