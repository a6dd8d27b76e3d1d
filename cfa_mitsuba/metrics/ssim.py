"""SSIM (Wang et al. 2004) with the reference code's settings (Bae 2020 s. 2.2.3)."""

from __future__ import annotations

__all__ = ["RECORDS", "ssim", "ssim_reference_moments"]

import functools

import numpy as np

from ..errors import require
from ._common import as_image, as_pair, code_range, round_half_away
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


def _planes(image, channel: str, downsample: bool) -> list[np.ndarray]:
    """The planes SSIM compares: the luma, or each channel; downsampled if asked."""
    if image.ndim == 2:
        planes = [image]
    elif channel == "gray":
        planes = [rgb_to_gray(image)]
    else:
        planes = [image[..., c] for c in range(3)]
    if downsample:
        planes = [_wang2009_downsample(p) for p in planes]
        require(min(planes[0].shape) >= WINDOW_PX, f"after downsampling the images are {planes[0].shape[0]} x "
                                                    f"{planes[0].shape[1]} px, smaller than the 11 x 11 window")
    return planes


def _gaussian(x: np.ndarray) -> np.ndarray:
    """The window of a plane (H, W): scikit-image's SSIM window, its
    ``gaussian`` with the arguments ``structural_similarity`` passes (sigma
    1.5, truncate 3.5: 11 taps, 'reflect'), which is ndimage's ``gaussian_filter``: the column pass, then
    the row pass.  Both passes are the compiled ones of
    :mod:`cfa_mitsuba.isp.column_filter` (ndimage's sums in its order: the
    same bits, 4x and 2x faster); tests/metrics/test_ssim.py checks the
    result equals scikit-image's."""
    from ..isp.column_filter import correlate_along_rows, correlate_columns

    return correlate_along_rows(correlate_columns(x, _window(), mode="reflect"), _window(), mode="reflect")


@functools.lru_cache(maxsize=1)
def _window() -> np.ndarray:
    """The 1-D Gaussian weights ndimage's ``gaussian_filter1d`` makes for
    sigma 1.5, truncate 3.5 (radius int(3.5 x 1.5 + 0.5) = 5), by its
    arithmetic: exp(-0.5 / sigma^2 x^2), divided by their sum."""
    radius = int(3.5 * SIGMA_PX + 0.5)
    x = np.arange(-radius, radius + 1)
    w = np.exp(-0.5 / (SIGMA_PX * SIGMA_PX) * x ** 2)
    w = w / w.sum()
    w.flags.writeable = False
    return w


def ssim_reference_moments(reference, *, data_range: float = 255.0, channel: str = "gray",
                           downsample: bool = False) -> tuple:
    """What :func:`ssim` computes from the reference alone: per plane, the
    plane and its windowed mean and mean square (scikit-image's ``ux`` and
    ``uxx``).  Pass it as ``reference_moments`` when one reference is
    compared with many test images (same options): the result is identical."""
    require(channel in ("gray", "rgb_mean"), f"unknown SSIM channel mode {channel!r} (expected 'gray' or 'rgb_mean')")
    ref = as_image(reference, "reference image", allow_gray=True, min_size=WINDOW_PX)
    ref, _ = code_range(ref, ref, data_range, "ssim")
    return _moments(ref, channel, downsample)


def _moments(ref: np.ndarray, channel: str, downsample: bool) -> tuple:
    return tuple((p, _gaussian(p), _gaussian(p * p)) for p in _planes(ref, channel, downsample))


def _ssim_plane(x, ux, uxx, y) -> float:
    """scikit-image 0.26's ``structural_similarity`` (gaussian_weights=True,
    sigma 1.5, population covariance, data_range 255) term for term, with the
    reference's window moments given: the same float64 operations in the same
    order (tests/metrics/test_ssim.py checks the values equal)."""
    from ._ssim_kernel import index_map

    uy, uyy, uxy = _gaussian(y), _gaussian(y * y), _gaussian(x * y)
    c1, c2 = (0.01 * 255.0) ** 2, (0.03 * 255.0) ** 2
    pad = (WINDOW_PX - 1) // 2
    # scikit-image's vx, vy, vxy (cov_norm = 1), a1, a2, b1, b2 and s = a1 a2 / (b1 b2) per pixel, compiled
    s = index_map(ux, uxx, uy, uyy, uxy, c1, c2, pad)
    return s[pad:s.shape[0] - pad, pad:s.shape[1] - pad].mean(dtype=np.float64)


def ssim(reference, test, *, data_range: float = 255.0, channel: str = "gray",
         downsample: bool = False, reference_moments=None) -> float:
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
    reference_moments : optional, :func:`ssim_reference_moments` of this
        reference with the same options (a speed-up only: the result is
        identical).

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
    require(channel in ("gray", "rgb_mean"), f"unknown SSIM channel mode {channel!r} (expected 'gray' or 'rgb_mean')")
    ref, test = as_pair(reference, test, allow_gray=True, min_size=WINDOW_PX)
    ref, test = code_range(ref, test, data_range, "ssim")
    if reference_moments is None:
        reference_moments = _moments(ref, channel, downsample)
    planes = _planes(test, channel, downsample)
    require(len(planes) == len(reference_moments) and planes[0].shape == reference_moments[0][0].shape,
            "reference_moments do not belong to images of this shape and channel mode")
    return float(np.mean([_ssim_plane(*m, p) for m, p in zip(reference_moments, planes)]))


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (
    MetricRecord(name="ssim", function=ssim, scenes=(NATURAL,), inputs="srgb8", unit="", higher_is_better=True,
                 identical_value=1.0,
                 scored=True, label="SSIM", order=3, decimals=3,
                 description="structural similarity (Wang 2004) of the 8-bit sRGB luma",
                 paper="SSIM (s. 2.2.3, Fig 10)", score_range=(0.0, 1.0),
                 reference_cache=("reference_moments", ssim_reference_moments),
                 practical_difference=(("", 0.05),),
                 practical_source="0.05: the fall from 1 at which half of the observers saw JPEG distortion "
                                  "(SSIM 0.95 on average over six images; Flynn, Ward, Abich & Poole 2013, "
                                  "HCI International, LNCS 8019:23-30)"),
)
