"""The design proxy's noise propagation (design/proxy.py) against a
Monte-Carlo capture: a flat grey mosaic with independent per-channel noise
of known variance, many realisations, through the real demosaic and the
colour matrix."""

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.design import proxy as P
from cfa_mitsuba.design.search import fixed_models
from cfa_mitsuba.design.spectra import letter_curves

LETTERS = ("R", "G", "B")


@pytest.fixture(scope="module")
def model():
    return fixed_models(letter_curves(LETTERS, "isetcam-rgb"), LETTERS)((0, 1, 2))


def _monte_carlo(layout, method, m, rel_sd, realisations=24, reps=36, seed=0):
    rng = np.random.default_rng(seed)
    h, w = layout.shape
    tile = P._Tile(np.array(LETTERS, dtype=object)[layout], LETTERS)
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


def test_the_exposure_program_gives_a_sensitive_channel_more_electrons_in_dim_light(model):
    """Under 'reference' the most sensitive channel fixes the exposure, so
    the channels' electrons scale with their share of the maximum; under the
    program in dim light the time is the cap for everyone, so electrons
    follow the channels' absolute rates and rise with the luminance."""
    ref = P.grey_electrons(model, P.ProxySettings(policy="reference", luminance_ratio=0.1))
    assert ref.max() == pytest.approx(0.18 * 0.95 * 6200 * 0.1)
    dim = P.ProxySettings(policy="program", luminance_cd_m2=3.0, max_exposure_s=1 / 30)
    e3 = P.grey_electrons(model, dim)
    e30 = P.grey_electrons(model, P.ProxySettings(policy="program", luminance_cd_m2=30.0, max_exposure_s=1 / 30))
    np.testing.assert_allclose(e30 / e3, 10.0, rtol=1e-12)                  # capped time: linear in light
    np.testing.assert_allclose(e3 / e3.max(), model.white_response / model.white_response.max(), rtol=1e-12)
    bright = P.grey_electrons(model, P.ProxySettings(policy="program", luminance_cd_m2=1e6))
    # bright: the metered time, the brightest pixel's best channel at 95 % of the well
    assert bright.max() * P._BRIGHT_OF_MEAN / P._GREY_OF_MEAN == pytest.approx(0.95 * 6200)
