"""Colour: white balance, the N x 3 colour-correction fit, XYZ -> sRGB.

Scales (DESIGN.md: radiometry is absolute):

* A camera channel's signal is in electrons; ``RawImage.electrons_per_radiance``
  (C, B) predicts it for any spectral radiance L (B,) in W/(m^2 sr nm):
  e_c = sum_b epr[c, b] L_b.
* White balance divides each channel by its response to the scene white
  (``RawImage.white_radiance``): *balanced* units, where a perfect white
  diffuser reads 1.0 in every channel, so the channels agree on achromatic
  content, which the cross-channel demosaics need.
* The colour matrix M (N x 3) maps balanced channels to CIE 1931 XYZ in
  cd/m^2 (Y = luminance): the ideal sensor's absolute scale, on which a
  perfect white reads ``xyz_from_radiance(white_radiance)``.  It is fitted
  by least squares on the 190 rawtoaces training reflectances under the
  scene illuminant (never on the test chart), optionally constrained to map
  white exactly to the white's XYZ (white-preserving, Finlayson & Drew 1996).
* Display: sRGB (IEC 61966-2-1) with the scene white mapped to (1, 1, 1)
  by a Bradford adaptation from the white's chromaticity to D65, encoded
  with the sRGB transfer function and clipped to 0..1 (colour-science).

The ISETCam route (research/isetcam.md s. 4.4) differs: it fits on the 24
Macbeth patches (the test chart itself), clips at 0 and normalises every
image by its own maximum; here the fit never sees the test chart and the
output stays on the absolute scale.  ``colour_fit="mcc"``
(:func:`colour_fit_reflectances`) fits on the chart as ISETCam's 'MCC
optimized' does, for a like-for-like comparison with the paper.
"""

from __future__ import annotations

__all__ = [
    "ColourFit",
    "white_response",
    "white_balance_gains",
    "gray_world_gains",
    "fit_colour_matrix",
    "channel_noise",
    "GREY_REFLECTANCE",
    "COLOUR_FITS",
    "colour_fit_reflectances",
    "isetcam_colorchecker",
    "luminance_weights",
    "cfa_luminance_weights",
    "electrons_per_radiance_of",
    "xyz_to_srgb",
    "delta_e00",
]

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import colorimetry, spectra
from ..errors import CfaMitsubaError


def white_response(electrons_per_radiance, white_radiance) -> np.ndarray:
    """(C,) electrons each channel collects from the scene white."""
    epr = np.asarray(electrons_per_radiance, dtype=np.float64)
    white = np.asarray(white_radiance, dtype=np.float64)
    if epr.ndim != 2 or white.ndim != 1 or epr.shape[1] != white.size:
        raise CfaMitsubaError(
            f"electrons_per_radiance {epr.shape} and white_radiance {white.shape} do not share a band grid"
        )
    with np.errstate(over="ignore", invalid="ignore"):
        e = epr @ white
    if not np.all(np.isfinite(e)):
        bad = int(np.flatnonzero(~np.isfinite(e))[0])
        raise CfaMitsubaError(f"channel {bad}'s response to the scene white is not finite ({e[bad]}): "
                              "NaN, infinite or overflowing electrons_per_radiance or white_radiance")
    if np.any(e <= 0):
        bad = int(np.flatnonzero(e <= 0)[0])
        raise CfaMitsubaError(f"channel {bad} collects no signal from the scene white: cannot white-balance")
    return e


def white_balance_gains(electrons_per_radiance, white_radiance) -> np.ndarray:
    """(C,) gains per electron that make the scene white read 1.0 in every
    channel (known-illuminant white balance): 1 / white_response.

    Examples
    --------
    >>> white_balance_gains([[1.0, 1.0], [0.5, 0.0]], [2.0, 2.0]).tolist()
    [0.25, 1.0]
    """
    return 1.0 / white_response(electrons_per_radiance, white_radiance)


def gray_world_gains(mosaic_e, masks, electrons_per_radiance, white_radiance) -> np.ndarray:
    """(C,) gray-world gains per electron: each channel's mean over the
    image is made equal (the scene is assumed achromatic on average).

    The common level is the density-weighted mean of the known-illuminant
    balanced means, so gray world changes the colour of the light, not the
    exposure scale.  A channel with a non-positive mean (an all-black
    image) keeps its known-illuminant gain.
    """
    known = white_balance_gains(electrons_per_radiance, white_radiance)
    m = np.asarray(masks, dtype=bool)
    means = np.array([mosaic_e[mc].mean() if mc.any() else 0.0 for mc in m])
    dens = m.reshape(m.shape[0], -1).mean(axis=1)
    ok = means > 0
    if not ok.any():
        return known
    level = float(np.sum((dens * means * known)[ok]) / np.sum(dens[ok]))
    return np.where(ok, level / np.where(ok, means, 1.0), known)


@dataclass(frozen=True)
class ColourFit:
    """A fitted colour correction.

    matrix : (N, 3) balanced channels -> XYZ in cd/m^2 (row c: channel c's
        contribution).
    white_xyz : (3,) XYZ of the scene white, cd/m^2.
    condition_number : of the white-normalised matrix (matrix / white_xyz
        column-wise): sigma_max / sigma_min.
    noise_gain : (3,) for X, Y, Z: ||M[:, j]|| / sum_c M[c, j], the output's
        relative noise on a white patch when every balanced channel carries
        unit relative noise, independent (1 for a 3-channel identity; CMY
        and panchromatic channels raise it: physics, not a bug).
    rms_error_training : RMS XYZ error on the training set relative to the
        white's Y (dimensionless).
    white_preserving : whether white maps exactly to ``white_xyz``.
    rank : the number of independent channel directions the fit used: the
        numerical rank of the balanced training responses at the fit's
        ``rcond`` (N for independent channels; 3 for rgbw1's R, G, B and
        W = R + G + B, whose W direction is merged).  None when unknown.
    """

    matrix: np.ndarray
    white_xyz: np.ndarray
    condition_number: float
    noise_gain: np.ndarray
    rms_error_training: float
    white_preserving: bool
    rank: int | None = None

    def apply(self, balanced: np.ndarray) -> np.ndarray:
        """(..., N) balanced channels -> (..., 3) XYZ in cd/m^2."""
        return balanced @ self.matrix

    def as_meta(self) -> dict:
        return {
            "colour_matrix": self.matrix.tolist(),
            "condition_number": self.condition_number,
            "noise_gain_xyz": self.noise_gain.tolist(),
            "fit_rms_error_training": self.rms_error_training,
            "white_preserving": self.white_preserving,
            "fit_rank": self.rank,
        }


#: The reflectances a colour matrix can be fitted on: ``training`` (the 190
#: rawtoaces training patches, never the test chart: the default) or ``mcc``
#: (the 24 ColorChecker patches, the Macbeth test chart itself: ISETCam's
#: 'MCC optimized' sensor conversion, research/isetcam.md s. 4.4), or
#: ``mcc-isetcam`` (the same fit on ISETCam's own ColorChecker table,
#: ``data/reflectances/isetcam_macbethChart.csv``, as ISETCam does it).
COLOUR_FITS = ("training", "mcc", "mcc-isetcam")


def colour_fit_reflectances(name: str, wavelengths=spectra.DEFAULT_WAVELENGTHS) -> np.ndarray:
    """(K, B) reflectances of the colour fit called ``name`` (:data:`COLOUR_FITS`).

    Examples
    --------
    >>> colour_fit_reflectances("mcc").shape, colour_fit_reflectances("training").shape
    ((24, 31), (190, 31))
    """
    if name == "training":
        return spectra.training_reflectances(wavelengths)
    if name == "mcc":
        return spectra.colorchecker(wavelengths)[1]
    if name == "mcc-isetcam":
        return isetcam_colorchecker(wavelengths)
    raise CfaMitsubaError(f"unknown colour fit {name!r} (choose {', '.join(COLOUR_FITS)})")


#: ISETCam's ColorChecker table (data/reflectances/README.md).
ISETCAM_MACBETH_CSV = Path(__file__).resolve().parent.parent / "data" / "reflectances" / "isetcam_macbethChart.csv"


def isetcam_colorchecker(wavelengths=spectra.DEFAULT_WAVELENGTHS) -> np.ndarray:
    """(24, B) ISETCam's ColorChecker reflectances (``macbethChart.mat``,
    shipped as ``data/reflectances/isetcam_macbethChart.csv``, reading
    order), band-averaged onto ``wavelengths`` (nm) as every tabulated
    spectrum is (DESIGN.md)."""
    table = np.loadtxt(ISETCAM_MACBETH_CSV, delimiter=",", skiprows=1)
    return spectra.band_average(table[:, 0], table[:, 1:], wavelengths).T


def _balanced_responses(epr, white, reflectances):
    # Only the spectral shape matters after white balance: remove the
    # exposure scale, so that extreme exposures neither underflow nor overflow.
    peak = float(np.max(np.abs(epr))) if epr.size else 0.0
    if np.isfinite(peak) and peak > 0:
        epr = epr / peak
    radiance = reflectances * white[None, :]
    cam = radiance @ epr.T / white_response(epr, white)[None, :]
    return radiance, cam


#: The grey at which :func:`channel_noise` evaluates a channel's noise: the
#: 18 % mid-grey of exposure metering (ISO 2720's reflected-light calibration).
GREY_REFLECTANCE = 0.18


def channel_noise(white_electrons, *, read_noise_e: float = 0.0, grey: float = GREY_REFLECTANCE) -> np.ndarray:
    """(N,) relative noise of each white-balanced channel at a mid grey:
    sqrt(grey N_c + r^2) / N_c, N_c the electrons channel c collects from the
    scene white in this capture and r the read noise (electrons rms); in
    balanced units (the white reads 1).  The Tikhonov weights of
    :func:`fit_colour_matrix` (``channel_noise=``).

    Examples
    --------
    >>> channel_noise([5000.0, 1250.0]).round(4).tolist()
    [0.006, 0.012]
    """
    n = np.asarray(white_electrons, dtype=np.float64)
    if n.ndim != 1 or not np.all(np.isfinite(n)) or np.any(n <= 0):
        raise CfaMitsubaError(f"channel_noise needs positive electrons per channel, got {n.tolist()}")
    return np.sqrt(grey * n + float(read_noise_e) ** 2) / n


def _rank(a, rcond) -> int:
    """Numerical rank of the training responses as ``numpy.linalg.lstsq``
    counts it at ``rcond`` (of the data alone, not the Tikhonov rows)."""
    sv = np.linalg.svd(a, compute_uv=False)
    if sv.size == 0 or sv[0] == 0:
        return 0
    tol = (np.finfo(float).eps * max(a.shape) if rcond is None else rcond) * sv[0]
    return int(np.count_nonzero(sv > tol))


def fit_colour_matrix(electrons_per_radiance, white_radiance, wavelengths=spectra.DEFAULT_WAVELENGTHS, *,
                      white_preserving: bool = True, reflectances=None, rcond: float | None = None,
                      channel_noise=None) -> ColourFit:
    """Fit the N x 3 matrix from balanced channels to absolute XYZ.

    Parameters
    ----------
    electrons_per_radiance : (N, B) electrons per unit band radiance
        (W/(m^2 sr nm)) of each channel (only its spectral shape matters
        after white balance).
    white_radiance : (B,) radiance of the scene's perfect white, W/(m^2 sr nm).
    wavelengths : (B,) band centres, nm.
    white_preserving : constrain white -> white's XYZ exactly (equality-
        constrained least squares, Finlayson & Drew 1996).
    reflectances : (K, B) training reflectances; default the 190 rawtoaces
        patches (:func:`cfa_mitsuba.spectra.training_reflectances`).
    rcond : relative cut-off for small singular values of the balanced
        training responses (``numpy.linalg.lstsq``): directions below
        ``rcond`` x the largest are dropped (minimum-norm solution).  None
        (default): machine precision x K, so only channels that are linear
        combinations of others to rounding (rgbw1's W = R + G + B) are
        merged, and two *nearly* identical channels get the exact, large
        least-squares matrix, whose noise gain is reported.  A larger value
        (e.g. 1e-6) regularises such a CFA.
    channel_noise : (N,) relative standard deviation sigma_c of each balanced
        channel's error (the white reads 1), or None (default) for the exact
        least-squares fit.  Given, the fit minimises the *expected* error on
        the training set when every channel carries independent errors of
        that size, ||A M - X||^2 + K sum_c sigma_c^2 ||M_c||^2 (K training
        reflectances): Tikhonov regularisation with lambda_c = K sigma_c^2,
        the linear minimum-mean-square-error colour correction.  It matters
        only where channels are nearly dependent (cmy2's six channels: noise
        gain 5.5 -> 2.4 at sigma 0.005); ``process`` passes the capture's own
        noise at an 18 % grey (:func:`channel_noise`).

    Returns
    -------
    :class:`ColourFit`.

    The fit is solved on the responses themselves (SVD), never on the
    normal equations, which square the condition number: the constrained
    fit eliminates the constraint (null-space method, Golub & Van Loan
    s. 6.2) and the white is restored exactly afterwards, so a spectrally
    flat grey maps to grey even when the matrix holds entries of 1e6.

    References
    ----------
    G. D. Finlayson, M. S. Drew, "Constrained least-squares regression in
    color spaces", J. Electronic Imaging 6(4), 1997 (white-point preserving).
    G. H. Golub, C. F. Van Loan, "Matrix Computations", 4th ed., s. 6.2
    (least squares with linear equality constraints, null-space method).

    Examples
    --------
    An XYZ camera needs the identity (scaled to white's XYZ):

    >>> from cfa_mitsuba import spectra
    >>> wl = spectra.DEFAULT_WAVELENGTHS
    >>> epr = (spectra.cmfs_xyz(wl) * spectra.band_widths(wl)[:, None] * 683).T
    >>> fit = fit_colour_matrix(epr, spectra.illuminant("D65", wl) / 100)
    >>> ((fit.matrix / fit.white_xyz).round(9) + 0.0).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    """
    epr = np.asarray(electrons_per_radiance, dtype=np.float64)
    white = np.asarray(white_radiance, dtype=np.float64)
    wl = spectra.validate_wavelengths(wavelengths)
    if epr.ndim != 2 or epr.shape[1] != wl.size or white.shape != (wl.size,):
        raise CfaMitsubaError(
            f"colour fit: electrons_per_radiance {epr.shape} and white_radiance {white.shape} "
            f"must be on the {wl.size}-band grid"
        )
    if rcond is not None and not (np.isfinite(rcond) and 0 <= rcond < 1):
        raise CfaMitsubaError(f"colour fit: rcond must lie in [0, 1), got {rcond!r}")
    refl = spectra.training_reflectances(wl) if reflectances is None else np.asarray(reflectances, float)
    white_xyz = spectra.xyz_from_radiance(white, wl)
    if not (np.all(np.isfinite(white_xyz)) and white_xyz[1] > 0):
        raise CfaMitsubaError(f"colour fit: the scene white's XYZ {white_xyz.tolist()} is not finite and positive")
    # Fit for the white at Y = 1 and scale the matrix after: the numbers stay
    # O(1) at any luminance (1e-30 or 1e300 cd/m^2 alike).
    y_white, white_xyz_abs = float(white_xyz[1]), white_xyz
    radiance, cam = _balanced_responses(epr, white / y_white, refl)
    target = spectra.xyz_from_radiance(radiance, wl)
    white_xyz = white_xyz / y_white
    n = epr.shape[0]
    sig = None
    if channel_noise is not None:
        sig = np.asarray(channel_noise, dtype=np.float64).reshape(-1)
        if sig.size != n or not np.all(np.isfinite(sig)) or np.any(sig < 0):
            raise CfaMitsubaError(f"colour fit: channel_noise needs {n} finite non-negative values, got {sig.tolist()}")
        if not np.any(sig > 0):
            sig = None
    if white_preserving:
        # min ||A M - X||^2 subject to 1^T M = white_xyz: M = M0 + N Z with
        # M0 = 1 white_xyz^T / n (meets the constraint) and N an orthonormal
        # basis of the vectors summing to 0; Z is a plain least-squares fit.
        m0 = np.full((n, 1), 1.0 / n) @ white_xyz[None, :]
        basis = np.linalg.qr(np.ones((n, 1)), mode="complete")[0][:, 1:]
        a, b = cam @ basis, target - cam @ m0
        if sig is not None:  # Tikhonov rows: sqrt(K) sigma_c (M0 + N Z)_c ~ 0
            d = np.sqrt(cam.shape[0]) * sig[:, None]
            a, b = np.vstack([a, d * basis]), np.vstack([b, -d * m0])
        z = np.linalg.lstsq(a, b, rcond=rcond)[0]
        rank = _rank(cam @ basis, rcond) + 1  # the constrained direction (the white) is always determined
        m = m0 + basis @ z
        # the elimination holds the sums only to rounding x |Z|: restore them
        m += (white_xyz - m.sum(axis=0))[None, :] / n
    else:
        a, b = cam, target
        if sig is not None:
            a = np.vstack([a, np.sqrt(cam.shape[0]) * np.diag(sig)])
            b = np.vstack([b, np.zeros((n, 3))])
        m = np.linalg.lstsq(a, b, rcond=rcond)[0]
        rank = _rank(cam, rcond)
    rel = m / white_xyz[None, :]
    sv = np.linalg.svd(rel, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    noise = np.linalg.norm(m, axis=0) / np.abs(m.sum(axis=0))
    rms = float(np.sqrt(np.mean((cam @ m - target) ** 2)) / white_xyz[1])
    return ColourFit(m * y_white, white_xyz_abs, cond, noise, rms, bool(white_preserving), rank)


def luminance_weights(electrons_per_radiance, white_radiance, wavelengths=spectra.DEFAULT_WAVELENGTHS) -> np.ndarray:
    """(N,) non-negative weights, summing to 1, of the balanced channels
    whose sum best predicts luminance Y over the training reflectances
    (non-negative least squares).  The luminance reference of the
    cross-channel demosaics when no channel is densest."""
    from scipy.optimize import nnls

    epr = np.asarray(electrons_per_radiance, dtype=np.float64)
    white = np.asarray(white_radiance, dtype=np.float64)
    wl = spectra.validate_wavelengths(wavelengths)
    radiance, cam = _balanced_responses(epr, white, spectra.training_reflectances(wl))
    y = spectra.luminance_cd_m2(radiance, wl) / spectra.luminance_cd_m2(white, wl)
    w, _ = nnls(cam, y)
    if w.sum() <= 0:
        return np.full(epr.shape[0], 1.0 / epr.shape[0])
    return w / w.sum()


def electrons_per_radiance_of(sensitivities, wavelengths) -> np.ndarray:
    """(C, B) relative electrons per unit band radiance for QE curves (C, B):
    QE x photons per joule x band width (the optics and exposure factor,
    common to all channels, is left out)."""
    wl = spectra.validate_wavelengths(wavelengths)
    return np.asarray(sensitivities, float) * (spectra.photons_per_joule(wl) * spectra.band_widths(wl))[None, :]


@functools.lru_cache(maxsize=64)
def _cfa_weights(key: tuple, sens: bytes, shape: tuple) -> tuple:
    wl = spectra.DEFAULT_WAVELENGTHS
    qe = np.frombuffer(sens, dtype=np.float64).reshape(shape)
    w = luminance_weights(electrons_per_radiance_of(qe, wl), spectra.illuminant("D65", wl), wl)
    return tuple(w.tolist())


def cfa_luminance_weights(cfa) -> np.ndarray:
    """:func:`luminance_weights` of a CFA's own spectra under D65 (equal
    weights for a CFA object that has no ``sensitivities``)."""
    n = len(cfa.channels)
    if not hasattr(cfa, "sensitivities"):
        return np.full(n, 1.0 / n)
    qe = np.ascontiguousarray(cfa.sensitivities(spectra.DEFAULT_WAVELENGTHS), dtype=np.float64)
    return np.array(_cfa_weights((getattr(cfa, "name", ""), tuple(cfa.channels)), qe.tobytes(), qe.shape))


#: The chromatic adaptation of the project's display encoding (:func:`xyz_to_srgb`,
#: and the study's thumbnails): the scene white to sRGB's D65
DISPLAY_ADAPTATION = "Bradford"


def xyz_to_srgb(xyz, white_xyz) -> np.ndarray:
    """Display sRGB, 0..1, of absolute XYZ: the project's one encoding
    (:func:`cfa_mitsuba.colorimetry.xyz_to_srgb`) with Bradford adaptation
    from the scene white to sRGB's D65, so the scene white shows as (1, 1, 1)."""
    white = np.asarray(white_xyz, dtype=np.float64)
    if white.shape != (3,) or not np.all(np.isfinite(white)) or white[1] <= 0:
        raise CfaMitsubaError(f"white XYZ must be 3 finite values with Y > 0, got {white.tolist()}")
    return colorimetry.xyz_to_srgb(xyz, white, adaptation=DISPLAY_ADAPTATION)


#: CIEDE2000 of two absolute XYZ arrays (kept here for the isp's users).
delta_e00 = colorimetry.delta_e00
