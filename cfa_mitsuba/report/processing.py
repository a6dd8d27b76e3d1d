"""'With noise reduction': the report's section on the processing settings
a study swept (``denoise``, ``sharpen``: the ISP axes), beside the study's
own (plain) processing.  From result files only: metrics.csv's rows of each
setting (:mod:`cfa_mitsuba.study.isp_settings`), snr10.csv per setting and
decisions.csv's low-light rows per setting.

- the trade-off a camera tuner reads: texture acutance (the dead-leaves
  chart, CPIQ) against YSNR (the gray bar's mid-grey), one point per
  luminance, a line per CFA, a panel per setting (the plain curves faint
  behind the others);
- per CFA and setting, at the lowest level every one of them was measured
  at and at the base level: YSNR, SNR10, texture acutance, edge MTF50 and
  S-CIELAB, each the mean of the realisations with half its 95 % interval,
  and the setting's YSNR gain and acutance cost over the plain;
- the low-light decisions, plain and with each setting, side by side.
"""

from __future__ import annotations

__all__ = ["SETTING_METRICS", "settings_in", "comparison_table", "table_level", "acutance_ysnr_figure",
           "processing_html"]

import html

import numpy as np

from ..study.isp_settings import at_base_axes, isp_settings, setting_label, with_setting
from .figure import Absent, ReportFigure, cfa_legend, legend_rows, panel_grid
from .results import Results
from .style import cfa_styles

#: The metrics the section compares, in column order (each on the scene that feeds it).
SETTING_METRICS = ("ysnr", "texture-acutance", "mtf", "scielab")


def _e(text) -> str:
    return html.escape(str(text))


def _metrics(res: Results):
    return res.all_metrics if res.all_metrics is not None else res.metrics


def settings_in(metrics) -> list[tuple[str, str] | None]:
    """[None (the study's own processing), (axis, value), ...]: the settings to compare."""
    others = isp_settings(metrics)
    return [None, *others] if others else []


def _rows(metrics, setting):
    return at_base_axes(metrics) if setting is None else with_setting(metrics, *setting)


def _name(setting, own: str = "plain") -> str:
    return own if setting is None else setting_label(*setting)


def table_level(metrics, settings, metrics_wanted=SETTING_METRICS) -> float | None:
    """The lowest luminance at which every setting has a row of every wanted metric the study measured."""
    have = [m for m in metrics_wanted if (metrics["metric"] == m).any()]
    levels = None
    for s in settings:
        rows = _rows(metrics, s)
        for m in have:
            lv = set(rows.loc[rows["metric"] == m, "luminance"].astype(float))
            levels = lv if levels is None else levels & lv
    return min(levels) if levels else None


def comparison_table(metrics, snr10, level: float, settings, cfas=None, demosaics=None):
    """One row per (CFA, demosaic, setting): each of :data:`SETTING_METRICS`
    at ``level`` (``<metric>``, ``<metric>_half``: half the 95 % interval),
    ``snr10`` (cd/m^2; snr10.csv of the setting, NaN where YSNR does not
    cross 10 within the sweep), and against the plain setting of the same CFA
    and demosaic ``ysnr_gain`` (ratio) and ``acutance_change`` (difference).
    ``metrics``: metrics.csv; ``snr10``: snr10.csv (or None)."""
    import pandas as pd

    from ..study.isp_settings import isp_axes

    cfas = cfas or list(dict.fromkeys(metrics["cfa"]))
    demosaics = demosaics or list(dict.fromkeys(metrics["demosaic"]))
    out = []
    for s in settings:
        rows = _rows(metrics, s)
        rows = rows[rows["luminance"].astype(float) == float(level)]
        s10 = None
        if snr10 is not None and len(snr10):
            s10 = snr10
            for axis in isp_axes(snr10.columns):
                own = rows[axis].astype(str).iloc[0] if len(rows) and axis in rows else None
                want = s[1] if s is not None and s[0] == axis else own
                if want is not None:
                    s10 = s10[s10[axis].astype(str) == want]
        for cfa in cfas:
            for dem in demosaics:
                r = {"cfa": cfa, "demosaic": dem, "setting": _name(s), "luminance": float(level)}
                sel = rows[(rows["cfa"] == cfa) & (rows["demosaic"] == dem)]
                for m in SETTING_METRICS:
                    g = sel[sel["metric"] == m]
                    v = float(g["value"].iloc[0]) if len(g) else np.nan
                    half = (float(g["ci_high"].iloc[0]) - float(g["ci_low"].iloc[0])) / 2 if len(g) else np.nan
                    r[m], r[f"{m}_half"] = v, half
                g = s10[(s10["cfa"] == cfa) & (s10["demosaic"] == dem)] if s10 is not None else None
                r["snr10"] = float(g["snr10_cd_m2"].iloc[0]) if g is not None and len(g) else np.nan
                out.append(r)
    df = pd.DataFrame(out)
    if df.empty:
        return df
    plain = df[df["setting"] == _name(None)].set_index(["cfa", "demosaic"])
    key = list(zip(df["cfa"], df["demosaic"]))
    with np.errstate(divide="ignore", invalid="ignore"):
        df["ysnr_gain"] = [v / plain["ysnr"].get(k, np.nan) for v, k in zip(df["ysnr"], key)]
        df["acutance_change"] = [v - plain["texture-acutance"].get(k, np.nan)
                                 for v, k in zip(df["texture-acutance"], key)]
    return df


def _curves(metrics, setting, cfa, dem):
    """(luminance, YSNR, texture acutance) at the levels both were measured at."""
    rows = _rows(metrics, setting)
    rows = rows[(rows["cfa"] == cfa) & (rows["demosaic"] == dem)]
    y = rows[rows["metric"] == "ysnr"].groupby("luminance")["value"].first()
    a = rows[rows["metric"] == "texture-acutance"].groupby("luminance")["value"].first()
    lv = sorted(set(y.index) & set(a.index))
    return np.array(lv, dtype=float), y.loc[lv].to_numpy(float), a.loc[lv].to_numpy(float)


def acutance_ysnr_figure(res: Results):
    """Texture acutance against YSNR per CFA, a panel per setting, a figure (tab) per demosaic."""
    title = "Texture acutance against YSNR: what noise reduction buys and costs"
    m = _metrics(res)
    settings = settings_in(m)
    if not settings:
        return Absent("processing", title, "a sweep of a processing setting ([[sweep]] denoise = [\"none\", "
                      "\"nl-means\"]) on the gray bar and the dead-leaves chart", not_in_study=True)
    if not ((m["metric"] == "ysnr").any() and (m["metric"] == "texture-acutance").any()):
        return Absent("processing", title, "YSNR (the gray bar) and the texture acutance (the dead-leaves "
                      "chart) measured at the same luminances")
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    plain_fmt = FuncFormatter(lambda v, _: f"{v:g}")
    cst = cfa_styles(res.cfas)
    ncol = min(len(res.cfas), 7)
    out = []
    for dem in res.demosaics:
        curves = {(s, c): _curves(m, s, c, dem) for s in settings for c in res.cfas}
        if not any(len(v[0]) for v in curves.values()):
            continue
        fig, axes = panel_grid(1, len(settings), 2.9, 2.6, left=0.7, right=0.2,
                               top=0.45 + 0.2 * legend_rows(len(res.cfas), ncol), bottom=0.55, wspace=0.15,
                               sharex=True, sharey=True, width=6.0)
        drawn = []
        for i, s in enumerate(settings):
            ax = axes[i]
            for c in res.cfas:
                st = cst[c]
                if s is not None:  # the plain curve, faint, behind this setting's
                    lv, y, a = curves[(None, c)]
                    ax.plot(y, a, color=st["color"], alpha=0.25, linewidth=0.9, linestyle=st["linestyle"])
                lv, y, a = curves[(s, c)]
                if not len(lv):
                    continue
                ax.plot(y, a, color=st["color"], marker=st["marker"], linestyle=st["linestyle"], linewidth=1.1,
                        markersize=3.2)
                drawn.append(c)
            ax.set_xscale("log")
            ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 3.0)))
            ax.xaxis.set_major_formatter(plain_fmt)
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.axvline(10.0, color="0.5", linewidth=0.7, linestyle=":")
            ax.set_title(_name(s, "plain (" + ", ".join(f"{a} {v}" for a, v in _own(res, m)) + ")"), fontsize=8)
            ax.set_xlabel("YSNR (gray bar mid-grey)", fontsize=7)
            if i == 0:
                ax.set_ylabel("texture acutance (CPIQ)", fontsize=7)
            else:
                ax.tick_params(labelleft=False)
            ax.tick_params(labelsize=6.5)
        cfa_legend(fig, cst, [c for c in res.cfas if c in drawn], ncol=ncol)
        levels = sorted({float(v) for k in curves for v in curves[k][0]})
        cap = (f"{dem}: one point per scene luminance ({', '.join(f'{v:g}' for v in levels)} cd/m²; low light at "
               "the left), a line per CFA; YSNR on the gray bar's mid-grey, the texture acutance of the dead-leaves "
               "chart (its texture MTF weighted by the CPIQ contrast sensitivity, a 100 ppi display at 0.6 m).  "
               "Each panel after the first is one processing setting, the plain curves faint behind it: a point "
               "moved right gained SNR, one moved down lost texture.  The dotted line is YSNR 10.")
        out.append(ReportFigure(f"acutance-ysnr-{dem}", "processing", title, cap, fig, group=dem))
    return out or Absent("processing", title, "no luminance with both YSNR and texture acutance")


def _own(res: Results, metrics) -> list[tuple[str, str]]:
    from ..study.isp_settings import isp_axes
    from .low_light import own_setting

    return [(a, own_setting(res, a)) for a in isp_axes(metrics.columns)]


def _cell(v, half, spec: str) -> str:
    if not np.isfinite(v):
        return "<td class=\"na\">—</td>"
    ci = f' <span class="ci">±{format(half, spec)}</span>' if np.isfinite(half) else ""
    return f"<td>{format(v, spec)}{ci}</td>"


def _table_html(df, settings) -> str:
    names = [_name(s) for s in settings]
    heads = [("YSNR", "ysnr", ".3g"), ("texture acutance", "texture-acutance", ".3f"), ("MTF50 (cy/mm)", "mtf", ".1f"),
             ("S-CIELAB (ΔE)", "scielab", ".2f")]
    heads = [h for h in heads if df[h[1]].notna().any()]
    top = "".join(f'<th colspan="{len(names)}">{_e(h)}</th>' for h, _, _ in heads)
    top += f'<th colspan="{len(names)}">SNR10 (cd/m²)</th>' if df["snr10"].notna().any() else ""
    sub = "".join(f"<th>{_e(n)}</th>" for _ in range(len(heads) + df["snr10"].notna().any()) for n in names)
    out = [f'<div class="tablewrap"><table class="data"><thead><tr><th rowspan="2">CFA</th>'
           f'<th rowspan="2">demosaic</th>{top}</tr><tr>{sub}</tr></thead><tbody>']
    for (cfa, dem), g in df.groupby(["cfa", "demosaic"], sort=False):
        g = g.set_index("setting")
        cells = []
        for _, col, spec in heads:
            cells += [_cell(g.at[n, col], g.at[n, f"{col}_half"], spec) if n in g.index else "<td>—</td>"
                      for n in names]
        if df["snr10"].notna().any():
            cells += [_cell(g.at[n, "snr10"], np.nan, ".3g") if n in g.index else "<td>—</td>" for n in names]
        out.append(f"<tr><th>{_e(cfa)}</th><td>{_e(dem)}</td>{''.join(cells)}</tr>")
    out.append("</tbody></table></div>")
    return "".join(out)


def _gains_html(df, settings) -> str:
    """The YSNR gain and the acutance cost of each setting, per CFA (the first demosaic)."""
    others = [_name(s) for s in settings[1:]]
    if not others:
        return ""
    dem = df["demosaic"].iloc[0]
    d = df[df["demosaic"] == dem]
    parts = []
    for n in others:
        g = d[d["setting"] == n]
        if not g["ysnr_gain"].notna().any():
            continue
        best = g.loc[g["ysnr_gain"].idxmax()]
        parts.append(f"{_e(n)} multiplies YSNR by {g['ysnr_gain'].min():.2f} to {g['ysnr_gain'].max():.2f} "
                     f"(most for {_e(best['cfa'])}) and changes the texture acutance by "
                     f"{g['acutance_change'].min():+.3f} to {g['acutance_change'].max():+.3f} ({_e(dem)})")
    return "; ".join(parts)


def _decisions_html(res: Results, settings) -> str:
    """decisions.csv's low-light rows, plain and with each setting, side by side."""
    from .decision_panel import answer_words, read_decisions

    d = read_decisions(res.root)
    if d is None or not len(d):
        return ""
    names = [setting_label(*s) for s in settings[1:]]
    plain = d[d["aspect"].astype(str).str.startswith("low light")
              & ~d["aspect"].astype(str).str.contains(" with ", regex=False)]
    if not len(plain):
        return ""
    rows = [f'<table class="data decisions"><thead><tr><th>decision</th><th>plain</th>'
            + "".join(f"<th>with {_e(n)}</th>" for n in names) + "</tr></thead><tbody>"]
    by = {str(r.aspect): r for r in d.itertuples(index=False)}
    for r in plain.itertuples(index=False):
        cells = [answer_words(r)] + [answer_words(by[f"{r.aspect} with {n}"]) if f"{r.aspect} with {n}" in by
                                     else "—" for n in names]
        rows.append(f"<tr><th>{_e(r.aspect)}</th>" + "".join(f"<td>{_e(c)}</td>" for c in cells) + "</tr>")
    rows.append("</tbody></table>")
    return ("<h3>Low-light decisions, plain and with each setting</h3><p class=\"note\">The rule of decisions.csv "
            "(rank intervals from paired realisations, a winner only with a lead of at least the practical "
            "difference, robust when no reasonable alternative changes it); each row decided on that "
            "setting's own rows.</p>" + "".join(rows))


def processing_html(res: Results) -> str | None:
    """The section's tables (HTML), or None when the study swept no processing setting."""
    m = _metrics(res)
    settings = settings_in(m)
    if not settings:
        return None
    snr10 = None
    if (res.root / "snr10.csv").exists():
        from ..io.guard import read_csv

        snr10 = read_csv(res.root / "snr10.csv", keep_default_na=True)
    parts = []
    low = table_level(m, settings)
    levels = [lv for lv in dict.fromkeys([low, *(res.base_luminances or [])]) if lv is not None]
    for lv in levels:
        df = comparison_table(m, snr10, lv, settings, res.cfas, res.demosaics)
        if df.empty or not df[list(SETTING_METRICS)].notna().any().any():
            continue
        gains = _gains_html(df, settings)
        parts.append(f"<h3>At {lv:g} cd/m²</h3>"
                     + (f'<p class="note">{gains}.</p>' if gains else "") + _table_html(df, settings))
    parts.append(_decisions_html(res, settings))
    note = ('<p class="note">Each value is the mean over the noise realisations ± half its 95 % interval; each setting '
            "is the same captures (the same noise seeds) processed otherwise.  YSNR on the gray bar's mid-grey, "
            "texture acutance on the dead-leaves chart, MTF50 on the slanted edge, S-CIELAB on the puppy; SNR10 "
            "from snr10.csv (— where YSNR does not cross 10 within the sweep).</p>")
    return note + "".join(parts)
