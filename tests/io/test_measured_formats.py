"""Measured spectral images as scenes, each format written by the library
that owns it (issue 13, acceptance 2): a reflectance cube of the 24
'ColorChecker N Ohta' patches under D65 renders to an EXR whose patch
interiors match the box means of D65 x reflectance within 0.5 % per band,
and colour-science's own test EXRs render with their spectra intact."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from conftest import run_cli
from cfa_mitsuba import spectra
from cfa_mitsuba.io import read_spectral_exr
from cfa_mitsuba.render.measured import measured_image
from measured_charts import (D65, P, SRC_WL, TABLES, WRITERS, _colour, chart_cube, worst_patch_error,  # noqa: F401
                             write_envi, write_png)



@pytest.mark.parametrize("fmt", list(WRITERS))
def test_colorchecker_cube_renders_to_d65_times_reflectance(tmp_path, fmt):
    path = WRITERS[fmt](tmp_path)
    extra = {"mat_wavelengths": "wl"} if fmt == "mat-v73" else {}
    img = measured_image(path, illuminant="D65", **extra)
    assert img.data.shape == (4 * P, 6 * P, 31)
    assert abs(spectra.luminance_cd_m2(img.data).mean() - 100.0) < 1e-6
    # 16-bit codes: half a code in ~2000 on the black patch (2.5e-4); the others are exact to float32
    assert worst_patch_error(img) < (3e-4 if fmt == "png" else 1e-6), worst_patch_error(img)
    white = np.asarray(img.meta["white_radiance"])
    d65 = spectra.band_average(*D65, img.wavelengths)
    np.testing.assert_allclose(white / white[15], d65 / d65[15], rtol=1e-9)


def test_cave_layout_png_folder(tmp_path):
    """NAME_ms_01.png ... NAME_ms_31.png are 400 ... 700 nm: samples on
    the band centres, so they are band values and pass through unchanged,
    times D65's band means (DESIGN.md, Conventions; issue 27 item 12)."""
    img = measured_image(write_png(tmp_path, cave=True), illuminant="D65")
    wl10 = np.arange(400.0, 701.0, 10.0)
    scale = img.meta["scale_from_canonical"]
    d65_bands = spectra.band_average(*D65, img.wavelengths)
    for i in range(24):
        row, col = divmod(i, 6)
        got = img.data[row * P + 2, col * P + 2] / scale
        want = np.interp(wl10, *TABLES[i]) * d65_bands
        np.testing.assert_allclose(got, want, rtol=3e-4)  # 16-bit codes
    assert any("CAVE layout" in n for n in img.meta["read_notices"])
    # Against the box means of colour's 5-nm tables: a point sample at the
    # centre is not its box's mean (the data's sampling, not the conversion).
    assert 0.02 < worst_patch_error(img) < 0.04


def test_v73_written_by_h5py_with_a_user_block(tmp_path):
    """MATLAB's own layout by hand: an HDF5 file after a 512-byte header,
    arrays stored transposed."""
    import h5py

    p = tmp_path / "cube.mat"
    cube = chart_cube()
    with h5py.File(p, "w", userblock_size=512) as f:
        f.create_dataset("reflectance", data=np.transpose(cube.astype(np.float64)))
        f.create_dataset("wavelengths", data=SRC_WL[None, :].T.T)
    with open(p, "r+b") as fh:
        fh.write(b"MATLAB 7.3 MAT-file, written by h5py".ljust(116, b" "))
    img = measured_image(p, illuminant="D65", mat_cube="reflectance")
    assert worst_patch_error(img) < 1e-6


def test_isetcam_scene_file(tmp_path):
    """An ISETCam scene struct: photons = radiance x lambda / (h c), the
    illuminant's photons on a perfect reflector, wAngular and distance."""
    import scipy.io

    radiance = chart_cube().astype(np.float64) * np.interp(SRC_WL, *D65)
    q = spectra.photons_per_joule(SRC_WL)
    light = np.interp(SRC_WL, *D65) * q
    scene = {"data": {"photons": radiance * q}, "spectrum": {"wave": SRC_WL}, "wAngular": 7.5, "distance": 2.5,
             "illuminant": {"data": {"photons": light}, "spectrum": {"wave": SRC_WL}}}
    scipy.io.savemat(tmp_path / "scene.mat", {"scene": scene})
    img = measured_image(tmp_path / "scene.mat")
    assert img.meta["fov_deg"] == 7.5 and img.meta["scene_distance_m"] == 2.5
    assert img.meta["source"]["quantity"] == "photons"
    # the product is tabulated at 5 nm and interpolated as one spectrum here
    assert worst_patch_error(img) < 5e-3, worst_patch_error(img)
    white = np.asarray(img.meta["white_radiance"])
    np.testing.assert_allclose(white / white[15], spectra.band_average(*D65, img.wavelengths)
                               / spectra.band_average(*D65, img.wavelengths)[15], rtol=1e-9)


def test_render_cli_writes_exr_and_sidecar(tmp_path):
    path = write_envi(tmp_path)
    out = tmp_path / "out"
    proc = run_cli("render", path, "--illuminant", "D65", "--fov", "20", "--luminance", "50", "--out", out,
                   "--no-cache", check_rc=0)
    assert proc.stdout.split() == [str(out / "chart.exr"), str(out / "chart.json")]
    assert "illuminant D65 (from --illuminant) lights the reflectance" in proc.stderr
    img = read_spectral_exr(out / "chart.exr")
    side = json.loads((out / "chart.json").read_text())
    assert side["fov_deg"] == 20 and side["luminance_cd_m2"] == 50 and side["illuminant"] == "D65"
    assert side["kind"] == "natural"  # the image metrics (the metric records say which)
    assert abs(spectra.luminance_cd_m2(img.data).mean() - 50.0) < 1e-4
    assert worst_patch_error(img) < 1e-6


COLOUR_RESOURCES = os.path.join(os.path.dirname(_colour().__file__), "io", "tests", "resources")


def _file_spectra(name, comp):
    """(wavelengths, (H, W, N) values) of a colour test EXR, read with OpenEXR."""
    import OpenEXR

    from cfa_mitsuba.io.exr import parse_spectral_channel

    with OpenEXR.File(os.path.join(COLOUR_RESOURCES, name), separate_channels=True) as f:
        chans = [(parse_spectral_channel("S0." + n.split(".", 1)[1]), ch.pixels) for n, ch in f.channels().items()
                 if n.startswith(comp + ".") and n.count(".") == 1]
    chans.sort(key=lambda t: t[0])
    return np.array([c[0] for c in chans]), np.stack([c[1] for c in chans], -1).astype(np.float64)


def test_colour_d65_exr_emissive_renders_intact():
    """colour's D65.exr: one pixel, 300-780 nm at 5 nm (was refused: it
    starts below 360 nm).  Bands outside the grid are cropped; the rest are
    D65 itself (float16 in the file: 0.05 %)."""
    img = measured_image(os.path.join(COLOUR_RESOURCES, "D65.exr"))
    wl, vals = _file_spectra("D65.exr", "S0")
    got = img.data[0, 0] / img.meta["scale_from_canonical"]
    np.testing.assert_allclose(got, spectra.band_average(wl, vals[0, 0], img.wavelengths), rtol=1e-6)
    d65 = spectra.band_average(*D65, img.wavelengths)
    ratio = got / d65
    assert np.ptp(ratio) / ratio.mean() < 2e-3
    assert any("cropped" in n for n in img.meta["read_notices"])
    assert img.meta["illuminant"].startswith("D65")


def test_colour_ohta_exr_reflective_renders_intact():
    """colour's Ohta1997.exr: 4 x 6 reflective pixels at 400-700 nm every 20
    nm, lit by its 'illuminant' attribute (D65)."""
    img = measured_image(os.path.join(COLOUR_RESOURCES, "Ohta1997.exr"))
    assert img.meta["illuminant"] == "D65 (the file's 'illuminant' attribute)"
    wl, refl = _file_spectra("Ohta1997.exr", "T")
    scale = img.meta["scale_from_canonical"]
    worst = 0.0
    for i in range(24):
        row, col = divmod(i, 6)
        # the file holds the Ohta table at 400, 420, ..., 700 nm, as float16
        np.testing.assert_allclose(refl[row, col], np.interp(wl, *TABLES[i]), rtol=1e-3, atol=1e-4)
        got = img.data[row, col] / scale
        exact = spectra.band_average_product([D65, (wl, refl[row, col])], img.wavelengths)
        worst = max(worst, float(np.max(np.abs(got / exact - 1))))
    assert worst < 1e-6  # exactly what the file holds, lit by D65


def test_colour_polarised_and_bispectral_exrs_render():
    """Stokes S1-S3 and bispectral re-radiation are left out with a notice;
    S0 and the T diagonal render."""
    for name in ("Polarised.exr", "BiSpectral.exr"):
        img = measured_image(os.path.join(COLOUR_RESOURCES, name))
        assert img.data.shape[2] == 31 and np.all(np.isfinite(img.data)) and img.data.min() >= 0
        assert any("left out" in n for n in img.meta["read_notices"])
