"""The variance-components model of study/variance.py: each component by
hand, the render component pooled over a scene and level's values, and the
property the per-value pre-test lacked: an interval that does not jump by
an order of magnitude with the draw of one render.

Expected numbers are worked by hand from the model's formulas (the ANOVA
estimate, Satterthwaite's degrees of freedom) with scipy's t quantile, an
independent implementation of the distribution; the coverage test draws
from the model itself and counts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import t as student_t

from cfa_mitsuba.study.intervals import aggregate, nested_interval, sensor_half_width
from cfa_mitsuba.study.variance import NO_POOL, cell, cell_interval, pool_render


def _satterthwaite(terms):
    """(sum, df) of [(variance term, its df)]."""
    total = sum(v for v, _ in terms)
    return total, total ** 2 / sum(v ** 2 / d for v, d in terms if math.isfinite(d))


def test_cell_mean_squares_by_hand():
    c = cell([1.0, 1.2, 1.4, 3.0, 3.1, 3.2], [0, 0, 0, 1, 1, 1])
    assert (c.n, c.renders, c.df_within, c.df_between, c.n0) == (6, 2, 4, 1, 3.0)
    assert c.ms_within == pytest.approx((0.08 + 0.02) / 4)
    assert c.ms_between == pytest.approx(3 * ((1.2 - 2.15) ** 2 + (3.1 - 2.15) ** 2))
    assert c.render_weight == pytest.approx(0.5)  # (9 + 9) / 36


def test_pooled_render_component_and_interval_by_hand():
    """Two values of one scene and level: the render variance from their mean
    squares together, each value's interval from it and its own within spread."""
    a = [1.0, 1.2, 1.4, 3.0, 3.1, 3.2]
    b = [2.0, 2.1, 2.3, 2.2, 2.3, 2.2]
    g = [0, 0, 0, 1, 1, 1]
    ca, cb = cell(a, g), cell(b, g)
    ms_b = (ca.ms_between + cb.ms_between) / 2
    ms_w = (ca.ms_within + cb.ms_within) / 2
    sigma_r2 = (ms_b - ms_w) / 3
    df_r = (ms_b - ms_w) ** 2 / (ms_b ** 2 / 2 + ms_w ** 2 / 8)
    pool = pool_render([ca, cb])
    assert pool.variance == pytest.approx(sigma_r2) and pool.df == pytest.approx(df_r) and pool.cells == 2
    var, df = _satterthwaite([(sigma_r2 / 2, df_r), (cb.ms_within / 6, 4)])
    mean, lo, hi, _, n = cell_interval(cb, pool)
    half = student_t.ppf(0.975, max(df, 1.0)) * math.sqrt(var)
    assert n == 6 and mean == pytest.approx(np.mean(b))
    assert hi - mean == pytest.approx(half, rel=1e-3) and mean - lo == pytest.approx(half, rel=1e-3)


def test_no_render_component_gives_the_sensor_only_interval():
    c = cell([1.0, 1.2, 1.1, 1.1, 1.0, 1.2], [0, 0, 0, 1, 1, 1])
    pool = pool_render([c])
    assert pool.variance == 0.0
    mean, lo, hi, _, _ = cell_interval(c, pool)
    assert hi - mean == pytest.approx(sensor_half_width([1.0, 1.2, 1.1, 1.1, 1.0, 1.2], [0, 0, 0, 1, 1, 1]))


def test_charts_and_single_renders_take_no_part_in_the_pool():
    one_render = cell([1.0, 2.0, 3.0])
    one_per_render = cell([1.0, 2.0], [0, 1])
    assert pool_render([one_render, one_per_render]) == NO_POOL
    assert cell_interval(one_render, NO_POOL)[1:3] == nested_interval([1.0, 2.0, 3.0])[1:3]


def test_one_render_drawn_again_moves_the_pooled_interval_little():
    """The coin flip of issue 46: one value's second render lands far from its
    first.  Judged on its own two renders (the pre-test's world) its interval
    grows by an order of magnitude; with the render component pooled over the
    scene and level's 48 values it moves by less than 2x (a render's shift
    leaves the value's within-render spread as it was; only its share of the
    pool moves)."""
    rng = np.random.default_rng(7)
    g = np.repeat([0, 1], 3)
    values = [rng.normal(0, 0.1, 2)[g] + rng.normal(0, 0.1, 6) for _ in range(48)]
    cells = [cell(v, g) for v in values]
    pool = pool_render(cells)
    first = values[0]
    flipped = first + np.where(g == 1, 1.0, 0.0)  # its second render drawn ten render sigmas away
    own = [cell_interval(cell(v, g))[2] - cell_interval(cell(v, g))[0] for v in (first, flipped)]
    pooled_pool = pool_render([cell(flipped, g), *cells[1:]])
    pooled = [cell_interval(cell(first, g), pool)[2] - np.mean(first),
              cell_interval(cell(flipped, g), pooled_pool)[2] - np.mean(flipped)]
    assert own[1] > 10 * own[0]
    assert pooled[1] < 2 * pooled[0]


@pytest.mark.parametrize("sigma_r", [0.0, 0.5, 1.0, 2.0])
def test_coverage_of_the_pooled_interval_is_nominal(sigma_r):
    """Values drawn from the model (R = 2 renders x S = 3 sensor seeds, 48
    values per pool, sigma_s = 1): the 95 % intervals cover the true mean
    (0) about 95 % of the time for every share of render noise."""
    rng = np.random.default_rng(11)
    g = np.repeat([0, 1], 3)
    hits = total = 0
    for _ in range(60):
        values = [rng.normal(0, sigma_r, 2)[g] + rng.normal(0, 1.0, 6) for _ in range(48)]
        cells = [cell(v, g) for v in values]
        pool = pool_render(cells)
        for c in cells:
            _, lo, hi, _, _ = cell_interval(c, pool)
            hits += lo <= 0.0 <= hi
            total += 1
    assert 0.93 <= hits / total <= 0.975


def test_aggregate_pools_by_the_named_columns_only():
    """Two metrics in one table: each pools its own values (different units
    must not share a render variance)."""
    import pandas as pd

    rng = np.random.default_rng(2)
    rows = []
    for metric, sr in (("loud", 5.0), ("quiet", 0.0)):
        for cfa in "abcdefgh":
            shift = rng.normal(0, sr, 2)
            for k in range(6):
                rows.append(dict(metric=metric, cfa=cfa, realisation=k, render_seed=k // 3,
                                 value=shift[k // 3] + rng.normal(0, 0.1)))
    df = pd.DataFrame(rows)
    pooled = aggregate(df, ["metric", "cfa"], "value", groups="render_seed", pool_by=["metric"]).set_index(["metric", "cfa"])
    alone = aggregate(df, ["metric", "cfa"], "value", groups="render_seed").set_index(["metric", "cfa"])
    half = (pooled["ci_high"] - pooled["ci_low"]) / 2
    sensor = df.groupby(["metric", "cfa"]).apply(
        lambda d: sensor_half_width(d["value"], d["render_seed"]), include_groups=False)
    assert (half.loc["loud"] > 5 * sensor.loc["loud"]).all()  # render noise seen in every loud value
    assert (half.loc["quiet"] / sensor.loc["quiet"]).median() < 2  # and not lent to the quiet ones
    assert not np.allclose(pooled["ci_high"], alone["ci_high"])
