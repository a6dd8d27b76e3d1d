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
