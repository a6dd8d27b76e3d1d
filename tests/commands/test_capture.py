"""``cfa-mitsuba capture``: spectral EXR in, raw .npz out; bad input exits 2
with one line and leaves no file behind.

Most cases call the CLI's ``main`` in-process (a subprocess costs seconds of
imports); two run the real command."""

import json
import os

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.cli import main
from cfa_mitsuba.io import load_raw_npz
from cfa_mitsuba.sensor import cfa_from_raw
from cfa_mitsuba.values import SpectralImage

from conftest import REPO, assert_one_line_error, run_cli

WL = cm.spectra.DEFAULT_WAVELENGTHS


def _chart(h=48, w=72, luminance=100.0):
    refl = cm.spectra.colorchecker(WL)[1]
    d65 = cm.spectra.illuminant("D65", WL)
    idx = np.arange(24).reshape(4, 6)
    data = (refl[idx] * d65).repeat(h // 4, 0).repeat(w // 6, 1)
    s = luminance / cm.spectra.luminance_cd_m2(data, WL).mean()
    return data * s, d65 * s


@pytest.fixture(scope="module")
def exr(tmp_path_factory):
    d = tmp_path_factory.mktemp("exr")
    data, white = _chart()
    meta = {"width": 72, "height": 48, "fov_deg": 10.0, "oversample": 1, "scene_distance_m": 1.2,
            "illuminant": "D65", "white_radiance": white.tolist(), "luminance_cd_m2": 100.0,
            "white_luminance_cd_m2": float(cm.spectra.luminance_cd_m2(white)), "geometry": {"patches": [{"rect": [0, 0, 12, 12]}]}}
    p = d / "chart.exr"
    cm.io.write_spectral_exr(p, SpectralImage(data, WL, meta))
    bare = d / "bare.exr"  # a JCGT EXR with no metadata of ours
    cm.io.write_spectral_exr(bare, SpectralImage(data, WL, {}))
    over = d / "over2.exr"
    cm.io.write_spectral_exr(over, SpectralImage(data, WL, {**meta, "oversample": 2}))
    return {"chart": p, "bare": bare, "over2": over}


def cli(capsys, *args):
    try:
        rc = main([str(a) for a in args])
    except SystemExit as exc:  # argparse
        rc = exc.code
    out, err = capsys.readouterr()
    return rc, out, err


def test_capture_bayer_writes_everything_process_needs(exr, tmp_path, capsys):
    out = tmp_path / "bayer.npz"
    rc, stdout, err = cli(capsys, "capture", exr["chart"], "--cfa", "bayer", "--out", out)
    assert rc == 0, err
    print(stdout)
    assert "wrote" in stdout and "exposure" in stdout
    with np.load(out, allow_pickle=False) as z:  # plain arrays, no pickles
        for key in ("raw", "pattern", "channels", "spectra", "wavelengths", "white_radiance", "exposure_s",
                    "dn_per_electron", "seed", "settings_json", "meta_json", "electrons_per_radiance",
                    "black_level_dn"):
            assert key in z.files, key
        assert z["raw"].shape == (48, 72)
        assert z["pattern"].tolist() == [["G", "R"], ["B", "G"]]
        assert z["channels"].tolist() == ["R", "G", "B"]
        assert z["spectra"].shape == (3, 31)
    raw = load_raw_npz(out)
    assert raw.settings["noise"] == "all" and raw.settings["exposure_mode"] == "auto"
    assert raw.meta["geometry"] == {"patches": [{"rect": [0, 0, 12, 12]}]} and raw.meta["oversample"] == 1
    assert raw.meta["pixel_pitch_um"] == 2.2 and raw.meta["luminance_cd_m2"] == pytest.approx(100.0)
    np.testing.assert_array_equal(cfa_from_raw(raw).sensitivities(raw.wavelengths), raw.spectra)
    assert [p.name for p in tmp_path.iterdir()] == ["bayer.npz"]  # no temporary file left


def test_capture_ideal_and_toml(exr, tmp_path, capsys):
    rc, stdout, err = cli(capsys, "capture", exr["chart"], "--cfa", "ideal", "--out", tmp_path / "i.npz")
    assert rc == 0, err
    ideal = load_raw_npz(tmp_path / "i.npz")
    assert ideal.raw.shape == (48, 72, 3) and ideal.channels == ("X", "Y", "Z")
    assert ideal.raw[..., 1].mean() == pytest.approx(100.0, rel=0.02)  # mean luminance, less the falloff
    toml = REPO / "configs/cfas/rgbv_photopic.toml"
    rc, stdout, err = cli(capsys, "capture", exr["chart"], "--cfa", toml, "--out", tmp_path / "v.npz")
    assert rc == 0, err
    v = load_raw_npz(tmp_path / "v.npz")
    assert v.channels == ("R", "G", "B", "V") and v.settings["cfa"]["name"] == "rgbv-photopic"
    assert cfa_from_raw(v).tile_text() == "G R / B V"


def test_exposure_program_options(exr, tmp_path, capsys):
    """--exposure auto runs the program by default (issue 22); the policy and its limits are options."""
    def run(*extra):
        out = tmp_path / "p.npz"
        rc, stdout, err = cli(capsys, "capture", exr["chart"], "--cfa", "rgbw1", "--out", out, "--noise", "off", *extra)
        assert rc == 0, err
        return load_raw_npz(out), stdout

    dim, stdout = run("--luminance", "1", "--max-exposure-s", "0.01", "--max-analog-gain", "4")
    st = dim.settings
    assert st["exposure_policy"] == "program" and dim.exposure_s == pytest.approx(0.01)
    assert st["analog_gain"] == pytest.approx(4.0) and st["digital_gain"] > 1.0 and "analogue gain 4" in stdout
    same, _ = run("--luminance", "1", "--exposure-policy", "bayer", "--max-exposure-s", "0.01")
    assert same.settings["exposure_policy"] == "bayer"
    ref, _ = run("--luminance", "1", "--reference-luminance", "100")
    assert ref.settings["exposure_policy"] == "reference" and ref.settings["analog_gain"] == 1.0
    rc, _, err = cli(capsys, "capture", exr["chart"], "--cfa", "bayer", "--out", tmp_path / "q.npz",
                     "--max-analog-gain", "0.5")
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "max_analog_gain" in err


def test_luminance_exposure_and_noise_options(exr, tmp_path, capsys):
    def run(*extra):
        out = tmp_path / "x.npz"
        rc, _, err = cli(capsys, "capture", exr["chart"], "--cfa", "rgbw1", "--out", out, *extra)
        assert rc == 0, err
        return load_raw_npz(out)

    a = run("--luminance", "20", "--exposure", "0.01", "--noise", "off")
    b = run("--luminance", "40", "--exposure", "0.01", "--noise", "off")
    assert a.exposure_s == 0.01 and a.settings["exposure_mode"] == "fixed"
    np.testing.assert_allclose(b.raw, 2 * a.raw, rtol=1e-9)
    kept = run("--noise", "off")  # no --luminance: the EXR's radiance
    assert kept.meta["luminance_cd_m2"] == pytest.approx(100.0)
    s1 = run("--seed", "5", "--prnu-percent", "1", "--f-number", "2.8", "--pixel-pitch-um", "1.4",
             "--fill-factor", "0.8", "--no-relative-illumination", "--black-level-dn", "100")
    s2 = run("--seed", "5", "--prnu-percent", "1", "--f-number", "2.8", "--pixel-pitch-um", "1.4",
             "--fill-factor", "0.8", "--no-relative-illumination", "--black-level-dn", "100")
    np.testing.assert_array_equal(s1.raw, s2.raw)
    assert s1.settings["sensor"]["pixel_pitch_um"] == 1.4 and s1.settings["optics"]["f_number"] == 2.8
    assert s1.black_level_dn == 100 and s1.settings["optics"]["relative_illumination"] is False


def test_sidecar_oversample_and_bare_exr(exr, tmp_path, capsys):
    rc, _, err = cli(capsys, "capture", exr["over2"], "--cfa", "bayer", "--out", tmp_path / "o.npz")
    assert rc == 0, err
    assert load_raw_npz(tmp_path / "o.npz").raw.shape == (24, 36)
    rc, _, err = cli(capsys, "capture", exr["chart"], "--cfa", "bayer", "--oversample", "3", "--out",
                     tmp_path / "o3.npz")
    assert rc == 0, err
    assert load_raw_npz(tmp_path / "o3.npz").raw.shape == (16, 24)
    rc, stdout, err = cli(capsys, "capture", exr["bare"], "--cfa", "bayer", "--out", tmp_path / "b.npz")
    assert rc == 0, err
    bare = load_raw_npz(tmp_path / "b.npz")
    assert bare.meta["optics"]["fov_source"] == "default" and bare.meta["white_source"].startswith("assumed")


def _bad_cases(exr, tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("not an image")
    fake = tmp_path / "fake.exr"
    fake.write_text("not an exr either")
    blocker = tmp_path / "afile"
    blocker.write_text("x")
    good = ["--cfa", "bayer", "--out", tmp_path / "out" / "r.npz"]
    return {
        "missing EXR": ([tmp_path / "nope.exr", *good], "nope.exr"),
        "text file": ([text, *good], "notes.txt"),
        "not an EXR": ([fake, *good], "fake.exr"),
        "bad exposure": ([exr["chart"], *good, "--exposure", "fast"], "exposure"),
        "negative exposure": ([exr["chart"], *good, "--exposure", "-1"], "exposure"),
        "bad noise": ([exr["chart"], *good, "--noise", "loud"], "noise"),
        "zero luminance": ([exr["chart"], *good, "--luminance", "0"], "luminance"),
        "negative luminance": ([exr["chart"], *good, "--luminance", "-5"], "luminance"),
        "zero oversample": ([exr["chart"], *good, "--oversample", "0"], "oversample"),
        "oversample 5": ([exr["chart"], *good, "--oversample", "5"], "does not divide"),
        "oversample 2 of 2": ([exr["over2"], *good, "--oversample", "5"], "does not divide"),
        "out not npz": ([exr["chart"], "--cfa", "bayer", "--out", tmp_path / "r.png"], ".npz"),
        "out is a dir": ([exr["chart"], "--cfa", "bayer", "--out", tmp_path / "d.npz"], "directory"),
        "out under a file": ([exr["chart"], "--cfa", "bayer", "--out", blocker / "r.npz"], "not a directory"),
        "unknown cfa": ([exr["chart"], "--cfa", "bayr", *good[2:]], "unknown CFA"),
        "missing toml": ([exr["chart"], "--cfa", tmp_path / "none.toml", *good[2:]], "cannot read CFA file"),
        "bad fill factor": ([exr["chart"], *good, "--fill-factor", "1.5"], "fill_factor"),
        "bad lens": ([exr["chart"], *good, "--lens-transmittance", "2"], "transmittance"),
        "no cfa": ([exr["chart"], "--out", tmp_path / "r.npz"], "--cfa"),
    }


CASES = ["missing EXR", "text file", "not an EXR", "bad exposure", "negative exposure", "bad noise",
         "zero luminance", "negative luminance", "zero oversample", "oversample 5", "oversample 2 of 2",
         "out not npz", "out is a dir", "out under a file", "unknown cfa", "missing toml", "bad fill factor",
         "bad lens", "no cfa"]


@pytest.mark.parametrize("case", CASES)
def test_bad_input_exits_2_with_one_line_and_no_file(exr, tmp_path, capsys, case):
    (tmp_path / "d.npz").mkdir()
    args, needle = _bad_cases(exr, tmp_path)[case]
    before = sorted(os.listdir(tmp_path))
    rc, out, err = cli(capsys, "capture", *args)
    assert rc == 2, (rc, err)
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert needle.lower() in lines[0].lower(), lines[0]
    assert sorted(os.listdir(tmp_path)) == before  # nothing written, not even a folder
    assert os.listdir(tmp_path / "d.npz") == []


def test_real_command(exr, tmp_path):
    out = tmp_path / "sub" / "r.npz"
    proc = run_cli("capture", exr["chart"], "--cfa", "cmy3", "--out", out, "--noise", "shot", "--seed", "3")
    assert proc.returncode == 0, proc.stderr
    assert load_raw_npz(out).channels == ("G", "C", "M", "Y")
    proc = run_cli("capture", exr["chart"], "--cfa", "bayer", "--out", tmp_path / "x.npz", "--oversample", "5")
    assert_one_line_error(proc, "does not divide")
    assert not (tmp_path / "x.npz").exists()


def test_settings_and_meta_are_json(exr, tmp_path, capsys):
    out = tmp_path / "r.npz"
    assert cli(capsys, "capture", exr["chart"], "--cfa", "rgbw2", "--out", out)[0] == 0
    with np.load(out, allow_pickle=False) as z:
        settings = json.loads(str(z["settings_json"]))
        meta = json.loads(str(z["meta_json"]))
    assert settings["cfa"] == {"name": "rgbw2", "description": cm.sensor.get_cfa("rgbw2").description,
                               "tile": "W B W G / B W G W / W G W R / G W R W", "spectra": "isetcam-rgbw"}
    assert meta["optics"]["f_number"] == 4.0 and meta["optics"]["boundary"].startswith("mirror")
