"""The proxy's area-referred noise: what the metric ``ysnr-area``
(:mod:`cfa_mitsuba.metrics.snr`) measures, predicted for a linear demosaic.

The metric refers the Y noise to an area through the noise power spectrum
at zero frequency, NPS(0) = sum over lags d (|dx|, |dy| <= L) of the noise
autocovariance C(d).  Through a linear demosaic and the colour matrix the
output noise is n_j(p) = sum_q r_qj(p) e_q: r_qj the response of output
channel j (XYZ over the white's) to an impulse at raw pixel q, e_q
independent with the relative variance v_c of q's channel.  Averaged over
the tile's n phases,

    C_j(d) = (1 / n) sum_k v_ch(k) sum_p r_kj(p) r_kj(p + d),
    NPS_j(0) = sum_c A[c, j] v_c,
    A[c, j] = (1 / n) sum_{k of channel c} sum_p r_kj(p) (sum_{|d| <= L} r_kj(p + d)),

k over the tile's positions.  When the lags reach as far as the responses'
autocorrelation (2 x their half-width), the inner sum is the whole DC gain
S_kj = sum_p r_kj(p) and A[c, j] = (1 / n) sum_k S_kj^2.  Bilinear with an
identity matrix gives each output pixel unit weight in each channel, so the
n d_c samples of a channel of density d_c have S = 1 / d_c on average and
NPS(0) >= v_c / d_c, equal when the samples are alike (Bayer's channels):
the Dainty-Shaw area noise of d_c samples per pixel, which smoothing does
not lower.  The Laplacian adds cross-channel terms (a G impulse moves R and
B too), and the colour matrix mixes the channels.  Where the responses
reach further than L / 2 (a channel with one sample in 4 x 2, whose
bilinear tent is wider) the metric's sum stops at L and so does this one:
A is what the metric measures (B B / B B / B B / G R's G: 7.45 v within
4 px, 8 v in all), not the untruncated DC gain.

Hand-written: no library propagates noise through a demosaic's impulse
responses.

References
----------
J. C. Dainty, R. Shaw, Image Science, Academic Press 1974, ch. 8 (NPS(0)
and the variance of area means).
"""

from __future__ import annotations

__all__ = ["AREA_LAG_PX", "area_noise_gains"]

import numpy as np

#: The largest lag L (px) summed: the metric's default (metrics/snr.py
#: ``ysnr(correlation_px=4)``; tests/design/test_responses.py checks they agree).
AREA_LAG_PX = 4


def area_noise_gains(resp: np.ndarray, layout: np.ndarray, n_channels: int, lag: int = AREA_LAG_PX) -> np.ndarray:
    """(C, 3) area noise gains A (module doc) from ``resp`` (bh, n, bw, 3),
    the responses to an impulse at each of the tile's n positions, each in
    its own block of zeros (responses.py ``_impulse_responses``); ``layout``
    (h, w) the channel index of each position.  NPS_j(0) = sum_c A[c, j] v_c
    for relative variances v_c (relative^2 x px^2)."""
    from scipy.ndimage import uniform_filter

    k = 2 * int(lag) + 1
    # the sum of each response over the lags around every output pixel: a k x k box sum within each block
    near = uniform_filter(resp, size=(k, 1, k, 1), mode="constant", cval=0.0) * (k * k)
    per_impulse = (resp * near).sum(axis=(0, 2))                # (n, 3)
    gains = np.zeros((n_channels, 3))
    np.add.at(gains, np.asarray(layout).ravel(), per_impulse)
    return gains / per_impulse.shape[0]
