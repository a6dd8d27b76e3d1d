"""Preparing a camera image for comparison with the ideal one."""

from __future__ import annotations

__all__ = ["mean_match"]

import numpy as np

from ..errors import require
from ._common import as_pair


def mean_match(test, reference, *, border: int = 10, return_scale: bool = False):
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
    t, r = as_pair(test, reference, channels=(1, 2, 3, 4), allow_gray=True)
    b = int(border)
    h, w = t.shape[:2]
    require(b >= 0 and h > 2 * b and w > 2 * b, f"border {b} px leaves nothing of the {h} x {w} image")
    mt, mr = t[b:h - b, b:w - b].mean(), r[b:h - b, b:w - b].mean()
    require(mt > 0, f"cannot mean-match: the test image's interior mean is {mt:g} (need > 0)")
    # a black reference would scale the test image to exactly 0, a perfect score for any camera
    require(mr > 0, f"cannot mean-match: the reference image's interior mean is {mr:g} (need > 0)")
    scale = float(mr / mt)
    out = t * scale
    return (out, scale) if return_scale else out
