"""A study from Python (issue 50): ``cm.study.run`` returns the tables as
pandas DataFrames and the report's path; ``cm.study.load`` reads the same
directory the same way; bad input is one line."""

from __future__ import annotations

import pandas as pd
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError

CONFIG = {
    "name": "api", "seed": 2, "seeds": 2,
    "scenes": ["macbeth", "gray-bar"], "cfas": ["bayer", "rgbw1"], "demosaics": ["bilinear"],
    "luminances": [100],
    "sweep": [{"scene": "gray-bar", "metrics": ["ysnr"], "luminances": [10, 100]}],
    "render": {"macbeth": {"width": 120, "height": 106}, "gray-bar": {"width": 250, "height": 60}},
    "output": {"figures": ["png"], "thumbnails": False},
}


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    out = tmp_path_factory.mktemp("api") / "out"
    return out, cm.study.run(CONFIG, out, workers=1, quiet=True)


def test_run_returns_the_tables_as_dataframes(ran):
    out, r = ran
    for name in ("metrics", "scores", "decisions", "snr", "patches", "steps"):
        assert isinstance(getattr(r, name), pd.DataFrame), name
    assert r.mtf is None  # no slanted edge in this study
    assert r.report_path == out / "report.html" and r.report_path.is_file()
    assert set(r.metrics["cfa"]) == {"bayer", "rgbw1"}
    assert pd.read_csv(out / "metrics.csv").equals(r.metrics)
    assert set(r.snr["luminance"]) == {10.0, 100.0}
    assert "report_s" in r.timing["phases"]


def test_load_reads_the_same(ran):
    out, r = ran
    again = cm.study.load(out)
    for name in ("metrics", "scores", "decisions", "snr", "steps"):
        assert getattr(again, name).equals(getattr(r, name)), name
    assert again.config["name"] == "api" and "tables metrics, scores, decisions, snr" in repr(again)


def test_tables_only_and_bad_input(tmp_path):
    r = cm.study.run({**CONFIG, "scenes": ["macbeth"], "sweep": []}, tmp_path / "t", workers=1, quiet=True,
                     report=False)
    assert r.report_path is None and r.snr is None and len(r.patches) == 2 * 24
    with pytest.raises(CfaMitsubaError, match="no such results directory"):
        cm.study.load(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(CfaMitsubaError, match="no metrics.csv"):
        cm.study.load(tmp_path / "empty")
    with pytest.raises(CfaMitsubaError, match="config path, a dict or a StudyConfig"):
        cm.study.run(42)
