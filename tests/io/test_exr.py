"""Spectral EXR (JCGT layout) and sidecar I/O."""

import json

import numpy as np
import OpenEXR
import pytest

from cfa_mitsuba import spectra
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.io import read_sidecar, read_spectral_exr, write_sidecar, write_spectral_exr
from cfa_mitsuba.io.exr import parse_spectral_channel, spectral_channel_name
from cfa_mitsuba.values import SpectralImage


def _image(h=5, w=7, wl=spectra.DEFAULT_WAVELENGTHS, seed=0):
    rng = np.random.default_rng(seed)
    return SpectralImage(rng.uniform(0, 0.2, (h, w, len(wl))), np.asarray(wl, float),
                         {"scene": "test", "white_luminance_cd_m2": 100.0, "geometry": {"roi": [0, 0, 2, 2]}})


def _write_raw(path, channels, header=None):
    h = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **(header or {})}
    with OpenEXR.File(h, {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in channels.items()}) as f:
        f.write(str(path))


def test_round_trip_float32_names_and_attributes(tmp_path):
    img = _image()
    p = write_spectral_exr(tmp_path / "a.exr", img)
    back = read_spectral_exr(p)
    np.testing.assert_array_equal(back.wavelengths, spectra.DEFAULT_WAVELENGTHS)
    np.testing.assert_allclose(back.data, img.data.astype(np.float32), rtol=0, atol=0)
    assert back.meta["scene"] == "test" and back.meta["geometry"] == {"roi": [0, 0, 2, 2]}
    assert back.meta["units"] == "W/(m^2 sr nm)"
    with OpenEXR.File(str(p), separate_channels=True) as f:
        header = dict(f.header().items())
        chans = dict(f.channels().items())
    assert header["spectralLayoutVersion"] == "1.0" and header["emissiveUnits"] == "W.m^-2.sr^-1"
    assert "S0.400,000000nm" in chans and "S0.550,000000nm" in chans
    assert all(c.pixels.dtype == np.float32 for c in chans.values())
    assert json.loads(header["cfaMitsuba"])["scene"] == "test"


def test_channel_names():
    assert spectral_channel_name(400) == "S0.400,000000nm"
    assert spectral_channel_name(402.5) == "S0.402,500000nm"
    for name, nm in [("S0.550,000000nm", 550), ("S0.550,0nm", 550), ("S0.550nm", 550), ("S0.0,55um", 550),
                     ("S0.5,5E-7m", 550), ("S0.5500,000000Am", None), ("S1.550nm", None), ("T.550nm", None),
                     ("R", None), ("S0.nm", None)]:
        got = parse_spectral_channel(name)
        assert (got is None and nm is None) or got == pytest.approx(nm, rel=1e-12), name
    assert parse_spectral_channel("S0.545,077THz") == pytest.approx(550.0, rel=1e-5)


def test_reads_any_jcgt_file_sorted_by_wavelength(tmp_path):
    """A foreign file: other decimals, channels out of order, no metadata."""
    wl = [450.0, 550.0, 650.0]
    planes = {"S0.650,0nm": np.full((2, 3), 3.0), "S0.450nm": np.full((2, 3), 1.0), "S0.0,55um": np.full((2, 3), 2.0),
              "R": np.zeros((2, 3)), "G": np.zeros((2, 3)), "B": np.zeros((2, 3))}
    _write_raw(tmp_path / "f.exr", planes, {"spectralLayoutVersion": "1.0", "emissiveUnits": "W.m^-2.sr^-1"})
    img = read_spectral_exr(tmp_path / "f.exr")
    np.testing.assert_array_equal(img.wavelengths, wl)
    np.testing.assert_array_equal(img.data[0, 0], [1.0, 2.0, 3.0])
    assert img.meta["wavelengths"] == wl and img.meta["width"] == 3 and img.meta["height"] == 2


def test_sidecar_beside_the_file_wins(tmp_path):
    p = write_spectral_exr(tmp_path / "a.exr", _image())
    write_sidecar(tmp_path / "a.json", {"scene": "from-sidecar", "wavelengths": list(spectra.DEFAULT_WAVELENGTHS)})
    assert read_spectral_exr(p).meta["scene"] == "from-sidecar"
    write_sidecar(tmp_path / "a.json", {"scene": "x", "wavelengths": [400, 500]})
    with pytest.raises(CfaMitsubaError, match="2 wavelengths"):
        read_spectral_exr(p)


def test_nan_refused_on_write_and_reported_on_read(tmp_path):
    img = _image()
    img.data[1, 2, 3] = np.nan
    img.data[0, 0, 0] = np.inf
    with pytest.raises(CfaMitsubaError, match="2 NaN or infinite"):
        write_spectral_exr(tmp_path / "bad.exr", img)
    assert not list(tmp_path.iterdir())  # nothing left behind
    planes = {spectral_channel_name(w): np.ones((2, 2)) for w in (500, 600)}
    planes["S0.500,000000nm"][0, 1] = np.nan
    _write_raw(tmp_path / "nan.exr", planes)
    with pytest.raises(CfaMitsubaError, match="1 NaN or infinite"):
        read_spectral_exr(tmp_path / "nan.exr")


def test_unreadable_inputs(tmp_path):
    with pytest.raises(CfaMitsubaError, match="no such file"):
        read_spectral_exr(tmp_path / "none.exr")
    (tmp_path / "junk.exr").write_bytes(b"not an exr")
    with pytest.raises(CfaMitsubaError, match="not a readable OpenEXR"):
        read_spectral_exr(tmp_path / "junk.exr")
    _write_raw(tmp_path / "rgb.exr", {"R": np.ones((2, 2)), "G": np.ones((2, 2)), "B": np.ones((2, 2))})
    with pytest.raises(CfaMitsubaError, match="not a spectral EXR"):
        read_spectral_exr(tmp_path / "rgb.exr")
    (tmp_path / "s.json").write_text("{not json")
    with pytest.raises(CfaMitsubaError, match="not valid JSON"):
        read_sidecar(tmp_path / "s.json")


def test_write_is_atomic(tmp_path, monkeypatch):
    """A failure while writing leaves neither the target nor a temp file."""
    class HalfWrite:  # writes some bytes, then the disk fills up
        def __init__(self, header, channels):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def write(self, path):
            with open(path, "wb") as fh:
                fh.write(b"partial")
            raise OSError(28, "No space left on device")

    p = write_spectral_exr(tmp_path / "keep.exr", _image(seed=1))
    before = p.read_bytes()
    monkeypatch.setattr(OpenEXR, "File", HalfWrite)
    with pytest.raises(OSError):
        write_spectral_exr(p, _image(seed=2))
    assert p.read_bytes() == before and sorted(x.name for x in tmp_path.iterdir()) == ["keep.exr"]
