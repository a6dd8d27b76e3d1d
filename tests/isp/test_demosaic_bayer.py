"""The paper's methods on Bayer compared on crops of real photographs (PSNR
ordering; soft edge-directed weights against hard).  Each method against its
independent oracle: tests/isp/test_bilinear.py, test_laplacian.py."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm


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
