"""One evaluation task: an output that cannot be measured is a failure
record in failures.csv, not an aborted run or a silent row."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.values import SpectralImage
from conftest import run_cli

WL = spectra.DEFAULT_WAVELENGTHS


def _frame_exr(path, metrics):
    """A 40 x 40 scene lit in a 4-pixel frame, dark inside, with the sidecar
    a render gives; ``metrics`` is the list the sidecar names."""
    d65 = spectra.illuminant("D65", WL)
    white = d65 * (100.0 / spectra.luminance_cd_m2(d65, WL))
    data = np.zeros((40, 40, WL.size))
    data[:4], data[-4:], data[:, :4], data[:, -4:] = white, white, white, white
    meta = {"scene": "frame", "fov_deg": 10.0, "scene_distance_m": 1.2, "oversample": 1,
            "illuminant": "D65", "white_radiance": white.tolist(), "metrics": list(metrics)}
    cm.io.write_spectral_exr(path, SpectralImage(data, WL.copy(), meta), preview=False)


def test_unmeasurable_metric_goes_to_failures_csv(tmp_path):
    """moire needs the chirp's frequency map, which this scene's sidecar
    lacks, and MTF finds no edge in it: their values are failures, each with
    its reason; SSIM's are rows."""
    renders = tmp_path / "renders"
    renders.mkdir()
    _frame_exr(renders / "frame.exr", ["moire", "mtf", "ssim"])
    out = tmp_path / "out"
    # one realisation: this frame's noise decides whether an "edge" is found in it, realisation by realisation
    proc = run_cli("evaluate", "--renders", renders, "--cfa", "bayer,rgbw1", "--demosaic", "bilinear,pocs",
                   "--luminance", "100", "--seeds", "1", "--out", out, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr and "could not be measured" in proc.stderr
    failures = pd.read_csv(out / "failures.csv")
    assert len(failures) == 2 * 2 * 2 and set(failures["metric"]) == {"moire", "mtf"}
    reasons = dict(zip(failures["metric"], failures["error"]))
    assert "frequency_cy_per_deg" in reasons["moire"] and "no edge" in reasons["mtf"]
    metrics = pd.read_csv(out / "metrics.csv")
    assert set(metrics["metric"]) == {"ssim"} and len(metrics) == 4
    assert np.isfinite(metrics["value"]).all()


def test_black_ideal_interior_is_a_recorded_failure(tmp_path, monkeypatch):
    """mean_match refuses a black reference interior (any camera would be
    scaled to 0 and score perfectly); the task records every metric of that
    output as a failure and goes on.  Optics leave light everywhere, so the
    refusal is injected here (mean_match's own test covers when it fires)."""
    from cfa_mitsuba import metrics
    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.study import tasks

    exr = tmp_path / "frame.exr"
    _frame_exr(exr, ["ssim", "haarpsi"])

    def refuse(*args, **kwargs):
        raise CfaMitsubaError("cannot mean-match: the reference image's interior mean is 0 (need > 0)")

    monkeypatch.setattr(metrics, "mean_match", refuse)
    from cfa_mitsuba.study.chain import ChainSettings
    from cfa_mitsuba.study.conditions import Condition

    task = {"source": {"kind": "exr", "path": str(exr)}, "scene": "frame", "condition": Condition(100.0),
            "cfa": "bayer", "demosaics": ["bilinear", "pocs"], "metrics": ["ssim", "haarpsi"],
            "chain": ChainSettings(), "details_dir": None}
    result = tasks.evaluate_task(task)
    assert result.rows == []
    assert len(result.failures) == 4
    assert {(f["demosaic"], f["metric"]) for f in result.failures} == {
        (d, m) for d in ("bilinear", "pocs") for m in ("ssim", "haarpsi")}
    assert all("interior mean is 0" in f["error"] for f in result.failures)


def test_unreachable_scheduler_is_refused_before_anything_is_written(tmp_path, monkeypatch):
    import pytest

    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.study import executors
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import run_study
    from conftest import REPO

    monkeypatch.setitem(executors.DaskExecutor.__init__.__kwdefaults__, "timeout_s", 2.0)
    out = tmp_path / "out"
    with pytest.raises(CfaMitsubaError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:1"):
        run_study(load_config(REPO / "configs" / "quick.toml"), out, scheduler="tcp://127.0.0.1:1",
                  progress=False, log=lambda m: None)
    assert list(out.iterdir()) == []


def test_evaluate_seeds_gives_real_intervals(tmp_path):
    """``evaluate --seeds N`` (issue 24): N noise realisations per capture, so every value has
    n = N and an interval of non-zero width; a failure is listed once, not once per realisation;
    --seeds 0 is one line and exit 2."""
    renders = tmp_path / "renders"
    renders.mkdir()
    _frame_exr(renders / "frame.exr", ["ssim", "mtf"])
    out = tmp_path / "out"
    proc = run_cli("evaluate", "--renders", renders, "--cfa", "bayer", "--demosaic", "bilinear",
                   "--luminance", "20", "--seeds", "2", "--out", out, "--quiet")
    assert proc.returncode == 0, proc.stderr
    m = pd.read_csv(out / "metrics.csv")
    assert (m["n"] == 2).all() and (m["ci_high"] > m["ci_low"]).all()
    assert len(pd.read_csv(out / "failures.csv")) == 1  # mtf: no edge, once
    bad = run_cli("evaluate", "--renders", renders, "--cfa", "bayer", "--demosaic", "bilinear",
                  "--seeds", "0", "--out", tmp_path / "bad")
    assert bad.returncode == 2 and "--seeds must be at least 1" in bad.stderr and "Traceback" not in bad.stderr


def test_thumbnail_is_the_display_encoding_of_the_block_mean_in_linear_light(tmp_path):
    """The report's preview: XYZ averaged over blocks, then the image's own
    display encoding (the scene white adapted to sRGB's: a warm white shows
    white); equal to the full-size display image wherever a block is uniform."""
    from PIL import Image

    from cfa_mitsuba.isp import xyz_to_srgb
    from cfa_mitsuba.study.tasks import _thumbnail
    from cfa_mitsuba.values import RenderedImage

    rng = np.random.default_rng(4)
    white = np.array([109.85, 100.0, 35.58])  # illuminant A: adaptation matters
    xyz = np.repeat(np.repeat(rng.random((20, 31, 3)) * 80, 3, axis=0), 3, axis=1)  # 60 x 93, uniform 3 x 3 blocks
    xyz[:3, :3] = white  # one block is the scene white
    noisy = xyz + rng.normal(0, 5, xyz.shape)  # blocks no longer uniform: linear mean != encoded mean
    for img, uniform in ((xyz, True), (noisy, False)):
        path = tmp_path / f"t{uniform}.png"
        rendered = RenderedImage(xyz=img, srgb=xyz_to_srgb(img, white), white_xyz=white, meta={})
        _thumbnail(rendered, path, longest=31)
        with Image.open(path) as im:
            got = np.asarray(im, dtype=np.float64)
        assert got.shape == (20, 31, 3)
        small = img.reshape(20, 3, 31, 3, 3).mean(axis=(1, 3))
        np.testing.assert_allclose(got, np.round(255 * xyz_to_srgb(small, white)), atol=0.5)
        full = rendered.srgb.reshape(20, 3, 31, 3, 3).mean(axis=(1, 3))
        assert np.allclose(got, np.round(255 * full), atol=0.5) == uniform
        if uniform:
            np.testing.assert_allclose(got[0, 0], 255.0, atol=1.0)  # the scene white shows white


@pytest.mark.parametrize("shape", [(636, 720, 3), (636, 720), (481, 250), (7, 5, 3), (250, 481, 2)])
def test_block_mean_is_the_mean_of_each_whole_block(shape):
    """The report's reduced maps and thumbnails: the mean of each step x step
    block (step brings the longer side to at most 240 px; partial blocks at
    the right and bottom dropped), against numpy's mean over the block axes."""
    from cfa_mitsuba.study.tasks import _block_mean

    a = np.random.default_rng(sum(shape)).random(shape)
    h, w = shape[:2]
    step = max(1, -(-max(h, w) // 240))
    hh, ww = h // step * step, w // step * step
    want = a[:hh, :ww].reshape(hh // step, step, ww // step, step, *shape[2:]).mean(axis=(1, 3))
    got = _block_mean(a)
    assert got.shape == want.shape == (h // step, w // step, *shape[2:])
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=0)


def test_summary_options_skip_only_what_no_row_reads(tmp_path, monkeypatch):
    """S-CIELAB's median and 95th percentile (a partial sort of the whole
    map) are computed for the camera outputs whose details the task keeps
    (the first realisation) and left out of the others (the record's
    ``summary_options``); every row is the same as with the order statistics
    computed for all, and the kept details still hold them.  A config that
    sets the option itself wins."""
    import json

    from cfa_mitsuba import metrics
    from cfa_mitsuba.metrics import _result
    from cfa_mitsuba.study import tasks
    from cfa_mitsuba.study.chain import ChainSettings
    from cfa_mitsuba.study.conditions import Condition

    exr = tmp_path / "frame.exr"
    _frame_exr(exr, ["scielab", "ssim"])
    sorts = []
    real = _result.median_and_p95
    monkeypatch.setattr(_result, "median_and_p95", lambda v: sorts.append(v.size) or real(v))

    def run(details, chain=ChainSettings()):
        sorts.clear()
        task = {"source": {"kind": "exr", "path": str(exr)}, "scene": "frame", "condition": Condition(30.0),
                "cfa": "bayer", "demosaics": ["bilinear", "pocs"], "metrics": ["scielab", "ssim"],
                "chain": chain, "details_dir": str(details), "realisations": 3}
        return tasks.evaluate_task(task).rows, len(sorts)

    rows, n_sorts = run(tmp_path / "d1")
    kept = json.loads((tmp_path / "d1" / "frame" / "bayer" / "pocs" / "L30.json").read_text())
    assert kept["scielab"]["median"] is not None and kept["scielab"]["p95"] is not None

    monkeypatch.setattr(metrics, "summary_options", lambda: {})
    rows_all, n_all = run(tmp_path / "d2")
    assert n_all == n_sorts + 4 and rows_all == rows  # the 2 x 2 outputs of realisations 1 and 2 sorted no map
    assert {r["metric"] for r in rows} == {"scielab", "scielab-interior", "ssim"} and len(rows) == 3 * 2 * 3
    monkeypatch.undo()
    monkeypatch.setattr(_result, "median_and_p95", lambda v: sorts.append(v.size) or real(v))
    forced = ChainSettings(metric_options=(("scielab", (("order_statistics", True),)),))
    assert run(tmp_path / "d3", forced) == (rows, n_all)
