"""The proxy's colour error and noise as differentiable functions of the
channels' band quantum efficiencies, for a gradient search of filter
spectra (:mod:`.gradient_search`).

Every number is the one the proxy (:mod:`.proxy`) computes for a fixed
layout and a linear demosaic, written with autograd's numpy so that its
gradient with respect to the (C, B) band QE (whole-pixel: the dye's
transmittance x the common IR cut x silicon, band-averaged on the study's
grid) comes by reverse-mode differentiation of the same code, never by
finite differences (``tests/design/test_gradient.py`` checks it against
central differences within 1e-4):

* ``colour``: mean CIEDE2000 (Sharma, Wu & Dalal 2005) over a chart's
  reflectances under D65 (``macbeth``: the 24 ColorChecker patches, the
  design objective's chart; ``training``: the 190 training reflectances,
  the proxy's ``colour``), each camera colour mapped by the image
  processor's white-preserving, noise-regularised least-squares matrix
  fitted on the 190 training reflectances.  The fit is the closed form of
  :func:`cfa_mitsuba.isp.colour_matrix.fit_colour_matrix`'s: minimise
  ||A M - X||^2 + K sum_c s_c^2 ||M_c||^2 subject to 1^T M = w (Lagrange):
  M = H^-1 (A^T X - 1 mu^T), H = A^T A + K diag(s^2),
  mu^T = (1^T H^-1 A^T X - w^T) / (1^T H^-1 1), s_c the channel's
  relative noise with the white filling the most sensitive channel's well
  (Finlayson & Drew 1997, white preserving; Tikhonov regularisation);
* ``noise`` / ``noise_area``: the relative rms of Y on the gray bar's
  mid-grey at the proxy's luminance, per pixel or referred to an area:
  var Y = sum_c v_c m^T K_c m, m the matrix's Y column over the white's Y
  and K_c (C x C) the demosaic's quadratic form of channel c
  (:func:`noise_forms`: the same impulse responses as the proxy's
  ``demosaic_noise_gains`` and ``area_noise_gains``), v_c = (e_c + r^2) /
  e_c^2 from the electrons of :func:`.proxy.grey_electrons` (the study's
  exposure policy);
* ``snr10`` / ``snr10_area``: the luminance (cd/m^2) where 1 / noise
  reaches 10, the root of the proxy's quadratic (:func:`.proxy._snr10`).

The noise forms are those of ``bilinear``, whose weights do not depend on
the spectra; the Laplacian's luminance reference is fitted to the spectra
(NNLS), so its forms would move with them.

References
----------
G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference formula",
Color Res. Appl. 30(1), 2005.  G. D. Finlayson, M. S. Drew, "Constrained
least-squares regression in color spaces", J. Electronic Imaging 6(4),
1997.  D. Maclaurin, D. Duvenaud, R. P. Adams, "Autograd", ICML AutoML
workshop 2015 (the differentiation).
"""

from __future__ import annotations

__all__ = ["GradientProxy", "make_gradient_proxy", "noise_forms", "lab", "ciede2000", "OBJECTIVES", "CHARTS"]

import dataclasses
from dataclasses import dataclass

import autograd.numpy as anp
import numpy as np

from .. import spectra
from . import proxy as P
from . import responses as R

#: The differentiable objectives (all lower is better) and the charts of the colour error.
OBJECTIVES = ("colour", "noise", "noise_area", "snr10", "snr10_area")
CHARTS = ("macbeth", "training")
_EPS = 1e-12


def lab(xyz, white):
    """CIE 1976 L*a*b* of (N, 3) XYZ relative to ``white`` (3,), in autograd
    numpy (CIE 015: 216/24389, 24389/27); equal to :func:`cfa_mitsuba.colorimetry.xyz_to_lab`."""
    t = xyz / white[None, :]
    e, k = 216.0 / 24389.0, 24389.0 / 27.0
    f = anp.where(t > e, anp.maximum(t, e) ** (1.0 / 3.0), (k * t + 16.0) / 116.0)
    return anp.stack([116.0 * f[:, 1] - 16.0, 500.0 * (f[:, 0] - f[:, 1]), 200.0 * (f[:, 1] - f[:, 2])], axis=1)


def _hue(b, a):
    h = anp.arctan2(b, a)
    return anp.where(h < 0, h + 2 * np.pi, h)


def ciede2000(lab1, lab2):
    """(N,) CIEDE2000 (kL = kC = kH = 1) of two (N, 3) CIELAB arrays, in
    autograd numpy, Sharma et al. 2005 eq. 1-22; equal to
    :func:`cfa_mitsuba.colorimetry.delta_e_2000`.  Its hue branches are
    piecewise smooth: the gradient is that of the branch taken."""
    l1, a1, b1 = lab1[:, 0], lab1[:, 1], lab1[:, 2]
    l2, a2, b2 = lab2[:, 0], lab2[:, 1], lab2[:, 2]
    c7 = ((anp.sqrt(a1 ** 2 + b1 ** 2 + _EPS) + anp.sqrt(a2 ** 2 + b2 ** 2 + _EPS)) / 2.0) ** 7
    g = 0.5 * (1.0 - anp.sqrt(c7 / (c7 + 25.0 ** 7)))
    a1p, a2p = (1.0 + g) * a1, (1.0 + g) * a2
    c1p, c2p = anp.sqrt(a1p ** 2 + b1 ** 2 + _EPS), anp.sqrt(a2p ** 2 + b2 ** 2 + _EPS)
    h1p, h2p = _hue(b1, a1p), _hue(b2, a2p)
    dlp, dcp = l2 - l1, c2p - c1p
    dh = h2p - h1p
    dh = anp.where(dh > np.pi, dh - 2 * np.pi, anp.where(dh < -np.pi, dh + 2 * np.pi, dh))
    dhp = 2.0 * anp.sqrt(c1p * c2p) * anp.sin(dh / 2.0)
    lbar, cbar = (l1 + l2) / 2.0, (c1p + c2p) / 2.0
    hsum = h1p + h2p
    hbar = anp.where(anp.abs(h1p - h2p) > np.pi,
                     anp.where(hsum < 2 * np.pi, hsum / 2.0 + np.pi, hsum / 2.0 - np.pi), hsum / 2.0)
    t = (1.0 - 0.17 * anp.cos(hbar - np.pi / 6) + 0.24 * anp.cos(2 * hbar) + 0.32 * anp.cos(3 * hbar + np.pi / 30)
         - 0.20 * anp.cos(4 * hbar - 63.0 * np.pi / 180))
    dtheta = (30.0 * np.pi / 180) * anp.exp(-(((hbar * 180 / np.pi) - 275.0) / 25.0) ** 2)
    cb7 = cbar ** 7
    rc = 2.0 * anp.sqrt(cb7 / (cb7 + 25.0 ** 7))
    sl = 1.0 + 0.015 * (lbar - 50.0) ** 2 / anp.sqrt(20.0 + (lbar - 50.0) ** 2)
    sc, sh = 1.0 + 0.045 * cbar, 1.0 + 0.015 * cbar * t
    rt = -anp.sin(2 * dtheta) * rc
    return anp.sqrt((dlp / sl) ** 2 + (dcp / sc) ** 2 + (dhp / sh) ** 2 + rt * (dcp / sc) * (dhp / sh) + _EPS)


def noise_forms(layout: np.ndarray, n_channels: int, method: str = "bilinear", lag: int | None = None):
    """((C, C, C) per-pixel, (C, C, C) area) quadratic forms of a linear
    demosaic (module doc): K[c] such that the proxy's noise gain of channel
    c on output j is m_j^T K[c] m_j for the colour matrix column m_j, read
    off the demosaic's responses to an impulse at each tile position (the
    proxy's blocks, :func:`.responses._impulse_responses`)."""
    from scipy.ndimage import uniform_filter

    from ..isp import demosaic
    from .noise_area import AREA_LAG_PX

    layout = np.asarray(layout)
    h, w = layout.shape
    names = tuple(str(i) for i in range(n_channels))
    tile = R._Tile(np.asarray(names, dtype=object)[layout], names)
    bh, bw, n = R._block(h, h), R._block(w, w), h * w
    raw = np.zeros((bh, bw * n))
    r0, c0 = (bh // h // 2) * h, (bw // w // 2) * w
    for k in range(n):
        raw[r0 + k // w, k * bw + c0 + k % w] = 1.0
    out = demosaic(raw, tile, method).reshape(bh, n, bw, n_channels)
    size = 2 * int(AREA_LAG_PX if lag is None else lag) + 1
    near = uniform_filter(out, size=(size, 1, size, 1), mode="constant", cval=0.0) * size * size
    pix = np.einsum("pkqi,pkqj->kij", out, out)
    area = np.einsum("pkqi,pkqj->kij", out, near)
    forms = np.zeros((2, n_channels, n_channels, n_channels))
    for k, c in enumerate(layout.ravel()):
        forms[0, c] += pix[k] / n
        forms[1, c] += 0.5 * (area[k] + area[k].T) / n
    return forms[0], forms[1]


@dataclass(frozen=True)
class GradientProxy:
    """The constants of the differentiable proxy for one layout (module doc);
    built by :func:`make_gradient_proxy`."""

    settings: P.ProxySettings
    epr_per_qe: np.ndarray      # (B,) electrons per unit band radiance per unit QE (photons/J x band width)
    white: np.ndarray           # (B,) D65, W/(m^2 sr nm), as the proxy's ColourModel uses it
    fit_radiance: np.ndarray    # (K, B) training radiances, white Y = 1
    fit_xyz: np.ndarray         # (K, 3)
    chart_radiance: np.ndarray  # (N, B) the colour objective's chart, white Y = 1
    chart_lab: np.ndarray       # (N, 3) its true CIELAB
    white_xyz: np.ndarray       # (3,) white, Y = 1
    forms: np.ndarray           # (C, C, C) per-pixel noise forms
    area_forms: np.ndarray      # (C, C, C) area noise forms
    chart: str = "macbeth"

    def matrix(self, qe):
        """(C, 3) the colour matrix (white Y = 1) and (C,) the white's electrons per unit exposure."""
        epr = qe * self.epr_per_qe[None, :]
        white_e = anp.dot(epr, self.white)
        s = self.settings
        n = s.well_e * white_e / anp.max(white_e)
        sig = anp.sqrt(P._GREY * n + s.read_noise_e ** 2) / n   # isp.colour_matrix.channel_noise at the 18 % grey
        white_y = anp.dot(epr, self.white / _white_y(self.white))
        cam = anp.dot(self.fit_radiance, epr.T) / white_y[None, :]
        k = cam.shape[0]
        h = anp.dot(cam.T, cam) + anp.diag(k * sig ** 2)
        g = anp.dot(cam.T, self.fit_xyz)
        ones = anp.ones(qe.shape[0])
        hg = anp.linalg.solve(h, g)
        h1 = anp.linalg.solve(h, ones)
        mu = (anp.dot(ones, hg) - self.white_xyz) / anp.dot(ones, h1)
        return hg - h1[:, None] * mu[None, :], white_e, white_y

    def colour(self, qe):
        """Mean CIEDE2000 over the chart (module doc)."""
        m, _, white_y = self.matrix(qe)
        epr = qe * self.epr_per_qe[None, :]
        cam = anp.dot(self.chart_radiance, epr.T) / white_y[None, :]
        return anp.mean(ciede2000(lab(anp.dot(cam, m), self.white_xyz), self.chart_lab))

    def _model(self, qe, white_e):
        resp = white_e
        return P.ColourModel(None, resp / anp.max(resp), 0.0, 0.0, None,
                             resp / float(spectra.luminance_cd_m2(self.white)), None)

    def _gains(self, qe, area: bool):
        m, white_e, _ = self.matrix(qe)
        my = m[:, 1] / self.white_xyz[1]
        forms = self.area_forms if area else self.forms
        return anp.stack([anp.dot(my, anp.dot(forms[c], my)) for c in range(forms.shape[0])]), white_e

    def noise(self, qe, area: bool = False):
        """Relative rms Y noise on the gray bar's mid-grey at the proxy's luminance."""
        gains, white_e = self._gains(qe, area)
        e = P.grey_electrons(self._model(qe, white_e), self.settings)
        return anp.sqrt(anp.sum(gains * (e + self.settings.read_noise_e ** 2) / e ** 2))

    def snr10(self, qe, area: bool = False):
        """The luminance (cd/m^2) of YSNR 10 (per pixel, or referred to an area)."""
        gains, white_e = self._gains(qe, area)
        s = self.settings
        dim = dataclasses.replace(s, luminance_cd_m2=1.0, luminance_ratio=1.0 / s.exposure.reference_luminance_cd_m2)
        a = P.grey_electrons(self._model(qe, white_e), dim)
        b = anp.sum(gains / a)
        c = s.read_noise_e ** 2 * anp.sum(gains / a ** 2)
        q = 1.0 / 100.0
        return (b + anp.sqrt(b * b + 4.0 * q * c)) / (2.0 * q)

    def objective(self, name: str, qe):
        """One of :data:`OBJECTIVES` of (C, B) band QE."""
        return {"colour": lambda: self.colour(qe), "noise": lambda: self.noise(qe),
                "noise_area": lambda: self.noise(qe, area=True), "snr10": lambda: self.snr10(qe),
                "snr10_area": lambda: self.snr10(qe, area=True)}[name]()


def _white_y(white):
    return float(spectra.luminance_cd_m2(white))


def make_gradient_proxy(layout: np.ndarray, n_channels: int, settings: P.ProxySettings, *, chart: str = "macbeth",
                        method: str = "bilinear") -> GradientProxy:
    """The :class:`GradientProxy` of ``layout`` ((h, w) channel indices) under
    the study's ``settings`` (:func:`.search.proxy_settings`); ``chart`` the
    colour error's reflectances (:data:`CHARTS`)."""
    wl = spectra.DEFAULT_WAVELENGTHS
    white = spectra.illuminant("D65", wl)
    y = _white_y(white)
    fit_rad = spectra.training_reflectances(wl) * (white / y)[None, :]
    refl = spectra.colorchecker(wl)[1] if chart == "macbeth" else spectra.training_reflectances(wl)
    chart_rad = refl * (white / y)[None, :]
    white_xyz = spectra.xyz_from_radiance(white, wl) / y
    forms, area = noise_forms(layout, n_channels, method)
    return GradientProxy(settings, spectra.photons_per_joule(wl) * spectra.band_widths(wl), white, fit_rad,
                         spectra.xyz_from_radiance(fit_rad, wl), chart_rad,
                         np.asarray(lab(spectra.xyz_from_radiance(chart_rad, wl), white_xyz)), white_xyz, forms,
                         area, chart)
