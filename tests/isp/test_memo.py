"""The one-entry memo that lets 'pocs' reuse the bilinear image and the
edge-directed reference made just before on the same mosaic
(cfa_mitsuba/isp/_memo.py): the same bits as computing afresh, never a
stale entry."""

import numpy as np
import pytest

from cfa_mitsuba.isp import demosaic, list_demosaics
from cfa_mitsuba.isp import bilinear as bilinear_module
from cfa_mitsuba.isp import laplacian_reference as reference_module
from cfa_mitsuba.isp._memo import LastImage, clear_all


def _clear():
    clear_all()


def test_last_image_returns_the_kept_result_only_for_an_equal_key_and_mosaic():
    calls = []
    memo = LastImage()

    def maker(a):
        def make():
            calls.append(1)
            return a * 2
        return make

    raw = np.arange(12.0).reshape(3, 4)
    first = memo.get("k", raw, maker(raw))
    assert not first.flags.writeable
    again = memo.get("k", raw.copy(), maker(raw))  # equal values, another array
    assert again is first and len(calls) == 1
    memo.get("other", raw, maker(raw))
    assert len(calls) == 2
    changed = raw.copy()
    changed[1, 2] += 1e-12
    np.testing.assert_array_equal(memo.get("other", changed, maker(changed)), changed * 2)
    assert len(calls) == 3
    nan = changed.copy()
    nan[0, 0] = np.nan
    memo.get("other", nan, maker(nan))
    memo.get("other", nan, maker(nan))  # NaN never equals: computed each time
    assert len(calls) == 5
    memo.get("other", raw.astype(np.float32), maker(raw))  # another dtype
    assert len(calls) == 6


def test_a_failing_make_leaves_no_entry():
    memo = LastImage()
    raw = np.ones((2, 2))
    memo.get("k", raw, lambda: raw)

    def boom():
        raise RuntimeError("no")

    with pytest.raises(RuntimeError):
        memo.get("j", raw, boom)
    calls = []
    memo.get("k", raw, lambda: calls.append(1) or raw)
    assert calls == [1]


def test_the_mosaic_kept_is_a_copy():
    memo = LastImage()
    raw = np.ones((2, 2))
    memo.get("k", raw, lambda: raw + 1)
    raw[0, 0] = 5.0  # the caller changes its array afterwards
    calls = []
    np.testing.assert_array_equal(memo.get("k", raw, lambda: calls.append(1) or raw + 1), raw + 1)
    assert calls == [1]


@pytest.mark.parametrize("cfa", ["bayer", "rgbw1", "rgb3", "cmy2"])
def test_pocs_after_the_other_methods_equals_pocs_alone(cfa):
    """The study's order (bilinear, laplacian, adaptive-laplacian, pocs on
    one mosaic) against each method on an empty memo: the same bits; a
    caller changing a returned image does not reach the memo."""
    rng = np.random.default_rng(4)
    raw = rng.uniform(0.05, 1.0, (48, 60))
    methods = [n for n, _ in list_demosaics()]  # the registry's order is the study's
    alone = {}
    for m in methods:
        _clear()
        alone[m] = demosaic(raw, cfa, m)
    _clear()
    for m in methods:
        out = demosaic(raw.copy(), cfa, m)
        np.testing.assert_array_equal(out, alone[m])
        out[...] = -1.0  # the caller's own array
    np.testing.assert_array_equal(demosaic(raw, cfa, "pocs"), alone["pocs"])
    np.testing.assert_array_equal(demosaic(raw, cfa, "pocs", update_reference=True),
                                  (_clear(), demosaic(raw, cfa, "pocs", update_reference=True))[1])
    other = raw * 1.5
    _clear()
    expect = demosaic(other, cfa, "pocs")
    demosaic(raw, cfa, "adaptive-laplacian")
    np.testing.assert_array_equal(demosaic(other, cfa, "pocs"), expect)


def test_clear_all_empties_every_memo():
    raw = np.random.default_rng(1).uniform(0.1, 1.0, (24, 24))
    demosaic(raw, "bayer", "adaptive-laplacian")
    demosaic(raw, "bayer", "bilinear")
    assert bilinear_module._LAST._entry is not None and reference_module._LAST_REFERENCE._entry is not None
    clear_all()
    assert bilinear_module._LAST._entry is None and reference_module._LAST_REFERENCE._entry is None


def test_a_result_too_big_to_hold_twice_is_not_kept(monkeypatch):
    from cfa_mitsuba.isp import _memo

    monkeypatch.setattr(_memo, "MAX_BYTES", 1000)
    memo = LastImage()
    calls = []
    small, big = np.ones((5, 5)), np.ones((20, 20))  # 200 + 200 bytes; 3200 + 3200 bytes
    memo.get("k", small, lambda: calls.append(1) or small * 2)
    memo.get("k", small, lambda: calls.append(1) or small * 2)
    assert len(calls) == 1
    out = memo.get("k", big, lambda: calls.append(1) or big * 2)
    np.testing.assert_array_equal(out, big * 2)
    memo.get("k", big, lambda: calls.append(1) or big * 2)
    assert len(calls) == 3 and memo._entry is None


def test_a_result_that_is_the_callers_mosaic_is_copied_before_it_is_kept():
    memo = LastImage()
    raw = np.ones((3, 3))
    kept = memo.get("k", raw, lambda: raw)
    assert raw.flags.writeable and not kept.flags.writeable and kept is not raw
    fresh = np.zeros((3, 3))
    assert memo.get("j", raw, lambda: fresh) is fresh  # a new array is kept as made, no copy
