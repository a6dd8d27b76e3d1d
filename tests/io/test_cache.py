"""The render cache: keys, reuse, rescaling, locking, atomic entries
(issue 2 acceptance 6)."""

import multiprocessing
import time

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.io.cache import RenderCache, hash_key
from cfa_mitsuba.values import SpectralImage

SMALL = dict(width=64, height=48)


def test_key_covers_what_determines_the_render():
    base = cm.render.cache_key("macbeth", **SMALL)
    assert base == cm.render.cache_key("macbeth", **SMALL, seed=0, spp=16)  # the defaults, spelled out
    assert base == cm.render.cache_key("macbeth", **SMALL, luminance=3.0)  # luminance only rescales
    others = [
        cm.render.cache_key("chirp", **SMALL),
        cm.render.cache_key("macbeth", width=64, height=40),
        cm.render.cache_key("macbeth", **SMALL, seed=1),
        cm.render.cache_key("macbeth", **SMALL, spp=64),
        cm.render.cache_key("macbeth", **SMALL, bands="400:700:20"),
        cm.render.cache_key("macbeth", **SMALL, variant="scalar_spectral"),
        cm.render.cache_key("macbeth", **SMALL, oversample=2),
        cm.render.cache_key("macbeth", **SMALL, fov=20),
    ]
    assert len({base, *others}) == len(others) + 1
    assert hash_key({"a": 1, "b": [1, 2]}) == hash_key({"b": [1, 2], "a": 1})


def test_second_call_reuses_and_rescales(tmp_path):
    first = cm.render.render_cached("gray-bar", cache=tmp_path, **SMALL)
    assert first.meta["cache_reused"] is False
    entries = list((tmp_path / "renders").rglob("*.exr"))
    assert len(entries) == 1 and entries[0].stem == first.meta["cache_key"]
    second = cm.render.render_cached("gray-bar", cache=tmp_path, luminance=40.0, **SMALL)
    assert second.meta["cache_reused"] is True
    np.testing.assert_allclose(second.data, first.data * 0.4, rtol=1e-12)
    assert second.meta["render_time_s"] == first.meta["render_time_s"]
    # A cached render is the same numbers as a fresh one.
    fresh = cm.render.render("gray-bar", **SMALL)
    np.testing.assert_array_equal(fresh.data, first.data)


def test_unreadable_entry_is_rendered_again(tmp_path):
    key = cm.render.cache_key("gray-bar", **SMALL)
    cache = RenderCache(tmp_path)
    cache.path(key).parent.mkdir(parents=True)
    cache.path(key).write_bytes(b"garbage")
    img = cm.render.render_cached("gray-bar", cache=cache, **SMALL)
    assert img.meta["cache_reused"] is False
    assert cm.render.render_cached("gray-bar", cache=cache, **SMALL).meta["cache_reused"] is True


def test_unwritable_cache_is_a_clear_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(CfaMitsubaError, match="render cache"):
        cm.render.render_cached("gray-bar", cache=blocker / "cache", **SMALL)


def _slow_make(marker):
    def make():
        with open(marker, "a") as fh:
            fh.write("rendered\n")
        time.sleep(1.0)
        return SpectralImage(np.ones((2, 2, 3)), np.array([450.0, 500.0, 550.0]), {"scene": "x"})
    return make


def _worker(root, marker, queue):
    image, reused = RenderCache(root).get_or_create("k" * 32, _slow_make(marker))
    queue.put(reused)


def test_concurrent_callers_render_once(tmp_path):
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    marker = tmp_path / "marker"
    procs = [ctx.Process(target=_worker, args=(tmp_path / "c", marker, queue)) for _ in range(3)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(30)
    reused = sorted(queue.get(timeout=5) for _ in procs)
    assert marker.read_text().count("rendered") == 1
    assert reused == [False, True, True]
