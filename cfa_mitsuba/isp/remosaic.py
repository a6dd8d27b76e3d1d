"""The image processor's side of the read-out modes
(:mod:`cfa_mitsuba.sensor.readout`): remosaic, the binned image's return to
the full pixel grid, and per-channel gains.

Remosaic.  A block layout read at full resolution (quad-bayer, nona,
tetra2) is rearranged into the Bayer mosaic whose tile is the block
layout's tile with one pixel per block (quad-bayer's ``G R / B G``), at
the same pixel grid, and that mosaic goes to the chosen demosaicker.  The
algorithm is the simplest documented one: a pixel whose colour already is
the Bayer colour wanted there keeps its sample; any other pixel gets the
wanted colour by per-pixel interpolation from the nearest samples of that
colour, the normalised convolution of this package's ``bilinear`` method
(docs/isp.md) evaluated at the pixel.  This is the interpolation baseline
of remosaicing, not an edge-adaptive engine: sensor makers' on-chip
remosaic and the learned ones of the MIPI 2022 Quad-Bayer remosaic
challenge (Yang et al., ECCV Workshops 2022) adapt to edges, so the
remosaic scores here are a lower bound of what remosaicing reaches.

Binned output on the full grid.  A binned capture is demosaiced at its own
1/n resolution and the XYZ image is then brought back to the ideal
sensor's grid (the metrics compare pixel for pixel with it) by bilinear
interpolation between block centres (a binned pixel's centre is the
centre of its n x n block; beyond the outermost centres the edge value is
held).  This is how the binned picture is seen at the size of the
full-resolution one: its lost resolution shows in MTF50, S-CIELAB and
SSIM, its lower noise in the achromatic and colour errors.  Binning the
ideal instead would compare at the binned pitch and hide the resolution
that binning gives up.
"""

from __future__ import annotations

__all__ = ["remosaic", "upsample_blocks", "channel_gain_divisors", "readout_of"]

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class _Tile:
    name: str
    pattern: np.ndarray
    channels: tuple[str, ...]


def readout_of(raw) -> dict:
    """The raw image's read-out record (``meta['readout']``; older raw files: full)."""
    info = (raw.meta or {}).get("readout") if isinstance(raw.meta, dict) else None
    return info if isinstance(info, dict) else {"mode": "full", "block": 1}


def remosaic(mosaic: np.ndarray, cfa) -> tuple[np.ndarray, object]:
    """(the Bayer mosaic, its CFA) of a white-balanced block-layout mosaic
    (module doc).  ``cfa`` has ``pattern``, ``channels``, ``name``."""
    from ..sensor.readout import binned_pattern
    from .demosaic import demosaic

    native = np.asarray(cfa.pattern)
    target = binned_pattern(native)
    h, w = mosaic.shape
    th, tw = target.shape
    nh, nw = native.shape
    want = target[np.arange(h)[:, None] % th, np.arange(w)[None, :] % tw]
    have = native[np.arange(h)[:, None] % nh, np.arange(w)[None, :] % nw]
    full = demosaic(mosaic, cfa, "bilinear")  # every channel at every pixel, from its own samples only
    lut = {c: i for i, c in enumerate(cfa.channels)}
    index = np.vectorize(lut.__getitem__, otypes=[np.intp])(want)
    out = np.take_along_axis(full, index[..., None], axis=2)[..., 0]
    out = np.where(want == have, mosaic, out)
    return out, _Tile(f"{getattr(cfa, 'name', 'cfa')} (remosaic)", target, tuple(cfa.channels))


def upsample_blocks(image: np.ndarray, n: int, shape) -> np.ndarray:
    """(H, W, C): a binned (h, w, C) image on the full grid of ``shape``
    (H, W) by bilinear interpolation between block centres (module doc)."""
    out = image
    for axis, size in ((0, int(shape[0])), (1, int(shape[1]))):
        m = out.shape[axis]
        pos = np.clip((np.arange(size) - (n - 1) / 2.0) / n, 0.0, m - 1.0)
        i0 = np.minimum(np.floor(pos).astype(np.intp), m - 1)
        i1 = np.minimum(i0 + 1, m - 1)
        f = pos - i0
        a, b = np.take(out, i0, axis=axis), np.take(out, i1, axis=axis)
        shape_f = [1] * out.ndim
        shape_f[axis] = size
        f = f.reshape(shape_f)
        out = a * (1.0 - f) + b * f
    return out


def channel_gain_divisors(raw, channels) -> np.ndarray | None:
    """(C,) relative analogue gain of each channel (``channel_gain`` in the
    raw's sensor settings), or None when every channel has gain 1."""
    sensor = ((raw.settings or {}).get("sensor") or {}) if isinstance(raw.settings, dict) else {}
    gains = sensor.get("channel_gain") or {}
    if not gains:
        return None
    return np.array([float(gains.get(c, 1.0)) for c in channels])
