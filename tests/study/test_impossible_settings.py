"""A study config with a physically impossible setting is refused by its
key with the physical reason; a study in which every measurement failed
exits 2 with the cause; a scheduler address that is not one is one line
(issue 51, items 9 and 10)."""

from __future__ import annotations

import pytest

import tiny_study
from cli_limits import assert_error_last, run_limited
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.study.config import load_config

TINY = tiny_study.TINY + tiny_study.NO_REPORT


@pytest.mark.parametrize("extra,match", [
    ("[sensor]\npixel_pitch_um = 1e-9\n", r"tiny.toml: sensor: .*pixel_pitch_um 1e-09 um is below 0.1 um"),
    ("[optics]\nf_number = 0.01\n", r"tiny.toml: optics: f-number 0.01 is below f/0.5"),
    ("[sensor]\nwell_capacity_e = 2\nread_noise_e = 50\n", r"well_capacity_e 2 e- is not above the read noise 50"),
    ("[sensor]\nchannel_well_e = { Q = 2.0 }\n",
     r"channel_well_e sets channel 'Q', not a channel of any CFA of this study \(B, G, R, W\)"),
    ('[[sweep]]\nscene = "macbeth"\npixel_pitch_um = [2.2, 1e-9]\n', r"sweep.*pixel_pitch_um.* below 0.1 um"),
    ('[[sweep]]\nscene = "macbeth"\nf_number = [4, 0.2]\n', r"sweep.*f_number.* below f/0.5"),
])
def test_an_impossible_study_setting_is_refused_by_its_key(tmp_path, extra, match):
    f = tmp_path / "tiny.toml"
    f.write_text(TINY + extra)
    with pytest.raises(CfaMitsubaError, match=match):
        load_config(f)


def test_a_study_in_which_every_measurement_failed_exits_2_with_the_cause(tmp_path):
    f = tmp_path / "dark.toml"
    f.write_text(TINY.replace("luminances = [100]", "luminances = [1e-300]"))
    out = tmp_path / "out"
    proc = run_limited("study", f, "--out", out, "--quiet", "--workers", 1, timeout=600)
    assert_error_last(proc, "every one of the", "measurement(s) failed", "failures.csv", "1e-300 cd/m^2",
                      "no usable signal")
    assert (out / "failures.csv").is_file() and not (out / "metrics.csv").exists()


@pytest.mark.parametrize("address", ["not a url", "tcp://host", "tcp://host:port", "foo://h:1", "h:99999", ""])
def test_a_scheduler_address_that_is_not_one_is_one_line(tmp_path, address):
    f = tmp_path / "tiny.toml"
    f.write_text(TINY)
    proc = run_limited("study", f, "--out", tmp_path / "out", "--scheduler", address)
    line = assert_error_last(proc, "expected a Dask scheduler address such as tcp://HOST:PORT")
    assert proc.stderr.strip() == line  # nothing said (no size estimate) and nothing written before it
    assert not (tmp_path / "out").exists()
