"""The Examples in the metric and scoring docstrings run and give what they say."""

from __future__ import annotations

import doctest
import importlib

import pytest

import cfa_mitsuba as cm

#: Every registered metric's module (a new metric is covered without an
#: edit here), then the shared helpers and scoring.
MODULES = list(dict.fromkeys(
    [r.function.__module__ for r in cm.metrics.METRICS.values() if r.function is not None]
    + ["cfa_mitsuba.metrics._result", "cfa_mitsuba.metrics.preprocess", "cfa_mitsuba.metrics.geometry",
       "cfa_mitsuba.metrics.registry", "cfa_mitsuba.study.scoring", "cfa_mitsuba.colorimetry"]))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0, f"{name} has no example to run"
    assert result.failed == 0
