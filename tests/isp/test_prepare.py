"""``isp.prepare``: the part of processing every demosaicing method shares,
done once per capture (issue 25).  Processing a prepared capture gives the
same bits as processing the capture; a study prepares each capture once for
its four methods."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.sensor import SensorParams
from synthetic_raw import WHITE, WL, synthetic_raw

#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in cm.isp.list_demosaics())


def _noisy(cfa, *, readout="full", seed=3):
    """A noisy capture of a small two-tone scene (a real capture: sensor.capture)."""
    scene = np.broadcast_to(0.2 * WHITE, (24, 24, WL.size)).copy()
    scene[:, 12:] *= 3.0
    oi = cm.optics.compute_optics(cm.values.SpectralImage(scene, WL.copy(), {"scene": "two-tone", "fov_deg": 2.0,
                                                                             "white_radiance": WHITE.tolist()}))
    return cm.sensor.capture(oi, cfa, luminance_cd_m2=20.0, seed=seed, sensor=SensorParams(readout=readout))


def _same(a, b):
    assert np.array_equal(a.xyz, b.xyz)
    assert np.array_equal(a.white_xyz, b.white_xyz)
    assert a.meta == b.meta


@pytest.mark.parametrize("cfa,readout", [("bayer", "full"), ("rgbw1", "full"), ("cmy2", "full"),
                                         ("quad-bayer", "remosaic"), ("quad-bayer", "bin")])
def test_processing_a_prepared_capture_is_processing_the_capture(cfa, readout):
    raw = _noisy(cfa, readout=readout)
    for kw in ({}, {"white_balance": "gray-world", "regularise": False},
               {"clip_highlights": False, "colour_fit": "mcc", "white_preserving": False}):
        prepared = cm.isp.prepare(raw, **kw)
        for method in METHODS:
            _same(cm.isp.process_prepared(prepared, method, demosaic_precision="single"),
                  cm.isp.process(raw, method, demosaic_precision="single", **kw))
    # options of the method go through, as with process
    _same(cm.isp.process_prepared(cm.isp.prepare(raw), "pocs", iterations=2),
          cm.isp.process(raw, "pocs", iterations=2))


def test_a_clipped_capture_prepares_the_same():
    raw = synthetic_raw(np.broadcast_to(0.9 * WHITE, (12, 12, WL.size)), "cmy2", peak_e=5e6)
    raw.raw = np.minimum(raw.raw, 2**12 - 1)
    prepared = cm.isp.prepare(raw)
    assert prepared.clipped > 0
    _same(cm.isp.process_prepared(prepared, "laplacian"), cm.isp.process(raw, "laplacian"))


def test_the_prepared_mosaic_cannot_be_changed_and_bad_input_is_refused():
    raw = _noisy("bayer")
    prepared = cm.isp.prepare(raw)
    with pytest.raises(ValueError):
        prepared.balanced[0, 0] = 1.0
    with pytest.raises(ValueError):
        prepared.luminance_weights[0] = 1.0
    with pytest.raises(CfaMitsubaError, match="PreparedRaw"):
        cm.isp.process_prepared(raw, "bilinear")
    with pytest.raises(CfaMitsubaError, match="unknown white balance"):
        cm.isp.prepare(raw, white_balance="daylight")
    with pytest.raises(CfaMitsubaError, match="unknown demosaic precision"):
        cm.isp.process_prepared(prepared, "bilinear", demosaic_precision="half")
    with pytest.raises(CfaMitsubaError, match="gamut_check"):
        cm.isp.process_prepared(prepared, "bilinear", gamut_check="yes")
    ideal = cm.sensor.capture_ideal(cm.optics.compute_optics(cm.values.SpectralImage(
        np.broadcast_to(0.2 * WHITE, (8, 8, WL.size)).copy(), WL.copy(), {"scene": "grey", "fov_deg": 2.0})),
        luminance_cd_m2=20.0)
    with pytest.raises(CfaMitsubaError, match="ideal sensor"):
        cm.isp.prepare(ideal)
    assert set(cm.isp.PREPARE_KEYWORDS) == {"white_balance", "white_preserving", "regularise", "clip_highlights",
                                           "colour_fit"}


def test_the_study_chain_prepares_each_capture_once(monkeypatch):
    """CameraChain.evaluate prepares a capture once for all its methods, and
    each output is the one processing the capture by that method gives."""
    from cfa_mitsuba.isp import pipeline
    from cfa_mitsuba.study.chain import CameraChain, ChainSettings
    from cfa_mitsuba.study.conditions import Condition

    calls = []
    real = pipeline.prepare
    monkeypatch.setattr(pipeline, "prepare", lambda *a, **k: calls.append(1) or real(*a, **k))
    monkeypatch.setattr(cm.isp, "prepare", pipeline.prepare)
    scene = np.broadcast_to(0.2 * WHITE, (24, 24, WL.size)).copy()
    scene[:, 12:] *= 3.0
    image = cm.values.SpectralImage(scene, WL.copy(), {"scene": "two-tone", "fov_deg": 2.0,
                                                       "white_radiance": WHITE.tolist()})
    chain = CameraChain(ChainSettings(isp=(("white_balance", "gray-world"),)))
    cond = Condition(20.0)
    outs = list(chain.evaluate(image, "rgbw2", list(METHODS), ["ssim"], cond, seed=4))
    assert len(calls) == 1 and [o[2] for o in outs] == list(METHODS)
    raw = outs[0][0]
    for _, _, method, ev in outs:
        direct = cm.isp.process(raw, method, white_balance="gray-world", demosaic_precision="single",
                                gamut_check=False)
        _same(ev.processed, direct)
