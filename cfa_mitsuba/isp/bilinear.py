"""Bilinear demosaicing: normalised convolution of each channel with a tent.

For channel c, NC_c = (K * (m_c y)) / (K * m_c) at its gaps, with m_c its
0/1 sampling mask and K a separable tent of half-width r_c,
w(d) = (r_c + 1 - |d|) per axis; observed samples are kept.  r_c is the
smallest half-width whose window holds samples of c that surround every gap
of c (:func:`~cfa_mitsuba.isp.mosaic.tent_radius`): 1 for every Bayer
channel, where this is the classic bilinear demosaic (the four cross
neighbours for G; two or four neighbours for R and B) and equals
colour-demosaicing's ``demosaicing_CFA_Bayer_bilinear`` in the interior; 2 for
the stripe CFAs (so a stripe's gap is a linear interpolation between the
stripes on either side, not a copy of the nearer one) and for the 1/8-density
R and B of the Kodak RGBW tiles.

Differs from ISETCam, whose ``ieBilinear`` applies fixed unnormalised
kernels (2 x 2 tiles only) and whose other tiles go through ``griddata``
followed by rescaling the image to a maximum of 1 (research/isetcam.md
s. 4.3): here every CFA gets the same definition and no rescaling.

References
----------
Research notes: research/cfa-demosaic.md s. 3.1.
"""

from __future__ import annotations

__all__ = ["bilinear", "bilinear_image", "interpolate_channel"]

import numpy as np

from ._memo import LastImage
from .demosaic import AccuracyBar, DemosaicMethod
from .mosaic import Mosaic, apply_stencils, extend, geometry, tent_radius, tent_stencil


def interpolate_channel(ext, ph, pw, shape, mosaic: Mosaic, c: int, out: np.ndarray) -> np.ndarray:
    """Fill ``out`` (H, W) with channel ``c``'s bilinear estimate from the
    extended mosaic ``ext`` (observed samples copied)."""
    th, tw = mosaic.tile_shape
    h, w = shape
    for i, j in mosaic.phases(c):
        out[i::th, j::tw] = ext[ph + i: ph + h: th, pw + j: pw + w: tw]
    stencils = {p: tent_stencil(mosaic, c, *p) for p in mosaic.gaps(c)}
    return apply_stencils(ext, ph, pw, shape, mosaic.tile_shape, stencils, out)


def bilinear(raw: np.ndarray, cfa) -> np.ndarray:
    """Bilinear (normalised-convolution) demosaic of any periodic CFA.

    Parameters
    ----------
    raw : (H, W) float64 white-balanced mosaic (white balance does not
        change this method's result, which never mixes channels).
    cfa : CFA (``pattern``, ``channels``).

    Returns
    -------
    (H, W, C) float64, ``cfa.channels`` order.

    Examples
    --------
    >>> import numpy as np
    >>> from cfa_mitsuba.isp import demosaic
    >>> raw = np.array([[0., 4.], [2., 0.]])       # Bayer G R / B G
    >>> demosaic(raw, "bayer", "bilinear")[0, 0].tolist()  # R, G, B at a G site
    [4.0, 0.0, 2.0]
    """
    return bilinear_image(raw, geometry(cfa)).copy()


#: the last mosaic's bilinear image: 'pocs' starts from it (:mod:`._memo`)
_LAST = LastImage()


def bilinear_image(raw: np.ndarray, mosaic: Mosaic) -> np.ndarray:
    """(H, W, C) bilinear estimate of every channel, read-only: kept for the
    next call on an equal mosaic (:class:`~._memo.LastImage`)."""

    def make():
        shape = raw.shape
        radius = max(tent_radius(mosaic, c) for c in range(len(mosaic.channels)))
        ext, ph, pw = extend(raw, mosaic, radius)
        out = np.empty((*shape, len(mosaic.channels)), dtype=raw.dtype)  # float32 stays float32
        for c in range(len(mosaic.channels)):
            interpolate_channel(ext, ph, pw, shape, mosaic, c, out[..., c])
        return out

    return _LAST.get(mosaic, raw, make)


#: This module's method (registered by :func:`.demosaic.collect_demosaics`).
def support_radius(cfa, options: dict) -> int:
    """How far (px) an output pixel reads the mosaic: the widest tent's half-width."""
    mosaic = geometry(cfa)
    return int(max(tent_radius(mosaic, c) for c in range(len(mosaic.channels))))


DEMOSAICS = (DemosaicMethod(name="bilinear", function=bilinear, order=1, linear=True, accuracy=AccuracyBar(),
                            support=support_radius,
                            description="normalised convolution per channel, tent wide enough for each channel's gaps"),)
