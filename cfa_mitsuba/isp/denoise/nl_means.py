"""``nl-means``: non-local means (scikit-image's ``denoise_nl_means``).

Each pixel becomes the weighted mean of the pixels within
``patch_distance`` whose surrounding ``patch_size`` x ``patch_size`` patches
look like its own, weights exp(-max(d^2 - 2 s^2, 0) / h^2) with d^2 the
mean squared patch difference and s the noise standard deviation (Buades,
Coll and Morel; the 'fast' variant of Darbon et al. with uniform patch
weights and the noise variance subtracted, as scikit-image computes it).
The stage hands it planes of unit noise (s = 1); ``sigma`` = the tuning
constant x ``scale`` is the filtering parameter h.

References
----------
A. Buades, B. Coll, J.-M. Morel, "A non-local algorithm for image
denoising", CVPR 2005, 60-65.  J. Darbon, A. Cunha, T. F. Chan, S. Osher,
G. J. Jensen, "Fast nonlocal filtering applied to electron cryomicroscopy",
ISBI 2008, 1331-1334.  scikit-image, ``skimage.restoration.denoise_nl_means``
(BSD-3).
"""

from __future__ import annotations

__all__ = ["nl_means"]

import numpy as np

from . import DenoiseMethod
from ._tuning import rule


def nl_means(plane: np.ndarray, *, sigma: float, patch_size: int = 5, patch_distance: int = 6) -> np.ndarray:
    """Non-local means of a 2-D ``plane`` whose noise has standard deviation 1.

    Parameters
    ----------
    plane : (H, W) float, stabilised (unit noise).
    sigma : the filtering parameter h (in noise standard deviations).
    patch_size : side of the compared patches (pixels of the plane).
    patch_distance : largest offset searched (pixels of the plane).

    Returns
    -------
    (H, W) float64, the denoised plane.
    """
    from skimage.restoration import denoise_nl_means

    return denoise_nl_means(np.asarray(plane, dtype=np.float64), h=float(sigma), sigma=1.0, fast_mode=True,
                            patch_size=int(patch_size), patch_distance=int(patch_distance), preserve_range=True)


#: This module's method (registered by :func:`.collect_denoisers`).
DENOISERS = (DenoiseMethod(name="nl-means", function=nl_means, order=2, domains=("raw", "rgb"),
                           strength=0.75, tuning=rule("nl-means"),
                           licence="scikit-image (BSD-3-Clause)",
                           # local: an output pixel weighs pixels within patch_distance, each by its patch
                           support=lambda o: int(o["patch_distance"]) + int(o["patch_size"]) // 2,
                           description="non-local means: weighted mean of pixels with similar 5 x 5 patches "
                                       "(scikit-image, fast mode)"),)
