"""MDSI, the Mean Deviation Similarity Index (Nafchi et al. 2016; Bae 2020 s. 2.2.7).

Written here (no maintained numpy implementation reproduces the authors'
MATLAB code): gradient similarity with luminance fusion, chromaticity
similarity, and deviation pooling, with the authors' constants and their
MATLAB conventions (reference README s. 5): zero-padded ``conv2 'same'``,
the MEAN absolute deviation, complex powers for negative similarities.
"""

from __future__ import annotations

__all__ = ["RECORDS", "mdsi", "mdsi_reference_maps"]

import numpy as np

from ..errors import require
from ._common import as_image, as_pair, code_range, conv2_same, round_half_away
from .record import NATURAL, MetricRecord

C1, C2, C3 = 140.0, 55.0, 550.0
ALPHA = 0.6  # 'sum' combination weight of the gradient similarity
GAMMA, BETA = 0.2, 0.1  # 'mult' exponents
_PREWITT_X = np.array([[1.0, 0.0, -1.0]] * 3) / 3.0


def _downsample(x: np.ndarray, f: int) -> np.ndarray:
    if f == 1:
        return x
    return conv2_same(x, np.full((f, f), 1.0 / (f * f)))[::f, ::f]


def _gradient(lum: np.ndarray) -> np.ndarray:
    gx = conv2_same(lum, _PREWITT_X)
    gy = conv2_same(lum, _PREWITT_X.T)
    return np.sqrt(gx * gx + gy * gy)


def _similarity(a, b, c):
    # (2ab + c) / (a^2 + b^2 + c) written as 1 - (a - b)^2 / (...): the same
    # number to rounding, but exactly 1 for equal inputs, so identical images
    # give exactly 0 (the 4th roots would lift rounding noise of 1e-16 to 1e-4).
    return 1.0 - (a - b) ** 2 / (a * a + b * b + c)


_LUM = np.array([0.2989, 0.5870, 0.1140])
_H = np.array([0.30, 0.04, -0.35])
_M = np.array([0.34, -0.60, 0.17])


def _maps(img: np.ndarray, data_range: float) -> tuple:
    """What MDSI takes from one image (0..255 codes) before comparing: its
    shape and ``data_range``, then its luminance, the luminance's gradient
    magnitude and its H and M chromaticity channels, all after the f x f
    mean and subsampling."""
    f = max(1, round_half_away(min(img.shape[:2]) / 256.0))
    d = np.stack([_downsample(img[..., c], f) for c in range(3)], axis=-1)
    lum = d @ _LUM
    return (img.shape, float(data_range)), lum, _gradient(lum), d @ _H, d @ _M


def mdsi_reference_maps(reference, *, data_range: float = 255.0) -> tuple:
    """What :func:`mdsi` computes from the reference alone: pass it as
    ``reference_maps`` when one reference is compared with many test images
    (same ``data_range``): the result is identical."""
    ref = as_image(reference, "reference image", min_size=2)
    ref, _ = code_range(ref, ref, data_range, "mdsi")
    return _maps(ref, data_range)


def mdsi(reference, test, *, data_range: float = 255.0, combination: str = "sum", reference_maps=None) -> float:
    """MDSI of ``test`` (distorted) against ``reference``; 0 = identical, lower is better.

    Parameters
    ----------
    reference, test : (H, W, 3) RGB code values in 0..``data_range`` (8-bit
        sRGB by default).  The order matters: MDSI is not symmetric (the
        authors' ``MDSI(Ref, Dist)``).
    data_range : the code range; values are rescaled to 0..255, the range
        C1 = 140, C2 = 55, C3 = 550 assume.
    combination : ``'sum'`` (default, GCS = 0.6 GS + 0.4 CS) or ``'mult'``
        (GCS = GS^0.2 CS^0.1).
    reference_maps : optional, :func:`mdsi_reference_maps` of this
        reference with the same ``data_range`` (a speed-up only: the result
        is identical).

    Returns
    -------
    float
        ``mad(GCS^(1/4))^(1/4)``, mad = mean absolute deviation, computed on
        complex values where GCS < 0.  Both images are first averaged and
        subsampled by ``f = max(1, round(min(H, W) / 256))``.  Deviation
        pooling measures how *unevenly* the similarity is spread: a uniform
        colour difference over a flat image registers only through the
        zero-padded border of the gradient filters (finite, but not a
        colour-accuracy measure; use delta-e or scielab for that).

    References
    ----------
    H. Z. Nafchi, A. Shahkolaei, R. Hedjam, M. Cheriet, "Mean deviation
    similarity index: efficient and reliable full-reference image quality
    evaluator", IEEE Access 4 (2016) 5579-5590, eqs. 2-12; Bae 2020 eqs. 3-5.

    Examples
    --------
    >>> rng = np.random.default_rng(2)
    >>> a = rng.integers(0, 256, (40, 40, 3)).astype(float)
    >>> mdsi(a, a)
    0.0
    """
    require(combination in ("sum", "mult"), f"unknown MDSI combination {combination!r} (expected 'sum' or 'mult')")
    ref, test = as_pair(reference, test, min_size=2)
    ref, test = code_range(ref, test, data_range, "mdsi")
    if reference_maps is None:
        reference_maps = _maps(ref, data_range)
    require(reference_maps[0] == (ref.shape, float(data_range)),
            "reference_maps do not belong to images of this shape and data_range")
    _, l1, g1, h1, m1 = reference_maps
    _, l2, g2, h2, m2 = _maps(test, data_range)

    gf = _gradient(0.5 * (l1 + l2))
    gs = _similarity(g1, g2, C1) + _similarity(g2, gf, C2) - _similarity(g1, gf, C2)
    cs = 1.0 - ((h1 - h2) ** 2 + (m1 - m2) ** 2) / (h1 * h1 + h2 * h2 + m1 * m1 + m2 * m2 + C3)

    gs_c, cs_c = gs.astype(np.complex128), cs.astype(np.complex128)
    if combination == "sum":
        gcs = ALPHA * gs_c + (1.0 - ALPHA) * cs_c
    else:
        gcs = np.power(gs_c, GAMMA) * np.power(cs_c, BETA)
    q = np.sqrt(np.sqrt(gcs.ravel()))  # principal branch, as MATLAB's (x.^0.5).^0.5
    value = np.mean(np.abs(q - q.mean())) ** 0.25
    return float(value)


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (
    MetricRecord(name="mdsi", function=mdsi, scenes=(NATURAL,), inputs="srgb8", unit="", higher_is_better=False,
                 identical_value=0.0,
                 scored=True, label="MDSI", order=7, decimals=3,
                 description="mean deviation similarity index (Nafchi 2016), 0 = identical",
                 paper="MDSI (s. 2.2.7, Fig 15)", score_range=(0.5, 0.0),
                 reference_cache=("reference_maps", mdsi_reference_maps),
                 practical_difference=(("", 0.02),),
                 practical_source="0.02: our choice, no published threshold for MDSI (4 % of the paper's "
                                  "0-0.5 range)"),
)
