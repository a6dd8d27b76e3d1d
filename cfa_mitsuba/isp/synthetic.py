"""Mosaics from full-colour images, for demosaicing research and tests.

A spectral scene goes through the sensor stage (``cm.sensor.capture``); these
helpers are the shortcut the demosaicing literature takes instead: sample a
full-colour image through a CFA's tile.
"""

from __future__ import annotations

__all__ = ["mosaic_image", "channels_from_rgb"]

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError
from .colour_matrix import electrons_per_radiance_of
from .demosaic import resolve_cfa
from .mosaic import geometry


def mosaic_image(image, cfa) -> np.ndarray:
    """(H, W) mosaic of a full image (H, W, C), C = ``len(cfa.channels)``
    in ``cfa.channels`` order: each pixel keeps the channel its filter
    passes (``image[0, 0]`` under ``cfa.pattern[0, 0]``).

    Examples
    --------
    >>> import numpy as np
    >>> img = np.stack([np.full((2, 2), v) for v in (1.0, 2.0, 3.0)], axis=-1)
    >>> mosaic_image(img, "bayer").tolist()   # G R / B G
    [[2.0, 1.0], [3.0, 2.0]]
    """
    mosaic = geometry(resolve_cfa(cfa))
    img = np.asarray(image, dtype=np.float64)
    if img.ndim != 3 or img.shape[2] != len(mosaic.channels):
        raise CfaMitsubaError(f"image of shape {img.shape} does not have the CFA's {len(mosaic.channels)} channels")
    th, tw = mosaic.tile_shape
    out = np.empty(img.shape[:2])
    for (i, j), c in np.ndenumerate(mosaic.index):
        out[i::th, j::tw] = img[i::th, j::tw, c]
    return out


def channels_from_rgb(rgb, cfa, illuminant: str = "D65") -> np.ndarray:
    """A white-balanced RGB image (H, W, 3), seen as the responses of the
    project's camera R, G, B (:func:`cfa_mitsuba.spectra.camera_rgb`),
    converted to a CFA's white-balanced channels (H, W, C).

    Each channel's sensitivity is approximated by the least-squares
    combination of the camera's R, G, B over wavelength (exact for the
    built-in C, M, Y, W, which are sums of them); rows are normalised so
    that white (1, 1, 1) gives 1 in every channel.
    """
    cfa = resolve_cfa(cfa)
    wl = spectra.DEFAULT_WAVELENGTHS
    light = spectra.illuminant(illuminant, wl)
    cam = electrons_per_radiance_of(spectra.camera_rgb(wl).T, wl)  # (3, B)
    own = electrons_per_radiance_of(cfa.sensitivities(wl), wl)  # (C, B)
    mix = np.linalg.lstsq(cam.T, own.T, rcond=None)[0].T  # (C, 3): own ~ mix @ cam
    mix = mix * (cam @ light)[None, :]  # act on balanced RGB
    mix = mix / mix.sum(axis=1, keepdims=True)
    return np.asarray(rgb, dtype=np.float64) @ mix.T
