"""One record per metric: ``cfa-mitsuba list metrics --json``, the records
against the scenes and the scoring ranges, and evaluation by name."""

from __future__ import annotations

import json

import numpy as np
import pytest

import cfa_mitsuba as cm
import registry_checks as checks
from conftest import run_cli


def test_list_metrics_json_is_one_object_per_metric():
    proc = run_cli("list", "metrics", "--json", check_rc=0)
    records = json.loads(proc.stdout)
    assert isinstance(records, list)
    names = [r["name"] for r in records]
    assert names[:8] == list(cm.metrics.scored_metrics())  # the paper's eight first, in its order
    for r in records:
        for key in ("name", "scenes", "unit", "higher_is_better", "scored", "inputs", "label"):
            assert key in r, (r["name"], key)
        assert isinstance(r["scenes"], list) and r["scenes"]
        assert isinstance(r["higher_is_better"], bool) and isinstance(r["scored"], bool)
    by = {r["name"]: r for r in records}
    assert [n for n in names if by[n]["scored"]] == names[:8]
    assert by["mtf"]["unit"] == "cy/mm" and by["mtf"]["higher_is_better"] is True
    assert by["delta-e"]["scenes"] == ["macbeth"] and by["ssim"]["scenes"] == ["natural"]
    assert by["delta-l"]["derived_from"] == "delta-e" and by["delta-l"]["scored"] is False


def test_records_agree_with_the_scenes_and_the_scoring():
    from cfa_mitsuba import render
    from cfa_mitsuba.study.scoring import default_ranges

    for name, _ in render.list_scenes():
        assert cm.metrics.metrics_for_scene(render.get_scene(name).kind), name  # every scene feeds a metric
    ranges = default_ranges()
    assert set(ranges) == set(cm.metrics.scored_metrics())
    for r in cm.metrics.METRICS.values():
        if r.scored and r.range_scaling is None:
            assert (ranges[r.name].worst, ranges[r.name].best) == r.score_range
            assert (ranges[r.name].best > ranges[r.name].worst) == r.higher_is_better


@pytest.mark.parametrize("name", cm.metrics.metric_names())
def test_every_metric_passes_the_generic_checks(name):
    """Every registered metric, on a scene of a kind it names: its record,
    evaluation by name, its value on identical images (the record's), its
    refusals and its options (tests/registry_checks.py)."""
    checks.check_metric(cm.metrics.get_metric(name))


def test_a_metric_without_its_geometry_or_name_is_one_line():
    xyz = np.full((16, 16, 3), 40.0)
    white = np.array([95.05, 100.0, 108.9])
    with pytest.raises(cm.CfaMitsubaError, match="needs the chirp"):
        cm.metrics.evaluate("moire", cm.metrics.MetricInputs(xyz, xyz, white))
    with pytest.raises(cm.CfaMitsubaError, match="unknown metric"):
        cm.metrics.get_metric("no-such-metric")


def test_every_scored_metric_states_its_practical_difference_and_its_source():
    """Issue 46: a decision names a winner only past the smallest difference that matters; each scored
    record gives it in its own unit (or as a share of the value) with where it comes from."""
    for r in cm.metrics.METRICS.values():
        if not r.scored:
            continue
        amount = r.practical(r.unit, typical=100.0)
        assert amount is not None and amount > 0, r.name
        assert len(r.practical_source) > 20 and any(ch.isdigit() for ch in r.practical_source), r.name
    de = cm.metrics.get_metric("delta-e")
    assert de.practical("dE00") == 0.8 and de.practical("dE76") == 2.3  # ISETCam's dE76 runs get CIELAB's JND
    assert cm.metrics.get_metric("mtf").practical("cy/mm", typical=80.0) == pytest.approx(4.0)
