"""The CFAs by family and read-out mode, each layout's tile drawn beside its
scores (issue 16): one row per (CFA, readout), grouped by the filter
letters the layout uses; a bar per demosaic for the mean of the eight
scores.

A readout other than the study's own is measured only by a ``[[sweep]]
readout = [...]``, so it has no row in scores.csv; its scores here are the
same eq. 8 map with the study's ranges (``ranges.json``; clipped to [0, 1]
as the study clips), averaged over the scored metrics the sweep measured,
so every row of the figure is scored alike.
"""

from __future__ import annotations

__all__ = ["draw_tile", "family_of", "tiles_by_family", "FILTER_COLOURS"]


import numpy as np

from .figure import Absent, ReportFigure
from .results import SCORED_METRICS, Results
from .style import demosaic_styles

#: Fill of each filter letter (W: clear/panchromatic; other names grey, labelled).
FILTER_COLOURS = {"R": "#d83a34", "G": "#3fa34d", "B": "#3b6fd1", "C": "#37c3d6", "M": "#d65bc1", "Y": "#f2d21b",
                  "W": "#f7f7f7", "X": "#cccccc"}
#: Readable names of the letter sets (W is any clear pixel: RCCB's and RCCC's C).
_FAMILIES = {"RGB": "RGB", "RBY": "RYYB (yellow for green)", "RBW": "RCCB (clear for green)", "RW": "RCCC (clear + red)",
             "RGBW": "RGBW", "CMY": "CMY", "GCMY": "CMYG", "W": "monochrome"}
_READOUT_ORDER = ("full", "remosaic", "bin")


def family_of(channels) -> str:
    """The family label of a CFA from its filter letters (channel order)."""
    key = "".join(channels)
    return _FAMILIES.get(key, key)


def draw_tile(ax, pattern, x0: float, y0: float, size: float, block: int = 1) -> None:
    """Draw ``pattern`` (tile of filter names) as coloured squares in the box
    [x0, x0 + size] x [y0, y0 + size] of ``ax`` (top row at the top); with
    ``block`` > 1, outline the binned blocks."""
    from matplotlib.patches import Rectangle

    p = np.asarray(pattern)
    th, tw = p.shape
    cell = size / max(th, tw)
    for (i, j), name in np.ndenumerate(p):
        colour = FILTER_COLOURS.get(str(name), FILTER_COLOURS["X"])
        ax.add_patch(Rectangle((x0 + j * cell, y0 + size - (i + 1) * cell), cell, cell, facecolor=colour,
                               edgecolor="#555555", linewidth=0.3))
        if str(name) not in FILTER_COLOURS and cell > 0.08:
            ax.text(x0 + (j + 0.5) * cell, y0 + size - (i + 0.5) * cell, str(name), fontsize=4, ha="center",
                    va="center")
    if block > 1:
        for bi in range(th // block):
            for bj in range(tw // block):
                ax.add_patch(Rectangle((x0 + bj * block * cell, y0 + size - (bi + 1) * block * cell), block * cell,
                                       block * cell, fill=False, edgecolor="black", linewidth=1.0))


def _block_size(facts: dict) -> int:
    return int(facts.get("block") or 1)


def _ranges(res: Results) -> tuple[dict, set]:
    from ..study.scoring import DEFAULT_RANGES

    ranges = {m: v for m, v in res.ranges.items() if m in SCORED_METRICS}
    if not ranges:
        ranges = {k: (r.worst, r.best) for k, r in DEFAULT_RANGES.items()}
    from ..io.guard import read_json

    raw = {}
    try:  # bounded, not nested deeper than a ranges file (100,000 '[' is refused unparsed)
        raw = read_json(res.root / "ranges.json", allow_nan=True)
    except (OSError, ValueError):  # CfaMitsubaError is a ValueError
        pass
    constant = set(raw.get("_constant") or []) if isinstance(raw, dict) else set()
    return ranges, constant


def _scores(res: Results) -> dict:
    """{(cfa, readout): {demosaic: mean score}} at the primary luminance.

    The study's own read-out: scores.csv's ``mean_score`` (Table 3's cells,
    the one rule for scores and bounds: study/censored.py).  Another
    read-out (a ``[[sweep]] readout``): its values in metrics.csv scored with
    the same ranges and the same rule for a bound."""
    import pandas as pd

    from ..study.censored import values_for_scoring
    from ..study.scoring import ScoreRange
    from .figures_sweep import axis_rows

    own = str((res.config.get("base_condition") or {}).get("readout") or "full")
    out: dict = {}
    s = res.scores
    if s is not None and len(s) and res.primary_luminance is not None:
        s = s[s["luminance"] == res.primary_luminance]
        for (cfa, dem), g in s.groupby(["cfa", "demosaic"], sort=False):
            out.setdefault((str(cfa), own), {})[str(dem)] = float(g["mean_score"].iloc[0])
    m = res.all_metrics if res.all_metrics is not None else res.metrics
    if "readout" not in m.columns:
        return out
    rows = axis_rows(res, "readout")
    rows = rows[rows["readout"].astype(str) != own]
    if res.primary_luminance is not None:
        rows = rows[rows["luminance"] == res.primary_luminance]
    ranges, constant = _ranges(res)
    clip = bool((res.config.get("clip_scores", True)))
    by: dict = {}
    for metric in SCORED_METRICS:
        if metric not in ranges or metric in constant:
            continue
        g = rows[(rows["metric"] == metric) & (rows["scene"] == res.scene_for(metric))]
        if not len(g):
            continue
        worst, best = (float(v) for v in ranges[metric])
        g = values_for_scoring(g.assign(censored=g["censored"] if "censored" in g else False),
                               {metric: ScoreRange(worst, best)})
        for r in g.itertuples(index=False):
            sc = (float(r.value) - worst) / (best - worst)
            sc = min(max(sc, 0.0), 1.0) if clip else sc
            by.setdefault((str(r.cfa), str(r.readout)), {}).setdefault(str(r.demosaic), []).append(sc)
    out.update({k: {d: float(pd.Series(v).mean()) for d, v in per.items()} for k, per in by.items()})
    return out


def tiles_by_family(res: Results):
    """The figure: CFAs grouped by family and read-out mode, tile beside scores."""
    import matplotlib.pyplot as plt

    title = "CFAs by family and read-out mode"
    scores = _scores(res)
    if not scores:
        return Absent("scores", title, "scored metrics at the primary luminance")
    cfas = res.cfa_facts  # cfas.json: what the study recorded of each CFA
    families: dict = {}
    for cfa in res.cfas:
        for readout in _READOUT_ORDER:
            if (cfa, readout) in scores:
                fam = family_of(cfas[cfa]["channels"]) if cfa in cfas else "other"
                families.setdefault(fam, []).append((cfa, readout))
    dems = [d for d in res.demosaics if any(d in by for by in scores.values())]
    dst = demosaic_styles(res.demosaics)
    n_rows = sum(len(v) + 1 for v in families.values())
    y, bar_x0, bar_w = 0.0, 3.9, 4.0
    fig, ax = plt.subplots(figsize=(0.62 * (bar_x0 + bar_w + 0.8), 0.62 * (n_rows + 0.7)))
    fig.subplots_adjust(left=0.02, right=0.98, top=0.98, bottom=0.01)
    for fam, entries in families.items():
        ax.text(0.0, y - 0.45, fam, fontsize=8, fontweight="bold", va="center")
        ax.plot([0, bar_x0 + bar_w + 0.8], [y - 0.85, y - 0.85], color="#999999", linewidth=0.5)
        y -= 1.0
        for cfa, readout in entries:
            obj = cfas.get(cfa)
            if obj is not None:
                n = _block_size(obj)
                draw_tile(ax, obj["pattern"], 0.05, y - 0.92, 0.84, block=n if readout == "bin" else 1)
                if readout in ("remosaic", "bin") and n > 1 and obj.get("binned_pattern"):
                    draw_tile(ax, obj["binned_pattern"], 1.0, y - 0.7, 0.44)
            label = cfa if readout == "full" else (f"{cfa}\nremosaic to Bayer" if readout == "remosaic"
                                                   else f"{cfa}\nbinned {n}×{n}" if obj is not None
                                                   else f"{cfa}\n{readout}")
            ax.text(1.6, y - 0.46, label, fontsize=7, va="center")
            by = scores[(cfa, readout)]
            h = 0.8 / max(len(dems), 1)
            for k, d in enumerate(dems):
                if d not in by:
                    continue
                yy = y - 0.1 - (k + 1) * h
                ax.add_patch(plt.Rectangle((bar_x0, yy), bar_w * by[d], h * 0.85, color=dst[d]["color"]))
                ax.text(bar_x0 + bar_w * by[d] + 0.05, yy + h * 0.42, f"{by[d]:.2f}", fontsize=5, va="center")
            y -= 1.0
    ax.set_xlim(0, bar_x0 + bar_w + 0.8)
    ax.set_ylim(y - 0.1, 0.6)
    ax.set_aspect("equal")
    ax.axis("off")
    x = 0.0
    for d in dems:  # the demosaic legend across the top
        ax.add_patch(plt.Rectangle((x, 0.2), 0.25, 0.25, color=dst[d]["color"], clip_on=False))
        ax.text(x + 0.32, 0.32, d, fontsize=6, va="center")
        x += 0.6 + 0.11 * len(d)
    lum = f" at {res.primary_luminance:g} cd/m²" if res.primary_luminance is not None else ""
    cap = ("Each CFA's repeating tile (R, G, B, C, M, Y as their colours; W, any clear pixel, white) beside the mean of "
           f"its scores{lum}, one bar per demosaic (0 worst, 1 best, the study's score ranges; Table 3's cells, "
           "a moiré bound scored by the same rule), grouped by the "
           "filter letters the layout uses.  A block layout read with remosaic is drawn with the Bayer tile it is "
           "rearranged to, one binned with its blocks outlined and the binned tile; a readout other than the "
           "study's own comes from a [[sweep]] readout = [...] and is scored here with the same ranges.")
    return ReportFigure("tiles", "scores", title, cap, fig)
