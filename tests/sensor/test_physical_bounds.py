"""Physically impossible sensors and lenses are refused with the physical
reason and the bound, in a sensor's parameters and in a sensor file
(issue 51, item 9)."""

from __future__ import annotations

import pytest

from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.optics import OpticsParams
from cfa_mitsuba.sensor.params import SensorParams
from cfa_mitsuba.sensor.sensor_file import read_sensor_file
from conftest import REPO


def test_pixel_pitch_bound():
    assert SensorParams(pixel_pitch_um=0.1).pixel_pitch_um == 0.1  # sensor.params.MIN_PIXEL_PITCH_UM
    for bad in (1e-9, 0.099):
        with pytest.raises(CfaMitsubaError, match=r"pixel_pitch_um .* below 0\.1 um, a quarter of the shortest "
                                                  r"visible wavelength"):
            SensorParams(pixel_pitch_um=bad)


def test_f_number_bound():
    assert OpticsParams(f_number=0.5).f_number == 0.5
    for bad in (0.01, 0.499):
        with pytest.raises(CfaMitsubaError, match=r"below f/0\.5, the fastest a lens in air can be: N = 1 / \(2 NA\)"):
            OpticsParams(f_number=bad)


def test_the_full_well_must_stand_above_the_read_noise():
    with pytest.raises(CfaMitsubaError, match=r"well_capacity_e 2 e- is not above the read noise 50 e-: a dynamic "
                                              r"range \(well / read noise\) of 0\.04"):
        SensorParams(well_capacity_e=2.0, read_noise_e=50.0)
    with pytest.raises(CfaMitsubaError, match="not above the read noise"):
        SensorParams(well_capacity_e=50.0, read_noise_e=50.0)
    with pytest.raises(CfaMitsubaError, match=r"channel_well_e\['B'\] 3 e- is not above"):
        SensorParams(read_noise_e=5.0, channel_well_e={"B": 3.0})
    with pytest.raises(CfaMitsubaError, match="below one electron"):
        SensorParams(well_capacity_e=0.5, read_noise_e=0.0)
    # a photon-counting pixel (a 2 e- well below 1 e- of read noise) is a real device
    assert SensorParams(well_capacity_e=2.0, read_noise_e=0.2).well_capacity_e == 2.0


def test_a_per_channel_setting_for_a_channel_the_cfa_lacks():
    SensorParams(channel_well_e={"R": 5000.0}).check_channels(("R", "G", "B"), "the CFA 'bayer'")
    with pytest.raises(CfaMitsubaError, match=r"channel_well_e sets channel 'Q', not a channel of the CFA 'bayer' "
                                              r"\(B, G, R\)"):
        SensorParams(channel_well_e={"Q": 2000.0}).check_channels(("R", "G", "B"), "the CFA 'bayer'")


_BASE = f'name = "s"\ncfa = "bayer"\nqe = "{(REPO / "configs" / "sensors" / "mt9v024-rgb-qe.csv").as_posix()}"\n' \
        "[pixel]\nadc_bits = 10\n"


@pytest.mark.parametrize("extra,match", [
    ("pixel_pitch_um = 1e-9\n", "below 0.1 um"),
    ("[datasheet]\nwell_capacity_e = 2\nread_noise_e = 50\n", "not above the read noise 50 e-"),
    ("[emva]\nsystem_gain_dn_per_e = 0.0377\nsaturation_capacity_e = 1.0\ntemporal_dark_noise_e = 0.2\n",
     r"system_gain_dn_per_e x emva.saturation_capacity_e = 0.0377 DN: from dark to saturation the output would "
     r"span less than one digital number"),
    ("[emva]\nsystem_gain_dn_per_e = 0.0377\nsaturation_capacity_e = 1.0\ntemporal_dark_noise_e = 9.09\n",
     "less than one digital number"),
    ("channel_well_e = { Q = 2.0 }\n", r"channel_well_e sets channel 'Q', not a channel of the file's tile"),
])
def test_a_sensor_file_with_an_impossible_sensor(tmp_path, extra, match):
    f = tmp_path / "s.toml"
    f.write_text(_BASE + extra)
    with pytest.raises(CfaMitsubaError, match=match) as err:
        read_sensor_file(f)
    assert str(err.value).count(str(f)) == 1  # the file named once


def test_the_shipped_sensor_file_still_reads():
    assert read_sensor_file(REPO / "configs" / "sensors" / "mt9v024-rgb.toml")["params"].pixel_pitch_um == 6.0
