"""HaarPSI, the Haar wavelet-based perceptual similarity index (Reisenhofer et
al. 2018; Bae 2020 s. 2.2.8).

Written here (no maintained library reproduces the authors' MATLAB numbers
to 1e-6: piq uses other YIQ digits): Haar filters of three scales applied
with MATLAB's zero-padded ``conv2 'same'`` (even-kernel alignment), YIQ with
MATLAB's coefficients, C = 30, alpha = 4.2 for 0..255 data.
"""

from __future__ import annotations

__all__ = ["RECORDS", "haarpsi", "haarpsi_reference_maps"]

import numpy as np

from ..errors import require
from ._common import as_image, as_pair, code_range, conv2_same
from .record import NATURAL, MetricRecord

C, ALPHA = 30.0, 4.2
_Y = np.array([0.299, 0.587, 0.114])
_I = np.array([0.596, -0.274, -0.322])
_Q = np.array([0.211, -0.523, 0.312])
_MEAN2 = np.full((2, 2), 0.25)


def _subsample(x: np.ndarray) -> np.ndarray:
    return conv2_same(x, _MEAN2)[::2, ::2]


def _haar(x: np.ndarray, scale: int, transpose: bool) -> np.ndarray:
    n = 2 ** scale
    k = np.full((n, n), 2.0 ** -scale)
    k[: n // 2] *= -1.0
    return conv2_same(x, k.T if transpose else k)


def _similarity(a, b):
    # (2ab + C) / (a^2 + b^2 + C), as 1 - (a - b)^2 / (...): exactly 1 for equal inputs.
    return 1.0 - (a - b) ** 2 / (a * a + b * b + C)


def _sigmoid(x):
    return 1.0 / (1.0 + np.exp(-ALPHA * x))


def _logit(p):
    return np.log(p / (1.0 - p)) / ALPHA


def _maps(img: np.ndarray, subsample: bool, data_range: float) -> tuple:
    """What HaarPSI takes from one image (0..255 codes): its shape and the
    options (``subsample``, ``data_range``), then per
    orientation (rows, columns) the absolute Haar responses of scales 1-3 of
    its Y channel, then (colour images) the absolute 2 x 2 means of its I
    and Q channels (after the 2 x 2 subsampling when ``subsample``)."""
    colour_image = img.ndim == 3
    y = img @ _Y if colour_image else img
    if subsample:
        y = _subsample(y)
    haar = tuple([np.abs(_haar(y, s, transpose)) for s in (1, 2, 3)] for transpose in (False, True))
    chroma = ()
    if colour_image:
        iq = (img @ _I, img @ _Q)
        if subsample:
            iq = tuple(_subsample(v) for v in iq)
        chroma = tuple(np.abs(conv2_same(v, _MEAN2)) for v in iq)
    return ((img.shape, bool(subsample), float(data_range)), haar, chroma)


def haarpsi_reference_maps(reference, *, data_range: float = 255.0, subsample: bool = True) -> tuple:
    """What :func:`haarpsi` computes from the reference alone (its Haar
    responses and smoothed chroma): pass it as ``reference_maps`` when one
    reference is compared with many test images (same options): the result
    is identical."""
    ref = as_image(reference, "reference image", allow_gray=True, min_size=2)
    ref, _ = code_range(ref, ref, data_range, "haarpsi")
    return _maps(ref, subsample, data_range)


def haarpsi(reference, test, *, data_range: float = 255.0, subsample: bool = True, reference_maps=None) -> float:
    """HaarPSI of two images; 1 = identical, higher is better (symmetric).

    Parameters
    ----------
    reference, test : (H, W, 3) RGB code values in 0..``data_range`` (colour
        version: Y, I, Q) or (H, W) gray images (luminance only).
    data_range : the code range; values are rescaled to 0..255, the range
        C = 30 assumes.
    subsample : the authors' default 2 x 2 mean and 2x subsampling first.
    reference_maps : optional, :func:`haarpsi_reference_maps` of this
        reference with the same options (a speed-up only: the result is
        identical).

    Returns
    -------
    float
        ``logit(sum sigmoid(S) W / sum W)^2`` with local similarities S from
        Haar scales 1-2 (and the smoothed I, Q channels) and weights W from
        scale 3.  If both images are perfectly flat (all weights 0) the
        weights are taken as uniform, so flat images still get a finite
        score (1 when they are equal).

    References
    ----------
    R. Reisenhofer, S. Bosse, G. Kutyniok, T. Wiegand, "A Haar wavelet-based
    perceptual similarity index for image quality assessment", Signal
    Processing: Image Communication 61 (2018) 33-43, eqs. 8-14; Bae 2020 eqs. 6-7.

    Examples
    --------
    >>> rng = np.random.default_rng(3)
    >>> a = rng.integers(0, 256, (32, 32, 3)).astype(float)
    >>> haarpsi(a, a)
    1.0
    """
    ref, test = as_pair(reference, test, allow_gray=True, min_size=2)
    ref, test = code_range(ref, test, data_range, "haarpsi")
    if reference_maps is None:
        reference_maps = _maps(ref, subsample, data_range)
    require(reference_maps[0] == (ref.shape, bool(subsample), float(data_range)),
            "reference_maps do not belong to images of this shape and these options")
    _, haar1, chroma1 = reference_maps
    _, haar2, chroma2 = _maps(test, subsample, data_range)

    sims, weights = [], []
    for c1, c2 in zip(haar1, haar2):
        weights.append(np.maximum(c1[2], c2[2]))
        sims.append((_similarity(c1[0], c2[0]) + _similarity(c1[1], c2[1])) / 2.0)
    if chroma1:
        sims.append((_similarity(chroma1[0], chroma2[0]) + _similarity(chroma1[1], chroma2[1])) / 2.0)
        weights.append((weights[0] + weights[1]) / 2.0)
    s, w = np.stack(sims), np.stack(weights)
    if np.all(s == 1.0):  # identical structure everywhere: exactly 1, not 1 - 4e-16
        return 1.0
    total = w.sum()
    pooled = (_sigmoid(s) * w).sum() / total if total > 0 else _sigmoid(s).mean()
    # Similarities are <= 1, so the score is <= 1; the sigmoid/logit round trip
    # can overshoot by ~1e-15, which we clip so identical images give exactly 1.
    return float(min(_logit(pooled) ** 2, 1.0))


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (
    MetricRecord(name="haarpsi", function=haarpsi, scenes=(NATURAL,), inputs="srgb8", unit="",
                 higher_is_better=True, identical_value=1.0, scored=True, label="HaarPSI", order=8, decimals=3,
                 description="Haar wavelet perceptual similarity (Reisenhofer 2018), 1 = identical",
                 paper="HaarPSI (s. 2.2.8, Fig 15)", score_range=(0.0, 1.0),
                 reference_cache=("reference_maps", haarpsi_reference_maps),
                 practical_difference=(("", 0.02),),
                 practical_source="0.02: our choice, no published threshold for HaarPSI (2 % of its 0-1 "
                                  "range, less than SSIM's 0.05, as HaarPSI spreads a distortion over more "
                                  "of its range)"),
)
