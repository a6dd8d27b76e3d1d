"""Slanted-edge MTF (ISO 12233 e-SFR, sfrmat3 lineage; Bae 2020 s. 2.2.4, Fig 6).

Written here: no maintained Python package implements the ISO e-SFR with
sfrmat3's conventions.  Steps (P. D. Burns' sfrmat3, ISO 12233:2014):

1. rotate so the edge runs top to bottom (near-vertical); either polarity;
2. per row, the centroid of the [0.5, -0.5] derivative under a Hamming
   window gives the edge position; a line is fitted, the centroids are taken
   again with windows centred on the line, and the line refitted;
3. the rows are cut to a whole number of edge-phase cycles;
4. every pixel is binned by its horizontal distance to the edge line into
   a 4x super-sampled edge spread function (ESF);
5. the ESF's 3-tap derivative (LSF) is centred, Hamming-windowed and
   Fourier transformed; |FFT| is normalised at zero frequency and divided by
   the derivative filter's own response (x / sin x, capped at 10);
6. frequencies are cycles per pixel *normal to the edge* (the horizontal
   sampling scaled by cos(angle)).

MTF50 is the first crossing of 0.5, linearly interpolated between the two
samples around it (not snapped to a grid, unlike ISETCam's ISO12233).

``convention="isetcam"`` reproduces ISETCam's ``metrics/ISO/ISO12233.m``
(sfrmat v1/v2 lineage; docs/isetcam-parity.md): frequencies along the
pixel rows (not divided by cos(angle), so a slanted edge reads cos(angle)
lower), no correction for the derivative filter, and MTF50 the point of a
0.2-unit grid from 0 to Nyquist whose MTF, linearly interpolated from the
samples strictly below Nyquist, is closest to 0.5 (grid points past the last
such sample are undefined, so an MTF above 0.5 there returns the last grid
point below that sample, not Nyquist).
MTF50P (Imatest's measure for sharpened images) is the first crossing of
half the MTF's peak (the peak up to Nyquist) above the peak's frequency: a
sharpening overshoot raises the peak above 1 and MTF50, not MTF50P.
"""

from __future__ import annotations

__all__ = ["RECORDS", "mtf", "find_edge_roi"]

import numpy as np

from ..errors import CfaMitsubaError, require
from ._common import as_image
from ._result import MetricResult
from ._sfr import _esf, _fit_edge, _mtf50, _mtf50_isetcam, _mtf50p, _row_derivative, _sfr
from .record import MetricRecord

#: Luminance weights of the CFA paper and ISETCam (not sfrmat's Rec. 709 default).
LUM_WEIGHTS = (0.3, 0.6, 0.1)
NBIN = 4


def find_edge_roi(image, *, margin_px: int = 64):
    """Locate a single straight edge and return a ROI ``(y0, x0, y1, x1)`` around it.

    The edge must cross the whole image (top to bottom, or left to right);
    the ROI keeps every row and the columns within ``margin_px`` of the
    fitted edge (the other axis for a near-horizontal edge).  Raises
    :class:`CfaMitsubaError` when no edge is found.
    """
    a = as_image(image, "edge image", channels=(3,), allow_gray=True, min_size=8)
    lum = a @ np.asarray(LUM_WEIGHTS) if a.ndim == 3 else a
    transposed = _is_horizontal(lum)
    work = lum.T if transposed else lum
    sign = _polarity(work)
    slope, intercept, _ = _fit_edge(_row_derivative(work) * sign)
    rows = np.array([0.0, work.shape[0] - 1.0])
    xs = intercept + slope * rows
    x0 = int(max(0, np.floor(xs.min()) - margin_px))
    x1 = int(min(work.shape[1], np.ceil(xs.max()) + margin_px + 1))
    if transposed:
        return (x0, 0, x1, lum.shape[1])
    return (0, x0, lum.shape[0], x1)


def _is_horizontal(lum: np.ndarray) -> bool:
    """True when the top and bottom differ more than the left and right."""
    testv = abs(lum[-2].mean() - lum[1].mean()) if lum.shape[0] > 2 else 0.0
    testh = abs(lum[:, -2].mean() - lum[:, 1].mean()) if lum.shape[1] > 2 else 0.0
    return testv > testh


def _sides(work: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The flat columns at the two ends of an edge region (up to 5 each,
    at most a quarter of its width): the dark and bright sides, in some order."""
    k = max(1, min(5, work.shape[1] // 4))
    return work[:, :k], work[:, -k:]


def _polarity(work: np.ndarray) -> float:
    left, right = (side.mean() for side in _sides(work))
    scale = max(abs(left), abs(right), 1e-300)
    if not abs(right - left) > 0.02 * scale:
        raise CfaMitsubaError(
            f"no edge found: the two sides differ by {abs(right - left) / scale:.1%} "
            "(need a dark/bright edge crossing the region, or a ROI around one)")
    return 1.0 if right > left else -1.0


def _require_edge_above_noise(work: np.ndarray, factor: float = 5.0) -> None:
    """Refuse an image whose edge step is lost in the noise of its ESF.

    Used when the image's own edge fit failed and the reference's line is
    borrowed: orientation and polarity can come out right by chance when
    the step is far below the noise, and the e-SFR of noise is a finite but
    meaningless number (an MTF50 beyond the diffraction cut-off).  Each bin
    of the 4x super-sampled ESF averages about nlin / 4 pixels, so its noise
    is sigma / sqrt(nlin / 4), sigma the pixel noise of the two flat sides;
    the step must exceed ``factor`` times that.
    """
    nlin = work.shape[0]
    left, right = _sides(work)
    step = abs(right.mean() - left.mean())
    sigma = 0.5 * (left.std() + right.std())
    bin_noise = sigma / np.sqrt(max(1.0, nlin / 4.0))
    require(step > factor * bin_noise,
            f"no edge found in the image: noise or clipping hides it (edge step {step:.3g} is "
            f"{step / max(bin_noise, 1e-300):.1f} x the noise of one ESF bin; need > {factor:g})")


def _reference_edge(reference, bounds, weights, transposed: bool, sign: float):
    """Fit the edge line on the reference image's luminance in the same
    region, orientation and polarity as the image under test, after checking
    that the image shows that edge at all: the same orientation and polarity
    (decided on the image before its edge fit failed; when noise decided
    them, the line would be fitted along the wrong axis or with the wrong
    sign, and fail with a misleading message)."""
    y0, y1, x0, x1 = bounds
    r = as_image(reference, "reference edge image", channels=(3,), allow_gray=True, min_size=8)
    require(r.shape[0] >= y1 and r.shape[1] >= x1, "the reference image is smaller than the edge region")
    r = r[y0:y1, x0:x1]
    lum = r @ np.asarray(weights, dtype=np.float64) if r.ndim == 3 else r
    hidden = "no edge found in the image: noise or clipping hides it"
    require(_is_horizontal(lum) == transposed and _polarity(lum.T if transposed else lum) == sign,
            f"{hidden} (its orientation or polarity differs from the reference's edge)")
    if transposed:
        lum = lum.T
    slope, intercept, rms = _fit_edge(_row_derivative(lum) * sign)
    require(rms < 2.0, f"no straight edge found in the image or its reference (scatter {rms:.1f} px)")
    return slope, intercept, rms


def mtf(image, *, roi=None, pixel_pitch_um: float | None = None, weights=LUM_WEIGHTS,
        nbin: int = NBIN, reference=None, convention: str = "sfrmat3",
        picture_height_px: int | None = None) -> MetricResult:
    """Slanted-edge MTF50, MTF at Nyquist and percent alias of a linear image.

    Parameters
    ----------
    image : (H, W, 3) linear RGB or (H, W) linear gray (no OECF, no sRGB
        encoding: an encoded image inflates MTF50 by ~9 %).
    roi : ``(y0, x0, y1, x1)`` half-open pixel bounds of the region holding
        one near-vertical or near-horizontal edge (either polarity); ``None``
        finds it with :func:`find_edge_roi`.
    pixel_pitch_um : pixel pitch in micrometres; when given, the headline is
        in cy/mm on the sensor, else cy/px.
    weights : luminance weights (R, G, B) applied *on the image* to form the
        luminance record; default 0.3, 0.6, 0.1 (the paper, ISETCam).
    nbin : super-sampling factor of the ESF (4, as ISO 12233).
    reference : optional image of the same edge on the same pixel grid (the
        ideal sensor's).  Used only when the edge cannot be located in
        ``image`` itself (demosaicing artefacts that repeat with the CFA tile
        can scatter the per-row centroids by pixels): the line is then
        fitted on ``reference`` and ``details['edge_source']`` says
        ``'reference'`` instead of ``'image'``.  Not when the image's edge
        runs the other way or has the other polarity (noise or clipping
        decided them): that is an error.
    convention : ``"sfrmat3"`` (default: frequencies normal to the edge,
        derivative corrected, MTF50 the interpolated crossing) or
        ``"isetcam"`` (ISETCam's ISO12233, module doc).
    picture_height_px : the height (px) MTF50 in line widths per picture
        height refers to (a sensor's rows, say); default the image's height.

    Returns
    -------
    MetricResult
        Headline: luminance (or gray) MTF50, unit ``'cy/px'`` or ``'cy/mm'``.
        Details: ``records`` {name: {freq_cy_px, mtf, mtf50_cy_px, mtf50_cy_mm, mtf_at_nyquist,
        mtf50_found, mtf50p_cy_px, mtf50p_cy_mm, mtf50p_found, mtf_peak, mtf_peak_cy_px}} for R, G,
        B and lum (or gray; a colour channel without an edge gets ``None`` values and an ``error``
        text instead of failing the luminance result); ``mtf50_cy_px``, ``mtf50_cy_mm``,
        ``mtf_at_nyquist``, the luminance ``mtf_peak`` (the MTF's maximum up to Nyquist, 1 at DC
        without overshoot; unitless) at ``mtf_peak_cy_px``, ``mtf50p_cy_px`` / ``mtf50p_cy_mm``
        (the first frequency above the peak where the MTF falls below half the peak, Imatest's
        MTF50P; MTF50 when the peak is the DC value), ``percent_alias`` (100 x sum of the
        luminance MTF above Nyquist over its sum up to 1 cy/px, ISETCam's ISO12233 on luminance
        as the paper says; a box pixel behind a perfect lens reads 25.2 %, its sinc times the
        sinc of the ESF's 1/``nbin`` px bins, which the e-SFR does not correct:
        tests/metrics/test_mtf_alias.py), ``mtf50_lw_ph`` (2 x cy/px x ``picture_height_px``),
        ``picture_height_px``, ``edge_angle_deg``, ``orientation``, ``roi``, ``edge_fit_rms_px``,
        ``contrast`` ((bright - dark) / (bright + dark), a dark side below 0 counted as 0; below
        ISO 12233's 0.2, ``low_contrast``).  An MTF that never falls below 0.5 up to the highest
        analysed frequency reports that frequency with ``mtf50_found = False``.

    References
    ----------
    ISO 12233:2014 Annex D (e-SFR); P. D. Burns, "Slanted-edge MTF for
    digital camera and scanner analysis", PICS 2000, 135-138; Bae 2020 s. 2.2.4.

    Examples
    --------
    >>> from scipy.special import erf
    >>> y, x = np.mgrid[0:100, 0:80]
    >>> d = (x - 40 - (y - 50) * np.tan(np.radians(5))) * np.cos(np.radians(5))
    >>> edge = 0.2 + 0.6 * 0.5 * (1 + erf(d / (np.sqrt(2) * 1.0)))
    >>> round(float(mtf(edge)), 3)  # analytic 0.18739 / sigma = 0.187
    0.187
    """
    a = as_image(image, "edge image", channels=(3,), allow_gray=True, min_size=8)
    require(convention in ("sfrmat3", "isetcam"), f"unknown MTF convention {convention!r} (sfrmat3 or isetcam)")
    isetcam = convention == "isetcam"
    require(int(nbin) == nbin and nbin >= 1, f"nbin must be a positive integer, got {nbin}")
    if pixel_pitch_um is not None:
        require(np.isfinite(pixel_pitch_um) and pixel_pitch_um > 0, f"pixel pitch must be positive, got {pixel_pitch_um}")
    roi = _checked_roi(a, find_edge_roi(a) if roi is None else roi)
    records, main = _records(a[roi[0]:roi[2], roi[1]:roi[3]], weights)
    transposed = _is_horizontal(records[main])
    if transposed:
        records = {k: v.T for k, v in records.items()}
    sign = _polarity(records[main])
    edge = _edge(records[main], sign, roi, reference, weights, transposed)
    per_mm = 1.0 / (pixel_pitch_um * 1e-3) if pixel_pitch_um else None
    out = {name: _record_mtf(name, rec, main, edge, sign, int(nbin), per_mm, isetcam) for name, rec in records.items()}
    lum = out[main]
    band = lum["freq_cy_px"] <= 1.0
    above = band & (lum["freq_cy_px"] > 0.5)
    alias = 100.0 * lum["mtf"][above].sum() / lum["mtf"][band].sum()
    contrast = _contrast(records[main])
    height = a.shape[0] if picture_height_px is None else picture_height_px
    require(isinstance(height, (int, np.integer)) and not isinstance(height, bool) and height >= 1,
            f"picture_height_px must be a whole number of pixels >= 1, got {height!r}")
    details = {
        "records": out,
        "mtf50_cy_px": lum["mtf50_cy_px"], "mtf50_cy_mm": lum["mtf50_cy_mm"],
        "mtf50_found": lum["mtf50_found"],
        "mtf50p_cy_px": lum["mtf50p_cy_px"], "mtf50p_cy_mm": lum["mtf50p_cy_mm"],
        "mtf50p_found": lum["mtf50p_found"], "mtf_peak": lum["mtf_peak"], "mtf_peak_cy_px": lum["mtf_peak_cy_px"],
        "mtf_at_nyquist": lum["mtf_at_nyquist"], "percent_alias": float(alias),
        "mtf50_lw_ph": 2.0 * lum["mtf50_cy_px"] * int(height), "picture_height_px": int(height),
        "nyquist_cy_px": 0.5,
        "nyquist_cy_mm": 0.5 / (pixel_pitch_um * 1e-3) if pixel_pitch_um else None,
        "edge_angle_deg": edge["angle"], "orientation": "horizontal" if transposed else "vertical",
        "roi": list(roi), "rows_used": edge["rows"], "edge_fit_rms_px": edge["rms"], "edge_source": edge["source"],
        "contrast": float(contrast), "low_contrast": bool(contrast < 0.2),
        "pixel_pitch_um": pixel_pitch_um, "convention": convention,
        "weights": list(map(float, weights)) if a.ndim == 3 else None,
    }
    if pixel_pitch_um:
        return MetricResult(lum["mtf50_cy_mm"], name="mtf", unit="cy/mm", details=details)
    return MetricResult(lum["mtf50_cy_px"], name="mtf", unit="cy/px", details=details)


def _checked_roi(a, roi) -> tuple[int, int, int, int]:
    y0, x0, y1, x1 = (int(v) for v in roi)
    require(0 <= y0 < y1 <= a.shape[0] and 0 <= x0 < x1 <= a.shape[1],
            f"roi {[y0, x0, y1, x1]} is empty or outside the {a.shape[0]} x {a.shape[1]} image")
    require(min(y1 - y0, x1 - x0) >= 8, f"roi {[y0, x0, y1, x1]} is smaller than 8 x 8 px")
    return y0, x0, y1, x1


def _records(a, weights) -> tuple[dict, str]:
    """The records analysed ({name: 2-D array}) and the headline's name:
    R, G, B and their weighted luminance ('lum'), or the one 'gray'."""
    if a.ndim != 3:
        return {"gray": a}, "gray"
    w = np.asarray(weights, dtype=np.float64)
    require(w.shape == (3,), f"weights must be 3 numbers (R, G, B), got {w.tolist()}")
    return {"R": a[..., 0], "G": a[..., 1], "B": a[..., 2], "lum": a @ w}, "lum"


def _edge(work, sign, roi, reference, weights, transposed) -> dict:
    """The headline record's edge line: slope, rms scatter (px), where it
    was fitted ('image', or 'reference' when the image's own edge cannot be
    located), its angle (deg), the rows used (a whole number of phase
    cycles) and cos(angle)."""
    y0, x0, y1, x1 = roi
    nlin = work.shape[0]
    source = "image"
    try:
        slope, _, rms = _fit_edge(_row_derivative(work) * sign)
        require(rms < 2.0, f"no straight edge found: edge positions scatter {rms:.1f} px about the fitted line")
    except CfaMitsubaError:
        if reference is None:
            raise
        slope, _, rms = _reference_edge(reference, (y0, y1, x0, x1), weights, transposed, sign)
        source = "reference"
        _require_edge_above_noise(work)
    angle = float(np.degrees(np.arctan(slope)))
    cycles = np.floor(nlin * abs(slope))
    require(cycles >= 1,
            f"edge too close to {'horizontal' if transposed else 'vertical'} ({angle:.2f} deg over {nlin} rows): "
            "the edge must shift by at least one pixel across the region (slant it 2-10 deg)")
    require(abs(angle) < 40, f"edge slant {angle:.1f} deg is too far from vertical/horizontal (need < 40 deg)")
    return {"slope": slope, "rms": rms, "source": source, "angle": angle,
            "rows": int(np.floor(cycles / abs(slope) + 0.5)), "cos": float(np.cos(np.arctan(slope)))}


def _contrast(work) -> float:
    """Michelson contrast of the edge, for non-negative signals: a dark side
    below 0 (read noise about black in a linear camera image) counts as 0,
    so the value stays in [0, 1] (not 1e16 or NaN as bright + dark -> 0)."""
    dark, bright = sorted(side.mean() for side in _sides(work))
    dark = max(dark, 0.0)
    return (bright - dark) / (bright + dark) if bright > 0 else 0.0


def _record_mtf(name, rec, main, edge, sign, nbin, per_mm, isetcam: bool = False) -> dict:
    """One record's MTF curve with its MTF50, MTF50P, peak and value at
    Nyquist (``isetcam``: ISETCam's ISO12233 conventions, module doc)."""
    s_r = edge["slope"]
    if name != main and edge["source"] == "image":  # each colour record gets its own edge fit (sfrmat3) ...
        try:
            s_fit, _, rms_r = _fit_edge(_row_derivative(rec) * sign)
            if rms_r < 2.0 and abs(s_fit - s_r) < 0.1 * abs(s_r) + 0.01:
                s_r = s_fit
        except CfaMitsubaError:  # ... unless a weak channel has no usable edge
            pass
    try:
        esf = _esf(rec[:edge["rows"]], s_r, nbin)
        freq, m = _sfr(esf, nbin, 1.0 if isetcam else edge["cos"], sign, correct=not isetcam)
    except CfaMitsubaError as exc:
        if name == main:
            raise
        return {"mtf50_cy_px": None, "mtf50_cy_mm": None, "mtf_at_nyquist": None,
                "mtf50_found": False, "mtf50p_cy_px": None, "mtf50p_cy_mm": None,
                "mtf50p_found": False, "mtf_peak": None, "mtf_peak_cy_px": None,
                "error": str(exc)}  # a channel without an edge
    m50, found = _mtf50(freq, m)
    if isetcam:
        m50 = _mtf50_isetcam(freq, m, per_mm or 1.0)
    m50p, peak, f_peak, found_p = _mtf50p(freq, m)
    return {
        "freq_cy_px": freq, "mtf": m,
        "mtf50_cy_px": m50, "mtf50_found": found,
        "mtf50_cy_mm": m50 * per_mm if per_mm else None,
        "mtf50p_cy_px": m50p, "mtf50p_found": found_p,
        "mtf50p_cy_mm": m50p * per_mm if per_mm else None,
        "mtf_peak": peak, "mtf_peak_cy_px": f_peak,
        "mtf_at_nyquist": float(np.interp(0.5, freq, m)),
    }


def edge_region(geometry: dict, shape, options: dict, reference_xyz=None, white_xyz=None) -> list | None:
    """The edge's region (the scene geometry's ``roi``); None (the whole
    image, where the edge is searched for) without one."""
    roi = options.get("roi", geometry.get("roi"))
    return None if roi is None else [tuple(roi)]


#: This module's metric records (collected by :mod:`.registry`).
_MTF = MetricRecord(
    name="mtf", function=mtf, scenes=("slanted-edge",), inputs="linear", unit="cy/mm", higher_is_better=True,
    reads=edge_region,
    scored=True, label="MTF50", order=4, decimals=1, paper="MTF50 (s. 2.2.4, Figs 6, 11)",
    score_range=(30.0, 110.0), range_scaling="pixel_pitch", ideal_details=True,
    description="luminance MTF50 of the slanted edge (ISO 12233 e-SFR)",
    practical_difference=(("%", 5.0),),
    practical_source="5 % of the MTF50: our choice, no published threshold; perceived sharpness is acutance's "
                     "(IEEE 1858-2016 CPIQ), whose just noticeable difference depends on the print or display "
                     "size and the viewing distance, so none holds for MTF50 alone")
RECORDS = (
    _MTF,
    _MTF.detail("mtf50p_cy_mm", name="mtf50p", unit="cy/mm", label="MTF50P", order=103, decimals=1,
                higher_is_better=True,
                description="luminance MTF50P: where the MTF falls to half its peak (Imatest; not raised by overshoot)"),
    _MTF.detail("mtf_peak", name="mtf-peak", unit="", label="MTF peak", order=104, decimals=3,
                description="peak of the luminance MTF up to Nyquist (1 without overshoot; above 1: sharpening)"),
    _MTF.detail("mtf50_cy_px", name="mtf50-cy-px", unit="cy/px", label="MTF50 (cy/px)", order=105, decimals=3,
                higher_is_better=True, description="luminance MTF50 in cycles per pixel (0.5 is Nyquist)"),
    _MTF.detail("mtf50_lw_ph", name="mtf50-lw-ph", unit="LW/PH", label="MTF50 (LW/PH)", order=106, decimals=0,
                higher_is_better=True,
                description="luminance MTF50 in line widths per picture height (the captured image's height unless "
                            "[metrics.mtf] picture_height_px gives a sensor's)"),
    _MTF.detail("percent_alias", name="mtf-alias", unit="%", label="aliasing (ISO 12233)", order=107, decimals=1,
                description="ISO 12233 aliasing percentage: the luminance MTF's area above Nyquist over its area "
                            "up to 1 cy/px (ISETCam's ISO12233 aliasingPercentage)"),
)

