"""The ysnr metric (metrics/snr.py) on images of known noise."""

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError


def test_ysnr_of_known_gaussian_noise_and_the_mid_grey_step():
    rng = np.random.default_rng(3)
    h, w = 60, 100
    steps = [(0, 50), (50, 100)]
    ref = np.empty((h, w, 3))
    ref[:, :50] = 0.18 * 100.0   # the mid-grey step
    ref[:, 50:] = 0.70 * 100.0
    sigma = 0.9
    test = ref.copy()
    test[..., 1] += sigma * rng.standard_normal((h, w))       # Y noise only on Y
    test[..., 0] += 2 * sigma * rng.standard_normal((h, w))   # chroma noise in X
    r = cm.metrics.ysnr(ref, test, [100.0, 100.0, 100.0], steps=steps, margin=3)
    assert r.details["region"] == [3, 3, 57, 47] and r.details["mean_y_rel"] == pytest.approx(0.18)
    assert float(r) == pytest.approx(18.0 / sigma, rel=0.03)
    # x' - y' has variance (4 + 1) sigma^2, z' - y' sigma^2 (white 100, 100, 100): mean 3 sigma^2
    assert r.details["chroma_snr"] == pytest.approx(18.0 / (np.sqrt(3.0) * sigma), rel=0.03)


def test_ysnr_does_not_count_the_scene_s_own_slow_variation_as_noise():
    ramp = np.linspace(0.9, 1.1, 80)[None, :, None] * np.full((40, 80, 3), 18.0)
    rng = np.random.default_rng(1)
    test = ramp * (1 + 0.02 * rng.standard_normal((40, 80, 3)))
    assert float(cm.metrics.ysnr(ramp, test, [100.0, 100.0, 100.0])) == pytest.approx(50.0, rel=0.05)


def test_noise_free_image_is_refused_in_one_line():
    ref = np.full((20, 20, 3), 18.0)
    with pytest.raises(CfaMitsubaError, match="no noise") as info:
        cm.metrics.ysnr(ref, ref, [100.0, 100.0, 100.0])
    assert "\n" not in str(info.value)
    with pytest.raises(CfaMitsubaError, match="margin"):
        cm.metrics.ysnr(ref, ref + 1, [100.0, 100.0, 100.0], margin=10)


def test_the_record_is_fed_by_the_gray_bar_and_not_scored():
    rec = cm.metrics.METRICS["ysnr"]
    assert rec.scenes == ("gray-bar",) and rec.higher_is_better and not rec.scored
    assert cm.metrics.METRICS["chroma_snr"].parent == "ysnr"
    assert "ysnr" in cm.metrics.metrics_for_scene("gray-bar")
