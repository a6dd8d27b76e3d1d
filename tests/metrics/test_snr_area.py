"""YSNR referred to an area (metrics/snr.py, ``ysnr-area``): the noise power
spectrum at zero frequency, which smoothing with unit gain at zero
frequency does not change.  Checked against the analytic NPS(0) of white
noise, of box-blurred white noise, and of a Bayer mosaic interpolated by
colour-demosaicing's bilinear (an independent demosaicker): a channel of
sample density d with per-sample variance s^2 has NPS(0) = s^2 / d."""

import numpy as np
import pytest
from scipy import ndimage

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError

WHITE = [100.0, 100.0, 100.0]


def _grey_with_y_noise(noise_y: np.ndarray, level: float = 18.0):
    ref = np.full((*noise_y.shape, 3), level)
    test = ref.copy()
    test[..., 1] += noise_y
    # X and Z: Y's noise and some of their own (chroma noise is not what is tested here)
    test[..., 0] += noise_y + 0.1 * noise_y.std() * np.random.default_rng(99).standard_normal(noise_y.shape)
    test[..., 2] += noise_y
    return ref, test


def _mean_over_seeds(make, n=12):
    per_pixel, area = [], []
    for seed in range(n):
        r = cm.metrics.ysnr(*make(np.random.default_rng(seed)), WHITE)
        per_pixel.append(float(r))
        area.append(r.details["ysnr_area"])
    return np.mean(per_pixel), np.mean(area)


@pytest.mark.parametrize("blur", [1, 3, 5])
def test_box_blur_raises_pixel_ysnr_but_not_the_area_ysnr(blur):
    sigma = 0.9

    def make(rng):
        white = sigma * rng.standard_normal((220, 120))
        smoothed = ndimage.uniform_filter(white, blur, mode="wrap") if blur > 1 else white
        return _grey_with_y_noise(smoothed)

    per_pixel, area = _mean_over_seeds(make)
    assert per_pixel == pytest.approx(blur * 18.0 / sigma, rel=0.05)   # a k x k box divides the sd by k
    assert area == pytest.approx(18.0 / sigma, rel=0.05)               # NPS(0) = sigma^2 whatever the blur


def test_bilinear_bayer_green_and_red_have_the_nps_of_their_sample_density():
    """colour-demosaicing's bilinear on a flat Bayer mosaic with white noise:
    G (density 1/2) has NPS(0) = 2 s^2, R (1/4) 4 s^2, while the per-pixel
    variance is 0.625 s^2 and 0.5625 s^2 (the interpolation averages)."""
    from colour_demosaicing import demosaicing_CFA_Bayer_bilinear

    s, level = 0.02, 0.5
    rows = {"G": [], "R": [], "G pixel": []}
    for seed in range(10):
        rng = np.random.default_rng(seed)
        mosaic = level + s * rng.standard_normal((260, 140))
        rgb = demosaicing_CFA_Bayer_bilinear(mosaic, "RGGB")[6:-6, 6:-6]
        for name, c in (("G", 1), ("R", 0)):
            ref, test = _grey_with_y_noise(rgb[..., c] - level, level=level)
            r = cm.metrics.ysnr(ref, test, [1.0, 1.0, 1.0])
            rows[name].append(r.details["ysnr_area"])
            if name == "G":
                rows["G pixel"].append(float(r))
    assert np.mean(rows["G"]) == pytest.approx(level / (s * np.sqrt(2.0)), rel=0.05)
    assert np.mean(rows["R"]) == pytest.approx(level / (s * 2.0), rel=0.05)
    assert np.mean(rows["G pixel"]) == pytest.approx(level / (s * np.sqrt(0.625)), rel=0.05)


def test_a_region_too_small_for_the_lags_gives_no_area_value_and_no_row():
    rng = np.random.default_rng(0)
    ref, test = _grey_with_y_noise(0.5 * rng.standard_normal((30, 14)))   # 24 x 8 px after the margin
    r = cm.metrics.ysnr(ref, test, WHITE)
    assert r.details["ysnr_area"] is None and np.isfinite(float(r))
    rows = cm.metrics.result_rows({"ysnr": r})
    assert {row["metric"] for row in rows} == {"ysnr", "chroma_snr"}
    assert cm.metrics.ysnr(ref, test, WHITE, correlation_px=1).details["ysnr_area"] > 0


@pytest.mark.parametrize("bad", [-1, 2.5, True, "4"])
def test_bad_correlation_lag_is_refused_in_one_line(bad):
    ref, test = _grey_with_y_noise(np.random.default_rng(0).standard_normal((40, 40)))
    with pytest.raises(CfaMitsubaError, match="correlation_px") as info:
        cm.metrics.ysnr(ref, test, WHITE, correlation_px=bad)
    assert "\n" not in str(info.value)


def test_nps_at_zero_equals_the_sum_over_every_lag_to_the_bit():
    """_nps_at_zero computes the dot product of each lag pair once (the
    lag and its opposite pair the same windows): the sum equals the
    direct one over all (2L + 1)^2 lags, in the same order, bit for bit."""
    from cfa_mitsuba.metrics.snr import _nps_at_zero

    def direct(noise, lag):
        h, w = noise.shape
        total = 0.0
        for dy in range(-lag, lag + 1):
            for dx in range(-lag, lag + 1):
                a = noise[max(dy, 0):h + min(dy, 0), max(dx, 0):w + min(dx, 0)]
                b = noise[max(-dy, 0):h + min(-dy, 0), max(-dx, 0):w + min(-dx, 0)]
                total += float(np.vdot(a, b)) / a.size
        return total

    rng = np.random.default_rng(17)
    for shape in [(494, 80), (37, 61), (9, 9), (200, 33)]:
        for lag in (0, 1, 2, 4):
            if min(shape) < 4 * lag + 1:
                assert _nps_at_zero(np.zeros(shape), lag) is None
                continue
            noise = rng.standard_normal(shape) * rng.uniform(0.01, 10)
            noise -= noise.mean()
            assert _nps_at_zero(noise, lag) == direct(noise, lag), (shape, lag)
