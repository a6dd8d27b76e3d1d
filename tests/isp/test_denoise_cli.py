"""``cfa-mitsuba process --denoise/--sharpen`` and ``list denoise``."""

from __future__ import annotations

import numpy as np

import cfa_mitsuba as cm
from conftest import assert_one_line_error, run_cli


def test_list_denoise_shows_both_stages():
    out = run_cli("list", "denoise", check_rc=0).stdout
    for name in ("none", "wavelet", "nl-means", "wavelet-ti", "unsharp"):
        assert f"\n{name} " in "\n" + out
    assert "sharpen: unsharp" in out and "denoise: [raw|rgb]" in out


def test_process_denoises_and_sharpens(tmp_path):
    from cfa_mitsuba.io.raw_npz import save_raw_npz

    img = cm.render.render_cached("gray-bar", width=320, height=96)
    raw = cm.sensor.capture(img, "bayer", luminance_cd_m2=10.0, noise="all", seed=1)
    path = tmp_path / "raw.npz"
    save_raw_npz(path, raw)
    proc = run_cli("process", str(path), "--denoise", "wavelet", "--sharpen", "unsharp", "--radius", "2",
                   "--out", str(tmp_path / "o.npz"), check_rc=0)
    assert "denoise wavelet, sharpen unsharp" in proc.stdout
    with np.load(tmp_path / "o.npz") as z:
        assert z["xyz"].shape == (96, 320, 3)
    bad = run_cli("process", str(path), "--denoise", "bm3d", "--out", str(tmp_path / "x.png"))
    assert_one_line_error(bad, "unknown denoiser 'bm3d'")
    bad = run_cli("process", str(path), "--radius", "2", "--out", str(tmp_path / "x.png"))
    assert_one_line_error(bad, "--radius and --amount apply to --sharpen unsharp")
