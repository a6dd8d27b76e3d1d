"""The raw .npz: a lossless round trip of every RawImage field, atomic
writes, one-line refusals of files that are not ours."""

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.io import load_raw_npz, save_raw_npz
from cfa_mitsuba.values import SpectralImage


@pytest.fixture(scope="module")
def raws():
    data = np.random.default_rng(0).uniform(0.005, 0.02, (12, 16, 31))
    scene = SpectralImage(data, cm.spectra.DEFAULT_WAVELENGTHS, {"fov_deg": 12.0, "scene_distance_m": "inf",
                                                                 "geometry": {"edge": [1.5, 2.5]}})
    oi = cm.optics.compute_optics(scene)
    return {"cmy2": cm.sensor.capture(oi, "cmy2", seed=7), "ideal": cm.sensor.capture_ideal(oi)}


@pytest.mark.parametrize("which", ["cmy2", "ideal"])
def test_round_trip_keeps_every_field(raws, tmp_path, which):
    raw = raws[which]
    p = save_raw_npz(tmp_path / "r.npz", raw)
    back = load_raw_npz(p)
    for name in ("raw", "pattern", "spectra", "wavelengths", "electrons_per_radiance", "white_radiance"):
        np.testing.assert_array_equal(getattr(back, name), getattr(raw, name))
    assert back.channels == raw.channels
    for name in ("exposure_s", "dn_per_electron", "black_level_dn", "seed"):
        assert getattr(back, name) == getattr(raw, name)
    assert back.settings["cfa"] == raw.settings["cfa"]
    assert back.meta["geometry"] == {"edge": [1.5, 2.5]}
    assert back.meta["optics"]["scene_distance_m"] == "inf"
    assert back.is_ideal == raw.is_ideal


def test_refusals(raws, tmp_path):
    with pytest.raises(CfaMitsubaError, match=".npz"):
        save_raw_npz(tmp_path / "r.raw", raws["cmy2"])
    with pytest.raises(CfaMitsubaError, match="does not exist"):
        load_raw_npz(tmp_path / "none.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(CfaMitsubaError, match="not a valid .npz"):
        load_raw_npz(tmp_path / "junk.npz")
    np.savez(tmp_path / "other.npz", raw=np.zeros(3))
    with pytest.raises(CfaMitsubaError, match="not a cfa-mitsuba raw file"):
        load_raw_npz(tmp_path / "other.npz")


def test_failed_write_leaves_nothing(raws, tmp_path, monkeypatch):
    def boom(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "savez_compressed", boom)
    with pytest.raises(OSError):
        save_raw_npz(tmp_path / "r.npz", raws["cmy2"])
    assert list(tmp_path.iterdir()) == []
