"""The ISP axes of a study (``denoise``, ``sharpen``; study/axes.py) and the
rows of one processing setting (study/isp_settings.py): a value is checked
and spelled once, reaches isp.process as the keywords its record gives, and
the tables that answer "with noise reduction" read one setting's rows."""

from __future__ import annotations

import pandas as pd
import pytest

from cfa_mitsuba import isp
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.study.conditions import Condition
from cfa_mitsuba.study.config import parse_config
from cfa_mitsuba.study.isp_settings import at_base_axes, isp_axes, isp_settings, with_setting

BASE = {"scenes": ["gray-bar"], "cfas": ["bayer"], "demosaics": ["bilinear"]}


def test_a_sweep_spells_each_setting_once_and_the_chain_passes_its_keywords():
    cfg = parse_config({**BASE, "sweep": [{"scene": "gray-bar", "denoise": ["none", "nl-means:1", "wavelet:2"],
                                           "sharpen": ["unsharp:0.5", "unsharp:1"]}]})
    values = cfg.sweeps[0].values
    assert tuple(values["denoise"]) == ("none", "nl-means", "wavelet:2")  # scale 1 is the plain name
    assert tuple(values["sharpen"]) == ("unsharp", "unsharp:1")  # amount 0.5 is unsharp's default
    opts = cfg.chain_settings().isp_options("bilinear", Condition(denoise="wavelet:2", sharpen="unsharp:1"))
    assert opts["denoise"] == "wavelet" and opts["denoise_options"] == {"scale": 2.0}
    assert opts["sharpen"] == "unsharp" and opts["sharpen_options"] == {"amount": 1.0}


def test_the_isp_table_sets_the_studys_own_setting():
    cfg = parse_config({**BASE, "isp": {"denoise": "nl-means:1.5"}})
    cond = cfg.base_condition()
    assert cond.denoise == "nl-means:1.5" and cond.sharpen == "none"
    opts = cfg.chain_settings().isp_options("bilinear", cond)
    assert opts["denoise"] == "nl-means" and opts["denoise_options"] == {"scale": 1.5}


@pytest.mark.parametrize("value, words", [
    ("bm3d", "bm3d"), ("nl-means:-1", "number >= 0"), ("nl-means:x", "number >= 0"), ("none:2", "no strength"),
])
def test_a_bad_denoise_value_is_a_one_line_error(value, words):
    with pytest.raises(CfaMitsubaError, match=words) as exc:
        parse_config({**BASE, "sweep": [{"scene": "gray-bar", "denoise": [value]}]})
    assert "\n" not in str(exc.value)


def test_each_method_records_its_reach_for_a_chain_that_crops():
    # nl-means: patch_distance 6 + patch_size 5 // 2 = 8 plane pixels; a Bayer plane pixel is 2 image pixels
    assert isp.denoise_support_px("nl-means", None, (2, 2)) == 16
    assert isp.denoise_support_px("nl-means", {"domain": "rgb"}, (2, 2)) == 8
    # the wavelet methods threshold each subband from the whole plane: global, run before any crop
    assert isp.denoise_support_px("wavelet") is None and isp.denoise_support_px("wavelet-ti") is None
    assert isp.denoise_support_px("none") == 0 and isp.denoise_support_px("nl-means", {"scale": 0.0}) == 0
    assert isp.sharpen_support_px("unsharp", {"radius": 1.5}) == 6  # 4 Gaussian sigmas


def _rows():
    """Two CFAs, the study's own processing (base rows: denoise none) and a
    sweep of denoise at two levels, plus a read-noise sweep that must not mix in."""
    rows = []
    for cfa in ("bayer", "rgbw1"):
        rows.append((cfa, 100, "none", 6.2, True, 1.0))
        for lum in (3, 100):
            for dn in ("none", "nl-means"):
                rows.append((cfa, lum, dn, 6.2, False, 2.0 if dn == "nl-means" else 1.0))
        rows.append((cfa, 3, "none", 12.4, False, 0.5))  # another axis swept: not the study's own
    return pd.DataFrame(rows, columns=["cfa", "luminance", "denoise", "read_noise_e", "base", "value"]).assign(
        scene="gray-bar", sharpen="none")


def test_one_settings_rows_hold_every_other_axis_at_the_studys_own_value():
    rows = _rows()
    assert isp_axes(rows.columns) == ["denoise", "sharpen"]
    assert isp_settings(rows) == [("denoise", "nl-means")]
    den = with_setting(rows, "denoise", "nl-means")
    assert len(den) == 4 and set(den["value"]) == {2.0}
    own = at_base_axes(rows)
    assert set(own["denoise"]) == {"none"} and set(own["read_noise_e"]) == {6.2} and len(own) == 6
    assert with_setting(rows, "spectra", "x").empty  # an axis the table does not hold
