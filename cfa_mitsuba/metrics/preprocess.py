"""Preparing a camera image for comparison with the ideal one."""

from __future__ import annotations

__all__ = ["mean_match", "reference_interior_mean"]

import numpy as np

from ..errors import require
from ._common import as_image, as_pair


def mean_match(test, reference, *, border: int = 10, return_scale: bool = False, reference_mean: float | None = None):
    """Scale ``test`` so that its mean over the interior equals ``reference``'s.

    ISETCam's recipe before its full-reference metrics (``cameraFullReference``,
    ``cameraMoire``): one scalar for all channels, computed over the image
    without ``border`` pixels on each side, applied to the whole image.  It
    removes exposure/gain differences so the metrics see only the CFA's and
    the demosaic's errors.

    Parameters
    ----------
    test, reference : arrays of the same shape ((H, W) or (H, W, C)).
    border : pixels left out of the means on each side (default 10).
    return_scale : also return the factor.
    reference_mean : the reference's interior mean with this ``border``, when
        already known (a study compares one ideal image with every camera
        output): ``reference`` is then not checked or averaged again (a
        speed-up only: :func:`reference_interior_mean` gives it, and the
        result is identical).

    Returns
    -------
    ndarray (and the scale factor if ``return_scale``).  Refused (one-line
    :class:`~cfa_mitsuba.errors.CfaMitsubaError`) when either interior mean
    is not positive: a black reference would scale any test image to 0.

    Examples
    --------
    >>> ref = np.ones((30, 30, 3))
    >>> float(mean_match(ref * 0.5, ref, border=2).mean())
    1.0
    """
    if reference_mean is None:
        r, t = as_pair(reference, test, channels=_CHANNELS, allow_gray=True)
    else:
        t = as_image(test, "test image", channels=_CHANNELS, allow_gray=True)
        shape = _checked_shape(np.shape(reference))
        require(shape == t.shape, f"reference and test images differ in shape: {shape} vs {t.shape}")
    mt = _interior_mean(t, border)
    mr = _interior_mean(r, border) if reference_mean is None else reference_mean
    require(mt > 0, f"cannot mean-match: the test image's interior mean is {mt:g} (need > 0)")
    # a black reference would scale the test image to exactly 0, a perfect score for any camera
    require(mr > 0, f"cannot mean-match: the reference image's interior mean is {mr:g} (need > 0)")
    scale = float(mr / mt)
    out = t * scale
    return (out, scale) if return_scale else out


def reference_interior_mean(reference, *, border: int = 10):
    """The interior mean :func:`mean_match` computes of ``reference`` (the
    same check and the same expression), for its ``reference_mean``."""
    return _interior_mean(as_image(reference, "reference image", channels=_CHANNELS, allow_gray=True), border)


#: the channel counts mean_match accepts (a single channel is a gray image)
_CHANNELS = (1, 2, 3, 4)


def _checked_shape(shape: tuple) -> tuple:
    """``shape`` as :func:`~._common.as_image` leaves it: (H, W, 1) is gray (H, W)."""
    return tuple(shape[:2]) if len(shape) == 3 and shape[2] == 1 else tuple(shape)


def _interior_mean(image: np.ndarray, border: int):
    """The mean of a checked image without ``border`` pixels on each side."""
    b = int(border)
    h, w = image.shape[:2]
    require(b >= 0 and h > 2 * b and w > 2 * b, f"border {b} px leaves nothing of the {h} x {w} image")
    return image[b:h - b, b:w - b].mean()
