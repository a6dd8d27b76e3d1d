"""Bad measured images (issue 13, deliverable 5): exit 2, one line on
stderr, no traceback, nothing written."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import assert_one_line_error, run_cli


def _envi(d, cube, wavelengths, name="c"):
    import spectral.io.envi as envi

    meta = {} if wavelengths is None else {"wavelength": [float(v) for v in wavelengths], "wavelength units": "nm"}
    envi.save_image(str(d / f"{name}.hdr"), np.asarray(cube, np.float32), metadata=meta, force=True)
    return d / f"{name}.hdr"


def _flat(n=4):
    return np.full((4, 5, n), 0.5, np.float32)


def band_count(d):
    return _envi(d, _flat(3), [400, 500, 600, 700]), "3 bands but 4 wavelengths"


def no_wavelengths(d):
    return _envi(d, _flat(3), None), "no wavelengths"


def unsorted(d):
    return _envi(d, _flat(3), [400, 600, 500]), "not strictly ascending"


def nan(d):
    cube = _flat()
    cube[1, 2, 3] = np.nan
    return _envi(d, cube, [400, 500, 600, 700]), "1 NaN or infinite"


def negative(d):
    cube = _flat()
    cube[0, 0, 0] = -0.25
    return _envi(d, cube, [400, 500, 600, 700]), "1 negative value"


def too_large(d):
    p = _envi(d, _flat(), [400, 500, 600, 700])
    text = p.read_text().replace("samples = 5", "samples = 400000").replace("lines = 4", "lines = 300000")
    p.write_text(text)
    return p, "too large for memory"


def too_large_v73(d):
    import h5py

    p = d / "big.mat"
    with h5py.File(p, "w", userblock_size=512) as f:  # declared, never written: the file stays small
        f.create_dataset("cube", shape=(31, 300000, 400000), dtype="f4", chunks=(31, 64, 64))
        f.create_dataset("wavelengths", data=np.arange(400.0, 701.0, 10.0)[:, None])
    return p, "too large for memory"


def missing_band(d):
    from PIL import Image

    folder = d / "scene_ms"
    folder.mkdir()
    for i in range(1, 32):
        if i != 5:
            Image.fromarray(np.full((4, 5), 1000, np.uint16)).save(folder / f"scene_ms_{i:02d}.png")
    return folder, "band(s) missing: scene_ms_05.png"


def mat_band_count(d):
    import scipy.io

    scipy.io.savemat(d / "m.mat", {"cube": _flat(4).astype(float), "wavelengths": np.array([400.0, 500, 600])})
    return d / "m.mat", "4 bands but 3 wavelengths"


def unknown_units(d):
    import OpenEXR

    chans = {f"S0.{w},0nm": np.full((4, 4), 0.01, np.float32) for w in (400, 500, 600, 700)}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "spectralLayoutVersion": "1.0", "emissiveUnits": "furlongs.fortnight^-1"}
    with OpenEXR.File(header, chans) as f:
        f.write(str(d / "u.exr"))
    return d / "u.exr", "unknown emissiveUnits 'furlongs.fortnight^-1'"


CASES = [band_count, no_wavelengths, unsorted, nan, negative, too_large, too_large_v73, missing_band, mat_band_count,
         unknown_units]


@pytest.mark.parametrize("case", CASES, ids=[c.__name__ for c in CASES])
def test_bad_measured_image_is_one_line_and_leaves_nothing(tmp_path, case):
    path, needle = case(tmp_path)
    out = tmp_path / "out"
    proc = run_cli("render", path, "--out", out, "--no-cache")
    assert_one_line_error(proc, needle)
    assert not out.exists()


def test_wavelengths_flag_must_match_the_folder(tmp_path):
    from PIL import Image

    folder = tmp_path / "four"
    folder.mkdir()
    for i in range(1, 5):
        Image.fromarray(np.full((4, 5), 1000 * i, np.uint16)).save(folder / f"four_{i:02d}.png")
    proc = run_cli("render", folder, "--wavelengths", "400,500,600", "--out", tmp_path / "o", "--no-cache")
    assert_one_line_error(proc, "4 bands but 3 wavelengths")
    assert not (tmp_path / "o").exists()
    proc = run_cli("render", folder, "--wavelengths", "400:700:100", "--out", tmp_path / "o", "--no-cache",
                   check_rc=0)
    assert "relative radiance" in proc.stderr and (tmp_path / "o" / "four.exr").exists()


def test_measured_flags_refused_for_a_built_in_scene(tmp_path):
    proc = run_cli("render", "macbeth", "--illuminant", "A", "--out", tmp_path / "o")
    assert_one_line_error(proc, "--illuminant apply to measured spectral images", "not to 'macbeth'")
    assert not (tmp_path / "o").exists()
