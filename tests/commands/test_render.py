"""``cfa-mitsuba render``: outputs, cache reuse, and every bad input
(issue 2 acceptance 6, 7)."""

import json

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.io import read_spectral_exr
from conftest import assert_one_line_error, run_cli

SIDECAR_KEYS = {
    "scene", "width", "height", "fov_deg", "oversample", "wavelengths", "units", "luminance_cd_m2", "illuminant",
    "white_radiance", "white_luminance_cd_m2", "scene_distance_m", "spp", "variant", "seed", "render_time_s",
    "cache_key", "kind", "geometry",
}


def test_render_writes_exr_and_sidecar_then_reuses_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CFA_MITSUBA_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "out"
    first = run_cli("render", "slanted-edge", "--out", out, "--width", 64, "--height", 48, check_rc=0)
    assert "variant llvm_ad_spectral" in first.stderr or "variant cuda_ad_spectral" in first.stderr
    assert "rendered slanted-edge" in first.stderr and "reused" not in first.stderr
    exr, side = out / "slanted-edge.exr", out / "slanted-edge.json"
    assert first.stdout.split() == [str(exr), str(side)]

    import OpenEXR

    with OpenEXR.File(str(exr), separate_channels=True) as f:
        header = dict(f.header().items())
        chans = {k: v.pixels for k, v in f.channels().items()}
    assert header["spectralLayoutVersion"] == "1.0" and header["emissiveUnits"] == "W.m^-2.sr^-1"
    names = sorted(k for k in chans if k.startswith("S0."))
    assert names[0] == "S0.400,000000nm" and names[-1] == "S0.700,000000nm" and len(names) == 31
    assert all(chans[n].dtype == np.float32 and chans[n].shape == (48, 64) for n in names)
    assert {"R", "G", "B"} <= set(chans)

    meta = json.loads(side.read_text())
    assert SIDECAR_KEYS <= set(meta)
    assert meta["width"] == 64 and meta["height"] == 48 and meta["oversample"] == 4
    assert meta["luminance_cd_m2"] == 100.0 and meta["kind"] == "slanted-edge"
    assert cm.metrics.metrics_for_scene(meta["kind"]) == ("mtf", "info-capacity")
    img = read_spectral_exr(exr)
    assert spectra.luminance_cd_m2(img.data).mean() == pytest.approx(100.0, rel=1e-4)

    # Same settings, another luminance: the cached render is reused and rescaled.
    second = run_cli("render", "slanted-edge", "--out", out, "--width", 64, "--height", 48, "--luminance", 20, check_rc=0)
    assert "reused cached render" in second.stderr and meta["cache_key"] in second.stderr
    img2 = read_spectral_exr(exr)
    np.testing.assert_allclose(img2.data, img.data * 0.2, rtol=1e-6, atol=1e-12)
    assert json.loads(side.read_text())["luminance_cd_m2"] == 20.0
    # Another seed is another render.
    third = run_cli("render", "slanted-edge", "--out", out, "--width", 64, "--height", 48, "--seed", 3, check_rc=0)
    assert "rendered slanted-edge" in third.stderr


def test_variant_override_and_preview(tmp_path):
    out = tmp_path / "o"
    proc = run_cli("render", "gray-bar", "--out", out, "--width", 40, "--height", 8, "--variant", "scalar_spectral",
                   "--preview", "--no-cache", check_rc=0)
    assert "variant scalar_spectral" in proc.stderr and "cache not used" in proc.stderr
    assert (out / "gray-bar.png").is_file()
    assert json.loads((out / "gray-bar.json").read_text())["variant"] == "scalar_spectral"


def test_help_lists_options():
    proc = run_cli("render", "--help", check_rc=0)
    for opt in ("--out", "--width", "--height", "--spp", "--luminance", "--variant", "--seed", "--bands", "--oversample"):
        assert opt in proc.stdout


@pytest.mark.parametrize("args,needles", [
    (["no-such-scene"], ["unknown scene", "no-such-scene"]),
    (["{tmp}/missing.xml"], ["no such scene file"]),
    (["{tmp}/broken.xml"], ["well-formed"]),
    (["macbeth", "--width", "0"], ["width", "at least 1"]),
    (["macbeth", "--height", "-5"], ["height"]),
    (["macbeth", "--spp", "0"], ["spp"]),
    (["macbeth", "--spp", "-4"], ["spp"]),
    (["macbeth", "--luminance", "0"], ["luminance"]),
    (["macbeth", "--luminance", "-10"], ["luminance"]),
    (["macbeth", "--luminance", "nan"], ["luminance"]),
    (["macbeth", "--bands", "700:400:10"], ["band grid"]),
    (["macbeth", "--bands", "300:700:10"], ["band grid"]),
    (["macbeth", "--bands", "abc"], ["band grid"]),
    (["macbeth", "--variant", "llvm_ad_rgb"], ["variant"]),
    (["macbeth", "--width", "ten"], ["width"]),
])
def test_bad_input_is_one_line_exit_2_and_leaves_nothing(tmp_path, args, needles):
    (tmp_path / "broken.xml").write_text("<scene version='3.0.0'><shape type='sphere'>")
    out = tmp_path / "out"
    proc = run_cli("render", *[a.format(tmp=tmp_path) for a in args], "--out", out)
    assert_one_line_error(proc, *needles)
    assert not out.exists()


def test_unwritable_output_is_refused_before_rendering(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    for out, needle in [(blocker, "is a file"), (blocker / "sub", "is a file"), ("/proc/cfa-mitsuba-test", "output directory")]:
        proc = run_cli("render", "macbeth", "--out", out, "--width", 64, "--height", 48)
        assert_one_line_error(proc, needle)
        assert "rendered" not in proc.stderr
    assert blocker.read_text() == "x"
