"""The compiled CIELAB and CIEDE2000 loops (cfa_mitsuba/colour_kernels.py)
against the libraries they stand in for: scikit-image's and colour-science's
CIEDE2000, colour-science's XYZ_to_Lab."""

import warnings

import numpy as np
import pytest

from cfa_mitsuba import colorimetry as cm
from cfa_mitsuba.colour_kernels import ciede2000, lab_cie

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import colour
from skimage.color import deltaE_ciede2000


def _lab_pairs(n=200_000, seed=3):
    rng = np.random.default_rng(seed)
    a = np.stack([rng.uniform(0, 100, n), rng.normal(0, 40, n), rng.normal(0, 40, n)], axis=-1)
    b = a + rng.normal(0, 4, a.shape)
    # the formula's special cases: zero chroma on one or both sides, hues either side of the 0/360 seam,
    # hue differences just over and under 180 degrees
    a[:50, 1:] = 0.0
    b[25:75, 1:] = 0.0
    a[100:200, 1], a[100:200, 2] = 30.0, rng.uniform(-1, 1, 100)
    b[100:200, 1], b[100:200, 2] = 30.0, rng.uniform(-1, 1, 100)
    ang = np.deg2rad(rng.uniform(0, 360, 300))
    a[200:500, 1], a[200:500, 2] = 20 * np.cos(ang), 20 * np.sin(ang)
    b[200:500, 1], b[200:500, 2] = 20 * np.cos(ang + np.pi + rng.normal(0, 1e-3, 300)), 20 * np.sin(
        ang + np.pi + rng.normal(0, 1e-3, 300))
    return a, b


def test_ciede2000_equals_scikit_image_and_colour():
    a, b = _lab_pairs()
    got = ciede2000(a, b)
    sk = deltaE_ciede2000(a, b, channel_axis=-1)
    np.testing.assert_allclose(got, sk, rtol=1e-12, atol=1e-12)
    cs = colour.delta_E(a[:20000], b[:20000], method="CIE 2000")
    np.testing.assert_allclose(got[:20000], cs, rtol=1e-12, atol=1e-11)


def test_ciede2000_blocks_do_not_leak_into_each_other():
    """Pairs go through in blocks of BLOCK, the special cases (zero chroma,
    hues opposite) across block boundaries: every value equals the pair's
    own, computed alone, and scikit-image's."""
    from cfa_mitsuba.colour_kernels import BLOCK

    a, b = _lab_pairs(2 * BLOCK + 7)
    a, b = np.roll(a, BLOCK - 60, axis=0), np.roll(b, BLOCK - 60, axis=0)
    got = ciede2000(a, b)
    np.testing.assert_allclose(got, deltaE_ciede2000(a, b, channel_axis=-1), rtol=1e-12, atol=1e-12)
    for i in [*range(BLOCK - 70, BLOCK + 520), 2 * BLOCK - 1, 2 * BLOCK, 2 * BLOCK + 6]:
        np.testing.assert_allclose(got[i], ciede2000(a[i], b[i]), rtol=1e-15, atol=0)


def test_ciede2000_shapes_broadcasting_and_nan():
    a, b = _lab_pairs(1200)
    img_a, img_b = a.reshape(30, 40, 3), b.reshape(30, 40, 3)
    assert cm.delta_e_2000(img_a, img_b).shape == (30, 40)
    one = cm.delta_e_2000(img_a, [50.0, 0.0, 0.0])
    np.testing.assert_allclose(one, deltaE_ciede2000(img_a, np.broadcast_to([50.0, 0.0, 0.0], img_a.shape),
                                                     channel_axis=-1), rtol=1e-12, atol=1e-12)
    assert cm.delta_e_2000([50, 1, 2], [50, 1, 2]).shape == ()
    assert cm.delta_e_2000(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)
    bad = img_b.copy()
    bad[3, 4, 1] = np.nan
    out = cm.delta_e_2000(img_a, bad)
    assert np.isnan(out[3, 4]) and np.isfinite(np.delete(out.ravel(), 3 * 40 + 4)).all()


def test_lab_equals_colour_science_across_the_dark_branch():
    rng = np.random.default_rng(5)
    white = np.array([95.05, 100.0, 108.9])
    xyz = rng.uniform(0, 120, (100_000, 3))
    xyz[:20000] *= 0.01  # below (24/116)^3 of the white: the linear branch
    xyz[:100] = -xyz[:100]  # negative XYZ (a demosaic overshoot) takes the linear branch too
    with colour.utilities.domain_range_scale("reference"):
        ref = colour.XYZ_to_Lab(xyz / white[1], illuminant=colour.XYZ_to_xy(white / white[1]))
    got = lab_cie(xyz, white)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * 100)
    np.testing.assert_allclose(cm.xyz_to_lab(xyz.reshape(100, 1000, 3), white).reshape(-1, 3), ref, atol=1e-10)


def test_lab_rejects_a_last_axis_that_is_not_three():
    from cfa_mitsuba.errors import CfaMitsubaError

    with pytest.raises(CfaMitsubaError, match="3 values in its last axis"):
        cm.xyz_to_lab(np.ones((4, 4, 2)), [95.05, 100.0, 108.9])


def test_opponent_lab_equals_the_library_chain():
    """opponent planes -> XYZ -> CIELAB in blocks of rows against numpy's
    matrix product then colour-science's XYZ_to_Lab."""
    from cfa_mitsuba.colour_kernels import opponent_lab
    from cfa_mitsuba.metrics.scielab import OPPONENT_MATRICES

    rng = np.random.default_rng(8)
    white = np.array([95.05, 100.0, 108.9])
    m = OPPONENT_MATRICES["xyz2"]
    xyz = rng.uniform(0.01, 100, (150, 130, 3))  # three blocks of rows
    xyz[60:70] *= 0.001  # the linear branch, across a block's edge
    planes = np.moveaxis(xyz @ m.T, -1, 0)[:, 1:-1, 2:]  # a strided view, as S-CIELAB passes it
    inv = np.linalg.inv(m)
    with colour.utilities.domain_range_scale("reference"):
        expected = colour.XYZ_to_Lab((np.moveaxis(planes, 0, -1) @ inv.T) / white[1],
                                     illuminant=colour.XYZ_to_xy(white / white[1]))
    np.testing.assert_allclose(opponent_lab(planes, inv, white), expected, rtol=0, atol=1e-11)


def test_opponent_lab_with_a_base_is_the_lab_of_the_sum_bit_for_bit():
    """``base + planes`` added inside the pass (planes float32, S-CIELAB's
    filtered difference, or float64) gives the same bits as the sum made by
    numpy first; a base of another shape is refused."""
    from cfa_mitsuba.colour_kernels import opponent_lab

    rng = np.random.default_rng(9)
    white = np.array([95.05, 100.0, 108.9])
    inv = np.linalg.inv(rng.uniform(-1, 1, (3, 3)) + 3 * np.eye(3))
    base = rng.uniform(1, 80, (3, 30, 41))
    for dtype in (np.float32, np.float64):
        full = rng.normal(0, 5, (3, 36, 45)).astype(dtype)
        planes = full[:, 3:33, 2:43]  # a strided view, as the filter's crop is
        np.testing.assert_array_equal(opponent_lab(planes, inv, white, base=base),
                                      opponent_lab(base + planes, inv, white))
    with pytest.raises(ValueError, match="differ"):
        opponent_lab(base[:, :4], inv, white, base=base)


def test_srgb8_codes_equal_the_formula_rounded():
    """The table's codes against round(255 x sRGB(clip(v))) at every code
    boundary's float neighbours and on ten million values (a tenth near 0,
    where the codes are densest); NaN stays NaN."""
    from cfa_mitsuba.colour_kernels import _srgb8_tables, srgb8_codes

    def formula(v):
        return np.round(255.0 * cm.linear_to_srgb(np.clip(v, 0.0, 1.0)))

    thresholds, _ = _srgb8_tables(cm.linear_to_srgb)
    steps = [thresholds]
    for direction in (-1.0, 2.0):
        v = thresholds
        for _ in range(3):
            v = np.nextafter(v, direction)
            steps.append(v)
    near = np.concatenate(steps)
    np.testing.assert_array_equal(srgb8_codes(near, cm.linear_to_srgb), formula(near))
    rng = np.random.default_rng(11)
    v = np.concatenate([rng.uniform(-0.2, 1.2, 9_000_000), rng.uniform(0, 0.005, 1_000_000)])
    np.testing.assert_array_equal(srgb8_codes(v, cm.linear_to_srgb), formula(v))
    np.testing.assert_array_equal(srgb8_codes(v[:1200].reshape(30, 40), cm.linear_to_srgb),
                                  formula(v[:1200].reshape(30, 40)))
    assert np.isnan(srgb8_codes([np.nan, 0.5], cm.linear_to_srgb)).tolist() == [True, False]
    xyz = rng.uniform(0, 120, (50, 60, 3))
    white = np.array([95.05, 100.0, 108.9])
    np.testing.assert_array_equal(cm.xyz_to_srgb8(xyz, white), np.round(cm.xyz_to_srgb8(xyz, white, quantize=False)))
    # with the white adapted (the study's thumbnails): the codes of the adapted encoding, and not the
    # unadapted codes under a warm white
    warm = np.array([109.85, 100.0, 35.58])
    adapted = cm.xyz_to_srgb8(xyz, warm, adaptation="Bradford")
    np.testing.assert_array_equal(adapted, np.round(255 * cm.xyz_to_srgb(xyz, warm, adaptation="Bradford")))
    assert not np.array_equal(adapted, cm.xyz_to_srgb8(xyz, warm))


def test_realisable_shapes_nan_and_bad_axis():
    from cfa_mitsuba.errors import CfaMitsubaError

    xyz = np.array([[[95.05, 100.0, 108.9], [np.nan, 1.0, 1.0], [-5.0, 10.0, 10.0]]] * 2)
    assert cm.realisable(xyz).tolist() == [[True, False, False]] * 2
    assert cm.realisable(np.zeros((0, 3))).shape == (0,)
    with pytest.raises(CfaMitsubaError, match="3 values in its last axis"):
        cm.realisable(np.ones((4, 2)))


def test_ciede2000_degenerate_hue_pairs_take_the_angle_formula():
    """Equal hues, exactly opposite hues, hues within the 1.15 degree band
    of opposite and zero chroma: the pairs where the vector form of the hue
    terms is degenerate or loses digits, against scikit-image."""
    a = np.array([[50, 10, 5], [50, 10, 0], [50, 0, 10], [40, 10, 5], [60, 0, 0], [50, -20, 0.0]])
    b = np.array([[60, 20, 10], [50, -10, 0], [55, 0.2, -12], [45, -12, -5.9], [70, 3, 4], [50, 20, 0.0]])
    np.testing.assert_allclose(ciede2000(a, b), deltaE_ciede2000(a, b, channel_axis=-1), rtol=1e-12, atol=1e-12)
