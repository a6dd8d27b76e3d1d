"""The e-SFR steps of the slanted-edge MTF (ISO 12233:2014, P. D. Burns'
sfrmat3; :mod:`.mtf` states them and holds the metric): the per-row edge
centroids and the fitted edge line, the super-sampled edge spread function,
its derivative's Fourier transform (the SFR), and the MTF50 readings
(ours, ISETCam's grid and Imatest's MTF50P).

Written here: no maintained Python package implements the ISO e-SFR with
sfrmat3's conventions.
"""

from __future__ import annotations

import numpy as np

from ..errors import require

def _hamming(n: int, centre: float) -> np.ndarray:
    """Hamming window of length n centred at ``centre`` (0-based), half-width
    the larger distance to an end (sfrmat's asymmetric ``ahamming``)."""
    i = np.arange(n, dtype=np.float64)
    wid = max(centre, n - 1 - centre, 1e-9)
    w = 0.54 + 0.46 * np.cos(np.pi * (i - centre) / wid)
    return np.clip(w, 0.0, None)


def _row_derivative(a: np.ndarray) -> np.ndarray:
    d = np.empty_like(a)
    d[:, 1:] = 0.5 * (a[:, 1:] - a[:, :-1])
    d[:, 0] = d[:, 1]
    return d


def _centroids(d: np.ndarray, centres) -> np.ndarray:
    nlin, npix = d.shape
    x = np.arange(npix, dtype=np.float64)
    out = np.empty(nlin)
    for r in range(nlin):
        w = d[r] * _hamming(npix, float(centres[r]))
        s = w.sum()
        out[r] = (x * w).sum() / s if s > 0 else np.nan
    return out - 0.5  # the 2-tap derivative sits half a pixel left


def _fit_edge(d: np.ndarray):
    """Edge position per row: centroid, line fit, windowed centroid, refit."""
    nlin, npix = d.shape
    rows = np.arange(nlin, dtype=np.float64)
    loc = _centroids(d, np.full(nlin, (npix - 1) / 2.0))
    ok = np.isfinite(loc)
    require(ok.sum() >= 3, "no edge found: the region has no usable edge profile in its rows")
    slope, intercept = np.polyfit(rows[ok], loc[ok], 1)
    place = np.clip(intercept + slope * rows, 0, npix - 1)
    loc = _centroids(d, place)
    ok = np.isfinite(loc)
    require(ok.sum() >= 3, "no edge found: the region has no usable edge profile in its rows")
    slope, intercept = np.polyfit(rows[ok], loc[ok], 1)
    resid = loc[ok] - (intercept + slope * rows[ok])
    return slope, intercept, float(np.sqrt(np.mean(resid ** 2)))


def _esf(a: np.ndarray, slope: float, nbin: int) -> np.ndarray:
    """4x super-sampled ESF: pixels binned by horizontal distance to the edge."""
    nlin, npix = a.shape
    nn = npix * nbin
    y, x = np.mgrid[0:nlin, 0:npix].astype(np.float64)
    offset = int(np.floor(nbin * (-(nlin - 1) * slope) + 0.5))
    span = abs(offset)
    offset = min(offset, 0)
    idx = (np.ceil((x - y * slope) * nbin) - offset).astype(np.int64).ravel()
    idx -= idx.min()
    counts = np.bincount(idx)
    sums = np.bincount(idx, weights=a.ravel())
    start = int(np.floor(0.5 * span + 0.5))
    sel_c = np.zeros(nn)
    sel_s = np.zeros(nn)
    avail = max(0, min(nn, counts.size - start))
    sel_c[:avail] = counts[start:start + avail]
    sel_s[:avail] = sums[start:start + avail]
    empty = sel_c == 0
    require(empty.mean() < 0.25, "edge analysis failed: too many empty ESF bins (edge too close to 0 or 45 degrees?)")
    esf = np.where(empty, np.nan, sel_s / np.where(empty, 1, sel_c))
    if empty.any():  # fill the rare empty bins from their neighbours
        good = np.flatnonzero(~empty)
        esf[empty] = np.interp(np.flatnonzero(empty), good, esf[good])
    return esf


def _sfr(esf: np.ndarray, nbin: int, cos_angle: float, sign: float, correct: bool = True):
    nn = esf.size
    lsf = np.empty(nn)
    lsf[1:-1] = 0.5 * (esf[2:] - esf[:-2])
    lsf[0], lsf[-1] = lsf[1], lsf[-2]
    lsf *= sign
    pos = np.clip(lsf, 0, None)
    centre = (np.arange(nn) * pos).sum() / pos.sum() if pos.sum() > 0 else nn / 2.0
    shift = int(np.floor(nn / 2.0 - centre + 0.5))  # move the LSF peak to the middle (zero fill)
    centred = np.zeros(nn)
    if shift >= 0:
        centred[shift:] = lsf[:nn - shift]
    else:
        centred[:nn + shift] = lsf[-shift:]
    centred *= _hamming(nn, (nn - 1) / 2.0)
    spec = np.abs(np.fft.fft(centred))
    nn2 = nn // 2 + 1
    require(spec[0] > 0, "edge analysis failed: the line spread function integrates to zero")
    m = spec[:nn2] / spec[0]
    k = np.arange(nn2)
    xk = 2.0 * np.pi * k / nn  # the centred difference's response is sin(x)/x
    corr = np.ones(nn2)
    if correct:
        corr[1:] = np.minimum(xk[1:] / np.sin(np.clip(xk[1:], 1e-12, np.pi - 1e-9)), 10.0)
    freq = nbin * k / (nn * cos_angle)
    return freq, m * corr


def _mtf50(freq, m):
    below = np.flatnonzero(m < 0.5)
    if below.size == 0 or below[0] == 0:
        return float(freq[-1]), False
    i = below[0]
    f0, f1, m0, m1 = freq[i - 1], freq[i], m[i - 1], m[i]
    return float(f0 + (m0 - 0.5) * (f1 - f0) / (m0 - m1)), True


def _mtf50_isetcam(freq, m, unit_per_cy_px: float, step: float = 0.2):
    """ISETCam ISO12233's MTF50 (module doc): the 0.2-step grid point, in
    the headline unit (``unit_per_cy_px`` of them per cy/px), whose
    interpolated MTF is closest to 0.5."""
    f = np.asarray(freq) * unit_per_cy_px
    nyq = 0.5 * unit_per_cy_px
    below = f < nyq
    grid = np.arange(int(np.floor(nyq / step + 1e-9)) + 1) * step
    inside = (grid >= f[below][0]) & (grid <= f[below][-1])
    dist = np.full(grid.size, np.inf)
    dist[inside] = np.abs(np.interp(grid[inside], f[below], np.asarray(m)[below]) - 0.5)
    return float(grid[int(np.argmin(dist))]) / unit_per_cy_px


def _mtf50p(freq, m, nyquist: float = 0.5):
    """(MTF50P, peak, peak frequency, found): the first frequency above the
    peak where the MTF falls below half the peak, the peak taken over
    0..``nyquist`` cy/px (beyond it aliasing, not the lens or the
    sharpening, lifts the curve).  Without overshoot the peak is the DC
    value 1 and MTF50P is MTF50 exactly."""
    band = np.flatnonzero(freq <= nyquist + 1e-12)
    ipk = int(band[np.argmax(m[band])])
    peak = float(m[ipk])
    f, v = freq[ipk:], m[ipk:] / peak
    m50p, found = _mtf50(f, v)
    return m50p, peak, float(freq[ipk]), found
