"""report/render_noise.py on hand-made tables: the half-width ratios per
metric and the rank intervals against a baseline study's, and a clear
refusal of tables written before render seeds."""

from __future__ import annotations

import pandas as pd
import pytest

from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.report.render_noise import half_width_ratios, rank_changes, render_noise_md


def _metrics(rows):
    return pd.DataFrame([dict(scene=s, cfa=c, metric=m, value=1.0, ci_low=1.0 - h, ci_high=1.0 + h, render_seeds=r,
                              sensor_half_width=sh) for s, c, m, h, r, sh in rows])


def _scores(rows):
    return pd.DataFrame([dict(cfa=c, luminance=100.0, total_score=t, total_rank=k, total_rank_best=b,
                              total_rank_worst=w) for c, t, k, b, w in rows])


@pytest.fixture
def study(tmp_path):
    out, base = tmp_path / "new", tmp_path / "old"
    out.mkdir(), base.mkdir()
    _metrics([("puppy", "a", "ssim", 0.02, 2, 0.01), ("puppy", "b", "ssim", 0.06, 2, 0.01),
              ("puppy", "c", "ssim", 0.04, 2, 0.01), ("puppy", "a", "mdsi", 0.5, 2, 0.1),
              ("macbeth", "a", "delta-e", 0.3, 1, 0.3)]).to_csv(out / "metrics.csv", index=False)
    _scores([("a", 0.7, 1, 1, 2), ("b", 0.6, 2, 1, 2), ("c", 0.2, 3, 3, 3)]).to_csv(out / "scores.csv", index=False)
    _scores([("a", 0.71, 1, 1, 1), ("b", 0.6, 2, 2, 2), ("c", 0.2, 3, 3, 3)]).to_csv(base / "scores.csv", index=False)
    return tmp_path


def test_ratios_are_medians_over_the_path_traced_values(study):
    r = half_width_ratios(study / "new").set_index("metric")
    assert list(r.index) == ["ssim", "mdsi"]  # the chart's dE (one render) is not counted
    assert r.loc["ssim", "values"] == 3 and r.loc["ssim", "median_ratio"] == pytest.approx(4.0)
    assert r.loc["ssim", "max_ratio"] == pytest.approx(6.0) and r.loc["mdsi", "median_ratio"] == pytest.approx(5.0)


def test_rank_changes_against_a_baseline(study):
    t, source = rank_changes(study / "new", study / "old")
    assert source.endswith("scores.csv") and list(t.index) == ["a", "b", "c"]
    assert (t.loc["a", "total_rank_worst"], t.loc["a", "total_rank_worst_sensor"]) == (2, 1)
    md = render_noise_md(study, "new", "old")
    assert "| `a` | 0.7000 | 1–2 | 1 |" in md and "2 of 3 CFAs" in md and "a, b (sensor noise only: a)" in md


def test_tables_without_render_seeds_are_refused_by_name(study):
    pd.read_csv(study / "new" / "metrics.csv").drop(columns="sensor_half_width").to_csv(
        study / "new" / "metrics.csv", index=False)
    with pytest.raises(CfaMitsubaError, match="no sensor_half_width column"):
        half_width_ratios(study / "new")
