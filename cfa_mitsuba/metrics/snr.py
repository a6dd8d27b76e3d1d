"""Luminance and chroma SNR on a flat mid-grey after the whole image
processor (demosaic and colour matrix): the sensor engineer's SNR against
light (ISO 15739's 'total noise' region SNR, here on the camera's XYZ).

The region is the gray bar's step nearest an 18 % grey (the mid-grey of
exposure metering, ISO 2720), inset by ``margin`` pixels on every side so
that the demosaic's and the optics' blur across the step edges stays out.

Noise is what differs from the ideal sensor: the camera's Y less the
ideal's Y scaled to the camera's mean on the region, so that the scene's
own slow variation over the region (the lens's off-axis falloff) is not
counted as noise.  With ``n`` the noise image on the region:

    YSNR       = mean(Y) / std(n_Y)
    chroma SNR = mean(Y) / sqrt((var(n_x) + var(n_z)) / 2)

YSNR per pixel rewards blur: a demosaic that spreads a sparse channel's
samples over more output pixels lowers each pixel's noise while the noise
of any area of the image stays.  ``ysnr-area`` (the detail ``ysnr_area``)
refers the noise to an area instead, through the noise power spectrum at
zero frequency: the sum of n_Y's autocovariance C over all lags, here over
the lags up to L = ``correlation_px`` (4 by default) in each direction,

    NPS(0) = sum_{|dx|, |dy| <= L} C(dx, dy),   YSNR_area = mean(Y) / sqrt(NPS(0))

(C(d) the mean product of the noise at pixels d apart, over every such pair
in the region).  A linear filter with unit gain at zero frequency (any
interpolation) leaves NPS(0) unchanged: for uncorrelated noise YSNR_area
equals YSNR, for noise smoothed over at most L pixels it is the YSNR the
same light gives without the smoothing (a 3 x 3 or 5 x 5 box blur triples
or quintuples YSNR and leaves YSNR_area within its sampling error, which
grows as the region shrinks).  NPS(0) = var(area mean) x area in the limit
of large areas (Dainty & Shaw 1974, ch. 8): it is the noise of an area,
not of a pixel.

where the chroma noise is that of the white-normalised opponent signals
x' - y' and z' - y' (x' = X / Xw, y' = Y / Yw, z' = Z / Zw; both 0 on a
neutral grey), in the units of y' (so the two SNRs are comparable: a
camera whose X, Y and Z noise were equal and independent would have chroma
SNR = YSNR / sqrt(2)).  This chroma definition is ours (ISO 15739 gives
colour noise in CIELAB; a linear opponent pair keeps the SNR independent of
the exposure scale and free of the L* curve's bias at low signal).

References
----------
ISO 15739:2017, Photography -- Electronic still-picture imaging -- Noise
measurements (region SNR on uniform patches).
J. C. Dainty, R. Shaw, Image Science, Academic Press 1974, ch. 8 (the
noise power spectrum at zero frequency from the variance of area means).
"""

from __future__ import annotations

__all__ = ["RECORDS", "ysnr", "GREY_REFLECTANCE"]

import numpy as np

from ..errors import require
from ._common import as_pair, as_white
from ._result import MetricResult
from .record import MetricRecord

#: The reflectance whose gray-bar step is measured (18 %, ISO 2720's mid-grey).
GREY_REFLECTANCE = 0.18


def _region(ref_y: np.ndarray, white_y: float, steps, margin: int, grey: float) -> tuple[int, int, int, int]:
    """(y0, x0, y1, x1) of the step whose ideal mean Y / Yw is nearest ``grey``
    (the whole image when ``steps`` is None), inset by ``margin``."""
    h, w = ref_y.shape
    if steps:
        level = [abs(float(ref_y[:, max(a, 0):min(b, w)].mean()) / white_y - grey) if min(b, w) > max(a, 0)
                 else np.inf for a, b in steps]
        x0, x1 = steps[int(np.argmin(level))]
    else:
        x0, x1 = 0, w
    y0, y1, x0, x1 = margin, h - margin, max(int(x0), 0) + margin, min(int(x1), w) - margin
    require(y1 - y0 >= 2 and x1 - x0 >= 2,
            f"the mid-grey region is empty after a {margin} px margin (image {h} x {w} px): a larger gray bar is needed")
    return y0, x0, y1, x1


def _nps_at_zero(noise: np.ndarray, lag: int) -> float | None:
    """The autocovariance of a (h, w) zero-mean noise image summed over the
    lags up to ``lag`` px in each direction (module doc); None when the
    image is not 4 lag + 1 px in both sides or the sum is not positive."""
    h, w = noise.shape
    if h < 4 * lag + 1 or w < 4 * lag + 1:
        return None
    # The lag (-dy, -dx) pairs the same two windows the other way round, and
    # their dot product is the same number (the same products, summed in the
    # same order): each is computed once and the sum kept in lag order.
    seen: dict = {}
    total = 0.0
    for dy in range(-lag, lag + 1):
        for dx in range(-lag, lag + 1):
            v = seen.get((-dy, -dx))
            if v is None:
                a = noise[max(dy, 0):h + min(dy, 0), max(dx, 0):w + min(dx, 0)]
                b = noise[max(-dy, 0):h + min(-dy, 0), max(-dx, 0):w + min(-dx, 0)]
                v = seen[dy, dx] = float(np.vdot(a, b)) / a.size
            total += v
    return total if total > 0 else None


def ysnr(reference_xyz, test_xyz, white_xyz, *, steps=None, margin: int = 3,
         grey: float = GREY_REFLECTANCE, correlation_px: int = 4, step_snrs: bool = True) -> MetricResult:
    """Luminance SNR (and, in the details, chroma SNR) on a flat mid-grey.

    Parameters
    ----------
    reference_xyz, test_xyz : (H, W, 3) XYZ of the ideal and camera images
        (any common scale: the SNR is a ratio).
    white_xyz : (3,) scene white, on the reference's scale.
    steps : the gray bar's ``(x0, x1)`` column ranges (scene geometry); the
        step nearest ``grey`` is measured; None: the whole image (a flat patch).
    margin : pixels left out at each side of the region.
    grey : the reflectance of the step chosen (Y / Yw of the ideal).
    correlation_px : the largest lag L (pixels) summed for ``ysnr_area``
        (module doc).
    step_snrs : measure every step for the details' ``steps`` (default);
        False leaves them None (a study's realisations whose details it does
        not keep: steps.csv reads the kept ones; the headline and the other
        details are the same).

    Raises CfaMitsubaError on a noise-free image (the ideal against itself).

    Returns
    -------
    MetricResult
        Headline YSNR (unit ``''``, a ratio; higher is better).  Details:
        ``chroma_snr``, ``ysnr_db`` (20 log10), ``region`` (y0, x0, y1, x1),
        ``mean_y_rel`` (the region's Y / Yw of the ideal) and ``noise_y``,
        ``noise_chroma`` (rms, in units of the region's mean Y);
        ``ysnr_area`` (the noise referred to an area, module doc; None when
        the region is not 4 L + 1 pixels in both sides) and ``correlation_px``;
        ``steps`` (with ``steps`` given): the SNR of every step, the ISO 15739
        grey-scale reading (:func:`_step_snrs`), else None.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> ref = np.full((40, 40, 3), 18.0)
    >>> test = ref * (1 + 0.05 * rng.standard_normal((40, 40, 3)))   # 5 % noise, independent per channel
    >>> r = ysnr(ref, test, [100.0, 100.0, 100.0])
    >>> round(float(r)), round(r.details["chroma_snr"])                # chroma: YSNR / sqrt(2)
    (21, 14)
    >>> round(r.details["ysnr_area"])                                  # uncorrelated: the same, within its error
    19
    """
    require(isinstance(correlation_px, (int, np.integer)) and not isinstance(correlation_px, bool)
            and correlation_px >= 0, f"correlation_px must be a whole number of pixels >= 0, got {correlation_px!r}")
    ref, test = as_pair(reference_xyz, test_xyz)
    white = as_white(white_xyz)
    y0, x0, y1, x1 = _region(ref[..., 1], float(white[1]), steps, int(margin), float(grey))
    r = ref[y0:y1, x0:x1].reshape(-1, 3)
    t = test[y0:y1, x0:x1].reshape(-1, 3)
    mean_y = float(t[:, 1].mean())
    require(mean_y > 0, "the mid-grey region of the camera image is black: no SNR")
    r_mean = r.mean(axis=0)
    noise = t - r * (t.mean(axis=0) / np.where(r_mean > 0, r_mean, 1.0))
    rel = noise / (white / white[1])  # x' - ..., on Y's scale
    sd_y = float(noise[:, 1].std(ddof=1))
    chroma_var = 0.5 * (float((rel[:, 0] - rel[:, 1]).var(ddof=1)) + float((rel[:, 2] - rel[:, 1]).var(ddof=1)))
    require(sd_y > 0 and chroma_var > 0, "the mid-grey region has no noise (a noise-free image): its SNR is unbounded")
    value = mean_y / sd_y
    chroma = mean_y / np.sqrt(chroma_var)
    nps0 = _nps_at_zero(noise[:, 1].reshape(y1 - y0, x1 - x0), int(correlation_px))
    details = {"chroma_snr": float(chroma), "ysnr_db": float(20 * np.log10(value)),
               "region": [y0, x0, y1, x1], "mean_y_rel": float(r[:, 1].mean() / white[1]),
               "noise_y": sd_y / mean_y, "noise_chroma": float(np.sqrt(chroma_var)) / mean_y,
               "ysnr_area": mean_y / float(np.sqrt(nps0)) if nps0 else None, "correlation_px": int(correlation_px),
               "steps": _step_snrs(ref, test, float(white[1]), steps, int(margin)) if steps and step_snrs else None}
    return MetricResult(value, name="ysnr", unit="", details=details)


def _step_snrs(ref: np.ndarray, test: np.ndarray, white_y: float, steps, margin: int) -> list[dict]:
    """The luminance SNR of every gray-bar step (ISO 15739 reads the SNR on
    each step of a grey scale): per step its columns ``x0``, ``x1`` (before
    the ``margin`` inset), the ideal's ``reflectance`` (mean Y / Yw), the
    camera's ``signal_rel`` (mean Y / Yw) and ``noise_rel`` (the rms of its Y
    noise / Yw, the noise as :func:`ysnr` defines it) and ``snr`` =
    signal / noise (None where the step is too narrow after the inset, or
    has no noise or no signal)."""
    h, w = ref.shape[:2]
    out = []
    for a, b in steps:
        y0, y1, x0, x1 = margin, h - margin, max(int(a), 0) + margin, min(int(b), w) - margin
        row = {"x0": int(a), "x1": int(b), "reflectance": None, "signal_rel": None, "noise_rel": None, "snr": None}
        if y1 - y0 >= 2 and x1 - x0 >= 2:
            r = ref[y0:y1, x0:x1, 1].ravel()
            t = test[y0:y1, x0:x1, 1].ravel()
            r_mean, t_mean = float(r.mean()), float(t.mean())
            sd = float((t - r * (t_mean / r_mean if r_mean > 0 else 0.0)).std(ddof=1))
            row.update(reflectance=r_mean / white_y, signal_rel=t_mean / white_y, noise_rel=sd / white_y,
                       snr=t_mean / sd if sd > 0 and t_mean > 0 else None)
        out.append(row)
    return out


def _reads(geometry: dict, shape, options: dict, reference_xyz, white_xyz) -> list | None:
    """The mid-grey step's region (:func:`_region`, chosen on the ideal),
    and every step, all rows, while ``step_snrs`` measures them; None (the
    whole image) without steps."""
    steps = options.get("steps", geometry.get("steps"))
    if not steps:
        return None
    if options.get("step_snrs", True):
        return [(0, max(int(a), 0), shape[0], min(int(b), shape[1])) for a, b in steps]
    ref_y = np.asarray(reference_xyz)[..., 1]
    return [_region(ref_y, float(np.asarray(white_xyz)[1]), steps, int(options.get("margin", 3)),
                    float(options.get("grey", GREY_REFLECTANCE)))]


_YSNR = MetricRecord(
    name="ysnr", function=ysnr, scenes=("gray-bar",), inputs="xyz", unit="", higher_is_better=True, scored=False,
    reads=_reads, summary_options=(("step_snrs", False),),
    label="YSNR", order=40, decimals=2, decibels=True,
    description="luminance SNR on the gray bar's mid-grey step after demosaic and colour matrix (ISO 15739 region SNR)")

#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (
    _YSNR,
    _YSNR.detail("chroma_snr", name="chroma_snr", unit="", higher_is_better=True, label="chroma SNR", order=41,
                 decimals=2, decibels=True, description="chroma SNR on the same mid-grey: mean Y over the rms of the white-normalised "
                                         "opponent noise (x' - y', z' - y')"),
    _YSNR.detail("ysnr_area", name="ysnr-area", unit="", higher_is_better=True, label="YSNR (area)", order=42,
                 decimals=2, decibels=True, description="YSNR with the noise referred to an area (the noise power spectrum at zero "
                                         "frequency): smoothing by the demosaic does not raise it"),
)
