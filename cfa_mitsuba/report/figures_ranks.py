"""Rank charts with their intervals, and the score heatmap that replaces the
radar plots above six CFAs.

- :func:`rank_chart`: per demosaic and for the total, each CFA's mean
  score as a bar with its 95 % interval as an error bar, and its rank
  interval in the label (``1–3 rgb5``: tied CFAs are drawn as tied, not as
  strictly ordered).  Names sit left of the axis and values right of the
  interval's end, so no label overlaps a bar or another label.
- :func:`score_heatmap`: CFA x metric per demosaic, the score as a colour
  and a number (± half its interval in the cell when it is wide enough to
  matter): readable for any number of CFAs, where 12 radar polygons are not.
"""

from __future__ import annotations

__all__ = ["rank_chart", "score_heatmap", "HEATMAP_ABOVE"]

import math

import numpy as np

from .figure import Absent, ReportFigure, panel_grid
from .results import SCORED_METRICS, Results
from .style import cfa_styles, metric_display

#: Above this many CFAs the report draws the heatmap instead of the radar plots.
HEATMAP_ABOVE = 6


def _span(b: int, w: int) -> str:
    return f"{b}" if b == w else f"{b}–{w}"


def _panels(res: Results, s):
    """[(label, DataFrame cfa -> score, lo, hi, best, worst)] per demosaic and the total."""
    import pandas as pd

    per = s.drop_duplicates(["cfa", "demosaic"])
    have = "mean_score_ci_low" in per.columns
    out = []
    for d in [d for d in res.demosaics if d in set(per["demosaic"])]:
        g = per[per["demosaic"] == d].set_index("cfa")
        out.append((d, pd.DataFrame({
            "score": g["mean_score"].astype(float),
            "lo": g["mean_score_ci_low"].astype(float) if have else g["mean_score"].astype(float),
            "hi": g["mean_score_ci_high"].astype(float) if have else g["mean_score"].astype(float),
            "best": g["demosaic_rank_best"] if have else g["demosaic_rank"],
            "worst": g["demosaic_rank_worst"] if have else g["demosaic_rank"]})))
    if "total_score" in per.columns and len(out) > 1:
        g = per.drop_duplicates("cfa").set_index("cfa")
        out.append(("total (mean over demosaics)", pd.DataFrame({
            "score": g["total_score"].astype(float),
            "lo": g["total_score_ci_low"].astype(float) if have else g["total_score"].astype(float),
            "hi": g["total_score_ci_high"].astype(float) if have else g["total_score"].astype(float),
            "best": g["total_rank_best"] if have else g["total_rank"],
            "worst": g["total_rank_worst"] if have else g["total_rank"]})))
    return out


def rank_chart(res: Results):
    """Mean normalised score, its 95 % interval and rank interval of each CFA,
    one panel per demosaic and one for the total (the paper's Fig 17 a-e)."""
    title = "CFA ranks per demosaicing method and in total, with their intervals (paper Fig 17)"
    s = res.scores
    if s is None or res.primary_luminance is None or not len(s):
        return Absent("scores", title, "no scores")
    panels = _panels(res, s[s["luminance"] == res.primary_luminance])
    if not panels:
        return Absent("scores", title, "no scores")
    cst = cfa_styles(res.cfas)
    n_cfa = max(len(p[1]) for p in panels)
    cols = min(len(panels), 3)
    rows = math.ceil(len(panels) / cols)
    fig, axes = panel_grid(rows, cols, 2.2, 0.24 * n_cfa + 0.3, left=1.05, right=0.15, top=0.3, bottom=0.45,
                           wspace=1.25, hspace=0.8, n=len(panels))
    vmax = max(1.0, max(float(p[1]["hi"].max()) for p in panels))
    vmin = min(0.0, min(float(p[1]["lo"].min()) for p in panels))
    for ax, (label, df) in zip(axes, panels):
        df = df.sort_values("score", ascending=False, kind="stable")
        y = np.arange(len(df))
        ax.barh(y, df["score"].to_numpy(), color=[cst[c]["color"] for c in df.index], edgecolor="#333333",
                linewidth=0.4, height=0.7)
        ax.errorbar(df["score"].to_numpy(), y, xerr=np.vstack([df["score"] - df["lo"], df["hi"] - df["score"]]),
                    fmt="none", ecolor="#000000", elinewidth=0.9, capsize=2.0)
        ax.set_yticks(y)
        ax.set_yticklabels([f"{_span(int(r.best), int(r.worst))}  {c}" for c, r in df.iterrows()], fontsize=7.5)
        for yy, (c, r) in zip(y, df.iterrows()):
            ax.text(r.hi + 0.015 * (vmax - vmin), yy, f"{r.score:.3f}", va="center", ha="left", fontsize=6.5)
        ax.set_ylim(len(df) - 0.5, -0.5)
        ax.set_xlim(vmin, vmax * 1.22)
        ax.set_xlabel("mean normalised score")
        ax.set_title(label, fontsize=9)
        ax.grid(axis="y", visible=False)
    from .decision_panel import intervals_cover

    cap = (f"Bars: the mean of a CFA's normalised metric scores for each demosaicing method (Table 3) and "
           f"their mean over the methods, at {res.primary_luminance:g} cd/m²; whiskers: the 95 % interval over "
           "the realisations. The label gives the rank interval before the name: CFAs that share ranks (1–3) "
           "are tied, whatever order the bars are in. " + intervals_cover(res.config))
    return ReportFigure("ranks", "scores", title, cap, fig)


def score_heatmap(res: Results):
    """CFA x metric scores, one panel per demosaic (in place of radars above six CFAs)."""
    title = "Normalised metric scores per CFA and demosaicing method (heatmap)"
    s = res.scores
    if s is None or res.primary_luminance is None or not len(s):
        return Absent("scores", title, "no scores")
    s = s[s["luminance"] == res.primary_luminance]
    metrics = [m for m in SCORED_METRICS if m in set(s["metric"])]
    tot = s.drop_duplicates("cfa").sort_values("total_score", ascending=False, kind="stable")
    cfas = [c for c in tot["cfa"] if c in res.cfas]
    dems = [d for d in res.demosaics if d in set(s["demosaic"])]
    by = {(r.cfa, r.demosaic, r.metric): r for r in s.itertuples(index=False)}
    cols = 2 if len(dems) > 1 else 1
    rows = math.ceil(len(dems) / cols)
    fig, axes = panel_grid(rows, cols, 0.62 * len(metrics) + 0.2, 0.3 * len(cfas) + 0.2, left=0.75, right=0.2,
                           top=0.35, bottom=0.75, wspace=0.9, hspace=1.0, n=len(dems))
    for ax, d in zip(axes, dems):
        grid = np.full((len(cfas), len(metrics)), np.nan)
        for i, c in enumerate(cfas):
            for j, m in enumerate(metrics):
                r = by.get((c, d, m))
                if r is not None:
                    grid[i, j] = float(r.score)
                    half = ((float(r.score_ci_high) - float(r.score_ci_low)) / 2
                            if hasattr(r, "score_ci_low") else 0.0)
                    text = f"{r.score:.2f}" + (f"\n±{half:.2f}" if half >= 0.005 else "")
                    ax.text(j, i, text, ha="center", va="center", fontsize=5.6, linespacing=0.9,
                            color="white" if r.score < 0.45 else "black")
        ax.imshow(grid, cmap="viridis", vmin=0.0, vmax=1.0, aspect="auto")
        ax.set_xticks(range(len(metrics)))
        ax.set_xticklabels([metric_display(m).short for m in metrics], rotation=45, ha="right", fontsize=7)
        ax.set_yticks(range(len(cfas)))
        ax.set_yticklabels(cfas, fontsize=7)
        ax.set_title(d, fontsize=9)
        ax.grid(False)
    cap = (f"Each cell: a CFA's normalised score on one metric (eq. 8) with one demosaicing method, at "
           f"{res.primary_luminance:g} cd/m², ± half its 95 % interval where that is at least 0.005; rows sorted "
           "by the total score (Table 3); colour: viridis from 0 (dark blue) to 1 (yellow, the ideal sensor). Drawn in place of the radar plots when more than "
           f"{HEATMAP_ABOVE} CFAs are compared, where a radar's polygons can no longer be told apart.")
    return ReportFigure("heatmap", "scores", title, cap, fig)
