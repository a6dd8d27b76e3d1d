"""Colour the camera can output (issue 12.6): highlights clipped
consistently, the colour fit regularised for the capture's noise, and
output XYZ that no light has flagged."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.colorimetry import realisable, xyz_to_xy
from cfa_mitsuba.isp.colour_matrix import channel_noise, electrons_per_radiance_of, fit_colour_matrix
from synthetic_raw import WHITE, WL, synthetic_raw


def _overexposed(cfa, factor=1000.0):
    """A bright grey 1000 times past full well: every pixel at the ADC's top code."""
    raw = synthetic_raw(np.broadcast_to(0.9 * WHITE, (12, 12, WL.size)), cfa, peak_e=5000.0 * factor)
    raw.raw = np.minimum(raw.raw, 2**12 - 1)
    return raw


@pytest.mark.parametrize("cfa", ["cmy2", "bayer", "rgbw1", "cmy1"])
def test_full_wells_map_to_grey(cfa):
    out = cm.isp.process(_overexposed(cfa), "bilinear")
    assert realisable(out.xyz).all() and out.meta["isp"]["out_of_gamut_fraction"] == 0.0
    xy = xyz_to_xy(out.xyz.reshape(-1, 3))
    assert np.allclose(xy, xyz_to_xy(out.white_xyz), atol=1e-9)  # the white's chromaticity: a grey
    assert out.meta["isp"]["highlight_clipped_fraction"] > 0


def test_without_the_clip_cmy2_full_wells_leave_the_gamut():
    """The case the clip exists for: unequal clipped, white-balanced channels
    through cmy2's six-channel matrix."""
    out = cm.isp.process(_overexposed("cmy2"), "bilinear", clip_highlights=False)
    assert out.meta["isp"]["out_of_gamut_fraction"] > 0.5


def test_tikhonov_fit_is_the_expected_error_minimiser():
    """Least squares on the training responses with many independent noise
    draws of sigma_c per channel converges to the Tikhonov fit with
    lambda_c = K sigma_c^2 (plain fit; white-preserving adds a constraint)."""
    cfa = cm.sensor.get_cfa("cmy2")
    epr = electrons_per_radiance_of(cfa.sensitivities(WL), WL)
    sig = np.array([0.02, 0.01, 0.03, 0.02, 0.01, 0.015])
    fit = fit_colour_matrix(epr, WHITE, WL, white_preserving=False, channel_noise=sig)
    refl = spectra.training_reflectances(WL)
    rad = refl * WHITE[None, :]
    cam = rad @ epr.T / (epr @ WHITE)[None, :]
    y_white = spectra.xyz_from_radiance(WHITE, WL)[1]
    target = spectra.xyz_from_radiance(rad, WL) / y_white
    rng = np.random.default_rng(0)
    reps = 400
    noisy = np.concatenate([cam + rng.normal(0, 1, cam.shape) * sig for _ in range(reps)])
    m_mc = np.linalg.lstsq(noisy, np.tile(target, (reps, 1)), rcond=None)[0]
    got = fit.matrix / y_white
    assert np.abs(got - m_mc).max() < 0.05 * np.abs(m_mc).max()
    exact = fit_colour_matrix(epr, WHITE, WL, white_preserving=False)
    assert np.abs(exact.matrix - fit.matrix).max() > 0.2 * np.abs(exact.matrix).max()  # it does regularise
    assert fit.noise_gain.max() < exact.noise_gain.max()


def test_regularised_fit_keeps_white_and_zero_noise_is_exact():
    cfa = cm.sensor.get_cfa("cmy2")
    epr = electrons_per_radiance_of(cfa.sensitivities(WL), WL)
    white_xyz = spectra.xyz_from_radiance(WHITE, WL)
    fit = fit_colour_matrix(epr, WHITE, WL, channel_noise=channel_noise(epr @ WHITE / (epr @ WHITE).max() * 5000))
    assert np.allclose(fit.matrix.sum(axis=0), white_xyz, rtol=1e-12)
    exact = fit_colour_matrix(epr, WHITE, WL)
    assert np.array_equal(fit_colour_matrix(epr, WHITE, WL, channel_noise=np.zeros(6)).matrix, exact.matrix)
    assert fit.rank == exact.rank == 6


def test_channel_noise_is_shot_and_read_noise_at_a_mid_grey():
    n = np.array([6000.0, 1500.0])
    assert np.allclose(channel_noise(n, read_noise_e=6.2), np.sqrt(0.18 * n + 6.2**2) / n)


def test_realisable_is_the_cone_of_the_spectral_locus():
    cmfs = spectra.cmfs_xyz(WL)  # every single wavelength is a light
    assert realisable(cmfs * 10.0).all()
    assert realisable(np.array([[0.0, 0.0, 0.0], [95.05, 100.0, 108.9]])).all()
    # past the locus between green and red (x + y = 1 is the spectrum locus's far edge), and negative
    assert not realisable(np.array([[0.5, 0.6, 0.0], [-1.0, 5.0, 5.0], [1.0, -0.1, 1.0]])).any()


def test_gamut_check_off_leaves_the_share_unmeasured_and_the_image_the_same():
    """A study does not read the out-of-gamut share, so its chain turns the
    per-pixel test off: the meta says None, every value is the same; the
    chain's outputs carry None, and a bad value is refused."""
    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.study.chain import CameraChain

    raw = _overexposed("cmy2")
    on = cm.isp.process(raw, "bilinear", clip_highlights=False)
    off = cm.isp.process(raw, "bilinear", clip_highlights=False, gamut_check=False)
    assert on.meta["isp"]["out_of_gamut_fraction"] > 0.5 and off.meta["isp"]["out_of_gamut_fraction"] is None
    assert np.array_equal(on.xyz, off.xyz)
    assert {k: v for k, v in on.meta["isp"].items() if k != "out_of_gamut_fraction"} == \
        {k: v for k, v in off.meta["isp"].items() if k != "out_of_gamut_fraction"}
    assert CameraChain().process(raw, "bilinear").meta["isp"]["out_of_gamut_fraction"] is None
    with pytest.raises(CfaMitsubaError, match="gamut_check must be True or False"):
        cm.isp.process(raw, "bilinear", gamut_check="no")
