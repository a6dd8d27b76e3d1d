"""Hardening, round three (issue 27), items 6 and 9: metrics refuse what
they cannot measure (an infinity, a finite but absurd 1e300) instead of
clipping it or crashing on it, and ``process`` checks a raw file's pixels
against its tile and its recorded settings.  Each case: exit 2, one line
naming the file and the problem, nothing written."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import assert_one_line_error, run_cli

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.io import save_raw_npz
from cfa_mitsuba.values import SpectralImage

GREY = [40.0, 42.0, 45.0]


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    d = tmp_path_factory.mktemp("metric_inputs")
    ref = np.full((32, 32, 3), GREY) * np.linspace(0.5, 1.0, 32)[None, :, None]
    inf, big = ref.copy(), ref.copy()
    inf[3, 3, 1] = np.inf
    big[5, 7] = 1e300
    for name, arr in (("ref", ref), ("inf", inf), ("big", big)):
        np.save(d / f"{name}.npy", arr)
    return d


@pytest.mark.parametrize("metric", ["ssim", "mdsi", "haarpsi"])
@pytest.mark.parametrize("mode", ["linear", "xyz"])
def test_display_metrics_refuse_an_infinite_pixel(images, metric, mode):
    # linear input used to be clipped to 0..1 before the check: Inf became the white and ssim printed ~1
    proc = run_cli("metric", metric, images / "ref.npy", images / "inf.npy", "--input", mode)
    assert_one_line_error(proc, "inf.npy", "infinite")


@pytest.mark.parametrize("metric", ["delta-e", "scielab", "ssim", "achromatic"])
def test_a_finite_but_absurd_value_is_refused_not_a_key_error(images, metric):
    # 1e300 overflowed the CIEDE2000 maths to NaN: delta-e's mean skipped it (or KeyError: 'mean' when all were)
    proc = run_cli("metric", metric, images / "ref.npy", images / "big.npy", "--samples-per-degree", 30)
    assert_one_line_error(proc, "big.npy", "1e+300")


@pytest.mark.parametrize("fn", [cm.metrics.delta_e, cm.metrics.scielab])
def test_library_functions_refuse_huge_xyz(fn):
    huge = np.full((24, 24, 3), 1e300)
    kw = {"samples_per_degree": 20.0} if fn is cm.metrics.scielab else {}
    with pytest.raises(CfaMitsubaError, match="reference image has 1728 value"):
        fn(huge, huge, [95.05, 100.0, 108.9], **kw)


def test_the_bound_leaves_bright_scenes_alone():
    # the sun's disc (1.6e9 cd/m^2) is far inside the bound: still a number, dE of an image with itself is 0
    sun = np.full((8, 8, 3), [1.5e9, 1.6e9, 1.7e9])
    assert float(cm.metrics.delta_e(sun, sun, [1.5e9, 1.6e9, 1.7e9])) == 0.0


# ------------------------------------------------------------------ process (item 9)

@pytest.fixture(scope="module")
def bayer_npz(tmp_path_factory):
    d = tmp_path_factory.mktemp("raws")
    data = np.random.default_rng(0).uniform(0.005, 0.02, (12, 16, 31))
    scene = SpectralImage(data, cm.spectra.DEFAULT_WAVELENGTHS, {"fov_deg": 12.0, "scene_distance_m": "inf"})
    oi = cm.optics.compute_optics(scene)
    out = {}
    for noise in ("all", "off"):
        p = d / f"bayer_{noise}.npz"
        save_raw_npz(p, cm.sensor.capture(oi, "bayer", seed=3, noise=noise))
        out[noise] = p
    return out


def _altered(src, dst, **changes):
    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    arrays.update(changes)
    np.savez(dst, **arrays)
    return dst


def _raw(src):
    with np.load(src, allow_pickle=False) as z:
        return z["raw"].copy()


@pytest.mark.parametrize("noise", ["all", "off"])
def test_good_raws_still_process(bayer_npz, tmp_path, noise):
    proc = run_cli("process", bayer_npz[noise], "--out", tmp_path / "o.npz")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "o.npz").is_file()


def _bad_cases(bayer_npz):
    good = _raw(bayer_npz["all"])
    neg, huge = good.copy(), good.copy()
    neg[1, 1], huge[2, 2] = -5.0, 1e300
    off_huge = _raw(bayer_npz["off"])
    off_huge[0, 0] = 1e300
    return {
        "3-D": (bayer_npz["all"], {"raw": np.repeat(good[..., None], 3, axis=2)}, "2-D mosaic"),
        "black": (bayer_npz["all"], {"black_level_dn": np.array(1e9)}, "black_level_dn"),
        "black_vs_settings": (bayer_npz["all"], {"black_level_dn": np.array(100.0)}, "contradicts its settings"),
        "negative": (bayer_npz["all"], {"raw": neg}, "negative DN"),
        "huge": (bayer_npz["all"], {"raw": huge}, "1e+300"),
        "huge_unquantised": (bayer_npz["off"], {"raw": off_huge}, "fullest well"),
    }


@pytest.mark.parametrize("case", ["3-D", "black", "black_vs_settings", "negative", "huge", "huge_unquantised"])
def test_process_refuses_raws_that_contradict_themselves(bayer_npz, tmp_path, case):
    src, changes, needle = _bad_cases(bayer_npz)[case]
    bad = _altered(src, tmp_path / f"bad_{case}.npz", **changes)
    out = tmp_path / "out.png"
    proc = run_cli("process", bad, "--out", out)
    assert_one_line_error(proc, f"bad_{case}.npz", needle)
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == [bad.name]
