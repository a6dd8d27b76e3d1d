"""The gradient-corrected methods (isp/laplacian.py) against independent
oracles on every Bayer phase: the Laplacian's green is colour-demosaicing's
Malvar2004, the edge-directed method with hard weights is Hamilton-Adams as a
loop-by-loop transcription of the patent's formulas (ISETCam's
AdaptiveLaplacian.m) written here."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from bayer_phases import PHASES, bayer, cdm


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
