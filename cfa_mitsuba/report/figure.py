"""What a figure function returns: a drawn figure with its caption, or the
reason it could not be drawn (data the study did not produce).

Figures are made with matplotlib's object interface (``Figure`` on the Agg
canvas, never pyplot), so building a report neither opens windows nor
changes the backend of a user's session.  Panels are placed at fixed
margins in inches (:func:`panel_grid`) rather than by a layout engine: a
figure is then drawn once per file written, which keeps the paper-sized
report (12 CFAs x 4 demosaics) fast to build.
"""

from __future__ import annotations

__all__ = ["ReportFigure", "Absent", "new_figure", "panel_grid", "RC", "figure_bytes", "grid_shape", "cfa_legend",
           "legend_rows"]

import io
import math
from dataclasses import dataclass

#: Matplotlib settings of every report figure (used through rc_context).
#: ``svg.hashsalt`` fixes the SVG ids, so that a rebuild writes the same files.
RC = {
    "figure.dpi": 100, "savefig.dpi": 130, "font.size": 9, "axes.titlesize": 9.5, "axes.labelsize": 9,
    "legend.fontsize": 8, "xtick.labelsize": 8, "ytick.labelsize": 8, "axes.grid": True,
    "grid.color": "#dddddd", "grid.linewidth": 0.6, "axes.spines.top": False, "axes.spines.right": False,
    "svg.hashsalt": "cfa-mitsuba-report", "svg.fonttype": "path", "path.simplify": True,
    "savefig.pad_inches": 0.08, "axes.titleweight": "normal", "legend.frameon": False,
    "font.family": "DejaVu Sans",
    # a fixed title position skips matplotlib's per-draw search for overlapping ticks (no top ticks here)
    "axes.titley": 1.0, "axes.titlepad": 5.0,
    # labels are users' CFA and scene names: a '$' in one must stay a dollar sign, not start mathtext
    "text.parse_math": False,
}


@dataclass
class ReportFigure:
    """A finished figure.

    ``key``: file stem under figures/ (e.g. ``mtf``, ``ab-bilinear``);
    ``section``: the report section it belongs to; ``title``, ``caption``:
    what the reader sees above and below it; ``raster``: an image figure,
    embedded as PNG (vector figures are embedded as SVG); ``group``: a label
    that puts several figures of one section into tabs (e.g. the demosaic);
    ``image``: a finished Pillow image (``figure`` None), written as PNG only.
    """

    key: str
    section: str
    title: str
    caption: str
    figure: object
    raster: bool = False
    group: str | None = None
    image: object = None         # a Pillow image instead of a matplotlib figure (image sheets; PNG only)
    inches: tuple | None = None  # the matplotlib figure's size (width, height), kept by release()
    pixels: tuple | None = None  # the image's size (width, height), kept by release()
    lossless: bool = False       # an image embedded as PNG whatever its size, shown pixelated (the crops)

    def release(self) -> None:
        """Keep the sizes the page needs and drop the matplotlib figure and
        the image (once its bytes are encoded: they hold most of a report's
        memory, and a worker process sends the figure back without them)."""
        if self.figure is not None:
            self.inches = tuple(float(v) for v in self.figure.get_size_inches())
            self.figure.clear()
            self.figure = None
        if self.image is not None:
            self.pixels = (int(self.image.width), int(self.image.height))
            self.image = None

    def size_inches(self) -> tuple | None:
        """(width, height) of the matplotlib figure in inches (None for an image)."""
        return tuple(self.figure.get_size_inches()) if self.figure is not None else self.inches

    def size_pixels(self) -> tuple | None:
        """(width, height) of the image in pixels (None for a matplotlib figure)."""
        return (self.image.width, self.image.height) if self.image is not None else self.pixels


@dataclass
class Absent:
    """A figure the data does not support, and why (shown in the report).

    ``not_in_study``: the study did not measure it at all (no scene feeds
    the metric); the page then names it once in the summary instead of
    showing an empty section.  Otherwise it was measured but something the
    figure needs is missing, and the section says so.
    """

    section: str
    title: str
    reason: str
    not_in_study: bool = False


def new_figure(width_in: float, height_in: float):
    """A matplotlib Figure on the Agg canvas (no pyplot, no global state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in))
    FigureCanvasAgg(fig)
    return fig


def legend_rows(n_items: int, ncol: int) -> int:
    return max(1, math.ceil(n_items / max(1, ncol)))


def panel_grid(rows: int, cols: int, panel_w: float, panel_h: float, *, left: float = 0.65,
               right: float = 0.15, top: float = 0.35, bottom: float = 0.5, wspace: float = 0.35,
               hspace: float = 0.5, sharex: bool = False, sharey: bool = False, n: int | None = None,
               projection=None, width: float | None = None):
    """A figure holding a rows x cols grid of panels of ``panel_w`` x
    ``panel_h`` inches, margins and gaps in inches (``top`` includes room
    for a figure legend).  ``n`` panels (default all) are made, row by row.
    Returns (figure, [axes]).  ``width``: a minimum figure width (the grid
    is centred in it)."""
    grid_w = cols * panel_w + (cols - 1) * wspace
    W = left + grid_w + right
    extra = 0.0
    if width is not None and width > W:
        extra = (width - W) / 2
        W = width
    H = top + rows * panel_h + (rows - 1) * hspace + bottom
    fig = new_figure(W, H)
    axes = []
    first = None
    for i in range((rows * cols) if n is None else n):
        r, c = divmod(i, cols)
        x0 = extra + left + c * (panel_w + wspace)
        y0 = H - top - (r + 1) * panel_h - r * hspace
        kw = {}
        if projection:
            kw["projection"] = projection
        if first is not None and sharex:
            kw["sharex"] = first
        if first is not None and sharey:
            kw["sharey"] = first
        ax = fig.add_axes((x0 / W, y0 / H, panel_w / W, panel_h / H), **kw)
        first = first or ax
        axes.append(ax)
    return fig, axes


def figure_bytes(fig, fmt: str, dpi: float | None = None) -> bytes:
    """The figure encoded as ``fmt`` ('png', 'svg', 'pdf')."""
    buf = io.BytesIO()
    kwargs = {"format": fmt, "metadata": _metadata(fmt)}
    if dpi is not None:
        kwargs["dpi"] = dpi
    import numpy as np

    # matplotlib names an SVG clip rectangle by a hash of its bounds' repr, numpy floats among them;
    # importing colour-science switches numpy to its 1.13 print mode, which writes them otherwise, so
    # without this the ids (not the drawing) would depend on what the process had imported before
    with np.printoptions(legacy=False):
        fig.savefig(buf, **kwargs)
    return buf.getvalue()


def _metadata(fmt: str) -> dict:
    # no dates: a rebuild from the same results gives the same bytes
    if fmt == "svg":
        return {"Date": None, "Creator": "cfa-mitsuba report (matplotlib)"}
    if fmt == "pdf":
        return {"CreationDate": None, "ModDate": None, "Creator": "cfa-mitsuba report (matplotlib)"}
    if fmt == "png":
        return {"Software": "cfa-mitsuba report (matplotlib)"}
    return {}


def grid_shape(n: int, max_cols: int = 4) -> tuple[int, int]:
    """(rows, cols) of a small-multiples grid for ``n`` panels."""
    cols = max(1, min(max_cols, n))
    return math.ceil(n / cols), cols


def cfa_legend(fig, styles: dict, cfas, *, extra=(), ncol: int | None = None, top_in: float = 0.05):
    """One legend for the whole figure: a line and marker per CFA (plus
    ``extra`` (handle, label) pairs, e.g. the ideal sensor)."""
    from matplotlib.lines import Line2D

    handles = [h for h, _ in extra] + [
        Line2D([], [], color=styles[c]["color"], marker=styles[c]["marker"], linestyle=styles[c]["linestyle"],
               markersize=5, linewidth=1.4) for c in cfas]
    labels = [lab for _, lab in extra] + list(cfas)
    n = len(labels)
    H = fig.get_figheight()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 1.0 - top_in / H), ncol=ncol or min(n, 7),
               handlelength=2.4, columnspacing=1.2, borderaxespad=0.0)


#: What each chart-fed metric needs, for the note of a figure the study did not run.
_NOT_RUN = {
    "delta-e": "the ColorChecker (macbeth: ΔE00, Table 1, Figs 8-9)",
    "mtf": "the slanted edge (MTF50, Figs 6, 11)",
    "moire": "the chirp (MSP, Fig 13)",
    "achromatic": "the gray bar (AR error, Fig 14)",
}


def no_details(section, title, res, metric, what):
    """The Absent note of a detail figure: the study ran no scene for
    ``metric``, or its details files are missing."""
    from .style import metric_display

    scene = res.scene_for(metric)
    if scene is None:
        return Absent(section, title, _NOT_RUN.get(metric, f"a scene for {metric_display(metric).short}"),
                      not_in_study=True)
    return Absent(section, title, f"'{metric}' was measured on {scene!r} but its details "
                  f"(details/{scene}/<cfa>/<demosaic>/L*.json) are missing: rerun the study to rebuild them")


def label_sweep_panel(ax, row: int, col: int, rows: int, title: str, xlabel: str, info, scene: str) -> None:
    """Titles and labels of one panel of a metric-against-axis grid (rows
    are (scene, metric), columns demosaics): the method on the top row, the
    axis under the bottom row, the metric, its unit and direction at the left."""
    if row == 0:
        ax.set_title(title)
    if row == rows - 1:
        ax.set_xlabel(xlabel)
    if col == 0:
        unit = f" ({info.unit})" if info.unit else ""
        better = "higher" if info.higher_better else "lower"
        ax.set_ylabel(f"{info.short}{unit}\n{scene}, {better} is better")
    else:
        ax.tick_params(labelleft=False)
