"""Spectra sets (issue 12, deliverable 1): each CFA family its own real
filters, on one footing (common silicon QE and IR cut), read from package
data with the source files' known defects handled."""

from __future__ import annotations

import csv
import hashlib
from pathlib import Path

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.sensor import get_cfa, get_spectra_set, list_spectra_sets
from cfa_mitsuba.sensor.spectra_sets import FILTERS_DIR, ir_cut, read_curve_csv, silicon_qe

from conftest import run_cli


def _csv(path):
    """The CSV as typed: header and float rows in stored order (no sorting)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array([[float(v) for v in r] for r in rows[1:]])


def _at(curve, wl):
    return np.interp(wl, *curve)


def _same(a, b):
    return np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


# --- acceptance ----------------------------------------------------------------


def test_bayer_and_cmy1_stacked_have_rank_above_3():
    """Issue 12 acceptance 1: with the family sets the RGB and CMY filters
    span more than one 3-D space (with the Nikon set they do not: C = G + B...)."""
    stacked = np.vstack([get_cfa("bayer").sensitivities(), get_cfa("cmy1").sensitivities()])
    assert stacked.shape == (6, 31)
    assert np.linalg.matrix_rank(stacked, tol=1e-3 * np.abs(stacked).max()) > 3
    nikon = np.vstack([get_cfa("bayer", spectra="nikon-d5100").sensitivities(),
                       get_cfa("cmy1", spectra="nikon-d5100").sensitivities()])
    assert np.linalg.matrix_rank(nikon, tol=1e-9 * nikon.max()) == 3


def test_the_paper_cfas_use_their_family_sets():
    family = {"bayer": "isetcam-rgb", "rgb1": "isetcam-rgb", "rgb2": "isetcam-rgb", "rgb3": "isetcam-rgb",
              "rgb4": "isetcam-rgb", "rgb5": "isetcam-rgb", "cmy1": "isetcam-cmy", "cmy2": "isetcam-cmy",
              "cmy3": "isetcam-cmy", "rgbw1": "isetcam-rgbw", "rgbw2": "isetcam-rgbw", "rgbw3": "isetcam-rgbw"}
    for name, sset in family.items():
        assert get_cfa(name).spectra == sset, name
        assert get_cfa(name, spectra="nikon-d5100").spectra == "nikon-d5100"
    assert get_cfa("bayer", spectra="nikon-d5100") is get_cfa("bayer", spectra="nikon-d5100")
    assert not _same(get_cfa("bayer").curves["R"], get_cfa("bayer", spectra="nikon-d5100").curves["R"])


def test_sensitivities_are_bands_of_the_combined_curves():
    """RGB.csv is whole pixel without IR cut: band value = box mean of R x IR;
    cym.csv is dye alone: Y x IR x silicon (checked at 550 nm by an
    independent trapezoid over 1-nm samples of the typed CSVs)."""
    hdr, rgb = _csv(FILTERS_DIR / "isetcam/colorfilters/RGB.csv")
    _, cym = _csv(FILTERS_DIR / "isetcam/colorfilters/cym.csv")
    cym = cym[::-1]  # stored descending
    _, ir = _csv(FILTERS_DIR / "isetcam/ircf_public.csv")
    _, si = _csv(FILTERS_DIR / "isetcam/photodetectors/cmosPhotodetectorQE.csv")
    si = si[np.argsort(si[:, 0])]
    x = np.linspace(545.0, 555.0, 10001)
    irx, six = np.interp(x, ir[:, 0], ir[:, 1]), np.interp(x, si[:, 0], si[:, 1] / 100)
    r_expect = np.trapezoid(np.interp(x, rgb[:, 0], rgb[:, 1]) * irx, x) / 10
    y_expect = np.trapezoid(np.interp(x, cym[:, 0], cym[:, 2]) * irx * six, x) / 10
    wl = cm.spectra.DEFAULT_WAVELENGTHS
    b = list(wl).index(550.0)
    assert get_cfa("bayer").sensitivities()[0, b] == pytest.approx(r_expect, rel=1e-4)
    cmy1 = get_cfa("cmy1")
    assert cmy1.sensitivities()[cmy1.channels.index("Y"), b] == pytest.approx(y_expect, rel=1e-4)


def test_stacked_dyes_and_borrowed_letters():
    """cmy2 multiplies two dye layers on the common silicon; cmy3's G is
    ISETCam's RGB G (as its CMYG.mat); ryyb's Y is the CMY set's yellow."""
    cmy = get_spectra_set("isetcam-cmy")
    clear = cmy.curve("W")
    wl = np.arange(410.0, 700.0, 7.0)
    t = {k: _at(cmy.curve(k), wl) / _at(clear, wl) for k in "CMY"}
    for letter, (a, b) in {"C2": "CC", "MY": "MY", "CY": "CY", "CM": "CM"}.items():
        np.testing.assert_allclose(_at(cmy.curve(letter), wl), t[a] * t[b] * _at(clear, wl), rtol=2e-3)
    cmy2 = get_cfa("cmy2")
    assert _same(cmy2.curves["R"], cmy.curve("MY")) and _same(cmy2.curves["C2"], cmy.curve("C2"))
    assert _same(get_cfa("cmy3").curves["G"], get_spectra_set("isetcam-rgb").curve("G"))
    assert _same(get_cfa("ryyb").curves["Y"], cmy.curve("Y"))
    np.testing.assert_allclose(_at(clear, wl), _at(ir_cut(), wl) * _at(silicon_qe(), wl), rtol=1e-3)


def test_relative_sets_rgb_sum_peaks_at_the_camera_qe():
    for name in list_spectra_sets():
        s = get_spectra_set(name)
        for letter, (wl, qe) in s.curves.items():
            assert np.all(np.diff(wl) > 0) and np.all(np.isfinite(qe)), (name, letter)
            assert 0 <= qe.min() and qe.max() <= 1.0, (name, letter)
    for name in ("nikon-d5100", "isetcam-rgbw", "pbrt-sony-ilce-9", "isetcam-nikon-d2xs", "aptina-mt9m031"):
        grid = np.arange(380.0, 781.0, 0.5)
        s = get_spectra_set(name)
        total = sum(_at(s.curve(k), grid) for k in "RGB")
        assert total.max() == pytest.approx(cm.spectra.CAMERA_PEAK_QE, rel=2e-3), name


def test_isetcam_rgbw_keeps_the_file_ratios_and_gives_w_the_ir_cut():
    hdr, d = _csv(FILTERS_DIR / "isetcam/colorfilters/interleavedRGBW.csv")
    s = get_spectra_set("isetcam-rgbw")
    wl = np.array([450.0, 550.0, 600.0, 650.0])
    k = _at(s.curve("G"), wl) / np.interp(wl, d[:, 0], d[:, 2])
    np.testing.assert_allclose(k, k[0], rtol=1e-9)  # one factor: R, G, B as stored
    w = np.interp(wl, d[:, 0], d[:, 4]) * k[0] * _at(ir_cut(), wl)
    np.testing.assert_allclose(_at(s.curve("W"), wl), w, rtol=1e-6)


# --- the known defects of the shipped files --------------------------------------


def test_descending_rows_are_sorted():
    hdr, raw = _csv(FILTERS_DIR / "isetcam/colorfilters/cym.csv")
    assert raw[0, 0] == 780.0 and np.all(np.diff(raw[:, 0]) < 0)  # the defect is there
    cols = read_curve_csv(FILTERS_DIR / "isetcam/colorfilters/cym.csv")
    wl, c = cols["C"]
    assert np.all(np.diff(wl) > 0) and wl[0] == raw[-1, 0]
    np.testing.assert_array_equal(c, raw[::-1, 1])


def test_unsorted_percent_silicon_qe():
    hdr, raw = _csv(FILTERS_DIR / "isetcam/photodetectors/cmosPhotodetectorQE.csv")
    assert not np.all(np.diff(raw[:, 0]) > 0) and raw[:, 1].max() == pytest.approx(75.4286)
    wl, qe = silicon_qe()
    assert np.all(np.diff(wl) > 0) and qe.max() == pytest.approx(0.754286)
    order = np.argsort(raw[:, 0])
    np.testing.assert_array_equal(qe, raw[order, 1] / 100)


def test_percent_declared_on_fractions_is_refused(tmp_path):
    p = tmp_path / "f.csv"
    p.write_text("wavelength_nm,QE\n400,0.2\n500,0.6\n700,0.3\n")
    with pytest.raises(CfaMitsubaError, match="declared in percent but peaks at 0.6"):
        read_curve_csv(p, unit="percent")


def test_nan_is_a_missing_sample():
    path = FILTERS_DIR / "isetcam/colorfilters/auto/AptinaMT9M031.csv"
    hdr, raw = _csv(path)
    assert np.isnan(raw[0, 1]) and np.isnan(raw[0, 3]) and np.isnan(raw[-1, 3])
    cols = read_curve_csv(path)
    assert cols["R"][0][0] == 410.0 and cols["G"][0][0] == 400.0 and cols["B"][0][-1] == 690.0
    s = get_spectra_set("aptina-mt9m031")
    band = get_cfa("bayer", spectra="aptina-mt9m031").sensitivities()
    assert np.all(np.isfinite(band)) and np.all(band >= 0)
    # R at 400 nm is held at its 410-nm value (times the common IR cut)
    np.testing.assert_allclose(_at(s.curve("R"), [400.0]) / _at(ir_cut(), [400.0]),
                               _at(s.curve("R"), [410.0]) / _at(ir_cut(), [410.0]), rtol=1e-9)


def test_negative_round_off_is_zero_and_real_negatives_are_refused(tmp_path):
    path = FILTERS_DIR / "isetcam/colorfilters/nikon/NikonD2xsNikon50mm.csv"
    hdr, raw = _csv(path)
    assert raw[:, 1].min() < 0  # -2.2e-19 at 760 nm
    wl, r = read_curve_csv(path)["R"]
    assert r.min() == 0.0 and r[wl == 760.0][0] == 0.0
    assert np.all(get_cfa("bayer", spectra="isetcam-nikon-d2xs").sensitivities() >= 0)
    bad = tmp_path / "neg.csv"
    bad.write_text("wavelength_nm,R\n400,0.1\n500,-0.01\n700,0.2\n")
    with pytest.raises(CfaMitsubaError, match="negative values down to -0.01"):
        read_curve_csv(bad)


def test_duplicate_wavelengths(tmp_path):
    same = tmp_path / "same.csv"
    same.write_text("wavelength_nm,R\n400,0.1\n500,0.4\n500,0.4\n700,0.2\n")
    wl, r = read_curve_csv(same)["R"]
    assert wl.tolist() == [400.0, 500.0, 700.0] and r.tolist() == [0.1, 0.4, 0.2]
    clash = tmp_path / "clash.csv"
    clash.write_text("wavelength_nm,R\n400,0.1\n500,0.4\n500,0.5\n700,0.2\n")
    with pytest.raises(CfaMitsubaError, match="500 nm is listed twice with different values"):
        read_curve_csv(clash)


#: upstream files the package does not ship (each rebuilt from a shipped one), kept as test data
UPSTREAM_ONLY = Path(__file__).resolve().parents[1] / "data" / "filters"


def _sha256sums(folder):
    lines = (folder / "SHA256SUMS").read_text().splitlines()
    return {rel: digest for digest, rel in (line.split("  ", 1) for line in lines)}


def test_shipped_files_are_verbatim_copies_and_not_duplicated():
    # SHA256SUMS holds the digests of the upstream extracts (ISETCam, pbrt-v4) the files were copied from
    upstream = _sha256sums(FILTERS_DIR)
    files = sorted(p for p in FILTERS_DIR.rglob("*.csv"))
    assert sorted(str(p.relative_to(FILTERS_DIR)) for p in files) == sorted(upstream)
    contents = {}
    for p in files:
        rel = p.relative_to(FILTERS_DIR)
        assert hashlib.sha256(p.read_bytes()).hexdigest() == upstream[str(rel)], rel
        _, d = _csv(p)
        key = np.round(d[:, 1:], 12).tobytes()
        assert key not in contents, (rel, contents.get(key))
        contents[key] = rel


def test_duplicated_datasets_are_rebuilt_not_shipped():
    for rel, digest in _sha256sums(UPSTREAM_ONLY).items():
        assert hashlib.sha256((UPSTREAM_ONLY / rel).read_bytes()).hexdigest() == digest, rel
        assert not (FILTERS_DIR / rel).exists(), rel  # test data only: the package rebuilds it
    f, shipped = UPSTREAM_ONLY / "isetcam", FILTERS_DIR / "isetcam"
    # ISETCam's RGBW join is the set mt9v024-rgbw
    _, joined = _csv(f / "colorfilters/auto/MT9V024_RGBW.csv")
    joined = joined[(joined[:, 0] >= 400) & (joined[:, 0] <= 700)]  # where the IR cut passes light
    s = get_spectra_set("mt9v024-rgbw")
    for i, letter in enumerate("RGBW"):
        np.testing.assert_allclose(_at(s.curve(letter), joined[:, 0]) / _at(ir_cut(), joined[:, 0]),
                                   joined[:, i + 1], rtol=1e-12)
    # the IMX363 placeholder is MT9V024 RGB, bit for bit
    assert (f / "qe_IMX363_public.csv").read_bytes().split(b"\n", 1)[1] == \
        (shipped / "colorfilters/auto/MT9V024_RGB.csv").read_bytes().split(b"\n", 1)[1]
    # D200 IR: the two files differ by the factor 0.8 only
    _, a = _csv(shipped / "colorfilters/nikon/NikonD200IR.csv")
    _, b = _csv(f / "colorfilters/nikon/d200irSensitivities.csv")
    np.testing.assert_allclose(a[:, 1:], 0.8 * b[:, 1:], rtol=1e-12)


def test_unknown_set_and_missing_letters_are_one_line_errors():
    with pytest.raises(CfaMitsubaError, match="unknown spectra set 'nope'"):
        get_cfa("bayer", spectra="nope")
    with pytest.raises(CfaMitsubaError, match="the set has no filter 'W'"):
        get_cfa("rgbw1", spectra="isetcam-rgb")
    with pytest.raises(CfaMitsubaError, match="has no filter 'Q'"):
        get_spectra_set("isetcam-rgb").curve("Q")


def test_toml_spectra_set(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('tile = "G R / B W"\nspectra_set = "isetcam-rgbw"\n')
    cfa = cm.sensor.load_cfa_toml(p)
    assert cfa.spectra == "isetcam-rgbw" and _same(cfa.curves["W"], get_spectra_set("isetcam-rgbw").curve("W"))
    assert _same(get_cfa(str(p), spectra="nikon-d5100").curves["W"], get_spectra_set("nikon-d5100").curve("W"))
    p.write_text('tile = "G R / B W"\n')
    assert cm.sensor.load_cfa_toml(p).spectra == "isetcam-rgbw"  # user files: the set of the built-in RGBW CFAs


def test_list_spectra_names_every_set_with_its_source():
    proc = run_cli("list", "spectra", check_rc=0)
    lines = proc.stdout.splitlines()
    assert len(lines) == len(list_spectra_sets()) >= 32  # 15 named + 17 pbrt-v4 cameras
    for name in ("isetcam-rgb", "isetcam-cmy", "isetcam-rgbw", "nikon-d5100", "pbrt-nikon-d850",
                 "isetcam-nikon-d100", "mt9v024-rccc"):
        line = next(l for l in lines if l.split()[0] == name)
        assert "source:" in line and ("ISETCam" in line or "pbrt-v4" in line or "colour-science" in line)
