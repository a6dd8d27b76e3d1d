"""The design report's figures (matplotlib's object interface on Agg, the
report stage's settings :data:`cfa_mitsuba.report.figure.RC`).

* the Pareto front: the full chain's objectives pairwise, each CFA with
  its 95 % intervals, named CFAs labelled;
* the proxy space: every candidate, the chosen ones and the named CFAs;
* the agreement: proxy score against full-chain score;
* a CFA card: the tile drawn in its filters' colours (each letter's colour
  is the sRGB of D65 seen through its QE curve, brightest channel at 1)
  beside its QE curves.
"""

from __future__ import annotations

__all__ = ["letter_colours", "front_figure", "proxy_figure", "agreement_figure", "card_figure", "agreement_text"]

import numpy as np

from .. import spectra as _spectra
from ..colorimetry import XYZ_TO_SRGB, linear_to_srgb
from ..report.figure import new_figure

_NAMED = ("#332288", "#CC6677", "#117733", "#DDCC77", "#88CCEE", "#882255", "#44AA99", "#999933")


def letter_colours(cfa) -> dict:
    """{letter: sRGB (3,) in 0..1} of a built CFA's filters (module doc)."""
    wl = _spectra.DEFAULT_WAVELENGTHS
    qe = cfa.sensitivities(wl)
    light = _spectra.illuminant("D65", wl)
    out = {}
    for c, q in zip(cfa.channels, qe):
        lin = XYZ_TO_SRGB @ ((q * light) @ _spectra.cmfs_xyz(wl))
        lin = np.clip(lin, 0, None)
        lin = lin / lin.max() if lin.max() > 0 else lin
        out[c] = np.clip(linear_to_srgb(lin), 0, 1)
    return out


def _pairs(objectives):
    n = len(objectives)
    if n == 1:
        return [(0, None)]
    return [(i, j) for i in range(n) for j in range(i + 1, n)][:3]


def front_figure(table, objectives):
    """Each pair of objectives: every CFA run through the full chain, mean
    and 95 % interval; Pareto candidates filled, dominated ones hollow,
    named CFAs as labelled squares."""
    pairs = _pairs(objectives)
    named = table[table["kind"] == "named"]
    side = 3.2 if len(named) > 4 else 0.0   # many named CFAs: the legend in a column of its own at the right
    width = 4.6 * len(pairs) + 0.4 + side
    fig = new_figure(width, 4.6 if not side else max(4.6, 0.19 * (len(named) + 3)))
    for k, (i, j) in enumerate(pairs):  # each panel 4.6 in wide: 1.0 in for the y label, 0.4 in of gap
        ax = fig.add_axes(((1.0 + 4.6 * k) / width, 0.17, 3.2 / width, 0.63 if not side else 0.74))
        ox = objectives[i]
        oy = objectives[j] if j is not None else None

        def xy(rows):
            x = rows[ox.label].to_numpy(float)
            xe = np.abs(np.stack([x - rows[f"{ox.label} low"], rows[f"{ox.label} high"] - x]))
            if oy is None:
                return x, np.zeros_like(x), xe, None
            y = rows[oy.label].to_numpy(float)
            ye = np.abs(np.stack([y - rows[f"{oy.label} low"], rows[f"{oy.label} high"] - y]))
            return x, y, xe, ye

        for sel, style in ((table[(table["kind"] == "candidate") & ~table["pareto"]],
                            dict(fmt="o", color="#999999", mfc="white", label="candidate (dominated or infeasible)")),
                           (table[table["pareto"]], dict(fmt="*", color="#CC3311", ms=10, label="Pareto candidate"))):
            if len(sel):
                x, y, xe, ye = xy(sel)
                ax.errorbar(x, y, xerr=xe, yerr=ye, linestyle="none", capsize=2, **style)
        for n, (_, r) in enumerate(named.iterrows()):  # named in the legend: labels never overlap
            x, y, xe, ye = xy(named.loc[[_]])
            ax.errorbar(x, y, xerr=xe, yerr=ye, fmt="sDv^<>ph"[n // len(_NAMED) % 8], color=_NAMED[n % len(_NAMED)],
                        capsize=2, ms=7, label=r["cfa"])
        ax.set_xlabel(_axis_title(ox, 56), fontsize=8)
        if oy is not None:
            ax.set_ylabel(_axis_title(oy, 40), fontsize=8)
        else:
            ax.set_yticks([])
    handles, labels = fig.axes[0].get_legend_handles_labels()
    if side:
        fig.legend(handles, labels, loc="center right", ncol=1, fontsize=7, frameon=False)
    else:
        fig.legend(handles, labels, loc="upper center", ncol=min(len(labels), 4), fontsize=7, frameon=False)
    return fig


def _axis_title(o, width: int = 44) -> str:
    """An axis named by metric, condition and unit, with its direction,
    wrapped at ``width`` characters so that a long name stays within the
    panel's height (a y label) or width (an x label)."""
    import textwrap

    title = getattr(o, "title", o.label)
    return textwrap.fill(title, width) + f"\n({'lower' if o.goal == 'min' else 'higher'} is better)"


#: Axis names of the proxies (design/proxy.py), each lower-is-better.
PROXY_TITLES = {
    "aliasing": "aliasing proxy (carrier crosstalk + sampling)",
    "aliasing_h": "horizontal aliasing proxy",
    "blur": "blur proxy: 1 / edge MTF50 [px/cy]",
    "neg_capacity": "minus edge information capacity [bit/px]",
    "noise": "noise proxy: rms Y noise / Y on the grey",
    "noise_area": "area noise proxy: sqrt(NPS(0)) of Y / Y on the grey [px]",
    "snr10": "SNR10 proxy [cd/m²]",
    "snr10_area": "SNR10 proxy on the area YSNR [cd/m²]",
    "colour": "colour proxy: training-fit ΔE00",
}


def proxy_figure(cands, named_proxies, proxies=("aliasing", "noise")):
    """The first two proxies the objectives use (x, y; ``noise`` and
    ``aliasing`` by default) for every candidate (colour: the colour proxy
    when it varies), the chosen ones ringed, the named CFAs as squares."""
    xn, yn = (list(proxies) + ["aliasing", "noise"])[:2] if len(proxies) < 2 else list(proxies)[:2]
    if xn == yn:
        yn = "noise" if xn != "noise" else "aliasing"
    fig = new_figure(6.4, 4.6)
    ax = fig.add_axes((0.13, 0.12, 0.7, 0.8))
    c = cands["colour"].to_numpy(float)
    varies = np.ptp(c) > 1e-9
    kw = dict(c=c, cmap="viridis") if varies else dict(color="#88CCEE")
    sc = ax.scatter(cands[xn], cands[yn], s=4, alpha=0.6, rasterized=True, label=f"{len(cands):,} candidates", **kw)
    if varies:
        cb = fig.colorbar(sc, cax=fig.add_axes((0.86, 0.12, 0.025, 0.8)))
        cb.set_label("colour proxy (training-fit ΔE00)")
    for kind, col in (("best", "#CC3311"), ("sample", "#222222")):
        sel = cands[cands["chosen"] == kind]
        ax.scatter(sel[xn], sel[yn], s=40, facecolors="none", edgecolors=col, linewidths=1.2,
                   label=f"full chain: {'best by proxy' if kind == 'best' else 'agreement sample'}")
    for n, (name, p) in enumerate(named_proxies.items()):  # named in the legend: labels never overlap
        ax.scatter([p[xn]], [p[yn]], marker="s", s=40, color=_NAMED[n % len(_NAMED)], label=name)
    ax.set_xlabel(f"{PROXY_TITLES.get(xn, xn)} (lower is better)", fontsize=8)
    ax.set_ylabel(f"{PROXY_TITLES.get(yn, yn)} (lower is better)", fontsize=8)
    ax.legend(loc="best", fontsize=7, ncol=2)
    return fig


def agreement_figure(table, agree):
    fig = new_figure(4.6, 3.8)
    ax = fig.add_axes((0.16, 0.14, 0.78, 0.74))
    cand = table[table["kind"] == "candidate"]
    for kind, col in (("best", "#CC3311"), ("sample", "#222222")):
        sel = cand[cand["chosen"] == kind]
        ax.scatter(sel["proxy_score"], sel["score"], color=col, s=25, label=kind)
    ax.set_xlabel("proxy score (lower is better)")
    ax.set_ylabel("full-chain score (higher is better)")
    ax.set_title("proxy against full chain: " + agreement_text(agree), fontsize=8)
    ax.legend(fontsize=7)
    return fig


def agreement_text(agree) -> str:
    """The one agreement number the page and the plot both show: Spearman
    of minus the proxy score against the full-chain score (+1: the proxy
    orders the candidates as the full chain does), with its interval."""
    rho = agree.get("combined")
    if rho is None:
        return "Spearman n/a (fewer than 3 candidates)"
    ci = agree.get("combined_interval")
    return f"Spearman {rho:+.2f}" + (f" [{ci[0]:+.2f}, {ci[1]:+.2f}]" if ci else "") + f", n = {agree['n']}"


def card_figure(cfa, title: str):
    """The tile in its filters' colours, letters written in, beside the QE curves."""
    colours = letter_colours(cfa)
    fig = new_figure(6.2, 2.4)
    h, w = cfa.tile_shape
    side = 1.9
    ax = fig.add_axes((0.02, 0.08, side * min(1, w / h) / 6.2, side * min(1, h / w) / 2.4))
    img = np.array([[colours[c] for c in row] for row in cfa.pattern])
    ax.imshow(img, interpolation="nearest")
    for r in range(h):
        for c in range(w):
            lum = float(img[r, c] @ [0.2126, 0.7152, 0.0722])
            ax.text(c, r, cfa.pattern[r, c], ha="center", va="center", fontsize=9 if max(h, w) <= 4 else 6,
                    color="black" if lum > 0.5 else "white")
    ax.set_xticks(np.arange(-0.5, w, 1), minor=True)
    ax.set_yticks(np.arange(-0.5, h, 1), minor=True)
    ax.grid(which="minor", color="white", linewidth=1.0)
    ax.grid(which="major", visible=False)
    ax.tick_params(which="both", length=0, labelbottom=False, labelleft=False)
    ax.set_title(title, fontsize=8, loc="left")
    sx = fig.add_axes((0.43, 0.2, 0.54, 0.7))
    wl = _spectra.DEFAULT_WAVELENGTHS
    for c, q in zip(cfa.channels, cfa.sensitivities(wl)):
        col = colours[c] * 0.85
        sx.plot(wl, q, color=col, label=c, linewidth=1.6)
    sx.set_xlabel("wavelength (nm)", fontsize=8)
    sx.set_ylabel("QE (e⁻/photon)", fontsize=8)
    sx.set_xlim(400, 700)
    sx.set_ylim(bottom=0)
    sx.legend(fontsize=7, ncol=min(4, len(cfa.channels)))
    return fig
