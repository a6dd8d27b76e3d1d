"""Paths as results record them (cfa_mitsuba/io/portable.py): relative to
the output folder, and the pattern that finds an absolute one."""

from __future__ import annotations

import pytest

from cfa_mitsuba.io.portable import ABSOLUTE_PATH, relative_command, relative_path


@pytest.mark.parametrize("text, found", [
    ('"toml": "/tmp/d-dyes/cfas/a.toml"', True),
    ("a,/work/main/docs/x.toml,b", True),
    ("--keep /tmp/bench", True),
    ('"path": "C:\\\\data\\\\x.toml"', True),
    ("cfas/a.toml", False),
    ("../../configs/paper.toml", False),
    ("luminance cd/m^2, e-/s, W/(m^2 sr nm), 1/30 s", False),
])
def test_the_pattern_finds_absolute_paths_and_not_units(text, found):
    assert bool(ABSOLUTE_PATH.search(text)) is found


def test_paths_are_recorded_relative_to_the_output_folder(tmp_path):
    out = tmp_path / "out"
    assert relative_path(out / "cfas" / "x.toml", out) == "cfas/x.toml"
    assert relative_path(tmp_path / "configs" / "a.toml", out) == "../configs/a.toml"
    assert (out / relative_path(tmp_path / "configs" / "a.toml", out)).resolve() == (tmp_path / "configs" / "a.toml")
    cmd = relative_command(["--keep", str(out / "k"), "--json=" + str(out / "r.json"), "--paper"], out)
    assert cmd == "--keep k --json=r.json --paper" and not ABSOLUTE_PATH.search(cmd)
