"""The paper's claims judged by the stated rule, recomputed from the committed CSVs.

The rule (docs/paper-comparison.md, "How a verdict is reached"): a claim
holds only when every comparison it makes is separated by the 95 %
intervals in the claimed direction, is a tie when none is reversed but some
overlap, and differs when one is separated the other way; group claims are
judged CFA against CFA.  The recomputation here is written from that
sentence on the raw CSV rows, not through the package's judge, and must
find the verdict docs/paper-comparison.md prints.
"""

from __future__ import annotations

import itertools
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.report import claim_verdicts

REPO = Path(__file__).resolve().parents[1]
PAGE = REPO / "docs" / "paper-comparison.md"
CLAIMS = tomllib.loads((REPO / "cfa_mitsuba" / "data" / "paper" / "claims.toml").read_text())["claim"]
#: the page's column for each committed run (a run whose folder is not committed is not on the page)
RUNS = {"ours, defaults": REPO / "docs" / "example-report",
        "ours, ISETCam procedure": REPO / "docs" / "example-report-isetcam"}
HIGHER_IS_BETTER = {"delta-e76": False, "delta-e": False, "delta-l": False, "scielab": False, "ssim": True,
                    "mtf": True, "moire": True, "achromatic": False, "mdsi": False, "haarpsi": True}


def _page_verdicts() -> dict:
    """{column label: {claim text: verdict}} from the page's glance table."""
    text = PAGE.read_text()
    table = text.split("## Verdicts at a glance")[1].split("\n## ")[0].strip().splitlines()
    header = [c.strip() for c in table[0].strip("|").split("|")]
    out = {h: {} for h in header[2:]}
    for line in table[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        for h, c in zip(header[2:], cells[2:]):
            out[h][cells[0]] = c.replace("*", "")
    return out


def _intervals(folder: Path, metric: str, demosaic: str) -> dict:
    m = pd.read_csv(folder / "metrics.csv")
    m = m[m["base"].astype(str).str.lower().isin(("true", "1"))]
    m = m[(m["luminance"] == m["luminance"].min()) & (m["metric"] == metric) & (m["demosaic"] == demosaic)]
    return {r.cfa: (r.value, r.ci_low, r.ci_high) for r in m.itertuples(index=False)}


def _by_rule(folder: Path, claim: dict) -> str:
    """The verdict, from the rule's sentence on the CSV rows."""
    if claim["kind"] == "best":
        # "best" needs a rank interval of exactly 1; another CFA is surely better when this one's best rank is
        # above 1 (scores.csv's rank intervals: paired comparisons where the study kept its realisations)
        s = pd.read_csv(folder / "scores.csv")
        s = s[s["luminance"] == s["luminance"].min()]
        if claim["demosaic"] == "total":
            rows = s.drop_duplicates("cfa").set_index("cfa")[["total_rank_best", "total_rank_worst"]]
        else:
            rows = s[s["demosaic"] == claim["demosaic"]].drop_duplicates("cfa").set_index("cfa")[
                ["demosaic_rank_best", "demosaic_rank_worst"]]
        best, worst = rows.loc[claim["cfa"]]
        return "differs" if best > 1 else "holds" if worst == 1 else "tie"
    vals = _intervals(folder, claim["metric"], claim["demosaic"])
    hib = HIGHER_IS_BETTER[claim["metric"]]
    if claim["kind"] == "order":
        results = []
        for gi, gj in itertools.combinations(claim["groups"], 2):
            for a, b in itertools.product(gi, gj):
                (_, a_lo, a_hi), (_, b_lo, b_hi) = vals[a], vals[b]
                a_better = a_lo > b_hi if hib else a_hi < b_lo
                b_better = b_lo > a_hi if hib else b_hi < a_lo
                results.append("ok" if a_better else "rev" if b_better else "tie")
        return "differs" if "rev" in results else "tie" if "tie" in results else "holds"
    rows = [vals[c] for c in claim["cfas"]]
    if claim["kind"] == "similar":
        outer = max(r[2] for r in rows) - min(r[1] for r in rows)
        inner = max(r[1] for r in rows) - min(r[2] for r in rows)
        return "holds" if outer <= claim["max_range"] else "differs" if inner > claim["max_range"] else "tie"
    if claim["kind"] == "at_most":
        return ("holds" if all(r[2] <= claim["max_value"] for r in rows)
                else "differs" if any(r[1] > claim["max_value"] for r in rows) else "tie")
    raise AssertionError(f"unknown kind {claim['kind']}")


def test_the_page_states_the_rule():
    text = PAGE.read_text()
    assert "## How a verdict is reached" in text
    assert "judged pairwise" in text and "rank interval is exactly 1" in text


@pytest.mark.parametrize("column", list(RUNS))
def test_every_claims_verdict_follows_from_the_committed_csvs(column):
    folder = RUNS[column]
    page = _page_verdicts()
    if not (folder / "metrics.csv").is_file():
        # a run that is not committed must not be on the page either: nothing could check its verdicts
        assert column not in page, f"the page has a {column!r} column but {folder} is not committed"
        return
    assert column in page, f"{folder} is committed but the page has no {column!r} column"
    for claim in CLAIMS:
        assert page[column][claim["text"]] == _by_rule(folder, claim), claim["id"]


def test_pairwise_both_directions_and_overlap():
    hi = [("a", 2.0, 1.9, 2.1)]
    lo = [("b", 1.0, 0.9, 1.1)]
    assert claim_verdicts.order_verdict([hi, lo], True)[0] == "holds"
    assert claim_verdicts.order_verdict([lo, hi], True)[0] == "differs"
    assert claim_verdicts.order_verdict([lo, hi], False)[0] == "holds"
    assert claim_verdicts.order_verdict([hi, lo], False)[0] == "differs"
    touching = [("c", 1.5, 1.1, 1.9)]
    assert claim_verdicts.order_verdict([touching, lo], True)[0] == "tie"  # 1.1 is not above 1.1
    # a group whose mean is better but one member reversed: differs
    assert claim_verdicts.order_verdict([[*hi, ("d", 0.5, 0.4, 0.6)], lo], True)[0] == "differs"


def test_best_claim_needs_a_rank_interval_of_exactly_one():
    assert claim_verdicts.best_verdict(1, 1) == "holds"
    assert claim_verdicts.best_verdict(1, 3) == "tie"
    assert claim_verdicts.best_verdict(2, 6) == "differs"


@pytest.mark.parametrize("rho, lo, hi", [(0.78, 0.36, 0.94), (0.73, 0.25, 0.92)])
def test_spearman_interval_matches_fisher_z_for_twelve_cfas(rho, lo, hi):
    """The issue's ranges for 12 CFAs (Fisher z, se sqrt(1.06 / 9)), from a
    ranking built to have that rho: the interval depends on rho and n only."""
    from scipy.stats import norm

    half = norm.ppf(0.975) * np.sqrt(1.06 / 9)
    assert np.tanh(np.arctanh(rho) - half) == pytest.approx(lo, abs=0.006)
    assert np.tanh(np.arctanh(rho) + half) == pytest.approx(hi, abs=0.006)
    # the package's function on two rankings with a known rho
    a = np.arange(12)
    got = claim_verdicts.spearman_interval(a, a)
    assert got[:3] == (1.0, 1.0, 1.0)
    b = np.array([1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10])  # rho = 1 - 6 * 12 / (12 * 143) = 0.958
    rho_b, lo_b, hi_b, n = claim_verdicts.spearman_interval(a, b)
    assert rho_b == pytest.approx(1 - 6 * 12 / (12 * 143)) and n == 12
    assert np.tanh(np.arctanh(rho_b) - half) == pytest.approx(lo_b) and lo_b < rho_b < hi_b


def test_the_page_is_what_the_committed_runs_generate(tmp_path):
    """Every number of docs/paper-comparison.md comes from the committed runs: regenerating it changes nothing."""
    from cfa_mitsuba.report.paper_comparison import write_comparison

    committed = {k: v for k, v in RUNS.items() if (v / "metrics.csv").is_file()}
    out = write_comparison(tmp_path / "page.md", default=committed.get("ours, defaults"),
                           isetcam=committed.get("ours, ISETCam procedure"))
    assert out.read_text() == PAGE.read_text()


def test_order_claims_use_paired_differences_where_the_run_has_them():
    """Marginal intervals overlap (a tie), the paired difference is separated:
    with paired differences the claim holds; reversed, it differs."""
    from cfa_mitsuba.report.claim_verdicts import order_verdict

    groups = [[("a", 2.0, 1.0, 3.0)], [("b", 1.9, 0.9, 2.9)]]
    assert order_verdict(groups, True)[0] == "tie"
    verdict, words = order_verdict(groups, True, lambda x, y: (0.05, 0.15))
    assert verdict == "holds" and "paired differences" in words
    assert order_verdict(groups, False, lambda x, y: (0.05, 0.15))[0] == "differs"
    assert order_verdict(groups, True, lambda x, y: (-0.05, 0.15))[0] == "tie"
    assert order_verdict(groups, True, lambda x, y: None)[0] == "tie"  # no realisations: the marginal rule


def test_run_pairs_realisations_by_index(tmp_path):
    import pandas as pd

    from cfa_mitsuba.report.paper_data import load_run

    rows = [dict(scene="macbeth", cfa=c, demosaic="bilinear", luminance=100, base=True, metric="delta-e", value=v,
                 ci_low=v - 1, ci_high=v + 1, unit="", realisation=k, render_seed=0)
            for c, vals in (("bayer", (2.0, 3.0, 4.0)), ("rgb4", (2.1, 3.1, 4.1))) for k, v in enumerate(vals)]
    pd.DataFrame(rows).to_csv(tmp_path / "metrics_realisations.csv", index=False)
    pd.DataFrame(rows).drop_duplicates("cfa").to_csv(tmp_path / "metrics.csv", index=False)
    run = load_run(tmp_path, "k", "label")
    lo, hi = run.paired("delta-e", "bilinear", "bayer", "rgb4")
    assert lo == pytest.approx(-0.1) and hi == pytest.approx(-0.1)
    assert run.paired("delta-e", "pocs", "bayer", "rgb4") is None
