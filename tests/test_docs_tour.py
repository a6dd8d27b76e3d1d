"""The README's command-line tour is what running it prints now (cfa_mitsuba/report/docs_tour.py).

Runs the tour's commands in a fresh folder with an empty render cache (about
a minute on 2 cores: a 720 x 636 Macbeth render, two captures, two
processes, one metric) and compares the output with the README's block,
seconds and cache keys masked.
"""

from __future__ import annotations

from pathlib import Path

from cfa_mitsuba.report import docs_tour

REPO = Path(__file__).resolve().parents[1]


def test_the_tour_block_layout_is_read_back():
    block = "$ cfa-mitsuba list cfas\na\nb\n...\nz\n$ cfa-mitsuba list spectra   # comment\n\n$ cfa-mitsuba x\ny\n"
    cmds = docs_tour.tour_commands(block)
    assert [c[0] for c in cmds] == ["$ cfa-mitsuba list cfas", "$ cfa-mitsuba list spectra   # comment",
                                    "$ cfa-mitsuba x"]
    assert cmds[0][1] == ["a", "b", "...", "z"] and cmds[1][1] == [] and cmds[1][2] is True
    assert docs_tour._shape(["1", "2", "3", "4", "5"], ["a", "b", "...", "z"]) == ["1", "2", "...", "5"]
    assert docs_tour._shape(["x; pass --white X,Y,Z to override", "kept"], ["old"]) == ["kept"]
    assert docs_tour.normalised("rendered in 1.9 s, cached as 0a9ec14f9fa25332411fc7ee70e4fa5e") == \
        "rendered in T s, cached as KEY"


def test_the_readme_tour_is_what_the_tour_prints_now():
    src = (REPO / "README.md").read_text()
    m = docs_tour.TOUR.search(src)
    assert m, "README.md has no tour block"
    fresh = docs_tour.run_tour_block(REPO, m.group("block"))
    assert docs_tour.normalised(fresh) == docs_tour.normalised(m.group("block"))
    assert "delta-e:" in fresh and "condition number" in fresh and "error: unknown CFA 'nosuch'" in fresh
