"""What every two-image metric shares: the ideal values on identical images,
a result that is a float with its unit and details (and pickles), one-line
refusals of bad or extreme input, the registry's order and the scene
geometry each reads.  Each metric's own known answers and reference values
are in its file (tests/metrics/test_<metric>.py)."""

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
