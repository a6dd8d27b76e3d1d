"""Every method on every CFA: shape, finiteness, phase-true borders, smooth
and achromatic images, and gains over bilinear on an edge-rich photograph."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.isp.mosaic import _mirror_index, geometry

CFAS = cm.sensor.list_cfas()
#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in cm.isp.list_demosaics())
#: The paper's four, which the cross-channel comparison below is about.
PAPER_METHODS = ("bilinear", "laplacian", "adaptive-laplacian", "pocs")


def test_registry_lists_the_four_methods():
    names = [n for n, _ in cm.isp.list_demosaics()]
    assert names[:4] == list(PAPER_METHODS)
    assert all(desc for _, desc in cm.isp.list_demosaics())


@pytest.mark.parametrize("cfa", CFAS)
@pytest.mark.parametrize("method", METHODS)
def test_shape_finite_and_samples_kept(cfa, method):
    c = cm.sensor.get_cfa(cfa)
    th, tw = c.tile_shape
    # Partial tiles at both borders.
    shape = (4 * th + th // 2 + 1, 5 * tw + 1)
    raw = np.random.default_rng(0).random(shape)
    out = cm.isp.demosaic(raw, c, method)
    assert out.shape == (*shape, len(c.channels))
    assert np.all(np.isfinite(out))
    masks = c.masks(shape)
    for k in range(len(c.channels)):
        assert np.array_equal(out[..., k][masks[k]], raw[masks[k]])


@pytest.mark.parametrize("cfa", CFAS)
@pytest.mark.parametrize("method", METHODS)
def test_per_channel_constants_exact_to_the_border(cfa, method):
    """A scene that is a different constant in each channel: any border
    handling that shifts the CFA phase mixes channels and fails."""
    c = cm.sensor.get_cfa(cfa)
    th, tw = c.tile_shape
    shape = (3 * th + 1, 3 * tw + 2)
    levels = np.linspace(0.2, 0.9, len(c.channels))
    truth = np.broadcast_to(levels, (*shape, len(levels)))
    # bilinear never mixes channels; the cross-channel methods are exact on
    # constant colour differences only with the full colour difference.
    out = cm.isp.demosaic(cm.isp.mosaic_image(truth, c), c, method)
    assert np.abs(out - truth).max() < 1e-12


#: Binned layouts: same-colour blocks of b x b pixels, so a channel's samples
#: cluster and leave gaps of up to 2b - 1 pixels (a 2b x 2b tile).
BLOCKS = {"quad-bayer": 2, "nona": 3, "tetra2": 4}


def _smooth_errors(cfa, method):
    yy, xx = np.mgrid[0:48, 0:52].astype(float)
    scene = 0.5 + 0.2 * np.sin(2 * np.pi * xx / 96) * np.cos(2 * np.pi * yy / 112) + 0.002 * xx
    out = cm.isp.demosaic(scene, cm.sensor.get_cfa(cfa), method)
    err = np.abs(out - scene[..., None])
    return err, err[6:-6, 6:-6]


#: Published layouts whose channels' samples do not form a lattice (sparse
#: colour, same-colour quadrants, runs along diagonals): a normalised
#: convolution's tent around a pixel then weighs its samples unevenly, so a
#: slope leaves a first-order error, as in the block layouts.  Measured
#: worst over the four methods (inner max / inner mean / whole max):
#: hamilton-rgbw bilinear 0.017 / 0.0032 / 0.079, chakrabarti-learned
#: bilinear 0.015 / 0.0021 / 0.064, omnivision-rgbc 0.013 / 0.0022 / 0.052,
#: chakrabarti-sparse laplacian 0.013 / 0.0024 / 0.040, wang-rgbw laplacian
#: 0.0088 / 0.0010 / 0.037, kaizu-rgbw bilinear 0.0044 / 0.0009 / 0.054.
IRREGULAR = ("chakrabarti-learned", "chakrabarti-sparse", "hamilton-rgbw", "kaizu-rgbw", "wang-rgbw",
             "omnivision-rgbc")


@pytest.mark.parametrize("cfa", IRREGULAR)
@pytest.mark.parametrize("method", METHODS)
def test_smooth_achromatic_image_on_irregular_layouts(cfa, method):
    """The same scene on the irregular published layouts, within a bound that
    a first-order error meets and a broken method (errors of 0.1-0.5) does not."""
    err, inner = _smooth_errors(cfa, method)
    assert inner.max() < 0.02, inner.max()
    assert inner.mean() < 4e-3, inner.mean()
    assert err.max() < 0.1, err.max()


@pytest.mark.parametrize("cfa", [c for c in CFAS if c not in BLOCKS and c not in IRREGULAR])
@pytest.mark.parametrize("method", METHODS)
def test_smooth_achromatic_image_reproduced(cfa, method):
    """White-balanced achromatic content: every channel equals the scene
    (0.5 +- 0.2, periods of 96 and 112 px, plus a ramp) to within 2 % of the
    modulation inside, and within one pixel's change at the borders, where
    the mirror meets the ramp."""
    err, inner = _smooth_errors(cfa, method)
    assert inner.max() < 4e-3, inner.max()
    assert inner.mean() < 1.5e-3, inner.mean()
    assert err.max() < 0.05, err.max()


@pytest.mark.parametrize("cfa", list(BLOCKS))
@pytest.mark.parametrize("method", METHODS)
def test_smooth_achromatic_image_on_binned_layouts(cfa, method):
    """The same scene on the block layouts: the clustered samples make every
    method's error first order in the slope (largest inside, measured:
    quad-bayer 0.003-0.008, nona 0.015-0.034, tetra2 0.016-0.043 on a
    modulation of 0.2), so the bound grows with the block size b."""
    b = BLOCKS[cfa]
    err, inner = _smooth_errors(cfa, method)
    assert inner.max() < 0.015 * b, inner.max()
    assert inner.mean() < 2e-3 * b, inner.mean()
    assert err.max() < 0.03 * b, err.max()


@pytest.mark.parametrize("method", METHODS)
def test_linear_ramp_exact_in_interior_bayer(method):
    """A ramp is exact away from the borders (where the mirror folds it);
    pocs spreads the border's fold further inwards with its low-pass."""
    ramp = np.add.outer(0.01 * np.arange(48.0), 0.02 * np.arange(52.0))
    out = cm.isp.demosaic(ramp, "bayer", method)
    m = 16 if method == "pocs" else 3
    assert np.abs(out - ramp[..., None])[m:-m, m:-m].max() < 1e-9


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
    p = {m: peak_signal_noise_ratio(truth[b:-b, b:-b], cm.isp.demosaic(raw, cfa, m)[b:-b, b:-b], data_range=1.0)
         for m in PAPER_METHODS}
    for m in PAPER_METHODS[1:]:
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

    cm.isp.register_demosaic("test-copy", copy_nearest, description="test", replace=True)
    out = cm.isp.demosaic(np.ones((4, 4)), "bayer", "test-copy", shift=1.0)
    # observed samples are put back whatever the method returns there
    assert out.shape == (4, 4, 3) and out[0, 1, 0] == 1.0 and out[0, 0, 0] == 2.0
    assert ("test-copy", "test") in cm.isp.list_demosaics()
    with pytest.raises(cm.CfaMitsubaError, match="already registered"):
        cm.isp.register_demosaic("test-copy", copy_nearest)
