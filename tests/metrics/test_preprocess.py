"""Mean matching (metrics/preprocess.py): the camera image scaled to the
ideal's interior mean, the same bits with the reference mean given once, and
each bad input named as what it is."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba.metrics as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.metrics import colourspace as mc

XYZ = mc.srgb8_to_xyz(np.random.default_rng(7).integers(0, 256, (48, 64, 3)).astype(np.float64))


def test_mean_match_scales_to_the_interior_mean():
    out, k = cm.mean_match(XYZ * 0.5, XYZ, border=5, return_scale=True)
    assert k == pytest.approx(2.0) and out == pytest.approx(XYZ)
    with pytest.raises(CfaMitsubaError, match="mean"):
        cm.mean_match(np.zeros_like(XYZ), XYZ)


def test_mean_match_with_the_reference_mean_given_is_identical_and_names_each_image():
    """A study gives the ideal's interior mean once (reference_interior_mean):
    the same scale and image, bit for bit; a bad input is named as what it is."""
    from cfa_mitsuba.metrics import reference_interior_mean

    test = XYZ * np.random.default_rng(3).uniform(0.3, 0.7, XYZ.shape)
    for border in (0, 5, 10):
        want, k = cm.mean_match(test, XYZ, border=border, return_scale=True)
        got, k2 = cm.mean_match(test, XYZ, border=border, return_scale=True,
                                reference_mean=reference_interior_mean(XYZ, border=border))
        assert k2 == k and np.array_equal(got, want)
    bad = test.copy()
    bad[3, 3, 1] = np.nan
    for kw in ({}, {"reference_mean": reference_interior_mean(XYZ)}):
        with pytest.raises(CfaMitsubaError, match="^test image"):
            cm.mean_match(bad, XYZ, **kw)
        with pytest.raises(CfaMitsubaError, match="differ in shape"):
            cm.mean_match(test[:-1], XYZ, **kw)
    with pytest.raises(CfaMitsubaError, match="^reference image"):
        cm.mean_match(test, bad)
    with pytest.raises(CfaMitsubaError, match="^reference image"):
        reference_interior_mean(bad)
    with pytest.raises(CfaMitsubaError, match="reference image's interior mean"):
        cm.mean_match(test, XYZ, reference_mean=0.0)
    gray, gray_ref = test[..., 1:2], XYZ[..., 1:2]  # (H, W, 1): a gray image, as without the mean given
    want = cm.mean_match(gray, gray_ref, return_scale=True)
    got = cm.mean_match(gray, gray_ref, return_scale=True, reference_mean=reference_interior_mean(gray_ref))
    assert got[1] == want[1] and np.array_equal(got[0], want[0]) and got[0].shape == gray.shape[:2]
