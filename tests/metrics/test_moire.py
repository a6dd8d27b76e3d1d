"""The moire metric (metrics/moire.py) on chroma ramps of known start: the first
column above the threshold in cy/deg, either direction, a chirp without moire
as a flagged bound, and its bad arguments."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba.metrics as cm
from cfa_mitsuba.errors import CfaMitsubaError
from lab_images import WHITE, lab_image_to_xyz


def _chroma_ramp(h, w, top):
    lab = np.zeros((h, w, 3))
    lab[..., 0] = 50.0
    lab[..., 1] = np.linspace(0.0, top, w)[None, :]
    return lab_image_to_xyz(lab)


def test_moire_start_is_the_first_column_above_threshold_in_cpd():
    h, w = 31, 200
    ideal = _chroma_ramp(h, w, 0.0)
    camera = _chroma_ramp(h, w, 60.0)
    freq = np.linspace(0.5, 50.0, w)
    r = cm.moire(ideal, camera, WHITE, frequency_cy_per_deg=freq)
    a = np.linspace(0.0, 60.0, w)
    col = int(np.flatnonzero(a > 25.0)[0])
    assert r.details["passed"] and r.details["msp_px"] == col and r.details["censored"] is False
    assert float(r) == pytest.approx(freq[col]) and r.unit == "cy/deg"
    # a chirp whose frequency falls left to right is searched from the right
    r2 = cm.moire(ideal[:, ::-1], camera[:, ::-1], WHITE, frequency_cy_per_deg=freq[::-1])
    assert r2.details["msp_px"] == w - 1 - col and float(r2) == pytest.approx(float(r))
    for block in (5, 7):
        assert cm.moire(ideal, camera, WHITE, frequency_cy_per_deg=freq, block=block).details["passed"]


def test_chirp_without_moire_reports_the_highest_frequency_with_a_flag():
    ideal = _chroma_ramp(31, 100, 0.0)
    freq = np.linspace(1.0, 40.0, 100)
    r = cm.moire(ideal, ideal, WHITE, frequency_cy_per_deg=freq)
    assert not r.details["passed"] and np.isfinite(float(r))
    assert r.details["censored"] is True  # a bound: stored and shown as one (issue 12.5)
    assert cm.METRICS["moire"].censored_key == "censored"
    assert all(rec.censored_key is None for rec in cm.METRICS.values() if rec.name != "moire")
    assert float(r) == pytest.approx(freq[100 - 1 - 7])  # last column where a 15-px block fits


def test_moire_bad_arguments():
    ideal = _chroma_ramp(31, 100, 0.0)
    with pytest.raises(CfaMitsubaError, match="one per column"):
        cm.moire(ideal, ideal, WHITE, frequency_cy_per_deg=np.ones(50))
    with pytest.raises(CfaMitsubaError, match="odd"):
        cm.moire(ideal, ideal, WHITE, frequency_cy_per_deg=np.ones(100), block=4)
    with pytest.raises(CfaMitsubaError, match="does not fit"):
        cm.moire(ideal[:10], ideal[:10], WHITE, frequency_cy_per_deg=np.ones(100))
