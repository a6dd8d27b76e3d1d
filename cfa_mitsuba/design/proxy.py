"""The fast proxy: three numbers per candidate, vectorised over layouts.

* ``aliasing`` (lower is better), the layout's spatial-frequency structure.
  A mosaic is sum_c m_c(x) I_c(x); the tile's periodic masks m_c have
  spectral lines at the frequencies f of the tile's reciprocal lattice, of
  amplitude F_c(f) (the masks' DFT over the tile, F_c(0) = d_c, the
  density).  Two terms (Alleysson, Susstrunk & Herault 2005; Hirakawa &
  Wolfe 2008):

  - crosstalk: the chrominance carriers.  Since sum_c m_c = 1, a grey
    scene has no carrier; colour is modulated onto each f != 0 with
    energy sum_c |F_c(f)|^2, and it collides with the luminance there.
    Cost sum_{f != 0} S(f) sum_c |F_c(f)|^2;
  - sampling: each channel on its own lattice (what a per-channel
    interpolation sees): replicas of relative amplitude F_c(f) / d_c, cost
    sum_c w_c sum_{f != 0} S(f) |F_c(f) / d_c|^2, w_c the channel's share of
    luminance in the colour matrix.

  S(f) is the luminance power that reaches frequency f (cycles per pixel):
  a natural-image spectrum 1 / (|f|^2 + f0^2) (f0 = 0.05) times the squared
  system MTF (diffraction at 550 nm at the study's f-number, times the
  pixel aperture's sinc), so a carrier the lens already suppresses costs
  little.  aliasing = crosstalk + sampling.  ``aliasing_h`` is the same sum
  over the carriers with f_y = 0 only: what a near-vertical slanted edge
  measures (its profile varies along x; a carrier with f_y != 0 puts its
  alias at a vertical frequency that the edge's projection averages out),
  so a tile with a luminance-heavy channel in full columns scores worse
  than its transpose.
* ``noise`` (lower is better): relative rms noise of the luminance Y on an
  18 % grey after the colour matrix, at the objectives' lowest luminance
  (``noise_xyz``, the rms over X, Y and Z, is reported beside it).  Each
  channel's electrons follow from its response to the scene white and the
  auto exposure (the most sensitive channel present fills 95 % of the well
  at the reference luminance: a W pixel shortens every colour pixel's
  exposure), shot plus read noise; a channel's noise is carried into the
  image by interpolation: a 5 x 5 binomial normalised convolution of its
  samples, whose variance factor g_c (1 at a sample, sum w^2 / (sum w)^2
  between samples) is averaged over the tile.
* ``colour`` (lower is better): mean CIEDE2000 of the 190 training
  reflectances after the white-preserving colour fit (what the ISP does,
  :func:`cfa_mitsuba.isp.colour_matrix.fit_colour_matrix`); the Vora-Trussell
  mu-factor (1 = the filters span the colour-matching functions; JOSA A
  10(7) 1993) is reported beside it.

Layout-independent parts (fit, responses) are computed once per set of
letters present (:class:`ColourModel`).
"""

from __future__ import annotations

__all__ = ["ProxySettings", "ColourModel", "colour_model", "evaluate_layouts", "PROXY_NAMES",
           "frequency_weights"]

import functools
from dataclasses import dataclass

import numpy as np

from .. import spectra
from ..colorimetry import delta_e00
from ..isp.colour_matrix import electrons_per_radiance_of, fit_colour_matrix

#: The proxies, each lower-is-better.
PROXY_NAMES = ("aliasing", "aliasing_h", "noise", "colour")
_F0 = 0.05
_GREY = 0.18
_AE_LEVEL = 0.95


@dataclass(frozen=True)
class ProxySettings:
    """What the proxy takes from the study: the optics' f-number and pixel
    pitch (um) for S(f); the well (e-), read noise (e- rms) and the
    luminance ratio to the auto-exposure reference (1 under 'each')."""

    f_number: float = 4.0
    pixel_pitch_um: float = 2.2
    well_e: float = 6200.0
    read_noise_e: float = 6.2
    luminance_ratio: float = 1.0


@dataclass(frozen=True)
class ColourModel:
    """Layout-independent numbers of a set of filters (channels in the
    order given)."""

    matrix_rel: np.ndarray     # (C, 3) colour matrix / white XYZ (columns sum to 1)
    white_response: np.ndarray  # (C,) relative electrons per unit exposure from the white
    colour_de00: float
    vora_trussell: float
    luminance_share: np.ndarray  # (C,) |M_cY| / sum |M_cY|


def colour_model(qe_bands: np.ndarray, wavelengths=spectra.DEFAULT_WAVELENGTHS) -> ColourModel:
    """The :class:`ColourModel` of (C, B) band QEs under D65."""
    wl = spectra.validate_wavelengths(wavelengths)
    white = spectra.illuminant("D65", wl)
    epr = electrons_per_radiance_of(qe_bands, wl)
    fit = fit_colour_matrix(epr, white, wl)
    rel = fit.matrix / fit.white_xyz[None, :]
    resp = epr @ white
    refl = spectra.training_reflectances(wl)
    radiance = refl * white[None, :]
    cam = radiance @ epr.T / resp[None, :]
    de = delta_e00(cam @ fit.matrix / fit.white_xyz[1] * fit.white_xyz[1], spectra.xyz_from_radiance(radiance, wl),
                   fit.white_xyz)
    share = np.abs(rel[:, 1]) / np.sum(np.abs(rel[:, 1]))
    return ColourModel(rel, resp / resp.max(), float(np.mean(de)), vora_trussell(epr, white, wl), share)


def vora_trussell(epr: np.ndarray, white: np.ndarray, wavelengths) -> float:
    """The mu-factor: trace(P_A P_S) / 3, P_A the projector on the span of
    the illuminant-weighted colour-matching functions, P_S on the span of the
    illuminant-weighted channel responses (Vora & Trussell 1993)."""
    cmf = spectra.cmfs_xyz(wavelengths) * white[:, None]
    sens = (epr * white[None, :]).T

    def proj(a):
        q, r = np.linalg.qr(a)
        keep = np.abs(np.diag(r)) > 1e-12 * np.abs(r).max()
        q = q[:, keep]
        return q @ q.T

    return float(np.trace(proj(cmf) @ proj(sens)) / 3.0)


@functools.lru_cache(maxsize=32)
def frequency_weights(h: int, w: int, f_number: float, pixel_pitch_um: float) -> np.ndarray:
    """(h, w) S(f) on the tile's reciprocal lattice (module doc), 0 at f = 0."""
    from ..optics.diffraction import diffraction_mtf

    fy = np.fft.fftfreq(h)[:, None]
    fx = np.fft.fftfreq(w)[None, :]
    f = np.hypot(fy, fx)
    otf = diffraction_mtf(f / (pixel_pitch_um * 1e-3), 550.0, f_number) * np.sinc(fy) * np.sinc(fx)
    s = otf ** 2 / (f ** 2 + _F0 ** 2)
    s[0, 0] = 0.0
    return s


@functools.lru_cache(maxsize=8)
def _kernel() -> np.ndarray:
    b = np.array([1.0, 4.0, 6.0, 4.0, 1.0])
    return np.outer(b, b) / 256.0


def interpolation_gain(masks: np.ndarray) -> np.ndarray:
    """(N, K) mean variance factor of each channel after a 5 x 5 binomial
    normalised convolution of its samples (masks (N, K, h, w) float, periodic)."""
    kern = _kernel()
    s1 = np.zeros_like(masks)
    s2 = np.zeros_like(masks)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            rolled = np.roll(masks, (dy, dx), axis=(2, 3))
            wgt = kern[dy + 2, dx + 2]
            s1 += wgt * rolled
            s2 += wgt * wgt * rolled
    with np.errstate(divide="ignore", invalid="ignore"):
        between = np.where(s1 > 0, s2 / np.maximum(s1, 1e-300) ** 2, 1.0)
    g = np.where(masks > 0, 1.0, between)
    return g.mean(axis=(2, 3))


def evaluate_layouts(layouts: np.ndarray, h: int, w: int, models: dict, settings: ProxySettings) -> dict:
    """The proxies of ``layouts`` (N, h w) uint8 letter indices.

    ``models``: a function or dict from the tuple of letter indices present
    (ascending) to that set's :class:`ColourModel` (channels in that order).
    Returns {name: (N,) array} for ``aliasing``, ``aliasing_h``, ``crosstalk``, ``sampling``,
    ``noise``, ``noise_xyz``, ``colour``, ``vora_trussell``.
    """
    layouts = np.atleast_2d(np.asarray(layouts, dtype=np.uint8))
    n = len(layouts)
    k = int(layouts.max()) + 1 if n else 1
    get = models if callable(models) else models.__getitem__
    masks = np.stack([(layouts == j) for j in range(k)], axis=1).reshape(n, k, h, w).astype(np.float64)
    dens = masks.mean(axis=(2, 3))
    spec = np.fft.fft2(masks, axes=(2, 3)) / (h * w)
    power = np.abs(spec) ** 2
    s = frequency_weights(h, w, float(settings.f_number), float(settings.pixel_pitch_um))
    per_channel = np.einsum("nkij,ij->nk", power, s)
    crosstalk = per_channel.sum(axis=1)
    horizontal = np.einsum("nkj,j->nk", power[:, :, 0, :], s[0, :])  # carriers with f_y = 0
    gain = interpolation_gain(masks)
    present = dens > 0
    out = {name: np.zeros(n) for name in ("sampling", "aliasing_h", "noise", "noise_xyz",
                                                  "colour", "vora_trussell")}
    keys = present @ (1 << np.arange(k))
    for key in np.unique(keys):
        rows = np.flatnonzero(keys == key)
        idx = tuple(int(j) for j in range(k) if key >> j & 1)
        m = get(idx)
        d = dens[rows][:, idx]
        out["sampling"][rows] = np.sum(m.luminance_share[None, :] * per_channel[rows][:, idx] / d ** 2, axis=1)
        out["aliasing_h"][rows] = np.sum((1 + m.luminance_share[None, :] / d ** 2) * horizontal[rows][:, idx], axis=1)
        electrons = (_GREY * _AE_LEVEL * settings.well_e * settings.luminance_ratio
                     * m.white_response / m.white_response.max())
        var = (electrons + settings.read_noise_e ** 2) / electrons ** 2
        xyz_var = (gain[rows][:, idx] * var[None, :]) @ (m.matrix_rel ** 2)
        out["noise"][rows] = np.sqrt(xyz_var[:, 1])
        out["noise_xyz"][rows] = np.sqrt(xyz_var.mean(axis=1))
        out["colour"][rows] = m.colour_de00
        out["vora_trussell"][rows] = m.vora_trussell
    out["crosstalk"] = crosstalk
    out["aliasing"] = crosstalk + out["sampling"]
    return out
