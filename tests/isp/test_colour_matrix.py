"""White balance, the N x 3 colour fit, its condition number and noise gain,
sRGB; colour error of every CFA's fit on a set it was not fitted on."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.isp.colour_matrix import electrons_per_radiance_of, white_response

WL = spectra.DEFAULT_WAVELENGTHS
D65 = spectra.illuminant("D65", WL)
WHITE = D65 * (100.0 / spectra.luminance_cd_m2(D65, WL))  # 100 cd/m^2 white


def epr_of(name, scale=1e20, spectra=None):
    return electrons_per_radiance_of(cm.sensor.get_cfa(name, spectra=spectra).sensitivities(WL), WL) * scale


#: CFAs with at least three channels (rccc and mono cannot reproduce colour)
COLOUR_CFAS = [n for n in cm.sensor.list_cfas() if len(cm.sensor.get_cfa(n).channels) >= 3]


def test_white_balance_makes_white_one():
    epr = epr_of("rgbw2")
    g = cm.isp.white_balance_gains(epr, WHITE)
    assert np.allclose(g * white_response(epr, WHITE), 1.0, rtol=1e-14)


def test_white_balance_refuses_blind_channel():
    epr = epr_of("bayer")
    epr[2] = 0.0
    with pytest.raises(cm.CfaMitsubaError, match="channel 2 collects no signal"):
        cm.isp.white_balance_gains(epr, WHITE)


@pytest.mark.parametrize("name", cm.sensor.list_cfas())
def test_white_preserving_fit_maps_white_exactly(name):
    fit = cm.isp.fit_colour_matrix(epr_of(name), WHITE, WL)
    n = len(cm.sensor.get_cfa(name).channels)
    assert fit.matrix.shape == (n, 3)
    assert np.allclose(np.ones(n) @ fit.matrix, spectra.xyz_from_radiance(WHITE, WL), rtol=1e-10)
    assert np.allclose(fit.white_xyz[1], 100.0)
    assert np.isfinite(fit.condition_number) and fit.condition_number >= 1
    assert np.all(fit.noise_gain > 0)


def test_fit_is_independent_of_the_exposure_scale():
    a = cm.isp.fit_colour_matrix(epr_of("cmy3", 1.0), WHITE, WL)
    b = cm.isp.fit_colour_matrix(epr_of("cmy3", 1e6), WHITE, WL)
    assert np.allclose(a.matrix, b.matrix, rtol=1e-9)


def test_least_squares_fit_is_the_unconstrained_optimum():
    epr = epr_of("bayer")
    free = cm.isp.fit_colour_matrix(epr, WHITE, WL, white_preserving=False)
    tied = cm.isp.fit_colour_matrix(epr, WHITE, WL)
    assert not free.white_preserving and tied.white_preserving
    assert free.rms_error_training <= tied.rms_error_training
    # independent solution of the normal equations
    refl = spectra.training_reflectances(WL)
    rad = refl * WHITE
    cam = rad @ epr.T / white_response(epr, WHITE)
    m = np.linalg.solve(cam.T @ cam, cam.T @ spectra.xyz_from_radiance(rad, WL))
    assert np.allclose(free.matrix, m, rtol=1e-8)


def test_complementary_and_stacked_dyes_amplify_noise():
    """Physics, reported rather than hidden: CMY subtract channels."""
    g = {n: cm.isp.fit_colour_matrix(epr_of(n), WHITE, WL) for n in ("bayer", "cmy1", "cmy2")}
    assert g["cmy1"].noise_gain[1] > g["bayer"].noise_gain[1]
    assert g["cmy2"].condition_number > 3 * g["bayer"].condition_number


def _chart_de(epr):
    fit = cm.isp.fit_colour_matrix(epr, WHITE, WL)
    _, chart = spectra.colorchecker(WL)
    rad = chart * WHITE
    cam = rad @ epr.T / white_response(epr, WHITE)
    return cm.isp.delta_e00(fit.apply(cam), spectra.xyz_from_radiance(rad, WL), fit.white_xyz)


@pytest.mark.parametrize("name", COLOUR_CFAS)
def test_colour_error_on_the_chart_not_fitted(name):
    """Fitted on the 190 training reflectances, tested on the 24
    ColorChecker patches (the benchmark prints both directions), with the
    Nikon camera's filters (a camera made to reproduce colour)."""
    de = _chart_de(epr_of(name, spectra="nikon-d5100"))
    assert de.mean() < 2.0 and de.max() < 6.0, (de.mean(), de.max())


@pytest.mark.parametrize("name", COLOUR_CFAS)
def test_colour_error_with_the_family_filters(name):
    """With each layout's own spectra set the filters decide (measured mean
    dE00: RGB 2.57, RYYB 2.37, CMY1 2.17, RGBW 1.57, RCCB 1.49, CMY3 1.10,
    CMY2 0.30; max 8.4)."""
    de = _chart_de(epr_of(name))
    assert de.mean() < 3.0 and de.max() < 9.0, (de.mean(), de.max())


def test_family_filters_rank_as_isetcam_found():
    """ISETCam's own fit with these filter files (isetcam-paper-check.md):
    RGBW < CMY1 < RGB in dE; with the Nikon set all three are equal."""
    fam = {n: _chart_de(epr_of(n)).mean() for n in ("rgbw1", "cmy1", "bayer")}
    assert fam["rgbw1"] < fam["cmy1"] < fam["bayer"], fam
    nik = {n: _chart_de(epr_of(n, spectra="nikon-d5100")).mean() for n in ("rgbw1", "cmy1", "bayer")}
    assert max(nik.values()) - min(nik.values()) < 1e-6, nik


@pytest.mark.parametrize("name", ["rccc", "mono"])
def test_fewer_than_three_channels_cannot_reproduce_colour(name):
    assert _chart_de(epr_of(name)).mean() > 10.0


def test_srgb_white_and_grey():
    white_xyz = spectra.xyz_from_radiance(WHITE, WL)
    # 1 to within the standard's 4-decimal XYZ -> RGB matrix
    assert np.allclose(cm.isp.xyz_to_srgb(white_xyz, white_xyz), 1.0, atol=1e-4)
    grey = cm.isp.xyz_to_srgb(0.18 * white_xyz, white_xyz)
    # IEC 61966-2-1 encoding of 0.18: 1.055 * 0.18^(1/2.4) - 0.055
    assert np.allclose(grey, 1.055 * 0.18 ** (1 / 2.4) - 0.055, atol=1e-4)
    assert np.all(cm.isp.xyz_to_srgb(np.array([-5.0, 300.0, 2.0]), white_xyz) >= 0)
    with pytest.raises(cm.CfaMitsubaError, match="white XYZ"):
        cm.isp.xyz_to_srgb(white_xyz, [1.0, 0.0, 1.0])


def test_gray_world_on_an_achromatic_scene_matches_the_illuminant():
    epr = epr_of("bayer")
    cfa = cm.sensor.get_cfa("bayer")
    e = np.broadcast_to(white_response(epr, WHITE) * 0.3, (8, 8, 3))
    mosaic = cm.isp.mosaic_image(e, cfa)
    gw = cm.isp.gray_world_gains(mosaic, cfa.masks((8, 8)), epr, WHITE)
    assert np.allclose(gw * 0.3, cm.isp.white_balance_gains(epr, WHITE), rtol=1e-12)
    # an all-black image keeps the known gains
    black = cm.isp.gray_world_gains(np.zeros((8, 8)), cfa.masks((8, 8)), epr, WHITE)
    assert np.allclose(black, cm.isp.white_balance_gains(epr, WHITE))


def test_luminance_weights_non_negative_and_fit_luminance():
    for name in ("rgb3", "cmy2", "cmy3", "rgbw1"):
        w = cm.isp.luminance_weights(epr_of(name), WHITE, WL)
        assert np.all(w >= 0) and abs(w.sum() - 1) < 1e-12


def _kkt_fit(epr):
    """The textbook white-preserving fit (KKT system on the normal
    equations): an independent solution for well-conditioned CFAs."""
    refl = spectra.training_reflectances(WL)
    rad = refl * WHITE
    cam = rad @ epr.T / white_response(epr, WHITE)
    n = epr.shape[0]
    kkt = np.block([[2 * cam.T @ cam, np.ones((n, 1))], [np.ones((1, n)), np.zeros((1, 1))]])
    rhs = np.vstack([2 * cam.T @ spectra.xyz_from_radiance(rad, WL), spectra.xyz_from_radiance(WHITE, WL)[None]])
    return np.linalg.lstsq(kkt, rhs, rcond=None)[0][:n]


@pytest.mark.parametrize("name, spectra_set, rank", [
    ("bayer", "nikon-d5100", 3), ("cmy1", "nikon-d5100", 3), ("cmy2", "nikon-d5100", 6),
    ("rgbw1", "nikon-d5100", 3), ("cmy3", "nikon-d5100", 3),
    ("bayer", None, 3), ("cmy1", None, 3), ("cmy2", None, 6), ("rgbw1", None, 4), ("cmy3", None, 4)])
def test_white_preserving_fit_equals_the_kkt_solution(name, spectra_set, rank):
    """The null-space solver gives the KKT (minimum-norm) matrix, also where
    a channel is an exact sum of others (the Nikon set's W = R + G + B,
    cmy3's G = (C + Y - M) / 2: rank 3); with the family sets rgbw1's W and
    cmy3's G are channels of their own (rank 4)."""
    epr = epr_of(name, spectra=spectra_set)
    fit = cm.isp.fit_colour_matrix(epr, WHITE, WL)
    assert np.allclose(fit.matrix, _kkt_fit(epr), rtol=0, atol=1e-8 * np.abs(fit.matrix).max())
    assert fit.rank == rank


def _near_twin_epr(eps):
    """bayer-like G R / B H with H = G (1 + eps ripple): nearly dependent."""
    g = cm.sensor.get_cfa("bayer").sensitivities(WL)
    ripple = 1.0 + eps * np.sin(2 * np.pi * (WL - 400.0) / 60.0)
    return electrons_per_radiance_of(np.vstack([g, g[1] * ripple]), WL) * 1e20


@pytest.mark.parametrize("eps", [1e-3, 1e-6, 1e-9])
def test_nearly_dependent_channels_fit_stably(eps):
    """The huge least-squares matrix is solved on the responses (not the
    normal equations, which square the condition number and used to switch
    silently to the merged solution near eps = 1e-6): the noise gain grows
    as 1 / eps, the white stays exact."""
    fit = cm.isp.fit_colour_matrix(_near_twin_epr(eps), WHITE, WL)
    assert fit.rank == 4
    assert 0.3 / eps < fit.noise_gain.min() and fit.noise_gain.max() < 3.0 / eps
    white = spectra.xyz_from_radiance(WHITE, WL)
    # exact to the rounding of summing entries of size 1 / eps
    assert np.allclose(fit.matrix.sum(axis=0), white, rtol=1e-12, atol=1e-14 * np.abs(fit.matrix).max())


def test_rcond_regularises_nearly_dependent_channels():
    fit = cm.isp.fit_colour_matrix(_near_twin_epr(1e-6), WHITE, WL, rcond=1e-4)
    same = cm.isp.fit_colour_matrix(_near_twin_epr(0.0), WHITE, WL)
    assert fit.rank == 3 and same.rank == 3
    assert np.allclose(fit.matrix, same.matrix, rtol=0, atol=1e-3)
    assert fit.noise_gain.max() < 2
    with pytest.raises(cm.CfaMitsubaError, match="rcond"):
        cm.isp.fit_colour_matrix(_near_twin_epr(0.0), WHITE, WL, rcond=-1)


@pytest.mark.parametrize("scale", [1e-250, 1e250])
def test_fit_survives_extreme_exposure_and_luminance_scales(scale):
    ref = cm.isp.fit_colour_matrix(epr_of("cmy2"), WHITE, WL)
    with np.errstate(all="raise"):  # no overflow or underflow on the way
        a = cm.isp.fit_colour_matrix(epr_of("cmy2", scale), WHITE, WL)
        b = cm.isp.fit_colour_matrix(epr_of("cmy2"), WHITE * scale, WL)
    assert np.allclose(a.matrix, ref.matrix, rtol=1e-9)
    assert np.allclose(b.matrix / scale, ref.matrix, rtol=1e-9)
    assert np.allclose(b.noise_gain, ref.noise_gain, rtol=1e-9)


def test_white_response_names_a_non_finite_response():
    epr = epr_of("bayer")
    epr[1, 3] = np.nan
    with pytest.raises(cm.CfaMitsubaError, match="channel 1's response to the scene white is not finite"):
        cm.isp.white_balance_gains(epr, WHITE)
