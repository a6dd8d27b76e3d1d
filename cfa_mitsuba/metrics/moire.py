"""Moire starting point (MSP) on a linear chirp (Bae 2020 s. 2.2.5, Figs 7, 12-13).

Written here (the paper's metric; ISETCam's ``cameraMoire`` calls a helper
that is not part of ISETCam).  The chroma C*ab = sqrt(a*^2 + b*^2) of the
camera image is averaged over square blocks centred on the central row; the
MSP is the first position, going from low to high frequency, where the block
mean exceeds the threshold (25, the paper's).  Unlike ISETCam, which reports
a pixel index under the name "cpd", the position is converted to true
cycles per degree with the chirp's own frequency map.
"""

from __future__ import annotations

__all__ = ["RECORDS", "moire", "block_chroma", "msp_column"]

import numpy as np

from ..errors import require, require_finite
from ._common import as_pair, as_white
from ._result import MetricResult
from .colourspace import realisable, xyz_to_lab
from .record import MetricRecord


def block_chroma(xyz, white_xyz, *, row: int, block: int = 15) -> tuple[np.ndarray, np.ndarray]:
    """C*ab along ``row`` and its ``block`` x ``block`` mean.

    Returns ``(chroma, block_mean)``, both of the image width; ``block_mean``
    is NaN where the block does not fit inside the image (the first and last
    ``block // 2`` columns).
    """
    from scipy.ndimage import uniform_filter1d  # lazy import

    xyz = np.asarray(xyz, dtype=np.float64)
    h = block // 2
    band = xyz[row - h:row + h + 1]
    lab = xyz_to_lab(band, white_xyz)
    c = np.hypot(lab[..., 1], lab[..., 2])
    column_mean = c.mean(axis=0)
    bm = uniform_filter1d(column_mean, size=block, mode="nearest")
    bm[:h] = np.nan
    if h:
        bm[-h:] = np.nan
    return c[h], bm


def msp_column(frequency_cy_per_deg, block_mean, threshold: float, block: int = 15) -> tuple[int, bool]:
    """(column, passed): the first column, in ascending frequency, whose
    block-mean C*ab exceeds ``threshold``; when none does, the column of the
    top frequency and ``passed`` False (the MSP is then a lower bound).
    Columns within ``block // 2`` of the sides have no block mean.

    >>> msp_column([1.0, 2.0, 3.0, 4.0, 5.0], [0.0, 10.0, 30.0, 22.0, 40.0], 25.0, block=1)
    (2, True)
    >>> msp_column([1.0, 2.0, 3.0, 4.0, 5.0], [0.0, 10.0, 30.0, 22.0, 40.0], 50.0, block=1)
    (4, False)
    """
    freq = np.asarray(frequency_cy_per_deg, dtype=float).reshape(-1)
    bm = np.asarray(block_mean, dtype=float).reshape(-1)
    half = int(block) // 2
    cols = np.arange(half, freq.size - half)
    order = cols[np.argsort(freq[cols], kind="stable")]
    hits = order[bm[order] > threshold]
    return (int(hits[0]), True) if hits.size else (int(order[-1]), False)


def moire(reference_xyz, test_xyz, white_xyz, *, frequency_cy_per_deg, row: int | None = None,
          block: int = 15, threshold: float = 25.0) -> MetricResult:
    """Moire starting point of a camera image of a black-and-white chirp.

    Parameters
    ----------
    reference_xyz, test_xyz : (H, W, 3) XYZ of the ideal and the camera image
        of the chirp, on the scale of ``white_xyz``.
    white_xyz : (3,) the scene white (CIELAB's white).
    frequency_cy_per_deg : (W,) local frequency of the chirp at each column
        of these images, cycles per degree (the sidecar's map, resampled to
        the camera's columns).  Any monotonic or non-monotonic layout: the
        search runs over columns in increasing frequency.
    row : the analysed row (default the central row, H // 2).
    block : side of the square averaging block in px, odd (15 default, as
        the paper's Fig 13b; 5 and 7 as Fig 7d and ISETCam).
    threshold : C*ab level that marks moire (25, the paper's).

    Returns
    -------
    MetricResult
        Headline: the MSP in cycles per degree (unit ``'cy/deg'``; higher is
        better).  Details: ``msp_px`` (column), ``passed`` (False when the
        camera's block mean never exceeds the threshold: the headline is
        then the highest analysed frequency, a lower bound, not NaN),
        ``censored`` (``not passed``: the headline is a bound, right-censored
        at the chirp's top analysed frequency, and must be stored and shown
        as one),
        ``frequency_cy_per_deg`` (W,), ``chroma_test`` / ``chroma_reference``
        (W,) along the row, ``block_mean_test`` / ``block_mean_reference``
        (W,; NaN within ``block // 2`` of the sides), ``threshold``,
        ``block``, ``row``, ``reference_passes`` (the ideal itself exceeds
        the threshold somewhere: the chart or white is not achromatic).

    References
    ----------
    Bae 2020, s. 2.2.5; ISETCam ``cameraMoire.m`` (7 x 7 blocks, threshold 25).

    Examples
    --------
    >>> grey = np.full((20, 40, 3), [47.5, 50.0, 54.45])
    >>> r = moire(grey, grey, [95.05, 100, 108.9], frequency_cy_per_deg=np.linspace(0, 30, 40), block=5)
    >>> float(r), r.details["passed"], r.details["censored"]
    (28.461538461538463, False, True)
    """
    ref, test = as_pair(reference_xyz, test_xyz)
    white = as_white(white_xyz)
    h, w = test.shape[:2]
    require(int(block) == block and block >= 1 and block % 2 == 1, f"block must be an odd number of pixels, got {block}")
    block = int(block)
    require(np.isfinite(threshold) and threshold > 0, f"threshold must be positive, got {threshold}")
    freq = require_finite(frequency_cy_per_deg, "chirp frequency map").reshape(-1)
    require(freq.size == w, f"frequency map has {freq.size} values for an image {w} px wide (one per column)")
    row = h // 2 if row is None else int(row)
    half = block // 2
    require(half <= row < h - half and w >= block,
            f"a {block} x {block} block around row {row} does not fit the {h} x {w} image")

    c_t, bm_t = block_chroma(test, white, row=row, block=block)
    c_r, bm_r = block_chroma(ref, white, row=row, block=block)
    col, passed = msp_column(freq, bm_t, threshold, block)
    details = {
        "msp_px": col, "passed": bool(passed), "censored": not passed,
        "frequency_cy_per_deg": freq,
        "chroma_test": c_t, "chroma_reference": c_r,
        "block_mean_test": bm_t, "block_mean_reference": bm_r,
        "threshold": float(threshold), "block": block, "row": row,
        "reference_passes": bool(np.nanmax(bm_r) > threshold),
        "out_of_gamut_fraction": float(np.mean(~realisable(test[row - half:row + half + 1]))),
    }
    return MetricResult(float(freq[col]), name="moire", unit="cy/deg", details=details)


def _reads(geometry: dict, shape, options: dict, reference_xyz=None, white_xyz=None) -> list:
    """The band of ``block`` rows around the analysed row, every column."""
    import inspect

    row = options.get("row", geometry.get("row"))
    row = shape[0] // 2 if row is None else int(row)
    half = int(options.get("block", inspect.signature(moire).parameters["block"].default)) // 2
    return [(max(row - half, 0), 0, min(row + half + 1, shape[0]), shape[1])]


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (
    MetricRecord(name="moire", function=moire, scenes=("chirp",), inputs="xyz", unit="cy/deg", reads=_reads,
                 higher_is_better=True, scored=True, label="MSP", order=5, decimals=2,
                 description="moiré starting point: first frequency where the block-mean C*ab passes 25",
                 paper="MSP (s. 2.2.5, Figs 12-13)", score_range=(0.04, 0.30), range_scaling="chirp_cy_px",
                 censored_key="censored", practical_difference=(("%", 10.0),),
                 practical_source="10 % of the starting frequency (about 1/7 octave): our choice, no published "
                                  "threshold for where colour moire starts"),
)
