"""The end of every demosaic in one compiled pass (cfa_mitsuba/isp/_finish_kernel.py)
against the numpy steps it replaces: the float64 image bit for bit (the
estimates widened, each pixel's observed channel the mosaic's sample) and
the same verdict on non-finite estimates, a NaN at an observed site (which
the sample replaces) included."""

import numpy as np
import pytest

from cfa_mitsuba.isp._finish_kernel import finish
from cfa_mitsuba.isp.mosaic import geometry
from cfa_mitsuba.sensor import get_cfa


def _numpy(est, raw, index):
    out = np.array(est, dtype=np.float64)
    th, tw = index.shape
    for (i, j), c in np.ndenumerate(index):
        out[i::th, j::tw, c] = raw[i::th, j::tw]
    return out, bool(np.all(np.isfinite(out)))


@pytest.mark.parametrize("name", ["bayer", "rgbw1", "cmy2", "rgb4", "rgbw3"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("shape", [(64, 90), (7, 5), (33, 50)])
def test_finish_equals_the_numpy_steps(name, dtype, shape):
    index = geometry(get_cfa(name)).index
    n = int(index.max()) + 1
    rng = np.random.default_rng(shape[0] + n)
    raw = rng.random(shape)
    est = (rng.normal(size=(*shape, n)) * 1e3).astype(dtype)
    got, ok = finish(est, raw, index)
    want, want_ok = _numpy(est, raw, index)
    assert got.dtype == np.float64 and ok and want_ok
    np.testing.assert_array_equal(got, want)
    # non-finite estimates: at a kept site refused, at an observed site replaced by the sample
    th, tw = index.shape
    kept = next((i, j, c) for i in range(th) for j in range(tw) for c in range(n) if index[i, j] != c)
    seen = (0, 0, int(index[0, 0]))
    for site, value, want_finite in ((kept, np.nan, False), (kept, np.inf, False), (kept, -np.inf, False),
                                     (seen, np.nan, True), (seen, np.inf, True)):
        bad = est.copy()
        bad[site] = value
        got, ok = finish(bad, raw, index)
        want, want_ok = _numpy(bad, raw, index)
        assert ok == want_ok == want_finite
        np.testing.assert_array_equal(got, want)


def test_other_estimates_are_left_to_numpy_and_demosaic_refuses_non_finite_ones():
    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.isp import demosaic
    from cfa_mitsuba.isp.demosaic import register_demosaic, unregister_demosaic

    index = geometry(get_cfa("bayer")).index
    assert finish(np.zeros((4, 4, 3), dtype=np.float16), np.zeros((4, 4)), index) is None
    assert finish(np.zeros((4, 12)), np.zeros((4, 4)), index) is None
    planes = np.moveaxis(np.zeros((3, 4, 4), dtype=np.float32), 0, -1)  # POCS's (H, W, C) view of its planes
    assert not planes.flags.c_contiguous and finish(planes, np.zeros((4, 4)), index) is None
    raw = np.random.default_rng(1).random((8, 8))
    out = demosaic(raw, "bayer", "bilinear", precision="single")
    assert out.dtype == np.float64 and np.isfinite(out).all()
    for (i, j), c in np.ndenumerate(index):  # the observed samples are the float64 mosaic's own
        np.testing.assert_array_equal(out[i::2, j::2, c], raw[i::2, j::2])

    def holes(mosaic, cfa, at):
        est = np.repeat(mosaic[..., None], 3, axis=-1).astype(np.float16)  # numpy's path
        est[at] = np.nan
        return est

    seen = int(index[0, 0])
    register_demosaic("test-holes", holes, description="NaN at one site")
    try:
        with pytest.raises(CfaMitsubaError, match="'test-holes' produced NaN or infinite values"):
            demosaic(raw, "bayer", "test-holes", at=(0, 0, (seen + 1) % 3))  # a kept site
        ok = demosaic(raw, "bayer", "test-holes", at=(0, 0, seen))  # the observed site: the sample replaces it
        assert ok[0, 0, seen] == raw[0, 0]
    finally:
        unregister_demosaic("test-holes")
