"""The compiled column and row correlations (isp/column_filter.py) against
scipy.ndimage.correlate1d(axis=0 and 1), the library calls they stand in
for in POCS and SSIM: bit for bit."""

import numpy as np
import pytest
from scipy import ndimage

from cfa_mitsuba.isp.column_filter import correlate_along_rows, correlate_columns
from cfa_mitsuba.isp.pocs import lowpass_kernel

GAUSS = np.exp(-0.5 / 2.25 * np.arange(-5, 6) ** 2)
GAUSS = GAUSS / GAUSS.sum()  # SSIM's window, as gaussian_filter1d makes it
PASSES = {0: correlate_columns, 1: correlate_along_rows}  # ndimage's axis -> the compiled pass


@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("shape", [(1, 5), (2, 7), (3, 4), (9, 1), (5, 2), (40, 33), (257, 130)])
@pytest.mark.parametrize("kernel", ["pocs1", "pocs2", "pocs3", "gauss"])
@pytest.mark.parametrize("mode", ["mirror", "reflect"])
def test_equals_ndimage_bit_for_bit(axis, shape, kernel, mode):
    # shapes shorter than the kernel's reach fold the extension more than once
    rng = np.random.default_rng(sum(shape))
    x = rng.normal(0.0, 50.0, shape)
    k = GAUSS if kernel == "gauss" else lowpass_kernel(int(kernel[-1]))
    np.testing.assert_array_equal(PASSES[axis](x, k, mode=mode), ndimage.correlate1d(x, k, axis=axis, mode=mode))


@pytest.mark.parametrize("axis", [0, 1])
def test_strided_input_and_given_out(axis):
    rng = np.random.default_rng(2)
    x = rng.random((60, 80))[5:50, ::2]  # a strided view
    out = np.full(x.shape, np.nan)
    got = PASSES[axis](x, GAUSS, out, mode="reflect")
    assert got is out
    np.testing.assert_array_equal(out, ndimage.correlate1d(x, GAUSS, axis=axis, mode="reflect"))


@pytest.mark.parametrize("axis", [0, 1])
def test_refuses_what_it_does_not_reproduce(axis):
    x = np.zeros((4, 4))
    for bad in (np.ones(4), np.array([0.1, 0.5, 0.4])):
        with pytest.raises(ValueError, match="symmetric 1-D kernel of odd length"):
            PASSES[axis](x, bad)
    with pytest.raises(ValueError, match="mode must be"):
        PASSES[axis](x, np.ones(3), mode="wrap")
    with pytest.raises(ValueError, match="share memory"):
        PASSES[axis](x, np.ones(3), out=x)
