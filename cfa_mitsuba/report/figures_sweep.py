"""A metric against any swept study axis (f-number, pixel pitch, exposure,
read noise, noise seed): one figure per axis that a ``[[sweep]]`` varied,
one row per (scene, metric), one column per demosaic, a line per CFA.

Luminance has its own figure (:func:`.figures_scores.luminance_sweep`, the
paper's sweep); here every other axis is drawn at the scores' luminance,
the other axes held at the study's own values.  What the figure knows of an
axis (its label and unit, numbers or categories, realisations or a scale,
the caption's note) is its record's (:class:`~cfa_mitsuba.study.axes.Axis`).
"""

from __future__ import annotations

__all__ = ["axis_sweep", "axis_rows"]

import numpy as np

from ..study.axes import AXES, get_axis
from .figure import Absent, ReportFigure, cfa_legend, label_sweep_panel, legend_rows, panel_grid
from .results import SCORED_METRICS, Results
from .style import cfa_styles, metric_display

def axis_rows(res: Results, axis: str):
    """The rows of metrics.csv where ``axis`` varies and every other axis but
    luminance keeps its study value (per scene), at the primary luminance."""
    m = res.all_metrics if res.all_metrics is not None else res.metrics
    if axis not in m.columns:
        return m.iloc[0:0]
    others = [a for a in list(AXES)[1:] if a != axis and a in m.columns]
    base = res.metrics
    keep = np.zeros(len(m), dtype=bool)
    for (scene, cfa), g in base.groupby(["scene", "cfa"], sort=False):
        ref = {a: str(g[a].iloc[0]) for a in others}
        sel = ((m["scene"] == scene) & (m["cfa"] == cfa)).to_numpy().copy()
        for a, v in ref.items():
            sel &= (m[a].astype(str) == v).to_numpy()
        keep |= sel
    if res.primary_luminance is not None:
        keep &= (m["luminance"] == res.primary_luminance).to_numpy()
    return m[keep]


def _numeric(record, values) -> bool:
    """Whether the values are drawn on a numeric scale: a numeric axis whose
    values are all numbers (an exposure sweep with 'auto' is categories)."""
    if not record.numeric:
        return False
    try:
        values.astype(float)
    except (TypeError, ValueError):
        return False
    return True


def axis_sweep(res: Results, axis: str):
    record = get_axis(axis)
    title = f"Metrics against {record.label}"
    m = axis_rows(res, axis)
    pairs = [(s, k) for (s, k), g in m.groupby(["scene", "metric"], sort=False)  # varied for one CFA, not across
             if g.groupby("cfa")[axis].agg(lambda v: v.astype(str).nunique()).max() > 1 and k in SCORED_METRICS]
    if not pairs:
        return Absent("sweep", title, f"a sweep of {axis} ([[sweep]] {axis} = [...])", not_in_study=True)
    pairs.sort(key=lambda p: (SCORED_METRICS.index(p[1]), p[0]))
    dems = [d for d in res.demosaics if d in set(m["demosaic"])]
    cst = cfa_styles(res.cfas)
    rows, cols = len(pairs), len(dems)
    ncol = min(len(res.cfas), 7)
    fig, axes = panel_grid(rows, cols, 2.7, 2.0, left=0.95, right=0.15,
                           top=0.35 + 0.2 * legend_rows(len(res.cfas), ncol), bottom=0.5, wspace=0.15, hspace=0.35,
                           width=6.0)
    numeric = _numeric(record, m[axis])
    drawn = []
    unit = record.unit
    for r, (scene, metric) in enumerate(pairs):
        info = metric_display(metric)
        g = m[(m["scene"] == scene) & (m["metric"] == metric)]
        levels = sorted(g[axis].astype(float).unique()) if numeric else list(dict.fromkeys(g[axis].astype(str)))
        share = None
        for c, d in enumerate(dems):
            ax = axes[r * cols + c]
            if share is not None:
                ax.sharey(share)
            share = share or ax
            for cfa in res.cfas:
                gc = g[(g["demosaic"] == d) & (g["cfa"] == cfa)]
                if not len(gc):
                    continue
                x = gc[axis].astype(float) if numeric else gc[axis].astype(str).map(levels.index)
                order = np.argsort(np.asarray(x, dtype=float))
                st = cst[cfa]
                ax.plot(np.asarray(x, dtype=float)[order], gc["value"].to_numpy()[order], color=st["color"],
                        marker=st["marker"], linestyle="none" if record.realisations else st["linestyle"],
                        linewidth=1.2, markersize=3.5)
                if cfa not in drawn:
                    drawn.append(cfa)
            if not numeric:
                ax.set_xticks(range(len(levels)))
                ax.set_xticklabels(levels, fontsize=7)
            label_sweep_panel(ax, r, c, rows, d, record.label + (f" ({unit})" if unit else ""), info, scene)
    cfa_legend(fig, cst, [c for c in res.cfas if c in drawn], ncol=ncol)
    lum = f" at {res.primary_luminance:g} cd/m²" if res.primary_luminance is not None else ""
    cap = (f"Each scored metric that a sweep measured at several values of {record.label}{lum}, "
           "every other axis at the study's own value. " + record.note)
    return ReportFigure(f"sweep-{axis}", "sweep", title, cap, fig)
