"""Sensor files (issue 28, "a sensor in"): TOML with QE curves in CSV, from
datasheet or EMVA 1288 numbers; the MT9V024 example equals the preset;
malformed files are refused in one line naming the key."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.sensor import get_sensor_preset

from conftest import REPO, assert_one_line_error, run_cli
from chart_files import chart_exr  # noqa: F401  (the small chart EXR fixture)

EXAMPLE = REPO / "configs" / "sensors" / "mt9v024-rgb.toml"
CSV = EXAMPLE.with_name("mt9v024-rgb-qe.csv")


def _file(tmp_path, body: str, csv_text: str | None = None, name="s.toml") -> Path:
    """A sensor file in ``tmp_path`` with the example's CSV (or ``csv_text``) beside it."""
    if csv_text is None:
        shutil.copy(CSV, tmp_path / "qe.csv")
    else:
        (tmp_path / "qe.csv").write_text(csv_text)
    p = tmp_path / name
    p.write_text(body)
    return p


_BASE = 'cfa = "bayer"\nqe = "qe.csv"\n[pixel]\npixel_pitch_um = 3.0\nadc_bits = 12\n'


def test_the_mt9v024_file_holds_the_presets_numbers_and_curves():
    f, p = get_sensor_preset(str(EXAMPLE)), get_sensor_preset("mt9v024-rgb")
    assert f.params == p.params
    assert f.params.well_capacity_e == pytest.approx(2.8 / 110e-6)  # the datasheet's swing / conversion gain
    assert f.cfa().tile_text() == p.cfa().tile_text() and f.spectra == "" and f.path == str(EXAMPLE)
    for c in "RGB":
        assert np.array_equal(f.cfa().curves[c][1], get_cfa_set_curve(c))


def get_cfa_set_curve(letter):
    return cm.sensor.get_spectra_set("mt9v024-rgb").curve(letter)[1]


def test_the_mt9v024_file_captures_what_the_preset_captures(chart_exr, tmp_path):
    """Acceptance 2: the same seed gives the same raw mosaic, code for code."""
    a, b = tmp_path / "preset.npz", tmp_path / "file.npz"
    run_cli("capture", chart_exr, "--sensor", "mt9v024-rgb", "--luminance", "30", "--seed", "5", "--out", a,
            check_rc=0)
    proc = run_cli("capture", chart_exr, "--sensor", EXAMPLE, "--luminance", "30", "--seed", "5", "--out", b,
                   check_rc=0)
    assert "sensor preset" in proc.stdout
    ra, rb = cm.io.load_raw_npz(a), cm.io.load_raw_npz(b)
    assert ra.raw.std() > 1.0  # a real image, not a constant
    assert np.array_equal(ra.raw, rb.raw)
    assert np.array_equal(ra.spectra, rb.spectra) and ra.dn_per_electron == rb.dn_per_electron
    assert ra.exposure_s == rb.exposure_s


def test_emva_numbers_set_the_gain_and_the_well(tmp_path):
    """K and the saturation capacity: DN per electron = K, the well = mu_e.sat."""
    p = _file(tmp_path, _BASE + "[emva]\nsystem_gain_dn_per_e = 0.25\nsaturation_capacity_e = 9000.0\n"
                                "temporal_dark_noise_e = 2.5\ndark_current_e_s = 3.0\ndsnu_e = 1.5\n"
                                "prnu_percent = 0.8\n")
    q = get_sensor_preset(str(p)).params
    assert q.dn_per_electron == pytest.approx(0.25, rel=1e-12)
    assert (q.well_capacity_e, q.read_noise_e, q.dark_current_e_s, q.dsnu_e, q.prnu_percent) == \
        (9000.0, 2.5, 3.0, 1.5, 0.8)
    assert q.analog_gain == pytest.approx(0.25 * 9000.0 / (4095 - 64))


def test_per_channel_csv_files_and_another_layout(tmp_path):
    for c in "RGB":
        (tmp_path / f"{c}.csv").write_text("wavelength_nm,qe\n400,0.1\n550,0.5\n700,0.1\n")
    p = tmp_path / "s.toml"
    p.write_text('tile = "G R / B G"\n[qe]\nR = "R.csv"\nG = "G.csv"\nB = "B.csv"\n[datasheet]\nwell_capacity_e = 5000\n')
    s = get_sensor_preset(str(p))
    assert s.params.well_capacity_e == 5000.0 and s.cfa().channels == ("R", "G", "B")
    assert s.cfa("quad-bayer").tile_shape == (4, 4)  # another layout with the file's curves
    assert cm.sensor.get_cfa(str(p)).curves["R"][1].tolist() == [0.1, 0.5, 0.1]  # as a CFA file in a study


@pytest.mark.parametrize("body, csv_text, needles", [
    (_BASE, "wavelength_nm,R,G\n400,0.1,0.2\n700,0.1,0.2\n", ("qe", "'B'")),  # missing channel curve
    ('tile = "G R / B G"\n[qe]\nR = "qe.csv"\nG = "qe.csv"\n', None, ("qe.B", "missing")),
    (_BASE, "wavelength_nm,R,G,B\n400,0.1,0.2,0.3\n550,-0.2,0.2,0.3\n700,0.1,0.2,0.3\n", ("qe", "'R'", "negative")),
    (_BASE + "[emva]\nsystem_gain_dn_per_e = 0\nsaturation_capacity_e = 9000\n", None,
     ("emva.system_gain_dn_per_e", "positive")),
    (_BASE + "[datasheet]\nconversion_gain_uv_per_e = 0.0\nvoltage_swing_v = 1.0\n", None,
     ("datasheet.conversion_gain_uv_per_e", "positive")),
    (_BASE + "[datasheet]\nread_noise_e = \"five\"\n", None, ("datasheet.read_noise_e", "number")),
    (_BASE.replace("adc_bits = 12", "adc_bits = \"12\""), None, ("pixel.adc_bits", "number")),
    (_BASE + "[datasheet]\nwell_capacity_e = 100\n[emva]\nsystem_gain_dn_per_e = 1\nsaturation_capacity_e = 90\n",
     None, ("emva.saturation_capacity_e", "well_capacity_e")),  # one quantity given twice
    (_BASE + "[pixel2]\nx = 1\n", None, ("pixel2",)),
])
def test_malformed_sensor_files_are_refused_naming_the_key(tmp_path, body, csv_text, needles):
    p = _file(tmp_path, body, csv_text)
    with pytest.raises(CfaMitsubaError):
        get_sensor_preset(str(p))
    assert_one_line_error(run_cli("list", "sensors", p), *needles)


def test_a_malformed_file_stops_capture_before_the_exr_is_read(tmp_path):
    p = _file(tmp_path, _BASE + "[emva]\nsystem_gain_dn_per_e = 0\nsaturation_capacity_e = 9000\n")
    out = tmp_path / "x.npz"
    assert_one_line_error(run_cli("capture", tmp_path / "absent.exr", "--sensor", p, "--out", out),
                          "emva.system_gain_dn_per_e")
    assert not out.exists()


def test_list_sensors_shows_files_given_and_from_the_folder(tmp_path, monkeypatch):
    proc = run_cli("list", "sensors", EXAMPLE, check_rc=0)
    last = proc.stdout.splitlines()[-1]
    assert last.startswith("mt9v024-rgb-file") and "own QE curves (R, G, B)" in last and str(EXAMPLE) in last
    (tmp_path / "mine.toml").write_text(EXAMPLE.read_text().replace('qe = "mt9v024-rgb-qe.csv"', f'qe = "{CSV}"')
                                        .replace('name = "mt9v024-rgb-file"', 'name = "mine"'))
    monkeypatch.setenv("CFA_MITSUBA_SENSORS", str(tmp_path))
    names = [line.split()[0] for line in run_cli("list", "sensors", check_rc=0).stdout.splitlines()]
    assert names[-1] == "mine" and names[:-1] == cm.sensor.list_sensor_presets()
    assert_one_line_error(run_cli("list", "cfas", EXAMPLE), "only with 'sensors'")


def test_a_study_config_takes_a_sensor_file_relative_to_it(tmp_path):
    from cfa_mitsuba.study.config import parse_config

    (tmp_path / "sensors").mkdir()
    _file(tmp_path / "sensors", _BASE + "[datasheet]\nread_noise_e = 1.5\n", name="mine.toml")
    base = {"scenes": ["gray-bar"], "cfas": ["bayer", "sensors/mine.toml"], "demosaics": ["bilinear"]}
    cfg = parse_config({**base, "sensor": "sensors/mine.toml"}, base=tmp_path)
    q = cfg.chain_settings().sensor
    assert (q.pixel_pitch_um, q.read_noise_e, q.adc_bits) == (3.0, 1.5, 12)
    assert cfg.capture["sensor_preset"] == "mine"
    with pytest.raises(CfaMitsubaError, match="sensor"):
        parse_config({**base, "sensor": "sensors/absent.toml"}, base=tmp_path)


def test_a_design_config_takes_a_sensor_file_in_its_study():
    import tomllib

    from cfa_mitsuba.design.config import parse_design

    path = REPO / "configs" / "design-quick.toml"
    data = tomllib.loads(path.read_text())
    data["study"]["sensor"] = "sensors/mt9v024-rgb.toml"  # relative to the config's folder
    cfg = parse_design(data, where=path.name, base=path.parent)
    assert cfg.study.chain_settings().sensor == get_sensor_preset("mt9v024-rgb").params
    assert cfg.study.capture["sensor_preset"] == "mt9v024-rgb-file"
