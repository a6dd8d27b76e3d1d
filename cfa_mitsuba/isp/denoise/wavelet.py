"""``wavelet``: wavelet shrinkage, BayesShrink soft thresholds per subband
(scikit-image's ``denoise_wavelet``).

Each detail subband of the orthogonal wavelet transform is soft-thresholded
at T = sigma^2 / sigma_x, sigma_x the subband's estimated signal standard
deviation (sqrt(max(var - sigma^2, 0))): Chang, Yu and Vetterli's
BayesShrink, the near-optimal threshold for a generalised Gaussian prior.
The stage (:mod:`cfa_mitsuba.isp.denoise`) hands it planes of unit noise;
``sigma`` = the tuning constant x ``scale`` sets the thresholds.

References
----------
S. G. Chang, B. Yu, M. Vetterli, "Adaptive wavelet thresholding for image
denoising and compression", IEEE Trans. Image Process. 9(9) (2000)
1532-1546.  scikit-image, ``skimage.restoration.denoise_wavelet`` (BSD-3).
"""

from __future__ import annotations

__all__ = ["wavelet"]

import numpy as np

from . import DenoiseMethod
from ._tuning import rule


def wavelet(plane: np.ndarray, *, sigma: float, wavelet: str = "db2", levels: int | None = None) -> np.ndarray:
    """BayesShrink soft thresholding of a 2-D ``plane`` whose noise has
    standard deviation 1 (module doc).

    Parameters
    ----------
    plane : (H, W) float, stabilised (unit noise).
    sigma : the noise standard deviation assumed for the thresholds (the
        strength; 1 = the predicted noise).
    wavelet : a PyWavelets wavelet name ('db2': Daubechies, 2 vanishing moments).
    levels : decomposition levels; None: scikit-image's default (3 less than
        the most the plane allows, at least 1).

    Returns
    -------
    (H, W) float64, the denoised plane.
    """
    from skimage.restoration import denoise_wavelet

    return denoise_wavelet(np.asarray(plane, dtype=np.float64), sigma=float(sigma), wavelet=wavelet, mode="soft",
                           wavelet_levels=levels, method="BayesShrink", rescale_sigma=False)


#: This module's method (registered by :func:`.collect_denoisers`).
DENOISERS = (DenoiseMethod(name="wavelet", function=wavelet, order=1, domains=("raw", "rgb"),
                           strength=1.0, tuning=rule("wavelet"),
                           licence="scikit-image (BSD-3-Clause), PyWavelets (MIT)",
                           support=None,  # global: BayesShrink estimates each subband's threshold from all of it
                           description="wavelet shrinkage: BayesShrink soft thresholds per subband (scikit-image)"),)
