"""Issue 22: low light as a camera meets it.  The exposure program (clipping
in bright light, time and gain in dim light), a clear pixel's electrons at
the same time and gain, YSNR against a hand calculation, and a colour
matrix that cannot make a capture worse with more light."""

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.sensor import capture
from cfa_mitsuba.sensor.exposure_program import ExposureProgram
from cfa_mitsuba.values import SpectralImage

PAPER_CFAS = ["bayer", "rgb1", "rgb2", "rgb3", "rgb4", "rgb5", "cmy1", "cmy2", "cmy3", "rgbw1", "rgbw2", "rgbw3"]
WL = np.arange(400.0, 701.0, 10.0)


@pytest.fixture(scope="module")
def puppy_oi():
    """A small puppy (120 x 106 EXR pixels, 8 spp) through the default optics."""
    img = cm.render.render_cached("puppy", width=120, height=106, spp=8)
    return cm.optics.compute_optics(img, pixel_pitch_um=2.2)


def d65_grey(luminance, h=128, w=128):
    """A uniform D65 field of ``luminance`` cd/m^2, built from colour-science
    directly (683 sum L ybar dl = luminance on the 10 nm boxes)."""
    import colour

    d65 = cm.spectra.band_average(colour.SDS_ILLUMINANTS["D65"].wavelengths, colour.SDS_ILLUMINANTS["D65"].values, WL)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    ybar = cm.spectra.band_average(cmfs.wavelengths, cmfs.values[:, 1], WL)
    rad = d65 * luminance / (683.0 * np.sum(d65 * ybar * 10.0))
    meta = {"fov_deg": 10.0, "scene_distance_m": 1.2}
    return SpectralImage(np.broadcast_to(rad, (h, w, WL.size)).copy(), WL, meta), rad


def test_program_never_clips_the_puppy_at_400_and_runs_out_of_time_at_3(puppy_oi):
    """Acceptance 1: no paper CFA clips more than 0.1 % of the puppy's pixels
    at 400 cd/m^2; at 3 cd/m^2 every CFA is at the longest time, with gain."""
    for cfa in PAPER_CFAS:
        bright = capture(puppy_oi, cfa, luminance_cd_m2=400.0, seed=1)
        assert bright.meta["clipped_fraction"] <= 1e-3, (cfa, bright.meta["clipped_fraction"])
        assert bright.settings["exposure_policy"] == "program"
        dim = capture(puppy_oi, cfa, luminance_cd_m2=3.0, seed=1)
        assert dim.exposure_s == pytest.approx(ExposureProgram().max_exposure_s, rel=1e-12), cfa
        assert dim.settings["analog_gain"] * dim.settings["digital_gain"] > 1.0, cfa
        # the gains make up exactly what the time could not: the metered time at base gain
        total = dim.exposure_s * dim.settings["analog_gain"] * dim.settings["digital_gain"]
        assert total == pytest.approx(dim.settings["metered_exposure_s"], rel=1e-9)
    # the old rule (ISETCam's exposure chosen at 100 cd/m^2 and kept) clips the same scene at 400
    kept = capture(puppy_oi, "bayer", luminance_cd_m2=400.0, seed=1, exposure_policy="reference")
    assert kept.meta["clipped_fraction"] > 0.01


def test_program_steps_time_then_analogue_then_digital_gain():
    assert ExposureProgram().choose(0.01).exposure_s == 0.01
    small = ExposureProgram(max_exposure_s=0.02, max_analog_gain=4.0)
    c = small.choose(0.1)
    assert (c.exposure_s, c.analog_gain, c.digital_gain) == (0.02, 4.0, pytest.approx(1.25))
    c = small.choose(0.06)
    assert (c.analog_gain, c.digital_gain) == (pytest.approx(3.0), 1.0)
    with pytest.raises(CfaMitsubaError, match="max_analog_gain"):
        ExposureProgram(max_analog_gain=0.5)
    with pytest.raises(CfaMitsubaError, match="unknown exposure policy 'sometimes'"):
        ExposureProgram("sometimes")


def test_bayer_protocol_gives_every_cfa_bayers_time_and_gain(puppy_oi):
    ref = capture(puppy_oi, "bayer", luminance_cd_m2=3.0, seed=1)
    for cfa in ("rgbw1", "cmy2"):
        r = capture(puppy_oi, cfa, luminance_cd_m2=3.0, seed=1, exposure_policy="bayer")
        assert r.exposure_s == ref.exposure_s
        assert r.settings["analog_gain"] == ref.settings["analog_gain"]
        assert r.settings["digital_gain"] == ref.settings["digital_gain"]


def test_a_clear_pixel_collects_more_than_green_by_the_ratio_of_qe_integrals():
    """Acceptance 2: at the same time and gain (one rgbw1 capture under the
    bayer protocol, at low light where the gain is above 1), a W pixel on a
    grey collects W/G = sum QE_W L lambda / sum QE_G L lambda more
    electrons than the G beside it, within 2 %."""
    scene, rad = d65_grey(3.0, 32, 32)
    cfa = cm.sensor.get_cfa("rgbw1")
    raw = capture(scene, cfa, noise="off", exposure_policy="bayer")
    assert raw.settings["analog_gain"] > 1.0
    electrons = raw.raw / raw.dn_per_electron
    pattern = np.asarray(raw.pattern)
    (wi, wj), = np.argwhere(pattern == "W")[:1]
    (gi, gj), = np.argwhere(pattern == "G")[:1]
    th, tw = pattern.shape
    c0 = (16 // th) * th, (16 // tw) * tw  # a tile at the centre (no off-axis falloff between them)
    e_w, e_g = electrons[c0[0] + wi, c0[1] + wj], electrons[c0[0] + gi, c0[1] + gj]
    qe = dict(zip(cfa.channels, cfa.sensitivities(WL)))
    expected = np.sum(qe["W"] * rad * WL) / np.sum(qe["G"] * rad * WL)  # photons ~ energy x lambda
    assert e_w > e_g
    assert e_w / e_g == pytest.approx(expected, rel=0.02)


def _bilinear_variance_factor():
    """Mean over a Bayer tile of the sum of squared bilinear weights per
    channel (independent pixel noise through the interpolation): G 1 at its
    own sites and 4 x (1/4)^2 elsewhere -> 0.625; R and B 1, 2 x (1/2)^2
    (twice), 4 x (1/4)^2 -> 0.5625."""
    return {"G": (2 * 1.0 + 2 * 0.25) / 4, "R": (1.0 + 2 * 0.5 + 0.25) / 4, "B": (1.0 + 2 * 0.5 + 0.25) / 4}


def test_bayer_ysnr_on_mid_grey_matches_the_hand_calculation():
    """Acceptance 3: YSNR on a mid-grey after demosaic and colour matrix
    against sigma_Y^2 = sum_c M_cY^2 g_c^2 f_c (e_c + r^2 + q^2 / 12):
    e_c the channel's electrons (photo and dark), r the read noise,
    q the ADC step in electrons (before the digital gain), g_c the
    white-balance gain, f_c the bilinear interpolation's variance factor,
    M the colour matrix's Y column; within 5 %."""
    scene, _ = d65_grey(2.0)  # a flat field at 2 cd/m^2: the program's gain is on
    f = _bilinear_variance_factor()
    measured, hand = [], []
    for seed in range(3):
        raw = capture(scene, "bayer", luminance_cd_m2=2.0, seed=seed)
        st = raw.settings["sensor"]
        out = cm.isp.process(raw, "bilinear")
        ideal = cm.isp.process(cm.sensor.capture_ideal(scene, luminance_cd_m2=2.0))
        measured.append(float(cm.metrics.ysnr(ideal.xyz, out.xyz, ideal.white_xyz, margin=4)))
        isp = out.meta["isp"]
        m_y = np.asarray(isp["colour_matrix"])[:, 1]
        g = np.asarray(isp["white_balance_gains_per_electron"])
        pattern = np.asarray(raw.pattern)
        e = (raw.raw - raw.black_level_dn) / raw.dn_per_electron
        mean_e = np.array([e[8:-8, 8:-8][(pattern == c)[np.arange(e.shape[0] - 16)[:, None] % 2,
                                                         np.arange(e.shape[1] - 16)[None, :] % 2]].mean()
                           for c in raw.channels])
        q_e = 1.0 / st["dn_per_electron"]  # the ADC step before the digital gain (analogue gain in it)
        var_c = mean_e + st["read_noise_e"] ** 2 + q_e**2 / 12.0  # Poisson (photo + dark) + read + ADC
        var_y = sum(m_y[i] ** 2 * g[i] ** 2 * f[c] * var_c[i] for i, c in enumerate(raw.channels))
        hand.append(float(np.sum(m_y * g * mean_e) / np.sqrt(var_y)))
    print(f"YSNR measured {np.mean(measured):.3f}, by hand {np.mean(hand):.3f}")
    assert raw.settings["analog_gain"] > 1.0
    assert np.mean(measured) == pytest.approx(np.mean(hand), rel=0.05)


def test_colour_matrix_does_not_make_cmy2_worse_with_more_light(puppy_oi):
    """Acceptance 4 where the old rule failed: cmy2 under the exposure kept
    from 100 cd/m^2 (the regime of the reversal, S-CIELAB 7.6 -> 8.3 -> 10.4
    with the capture's own noise as the matrix's regularisation)."""
    from cfa_mitsuba.study.chain import CameraChain, ChainSettings
    from cfa_mitsuba.study.intervals import t_interval

    chain = CameraChain(ChainSettings(exposure_program=ExposureProgram("reference")))
    img = puppy_oi
    prev = None
    for lum in (12.0, 50.0, 100.0):
        cond = chain.settings.base_condition(luminance=lum)
        ideal = chain.ideal(img, cond)
        vals, conds = [], set()
        for seed in range(3):
            out = chain.process(chain.capture(img, "cmy2", cond, seed), "bilinear", cond)
            vals.append(float(chain.measure(ideal, out, ["scielab"], cond)[0]["scielab"]))
            conds.add(round(out.meta["isp"]["condition_number"], 9))
        mean, lo, hi, _, _ = t_interval(vals)
        assert len(conds) == 1  # one matrix whatever the noise realisation
        if prev is not None:
            assert lo <= prev[2], f"S-CIELAB worse at {lum} cd/m^2 ({mean:.3f}) than at the lower level ({prev[0]:.3f})"
            assert conds == prev[3]  # and whatever the light
        prev = (mean, lo, hi, conds)
