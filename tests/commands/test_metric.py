"""``cfa-mitsuba metric``: one JSON object on stdout, notices on stderr, exit 2
with one line on bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import assert_one_line_error, run_cli
from reference_data import EXPECTED, REFERENCE, input_path

from cfa_mitsuba.cli import main


@pytest.fixture
def cli(capsys):
    """Run the CLI in this process (fast); a few tests below use a real subprocess."""
    from types import SimpleNamespace

    def run(*args):
        capsys.readouterr()
        try:
            rc = main([str(a) for a in args])
        except SystemExit as exc:  # argparse errors
            rc = exc.code
        out = capsys.readouterr()
        return SimpleNamespace(returncode=rc, stdout=out.out, stderr=out.err)

    return run

COLOUR = REFERENCE / "inputs" / "colour"


def ref_value(entries, oracle, variant):
    (e,) = [e for e in entries if e["oracle"] == oracle and e["variant"] == variant]
    return e["value"]


def one_json(proc):
    assert proc.returncode == 0, proc.stderr
    lines = [l for l in proc.stdout.splitlines() if l.strip()]
    assert len(lines) == 1, proc.stdout
    return json.loads(lines[0])


@pytest.mark.parametrize("name,oracle,variant", [
    ("ssim", "ssim_index.m", "gray|no_downsampling"),
    ("mdsi", "MDSI.m", "sum"),
    ("haarpsi", "HaarPSI.m", "rgb"),
])
def test_png_pair_json_matches_reference(cli, name, oracle, variant):
    out = one_json(cli("metric", name, COLOUR / "scene_ref.png", COLOUR / "scene_bayer_bilinear.png", "--json"))
    want = ref_value(EXPECTED["colour_pairs"]["scene_bayer_bilinear"][name], oracle, variant)
    assert out["metric"] == name and out["value"] == pytest.approx(want, abs=1e-9)


def test_delta_e_per_pixel_headline_and_notice_on_stderr():
    proc = run_cli("metric", "delta-e", COLOUR / "scene_ref.png", COLOUR / "scene_hue_chroma.png", "--json")
    out = one_json(proc)
    want = ref_value(EXPECTED["colour_pairs"]["scene_hue_chroma"]["cielab"], "isetcam", "deltaEab|dE2000")
    assert out["value"] == pytest.approx(want["mean"], rel=1e-6) and out["unit"] == "dE00"
    assert "srgb8" in proc.stderr


def test_scielab_xyz_npy_and_mtf_16bit_png(cli, tmp_path):
    ref, shift = (input_path(f"xyz/xyz_scene_{k}.npy", tmp_path) for k in ("ref", "shift"))
    out = one_json(cli("metric", "scielab", ref, shift,
                           "--samples-per-degree", "72", "--version", "1976", "--json"))
    want = ref_value(EXPECTED["xyz_pairs"]["scene_shift"]["scielab"], "isetcam", "scielab|spd=72|xyz2|dE1976")
    assert out["mean_interior"] == pytest.approx(want["mean_interior"], rel=2e-6)
    assert out["map"]["shape"] == [192, 256]  # summarised, not dumped
    edge = REFERENCE / "inputs" / "edges" / "edge_05deg_rgb.png"
    out = one_json(cli("metric", "mtf", edge, "--json", "--pixel-pitch-um", "2.2"))
    lum = ref_value(EXPECTED["slanted_edges"]["edge_05deg_rgb"]["mtf"], "sfrmat3", "sfrmat3")["lum"]["mtf50"]
    assert out["unit"] == "cy/mm" and out["mtf50_cy_px"] == pytest.approx(lum, rel=0.01)


def test_moire_with_geometry_sidecar_and_mean_match(cli, tmp_path):
    from cfa_mitsuba.io import write_image

    h, w = 31, 120
    ideal = np.full((h, w, 3), [47.525, 50.0, 54.45])
    write_image(tmp_path / "ideal.exr", ideal)
    write_image(tmp_path / "camera.exr", ideal * 0.5)
    side = {"oversample": 2, "geometry": {"frequency_cy_per_deg": np.linspace(0, 24, 2 * w).tolist(), "row": 30}}
    (tmp_path / "chirp.json").write_text(json.dumps(side))
    proc = cli("metric", "moire", tmp_path / "ideal.exr", tmp_path / "camera.exr", "--geometry",
                   tmp_path / "chirp.json", "--white", "95.05,100,108.9", "--mean-match", "--json")
    out = one_json(proc)
    assert out["passed"] is False and out["row"] == 15 and out["unit"] == "cy/deg"
    assert "mean-matched" in proc.stderr


@pytest.mark.parametrize("args,needle", [
    (("ssim", COLOUR / "scene_ref.png", COLOUR / "big_ref.png"), "differ in size"),
    (("ssim", COLOUR / "scene_ref.png", COLOUR / "missing.png"), "no such file"),
    (("scielab", COLOUR / "scene_ref.png", COLOUR / "scene_quant8.png"), "samples-per-degree"),
    (("mtf", COLOUR / "flat_ref.png"), "no edge"),
    (("mtf", COLOUR / "scene_ref.png", COLOUR / "scene_ref.png"), "one image"),
    (("moire", COLOUR / "scene_ref.png", COLOUR / "scene_quant8.png"), "frequency"),
])
def test_bad_input_is_one_line_exit_2(cli, args, needle):
    assert_one_line_error(cli("metric", *args), needle)


def test_bad_input_in_a_real_process_has_no_traceback():
    assert_one_line_error(run_cli("metric", "mtf", COLOUR / "flat_ref.png"), "no edge")


def test_list_metrics(cli):
    proc = cli("list", "metrics")
    assert proc.returncode == 0
    import cfa_mitsuba as cm

    names = [l.split()[0] for l in proc.stdout.splitlines()]
    assert names == list(cm.metrics.metric_names())  # every registered metric, in the registry's order
    assert names[:len(cm.metrics.scored_metrics())] == list(cm.metrics.scored_metrics())  # the scored first


def test_processed_npz_white_is_used_unless_white_given(cli, tmp_path):
    """A 'cfa-mitsuba process' .npz stores the white of its absolute XYZ;
    delta-e on two of them uses it (here a 250 cd/m^2 white, far from the
    sRGB default's 100), and --white still overrides it."""
    import cfa_mitsuba as cm

    rng = np.random.default_rng(3)
    white = np.array([237.6, 250.0, 272.2])
    ref = rng.uniform(10, 200, (24, 32, 3))
    test = ref * rng.uniform(0.95, 1.05, ref.shape)
    for name, xyz in (("ref", ref), ("test", test)):
        np.savez(tmp_path / f"{name}.npz", xyz=xyz, srgb=np.zeros_like(xyz), white_xyz=white, meta="{}")
    args = ("metric", "delta-e", tmp_path / "ref.npz", tmp_path / "test.npz", "--json")
    proc = cli(*args)
    got = one_json(proc)["value"]
    assert got == pytest.approx(float(cm.metrics.delta_e(ref, test, white)), rel=1e-12)
    assert "white_xyz" in proc.stderr
    default = float(cm.metrics.delta_e(ref, test, np.array([95.05, 100.0, 108.9])))
    assert abs(got - default) > 0.1  # the stored white matters
    assert one_json(cli(*args, "--white", "95.05,100,108.9"))["value"] == pytest.approx(default, rel=1e-12)
