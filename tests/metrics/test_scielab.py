"""S-CIELAB's single-precision filtering (``fft_precision = 'single'``, a
study's default): the test image is filtered as the reference's planes plus
the filtered difference, so it moves the dE map by less than 1e-5 dE00 on
a camera-like pair, and a study passes it unless its config says otherwise."""

import numpy as np
import pytest
from scipy import ndimage

from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.metrics.scielab import FilteredReference, scielab, scielab_reference, scielab_reference_lab

WHITE = np.array([95.05, 100.0, 108.9])


def _pair(h=120, w=150, seed=0):
    rng = np.random.default_rng(seed)
    ramp = np.linspace(2, 90, w)[None, :, None] * np.array([0.95, 1.0, 1.05])
    ref = ndimage.gaussian_filter(ramp * (0.6 + 0.8 * rng.random((h, w, 3))), (2, 2, 0))
    test = ref * (1 + rng.normal(0, 0.05, ref.shape))  # a noisy camera output
    return ref, test


@pytest.mark.parametrize("boundary", ["symmetric", "isetcam"])
@pytest.mark.parametrize("lab_constants", ["cie", "isetcam"])
def test_single_precision_map_within_1e_5_of_double(boundary, lab_constants):
    ref, test = _pair()
    kw = dict(samples_per_degree=24, boundary=boundary, lab_constants=lab_constants)
    d = scielab(ref, test, WHITE, **kw)
    s = scielab(ref, test, WHITE, fft_precision="single", **kw)
    assert float(d) > 0.5
    assert np.abs(s.details["map"] - d.details["map"]).max() < 1e-5
    assert abs(float(s) - float(d)) < 1e-6 * float(d)
    assert s.details["fft_precision"] == "single"
    # a reference compared with itself stays exactly 0 (the difference is 0)
    assert float(scielab(ref, ref, WHITE, fft_precision="single", **kw)) == 0.0


def test_cached_reference_gives_the_same_result():
    ref, test = _pair(seed=2)
    kw = dict(samples_per_degree=24)
    fr = scielab_reference(ref, WHITE, **kw)
    assert isinstance(fr, FilteredReference) and fr.planes.shape == (3, *ref.shape[:2])
    np.testing.assert_array_equal(fr.lab, scielab_reference_lab(ref, WHITE, **kw))
    for precision in ("double", "single"):
        plain = scielab(ref, test, WHITE, fft_precision=precision, **kw)
        for given in (fr, fr.lab):
            cached = scielab(ref, test, WHITE, fft_precision=precision, reference_lab=given, **kw)
            np.testing.assert_array_equal(cached.details["map"], plain.details["map"])


def test_unknown_precision_is_refused():
    ref, test = _pair(20, 30)
    with pytest.raises(CfaMitsubaError, match="fft_precision"):
        scielab(ref, test, WHITE, samples_per_degree=8, fft_precision="half")


def test_a_study_uses_single_unless_its_config_says_double():
    from cfa_mitsuba.study.chain import ChainSettings

    assert ChainSettings().options_of_metrics()["scielab"] == {"fft_precision": "single"}
    mine = ChainSettings(metric_options={"scielab": {"fft_precision": "double", "matrix": "xyz10"}})
    assert mine.options_of_metrics()["scielab"] == {"fft_precision": "double", "matrix": "xyz10"}


@pytest.mark.parametrize("shape, half, fshape", [((120, 150), 12, (150, 180)), ((7, 5), 9, (27, 25)),
                                                 ((7, 5), 40, (90, 96)), ((30, 41), 0, (32, 45))])
def test_single_precision_input_is_numpys_opponent_difference_padded(shape, half, fshape):
    """The compiled input of the single-precision filtering (the opponent
    transform of test - reference, cast to float32, extended
    symmetrically, zero beyond) against numpy's steps: within one float32
    rounding (the kernel sums each matrix row left to right), and exactly
    zero in the transform's padding, also where the extension is longer
    than the image."""
    from cfa_mitsuba.metrics._scielab_kernel import opponent_difference_padded
    from cfa_mitsuba.metrics.scielab import OPPONENT_MATRICES

    rng = np.random.default_rng(half)
    ref = 100 * rng.random((*shape, 3))
    test = 100 * rng.random((*shape, 3))
    m = OPPONENT_MATRICES["xyz2"]
    planes = np.moveaxis((test - ref) @ m.T, -1, 0).astype(np.float32)
    want = np.zeros((3, *fshape), dtype=np.float32)
    eh, ew = shape[0] + 2 * half, shape[1] + 2 * half
    want[:, :eh, :ew] = np.pad(planes, ((0, 0), (half, half), (half, half)), mode="symmetric")
    got = opponent_difference_padded(test, ref, m, half, fshape)
    assert got.dtype == np.float32 and got.shape == (3, *fshape)
    assert np.all(got[:, eh:] == 0) and np.all(got[:, :, ew:] == 0)
    assert np.allclose(got, want, rtol=2 * np.finfo(np.float32).eps, atol=1e-5)
