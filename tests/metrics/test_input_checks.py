"""The metrics' input check (metrics._common.check_values) runs once for an
array nothing can write to: a read-only array that owns its memory (a
study's ideal image and its sRGB codes, compared with every camera output
of a task).  Every other array is checked at every call, so a NaN that
appears in it later is still refused (issue 25)."""

from __future__ import annotations

import gc

import numpy as np
import pytest

from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.metrics import _common


def _read_only(a):
    a.flags.writeable = False
    return a


def test_a_read_only_owner_is_checked_once_and_forgotten_when_it_dies():
    ro = _read_only(np.full((8, 9, 3), 20.0))
    assert _common.check_values(ro, "reference image") is ro
    assert _common._PASSED[id(ro)]() is ro
    assert _common.check_values(ro, "reference image") is ro
    key = id(ro)
    del ro
    gc.collect()
    assert key not in _common._PASSED


def test_an_array_something_can_write_to_is_checked_every_time():
    rw = np.full((8, 9, 3), 20.0)
    _common.check_values(rw, "test image")
    assert id(rw) not in _common._PASSED
    rw[2, 3, 1] = np.nan
    with pytest.raises(CfaMitsubaError, match="test image"):
        _common.check_values(rw, "test image")
    # a read-only view of a writeable array: its owner can still change it
    base = np.full((8, 9, 3), 20.0)
    view = _read_only(base[:, :])
    _common.check_values(view, "reference image")
    assert id(view) not in _common._PASSED
    base[0, 0, 0] = np.inf
    with pytest.raises(CfaMitsubaError, match="reference image"):
        _common.check_values(view, "reference image")


def test_a_failing_read_only_array_is_never_remembered():
    bad = _read_only(np.array([[[1.0, np.nan, 2.0]]]))
    for _ in range(2):
        with pytest.raises(CfaMitsubaError, match="NaN"):
            _common.check_values(bad, "test image")
    assert id(bad) not in _common._PASSED


def test_the_study_chain_hands_the_metrics_a_read_only_ideal():
    """The ideal image a chain keeps for its task's camera outputs, and the
    sRGB codes kept with it, are read-only owners (so checked once)."""
    from cfa_mitsuba import spectra
    from cfa_mitsuba.study.chain import CameraChain
    from cfa_mitsuba.study.conditions import Condition
    from cfa_mitsuba.values import SpectralImage

    wl = spectra.DEFAULT_WAVELENGTHS
    d65 = spectra.illuminant("D65", wl)
    white = d65 * (100.0 / spectra.luminance_cd_m2(d65, wl))
    scene = np.broadcast_to(0.3 * white, (24, 24, wl.size)).copy()
    image = SpectralImage(scene, wl.copy(), {"scene": "grey", "fov_deg": 2.0, "white_radiance": white.tolist()})
    chain = CameraChain()
    outs = list(chain.evaluate(image, "bayer", ["bilinear"], ["ssim"], Condition(20.0), seed=1, scene_key="grey"))
    _, ideal, _, ev = outs[0]
    assert _common._unchangeable(ideal.xyz) and id(ideal.xyz) in _common._PASSED
    codes = ideal.__dict__["_metric_shared"]["srgb8_reference"]
    assert _common._unchangeable(codes)
    assert np.isfinite(float(ev.results["ssim"]))
    with pytest.raises(ValueError):
        ideal.xyz[0, 0, 0] = 1.0


def test_the_camera_side_arrays_a_study_makes_are_read_only_owners(monkeypatch):
    """The chain's mean-matched camera image and the sRGB codes / linear RGB
    that MetricInputs derives from a test image are new arrays that only
    the metrics read: read-only owners, so every metric after the first
    skips their check.  A caller's own test array is left writeable."""
    from cfa_mitsuba import metrics as m
    from cfa_mitsuba import spectra
    from cfa_mitsuba.study.chain import CameraChain
    from cfa_mitsuba.study.conditions import Condition
    from cfa_mitsuba.values import SpectralImage

    seen = []
    real = m.evaluate_many

    def spy(names, inputs, *args, **kwargs):
        seen.append(inputs)
        return real(names, inputs, *args, **kwargs)

    monkeypatch.setattr(m, "evaluate_many", spy)
    wl = spectra.DEFAULT_WAVELENGTHS
    d65 = spectra.illuminant("D65", wl)
    white = d65 * (100.0 / spectra.luminance_cd_m2(d65, wl))
    scene = np.broadcast_to(0.3 * white, (24, 24, wl.size)).copy()
    image = SpectralImage(scene, wl.copy(), {"scene": "grey", "fov_deg": 2.0, "white_radiance": white.tolist()})
    outs = list(CameraChain().evaluate(image, "bayer", ["bilinear"], ["ssim"], Condition(20.0), seed=1,
                                       scene_key="grey-camera-side"))
    assert np.isfinite(float(outs[0][3].results["ssim"]))
    (inp,) = seen
    assert _common._unchangeable(inp.test_xyz)
    assert _common._unchangeable(inp.srgb8("test")) and id(inp.srgb8("test")) in _common._PASSED
    assert outs[0][3].processed.xyz.flags.writeable  # the processed output itself is untouched

    mine = np.full((8, 9, 3), 20.0)
    own = m.MetricInputs(mine, mine.copy(), [95.047, 100.0, 108.883])
    assert _common._unchangeable(own.linear("test")) and _common._unchangeable(own.srgb8("test"))
    assert own.test_xyz.flags.writeable and own.reference_xyz.flags.writeable


@pytest.mark.parametrize("layout", ["contiguous", "strided", "float32"])
def test_the_one_pass_bounds_test_answers_as_min_and_max(layout):
    """metrics._bounds_kernel.within against numpy's two reductions, on
    arrays with NaN, +-inf, values just inside and just beyond the limit,
    and (for strided and float32 arrays) numpy's own path."""
    from cfa_mitsuba.metrics._bounds_kernel import within

    limit = _common.MAX_ABS_INPUT
    rng = np.random.default_rng(4)
    edge = [limit, -limit, np.nextafter(limit, np.inf), np.nextafter(-limit, -np.inf), np.nan, np.inf, -np.inf]
    for k in range(60):
        a = rng.normal(0.0, 10.0, (13, 17, 3))
        if k % 2:
            a.flat[rng.integers(a.size)] = edge[k % len(edge)]
        if layout == "strided":
            a = a[:, ::2]
        elif layout == "float32":
            a = a.astype(np.float32)
        assert within(a, limit) == bool(-limit <= float(a.min()) and float(a.max()) <= limit), (k, layout)
