"""Bayer demosaicing against independent oracles: colour-demosaicing 0.2.7
(bilinear, Malvar2004) and a loop-by-loop Hamilton-Adams written here from
the patent's formulas; PSNR ordering on crops of real photographs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.sensor.cfa import builtin_filter_curve, make_cfa

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import colour_demosaicing as cdm

PHASES = ("RGGB", "BGGR", "GRBG", "GBRG")


def bayer(pattern: str):
    tile = f"{pattern[0]} {pattern[1]} / {pattern[2]} {pattern[3]}"
    return make_cfa(f"bayer-{pattern.lower()}", tile, {c: builtin_filter_curve(c) for c in "RGB"})


@pytest.mark.parametrize("pattern", PHASES)
@pytest.mark.parametrize("shape", [(17, 22), (32, 41)])
def test_bilinear_equals_colour_demosaicing(pattern, shape):
    raw = np.random.default_rng(1).random(shape)
    ours = cm.isp.demosaic(raw, bayer(pattern), "bilinear")
    theirs = cdm.demosaicing_CFA_Bayer_bilinear(raw, pattern)
    assert np.abs(ours - theirs)[1:-1, 1:-1].max() <= 1e-12


@pytest.mark.parametrize("pattern", PHASES)
def test_laplacian_green_equals_malvar2004(pattern):
    raw = np.random.default_rng(2).random((21, 26))
    ours = cm.isp.demosaic(raw, bayer(pattern), "laplacian")
    theirs = cdm.demosaicing_CFA_Bayer_Malvar2004(raw, pattern)
    assert np.abs(ours[..., 1] - theirs[..., 1])[2:-2, 2:-2].max() <= 1e-12


def _hamilton_adams(raw, pattern, g):
    """Hamilton-Adams (US 5,629,734) as ISETCam's AdaptiveLaplacian.m, loop
    by loop, with the colour-difference gain g; interior pixels only."""
    h, w = raw.shape
    tile = np.array(list(pattern)).reshape(2, 2)
    ch = np.vectorize(lambda r, c: tile[r % 2, c % 2])(*np.indices((h, w)))
    y = raw
    G = np.where(ch == "G", y, np.nan)
    for i in range(2, h - 2):
        for j in range(2, w - 2):
            if ch[i, j] == "G":
                continue
            dh = abs(y[i, j - 1] - y[i, j + 1]) + abs(2 * y[i, j] - y[i, j - 2] - y[i, j + 2])
            dv = abs(y[i - 1, j] - y[i + 1, j]) + abs(2 * y[i, j] - y[i - 2, j] - y[i + 2, j])
            eh = (y[i, j - 1] + y[i, j + 1]) / 2 + (2 * y[i, j] - y[i, j - 2] - y[i, j + 2]) / 4
            ev = (y[i - 1, j] + y[i + 1, j]) / 2 + (2 * y[i, j] - y[i - 2, j] - y[i + 2, j]) / 4
            G[i, j] = eh if dh < dv else ev if dv < dh else (eh + ev) / 2
    out = {"G": G}
    for X in "RB":
        P = np.where(ch == X, y, np.nan)
        for i in range(3, h - 3):
            for j in range(3, w - 3):
                if ch[i, j] == X:
                    continue
                if ch[i, j] == "G":  # the two X neighbours on the row or the column
                    pairs = [((i, j - 1), (i, j + 1))] if ch[i, j - 1] == X else [((i - 1, j), (i + 1, j))]
                    (a, b), = pairs
                    P[i, j] = (y[a] + y[b]) / 2 + g * (G[i, j] - (G[a] + G[b]) / 2)
                    continue
                est, cost = [], []
                for a, b in (((i - 1, j - 1), (i + 1, j + 1)), ((i - 1, j + 1), (i + 1, j - 1))):
                    est.append((y[a] + y[b]) / 2 + g * (G[i, j] - (G[a] + G[b]) / 2))
                    cost.append(abs(y[a] - y[b]) + abs(2 * G[i, j] - G[a] - G[b]))
                P[i, j] = est[0] if cost[0] < cost[1] else est[1] if cost[1] < cost[0] else sum(est) / 2
        out[X] = P
    return np.stack([out["R"], out["G"], out["B"]], axis=-1)


@pytest.mark.parametrize("pattern", PHASES)
@pytest.mark.parametrize("g", [1.0, 0.5])
def test_adaptive_hard_is_hamilton_adams(pattern, g):
    rng = np.random.default_rng(3)
    # Quantised values make exact direction ties happen, as in 8-bit images.
    raw = np.round(rng.random((16, 18)) * 8) / 8
    ours = cm.isp.demosaic(raw, bayer(pattern), "adaptive-laplacian", weighting="hard", chroma_gain=g)
    ref = _hamilton_adams(raw, pattern, g)
    assert np.abs(ours - ref)[4:-4, 4:-4].max() <= 1e-12


# --- photographs ----------------------------------------------------------------

CROPS = {
    "astronaut": (slice(0, 160), slice(100, 260)),
    "coffee": (slice(100, 260), slice(200, 360)),
    "chelsea": (slice(60, 220), slice(120, 280)),
    "rocket": (slice(150, 310), slice(250, 410)),
}


@pytest.fixture(scope="module")
def photos():
    import skimage.data

    return {name: getattr(skimage.data, name)()[rows, cols] / 255.0 for name, (rows, cols) in CROPS.items()}


def psnr_of(truth, out, border=6):
    from skimage.metrics import peak_signal_noise_ratio

    return peak_signal_noise_ratio(truth[border:-border, border:-border], out[border:-border, border:-border],
                                   data_range=1.0)


@pytest.mark.parametrize("name", list(CROPS))
def test_bayer_psnr_ordering_on_photographs(photos, name):
    img = photos[name]
    raw = cm.isp.mosaic_image(img, "bayer")
    def p(m):
        return psnr_of(img, cm.isp.demosaic(raw, "bayer", m))

    bilinear, laplacian, adaptive, pocs = p("bilinear"), p("laplacian"), p("adaptive-laplacian"), p("pocs")
    assert bilinear < laplacian < adaptive, (bilinear, laplacian, adaptive)
    assert pocs > laplacian, (pocs, laplacian)


def test_hamilton_adams_soft_beats_hard_on_average(photos):
    """The default soft weighting is there because it measures better."""
    gains = []
    for img in photos.values():
        raw = cm.isp.mosaic_image(img, "bayer")
        soft = psnr_of(img, cm.isp.demosaic(raw, "bayer", "adaptive-laplacian"))
        hard = psnr_of(img, cm.isp.demosaic(raw, "bayer", "adaptive-laplacian", weighting="hard"))
        gains.append(soft - hard)
    assert np.mean(gains) > 0.2, gains
