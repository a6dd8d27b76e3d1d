"""Numbers in README.md and docs/*.md filled from committed results, so none can go stale.

A number that comes from a run sits in the Markdown between two HTML
comments (invisible on GitHub), which name where it comes from::

    total <!--= docs/example-report/timing.json phases.total_s .1f -->274.8<!--/=--> s
    <!--= docs/example-report/scores.csv nunique:cfa -->12<!--/=--> CFAs
    <!--= @readme-rank-table -->
    | rank | CFA | ... (a whole generated block) ...
    <!--/=-->

The opening comment holds a *source*, a *query* and an optional Python
format spec (``.1f``, ``d``, ``,d``; none: ``str``):

- ``PATH.json QUERY``: ``QUERY`` is a dotted path into the JSON
  (``phases.total_s``, ``renders.puppy@f4.render_time_s``);
- ``PATH.csv QUERY``: ``[AGG:]COLUMN[FILTER]``, where ``FILTER`` is
  ``[col=value;col2=value2]`` (string comparison), and ``AGG`` one of
  ``first`` (default), ``mean``, ``min``, ``max``, ``sum``, ``count``
  (rows), ``nunique``;
- ``@NAME [ARGS]``: a named generator of :data:`.docs_tables.GENERATORS` (tables and
  sentences that follow the decision rule: a CFA is called first only when
  its rank interval is exactly 1).

Paths are relative to the repository root.  ``python3 -m
cfa_mitsuba.report.docs_numbers`` rewrites every marked span from its
source; ``--check`` changes nothing and exits 1 listing each span whose
text differs from its source (tests/report/test_docs_numbers.py runs the check);
``--tour`` also re-runs every command-line tour block of README.md and
docs/*.md (:mod:`.docs_tour`) and writes its output into the block.

Hand-written: a 60-line marker parser; nothing in the field's libraries
fills Markdown spans from CSV queries.
"""

from __future__ import annotations

__all__ = ["MARKER", "DOC_FILES", "Span", "find_spans", "evaluate", "fill", "check", "main"]

import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from ..errors import CfaMitsubaError

REPO = Path(__file__).resolve().parents[2]

#: One marked span: the spec in the opening comment, the text up to the closing one.
MARKER = re.compile(r"<!--=\s*(?P<spec>[^>]*?)\s*-->(?P<text>.*?)<!--/=-->", re.S)


def DOC_FILES(repo: Path = REPO) -> list[Path]:
    """README.md and every docs/*.md: the files the check covers."""
    return [repo / "README.md", *sorted((repo / "docs").glob("*.md"))]


@dataclass(frozen=True)
class Span:
    """One marked span of a document."""

    path: Path
    line: int
    spec: str
    text: str
    start: int
    end: int


def _in_code(src: str, pos: int) -> bool:
    """Whether ``pos`` lies in a code block (fenced, or a line indented by 4 spaces): examples, not markers."""
    line_start = src.rfind("\n", 0, pos) + 1
    if src.startswith("    ", line_start) or src.startswith("\t", line_start):
        return True
    return src.count("\n```", 0, pos) % 2 == 1


def find_spans(path: Path) -> list[Span]:
    """Every marked span of the Markdown file ``path``, in order (code blocks left out)."""
    src = path.read_text()
    return [Span(path, src.count("\n", 0, m.start()) + 1, m.group("spec"), m.group("text"),
                 m.start("text"), m.end("text")) for m in MARKER.finditer(src) if not _in_code(src, m.start())]


# a column may hold @, /, + and dots (a design's objective labels: ysnr-area@gray-bar/L10/best)
_CSV_QUERY = re.compile(r"^(?:(?P<agg>first|mean|min|max|sum|count|nunique):)?(?P<col>[\w@/+.-]+)"
                        r"(?:\[(?P<filter>[^\]]*)\])?$")
_CACHE: dict = {}


def _read(path: Path):
    key = (path, path.stat().st_mtime_ns)
    if key not in _CACHE:
        if path.suffix == ".json":
            _CACHE[key] = json.loads(path.read_text())
        else:
            import pandas as pd

            _CACHE[key] = pd.read_csv(path, dtype=str, keep_default_na=False, comment="#")
    return _CACHE[key]


def _json_value(data, query: str):
    value = data
    # keys may hold dots of their own (none do today): take the longest key that matches
    parts = query.split(".")
    i = 0
    while i < len(parts):
        for j in range(len(parts), i, -1):
            key = ".".join(parts[i:j])
            if isinstance(value, dict) and key in value:
                value, i = value[key], j
                break
            if isinstance(value, list) and key.isdigit() and int(key) < len(value):
                value, i = value[int(key)], j
                break
        else:
            raise CfaMitsubaError(f"no {'.'.join(parts[:i + 1])!r} in the JSON")
    return value


def _csv_value(df, query: str):
    m = _CSV_QUERY.match(query)
    if not m:
        raise CfaMitsubaError(f"bad CSV query {query!r} (expected [AGG:]COLUMN[col=value;...])")
    agg, col = m.group("agg") or "first", m.group("col")
    if col not in df.columns and agg != "count":
        raise CfaMitsubaError(f"no column {col!r}")
    sel = df
    for cond in filter(None, (m.group("filter") or "").split(";")):
        k, _, v = cond.partition("=")
        if k not in df.columns:
            raise CfaMitsubaError(f"no column {k!r} to filter on")
        sel = sel[sel[k] == v]
    if agg == "count":
        return len(sel)
    if agg == "nunique":
        return int(sel[col].nunique())
    if sel.empty:
        raise CfaMitsubaError(f"no row matches {query!r}")
    if agg == "first":
        return _number(sel[col].iloc[0])
    values = sel[col].astype(float)
    return float(getattr(values, agg)())


def _number(text: str):
    try:
        return int(text)
    except ValueError:
        try:
            return float(text)
        except ValueError:
            return text


def evaluate(spec: str, repo: Path = REPO) -> str:
    """The text a span with opening ``spec`` must hold."""
    words = spec.split()
    if not words:
        raise CfaMitsubaError("empty marker")
    if words[0].startswith("@"):
        name = words[0][1:]
        from .docs_tables import GENERATORS

        if name not in GENERATORS:
            raise CfaMitsubaError(f"unknown generator {name!r} (known: {', '.join(sorted(GENERATORS))})")
        return GENERATORS[name](repo, *words[1:])
    if len(words) not in (2, 3):
        raise CfaMitsubaError(f"bad marker {spec!r} (expected: PATH QUERY [FORMAT])")
    path = repo / words[0]
    if not path.is_file():
        raise CfaMitsubaError(f"source {words[0]} not found")
    data = _read(path)
    value = _json_value(data, words[1]) if path.suffix == ".json" else _csv_value(data, words[1])
    if len(words) == 2:
        return str(value)
    try:
        return format(value, words[2])
    except (ValueError, TypeError) as exc:
        raise CfaMitsubaError(f"bad format {words[2]!r} in marker {spec!r}: {exc}") from None


def _replace_all(path: Path, repo: Path) -> tuple[str, list[tuple[Span, str]]]:
    src = path.read_text()
    out, last, diffs = [], 0, []
    for span in find_spans(path):
        want = evaluate(span.spec, repo)
        if want != span.text:
            diffs.append((span, want))
        out.append(src[last:span.start])
        out.append(want)
        last = span.end
    out.append(src[last:])
    return "".join(out), diffs


def check(repo: Path = REPO, files=None) -> list[str]:
    """One line per marked span whose text differs from its source (empty: all current)."""
    problems = []
    for path in files or DOC_FILES(repo):
        try:
            _, diffs = _replace_all(path, repo)
        except CfaMitsubaError as e:
            problems.append(f"{path.relative_to(repo)}: {e}")
            continue
        for span, want in diffs:
            # where they first differ, with a little context either side
            at = next((i for i, (a, b) in enumerate(zip(span.text, want)) if a != b), min(len(span.text), len(want)))
            lo = max(0, at - 25)
            problems.append(f"{path.relative_to(repo)}:{span.line}: '{span.spec}' holds {span.text[lo:at + 25]!r}, "
                            f"its source gives {want[lo:at + 25]!r}")
    return problems


def fill(repo: Path = REPO, files=None) -> int:
    """Rewrite every marked span from its source; the number of spans changed."""
    changed = 0
    for path in files or DOC_FILES(repo):
        text, diffs = _replace_all(path, repo)
        if diffs:
            path.write_text(text)
            changed += len(diffs)
    return changed


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python3 -m cfa_mitsuba.report.docs_numbers",
                                 description="Fill the marked numbers of README.md and docs/*.md from committed "
                                             "results (--check: only compare).")
    ap.add_argument("--check", action="store_true", help="change nothing; exit 1 when a span differs from its source")
    ap.add_argument("--tour", action="store_true", help="also re-run the command-line tours of README.md and docs/*.md (minutes)")
    args = ap.parse_args(argv)
    try:
        if args.check:
            problems = check()
            for p in problems:
                print(p)
            print(f"{len(problems)} span(s) differ from their source" if problems else "every marked number is current")
            return 1 if problems else 0
        if args.tour:
            from .docs_tour import run_tour

            print(f"{run_tour(REPO)} tour block(s) re-run")
        n = fill()
        print(f"{n} span(s) rewritten from their sources")
        return 0
    except CfaMitsubaError as e:
        print(f"docs_numbers: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
