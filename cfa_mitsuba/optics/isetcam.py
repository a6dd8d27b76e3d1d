"""ISETCam's sampling of an optical image, for ``mode = "isetcam"``
(docs/isetcam-parity.md).

ISETCam fixes the lens's focal length, so its optical image (OI) is sampled
by the *scene* (its field of view and pixel count), not by the sensor; the
sensor then reads the OI at its pixel centres (``regridOI2ISA.m``): each
band is blurred by a Gaussian of ceil(pixel pitch / OI spacing) samples
square with sigma a quarter of that (``fspecial``), then linearly
interpolated at the pixel centres, 0 outside the OI.  With one sample per
pixel (the default) the fill factor only scales the signal
(``spatialIntegration.m``).  That Gaussian-and-bilinear read-out is ISETCam's
pixel aperture: at 2 um pixels on a 0.66 um OI it is a 4 x 4 Gaussian of
sigma 0.66 um plus a 0.66 um triangle, wider than the 2 um box
(:func:`~cfa_mitsuba.optics.compute.integrate_pixels`), so the MTF is lower.

Written here: ISETCam's specific resampling exists in no library.

References
----------
ISETCam ``sensor/simulation/regridOI2ISA.m``, ``spatialIntegration.m``,
``utility/sample2space.m``, ``opticalimage/oiCompute`` (padding by 1/8 of the
scene size each side), ``opticsGet`` 'image distance' (lensmaker equation).
horizon-research/isetcam ad5627536ef3cee85a387f5b3db47878644962c1.
"""

from __future__ import annotations

__all__ = ["isetcam_oi_spacing_um", "isetcam_pad_px", "regrid_isetcam"]

import math

import numpy as np

from ..errors import require


def isetcam_oi_spacing_um(scene_cols: int, fov_deg: float, scene_distance_m: float, focal_length_mm: float) -> float:
    """ISETCam's OI sample spacing (um): OI width 2 d_img tan(FOV/2) over the
    scene's columns, d_img = 1 / (1/f - 1/d) (thin lens focused at the scene)."""
    require(scene_cols > 0 and 0 < fov_deg < 180 and scene_distance_m > 0 and focal_length_mm > 0,
            "OI spacing needs positive columns, FOV in (0, 180) deg, distance and focal length")
    f_m = focal_length_mm * 1e-3
    require(scene_distance_m > f_m, f"scene distance {scene_distance_m} m is inside the focal length")
    d_img = 1.0 / (1.0 / f_m - 1.0 / scene_distance_m)
    return 2.0 * d_img * math.tan(math.radians(fov_deg) / 2.0) / scene_cols * 1e6


def isetcam_pad_px(n: int) -> int:
    """ISETCam's ``oiCompute`` zero padding on each side: round(n / 8)
    (MATLAB rounds halves away from zero)."""
    return int(math.floor(n / 8.0 + 0.5))


def _centres(n: int, pitch: float) -> np.ndarray:
    """``sample2space``: positions (n,) centred on the array's middle."""
    return (np.arange(n, dtype=np.float64) - (n - 1) / 2.0) * pitch


def _linear_weights(x_out: np.ndarray, n_in: int, pitch_in: float) -> np.ndarray:
    """(len(x_out), n_in) linear-interpolation matrix; rows outside the
    input's span are 0 (ISETCam: NaN from interp2, then 0)."""
    u = x_out / pitch_in + (n_in - 1) / 2.0
    w = np.zeros((x_out.size, n_in))
    inside = (u >= 0) & (u <= n_in - 1)
    i0 = np.minimum(np.floor(u[inside]).astype(np.int64), n_in - 2) if n_in > 1 else np.zeros(0, np.int64)
    rows = np.flatnonzero(inside)
    if n_in == 1:
        w[rows, 0] = 1.0
        return w
    frac = u[inside] - i0
    w[rows, i0] = 1.0 - frac
    w[rows, i0 + 1] = frac
    return w


def _gaussian_same(n: int, length: int) -> np.ndarray:
    """(length, length) matrix of MATLAB ``conv2(x, g, 'same')`` along one
    axis, g the 1-D factor of ``fspecial('gaussian', [n n], n/4)`` (zero
    outside the array; an even kernel keeps MATLAB's half-sample offset)."""
    sigma = n / 4.0
    x = np.arange(n, dtype=np.float64) - (n - 1) / 2.0
    g = np.exp(-x * x / (2.0 * sigma * sigma))
    g /= g.sum()
    m = np.zeros((length, length))
    start = n // 2  # 'same' keeps full-convolution indices start .. start + length - 1
    for i in range(length):
        for t in range(n):
            j = i + start - t
            if 0 <= j < length:
                m[i, j] += g[t]
    return m


def regrid_isetcam(irradiance_hwb: np.ndarray, sample_pitch_um: float, pixel_pitch_um: float,
                   rows: int, cols: int) -> np.ndarray:
    """ISETCam's read-out of an OI at a sensor's pixel centres (module doc).

    Parameters
    ----------
    irradiance_hwb : (h, w, B) OI irradiance, any linear unit (W/(m^2 nm)).
    sample_pitch_um : the OI's sample spacing (um).
    pixel_pitch_um : the sensor's pixel pitch (um).
    rows, cols : the sensor's size (pixels); sensor and OI share their centre.

    Returns
    -------
    (rows, cols, B) irradiance at the pixel centres, same unit; 0 where a
    pixel centre falls outside the OI.
    """
    a = np.asarray(irradiance_hwb, dtype=np.float64)
    require(a.ndim == 3, f"OI irradiance must be (H, W, B), got shape {a.shape}")
    require(sample_pitch_um > 0 and pixel_pitch_um > 0 and rows > 0 and cols > 0,
            "regrid needs positive pitches and sensor size")
    h, w, _ = a.shape
    n = int(math.ceil(pixel_pitch_um / sample_pitch_um - 1e-9))
    wy = _linear_weights(_centres(rows, pixel_pitch_um), h, sample_pitch_um)
    wx = _linear_weights(_centres(cols, pixel_pitch_um), w, sample_pitch_um)
    if n > 1:
        wy = wy @ _gaussian_same(n, h)
        wx = wx @ _gaussian_same(n, w)
    out = np.einsum("rh,hwb->rwb", wy, a)
    return np.ascontiguousarray(np.einsum("cw,rwb->rcb", wx, out))
