"""Figures of the normalised scores: radar plots (the paper's Fig 16), rank
charts (Fig 17) and the metrics against luminance (the paper's sweep of
S-CIELAB and SSIM over 3..400 cd/m^2, s. 3)."""

from __future__ import annotations

__all__ = ["radar_per_cfa", "radar_per_demosaic", "rank_chart", "luminance_sweep"]


import numpy as np

from .figure import Absent, ReportFigure, cfa_legend, grid_shape, label_sweep_panel, legend_rows, panel_grid
from .results import SCORED_METRICS, Results
from .style import cfa_styles, demosaic_styles, metric_display


def _score_grid(res: Results):
    """(metrics, {(cfa, demosaic): array of scores in metric order}) at the
    primary luminance, or None."""
    s = res.scores
    if s is None or res.primary_luminance is None:
        return None
    s = s[s["luminance"] == res.primary_luminance]
    metrics = [m for m in SCORED_METRICS if m in set(s["metric"])]
    metrics += [m for m in dict.fromkeys(s["metric"]) if m not in metrics]
    grid = {}
    for (cfa, dem), g in s.groupby(["cfa", "demosaic"], sort=False):
        by = dict(zip(g["metric"], g["score"].astype(float)))
        grid[(cfa, dem)] = np.array([by.get(m, np.nan) for m in metrics], dtype=float)
    return metrics, grid


def _score_bands(res: Results, metrics) -> dict:
    """{(cfa, demosaic): (low, high)} of each spoke's 95 % score interval
    (scores.csv's score_ci_low / score_ci_high), empty for older results."""
    s = res.scores
    if s is None or "score_ci_low" not in s.columns:
        return {}
    s = s[s["luminance"] == res.primary_luminance]
    out = {}
    for (cfa, dem), g in s.groupby(["cfa", "demosaic"], sort=False):
        lo = dict(zip(g["metric"], g["score_ci_low"].astype(float)))
        hi = dict(zip(g["metric"], g["score_ci_high"].astype(float)))
        out[(cfa, dem)] = (np.array([lo.get(m, np.nan) for m in metrics]), np.array([hi.get(m, np.nan) for m in metrics]))
    return out


def _overflow(grid) -> tuple[bool, bool]:
    vals = np.concatenate([v for v in grid.values()]) if grid else np.array([0.0])
    vals = vals[np.isfinite(vals)]
    return bool((vals > 1.0).any()), bool((vals < 0.0).any())


class _Radar:
    """A radar (spider) chart drawn on plain axes: polygons for the score
    levels 0.25 ... 1, a spoke per metric, outward = better.  A score above
    1 is drawn at 1.1 with a hollow marker, one below 0 at the centre.
    (Matplotlib's polar axes draw several times slower, which matters at
    12 CFAs.)"""

    OVER = 1.1

    def __init__(self, ax, metrics, title, label_size=7.5):
        self.ax = ax
        n = len(metrics)
        self.theta = np.pi / 2 - 2 * np.pi * np.arange(n) / n
        ax.set_aspect("equal")
        ax.set_axis_off()
        lim = 1.45
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim * 1.02, lim * 1.02)
        ct, st = np.cos(self.theta), np.sin(self.theta)
        half = np.pi / n
        for t in (0.25, 0.5, 0.75, 1.0):
            ax.plot(np.append(t * ct, t * ct[0]), np.append(t * st, t * st[0]),
                    color="#bbbbbb" if t == 1.0 else "#dddddd", linewidth=0.8 if t == 1.0 else 0.6, zorder=0)
            ax.text(t * np.cos(self.theta[0] - half), t * np.sin(self.theta[0] - half), f"{t:g}", fontsize=6,
                    color="#888888", ha="center", va="center", zorder=1)
        for c, s_, m in zip(ct, st, metrics):
            ax.plot([0, c], [0, s_], color="#dddddd", linewidth=0.6, zorder=0)
            ha = "left" if c > 0.15 else ("right" if c < -0.15 else "center")
            va = "bottom" if s_ > 0.15 else ("top" if s_ < -0.15 else "center")
            ax.text(1.16 * c, 1.16 * s_, metric_display(m).short, fontsize=label_size, ha=ha, va=va)
        ax.text(0, lim * 1.02, title, ha="center", va="bottom", fontsize=9.5, fontweight="bold")

    def band(self, low, high, color):
        """The 95 % interval of every spoke's score as a shaded ring between
        the low and the high polygon."""
        lo = np.clip(np.asarray(low, dtype=float), 0.0, 1.0)
        hi = np.clip(np.asarray(high, dtype=float), 0.0, 1.0)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))) or np.allclose(lo, hi):
            return
        c, s_ = np.cos(self.theta), np.sin(self.theta)
        n = len(lo)
        for i in range(n):  # one quadrilateral per pair of neighbouring spokes: a ring, not a disc
            j = (i + 1) % n
            self.ax.fill([hi[i] * c[i], hi[j] * c[j], lo[j] * c[j], lo[i] * c[i]],
                         [hi[i] * s_[i], hi[j] * s_[j], lo[j] * s_[j], lo[i] * s_[i]],
                         color=color, alpha=0.22, linewidth=0, zorder=1)

    def polygon(self, values, *, fill=False, **style):
        v = np.asarray(values, dtype=float)
        over, under = v > 1.0, v < 0.0
        rho = np.where(over, self.OVER, np.clip(v, 0.0, 1.0))
        x, y = rho * np.cos(self.theta), rho * np.sin(self.theta)
        marker = style.pop("marker", None)
        self.ax.plot(np.append(x, x[0]), np.append(y, y[0]), linewidth=1.2, **style)
        ok = np.isfinite(v) & ~over & ~under
        if marker:
            self.ax.plot(x[ok], y[ok], marker=marker, markersize=3, linestyle="none", color=style.get("color"))
        if (over | under).any():
            self.ax.plot(x[over | under], y[over | under], marker=marker or "o", markersize=4.5, linestyle="none",
                         markerfacecolor="white", markeredgecolor=style.get("color"), markeredgewidth=1.0)
        if fill:
            f = np.isfinite(x)
            self.ax.fill(x[f], y[f], color=style.get("color"), alpha=0.10, linewidth=0)


def _clip_note(grid) -> str:
    above, below = _overflow(grid)
    if above or below:
        where = " and ".join(w for w, f in (("just outside the outer polygon (above 1)", above),
                                            ("at the centre (below 0)", below)) if f)
        return (f" Scores outside [0, 1] (values beyond their score range, which this study did not clip) are "
                f"drawn {where} with a hollow marker; Tables 2-3 hold their values.")
    return ""


def _legend_top(fig, handles, labels, ncol, title=None):
    H = fig.get_figheight()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 1.0 - 0.05 / H), ncol=ncol,
               title=title, borderaxespad=0.0, handlelength=2.4, columnspacing=1.2)


def radar_per_cfa(res: Results):
    """Radar of the normalised metrics, one panel per CFA, one polygon per
    demosaic: how a CFA's strengths move with the demosaicing method (the
    paper's Fig 16 turned around)."""
    from matplotlib.lines import Line2D

    title = "Normalised metrics per CFA (radar)"
    got = _score_grid(res)
    if got is None:
        return Absent("scores", title, "no scores (scores.csv is absent and nothing could be scored)")
    metrics, grid = got
    if len(metrics) < 3:
        return Absent("scores", title, f"a radar needs at least three metrics; this study scored "
                      f"{len(metrics)} ({', '.join(metrics)}): see Tables 2-3")
    cfas = [c for c in res.cfas if any((c, d) in grid for d in res.demosaics)]
    dems = [d for d in res.demosaics if any((c, d) in grid for c in cfas)]
    dst = demosaic_styles(res.demosaics)
    rows, cols = grid_shape(len(cfas), 4)
    fig, axes = panel_grid(rows, cols, 2.7, 2.7, left=0.15, right=0.15, top=0.55, bottom=0.1, wspace=0.25,
                           hspace=0.2, n=len(cfas))
    bands = _score_bands(res, metrics)
    for ax, cfa in zip(axes, cfas):
        radar = _Radar(ax, metrics, cfa)
        for d in dems:
            v = grid.get((cfa, d))
            if v is not None:
                st = dst[d]
                if (cfa, d) in bands:
                    radar.band(*bands[(cfa, d)], st["color"])
                radar.polygon(v, fill=len(dems) <= 2, color=st["color"], linestyle=st["linestyle"],
                              marker=st["marker"])
    handles = [Line2D([], [], color=dst[d]["color"], linestyle=dst[d]["linestyle"], marker=dst[d]["marker"],
                      markersize=4) for d in dems]
    _legend_top(fig, handles, dems, len(dems))
    cap = (f"Each spoke is one metric's score (eq. 8: 0 = the range's worst end at the centre, 1 = its best; "
           f"outward is better for every metric), at {res.primary_luminance:g} cd/m². One panel per CFA, one "
           f"polygon per demosaicing method; the shaded ring around each is its 95 % interval over the noise "
           f"realisations." + _clip_note(grid))
    return ReportFigure("radar-cfa", "scores", title, cap, fig)


def radar_per_demosaic(res: Results):
    """Radar of the normalised metrics, one panel per demosaic, one polygon
    per CFA (the paper's Fig 16)."""
    title = "Normalised metrics per demosaicing method (radar, paper Fig 16)"
    got = _score_grid(res)
    if got is None:
        return Absent("scores", title, "no scores (scores.csv is absent and nothing could be scored)")
    metrics, grid = got
    if len(metrics) < 3:
        return Absent("scores", title, f"a radar needs at least three metrics; this study scored {len(metrics)}")
    cfas = [c for c in res.cfas if any((c, d) in grid for d in res.demosaics)]
    dems = [d for d in res.demosaics if any((c, d) in grid for c in cfas)]
    cst = cfa_styles(res.cfas)
    rows, cols = grid_shape(len(dems), 4 if len(cfas) <= 4 else 2)
    size = 4.4 if len(cfas) > 4 else 3.4
    ncol = min(len(cfas), 6)
    top = 0.35 + 0.2 * legend_rows(len(cfas), ncol)
    fig, axes = panel_grid(rows, cols, size, size, left=0.2, right=0.2, top=top, bottom=0.1, wspace=0.3,
                           hspace=0.25, n=len(dems), width=6.0)
    bands = _score_bands(res, metrics)
    for ax, d in zip(axes, dems):
        radar = _Radar(ax, metrics, d, label_size=8.5)
        for cfa in cfas:
            v = grid.get((cfa, d))
            if v is not None:
                st = cst[cfa]
                if (cfa, d) in bands:
                    radar.band(*bands[(cfa, d)], st["color"])
                radar.polygon(v, fill=len(cfas) <= 3, color=st["color"], linestyle=st["linestyle"],
                              marker=st["marker"])
    cfa_legend(fig, cst, cfas, ncol=ncol)
    cap = (f"One panel per demosaicing method, one polygon per CFA, at {res.primary_luminance:g} cd/m²; "
           "outward is better on every spoke (0 at the centre, 1 at the outer polygon); the shaded ring around "
           "each polygon is its 95 % interval over the noise realisations." + _clip_note(grid))
    return ReportFigure("radar-demosaic", "scores", title, cap, fig)


def rank_chart(res: Results):
    """The rank chart with score and rank intervals (:func:`.figures_ranks.rank_chart`)."""
    from .figures_ranks import rank_chart as chart

    return chart(res)


def luminance_sweep(res: Results):
    """The metrics measured at several luminances (the paper's sweep of
    S-CIELAB and SSIM on PUPPY, 3..400 cd/m^2) against luminance on a log
    axis: one row per metric, one column per demosaic, a line per CFA."""
    from .conditions import exposure_policy_sentence

    title = "Metrics against scene luminance"
    m = res.metrics
    pairs = []
    for (scene, metric), g in m.groupby(["scene", "metric"], sort=False):
        if g["luminance"].nunique() > 1 and metric in SCORED_METRICS:
            pairs.append((scene, metric))
    if not pairs:
        return Absent("sweep", title, "a luminance sweep (a [[sweep]] in the config adds one, as the paper's "
                      "S-CIELAB and SSIM on puppy at 3-400 cd/m²)", not_in_study=True)
    pairs.sort(key=lambda p: (SCORED_METRICS.index(p[1]), p[0]))
    dems = [d for d in res.demosaics if d in set(m["demosaic"])]
    cst = cfa_styles(res.cfas)
    rows, cols = len(pairs), len(dems)
    ncol = min(len(res.cfas), 7)
    fig, axes = panel_grid(rows, cols, 2.7, 2.0, left=0.95, right=0.15, top=0.35 + 0.2 * legend_rows(len(res.cfas), ncol),
                           bottom=0.5, wspace=0.15, hspace=0.35, width=6.0)
    cfas_drawn = []
    for r, (scene, metric) in enumerate(pairs):
        info = metric_display(metric)
        g = m[(m["scene"] == scene) & (m["metric"] == metric)]
        lums = sorted(g["luminance"].unique())
        share = None
        for c, d in enumerate(dems):
            ax = axes[r * cols + c]
            if share is not None:
                ax.sharey(share)
            share = share or ax
            gd = g[g["demosaic"] == d]
            for cfa in res.cfas:
                gc = gd[gd["cfa"] == cfa].sort_values("luminance")
                if not len(gc):
                    continue
                st = cst[cfa]
                ax.plot(gc["luminance"], gc["value"], color=st["color"], marker=st["marker"],
                        linestyle=st["linestyle"], linewidth=1.2, markersize=3.5)
                if {"ci_low", "ci_high"} <= set(gc.columns):  # the 95 % interval over the noise realisations
                    # (clipped at 0: a mean rounded in metrics.csv can sit a hair outside its interval)
                    ax.errorbar(gc["luminance"], gc["value"], yerr=np.maximum(np.vstack([gc["value"] - gc["ci_low"],
                                                                                        gc["ci_high"] - gc["value"]]), 0),
                                fmt="none", ecolor=st["color"], elinewidth=0.9, capsize=2.0)
                if cfa not in cfas_drawn:
                    cfas_drawn.append(cfa)
            ax.set_xscale("log")
            ax.set_xticks(lums)
            ax.set_xticklabels([f"{v:g}" for v in lums], fontsize=7)
            ax.minorticks_off()
            if res.primary_luminance is not None and min(lums) <= res.primary_luminance <= max(lums):
                ax.axvline(res.primary_luminance, color="#999999", linewidth=0.8, linestyle=":")
            label_sweep_panel(ax, r, c, rows, d, "scene luminance (cd/m²)", info, scene)
    cfa_legend(fig, cst, [c for c in res.cfas if c in cfas_drawn], ncol=ncol)
    cap = ("Each metric that was measured at several luminances, against the scene's mean luminance "
           "(log axis; the dotted line is the luminance the scores use); whiskers: the 95 % interval over the "
           "noise realisations. " + exposure_policy_sentence(res.config))
    return ReportFigure("luminance-sweep", "sweep", title, cap, fig)
