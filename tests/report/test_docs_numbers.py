"""README.md and docs/*.md cannot go stale: their marked numbers equal their sources.

``python3 -m cfa_mitsuba.report.docs_numbers`` fills every marked span
from committed results; here ``--check`` must find nothing to change, a
change to one committed CSV value must make it fail, every link must point
inside the repository, and no sentence may call a CFA first or best unless
its rank interval is exactly 1.
"""

from __future__ import annotations

import json

import re
from pathlib import Path

import pandas as pd
import pytest

from cfa_mitsuba.report import docs_numbers
from docs_copy import _copy_docs

REPO = Path(__file__).resolve().parents[2]


def test_every_doc_holds_markers_and_each_equals_its_source():
    spans = [s for f in docs_numbers.DOC_FILES(REPO) for s in docs_numbers.find_spans(f)]
    assert len(spans) >= 10
    assert any(s.path.name == "README.md" and s.spec.startswith("@rank-table") for s in spans)
    assert docs_numbers.check(REPO) == []


def test_the_check_covers_readme_and_every_doc():
    names = {p.relative_to(REPO).as_posix() for p in docs_numbers.DOC_FILES(REPO)}
    assert "README.md" in names
    assert {f"docs/{p.name}" for p in (REPO / "docs").glob("*.md")} <= names


def test_changing_one_committed_csv_value_fails_the_check(tmp_path):
    repo = _copy_docs(tmp_path)
    assert docs_numbers.check(repo) == []
    scores = repo / "docs" / "example-report" / "scores.csv"
    df = pd.read_csv(scores)
    df.loc[df["cfa"] == "bayer", "total_score"] += 0.01  # one value: Bayer's total
    df.to_csv(scores, index=False)
    problems = docs_numbers.check(repo)
    assert any(p.startswith("README.md:") and "@rank-table" in p for p in problems), problems
    # and filling repairs it
    assert docs_numbers.fill(repo) >= 1
    assert docs_numbers.check(repo) == []


def test_changing_timing_json_or_the_stored_quick_values_fails_the_check(tmp_path):
    repo = _copy_docs(tmp_path)
    timing = repo / "docs" / "example-report" / "timing.json"
    t = json.loads(timing.read_text())
    t["phases"]["total_s"] += 10.0  # the study took 10 s longer
    timing.write_text(json.dumps(t, indent=1))
    quick = repo / "tests" / "data" / "quick_expected.csv"
    quick.write_text("".join(quick.read_text().splitlines(keepends=True)[:-1]))  # one stored value fewer
    problems = docs_numbers.check(repo)
    assert any("@timing" in p for p in problems), problems
    assert any("quick_expected.csv count" in p for p in problems), problems


def test_a_bad_marker_is_one_clear_problem(tmp_path):
    repo = _copy_docs(tmp_path)
    (repo / "docs" / "x.md").write_text("a <!--= docs/example-report/nosuch.csv value -->1<!--/=--> b\n")
    problems = docs_numbers.check(repo)
    assert any("nosuch.csv not found" in p for p in problems), problems
    (repo / "docs" / "x.md").write_text("a <!--= docs/data/cuda-paper/timing.json phases.total_s :.1% -->1<!--/=--> b\n")
    problems = docs_numbers.check(repo)
    assert any("bad format ':.1%'" in p for p in problems), problems


def _prose(text: str) -> str:
    """The text without fenced blocks and code spans (where ``[x](y)`` is code, not a link)."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    return re.sub(r"`[^`\n]*`", "", text)


def test_every_link_points_inside_the_repository():
    bad = []
    for f in docs_numbers.DOC_FILES(REPO):
        for m in re.finditer(r"\]\(([^)\s]+)\)", _prose(f.read_text())):
            target = m.group(1)
            if target.startswith(("#", "mailto:")) or re.match(r"https?://", target):
                continue
            path = (f.parent / target.split("#")[0]).resolve()
            if not path.exists() or REPO.resolve() not in path.parents:
                bad.append(f"{f.name}: {target}")
    assert not bad, bad


_CLAIM = re.compile(r"`?(?P<cfa>[a-z]+\d?)`? (?:is|comes|ranks) (?:first|best|the winner)"
                    r"(?: (?:overall|with (?P<demosaic>[a-z-]+)))?", re.I)


def _rank_intervals(results: Path) -> dict:
    s = pd.read_csv(results / "scores.csv")
    s = s[s["luminance"] == s["luminance"].min()]
    out = {(r.cfa, None): (r.total_rank_best, r.total_rank_worst) for r in s.drop_duplicates("cfa").itertuples()}
    for r in s.drop_duplicates(["cfa", "demosaic"]).itertuples():
        out[(r.cfa, r.demosaic)] = (r.demosaic_rank_best, r.demosaic_rank_worst)
    return out


def first_claims_that_break_the_rule(text: str, ranks: dict) -> list[str]:
    """Phrases naming a CFA first/best/the winner whose rank interval is not exactly 1."""
    bad = []
    for m in _CLAIM.finditer(text):
        key = (m.group("cfa").lower(), m.group("demosaic"))
        if key[0] in {c for c, _ in ranks} and ranks.get(key) != (1, 1):
            bad.append(m.group(0))
    return bad


def test_no_doc_sentence_calls_a_cfa_first_unless_its_rank_interval_is_exactly_one():
    ranks = _rank_intervals(REPO / "docs" / "example-report")
    text = "\n".join(f.read_text() for f in docs_numbers.DOC_FILES(REPO))
    assert first_claims_that_break_the_rule(text, ranks) == []
    # the check itself can fail: a tied CFA called first
    tied = next(c for (c, d), (b, w) in ranks.items() if d is None and b == 1 and w > 1) if any(
        d is None and b == 1 and w > 1 for (c, d), (b, w) in ranks.items()) else None
    laplacian_tied = next(c for (c, d), (b, w) in ranks.items() if d == "laplacian" and (b, w) != (1, 1))
    assert first_claims_that_break_the_rule(f"`{laplacian_tied}` is first with laplacian.", ranks)
    if tied:
        assert first_claims_that_break_the_rule(f"{tied} is first overall", ranks)


@pytest.mark.parametrize("spec, expected", [
    ("docs/example-report/timing.json phases.total_s .1f", None),
    ("docs/example-report/scores.csv nunique:cfa d", "12"),
])
def test_markers_read_json_and_csv(spec, expected):
    got = docs_numbers.evaluate(spec, REPO)
    if expected is not None:
        assert got == expected
    else:
        import json

        assert got == f"{json.loads((REPO / 'docs/example-report/timing.json').read_text())['phases']['total_s']:.1f}"
