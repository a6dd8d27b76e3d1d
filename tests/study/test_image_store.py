"""The study's store of optical images (study/image_store.py): made once,
read back bit for bit by another chain (another worker), atomic, emptied
when a study starts, and never trusted when unreadable."""

from __future__ import annotations

import numpy as np

import cfa_mitsuba as cm
from cfa_mitsuba.study import chain as chain_module, image_store
from cfa_mitsuba.study.chain import CameraChain, ChainSettings


def _scene():
    return cm.render.render_cached("gray-bar", width=64, height=48)


def _fresh_memo(monkeypatch):
    """A new process's memo (a worker that has made no optical image)."""
    monkeypatch.setattr(chain_module, "_OPTICAL", chain_module._Memo(2))


def test_a_second_worker_reads_the_first_ones_optical_image_bit_for_bit(tmp_path, monkeypatch):
    store = image_store.fresh(tmp_path / ".work")
    first = CameraChain(image_store=str(store))
    cond = first.settings.base_condition(luminance=30.0)
    _fresh_memo(monkeypatch)
    made = first.optical(_scene(), cond, scene_key="gray-bar-64")
    assert len(list(store.glob("optical-*.npz"))) == 1 and not list(store.glob(".part-*"))

    _fresh_memo(monkeypatch)  # another worker: it must not compute the optics again

    def refuse(*a, **k):
        raise AssertionError("the optical image was computed again")

    monkeypatch.setattr(cm.optics, "compute_optics", refuse)
    got = CameraChain(image_store=str(store)).optical(_scene(), cond, scene_key="gray-bar-64")
    for name in ("irradiance_w_m2_nm", "wavelengths", "pixel_irradiance_w_m2_nm"):
        a, b = getattr(made, name), getattr(got, name)
        assert (a is None and b is None) or (a.dtype == b.dtype and np.array_equal(a, b)), name
    assert got.sample_pitch_um == made.sample_pitch_um and got.meta == made.meta
    # other optics are another image: computed, not read
    other = CameraChain(ChainSettings(optics=cm.optics.OpticsParams(f_number=8.0)),
                        image_store=str(store))
    monkeypatch.undo()
    _fresh_memo(monkeypatch)
    other.optical(_scene(), other.settings.base_condition(luminance=30.0), scene_key="gray-bar-64")
    assert len(list(store.glob("optical-*.npz"))) == 2


def test_the_ideal_image_is_read_back_bit_for_bit(tmp_path, monkeypatch):
    store = image_store.fresh(tmp_path / ".work")
    chain = CameraChain(image_store=str(store))
    cond = chain.settings.base_condition(luminance=30.0)
    monkeypatch.setattr(chain_module, "_IDEAL", chain_module._Memo(4))
    oi = chain.optical(_scene(), cond, scene_key="k")
    made = chain.ideal(oi, cond, scene_key="k")
    assert len(list(store.glob("ideal-*.npz"))) == 1
    monkeypatch.setattr(chain_module, "_IDEAL", chain_module._Memo(4))
    monkeypatch.setattr(cm.sensor, "capture_ideal", lambda *a, **k: (_ for _ in ()).throw(AssertionError("again")))
    got = CameraChain(image_store=str(store)).ideal(oi, cond, scene_key="k")
    for name in ("xyz", "srgb", "white_xyz"):
        assert np.array_equal(getattr(got, name), getattr(made, name)), name
    assert got.meta == made.meta and not got.xyz.flags.writeable


def test_a_broken_file_is_made_again_and_a_study_start_empties_the_store(tmp_path, monkeypatch):
    store = image_store.fresh(tmp_path / ".work")
    chain = CameraChain(image_store=str(store))
    cond = chain.settings.base_condition(luminance=30.0)
    _fresh_memo(monkeypatch)
    made = chain.optical(_scene(), cond, scene_key="k")
    (path,) = store.glob("optical-*.npz")
    path.write_bytes(path.read_bytes()[:100])  # half a file
    _fresh_memo(monkeypatch)
    again = CameraChain(image_store=str(store)).optical(_scene(), cond, scene_key="k")
    assert np.array_equal(again.irradiance_w_m2_nm, made.irradiance_w_m2_nm)
    assert path.stat().st_size > 100  # written whole again
    assert image_store.fresh(tmp_path / ".work") == store and not store.exists()
