"""Publication style of every flexgear figure: journal sizes, fonts, thin lines, atomic PNG writing.

Figures are built with :class:`matplotlib.figure.Figure` and the Agg canvas, without pyplot, so
using them never changes the user's matplotlib backend or global state; styling is applied
through :func:`paper_style` (a ``matplotlib.rc_context``). Sizes follow a journal layout: one
column 3.5 in, two columns 7 in; PNGs are written at 300 dpi.
"""
from __future__ import annotations

import contextlib
import functools
from pathlib import Path

from .files import atomic_write, check_targets

COLUMN_WIDTH = 3.5  # in, one journal column
DOUBLE_WIDTH = 7.0  # in, two columns
DPI = 300
#: Mesh periods a zoom on a long force trace shows (and the friction figure's window).
ZOOM_PERIODS = 6
#: Colour of marks drawn over a trace: a zoom's window, the pitch-point crossings.
MARK_COLOR = "#c0392b"
_RC = {
    "font.family": "serif",
    "font.serif": ["STIXGeneral", "DejaVu Serif"],
    "mathtext.fontset": "stix",
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "legend.fontsize": 6.5,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "axes.linewidth": 0.6,
    "lines.linewidth": 0.6,
    "xtick.major.width": 0.5,
    "ytick.major.width": 0.5,
    "xtick.minor.width": 0.4,
    "ytick.minor.width": 0.4,
    "xtick.direction": "in",
    "ytick.direction": "in",
    "xtick.top": True,
    "ytick.right": True,
    "axes.grid": True,
    "grid.linewidth": 0.3,
    "grid.alpha": 0.5,
    "grid.color": "0.6",
    "legend.frameon": False,
    "savefig.dpi": DPI,
    "figure.dpi": 100,
    "axes.formatter.useoffset": False,
}
_POWERS = str.maketrans("-0123456789", "\u207b\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079")


def unit_label(units: str) -> str:
    """``units`` as a figure shows them: powers superscript (``m/s^2`` as m/s\u00b2), as published
    figures write them; files and tables keep the plain form."""
    import re

    return re.sub(r"\^(-?\d+)(?![.\d])", lambda m: m.group(1).translate(_POWERS), units)


@contextlib.contextmanager
def paper_style():
    """Context manager applying the publication style (serif, thin lines, light grid)."""
    import matplotlib

    with matplotlib.rc_context(_RC):
        yield


def styled(func):
    """Decorator: run ``func`` inside :func:`paper_style`."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with paper_style():
            return func(*args, **kwargs)

    return wrapper


@functools.cache
def _paper_figure_class():
    from matplotlib.figure import Figure

    class PaperFigure(Figure):
        """A Figure that draws and saves itself in :func:`paper_style`, wherever that happens
        (``fig.savefig`` in a script, a notebook): matplotlib makes the tick labels and the
        constrained layout at draw time, from the rc parameters then in force."""

        def draw(self, renderer):
            with paper_style():
                return super().draw(renderer)

        def savefig(self, *args, **kwargs):
            with paper_style():  # 300 dpi unless told otherwise
                return super().savefig(*args, **kwargs)

    PaperFigure.__module__, PaperFigure.__qualname__ = __name__, "PaperFigure"  # picklable by name
    return PaperFigure


def __getattr__(name):
    if name == "PaperFigure":  # the class is made on first use (matplotlib imported then)
        return _paper_figure_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def figure(width: float, height: float, layout: str | None = "constrained"):
    """A ``PaperFigure`` (a Figure that draws in :func:`paper_style`) on the Agg canvas (no
    pyplot), size in inches; constrained layout unless ``layout`` is None (fixed margins: one
    drawing pass instead of a layout pass and a drawing)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = _paper_figure_class()(figsize=(width, height), layout=layout)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path, overwrite: bool = False) -> Path:
    """Write ``fig`` as a 300 dpi PNG, atomically (temporary file + ``os.replace``).

    Raises
    ------
    ResultExistsError
        If ``path`` exists and ``overwrite`` is False.
    """
    path = Path(path)
    check_targets([path], overwrite)

    def write(tmp):
        with paper_style():
            fig.savefig(tmp, dpi=DPI, format="png")

    atomic_write(path, write)
    return path


def save_figures(items, overwrite: bool = False, compress_level: int = 1) -> list[Path]:
    """Write several figures as 300 dpi PNGs (RGB), checking every target first.

    Each figure is made and drawn here and its PNG compressed in a worker thread (Pillow releases
    the GIL while it compresses), so that compressing one overlaps drawing the next.

    Parameters
    ----------
    items : sequence of (Figure or callable returning a Figure, path)
        A callable is called only when its turn comes (after the previous figure is drawn).
    overwrite : bool, optional
        Replace existing files; otherwise any existing target raises before anything is drawn.
    compress_level : int, optional
        zlib level, 0-9. Default 1 (fast).

    Raises
    ------
    ResultExistsError
        If a target exists and ``overwrite`` is False.
    """
    from concurrent.futures import ThreadPoolExecutor

    import numpy as np
    from PIL import Image

    paths = [Path(p) for _, p in items]
    check_targets(paths, overwrite)

    def encode(rgb, path):
        atomic_write(path, lambda tmp: Image.fromarray(rgb).save(tmp, format="png", dpi=(DPI, DPI),
                                                                 compress_level=compress_level))

    with ThreadPoolExecutor(max_workers=1) as pool:
        done = []
        for make, path in items:
            with paper_style():
                fig = make() if callable(make) else make
                fig.set_dpi(DPI)
                fig.canvas.draw()
            done.append(pool.submit(encode, np.ascontiguousarray(np.asarray(fig.canvas.buffer_rgba())[..., :3]), path))
        for f in done:
            f.result()
    return paths

