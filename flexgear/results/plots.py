"""Publication-style figures of a :class:`~flexgear.results.Result` (the paper's Figs. 3-12).

Figures are built on :class:`matplotlib.figure.Figure` with the Agg canvas, without pyplot, so
importing this module never changes the user's backend or global state; styling goes through
:func:`paper_style` (a ``matplotlib.rc_context``). One column 3.5 in, two columns 7 in; PNGs at
300 dpi. :func:`paper_figures` writes ``fig03_pinion_wheel_force.png`` and
``fig04_pinion_wheel_spectrum.png`` (spur), or ``fig07_planet_positions.png``,
``fig08_planet1_ring_force.png``, ``fig09_planet1_ring_spectrum.png``,
``fig10_ring_forces_all_planets.png``, ``fig11_sun_planet1_force.png`` and
``fig12_sun_planet1_spectrum.png`` (planetary), with :func:`fig_mesh_force`,
:func:`fig_mesh_spectrum`, :func:`fig_planet_positions` and :func:`fig_ring_forces`; a run
with tooth friction adds ``friction_<mesh>.png`` for the same meshes
(:func:`~flexgear.results.friction_plot.fig_friction`), one with sensors ``sensor_<name>.png``
for each (:func:`~flexgear.results.sensor_plot.fig_sensor`).
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import ResultExistsError
from ..style import (COLUMN_WIDTH, DOUBLE_WIDTH, DPI, MARK_COLOR, ZOOM_PERIODS, figure as _figure, paper_style,
                     save_figure, styled as _styled)
from .events import fault_event, window_start
from .friction_plot import fig_friction
from .sensor_plot import fig_sensor
from .signals import Line, amplitude_spectrum, db as _db, planetary_lines, spur_lines

__all__ = [
    "COLUMN_WIDTH",
    "DOUBLE_WIDTH",
    "DPI",
    "paper_style",
    "is_planetary",
    "characteristic_frequencies",
    "characteristic_lines",
    "mesh_force",
    "plot_force",
    "plot_spectrum",
    "passband_edge",
    "fig_mesh_force",
    "fig_mesh_spectrum",
    "fig_planet_positions",
    "fig_ring_forces",
    "save_figure",
    "paper_figures",
]


_PLANET_STYLES = [dict(color="k", linestyle="-"), dict(color="#1f5fa8", linestyle="--"),
                  dict(color="#c0392b", linestyle=":"), dict(color="#2e8b57", linestyle="-."),
                  dict(color="#8e44ad", linestyle=(0, (5, 1, 1, 1, 1, 1)))]
_LINE_STYLES = {
    "carrier": dict(color="#2e8b57", linestyle="-.", linewidth=0.5),
    "mesh": dict(color="#c0392b", linestyle="--", linewidth=0.5),
    "sideband": dict(color="#1f5fa8", linestyle=":", linewidth=0.5),
    # dash-dot-dot: a solid marker beside a spectrum's own solid lines read as a line of the data
    "fault": dict(color="#d35400", linestyle=(0, (6, 1.5, 1, 1.5, 1, 1.5)), linewidth=0.6),
    "fault_harmonic": dict(color="#d35400", linestyle=(0, (6, 1.5, 1, 1.5, 1, 1.5)), linewidth=0.35),
}
#: Harmonics of each fault's characteristic frequency marked on a spectrum.
FAULT_HARMONICS = 3
_COMPONENTS = {"x": "horizontal force $F_x$", "y": "vertical force $F_y$",
               "normal": "normal force $F_n$"}


# --------------------------------------------------------------------------- result helpers

_PLANET_MESH = re.compile(r"^(sun-planet\d+|planet\d+-ring)$")


def is_planetary(result) -> bool:
    """True if ``result`` has planetary meshes (``sun-planet<i>`` or ``planet<i>-ring``)."""
    return any(_PLANET_MESH.match(name) for name in result.meshes)


def _planets(result) -> list[str]:
    names = {m.group(1) for name in list(result.meshes) + list(result.bodies)
             if (m := re.search(r"(planet\d+)", name))}
    return sorted(names, key=lambda s: int(s[len("planet"):]))


def _spur_mesh(result) -> str:
    if "pinion-wheel" in result.meshes:
        return "pinion-wheel"
    if len(result.meshes) == 1:
        return next(iter(result.meshes))
    raise ValueError(f"cannot tell the spur mesh among {sorted(result.meshes)}; expected "
                     f"'pinion-wheel'")


def _mean_rot_freq(result, body: str) -> float:
    return float(np.mean(result.bodies[body].angular_velocity) / (2 * np.pi))


def characteristic_frequencies(result) -> dict[str, float]:
    """Carrier and mesh frequency [Hz] of a result.

    Taken from ``result.attrs["carrier_frequency"]`` and ``["mesh_frequency"]`` when present;
    otherwise computed from the mean body speeds and tooth counts (``z`` in the body or
    ``z_a`` in the mesh attributes).

    Returns
    -------
    dict
        ``{"carrier": f_a, "mesh": f_m}`` [Hz]; ``f_a = 0`` for a fixed-axis set.
    """
    fa = result.attrs.get("carrier_frequency")
    fm = result.attrs.get("mesh_frequency")
    planetary = is_planetary(result)
    if fa is None:
        fa = 0.0
        if planetary and "carrier" in result.bodies:
            ring = _mean_rot_freq(result, "ring") if "ring" in result.bodies else 0.0
            fa = abs(_mean_rot_freq(result, "carrier") - ring)
    if fm is None or not fm > 0:
        if planetary:
            sun = result.bodies["sun"]
            z = sun.attrs.get("z")
            if z is None:
                mesh = next(m for n, m in result.meshes.items() if n.startswith("sun-"))
                z = mesh.attrs["z_a"]
            fc = _mean_rot_freq(result, "carrier") if "carrier" in result.bodies else 0.0
            fm = z * abs(_mean_rot_freq(result, "sun") - fc)
        else:
            mesh = result.meshes[_spur_mesh(result)]
            z = mesh.attrs.get("z_a", result.bodies[mesh.body_a].attrs.get("z"))
            fm = z * abs(_mean_rot_freq(result, mesh.body_a))
    return {"carrier": float(fa), "mesh": float(fm)}


def characteristic_lines(result, n_harmonics: int | None = None, n_sidebands: int = 3
                         ) -> list[Line]:
    """Marker lines for a result: planetary (carrier, mesh, sidebands) or spur (mesh).

    Parameters
    ----------
    result : Result
    n_harmonics : int, optional
        Mesh harmonics; default 3 (planetary) or 4 (spur).
    n_sidebands : int, optional
        Sidebands per harmonic (planetary). Default 3.
    """
    fr = characteristic_frequencies(result)
    if is_planetary(result) and fr["carrier"] > 0:
        lines = planetary_lines(fr["carrier"], fr["mesh"], n_harmonics or 3, n_sidebands)
    else:
        lines = spur_lines(fr["mesh"], n_harmonics or 4)
    return lines + fault_marks(result)


def fault_marks(result) -> list[Line]:
    """The characteristic frequency of each fault and error of ``result.faults`` (``/faults``),
    labelled ``f_{F1}``, ``f_{F2}``, ... in the order of ``result.faults["labels"]`` (kind
    ``fault``), and its next FAULT_HARMONICS - 1 harmonics (kind ``fault_harmonic``, drawn
    unlabelled: they crowd the low end of a spectrum); none for perfect gears."""
    faults = getattr(result, "faults", None)
    if not faults:
        return []
    out = []
    for i, f in enumerate(faults.get("frequency_hz", []), start=1):
        f = abs(float(f))
        if f > 0:
            out += [Line(k * f, f"{'' if k == 1 else k}f_{{F{i}}}", "fault" if k == 1 else "fault_harmonic")
                    for k in range(1, FAULT_HARMONICS + 1)]
    return out


def mesh_force(result, mesh: str, component: str = "y") -> np.ndarray:
    """A mesh force signal [N]: ``"x"``, ``"y"`` (vertical, global) or ``"normal"``."""
    if mesh not in result.meshes:
        raise KeyError(f"mesh {mesh!r} not in result; meshes: {sorted(result.meshes)}")
    m = result.meshes[mesh]
    if component == "normal":
        return np.asarray(m.normal_force, dtype=float)
    if component in ("x", "y"):
        return np.asarray(m.force_global, dtype=float)[:, "xy".index(component)]
    raise ValueError(f"unknown force component {component!r}; choose 'x', 'y' or 'normal'")


def _window_slice(t: np.ndarray, t_start: float | None, duration: float | None) -> slice:
    t0 = t[0] if t_start is None else t_start
    i0 = int(np.searchsorted(t, t0 - 1e-12))
    if duration is None:
        return slice(i0, t.size)
    i1 = int(np.searchsorted(t, t0 + duration + 1e-12))
    return slice(i0, max(i1, i0 + 2))


def _tex(label: str) -> str:
    return "$" + label.replace("-", "{-}").replace("+", "{+}") + "$"


# --------------------------------------------------------------------------- axes-level plots

def plot_force(result, mesh: str, component: str = "y", t_start: float | None = None,
               duration: float | None = None, ax=None, label: str | None = None, **line_kw):
    """Plot a mesh force against time into ``ax``.

    Parameters
    ----------
    result : Result
    mesh : str
        Mesh name, e.g. ``"planet1-ring"``.
    component : {"y", "x", "normal"}, optional
        Vertical (default) or horizontal global component, or the normal force.
    t_start, duration : float, optional
        Time window [s]; default the whole output.
    ax : matplotlib Axes, optional
        Target; a new single-column figure if omitted.
    label : str, optional
        Legend label.
    **line_kw
        Passed to ``ax.plot``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    if ax is None:
        ax = _figure(COLUMN_WIDTH, 2.3).add_subplot()
    t = np.asarray(result.time, dtype=float)
    sl = _window_slice(t, t_start, duration)
    ax.plot(t[sl], mesh_force(result, mesh, component)[sl], label=label, **line_kw)
    ax.set_xlim(t[sl][0], t[sl][-1])
    ax.set_xlabel("Time $t$ [s]")
    ax.set_ylabel(_COMPONENTS[component][0].upper() + _COMPONENTS[component][1:] + " [N]")
    return ax


MAX_ZOOM_PANELS = 4  # sideband zoom panels under a planetary spectrum (the largest groups)
LABEL_BAND = 0.22  # top fraction of a spectrum panel kept for the line labels (no data, no lines)
ZERO_MARGIN = 0.015  # a range from 0 Hz starts this fraction of its span below 0, so that a line
#                     at a few Hz (the carrier f_a) and its label stand clear of the axis spine


def _left_edge(fmin: float, fmax: float) -> float:
    """Left end of a spectrum's frequency axis [Hz]: ``fmin``, or just below 0 Hz for a range
    from 0 (see :data:`ZERO_MARGIN`)."""
    return -ZERO_MARGIN * fmax if fmin <= 0.0 else fmin


def passband_edge(result) -> float | None:
    """Upper edge [Hz] of the trustworthy band of a result (``attrs["passband_hz"]``, see
    :mod:`flexgear.results.decimation`), or None when the result does not state it."""
    pb = result.attrs.get("passband_hz")
    return float(pb) if pb is not None else None


def _mark_lines(ax, lines: Sequence[Line], fmin: float, fmax: float, label_kinds,
                fontsize: float = 5.5, label_band: float = LABEL_BAND, rotation: float = 90) -> None:
    """Marker lines up to the label band, each label centred on its line inside the band
    (so no marker line crosses a label); ``label_band = 0``: full-height lines, no labels."""
    from matplotlib.transforms import blended_transform_factory

    tr = blended_transform_factory(ax.transData, ax.transAxes)
    top = 1.0 - label_band
    left = _left_edge(fmin, fmax)
    span = fmax - left
    for ln in lines:
        if not fmin <= ln.freq < fmax - 0.005 * span:  # none on the right edge (a harmonic at Nyquist)
            continue
        style = _LINE_STYLES.get(ln.kind, _LINE_STYLES["mesh"])
        ax.axvline(ln.freq, ymax=top, zorder=0.5, **style)
        if ln.kind in label_kinds and label_band > 0:
            ha = "center" if rotation == 90 or ln.freq - left > 0.02 * span else "left"
            ax.text(ln.freq, top + 0.02, _tex(ln.label), transform=tr, rotation=rotation, ha=ha,
                    va="bottom", fontsize=fontsize, color=style["color"], clip_on=False)


def _shade_beyond_passband(ax, passband: float | None, fmin: float, fmax: float, label: bool) -> None:
    """Grey the band above the trustworthy band (filter roll-off) and mark its edge."""
    if passband is None or passband >= fmax:
        return
    ax.axvspan(max(passband, fmin), fmax, color=_ROLL_OFF_COLOR, zorder=0, linewidth=0)
    if passband > fmin:
        ax.axvline(passband, color="0.45", linewidth=0.6, zorder=0.6)
    if label and passband > fmin:
        from matplotlib.transforms import blended_transform_factory

        tr = blended_transform_factory(ax.transData, ax.transAxes)
        ax.text(fmax - 0.005 * (fmax - fmin), 0.5,
                f"above {passband:.0f} Hz:\nattenuated by the\nanti-aliasing filter", transform=tr,
                ha="right", va="center", fontsize=5.5, color="0.3", zorder=3,
                bbox=dict(facecolor=_ROLL_OFF_COLOR, edgecolor="none", pad=0.5))


_ROLL_OFF_COLOR = "0.9"


def plot_spectrum(result, mesh: str, component: str = "y", fmax: float | None = None,
                  db: bool = False, window: str = "hann", lines: Sequence[Line] | None = None,
                  label_kinds=("carrier", "mesh", "sideband"), ax=None, fmin: float = 0.0,
                  db_ref: float = 1.0, ylim_from: float | None = None, note_passband: bool = True,
                  ylim: tuple[float, float] | None = None, label_band: float = LABEL_BAND,
                  label_rotation: float = 90):
    """Plot the amplitude spectrum of a mesh force with characteristic-line markers.

    The band above the result's trustworthy band (``attrs["passband_hz"]``, 0.8 x the output
    Nyquist frequency when anti-aliased) is shaded grey: lines there are attenuated by the
    anti-aliasing filter. The top of the panel is kept free for the marker labels.

    Parameters
    ----------
    result : Result
    mesh : str
        Mesh name.
    component : {"y", "x", "normal"}, optional
        Force component (default vertical).
    fmax : float, optional
        Upper frequency [Hz]; default the output Nyquist frequency ``fs/2`` (the whole
        trustworthy band and the shaded roll-off above it).
    db : bool, optional
        Amplitude in dB re ``db_ref`` N instead of N (linear, default).
    window : str, optional
        Window for :func:`flexgear.results.signals.amplitude_spectrum`. Default ``"hann"``.
    lines : sequence of Line, optional
        Markers (thin vertical lines with small labels); default :func:`characteristic_lines`.
        Pass ``[]`` for none.
    label_kinds : tuple of str, optional
        Which kinds of lines get a text label.
    ax : matplotlib Axes, optional
        Target; a new single-column figure if omitted.
    fmin : float, optional
        Lower frequency [Hz]. Default 0.
    db_ref : float, optional
        dB reference [N]. Default 1.
    ylim_from : float, optional
        Linear scale only: fit the amplitude axis to the spectrum above this frequency [Hz];
        taller lines below it are clipped and their amplitude is written next to them.
        Default: fit to the whole range (nothing clipped).
    note_passband : bool, optional
        Write a short explanation into the shaded band, if no marker line lies in it (the note
        would cover them; the figures name the band in their legend). Default True.
    ylim : (float, float), optional
        Amplitude range; default from the data, with the label band on top.
    label_band : float, optional
        Top fraction of the panel kept for the marker labels; 0: none (lines full height).
    label_rotation : float, optional
        Label angle [deg]: 90 (default) or 0.

    Returns
    -------
    matplotlib.axes.Axes
    """
    if ax is None:
        ax = _figure(COLUMN_WIDTH, 2.3).add_subplot()
    f, A = amplitude_spectrum(mesh_force(result, mesh, component), result.fs, window=window)
    if fmax is None:
        fmax = result.fs / 2
    fmax = min(fmax, f[-1])
    sel = (f >= fmin) & (f <= fmax)
    y = _db(A[sel], db_ref) if db else A[sel]
    ax.plot(f[sel], y, color="k", linewidth=0.5, zorder=2)
    ax.set_xlim(_left_edge(fmin, fmax), fmax)
    if db:
        top, bottom = float(np.max(y)), max(float(np.min(y)), float(np.max(y)) - 100.0)
        ax.set_ylim(bottom, bottom + (top + 3.0 - bottom) / (1.0 - label_band))
        ax.set_ylabel(f"Amplitude [dB re {db_ref:g} N]")
    else:
        fs_ = f[sel]
        ref = y[fs_ >= ylim_from] if ylim_from is not None else y
        peak = float(np.max(ref)) if ref.size and np.max(ref) > 0 else 1.0
        top = 1.05 * peak / (1.0 - label_band)
        if ylim_from is not None and np.max(y) > top:
            _note_clipped(ax, fs_, y, ylim_from, top)
        ax.set_ylim(0.0, top)
        ax.set_ylabel("Amplitude [N]")
    if ylim is not None:
        ax.set_ylim(*ylim)
    ax.set_xlabel("Frequency $f$ [Hz]")
    if lines is None:
        lines = characteristic_lines(result)
    passband = passband_edge(result)
    # the note would cover marker lines in the band (a legend names the band then)
    crossed = passband is not None and any(passband < ln.freq <= fmax for ln in lines)
    _shade_beyond_passband(ax, passband, fmin, fmax, note_passband and not crossed)
    _mark_lines(ax, lines, fmin, fmax, label_kinds, label_band=label_band, rotation=label_rotation)
    return ax


def _note_clipped(ax, f, y, f_below, top) -> None:
    """Write the amplitude of clipped peaks below ``f_below`` next to them."""
    from .signals import find_peaks

    for p in find_peaks(f, y, 3, fmax=f_below, min_amplitude=top):
        ax.annotate(f"{p.amplitude:.3g} N", xy=(p.freq, top), xytext=(4, -10),
                    textcoords="offset points", fontsize=6, ha="left", va="top",
                    arrowprops=dict(arrowstyle="-|>", linewidth=0.4, color="0.3",
                                    mutation_scale=5, shrinkA=0, shrinkB=0))


def _titled_legend(ax, title: str, kinds, passband: float | None = None) -> None:
    """The panel's title, and under it, on a line of its own above the panel (never over the
    data, never beside the title), the legend of the marker kinds and the shaded band."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    names = {"carrier": "carrier $f_a$", "mesh": "mesh $k f_m$",
             "sideband": "sidebands $k f_m \\pm j f_a$", "fault": "faults $k f_{Fi}$"}
    handles = [Line2D([], [], **_LINE_STYLES[k], label=names[k]) for k in kinds]
    if passband is not None:
        handles.append(Patch(color=_ROLL_OFF_COLOR, label=f"beyond the passband ({passband:.0f} Hz)"))
    leg = ax.legend(handles=handles, loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=len(handles),
                    handlelength=2.2, borderaxespad=0.3, columnspacing=1.2)
    fig = ax.figure
    height_pt = leg.get_window_extent(fig.canvas.get_renderer()).height * 72.0 / fig.dpi
    ax.set_title(title, loc="left", pad=height_pt + 4.0)


# --------------------------------------------------------------------------- figures

#: More mesh periods than this in one column-wide trace read as a solid band.
BAND_PERIODS = 60


def zoom_window(result, mesh: str, component: str, t: np.ndarray, periods: float) -> tuple[float, float, float | None]:
    """Start and end [s] of a zoom of ``periods`` mesh periods inside the times ``t``, and the
    time of the fault event it shows (None: none): centred, for a result with faults or errors,
    on the largest fault event (:func:`fault_event`), otherwise on the largest absolute force
    (where the envelope of a planet's force peaks and the mesh ripple is largest)."""
    width = periods / characteristic_frequencies(result)["mesh"]
    f, event = _fault_event(result, mesh, component, t)
    start = window_start(t, t[int(np.argmax(np.abs(f)))] if event is None else event, width)
    return start, float(min(start + width, t[-1])), event


def _fault_event(result, mesh: str, component: str, t: np.ndarray) -> tuple[np.ndarray, float | None]:
    """The force at the output times ``t`` (part of ``result.time``) and its largest fault event
    [s] (:func:`fault_event`; None for a result without faults or errors)."""
    i0 = int(np.searchsorted(np.asarray(result.time, dtype=float), t[0] - 1e-12))
    f = mesh_force(result, mesh, component)[i0:i0 + t.size]
    fm = characteristic_frequencies(result)["mesh"]
    return f, (fault_event(t, f, 1.0 / fm) if getattr(result, "faults", None) else None)


@_styled
def fig_mesh_force(result, mesh: str, component: str = "y", t_start: float | None = None,
                   duration: float | None = None, width: float = COLUMN_WIDTH,
                   height: float | None = None, zoom: float | bool | None = None):
    """Mesh force against time (paper Figs. 3, 8, 11).

        A trace of many mesh periods is a solid band at this width, so it gets a second panel with
        a few mesh periods, whose window is marked on the full trace.

        Parameters
        ----------
        result : Result
        mesh : str
            Mesh name (``"pinion-wheel"``, ``"planet1-ring"``, ``"sun-planet1"``).
        component : {"y", "x", "normal"}, optional
            Default ``"y"`` (vertical, global frame).
        t_start, duration : float, optional
            Time window [s]; default the whole output.
        width, height : float, optional
            Figure size [in]; default height 2.3 in, 4.2 in with the zoom panel.
        zoom : float or bool, optional
            Mesh periods in the zoom panel (True: :data:`~flexgear.style.ZOOM_PERIODS`, False:
            none); default :data:`~flexgear.style.ZOOM_PERIODS` when the trace holds more than
            :data:`BAND_PERIODS` mesh periods.

        Returns
        -------
        matplotlib.figure.Figure
    """
    t = np.asarray(result.time, dtype=float)
    t = t[_window_slice(t, t_start, duration)]
    fm = characteristic_frequencies(result)["mesh"]
    periods = (t[-1] - t[0]) * fm if fm > 0 else 0.0
    if zoom is None or zoom is True:
        zoom = ZOOM_PERIODS if (zoom is True or periods > BAND_PERIODS) and fm > 0 else False
    zoom = float(zoom) if zoom and periods > zoom else False
    fig = _figure(width, height or (4.2 if zoom else 2.3))
    if not zoom:  # a fault event marked (dashed): its departure is often small beside the mesh ripple
        plot_force(result, mesh, component, t_start, duration, ax=fig.add_subplot(), color="k")
        event = _fault_event(result, mesh, component, t)[1]
        if event is not None:
            fig.axes[0].axvline(event, color=MARK_COLOR, linestyle="--", linewidth=0.7, zorder=0)
        fig.axes[0].set_title(f"Meshing force, {mesh}{'' if event is None else ': a fault event (dashed)'}", loc="left")
        return fig
    ax, axz = fig.subplots(2, 1, height_ratios=[1.0, 1.0])
    plot_force(result, mesh, component, t_start, duration, ax=ax, color="k")
    z0, z1, event = zoom_window(result, mesh, component, t, zoom)
    plot_force(result, mesh, component, z0, z1 - z0, ax=axz, color="k", marker="o", markersize=1.2)
    axz.set_xlim(z0, z1)
    ax.set_title(f"(a) Meshing force, {mesh}", loc="left")
    if event is None:
        axz.set_title(f"(b) Zoom on {zoom:g} mesh periods ({1e3 * (z1 - z0):.1f} ms, red box in (a))", loc="left")
    else:  # the event marked: a fault's departure is often small beside the mesh ripple
        axz.axvline(event, color=MARK_COLOR, linestyle="--", linewidth=0.7, zorder=0)
        axz.set_title(f"(b) A fault event (dashed): {zoom:g} mesh periods, {1e3 * (z1 - z0):.1f} ms", loc="left")
    _mark_zoom(ax, axz, z0, z1)
    return fig


def _mark_zoom(ax, axz, z0: float, z1: float) -> None:
    """Mark the window [z0, z1] of the zoom panel ``axz`` on the full trace ``ax``: a box over
    the force range the zoom shows, in the colour of the zoom panel's frame (no joining lines:
    they would cross the full trace's tick labels)."""
    from matplotlib.patches import Rectangle

    lo, hi = axz.get_ylim()
    ax.add_patch(Rectangle((z0, lo), z1 - z0, hi - lo, facecolor="none", edgecolor=MARK_COLOR,
                           linewidth=0.9, zorder=3))
    for side in ("top", "bottom", "left", "right"):
        axz.spines[side].set_edgecolor(MARK_COLOR)
        axz.spines[side].set_linewidth(0.9)


@_styled
def fig_mesh_spectrum(result, mesh: str, component: str = "y", fmax: float | None = None,
                      db: bool = False, window: str = "hann", zoom: bool | None = None,
                      n_sidebands: int = 3):
    """Amplitude spectrum of a mesh force with markers (paper Figs. 4, 9, 12).

        The whole output band, the part above the trustworthy band shaded, every mesh harmonic
        marked; a planetary result adds, if ``zoom``, panels of the MAX_ZOOM_PANELS largest mesh
        harmonics with their sidebands ``k f_m +/- j f_a``.

        Parameters
        ----------
        result : Result
        mesh : str
            Mesh name.
        component : {"y", "x", "normal"}, optional
            Default ``"y"`` (vertical).
        fmax : float, optional
            Upper frequency [Hz]; default the output Nyquist frequency.
        db : bool, optional
            Amplitude in dB re 1 N instead of N.
        window : str, optional
            Spectral window. Default ``"hann"``.
        zoom : bool, optional
            Add sideband zoom panels; default True for planetary results.
        n_sidebands : int, optional
            Sidebands marked on each side of a harmonic (planetary). Default 3.

        Returns
        -------
        matplotlib.figure.Figure
    """
    planetary = is_planetary(result)
    fr = characteristic_frequencies(result)
    fmax = result.fs / 2 if fmax is None else min(fmax, result.fs / 2)
    n_harm = max(1, int(fmax // fr["mesh"])) if fr["mesh"] > 0 else None
    lines = characteristic_lines(result, n_harmonics=n_harm, n_sidebands=n_sidebands)
    passband = passband_edge(result)
    comp = "vertical" if component == "y" else component
    title = f"Spectrum of the meshing force, {mesh} ({comp})"
    band = passband if passband and passband < fmax else None
    if not planetary or fr["carrier"] <= 0:
        fig = _figure(COLUMN_WIDTH, 2.7)
        faulty = ("fault",) if any(ln.kind == "fault" for ln in lines) else ()
        ax = plot_spectrum(result, mesh, component, fmax, db, window, lines,
                           label_kinds=("mesh",) + faulty, ax=fig.add_subplot())
        _titled_legend(ax, title, ("mesh",) + faulty, band)
        return fig
    harmonics = [ln for ln in lines if ln.kind == "mesh" and ln.freq <= fmax]
    if len(harmonics) > MAX_ZOOM_PANELS:
        # the largest sideband groups inside the trustworthy band, in frequency order
        half = (n_sidebands + 1.5) * fr["carrier"]
        f, A = amplitude_spectrum(mesh_force(result, mesh, component), result.fs, window=window)
        inside = [h for h in harmonics if passband is None or h.freq <= passband] or harmonics

        def group_peak(h):
            sel = np.abs(f - h.freq) <= half
            return float(np.max(A[sel])) if np.any(sel) else 0.0

        harmonics = sorted(sorted(inside, key=group_peak, reverse=True)[:MAX_ZOOM_PANELS], key=lambda h: h.freq)
    zoom = bool(harmonics) if zoom is None else (zoom and bool(harmonics))
    fig = _figure(DOUBLE_WIDTH, 5.0 if zoom else 3.0)
    gs = fig.add_gridspec(3 if zoom else 2, max(1, len(harmonics)) if zoom else 1,
                          height_ratios=[0.45, 1.0, 1.1] if zoom else [0.45, 1.0], hspace=0.0)
    ax_hi, ax_lo = fig.add_subplot(gs[0, :]), fig.add_subplot(gs[1, :])
    top = _broken_full_spectrum(result, mesh, component, fmax, db, window,
                                [ln for ln in lines if ln.kind != "sideband"], fr, ax_hi, ax_lo)
    _titled_legend(top, title, ("carrier", "mesh", "sideband") + (("fault",) if fault_marks(result) else ()), band)
    if zoom:
        half = (n_sidebands + 1.5) * fr["carrier"]
        for i, h in enumerate(harmonics):
            axz = fig.add_subplot(gs[2, i])
            plot_spectrum(result, mesh, component, min(h.freq + half, fmax), db, window,
                          [ln for ln in lines if abs(ln.freq - h.freq) <= half],
                          label_kinds=("mesh", "sideband"), ax=axz,
                          fmin=max(0.0, h.freq - half), note_passband=False)
            note = ", attenuated" if passband is not None and h.freq > passband else ""
            res = result.fs / result.time.size  # the spectrum's bin [Hz]; Hann resolves lines 2 bins apart
            note += f", {res:.0f} Hz bins: sidebands not resolved" if 2 * res > fr["carrier"] else ""
            axz.set_title(f"{_tex(h.label)} = {h.freq:.0f} Hz{note}", loc="left")
            if i:
                axz.set_ylabel("")
    return fig


def _broken_full_spectrum(result, mesh, component, fmax, db, window, lines, fr, ax_hi, ax_lo):
    """Full-range spectrum on a broken amplitude axis: the lower panel is scaled to the
    mesh-related lines, the upper one shows the top of the (much taller) carrier line, so
    nothing is clipped. In dB one panel suffices (the upper one is hidden). Returns the top
    visible panel."""
    f, A = amplitude_spectrum(mesh_force(result, mesh, component), result.fs, window=window)
    sel = f <= fmax
    low = sel & (f < 0.5 * fr["mesh"])
    mesh_peak = float(np.max(A[sel & ~low])) if np.any(sel & ~low) else 0.0
    carrier_peak = float(np.max(A[low])) if np.any(low) else 0.0
    if db or not mesh_peak > 0 or carrier_peak < 2.0 * mesh_peak:
        ax_hi.set_visible(False)
        plot_spectrum(result, mesh, component, fmax, db, window, lines, label_kinds=("carrier", "mesh"),
                      ax=ax_lo, label_rotation=0, note_passband=False)  # the legend names the band
        return ax_lo
    lo_top = 1.3 * mesh_peak
    hi_bottom = 0.85 * carrier_peak
    hi_top = hi_bottom + (1.04 * carrier_peak - hi_bottom) / (1.0 - 0.35)
    plot_spectrum(result, mesh, component, fmax, db, window, lines, label_kinds=("carrier", "mesh"),
                  ax=ax_hi, ylim=(hi_bottom, hi_top), label_band=0.35, label_rotation=0,
                  note_passband=False)  # the legend names the shaded band; a note would meet the labels
    plot_spectrum(result, mesh, component, fmax, db, window, lines, label_kinds=(), ax=ax_lo,
                  ylim=(0.0, lo_top), label_band=0.0, note_passband=False)
    ax_hi.set_xlabel("")
    ax_hi.set_ylabel("")
    ax_hi.tick_params(labelbottom=False, bottom=False)
    ax_lo.tick_params(top=False)
    ax_hi.spines["bottom"].set_visible(False)
    ax_lo.spines["top"].set_visible(False)
    for ax, y in ((ax_hi, 0.0), (ax_lo, 1.0)):  # break marks on both vertical axes
        for x in (0.0, 1.0):
            ax.plot([x - 0.005, x + 0.005], [y - 0.04, y + 0.04], transform=ax.transAxes, color="k",
                    linewidth=0.6, clip_on=False)
    ax_lo.yaxis.set_label_coords(-0.045, 0.7)
    return ax_hi


@_styled
def fig_planet_positions(result, t_start: float | None = None, duration: float | None = None):
    """Planet centre x and y against time, all planets (paper Fig. 7).

    Parameters
    ----------
    result : Result
        Planetary result (bodies ``planet1``, ``planet2``, ...).
    t_start, duration : float, optional
        Time window [s]; default the whole output.

    Returns
    -------
    matplotlib.figure.Figure
    """
    planets = [p for p in _planets(result) if p in result.bodies]
    if not planets:
        raise ValueError(f"no planet bodies in result; bodies: {sorted(result.bodies)}")
    fig = _figure(COLUMN_WIDTH, 3.4)
    axes = fig.subplots(2, 1, sharex=True)
    t = np.asarray(result.time, dtype=float)
    sl = _window_slice(t, t_start, duration)
    for k, name in enumerate(planets):
        pos = np.asarray(result.bodies[name].position, dtype=float)[sl] * 1e3
        style = _PLANET_STYLES[k % len(_PLANET_STYLES)]
        for c, ax in enumerate(axes):
            ax.plot(t[sl], pos[:, c], label=name, **style)
    for c, ax in enumerate(axes):
        ax.set_ylabel(f"Planet centre ${'xy'[c]}$ [mm]")
        ax.set_xlim(t[sl][0], t[sl][-1])
    axes[1].set_xlabel("Time $t$ [s]")
    axes[0].set_title("Planet centre positions (global frame)", loc="left")
    axes[0].legend(loc="upper right", ncol=len(planets))
    for ax in axes:
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.25 * (hi - lo))  # room for the legend
    return fig


@_styled
def fig_ring_forces(result, component: str = "y", t_start: float | None = None,
                    duration: float | None = None):
    """Vertical ring-mesh forces of all planets, showing their phase shift (paper Fig. 10).

    Parameters
    ----------
    result : Result
        Planetary result (meshes ``planet<i>-ring``).
    component : {"y", "x", "normal"}, optional
        Default ``"y"``.
    t_start, duration : float, optional
        Time window [s]; default two carrier revolutions (or the whole output if shorter).

    Returns
    -------
    matplotlib.figure.Figure
    """
    meshes = [f"{p}-ring" for p in _planets(result) if f"{p}-ring" in result.meshes]
    if not meshes:
        raise ValueError(f"no planet-ring meshes in result; meshes: {sorted(result.meshes)}")
    if duration is None:
        fa = characteristic_frequencies(result)["carrier"]
        duration = 2.0 / fa if fa > 0 else None
    fig = _figure(DOUBLE_WIDTH, 2.6)
    ax = fig.add_subplot()
    for k, mesh in enumerate(meshes):
        plot_force(result, mesh, component, t_start, duration, ax=ax, label=mesh,
                   **_PLANET_STYLES[k % len(_PLANET_STYLES)])
    ax.set_title("Meshing forces of the planets with the ring", loc="left")
    ax.legend(loc="upper right", ncol=len(meshes))
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi + 0.2 * (hi - lo))
    return fig


# --------------------------------------------------------------------------- writing

def paper_figure_names(kind: str, friction: bool = False, sensors=()) -> list[str]:
    """File names :func:`paper_figures` writes for a run of a ``kind`` ("spur" or "planetary")
    configuration (with ``friction``: one with tooth friction; ``sensors``: the names of its
    sensors), known before the run so that a caller can refuse to overwrite before any work."""
    seen = [f"sensor_{name}.png" for name in sensors]
    if kind == "planetary":
        return ["fig07_planet_positions.png", "fig08_planet1_ring_force.png", "fig09_planet1_ring_spectrum.png",
                "fig10_ring_forces_all_planets.png", "fig11_sun_planet1_force.png", "fig12_sun_planet1_spectrum.png"
                ] + (["friction_planet1_ring.png", "friction_sun_planet1.png"] if friction else []) + seen
    return ["fig03_pinion_wheel_force.png", "fig04_pinion_wheel_spectrum.png"] + (
        ["friction_pinion_wheel.png"] if friction else []) + seen


def _paper_figure_specs(result, db: bool):
    """(file name, builder) pairs of the paper figures for this result."""
    if is_planetary(result):
        p1 = _planets(result)[0] if _planets(result) else "planet1"
        ring, sun = f"{p1}-ring", f"sun-{p1}"
        specs = [("fig07_planet_positions.png", lambda: fig_planet_positions(result))]
        if ring in result.meshes:
            specs += [
                (f"fig08_{p1}_ring_force.png", lambda: fig_mesh_force(result, ring)),
                (f"fig09_{p1}_ring_spectrum.png", lambda: fig_mesh_spectrum(result, ring, db=db)),
                ("fig10_ring_forces_all_planets.png", lambda: fig_ring_forces(result)),
            ]
        if sun in result.meshes:
            specs += [
                (f"fig11_sun_{p1}_force.png", lambda: fig_mesh_force(result, sun)),
                (f"fig12_sun_{p1}_spectrum.png", lambda: fig_mesh_spectrum(result, sun, db=db)),
            ]
        return specs + _friction_specs(result, [ring, sun]) + _sensor_specs(result)
    mesh = _spur_mesh(result)
    tag = mesh.replace("-", "_")
    t = np.asarray(result.time, dtype=float)  # Fig. 3: the paper's first 0.06 s, or about a fault's largest event
    start = None if (event := _fault_event(result, mesh, "y", t)[1]) is None else window_start(t, event, 0.06)
    return [
        (f"fig03_{tag}_force.png", lambda: fig_mesh_force(result, mesh, t_start=start, duration=0.06)),
        (f"fig04_{tag}_spectrum.png", lambda: fig_mesh_spectrum(result, mesh, db=db)),
    ] + _friction_specs(result, [mesh]) + _sensor_specs(result)


def _sensor_specs(result) -> list:
    """(file name, builder) of :func:`~flexgear.results.sensor_plot.fig_sensor` for each sensor."""
    return [(f"sensor_{name}.png", lambda name=name: fig_sensor(result, name))
            for name in (getattr(result, "sensors", None) or {})]


def _friction_specs(result, meshes) -> list:
    """(file name, builder) of :func:`~flexgear.results.friction_plot.fig_friction` for those of
    ``meshes`` with tooth friction."""
    return [(f"friction_{mesh.replace('-', '_')}.png", lambda mesh=mesh: fig_friction(result, mesh)) for mesh in meshes
            if mesh in result.meshes and getattr(result.meshes[mesh], "friction_force", None) is not None]


def paper_figures(result, outdir, overwrite: bool = False, db: bool = False) -> list[Path]:
    """Write the paper's figures for a result as PNGs into ``outdir`` (file names: module docstring).

        Parameters
        ----------
        result : Result
        outdir : str or os.PathLike
            Output directory, created if missing.
        overwrite : bool, optional
            Replace existing figures. Default False: if any target exists nothing is written.
        db : bool, optional
            Spectra in dB re 1 N instead of N.

        Returns
        -------
        list of pathlib.Path
            The files written, in figure order.

        Raises
        ------
        ResultExistsError
            If a target file exists and ``overwrite`` is False (checked before writing anything).
    """
    outdir = Path(outdir)
    specs = _paper_figure_specs(result, db)
    existing = [str(outdir / name) for name, _ in specs if (outdir / name).exists()]
    if existing and not overwrite:
        raise ResultExistsError(f"figure file(s) {', '.join(existing)} already exist; refusing "
                                f"to overwrite (pass overwrite=True, command line --overwrite)")
    outdir.mkdir(parents=True, exist_ok=True)
    written = []
    for name, build in specs:
        fig = build()
        written.append(save_figure(fig, outdir / name, overwrite=True))
    return written
