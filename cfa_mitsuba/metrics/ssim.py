"""SSIM (Wang et al. 2004) with the reference code's settings (Bae 2020 s. 2.2.3)."""

from __future__ import annotations

__all__ = ["RECORDS", "ssim"]

import numpy as np

from ..errors import require
from ._common import as_pair, code_range, round_half_away
from .colourspace import rgb_to_gray
from .record import NATURAL, MetricRecord

#: 11 x 11 Gaussian window, sigma 1.5 px (``fspecial('gaussian', 11, 1.5)``).
WINDOW_PX, SIGMA_PX = 11, 1.5


def _wang2009_downsample(x: np.ndarray) -> np.ndarray:
    """Wang's 2009 ``ssim.m`` pre-filter: f x f mean (symmetric extension,
    MATLAB ``imfilter`` alignment), then every f-th sample from the first."""
    f = max(1, round_half_away(min(x.shape[:2]) / 256.0))
    if f == 1:
        return x
    before = (f + 1) // 2 - 1  # imfilter's centre is floor((f + 1) / 2), 1-based
    padded = np.pad(x, ((before, f - 1 - before), (before, f - 1 - before)), mode="symmetric")
    c = np.cumsum(np.cumsum(np.pad(padded, ((1, 0), (1, 0))), axis=0), axis=1)
    h, w = x.shape
    box = c[f:f + h, f:f + w] - c[:h, f:f + w] - c[f:f + h, :w] + c[:h, :w]
    return (box / (f * f))[::f, ::f]


def ssim(reference, test, *, data_range: float = 255.0, channel: str = "gray",
         downsample: bool = False) -> float:
    """Mean SSIM index of ``test`` against ``reference``.

    Parameters
    ----------
    reference, test : (H, W, 3) sRGB code values (0..``data_range``; 8-bit
        sRGB by default) or (H, W) gray images.  H, W >= 11.
    data_range : the code range; values are rescaled to 0..255 (L = 255).
    channel : ``'gray'`` (default: one SSIM on the luma with MATLAB's
        ``rgb2gray`` weights, unrounded, as ISETCam/Bae) or ``'rgb_mean'``
        (mean of the per-channel SSIMs).
    downsample : apply Wang's 2009 automatic downsampling (``f =
        max(1, round(min(H, W) / 256))``); off by default, as the 2004 paper
        and ``ssim_index.m``.

    Returns
    -------
    float
        Mean of the SSIM map (1 for identical images; higher is better).
        K1 = 0.01, K2 = 0.03, L = 255, 11 x 11 Gaussian window sigma 1.5,
        population covariance, 'valid' map ((H - 10) x (W - 10)); computed
        with scikit-image's ``structural_similarity`` in those settings.

    References
    ----------
    Z. Wang, A. C. Bovik, H. R. Sheikh, E. P. Simoncelli, "Image quality
    assessment: from error visibility to structural similarity", IEEE TIP
    13 (2004) 600-612, eqs. 6-13; Bae 2020 eq. 2.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> a = rng.integers(0, 256, (32, 32, 3)).astype(float)
    >>> ssim(a, a)
    1.0
    """
    from skimage.metrics import structural_similarity

    require(channel in ("gray", "rgb_mean"), f"unknown SSIM channel mode {channel!r} (expected 'gray' or 'rgb_mean')")
    ref, test = as_pair(reference, test, allow_gray=True, min_size=WINDOW_PX)
    ref, test = code_range(ref, test, data_range, "ssim")
    if ref.ndim == 2:
        planes = [(ref, test)]
    elif channel == "gray":
        planes = [(rgb_to_gray(ref), rgb_to_gray(test))]
    else:
        planes = [(ref[..., c], test[..., c]) for c in range(3)]
    values = []
    for a, b in planes:
        if downsample:
            a, b = _wang2009_downsample(a), _wang2009_downsample(b)
            require(min(a.shape) >= WINDOW_PX,
                    f"after downsampling the images are {a.shape[0]} x {a.shape[1]} px, smaller than the 11 x 11 window")
        values.append(structural_similarity(a, b, data_range=255.0, gaussian_weights=True, sigma=SIGMA_PX,
                                            use_sample_covariance=False))
    return float(np.mean(values))


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (
    MetricRecord(name="ssim", function=ssim, scenes=(NATURAL,), inputs="srgb8", unit="", higher_is_better=True,
                 scored=True, label="SSIM", order=3, decimals=3,
                 description="structural similarity (Wang 2004) of the 8-bit sRGB luma",
                 paper="SSIM (s. 2.2.3, Fig 10)", score_range=(0.0, 1.0)),
)
