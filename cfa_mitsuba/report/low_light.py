"""Low light in the report, from result files only (issue 22): YSNR against
luminance (``snr.csv``, a log-log figure), SNR10 (``snr10.csv``), what
decided each capture (metrics.csv's ``exposure_s``, ``analog_gain``,
``digital_gain``, ``clipped_fraction``; the details' electrons on a
mid-grey, the colour matrix's condition number and noise gain) and each
CFA's spectra set (``cfas.json``)."""

from __future__ import annotations

__all__ = ["snr_figure", "low_light_tables", "read_snr", "own_setting", "versus_reference", "VERSUS_METRICS"]

import html

import numpy as np

from ..metrics import get_metric
from .figure import ReportFigure, cfa_legend, legend_rows, panel_grid
from .results import SCORED_METRICS, Results
from .style import cfa_styles


def _e(text) -> str:
    return html.escape(str(text))


def own_setting(res: Results, axis: str) -> str:
    """The study's own value of a processing axis (config.json's base condition, else the stage's default)."""
    from ..study.axes import get_axis

    base = (res.config or {}).get("base_condition") or {}
    return str(base.get(axis, get_axis(axis).default_value()))


def read_snr(res: Results, name: str = "snr.csv", setting: tuple[str, str] | None = None):
    """``snr.csv`` or ``snr10.csv`` of the results as a DataFrame, the rows
    of the CFAs and demosaics the report shows at the study's own processing
    setting (``setting``: (axis, value) of another, :mod:`cfa_mitsuba.study.isp_settings`);
    None when there are none."""
    from ..io.guard import read_csv
    from ..study.isp_settings import isp_axes

    path = res.root / name
    if not path.exists():
        return None
    df = read_csv(path, keep_default_na=True)
    df = df[df["cfa"].astype(str).isin(res.cfas) & df["demosaic"].astype(str).isin(res.demosaics)]
    for axis in isp_axes(df.columns):
        want = setting[1] if setting is not None and setting[0] == axis else own_setting(res, axis)
        df = df[df[axis].astype(str) == want]
    return df if len(df) else None


def snr_figure(res: Results):
    """YSNR against scene luminance, log-log: one panel per demosaic, a line
    per CFA with its 95 % interval, the YSNR = 10 line ([] without ``snr.csv``)."""
    title = "YSNR against luminance (mid-grey, after demosaic and colour matrix)"
    snr = read_snr(res)
    if snr is None:  # the study asked for no SNR sweep: nothing to draw or to mention
        return []
    dems = [d for d in res.demosaics if d in set(snr["demosaic"])]
    cfas = [c for c in res.cfas if c in set(snr["cfa"])]
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    plain = FuncFormatter(lambda v, _: f"{v:g}")  # the report's text has no mathtext
    cst = cfa_styles(cfas)
    ncol = min(len(cfas), 7)
    lo = float(np.nanmin(snr[["ysnr", "ysnr_low"]].to_numpy(float)))
    hi = float(np.nanmax(snr[["ysnr", "ysnr_high"]].to_numpy(float)))
    fig, axes = panel_grid(1, len(dems), 2.7, 2.4, left=0.7, right=0.55,
                           top=0.85 + 0.2 * legend_rows(len(cfas), ncol), bottom=0.55, wspace=0.12, width=6.0)
    for i, d in enumerate(dems):
        ax = axes[i]
        for c in cfas:
            g = snr[(snr["demosaic"] == d) & (snr["cfa"] == c)].sort_values("luminance")
            if not len(g):
                continue
            st = cst[c]
            y = g["ysnr"].to_numpy(float)
            err = np.vstack([y - g["ysnr_low"].to_numpy(float), g["ysnr_high"].to_numpy(float) - y])
            ax.errorbar(g["luminance"], y, yerr=np.maximum(err, 0), color=st["color"], marker=st["marker"],
                        linestyle=st["linestyle"], linewidth=1.1, markersize=3.2, capsize=1.5)
        ax.axhline(10.0, color="0.5", linewidth=0.7, linestyle=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(max(lo, 1e-3) / 1.3, max(hi, 10.0) * 1.3)
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_locator(LogLocator(base=10, subs=(1.0, 3.0)))
            axis.set_major_formatter(plain)
            axis.set_minor_formatter(NullFormatter())
        ax.set_title(d, fontsize=8, pad=26 if "scene_illuminance_lux" in snr.columns else 5)
        ax.set_xlabel("scene luminance (cd/m²)", fontsize=7)
        if i == 0:
            ax.set_ylabel("YSNR", fontsize=7)
        else:
            ax.tick_params(labelleft=False)
        ax.tick_params(labelsize=6.5)
        _field_axes(ax, snr, i == len(dems) - 1, plain)
    cfa_legend(fig, cst, cfas, ncol=ncol)
    cap = ("YSNR (mean over rms of the luminance noise) on the gray bar's mid-grey step after the whole image "
           "processor, the mean of the noise realisations with its 95 % interval; the dotted line is YSNR 10, "
           "whose luminance (SNR10) the table 'Low light' gives.  Exposure as the study's policy chose it "
           f"({_policy(res)}).")
    return ReportFigure("snr-luminance", "sweep", title, cap, fig)


def _field_axes(ax, snr, last: bool, plain) -> None:
    """The field's units on a YSNR panel (issue 50): the scene's illuminance
    in lux along the top (snr.csv's lux per cd/m^2, the gray bar's white) and,
    on the last panel, YSNR in dB at the right."""
    if "scene_illuminance_lux" in snr.columns:
        ratio = (snr["scene_illuminance_lux"].astype(float) / snr["luminance"].astype(float)).median()
        if np.isfinite(ratio) and ratio > 0:
            top = ax.secondary_xaxis("top", functions=(lambda v: v * ratio, lambda v: v / ratio))
            top.set_xlabel("illuminance (lux)", fontsize=6.5)
            top.xaxis.set_major_formatter(plain)
            top.tick_params(labelsize=6)
    if last:  # a linear dB axis whose limits are the log axis's: 20 log10 maps one onto the other
        right = ax.twinx()
        lo, hi = ax.get_ylim()
        right.set_ylim(20 * np.log10(lo), 20 * np.log10(hi))
        right.set_ylabel("YSNR (dB)", fontsize=7)
        right.grid(False)
        right.tick_params(labelsize=6)


def _policy(res: Results) -> str:
    from ..study.config import exposure_program_of

    return exposure_program_of(res.config).policy


def _fmt(v, spec: str) -> str:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return "—"
    return "—" if not np.isfinite(x) else format(x, spec)


def _snr10_html(res: Results) -> str | None:
    s10 = read_snr(res, "snr10.csv")
    if s10 is None:
        return None
    lux = "snr10_lux" in s10.columns
    rows = ['<table class="data"><thead><tr><th>CFA</th><th>demosaic</th><th>SNR10 (cd/m²)</th>'
            + ("<th>SNR10 (lux)</th>" if lux else "") + "<th>95 % interval</th><th>note</th></tr></thead><tbody>"]
    for r in s10.itertuples(index=False):
        note = "" if not isinstance(r.note, str) else r.note
        rows.append(f"<tr><th>{_e(r.cfa)}</th><td>{_e(r.demosaic)}</td><td>{_fmt(r.snr10_cd_m2, '.3g')}</td>"
                    + (f"<td>{_fmt(r.snr10_lux, '.3g')}</td>" if lux else "")
                    + f"<td>{_fmt(r.ci_low, '.3g')} – {_fmt(r.ci_high, '.3g')}</td><td>{_e(note)}</td></tr>")
    rows.append("</tbody></table>")
    return "".join(rows)


def _sweep_scene(m) -> str | None:
    """The scene of the luminance sweep of the scored metrics (the puppy in the paper's study)."""
    lums = m.groupby("scene")["luminance"].nunique()
    lums = lums[lums > 1]
    if "metric" in m and len(lums):
        return str(lums.sort_values(ascending=False).index[0])
    return None


def _capture_html(res: Results) -> str | None:
    """Per CFA and luminance of the sweep: time, gains, clipped pixels, and
    (details) electrons on a mid-grey, the matrix's condition number and noise gain."""
    m = res.metrics  # every axis but luminance at the study's own value (a denoise sweep is its own section)
    if "exposure_s" not in m.columns:
        return None
    scene = _sweep_scene(m[m["metric"].isin(SCORED_METRICS)]) or _sweep_scene(m)
    if scene is None:
        return None
    g = m[m["scene"] == scene]
    dem = next((d for d in res.demosaics if d in set(g["demosaic"])), None)
    g = g[g["demosaic"] == dem].drop_duplicates(["cfa", "luminance"])
    out = [f'<p class="note">{_e(scene)}, {_e(dem)} (the capture does not depend on the demosaic); '
           f"exposure policy {_e(_policy(res))}.  e⁻ on 18 % grey: mean electrons per pixel of each channel "
           "on an 18 % grey on the axis; cond and noise gain Y: the colour matrix's.</p>",
           '<table class="data"><thead><tr><th>CFA</th><th>cd/m²</th><th>time (ms)</th><th>analogue gain</th>'
           "<th>digital gain</th><th>clipped %</th><th>e⁻ on 18 % grey</th><th>cond</th><th>noise gain Y</th>"
           "</tr></thead><tbody>"]
    for cfa in [c for c in res.cfas if c in set(g["cfa"])]:
        for r in g[g["cfa"] == cfa].sort_values("luminance").itertuples(index=False):
            extra = (res.detail(scene, cfa, dem, float(r.luminance)) or {}).get("extra") or {}
            grey = extra.get("grey_electrons") or {}
            noise = extra.get("noise_gain_xyz") or [None, None, None]
            out.append(f"<tr><th>{_e(cfa)}</th><td>{float(r.luminance):g}</td><td>{_fmt(r.exposure_s * 1e3, '.3g')}</td>"
                       f"<td>{_fmt(r.analog_gain, '.3g')}</td><td>{_fmt(r.digital_gain, '.3g')}</td>"
                       f"<td>{_fmt(100 * r.clipped_fraction, '.3g')}</td>"
                       f"<td>{_e(', '.join(f'{k} {v:.0f}' for k, v in grey.items())) or '—'}</td>"
                       f"<td>{_fmt(extra.get('condition_number'), '.3g')}</td><td>{_fmt(noise[1], '.3g')}</td></tr>")
    out.append("</tbody></table>")
    return "".join(out)


def _spectra_html(res: Results) -> str | None:
    """Each CFA's spectra set (cfas.json); the summary's 'Spectra' row
    (figures_sensor.spectra_note) says when the compared sets differ."""
    facts = res.cfa_facts or {}
    sets = {c: str(f.get("spectra") or "its own curves") for c, f in facts.items() if c in res.cfas}
    if not sets:
        return None
    rows = "".join(f"<tr><th>{_e(c)}</th><td>{_e(s)}</td></tr>" for c, s in sets.items())
    return f'<table class="data"><thead><tr><th>CFA</th><th>spectra set</th></tr></thead><tbody>{rows}</tbody></table>'


#: What the low-light comparison reads, each on the rows of the scenes its
#: record names (its direction, higher or lower better, from the record too).
VERSUS_METRICS = ("ysnr", "chroma_snr", "scielab")


def _levels(levels, empty: str = "never") -> str:
    """Luminances (cd/m^2) as a comma list, ``empty`` when there are none."""
    return ", ".join(f"{L:g}" for L in levels) or empty


def versus_reference(metrics, reference: str = "bayer") -> list[dict]:
    """Per (demosaic, CFA other than ``reference``): the luminances at which
    it beats ``reference`` (its 95 % interval wholly on the better side), at
    which it loses (wholly on the worse side), for each of
    :data:`VERSUS_METRICS`; and at the highest luminance of the study's own
    charts its ΔE00 and MTF50 beside the reference's (the cost in colour and
    sharpness).  ``metrics``: a metrics.csv table."""
    out = []
    m = metrics
    for dem in dict.fromkeys(m["demosaic"]):
        md = m[m["demosaic"] == dem]
        for cfa in [c for c in dict.fromkeys(md["cfa"]) if c != reference]:
            row = {"demosaic": dem, "cfa": cfa}
            for metric in VERSUS_METRICS:
                higher = get_metric(metric).higher_is_better
                g = md[md["metric"] == metric]
                a = g[g["cfa"] == cfa].set_index("luminance")
                b = g[g["cfa"] == reference].set_index("luminance")
                wins, losses = [], []
                for L in sorted(set(a.index) & set(b.index)):
                    (lo, hi), (rlo, rhi) = a.loc[L, ["ci_low", "ci_high"]], b.loc[L, ["ci_low", "ci_high"]]
                    better, worse = (lo > rhi, hi < rlo) if higher else (hi < rlo, lo > rhi)
                    (wins if better else losses if worse else []).append(float(L))
                row[f"{metric}_wins"], row[f"{metric}_losses"] = wins, losses
            for metric in ("delta-e", "mtf"):
                g = md[md["metric"] == metric]
                if len(g):
                    top = g["luminance"].max()
                    v = g[(g["luminance"] == top)].set_index("cfa")["value"]
                    row[metric] = (float(v.get(cfa, np.nan)), float(v.get(reference, np.nan)))
            out.append(row)
    return out


def _versus_html(res: Results) -> str | None:
    m = res.metrics  # every axis but luminance at the study's own value (a denoise sweep is its own section)
    if "bayer" not in set(m["cfa"]) or "ysnr" not in set(m["metric"]):
        return None
    head = "".join(f"<th>{_e(k)}: better / worse than Bayer at (cd/m²)</th>" for k in VERSUS_METRICS)
    rows = [f'<div class="tablewrap"><table class="data wraphead"><thead><tr><th>demosaic</th><th>CFA</th>{head}<th>ΔE00 (Bayer)</th>'
            "<th>MTF50 (Bayer)</th></tr></thead><tbody>"]
    for r in versus_reference(m[m["cfa"].isin(res.cfas) & m["demosaic"].isin(res.demosaics)]):
        cells = "".join(f"<td>{_levels(r[f'{k}_wins'])} / {_levels(r[f'{k}_losses'])}</td>" for k in VERSUS_METRICS)
        cost = "".join(f"<td>{_fmt(r[k][0], '.3g')} ({_fmt(r[k][1], '.3g')})</td>" if k in r else "<td>—</td>"
                       for k in ("delta-e", "mtf"))
        rows.append(f"<tr><td>{_e(r['demosaic'])}</td><th>{_e(r['cfa'])}</th>{cells}{cost}</tr>")
    rows.append("</tbody></table></div>")
    return ('<p class="note">Better or worse: the 95 % intervals over the noise realisations do not overlap; '
            "any luminance not listed is a tie.</p>" + "".join(rows))


def low_light_tables(res: Results) -> str | None:
    """The 'Low light' tables of the report (HTML), or None when the results hold none of them."""
    parts = []
    for title, body in (("Against Bayer: where each CFA is better in low light, and its cost", _versus_html(res)),
                        ("SNR10: the scene luminance of YSNR 10", _snr10_html(res)),
                        ("What decided each capture", _capture_html(res)),
                        ("Spectra sets", _spectra_html(res))):
        if body:
            parts.append(f"<h3>{_e(title)}</h3>{body}")
    return "".join(parts) or None
