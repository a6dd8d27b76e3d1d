"""Diffraction-limited OTF of a circular pupil, applied per band.

The incoherent OTF of an aberration-free circular pupil is real, radially
symmetric and non-negative:

    H(rho) = (2 / pi) [acos(v) - v sqrt(1 - v^2)],  v = rho / rho_c <= 1,
    H = 0 beyond, rho_c = 1 / (lambda N_w)

(Goodman, *Introduction to Fourier Optics*, 3rd ed., eq. 6-31; ISETCam
``optics/dlMTF.m``, ``dlCore.m``), N_w the working f-number.

Boundary: the image is extended by mirror symmetry at its edges, not by
ISETCam's zero padding of 1/8 of the size (``oiApplyOTF``), which darkens a
PSF-wide strip along every border (a uniform field loses about half its
irradiance at the edge pixels).  A mirror-extended image convolved with an
even PSF is diagonalised by the type-II DCT, so the convolution is exact for
that extension and needs no padding: the DCT coefficients are multiplied by
H at their frequencies k / (2 n dx).  Each band uses the OTF at its centre
wavelength (the cutoff changes by +-1.1 % across a 10 nm band at 450 nm).
"""

from __future__ import annotations

__all__ = ["diffraction_mtf", "apply_diffraction"]

import numpy as np

#: Table of H(v) on [0, 1] (then zeros), interpolated linearly by direct
#: indexing: the worst interpolation error is below 1e-7 (near v = 1, where
#: H ~ (1 - v)^1.5), and it is several times faster than acos/sqrt, or
#: np.interp's binary search, on every frequency of every band.
_TABLE_STEPS = 16384
_V_TABLE = np.linspace(0.0, 1.0, _TABLE_STEPS + 1)
_H_TABLE = np.concatenate([(2.0 / np.pi) * (np.arccos(_V_TABLE) - _V_TABLE * np.sqrt(1.0 - _V_TABLE**2)), [0.0, 0.0]])
_H_SLOPE = np.diff(_H_TABLE)


def _otf_lookup(rho: np.ndarray, scale: float) -> np.ndarray:
    """H(rho * scale) by linear interpolation in the table (0 beyond v = 1)."""
    x = rho * (scale * _TABLE_STEPS)
    np.minimum(x, _TABLE_STEPS + 1.0, out=x)
    i = x.astype(np.intp)
    x -= i
    x *= _H_SLOPE[i]
    x += _H_TABLE[i]
    return x


def diffraction_mtf(frequency_cy_mm, wavelength_nm, f_number):
    """Diffraction-limited MTF of a circular pupil.

    Parameters
    ----------
    frequency_cy_mm : spatial frequency on the sensor (cycles/mm), any shape.
    wavelength_nm : wavelength (nm).
    f_number : working f-number N_w (``LensGeometry.working_f_number``).

    Returns
    -------
    H, same shape as ``frequency_cy_mm``, in 0..1; cutoff 1 / (lambda N_w).

    Examples
    --------
    At 550 nm and f/4 the cutoff is 454.5 cy/mm; at the 2.2 um pixel's
    Nyquist (227.3 cy/mm, v = 0.5):

    >>> round(float(diffraction_mtf(1000 / 4.4, 550, 4.0)), 4)
    0.391
    """
    v = np.abs(np.asarray(frequency_cy_mm, dtype=np.float64)) * (float(wavelength_nm) * 1e-6) * float(f_number)
    v = np.minimum(v, 1.0)
    return (2.0 / np.pi) * (np.arccos(v) - v * np.sqrt(1.0 - v * v))


def apply_diffraction(cube_bhw: np.ndarray, wavelengths_nm, sample_pitch_um: float, working_f_number: float,
                      workers: int | None = None, band_gain=None) -> np.ndarray:
    """Convolve every band with its diffraction PSF.

    Parameters
    ----------
    cube_bhw : (B, H, W) float64 irradiance, C-contiguous; it may be
        overwritten (the transforms reuse its memory).
    wavelengths_nm : (B,) band centres.
    sample_pitch_um : spacing of the samples on the sensor plane (um).
    working_f_number : N_w.
    workers : threads for scipy.fft (default: all cores).
    band_gain : optional (B,) factor per band, folded into the OTF (saves a
        pass over the cube when the optics factor is applied here).

    Returns
    -------
    (B, H, W) filtered irradiance, mirror-symmetric boundaries (module doc).
    """
    import scipy.fft  # here, not at the top: a command that computes no optics does not pay for it

    b, h, w = cube_bhw.shape
    dx_mm = float(sample_pitch_um) * 1e-3
    fy = np.arange(h) / (2.0 * h * dx_mm)
    fx = np.arange(w) / (2.0 * w * dx_mm)
    rho = np.sqrt(fy[:, None] ** 2 + fx[None, :] ** 2)  # cy/mm
    workers = workers or -1
    coeffs = scipy.fft.dctn(cube_bhw, type=2, axes=(1, 2), norm="ortho", workers=workers, overwrite_x=True)
    gains = np.ones(b) if band_gain is None else np.asarray(band_gain, dtype=np.float64)
    for i, lam in enumerate(np.asarray(wavelengths_nm, dtype=np.float64)):
        otf = _otf_lookup(rho, lam * 1e-6 * working_f_number)
        if gains[i] != 1.0:
            otf *= gains[i]
        coeffs[i] *= otf
    return scipy.fft.idctn(coeffs, type=2, axes=(1, 2), norm="ortho", workers=workers, overwrite_x=True)
