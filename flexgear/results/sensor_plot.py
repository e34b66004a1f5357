"""A housing sensor's signals as a researcher first looks at them: the whole record, a zoom on a
few mesh periods and the amplitude spectrum with the mesh harmonics marked, one row per path
model (:func:`~flexgear.results.sensor_plot.fig_sensor`; written by
:func:`~flexgear.results.plots.paper_figures` as ``sensor_<name>.png``).
"""
from __future__ import annotations

import numpy as np

from ..style import DOUBLE_WIDTH, MARK_COLOR, ZOOM_PERIODS, figure, styled, unit_label
from .noise import NOISE_FREE, measured
from .signals import amplitude_spectrum


#: what a signal in these units measures (a path model's output need not be the sensor's quantity:
#: ``planet_pass`` gives the force a planet's mesh puts on the ring near the sensor)
QUANTITIES = {"m/s^2": "Acceleration", "m/s": "Velocity", "m": "Displacement", "N": "Force"}


def sensor_zoom(t: np.ndarray, x: np.ndarray, mesh_frequency: float, periods: float = ZOOM_PERIODS):
    """Start and end [s] of ``periods`` mesh periods of the times ``t`` centred on the largest
    deviation of ``x`` from its mean (where a fault's impulse or a planet's pass peaks); the
    whole record when it is shorter or the mesh frequency unknown."""
    if not mesh_frequency > 0 or (t[-1] - t[0]) * mesh_frequency <= periods:
        return float(t[0]), float(t[-1])
    width = periods / mesh_frequency
    centre = t[int(np.argmax(np.abs(x - x.mean())))]
    start = min(max(centre - 0.5 * width, t[0]), t[-1] - width)
    return float(start), float(start + width)


@styled
def fig_sensor(result, sensor: str, periods: float = ZOOM_PERIODS):
    """Sensor ``sensor`` of ``result``: per path model (``housing_path``, ``planet_pass``) a row
    of (a) the record with the zoom's window shaded, (b) the zoom on ``periods`` mesh periods
    around the largest deviation, (c) the amplitude spectrum (Hann window) with the mesh
    harmonics k f_m dashed and the band beyond the record's trustworthy passband shaded. A
    signal with measurement noise has its noise-free copy drawn over the zoom in colour, and the
    zoom centred where that copy peaks."""
    s = result.sensors[sensor]
    t = np.asarray(result.time, dtype=float)
    fs = 1.0 / (t[1] - t[0])
    fm = float(result.attrs.get("mesh_frequency", 0.0))
    band = result.attrs.get("passband_hz")
    quantity = str(s.attrs.get("quantity", "signal"))
    paths = measured(s.signals)
    fig = figure(DOUBLE_WIDTH, 0.6 + 2.0 * len(paths))
    axes = np.array(fig.subplots(len(paths), 3, squeeze=False, width_ratios=(1.3, 1.0, 1.3)))
    for i, path in enumerate(paths):
        x = np.asarray(s.signals[path], dtype=float)
        units = s.signal_attrs[path]["units"]
        label = f"{QUANTITIES.get(units, quantity.capitalize())} [{unit_label(units)}]"  # a path model: a force
        name = f"{sensor}, {path.replace('_', ' ')}"
        ax_t, ax_z, ax_f = axes[i]
        clean = np.asarray(s.signals[path + NOISE_FREE], dtype=float) if path + NOISE_FREE in s.signals else None
        z0, z1 = sensor_zoom(t, x if clean is None else clean, fm, periods)  # where the signal, not the noise, peaks
        ax_t.plot(t, x, color="k", lw=0.3)
        ax_t.axvspan(z0, z1, color=MARK_COLOR, alpha=0.3, lw=0)
        for edge in (z0, z1):  # a few mesh periods of a long record: its edges keep the window in sight
            ax_t.axvline(edge, color=MARK_COLOR, lw=0.5)
        ax_t.set_xlim(t[0], t[-1])
        ax_t.set_ylabel(label)
        ax_t.set_title(f"(a{i + 1}) {name}", loc="left")
        keep = (t >= z0) & (t <= z1)
        ax_z.plot(1e3 * t[keep], x[keep], color="k", lw=0.6)
        if clean is not None:
            ax_z.plot(1e3 * t[keep], clean[keep], color=MARK_COLOR, lw=0.6)
        ax_z.set_xlim(1e3 * z0, 1e3 * z1)
        ax_z.set_xlabel("Time $t$ [ms]")  # each row's zoom spans its own window
        noted = "" if clean is None else ", red: no noise"
        ax_z.set_title(f"(b{i + 1}) {periods:g} mesh periods{noted}", loc="left")
        f, amp = amplitude_spectrum(x, fs, window="hann")
        ax_f.plot(f, amp, color="k", lw=0.5)
        top = float(band) if band is not None else fs / 2
        for k in range(1, int(f[-1] / fm) + 1 if fm > 0 else 1):
            ax_f.axvline(k * fm, color=MARK_COLOR, ls="--", lw=0.3, alpha=0.45, zorder=0)  # under the lines
        if top < f[-1]:
            ax_f.axvspan(top, f[-1], color="0.85", lw=0, zorder=0)
        ax_f.set_xlim(0.0, f[-1])
        ax_f.set_ylim(0.0, None)
        ax_f.set_ylabel(f"Amplitude [{unit_label(units)}]")
        ax_f.set_title(f"(c{i + 1}) Spectrum (dashed: $k f_m$)", loc="left")
        if i == len(paths) - 1:
            ax_t.set_xlabel("Time $t$ [s]")
            ax_f.set_xlabel("Frequency $f$ [Hz]")
    return fig
