"""A ``<spectrum filename>`` beside a user's scene is found as plain
Mitsuba finds it, in the scene's folder first (issue 51, item 8)."""

from __future__ import annotations

import os
import shutil

import numpy as np
import pytest

import cfa_mitsuba as cm
from conftest import REPO

PANEL = REPO / "tests" / "data" / "scenes" / "whitepanel" / "whitepanel.xml"
FLOOR = '<spectrum name="reflectance" value="0.3"/>'


@pytest.fixture
def scenes(tmp_path):
    """The white-panel scene twice: its grey floor's 0.3 given inline, and
    read from ``sub/grey.spd`` (a flat 0.3)."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "grey.spd").write_text("300 0.3\n500 0.3\n900 0.3\n")
    inline = tmp_path / "inline.xml"
    shutil.copy(PANEL, inline)
    text = PANEL.read_text()
    assert text.count(FLOOR) == 1
    from_file = tmp_path / "from_file.xml"
    from_file.write_text(text.replace(FLOOR, '<spectrum name="reflectance" filename="sub/grey.spd"/>'))
    return inline, from_file


def test_a_spectrum_file_in_a_subfolder_of_the_scene_loads_and_renders_the_same(scenes, tmp_path, monkeypatch):
    inline, from_file = scenes
    monkeypatch.chdir(tmp_path / "sub")  # not the scene's folder: the name is resolved from the scene, not from here
    a = cm.render.render(str(inline), width=16, height=12, spp=4, seed=2)
    b = cm.render.render(str(from_file), width=16, height=12, spp=4, seed=2)
    np.testing.assert_allclose(b.data, a.data, rtol=1e-5, atol=1e-9)
    names = {os.path.basename(p) for _, p in b.meta["geometry"]["files"]}
    assert "grey.spd" in names  # and it is part of the cache key: an edit of it renders again
