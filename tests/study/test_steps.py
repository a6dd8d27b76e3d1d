"""The dynamic range method of study/steps.py (ISO 15739: saturation over
the luminance of SNR 1), against a noise model whose answer is known."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cfa_mitsuba.study.steps import dynamic_range


@pytest.mark.parametrize("a, b, c", [(1e-6, 2e-4, 0.0), (4e-6, 1e-5, 1e-4), (2.5e-5, 0.0, 0.0)])
def test_the_fit_recovers_the_model_and_solves_snr_1(a, b, c):
    s = np.array([0.86, 0.65, 0.48, 0.34, 0.23, 0.146, 0.085, 0.045, 0.0195, 0.006])
    noise = np.sqrt(a + b * s + c * s ** 2)
    got = dynamic_range(list(s), list(noise), saturation=0.9)
    assert (got["a"], got["b"], got["c"]) == pytest.approx((a, b, c), rel=1e-6, abs=1e-12)
    s1 = got["snr1_rel"]
    assert s1 / math.sqrt(a + b * s1 + c * s1 ** 2) == pytest.approx(1.0, rel=1e-9)  # SNR 1 there
    assert got["dynamic_range"] == pytest.approx(0.9 / s1)
    assert got["dynamic_range_db"] == pytest.approx(20 * math.log10(0.9 / s1))
    assert got["dynamic_range_ev"] == pytest.approx(math.log2(0.9 / s1))
    assert got["snr1_extrapolated"] is bool(s1 < s.min())


def test_read_noise_alone_has_snr_1_at_the_noise():
    """Constant noise sigma: SNR 1 where the signal equals sigma."""
    s = np.linspace(0.01, 0.9, 10)
    got = dynamic_range(list(s), [0.004] * 10, saturation=1.0)
    assert got["snr1_rel"] == pytest.approx(0.004, rel=1e-9)
    assert got["dynamic_range"] == pytest.approx(250.0, rel=1e-9)
    assert got["snr1_extrapolated"] is True


def test_too_few_steps_or_no_saturation_give_none():
    assert dynamic_range([0.5, 0.2], [0.01, 0.01], 0.9)["dynamic_range"] is None
    got = dynamic_range([0.5, 0.2, 0.1, None], [0.01, 0.01, 0.01, 0.3], None)
    assert got["snr1_rel"] == pytest.approx(0.01) and got["dynamic_range"] is None
