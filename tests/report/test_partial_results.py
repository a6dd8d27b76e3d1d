"""The report of partial and unusual results directories: it draws what the
data supports, says what is absent, and never fails.

Each case is cut from the small study of tests/report_fixtures.py
(copied, then edited on disk as a user's directory could be).
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pandas as pd
import pytest

from report_fixtures import study_dir

pytestmark = pytest.mark.slow


@pytest.fixture
def results(tmp_path_factory, tmp_path) -> Path:
    """A private copy of the study's results directory."""
    out = tmp_path / "results"
    shutil.copytree(study_dir(tmp_path_factory), out)
    return out


def _build(path: Path, **kw) -> str:
    from cfa_mitsuba.report import build_report

    kw.setdefault("formats", ())
    page = build_report(path, **kw)
    text = page.read_text(encoding="utf-8")
    assert "could not be drawn" not in text, re.findall(r"could not be drawn[^<]*", text)
    return text


def _figures(text: str) -> set[str]:
    return set(re.findall(r'data-figure="([^"]+)"', text))


def _rewrite(path: Path, fn) -> None:
    df = pd.read_csv(path, keep_default_na=False)
    fn(df).to_csv(path, index=False)


def test_metrics_csv_alone(results):
    """What ``cfa-mitsuba evaluate`` leaves: metrics.csv only.  The report
    scores it itself and says which figures need the study's details."""
    for p in results.iterdir():
        if p.name != "metrics.csv":
            shutil.rmtree(p) if p.is_dir() else p.unlink()
    text = _build(results)
    assert "scores.csv is absent" in text
    assert {"radar-demosaic", "radar-cfa", "ranks", "luminance-sweep"} <= _figures(text)
    assert "details" in text and "are missing" in text
    assert 'id="table3"' in text


def test_one_cfa_one_demosaic(results):
    keep = lambda df: df[(df["cfa"] == "bayer") & (df["demosaic"] == "bilinear")]  # noqa: E731
    _rewrite(results / "metrics.csv", keep)
    (results / "scores.csv").unlink()  # rescored here for the one CFA
    shutil.rmtree(results / "details" / "macbeth" / "rgbw1")
    text = _build(results)
    figs = _figures(text)
    assert {"ab-bilinear", "xy-bilinear", "mtf", "moire", "achromatic", "scielab-maps", "radar-cfa"} <= figs
    assert not any(f.endswith("-pocs") for f in figs)
    assert "rgbw1</th>" not in text


def test_a_custom_scene_instead_of_puppy(results):
    """A user scene called 'living-room' feeds the image metrics and the sweep."""
    def rename(df):
        df["scene"] = df["scene"].replace({"puppy": "living-room"})
        return df

    _rewrite(results / "metrics.csv", rename)
    _rewrite(results / "scores.csv", rename)
    (results / "details" / "puppy").rename(results / "details" / "living-room")
    cfg = json.loads((results / "config.json").read_text())
    for s in cfg["scenes"]:
        if s["name"] == "puppy":
            s["name"], s["file"] = "living-room", "/home/user/scenes/living-room.xml"
    cfg["sweeps"][0]["scene"] = "living-room"
    (results / "config.json").write_text(json.dumps(cfg))
    text = _build(results)
    assert {"scielab-maps", "luminance-sweep", "outputs-living-room"} <= _figures(text)
    assert "living-room" in text and "living-room.xml" in text and "/home/user" not in text


def test_toml_cfa_names_with_odd_characters(results):
    """A TOML CFA's name is its label; the details folder holds a safe form of it."""
    from cfa_mitsuba.report.results import safe_label

    odd = 'my <cfa> "v2"/β $x'
    for path in (results / "metrics.csv", results / "scores.csv"):
        _rewrite(path, lambda df: df.assign(cfa=df["cfa"].replace({"rgbw1": odd})))
    for scene_dir in (results / "details").iterdir():
        if (scene_dir / "rgbw1").is_dir():
            (scene_dir / "rgbw1").rename(scene_dir / safe_label(odd))
    text = _build(results, formats=("png",))
    assert "my &lt;cfa&gt; &quot;v2&quot;/β $x" in text and "<cfa>" not in text
    assert {"ab-bilinear", "mtf", "scielab-maps", "outputs-puppy"} <= _figures(text)
    assert (results / "figures" / "mtf.png").is_file()


def test_only_some_scenes(results):
    drop = {"slanted-edge", "chirp"}
    for path in (results / "metrics.csv", results / "scores.csv"):
        _rewrite(path, lambda df: df[~df["scene"].isin(drop)])
    for s in drop:
        shutil.rmtree(results / "details" / s)
    cfg = json.loads((results / "config.json").read_text())
    cfg["scenes"] = [s for s in cfg["scenes"] if s["name"] not in drop]
    (results / "config.json").write_text(json.dumps(cfg))
    text = _build(results)
    figs = _figures(text)
    assert "mtf" not in figs and "moire" not in figs and "ab-pocs" in figs
    assert "Not in this study" in text and "slanted edge" in text and "the chirp" in text
    assert 'id="mtf"' not in text  # no empty section


def test_no_sweep_no_thumbnails_no_timing(results):
    _rewrite(results / "metrics.csv", lambda df: df[df["luminance"] == 100])
    (results / "timing.json").unlink()
    text = _build(results, thumbnails=False)
    assert "luminance-sweep" not in _figures(text) and "a luminance sweep" in text
    assert not any(f.startswith("outputs-") for f in _figures(text))
    assert "thumbnails are turned off" in text
    assert "Run time" not in text


def test_header_only_metrics(results):
    (results / "metrics.csv").write_text("scene,cfa,demosaic,luminance,metric,value,unit\n")
    (results / "scores.csv").unlink()
    text = _build(results)
    assert "holds no measurements" in text and not _figures(text)


def test_two_base_luminances(results):
    """Scores at two levels: Tables 2-3 once per level, figures at 100 cd/m²."""
    from cfa_mitsuba.study.scoring import score

    m = pd.read_csv(results / "metrics.csv", keep_default_na=False)
    extra = m[m["luminance"] == 100].copy()
    extra["luminance"] = 50.0
    extra["value"] = extra["value"] * 1.01
    both = pd.concat([m[m["luminance"] != 30], extra])
    both.to_csv(results / "metrics.csv", index=False)
    from cfa_mitsuba.metrics import scored_metrics

    scored = both[both["metric"].isin(scored_metrics())]
    score(scored.assign(unit=scored["unit"].replace({"": ""}))).to_csv(results / "scores.csv", index=False)
    cfg = json.loads((results / "config.json").read_text())
    cfg["luminances"] = [50.0, 100.0]
    (results / "config.json").write_text(json.dumps(cfg))
    text = _build(results)
    assert text.count('id="table3"') == 2 and "at 50 cd/m²" in text and "at 100 cd/m²" in text
    assert "radar-demosaic" in _figures(text)
