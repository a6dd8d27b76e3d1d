"""The MSP at thresholds 20, 25 and 30 (cfa_mitsuba/report/moire_sensitivity.py)
uses the metric's own rule: at the paper's 25 it gives the metric's value."""

from __future__ import annotations

import numpy as np

from cfa_mitsuba.metrics.moire import moire, msp_column
from cfa_mitsuba.report.moire_sensitivity import THRESHOLDS, msp_by_threshold


def _chirp_pair(peak: float):
    """A grey chirp image and a camera image whose chroma grows linearly with the column to ``peak`` C*ab
    (as XYZ around D65 white), and the frequency per column."""
    h, w = 31, 120
    white = np.array([95.047, 100.0, 108.883])
    ref = np.broadcast_to(white * 0.5, (h, w, 3)).copy()
    test = ref.copy()
    # a reddish shift growing across the columns: X up, Z down
    ramp = np.linspace(0.0, 1.0, w)[None, :] * peak / 100.0
    test[..., 0] *= 1 + ramp
    test[..., 2] *= 1 - ramp
    return ref, test, white, np.linspace(0.5, 24.0, w)


def test_msp_at_25_is_the_metrics_value_and_thresholds_order_it():
    ref, test, white, freq = _chirp_pair(80.0)
    res = moire(ref, test, white, frequency_cy_per_deg=freq)
    got = msp_by_threshold(res.details)
    assert [t for t in THRESHOLDS] == [20.0, 25.0, 30.0]
    assert got[1] == (float(res), True)
    assert got[0][0] < got[1][0] < got[2][0]  # chroma rises with frequency: a lower threshold is passed sooner


def test_a_threshold_above_the_peak_chroma_gives_a_bound_at_the_top_frequency():
    ref, test, white, freq = _chirp_pair(40.0)
    res = moire(ref, test, white, frequency_cy_per_deg=freq)
    peak = float(np.nanmax(res.details["block_mean_test"]))
    below, above = msp_by_threshold(res.details, thresholds=(peak - 1.0, peak + 1.0))
    assert below[1] is True and below[0] < freq[-1]
    half = res.details["block"] // 2
    assert above == (float(freq[len(freq) - 1 - half]), False)  # the last column with a block mean
