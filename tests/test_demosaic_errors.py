"""Bad or extreme input: a one-line error or a documented finite result."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError

#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in cm.isp.list_demosaics())


@pytest.mark.parametrize("method", METHODS)
def test_smaller_than_tile(method):
    with pytest.raises(CfaMitsubaError, match="smaller than the CFA tile"):
        cm.isp.demosaic(np.ones((3, 3)), "rgbw2", method)
    with pytest.raises(CfaMitsubaError, match="smaller than the CFA tile"):
        cm.isp.demosaic(np.ones((1, 5)), "bayer", method)


@pytest.mark.parametrize("method", METHODS)
def test_exactly_one_tile_is_fine(method):
    for name in ("bayer", "rgbw2", "rgb3", "cmy2"):
        c = cm.sensor.get_cfa(name)
        out = cm.isp.demosaic(np.full(c.tile_shape, 0.3), c, method)
        assert np.allclose(out, 0.3)


@pytest.mark.parametrize("bad, needle", [
    (np.ones((8, 8, 3)), "must be 2-D"),
    (np.ones(16), "must be 2-D"),
    (np.array([["a", "b"], ["c", "d"]]), "numeric"),
])
def test_wrong_shape_or_type(bad, needle):
    with pytest.raises(CfaMitsubaError, match=needle):
        cm.isp.demosaic(bad, "bayer", "bilinear")


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("method", METHODS)
def test_nan_or_inf_refused(value, method):
    raw = np.ones((8, 8))
    raw[3, 4] = value
    with pytest.raises(CfaMitsubaError, match="1 NaN or infinite"):
        cm.isp.demosaic(raw, "bayer", method)


@pytest.mark.parametrize("cfa", ["bayer", "rgbw2", "cmy3"])
@pytest.mark.parametrize("method", METHODS)
def test_all_zero_and_saturated(cfa, method):
    zero = cm.isp.demosaic(np.zeros((12, 12)), cfa, method)
    assert np.all(zero == 0.0)
    full = cm.isp.demosaic(np.full((12, 12), 4095.0), cfa, method)
    assert np.allclose(full, 4095.0, rtol=0, atol=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_half_saturated_edge_stays_finite(method):
    raw = np.zeros((16, 16))
    raw[:, 8:] = 4095.0
    out = cm.isp.demosaic(raw, "rgbw2", method)
    assert np.all(np.isfinite(out))
    # gradient-corrected methods may overshoot, but by a bounded fraction
    assert out.min() > -0.5 * 4095 and out.max() < 1.5 * 4095


@pytest.mark.parametrize("method", METHODS)
def test_scale_invariant(method):
    raw = np.random.default_rng(5).random((16, 20))
    a = cm.isp.demosaic(raw, "rgbw3", method)
    b = cm.isp.demosaic(1000.0 * raw, "rgbw3", method)
    assert np.allclose(1000.0 * a, b, rtol=1e-9, atol=1e-9)


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
