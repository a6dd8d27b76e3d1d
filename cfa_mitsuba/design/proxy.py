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
* ``noise`` (lower is better): relative rms noise of the luminance Y on a
  mid-grey after demosaicking and the colour matrix, at the objectives'
  lowest luminance (``noise_xyz``, the rms over X, Y and Z, beside it).
  Each channel's electrons on the grey follow from the exposure policy
  (:func:`grey_electrons`): under ``reference`` the most sensitive channel
  present fills 95 % of the well at the reference luminance (a W pixel
  shortens every colour pixel's exposure); under the exposure ``program``
  (the default) the time is the metered one capped at ``max_exposure_s``,
  so in dim light every CFA integrates the same time and a sensitive
  channel simply collects more.  Shot plus read noise give each balanced
  channel's relative variance v_c.  For a demosaic whose record says it is
  linear (``bilinear``, ``laplacian``) the propagation is exact
  (:func:`~.responses.demosaic_noise_gains`):
  Y at output pixel p is sum_q w_pq raw_q with w = sum_k M_kY dout_k(p) /
  draw(q), the demosaic's weights at p's CFA phase combined through the
  colour matrix's Y column M_kY, so var Y(p) = sum_q w_pq^2 v_ch(q); the
  weights are read off the demosaic itself (an impulse at each tile
  position) and var Y averaged over the tile's phases (:mod:`.responses`).
  A nonlinear demosaic gets the Laplacian's gains (its linear core,
  :func:`~.responses.linear_core`).
* ``noise_area`` (lower is better): the same Y noise referred to an area,
  sqrt(NPS(0)) / Y, what the metric ``ysnr-area`` measures (1 / it), from
  the same impulse responses (:mod:`.noise_area`): a demosaic's smoothing
  does not lower it; ``snr10_area`` the luminance where 1 / ``noise_area``
  reaches 10, as ``snr10`` below.
* ``blur`` (lower is better, px per cycle): 1 / MTF50 of a grey slanted
  edge through the optics (diffraction at 550 nm, the pixel aperture) and
  the demosaic, from the same impulse responses: a vertical edge sees each
  response summed down its columns, and the slanted edge's super-sampled
  ESF averages the tile's phases, so the measured MTF is that of the
  phase-averaged line spread function (:func:`edge_mtf50`); with
  ``edge_both`` (an objective's ``orientation = "both"``) the worse of the
  tile's and its transpose's (the near-horizontal edge); a grey edge,
  white balanced, carries no chrominance, so the colour carriers do not
  enter; the best over the objectives' demosaics.
* ``neg_capacity`` (lower is better, bit/px): minus the slanted edge's
  information capacity predicted from the same impulse responses
  (:func:`edge_capacity`): the grey edge's MTF as for ``blur``, the noise
  power spectrum each channel's noise makes through the demosaic and the
  colour matrix, the channels' noise on the edge's mean level; the best
  over the objectives' demosaics.
* ``snr10`` (lower is better, cd/m^2): the mean scene luminance at which
  the predicted YSNR (1 / ``noise``) reaches 10, ISO 12232's noise-based
  speed point.  In dim light the exposure is the same at every luminance
  (the program's capped time; the reference policy's kept one), so each
  channel's electrons are a_c L and the Y variance is
  sum_c G_c (a_c L + r^2) / (a_c L)^2 = 1 / 100, a quadratic in L:
  L = (B + sqrt(B^2 + 4 C / 100)) / (2 / 100), B = sum_c G_c / a_c,
  C = r^2 sum_c G_c / a_c^2 (G_c the demosaic's noise gains, r the read noise).
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
           "frequency_weights", "demosaic_noise_gains", "demosaic_area_noise_gains", "grey_electrons", "edge_mtf50",
           "edge_capacity", "linear_core"]

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np

from .. import spectra
from ..colorimetry import delta_e00
from ..isp.colour_matrix import electrons_per_radiance_of, fit_colour_matrix
from ..sensor.exposure_program import ExposureProgram
from .responses import (_EDGE, _gains_and_lsf, demosaic_area_noise_gains, demosaic_noise_gains,  # noqa: F401
                        edge_capacity, edge_mtf50, linear_core)

#: The proxies, each lower-is-better.
PROXY_NAMES = ("aliasing", "aliasing_h", "blur", "neg_capacity", "noise", "noise_area", "snr10", "snr10_area",
               "colour")
_F0 = 0.05
_GREY = 0.18
_AE_LEVEL = 0.95
#: The gray bar (YSNR's chart, render/charts.py): its mean reflectance is
#: 0.289, its mid-grey step 0.145 and its white 0.876, so at a mean scene
#: luminance L the measured grey sits at about 0.5 L and the brightest
#: pixel (the program's meter) at about 3.0 L.
_GREY_OF_MEAN = 0.145 / 0.289
_BRIGHT_OF_MEAN = 0.876 / 0.289


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
    # the exposure program (policy, the program's longest time, where 'reference' meters): the study's
    exposure: ExposureProgram = ExposureProgram(policy="reference")
    luminance_cd_m2: float = 100.0    # the (lowest) objective luminance the noise is predicted at
    fill_factor: float = 1.0
    demosaics: tuple = ("bilinear",)  # the noise proxy is the best (lowest) over these
    edge_luminance_cd_m2: float = 100.0       # the slanted edge's luminance (the capacity proxy's)
    edge_both: bool = False  # blur and capacity: the worse of the tile's and its transpose's (design/orientation.py)


@dataclass(frozen=True)
class ColourModel:
    """Layout-independent numbers of a set of filters (channels in the
    order given)."""

    matrix_rel: np.ndarray     # (C, 3) colour matrix / white XYZ (columns sum to 1)
    white_response: np.ndarray  # (C,) relative electrons per unit exposure from the white
    colour_de00: float
    vora_trussell: float
    luminance_share: np.ndarray  # (C,) |M_cY| / sum |M_cY|
    white_rate: np.ndarray = None  # (C,) electrons per s per m^2 of pixel per (cd/m^2 of D65) at f/0.5 (module doc)
    lum_weights: np.ndarray = None  # (C,) the Laplacian demosaic's luminance reference weights


def colour_model(qe_bands: np.ndarray, wavelengths=spectra.DEFAULT_WAVELENGTHS, *, well_e: float | None = None,
                 read_noise_e: float = 0.0) -> ColourModel:
    """The :class:`ColourModel` of (C, B) band QEs under D65; with ``well_e``
    the colour matrix is the image processor's noise-regularised fit (the
    white filling the most sensitive channel's well, isp/pipeline.py)."""
    from ..isp.colour_matrix import channel_noise, luminance_weights

    wl = spectra.validate_wavelengths(wavelengths)
    white = spectra.illuminant("D65", wl)
    epr = electrons_per_radiance_of(qe_bands, wl)
    white_e = epr @ white
    noise = None
    if well_e and np.all(white_e > 0):
        noise = channel_noise(float(well_e) * white_e / white_e.max(), read_noise_e=float(read_noise_e))
    fit = fit_colour_matrix(epr, white, wl, channel_noise=noise)
    rel = fit.matrix / fit.white_xyz[None, :]
    resp = epr @ white
    refl = spectra.training_reflectances(wl)
    radiance = refl * white[None, :]
    cam = radiance @ epr.T / resp[None, :]
    de = delta_e00(cam @ fit.matrix / fit.white_xyz[1] * fit.white_xyz[1], spectra.xyz_from_radiance(radiance, wl),
                   fit.white_xyz)
    share = np.abs(rel[:, 1]) / np.sum(np.abs(rel[:, 1]))
    rate = resp / float(spectra.luminance_cd_m2(white, wl))
    return ColourModel(rel, resp / resp.max(), float(np.mean(de)), vora_trussell(epr, white, wl), share, rate,
                       luminance_weights(epr, white, wl))


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


def grey_electrons(model: ColourModel, settings: ProxySettings, *, level_of_mean: float = _GREY_OF_MEAN,
                   bright_of_mean: float = _BRIGHT_OF_MEAN, reference_level: float = _GREY) -> np.ndarray:
    """(C,) electrons each channel collects on the measured mid-grey (module doc).

    ``reference`` / ``each``: 18 % of 95 % of the well in the most sensitive
    channel at the reference luminance, times the luminance ratio.
    ``program``: the grey's electron rate (the channels' absolute response to
    D65 at the grey's luminance, through the f-number, the pixel area and
    fill factor) times the program's time: the metered time (the brightest
    pixel's most sensitive channel at 95 % of the well) capped at
    the program's ``max_exposure_s``; gains add no electrons.  The defaults measure the
    gray bar's mid-grey; ``level_of_mean`` and ``bright_of_mean`` (the
    measured level and the brightest pixel over the scene's mean
    luminance) and ``reference_level`` (the measured reflectance) another
    chart's."""
    if settings.exposure.policy in ("reference", "each") or model.white_rate is None:
        return (reference_level * _AE_LEVEL * settings.well_e * settings.luminance_ratio
                * model.white_response / model.white_response.max())
    optics = np.pi / (1.0 + 4.0 * settings.f_number ** 2) * (settings.pixel_pitch_um * 1e-6) ** 2 * settings.fill_factor
    rate = model.white_rate * optics * settings.luminance_cd_m2   # e-/s of a D65 field at the mean luminance
    metered = _AE_LEVEL * settings.well_e / (rate.max() * bright_of_mean)
    return rate * level_of_mean * min(metered, settings.exposure.max_exposure_s)


def _noise_gains(layout_row, h, w, idx, m: ColourModel, method: str, cache: dict) -> tuple:
    key = (h, w, layout_row.tobytes(), idx, method, m.matrix_rel.tobytes())
    if key not in cache:
        lut = {j: i for i, j in enumerate(idx)}
        local = np.vectorize(lut.__getitem__)(layout_row.reshape(h, w))
        cache[key] = _gains_and_lsf(local, tuple(str(i) for i in idx), m.matrix_rel, method, m.lum_weights)
    return cache[key]


_GAIN_CACHE: dict = {}


def _snr10(gain_y: np.ndarray, per_lux: np.ndarray, read_noise_e: float, target: float = 10.0) -> float:
    """The luminance (cd/m^2) where 1 / noise reaches ``target`` (module doc)."""
    b = float(np.sum(gain_y / per_lux))
    c = float(read_noise_e) ** 2 * float(np.sum(gain_y / per_lux ** 2))
    q = 1.0 / target ** 2
    return (b + np.sqrt(b * b + 4.0 * q * c)) / (2.0 * q)


def evaluate_layouts(layouts: np.ndarray, h: int, w: int, models: dict, settings: ProxySettings) -> dict:
    """The proxies of ``layouts`` (N, h w) uint8 letter indices.

    ``models``: a function or dict from the tuple of letter indices present
    (ascending) to that set's :class:`ColourModel` (channels in that order).
    Returns {name: (N,) array} for ``aliasing``, ``aliasing_h``, ``crosstalk``, ``sampling``, ``blur``,
    ``neg_capacity``, ``noise``, ``noise_xyz``, ``noise_area``, ``snr10``, ``snr10_area``, ``colour``,
    ``vora_trussell``.
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
    present = dens > 0
    out = {name: np.zeros(n) for name in ("sampling", "aliasing_h", "noise", "noise_xyz", "noise_area", "snr10",
                                          "snr10_area", "blur", "neg_capacity", "colour", "vora_trussell")}
    dim = dataclasses.replace(settings, luminance_cd_m2=1.0,
                              luminance_ratio=1.0 / settings.exposure.reference_luminance_cd_m2)
    edge_settings = dataclasses.replace(settings, luminance_cd_m2=settings.edge_luminance_cd_m2,
                                        luminance_ratio=settings.edge_luminance_cd_m2
                                        / settings.exposure.reference_luminance_cd_m2)
    keys = present @ (1 << np.arange(k))
    for key in np.unique(keys):
        rows = np.flatnonzero(keys == key)
        idx = tuple(int(j) for j in range(k) if key >> j & 1)
        m = get(idx)
        d = dens[rows][:, idx]
        out["sampling"][rows] = np.sum(m.luminance_share[None, :] * per_channel[rows][:, idx] / d ** 2, axis=1)
        out["aliasing_h"][rows] = np.sum((1 + m.luminance_share[None, :] / d ** 2) * horizontal[rows][:, idx], axis=1)
        electrons = grey_electrons(m, settings)
        var = (electrons + settings.read_noise_e ** 2) / electrons ** 2
        per_lux = grey_electrons(m, dim)  # a_c: electrons per cd/m^2 in dim light
        mean_refl = 0.5 * (_EDGE[0] + _EDGE[1])
        edge_e = grey_electrons(m, edge_settings, level_of_mean=1.0, bright_of_mean=_EDGE[1] / mean_refl,
                                reference_level=mean_refl)
        edge_var = mean_refl ** 2 * (edge_e + settings.read_noise_e ** 2) / edge_e ** 2  # white = 1 units
        for r in rows:
            best, snr10, blur, cap, area_var, snr10_area = None, np.inf, np.inf, -np.inf, np.inf, np.inf
            for method in settings.demosaics:
                gains, lsf, nps, area = _noise_gains(layouts[r], h, w, idx, m, method, _GAIN_CACHE)
                views = [(lsf, nps)]
                if settings.edge_both:  # the near-horizontal edge: the transposed tile across a vertical one
                    views.append(_noise_gains(layouts[r].reshape(h, w).T.ravel(), w, h, idx, m, method,
                                              _GAIN_CACHE)[1:])
                blur = min(blur, max(1.0 / edge_mtf50(v[0], settings.f_number, settings.pixel_pitch_um)
                                     for v in views))
                cap = max(cap, min(edge_capacity(v[0], v[1], edge_var, _EDGE[1] - _EDGE[0], settings.f_number,
                                                 settings.pixel_pitch_um) for v in views))
                xyz_var = var @ gains
                if best is None or xyz_var[1] < best[1]:
                    best = xyz_var
                snr10 = min(snr10, _snr10(gains[:, 1], per_lux, settings.read_noise_e))
                area_var = min(area_var, float(var @ area[:, 1]))  # each its own best demosaic, as the full chain's
                snr10_area = min(snr10_area, _snr10(area[:, 1], per_lux, settings.read_noise_e))
            out["noise"][r] = np.sqrt(best[1])
            out["noise_xyz"][r] = np.sqrt(best.mean())
            out["snr10"][r] = snr10
            out["noise_area"][r] = np.sqrt(area_var)
            out["snr10_area"][r] = snr10_area
            out["blur"][r] = blur
            out["neg_capacity"][r] = -cap
        out["colour"][rows] = m.colour_de00
        out["vora_trussell"][rows] = m.vora_trussell
    out["crosstalk"] = crosstalk
    out["aliasing"] = crosstalk + out["sampling"]
    return out
