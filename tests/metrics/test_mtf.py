"""Acceptance 2: Gaussian-blurred slanted edges give the analytic MTF50 within
1 % between 3 and 10 degrees of slant, either orientation and polarity."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import erf

import cfa_mitsuba.metrics as cm
from cfa_mitsuba.errors import CfaMitsubaError
from reference_data import EXPECTED, EDGES, edge_image

MTF50_TIMES_SIGMA = np.sqrt(np.log(2.0) / 2.0) / np.pi  # 0.187390 cy/px x sigma


def blurred_edge(angle_deg, sigma_px, *, h=128, w=96, dark=0.2, bright=0.8):
    """Ideal step blurred by a Gaussian PSF, sampled at pixel centres."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    t = np.radians(angle_deg)
    d = (x - (w - 1) / 2.0) * np.cos(t) - (y - (h - 1) / 2.0) * np.sin(t)
    return dark + (bright - dark) * 0.5 * (1.0 + erf(d / (np.sqrt(2.0) * sigma_px)))


@pytest.mark.parametrize("angle", [3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0])
@pytest.mark.parametrize("sigma", [0.7, 1.0, 1.5, 2.3])
def test_gaussian_edge_mtf50_within_1_percent(angle, sigma):
    r = cm.mtf(blurred_edge(angle, sigma))
    assert float(r) == pytest.approx(MTF50_TIMES_SIGMA / sigma, rel=0.01)
    assert r.details["edge_angle_deg"] == pytest.approx(angle, abs=0.05)


@pytest.mark.parametrize("transform", ["horizontal", "mirrored", "negative_slope_horizontal", "bright_left"])
def test_orientation_and_polarity_do_not_matter(transform):
    img = blurred_edge(6.0, 1.2)
    img = {"horizontal": img.T, "mirrored": img[:, ::-1], "negative_slope_horizontal": img[::-1].T,
           "bright_left": 1.0 - img}[transform]
    r = cm.mtf(img)
    assert float(r) == pytest.approx(MTF50_TIMES_SIGMA / 1.2, rel=1e-3)  # measured 0.023 % off
    assert r.details["orientation"] == ("horizontal" if "horizontal" in transform else "vertical")


def test_rgb_edge_luminance_is_weighted_on_the_image():
    sigmas = (0.9, 1.2, 1.8)
    img = np.stack([blurred_edge(5.0, s) for s in sigmas], axis=-1)
    r = cm.mtf(img)
    w = (0.3, 0.6, 0.1)
    lum = brentq(lambda f: sum(wc * np.exp(-2 * np.pi**2 * s**2 * f**2) for wc, s in zip(w, sigmas)) - 0.5, 0.01, 0.5)
    assert float(r) == pytest.approx(lum, rel=0.01)
    for name, s in zip("RGB", sigmas):
        assert r.details["records"][name]["mtf50_cy_px"] == pytest.approx(MTF50_TIMES_SIGMA / s, rel=0.01)
    assert 0 < r.details["percent_alias"] < 100
    assert 0 <= r.details["mtf_at_nyquist"] < 0.5


def test_edge_found_in_a_larger_image_and_roi_respected():
    big = np.full((300, 400), 0.2)
    big[50:250, 100:300] = blurred_edge(5.0, 1.0, h=200, w=200)
    big[50:250, 300:] = 0.8
    r = cm.mtf(big, roi=(50, 100, 250, 300))
    assert float(r) == pytest.approx(MTF50_TIMES_SIGMA, rel=0.01)


def test_sharp_edge_gives_finite_values():
    r = cm.mtf(blurred_edge(5.0, 0.05))
    assert np.isfinite(float(r)) and float(r) > 0.3


@pytest.mark.parametrize("img,needle", [
    (np.full((64, 64), 0.5), "no edge"),
    (np.random.default_rng(0).random((64, 64)), "edge"),
    (blurred_edge(0.0, 1.0), "too close"),
])
def test_edge_that_cannot_be_analysed_is_a_clear_error(img, needle):
    with pytest.raises(CfaMitsubaError, match=needle):
        cm.mtf(img)


def test_a_channel_without_an_edge_uses_the_luminance_fit():
    img = np.stack([blurred_edge(5.0, 1.0), blurred_edge(5.0, 1.0), np.full((128, 96), 0.5)], axis=-1)
    r = cm.mtf(img)
    assert r.details["records"]["R"]["mtf50_cy_px"] == pytest.approx(MTF50_TIMES_SIGMA, rel=0.01)
    assert np.isfinite(float(r))
    assert r.details["records"]["B"]["mtf50_cy_px"] is None and "error" in r.details["records"]["B"]


def test_bad_pitch_and_roi_are_refused():
    with pytest.raises(CfaMitsubaError, match="pitch"):
        cm.mtf(blurred_edge(5.0, 1.0), pixel_pitch_um=-1.0)
    with pytest.raises(CfaMitsubaError, match="outside"):
        cm.mtf(blurred_edge(5.0, 1.0), roi=(0, 0, 500, 50))


# -- reference values (tests/data/reference/expected.json: the authors' own code) ---------------

# -- MTF (sfrmat3 primary, sfrmat5 second check, analytic sanity check) ------------------------



@pytest.mark.parametrize("eid", EDGES)
def test_mtf_matches_sfrmat(eid):
    p = EXPECTED["slanted_edges"][eid]
    r = cm.mtf(edge_image(eid))
    for e in p["mtf"]:
        if e["variant"] not in ("sfrmat3", "sfrmat5|npol=5"):
            continue
        for rec, want in e["value"].items():
            if not isinstance(want, dict) or "mtf50" not in want:
                continue
            mine = r.details["records"][rec]
            # measured: 0.14 % at worst (the README allows 1 %); 0.3 % catches a real change
            assert mine["mtf50_cy_px"] == pytest.approx(want["mtf50"], rel=0.003), (e["variant"], rec)
            sfr = np.interp(e["value"]["sfr_freqs"], mine["freq_cy_px"], mine["mtf"])
            assert np.max(np.abs(sfr - want["sfr_at"])) <= 0.01, (e["variant"], rec)
    noisy = "noise" in eid
    for rec, want in p["analytic"].items():
        if isinstance(want, dict) and "mtf50" in want:
            got = r.details["records"][rec]["mtf50_cy_px"]
            assert got == pytest.approx(want["mtf50"], rel=0.02 if noisy else 0.01), rec
    assert r.details["edge_angle_deg"] == pytest.approx(p["angle_deg"], abs=0.1)


def test_mtf_headline_is_luminance_mtf50_in_cy_per_px_or_mm():
    img = edge_image("edge_05deg_rgb")
    r = cm.mtf(img)
    assert r.unit == "cy/px" and float(r) == r.details["records"]["lum"]["mtf50_cy_px"]
    mm = cm.mtf(img, pixel_pitch_um=2.2)
    assert mm.unit == "cy/mm" and float(mm) == pytest.approx(float(r) / 2.2e-3)
