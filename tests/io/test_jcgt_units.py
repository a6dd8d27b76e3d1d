"""Spectral EXRs from other tools, read as they say by capture (issue 13,
acceptance 3 and deliverable 3): emissiveUnits honoured, unknown units
refused, the illuminant of a file without our sidecar named."""

from __future__ import annotations

import warnings

import numpy as np

from conftest import assert_one_line_error, run_cli
from cfa_mitsuba import spectra
from cfa_mitsuba.io import load_raw_npz, read_spectral_exr
from cfa_mitsuba.io.cube import ReadNotice

WL = np.arange(400.0, 701.0, 10.0)


def write_flat(path, units, value=2e-4, size=16):
    """A flat field in the JCGT layout as the JCGT authors' writer makes it
    (S0.<nm>,000000nm float32 channels, spectralLayoutVersion,
    emissiveUnits), written with the OpenEXR package: ``value`` in ``units``
    in every band and pixel."""
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "spectralLayoutVersion": "1.0", "emissiveUnits": units}
    chans = {"S0." + f"{w:.6f}".replace(".", ",") + "nm": np.full((size, size), value, np.float32) for w in WL}
    with OpenEXR.File(header, chans) as f:
        f.write(str(path))
    return path


def test_channel_names_are_the_jcgt_ones(tmp_path):
    import OpenEXR

    with OpenEXR.File(str(write_flat(tmp_path / "w.exr", "W.m^-2.sr^-1")), header_only=True) as f:
        names = [c.name for c in f.header()["channels"]]
    assert "S0.400,000000nm" in names and len(names) == 31


def test_units_scale_what_is_read(tmp_path):
    w = read_spectral_exr(write_flat(tmp_path / "w.exr", "W.m^-2.sr^-1"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mw = read_spectral_exr(write_flat(tmp_path / "mw.exr", "mW.m^-2.sr^-1.nm^-1"))
    np.testing.assert_allclose(w.data, 1000 * mw.data, rtol=1e-12)
    assert any(issubclass(c.category, ReadNotice) and "x 0.001" in str(c.message) for c in caught)


def test_same_numbers_in_w_and_mw_capture_in_ratio_1000(tmp_path):
    raws = {}
    for name, units in (("w", "W.m^-2.sr^-1"), ("mw", "mW.m^-2.sr^-1")):
        exr = write_flat(tmp_path / f"{name}.exr", units)
        out = tmp_path / f"{name}.npz"
        run_cli("capture", exr, "--cfa", "bayer", "--exposure", "0.02", "--noise", "off", "--out", out, check_rc=0)
        raws[name] = load_raw_npz(out)
    w, mw = raws["w"], raws["mw"]
    assert w.meta["saturated_fraction"] == 0 and mw.raw.min() > 0
    assert w.black_level_dn == mw.black_level_dn == 0  # noise off: no offset, no ADC rounding
    ratio = w.raw / mw.raw
    assert abs(float(ratio.mean()) / 1000 - 1) < 1e-9 and np.ptp(ratio) < 1e-6, (ratio.mean(), np.ptp(ratio))


def test_unknown_unit_refused_by_capture_in_one_line(tmp_path):
    exr = write_flat(tmp_path / "u.exr", "W.cm^-2.sr^-1")
    proc = run_cli("capture", exr, "--cfa", "bayer", "--out", tmp_path / "r.npz")
    assert_one_line_error(proc, "unknown emissiveUnits 'W.cm^-2.sr^-1'")
    assert not (tmp_path / "r.npz").exists()


def test_capture_says_which_illuminant_and_uses_it(tmp_path):
    exr = write_flat(tmp_path / "f.exr", "W.m^-2.sr^-1")
    out = tmp_path / "a.npz"
    proc = run_cli("capture", exr, "--cfa", "bayer", "--illuminant", "A", "--noise", "off", "--out", out, check_rc=0)
    assert "illuminant A (from --illuminant) sets the white reference" in proc.stderr
    white = load_raw_npz(out).white_radiance
    a = spectra.illuminant("A", WL)
    np.testing.assert_allclose(white / white.sum(), a / a.sum(), rtol=1e-9)
    proc = run_cli("capture", exr, "--cfa", "bayer", "--noise", "off", "--out", tmp_path / "d.npz", check_rc=0)
    assert "illuminant D65 assumed (the file names none; pass --illuminant)" in proc.stderr


def test_colour_d65_exr_captures(tmp_path):
    """colour's own D65.exr (300-780 nm) was refused: its bands below 360 nm
    are now cropped with a notice."""
    import os

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour
    exr = os.path.join(os.path.dirname(colour.__file__), "io", "tests", "resources", "D65.exr")
    proc = run_cli("capture", exr, "--cfa", "ideal", "--out", tmp_path / "i.npz", check_rc=0)
    assert "cropped" in proc.stderr and "D65 (the file's 'illuminant' attribute)" in proc.stderr
