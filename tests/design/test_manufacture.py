"""Manufacturability (cfa_mitsuba/design/manufacture.py): the spectral
angle, the curve statistics, and the nearest measured filter set."""

from __future__ import annotations

import numpy as np
import pytest

from cfa_mitsuba import spectra
from cfa_mitsuba.design.manufacture import curve_stats, nearest_filters, spectral_angle_deg
from cfa_mitsuba.sensor import get_spectra_set

WL = spectra.DEFAULT_WAVELENGTHS


def test_spectral_angle_is_scale_free_and_90_degrees_for_disjoint_curves():
    a = np.array([0.0, 1.0, 2.0, 0.0])
    assert spectral_angle_deg(a, 3 * a) == pytest.approx(0.0, abs=1e-6)
    assert spectral_angle_deg([1, 0, 0], [0, 0, 1]) == pytest.approx(90.0)
    assert spectral_angle_deg([1, 1], [1, 0]) == pytest.approx(45.0)


def test_curve_stats_give_the_slope_per_10_nm_and_the_peak():
    x = np.arange(400.0, 501.0, 2.0)
    y = np.clip((x - 440.0) / 40.0, 0.0, 0.8)  # a ramp of 0.25 per 10 nm up to 0.8
    slope, peak = curve_stats(x, y)
    assert slope == pytest.approx(0.25) and peak == pytest.approx(0.8)


def test_a_measured_set_is_its_own_nearest():
    sset = get_spectra_set("pbrt-sony-ilce-9")
    curves = {a: spectra.band_average(*sset.curve(a), WL) for a in "RGB"}
    got = nearest_filters(curves)
    assert got["set"] == "pbrt-sony-ilce-9" and got["set_angle_deg"] == pytest.approx(0.0, abs=1e-4)
    assert all(v[1] == pytest.approx(0.0, abs=1e-4) for v in got["per_letter"].values())
    # a shifted green is further from every set, and its angle says by how much
    shifted = dict(curves, G=np.roll(curves["G"], 3))
    far = nearest_filters(shifted)
    assert far["per_letter"]["G"][1] > 5.0
