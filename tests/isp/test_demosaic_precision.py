"""Demosaicing in single precision (``precision='single'``, a study's
default, issue 25): the built-in methods keep float32 throughout, the result
is float64 with the mosaic's own samples, and the estimates stay within
float32 rounding of the double-precision ones."""

import numpy as np
import pytest
from scipy import ndimage
from skimage import data

from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.isp import channels_from_rgb, demosaic, get_demosaic, list_demosaics, mosaic_image
from cfa_mitsuba.isp._memo import clear_all
from cfa_mitsuba.isp.column_filter import correlate_along_rows, correlate_columns
from cfa_mitsuba.isp.mosaic import geometry
from cfa_mitsuba.sensor import get_cfa

#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in list_demosaics())


def _photo_mosaic(cfa_name, size=96):
    """A crop of scikit-image's astronaut (edges, texture, flat sky), linear
    light 0..1, mosaicked by the CFA's white-balanced channels."""
    rgb = (data.astronaut()[100:100 + size, 150:150 + size] / 255.0) ** 2.2
    cfa = get_cfa(cfa_name)
    return mosaic_image(channels_from_rgb(rgb, cfa), cfa)


@pytest.mark.parametrize("cfa_name", ["bayer", "rgbw1", "cmy1", "rgb3"])
@pytest.mark.parametrize("method", METHODS)
def test_single_is_double_to_float32_rounding(cfa_name, method):
    raw = _photo_mosaic(cfa_name)
    clear_all()
    double = demosaic(raw, cfa_name, method)
    single = demosaic(raw, cfa_name, method, precision="single")
    assert single.dtype == np.float64 and single.shape == double.shape
    span = float(raw.max() - raw.min())
    err = float(np.abs(single - double).max())
    # a few float32 roundings of the mosaic's range (eps 6e-8); a method
    # computing in double would give 0, one broken by the cast far more
    assert 0 < err <= 10 * np.finfo(np.float32).eps * span, err
    mosaic = geometry(get_cfa(cfa_name))
    th, tw = mosaic.tile_shape
    for (i, j), c in np.ndenumerate(mosaic.index):  # the samples are the mosaic's float64 values, not rounded
        np.testing.assert_array_equal(single[i::th, j::tw, c], raw[i::th, j::tw])


@pytest.mark.parametrize("cfa_name", ["bayer", "rgbw1", "cmy1"])
@pytest.mark.parametrize("method", METHODS)
def test_the_built_in_methods_keep_float32_throughout(cfa_name, method):
    """The speed comes from float32 arrays all the way: a method that widens
    to float64 inside (a float64 weight array, an allocation without dtype)
    would return float64 here."""
    raw = _photo_mosaic(cfa_name, 48).astype(np.float32)
    clear_all()
    out = get_demosaic(method)(raw, get_cfa(cfa_name))
    assert np.asarray(out).dtype == np.float32


def test_pocs_after_the_other_methods_is_pocs_alone_in_single_precision():
    """The memos key on the mosaic's dtype too: 'pocs' after the float32
    'bilinear' and 'adaptive-laplacian' reuses their float32 images, and
    equals 'pocs' on empty memos bit for bit; a float64 call in between
    does not hit the float32 entry."""
    raw = _photo_mosaic("bayer")
    clear_all()
    alone = demosaic(raw, "bayer", "pocs", precision="single")
    clear_all()
    for m in METHODS[:3]:
        demosaic(raw, "bayer", m, precision="single")
    np.testing.assert_array_equal(demosaic(raw, "bayer", "pocs", precision="single"), alone)
    double = demosaic(raw, "bayer", "pocs")
    clear_all()
    np.testing.assert_array_equal(double, demosaic(raw, "bayer", "pocs"))


@pytest.mark.parametrize("bad", ["half", "float32", None, 32])
def test_unknown_precision_is_a_one_line_error(bad):
    with pytest.raises(CfaMitsubaError, match="unknown demosaic precision") as exc:
        demosaic(np.zeros((4, 4)), "bayer", "bilinear", precision=bad)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("fn, axis", [(correlate_columns, 0), (correlate_along_rows, 1)])
@pytest.mark.parametrize("mode", ["mirror", "reflect"])
def test_column_filter_in_float32(fn, axis, mode):
    rng = np.random.default_rng(3)
    x = rng.random((37, 53))
    k = np.array([-1, 2, 6, 2, -1]) / 8.0
    got = fn(x.astype(np.float32), k, mode=mode)
    assert got.dtype == np.float32
    want = ndimage.correlate1d(x, k, axis=axis, mode=mode)
    np.testing.assert_allclose(got, want, rtol=0, atol=8 * np.finfo(np.float32).eps)
    # float64 and integer input are still filtered in float64, ndimage's bits
    np.testing.assert_array_equal(fn(x, k, mode=mode), want)
    np.testing.assert_array_equal(fn((x * 10).astype(int), k, mode=mode),
                                  ndimage.correlate1d((x * 10).astype(int).astype(float), k, axis=axis, mode=mode))


def test_a_study_demosaics_in_single_precision_unless_isp_says_otherwise(tmp_path):
    from cfa_mitsuba.study.chain import STUDY_DEMOSAIC_PRECISION, ChainSettings
    from cfa_mitsuba.study.config import load_config

    assert STUDY_DEMOSAIC_PRECISION == "single"
    assert ChainSettings().isp_options("pocs")["demosaic_precision"] == "single"
    base = 'name = "p"\nscenes = ["macbeth"]\ncfas = ["bayer"]\ndemosaics = ["pocs"]\n'
    for text, want in ((base, "single"), (base + '[isp]\ndemosaic_precision = "double"\n', "double")):
        path = tmp_path / "p.toml"
        path.write_text(text)
        assert load_config(path).chain_settings().isp_options("pocs")["demosaic_precision"] == want
    path.write_text(base + '[isp]\ndemosaic_precision = "half"\n')
    with pytest.raises(CfaMitsubaError, match="isp.demosaic_precision: must be one of double, single"):
        load_config(path)
