"""``cm.isp.process``: RawImage -> RenderedImage on the ideal sensor's
absolute scale; flat grey stays grey on every CFA with every method."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.values import RawImage
from synthetic_raw import WHITE, WL, synthetic_raw  # shared with the other ISP tests

#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in cm.isp.list_demosaics())


@pytest.mark.parametrize("cfa", cm.sensor.list_cfas())
@pytest.mark.parametrize("method", METHODS)
def test_flat_grey_stays_grey_on_the_absolute_scale(cfa, method):
    grey = np.broadcast_to(0.18 * WHITE, (12, 12, WL.size))
    out = cm.isp.process(synthetic_raw(grey, cfa), method)
    want = spectra.xyz_from_radiance(0.18 * WHITE, WL)
    de = cm.isp.delta_e00(out.xyz, want, out.white_xyz)
    assert de.max() < 0.5, de.max()
    assert np.allclose(out.xyz[..., 1], 18.0, rtol=1e-6)  # Y in cd/m^2
    assert np.allclose(out.srgb, out.srgb[..., :1], atol=1e-4)  # neutral on the display too


def test_grey_under_illuminant_a_is_balanced_by_the_known_illuminant():
    a = spectra.illuminant("A", WL)
    white = a * (100.0 / spectra.luminance_cd_m2(a, WL))
    out = cm.isp.process(synthetic_raw(np.broadcast_to(0.5 * white, (8, 8, WL.size)), "rgbw2", white=white), "pocs")
    assert np.allclose(out.srgb, out.srgb[..., :1], atol=1e-4)
    assert np.allclose(out.white_xyz, spectra.xyz_from_radiance(white, WL))


def test_meta_records_the_processing():
    out = cm.isp.process(synthetic_raw(np.broadcast_to(0.4 * WHITE, (8, 8, WL.size)), "cmy1"), "laplacian")
    isp = out.meta["isp"]
    assert isp["cfa"] == "cmy1" and isp["demosaic"] == "laplacian" and isp["channels"] == ["C", "M", "Y"]
    assert np.array(isp["colour_matrix"]).shape == (3, 3)
    assert isp["condition_number"] > 1 and len(isp["noise_gain_xyz"]) == 3
    assert min(isp["white_balance_gains"]) == 1.0 and isp["white_preserving"] is True
    assert isp["saturated_fraction"] == 0.0
    assert out.meta["scene"] == "test" and out.meta["capture"]["sensor"]["adc_bits"] == 12


def test_ideal_sensor_passes_through():
    xyz = np.random.default_rng(0).random((6, 7, 3)) * 50
    raw = RawImage(raw=xyz, pattern=np.array([["XYZ"]]), channels=("X", "Y", "Z"),
                   spectra=spectra.cmfs_xyz(WL).T.copy(), wavelengths=WL.copy(),
                   electrons_per_radiance=(spectra.cmfs_xyz(WL) * spectra.band_widths(WL)[:, None] * 683).T.copy(),
                   white_radiance=WHITE, exposure_s=1.0, dn_per_electron=1.0)
    out = cm.isp.process(raw, "pocs")
    assert np.array_equal(out.xyz, xyz)
    assert np.allclose(out.white_xyz, spectra.xyz_from_radiance(WHITE, WL))
    assert out.srgb.shape == xyz.shape and out.srgb.min() >= 0 and out.srgb.max() <= 1


def test_gray_world_option_and_bad_options():
    raw = synthetic_raw(np.broadcast_to(0.3 * WHITE, (8, 8, WL.size)), "bayer")
    out = cm.isp.process(raw, "bilinear", white_balance="gray-world")
    assert np.allclose(out.srgb, out.srgb[..., :1], atol=1e-4)
    with pytest.raises(cm.CfaMitsubaError, match="unknown white balance"):
        cm.isp.process(raw, white_balance="auto")
    with pytest.raises(cm.CfaMitsubaError, match="unknown demosaicing method"):
        cm.isp.process(raw, "nope")
    bad = synthetic_raw(np.broadcast_to(0.3 * WHITE, (8, 8, WL.size)), "bayer")
    bad.raw[2, 2] = np.nan
    with pytest.raises(cm.CfaMitsubaError, match="NaN"):
        cm.isp.process(bad)


def test_saturated_and_black_captures_are_finite():
    raw = synthetic_raw(np.broadcast_to(0.3 * WHITE, (8, 8, WL.size)), "rgbw3")
    raw.raw[:] = 4095.0
    out = cm.isp.process(raw, "adaptive-laplacian")
    assert np.all(np.isfinite(out.xyz)) and out.meta["isp"]["saturated_fraction"] == 1.0
    raw.raw[:] = raw.black_level_dn
    out = cm.isp.process(raw, "pocs")
    assert np.all(out.xyz == 0) and np.all(out.srgb == 0)


def test_colour_chart_through_the_real_sensor_matches_the_ideal_sensor():
    """sensor.capture -> process against capture_ideal: the absolute scales
    of the two paths agree and the chart's colours are within the fit's
    error (patch centres, noise off; the Nikon set, whose fit error on the
    chart is 1.08 dE00 mean: tests/isp/test_colour_matrix.py)."""
    names, refl = spectra.colorchecker(WL)
    p = 12
    img = np.zeros((4 * p, 6 * p, WL.size))
    for k in range(24):
        r, c = divmod(k, 6)
        img[r * p:(r + 1) * p, c * p:(c + 1) * p] = refl[k] * WHITE
    scene = cm.SpectralImage(img, WL.copy(), {"white_radiance": WHITE.tolist(), "fov_deg": 5.0})
    oi = cm.optics.compute_optics(scene)
    ideal = cm.isp.process(cm.sensor.capture(oi, "ideal"))
    cam = cm.isp.process(cm.sensor.capture(oi, cm.sensor.get_cfa("bayer", spectra="nikon-d5100"), noise="off"),
                         "pocs")

    def centres(x):
        return np.array([x[r * p + 4:(r + 1) * p - 4, c * p + 4:(c + 1) * p - 4].mean(axis=(0, 1))
                         for r in range(4) for c in range(6)])

    assert np.allclose(cam.white_xyz, ideal.white_xyz)
    de = cm.isp.delta_e00(centres(cam.xyz), centres(ideal.xyz), ideal.white_xyz)
    assert de.mean() < 2.0 and de.max() < 6.0, de
    assert np.allclose(centres(cam.xyz)[18:, 1], centres(ideal.xyz)[18:, 1], rtol=0.03)  # grey row, Y


# --- command line -----------------------------------------------------------------


@pytest.fixture
def raw_file(tmp_path):
    from cfa_mitsuba.io.raw_npz import save_raw_npz

    yy, xx = np.mgrid[0:16, 0:20]
    refl = np.where((xx // 5 + yy // 4) % 2 == 0, 0.2, 0.7)[..., None] * np.ones(WL.size)
    path = tmp_path / "raw.npz"
    save_raw_npz(path, synthetic_raw(refl * WHITE, "rgbw1"))
    return path


@pytest.fixture
def cli(capsys):
    from types import SimpleNamespace

    from cfa_mitsuba.cli import main

    def run(*args):
        capsys.readouterr()
        try:
            rc = main([str(a) for a in args])
        except SystemExit as exc:
            rc = exc.code
        out = capsys.readouterr()
        return SimpleNamespace(returncode=rc, stdout=out.out, stderr=out.err)

    return run


def test_cli_writes_png_exr_npz(cli, raw_file, tmp_path):
    from cfa_mitsuba.io.images import read_image

    for suffix in (".png", ".exr", ".npz"):
        out = tmp_path / f"img{suffix}"
        proc = cli("process", raw_file, "--demosaic", "pocs", "--iterations", "4", "--out", out)
        assert proc.returncode == 0, proc.stderr
        assert "rgbw1" in proc.stdout and "pocs" in proc.stdout
    png = read_image(tmp_path / "img.png")
    assert png.bit_depth == 8 and png.data.shape == (16, 20, 3)
    exr = read_image(tmp_path / "img.exr")
    assert exr.channels == ("X", "Y", "Z") and exr.meta["isp"]["demosaic"] == "pocs"
    with np.load(tmp_path / "img.npz", allow_pickle=False) as z:
        assert set(z.files) == {"xyz", "srgb", "white_xyz", "meta"}
        assert np.allclose(z["xyz"], exr.data, rtol=1e-6, atol=1e-4)  # EXR is float32
        assert np.allclose(z["white_xyz"][1], 100.0)
        # 0.2 / 0.7 grey checks on the absolute scale: Y = 20 and 70 cd/m^2 inside two checks
        # away from the image border (measured 19.1 and 73.2 with POCS at 4 iterations on rgbw1's
        # ISETCam filters, 17.9 and 70.2 with the Nikon set: 5 x 4 px checks leave demosaicking
        # overshoot in every pixel)
        y = z["xyz"][..., 1]
        assert y[5:7, 6:9].mean() == pytest.approx(20.0, abs=5.0)
        assert y[5:7, 11:14].mean() == pytest.approx(70.0, abs=5.0)


def test_cli_bad_input_is_one_line(cli, raw_file, tmp_path):
    from conftest import assert_one_line_error

    assert_one_line_error(cli("process", tmp_path / "missing.npz", "--out", tmp_path / "a.png"), "does not exist")
    assert_one_line_error(cli("process", raw_file, "--out", tmp_path / "a.tif"), ".png, .exr or .npz")
    assert_one_line_error(cli("process", raw_file, "--demosaic", "nope", "--out", tmp_path / "a.png"),
                          "unknown demosaicing method")
    assert_one_line_error(cli("process", raw_file, "--iterations", "3", "--out", tmp_path / "a.png"), "pocs")
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    assert_one_line_error(cli("process", junk, "--out", tmp_path / "a.png"), "junk.npz")
    assert not (tmp_path / "a.png").exists()


def test_demosaic_precision_reaches_the_method_and_the_meta():
    rng = np.random.default_rng(5)
    scene = np.broadcast_to(0.4 * WHITE, (16, 16, WL.size)) * (0.5 + rng.random((16, 16, 1)))
    raw = synthetic_raw(scene, "bayer")
    double = cm.isp.process(raw, "adaptive-laplacian")
    single = cm.isp.process(raw, "adaptive-laplacian", demosaic_precision="single")
    assert double.meta["isp"]["demosaic_precision"] == "double"
    assert single.meta["isp"]["demosaic_precision"] == "single"
    assert single.xyz.dtype == np.float64
    err = np.abs(single.xyz - double.xyz).max() / np.abs(double.xyz).max()
    assert 0 < err < 1e-6, err  # float32 rounding, not the same bits and not another method
    with pytest.raises(cm.CfaMitsubaError, match="unknown demosaic precision 'half'"):
        cm.isp.process(raw, "bilinear", demosaic_precision="half")
