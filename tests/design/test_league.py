"""The league (cfa_mitsuba/design/league.py): which demosaics each CFA
keeps, the table it builds from a study's tables, and the decision rule on
its entries; the command's bad input exits 2 with one line."""

from __future__ import annotations

import pandas as pd
import pytest

from cfa_mitsuba.design.league import aspect_labels, league_decisions, league_table, suited_demosaics
from cfa_mitsuba.study.config import load_config
from conftest import REPO, assert_one_line_error, run_cli

DEMOSAICS = ("bilinear", "laplacian", "adaptive-laplacian")


def test_the_league_config_holds_every_cfa_of_the_project():
    import cfa_mitsuba as cm

    cfg = load_config(REPO / "configs" / "league.toml")
    assert list(cfg.cfas) == cm.sensor.list_cfas()
    assert cfg.exposure_program.policy == "program"
    lums = {float(v) for s in cfg.sweeps for v in s.values.get("luminance", ())} | set(cfg.luminances)
    assert min(lums) == 3 and max(lums) == 400


@pytest.mark.parametrize("cfa, kept", [
    ("bayer", ["laplacian", "adaptive-laplacian"]),   # 34.98, 35.72 dB against bilinear's 30.97 (best 35.72)
    ("nona", ["bilinear"]),                           # the cross-channel methods lose 2.9-3.6 dB on 3x3 blocks
    ("rgb3", ["adaptive-laplacian"]),                 # none within 1 dB of pocs (31.30): the best of the three
])
def test_each_cfa_keeps_the_demosaics_that_suit_it(cfa, kept):
    import cfa_mitsuba as cm

    assert suited_demosaics(cm.sensor.get_cfa(cfa), DEMOSAICS)[0] == kept


def test_a_layout_never_measured_keeps_every_demosaic_and_mono_one():
    import cfa_mitsuba as cm

    bayer = cm.sensor.get_cfa("bayer")
    mine = cm.sensor.make_cfa("mine", "G R / B G", dict(bayer.curves))
    kept, why = suited_demosaics(mine, DEMOSAICS)
    assert kept == list(DEMOSAICS) and "not measured" in why
    assert suited_demosaics(cm.sensor.get_cfa("mono"), DEMOSAICS)[0] == ["bilinear"]


def _study(tmp_path):
    """A two-CFA study's tables by hand: bayer clearly best on colour, rgbw1 on low light, tied on sharpness."""
    rows = []
    for cfa, dem, de, mtf, sc3 in (("bayer", "laplacian", 2.0, 0.40, 9.0), ("bayer", "adaptive-laplacian", 2.3, 0.41, 9.1),
                                   ("rgbw1", "laplacian", 3.0, 0.405, 6.0), ("rgbw1", "adaptive-laplacian", 3.1, 0.40, 6.1),
                                   ("rgbw1", "bilinear", 9.0, 0.1, 9.0)):
        for metric, scene, lum, v, h in (("delta-e", "macbeth", 100, de, 0.05), ("mtf", "slanted-edge", 100, mtf, 0.02),
                                         ("scielab", "puppy", 3, sc3, 0.1), ("scielab", "puppy", 100, de, 0.1)):
            rows.append({"scene": scene, "cfa": cfa, "demosaic": dem, "luminance": lum, "metric": metric,
                         "value": v, "ci_low": v - h, "ci_high": v + h})
    d = tmp_path / "study"
    d.mkdir()
    pd.DataFrame(rows).to_csv(d / "metrics.csv", index=False)
    pd.DataFrame({"cfa": ["bayer", "bayer", "rgbw1", "rgbw1"], "demosaic": ["laplacian", "adaptive-laplacian"] * 2,
                  "snr10_cd_m2": [20.0, 20.5, 12.0, 12.2], "ci_low": [19, 19.5, 11.5, 11.7],
                  "ci_high": [21, 21.5, 12.5, 12.7]}).to_csv(d / "snr10.csv", index=False)
    pd.DataFrame({"cfa": ["bayer", "bayer", "rgbw1", "rgbw1"], "demosaic": ["laplacian", "adaptive-laplacian"] * 2,
                  "mean_score": [0.6, 0.62, 0.5, 0.51], "mean_score_ci_low": [0.58, 0.6, 0.48, 0.49],
                  "mean_score_ci_high": [0.62, 0.64, 0.52, 0.53]}).to_csv(d / "scores.csv", index=False)
    return d


def test_the_table_keeps_suited_entries_and_names_each_source(tmp_path):
    import dataclasses

    cfg = dataclasses.replace(load_config(REPO / "configs" / "league.toml"), cfas=("bayer", "rgbw1"),
                              demosaics=DEMOSAICS)
    table = league_table(_study(tmp_path), cfg)
    assert set(zip(table["cfa"], table["demosaic"])) == {("bayer", "laplacian"), ("bayer", "adaptive-laplacian"),
                                                        ("rgbw1", "laplacian"), ("rgbw1", "adaptive-laplacian"),
                                                        ("rgbw1", "bilinear")} - {("rgbw1", "bilinear")}
    assert table["source"].str.len().min() > 10 and (table["spectra"] != "").all()
    labels = {a: lab for a, lab, _, _ in aspect_labels(table)}
    assert labels["low-light colour"] == "scielab@puppy/L3" and labels["low light"] == "snr10@gray-bar"
    dec = league_decisions(table).set_index("aspect")
    assert dec.loc["colour", "entries"] == "bayer/laplacian" and dec.loc["colour", "verdict"] == "winner"
    assert dec.loc["low light", "entries"].split() == ["rgbw1/laplacian", "rgbw1/adaptive-laplacian"]
    assert dec.loc["low light", "verdict"] == "tie"
    assert dec.loc["sharpness", "verdict"] == "tie" and len(dec.loc["sharpness", "entries"].split()) == 4
    assert dec.loc["overall", "entries"].split() == ["bayer/adaptive-laplacian", "bayer/laplacian"]


def test_a_bad_league_config_exits_2_with_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\ncfas = ["bayer"]\n')
    proc = run_cli("league", bad, "--out", tmp_path / "out")
    assert_one_line_error(proc)
