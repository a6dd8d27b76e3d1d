"""Shannon information capacity of a camera from one slanted-edge capture,
in bits per pixel: sharpness and noise measured on the same image.

Imatest's slanted-edge method (N. Koren, "Image information metrics from
slanted edges", Electronic Imaging 2024; Imatest documentation
"Information capacity measurements from slanted edges: equations and
algorithms", https://www.imatest.com/docs/shannon-slanted-edges/) applies
the Shannon-Hartley capacity of a channel, C = W log2(1 + S/N), per spatial
frequency and integrates it over the 2-D frequency plane inside the
Nyquist circle (isotropy assumed, as Imatest does):

    C = integral_0^{2 pi} integral_0^{f_N} log2(1 + S(f) / N(f)) f df dtheta
      = 2 pi integral_0^{0.5} log2(1 + S(f) / N(f)) f df      [bit/px]

with f in cycles per pixel (f_N = 0.5), and, in the same units
(signal value^2 per (cy/px)^2):

* S(f) = (dV / 2)^2 MTF(f)^2: the signal is a two-level pattern with the
  edge's contrast (dark and bright levels dV apart; its variance is
  (dV / 2)^2) carried by the camera's MTF; MTF(f) is the slanted edge's
  luminance e-SFR (:func:`cfa_mitsuba.metrics.mtf`, normal to the edge);
* N(f) is the noise power spectrum (NPS) of the same capture, radially
  averaged: the noise image is the edge region less the edge itself (the
  image's own 4x super-sampled edge spread function evaluated at each
  pixel's distance to the edge line: Imatest's "noise image" method), so
  noise, and any demosaicking artefact that does not follow the edge, is
  counted; NPS(fx, fy) = |DFT(n w)|^2 / sum(w^2) (w a separable Hann
  window), whose integral over the Nyquist square is the noise variance.

Why it is an objective that blur cannot game: a linear filter H applied
after the capture multiplies S and N by the same |H(f)|^2, so S / N, and
the capacity, do not change where H is not negligible; MTF50 rises with
sharpening and YSNR with blur, the capacity with neither.  Written here:
no Python package computes it.

The luminance is the MTF's (0.3 R + 0.6 G + 0.1 B of linear sRGB, the
paper's and ISETCam's weights).
"""

from __future__ import annotations

__all__ = ["RECORDS", "info_capacity", "capacity_bits_per_px", "noise_power_spectrum"]

import numpy as np

from ..errors import require
from ._common import as_image
from ._result import MetricResult
from .mtf import LUM_WEIGHTS, NBIN, edge_region, mtf
from .record import MetricRecord


def capacity_bits_per_px(freq_cy_px, signal_power, noise_power) -> float:
    """2 pi integral_0^0.5 log2(1 + S(f) / N(f)) f df (bit/px; module doc),
    by the trapezoid rule over ``freq_cy_px`` (ascending, cycles per pixel;
    the part above 0.5 ignored, 0.5 interpolated in).

    >>> f = np.linspace(0, 0.5, 501)
    >>> round(capacity_bits_per_px(f, np.full_like(f, 3.0), np.ones_like(f)), 4)  # pi/4 log2(4)
    1.5708
    """
    f = np.asarray(freq_cy_px, dtype=np.float64)
    s = np.asarray(signal_power, dtype=np.float64)
    n = np.asarray(noise_power, dtype=np.float64)
    require(f.ndim == 1 and f.size >= 2 and s.shape == f.shape and n.shape == f.shape,
            "capacity: frequency, signal and noise must be 1-D arrays of the same length (at least 2)")
    require(np.all(n > 0), "capacity: the noise power must be positive at every frequency")
    integrand = np.log2(1.0 + np.clip(s, 0.0, None) / n) * f
    inside = f <= 0.5
    x, y = f[inside], integrand[inside]
    if x[-1] < 0.5 and f[-1] > 0.5:
        x, y = np.append(x, 0.5), np.append(y, np.interp(0.5, f, integrand))
    return float(2.0 * np.pi * np.trapezoid(y, x))


def noise_power_spectrum(noise, n_bins: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Radially averaged NPS of a 2-D noise image: (bin centres in cy/px up
    to 0.5, NPS in value^2 per (cy/px)^2); the mean is removed and a
    separable Hann window applied, so that sum(NPS) / (H W) over the whole
    DFT grid is the noise variance (white noise of variance s^2: NPS = s^2)."""
    n = np.asarray(noise, dtype=np.float64)
    h, w = n.shape
    win = np.outer(np.hanning(h + 2)[1:-1], np.hanning(w + 2)[1:-1])
    spec = np.abs(np.fft.fft2((n - n.mean()) * win)) ** 2 / np.sum(win ** 2)
    f = np.hypot(np.fft.fftfreq(h)[:, None], np.fft.fftfreq(w)[None, :]).ravel()
    n_bins = n_bins or max(6, min(h, w) // 16)  # a few hundred DFT samples per bin at least
    edges = np.linspace(0.0, 0.5, n_bins + 1)
    which = np.digitize(f, edges) - 1
    keep = (which >= 0) & (which < n_bins) & (f > 0)
    sums = np.bincount(which[keep], weights=spec.ravel()[keep], minlength=n_bins)
    counts = np.bincount(which[keep], minlength=n_bins)
    centres = 0.5 * (edges[1:] + edges[:-1])
    ok = counts > 0
    return centres[ok], sums[ok] / counts[ok]


def _edge_residual(work: np.ndarray, slope: float, nbin: int) -> tuple[np.ndarray, float]:
    """(the noise image: ``work`` less its edge spread function at each
    pixel's distance to the edge line, edge step dV)."""
    nlin, npix = work.shape
    y, x = np.mgrid[0:nlin, 0:npix].astype(np.float64)
    d = x - y * slope
    idx = np.floor((d - d.min()) * nbin).astype(np.int64)
    counts = np.bincount(idx.ravel())
    sums = np.bincount(idx.ravel(), weights=work.ravel())
    good = counts > 0
    centres = (np.arange(counts.size) + 0.5) / nbin + d.min()
    esf = sums[good] / counts[good]
    model = np.interp(d, centres[good], esf)
    k = max(1, esf.size // 10)
    step = abs(float(esf[-k:].mean() - esf[:k].mean()))
    return work - model, step


def info_capacity(image, *, roi=None, reference=None, weights=LUM_WEIGHTS, nbin: int = NBIN) -> MetricResult:
    """Shannon information capacity (bit/px) of a slanted-edge capture (module doc).

    Parameters
    ----------
    image : (H, W, 3) linear RGB or (H, W) linear gray, one near-vertical or
        near-horizontal slanted edge (as :func:`cfa_mitsuba.metrics.mtf`).
    roi : ``(y0, x0, y1, x1)`` of the edge region; None finds it.
    reference : the ideal sensor's image of the same edge, used (as by
        :func:`~cfa_mitsuba.metrics.mtf`) only when the image's own edge line
        cannot be fitted.
    weights : luminance weights (R, G, B).
    nbin : the edge spread function's super-sampling (4, ISO 12233).

    Returns
    -------
    MetricResult
        Headline capacity, unit ``'bit/px'`` (higher is better).  Details:
        ``signal_power`` ((dV / 2)^2), ``noise_rms`` (of the noise image),
        ``edge_snr`` (dV over it), ``freq_cy_px``, ``mtf``, ``nps`` (the
        NPS interpolated at those frequencies), ``mtf50_cy_px``, ``roi``.

    Raises CfaMitsubaError when the image holds no noise (the capacity of a
    noise-free capture is unbounded) or no edge.

    References
    ----------
    C. E. Shannon, "A mathematical theory of communication", Bell Syst. Tech.
    J. 27 (1948); N. Koren, "Image information metrics from slanted edges",
    IS&T Electronic Imaging 2024; Imatest, "Information capacity measurements
    from slanted edges: equations and algorithms" (documentation, v23.2).

    Examples
    --------
    >>> from scipy.special import erf
    >>> y, x = np.mgrid[0:120, 0:100]
    >>> d = (x - 50 - (y - 60) * np.tan(np.radians(5))) * np.cos(np.radians(5))
    >>> edge = 0.2 + 0.6 * 0.5 * (1 + erf(d / np.sqrt(2)))
    >>> noisy = edge + 0.01 * np.random.default_rng(0).standard_normal(edge.shape)
    >>> round(float(info_capacity(noisy)), 1)
    3.0
    """
    a = as_image(image, "edge image", channels=(3,), allow_gray=True, min_size=8)
    res = mtf(a, roi=roi, reference=reference, weights=weights, nbin=nbin)
    det = res.details
    y0, x0, y1, x1 = det["roi"]
    lum = a @ np.asarray(weights, dtype=np.float64) if a.ndim == 3 else a
    work = lum[y0:y1, x0:x1]
    if det["orientation"] == "horizontal":
        work = work.T
    slope = float(np.tan(np.radians(det["edge_angle_deg"])))
    noise, step = _edge_residual(work, slope, int(nbin))
    rms = float(noise.std())
    require(rms > 1e-9 * max(step, 1e-300),
            "the edge region has no noise (a noise-free image): its information capacity is unbounded")
    rec = det["records"]["lum" if a.ndim == 3 else "gray"]
    freq, m = np.asarray(rec["freq_cy_px"]), np.asarray(rec["mtf"])
    f_nps, nps = noise_power_spectrum(noise)
    band = freq <= 0.5 + 1e-12
    freq, m = freq[band], m[band]
    n_f = np.interp(freq, f_nps, nps)
    signal = (0.5 * step) ** 2
    cap = capacity_bits_per_px(freq, signal * m ** 2, n_f)
    details = {"signal_power": signal, "noise_rms": rms, "edge_snr": step / rms, "freq_cy_px": freq, "mtf": m,
               "nps": n_f, "mtf50_cy_px": det["mtf50_cy_px"], "roi": det["roi"], "edge_source": det["edge_source"]}
    return MetricResult(cap, name="info-capacity", unit="bit/px", details=details)


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (
    MetricRecord(name="info-capacity", function=info_capacity, scenes=("slanted-edge",), inputs="linear",
                 reads=edge_region,
                 unit="bit/px", higher_is_better=True, scored=False, label="information capacity", order=42,
                 decimals=3,
                 description="Shannon information capacity of the slanted-edge capture from its MTF and noise power "
                             "spectrum (Imatest's slanted-edge method), bits per pixel"),
)
