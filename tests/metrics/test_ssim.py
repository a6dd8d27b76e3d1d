"""SSIM with the reference's window moments computed once (issue 25): the
same numbers as scikit-image's ``structural_similarity`` itself, the
independent reference for the term-for-term copy in metrics/ssim.py."""

from __future__ import annotations

import numpy as np
import pytest
from skimage.metrics import structural_similarity

from cfa_mitsuba import metrics as m
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.metrics.ssim import ssim, ssim_reference_moments
import cfa_mitsuba.metrics as cm
from reference_data import COLOUR_PAIRS, entries, colour_pair


def _skimage(a, b):
    return structural_similarity(a, b, data_range=255.0, gaussian_weights=True, sigma=1.5,
                                 use_sample_covariance=False)


@pytest.fixture(scope="module")
def pair():
    rng = np.random.default_rng(7)
    ref = np.round(rng.random((61, 83, 3)) * 255.0)
    test = np.clip(ref + np.round(rng.normal(0.0, 9.0, ref.shape)), 0, 255)
    return ref, test


def test_gray_equals_scikit_image_exactly(pair):
    ref, test = pair
    gray = [x @ np.array([0.298936021293775, 0.587043074451121, 0.114020904255103]) for x in pair]
    assert ssim(ref, test) == _skimage(*gray)


def test_rgb_mean_and_given_moments_equal_scikit_image(pair):
    ref, test = pair
    expected = np.mean([_skimage(ref[..., c], test[..., c]) for c in range(3)])
    moments = ssim_reference_moments(ref, channel="rgb_mean")
    assert ssim(ref, test, channel="rgb_mean") == expected
    assert ssim(ref, test, channel="rgb_mean", reference_moments=moments) == expected


def test_the_adapter_caches_the_moments_per_reference(pair):
    ref, test = pair
    shared: dict = {}
    inputs = m.MetricInputs(reference_srgb8=ref, test_srgb8=test, shared=shared)
    first = float(m.evaluate("ssim", inputs))
    assert any(k[0] == "ssim" for k in shared if isinstance(k, tuple))
    again = float(m.evaluate("ssim", m.MetricInputs(reference_srgb8=ref, test_srgb8=test, shared=shared)))
    assert first == again == ssim(ref, test)


def test_moments_of_another_image_are_refused(pair):
    ref, test = pair
    with pytest.raises(CfaMitsubaError, match="reference_moments"):
        ssim(ref, test, reference_moments=ssim_reference_moments(ref[:40]))


def test_gaussian_window_is_scikit_images_bit_for_bit():
    """SSIM's window (a compiled column pass, ndimage's row pass) against
    scikit-image's ``gaussian`` on a camera-sized plane."""
    from skimage.filters import gaussian

    from cfa_mitsuba.metrics.ssim import _gaussian

    x = np.round(np.random.default_rng(3).random((317, 240)) * 255.0)
    np.testing.assert_array_equal(_gaussian(x), gaussian(x, sigma=1.5, truncate=3.5, mode="reflect"))


# -- reference values (tests/data/reference/expected.json: the authors' own code) ---------------

@pytest.mark.parametrize("pid", COLOUR_PAIRS)
def test_ssim_matches_ssim_index_m(pid):
    ref, dist = colour_pair(pid)
    for e in entries("colour_pairs", pid, "ssim", oracle="ssim_index.m"):
        channel, down = e["variant"].split("|")
        got = cm.ssim(ref, dist, channel=channel, downsample=down == "wang2009_downsampling")
        assert abs(got - e["value"]) <= 1e-6, (e["variant"], got, e["value"])
        assert abs(cm.ssim(dist, ref, channel=channel, downsample=down == "wang2009_downsampling") - got) < 1e-12
