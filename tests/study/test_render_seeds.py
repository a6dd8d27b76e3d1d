"""``render_seeds``: path-traced scenes rendered with several sampler seeds,
every value's realisations spanning render seeds x sensor seeds, paired
across CFAs (study/config.py, runner.py, tasks.py, sizing.py, tables.py)."""

from __future__ import annotations

import dataclasses
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.study.config import load_config
from conftest import REPO

TINY = """
name = "tiny"
seed = 1
seeds = 2
render_seeds = {render_seeds}
scenes = ["macbeth", "puppy"]
cfas = ["bayer", "rgbw1"]
demosaics = ["bilinear"]
luminances = [100]
[render.macbeth]
width = 60
height = 53
[render.puppy]
width = 60
height = 53
spp = 4
[output]
figures = []
report = false
"""


def _config(tmp_path: Path, render_seeds="2"):
    p = tmp_path / "tiny.toml"
    p.write_text(textwrap.dedent(TINY.format(render_seeds=render_seeds)))
    return load_config(p)


@pytest.mark.parametrize("value, why", [("0", "at least 1"), ('"two"', "must be an integer"), ("1.5", "integer")])
def test_bad_render_seeds_are_refused_by_key(tmp_path, value, why):
    with pytest.raises(CfaMitsubaError, match=rf"render_seeds: .*{why}"):
        _config(tmp_path, value)


def test_default_is_one_render_and_the_shipped_configs_say_theirs(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text(TINY.replace("render_seeds = {render_seeds}\n", ""))
    assert load_config(p).render_seeds == 1
    assert load_config(REPO / "configs" / "paper.toml").render_seeds == 2
    assert load_config(REPO / "configs" / "quick.toml").render_seeds == 1


def test_plan_renders_the_puppy_per_seed_and_the_chart_once(tmp_path):
    from cfa_mitsuba.study.render_seeds import path_traced
    from cfa_mitsuba.study.runner import plan_study

    cfg = _config(tmp_path)
    assert [path_traced(s) for s in cfg.scenes] == [False, True]
    sources, tasks = plan_study(cfg, None)
    puppy = [s for s in sources if s["scene"] == "puppy"]
    assert sorted(int(s["settings"].get("seed") or 0) for s in puppy) == [0, 1]
    assert len([s for s in sources if s["scene"] == "macbeth"]) == 1
    # realisations: the chart's task holds all R x S, the puppy's one task per render seed holds S
    for t in tasks:
        if t.scene == "macbeth":
            assert (t.realisations, t.realisation_offset, t.render_seed) == (4, 0, 0)
        else:
            assert t.realisations == 2 and t.realisation_offset == 2 * t.render_seed
    # distinct resume keys
    from cfa_mitsuba.study.runner import _task_id

    assert len({_task_id(t) for t in tasks}) == len(tasks) == 2 * (1 + 2)


def test_realisation_seeds_pair_across_cfas_and_keep_the_first():
    from cfa_mitsuba.study.tasks import realisation_seeds, task_seed

    seeds = realisation_seeds(1, "puppy", 100.0, 2, offset=2)
    assert seeds == [task_seed(1, "puppy", 100.0, 2), task_seed(1, "puppy", 100.0, 3)]
    assert realisation_seeds(1, "puppy", 100.0, 4)[2:] == seeds  # the same k, the same seed, whatever the task
    assert realisation_seeds(1, "puppy", 100.0, 1) == [task_seed(1, "puppy", 100.0)]
    assert len(set(realisation_seeds(1, "puppy", 100.0, 4))) == 4


def test_size_counts_render_seeds(tmp_path):
    from cfa_mitsuba.study.sizing import study_size

    one, two = (study_size(_config(tmp_path, str(n)), 1) for n in (1, 2))
    # captures: (1 chart + 1 puppy condition) x 2 CFAs x 2 seeds x render_seeds
    assert (one.captures, two.captures) == (8, 16)
    assert (one.tasks, two.tasks) == (4, 6)  # the puppy: one task per render seed
    assert two.seconds > one.seconds


def test_tiny_study_pairs_realisations_and_reports_the_render_share(tmp_path):
    from cfa_mitsuba.study.runner import run_study

    cfg = _config(tmp_path)
    run_study(cfg, tmp_path / "out", workers=1, progress=False, log=lambda m: None)
    every = pd.read_csv(tmp_path / "out" / "metrics_realisations.csv")
    means = pd.read_csv(tmp_path / "out" / "metrics.csv")
    assert set(every["realisation"]) == {0, 1, 2, 3}
    pup, mac = every[every["scene"] == "puppy"], every[every["scene"] == "macbeth"]
    assert (pup["render_seed"] == pup["realisation"] // 2).all() and (mac["render_seed"] == 0).all()
    # the same realisation of both CFAs: the same capture seed (exposure aside, the noise differs by CFA only
    # through the mosaic); realisations of one CFA differ
    ssim = pup[pup["metric"] == "ssim"].pivot(index="realisation", columns="cfa", values="value")
    assert ssim["bayer"].nunique() == 4
    by = means.set_index(["scene", "metric", "cfa"])
    assert (means["n"] == 4).all()
    assert (by.xs("macbeth", level="scene")["render_seeds"] == 1).all()
    assert (by.xs("puppy", level="scene")["render_seeds"] == 2).all()
    half = (means["ci_high"] - means["ci_low"]) / 2
    mac_rows = means["scene"] == "macbeth"
    assert np.allclose(half[mac_rows], means.loc[mac_rows, "sensor_half_width"], rtol=1e-6, atol=1e-9)
    assert (means["sensor_half_width"] >= 0).all()
    scores = pd.read_csv(tmp_path / "out" / "scores.csv")
    assert (scores["total_rank_best"] <= scores["total_rank"]).all()
    assert (scores["total_rank"] <= scores["total_rank_worst"]).all()
    assert (tmp_path / "out" / "decisions.csv").is_file()
    # the interval of a value from its realisations: the render component pooled over the scene and
    # metric's values (both CFAs), the sensor component the value's own (study/variance.py)
    from cfa_mitsuba.study.variance import cell, cell_interval, pool_render

    for (scene, metric), pool_rows in every.groupby(["scene", "metric"]):
        cells = {cfa: cell(g["value"], g["render_seed"]) for cfa, g in pool_rows.groupby("cfa")}
        pool = pool_render(list(cells.values()))
        for cfa, c in cells.items():
            mean, lo, hi, _, n = cell_interval(c, pool)
            row = by.loc[(scene, metric, cfa)]
            assert row["value"] == pytest.approx(mean, rel=1e-8)
            assert row["ci_low"] == pytest.approx(lo, rel=1e-6, abs=1e-9)
    # a second run with render_seeds = 1 reuses render 0 and realisations 0, 1 of the sensor seeds
    cfg1 = dataclasses.replace(cfg, render_seeds=1)
    run_study(cfg1, tmp_path / "one", workers=1, progress=False, log=lambda m: None)
    one = pd.read_csv(tmp_path / "one" / "metrics_realisations.csv")
    keys = ["scene", "cfa", "demosaic", "metric", "realisation"]
    both = one.merge(every, on=keys, suffixes=("_1", "_2"))
    assert len(both) == len(one) and np.allclose(both["value_1"], both["value_2"], rtol=1e-9)


def test_render_noise_generator_on_the_tiny_study(tmp_path):
    """The docs generator (report/render_noise.py): its rescoring path gives
    scores.csv's totals back from every realisation, and its table names
    every path-traced metric."""
    from cfa_mitsuba.report.render_noise import half_width_ratios, render_noise_md, sensor_only_ranks
    from cfa_mitsuba.study.runner import run_study

    run_study(_config(tmp_path), tmp_path / "out", workers=1, progress=False, log=lambda m: None)
    out = tmp_path / "out"
    again = sensor_only_ranks(out, render_seed=None).set_index("cfa")
    scores = pd.read_csv(out / "scores.csv").drop_duplicates("cfa").set_index("cfa")
    assert np.allclose(again.loc[scores.index, "total_score"], scores["total_score"], rtol=1e-9)
    assert (again.loc[scores.index, "total_rank_worst"] == scores["total_rank_worst"]).all()
    r = half_width_ratios(out).set_index("metric")
    assert {"scielab", "ssim", "mdsi", "haarpsi"} <= set(r.index) and "delta-e" not in r.index
    means = pd.read_csv(out / "metrics.csv").query("scene == 'puppy' and metric == 'mdsi'")
    ratio = ((means["ci_high"] - means["ci_low"]) / 2 / means["sensor_half_width"]).median()
    assert r.loc["mdsi", "median_ratio"] == pytest.approx(ratio)
    md = render_noise_md(tmp_path, "out")
    assert "| `bayer` |" in md and "sensor noise only" in md
