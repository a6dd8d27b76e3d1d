"""Acceptance 1 (radiometry) and the ideal sensor's absolute scale, against
hand calculations that do not go through the package's code path."""

import math

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.optics import OpticsParams, compute_optics
from cfa_mitsuba.sensor import SensorParams, capture, capture_ideal
from cfa_mitsuba.values import SpectralImage

WL = np.arange(400.0, 701.0, 10.0)
H_PLANCK, C_LIGHT = 6.62607015e-34, 299792458.0


def d65_radiance(luminance):
    """D65 scaled to ``luminance`` cd/m^2, W/(m^2 sr nm), built from
    colour-science directly: 683 sum L ybar dl = luminance on the 10 nm boxes."""
    import colour

    d65 = cm.spectra.band_average(colour.SDS_ILLUMINANTS["D65"].wavelengths,
                                  colour.SDS_ILLUMINANTS["D65"].values, WL)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    ybar = cm.spectra.band_average(cmfs.wavelengths, cmfs.values[:, 1], WL)
    return d65 * luminance / (683.0 * np.sum(d65 * ybar * 10.0)), ybar


def uniform_scene(luminance=100.0, h=32, w=48, **meta):
    rad, _ = d65_radiance(luminance)
    meta = {"fov_deg": 10.0, "scene_distance_m": 1.2, **meta}
    return SpectralImage(np.broadcast_to(rad, (h, w, WL.size)).copy(), WL, meta)


def nikon_qe():
    """R, G, B QE: the NPL data scaled so that R + G + B peaks at 0.6, boxed."""
    import colour

    m = colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]
    vals = m.values * (0.6 / m.values.sum(axis=1).max())
    return cm.spectra.band_average(m.wavelengths, vals, WL).T  # (3, B)


def test_uniform_field_electrons_match_the_hand_calculation():
    lum, t, fnum, pitch, dist, fov, w_px = 100.0, 0.01, 4.0, 2.2e-6, 1.2, 10.0, 48
    rad, _ = d65_radiance(lum)
    # --- by hand -------------------------------------------------------
    d = w_px * pitch / (2 * math.tan(math.radians(fov / 2)))  # image distance: FOV fills the sensor
    m = d / dist  # magnification
    e_irr = math.pi * rad / (1 + 4 * fnum**2 * (1 + m) ** 2)  # W/(m^2 nm), on axis, T = 1
    photons = e_irr * (WL * 1e-9 / (H_PLANCK * C_LIGHT)) * 10.0  # per s per m^2 in each 10 nm box
    expect = t * pitch**2 * 1.0 * (nikon_qe() @ photons)  # electrons of R, G, B pixels (FF = 1)
    # --- through the pipeline (noise off, centre pixels: RI = 1 - 6e-5) --
    # the Nikon set: its R, G, B are the NPL data computed independently above
    raw = capture(uniform_scene(lum), cm.sensor.get_cfa("bayer", spectra="nikon-d5100"), exposure_s=t, noise="off")
    e = raw.raw / raw.dn_per_electron
    got = {"G": e[16, 24], "R": e[16, 25], "B": e[17, 24]}  # GRBG tile, even row/col is G
    for i, ch in enumerate("RGB"):
        print(f"{ch}: hand {expect[i]:.2f} e-, pipeline {got[ch]:.2f} e-, {100 * (got[ch] / expect[i] - 1):+.4f} %")
        # measured -0.019 ... -0.026 % (relative illumination 1 - 6e-5 and the band-box photon
        # conversion); 0.05 % catches a wrong factor anywhere in the chain
        assert got[ch] == pytest.approx(expect[i], rel=5e-4)
    # electrons_per_radiance predicts the same electrons for any spectrum
    np.testing.assert_allclose(raw.electrons_per_radiance @ rad, expect, rtol=5e-4)


def test_auto_exposure_on_a_uniform_field_is_exact():
    oi = compute_optics(uniform_scene(40.0), OpticsParams(relative_illumination=False))
    for name in ("bayer", "rgbw1", "cmy2"):
        r = capture(oi, name, noise="off", exposure_policy="reference")  # at 100 cd/m^2: this 40 cd/m^2 field gets 40 %
        e = r.raw / r.dn_per_electron
        assert e.max() == pytest.approx(0.4 * 0.95 * SensorParams().well_capacity_e, rel=1e-9), name
        r = capture(oi, name, noise="off", reference_luminance_cd_m2=None)  # plain ISETCam AE
        assert (r.raw / r.dn_per_electron).max() == pytest.approx(0.95 * SensorParams().well_capacity_e, rel=1e-9)


def test_doubling_exposure_or_luminance_doubles_the_signal_until_the_well():
    scene = uniform_scene(50.0)
    oi = compute_optics(scene)
    a = capture(oi, "rgbw1", exposure_s=0.004, noise="off").raw
    b = capture(oi, "rgbw1", exposure_s=0.008, noise="off").raw
    c = capture(oi, "rgbw1", exposure_s=0.004, luminance_cd_m2=100.0, noise="off").raw
    well_dn = SensorParams().well_capacity_e * SensorParams().dn_per_electron
    assert b.max() < well_dn  # not clipped yet
    print(f"exposure x2: ratio {np.median(b / a):.6f}; luminance x2: ratio {np.median(c / a):.6f}")
    np.testing.assert_allclose(b / a, 2.0, rtol=1e-3)
    np.testing.assert_allclose(c / a, 2.0, rtol=1e-3)
    # keep doubling: the signal doubles until it meets the well, then stays there
    t = 0.004
    prev = a
    while True:
        t *= 2
        cur = capture(oi, "rgbw1", exposure_s=t, noise="off").raw
        unclipped = cur < well_dn * (1 - 1e-12)
        np.testing.assert_allclose(cur[unclipped] / prev[unclipped], 2.0, rtol=1e-3)
        assert np.all(cur[~unclipped] == pytest.approx(well_dn))
        prev = cur
        if not unclipped.any():
            break


def test_auto_exposure_fills_the_brightest_pixel_to_95_percent_at_the_reference():
    rad, _ = d65_radiance(100.0)
    data = np.broadcast_to(rad, (32, 48, 31)).copy()
    data[:, 24:] *= 0.25  # half the field darker: mean luminance 62.5
    scene = SpectralImage(data, WL, {"fov_deg": 10.0, "scene_distance_m": 1.2})
    # ISETCam's rule takes the brightest pixel as an on-axis uniform field,
    # so compare with the falloff off
    oi = compute_optics(scene, OpticsParams(relative_illumination=False))
    well = SensorParams().well_capacity_e
    for name in ("bayer", "rgbw2", "cmy1"):
        r = capture(oi, name, luminance_cd_m2=100.0, noise="off", reference_luminance_cd_m2=100.0)
        e = r.raw / r.dn_per_electron
        # the bright half's most sensitive channel sits at 0.95 of the well,
        # less the 0.3 % the Airy halo carries out to the dark half 12+ px away
        assert e[8:24, 4:12].max() == pytest.approx(0.95 * well, rel=5e-3), name
        # the exposure kept from the reference: 3 cd/m^2 is 100/3 times dimmer, same exposure
        dim = capture(oi, name, luminance_cd_m2=3.0, noise="off", exposure_policy="reference")
        assert dim.exposure_s == r.exposure_s
        np.testing.assert_allclose(dim.raw, r.raw * 0.03, rtol=1e-12)
    # brighter than the reference: the bright pixels clip at the well
    bright = capture(oi, "bayer", luminance_cd_m2=200.0, noise="off", exposure_policy="reference")
    assert (bright.raw / bright.dn_per_electron).max() == pytest.approx(well)


def test_ideal_sensor_reads_absolute_xyz():
    lum = 123.0
    rad, _ = d65_radiance(lum)
    scene = uniform_scene(lum, white_radiance=rad.tolist())
    ideal = capture_ideal(scene, exposure_s="auto")
    assert ideal.raw.shape == (32, 48, 3) and ideal.is_ideal
    y = ideal.raw[15:17, 23:25, 1]
    # Y in cd/m^2 on the axis; the 2e-4 shortfall is the Airy halo carrying
    # light in from the darker off-axis field (relative illumination)
    assert y.mean() == pytest.approx(lum, rel=1e-3)
    flat = capture_ideal(scene, optics=OpticsParams(relative_illumination=False))
    np.testing.assert_allclose(flat.raw[..., 1], lum, rtol=1e-9)  # everywhere, to the borders
    import warnings

    import colour

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # colour's notices about aligning shapes
        xyz_d65 = colour.sd_to_XYZ(colour.SDS_ILLUMINANTS["D65"]) / 100  # Y = 1
    np.testing.assert_allclose(ideal.raw[16, 24] / ideal.raw[16, 24, 1], xyz_d65 / xyz_d65[1], rtol=2e-3)
    # off axis the relative illumination lowers it, as for the camera
    assert ideal.raw[0, 0, 1] < ideal.raw[16, 24, 1]
    # electrons_per_radiance is XYZ per unit radiance: K_m cmf dl
    np.testing.assert_allclose(ideal.electrons_per_radiance @ rad, flat.raw[16, 24], rtol=1e-9)
    # luminance scaling and the same scale through a different f-number or fill factor
    other = capture_ideal(scene, luminance_cd_m2=10.0, optics=OpticsParams(f_number=8.0, relative_illumination=False),
                          sensor=SensorParams(fill_factor=0.5))
    np.testing.assert_allclose(other.raw[..., 1], 10.0, rtol=1e-9)
    assert ideal.pattern.tolist() == [["XYZ"]] and ideal.channels == ("X", "Y", "Z")


def test_white_radiance_and_meta_follow_the_luminance_scale():
    rad, _ = d65_radiance(80.0)
    scene = uniform_scene(80.0, white_radiance=(rad * 1.25).tolist(), luminance_cd_m2=80.0, geometry={"a": 1})
    raw = capture(scene, "bayer", luminance_cd_m2=40.0, noise="off")
    np.testing.assert_allclose(raw.white_radiance, rad * 1.25 * 0.5, rtol=1e-12)
    assert raw.meta["luminance_cd_m2"] == pytest.approx(40.0)
    assert raw.meta["render_luminance_cd_m2"] == 80.0
    assert raw.meta["white_luminance_cd_m2"] == pytest.approx(50.0, rel=1e-9)
    assert raw.meta["geometry"] == {"a": 1} and raw.meta["oversample"] == 1
    assert raw.meta["pixel_pitch_um"] == 2.2
    assert raw.settings["exposure_mode"] == "auto" and raw.settings["noise"] == "off"


def test_white_fallback_without_a_sidecar():
    rad, _ = d65_radiance(60.0)
    data = np.broadcast_to(rad, (8, 8, 31)).copy()
    data[0, 0] *= 2  # the brightest pixel: 120 cd/m^2
    raw = capture(SpectralImage(data, WL, {}), "bayer", noise="off")
    assert cm.spectra.luminance_cd_m2(raw.white_radiance) == pytest.approx(120.0, rel=1e-9)
    assert raw.meta["white_source"].startswith("assumed: D65")
    assert raw.meta["optics"]["fov_source"] == "default" and raw.meta["optics"]["fov_deg"] == 10.0


@pytest.mark.parametrize("kw, needle", [
    ({"exposure_s": "fast"}, "exposure"), ({"exposure_s": -1.0}, "exposure"), ({"exposure_s": float("nan")}, "exposure"),
    ({"luminance_cd_m2": 0.0}, "luminance"), ({"luminance_cd_m2": -3.0}, "luminance"),
    ({"noise": "loud"}, "noise"), ({"seed": -1}, "seed"), ({"seed": 1.5}, "seed"),
    ({"cfa": "nosuch"}, "unknown CFA"),
])
def test_bad_capture_arguments_are_refused(kw, needle):
    kw = {"cfa": "bayer", **kw}
    cfa = kw.pop("cfa")
    with pytest.raises(CfaMitsubaError, match=needle):
        capture(uniform_scene(h=4, w=4), cfa, **kw)


def test_black_scene_cannot_be_auto_exposed_or_scaled():
    black = SpectralImage(np.zeros((4, 4, 31)), WL, {})
    with pytest.raises(CfaMitsubaError, match="black"):
        capture(black, "bayer")
    with pytest.raises(CfaMitsubaError, match="black"):
        capture(black, "bayer", luminance_cd_m2=10.0, exposure_s=0.01)
    assert capture(black, "bayer", exposure_s=0.01, noise="off").raw.max() == 0.0


def test_optical_image_must_match_the_sensor():
    oi = compute_optics(uniform_scene(h=4, w=4), OpticsParams(relative_illumination=False))
    with pytest.raises(CfaMitsubaError, match="um"):
        capture(oi, "bayer", sensor=SensorParams(pixel_pitch_um=1.4))
    with pytest.raises(CfaMitsubaError, match="optics settings"):
        capture(oi, "bayer", optics=OpticsParams())
    # a different fill factor is recomputed from the irradiance, not refused
    a = capture(oi, "bayer", exposure_s=0.01, noise="off", sensor=SensorParams(fill_factor=0.5)).raw
    b = capture(oi, "bayer", exposure_s=0.01, noise="off").raw
    np.testing.assert_allclose(a, 0.5 * b, rtol=1e-9)  # a uniform field: half the area, half the electrons


@pytest.mark.parametrize("kw, needle", [({"fill_factor": 1.5}, "fill_factor"), ({"adc_bits": 0}, "adc_bits"),
                                        ({"well_capacity_e": 0}, "well"), ({"read_noise_e": -1}, "read_noise"),
                                        ({"black_level_dn": 5000}, "black level"), ({"sensor_seed": -2}, "seed")])
def test_bad_sensor_settings_are_refused(kw, needle):
    with pytest.raises(CfaMitsubaError, match=needle):
        SensorParams(**kw)


def test_default_sensor_is_documented_scale():
    s = SensorParams()
    assert s.well_capacity_e == 6200 and s.pixel_pitch_um == 2.2
    assert s.conversion_gain_uv_per_e == pytest.approx(1e6 / 6200)
    assert s.read_noise_e == pytest.approx(1e-3 / (1 / 6200), rel=1e-3)  # ISETCam's 1 mV
    assert s.dn_per_electron == pytest.approx((4095 - 64) / 6200)


def test_noise_seeds_of_one_capture_reuse_its_noise_free_part_exactly(monkeypatch):
    """A study captures several noise seeds of one optical image in a row;
    the exposure metering and mean response are reused from the last
    capture (capture._LAST_SIGNAL) and give the same raw, bit for bit, as
    a capture that computes them afresh; anything else that differs (the
    CFA, the luminance, the sensor, the optical image) computes afresh."""
    import importlib

    capture_module = importlib.import_module("cfa_mitsuba.sensor.capture")

    rng = np.random.default_rng(4)
    img = uniform_scene(80.0, 40, 44)
    img = SpectralImage(img.data * rng.uniform(0.2, 1.0, (40, 44, 1)), WL, img.meta)
    oi = compute_optics(img, OpticsParams(), pixel_pitch_um=2.2)
    kw = dict(luminance_cd_m2=3.0, sensor=SensorParams(), exposure_policy="program")

    def fresh(cfa, seed, **extra):
        capture_module._LAST_SIGNAL[0] = None
        return capture(oi, cfa, seed=seed, **{**kw, **extra})

    for cfa in ("bayer", "rgbw1"):
        for seed in (1, 2, 3):
            reused = capture(oi, cfa, seed=seed, **kw)
            assert capture_module._LAST_SIGNAL[0][0] is oi
            want = fresh(cfa, seed)
            np.testing.assert_array_equal(reused.raw, want.raw)
            np.testing.assert_array_equal(reused.electrons_per_radiance, want.electrons_per_radiance)
            assert reused.settings == want.settings and reused.meta == want.meta
    # three seeds in a row: computed once
    made = []
    real = capture_module._noise_free_signal
    monkeypatch.setattr(capture_module, "_noise_free_signal", lambda *a: made.append(1) or real(*a))
    capture_module._LAST_SIGNAL[0] = None
    for seed in (7, 8, 9):
        capture(oi, "rgbw1", seed=seed, **kw)
    assert len(made) == 1
    # a change of luminance, sensor or CFA is a new signal, not the last one's
    base = capture(oi, "bayer", seed=5, **kw)
    brighter = capture(oi, "bayer", seed=5, **{**kw, "luminance_cd_m2": 30.0})
    assert brighter.settings["luminance_scale"] != base.settings["luminance_scale"]
    np.testing.assert_array_equal(brighter.raw, fresh("bayer", 5, luminance_cd_m2=30.0).raw)
    noisy = capture(oi, "bayer", seed=5, **{**kw, "sensor": SensorParams(read_noise_e=20.0)})
    np.testing.assert_array_equal(noisy.raw, fresh("bayer", 5, sensor=SensorParams(read_noise_e=20.0)).raw)
    # the RawImage's arrays are its own: changing one leaves the next capture alone
    got = capture(oi, "bayer", seed=6, **kw)
    got.electrons_per_radiance[:] = 0.0
    np.testing.assert_array_equal(capture(oi, "bayer", seed=6, **kw).electrons_per_radiance,
                                  fresh("bayer", 6).electrons_per_radiance)
