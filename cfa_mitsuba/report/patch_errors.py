"""Which ColorChecker patches go wrong (issue 50): every CFA and demosaic's
chart drawn as its 24 swatches coloured by their CIEDE2000 error, on one
colour scale, with the error written in each swatch; the ideal sensor's
chart in its own colours at the top left.  Drawn from ``patches.csv``
(study/patches.py)."""

from __future__ import annotations

__all__ = ["patch_error_sheet", "read_table"]

from pathlib import Path

import numpy as np

from .figure import Absent, ReportFigure
from .results import Results

#: Swatch side (px) and the chart's layout (rows x columns, reading order).
_SIDE = 26
_ROWS, _COLS = 4, 6


def read_table(res: Results, name: str):
    """``res.root / name`` as a DataFrame, or None when absent or unreadable."""
    from ..errors import CfaMitsubaError
    from ..io.guard import read_csv

    path = Path(res.root) / name
    if not path.is_file():
        return None
    try:
        return read_csv(path)
    except (OSError, ValueError, CfaMitsubaError):
        return None


def _chart(values: np.ndarray, colours: np.ndarray, labels=None) -> np.ndarray:
    """A 4 x 6 chart of ``colours`` ((24, 3) uint8) with ``labels`` (text
    per swatch) drawn in black or white, whichever reads on the swatch."""
    from PIL import Image, ImageDraw

    from .sheets import _font

    gap = 2
    h, w = _ROWS * (_SIDE + gap) + gap, _COLS * (_SIDE + gap) + gap
    img = Image.new("RGB", (w, h), (40, 40, 40))
    draw = ImageDraw.Draw(img)
    font = _font(9)
    for i in range(min(len(colours), _ROWS * _COLS)):
        r, c = divmod(i, _COLS)
        x0, y0 = gap + c * (_SIDE + gap), gap + r * (_SIDE + gap)
        col = tuple(int(v) for v in colours[i])
        draw.rectangle((x0, y0, x0 + _SIDE - 1, y0 + _SIDE - 1), fill=col)
        if labels is not None:
            light = 0.2126 * col[0] + 0.7152 * col[1] + 0.0722 * col[2] > 140
            draw.text((x0 + _SIDE // 2, y0 + _SIDE // 2), labels[i], font=font, fill=(0, 0, 0) if light else
                      (255, 255, 255), anchor="mm")
    return np.asarray(img)


def _ideal_colours(g) -> np.ndarray:
    """sRGB of each patch as the ideal sensor sees it (CIELAB against a D65
    white, as the study's CIELAB is against the scene white)."""
    from ..colour_science import colour_science

    colour = colour_science()
    lab = g[["l_ideal", "a_ideal", "b_ideal"]].to_numpy(float)
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    xyz = colour.Lab_to_XYZ(lab, d65)
    rgb = colour.XYZ_to_sRGB(xyz, d65)
    return (np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8)


def patch_error_sheet(res: Results):
    """The patch-error sheet at the primary luminance (module doc)."""
    from .sheets import colourise, compose_sheet

    title = "ColorChecker: the error of each patch"
    t = read_table(res, "patches.csv")
    lum = res.primary_luminance
    if t is None or lum is None or not len(t):
        if res.scene_for("delta-e") is None:
            return Absent("colour", title, "the ColorChecker (macbeth)", not_in_study=True)
        return Absent("colour", title, "patches.csv is absent (results written before the study kept each "
                      "patch's error): rerun the study to write it")
    t = t[np.isclose(t["luminance"].astype(float), lum) & t["cfa"].isin(res.cfas) & t["demosaic"].isin(res.demosaics)]
    t = t[t["condition"] == t["condition"].iloc[0]] if len(t) else t
    if not len(t):
        return Absent("colour", title, f"patches.csv has no rows at {lum:g} cd/m²")
    vmax = max(float(np.nanpercentile(t["de00"], 99)), 1e-6)
    cells, caps = {}, {}
    for (c, d), g in t.groupby(["cfa", "demosaic"], sort=False):
        g = g.sort_values("patch")
        de = g["de00"].to_numpy(float)
        cells[(c, d)] = _chart(de, colourise(de[None, :], 0.0, vmax, "magma")[0], [f"{v:.1f}" for v in de])
        caps[(c, d)] = f"mean ΔE00 {np.nanmean(de):.2f}, worst {g['name'].iloc[int(np.nanargmax(de))]}"
    first = t[(t["cfa"] == t["cfa"].iloc[0]) & (t["demosaic"] == t["demosaic"].iloc[0])].sort_values("patch")
    ideal = _chart(np.zeros(len(first)), _ideal_colours(first))
    cfas = [c for c in res.cfas if any((c, d) in cells for d in res.demosaics)]
    dems = [d for d in res.demosaics if any((c, d) in cells for c in cfas)]
    img = compose_sheet(cfas, dems, cells, corner=("the chart (ideal sensor)", ideal), captions=caps,
                        colorbar=dict(cmap="magma", vmin=0.0, vmax=vmax, label="ΔE00 of the patch"))
    scene = str(t["scene"].iloc[0])
    cap = (f"The 24 ColorChecker patches ({scene}, {lum:g} cd/m²) in the chart's layout (dark skin at the top "
           f"left, the grey row at the bottom), each swatch coloured by its CIEDE2000 error against the ideal "
           f"sensor and labelled with it: rows are CFAs, columns demosaicing methods; top left, the chart as the "
           f"ideal sensor sees it. One colour scale (0 to {vmax:.1f} ΔE00, the 99th percentile). Under each chart "
           f"its mean (the first noise realisation's; Table 1 holds the mean over realisations) and its worst "
           f"patch. Every number is in patches.csv.")
    return ReportFigure("patch-errors", "colour", title, cap, None, raster=True, image=img)
