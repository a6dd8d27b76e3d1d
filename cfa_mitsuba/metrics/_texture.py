"""What the texture metrics share: the camera's and the chart's spectra on
the dead-leaves square, the noise spectrum of the flat patch, radial
averages, and the CPIQ contrast sensitivity function.

Written here: no maintained Python package computes a dead-leaves texture
MTF (research notes, "Texture, acutance, aliasing").

Spectra.  Both images are taken as luminance contrast, c = Y / mean(Y) - 1
(the mean weighted by the window), over the same N x N square of camera
pixels, times a separable Hann window w (so the square's border does not
leak into every frequency), and Fourier transformed: F_cam(f).  The chart
is known exactly (:func:`cfa_mitsuba.render.dead_leaves.chart_luminance`:
its luminance on the render's grid, K samples per camera pixel); its
transform over the same square, kept to the camera's band (|fx|, |fy| <
1/2 cycle per camera pixel), divided by K^2 (as many times the samples),
by the render pixel's box (sinc(fx / K) sinc(fy / K)) and shifted to the
camera pixels' centres, is the ideal F_ideal(f): the chart before optics,
pixels and processing.  Power spectra are |F|^2 / sum(w^2) (so white noise
of variance s^2 has the flat spectrum s^2, whatever the size), averaged
over rings one frequency bin (1 / N cycles per pixel) wide:

    P_cam(f) = <|F_cam|^2>,  P_ideal(f) = <|F_ideal|^2>,  P_cross(f) = <F_cam conj(F_ideal)>

The noise spectrum P_noise(f) is measured the same way on the flat patch
(square tiles down its height, their mean, the same ring average, then
interpolated to the texture's rings) in units of the texture's mean
luminance: the patch has the texture's mean reflectance, and a shot-noise
variance linear in the level averages over the texture to its value at
the mean.

References
----------
F. Cao, F. Guichard, H. Hornung, "Dead leaves model for measuring texture
quality on a digital camera", Proc. SPIE 7537 (2010) 75370E (the texture
MTF sqrt((P_cam - P_noise) / P_ideal), noise from a uniform patch).
L. Kirk, P. Herzer, U. Artmann, D. Kunz, "Description of texture loss
using the dead leaves target: current issues and a new intrinsic
approach", Proc. SPIE 9023 (2014) 90230C; U. Artmann, "Image quality
assessment using the dead leaves target: experience with the latest
approach and further investigations", Proc. SPIE 9404 (2015) 94040J (the
cross-power MTF P_cross / P_ideal, immune to noise uncorrelated with the
chart).  R. C. Sumner, R. Burada, N. Kram, "The effects of misregistration
on the dead leaves crosscorrelation texture blur analysis", Electronic
Imaging 2017, IQSP-257 (its modulus rather than its real part).
D. Baxter, F. Cao, H. Eliasson, J. Phillips, "Development of the I3A CPIQ
spatial metrics", Proc. SPIE 8293 (2012) 829302, and IEEE 1858-2016
(CPIQ): the acutance CSF.
"""

from __future__ import annotations

__all__ = ["texture_spectra", "cpiq_csf", "mtf50_of", "TEXTURE_SCENES", "HALF_NYQUIST"]

import functools
import json

import numpy as np

from ..errors import require
from ._common import as_image

#: The scene kind the texture metrics read.
TEXTURE_SCENES = ("dead-leaves",)
#: Half the camera's Nyquist frequency (cycles per pixel): the headline frequency of the MTF values.
HALF_NYQUIST = 0.25


def _hann(n: int, positions: np.ndarray) -> np.ndarray:
    """sin^2(pi u / n) at positions u (camera pixels from the square's edge)."""
    return np.sin(np.pi * positions / n) ** 2


def _rings(n: int):
    """(ring index of each (fy, fx) bin of an n x n DFT, frequency of each ring
    (cy/px), number of rings up to Nyquist)."""
    f = np.fft.fftfreq(n)
    r = np.hypot(f[:, None], f[None, :])
    idx = np.rint(r * n).astype(int)  # ring k holds |f| within half a bin of k / n
    return idx, np.arange(n // 2 + 1) / n, n // 2 + 1


def _ring_mean(values: np.ndarray, idx: np.ndarray, n_rings: int) -> np.ndarray:
    keep = idx < n_rings
    counts = np.bincount(idx[keep], minlength=n_rings).astype(np.float64)
    if np.iscomplexobj(values):
        s = (np.bincount(idx[keep], weights=values.real[keep], minlength=n_rings)
             + 1j * np.bincount(idx[keep], weights=values.imag[keep], minlength=n_rings))
    else:
        s = np.bincount(idx[keep], weights=values[keep], minlength=n_rings)
    return s / np.maximum(counts, 1.0)


@functools.lru_cache(maxsize=4)
def _ideal_spectrum(record_json: str, k: int, oy: int, ox: int, n: int) -> np.ndarray:
    """F_ideal (n x n, numpy FFT order) of the chart over the camera square
    whose top-left render pixel is (oy, ox) in the texture square (module doc)."""
    from ..render.dead_leaves import chart_luminance

    lum = chart_luminance(json.loads(record_json))
    m = n * k
    patch = lum[oy:oy + m, ox:ox + m]
    require(patch.shape == (m, m), "the texture square does not cover the camera's analysis square")
    u = (np.arange(m) + 0.5) / k  # render pixel centres, camera pixels from the square's edge
    w = _hann(n, u)
    w2 = w[:, None] * w[None, :]
    mean = float((w2 * patch).sum() / w2.sum())
    big = np.fft.fft2(w2 * (patch / mean - 1.0))
    sel = np.r_[0:n // 2 + 1, m - (n - n // 2 - 1):m]  # the camera's band, in numpy order
    low = big[np.ix_(sel, sel)] / (k * k)
    f = np.fft.fftfreq(n)  # cycles per camera pixel
    box = np.sinc(f / k)  # the render pixel's box, divided out
    # render pixel e sits at (e + 0.5) / K, camera pixel i at i + 0.5: the phase that moves one onto the other
    shift = np.exp(1j * np.pi * f * n * (1.0 - 1.0 / k) / n)
    corr = (shift / box)
    out = low * corr[:, None] * corr[None, :]
    out.flags.writeable = False
    return out


def _luminance(test_xyz) -> np.ndarray:
    a = as_image(test_xyz, "test image", channels=(3,), allow_gray=True, min_size=8)
    return a[..., 1] if a.ndim == 3 else a


def _noise_psd(y: np.ndarray, flat_roi, level: float, freq: np.ndarray) -> tuple[np.ndarray, int]:
    """The flat patch's noise spectrum in units of ``level`` squared at the
    texture's ring frequencies ``freq`` (tiles down the patch), and the tile size."""
    y0, x0, y1, x1 = (int(v) for v in flat_roi)
    flat = y[y0:y1, x0:x1]
    t = min(flat.shape)
    require(t >= 8, f"the flat patch ({flat.shape[1]} x {flat.shape[0]} px) is too small to measure noise")
    idx, f_t, n_r = _rings(t)
    w = _hann(t, np.arange(t) + 0.5)
    w2 = w[:, None] * w[None, :]
    acc = np.zeros(n_r)
    tiles = 0
    for i in range(0, flat.shape[0] - t + 1, t):
        for j in range(0, flat.shape[1] - t + 1, t):
            tile = flat[i:i + t, j:j + t]
            c = (tile - float((w2 * tile).sum() / w2.sum())) / level
            acc += _ring_mean(np.abs(np.fft.fft2(w2 * c)) ** 2 / float((w2 * w2).sum()), idx, n_r)
            tiles += 1
    return np.interp(freq, f_t, acc / tiles), t


def texture_spectra(test_xyz, *, texture_roi, flat_roi, dead_leaves) -> dict:
    """The ring-averaged spectra of one camera image of the dead-leaves chart.

    Parameters
    ----------
    test_xyz : (H, W, 3) camera XYZ (any scale) or (H, W) luminance.
    texture_roi, flat_roi : (y0, x0, y1, x1) camera pixels of the texture
        square and the flat patch (the scene geometry).
    dead_leaves : the sidecar's pattern record (``geometry['dead_leaves']``).

    Returns
    -------
    dict: ``freq_cy_px`` (ring frequencies, 0 to Nyquist), ``p_cam``,
    ``p_ideal``, ``p_noise`` (real), ``p_cross`` (complex), ``n`` (the
    analysis square's side, camera pixels), ``oversample`` (K),
    ``noise_tile_px``, ``mean_level`` (the texture's mean luminance, the
    image's unit).
    """
    y = _luminance(test_xyz)
    require(isinstance(dead_leaves, dict) and "texture_rect" in dead_leaves and "width" in dead_leaves,
            "the texture metrics need the dead-leaves chart's pattern record (its sidecar's geometry)")
    k = int(round(float(dead_leaves["width"]) / y.shape[1]))
    require(k >= 1 and abs(float(dead_leaves["width"]) / k - y.shape[1]) <= 1,
            f"the image ({y.shape[1]} px wide) is not the chart's {dead_leaves['width']} px divided by a whole number")
    ty0, tx0, ty1, tx1 = (int(v) for v in texture_roi)
    n = min(ty1 - ty0, tx1 - tx0)
    n -= n % 2
    require(n >= 16 and ty0 >= 0 and tx0 >= 0 and ty0 + n <= y.shape[0] and tx0 + n <= y.shape[1],
            f"the texture square {tuple(texture_roi)} does not fit a 16 px analysis square in the image {y.shape}")
    ry0, rx0 = (int(v) for v in dead_leaves["texture_rect"][:2])
    ideal = _ideal_spectrum(json.dumps(dead_leaves, sort_keys=True), k, ty0 * k - ry0, tx0 * k - rx0, n)
    cam = y[ty0:ty0 + n, tx0:tx0 + n]
    w = _hann(n, np.arange(n) + 0.5)
    w2 = w[:, None] * w[None, :]
    level = float((w2 * cam).sum() / w2.sum())
    require(np.isfinite(level) and level > 0, "the texture square is black in the camera image: no texture to measure")
    f_cam = np.fft.fft2(w2 * (cam / level - 1.0))
    norm = float((w2 * w2).sum())
    idx, freq, n_r = _rings(n)
    p_noise, tile = _noise_psd(y, flat_roi, level, freq)
    return {"freq_cy_px": freq, "p_cam": _ring_mean(np.abs(f_cam) ** 2 / norm, idx, n_r),
            "p_ideal": _ring_mean(np.abs(ideal) ** 2 / norm, idx, n_r),
            "p_cross": _ring_mean(f_cam * np.conj(ideal) / norm, idx, n_r), "p_noise": p_noise,
            "n": n, "oversample": k, "noise_tile_px": tile, "mean_level": level}


def mtf50_of(freq: np.ndarray, m: np.ndarray) -> tuple[float, bool]:
    """The first frequency where ``m`` falls below 0.5, linearly
    interpolated (as :mod:`.mtf`'s MTF50); the last frequency and False when
    it never does."""
    below = np.flatnonzero(m < 0.5)
    below = below[below > 0]
    if below.size == 0:
        return float(freq[-1]), False
    i = int(below[0])
    f0, f1, m0, m1 = freq[i - 1], freq[i], m[i - 1], m[i]
    return float(f0 + (m0 - 0.5) * (f1 - f0) / (m0 - m1)), True


#: CPIQ's acutance CSF, S(v) = a v^c exp(-b v) / K with v in cycles per degree
#: (Baxter et al. 2012; IEEE 1858): a, b, c, K.
CPIQ_CSF = (75.0, 0.2, 0.8, 34.05)


def cpiq_csf(v_cy_deg) -> np.ndarray:
    """CPIQ's contrast sensitivity function at ``v_cy_deg`` (cycles per
    degree): 75 v^0.8 exp(-0.2 v) / 34.05, largest at v = c / b = 4 cy/deg
    (its scale cancels in an acutance).

    >>> round(float(cpiq_csf(4.0)), 3), bool(cpiq_csf(4.0) > cpiq_csf(3.9)) and bool(cpiq_csf(4.0) > cpiq_csf(4.1))
    (3.0, True)
    """
    a, b, c, k = CPIQ_CSF
    v = np.asarray(v_cy_deg, dtype=np.float64)
    return a * np.power(np.maximum(v, 0.0), c) * np.exp(-b * v) / k
