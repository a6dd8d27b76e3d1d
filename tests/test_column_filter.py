"""The compiled column correlation (isp/column_filter.py) against
scipy.ndimage.correlate1d(axis=0, mode='mirror'), the library call it
stands in for in POCS."""

import numpy as np
import pytest
from scipy import ndimage

from cfa_mitsuba.isp.column_filter import correlate_columns
from cfa_mitsuba.isp.pocs import lowpass_kernel


@pytest.mark.parametrize("shape", [(1, 5), (2, 7), (3, 4), (9, 1), (40, 33), (257, 130)])
@pytest.mark.parametrize("levels", [1, 2, 3])
def test_equals_ndimage_mirror(shape, levels):
    rng = np.random.default_rng(sum(shape) + levels)
    x = rng.normal(0.0, 50.0, shape)
    k = lowpass_kernel(levels)
    expected = ndimage.correlate1d(x, k, axis=0, mode="mirror")
    np.testing.assert_allclose(correlate_columns(x, k), expected, rtol=0, atol=1e-15 * 50.0 * np.abs(k).sum() * 4)


def test_asymmetric_kernel_strided_input_and_out():
    rng = np.random.default_rng(2)
    big = rng.random((60, 80))
    x = big[5:50, ::2]  # a strided view
    k = np.array([0.1, -0.4, 0.7, 0.2, 0.05])
    out = np.full(x.shape, np.nan)
    got = correlate_columns(x, k, out)
    assert got is out
    np.testing.assert_allclose(out, ndimage.correlate1d(x, k, axis=0, mode="mirror"), rtol=0, atol=1e-15)


def test_refuses_even_kernels_and_aliasing():
    x = np.zeros((4, 4))
    with pytest.raises(ValueError, match="odd 1-D kernel"):
        correlate_columns(x, np.ones(4))
    with pytest.raises(ValueError, match="share memory"):
        correlate_columns(x, np.ones(3), out=x)
