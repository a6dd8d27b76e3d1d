"""Every method on every CFA (both from the registries): shape, finiteness,
phase-true borders, constants, precision and, for a method whose record
declares an accuracy bar, smooth and achromatic images and a ramp
(tests/registry_checks.py); and gains over bilinear on an edge-rich
photograph for the paper's cross-channel methods."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
import registry_checks as checks
from cfa_mitsuba.isp.mosaic import _mirror_index, geometry
from conftest import REPO

CFAS = cm.sensor.list_cfas()
#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in cm.isp.list_demosaics())


def _paper_methods() -> tuple:
    """The paper's four methods (configs/paper.toml), which the cross-channel comparison is about."""
    from cfa_mitsuba.study.config import load_config

    return tuple(load_config(REPO / "configs" / "paper.toml").demosaics)


def test_registry_lists_the_paper_methods_first_each_with_a_record():
    names = [n for n, _ in cm.isp.list_demosaics()]
    assert tuple(names[:4]) == _paper_methods()
    assert all(desc for _, desc in cm.isp.list_demosaics())
    for n in names:
        r = cm.isp.get_demosaic_record(n)
        assert r.name == n and isinstance(r.linear, bool)
    # linear in the mosaic, as the design proxy assumes: the Laplacian is, the adaptive methods are not
    assert cm.isp.get_demosaic_record("bilinear").linear and cm.isp.get_demosaic_record("laplacian").linear
    assert not cm.isp.get_demosaic_record("pocs").linear


@pytest.mark.parametrize("cfa", CFAS)
@pytest.mark.parametrize("method", METHODS)
def test_shape_finite_and_samples_kept(cfa, method):
    checks.check_demosaic_samples(method, cfa)


@pytest.mark.parametrize("cfa", CFAS)
@pytest.mark.parametrize("method", METHODS)
def test_per_channel_constants_zeros_and_saturation(cfa, method):
    checks.check_demosaic_constants(method, cfa)


@pytest.mark.parametrize("cfa", CFAS)
@pytest.mark.parametrize("method", METHODS)
def test_scale_invariant(cfa, method):
    checks.check_demosaic_scale(method, cfa)


@pytest.mark.parametrize("cfa", CFAS)
@pytest.mark.parametrize("method", METHODS)
def test_single_precision_is_double_to_float32_rounding(cfa, method):
    checks.check_demosaic_precision(method, cfa)


@pytest.mark.parametrize("cfa", CFAS)
@pytest.mark.parametrize("method", METHODS)
def test_accuracy_bar_on_smooth_images(cfa, method):
    """White-balanced achromatic content: every channel equals the scene
    within the method's accuracy bar (its record's), inside and at the
    borders.  The block layouts' clustered samples make every method's error
    first order in the slope (measured: quad-bayer 0.003-0.008, nona
    0.015-0.034, tetra2 0.016-0.043 on a modulation of 0.2), so the bound
    grows with the block size; so do the published layouts whose samples
    sit unevenly around a pixel (sparse colour, same-colour quadrants, runs
    along diagonals; worst over the four methods, inner max / inner mean /
    whole max: hamilton-rgbw bilinear 0.017 / 0.0032 / 0.079,
    chakrabarti-learned bilinear 0.015 / 0.0021 / 0.064, omnivision-rgbc
    0.013 / 0.0022 / 0.052, chakrabarti-sparse laplacian 0.013 / 0.0024 /
    0.040, wang-rgbw laplacian 0.0088 / 0.0010 / 0.037, kaizu-rgbw bilinear
    0.0044 / 0.0009 / 0.054), held to a wider bound that a first-order
    error meets and a broken method (errors of 0.1-0.5) does not."""
    checks.check_demosaic_accuracy(method, cfa)


def test_the_uneven_layouts_are_told_apart_by_the_ramp():
    """The block layouts sample unevenly (bilinear misses a ramp there), the
    paper's lattice layouts do not."""
    from cfa_mitsuba.sensor.readout import block_size

    for name in CFAS:
        if block_size(cm.sensor.get_cfa(name).pattern) > 1:
            assert checks.uneven_layout(name), name
    assert not any(checks.uneven_layout(c) for c in ("bayer", "rgb1", "cmy1", "rgbw1", "rgbw3"))


@pytest.mark.parametrize("method", METHODS)
def test_linear_ramp_exact_in_interior_bayer(method):
    checks.check_demosaic_ramp(method)


@pytest.mark.parametrize("method", METHODS)
def test_smaller_than_the_tile_is_refused_one_tile_is_fine(method):
    checks.check_demosaic_too_small(method)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("method", METHODS)
def test_nan_or_inf_refused(value, method):
    checks.check_demosaic_non_finite(method, value)


def test_a_linear_method_is_linear():
    """The records' linear flag is true of the method: the output of a sum
    is the sum of the outputs."""
    rng = np.random.default_rng(2)
    a, b = rng.random((20, 24)), rng.random((20, 24))
    for n in METHODS:
        if cm.isp.get_demosaic_record(n).linear:
            for cfa in ("bayer", "rgbw1"):
                lhs = cm.isp.demosaic(a + 2.0 * b, cfa, n)
                assert np.allclose(lhs, cm.isp.demosaic(a, cfa, n) + 2.0 * cm.isp.demosaic(b, cfa, n), atol=1e-12)


@pytest.fixture(scope="module")
def edge_rich():
    import skimage.data

    return skimage.data.astronaut()[0:128, 120:248] / 255.0


@pytest.mark.parametrize("cfa", ["cmy1", "cmy2", "cmy3", "rgbw1", "rgbw2", "rgbw3"])
def test_cross_channel_methods_beat_bilinear_on_cmy_and_rgbw(edge_rich, cfa):
    from skimage.metrics import peak_signal_noise_ratio

    truth = cm.isp.channels_from_rgb(edge_rich, cfa)
    raw = cm.isp.mosaic_image(truth, cfa)
    b = 6
    paper = _paper_methods()
    p = {m: peak_signal_noise_ratio(truth[b:-b, b:-b], cm.isp.demosaic(raw, cfa, m)[b:-b, b:-b], data_range=1.0)
         for m in paper}
    for m in paper[1:]:
        assert p[m] > p["bilinear"] + 1.0, p


def test_mirror_index_preserves_phase_and_is_scipy_mirror_for_period_2():
    for n in (2, 3, 5, 8, 9):
        for period in range(1, min(n, 4) + 1):
            idx = _mirror_index(n, period, 7)
            pos = np.arange(-7, n + 7)
            assert np.all((idx - pos) % period == 0)
            assert np.all((idx >= 0) & (idx < n))
            assert np.array_equal(idx[7:7 + n], np.arange(n))
    # period 2: d c b | a b c d | c b a
    assert _mirror_index(4, 2, 2).tolist() == [2, 1, 0, 1, 2, 3, 2, 1]


def test_reference_choice():
    from cfa_mitsuba.isp.laplacian import reference_for

    for name, expected in {"bayer": "G", "rgb1": "G", "cmy1": "Y", "rgbw2": "W", "rgbw3": "W"}.items():
        c = cm.sensor.get_cfa(name)
        ref = reference_for(c, geometry(c))
        assert c.channels[ref.channel] == expected
    for name in ("rgb3", "rgb4", "cmy2", "cmy3", "rgbw1"):
        c = cm.sensor.get_cfa(name)
        ref = reference_for(c, geometry(c))
        assert ref.channel is None
        w = np.array(ref.weights)
        assert np.all(w >= 0) and abs(w.sum() - 1) < 1e-12


def test_user_method_is_one_registry_entry():
    def copy_nearest(raw, cfa, *, shift=0):
        return np.repeat(raw[..., None] + shift, len(cfa.channels), axis=-1)

    from cfa_mitsuba.isp.demosaic import unregister_demosaic

    cm.isp.register_demosaic("test-copy", copy_nearest, description="test", replace=True)
    try:
        out = cm.isp.demosaic(np.ones((4, 4)), "bayer", "test-copy", shift=1.0)
        # observed samples are put back whatever the method returns there
        assert out.shape == (4, 4, 3) and out[0, 1, 0] == 1.0 and out[0, 0, 0] == 2.0
        assert ("test-copy", "test") in cm.isp.list_demosaics()
        record = cm.isp.get_demosaic_record("test-copy")
        assert record.linear is False and record.accuracy is None  # a user's method promises nothing unless it says
        with pytest.raises(cm.CfaMitsubaError, match="already registered"):
            cm.isp.register_demosaic("test-copy", copy_nearest)
    finally:
        unregister_demosaic("test-copy")
