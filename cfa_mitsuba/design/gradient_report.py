"""The gradient method's part of design.html: every L-BFGS-B run on the
proxy's two objectives (the front over the colour weights), each chosen
candidate's dye curves, and its manufacturability (:mod:`.manufacture`)."""

from __future__ import annotations

__all__ = ["gradient_front_figure", "gradient_curves_figure", "gradient_html"]

import html
import json

import numpy as np

from ..report.figure import new_figure


def gradient_front_figure(cands, noise_label: str):
    """Every run's proxy ΔE00 against its noise objective, coloured by its
    colour weight; the candidates chosen for the full chain ringed."""
    import matplotlib as mpl
    import matplotlib.ticker  # noqa: F401  (mpl.ticker)

    fig = new_figure(6.4, 4.4)
    ax = fig.add_axes((0.13, 0.14, 0.68, 0.76))
    w = cands["weight"].to_numpy(dtype=float)
    sc = ax.scatter(cands["gradient_colour"], cands["gradient_noise"], c=w, cmap="viridis", vmin=0, vmax=1, s=26,
                    zorder=3)
    chosen = cands["chosen"].fillna("").astype(str) != ""
    ax.scatter(cands.loc[chosen, "gradient_colour"], cands.loc[chosen, "gradient_noise"], s=90,
               facecolors="none", edgecolors="#CC3311", lw=1.2, label="run through the full chain", zorder=4)
    ax.set_xscale("log")
    ax.xaxis.set_major_formatter(mpl.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(mpl.ticker.NullFormatter())
    ax.set_xlabel("proxy ΔE00 (ColorChecker, after the ISP's colour fit)")
    ax.set_ylabel(noise_label)
    ax.legend(loc="upper right", frameon=False, fontsize=8)
    cax = fig.add_axes((0.84, 0.14, 0.03, 0.76))
    fig.colorbar(sc, cax=cax, norm=mpl.colors.Normalize(0, 1)).set_label("colour weight w")
    ax.set_title("L-BFGS-B runs: w log ΔE00 + (1 − w) log noise", fontsize=10)
    return fig


def gradient_curves_figure(config, cands, keys):
    """The chosen candidates' dye transmittances (spline) or QE (mixture), one panel each."""
    from .spectra import GRID_NM, letter_curves, spline_basis

    n = max(1, len(keys))
    fig = new_figure(3.3 * n, 2.9)
    colours = {"R": "#CC3311", "G": "#228833", "B": "#0077BB", "C": "#33BBEE", "M": "#EE3377", "Y": "#CCBB44",
               "W": "#555555"}
    for k, key in enumerate(keys):
        row = cands[cands["key"] == key].iloc[0]
        params = json.loads(row["params"])
        ax = fig.add_axes(((0.55 + 3.3 * k) / (3.3 * n), 0.18, 2.55 / (3.3 * n), 0.68))
        curves = letter_curves(config.alphabet, config.spectra_set, config.spectra, params)
        for a, p in zip(config.spectra.letters, params):
            y = (spline_basis(len(p["coefficients"])) @ np.asarray(p["coefficients"])
                 if "coefficients" in p else curves[a][1])
            ax.plot(GRID_NM, y, color=colours.get(a, "k"), lw=1.4, label=a)
        ax.set_ylim(0, 1.05)
        ax.set_xlim(380, 720)
        ax.set_xlabel("nm")
        ax.set_title(f"w = {row['weight']:g}, start {int(row['start'])}", fontsize=9)
        if k == 0:
            ax.set_ylabel("transmittance" if config.spectra.family == "spline" else "QE")
            ax.legend(frameon=False, fontsize=8, ncol=3)
    return fig


def gradient_html(config, cands, table, save) -> str:
    """The section: figures (``save(key, fig)`` -> src) and the manufacturability table."""
    e = html.escape
    noise = next(o for o in config.objectives if o.metric != "delta-e")
    short = {"snr10": "proxy SNR10 [cd/m²]", "ysnr": "proxy relative Y noise", "ysnr-area": "proxy area Y noise"}
    front = save("gradient-front", gradient_front_figure(cands, short.get(noise.metric, noise.metric)))
    picked = cands[cands["chosen"].fillna("").astype(str) == "best"].sort_values("proxy_rank")
    names = dict(zip(table["key"], table["cfa"])) if "key" in table else {}
    curves = save("gradient-curves", gradient_curves_figure(config, cands, list(picked["key"])[:4]))
    rows = []
    for _, r in picked.iterrows():
        per = json.loads(r["manufacturability"])
        detail = "; ".join(f"{a}: slope {v['max_slope_per_10nm']:.2f}, peak {v['peak']:.2f}, nearest {e(v['nearest'])} "
                           f"{v['angle_deg']:.1f}°" for a, v in per.items())
        rows.append(f"<tr><td class=l>{e(names.get(r['key'], r['key']))}</td><td>{r['weight']:g}</td>"
                    f"<td>{r['gradient_colour']:.3f}</td><td>{r['gradient_noise']:.3g}</td>"
                    f"<td>{r['max_slope_per_10nm']:.2f}</td><td>{r['peak']:.2f}</td>"
                    f"<td class=l>{e(r['nearest_set'])} ({r['nearest_set_angle_deg']:.1f}°)</td>"
                    f"<td class=l>{detail}</td></tr>")
    g = config.gradient
    return f"""<h2>Gradient search of the spectra</h2>
<p>{len(g.weights)} colour weights x {g.starts} starts, L-BFGS-B (at most {g.max_iter} iterations each) on the
differentiable proxy, {e(config.spectra.family)} curves{f' ({config.spectra.knots} cubic B-splines per letter)'
 if config.spectra.family == 'spline' else ''} for {' '.join(config.spectra.letters)} on the layout
{e(g.layout)}.</p><img src='{front}' style='width:560px'><img src='{curves}'>
<table><tr><th>CFA</th><th>w</th><th>proxy ΔE00</th><th>proxy noise</th><th>max slope per 10 nm</th><th>peak</th>
<th>nearest measured set (mean spectral angle)</th><th>per letter</th></tr>{''.join(rows)}</table>
<p class=note>Slope: the largest change of the curve over 10 nm (1 = from 0 to 1); spectral angle between band QE
curves, 0° the same shape; the nearest set matches letter to letter (R to R, ...).</p>"""
