"""The info-capacity metric (metrics/info_capacity.py) against closed forms."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter
from scipy.special import erf, spence

import cfa_mitsuba as cm
from cfa_mitsuba.metrics.info_capacity import capacity_bits_per_px, info_capacity, noise_power_spectrum


def _edge(blur_px=1.0, h=200, w=120, angle=5.0, low=0.2, step=0.6):
    y, x = np.mgrid[0:h, 0:w]
    d = (x - w / 2 - (y - h / 2) * np.tan(np.radians(angle))) * np.cos(np.radians(angle))
    return low + step * 0.5 * (1 + erf(d / (np.sqrt(2) * blur_px)))


def _gaussian_capacity(blur_px, step, sigma):
    """2 pi int_0^0.5 log2(1 + k exp(-2 a f^2)) f df, MTF = exp(-a f^2),
    a = 2 pi^2 blur^2, k = (step/2)^2 / sigma^2: pi / (2 a ln 2) (Li2(-k e^{-a/2}) - Li2(-k)),
    Li2(z) = scipy's spence(1 - z)."""
    a, k = 2 * np.pi ** 2 * blur_px ** 2, (step / 2) ** 2 / sigma ** 2
    li2 = lambda z: spence(1 - z)  # noqa: E731
    return np.pi / (2 * a * np.log(2)) * (li2(-k * np.exp(-a / 2)) - li2(-k))


def test_flat_mtf_and_white_noise_give_the_shannon_hartley_disc():
    f = np.linspace(0, 0.7, 701)
    # S/N = 15 at every frequency inside the Nyquist circle: pi/4 * log2(16)
    assert capacity_bits_per_px(f, np.full_like(f, 15.0), np.ones_like(f)) == pytest.approx(np.pi, rel=1e-6)


def test_white_noise_has_a_flat_nps_equal_to_its_variance():
    rng = np.random.default_rng(0)
    f, nps = noise_power_spectrum(0.05 * rng.standard_normal((256, 256)))
    # flat within 20 % above the lowest bin (the mean removed and the window depress that one)
    assert f.max() <= 0.5 and np.all(np.abs(nps[1:] / 0.05 ** 2 - 1) < 0.2)
    assert np.mean(nps) == pytest.approx(0.05 ** 2, rel=0.05)


@pytest.mark.parametrize("sigma, tol", [(0.002, 0.03), (0.006, 0.06)])
def test_gaussian_blurred_edge_with_white_noise_matches_the_closed_form(sigma, tol):
    rng = np.random.default_rng(1)
    img = _edge() + sigma * rng.standard_normal((200, 120))
    got = info_capacity(img)
    assert got.unit == "bit/px"
    assert float(got) == pytest.approx(_gaussian_capacity(1.0, 0.6, sigma), rel=tol)
    assert got.details["noise_rms"] == pytest.approx(sigma, rel=0.05)


def test_blur_after_capture_moves_mtf50_but_not_the_capacity():
    rng = np.random.default_rng(2)
    img = _edge() + 0.004 * rng.standard_normal((200, 120))
    blurred = gaussian_filter(img, 0.7)
    a, b = info_capacity(img), info_capacity(blurred)
    assert b.details["mtf50_cy_px"] < 0.85 * a.details["mtf50_cy_px"]   # blur costs MTF50 over 15 %
    assert float(b) == pytest.approx(float(a), rel=0.05)                 # and the capacity under 5 %
    noisier = info_capacity(_edge() + 0.012 * rng.standard_normal((200, 120)))
    assert float(noisier) < float(a) - 0.8                              # more noise: less information


def test_registered_for_the_slanted_edge():
    rec = cm.metrics.get_metric("info-capacity")
    assert rec.scenes == ("slanted-edge",) and rec.higher_is_better and rec.unit == "bit/px"
    assert "info-capacity" in cm.metrics.metrics_for_scene("slanted-edge")
