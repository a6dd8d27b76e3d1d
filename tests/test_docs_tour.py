"""The command-line tours of README.md and docs/*.md are what running them prints now
(cfa_mitsuba/report/docs_tour.py).

Runs each tour block's commands in a fresh folder with an empty render cache
(about a minute on 2 cores: the README's 720 x 636 Macbeth render, captures,
processes and a metric; docs/sensor.md's captures of a small render) and
compares the output with the block, seconds and cache keys masked.
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


def test_every_tour_is_what_the_tour_prints_now():
    files = docs_tour.tour_files(REPO)
    assert REPO / "README.md" in files and REPO / "docs" / "sensor.md" in files
    printed = []
    for path in files:
        for m in docs_tour.TOUR.finditer(path.read_text()):
            fresh = docs_tour.run_tour_block(REPO, m.group("block"))
            assert docs_tour.normalised(fresh) == docs_tour.normalised(m.group("block")), path.name
            printed.append(fresh)
    text = "\n".join(printed)
    assert "delta-e:" in text and "condition number" in text and "error: unknown CFA 'nosuch'" in text
    assert "(program: analogue gain 16" in text and "(auto at 100 cd/m^2)" in text
