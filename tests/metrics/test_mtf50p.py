"""MTF50P and the MTF peak (issue 12.4): sharpness that overshoot cannot raise.

Analytic cases: a Gaussian edge (no overshoot: peak 1 at DC, MTF50P equal
to MTF50) and an unsharp-masked edge, PSF (1 + k) G(s1) - k G(s2), whose
MTF (1 + k) exp(-2 pi^2 s1^2 f^2) - k exp(-2 pi^2 s2^2 f^2) rises above 1:
its peak and the frequency where it falls to half the peak follow in closed
form (peak) and by root finding on the closed form (MTF50P).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import erf

import cfa_mitsuba.metrics as cm
from cfa_mitsuba.metrics import METRICS, result_rows


def _phi(d, s):
    return 0.5 * (1.0 + erf(d / (np.sqrt(2.0) * s)))


def sharpened_edge(angle_deg, s1, s2, k, *, h=128, w=96, dark=0.2, bright=0.8):
    """A step through the PSF (1 + k) G(s1) - k G(s2), sampled at pixel centres."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    t = np.radians(angle_deg)
    d = (x - (w - 1) / 2.0) * np.cos(t) - (y - (h - 1) / 2.0) * np.sin(t)
    return dark + (bright - dark) * ((1 + k) * _phi(d, s1) - k * _phi(d, s2))


def analytic(s1, s2, k):
    """(peak, peak frequency, MTF50P, MTF50) of the sharpened edge's MTF, cy/px."""
    def mtf(f):
        return (1 + k) * np.exp(-2 * np.pi**2 * s1**2 * f**2) - k * np.exp(-2 * np.pi**2 * s2**2 * f**2)
    # d MTF / df = 0  <=>  exp(2 pi^2 f^2 (s2^2 - s1^2)) = k s2^2 / ((1 + k) s1^2)
    a = np.log(k * s2**2 / ((1 + k) * s1**2)) / (s2**2 - s1**2)
    f_peak = np.sqrt(a / (2 * np.pi**2))
    peak = mtf(f_peak)
    return peak, f_peak, brentq(lambda f: mtf(f) - peak / 2, f_peak, 2.0), brentq(lambda f: mtf(f) - 0.5, f_peak, 2.0)


@pytest.mark.parametrize("angle", [4.0, 8.0])
@pytest.mark.parametrize("sigma", [0.7, 1.5])
def test_gaussian_edge_has_peak_one_and_mtf50p_equal_to_mtf50(angle, sigma):
    edge = sharpened_edge(angle, sigma, 2 * sigma, 0.0)
    d = cm.mtf(edge, pixel_pitch_um=2.2).details
    assert d["mtf_peak"] == 1.0 and d["mtf_peak_cy_px"] == 0.0
    assert d["mtf50p_cy_px"] == d["mtf50_cy_px"] and d["mtf50p_cy_mm"] == d["mtf50_cy_mm"]
    assert d["mtf50p_found"]


@pytest.mark.parametrize("s1,s2,k", [(1.0, 3.0, 1.0), (1.0, 2.0, 0.5), (0.8, 2.5, 0.6), (1.2, 3.0, 1.5)])
@pytest.mark.parametrize("angle", [5.0, 8.0])
def test_sharpened_edge_peak_and_mtf50p_match_the_closed_form(s1, s2, k, angle):
    peak, f_peak, m50p, m50 = analytic(s1, s2, k)
    d = cm.mtf(sharpened_edge(angle, s1, s2, k)).details
    # measured: MTF50P within 0.2 %, the peak 0.2-1.6 % low (the Hamming
    # window on the LSF smooths the spectrum), its frequency within 1 bin
    assert d["mtf50p_cy_px"] == pytest.approx(m50p, rel=0.01)
    assert d["mtf_peak"] == pytest.approx(peak, rel=0.02)
    assert d["mtf_peak_cy_px"] == pytest.approx(f_peak, abs=1.0 / 96 + 1e-9)
    assert d["mtf50_cy_px"] == pytest.approx(m50, rel=0.01)
    # overshoot lifts MTF50 above MTF50P: the measure the score must not reward
    assert d["mtf50_cy_px"] > d["mtf50p_cy_px"]
    assert d["records"]["gray"]["mtf50p_cy_px"] == pytest.approx(m50p, rel=0.01)


def test_mtf50p_and_peak_are_records_read_from_the_mtf_details():
    r = cm.mtf(sharpened_edge(5.0, 1.0, 3.0, 1.0), pixel_pitch_um=2.2)
    rows = {row["metric"]: row for row in result_rows({"mtf": r})}
    assert rows["mtf50p"]["value"] == r.details["mtf50p_cy_mm"] and rows["mtf50p"]["unit"] == "cy/mm"
    assert rows["mtf-peak"]["value"] == r.details["mtf_peak"] and rows["mtf-peak"]["unit"] == ""
    assert METRICS["mtf50p"].parent == "mtf" and not METRICS["mtf50p"].scored
    assert METRICS["mtf-peak"].parent == "mtf" and not METRICS["mtf-peak"].scored
    # cy/mm is MTF50P in cy/px over the pitch in mm
    assert r.details["mtf50p_cy_mm"] == pytest.approx(r.details["mtf50p_cy_px"] / 2.2e-3, rel=1e-12)
