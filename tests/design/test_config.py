"""Design configs: the shipped ones load; bad ones exit 2 with one line
naming the key (empty alphabet, impossible density bounds, unknown
objective, a tile too large for exhaustive search, ...)."""

import textwrap

import pytest

from cfa_mitsuba.design.config import load_design
from conftest import REPO, assert_one_line_error, run_cli

GOOD = """
name = "t"
[layout]
tiles = ["2x2"]
alphabet = ["R", "G", "B"]
[[objective]]
metric = "delta-e"
[study]
scenes = ["macbeth"]
cfas = ["bayer"]
demosaics = ["bilinear"]
"""


@pytest.mark.parametrize("name", ["design-quick.toml", "design-rgbw.toml"])
def test_shipped_design_configs_load(name):
    cfg = load_design(REPO / "configs" / name)
    assert cfg.objectives and cfg.study.cfas


def test_defaults_and_engines():
    import tomllib

    from cfa_mitsuba.design.config import parse_design

    cfg = parse_design(tomllib.loads(GOOD))
    assert cfg.engine == {(2, 2): "exhaustive"} and cfg.objectives[0].goal == "min"
    data = tomllib.loads(GOOD.replace('tiles = ["2x2"]', 'tiles = ["2x2", "4x4"]')
                       .replace('"B"]', '"B", "W"]').replace('alphabet', 'spectra_set = "isetcam-rgbw"\nalphabet'))
    assert parse_design(data).engine == {(2, 2): "exhaustive", (4, 4): "nsga2"}


BAD = [
    ('alphabet = ["R", "G", "B"]', 'alphabet = []', "layout.alphabet"),
    ('alphabet = ["R", "G", "B"]', 'alphabet = ["R", "G", "B"]\ndensity = { R = [0.6, 1.0], G = [0.6, 1.0] }',
     "layout.density"),
    ('alphabet = ["R", "G", "B"]', 'alphabet = ["R", "G", "B"]\ndensity = { G = [0.1, 0.2] }', "layout.density.G"),
    ('metric = "delta-e"', 'metric = "sharpness"', "objective[0].metric"),
    ('tiles = ["2x2"]', 'tiles = ["4x4", "5x5"]\n[search]\nengine = "exhaustive"\n[layout.x]', "search.engine"),
    ('metric = "delta-e"', 'metric = "delta-e"\ngoal = "biggest"', "objective[0].goal"),
    ('alphabet = ["R", "G", "B"]', 'alphabet = ["R", "G", "Q"]', "layout.alphabet"),
    ('demosaics = ["bilinear"]', 'demosaics = ["bilinear"]\nluminances = [3]', "study.luminances"),
    ('tiles = ["2x2"]', 'tiles = ["2by2"]', "layout.tiles[0]"),
    ('metric = "delta-e"', 'metric = "delta-e"\norientation = "both"', "objective[0].orientation"),
    ('metric = "delta-e"', 'metric = "delta-e"\norientation = "diagonal"', "objective[0].orientation"),
    ('metric = "delta-e"', 'metric = "delta-e"\nbasis = "ysnr-area"', "objective[0].basis"),
]


@pytest.mark.parametrize("old,new,key", BAD, ids=[b[2] for b in BAD])
def test_bad_design_configs_exit_2_naming_the_key(tmp_path, old, new, key):
    text = textwrap.dedent(GOOD).replace(old, new)
    if "[layout.x]" in text:  # the engine case: [search] must not swallow the layout keys
        text = text.replace("[layout.x]\n", "").replace('[layout]\ntiles = ["4x4", "5x5"]\n[search]\nengine = "exhaustive"\n',
                                                         '[search]\nengine = "exhaustive"\n[layout]\ntiles = ["4x4", "5x5"]\n')
    p = tmp_path / "d.toml"
    p.write_text(text)
    proc = run_cli("design", p, "--out", tmp_path / "out")
    assert_one_line_error(proc, "d.toml", key)
    assert not (tmp_path / "out").exists()


def test_constraint_bounds_must_name_a_compared_cfa(tmp_path):
    p = tmp_path / "d.toml"
    p.write_text(GOOD + '\n[[constraint]]\nmetric = "delta-e"\nmax = "rgbw9"\n')
    assert_one_line_error(run_cli("design", p), "constraint[0].max", "rgbw9")
