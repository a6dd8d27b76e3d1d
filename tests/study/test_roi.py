"""Regions of interest (study/roi.py): demosaicing and measuring only the
windows the metrics read gives the whole image's values bit for bit, on
every chart scene, every demosaic and CFAs of several tile sizes and
families; what needs the whole image turns the windows off."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.metrics import metrics_for_scene, result_rows
from cfa_mitsuba.study import roi
from cfa_mitsuba.study.chain import CameraChain, ChainSettings
from registry_checks import _quick_render_settings, _scene_of_kind

#: every demosaic of the package (a toy another test registers is not one: their module names them)
DEMOSAICS = tuple(name for name, _ in cm.isp.list_demosaics()
                  if cm.isp.get_demosaic_record(name).function.__module__.startswith("cfa_mitsuba.isp."))
#: 2x2 Bayer, 3x3 RGB, 4x4 RGBW, 6x6 X-Trans, and cmy2's 2x3 tile of six channels
CFAS = ("bayer", "rgb4", "rgbw2", "xtrans", "cmy2")
KINDS = ("macbeth", "slanted-edge", "chirp", "gray-bar")
#: POCS with its early stop off: a bounded support (with the stop on it is demosaiced whole); two
#: iterations, so that its windows stay smaller than these small images
LOCAL_POCS = (("pocs", (("iterations", 2), ("tolerance", 0.0))),)


#: renders taller than the quick study's where its camera image is too small for POCS's windows
SIZES = {"slanted-edge": {"width": 512, "height": 448}, "chirp": {"width": 500, "height": 320}}


def _image(kind: str):
    name = _scene_of_kind(kind)
    return cm.render.render_cached(name, **SIZES.get(kind, _quick_render_settings().get(name, {})))


def _evaluate(image, cfa, metrics, settings, cond, seed=7, demosaics=DEMOSAICS):
    chain = CameraChain(settings)
    out = {}
    # the chain memoises optical images by this key for the whole process: a key of the image's content, not
    # id(image), which a later image may reuse once this one is freed (a stale optical image of another scene)
    key = ("roi-test", hashlib.sha256(np.ascontiguousarray(image.data).tobytes()).hexdigest())
    for _, _, method, ev in chain.evaluate(image, cfa, demosaics, metrics, cond, seed, key,
                                           details=False):
        assert hasattr(ev, "results"), ev
        out[method] = (result_rows(ev.results), ev.failures, ev.processed)
    return out


@pytest.mark.parametrize("kind", KINDS)
def test_windows_give_the_whole_images_values_to_the_last_bit(kind, monkeypatch):
    # windows free of their fixed cost: used on these small images too, one per region (the values
    # cannot depend on how the windows are cut, which this cuts as finely as it can)
    monkeypatch.setattr(roi, "WINDOW_COST_PX", 0)
    image = _image(kind)
    metrics = list(metrics_for_scene(kind))
    whole_settings = ChainSettings(mean_match=False, roi=False, demosaic_options=LOCAL_POCS)
    roi_settings = ChainSettings(mean_match=False, demosaic_options=LOCAL_POCS)
    cond = whole_settings.base_condition(luminance=100.0, seed=1)
    for cfa in CFAS:
        whole = _evaluate(image, cfa, metrics, whole_settings, cond)
        part = _evaluate(image, cfa, metrics, roi_settings, cond)
        for method in DEMOSAICS:
            rows_w, failed_w, proc_w = whole[method]
            rows_r, failed_r, proc_r = part[method]
            windows = proc_r.meta.get("roi", {}).get("windows")
            # the windows were used, and are smaller than the image; POCS on a luminance reference (no single
            # densest channel: rgb4, cmy2) declares no support and is demosaiced whole
            if cm.isp.get_demosaic_record(method).support(cm.sensor.get_cfa(cfa), dict(LOCAL_POCS[0][1])) is None:
                assert method == "pocs" and cfa in ("rgb4", "cmy2") and windows is None
                continue
            assert windows, (kind, cfa, method)
            h, w = proc_r.xyz.shape[:2]
            assert sum((b[2] - b[0]) * (b[3] - b[1]) for b in windows) < h * w
            th, tw = cm.sensor.get_cfa(cfa).pattern.shape
            assert all(b[0] % th == 0 and b[1] % tw == 0 for b in windows), windows  # the tile's phase kept
            assert rows_r == rows_w and failed_r == failed_w, (kind, cfa, method)
            assert "roi" not in proc_w.meta


def test_windows_with_a_local_denoiser_and_sharpener_give_the_whole_images_values(monkeypatch):
    """nl-means (raw domain: its reach in tile periods) and the unsharp mask
    after the colour matrix add their declared reach to the margin; the
    values stay the whole image's to the last bit."""
    monkeypatch.setattr(roi, "WINDOW_COST_PX", 0)
    image = _image("slanted-edge")
    metrics = list(metrics_for_scene("slanted-edge"))
    isp = {"denoise": "nl-means", "sharpen": "unsharp"}
    whole_settings = ChainSettings(mean_match=False, roi=False, isp=isp)
    roi_settings = ChainSettings(mean_match=False, isp=isp)
    cond = roi_settings.base_condition(luminance=100.0, seed=1)
    for cfa in ("bayer", "rgbw1"):  # 2 x 2 tiles: nl-means's reach (16 px on them) leaves windows this small image
        whole = _evaluate(image, cfa, metrics, whole_settings, cond, demosaics=("bilinear", "laplacian"))
        part = _evaluate(image, cfa, metrics, roi_settings, cond, demosaics=("bilinear", "laplacian"))
        for method, (rows_r, failed_r, proc_r) in part.items():
            assert proc_r.meta.get("roi", {}).get("windows"), (cfa, method)
            assert (rows_r, failed_r) == whole[method][:2], (cfa, method)


def test_macbeth_windows_are_the_patches_and_the_supports_margin(monkeypatch):
    """The patches' windows: each patch interior widened by the method's
    declared support and aligned outwards on the tile grid, merged where
    their box costs no more than the two (a window's fixed cost counted as
    ``WINDOW_COST_PX`` pixels)."""
    geometry = {"patches": [(10, 10, 20, 20), (10, 400, 20, 410), (10, 23, 20, 25)]}
    regions = cm.metrics.get_metric("delta-e").reads(geometry, (600, 800), {})
    assert roi.windows(regions, 3, (600, 800), (6, 6)) == [(6, 6, 24, 414)]  # one window costs less than two
    monkeypatch.setattr(roi, "WINDOW_COST_PX", 0)
    got = roi.windows(regions, 3, (600, 800), (6, 6))
    assert got == [(6, 6, 24, 30), (6, 396, 24, 414)]  # the first and third merged; the second too far
    assert roi.windows([(0, 775, 3, 800)], 2, (600, 800), (4, 4)) == [(0, 772, 8, 800)]  # clipped at the edge
    # a row across the image and a column band stay apart where their box would cost more than the two
    cross = roi.windows([(300, 0, 301, 800), (2, 400, 598, 406)], 1, (600, 800), (2, 2))
    assert cross == [(0, 398, 600, 408), (298, 0, 302, 800)]
    assert roi.core((298, 0, 302, 800), 1, (600, 800)) == (299, 0, 301, 800)  # in by the margin, not at the edges


@pytest.mark.parametrize("cfa", ("bayer", "xtrans"))
def test_support_grows_with_pocs_iterations_and_is_whole_with_its_early_stop(cfa):
    rec = cm.isp.get_demosaic_record("pocs")
    c = cm.sensor.get_cfa(cfa)
    r5, r10 = rec.support(c, {"tolerance": 0.0, "iterations": 5}), rec.support(c, {"tolerance": 0.0, "iterations": 10})
    assert 0 < r5 < r10 and (r10 - r5) % 5 == 0  # the low-pass half-length per iteration
    assert rec.support(c, {}) is None  # the default early stop reads the whole image
    assert cm.isp.get_demosaic_record("bilinear").support(c, {}) >= 1


def test_what_needs_the_whole_image_turns_the_windows_off(monkeypatch):
    """Mean-matching (every shipped config), a denoiser, kept details, a
    natural scene's metrics and the switch itself each give the whole image."""
    monkeypatch.setattr(roi, "WINDOW_COST_PX", 0)
    image = _image("macbeth")
    metrics = list(metrics_for_scene("macbeth"))

    def windows_of(settings, details=False, names=metrics, method="bilinear"):
        cond = settings.base_condition(luminance=100.0, seed=1)  # the settings' own ISP axes
        chain = CameraChain(settings)
        oi = chain.optical(image, cond)
        ideal = chain.ideal(oi, cond)
        prepared = chain.prepare(chain.capture(oi, "bayer", cond, 3), method, cond)
        return roi.plan(chain, prepared, method, cond, ideal, names, details=details)

    assert windows_of(ChainSettings(mean_match=False))[0] == 1  # bilinear's margin on Bayer
    assert windows_of(ChainSettings()) is None  # mean-matching reads the whole output
    assert windows_of(ChainSettings(mean_match=False, roi=False)) is None
    assert windows_of(ChainSettings(mean_match=False), details=True) is None
    assert windows_of(ChainSettings(mean_match=False, isp={"denoise": "wavelet"})) is None  # global
    local = windows_of(ChainSettings(mean_match=False, isp={"denoise": "nl-means", "sharpen": "unsharp"}))
    assert local[0] > 1  # bilinear's margin plus the denoiser's and the sharpener's reach
    assert windows_of(ChainSettings(mean_match=False), names=["scielab"]) is None
    assert windows_of(ChainSettings(mean_match=False), method="pocs") is None  # its early stop
    assert roi.blocked_by(ChainSettings(mean_match=False), {}, _Prepared(), details=False) is None


class _Prepared:
    readout = {"mode": "full"}
    cfa = cm.sensor.get_cfa("bayer")
