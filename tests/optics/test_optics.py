"""Optics against independent numbers: thin-lens geometry by hand, the
exit-pupil relative illumination by numerical integration, the OTF formula
against a pupil autocorrelation, the boundary and pixel-area rules."""

import math

import numpy as np
import pytest
from scipy import integrate

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.optics import (OpticsParams, compute_optics, diffraction_mtf, integrate_pixels,
                                lens_geometry, on_axis_factor, relative_illumination)
from cfa_mitsuba.values import SpectralImage

WL = cm.spectra.DEFAULT_WAVELENGTHS


def _scene(data, **meta):
    return SpectralImage(np.asarray(data, dtype=np.float64), WL[: np.shape(data)[2]] if np.shape(data)[2] != 31 else WL,
                         meta)


def test_lens_geometry_by_hand():
    # 720 px x 2.2 um = 1.584 mm behind a 10 deg field: d = w / (2 tan 5 deg);
    # thin lens 1/f = 1/s + 1/d, m = d / s, working N = N (1 + m).
    g = lens_geometry(720, 2.2, 10.0, 1.2, 4.0)
    d = 1.584e-3 / (2 * math.tan(math.radians(5)))
    assert g.image_distance_m == pytest.approx(d, rel=1e-12)
    assert g.magnification == pytest.approx(d / 1.2, rel=1e-12)
    assert 1 / g.focal_length_m == pytest.approx(1 / 1.2 + 1 / d, rel=1e-12)
    assert g.working_f_number == pytest.approx(4 * (1 + d / 1.2), rel=1e-12)
    inf = lens_geometry(720, 2.2, 10.0, math.inf, 4.0)
    assert inf.magnification == 0 and inf.focal_length_m == inf.image_distance_m


def test_on_axis_factor_matches_isetcam_example():
    # research/isetcam.md s. 2.2: f/4, scene at 1.2 m, ISETCam's 3.8628 mm
    # lens: factor ~ 0.0480.  Our formula with that magnification:
    f = 3.8628e-3
    d = 1 / (1 / f - 1 / 1.2)
    assert float(on_axis_factor(4.0, d / 1.2)) == pytest.approx(0.0480, abs=5e-5)
    assert float(on_axis_factor(4.0, 0.0)) == pytest.approx(math.pi / 65, rel=1e-12)


def _disk_irradiance(h, d, radius):
    """Irradiance (per unit radiance) at height h on a plane at distance d
    from a Lambertian disk of the given radius, parallel to it: the double
    integral of cos(t_s) cos(t_r) / rho^2 = d^2 / rho^4 over the disk."""
    def f(r, t):
        rho2 = d * d + (r * math.cos(t) - h) ** 2 + (r * math.sin(t)) ** 2
        return d * d / rho2**2 * r
    val, _ = integrate.dblquad(f, 0, 2 * math.pi, 0, radius, epsabs=0, epsrel=1e-11)
    return val


@pytest.mark.parametrize("n_w", [1.4, 4.0])
def test_relative_illumination_is_the_pupil_integral(n_w):
    d = 5e-3
    radius = d / (2 * n_w)
    heights = np.array([0.0, 1e-3, 2.5e-3, 4e-3])
    # a 1-row image whose sample centres sit at these heights
    pitch = 1e-6
    w = 2 * int(round(heights.max() / pitch)) + 2
    ri = relative_illumination((1, w), pitch, d, n_w)
    x = (np.arange(w) + 0.5 - w / 2) * pitch
    y = 0.5 * pitch
    e0 = _disk_irradiance(0.0, d, radius)
    assert e0 == pytest.approx(math.pi / (1 + 4 * n_w**2), rel=1e-9)  # the on-axis factor
    for hgt in heights[1:]:
        j = int(np.argmin(np.abs(x - hgt)))
        r = math.hypot(x[j], y)
        assert ri[0, j] == pytest.approx(_disk_irradiance(r, d, radius) / e0, rel=1e-7)


def test_relative_illumination_tends_to_cos4_for_a_small_pupil():
    d, pitch = 4e-3, 50e-6
    ri = relative_illumination((40, 60), pitch, d, 200.0)
    y = (np.arange(40) + 0.5 - 20) * pitch
    x = (np.arange(60) + 0.5 - 30) * pitch
    cos4 = (d**2 / (d**2 + y[:, None] ** 2 + x[None, :] ** 2)) ** 2
    np.testing.assert_allclose(ri, cos4, rtol=1e-4)
    assert cos4.min() < 0.9  # the test covers a real falloff


def test_diffraction_mtf_is_the_pupil_autocorrelation():
    # Independent: the OTF is the normalised overlap area of two unit disks
    # whose centres are 2v apart (Goodman eq. 6-31), computed on a grid.
    n = 801
    u = np.linspace(-1, 1, n)
    disk = (u[:, None] ** 2 + u[None, :] ** 2) <= 1
    for v in (0.1, 0.3, 0.5, 0.8):
        shift = int(round(2 * v / (u[1] - u[0])))
        overlap = np.count_nonzero(disk[:, shift:] & disk[:, :-shift]) / np.count_nonzero(disk)
        got = float(diffraction_mtf(v / (550e-6 * 4.0), 550.0, 4.0))  # rho = v * cutoff
        assert got == pytest.approx(overlap, abs=3e-3)
    assert float(diffraction_mtf(1 / (550e-6 * 4.0), 550, 4.0)) == pytest.approx(0.0, abs=1e-12)
    assert float(diffraction_mtf(1.01 / (550e-6 * 4.0), 550, 4.0)) == 0.0
    assert float(diffraction_mtf(0.0, 550, 4.0)) == 1.0


def test_uniform_field_stays_uniform_to_the_border():
    # Mirror boundaries: no ISETCam-style dark border from zero padding.
    rng = np.random.default_rng(1)
    spectrum = rng.uniform(0.01, 0.02, 31)
    data = np.broadcast_to(spectrum, (24, 40, 31))
    oi = compute_optics(_scene(data, fov_deg=10.0), OpticsParams(relative_illumination=False))
    expect = spectrum * float(on_axis_factor(4.0, oi.meta["optics"]["magnification"]))
    np.testing.assert_allclose(oi.irradiance_w_m2_nm, np.broadcast_to(expect, (24, 40, 31)), rtol=1e-12)


def test_diffraction_conserves_power_and_blurs():
    # K = 3: the EXR's Nyquist (682 cy/mm) lies above the f/4 cutoff at
    # 400 nm (625 cy/mm), so the OTF is not truncated and the PSF of a point
    # is non-negative: nothing is clipped and the power is conserved.
    data = np.zeros((48, 48, 31))
    data[24, 24] = 1.0
    from cfa_mitsuba.optics import apply_diffraction

    raw_psf = apply_diffraction(np.moveaxis(data, 2, 0).copy(), WL, 2.2 / 3, 4.0)
    assert raw_psf.min() > -1e-12
    oi = compute_optics(_scene(data, fov_deg=10.0, scene_distance_m="inf", oversample=3),
                        OpticsParams(relative_illumination=False))
    e = oi.irradiance_w_m2_nm / np.asarray(oi.meta["on_axis_factor"])
    np.testing.assert_allclose(e.sum(axis=(0, 1)), 1.0, rtol=1e-9)  # mirror: nothing leaks out
    assert e[24, 24, 30] < e[24, 24, 0] < 1  # red blurs more than blue


def test_truncated_otf_rings_little_and_is_clipped():
    # K = 1: the OTF is cut at the 227 cy/mm Nyquist; a single bright EXR
    # pixel then rings below zero by < 2 % of its peak, which is clipped.
    data = np.zeros((32, 32, 31))
    data[16, 16] = 1.0
    from cfa_mitsuba.optics import apply_diffraction

    raw_psf = apply_diffraction(np.moveaxis(data, 2, 0).copy(), WL, 2.2, 4.0)
    assert -0.02 < (raw_psf.min(axis=(1, 2)) / raw_psf.max(axis=(1, 2))).min() < 0
    oi = compute_optics(_scene(data, scene_distance_m="inf"), OpticsParams(relative_illumination=False))
    assert oi.irradiance_w_m2_nm.min() == 0.0


def test_integrate_pixels_block_mean_and_k1_identity():
    rng = np.random.default_rng(2)
    a = rng.uniform(size=(8, 12, 3))
    assert integrate_pixels(a, 1, 1.0) is a
    np.testing.assert_allclose(integrate_pixels(a, 4, 1.0)[1, 2], a[4:8, 8:12].mean(axis=(0, 1)))


@pytest.mark.parametrize("k", [1, 3, 4])
@pytest.mark.parametrize("ff", [0.5, 0.75])
def test_fill_factor_aperture_is_exact_on_band_limited_fields(k, ff):
    # A field that the mirror extension keeps smooth: E(x, y) = 1 + 0.4
    # cos(pi u x / X) cos(pi v y / Y) on [0, X] x [0, Y] (pixel units).  Its
    # EXR samples are exact box averages over each sub-sample; the pixel
    # value is the exact average over the centred aperture of side sqrt(FF):
    # each cosine factor is multiplied by sinc(side f), f = u / (2 X).
    hs, ws = 10, 12
    side = math.sqrt(ff)

    def box_avg_cos(m, n_px, centres, width):  # mean of cos(pi m x / L) over [c - width/2, c + width/2]
        return np.cos(np.pi * m * centres / n_px) * np.sinc(m / (2 * n_px) * width)

    for u, v in ((1, 2), (5, 3), (9, 7)):
        ys = (np.arange(hs * k) + 0.5) / k
        xs = (np.arange(ws * k) + 0.5) / k
        exr = 1 + 0.4 * np.outer(box_avg_cos(v, hs, ys, 1 / k), box_avg_cos(u, ws, xs, 1 / k))
        got = integrate_pixels(exr[..., None], k, ff)[..., 0]
        yc, xc = np.arange(hs) + 0.5, np.arange(ws) + 0.5
        expect = 1 + 0.4 * np.outer(box_avg_cos(v, hs, yc, side), box_avg_cos(u, ws, xc, side))
        np.testing.assert_allclose(got, expect, atol=1e-12)


def test_geometry_sources_and_overrides():
    data = np.full((12, 18, 31), 0.01)
    oi = compute_optics(_scene(data, fov_deg=20.0, scene_distance_m=2.0, oversample=3))
    o = oi.meta["optics"]
    assert (o["fov_deg"], o["fov_source"], o["scene_distance_source"]) == (20.0, "sidecar", "sidecar")
    assert oi.meta["oversample"] == 3 and oi.pixel_irradiance_w_m2_nm.shape == (4, 6, 31)
    assert oi.sample_pitch_um == pytest.approx(2.2 / 3)
    oi = compute_optics(_scene(data), OpticsParams(fov_deg=30.0), oversample=2)
    o = oi.meta["optics"]
    assert (o["fov_deg"], o["fov_source"], o["scene_distance_m"], o["scene_distance_source"]) == \
        (30.0, "option", 1.2, "default")
    assert (o["f_number"], o["f_number_source"]) == (4.0, "default")
    assert oi.meta["oversample"] == 2
    # f-number: option, else the sidecar's (top level, else its geometry, as the thin-lens puppy records it)
    for meta, params, expect in (({"f_number": 2.8}, None, (2.8, "sidecar")),
                                 ({"geometry": {"f_number": 2.0}}, None, (2.0, "sidecar geometry")),
                                 ({"f_number": 2.8}, OpticsParams(f_number=5.6), (5.6, "option"))):
        o = compute_optics(_scene(data, **meta), params).meta["optics"]
        assert (o["f_number"], o["f_number_source"]) == expect
        assert o["working_f_number"] == pytest.approx(expect[0] * (1 + o["magnification"]))


@pytest.mark.parametrize("k, needle", [(5, "does not divide"), (0, "positive integer"), (1.5, "positive integer"),
                                       (True, "positive integer")])
def test_bad_oversample_is_refused(k, needle):
    with pytest.raises(CfaMitsubaError, match=needle):
        compute_optics(_scene(np.ones((12, 18, 31))), oversample=k)


@pytest.mark.parametrize("value, needle", [(-1.0, "negative"), (np.nan, "NaN")])
def test_bad_radiance_is_refused(value, needle):
    data = np.ones((4, 4, 31))
    data[1, 1, 3] = value
    with pytest.raises(CfaMitsubaError, match=needle):
        compute_optics(_scene(data))


@pytest.mark.parametrize("kw, needle", [({"f_number": 0}, "f-number"), ({"lens_transmittance": 1.5}, "transmittance"),
                                        ({"fov_deg": 180}, "field of view"), ({"scene_distance_m": -1}, "distance")])
def test_bad_optics_settings_are_refused(kw, needle):
    with pytest.raises(CfaMitsubaError, match=needle):
        OpticsParams(**kw)


def test_per_band_transmittance_scales_bands():
    t = np.linspace(0.5, 1.0, 31)
    data = np.full((8, 8, 31), 0.02)
    a = compute_optics(_scene(data), OpticsParams(relative_illumination=False))
    b = compute_optics(_scene(data), OpticsParams(relative_illumination=False, lens_transmittance=tuple(t)))
    np.testing.assert_allclose(b.irradiance_w_m2_nm, a.irradiance_w_m2_nm * t, rtol=1e-12)


def test_doctests():
    import doctest

    from cfa_mitsuba.optics import diffraction, lens

    for mod in (lens, diffraction):
        result = doctest.testmod(mod)
        assert result.attempted > 0, f"{mod.__name__} has no example to run"
        assert result.failed == 0
