"""The glue between stages, each piece tested directly against an
independent number (issue 11: deliberate bugs in these pieces were caught
only by the stored quick-study values, or not at all).

- the XYZ -> 8-bit sRGB scaling that feeds SSIM, MDSI and HaarPSI;
- the moire metric's block average of C*ab;
- the luminance weights of the cross-channel demosaics (fitted on Y);
- Table 3's total (the mean of the per-demosaic means, not a grand mean);
- ``process --least-squares`` (a plain fit) against the default
  (white-preserving);
- the camera chain's shared optical image (the same numbers as computing it
  for each capture).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import colorimetry, spectra

WL = spectra.DEFAULT_WAVELENGTHS
D65_XYZ = np.array([95.047, 100.0, 108.883])


# -- XYZ -> sRGB code values (SSIM, MDSI, HaarPSI read these) --------------------------------------

@pytest.mark.parametrize("white_y", [1.0, 100.0, 3170.0])
def test_srgb8_of_neutral_greys_is_the_srgb_curve_of_relative_luminance(white_y):
    """A neutral grey of luminance Y (white's chromaticity) has all three
    linear sRGB values Y / Y_white, so its code is 255 x the IEC 61966-2-1
    encoding of that ratio (colour-science's encoding, rounded)."""
    import colour

    white = colorimetry.SRGB_WHITE_XYZ * white_y / 100.0
    ratios = np.array([0.0, 0.0031308, 0.01, 0.05, 0.18, 0.5, 0.9, 1.0])
    xyz = ratios[:, None] * white[None, :]
    codes = colorimetry.xyz_to_srgb8(xyz, white)
    expected = np.round(255.0 * colour.models.eotf_inverse_sRGB(ratios))
    assert np.array_equal(codes, np.repeat(expected[:, None], 3, axis=1)), (codes[:, 1], expected)
    # above the white clips, not wraps
    assert np.array_equal(colorimetry.xyz_to_srgb8(2.0 * white[None], white), [[255.0, 255.0, 255.0]])


def test_metric_inputs_feed_the_display_metrics_those_codes():
    """What the chain hands SSIM / MDSI / HaarPSI is exactly the codes of
    the function above, for the camera and the ideal image alike."""
    rng = np.random.default_rng(3)
    white = D65_XYZ * 0.8
    ideal = rng.uniform(0.0, 90.0, (16, 18, 3))
    cam = ideal * 1.01
    inp = cm.metrics.MetricInputs(ideal, cam, white)
    assert np.array_equal(inp.srgb8("reference"), colorimetry.xyz_to_srgb8(ideal, white))
    assert np.array_equal(inp.srgb8("test"), colorimetry.xyz_to_srgb8(cam, white))
    # and the SSIM of the study equals SSIM of those codes computed by hand
    direct = cm.metrics.ssim(colorimetry.xyz_to_srgb8(ideal, white), colorimetry.xyz_to_srgb8(cam, white))
    assert float(cm.metrics.evaluate("ssim", inp)) == pytest.approx(direct, abs=1e-15)


# -- the moire block average -------------------------------------------------------------------------

def _chroma_columns(width, height, spikes, chroma_xyz):
    """A grey image with full-height coloured columns at ``spikes``."""
    xyz = np.tile(0.3 * D65_XYZ, (height, width, 1))
    xyz[:, spikes] = chroma_xyz
    return xyz


def test_block_mean_is_the_15x15_box_mean_of_cstar():
    from cfa_mitsuba.metrics.moire import block_chroma

    rng = np.random.default_rng(0)
    xyz = rng.uniform(5.0, 90.0, (21, 60, 3))
    row, block = 10, 15
    chroma, mean = block_chroma(xyz, D65_XYZ, row=row, block=block)
    lab = colorimetry.xyz_to_lab(xyz, D65_XYZ)
    c = np.hypot(lab[..., 1], lab[..., 2])
    h = block // 2
    for col in (h, 20, 33, 60 - h - 1):
        box = c[row - h:row + h + 1, col - h:col + h + 1]
        assert mean[col] == pytest.approx(box.mean(), rel=1e-12)
    assert np.all(np.isnan(mean[:h])) and np.all(np.isnan(mean[-h:]))
    assert np.allclose(chroma, c[row])


def test_isolated_chroma_columns_do_not_start_moire():
    """One coloured column every 20 px: each pixel there has C*ab near 90,
    but the 15-px block mean stays near 90 / 15 = 6 < 25, so no moire."""
    width, height = 200, 31
    red = colorimetry.linear_to_xyz(np.array([0.6, 0.1, 0.1]), scale=100.0)
    spikes = list(range(30, 170, 20))
    grey = np.tile(0.3 * D65_XYZ, (height, width, 1))
    test = _chroma_columns(width, height, spikes, red)
    c_spike = np.hypot(*colorimetry.xyz_to_lab(red, D65_XYZ)[1:])
    assert c_spike > 40  # far above the threshold, pixel by pixel
    res = cm.metrics.moire(grey, test, D65_XYZ, frequency_cy_per_deg=np.linspace(0, 20, width))
    assert res.details["passed"] is False and np.nanmax(res.details["block_mean_test"]) < 25
    # a band of that colour 15 px wide does start it, at its first block-mean column above 25
    band = _chroma_columns(width, height, list(range(100, 130)), red)
    res2 = cm.metrics.moire(grey, band, D65_XYZ, frequency_cy_per_deg=np.linspace(0, 20, width))
    assert res2.details["passed"] and 100 - 7 <= res2.details["msp_px"] <= 100 + 7


# -- the luminance weights -----------------------------------------------------------------------------

def test_luminance_weights_pick_y_when_a_channel_is_ybar():
    """A camera whose channels respond as the CIE 1931 x, y, z matching functions:
    luminance is exactly its second channel, so the fitted weights are
    (0, 1, 0); fitted on X they would be (1, 0, 0)."""
    from cfa_mitsuba.isp.colour_matrix import electrons_per_radiance_of, luminance_weights

    cmfs = spectra.cmfs_xyz(WL).T  # (3, B)
    qe = cmfs / WL  # electrons count photons (x lambda): dividing by lambda makes each channel an XYZ integral
    epr = electrons_per_radiance_of(qe / qe.max(), WL)
    white = spectra.illuminant("D65", WL)
    w = luminance_weights(epr, white, WL)
    assert np.allclose(w, [0.0, 1.0, 0.0], atol=1e-6), w


# -- Table 3's total -------------------------------------------------------------------------------

def test_total_score_is_the_mean_of_the_per_demosaic_means():
    """Unequal metric counts per demosaic (a metric failed for one output):
    the grand mean and the mean of means differ; Table 3 is the latter."""
    from cfa_mitsuba.study.scoring import score

    rows = []
    for cfa, vals in {"a": {"bilinear": (0.9, 0.5, 0.1), "pocs": (0.8, 0.8)},
                      "b": {"bilinear": (0.6, 0.6, 0.6), "pocs": (0.7, 0.5)}}.items():
        for dem, vs in vals.items():
            for metric, v in zip(("ssim", "haarpsi", "mdsi"), vs):
                rows.append(dict(scene="puppy", cfa=cfa, demosaic=dem, luminance=100.0, metric=metric,
                                 value=v if metric != "mdsi" else 0.5 * (1 - v), unit=""))
    s = score(pd.DataFrame(rows))
    # scores equal the values for ssim/haarpsi (range 0..1) and for mdsi (0.5..0 maps 0.5(1-v) to v)
    a = s[s.cfa == "a"].drop_duplicates("demosaic").set_index("demosaic")["mean_score"]
    assert a["bilinear"] == pytest.approx(0.5) and a["pocs"] == pytest.approx(0.8)
    total_a = float(s[s.cfa == "a"]["total_score"].iloc[0])
    assert total_a == pytest.approx((0.5 + 0.8) / 2)           # mean of means: 0.65
    assert total_a != pytest.approx((0.9 + 0.5 + 0.1 + 0.8 + 0.8) / 5)  # grand mean: 0.62
    total_b = float(s[s.cfa == "b"]["total_score"].iloc[0])
    assert total_b == pytest.approx((0.6 + 0.6) / 2)
    assert int(s[s.cfa == "a"]["total_rank"].iloc[0]) == 1


# -- process --least-squares -----------------------------------------------------------------------

def test_process_least_squares_flag_is_a_plain_fit(tmp_path):
    """The default fit maps the scene white exactly onto its XYZ; the
    --least-squares one is the unconstrained fit and does not; the stored
    meta says which."""
    import json
    import sys

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from synthetic_raw import WHITE, synthetic_raw

    from cfa_mitsuba.cli import main
    from cfa_mitsuba.io.raw_npz import save_raw_npz

    refl = np.full((12, 12, WL.size), 1.0)
    raw_path = tmp_path / "raw.npz"
    save_raw_npz(raw_path, synthetic_raw(refl * WHITE, "cmy1"))
    metas = {}
    for flag in ((), ("--least-squares",)):
        out = tmp_path / f"out{len(flag)}.npz"
        assert main(["process", str(raw_path), "--out", str(out), *flag]) == 0
        with np.load(out, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            centre = z["xyz"][4:8, 4:8].reshape(-1, 3).mean(axis=0)
            metas[bool(flag)] = (meta["isp"], centre, z["white_xyz"])
    wp, centre_wp, white = metas[False]
    ls, centre_ls, _ = metas[True]
    assert wp["white_preserving"] is True and ls["white_preserving"] is False
    assert np.allclose(centre_wp, white, rtol=1e-6)         # white in, white out
    assert not np.allclose(centre_ls, white, rtol=1e-4)     # the plain fit misses it a little
    assert wp["colour_matrix"] != ls["colour_matrix"]


def test_process_precision_flag_reaches_the_demosaic(tmp_path):
    import json
    import sys

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from synthetic_raw import WHITE, synthetic_raw

    from cfa_mitsuba.cli import main
    from cfa_mitsuba.io.raw_npz import save_raw_npz

    rng = np.random.default_rng(2)
    raw_path = tmp_path / "raw.npz"
    save_raw_npz(raw_path, synthetic_raw((0.3 + 0.6 * rng.random((12, 12, 1))) * WHITE, "bayer"))
    got = {}
    for flag in ((), ("--precision", "single")):
        out = tmp_path / f"out{len(flag)}.npz"
        assert main(["process", str(raw_path), "--demosaic", "pocs", "--out", str(out), *flag]) == 0
        with np.load(out, allow_pickle=False) as z:
            got[len(flag)] = (json.loads(str(z["meta"]))["isp"]["demosaic_precision"], z["xyz"])
    assert got[0][0] == "double" and got[2][0] == "single"
    assert 0 < np.abs(got[2][1] - got[0][1]).max() < 1e-5 * np.abs(got[0][1]).max()


# -- the chain's shared optical image -----------------------------------------------------------------

def test_shared_optical_image_gives_the_numbers_of_a_fresh_one(monkeypatch):
    from cfa_mitsuba.study import chain as chain_mod
    from cfa_mitsuba.study.chain import CameraChain
    from cfa_mitsuba.study.conditions import Condition

    rng = np.random.default_rng(5)
    refl = rng.uniform(0.1, 0.9, (24, 24, 1)) * np.ones(WL.size)
    white = spectra.illuminant("D65", WL)
    white = white * 100.0 / spectra.luminance_cd_m2(white, WL)
    img = cm.SpectralImage(refl * white, WL.copy(), {"fov_deg": 10.0, "scene_distance_m": 1.2, "oversample": 1,
                                                     "white_radiance": white.tolist()})
    cond = Condition(luminance=100.0)
    ch = CameraChain()
    runs = []
    for key in ("scene-a", "scene-a", None):
        oi = ch.optical(img, cond, key)
        raw = ch.capture(oi, "bayer", cond, seed=7)
        runs.append((oi, raw.raw))
    assert runs[0][0] is runs[1][0]          # the second capture reused the first optical image
    assert runs[2][0] is not runs[0][0]      # no key: computed afresh
    assert np.array_equal(runs[0][1], runs[2][1]) and np.array_equal(runs[1][1], runs[2][1])
    monkeypatch.setenv(chain_mod.NO_MEMO_ENV, "1")
    assert ch.optical(img, cond, "scene-a") is not runs[0][0]


def test_shared_reference_work_gives_identical_values():
    """S-CIELAB's filtered reference and the reference's sRGB codes, computed
    once per ideal image and reused, give the numbers of a fresh computation."""
    rng = np.random.default_rng(8)
    white = D65_XYZ
    ideal = rng.uniform(5.0, 90.0, (40, 48, 3))
    shared: dict = {}
    geo = {"samples_per_degree": 12.0}
    for k in range(3):
        cam = ideal * rng.uniform(0.95, 1.05, ideal.shape)
        fresh = cm.metrics.MetricInputs(ideal, cam, white, geometry=geo)
        reused = cm.metrics.MetricInputs(ideal, cam, white, geometry=geo, shared=shared)
        for name in ("scielab", "ssim", "haarpsi"):
            assert float(cm.metrics.evaluate(name, reused)) == float(cm.metrics.evaluate(name, fresh)), name
    assert any(isinstance(key, tuple) and key[0] == "scielab" for key in shared)
    assert "srgb8_reference" in shared
