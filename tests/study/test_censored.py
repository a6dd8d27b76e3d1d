"""One rule for censored values (study/censored.py): the Kaplan-Meier median
against scipy's product-limit estimate (scipy.stats.ecdf on CensoredData,
an independent implementation), the distribution-free interval of a median
against the binomial coverage, metrics.csv's censored_count, the three
scoring conventions, and no value with bounds in only some realisations
printed as a bound anywhere in README, docs or the report."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.stats import CensoredData, binom, ecdf

from cfa_mitsuba.study.censored import (CONVENTIONS, apply_rule, bound_text, km_median, summarise,
                                        values_for_scoring)
from cfa_mitsuba.study.scoring import ScoreRange

REPO = Path(__file__).resolve().parents[2]


def _scipy_median(values, bounds):
    """The smallest measured value at which scipy's Kaplan-Meier survival function reaches 0.5."""
    v, b = np.asarray(values, float), np.asarray(bounds, bool)
    res = ecdf(CensoredData(uncensored=v[~b], right=v[b]))
    ok = np.flatnonzero(res.sf.probabilities <= 0.5 + 1e-12)
    return (float(res.sf.quantiles[ok[0]]), True) if ok.size else (None, False)


@pytest.mark.parametrize("seed", range(40))
def test_km_median_matches_scipy(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 12))
    values = np.round(rng.uniform(2, 24, n), 2)
    bounds = rng.random(n) < 0.4
    values[bounds] = np.maximum(values[bounds], 10.0)  # bounds sit high, as a chart's top does
    got, reached = km_median(values, bounds)
    want, want_reached = _scipy_median(values, bounds)
    assert reached == want_reached
    if reached:
        assert got == pytest.approx(want)


def test_the_issue_case_is_a_measurement_not_a_bound():
    """RGB5 bilinear in the committed paper study: 6.35 in four realisations, the chirp's top in two."""
    got = summarise([6.35196, 6.35196, 24.3764, 6.35196, 24.3764, 6.35196], [0, 0, 1, 0, 1, 0])
    assert got["value"] == pytest.approx(6.35196) and got["censored"] is False and got["censored_count"] == 2
    assert bound_text(got["value"], 2, got["censored"], 2, 6) == "6.35 (2 of 6 realisations bounds)"
    every = summarise([24.38] * 6, [1] * 6)
    assert every["censored"] and bound_text(every["value"], 2, True, 6, 6) == ">= 24.38"


@pytest.mark.parametrize("n", [6, 9, 12, 20])
def test_median_interval_has_its_binomial_coverage(n):
    """[x(k), x(n+1-k)] covers the median with probability P(k <= B <= n - k), B ~ Bin(n, 1/2):
    the largest k with coverage >= 95 %, from scipy's binomial."""
    v = np.arange(1.0, n + 1)
    got = summarise(v, np.zeros(n, bool))
    k = int(got["ci_low"])
    assert got["ci_high"] == n + 1 - k
    cover = lambda j: binom.cdf(n - j, n, 0.5) - binom.cdf(j - 1, n, 0.5)  # noqa: E731
    assert cover(k) >= 0.95 - 1e-12 and (k + 1 > n // 2 or cover(k + 1) < 0.95)


def test_conventions_score_a_bound_three_ways():
    rows = pd.DataFrame({"metric": ["moire"] * 3, "luminance": [100] * 3, "value": [4.0, 6.0, 24.0],
                         "censored": [False, False, True]})
    r = {"moire": ScoreRange(2.0, 24.0)}
    got = {c: values_for_scoring(rows, r, c)["value"].iloc[2] for c in CONVENTIONS}
    assert got == {"midpoint": 15.0, "bound": 24.0, "best measured": 6.0}


def test_old_metrics_tables_are_read_under_the_rule():
    """A metrics.csv written before censored_count: the count from the realisations, and a value
    with bounds in some of them replaced by their median."""
    real = pd.DataFrame({"scene": "chirp", "cfa": "rgb5", "demosaic": "bilinear", "luminance": 100.0,
                         "metric": "moire", "realisation": range(6),
                         "value": [6.35, 6.35, 24.38, 6.35, 24.38, 6.35], "censored": [0, 0, 1, 0, 1, 0]})
    old = pd.DataFrame({"scene": ["chirp"], "cfa": ["rgb5"], "demosaic": ["bilinear"], "luminance": [100.0],
                        "metric": ["moire"], "value": [12.36], "ci_low": [2.6], "ci_high": [22.1], "n": [6],
                        "censored": [True]})
    new = apply_rule(old, real)
    assert new["censored_count"].tolist() == [2] and new["censored"].tolist() == [False]
    assert new["value"].iloc[0] == pytest.approx(6.35)


def _mixed_values(folder: Path) -> list[str]:
    """The printed forms (two decimals) of values with bounds in some realisations only: the rule's
    value (their median) and the mean of bounds and measurements an older rule printed as a bound."""
    real = pd.read_csv(folder / "metrics_realisations.csv")
    m = pd.read_csv(folder / "metrics.csv")
    if "censored_count" not in m.columns:
        m = apply_rule(m, real)
    some = m[(m["censored_count"] > 0) & (m["censored_count"] < m["n"])]
    keys = ["scene", "cfa", "demosaic", "luminance", "metric"]
    means = real.merge(some[keys], on=keys).groupby(keys)["value"].mean()
    return [f"{v:.2f}" for v in some["value"]] + [f"{v:.2f}" for v in means]


def test_no_value_with_bounds_in_some_realisations_is_printed_as_a_bound(tmp_path):
    """README, docs/*.md and the report's tables rebuilt from the committed paper study: no value whose
    realisations are bounds only in part is printed after '>=' or '≥'."""
    from cfa_mitsuba.report.results import load_results
    from cfa_mitsuba.report.tables import table2

    folder = REPO / "docs" / "example-report"
    mixed = _mixed_values(folder)
    assert mixed, "the committed study has a value with bounds in some realisations (RGB5 with bilinear)"
    texts = {p.name: p.read_text() for p in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]}
    res = load_results(folder)
    texts["report Table 2"] = "".join(table2(res, lum) or "" for lum in res.base_luminances)
    for name, text in texts.items():
        plain = re.sub(r"<[^>]+>", "", text)
        for v in mixed:
            assert not re.search(rf"(>=|≥|&gt;=)\s*{re.escape(v)}\b", plain), (name, v)
    assert mixed[0] in texts["report Table 2"]  # the value is printed, as a measurement
    assert not math.isnan(float(mixed[0]))
