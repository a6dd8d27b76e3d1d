"""The metrics on inputs with known answers, their details, and bad or extreme
input (acceptance 1, ideal values; acceptance 4)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import cfa_mitsuba.metrics as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.metrics import colourspace as mc

WHITE = np.array([95.05, 100.0, 108.9])
RNG = np.random.default_rng(7)
CODES = RNG.integers(0, 256, (48, 64, 3)).astype(np.float64)
XYZ = mc.srgb8_to_xyz(CODES)


def lab_image_to_xyz(lab):
    import colour

    xy = colour.XYZ_to_xy(WHITE / 100.0)
    return 100.0 * np.asarray(colour.Lab_to_XYZ(lab, illuminant=xy))


# -- ideal values --------------------------------------------------------------------------------

def test_identical_images_give_the_ideal_values():
    assert cm.ssim(CODES, CODES) == 1.0
    assert cm.mdsi(CODES, CODES) == 0.0
    assert cm.mdsi(CODES, CODES, combination="mult") == 0.0
    assert cm.haarpsi(CODES, CODES) == 1.0
    assert float(cm.delta_e(XYZ, XYZ, WHITE)) == 0.0
    assert float(cm.scielab(XYZ, XYZ, WHITE, samples_per_degree=20)) == 0.0
    assert float(cm.achromatic(XYZ, XYZ, WHITE)) == 0.0


def test_result_is_a_float_with_unit_details_and_pickles():
    r = cm.delta_e(XYZ, XYZ * 1.01, WHITE)
    assert isinstance(r, float) and r.unit == "dE00" and r.name == "delta-e"
    assert r.to_dict()["de2000"]["shape"] == [48, 64]  # maps summarised
    back = pickle.loads(pickle.dumps(r))
    assert float(back) == float(r) and back.unit == r.unit and back.details.keys() == r.details.keys()
    import json

    json.dumps(r.to_dict(), allow_nan=False)


# -- delta-e with patches ---------------------------------------------------------------------

def test_delta_e_per_patch_grey_dl_and_chromaticities():
    h, w = 40, 60
    rects = [(r * 10, c * 10, r * 10 + 10, c * 10 + 10) for r in range(4) for c in range(6)]
    ref = np.empty((h, w, 3))
    for i, (y0, x0, y1, x1) in enumerate(rects):
        ref[y0:y1, x0:x1] = [20 + i, 22 + i, 25 + i] if i < 18 else np.array([0.9505, 1.0, 1.089]) * (10 + 10 * (i - 18))
    test = ref.copy()
    y0, x0, y1, x1 = rects[20]
    test[y0:y1, x0:x1] *= 1.1  # one grey patch brighter
    inner = [(y0 + 2, x0 + 2, y1 - 2, x1 - 2) for y0, x0, y1, x1 in rects]
    r = cm.delta_e(ref, test, WHITE, patches=inner)
    lab_r = mc.xyz_to_lab(ref[y0 + 2, x0 + 2], WHITE)
    lab_t = mc.xyz_to_lab(test[y0 + 2, x0 + 2], WHITE)
    dl = abs(lab_t[0] - lab_r[0])
    assert r.details["de1976"][20] == pytest.approx(dl, rel=1e-9)  # neutral: only L* moves
    assert np.count_nonzero(r.details["de2000"]) == 1
    assert float(r) == pytest.approx(r.details["de2000"][20] / 24)
    assert r.details["mean_dl_grey"] == pytest.approx(dl / 6)
    assert r.details["xy_reference"].shape == (24, 2)
    assert r.details["xy_test"][20] == pytest.approx(r.details["xy_reference"][20])
    assert cm.delta_e(ref, test, WHITE, patches=inner, version="1976").unit == "dE76"
    with pytest.raises(CfaMitsubaError, match="outside"):
        cm.delta_e(ref, test, WHITE, patches=[(0, 0, 50, 5)])


# -- moire ------------------------------------------------------------------------------------

def _chroma_ramp(h, w, top):
    lab = np.zeros((h, w, 3))
    lab[..., 0] = 50.0
    lab[..., 1] = np.linspace(0.0, top, w)[None, :]
    return lab_image_to_xyz(lab)


def test_moire_start_is_the_first_column_above_threshold_in_cpd():
    h, w = 31, 200
    ideal = _chroma_ramp(h, w, 0.0)
    camera = _chroma_ramp(h, w, 60.0)
    freq = np.linspace(0.5, 50.0, w)
    r = cm.moire(ideal, camera, WHITE, frequency_cy_per_deg=freq)
    a = np.linspace(0.0, 60.0, w)
    col = int(np.flatnonzero(a > 25.0)[0])
    assert r.details["passed"] and r.details["msp_px"] == col and r.details["censored"] is False
    assert float(r) == pytest.approx(freq[col]) and r.unit == "cy/deg"
    # a chirp whose frequency falls left to right is searched from the right
    r2 = cm.moire(ideal[:, ::-1], camera[:, ::-1], WHITE, frequency_cy_per_deg=freq[::-1])
    assert r2.details["msp_px"] == w - 1 - col and float(r2) == pytest.approx(float(r))
    for block in (5, 7):
        assert cm.moire(ideal, camera, WHITE, frequency_cy_per_deg=freq, block=block).details["passed"]


def test_chirp_without_moire_reports_the_highest_frequency_with_a_flag():
    ideal = _chroma_ramp(31, 100, 0.0)
    freq = np.linspace(1.0, 40.0, 100)
    r = cm.moire(ideal, ideal, WHITE, frequency_cy_per_deg=freq)
    assert not r.details["passed"] and np.isfinite(float(r))
    assert r.details["censored"] is True  # a bound: stored and shown as one (issue 12.5)
    assert cm.METRICS["moire"].censored_key == "censored"
    assert all(rec.censored_key is None for rec in cm.METRICS.values() if rec.name != "moire")
    assert float(r) == pytest.approx(freq[100 - 1 - 7])  # last column where a 15-px block fits


def test_moire_bad_arguments():
    ideal = _chroma_ramp(31, 100, 0.0)
    with pytest.raises(CfaMitsubaError, match="one per column"):
        cm.moire(ideal, ideal, WHITE, frequency_cy_per_deg=np.ones(50))
    with pytest.raises(CfaMitsubaError, match="odd"):
        cm.moire(ideal, ideal, WHITE, frequency_cy_per_deg=np.ones(100), block=4)
    with pytest.raises(CfaMitsubaError, match="does not fit"):
        cm.moire(ideal[:10], ideal[:10], WHITE, frequency_cy_per_deg=np.ones(100))


# -- achromatic --------------------------------------------------------------------------------

def test_achromatic_is_mean_abs_dl_without_the_border():
    h, w = 21, 120
    lstar = np.repeat(np.linspace(95, 20, 6), 20)[None, :].repeat(h, 0)
    lab = np.stack([lstar, np.zeros_like(lstar), np.zeros_like(lstar)], -1)
    ideal = lab_image_to_xyz(lab)
    lab2 = lab.copy()
    lab2[..., 0] += np.where(np.arange(w) % 2 == 0, 1.0, -1.0)[None, :]
    lab2[:, :10, 0] += 30.0  # ruined border: excluded
    r = cm.achromatic(ideal, lab_image_to_xyz(lab2), WHITE, steps=[(i * 20, i * 20 + 20) for i in range(6)])
    assert float(r) == pytest.approx(1.0, abs=1e-9) and r.unit == "L*"
    assert r.details["per_step"][1] == pytest.approx(1.0, abs=1e-9)
    assert r.details["l_reference"][50] == pytest.approx(lstar[0, 50])


def test_mean_match_scales_to_the_interior_mean():
    out, k = cm.mean_match(XYZ * 0.5, XYZ, border=5, return_scale=True)
    assert k == pytest.approx(2.0) and out == pytest.approx(XYZ)
    with pytest.raises(CfaMitsubaError, match="mean"):
        cm.mean_match(np.zeros_like(XYZ), XYZ)


def test_mean_match_with_the_reference_mean_given_is_identical_and_names_each_image():
    """A study gives the ideal's interior mean once (reference_interior_mean):
    the same scale and image, bit for bit; a bad input is named as what it is."""
    from cfa_mitsuba.metrics import reference_interior_mean

    test = XYZ * np.random.default_rng(3).uniform(0.3, 0.7, XYZ.shape)
    for border in (0, 5, 10):
        want, k = cm.mean_match(test, XYZ, border=border, return_scale=True)
        got, k2 = cm.mean_match(test, XYZ, border=border, return_scale=True,
                                reference_mean=reference_interior_mean(XYZ, border=border))
        assert k2 == k and np.array_equal(got, want)
    bad = test.copy()
    bad[3, 3, 1] = np.nan
    for kw in ({}, {"reference_mean": reference_interior_mean(XYZ)}):
        with pytest.raises(CfaMitsubaError, match="^test image"):
            cm.mean_match(bad, XYZ, **kw)
        with pytest.raises(CfaMitsubaError, match="differ in shape"):
            cm.mean_match(test[:-1], XYZ, **kw)
    with pytest.raises(CfaMitsubaError, match="^reference image"):
        cm.mean_match(test, bad)
    with pytest.raises(CfaMitsubaError, match="^reference image"):
        reference_interior_mean(bad)
    with pytest.raises(CfaMitsubaError, match="reference image's interior mean"):
        cm.mean_match(test, XYZ, reference_mean=0.0)
    gray, gray_ref = test[..., 1:2], XYZ[..., 1:2]  # (H, W, 1): a gray image, as without the mean given
    want = cm.mean_match(gray, gray_ref, return_scale=True)
    got = cm.mean_match(gray, gray_ref, return_scale=True, reference_mean=reference_interior_mean(gray_ref))
    assert got[1] == want[1] and np.array_equal(got[0], want[0]) and got[0].shape == gray.shape[:2]


# -- S-CIELAB details ---------------------------------------------------------------------------

def test_scielab_filters_follow_the_readme_construction():
    for spd, n in ((41, 41), (72, 71), (63.6, 63)):
        ks = cm.scielab_filters(spd)
        assert all(k.shape == (n, n) and k.sum() == pytest.approx(1.0) for k in ks)
        assert all(np.allclose(k, k.T) and np.allclose(k, k[::-1]) for k in ks)


def test_scielab_uniform_difference_equals_cielab_and_interior_is_reported():
    a = np.full((90, 100, 3), [30.0, 32.0, 35.0])
    b = a * [1.03, 1.0, 0.97]
    r = cm.scielab(a, b, WHITE, samples_per_degree=30)
    plain = cm.delta_e(a, b, WHITE)
    assert float(r) == pytest.approx(float(plain), rel=1e-9)
    assert r.details["mean_interior"] == pytest.approx(float(plain), rel=1e-9)
    assert r.details["interior_rect"] == [30, 30, 60, 70]
    small = cm.scielab(a[:20, :20], b[:20, :20], WHITE, samples_per_degree=30)
    assert np.isfinite(float(small)) and small.details["mean_interior"] is None


# -- bad or extreme input (acceptance 4) ------------------------------------------------------

PAIR_CALLS = {
    "ssim": lambda a, b: cm.ssim(a, b),
    "mdsi": lambda a, b: cm.mdsi(a, b),
    "haarpsi": lambda a, b: cm.haarpsi(a, b),
    "delta-e": lambda a, b: cm.delta_e(a, b, WHITE),
    "scielab": lambda a, b: cm.scielab(a, b, WHITE, samples_per_degree=20),
    "achromatic": lambda a, b: cm.achromatic(a, b, WHITE),
}


@pytest.mark.parametrize("name", PAIR_CALLS)
def test_different_shapes_are_refused(name):
    with pytest.raises(CfaMitsubaError, match="differ in shape"):
        PAIR_CALLS[name](CODES + 1, CODES[:, :-1] + 1)


@pytest.mark.parametrize("name", PAIR_CALLS)
def test_nan_is_refused(name):
    bad = CODES + 1
    bad[3, 4, 1] = np.nan
    with pytest.raises(CfaMitsubaError, match="NaN"):
        PAIR_CALLS[name](CODES + 1, bad)


@pytest.mark.parametrize("name", PAIR_CALLS)
def test_constant_images_give_finite_documented_values(name):
    a, b = np.full((32, 32, 3), 120.0), np.full((32, 32, 3), 90.0)
    same, diff = float(PAIR_CALLS[name](a, a.copy())), float(PAIR_CALLS[name](a, b))
    assert np.isfinite(same) and np.isfinite(diff)
    assert same == {"ssim": 1.0, "haarpsi": 1.0}.get(name, 0.0)
    if name == "mdsi":
        assert diff >= 0.0  # deviation pooling sees only the zero-padded border here (documented)
    elif name in ("ssim", "haarpsi"):
        assert diff < 1.0
    else:
        assert diff > 0.0


def test_images_smaller_than_the_window():
    tiny = CODES[:8, :8]
    with pytest.raises(CfaMitsubaError, match="at least 11"):
        cm.ssim(tiny, tiny)
    assert cm.mdsi(tiny, tiny[::-1]) >= 0.0 and np.isfinite(cm.haarpsi(tiny, tiny[::-1]))


def test_unit_range_data_is_refused_unless_declared():
    a, b = CODES / 255.0, CODES[::-1] / 255.0
    for f in (cm.ssim, cm.mdsi, cm.haarpsi):
        with pytest.raises(CfaMitsubaError, match="data_range"):
            f(a, b)
        assert f(a, b, data_range=1.0) == pytest.approx(f(CODES, CODES[::-1]), abs=1e-12)


def test_bad_keywords_are_refused():
    with pytest.raises(CfaMitsubaError):
        cm.ssim(CODES, CODES, channel="y")
    with pytest.raises(CfaMitsubaError):
        cm.mdsi(CODES, CODES, combination="max")
    with pytest.raises(CfaMitsubaError):
        cm.scielab(XYZ, XYZ, WHITE, samples_per_degree=20, matrix="xyz5")
    with pytest.raises(CfaMitsubaError):
        cm.delta_e(XYZ, XYZ, [1, -1, 1])
    with pytest.raises(CfaMitsubaError):
        cm.get_metric("psnr")


def test_registry_lists_the_scored_metrics_first():
    names = [n for n, _ in cm.list_metrics()]
    scored = [n for n in names if cm.get_metric(n).scored]
    assert names[:len(scored)] == scored  # the scored ones (the paper's eight among them) first
    assert names == list(cm.metric_names())


# -- sidecar geometry -> metric arguments -------------------------------------------------------

def test_scene_geometry_rescales_by_the_oversampling_factor():
    side = {"width": 500, "height": 500, "fov_deg": 10.0, "oversample": 4,
            "geometry": {"row": 250, "roi": [101, 58, 381, 300],
                         "frequency_cy_per_deg": np.linspace(0, 50, 500).tolist(),
                         "frequency_cy_per_px": np.linspace(0, 0.25, 500).tolist(),
                         "steps": [{"x0": 0, "x1": 50}, {"x0": 50, "x1": 101}],
                         "patches": [{"rect": [0, 0, 40, 40], "interior_rect": [5, 5, 35, 35]}]}}
    g = cm.scene_geometry(side, (125, 125, 3))
    assert g["oversample"] == 4 and g["row"] == 62 and g["samples_per_degree"] == 12.5
    assert g["roi"] == (26, 15, 95, 75)  # rounded inwards
    assert g["patches"] == [(2, 2, 8, 8)] and g["steps"] == [(0, 12), (13, 25)]
    assert g["frequency_cy_per_deg"].shape == (125,)
    assert g["frequency_cy_per_deg"][0] == pytest.approx(np.linspace(0, 50, 500)[:4].mean())
    assert g["frequency_cy_per_px"][-1] == pytest.approx(4 * np.linspace(0, 0.25, 500)[-4:].mean())
    assert cm.scene_geometry(side, (500, 500))["oversample"] == 1
    with pytest.raises(CfaMitsubaError, match="oversampling"):
        cm.scene_geometry(side, (100, 130))
