"""The paper's claims judged by the stated rule, recomputed from the committed CSVs.

The rule (docs/paper-comparison.md, "How a verdict is reached"): a claim
holds only when every comparison it makes is separated by the 95 %
intervals in the claimed direction, is a tie when none is reversed but some
are not separated, and differs when one is separated the other way; group
claims are judged CFA against CFA, each pair on its paired difference where
the run kept its realisations (the render component of the differences
pooled over every pair of the metric and demosaic, as the study's rank
intervals), on the two marginal intervals otherwise; a "best" claim by the
study's decision rule (decisions.csv).  The recomputation here is written
from that sentence on the raw CSV rows, not through the package's judge,
and must find the verdict docs/paper-comparison.md prints; every fact an
explanation states is recomputed the same way and must be the one the page
prints (a changed committed value fails it).
"""

from __future__ import annotations

import itertools
import math
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.metrics import get_metric, scored_metrics
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


def _base(df):
    df = df[df["base"].astype(str).str.lower().isin(("true", "1"))]
    return df[df["luminance"] == df["luminance"].min()]


def _intervals(folder: Path, metric: str, demosaic: str) -> dict:
    m = _base(pd.read_csv(folder / "metrics.csv"))
    m = m[(m["metric"] == metric) & (m["demosaic"] == demosaic)]
    return {r.cfa: (r.value, r.ci_low, r.ci_high) for r in m.itertuples(index=False)}


def _mean_squares(d, g):
    """(MS_between, df_b, MS_within, df_w, n0) of one value's realisations by render."""
    labels = sorted(set(g))
    groups = [d[g == k] for k in labels]
    n, r = d.size, len(labels)
    ms_w = sum(((x - x.mean()) ** 2).sum() for x in groups) / (n - r)
    ms_b = sum(x.size * (x.mean() - d.mean()) ** 2 for x in groups) / (r - 1)
    n0 = (n - sum(x.size ** 2 for x in groups) / n) / (r - 1)
    return ms_b, r - 1, ms_w, n - r, n0


def _paired(folder: Path, metric: str, demosaic: str):
    """{(a, b): (lo, hi)} of every pair's paired difference: a one-way random-effects
    model, its render variance pooled over all pairs (ANOVA estimate, Satterthwaite df)."""
    from scipy.stats import t

    r = _base(pd.read_csv(folder / "metrics_realisations.csv"))
    r = r[(r["metric"] == metric) & (r["demosaic"] == demosaic)]
    wide = r.pivot_table(index="cfa", columns="realisation", values="value")
    g = r.groupby("realisation")["render_seed"].max().reindex(wide.columns).to_numpy()
    pairs = list(itertools.combinations(wide.index, 2))
    nested = len(set(g)) > 1 and len(g) > len(set(g))
    sigma2, df_r = 0.0, math.inf
    if nested:
        stats = [_mean_squares(wide.loc[a].to_numpy() - wide.loc[b].to_numpy(), g) for a, b in pairs]
        dfb, dfw = sum(x[1] for x in stats), sum(x[3] for x in stats)
        msb, msw = sum(x[0] * x[1] for x in stats) / dfb, sum(x[2] * x[3] for x in stats) / dfw
        n0 = sum(x[4] * x[1] for x in stats) / dfb
        if msb > msw:
            sigma2, df_r = (msb - msw) / n0, (msb - msw) ** 2 / (msb ** 2 / dfb + msw ** 2 / dfw)
    out = {}
    for a, b in pairs:
        d = wide.loc[a].to_numpy() - wide.loc[b].to_numpy()
        if not nested:
            half = t.ppf(0.975, d.size - 1) * d.std(ddof=1) / math.sqrt(d.size)
        else:
            _, _, ms_w, df_w, _ = _mean_squares(d, g)
            weight = sum((g == k).sum() ** 2 for k in set(g)) / d.size ** 2
            ta, tb = sigma2 * weight, ms_w / d.size
            df = (ta + tb) ** 2 / ((ta ** 2 / df_r if ta else 0) + tb ** 2 / df_w) if ta + tb > 0 else math.inf
            half = t.ppf(0.975, max(df, 1.0)) * math.sqrt(ta + tb)
        out[(a, b)] = (d.mean() - half, d.mean() + half)
        out[(b, a)] = (-d.mean() - half, -d.mean() + half)
    return out


def _by_rule(folder: Path, claim: dict) -> str:
    """The verdict, from the rule's sentence on the CSV rows."""
    if claim["kind"] == "best":
        # the study's decision rule where decisions.csv has it (rank interval 1 and a practical lead), else
        # rank intervals alone: "best" needs a rank interval of exactly 1 (scores.csv, paired comparisons)
        d = pd.read_csv(folder / "decisions.csv", dtype=str, keep_default_na=False)
        aspect = "overall" if claim["demosaic"] == "total" else f"with {claim['demosaic']}"
        if "robust" in d.columns and aspect in set(d["aspect"]):
            row = d[d["aspect"] == aspect].iloc[0]
            named = row["cfas"].split()
            if row["verdict"] == "winner" and named == [claim["cfa"]]:
                return "holds"
            return "tie" if claim["cfa"] in named and row["verdict"] != "winner" else "differs"
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
        paired = (_paired(folder, claim["metric"], claim["demosaic"])
                  if (folder / "metrics_realisations.csv").is_file() else None)
        results = []
        for gi, gj in itertools.combinations(claim["groups"], 2):
            for a, b in itertools.product(gi, gj):
                if paired is not None:
                    lo, hi = paired[(a, b)]
                    a_better, b_better = (lo > 0, hi < 0) if hib else (hi < 0, lo > 0)
                else:
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


#: Decimals each metric prints with (its record's: the facts are checked as printed).
DECIMALS = {name: get_metric(name).decimals for name in scored_metrics()}


def _label(cfa: str) -> str:
    return "Bayer" if cfa == "bayer" else cfa.upper()


def _fact(folder: Path, spec: dict) -> str:
    """One explanation fact from the raw CSV rows (kinds: cfa_mitsuba/report/claim_facts.py's docstring)."""
    from scipy.stats import spearmanr

    m = _base(pd.read_csv(folder / "metrics.csv"))

    def values(metric, column="value", scene=None):
        sel = m[(m["metric"] == metric) & (m["demosaic"] == spec["demosaic"])]
        sel = sel if scene is None else sel[sel["scene"] == scene]
        return sel.groupby("cfa")[column].first().to_dict()

    if spec["kind"] == "ratio":
        v = values(spec["metric"], spec["column"], spec.get("scene"))
        return f"{v[spec['a']] / v[spec['b']]:.1f}"
    v, dec = values(spec["metric"]), DECIMALS[spec["metric"]]
    if spec["kind"] == "means":
        a, b = (float(np.mean([v[c] for c in g])) for g in spec["groups"])
        word = "above" if round(a, dec) > round(b, dec) else "below" if round(a, dec) < round(b, dec) else "equal to"
        return f"{spec['labels'][0]} {a:.{dec}f}, {word} {spec['labels'][1]} {b:.{dec}f}"
    if spec["kind"] == "spread":
        lo = min(spec["cfas"], key=lambda c: v[c])
        hi = max(spec["cfas"], key=lambda c: v[c])
        return f"{v[hi] - v[lo]:.{dec}f} ({_label(lo)} {v[lo]:.{dec}f} to {_label(hi)} {v[hi]:.{dec}f})"
    if spec["kind"] == "rank":
        order = sorted(v, key=v.get, reverse=spec["side"] == "highest")
        k = order.index(spec["cfa"]) + 1
        suffix = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
        return f"{k}{suffix} {spec['side']} of {len(order)} (the {spec['side']}: {_label(order[0])} {v[order[0]]:.{dec}f})"
    if spec["kind"] == "correlation":
        w = values(spec["other"])
        both = sorted(c for c in v if c in w)
        return f"{spearmanr([v[c] for c in both], [w[c] for c in both]).statistic:+.2f}"
    assert spec["kind"] == "compare", spec
    a, b = v[spec["a"]], v[spec["b"]]
    better = a > b if HIGHER_IS_BETTER[spec["metric"]] else a < b
    word = "equal to" if round(a, dec) == round(b, dec) else "better than" if better else "worse than"
    return f"{a:.{dec}f} ({word} {_label(spec['b'])}'s {b:.{dec}f})"


def _explanation_errors(page: str, column: str, folder: Path) -> list[str]:
    """The claims whose printed explanation is not their text with the facts recomputed from ``folder``."""
    errors = []
    for claim in CLAIMS:
        if not claim.get("facts"):
            continue
        verdict = _by_rule(folder, claim)
        text = claim.get({"holds": "why_holds", "differs": "why_differs", "tie": "why_tie"}[verdict], "")
        if not text:
            continue
        expected = text.format(**{k: _fact(folder, f) for k, f in claim["facts"].items()})
        line = next((x for x in page.splitlines() if x.startswith(f"- {column}: ") and f"Why: {expected}" in x), None)
        if line is None:
            errors.append(claim["id"])
    return errors


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


@pytest.mark.parametrize("column", list(RUNS))
def test_every_explanation_states_the_facts_of_the_committed_csvs(column):
    folder = RUNS[column]
    if not (folder / "metrics.csv").is_file():
        return
    assert _explanation_errors(PAGE.read_text(), column, folder) == []
    assert sum(1 for c in CLAIMS if c.get("facts")) >= 6  # the five of issue 46 and more


def test_a_changed_committed_value_fails_the_explanation_check(tmp_path):
    """HaarPSI's family means are facts of the haarpsi-rgb explanation: raise
    every CMY and RGBW tile's bilinear HaarPSI in a copy of the committed run
    and the page's sentence no longer matches the CSVs."""
    folder = tmp_path / "run"
    folder.mkdir()
    src = RUNS["ours, defaults"]
    for name in ("metrics.csv", "metrics_realisations.csv", "scores.csv", "decisions.csv"):
        if (src / name).is_file():
            shutil.copy(src / name, folder / name)
    m = pd.read_csv(folder / "metrics.csv")
    sel = (m["metric"] == "haarpsi") & (m["demosaic"] == "bilinear") & m["cfa"].str.match("cmy|rgbw")
    m.loc[sel, "value"] += 0.2
    m.to_csv(folder / "metrics.csv", index=False)
    assert "haarpsi-rgb" in _explanation_errors(PAGE.read_text(), "ours, defaults", folder)
