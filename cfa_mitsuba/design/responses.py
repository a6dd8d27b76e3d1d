"""A demosaic's response to each phase of a tile, through the colour
matrix: what the design proxy (:mod:`.proxy`) reads of a linear method.

One demosaic call puts an impulse at each of the tile's positions, each in
its own block of zeros (:func:`_impulse_responses`); from those responses:

* the noise gains (:func:`demosaic_noise_gains`): var(XYZ_j / white_j) =
  sum_c G[c, j] v_c for independent balanced-channel noise of relative
  variance v_c, and the area noise gains (:mod:`.noise_area`);
* the grey edge's phase-averaged line spread function, its MTF50 through
  the optics (:func:`edge_mtf50`) and the edge's information capacity
  (:func:`edge_capacity`), each channel's noise power spectrum beside it.

A method is predicted by its own responses when its record says it is
linear in the mosaic (:attr:`cfa_mitsuba.isp.DemosaicMethod.linear`), else
by the Laplacian's, the linear core of the nonlinear methods here
(:func:`linear_core`).
"""

from __future__ import annotations

__all__ = ["linear_core", "demosaic_noise_gains", "demosaic_area_noise_gains", "edge_mtf50", "edge_capacity"]

import functools
import inspect

import numpy as np


def linear_core(method: str) -> str:
    """The method whose impulse responses predict ``method``: itself when
    its record says it is linear in the mosaic, else the Laplacian."""
    from ..isp import get_demosaic_record

    return method if get_demosaic_record(method).linear else "laplacian"


class _Tile:
    """What the demosaics read of a CFA: its tile of filter names and its channels."""

    def __init__(self, pattern: np.ndarray, channels: tuple):
        self.pattern, self.channels = pattern, channels


def _block(n: int, period: int, support: int = 12) -> int:
    """A multiple of ``period`` at least 2 ``support``: room for one impulse response."""
    return period * max(2, -(-2 * support // period))


def _impulse_responses(layout: np.ndarray, channels: tuple, matrix_rel: np.ndarray, method: str,
                       lum_weights=None) -> tuple[np.ndarray, int]:
    """((bh, n, bw, 3) XYZ / white response to an impulse at each of the
    tile's n positions, each in its own block; the impulse's column in its
    block).  One demosaic call: each impulse in a block of zeros wide enough
    that the responses do not meet (the methods here reach a few tiles)."""
    from ..isp import demosaic, get_demosaic

    h, w = layout.shape
    names = np.asarray(channels, dtype=object)
    tile = _Tile(names[layout], tuple(channels))
    bh, bw = _block(h, h), _block(w, w)
    n = h * w
    raw = np.zeros((bh, bw * n))
    r0, c0 = (bh // h // 2) * h, (bw // w // 2) * w
    for k in range(n):
        raw[r0 + k // w, k * bw + c0 + k % w] = 1.0
    core = linear_core(method)
    takes = "luminance_weights" in inspect.signature(get_demosaic(core)).parameters  # the processor's weights
    opts = {"luminance_weights": list(map(float, lum_weights))} if takes and lum_weights is not None else {}
    out = demosaic(raw, tile, core, **opts)
    resp = out @ np.asarray(matrix_rel, dtype=np.float64)
    return resp.reshape(bh, n, bw, 3), c0


def demosaic_noise_gains(layout: np.ndarray, channels: tuple, matrix_rel: np.ndarray, method: str,
                         lum_weights=None) -> np.ndarray:
    """(C, 3) noise gains of a tile through a linear demosaic and the colour
    matrix (module doc): G[c, j] = the mean over the tile's phases of
    sum_q (sum_k M_kj dout_k(p) / draw(q))^2 over the raw pixels q of channel
    c, so that var(XYZ_j / white_j) = sum_c G[c, j] v_c for independent
    balanced-channel noise of relative variance v_c.

    ``layout`` (h, w) holds indices into ``channels`` (every one present);
    ``matrix_rel`` (C, 3) the colour matrix over the white's XYZ.
    """
    return _gains_and_lsf(layout, channels, matrix_rel, method, lum_weights)[0]


def demosaic_area_noise_gains(layout: np.ndarray, channels: tuple, matrix_rel: np.ndarray, method: str,
                              lum_weights=None, lag: int | None = None) -> np.ndarray:
    """(C, 3) area noise gains A of the same (:mod:`.noise_area`): NPS_j(0) =
    sum_c A[c, j] v_c over the lags up to ``lag`` px (default: the metric's)."""
    if lag is None:
        return _gains_and_lsf(layout, channels, matrix_rel, method, lum_weights)[3]
    from .noise_area import area_noise_gains

    return area_noise_gains(_impulse_responses(layout, channels, matrix_rel, method, lum_weights)[0], layout,
                            len(channels), lag)


#: Radial rings of the proxy's noise power spectrum over 0..0.5 cy/px.
_NPS_RINGS = 12
#: The slanted edge (render/charts.py EDGE_REFLECTANCES): dark 0.15, bright
#: 0.60, half of the region each, so its mean is 0.375 of the scene's white.
_EDGE = (0.15, 0.60)


def edge_capacity(lsf, nps_per_channel, level_var, step: float, f_number: float, pixel_pitch_um: float,
                  roi_width_px: float = 20.0) -> float:
    """Information capacity (bit/px) of the slanted edge predicted for a
    linear demosaic: the metric's formula (:mod:`cfa_mitsuba.metrics.info_capacity`)
    with S(f) = (step / 2)^2 MTF(f)^2 (MTF of the optics and the demosaic's
    grey line spread function, :func:`edge_mtf50`'s) and N(f) = sum_c var_c
    NPS_c(f), NPS_c the radially averaged power spectrum of the Y responses
    to channel c's impulses (phases averaged), var_c its noise variance
    (white = 1 units) on the edge's mean level."""
    from ..metrics.info_capacity import capacity_bits_per_px
    from ..optics.diffraction import diffraction_mtf

    offsets, weights, zipper = lsf
    centres = (np.arange(_NPS_RINGS) + 0.5) * 0.5 / _NPS_RINGS
    f = np.concatenate([[0.0], centres, [0.5]])
    h = np.abs(np.exp(-2j * np.pi * np.outer(f, offsets)) @ weights)
    h = h / h[0] if h[0] > 0 else h
    m = h * np.abs(np.sinc(f)) * diffraction_mtf(f / (pixel_pitch_um * 1e-3), 550.0, f_number)
    nps = np.asarray(level_var, dtype=np.float64) @ nps_per_channel
    nps = np.interp(f, centres, nps) + step ** 2 * zipper / roi_width_px
    return capacity_bits_per_px(f, (0.5 * step) ** 2 * m ** 2, np.maximum(nps, 1e-300))


def _gains_and_lsf(layout, channels, matrix_rel, method, lum_weights):
    """(noise gains (C, 3), the grey line spread function of Y across columns
    averaged over the tile's phases: (offsets px, weights, zipper), each
    channel's radial noise power spectrum, the area noise gains (C, 3))."""
    from .noise_area import area_noise_gains

    resp, c0 = _impulse_responses(layout, channels, matrix_rel, method, lum_weights)
    bh, n, bw, _ = resp.shape
    energy = (resp ** 2).sum(axis=(0, 2))                       # (n, 3): each impulse's
    gains = np.zeros((len(channels), 3))
    np.add.at(gains, layout.ravel(), energy)
    w = layout.shape[1]
    lsf = np.zeros(2 * bw)
    for k in range(n):  # a vertical edge sees each response summed down its columns, about its impulse
        col = resp[:, k, :, 1].sum(axis=0)
        start = bw - (c0 + k % w)
        lsf[start:start + bw] += col
    offsets = np.arange(2 * bw) - bw
    # each output phase's own line spread function against their average: a
    # grey edge rendered differently at each phase is what the edge's noise
    # image keeps as zipper (px^2 of ESF difference summed across the edge)
    h = layout.shape[0]
    rr, cc = np.meshgrid(np.arange(bh), np.arange(bw), indexing="ij")
    phase = ((rr % h) * w + cc % w).ravel()
    per_phase = np.zeros((n, 2 * bw))
    for k in range(n):
        np.add.at(per_phase, (phase, (c0 + k % w - cc).ravel() + bw), resp[:, k, :, 1].ravel())
    per_phase = per_phase[:, ::-1]  # index by output minus input, as lsf
    esf = np.cumsum(per_phase, axis=1)
    zipper = float(np.mean(np.sum((esf - esf.mean(axis=0)[None, :]) ** 2, axis=1)))
    power = np.abs(np.fft.fft2(resp[..., 1].transpose(1, 0, 2), axes=(1, 2))) ** 2   # (n, bh, bw): each impulse's
    f = np.hypot(np.fft.fftfreq(bh)[:, None], np.fft.fftfreq(bw)[None, :]).ravel()
    rings = np.minimum((f / 0.5 * _NPS_RINGS).astype(int), _NPS_RINGS)
    counts = np.bincount(rings, minlength=_NPS_RINGS + 1)[:_NPS_RINGS]
    per_channel = np.zeros((len(channels), _NPS_RINGS))
    for k in range(n):  # each channel's noise spectrum, radially averaged, phases averaged
        ring = np.bincount(rings, weights=power[k].ravel(), minlength=_NPS_RINGS + 1)[:_NPS_RINGS]
        per_channel[layout.ravel()[k]] += ring / np.maximum(counts, 1) / n
    return gains / n, (offsets, lsf / n, zipper), per_channel, area_noise_gains(resp, layout, len(channels))


@functools.lru_cache(maxsize=8)
def _dtft(n: int, start: int) -> tuple[np.ndarray, np.ndarray]:
    """(f, the DTFT matrix at f = 0..1 cy/px, 401 points, of offsets start..start+n-1)."""
    f = np.linspace(0.0, 1.0, 401)
    return f, np.exp(-2j * np.pi * np.outer(f, np.arange(start, start + n)))


@functools.lru_cache(maxsize=8)
def _optics_mtf(f_number: float, pixel_pitch_um: float) -> np.ndarray:
    """Diffraction at 550 nm times the pixel aperture on :func:`_dtft`'s frequencies."""
    from ..optics.diffraction import diffraction_mtf

    f = np.linspace(0.0, 1.0, 401)
    return np.abs(np.sinc(f)) * diffraction_mtf(f / (pixel_pitch_um * 1e-3), 550.0, f_number)


def edge_mtf50(lsf, f_number: float, pixel_pitch_um: float) -> float:
    """MTF50 (cy/px) of a grey slanted edge through the optics (diffraction
    at 550 nm, the pixel's box aperture) and the demosaic's phase-averaged
    line spread function ``lsf`` = (offsets px, weights): what the slanted
    edge's super-sampled ESF measures of a periodic, linear system (its
    phases averaged); the first crossing of 0.5 up to 1 cy/px."""

    offsets, weights = lsf[:2]
    f, kernel = _dtft(len(offsets), int(offsets[0]))
    h = np.abs(kernel @ weights)
    h = h / h[0] if h[0] > 0 else h
    m = h * _optics_mtf(f_number, pixel_pitch_um)
    below = np.flatnonzero(m < 0.5)
    if below.size == 0:
        return float(f[-1])
    i = int(below[0])
    return float(f[i - 1] + (m[i - 1] - 0.5) * (f[i] - f[i - 1]) / (m[i - 1] - m[i]))
