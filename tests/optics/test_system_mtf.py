"""Acceptance 3: the system MTF of an ideal slanted edge, measured from the
raw image the whole pipeline makes, equals the analytic product of the
circular-pupil diffraction MTF and the square pixel aperture within 2 % up
to Nyquist at 450, 550 and 650 nm.

Independent of the OTF code: the edge is rendered here with exact area
coverage (the render's box filter), the MTF is measured here from the
mosaic (edge-spread function -> derivative -> FFT), and the analytic MTF is
written out here from Goodman eq. 6-31 and sinc(p f).
"""

import math

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.optics import OpticsParams
from cfa_mitsuba.values import SpectralImage

N_ROWS_PER_PIXEL_SHIFT = 8  # edge slope 1/8: sample phases are exact multiples of 1/8 px


def _ramp_integral(u):
    """Antiderivative of clip(u, 0, 1)."""
    return np.where(u <= 0, 0.0, np.where(u >= 1, u - 0.5, 0.5 * u * u))


def edge_coverage(h, w, x0, slope):
    """Exact fraction of each pixel [j, j+1] x [i, i+1] right of the line
    x = x0 + slope (y - h/2): the integral over the pixel's rows of the
    clipped horizontal overlap."""
    i = np.arange(h)[:, None].astype(float)
    j = np.arange(w)[None, :].astype(float)
    a0 = j + 1 - (x0 + slope * (i - h / 2))
    return (_ramp_integral(a0) - _ramp_integral(a0 - slope)) / slope


def measure_mtf(img, x0_px, slope, rows, half=64):
    """MTF along the edge normal, cycles/pixel, from point samples of the
    edge-spread function (every 1/8 px, no binning)."""
    h, w = img.shape
    n = round(1 / slope)
    yy, xx = np.mgrid[0:h, 0:w] + 0.5
    dxh = xx - (x0_px + slope * (yy - h / 2))  # horizontal distance of each pixel centre to the edge
    sel = np.zeros_like(img, dtype=bool)
    sel[rows] = True
    sel &= np.abs(dxh) < half
    off = np.mod(dxh[sel][0] * n, 1.0)
    k = np.rint(dxh[sel] * n - off).astype(int)
    assert np.allclose((k + off) / n, dxh[sel])  # the phases really are exact
    k -= k.min()
    counts = np.bincount(k)
    assert counts.min() > 0
    esf = np.bincount(k, img[sel]) / counts
    delta = math.cos(math.atan(slope)) / n  # sample spacing along the normal, px
    lsf = np.gradient(esf)
    f = np.fft.rfftfreq(lsf.size, delta)
    mtf = np.abs(np.fft.rfft(lsf))
    mtf /= mtf[0]
    return f, mtf / np.sinc(2 * f * delta)  # undo the central difference


def analytic_mtf(f_cy_px, wavelength_nm, f_number, pitch_um, slope, fill_factor=1.0):
    """Goodman eq. 6-31 times the square pixel aperture (side sqrt(FF)
    pitches) projected on the edge normal (angle theta from the x axis)."""
    rho = f_cy_px / (pitch_um * 1e-3)  # cy/mm
    v = np.minimum(rho * wavelength_nm * 1e-6 * f_number, 1.0)
    diffraction = (2 / np.pi) * (np.arccos(v) - v * np.sqrt(1 - v * v))
    t = math.atan(slope)
    a = math.sqrt(fill_factor)
    return diffraction * np.abs(np.sinc(a * f_cy_px * math.cos(t)) * np.sinc(a * f_cy_px * math.sin(t)))


@pytest.mark.parametrize("oversample, fill_factor", [(4, 1.0), (1, 1.0), (4, 0.5), (3, 0.75)])
@pytest.mark.parametrize("wavelength", [450.0, 550.0, 650.0])
def test_edge_mtf_matches_diffraction_times_pixel(wavelength, oversample, fill_factor):
    k, hs, ws = oversample, 64, 160
    slope = 1 / N_ROWS_PER_PIXEL_SHIFT
    x0 = (ws / 2 + 0.25) * k
    cov = edge_coverage(hs * k, ws * k, x0, slope)
    wl = np.array([wavelength - 10, wavelength, wavelength + 10])
    data = np.zeros((hs * k, ws * k, 3))
    data[..., 1] = 0.05 + cov  # radiance only in the band centred on `wavelength`
    scene = SpectralImage(data, wl, {"fov_deg": 10.0, "scene_distance_m": "inf", "oversample": k})
    mono = cm.sensor.make_cfa("mono", "W", {"W": (np.array([300.0, 800.0]), np.array([0.5, 0.5]))})
    raw = cm.sensor.capture(scene, mono, noise="off", exposure_s=1e-3,
                            sensor=cm.sensor.SensorParams(fill_factor=fill_factor),
                            optics=OpticsParams(relative_illumination=False))
    assert raw.raw.shape == (hs, ws)
    f, mtf = measure_mtf(raw.raw, x0 / k, slope, slice(8, 8 + 6 * N_ROWS_PER_PIXEL_SHIFT))
    nyquist = f <= 0.5 + 1e-9
    expect = analytic_mtf(f[nyquist], wavelength, 4.0, 2.2, slope, fill_factor)
    rel = np.abs(mtf[nyquist] - expect) / expect
    print(f"{wavelength:.0f} nm K={k} FF={fill_factor}: MTF at Nyquist {mtf[nyquist][-1]:.4f} (analytic {expect[-1]:.4f}), "
          f"worst relative error up to Nyquist {rel.max() * 100:.2f} %")
    assert rel.max() < 0.02
