"""Bad or extreme input: a one-line error or a documented finite result
(what every method must refuse, and its zeros, saturation and scale, are
the generic checks of tests/registry_checks.py)."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError

#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in cm.isp.list_demosaics())


@pytest.mark.parametrize("bad, needle", [
    (np.ones((8, 8, 3)), "must be 2-D"),
    (np.ones(16), "must be 2-D"),
    (np.array([["a", "b"], ["c", "d"]]), "numeric"),
])
def test_wrong_shape_or_type(bad, needle):
    with pytest.raises(CfaMitsubaError, match=needle):
        cm.isp.demosaic(bad, "bayer", "bilinear")


@pytest.mark.parametrize("method", METHODS)
def test_half_saturated_edge_stays_finite(method):
    raw = np.zeros((16, 16))
    raw[:, 8:] = 4095.0
    out = cm.isp.demosaic(raw, "rgbw2", method)
    assert np.all(np.isfinite(out))
    # gradient-corrected methods may overshoot, but by a bounded fraction
    assert out.min() > -0.5 * 4095 and out.max() < 1.5 * 4095


def test_unknown_method_cfa_and_option():
    with pytest.raises(CfaMitsubaError, match="unknown demosaicing method 'nope'.*bilinear"):
        cm.isp.demosaic(np.ones((4, 4)), "bayer", "nope")
    with pytest.raises(CfaMitsubaError, match="unknown CFA"):
        cm.isp.demosaic(np.ones((4, 4)), "nope", "bilinear")
    with pytest.raises(CfaMitsubaError, match="'bilinear'.*iterations"):
        cm.isp.demosaic(np.ones((4, 4)), "bayer", "bilinear", iterations=3)
    with pytest.raises(CfaMitsubaError, match="iterations"):
        cm.isp.demosaic(np.ones((4, 4)), "bayer", "pocs", iterations=-1)
    with pytest.raises(CfaMitsubaError, match="tolerance"):
        cm.isp.demosaic(np.ones((4, 4)), "bayer", "pocs", tolerance=float("nan"))
    with pytest.raises(CfaMitsubaError, match="reference 'Q'"):
        cm.isp.demosaic(np.ones((4, 4)), "bayer", "laplacian", reference="Q")
    with pytest.raises(CfaMitsubaError, match="luminance_weights needs 3"):
        cm.isp.demosaic(np.ones((4, 4)), "bayer", "laplacian", reference="luminance", luminance_weights=[1, 2])
    with pytest.raises(CfaMitsubaError, match="weighting"):
        cm.isp.demosaic(np.ones((4, 4)), "bayer", "adaptive-laplacian", weighting="median")


def test_pocs_iterations_and_tolerance():
    import skimage.data

    img = skimage.data.chelsea()[:64, :64] / 255.0
    raw = cm.isp.mosaic_image(img, "bayer")
    info = {}
    cm.isp.demosaic(raw, "bayer", "pocs", tolerance=0.0, iterations=3, info=info)
    assert info["iterations"] == 3
    cm.isp.demosaic(raw, "bayer", "pocs", info=info)
    assert 1 <= info["iterations"] <= 10 and (info["change"] < 1e-3 or info["iterations"] == 10)
    zero_iter = cm.isp.demosaic(raw, "bayer", "pocs", iterations=0)
    assert np.all(np.isfinite(zero_iter))
