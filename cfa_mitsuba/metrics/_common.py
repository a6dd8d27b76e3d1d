"""Input checks and the few filtering conventions the metrics share."""

from __future__ import annotations

import weakref

import numpy as np

from ..errors import CfaMitsubaError, require, require_finite

#: The largest magnitude a metric accepts in any input (XYZ in cd/m^2, linear
#: RGB, 8-bit codes): far above any scene (the sun's disc is about 1.6e9
#: cd/m^2) and far below where the colour formulas overflow (CIEDE2000 raises
#: chroma, about 500 (X/Xw)^(1/3), to the 7th power: inf above ~1e120 x
#: white), so a finite but absurd value is refused instead of turning into
#: NaN that a mean then skips.
MAX_ABS_INPUT = 1e20


#: id -> weak reference of the read-only arrays that owned their data when
#: they passed :func:`check_values` (the ideal image and its sRGB codes, which
#: a study compares with every camera output of a task)
_PASSED: dict[int, weakref.ref] = {}


def _unchangeable(a: np.ndarray) -> bool:
    """Whether nothing can write to ``a``: read-only, and the owner of its
    memory (so no writeable view of another array reaches it)."""
    return not a.flags.writeable and a.base is None


def check_values(arr, what: str) -> np.ndarray:
    """``arr`` as float64, refused (one line naming ``what``) when it holds
    NaN, an infinity or a value beyond :data:`MAX_ABS_INPUT` in magnitude.
    The one input check of every metric (``as_image``, ``as_white``) and of
    the ``metric`` command's loaded files, before any conversion (which would
    clip an infinity to the sRGB white).

    A read-only array that owns its memory and has passed once is not
    checked again while it lives (nothing can have written to it since: a
    study's ideal image and its sRGB codes, compared with every camera
    output of a task, 1.5 ms a check on the puppy's size)."""
    from ._bounds_kernel import within  # numba: imported by the first check, not by every command

    a = np.asarray(arr, dtype=np.float64)
    known = _PASSED.get(id(a))
    if known is not None and known() is a and _unchangeable(a):
        return a
    if a.size and within(a, MAX_ABS_INPUT):
        # one compiled pass, no temporary: NaN fails the comparisons and falls through to the messages
        if _unchangeable(a):
            key = id(a)
            _PASSED[key] = weakref.ref(a, lambda _, key=key: _PASSED.pop(key, None))
        return a
    a = require_finite(a, what)
    big = int(np.count_nonzero(np.abs(a) > MAX_ABS_INPUT))
    require(big == 0, f"{what} has {big} value(s) beyond +-{MAX_ABS_INPUT:g} (largest magnitude "
                      f"{float(np.max(np.abs(a))):g}): not a physical image value")
    return a


def as_image(arr, what: str, *, channels=(3,), allow_gray: bool = False, min_size: int = 1) -> np.ndarray:
    """``arr`` as a finite float64 (H, W, C) (or (H, W) if ``allow_gray``)
    array within :data:`MAX_ABS_INPUT` (:func:`check_values`)."""
    a = check_values(arr, what)
    if a.ndim == 3 and a.shape[2] == 1 and allow_gray:
        a = a[..., 0]
    if a.ndim == 2:
        require(allow_gray, f"{what} must be (H, W, {'/'.join(map(str, channels))}), got a 2-D array of shape {a.shape}")
    elif a.ndim == 3:
        require(a.shape[2] in channels, f"{what} must have {' or '.join(map(str, channels))} channels, got shape {a.shape}")
    else:
        raise CfaMitsubaError(f"{what} must be an image (H, W[, C]), got shape {a.shape}")
    require(min(a.shape[:2]) >= min_size,
            f"{what} is {a.shape[0]} x {a.shape[1]} px: this metric needs at least {min_size} x {min_size}")
    return a


def as_pair(reference, test, *, channels=(3,), allow_gray=False, min_size=1):
    """Check a (reference, test) pair: same shape, finite, big enough."""
    r = as_image(reference, "reference image", channels=channels, allow_gray=allow_gray)
    t = as_image(test, "test image", channels=channels, allow_gray=allow_gray)
    require(r.shape == t.shape, f"reference and test images differ in shape: {r.shape} vs {t.shape}")
    require(min(r.shape[:2]) >= min_size,
            f"images are {r.shape[0]} x {r.shape[1]} px: this metric needs at least {min_size} x {min_size}")
    return r, t


def as_white(white_xyz) -> np.ndarray:
    """A white point (Xw, Yw, Zw), finite and positive."""
    w = check_values(white_xyz, "white point").reshape(-1)
    require(w.size == 3, f"white point must have 3 values (X, Y, Z), got {w.size}")
    require(bool(np.all(w > 0)), f"white point must be positive, got {w.tolist()}")
    return w


def code_range(reference, test, data_range: float, what: str):
    """Rescale 0..data_range inputs to the 0..255 range the constants assume.

    SSIM's L, MDSI's C1..C3 and HaarPSI's C are defined for 8-bit code
    values; 0..1 data with the default ``data_range=255`` gives plausible but
    wrong numbers without any error (reference README s. 5), so that case is
    refused.
    """
    require(np.isfinite(data_range) and data_range > 0, f"data_range must be positive, got {data_range}")
    if data_range == 255.0:
        top = max(float(np.max(reference)), float(np.max(test)))
        # the whole-image rounding test only where the range already looks like 0..1
        fractional = 0.0 < top <= 1.0 and (np.any(reference != np.round(reference)) or np.any(test != np.round(test)))
        require(not fractional,
                f"{what}: values lie in 0..1 but data_range is 255 (8-bit codes); "
                "pass data_range=1 or 8-bit code values")
        return reference, test
    k = 255.0 / float(data_range)
    return reference * k, test * k


def conv2_same(x: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """MATLAB ``conv2(x, kernel, 'same')``: zero padding, MATLAB's alignment.

    For an even-sized kernel MATLAB keeps the central part of the full
    convolution starting at index ``floor(m/2)``; scipy's ``'same'`` picks the
    other centre, so we slice the full result ourselves.
    """
    from scipy import ndimage, signal  # lazy: scipy.signal costs 0.6 s to import

    from ._conv2_kernel import conv2_same_separable, separable_factors

    factors = separable_factors(kernel) if np.ndim(x) == 2 else None
    if factors is not None:
        # every kernel of HaarPSI and MDSI is an outer product u v': two compiled 1-D passes,
        # 3-14x faster than the paths below on a camera image, ~1e-15 relative apart (._conv2_kernel)
        return conv2_same_separable(x, *factors)
    if kernel.size < 16:
        # Small kernels (HaarPSI's 2 x 2 mean, MDSI's 3 x 3 Prewitt): ndimage's direct convolution with
        # zeros outside, centred at floor(m/2) as MATLAB's 'same' for odd and even sizes alike; ~3x
        # faster than signal.convolve2d, the same sums in another order (~1e-16 relative apart).
        return ndimage.convolve(np.asarray(x, dtype=np.float64), kernel, mode="constant", cval=0.0)
    # FFT for the larger kernels (HaarPSI's 4x4 and 8x8): ~3x faster, ~1e-13 apart.
    full = signal.fftconvolve(x, kernel, mode="full")
    r0, c0 = kernel.shape[0] // 2, kernel.shape[1] // 2
    return full[r0:r0 + x.shape[0], c0:c0 + x.shape[1]]


def round_half_away(x: float) -> int:
    """MATLAB's ``round`` (half away from zero), not Python's banker's rounding."""
    return int(np.sign(x) * np.floor(abs(x) + 0.5))
