"""The study axes (cfa_mitsuba/study/axes.py): every registered axis passes
the generic checks (tests/registry_checks.py), and the behaviour an axis
record carries is what the chain, the runner and the sweep figure read:
its label and unit, numbers or categories, realisations, the value in
effect when a condition leaves it to the scene, the render setting it also
sets and the CFAs a value applies to."""

from __future__ import annotations

import pytest

import cfa_mitsuba as cm
import registry_checks as checks
from cfa_mitsuba.study.axes import AXES
from cfa_mitsuba.study.chain import condition_applies, condition_columns
from cfa_mitsuba.study.conditions import Condition


@pytest.mark.parametrize("name", list(AXES))
def test_every_axis_passes_the_generic_checks(name):
    checks.check_axis(AXES[name])


def test_the_scene_value_is_the_one_in_effect():
    """A condition that leaves the f-number to the scene records the one the
    optics used (the render's sidecar); any other axis records its value."""
    meta = {"optics": {"f_number": 5.6}}
    columns = condition_columns(Condition(), meta)
    assert columns["f_number"] == 5.6 and columns["luminance"] == 100.0
    assert condition_columns(Condition(f_number=8.0), meta)["f_number"] == 8.0
    assert [n for n, a in AXES.items() if a.scene_value is not None] == ["f_number"]


def test_a_block_readout_applies_to_the_block_layouts_only():
    assert condition_applies("quad-bayer", Condition(readout="bin"))
    assert not condition_applies("bayer", Condition(readout="bin"))
    assert all(condition_applies(c, Condition()) for c in cm.sensor.list_cfas())  # the defaults apply to every CFA


def test_a_3d_scene_renders_at_the_conditions_f_number():
    from cfa_mitsuba.study.config import parse_config
    from cfa_mitsuba.study.runner import _source

    cfg = parse_config({"scenes": ["puppy", "macbeth"], "cfas": ["bayer"], "demosaics": ["bilinear"]})
    puppy, macbeth = cfg.scenes
    assert _source(puppy, {}, Condition(f_number=8.0))["settings"]["f_number"] == 8.0
    assert "f_number" not in _source(puppy, {}, Condition())["settings"]  # left to the scene
    assert "f_number" not in _source(macbeth, {}, Condition(f_number=8.0))["settings"]  # a chart's render: none


def test_the_sweep_figure_reads_the_records():
    """Numbers on a scale or categories, a line or realisation points, the
    caption's note: each from the axis record (report/figures_sweep.py keeps
    no table of its own)."""
    import pandas as pd

    from cfa_mitsuba.report.figures_sweep import _numeric

    assert _numeric(AXES["f_number"], pd.Series([2.8, 8.0]))
    assert not _numeric(AXES["exposure"], pd.Series(["auto", "0.01"]))  # a numeric axis holding a word
    assert _numeric(AXES["exposure"], pd.Series(["0.02", "0.01"]))
    assert not _numeric(AXES["readout"], pd.Series(["full", "bin"]))
    assert AXES["seed"].realisations and not AXES["f_number"].realisations
    assert AXES["seed"].note and AXES["f_number"].note
