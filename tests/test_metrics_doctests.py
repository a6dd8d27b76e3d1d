"""The Examples in the metric and scoring docstrings run and give what they say."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = [
    "cfa_mitsuba.metrics._result", "cfa_mitsuba.metrics.delta_e",
    "cfa_mitsuba.metrics.scielab", "cfa_mitsuba.metrics.ssim", "cfa_mitsuba.metrics.mtf",
    "cfa_mitsuba.metrics.moire", "cfa_mitsuba.metrics.achromatic", "cfa_mitsuba.metrics.mdsi",
    "cfa_mitsuba.metrics.haarpsi", "cfa_mitsuba.metrics.preprocess", "cfa_mitsuba.metrics.geometry",
    "cfa_mitsuba.study.scoring", "cfa_mitsuba.colorimetry",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0, f"{name} has no example to run"
    assert result.failed == 0
