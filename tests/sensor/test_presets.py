"""Measured sensor presets (issue 16, deliverable 4): ISETCam's pixel values
converted from volts, the curves each preset uses, the CLI."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.sensor import get_sensor_preset, list_sensor_presets

import registry_checks as checks
from chart_files import chart_exr  # noqa: F401  (the small chart EXR fixture)
from conftest import assert_one_line_error, run_cli


@pytest.mark.parametrize("name", list_sensor_presets())
def test_every_preset_passes_the_generic_checks(name):
    checks.check_sensor_preset(name)


def test_the_five_presets():
    assert list_sensor_presets()[:5] == ["mt9v024-rgb", "mt9v024-rgbw", "mt9v024-rccc", "mt9v024-mono", "imx363"]
    assert {"isetcam-default", "isetcam-monochrome"} <= set(list_sensor_presets())  # issue 23


@pytest.mark.parametrize("name, cfa, spectra", [("mt9v024-rgb", "bayer", "mt9v024-rgb"),
                                                 ("mt9v024-rgbw", "rgbw1", "mt9v024-rgbw"),
                                                 ("mt9v024-rccc", "rccc", "mt9v024-rccc"),
                                                 ("mt9v024-mono", "mono", "mt9v024-mono")])
def test_mt9v024_pixel_from_isetcam_volts(name, cfa, spectra):
    """filters README: 6 um, 110 uV/e-, 2.8 V swing, 1 mV read noise, 1 mV/s
    dark: well 2.8 / 110e-6 = 25 454.5 e-, read noise and dark 9.09 e-."""
    p = get_sensor_preset(name)
    q = p.params
    assert q.pixel_pitch_um == 6.0 and q.voltage_swing_v == 2.8
    assert q.well_capacity_e == pytest.approx(25454.545, rel=1e-6)
    assert q.conversion_gain_uv_per_e == pytest.approx(110.0, rel=1e-12)
    assert q.read_noise_e == pytest.approx(9.0909, rel=1e-4) and q.dark_current_e_s == pytest.approx(9.0909, rel=1e-4)
    assert q.adc_bits == 10 and q.fill_factor == 1.0
    assert p.cfa_name == cfa and p.spectra == spectra
    assert p.cfa().spectra == spectra and p.cfa().name == cfa
    assert any("fill factor 1" in n for n in p.notes)


def test_imx363_published_parameters_and_its_curves():
    p = get_sensor_preset("imx363")
    q = p.params
    assert (q.pixel_pitch_um, q.well_capacity_e, q.read_noise_e, q.prnu_percent, q.adc_bits, q.black_level_dn) == \
        (1.4, 6000.0, 5.0, 0.7, 10, 64.0)
    assert q.dsnu_e == 0 and q.dark_current_e_s == 0 and q.fill_factor == 1.0
    assert q.conversion_gain_uv_per_e == pytest.approx(76.51, rel=1e-3)  # swing / well, as ISETCam
    # its curves are MT9V024 RGB (ISETCam's placeholder), which the notes say
    assert p.spectra == "mt9v024-rgb" and any("placeholder" in n for n in p.notes)
    np.testing.assert_array_equal(p.cfa().sensitivities(), cm.sensor.get_cfa("bayer", spectra="mt9v024-rgb")
                                  .sensitivities())


def test_unknown_preset():
    with pytest.raises(CfaMitsubaError, match="unknown sensor preset 'imx999'.*imx363"):
        get_sensor_preset("imx999")


def test_list_sensors_shows_parameters_and_source():
    lines = run_cli("list", "sensors", check_rc=0).stdout.splitlines()
    assert [l.split()[0] for l in lines] == list_sensor_presets()
    imx = next(l for l in lines if l.startswith("imx363"))
    for part in ("1.4 um", "well 6000 e-", "read noise 5 e-", "PRNU 0.7 %", "10 bit", "spectra mt9v024-rgb",
                 "source: ISETCam"):
        assert part in imx, (part, imx)


def test_capture_with_a_preset(chart_exr, tmp_path):
    out = tmp_path / "imx.npz"
    proc = run_cli("capture", chart_exr, "--sensor", "imx363", "--luminance", "100", "--out", out, check_rc=0)
    assert "sensor preset imx363" in proc.stdout and "spectra mt9v024-rgb" in proc.stdout
    raw = cm.io.load_raw_npz(out)
    s = raw.settings["sensor"]
    assert s["pixel_pitch_um"] == 1.4 and s["well_capacity_e"] == 6000.0 and s["adc_bits"] == 10
    assert raw.raw.max() <= 1023 and raw.pattern.tolist() == [["G", "R"], ["B", "G"]]
    # an option overrides one value; --cfa another layout with the preset's curves
    out2 = tmp_path / "rccb.npz"
    run_cli("capture", chart_exr, "--sensor", "mt9v024-rgbw", "--cfa", "rccb", "--read-noise-e", "3",
            "--out", out2, check_rc=0)
    raw2 = cm.io.load_raw_npz(out2)
    assert raw2.settings["sensor"]["read_noise_e"] == 3.0 and raw2.settings["sensor"]["pixel_pitch_um"] == 6.0
    assert raw2.settings["cfa"] == {**raw2.settings["cfa"], "name": "rccb", "spectra": "mt9v024-rgbw"}


def test_capture_spectra_option_and_errors(chart_exr, tmp_path):
    out = tmp_path / "c.npz"
    run_cli("capture", chart_exr, "--cfa", "cmy1", "--spectra", "nikon-d5100", "--out", out, check_rc=0)
    assert cm.io.load_raw_npz(out).settings["cfa"]["spectra"] == "nikon-d5100"
    assert_one_line_error(run_cli("capture", chart_exr, "--out", tmp_path / "x.npz"), "--cfa is required")
    assert_one_line_error(run_cli("capture", chart_exr, "--sensor", "nope", "--out", tmp_path / "x.npz"),
                          "unknown sensor preset 'nope'")
    assert_one_line_error(run_cli("capture", chart_exr, "--sensor", "mt9v024-rccc", "--cfa", "bayer",
                                  "--out", tmp_path / "x.npz"), "has no filter 'G'")
    assert not (tmp_path / "x.npz").exists()
