"""Noise on every gray step and the dynamic range read from it (ISO 15739;
issue 50), drawn from ``steps.csv`` (study/steps.py states the method)."""

from __future__ import annotations

__all__ = ["step_snr_figure", "dynamic_range_figure", "noise_figures"]

import math

import numpy as np

from .figure import Absent, ReportFigure, cfa_legend, grid_shape, legend_rows, panel_grid
from .patch_errors import read_table
from .results import Results
from .style import cfa_styles

_TITLE_SNR = "Gray bar: SNR on every step (ISO 15739)"
_TITLE_DR = "Dynamic range: saturation over the luminance of SNR 1 (ISO 15739)"
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def _steps(res: Results):
    """(steps.csv at the primary luminance and its first condition, or an Absent)."""
    t = read_table(res, "steps.csv")
    lum = res.primary_luminance
    if t is None or lum is None or not len(t):
        if res.scene_for("ysnr") is None:
            return None, Absent("noise", _TITLE_SNR, "the gray bar's SNR (ysnr)", not_in_study=True)
        return None, Absent("noise", _TITLE_SNR, "steps.csv is absent (results written before the study kept "
                            "each gray step's SNR): rerun the study to write it")
    t = t[np.isclose(t["luminance"].astype(float), lum) & t["cfa"].isin(res.cfas) & t["demosaic"].isin(res.demosaics)]
    if not len(t):  # (a results directory whose metrics.csv was cut to fewer CFAs keeps only theirs)
        return None, Absent("noise", _TITLE_SNR, f"steps.csv has no rows at {lum:g} cd/m² for these CFAs")
    return t[t["condition"] == t["condition"].iloc[0]], None


def step_snr_figure(res: Results, t):
    """SNR (dB) against each step's luminance, a line per CFA, a panel per demosaic."""
    from matplotlib.ticker import FuncFormatter

    dems = [d for d in res.demosaics if d in set(t["demosaic"])]
    cst = cfa_styles(res.cfas)
    rows, cols = grid_shape(len(dems), 2)
    n_leg = t["cfa"].nunique()
    ncol = min(n_leg, 7)
    fig, axes = panel_grid(rows, cols, 3.6, 2.5, left=0.8, right=0.2, top=0.35 + 0.2 * legend_rows(n_leg, ncol),
                           bottom=0.55, wspace=0.2, hspace=0.45, n=len(dems), sharex=True, sharey=True, width=6.0)
    drawn = []
    for i, (ax, d) in enumerate(zip(axes, dems)):
        for c in res.cfas:
            g = t[(t["cfa"] == c) & (t["demosaic"] == d)].sort_values("luminance_cd_m2")
            g = g[np.isfinite(g["snr_db"].astype(float)) & (g["luminance_cd_m2"].astype(float) > 0)]
            if not len(g):
                continue
            st = cst[c]
            ax.plot(g["luminance_cd_m2"], g["snr_db"], color=st["color"], linestyle=st["linestyle"],
                    marker=st["marker"], markersize=3.5, linewidth=1.0)
            if c not in drawn:
                drawn.append(c)
        for level, text in ((0.0, "SNR 1"), (20.0, "SNR 10")):
            ax.axhline(level, color="#888888", linewidth=0.7, linestyle=":")
            ax.text(0.99, level, text, transform=ax.get_yaxis_transform(), fontsize=7, va="bottom", ha="right",
                    color="#666666")
        ax.set_xscale("log")
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))  # (no mathtext: RC parses none)
        ax.set_title(d)
        if i + cols >= len(dems):
            ax.set_xlabel("step luminance (cd/m²)")
        if i % cols == 0:
            ax.set_ylabel("luminance SNR (dB)")
    cfa_legend(fig, cst, drawn, ncol=ncol)
    lum = float(t["luminance"].iloc[0])
    lux = t["luminance_cd_m2"].astype(float) / t["reflectance"].astype(float) * math.pi
    lux_text = f"; the bar's light is {float(np.nanmedian(lux)):.4g} lux" if np.isfinite(lux).any() else ""
    cap = (f"The luminance SNR (20 log10 of mean Y over the rms of its noise, after demosaicing and the colour "
           f"matrix) on each of the gray bar's ten steps, against the step's luminance, at a mean scene "
           f"luminance of {lum:g} cd/m²{lux_text}. ISO 15739 reads noise this way on a grey scale; the dotted "
           f"lines are SNR 1 (0 dB, the bottom of the dynamic range) and SNR 10 (20 dB, ISO 12232's 'acceptable'). "
           f"One noise realisation per capture; every value is in steps.csv.")
    return ReportFigure("step-snr", "noise", _TITLE_SNR, cap, fig)


def dynamic_range_figure(res: Results, t):
    """Each CFA's dynamic range in dB (and stops), a marker per demosaic;
    hollow where SNR 1 lies below the darkest step (extrapolated by the fit)."""
    per = t.drop_duplicates(["cfa", "demosaic"])
    per = per[np.isfinite(per["dynamic_range_db"].astype(float))]
    if not len(per):
        return Absent("noise", _TITLE_DR, "no capture's steps gave a dynamic range (too few steps with noise, "
                      "or no saturation level)")
    cfas = [c for c in res.cfas if c in set(per["cfa"])]
    dems = [d for d in res.demosaics if d in set(per["demosaic"])]
    fig, axes = panel_grid(1, 1, 5.2, 0.32 * len(cfas) + 0.4, left=1.1, right=0.3, top=1.25, bottom=0.55,
                           width=6.0)
    ax = axes[0]
    y = {c: len(cfas) - 1 - k for k, c in enumerate(cfas)}
    handles = []
    for j, d in enumerate(dems):
        g = per[per["demosaic"] == d]
        m = _MARKERS[j % len(_MARKERS)]
        ext = g["snr1_extrapolated"].astype(str).str.lower().isin(("true", "1"))
        off = (j - (len(dems) - 1) / 2) * 0.12
        ys = [y[c] + off for c in g["cfa"]]
        ax.scatter(g["dynamic_range_db"][~ext.to_numpy()], np.asarray(ys)[~ext.to_numpy()], marker=m, s=26,
                   color=f"C{j}", zorder=3)
        ax.scatter(g["dynamic_range_db"][ext.to_numpy()], np.asarray(ys)[ext.to_numpy()], marker=m, s=26,
                   facecolors="white", edgecolors=f"C{j}", zorder=3)
        handles.append(ax.scatter([], [], marker=m, s=26, color=f"C{j}", label=d))
    ax.set_yticks(list(y.values()), list(y.keys()))
    ax.set_xlabel("dynamic range (dB, 20 log10 of the luminance ratio)")
    top = ax.secondary_xaxis("top", functions=(lambda db: db / (20 * math.log10(2)),
                                               lambda ev: ev * 20 * math.log10(2)))
    top.set_xlabel("stops (EV)")
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.995), ncol=min(len(handles), 4),
               fontsize=7, frameon=False)
    n_ext = int(per["snr1_extrapolated"].astype(str).str.lower().isin(("true", "1")).sum())
    lum = float(t["luminance"].iloc[0])
    cap = (f"ISO 15739's dynamic range of each camera at {lum:g} cd/m² (its exposure program's time and gain there): "
           f"the luminance that clips its first channel on a neutral over the luminance where the luminance SNR "
           f"falls to 1. The SNR-1 point comes from the steps' noise fitted with a linear camera's noise model "
           f"(noise² = a + b S + c S², non-negative least squares in relative terms) and solved for SNR = 1; "
           f"hollow markers ({n_ext} of {len(per)}) are where that point lies below the darkest step, an "
           f"extrapolation by the model. docs/study.md states the method; steps.csv holds both luminances.")
    return ReportFigure("dynamic-range", "noise", _TITLE_DR, cap, fig)


def noise_figures(res: Results) -> list:
    """The two figures of the noise section (or the reason they are absent)."""
    t, absent = _steps(res)
    if absent is not None:
        return [absent]
    return [step_snr_figure(res, t), dynamic_range_figure(res, t)]
