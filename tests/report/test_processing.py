"""The report's 'With noise reduction' section (report/processing.py) from a
small real study that sweeps the denoise axis: the trade-off figure, the
per-CFA table's YSNR from snr.csv, the gain sentence, the low-light
decisions per setting; and no section for a study without the axis."""

from __future__ import annotations

import re

import pandas as pd
import pytest
from report_fixtures import study_dir

from cfa_mitsuba.report import build_report

STUDY_TOML = """
name = "denoise-test"
description = "tiny study with the denoise axis"
seed = 1
seeds = 2
scenes = ["gray-bar", "dead-leaves"]
cfas = ["bayer", "rgbw1"]
demosaics = ["bilinear"]
luminances = [100]

[[sweep]]
scene = "gray-bar"
metrics = ["ysnr"]
luminances = [1, 3, 12, 100]
denoise = ["none", "nl-means"]

[[sweep]]
scene = "dead-leaves"
metrics = ["texture-acutance"]
luminances = [3, 100]
denoise = ["none", "nl-means"]

[render.gray-bar]
width = 160
height = 100
[render.dead-leaves]
width = 640
height = 512
"""


@pytest.fixture(scope="module")
def denoise_study(tmp_path_factory):
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import run_study

    base = tmp_path_factory.mktemp("denoise-study")
    (base / "study.toml").write_text(STUDY_TOML)
    out = base / "results"
    run_study(load_config(base / "study.toml"), out, workers=1, progress=False, log=lambda msg: None)
    return out


def _section(page: str) -> str:
    start = page.index('<section id="processing">')
    return page[start:page.index("</section>", page.index("Low-light decisions", start))]


def test_the_section_shows_what_noise_reduction_buys_and_costs(denoise_study):
    page = build_report(denoise_study, formats=(), workers=1).read_text()
    sec = _section(page)
    assert 'data-figure="acutance-ysnr-bilinear"' in sec
    snr = pd.read_csv(denoise_study / "snr.csv")
    at3 = snr[snr["luminance"] == 3].set_index(["cfa", "denoise"])["ysnr"]
    text = re.sub(r"<[^>]+>", " ", sec)
    for cfa in ("bayer", "rgbw1"):
        for dn in ("none", "nl-means"):
            assert f"{at3[(cfa, dn)]:.3g}" in text, (cfa, dn)  # the table's YSNR at 3 cd/m^2 is snr.csv's
    gains = at3.xs("nl-means", level="denoise") / at3.xs("none", level="denoise")
    m = re.search(r"denoise nl-means multiplies YSNR by ([\d.]+) to ([\d.]+)", text)
    assert m and float(m.group(1)) == pytest.approx(gains.min(), abs=0.006)
    assert float(m.group(2)) == pytest.approx(gains.max(), abs=0.006)
    assert gains.min() > 1.5  # the denoiser does reduce noise where it acts
    decisions = pd.read_csv(denoise_study / "decisions.csv")
    assert "low light with denoise nl-means" in set(decisions["aspect"])
    assert "low light with denoise nl-means" in text or "with denoise nl-means" in text


def test_no_section_without_a_processing_setting(tmp_path_factory):
    page = build_report(study_dir(tmp_path_factory), formats=(), workers=1).read_text()
    assert '<section id="processing">' not in page and 'href="#processing"' not in page
