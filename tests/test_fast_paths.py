"""The evaluation's fast paths (issue 25) against the library code they
replace: colour-science's sRGB encoding and von Kries adaptation, the full
half-plane test of the spectral locus, scipy's FFT convolution per plane
for S-CIELAB, scipy's convolve2d for MATLAB's conv2 'same', and the (N, B)
x (B, C) product of the metered exposure."""

from __future__ import annotations

import numpy as np
import pytest

from cfa_mitsuba import colorimetry
from cfa_mitsuba.colorimetry import _colour, _locus_half_planes, linear_to_srgb, realisable, xyz_to_srgb


@pytest.fixture(scope="module")
def colour():
    return _colour()


def test_srgb_encoding_is_colour_sciences_to_the_bit(colour):
    x = np.random.default_rng(1).normal(0.3, 0.5, (400, 3))
    x[:5, 0] = [0.0, 0.0031308, -0.0031308, 1.0, -1e-9]
    assert np.array_equal(linear_to_srgb(x), colour.models.eotf_inverse_sRGB(x))
    assert float(linear_to_srgb(0.18)) == float(colour.models.eotf_inverse_sRGB(0.18))


def test_bradford_adaptation_matches_colour_science(colour):
    rng = np.random.default_rng(2)
    xyz = rng.random((50, 40, 3)) * 120.0
    white = np.array([98.0, 100.0, 80.0])  # not D65: the adaptation does something
    d65 = colorimetry.SRGB_WHITE_XYZ / colorimetry.SRGB_WHITE_XYZ[1]
    adapted = white[1] * colour.adaptation.chromatic_adaptation_VonKries(xyz / white[1], white / white[1], d65,
                                                                        transform="Bradford")
    expected = linear_to_srgb(np.clip(colorimetry.xyz_to_linear(adapted, scale=white[1]), 0.0, 1.0))
    np.testing.assert_allclose(xyz_to_srgb(xyz, white, adaptation="Bradford"), expected, rtol=0, atol=1e-13)


def test_realisable_equals_the_full_half_plane_test():
    rng = np.random.default_rng(3)
    xyz = rng.normal(0.3, 0.4, (100000, 3))
    cmfs = _colour().MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values
    locus = cmfs / cmfs.sum(axis=1, keepdims=True)
    centre = locus.mean(axis=0)
    near = np.concatenate([centre + (locus - centre) * (1 + e) for e in (-1e-5, -1e-7, 0.0, 1e-7, 1e-5)])
    xyz = np.concatenate([xyz, 10.0 * near, np.zeros((3, 3))])
    s = xyz.sum(axis=1)
    planes = _locus_half_planes()
    xy = xyz[:, :2] / np.where(s > 0, s, 1.0)[:, None]
    inside = np.all(xy @ planes[:, :2].T + planes[:, 2] <= 1e-6, axis=1)
    nonneg = np.all(xyz >= -1e-6 * np.maximum(np.abs(s), np.finfo(float).tiny)[:, None], axis=1)
    expected = nonneg & ((s <= 0) | inside)
    got = realisable(xyz)
    assert np.array_equal(got, expected)
    assert 0.1 < got.mean() < 0.9  # both answers well represented


def test_scielab_filtering_equals_fftconvolve_per_plane():
    from scipy import signal

    from cfa_mitsuba.metrics.scielab import _symmetric_filter, scielab_filters

    opp = np.random.default_rng(4).random((57, 64, 3)) * 50.0
    kernels = scielab_filters(23.0)
    n = kernels[0].shape[0]
    expected = np.stack([signal.fftconvolve(np.pad(opp[..., c], n // 2, mode="symmetric"), kernels[c], mode="valid")
                         for c in range(3)], axis=-1)
    got = np.moveaxis(_symmetric_filter(opp, 23.0, "distribution", n), 0, -1)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (2, 3), (3, 2)])
def test_small_conv2_same_equals_convolve2d(shape):
    from scipy import signal

    from cfa_mitsuba.metrics._common import conv2_same

    rng = np.random.default_rng(5)
    x, k = rng.random((31, 37)) * 255.0, rng.normal(size=shape)
    full = signal.convolve2d(x, k, mode="full")
    expected = full[shape[0] // 2:shape[0] // 2 + 31, shape[1] // 2:shape[1] // 2 + 37]
    np.testing.assert_allclose(conv2_same(x, k), expected, rtol=0, atol=1e-11)


def _haar(scale: int) -> np.ndarray:
    n = 2 ** scale
    k = np.full((n, n), 2.0 ** -scale)
    k[: n // 2] *= -1.0
    return k


@pytest.mark.parametrize("kernel", [np.full((2, 2), 0.25), np.array([[1.0, 0.0, -1.0]] * 3) / 3.0,
                                    np.array([[1.0, 0.0, -1.0]] * 3).T / 3.0, np.full((3, 3), 1 / 9),
                                    _haar(1), _haar(2), _haar(3).T, np.outer([1.0, -2.0, 0.5], [2.0, 4.0])],
                         ids=["mean2", "prewitt-x", "prewitt-y", "mean3", "haar2", "haar4", "haar8-t", "3x2"])
@pytest.mark.parametrize("shape", [(31, 37), (1, 9), (9, 1), (2, 3)])
def test_separable_conv2_same_equals_convolve2d(kernel, shape):
    """HaarPSI's and MDSI's kernels are outer products, filtered in two
    compiled 1-D passes; against scipy's 2-D convolution (MATLAB's 'same'
    centre at floor(m / 2)), odd and even sizes, images smaller than the
    kernel included."""
    from scipy import signal

    from cfa_mitsuba.metrics._common import conv2_same
    from cfa_mitsuba.metrics._conv2_kernel import separable_factors

    assert separable_factors(kernel) is not None
    x = np.random.default_rng(6).random(shape) * 255.0
    full = signal.convolve2d(x, kernel, mode="full")
    r0, c0 = kernel.shape[0] // 2, kernel.shape[1] // 2
    expected = full[r0:r0 + shape[0], c0:c0 + shape[1]]
    np.testing.assert_allclose(conv2_same(x, kernel), expected, rtol=0, atol=1e-12)


def test_a_kernel_that_is_no_outer_product_is_not_split():
    from cfa_mitsuba.metrics._conv2_kernel import separable_factors

    assert separable_factors(np.array([[1.0, 2.0], [3.0, 5.0]])) is None
    assert separable_factors(np.zeros((3, 3))) is None
    u, v = separable_factors(np.array([[0.5, -0.5], [1.0, -1.0]]))
    assert np.array_equal(np.outer(u, v), [[0.5, -0.5], [1.0, -1.0]])


def test_processed_srgb_is_encoded_on_first_read():
    import cfa_mitsuba as cm
    from cfa_mitsuba.isp.colour_matrix import xyz_to_srgb as display
    from synthetic_raw import WHITE, synthetic_raw

    radiance = np.broadcast_to(WHITE * 0.4, (12, 14, WHITE.size)) * np.linspace(0.5, 1.5, 14)[None, :, None]
    out = cm.isp.process(synthetic_raw(radiance, "rgbw1"), "bilinear")
    assert out.__dict__["_srgb"] is None  # not encoded yet
    assert np.array_equal(out.srgb, display(out.xyz, out.white_xyz))
    assert out.srgb is out.srgb  # encoded once, then kept
    assert isinstance(out, cm.values.RenderedImage)


def test_metered_peak_product_is_the_same_numbers():
    rng = np.random.default_rng(6)
    pix, w = rng.random((40, 50, 31)), rng.random((31, 4))
    # the same dot products; OpenBLAS's kernels may round the last bit differently
    np.testing.assert_allclose((w.T @ pix.reshape(-1, 31).T).T, pix.reshape(-1, 31) @ w, rtol=1e-14, atol=0)


@pytest.mark.parametrize("shape", [(636, 720, 3), (37, 41, 3), (1, 7, 3), (2, 5, 7, 3), (5, 3), (3,)])
def test_srgb_matrix_products_equal_the_transposed_view(shape):
    """xyz_to_linear and linear_to_xyz multiply an image by contiguous
    copies of the matrices' transposes (a faster product path): the same
    values as the product with the transposed view, bit for bit (a colour
    or a list of colours keeps the transposed view)."""
    from cfa_mitsuba import colorimetry as col

    x = np.random.default_rng(7).random(shape) * 120.0
    assert np.array_equal(col.xyz_to_linear(x, scale=97.0), (x / 97.0) @ col.XYZ_TO_SRGB.T)
    assert np.array_equal(col.linear_to_xyz(x, scale=97.0), 97.0 * x @ col.SRGB_TO_XYZ.T)
    strided = np.random.default_rng(8).random((40, 60, 3))[:, ::2]
    assert np.array_equal(col.xyz_to_linear(strided), (strided / 100.0) @ col.XYZ_TO_SRGB.T)


@pytest.mark.parametrize("weighting", ["soft", "hard"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_directional_colour_differences_compiled_equal_numpy(dtype, weighting):
    """'adaptive-laplacian''s edge-directed colour differences, compiled per
    gap phase, are bit for bit the numpy steps (_directional_estimate), for
    every registered CFA, both precisions and both weightings."""
    import cfa_mitsuba as cm
    from cfa_mitsuba.isp import laplacian as lap
    from cfa_mitsuba.isp._directional_kernel import directional_phase
    from cfa_mitsuba.isp.mosaic import directional_samples, extend, geometry, tent_radius

    rng = np.random.default_rng(9)
    checked = 0
    for name in cm.sensor.list_cfas():
        cfa = cm.sensor.get_cfa(name)
        mosaic = geometry(cfa)
        th, tw = mosaic.tile_shape
        raw = (rng.random((3 * th + 17, 3 * tw + 19)) * 900.0 + rng.random() * 50).astype(dtype)
        ref = lap.reference_for(cfa, mosaic)
        refimg = lap.reference_adaptive(raw, mosaic, ref, lap.MHC_ALPHA).astype(dtype)
        limit = max(th, tw)
        radius = max(max(tent_radius(mosaic, c) for c in range(len(mosaic.channels))), limit)
        ext_y, ph, pw = extend(raw, mosaic, radius)
        ext_r, _, _ = extend(refimg, mosaic, radius)
        eps = lap._eps(raw)
        for c in range(len(mosaic.channels)):
            for i, j in mosaic.gaps(c):
                dirs = directional_samples(mosaic, c, i, j, limit)
                if len(dirs) < 2:
                    continue
                want = lap._directional_estimate(ext_y, ext_r, refimg, ph, pw, raw.shape, (th, tw), i, j, dirs,
                                                 0.7, eps, weighting)
                got = np.empty(want.shape, dtype=dtype)
                directional_phase(ext_y, ext_r, refimg[i::th, j::tw], ph + i, pw + j, (th, tw), dirs, 0.7, eps,
                                  weighting == "soft", got)
                assert np.array_equal(got, want.astype(dtype)), (name, c, i, j)
                checked += 1
    assert checked > 20


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_colour_difference_gaps_and_sites_compiled_equal_numpy(dtype):
    """colour_differences' last steps for a channel (g x the reference added
    back at the gaps, the mosaic's samples at the sites), compiled, are bit
    for bit numpy's strided steps, for every registered CFA, both
    precisions and a gain that float32 cannot hold exactly; arrays of mixed
    precision are left to numpy."""
    import cfa_mitsuba as cm
    from cfa_mitsuba.isp._colour_difference_kernel import gaps_and_sites
    from cfa_mitsuba.isp.mosaic import geometry

    rng = np.random.default_rng(10)
    g = 0.7123456789
    for name in cm.sensor.list_cfas():
        mosaic = geometry(cm.sensor.get_cfa(name))
        th, tw = mosaic.tile_shape
        n = len(mosaic.channels)
        shape = (3 * th + 5, 3 * tw + 7)
        raw, refimg = ((rng.random(shape) * 900.0).astype(dtype) for _ in range(2))
        start = (rng.normal(size=(*shape, n)) * 50).astype(dtype)
        for c in range(n):
            want = start.copy()
            plane = want[..., c]
            for i, j in mosaic.gaps(c):
                plane[i::th, j::tw] += g * refimg[i::th, j::tw]
            for i, j in mosaic.phases(c):
                plane[i::th, j::tw] = raw[i::th, j::tw]
            got = start.copy()
            assert gaps_and_sites(got, c, refimg, raw, mosaic.index, g)
            assert np.array_equal(got, want), (name, c)
    mixed = np.zeros((4, 4, 3), dtype=dtype)
    assert not gaps_and_sites(mixed, 0, np.zeros((4, 4), dtype=np.float16), np.zeros((4, 4), dtype=dtype),
                              geometry(cm.sensor.get_cfa("bayer")).index, g)


def test_mirror_extension_by_blocks_equals_the_whole_gather():
    """isp.mosaic.extend copies the image in as a block and gathers only the
    border bands: the same array as indexing the whole extension with the
    mirror's row and column indices, for every registered CFA, images down
    to one tile (demosaic's smallest), extra axes and both precisions."""
    import math

    from cfa_mitsuba.isp import mosaic
    from cfa_mitsuba.isp.demosaic import resolve_cfa
    from cfa_mitsuba.sensor import list_cfas

    rng = np.random.default_rng(4)
    for name in list_cfas():
        geo = mosaic.geometry(resolve_cfa(name))
        th, tw = geo.tile_shape
        for shape in [(37, 41), (th, tw), (th, 2 * tw + 1), (th + 3, tw, 2), (12 + th, 10 + tw, 4)]:
            for dtype in (np.float32, np.float64):
                image = rng.random(shape).astype(dtype)
                for radius in (0, 1, 3, 7):
                    got, ph, pw = mosaic.extend(image, geo, radius)
                    assert (ph, pw) == (th * math.ceil(radius / th), tw * math.ceil(radius / tw))
                    rows = mosaic._mirror_index(shape[0], th, ph)
                    cols = mosaic._mirror_index(shape[1], tw, pw)
                    want = image[rows[:, None], cols[None, :]]
                    assert got.dtype == want.dtype and np.array_equal(got, want), (name, shape, radius)
