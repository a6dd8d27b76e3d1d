"""Every kind of committed source the docs' numbers come from makes the check fail when it changes.

tests/report/test_docs_numbers.py shows it for the example report's scores.csv and
timing.json; here for the other sources: the convergence runs'
CSV (docs/convergence.md), the stability matrix's JSON (docs/stability.md),
the benchmarks' JSON (README.md, docs/isp.md) and the
paper study's metrics.csv through a generated table (docs/metrics.md).
And no link in README.md or docs/*.md leaves the repository: inline,
reference-style and HTML links alike, web addresses included.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pandas as pd
import pytest
from docs_copy import _copy_docs  # README, docs/ and the sources, copied as in the repository

from cfa_mitsuba.report import docs_numbers

REPO = Path(__file__).resolve().parents[2]


def _bump_convergence_wall_time(repo: Path) -> None:
    path = repo / "docs/images/convergence/convergence_macbeth.csv"
    df = pd.read_csv(path, keep_default_na=False, dtype=str)
    rows = (df["stage"] == "render") & (df["quality"] == "16")
    df.loc[rows, "wall_s"] = "9.99"  # the macbeth's default level took 9.99 s
    df.to_csv(path, index=False)


def _change_stability_outcome(repo: Path) -> None:
    path = repo / "docs/data/stability.json"
    d = json.loads(path.read_text())
    d["outcomes"]["line-spectrum-550nm"] = d["outcomes"]["line-spectrum-550nm"].replace("dE00", "dE00 1 +")
    path.write_text(json.dumps(d))


def _change_bench(repo: Path) -> None:
    path = repo / "docs/data/bench_demosaic.json"
    d = json.loads(path.read_text())
    d["psnr_db"]["bayer"]["bilinear"]["mean"] += 0.5
    path.write_text(json.dumps(d))


def _change_colour(repo: Path) -> None:
    path = repo / "docs/data/bench_colour.json"
    d = json.loads(path.read_text())
    d["pipeline"][0]["bilinear"]["mean"] += 0.5  # the first CFA's mean dE00 with bilinear
    path.write_text(json.dumps(d))


def _change_moire(repo: Path) -> None:
    path = repo / "docs/example-report/metrics.csv"
    df = pd.read_csv(path, keep_default_na=False, dtype=str)
    row = (df["scene"] == "chirp") & (df["metric"] == "moire") & (df["cfa"] == "rgb1") & (df["demosaic"] == "bilinear")
    df.loc[row, "value"] = "4.5"
    df.to_csv(path, index=False)


@pytest.mark.parametrize("change, doc", [
    (_bump_convergence_wall_time, "docs/convergence.md"),
    (_change_stability_outcome, "docs/stability.md"),
    (_change_bench, "README.md"),
    (_change_colour, "docs/isp.md"),
    (_change_moire, "docs/metrics.md"),
], ids=["convergence-csv", "stability-json", "bench-json", "colour-json", "metrics-csv"])
def test_changing_one_committed_value_fails_the_check(tmp_path, change, doc):
    repo = _copy_docs(tmp_path)
    files = [repo / doc]
    assert docs_numbers.check(repo, files) == []
    change(repo)
    problems = docs_numbers.check(repo, files)
    assert any(p.startswith(f"{doc}:") for p in problems), problems
    assert docs_numbers.fill(repo, files) >= 1  # and filling repairs it
    assert docs_numbers.check(repo, files) == []


def _links(text: str) -> list[str]:
    """Link targets of Markdown text outside code: inline, reference-style, autolinks, HTML href/src."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    text = re.sub(r"`[^`\n]*`", "", text)
    return (re.findall(r"\]\(\s*<?([^)\s>]+)", text) + re.findall(r"^\s*\[[^\]]+\]:\s*<?(\S+?)>?\s*$", text, re.M)
            + re.findall(r"<(https?://[^>\s]+)>", text) + re.findall(r"(?:href|src)\s*=\s*[\"']([^\"']+)", text))


def outside_links(path: Path, repo: Path = REPO) -> list[str]:
    """The link targets of ``path`` that leave the repository (web addresses, absolute or escaping paths, missing files)."""
    bad = []
    for target in _links(path.read_text()):
        if target.startswith("#"):
            continue
        if re.match(r"[a-z][a-z0-9+.-]*:", target, re.I):  # http:, https:, file:, mailto: ...
            bad.append(target)
            continue
        resolved = (path.parent / target.split("#")[0]).resolve()
        if not resolved.exists() or repo.resolve() not in resolved.parents:
            bad.append(target)
    return bad


def test_no_link_leaves_the_repository():
    bad = {f.relative_to(REPO).as_posix(): outside_links(f) for f in docs_numbers.DOC_FILES(REPO)}
    assert not {k: v for k, v in bad.items() if v}


def test_the_link_check_can_fail(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "here.md").write_text("x")
    page = tmp_path / "docs" / "a.md"
    page.write_text("[ok](here.md) [web](https://example.org) [gone](missing.md)\n[ref]: ../../outside.md\n"
                    '<a href="http://x.org">x</a> `[code](https://ignored.org)`\n')
    assert sorted(outside_links(page, tmp_path)) == sorted(["https://example.org", "missing.md", "../../outside.md",
                                                            "http://x.org"])
