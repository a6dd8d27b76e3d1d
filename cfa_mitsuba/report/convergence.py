"""The plot of an error-against-run-time measurement
(:mod:`cfa_mitsuba.study.convergence`) and the writer of all its files:
``convergence_<scene>.csv``, ``.json`` (the study stage's) and the plot in
each figure format, in the report's figure style."""

from __future__ import annotations

__all__ = ["plot_convergence", "write_convergence"]

import numpy as np

from ..study.convergence import ConvergenceResult, radiance_series, rate_text, rows_frame, write_outputs
from .figure import RC
from .style import metric_display


def write_convergence(result: ConvergenceResult, out_dir, *, formats=("png", "svg")) -> dict:
    """Write the CSV and JSON (:func:`~cfa_mitsuba.study.convergence.write_outputs`)
    and the plot in each of ``formats``; returns {kind: path}."""
    paths = write_outputs(result, out_dir)
    csv = paths["csv"]
    for fmt in formats:
        paths[fmt] = csv.parent / f"{csv.stem}.{fmt}"
    plot_convergence(result, [paths[f] for f in formats])
    return paths


_RADIANCE_STYLES = {
    "radiance, image, median band": dict(color="#000000", linestyle="-", marker="o"),
    "radiance, image, worst band": dict(color="#777777", linestyle="--", marker="s"),
    "radiance, uniform region, median band": dict(color="#0077BB", linestyle="-.", marker="^"),
}
_METRIC_COLOURS = ("#CC3311", "#009988", "#EE7733", "#33BBEE", "#EE3377", "#0077BB", "#BBBBBB")
_METRIC_MARKERS = ("o", "s", "D", "^", "v", "P", "X")


def plot_convergence(result: ConvergenceResult, paths) -> None:
    """Log-log plot: (a) radiance error and (b) metric deviation against
    render wall time, (c) metric deviation against POCS processing time.
    The default quality is ringed and named; fitted rates in the legends;
    dotted lines are noise floors, dashed ones the smallest difference
    between the compared CFAs."""
    from matplotlib.figure import Figure

    import matplotlib

    p, s = result.plan, result.summary
    df = rows_frame(result.rows)
    headline = [m for m in p.metrics if m in s["reference"]["metric_values"]]
    rc = {**RC, "axes.grid": True}
    with matplotlib.rc_context(rc):
        fig = Figure(figsize=(16.0, 6.6), layout="constrained")
        axes = fig.subplots(1, 3)
        fig.suptitle(
            f"{p.name}: error against run time ({p.width} x {p.height} EXR px, K = {p.oversample}; {p.cfa} + "
            f"{p.demosaic}; reference 2 x {p.reference_spp} spp, seeds {p.seed + 1}, {p.seed + 2}; "
            f"{s['cores']} cores, shared)", fontsize=10)

        _panel_radiance(axes[0], p, s, df)
        _panel_metrics(axes[1], p, s, df, headline)
        _panel_pocs(axes[2], p, s, df, headline)

        for path in paths:
            fig.savefig(path, metadata={"Date": None} if str(path).endswith(".svg") else None)


def _metric_style(i: int, m: str, s: dict) -> tuple:
    """(display info, unit text, line style) of the i-th headline metric."""
    st = dict(color=_METRIC_COLOURS[i % 7], marker=_METRIC_MARKERS[i % 7], linestyle="-")
    return metric_display(m), s["checks"][m]["unit"] or "-", st


def _panel_radiance(ax, p, s, df) -> None:
    """(a) radiance error per band against render wall time."""
    lows = []
    for prefix, label in (("radiance", "image"), ("uniform", "uniform region")):
        t, med, mx, q = radiance_series(df, "render", prefix)
        pairs = [("median band", med)] + ([("worst band", mx)] if prefix == "radiance" else [])
        for agg, y in pairs:
            key = f"radiance, {label}, {agg}"
            st = _RADIANCE_STYLES[key]
            lows += _draw_series(ax, t, 100 * y, q, p.default_spp, st,
                                 f"{label}, {agg}: {_rates_label(s['rates']['render'][key], 'spp')}")
            if key == "radiance, image, median band":
                _label_points(ax, t, 100 * y, q, "spp")
    own = 100 * s["reference"]["own_noise_measured_median_band"]
    floor = 100 * s["reference"]["own_noise_image_median_band"]
    ax.axhline(floor, color="#000000", linestyle=":", linewidth=1,
               label=(f"floor: reference's own noise, median band ({floor:.2g} %)" if own >= floor else
                      f"floor: float32 rounding ({floor:.2g} %; reference's own noise {own:.2g} %)"))
    title = "(a) render: radiance per band"
    if all(v["per_wall_time"] is None for k, v in s["rates"]["render"].items() if k.startswith("radiance")):
        title += "\nevery level at the float32 floor: exact at any spp"
    _finish(ax, "render wall time (s)", "radiance error: rms / mean (%)", title, lows)


def _panel_metrics(ax, p, s, df, headline) -> None:
    """(b) metric deviation against render wall time."""
    lows = []
    for i, m in enumerate(headline):
        sub = df[(df["stage"] == "render") & (df["quantity"] == m)].sort_values("quality")
        info, unit, st = _metric_style(i, m, s)
        lows += _draw_series(ax, sub["wall_s"].to_numpy(float), sub["error"].to_numpy(float),
                             sub["quality"].to_numpy(float), p.default_spp, st,
                             f"{info.short} [{unit}]: {_rates_label(s['rates']['render'][m], 'spp')}")
        seeds = df[(df["stage"] == "render-seeds") & (df["quantity"] == m) & (df["error"] > 0)]
        at = sub[sub["quality"] == p.default_spp]["wall_s"]
        if len(seeds) and len(at):  # drawn at the default level's time (the same render cost)
            ax.plot(np.full(len(seeds), float(at.iloc[0])), seeds["error"].to_numpy(float), linestyle="none",
                    marker=st["marker"], markersize=4, markerfacecolor="none", markeredgecolor=st["color"],
                    alpha=0.8)
        pair = s["checks"][m].get("cfa_difference_deviation")
        if pair and pair > 0 and len(at):
            ax.plot([float(at.iloc[0]) * 1.12], [pair], linestyle="none", marker="*", markersize=10,
                    color=st["color"], markeredgecolor="#000000", markeredgewidth=0.4)
        spread = s["checks"][m].get("cfa_spread")
        gap = s["checks"][m].get("cfa_smallest_gap")
        if spread and spread > 0:
            ax.axhline(spread, color=st["color"], linestyle="--", linewidth=1)
        if gap and gap > 0:
            ax.axhline(gap, color=st["color"], linestyle=":", linewidth=1)
    if len(headline) and len(df[df["stage"] == "render"]):
        sub = df[(df["stage"] == "render") & (df["quantity"] == headline[0])].sort_values("quality")
        _label_points(ax, sub["wall_s"].to_numpy(float), sub["error"].to_numpy(float),
                      sub["quality"].to_numpy(float), "spp", below=True)
    if p.compare_cfas:
        names = ", ".join(p.compare_cfas)
        ax.plot([], [], color="#555555", linestyle="--", linewidth=1,
                label=f"dashed, metric's colour: spread between {names} ({p.demosaic})")
        ax.plot([], [], color="#555555", linestyle=":", linewidth=1,
                label="dotted: smallest gap between two of them")
        if (df["stage"] == "cfa-pairs").any():
            ax.plot([], [], linestyle="none", marker="*", markersize=10, color="#999999", markeredgecolor="#000000",
                    markeredgewidth=0.4, label="star: rms change of the differences between those CFAs "
                                               "at the default (what can reorder them)")
    noise = "sensor noise off" if p.render_noise == "off" else f"sensor noise '{p.render_noise}'"
    title = f"(b) render: metric deviation ({noise})" + _zero_note(df, "render", headline)
    _finish(ax, "render wall time (s)", "|metric - reference's| (metric's unit)", title, lows,
            seeds_note=bool((df["stage"] == "render-seeds").any()))


def _panel_pocs(ax, p, s, df, headline) -> None:
    """(c) metric deviation against POCS processing time."""
    lows = []
    pdflt = s["pocs_default"]
    for i, m in enumerate(headline):
        sub = df[(df["stage"] == "pocs") & (df["quantity"] == m)].sort_values("quality")
        info, unit, st = _metric_style(i, m, s)
        lows += _draw_series(ax, sub["wall_s"].to_numpy(float), sub["error"].to_numpy(float),
                             sub["quality"].to_numpy(float), None, st,
                             f"{info.short} [{unit}]: {_rates_label(s['rates']['pocs'][m], 'iteration')}")
        pspread = s.get("pocs_checks", {}).get(m, {}).get("cfa_spread")
        if pspread and pspread > 0:
            ax.axhline(pspread, color=st["color"], linestyle="--", linewidth=1)
        dev = pdflt["deviation"][m]
        if dev > 0:
            ax.plot([pdflt["wall_s"]], [dev], linestyle="none", marker="o", markersize=13, markerfacecolor="none",
                    markeredgecolor=st["color"], markeredgewidth=1.4)
    if headline:
        sub = df[(df["stage"] == "pocs") & (df["quantity"] == headline[0])].sort_values("quality")
        _label_points(ax, sub["wall_s"].to_numpy(float), sub["error"].to_numpy(float),
                      sub["quality"].to_numpy(float), "it")
    if p.compare_cfas:
        ax.plot([], [], color="#555555", linestyle="--", linewidth=1,
                label=f"dashed, metric's colour: spread between {', '.join(p.compare_cfas)} (pocs)")
    ax.axvline(pdflt["wall_s"], color="#555555", linestyle=":", linewidth=1,
               label=f"default: {p.pocs_default_iterations} iterations, tolerance 1e-3 "
                     f"(stopped at {pdflt['iterations_done']}; ringed)")
    _finish(ax, "processing wall time (s)", "|metric - converged POCS| (metric's unit)",
            f"(c) processing: POCS iterations vs {p.pocs_reference_iterations} (tolerance 0)"
            + _zero_note(df, "pocs", headline), lows)


def _zero_note(df, stage: str, metrics) -> str:
    sub = df[(df["stage"] == stage) & df["quantity"].isin(list(metrics))]
    if len(sub) and (sub["error"] == 0).all():
        return "\nevery deviation exactly 0: the metric does not change"
    return ""


def _rates_label(r: dict, per: str) -> str:
    other = r.get("per_spp", r.get("per_iteration"))
    if r["per_wall_time"] is None:
        return "rate n/a (no points above the floor)"
    return f"rate {rate_text(r['per_wall_time'])} per time, {rate_text(other)} per {per} ({r['points']} points)"


def _draw_series(ax, x, y, q, default_q, style, label) -> list:
    """Plot positive points on log axes; zeros (identical results) are drawn
    as hollow down-triangles at the bottom (returned for placement)."""
    x, y, q = np.asarray(x, float), np.asarray(y, float), np.asarray(q, float)
    pos = y > 0
    ax.plot(x[pos], y[pos], label=label, markersize=5, linewidth=1.4, **style)  # (an empty line keeps the legend)
    zeros = [(xx, style["color"]) for xx in x[~pos]]
    if default_q is not None:
        sel = (q == default_q) & pos
        if sel.any():
            ax.plot(x[sel], y[sel], linestyle="none", marker="o", markersize=13, markerfacecolor="none",
                    markeredgecolor=style["color"], markeredgewidth=1.4)
    return zeros


def _label_points(ax, x, y, q, what: str, below: bool = False) -> None:
    for xx, yy, qq in zip(x, y, q):
        if yy > 0 and np.isfinite(yy):
            ax.annotate(f"{int(qq)}", (xx, yy), textcoords="offset points", xytext=(0, -11 if below else 6),
                        ha="center", fontsize=7, color="#333333")


def _finish(ax, xlabel, ylabel, title, zeros, seeds_note: bool = False) -> None:
    from matplotlib.ticker import LogFormatter

    ax.set_xscale("log")
    ax.set_yscale("log")
    class _Plain(LogFormatter):
        """LogFormatter's choice of which ticks to label, written as %.3g
        (plain text: mathtext is off in the report's style; and 0.12, 0.15
        rather than two labels that both read 1e-01)."""

        def __call__(self, x, pos=None):
            return f"{x:.3g}" if super().__call__(x, pos) else ""

    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_formatter(_Plain(labelOnlyBase=False, minor_thresholds=(1.2, 0.4)))
        axis.set_minor_formatter(_Plain(labelOnlyBase=False, minor_thresholds=(1.2, 0.4)))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    if zeros:
        # Room below every drawn value (curves and reference lines) for the zero markers.
        ys = np.concatenate([np.asarray(line.get_ydata(), dtype=float).ravel() for line in ax.get_lines()] or [[]])
        ys = ys[np.isfinite(ys) & (ys > 0)]
        top = float(ys.max()) * 3 if ys.size else 1.0
        lo = float(ys.min()) / 30 if ys.size else 1e-3
        ax.set_ylim(lo, max(top, lo * 100))
        y0 = lo * 1.6
        for xx, colour in zeros:
            ax.plot([xx], [y0], linestyle="none", marker="v", markersize=6, markerfacecolor="none",
                    markeredgecolor=colour)
        ax.plot([], [], linestyle="none", marker="v", markerfacecolor="none", markeredgecolor="#333333",
                label="exactly 0 (identical to the reference)")
    ax.plot([], [], linestyle="none", marker="o", markersize=11, markerfacecolor="none", markeredgecolor="#333333",
            label="ringed: the scene's default" + ("; small hollow: the default with other seeds" if seeds_note else ""))
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=1, fontsize=7, handlelength=2.6)
