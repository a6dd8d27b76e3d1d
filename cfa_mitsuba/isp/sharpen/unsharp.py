"""``unsharp``: the unsharp mask, image + amount x (image - Gaussian blur).

Its transfer function is 1 + amount (1 - exp(-2 pi^2 radius^2 f^2)) at
frequency f (cycles per pixel): 1 at zero frequency (flat areas and the
mean keep their level), rising to 1 + amount at high frequencies, where it
raises both detail and noise; an edge gains the overshoot that MTF50P
discounts (docs/metrics.md).  scikit-image's ``unsharp_mask`` with the
range kept (no clipping: the linear XYZ may exceed any display range).

References
----------
W. K. Pratt, Digital Image Processing, 4th ed., Wiley 2007, s. 10.3
(unsharp masking).  scikit-image, ``skimage.filters.unsharp_mask`` (BSD-3).
"""

from __future__ import annotations

__all__ = ["unsharp"]

import numpy as np

from ...errors import require
from . import SharpenMethod


def unsharp(image: np.ndarray, *, radius: float = 1.0, amount: float = 0.5) -> np.ndarray:
    """Unsharp mask of every channel of an (H, W, C) linear image.

    Parameters
    ----------
    image : (H, W, C) float, linear.
    radius : the Gaussian's standard deviation (pixels), > 0.
    amount : the gain of the detail added back, >= 0.

    Returns
    -------
    (H, W, C) float64.

    Examples
    --------
    >>> img = np.zeros((9, 9, 3)); img[:, 5:] = 1.0
    >>> out = unsharp(img, radius=1.0, amount=1.0)
    >>> bool(out[4, 5, 0] > 1.0), bool(out[4, 4, 0] < 0.0), float(out[4, 0, 0]) == 0.0   # overshoot at the edge
    (True, True, True)
    """
    from skimage.filters import unsharp_mask

    for name, v, low in (("radius", radius, 0.0), ("amount", amount, None)):
        ok = isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
        require(ok and (v > low if low is not None else v >= 0),
                f"unsharp {name} must be a {'positive' if low is not None else 'non-negative'} number, got {v!r}")
    img = np.asarray(image, dtype=np.float64)
    if img.ndim == 2:
        return unsharp_mask(img, radius=float(radius), amount=float(amount), preserve_range=True)
    # channel by channel: scikit-image 0.26's channel_axis path returns an uninitialised array (garbage values)
    out = np.empty_like(img)
    for c in range(img.shape[-1]):
        out[..., c] = unsharp_mask(img[..., c], radius=float(radius), amount=float(amount), preserve_range=True)
    return out


#: This module's method (registered by :func:`.collect_sharpeners`).
SHARPENERS = (SharpenMethod(name="unsharp", function=unsharp, order=1,
                            licence="scikit-image (BSD-3-Clause)",
                            # local: scikit-image's Gaussian is truncated at 4 standard deviations
                            support=lambda o: 4.0 * float(o["radius"]),
                            description="unsharp mask after demosaicing: image + amount x (image - Gaussian(radius)); "
                                        "options radius (px, default 1), amount (default 0.5)"),)
