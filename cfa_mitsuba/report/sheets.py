"""Image sheets: many small images in a labelled grid, composed in numpy and
labelled with Pillow at the images' own pixels (no resampling, and far
faster than a matplotlib axes per image at 12 CFAs x 4 demosaics).

Used for the camera outputs (rows: CFAs, columns: demosaics, the ideal
sensor apart) and the S-CIELAB maps (the same grid on one colour scale with
a colour bar).
"""

from __future__ import annotations

__all__ = ["compose_sheet", "colourise"]

from functools import lru_cache

import numpy as np

_BG = (255, 255, 255)
_INK = (31, 35, 40)
_MUTED = (89, 99, 110)


@lru_cache(maxsize=8)
def _font(size: int, bold: bool = False):
    from PIL import ImageFont

    try:
        from matplotlib import font_manager

        path = font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans",
                                                                 weight="bold" if bold else "normal"))
        return ImageFont.truetype(path, size)
    except (OSError, ValueError, ImportError):  # pragma: no cover - no FreeType
        return ImageFont.load_default()


def _text_w(draw, text: str, font) -> int:
    x0, _, x1, _ = draw.textbbox((0, 0), text, font=font)
    return x1 - x0


def colourise(values: np.ndarray, vmin: float, vmax: float, cmap: str = "viridis") -> np.ndarray:
    """A 2-D array as uint8 RGB through a matplotlib colour map (NaN: light grey)."""
    import matplotlib

    cm = matplotlib.colormaps[cmap]
    v = np.asarray(values, dtype=float)
    t = np.clip((v - vmin) / (vmax - vmin), 0.0, 1.0)
    rgb = (cm(np.nan_to_num(t, nan=0.0))[..., :3] * 255 + 0.5).astype(np.uint8)
    rgb[~np.isfinite(v)] = (230, 230, 230)
    return rgb


def compose_sheet(row_labels, col_labels, cells: dict, *, corner=None, captions: dict | None = None,
                  colorbar: dict | None = None, scale: int = 1):
    """A labelled grid of images as a Pillow RGB image.

    ``cells``: {(row label, column label): (h, w, 3) uint8}; ``corner``:
    (label, image) shown left of the grid, level with its first row (the
    ideal sensor); ``captions``: {(row, column): text under the image};
    ``colorbar``: dict(cmap, vmin, vmax, label) drawn at the right;
    ``scale``: integer up-scaling of the images (nearest) for tiny ones.
    """
    from PIL import Image, ImageDraw

    f_lab, f_cap, f_head = _font(13), _font(11), _font(13, bold=True)
    imgs = {k: np.repeat(np.repeat(v, scale, 0), scale, 1) if scale > 1 else v for k, v in cells.items()}
    cimg = None
    if corner is not None and corner[1] is not None:
        cimg = corner[1]
        if scale > 1:
            cimg = np.repeat(np.repeat(cimg, scale, 0), scale, 1)
    shapes = [v.shape for v in imgs.values()] + ([cimg.shape] if cimg is not None else [])
    probe = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    th = max(s[0] for s in shapes)
    # a column is as wide as its widest image, header or caption
    texts = [_text_w(probe, str(c), f_head) for c in col_labels]
    texts += [_text_w(probe, t, f_cap) for t in (captions or {}).values()]
    if corner is not None:
        texts.append(_text_w(probe, str(corner[0]), f_head))
    tw = max([s[1] for s in shapes] + [t + 6 for t in texts])
    gap = 8
    cap_h = 16 if captions else 0
    left = 24 + max([_text_w(probe, str(r), f_lab) for r in row_labels] + [20])
    top = 24
    corner_w = (tw + 3 * gap) if cimg is not None else 0
    cb_w = 0
    if colorbar:
        cb_w = 30 + max(_text_w(probe, f"{v:.1f}", f_cap) for v in (colorbar["vmin"], colorbar["vmax"])) + 26
    W = left + corner_w + len(col_labels) * (tw + gap) + cb_w + 6
    H = top + len(row_labels) * (th + cap_h + gap) + 4
    sheet = Image.new("RGB", (W, H), _BG)
    draw = ImageDraw.Draw(sheet)
    x_grid = left + corner_w

    def put(img, x, y, centre=False):
        if centre:  # centre an image narrower than its column
            x += (tw - img.shape[1]) // 2
        sheet.paste(Image.fromarray(np.ascontiguousarray(img[..., :3])), (x, y))

    for k, c in enumerate(col_labels):
        cx = x_grid + k * (tw + gap) + tw // 2
        draw.text((cx, top - 6), str(c), font=f_head, fill=_INK, anchor="mb")
    for r, row in enumerate(row_labels):
        y = top + r * (th + cap_h + gap)
        draw.text((left - 8, y + th // 2), str(row), font=f_lab, fill=_INK, anchor="rm")
        for k, c in enumerate(col_labels):
            x = x_grid + k * (tw + gap)
            img = imgs.get((row, c))
            if img is None:
                draw.rectangle((x, y, x + tw - 1, y + th - 1), outline=(208, 215, 222))
                draw.text((x + tw // 2, y + th // 2), "not measured", font=f_cap, fill=_MUTED, anchor="mm")
                continue
            put(img, x, y, centre=True)
            if captions and (row, c) in captions:
                draw.text((x + tw // 2, y + th + 2), captions[(row, c)], font=f_cap, fill=_MUTED, anchor="mt")
    if cimg is not None:
        put(cimg, left, top, centre=True)
        draw.text((left + tw // 2, top - 6), str(corner[0]), font=f_head, fill=_INK, anchor="mb")
    if colorbar:
        x0 = W - cb_w + 10
        y0 = top
        h = max(120, min(H - top - 30, 360))
        ramp = np.linspace(colorbar["vmax"], colorbar["vmin"], h)[:, None].repeat(14, axis=1)
        put(colourise(ramp, colorbar["vmin"], colorbar["vmax"], colorbar.get("cmap", "viridis")), x0, y0)
        draw.rectangle((x0 - 1, y0 - 1, x0 + 14, y0 + h), outline=_MUTED)
        ticks = _nice_ticks(colorbar["vmin"], colorbar["vmax"])
        for t in ticks:
            yy = y0 + int(round((colorbar["vmax"] - t) / (colorbar["vmax"] - colorbar["vmin"]) * (h - 1)))
            draw.line((x0 + 14, yy, x0 + 18, yy), fill=_INK)
            draw.text((x0 + 21, yy), f"{t:g}", font=f_cap, fill=_INK, anchor="lm")
        label = colorbar.get("label", "")
        if label:
            lw = _text_w(probe, label, f_cap) + 4
            txt = Image.new("RGB", (lw, 16), _BG)
            ImageDraw.Draw(txt).text((2, 1), label, font=f_cap, fill=_INK)
            txt = txt.rotate(90, expand=True)
            sheet.paste(txt, (W - 20, y0 + max(0, (h - lw) // 2)))
    return sheet


def _nice_ticks(vmin: float, vmax: float) -> list[float]:
    span = vmax - vmin
    if span <= 0:
        return [vmin]
    raw = span / 5
    mag = 10 ** np.floor(np.log10(raw))
    step = min((m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw), default=raw)
    first = np.ceil(vmin / step) * step
    return [round(float(v), 10) for v in np.arange(first, vmax + step * 1e-9, step)]
