"""A measured spectral image as a study scene (issue 13, acceptance 4):
``[[custom_scenes]] image = "PATH"`` runs with two CFAs and reports the four
full-reference image metrics."""

from __future__ import annotations

import json
import math

import pandas as pd

import measured_charts as chart
from conftest import assert_one_line_error, run_cli

CONFIG = """\
name = "measured"
cfas = ["bayer", "rgbw1"]
demosaics = ["bilinear"]
luminances = [100]
workers = 1

[[custom_scenes]]
name = "chart"
image = "{image}"
illuminant = "D65"
fov = 10
{extra}
"""


def test_study_with_a_measured_image_reports_the_image_metrics(tmp_path):
    image = chart.write_envi(tmp_path)
    cfg = tmp_path / "s.toml"
    cfg.write_text(CONFIG.format(image=image.name, extra=""))
    out = tmp_path / "res"
    run_cli("study", cfg, "--out", out, check_rc=0)
    rows = pd.read_csv(out / "metrics.csv")
    for cfa in ("bayer", "rgbw1"):
        got = rows[(rows.scene == "chart") & (rows.cfa == cfa)].set_index("metric")["value"]
        for metric in ("scielab", "ssim", "mdsi", "haarpsi"):
            assert math.isfinite(got[metric]), (cfa, metric)
        assert 0 < got["ssim"] <= 1 and got["scielab"] > 0
    scores = pd.read_csv(out / "scores.csv")
    assert set(scores.metric) == {"scielab", "ssim", "mdsi", "haarpsi"}
    assert sorted(set(scores.cfa)) == ["bayer", "rgbw1"]
    assert "chart" in (out / "report.html").read_text()
    # The scene's name is not the study's (a measured scene once renamed the study after itself).
    assert json.loads((out / "config.json").read_text())["name"] == "measured"


def test_image_entry_is_checked_before_any_work(tmp_path):
    image = chart.write_envi(tmp_path)
    cfg = tmp_path / "s.toml"
    cfg.write_text(CONFIG.format(image=image.name, extra='spp = 64'))
    assert_one_line_error(run_cli("study", cfg, "--out", tmp_path / "r"), "custom_scenes[0].spp: unknown key")
    cfg.write_text(CONFIG.format(image="nothing.hdr", extra=""))
    assert_one_line_error(run_cli("study", cfg, "--out", tmp_path / "r"), "custom_scenes[0].image: no measured image")
    cfg.write_text(CONFIG.format(image=image.name, extra="").replace('"D65"', '"D99"'))
    assert_one_line_error(run_cli("study", cfg, "--out", tmp_path / "r"), "custom_scenes[0].illuminant: unknown illuminant")
    assert not (tmp_path / "r").exists()
