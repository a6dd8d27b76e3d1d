"""``cfa-mitsuba convergence``: error against run time (issue 7, acceptance 2).

One real end-to-end run on the path-traced puppy at a tiny size (the scene
whose error does depend on spp), a chart run through the Python API (its
renders are exact quadratures: the error must sit at float32 rounding at
every spp), the helpers against independent numbers, and every bad input.
"""

import csv
import json

import numpy as np
import pytest

from cfa_mitsuba.report.convergence import write_convergence
from cfa_mitsuba.study import convergence as conv
from conftest import assert_one_line_error, run_cli

COLUMNS = ["scene", "stage", "quality", "wall_s", "quantity", "error", "unit", "value"]


@pytest.mark.slow
def test_puppy_tiny_run_writes_csv_json_and_plot(tmp_path):
    out = tmp_path / "conv"
    proc = run_cli("convergence", "puppy", "--out", out, "--width", 48, "--height", 42, "--spp", "1,4,16",
                   "--reference-spp", 144, "--pocs-iterations", "1,2,4", "--pocs-reference", 16, "--repeat", 2,
                   "--compare-cfas", "bayer,rgbw1", "--noise-seeds", 2, check_rc=0)
    csv_path, json_path = out / "convergence_puppy.csv", out / "convergence_puppy.json"
    png, svg = out / "convergence_puppy.png", out / "convergence_puppy.svg"
    assert proc.stdout.split()[-4:] == [str(csv_path), str(json_path), str(png), str(svg)]
    assert "reference render 1/2" in proc.stderr  # progress goes to stderr
    assert "spp" in proc.stdout and "pocs it" in proc.stdout

    with open(csv_path, newline="") as fh:
        reader = csv.DictReader(fh)
        assert reader.fieldnames == COLUMNS
        rows = list(reader)
    stages = {r["stage"] for r in rows}
    assert {"render", "pocs", "reference", "sensor-noise", "cfa-spread", "cfa-gap"} <= stages
    render = [r for r in rows if r["stage"] == "render"]
    assert sorted({int(r["quality"]) for r in render}) == [1, 4, 16]
    assert all(float(r["wall_s"]) > 0 for r in render)
    # 31 bands, image and uniform region, per level; every scene metric per level.
    assert sum(r["quantity"].startswith("radiance:") for r in render) == 3 * 31
    assert sum(r["quantity"].startswith("uniform:") for r in render) == 3 * 31
    for m in ("scielab", "ssim", "mdsi", "haarpsi"):
        assert sum(r["quantity"] == m for r in render) == 3

    def median_error(spp):
        return np.median([float(r["error"]) for r in render
                          if int(r["quality"]) == spp and r["quantity"].startswith("radiance:")])

    e1, e4, e16 = median_error(1), median_error(4), median_error(16)
    assert e1 > e4 > e16 > 0  # Monte Carlo noise falls with spp ...
    assert 1.5 < e1 / e16 < 8  # ... about as 1/sqrt(spp) (4x from 1 to 16), never faster than 1/spp

    summary = json.loads(json_path.read_text())
    rate = summary["rates"]["render"]["radiance, image, median band"]
    # Against time the slope is finite; its value at 48 x 42 pixels is set by fixed costs (scene build,
    # white probe), so only the slope against spp is checked.
    assert rate["per_wall_time"] is not None and np.isfinite(rate["per_wall_time"])
    assert -1.0 < rate["per_spp"] < -0.25
    assert all(np.isfinite(v["per_wall_time"]) for v in summary["rates"]["pocs"].values()
               if v["per_wall_time"] is not None)
    assert summary["reference"]["seeds"] == [1, 2]
    assert 0 < summary["reference"]["own_noise_image_median_band"] < e16
    assert summary["pocs_default"]["iterations_done"] <= 10
    assert set(summary["checks"]) >= {"scielab", "ssim", "mdsi", "haarpsi"}

    # The plot is a real figure: big, and not one flat colour.
    from PIL import Image

    im = np.asarray(Image.open(png).convert("L"), dtype=float)
    assert im.shape[0] > 400 and im.shape[1] > 1000
    assert im.std() > 10 and (im < 128).mean() > 0.005
    text = svg.read_text()
    assert text.lstrip().startswith("<?xml") and text.count("<path") > 50


@pytest.mark.slow
def test_chart_renders_are_exact_at_every_spp(tmp_path):
    plan = conv.make_plan("gray-bar", width=60, height=24, spp=[1, 4], reference_spp=16, pocs_iterations=[1, 2],
                          pocs_reference_iterations=4, repeat=1, compare_cfas=(), noise_seeds=0)
    res = conv.run_convergence(plan, log=lambda msg: None)
    rad = [r["error"] for r in res.rows if r["stage"] == "render" and r["quantity"].startswith("radiance:")]
    assert len(rad) == 2 * 31 and max(rad) < conv.FLOAT_FLOOR  # float32 rounding, nothing to converge
    s = res.summary
    assert s["reference"]["exact_check"]["relative_rms_worst_band"] < 1e-6  # independent of Mitsuba
    assert s["rates"]["render"]["radiance, image, median band"]["per_wall_time"] is None  # all below the floor
    dev = [r["error"] for r in res.rows if r["stage"] == "render" and r["quantity"] == "achromatic"]
    assert len(dev) == 2 and max(dev) < 1e-6
    paths = write_convergence(res, tmp_path, formats=("png",))
    assert paths["png"].stat().st_size > 20_000
    assert "gray-bar" in conv.format_table(res)


def test_relative_rms_per_band_against_hand_numbers():
    ref = np.ones((4, 5, 2))
    ref[..., 1] = 2.0
    test = ref.copy()
    test[0, 0, 0] += 2.0  # one pixel of 20 off by 2: rms = sqrt(4/20)
    got = conv.relative_rms_per_band(test, ref)
    np.testing.assert_allclose(got, [np.sqrt(4 / 20) / 1.0, 0.0])
    np.testing.assert_allclose(conv.relative_rms_per_band(test, ref, (1, 0, 4, 5)), [0.0, 0.0])


def test_uniform_region_finds_the_flat_window():
    rng = np.random.default_rng(0)
    lum = 10 + rng.normal(0, 1, (60, 80))
    lum[30:50, 40:60] = 10.0  # perfectly flat
    y0, x0, y1, x1 = conv.uniform_region(lum, side=10)
    assert 30 <= y0 and y1 <= 50 and 40 <= x0 and x1 <= 60


def test_fit_rate_recovers_a_power_law_and_skips_the_floor():
    t = np.array([1.0, 4.0, 16.0, 64.0, 256.0])
    e = 0.3 * t ** -0.5
    assert conv.fit_rate(t, e)["rate"] == pytest.approx(-0.5)
    # The last two points sit on a floor of 0.03: left out of the fit.
    floored = np.sqrt(e ** 2 + 0.03 ** 2)
    r = conv.fit_rate(t, floored, 0.03)
    assert r["points"] == 3 and r["rate"] == pytest.approx(-0.5, abs=0.05)
    assert conv.fit_rate(t, np.zeros(5))["rate"] is None
    assert conv.fit_rate([1.0], [1.0])["rate"] is None


def test_default_levels_and_square_rounding():
    assert conv.default_spp_levels(16) == (1, 4, 16, 64)
    assert conv.default_spp_levels(100) == (1, 4, 16, 64, 100, 256)
    plan = conv.make_plan("macbeth", spp=[1, 5, 16], compare_cfas=())
    assert plan.spp_levels == (1, 9, 16) and plan.reference_spp == 256
    assert (plan.width, plan.height) == (720, 636)
    puppy = conv.make_plan("puppy")
    # the puppy's 400 spp default (20 x 20 strata), its reference 16 x that, its levels the powers of 4 around it
    assert (puppy.width, puppy.height) == (240, 212) and puppy.default_spp == 400 and puppy.reference_spp == 6400
    assert puppy.spp_levels == (1, 4, 16, 64, 256, 400, 1024)


@pytest.mark.parametrize("args, needle", [
    (["no-such-scene"], "unknown scene"),
    (["macbeth", "--spp", "4,1"], "increase"),
    (["macbeth", "--spp", "0,4"], "at least 1"),
    (["macbeth", "--spp", "-4"], "--spp"),
    (["macbeth", "--spp", "1,x"], "whole numbers"),
    (["macbeth", "--spp", "5,6"], "round up"),
    (["macbeth", "--spp", "1,4", "--reference-spp", "4"], "exceed"),
    (["macbeth", "--pocs-iterations", "2,2"], "increase"),
    (["macbeth", "--pocs-iterations", "10,60"], "below"),
    (["macbeth", "--cfa", "nope"], "unknown CFA"),
    (["macbeth", "--demosaic", "nope"], "unknown demosaicing"),
    (["macbeth", "--compare-cfas", "bayer,nope"], "unknown CFA"),
    (["macbeth", "--width", "0"], "at least 1"),
    (["slanted-edge", "--width", "250"], "multiples"),
    (["macbeth", "--formats", "jpg"], "png"),
])
def test_bad_input_exits_2_with_one_line(args, needle, tmp_path, capsys):
    assert_one_line_error(_main_in_process(capsys, "convergence", *args, "--out", tmp_path / "o"), needle)
    assert not (tmp_path / "o").exists()  # refused before any output


def test_bad_input_through_the_real_command_line(tmp_path):
    assert_one_line_error(run_cli("convergence", "macbeth", "--spp", "16,4", "--out", tmp_path), "increase")
    assert_one_line_error(run_cli("convergence", "nope.xml", "--out", tmp_path), "nope.xml")


def _main_in_process(capsys, *args):
    """cli.main in this process (a subprocess per case costs 3 s of imports):
    the exit status and what reached stderr, as run_cli returns them."""
    from types import SimpleNamespace

    from cfa_mitsuba import cli

    capsys.readouterr()
    try:
        rc = cli.main([str(a) for a in args])
    except SystemExit as exc:  # argparse
        rc = exc.code
    err = capsys.readouterr().err
    return SimpleNamespace(returncode=rc, stderr=err, stdout="")


def test_unwritable_out_exits_2_before_rendering(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert_one_line_error(_main_in_process(capsys, "convergence", "gray-bar", "--out", blocker), "is a file")
    # a directory that cannot be created (its parent is a regular file): the
    # same refusal as an unwritable one, and it binds root too
    assert_one_line_error(_main_in_process(capsys, "convergence", "gray-bar", "--out", blocker / "sub"),
                          "output directory")
