"""Achromatic reproduction (AR) error on the gray bar (Bae 2020 s. 2.2.6, Fig 14)."""

from __future__ import annotations

__all__ = ["RECORDS", "achromatic"]

import numpy as np

from ..errors import require
from ._common import as_pair, as_white
from ._result import MetricResult
from .colourspace import lightness, realisable
from .record import MetricRecord


def achromatic(reference_xyz, test_xyz, white_xyz, *, row: int | None = None, border: int = 10,
               steps=None) -> MetricResult:
    """Mean |dL*| between the ideal and the camera image along one row.

    The paper measures "the average difference in luminance for the central
    horizontal line"; we take it in CIE L* (perceptual lightness relative to
    the scene white, so the number is in the same units as the dE metrics
    and does not depend on the exposure scale), as the absolute difference
    per pixel, averaged over the row without ``border`` pixels at each end
    (demosaicking and filtering artefacts at the image edge are not the
    CFA's achromatic error; ISETCam crops 10 px for the same reason).

    Parameters
    ----------
    reference_xyz, test_xyz : (H, W, 3) XYZ of the ideal and camera images of
        the gray bar (or (H, W) luminance Y), on the scale of ``white_xyz``.
    white_xyz : (3,) scene white; only its Y is used.
    row : the analysed row (default H // 2).
    border : columns excluded at each end (default 10).
    steps : optional sequence of ``(x0, x1)`` column ranges of the gray
        steps, for per-step means in the details.

    Returns
    -------
    MetricResult
        Headline: mean |dL*| (unit ``'L*'``; lower is better).  Details:
        ``l_reference`` / ``l_test`` (W,) L* profiles, ``abs_dl`` (W,),
        ``columns`` [x0, x1) used, ``row``, ``per_step`` (if ``steps``),
        ``out_of_gamut_fraction`` (XYZ input: the fraction of the analysed
        row's camera pixels whose XYZ no light has, see
        :func:`~cfa_mitsuba.colorimetry.realisable`).

    References
    ----------
    Bae 2020, s. 2.2.6; CIE 015:2018 (L*).

    Examples
    --------
    >>> ref = np.full((21, 60, 3), [20.0, 21.0, 23.0])
    >>> round(float(achromatic(ref, ref * 1.05, [95.05, 100, 108.9])), 3)
    1.131
    """
    ref, test = as_pair(reference_xyz, test_xyz, allow_gray=True)
    white = as_white(white_xyz)
    h, w = ref.shape[:2]
    row = h // 2 if row is None else int(row)
    require(0 <= row < h, f"row {row} outside the image (0..{h - 1})")
    border = int(border)
    require(0 <= border and w - 2 * border >= 1,
            f"border {border} px leaves no columns of the {w} px wide image")
    y_r = ref[row, :, 1] if ref.ndim == 3 else ref[row]
    y_t = test[row, :, 1] if test.ndim == 3 else test[row]
    l_r, l_t = lightness(y_r, white[1]), lightness(y_t, white[1])
    d = np.abs(l_t - l_r)
    x0, x1 = border, w - border
    details = {"l_reference": l_r, "l_test": l_t, "abs_dl": d, "columns": [x0, x1], "row": row, "border": border}
    if test.ndim == 3:  # a value no light has (negative, past the locus) is flagged, not hidden
        details["out_of_gamut_fraction"] = float(np.mean(~realisable(test[row, x0:x1])))
    if steps is not None:
        per = []
        for s in steps:
            a, b = max(int(s[0]), x0), min(int(s[1]), x1)
            per.append(float(d[a:b].mean()) if b > a else None)
        details["per_step"] = per
    return MetricResult(float(d[x0:x1].mean()), name="achromatic", unit="L*", details=details)


def _reads(geometry: dict, shape, options: dict, reference_xyz=None, white_xyz=None) -> list:
    """The analysed row, whole (the metric's region of interest)."""
    row = options.get("row", geometry.get("row"))
    row = shape[0] // 2 if row is None else int(row)
    return [(row, 0, row + 1, shape[1])]


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (
    MetricRecord(name="achromatic", function=achromatic, scenes=("gray-bar",), inputs="xyz", unit="L*", reads=_reads,
                 higher_is_better=False, identical_value=0.0, scored=True, label="AR error", order=6, decimals=3,
                 description="achromatic reproduction error, mean |ΔL*| along the gray bar",
                 paper="ΔR (s. 2.2.6, Fig 14)", score_range=(1.0, 0.5),
                 practical_difference=(("L*", 0.8),),
                 practical_source="0.8 L*: CIEDE2000's 50:50 % perceptibility threshold (Paravina et al. 2015) "
                                  "for a pure lightness difference at mid-grey, where CIEDE2000 equals dL*"),
)
