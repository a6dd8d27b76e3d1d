"""A study with a third-party scene file end to end (issue 14 deliver 5):
camera and lights in included files, mesh through <path>, textured floor,
thin lens, conductor and dielectric; and allow_outside_paths in a config."""

import shutil

import numpy as np
import pandas as pd

from conftest import REPO, run_cli

SCENE = REPO / "tests" / "data" / "scenes" / "tabletop"


def test_study_with_a_scene_file_runs_end_to_end(tmp_path):
    shutil.copytree(SCENE, tmp_path / "tabletop")
    outside = tmp_path / "assets"
    outside.mkdir()
    shutil.move(tmp_path / "tabletop" / "textures" / "checker.png", outside / "checker.png")
    main = tmp_path / "tabletop" / "tabletop.xml"
    main.write_text(main.read_text().replace("textures/checker.png", "../assets/checker.png"))
    config = tmp_path / "study.toml"
    body = """
name = "tabletop"
scenes = []
cfas = ["bayer", "rgbw1"]
demosaics = ["bilinear"]
luminances = [100]

[[custom_scenes]]
name = "tabletop"
file = "tabletop/tabletop.xml"
width = 128   # 2.8 pixels per degree of its 45-degree field: S-CIELAB needs 2
height = 96
spp = 9
{extra}

[output]
figures = []
"""
    config.write_text(body.format(extra=""))
    refused = run_cli("study", config, "--out", tmp_path / "refused", "--quiet")
    assert refused.returncode != 0 and "outside the scene's folder" in refused.stdout + refused.stderr
    config.write_text(body.format(extra="allow_outside_paths = true"))
    proc = run_cli("study", config, "--out", tmp_path / "out", "--quiet")
    assert proc.returncode == 0, proc.stderr
    metrics = pd.read_csv(tmp_path / "out" / "metrics.csv")
    rows = metrics[metrics["scene"] == "tabletop"]
    assert set(rows["metric"]) >= {"scielab", "ssim", "mdsi", "haarpsi"}
    assert set(rows["cfa"]) == {"bayer", "rgbw1"} and np.isfinite(rows["value"]).all()
    assert not (tmp_path / "out" / "failures.csv").exists()
