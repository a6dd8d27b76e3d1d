"""Design objectives of issue 26: snr10 read off a gray-bar sweep,
``demosaic = "best"``, the proxy settings under the exposure program, the
agreement's interval and target, and the report's headline."""

import tomllib

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.design.config import load_design, parse_design
from cfa_mitsuba.design.front import agreement, spearman_interval
from cfa_mitsuba.design.report import headline
from cfa_mitsuba.design.search import proxy_settings
from cfa_mitsuba.errors import CfaMitsubaError
from conftest import REPO

BASE = """
name = "t"
layout = { tiles = ["2x2"], alphabet = ["R", "G", "B"] }
[[objective]]
metric = "snr10"
scene = "gray-bar"
luminances = [1, 3, 10, 30]
demosaic = "best"
[[objective]]
metric = "info-capacity"
scene = "slanted-edge"
luminance = 100
[study]
scenes = ["gray-bar", "slanted-edge"]
cfas = ["bayer"]
demosaics = ["bilinear", "laplacian"]
"""


def test_snr10_objective_sweeps_the_gray_bar_and_best_takes_every_demosaic():
    cfg = parse_design(tomllib.loads(BASE))
    snr10, cap = cfg.objectives
    assert snr10.label == "snr10@gray-bar/best" and snr10.goal == "min" and snr10.unit == "cd/m^2"
    assert snr10.sweep == (1.0, 3.0, 10.0, 30.0) and "cd/m²" in snr10.title
    assert cap.goal == "max" and cap.proxies == ("neg_capacity",) and "bit/px" in cap.title
    swept = sorted(v for s in cfg.study.sweeps for v in s.values["luminance"] if "ysnr" in s.metrics)
    assert swept == [1.0, 3.0, 10.0, 30.0]
    settings = proxy_settings(cfg)
    assert settings.exposure.policy == "program"          # the study default, not 'reference'
    assert settings.demosaics == ("bilinear", "laplacian")


@pytest.mark.parametrize("change, key", [
    ('luminances = [1, 3, 10, 30]', "objective[0].luminance"),
    ('metric = "info-capacity"\nscene = "slanted-edge"\nluminance = 100', "objective[1].luminances"),
])
def test_snr10_keys_are_checked(change, key):
    text = BASE.replace('luminances = [1, 3, 10, 30]', 'luminance = 10') if key.endswith("luminance") else \
        BASE.replace(change, change + "\nluminances = [1, 2]")
    with pytest.raises(CfaMitsubaError, match=key.replace("[", r"\[").replace("]", r"\]")):
        parse_design(tomllib.loads(text))


def test_snr10_on_the_area_ysnr_reads_its_rows_and_has_its_own_proxy():
    cfg = parse_design(tomllib.loads(BASE.replace('demosaic = "best"', 'demosaic = "best"\nbasis = "ysnr-area"', 1)))
    snr10 = cfg.objectives[0]
    assert snr10.basis == "ysnr-area" and snr10.proxies == ("snr10_area",)
    assert snr10.label == "snr10@gray-bar/ysnr-area/best" and "area-referred YSNR 10" in snr10.title
    assert parse_design(tomllib.loads(BASE)).objectives[0].proxies == ("snr10",)   # the default: per pixel
    area = parse_design(tomllib.loads(BASE.replace('metric = "snr10"', 'metric = "ysnr-area"')
                                      .replace('luminances = [1, 3, 10, 30]', 'luminance = 10')))
    assert area.objectives[0].proxies == ("noise_area",)
    assert proxy_settings(area).luminance_cd_m2 == 10.0   # the area noise is predicted at its objective's light


@pytest.mark.parametrize("where, line", [("snr10", 'basis = "area"'), ("info-capacity", 'basis = "ysnr-area"')])
def test_a_bad_snr10_basis_is_refused_in_one_line(where, line):
    text = BASE.replace(f'metric = "{where}"', f'metric = "{where}"\n{line}')
    with pytest.raises(CfaMitsubaError, match=r"objective\[\d\]\.basis") as info:
        parse_design(tomllib.loads(text))
    assert "\n" not in str(info.value)


def test_a_named_reference_policy_is_kept():
    cfg = load_design(REPO / "configs" / "design-quick.toml")
    assert proxy_settings(cfg).exposure.policy == "program"
    data = tomllib.loads(BASE + '[study.sensor]\nexposure_policy = "reference"\n')
    assert proxy_settings(parse_design(data)).exposure.policy == "reference"


def test_spearman_interval_follows_fisher_z_with_the_fieller_variance():
    low, high = spearman_interval(0.9, 14)
    half = 1.959964 * np.sqrt(1.06 / 11)
    assert low == pytest.approx(np.tanh(np.arctanh(0.9) - half), rel=1e-6)
    assert high == pytest.approx(np.tanh(np.arctanh(0.9) + half), rel=1e-6)
    assert spearman_interval(0.5, 3) is None


class _O:
    def __init__(self, label, goal, proxies):
        self.label, self.goal, self.proxies, self.title = label, goal, proxies, label


def _table(values, lows, highs, proxy):
    n = len(values)
    return pd.DataFrame({"cfa": [f"c{i}" for i in range(n)], "kind": "candidate", "tile_text": "G R / B G",
                         "proxy_score": proxy, "score": -np.asarray(proxy), "p": proxy,
                         "a": values, "a low": lows, "a high": highs, "pareto": False, "dominated_by": ""})


def test_agreement_judges_only_objectives_that_separate_the_candidates():
    v = np.arange(8.0)
    apart = _table(v, v - 0.1, v + 0.1, v)              # perfectly predicted, well separated
    got = agreement(apart, [_O("a", "min", ("p",))])
    assert got["per_objective"]["a"] == pytest.approx(1.0) and got["separating"]["a"] and got["meets_target"]
    tied = _table(v * 0.01, v * 0.01 - 1, v * 0.01 + 1, v[::-1])   # reversed, but all within the noise
    got = agreement(tied, [_O("a", "min", ("p",))])
    assert got["per_objective"]["a"] == pytest.approx(-1.0) and not got["separating"]["a"]
    assert not got["meets_target"]                      # nothing separates: nothing met


def test_headline_says_nothing_beat_bayer_with_its_numbers():
    o = _O("a", "min", ("p",))
    t = _table([2.0, 3.0], [1.9, 2.9], [2.1, 3.1], [0.1, 0.2])
    t.loc[len(t)] = {"cfa": "bayer", "kind": "named", "tile_text": "G R / B G", "a": 1.0, "a low": 0.9,
                     "a high": 1.1, "pareto": False, "dominated_by": "", "score": 1.0}
    t["dominated_by"] = ["bayer", "bayer", ""]
    text = headline(t, [o])
    assert text.startswith("<p class=answer><b>Nothing beat Bayer</b>") and "a 1 <span class=note>[0.9, 1.1]" in text
    assert "worse on a" in text  # the best candidate against Bayer, by separated intervals


def test_the_dye_search_compares_isetcam_rgb_with_the_17_camera_sets():
    cfg = load_design(REPO / "configs" / "design-dyes.toml")
    assert cfg.spectra.family == "bandpass" and set(cfg.spectra.letters) == {"R", "G", "B"}
    assert [o.metric for o in cfg.objectives] == ["delta-e", "snr10"]
    import cfa_mitsuba as cm

    cfas = [cm.sensor.get_cfa(c) for c in cfg.study.cfas]
    assert [c.name for c in cfas][0] == "bayer" and len({c.name for c in cfas}) == 18
    assert all(c.tile_text() == "G R / B G" for c in cfas)   # one layout: only the dyes differ
