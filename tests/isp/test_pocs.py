"""POCS's compiled end of a projection round (cfa_mitsuba/isp/_pocs_kernel.py)
against the numpy operations it replaces: the channel bit for bit, the sum
of squared changes to rounding."""

import numpy as np
import pytest

from cfa_mitsuba.isp._pocs_kernel import project


@pytest.mark.parametrize("tile", [(2, 2), (4, 4), (3, 6)])
def test_project_equals_the_numpy_round(tile):
    rng = np.random.default_rng(sum(tile))
    h, w = 37, 53
    x, ref, detail, raw = (rng.normal(size=(h, w)) for _ in range(4))
    observed = rng.random(tile) < 0.4
    observed[0, 0] = True
    new = ref + detail  # the numpy form: the sum everywhere, then each observed phase's samples
    for i, j in np.argwhere(observed):
        new[i::tile[0], j::tile[1]] = raw[i::tile[0], j::tile[1]]
    want_change = float(np.sum((new - x) ** 2))
    got = x.copy()
    change = project(got, ref, detail, raw, observed)
    np.testing.assert_array_equal(got, new)
    assert change == pytest.approx(want_change, rel=1e-12)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("taps,tile,shape", [(7, (2, 2), (37, 53)), (19, (4, 4), (41, 29)), (7, (3, 6), (5, 8)),
                                            (19, (2, 2), (20, 9)), (19, (2, 2), (3, 12)), (7, (2, 2), (2, 5)),
                                            (7, (4, 4), (8, 8))])
def test_lowpass_project_equals_the_two_passes_and_project(dtype, taps, tile, shape):
    """The fused round (the difference from the reference, the low-pass down
    the columns and along the rows, then the projection, row by row, the
    difference's rows in a ring) against the passes it replaces: the
    channel bit for bit, the sum of squared changes to rounding (each row's
    in eight partial sums), also for images shorter than the kernel, whose
    mirror images wrap more than once."""
    from cfa_mitsuba.isp._pocs_kernel import lowpass_project
    from cfa_mitsuba.isp.column_filter import correlate_along_rows, correlate_columns
    from cfa_mitsuba.isp.pocs import lowpass_kernel

    rng = np.random.default_rng(taps + shape[0])
    x, ref, raw = (rng.normal(size=shape).astype(dtype) for _ in range(3))
    k = lowpass_kernel(1 if taps == 7 else 2).astype(dtype)
    assert k.size == taps
    observed = rng.random(tile) < 0.4
    observed[0, 0] = True
    d = np.empty(shape, dtype)
    np.subtract(x, ref, out=d)  # as pocs made it before
    lowpassed = correlate_along_rows(correlate_columns(d, k), k)
    want_x = x.copy()
    want_change = project(want_x, ref, lowpassed, raw, observed)
    got_x = x.copy()
    got_change = lowpass_project(got_x, ref, raw, observed, k)
    np.testing.assert_array_equal(got_x, want_x)
    assert got_change == pytest.approx(want_change, rel=1e-13)  # the rows' sums in eight partial sums
