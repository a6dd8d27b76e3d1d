"""One record per metric: ``cfa-mitsuba list metrics --json``, the records
against the scenes and the scoring ranges, and evaluation by name."""

from __future__ import annotations

import json

import numpy as np
import pytest

import cfa_mitsuba as cm
from conftest import run_cli


def test_list_metrics_json_is_one_object_per_metric():
    proc = run_cli("list", "metrics", "--json", check_rc=0)
    records = json.loads(proc.stdout)
    assert isinstance(records, list)
    names = [r["name"] for r in records]
    assert names[:8] == ["delta-e", "scielab", "ssim", "mtf", "moire", "achromatic", "mdsi", "haarpsi"]
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


def test_every_metric_evaluates_by_name_on_one_input():
    """A tiny synthetic scene geometry for each metric; identical images give
    each metric's ideal value."""
    rng = np.random.default_rng(1)
    white = np.array([95.05, 100.0, 108.9])
    h, w = 48, 64
    xyz = np.clip(rng.normal(40.0, 5.0, (h, w, 3)), 1.0, None)
    x = np.arange(w)
    edge = np.where(x[None, :] > w / 2 + 0.1 * np.arange(h)[:, None], 80.0, 20.0)
    edge_xyz = edge[..., None] * (white / 100.0)
    geo = {"patches": [[4, 4, 12, 12], [20, 20, 28, 28]], "samples_per_degree": 20.0,
           "frequency_cy_per_deg": np.linspace(0.1, 10.0, w), "row": h // 2}
    for r in cm.metrics.METRICS.values():
        if r.secondary:
            continue
        img = edge_xyz if "slanted-edge" in r.scenes else xyz
        try:
            res = cm.metrics.evaluate(r.name, cm.metrics.MetricInputs(img, img, white, geometry=geo,
                                                                      pixel_pitch_um=2.2))
        except cm.CfaMitsubaError as exc:  # a noise measure is undefined on a noise-free pair: one line, then noisy
            assert "\n" not in str(exc), r.name
            noisy = img * (1 + 0.01 * rng.standard_normal(img.shape))
            res = cm.metrics.evaluate(r.name, cm.metrics.MetricInputs(img, noisy, white, geometry=geo,
                                                                      pixel_pitch_um=2.2))
            assert np.isfinite(float(res)), r.name
        assert res.name == r.name or r.name in ("ssim", "mdsi", "haarpsi")
        ideal = {"delta-e": 0.0, "scielab": 0.0, "achromatic": 0.0, "ssim": 1.0, "mdsi": 0.0, "haarpsi": 1.0}
        if r.name in ideal:
            assert float(res) == pytest.approx(ideal[r.name], abs=1e-9), r.name
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
