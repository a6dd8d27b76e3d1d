"""No committed result under docs/ records an absolute path (issue 52, point
4): results record paths relative to their output folder
(cfa_mitsuba/io/portable.py), so a committed table does not carry the
layout of the machine that made it."""

from __future__ import annotations

from pathlib import Path


from cfa_mitsuba.io.portable import ABSOLUTE_PATH

REPO = Path(__file__).resolve().parents[2]
#: What a run writes: tables, records, configs as run (pages, *.md, are prose, not results).
RESULT_SUFFIXES = (".csv", ".json", ".toml", ".txt", ".tsv")


def _results():
    return sorted(p for p in (REPO / "docs").rglob("*") if p.is_file() and p.suffix in RESULT_SUFFIXES)


def test_there_are_committed_results_to_check():
    names = {p.relative_to(REPO).as_posix() for p in _results()}
    assert "docs/example-design-dyes/fullchain.csv" in names and "docs/example-report/config.json" in names


def test_no_committed_result_under_docs_holds_an_absolute_path():
    bad = []
    for p in _results():
        for n, line in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            m = ABSOLUTE_PATH.search(line)
            if m:
                bad.append(f"{p.relative_to(REPO)}:{n}: {m.group(0)}")
    assert not bad, "absolute paths in committed results:\n" + "\n".join(bad[:20])
