"""Figures drawn from the per-evaluation details (``details/``): the curves,
patch tables and maps behind each metric, camera against the ideal sensor.

- :func:`mtf_curves`: MTF per channel with Nyquist and MTF50 (Figs 6, 11);
- :func:`moire_curves`: the chirp's block-mean chroma with the threshold
  and the MSP (Fig 13);
- :func:`patch_ab`, :func:`patch_xy`: the 24 patches in a*b* and in xy
  (Figs 8, 9), in :mod:`.figures_patches`;
- :func:`scielab_maps`: S-CIELAB dE maps on one colour scale (Fig 10);
- :func:`gray_bar_profiles`: the gray bar's L* profile and error (Fig 14);
- :func:`thumbnail_sheet`: every camera output next to the ideal.
"""

from __future__ import annotations

__all__ = ["mtf_curves", "moire_curves", "patch_ab", "patch_xy", "scielab_maps", "gray_bar_profiles",
           "thumbnail_sheet"]

import numpy as np

from .figures_patches import patch_ab, patch_xy  # noqa: F401  (listed here with the other detail figures)
from .figure import Absent, ReportFigure, no_details as _no_details, cfa_legend, grid_shape, legend_rows, panel_grid
from .results import Results
from .style import cfa_styles, fmt_value

#: Block-mean chroma above this is named in the chirp figure's caption as
#: false colour (issue 12: no surface colour of our scenes comes near it).
CHROMA_NO_SURFACE = 200.0

#: The ideal sensor: a broad grey line under the cameras' (unlike any CFA's line).
_IDEAL = dict(color="#000000", alpha=0.35, linestyle="-", linewidth=3.2, solid_capstyle="butt")


def _ideal_handle(label="ideal sensor"):
    from matplotlib.lines import Line2D

    return Line2D([], [], **_IDEAL), label


def _arr(values) -> np.ndarray:
    """A JSON list (None for NaN) as a float array."""
    return np.array([np.nan if v is None else v for v in values], dtype=float)


# -- MTF (Figs 6, 11) ---------------------------------------------------------------------------

def mtf_curves(res: Results):
    """MTF of the slanted edge per channel (R, G, B, luminance), one curve per
    CFA and the ideal sensor dashed, one row per demosaic; the vertical line
    is the Nyquist frequency and each CFA's marker sits at its MTF50 on the
    0.5 line (the paper's Fig 6 b and Fig 11)."""
    title = "Slanted edge: MTF per channel (paper Figs 6, 11)"
    lum = res.primary_luminance
    scene, pairs = res.detail_pairs("mtf", lum) if lum is not None else (None, [])
    if not pairs:
        return _no_details("mtf", title, res, "mtf", "slanted-edge MTF")
    ideal = res.metric_detail("mtf", scene, None, None, lum)
    channels = ["R", "G", "B", "lum"]
    dems = [d for d in res.demosaics if any(p[1] == d for p in pairs)]
    cst = cfa_styles(res.cfas)
    n_leg = len({p[0] for p in pairs}) + 2
    ncol = min(n_leg, 7)
    fig, axes = panel_grid(len(dems), len(channels), 2.55, 1.85, left=0.95, right=0.15,
                           top=0.55 + 0.2 * legend_rows(n_leg, ncol), bottom=0.5, wspace=0.12, hspace=0.12,
                           sharex=True, sharey=True)
    first = pairs[0][2]
    nyq_mm = float(first.get("nyquist_cy_mm") or np.nan)
    nyq_px = float(first.get("nyquist_cy_px") or 0.5)
    to_mm = nyq_mm / nyq_px if np.isfinite(nyq_mm) else np.nan
    unit = "cy/mm" if np.isfinite(to_mm) else "cy/px"
    k = to_mm if np.isfinite(to_mm) else 1.0
    xmax = 2.0 * nyq_px * k
    drawn = []
    for r, d in enumerate(dems):
        for ci, ch in enumerate(channels):
            ax = axes[r * len(channels) + ci]
            if ideal is not None:
                rec = (ideal.get("records") or {}).get(ch) or {}
                if rec.get("mtf") is not None:
                    ax.plot(_arr(rec["freq_cy_px"]) * k, _arr(rec["mtf"]), **_IDEAL, zorder=1.5)
            for c, dd, det in pairs:
                if dd != d:
                    continue
                rec = (det.get("records") or {}).get(ch) or {}
                if rec.get("mtf") is None:
                    continue
                st = cst[c]
                ax.plot(_arr(rec["freq_cy_px"]) * k, _arr(rec["mtf"]), color=st["color"],
                        linestyle=st["linestyle"], linewidth=1.1)
                m50 = rec.get("mtf50_cy_px")
                if rec.get("mtf50_found", True) and m50 is not None:
                    ax.plot([float(m50) * k], [0.5], marker=st["marker"], color=st["color"], markersize=5,
                            markeredgecolor="white", markeredgewidth=0.5, linestyle="none", zorder=4)
                if c not in drawn:
                    drawn.append(c)
            ax.axvline(nyq_px * k, color="#CC3311", linewidth=1.0, linestyle="-.")
            ax.axhline(0.5, color="#888888", linewidth=0.7, linestyle=":")
            ax.set_xlim(0, xmax)
            ax.set_ylim(-0.02, 1.05)
            if r == 0:
                ax.set_title({"lum": "luminance (0.3R+0.6G+0.1B)"}.get(ch, f"{ch} channel"))
            if r == len(dems) - 1:
                ax.set_xlabel(f"spatial frequency ({unit} on sensor)")
            else:
                ax.tick_params(labelbottom=False)
            if ci == 0:
                ax.set_ylabel(f"{d}\nMTF (SFR, 0-1)")
            else:
                ax.tick_params(labelleft=False)
    from matplotlib.lines import Line2D

    nyq = Line2D([], [], color="#CC3311", linewidth=1.0, linestyle="-.")
    cfa_legend(fig, cst, drawn, extra=[_ideal_handle(), (nyq, f"Nyquist ({nyq_px * k:.1f} {unit})")],
               ncol=ncol)
    alias = first.get("percent_alias")
    cap = (f"Spatial frequency response of the slanted edge ({scene}, {lum:g} cd/m²) for each colour channel "
           f"of the camera's output and for luminance, against the ideal sensor (broad grey line: same optics and "
           f"pixel, no mosaic or noise). The dash-dot line is the sensor's Nyquist frequency; each marker on "
           f"the dotted 0.5 line is that CFA's MTF50 for the channel (the luminance MTF50 is the scored "
           f"metric, Table 2).")
    if alias is not None:
        cap += (" The percent alias (area of the luminance MTF beyond Nyquist over the area below it) is in "
                "the details JSON.")
    return ReportFigure("mtf", "mtf", title, cap, fig)


# -- moire (Fig 13) -------------------------------------------------------------------------------

def moire_curves(res: Results):
    """Block-mean chroma C*ab along the chirp's central row against the
    chirp's local frequency, one panel per demosaic, a line per CFA and the
    ideal sensor dashed; the horizontal line is the threshold and each
    marker the CFA's moire starting point (the paper's Fig 13 b)."""
    title = "Chirp: chroma along the central row and the moiré starting point (paper Fig 13)"
    lum = res.primary_luminance
    scene, pairs = res.detail_pairs("moire", lum) if lum is not None else (None, [])
    if not pairs:
        return _no_details("moire", title, res, "moire", "chirp (moiré)")
    dems = [d for d in res.demosaics if any(p[1] == d for p in pairs)]
    cst = cfa_styles(res.cfas)
    rows, cols = grid_shape(len(dems), 2)
    n_leg = len({p[0] for p in pairs}) + 2
    ncol = min(n_leg, 7)
    fig, axes = panel_grid(rows, cols, 4.9, 2.6, left=0.75, right=0.15, top=0.35 + 0.2 * legend_rows(n_leg, ncol),
                           bottom=0.5, wspace=0.2, hspace=0.4, n=len(dems), sharex=True, sharey=True, width=6.0)
    first = pairs[0][2]
    thr = float(first.get("threshold", 25.0))
    block = first.get("block")
    # The axis shows the threshold region: up to 4x the threshold or the
    # upper quartile of the curves' peaks, whichever is higher; a CFA whose
    # chroma soars far above (cmy2's reaches ~100x the threshold) would
    # flatten every other curve, so it is cut off and named in the caption.
    peaks = {}
    for c, d, det in pairs:
        bm = _arr(det.get("block_mean_test") or [])
        if bm.size and np.isfinite(bm).any():
            peaks[(c, d)] = float(np.nanmax(bm))
    top = max(peaks.values(), default=thr)
    ymax = max(thr * 1.6, min(top * 1.05, max(thr * 4.0, 1.05 * float(np.quantile(list(peaks.values()) or [thr], 0.75)))))
    clipped = [f"{c} ({d}) peaks at {v:.0f}" for (c, d), v in peaks.items() if v > ymax]
    drawn, lower_bounds = [], []
    for i, (ax, d) in enumerate(zip(axes, dems)):
        ref_done = False
        for c, dd, det in pairs:
            if dd != d:
                continue
            f = _arr(det.get("frequency_cy_per_deg") or [])
            bm = _arr(det.get("block_mean_test") or [])
            if not f.size or f.size != bm.size:
                continue
            order = np.argsort(f)
            if not ref_done and det.get("block_mean_reference") is not None:
                br = _arr(det["block_mean_reference"])
                if br.size == f.size:
                    ax.plot(f[order], br[order], **_IDEAL, zorder=1.5)
                    ref_done = True
            st = cst[c]
            ax.plot(f[order], bm[order], color=st["color"], linestyle=st["linestyle"], linewidth=1.1)
            msp = det.get("value")
            if msp is not None:
                passed = bool(det.get("passed", True))
                ax.plot([float(msp)], [thr], marker=st["marker"] if passed else ">", color=st["color"],
                        markersize=6, markeredgecolor="black" if not passed else "white", markeredgewidth=0.6,
                        linestyle="none", zorder=5, clip_on=False)
                if not passed:
                    lower_bounds.append(f"{c} ({d})")
            if c not in drawn:
                drawn.append(c)
        ax.axhline(thr, color="#CC3311", linewidth=1.0, linestyle="-.")
        ax.set_ylim(0, ymax)
        ax.set_title(d)
        if i + cols >= len(dems):
            ax.set_xlabel("chirp frequency (cy/deg)")
        else:
            ax.tick_params(labelbottom=False)
        if i % cols == 0:
            ax.set_ylabel("block-mean chroma C*ab")
        else:
            ax.tick_params(labelleft=False)
    from matplotlib.lines import Line2D

    thr_h = Line2D([], [], color="#CC3311", linewidth=1.0, linestyle="-.")
    cfa_legend(fig, cst, drawn, extra=[_ideal_handle("ideal sensor"), (thr_h, f"threshold C*ab = {thr:g}")],
               ncol=ncol)
    bl = f"{block} × {block} px" if block else "square"
    cap = (f"Chroma C*ab = √(a*² + b*²) of the camera image of the black-and-white chirp ({scene}, "
           f"{lum:g} cd/m²), averaged over {bl} blocks centred on the central row, against the chirp's local "
           f"frequency; the ideal sensor (broad grey line) stays near 0 as the chart has no colour. The MSP, the "
           f"scored metric, is the first frequency (from low to high) where the block mean passes the "
           f"threshold; each CFA's marker sits there on the threshold line.")
    if clipped:
        cap += (" Cut off at the top of the axis: " + "; ".join(clipped[:6]) + (" …" if len(clipped) > 6 else "")
                + ".")
    beyond = []
    for c, d, det in pairs:
        pixel = _arr(det.get("chroma_test") or [])
        top_pixel = float(np.nanmax(pixel)) if pixel.size and np.isfinite(pixel).any() else 0.0
        if max(top_pixel, peaks.get((c, d), 0.0)) > CHROMA_NO_SURFACE:
            oog = det.get("out_of_gamut_fraction")
            beyond.append(f"{c} ({d}): C*ab up to {top_pixel:.0f} on the row, block mean up to "
                          f"{peaks.get((c, d), float('nan')):.0f}"
                          + (f", {100 * float(oog):.1f} % of the row's pixels outside the colours any light has"
                             if oog else ""))
    if beyond:
        cap += (f" Above C*ab {CHROMA_NO_SURFACE:g}, which no surface colour reaches (the ColorChecker's most "
                "saturated patch is below 100), the chroma is false colour, not a colour of the scene: a CFA whose "
                "channels are each sampled sparsely aliases each at its own phase on the chirp, and the colour "
                "matrix turns their disagreement into colours no light has (docs/isp.md): "
                + "; ".join(beyond[:8]) + (" …" if len(beyond) > 8 else "") + ".")
    if lower_bounds:
        cap += (" A ▷ marker means the drawn realisation never passed the threshold: its MSP is the chirp's top "
                "frequency, a lower bound (metrics.csv's censored_count says in how many realisations; "
                + ", ".join(lower_bounds[:8]) + (" …" if len(lower_bounds) > 8 else "") + ").")
    return ReportFigure("moire", "moire", title, cap, fig)


# -- ColorChecker (Figs 8, 9) ---------------------------------------------------------------------

def _read_png(path) -> np.ndarray | None:
    import io

    from PIL import Image

    from ..io.guard import read_bytes

    try:  # through the bounded reader: a FIFO among the results is skipped, not read for ever
        with Image.open(io.BytesIO(read_bytes(path, "thumbnail"))) as im:
            return np.asarray(im.convert("RGB"))
    except (OSError, ValueError):  # CfaMitsubaError is a ValueError
        return None


def scielab_maps(res: Results):
    """S-CIELAB dE00 maps, rows: CFAs, columns: demosaics, the ideal
    sensor's image apart, all on one colour scale with a colour bar (the
    paper's Fig 10)."""
    from .sheets import colourise, compose_sheet

    title = "S-CIELAB ΔE00 maps (paper Fig 10)"
    lum = res.primary_luminance
    scene = res.scene_for("scielab")
    if scene is None or lum is None:
        return Absent("scielab", title, "S-CIELAB maps (puppy or a custom scene, Fig 10)", not_in_study=True)
    maps = {}
    for d in res.demosaics:
        for c in res.cfas:
            a = res.scielab_map(scene, c, d, lum)
            if a is not None:
                maps[(c, d)] = a
    if not maps:
        return Absent("scielab", title, f"S-CIELAB was measured on {scene!r} but no maps were saved "
                      f"(details/{scene}/<cfa>/<demosaic>/L{lum:g}.scielab.npy)")
    allv = np.concatenate([a[np.isfinite(a)].ravel() for a in maps.values()])
    vmax = float(np.percentile(allv, 99.5)) if allv.size else 1.0
    vmax = max(vmax, 1e-6)
    ideal_img = None
    p = res.thumbnail_path(scene, None, None, lum)
    if p is not None:
        ideal_img = _read_png(p)
    cfas = [c for c in res.cfas if any((c, d) in maps for d in res.demosaics)]
    dems = [d for d in res.demosaics if any((c, d) in maps for c in cfas)]
    cells = {k: colourise(a, 0.0, vmax) for k, a in maps.items()}
    caps = {}
    for (c, d) in maps:
        v = res.value(scene, c, d, lum, "scielab")
        s_ = res.value(scene, c, d, lum, "ssim")
        caps[(c, d)] = f"ΔE {fmt_value('scielab', v)}" + (f" · SSIM {fmt_value('ssim', s_)}" if s_ is not None
                                                          else "")
    if ideal_img is not None and ideal_img.shape[:2] != next(iter(cells.values())).shape[:2]:
        ideal_img = None
    img = compose_sheet(cfas, dems, cells, corner=("ideal sensor (sRGB)", ideal_img) if ideal_img is not None
                        else None, captions=caps,
                        colorbar=dict(cmap="viridis", vmin=0.0, vmax=vmax, label="S-CIELAB ΔE00"),
                        scale=_sheet_scale(max(next(iter(cells.values())).shape[:2])))
    cap = (f"Per-pixel S-CIELAB colour difference (CIEDE2000 after the spatial filters of the eye) between the "
           f"ideal sensor and each camera ({scene}, {lum:g} cd/m²): rows are CFAs, columns demosaicing methods; "
           f"the ideal sensor's image is at the top left for orientation. One colour scale for every map (0 to "
           f"{vmax:.1f} ΔE00, the 99.5th percentile of all maps; brighter = larger error). Under each map: its "
           f"mean ΔE00 (the scored value) and the SSIM of the same image. Maps are block-averaged to at most "
           f"240 px.")
    return ReportFigure("scielab-maps", "scielab", title, cap, None, raster=True, image=img)


# -- gray bar (Fig 14) -------------------------------------------------------------------------------

def gray_bar_profiles(res: Results):
    """The gray bar's L* along the central row, ideal and every camera (top
    row), and the mean |dL*| of each of its steps (bottom row), one column
    per demosaic (the paper's Fig 14)."""
    title = "Gray bar: L* along the central row (paper Fig 14)"
    lum = res.primary_luminance
    scene, pairs = res.detail_pairs("achromatic", lum) if lum is not None else (None, [])
    pairs = [p for p in pairs if p[2].get("l_reference") and p[2].get("l_test")]
    if not pairs:
        return _no_details("achromatic", title, res, "achromatic", "gray-bar (AR error)")
    dems = [d for d in res.demosaics if any(p[1] == d for p in pairs)]
    cst = cfa_styles(res.cfas)
    n = len(dems)
    n_leg = len({p[0] for p in pairs}) + 1
    ncol = min(n_leg, 7)
    fig, axes = panel_grid(2, n, 2.9, 2.0, left=0.75, right=0.15, top=0.55 + 0.2 * legend_rows(n_leg, ncol),
                           bottom=0.5, wspace=0.15, hspace=0.75, width=6.0)
    drawn = []
    for i, d in enumerate(dems):
        top, bot = axes[i], axes[n + i]
        if i:
            top.sharey(axes[0])
            bot.sharey(axes[n])
        ref_done = False
        for c, dd, det in pairs:
            if dd != d:
                continue
            lr, lt = _arr(det["l_reference"]), _arr(det["l_test"])
            x = np.arange(lr.size)
            st = cst[c]
            top.plot(x, lt, color=st["color"], linestyle=st["linestyle"], linewidth=0.8, alpha=0.9)
            if not ref_done:
                top.plot(x, lr, **_IDEAL, zorder=1.5)
                ref_done = True
                x0, x1 = (det.get("columns") or [0, lr.size])[:2]
                for ax in (top,):
                    ax.axvspan(-0.5, x0 - 0.5, color="#eeeeee", zorder=0)
                    ax.axvspan(x1 - 0.5, lr.size - 0.5, color="#eeeeee", zorder=0)
            per = det.get("per_step")
            if per:
                p = _arr(per)
                bot.plot(np.arange(1, p.size + 1), p, color=st["color"], marker=st["marker"],
                         linestyle=st["linestyle"], linewidth=1.0, markersize=3.5)
                bot.set_xlabel("gray step (1 = white … 10 = black)")
                bot.set_xticks(np.arange(1, p.size + 1))
            else:
                ad = np.abs(lt - lr)
                bot.plot(x, ad, color=st["color"], linestyle=st["linestyle"], linewidth=0.8)
                bot.set_xlabel("column (px)")
            if c not in drawn:
                drawn.append(c)
        top.set_title(d)
        top.set_xlabel("column along the central row (px)")
        if i == 0:
            top.set_ylabel("L* (0-100)")
            bot.set_ylabel("mean |ΔL*| per step")
        else:
            top.tick_params(labelleft=False)
            bot.tick_params(labelleft=False)
    bottoms = [ln.get_ydata() for ax in axes[n:] for ln in ax.get_lines()]
    top_y = max((float(np.nanmax(y)) for y in bottoms if np.size(y) and np.isfinite(y).any()), default=1.0)
    axes[n].set_ylim(0, top_y * 1.05)
    cfa_legend(fig, cst, drawn, extra=[_ideal_handle()], ncol=ncol)
    cap = (f"Top: CIE L* along the central row of the gray bar ({scene}, {lum:g} cd/m²), the ideal sensor "
           f"as a broad grey line and each camera in its CFA's colour; the shaded ends are left out of the AR error "
           f"(demosaicing border effects). Bottom: the mean |ΔL*| (camera − ideal) within each of the ten "
           f"steps; the scored AR error is their pixel-weighted mean over the analysed columns (Table 2).")
    return ReportFigure("achromatic", "achromatic", title, cap, fig)


# -- thumbnails --------------------------------------------------------------------------------------

def _sheet_scale(side: int) -> int:
    """Integer enlargement of small images in a sheet (to about 200 px)."""
    return int(max(1, min(3, 200 // max(1, side))))


def thumbnail_sheet(res: Results, scene: str, lum: float):
    """Every camera output of one scene (rows: CFAs, columns: demosaics) next
    to the ideal sensor, at the thumbnails' own pixels (no resampling)."""
    from .sheets import compose_sheet

    title = "Camera outputs"
    cells = {}
    for c in res.cfas:
        for d in res.demosaics:
            p = res.thumbnail_path(scene, c, d, lum)
            img = _read_png(p) if p is not None else None
            if img is not None:
                cells[(c, d)] = img
    if not cells:
        return Absent("outputs", f"{title}: {scene}", f"no thumbnails of {scene!r} at {lum:g} cd/m² under details/")
    ideal_p = res.thumbnail_path(scene, None, None, lum)
    ideal = _read_png(ideal_p) if ideal_p is not None else None
    cfas = [c for c in res.cfas if any((c, d) in cells for d in res.demosaics)]
    dems = [d for d in res.demosaics if any((c, d) in cells for c in cfas)]
    side = max(max(a.shape[:2]) for a in cells.values())
    img = compose_sheet(cfas, dems, cells, corner=("ideal sensor", ideal) if ideal is not None else None,
                        scale=_sheet_scale(side))
    cap = (f"sRGB renderings of {scene} at {lum:g} cd/m² as each CFA and demosaicing method produce them (rows: "
           f"CFAs, columns: demosaicing methods), with the ideal sensor at the top left. Thumbnails are "
           f"block-averaged to at most 240 px, which hides detail finer than a few pixels"
           + (f" (shown at {_sheet_scale(side)}× here)" if _sheet_scale(side) > 1 else "") + ".")
    return ReportFigure(f"outputs-{scene}", "outputs", title, cap, None, raster=True, group=scene, image=img)
