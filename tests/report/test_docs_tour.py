"""The command-line tours of README.md and docs/*.md are what running them prints now
(cfa_mitsuba/report/docs_tour.py).

Runs each tour block's commands in a fresh folder with an empty render cache
(about a minute on 2 cores: the README's 720 x 636 Macbeth render, captures,
processes and a metric; docs/sensor.md's captures of a small render) and
compares the output with the block, seconds and cache keys masked, as text
and numbers: words and integers exactly, decimals within 1e-6 relative or one
unit in their last printed digit (docs_tour.differences), so another CPU,
BLAS or libm cannot fail it while a real change does.
"""

from __future__ import annotations

from pathlib import Path

from cfa_mitsuba.report import docs_tour

REPO = Path(__file__).resolve().parents[2]


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
            wrong = docs_tour.differences(fresh, m.group("block"))
            assert not wrong, f"{path.name}:\n" + "\n".join(wrong)
            printed.append(fresh)
    text = "\n".join(printed)
    assert "delta-e:" in text and "condition number" in text and "error: unknown CFA 'nosuch'" in text
    assert "(program: analogue gain 16" in text and "(auto at 100 cd/m^2)" in text


def _decimals(block):
    """(start, end, text) of every decimal the block prints with four or more significant digits."""
    import re

    out = []
    for m in re.finditer(r"(?<![\w.])\d+\.\d+(?![\d.])", block):
        if len(m.group().replace(".", "").lstrip("0")) >= 4:
            out.append((m.start(), m.end(), m.group()))
    return out


def test_a_number_off_by_its_tolerance_fails_and_rounding_does_not():
    """Acceptance 3 of issue 45, on the README's own tour: turning a printed decimal's last
    digit over by one unit (what rounding a value that moved by 1e-15 can do) passes; two
    units fail; 1 % fails every printed number, integers included; a changed word fails."""
    block = docs_tour.TOUR.search((REPO / "README.md").read_text()).group("block")
    assert docs_tour.differences(block, block) == []
    decimals = _decimals(block)
    assert len(decimals) >= 8
    for start, end, text in decimals:
        unit = 10.0 ** -len(text.split(".")[1])
        for steps, fails in ((1, False), (-1, False), (2, True)):
            changed = f"{float(text) + steps * unit:.{len(text.split('.')[1])}f}"
            assert bool(docs_tour.differences(block[:start] + changed + block[end:], block)) == fails, (text, changed)
        one_percent = f"{float(text) * 1.01:.{len(text.split('.')[1])}f}"
        assert docs_tour.differences(block[:start] + one_percent + block[end:], block), (text, one_percent)
    for count in ("3671", "636"):  # integers: a raw DN, a size
        at = block.index(count)
        bigger = str(round(int(count) * 1.01))
        assert docs_tour.differences(block[:at] + bigger + block[at + len(count):], block)
    assert docs_tour.differences(block.replace("dE00", "dE76", 1), block)
