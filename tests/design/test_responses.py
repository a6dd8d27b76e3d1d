"""The design proxy's noise propagation (design/proxy.py) against a
Monte-Carlo capture: a flat grey mosaic with independent per-channel noise
of known variance, many realisations, through the real demosaic and the
colour matrix; per pixel, and referred to an area (design/noise_area.py)
as the metric ``ysnr-area`` measures it."""

import inspect

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.design import proxy as P
from cfa_mitsuba.design import responses as R
from cfa_mitsuba.design.search import fixed_models
from cfa_mitsuba.design.spectra import letter_curves
from cfa_mitsuba.sensor import ExposureProgram

LETTERS = ("R", "G", "B")


@pytest.fixture(scope="module")
def model():
    return fixed_models(letter_curves(LETTERS, "isetcam-rgb"), LETTERS)((0, 1, 2))


def _monte_carlo(layout, method, m, rel_sd, realisations=24, reps=36, seed=0):
    rng = np.random.default_rng(seed)
    h, w = layout.shape
    tile = R._Tile(np.array(LETTERS, dtype=object)[layout], LETTERS)
    chan = np.tile(layout, (reps, reps))
    opts = {} if method == "bilinear" else {"luminance_weights": list(m.lum_weights)}
    err = []
    for _ in range(realisations):
        raw = 0.18 * (1 + rel_sd[chan] * rng.standard_normal(chan.shape))
        xyz = cm.isp.demosaic(raw, tile, method, **opts) @ m.matrix_rel
        err.append(xyz[8:-8, 8:-8] / 0.18 - 1)
    return np.sqrt(np.mean(np.square(err), axis=(0, 1, 2)))


@pytest.mark.parametrize("method", ["bilinear", "laplacian"])
@pytest.mark.parametrize("layout", [[[1, 0], [2, 1]], [[0, 1, 2], [1, 2, 0], [2, 0, 1]], [[1, 1, 0, 2]],
                                    [[1, 0, 1], [2, 1, 2]]])
def test_propagated_noise_matches_a_monte_carlo_grey_within_two_percent(model, method, layout):
    layout = np.array(layout)
    rel_sd = np.array([0.012, 0.005, 0.02])
    gains = P.demosaic_noise_gains(layout, LETTERS, model.matrix_rel, method, model.lum_weights)
    predicted = np.sqrt(rel_sd ** 2 @ gains)
    measured = _monte_carlo(layout, method, model, rel_sd)
    np.testing.assert_allclose(predicted, measured, rtol=0.02)


LAYOUTS = [[[1, 0], [2, 1]], [[0, 1, 2], [1, 2, 0], [2, 0, 1]], [[1, 1, 0, 2]], [[1, 0, 1], [2, 1, 2]],
           [[2, 2], [2, 2], [2, 2], [1, 0]]]


@pytest.mark.parametrize("method", ["bilinear", "laplacian"])
@pytest.mark.parametrize("layout", LAYOUTS)
def test_area_noise_matches_the_metric_on_a_monte_carlo_grey_within_four_percent(model, method, layout):
    """NPS(0) of Y, as cm.metrics.ysnr measures it (``ysnr_area``: the
    autocovariance summed over lags up to 4 px), on 16 realisations of a
    ~240 x 240 px flat grey through the real demosaic and colour matrix,
    against the proxy's prediction.  The estimator's sampling error is
    about 1.5 % here; the last layout is B B / B B / B B / G R, whose
    per-pixel YSNR bilinear smoothing inflates."""
    layout = np.array(layout)
    h, w = layout.shape
    rel_sd = np.array([0.012, 0.005, 0.02])
    area = P.demosaic_area_noise_gains(layout, LETTERS, model.matrix_rel, method, model.lum_weights)
    predicted = np.sqrt(rel_sd ** 2 @ area[:, 1])             # relative Y noise x px, white = 1
    rng = np.random.default_rng(1)
    tile = R._Tile(np.array(LETTERS, dtype=object)[layout], LETTERS)
    chan = np.tile(layout, (256 // h, 256 // w))
    opts = {} if method == "bilinear" else {"luminance_weights": list(model.lum_weights)}
    nps0 = []
    for _ in range(16):
        raw = 0.18 * (1 + rel_sd[chan] * rng.standard_normal(chan.shape))
        xyz = (cm.isp.demosaic(raw, tile, method, **opts) @ model.matrix_rel)[8:-8, 8:-8]
        r = cm.metrics.ysnr(np.full_like(xyz, 0.18), xyz, [1.0, 1.0, 1.0], margin=0)
        nps0.append((r.details["ysnr_area"] / xyz[..., 1].mean()) ** -2)   # (YSNR_area / mean Y)^-2 = NPS(0)
    measured = np.sqrt(np.mean(nps0)) / 0.18
    assert predicted == pytest.approx(measured, rel=0.04)


@pytest.mark.parametrize("layout, density", [([[1, 0], [2, 1]], [0.25, 0.5, 0.25]),
                                             ([[0, 1, 2], [1, 2, 0], [2, 0, 1]], [1 / 3] * 3)])
def test_bilinear_area_noise_of_a_channel_is_its_variance_over_its_density(layout, density):
    """Bilinear with an identity matrix on tiles whose samples of a channel
    are alike: each channel's NPS(0) is v_c / d_c (Dainty & Shaw: d_c
    samples per pixel) and no channel leaks into another."""
    area = P.demosaic_area_noise_gains(np.array(layout), LETTERS, np.eye(3), "bilinear")
    np.testing.assert_allclose(area, np.diag(1.0 / np.array(density)), rtol=1e-9, atol=1e-12)


def test_smoothing_a_sparse_channel_lowers_its_pixel_noise_not_its_area_noise():
    """B B / B B / B B / G R: bilinear spreads each G sample (density 1/8)
    over eight output pixels, so a G pixel's noise gain falls well below 1
    while its area noise, over all lags, stays at least 1 / d = 8 (equal
    only if the samples were alike); the metric's 4 px of lags keep most of
    it."""
    layout = np.array([[2, 2], [2, 2], [2, 2], [1, 0]])
    pixel = P.demosaic_noise_gains(layout, LETTERS, np.eye(3), "bilinear")
    full = P.demosaic_area_noise_gains(layout, LETTERS, np.eye(3), "bilinear", lag=12)
    metric = P.demosaic_area_noise_gains(layout, LETTERS, np.eye(3), "bilinear")
    assert pixel[1, 1] < 0.5
    assert full[1, 1] >= 8.0 - 1e-9 and full[0, 0] >= 8.0 - 1e-9 and full[2, 2] >= 1 / 0.75 - 1e-9
    assert 0.9 * full[1, 1] < metric[1, 1] <= full[1, 1] + 1e-12


def test_the_area_lag_is_the_metrics():
    from cfa_mitsuba.design.noise_area import AREA_LAG_PX

    assert inspect.signature(cm.metrics.ysnr).parameters["correlation_px"].default == AREA_LAG_PX


def test_the_exposure_program_gives_a_sensitive_channel_more_electrons_in_dim_light(model):
    """Under 'reference' the most sensitive channel fixes the exposure, so
    the channels' electrons scale with their share of the maximum; under the
    program in dim light the time is the cap for everyone, so electrons
    follow the channels' absolute rates and rise with the luminance."""
    ref = P.grey_electrons(model, P.ProxySettings(exposure=ExposureProgram("reference"), luminance_ratio=0.1))
    assert ref.max() == pytest.approx(0.18 * 0.95 * 6200 * 0.1)
    dim = P.ProxySettings(exposure=ExposureProgram("program", max_exposure_s=1 / 30), luminance_cd_m2=3.0)
    e3 = P.grey_electrons(model, dim)
    e30 = P.grey_electrons(model, P.ProxySettings(exposure=ExposureProgram("program", max_exposure_s=1 / 30),
                                                  luminance_cd_m2=30.0))
    np.testing.assert_allclose(e30 / e3, 10.0, rtol=1e-12)                  # capped time: linear in light
    np.testing.assert_allclose(e3 / e3.max(), model.white_response / model.white_response.max(), rtol=1e-12)
    bright = P.grey_electrons(model, P.ProxySettings(exposure=ExposureProgram("program"), luminance_cd_m2=1e6))
    # bright: the metered time, the brightest pixel's best channel at 95 % of the well
    assert bright.max() * P._BRIGHT_OF_MEAN / P._GREY_OF_MEAN == pytest.approx(0.95 * 6200)
