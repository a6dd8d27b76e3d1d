"""Issue 15: every bad input is a clean refusal, memory is checked before it
is spent, outputs stay where the user said.

One test per row of the issue's table (the scene-XML rows are the user-XML
module's): each bad input gives exit 2, one line on stderr, no traceback and
no file left behind; the memory refusals use ``CFA_MITSUBA_MEMORY_LIMIT``
(cfa_mitsuba.io.limits) to make a small machine.  docs/stability.md, section
11, lists every row with its message.
"""

from __future__ import annotations

import io
import json
import subprocess
import sys
import zipfile

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.values import SpectralImage
from conftest import REPO, assert_one_line_error, run_cli

WL = cm.spectra.DEFAULT_WAVELENGTHS


def _files(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def refused(folder, *args, needles=()):
    """Run the CLI; assert a one-line refusal and that ``folder`` is unchanged."""
    before = _files(folder)
    proc = run_cli(*args)
    assert_one_line_error(proc, *needles)
    assert _files(folder) == before, "a refused command left a file behind"
    return proc


# ------------------------------------------------------------------ fixtures


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A small chart EXR with its sidecar, a raw capture of it, an XYZ .npz."""
    d = tmp_path_factory.mktemp("inputs")
    refl = cm.spectra.colorchecker(WL)[1]
    d65 = cm.spectra.illuminant("D65", WL)
    data = (refl[np.arange(24).reshape(4, 6)] * d65).repeat(12, 0).repeat(12, 1)
    scale = 100.0 / cm.spectra.luminance_cd_m2(data, WL).mean()
    meta = {"width": 72, "height": 48, "fov_deg": 10.0, "oversample": 1, "white_radiance": (d65 * scale).tolist(),
            "luminance_cd_m2": 100.0, "geometry": {"patches": [{"rect": [0, 0, 12, 12]}]}}
    exr = d / "chart.exr"
    cm.io.write_spectral_exr(exr, SpectralImage(data * scale, WL, meta))
    cm.io.write_sidecar(exr.with_suffix(".json"), meta)
    raw = d / "bayer.npz"
    run_cli("capture", exr, "--cfa", "bayer", "--out", raw, check_rc=0)
    xyz = np.random.default_rng(0).uniform(1, 90, (48, 72, 3))
    good = d / "xyz.npz"
    np.savez(good, xyz=xyz, white_xyz=np.array([95.05, 100.0, 108.9]))
    return {"exr": exr, "meta": meta, "raw": raw, "xyz": good, "dir": d}


def _exr_with_sidecar(tmp_path, inputs, sidecar_text):
    exr = tmp_path / "scene.exr"
    exr.write_bytes(inputs["exr"].read_bytes())
    exr.with_suffix(".json").write_text(sidecar_text)
    return exr


def _raw_with(tmp_path, inputs, **changes):
    with np.load(inputs["raw"], allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    arrays.update(changes)
    p = tmp_path / "bad_raw.npz"
    np.savez(p, **arrays)
    return p


def _npz_declaring(path, name, shape):
    """An .npz whose member's header declares ``shape`` (float64) with no data behind it."""
    from numpy.lib import format as npf

    buf = io.BytesIO()
    npf.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False, "shape": shape})
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr(f"{name}.npy", buf.getvalue() + b"\0" * 64)
    return path


# ----------------------------------------------------- memory and render limits


def test_render_6000x6000_refused_before_allocating(tmp_path, monkeypatch):
    monkeypatch.setenv("CFA_MITSUBA_MEMORY_LIMIT", "16G")  # a 16 GiB machine
    out = tmp_path / "out"
    refused(tmp_path, "render", "macbeth", "--width", 6000, "--height", 6000, "--spp", 1, "--out", out,
            needles=("6000 x 6000", "needs about 43", "17.2 GB available", "CFA_MITSUBA_MEMORY_LIMIT"))


def test_render_20000x20000_film_beyond_drjit_refused(tmp_path):
    refused(tmp_path, "render", "macbeth", "--width", 20000, "--height", 20000, "--spp", 1, "--out", tmp_path / "o",
            needles=("14,000,000,000 values", "2^32 - 1"))


def test_render_8000x8000_under_10_gb_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("CFA_MITSUBA_MEMORY_LIMIT", "10G")
    refused(tmp_path, "render", "macbeth", "--width", 8000, "--height", 8000, "--out", tmp_path / "o",
            needles=("8000 x 8000", "10.7 GB available"))


@pytest.mark.parametrize("args, needle", [
    (("puppy", "--width", 96, "--height", 64, "--spp", 1048576), "6,442,450,944 samples"),
    (("macbeth", "--width", 720, "--height", 636, "--spp", 10000), "use at most 9,216 spp"),
])
def test_render_above_2_32_samples_refused(tmp_path, args, needle):
    refused(tmp_path, "render", *args, "--out", tmp_path / "o", needles=(needle, "2^32 - 1"))


def test_render_at_the_sample_limit_is_accepted():
    """The limit is Mitsuba's wavefront: 2^32 - 1 samples pass, 2^32 do not."""
    from cfa_mitsuba.io import limits

    limits.check_render(1, 1, 2**32 - 1, 1)
    limits.check_render(4096, 1024, 1023, 1)
    with pytest.raises(CfaMitsubaError, match="4,294,967,296 samples"):
        limits.check_render(4096, 1024, 1024, 1)
    with pytest.raises(CfaMitsubaError, match="4,294,967,296 samples"):
        limits.check_render(1, 1, 2**32, 1)


def test_memory_refusal_comes_before_mitsuba(tmp_path):
    """Acceptance 2: with 100 MB available the default macbeth render (about
    0.7 GB) is refused before Mitsuba is imported (how fast:
    benchmarks/bench_refusals.py)."""
    env_code = ("import os, sys; os.environ['CFA_MITSUBA_MEMORY_LIMIT'] = '100M'\n"
                "from cfa_mitsuba.render import engine\n"
                "from cfa_mitsuba.errors import CfaMitsubaError\n"
                "try:\n    engine.render('macbeth')\nexcept CfaMitsubaError as e:\n    print(e)\n"
                "print('mitsuba imported:', 'mitsuba' in sys.modules)\n")
    proc = subprocess.run([sys.executable, "-c", env_code], capture_output=True, text=True, cwd=REPO)
    assert "needs about" in proc.stdout and "mitsuba imported: False" in proc.stdout, proc.stdout + proc.stderr
    import os

    env = {**os.environ, "CFA_MITSUBA_MEMORY_LIMIT": "100M"}
    proc = subprocess.run([sys.executable, "-m", "cfa_mitsuba", "render", "macbeth", "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, cwd=REPO, env=env)
    assert_one_line_error(proc, "needs about", "105 MB available")
    assert not (tmp_path / "o").exists()


def test_capture_and_process_memory_refused_from_headers(tmp_path, inputs, monkeypatch):
    monkeypatch.setenv("CFA_MITSUBA_MEMORY_LIMIT", "150M")
    refused(tmp_path, "capture", inputs["exr"], "--cfa", "bayer", "--out", tmp_path / "r.npz",
            needles=("capturing", "72 x 48 pixels x 31 bands", "needs about"))
    refused(tmp_path, "process", inputs["raw"], "--out", tmp_path / "x.npz", needles=("processing", "needs about"))


def test_limits_read_the_environment_and_the_machine(monkeypatch):
    from cfa_mitsuba.io import limits

    monkeypatch.delenv(limits.MEMORY_ENV, raising=False)
    have, source = limits.available_memory_bytes()
    assert have > 1 << 28 and source in ("physical memory", "the cgroup memory limit")
    monkeypatch.setenv(limits.MEMORY_ENV, "1.5G")
    assert limits.available_memory_bytes() == (int(1.5 * 2**30), f"${limits.MEMORY_ENV}")
    monkeypatch.setenv(limits.MEMORY_ENV, "lots")
    with pytest.raises(CfaMitsubaError, match="expected a size"):
        limits.available_memory_bytes()


# ------------------------------------------------------------------ sidecars


SIDECARS = {
    "white-lots": (lambda meta: json.dumps({**meta, "white_radiance": "lots"}),
                   "white_radiance: 'lots' is not of type 'array'"),
    "nested-100000": (lambda meta: "[" * 100000 + "]" * 100000, "nested more than 32 levels"),
    "nan": (lambda meta: json.dumps({**meta, "white_radiance": [float("nan")] * 31}), "NaN"),
    "fov-string": (lambda meta: json.dumps({**meta, "fov_deg": "wide"}), "fov_deg: 'wide' is not of type 'number'"),
}


@pytest.mark.parametrize("case", list(SIDECARS))
def test_bad_sidecar_refused_by_capture(tmp_path, inputs, case):
    make, needle = SIDECARS[case]
    text = make(inputs["meta"])
    exr = _exr_with_sidecar(tmp_path, inputs, text)
    refused(tmp_path, "capture", exr, "--cfa", "bayer", "--out", tmp_path / "r.npz", needles=(needle,))


@pytest.mark.parametrize("geometry, needle", [
    ({"patches": [{"rect": [0, "a", 4, 4]}]}, "geometry.patches[0].rect[1]: 'a' is not of type 'number'"),
    ({"roi": "everything"}, "geometry.roi"),
    ({"row": -3}, "geometry.row"),
])
def test_bad_geometry_refused_by_metric(tmp_path, inputs, geometry, needle):
    g = tmp_path / "G.json"
    g.write_text(json.dumps({"width": 72, "height": 48, "geometry": geometry}))
    refused(tmp_path, "metric", "delta-e", inputs["xyz"], inputs["xyz"], "--geometry", g, needles=(needle,))


def test_deep_sidecar_refused_by_metric_geometry(tmp_path, inputs):
    g = tmp_path / "G.json"
    g.write_text('{"geometry": ' + "{\"a\": " * 100000 + "1" + "}" * 100001)
    refused(tmp_path, "metric", "delta-e", inputs["xyz"], inputs["xyz"], "--geometry", g, needles=("nested",))


# --------------------------------------------------------- numpy files, by content


def _npy_named_npz(tmp_path):
    p = tmp_path / "array.npz"
    with open(p, "wb") as fh:
        np.save(fh, np.ones((4, 4, 3)))
    return p


def _huge(tmp_path, name):
    return _npz_declaring(tmp_path / "huge.npz", name, (200000, 200000))


def _pickled(tmp_path):
    p = tmp_path / "pickled.npz"
    np.savez(p, xyz=np.array([{"a": 1}, None], dtype=object))
    return p


NUMPY_CASES = {
    "npy-named-npz": (_npy_named_npz, "its content is a .npy array"),
    "header-200000x200000": (lambda t: _huge(t, "xyz"), "needs about 640 GB"),
    "pickled-object-array": (_pickled, "holds Python objects (a pickle): refused without unpickling"),
}


@pytest.mark.parametrize("case", list(NUMPY_CASES))
@pytest.mark.parametrize("command", ["metric", "process"])
def test_bad_numpy_files_refused_by_every_reader(tmp_path, case, command):
    make, needle = NUMPY_CASES[case]
    src = tmp_path / "in"
    src.mkdir()
    bad = make(src)
    if command == "process" and case == "header-200000x200000":
        bad = _huge(src, "raw")
    if command == "metric":
        refused(tmp_path, "metric", "ssim", bad, bad, needles=(needle,))
    else:
        refused(tmp_path, "process", bad, "--out", tmp_path / "out.npz", needles=(needle,))


def test_npz_without_xyz_refused_by_metric(tmp_path, inputs):
    """It used to read the 'srgb' array as XYZ (SSIM 0.089)."""
    p = tmp_path / "srgb_only.npz"
    with np.load(inputs["xyz"]) as z:
        np.savez(p, srgb=np.clip(z["xyz"] / 100, 0, 1), white_xyz=z["white_xyz"], meta=np.array("{}"))
    refused(tmp_path, "metric", "ssim", p, p, needles=("has no 'xyz' or 'image' array", "srgb"))
    refused(tmp_path, "metric", "delta-e", inputs["xyz"], p, needles=("has no 'xyz'",))


# ------------------------------------------------------------ raw files, physics


@pytest.mark.parametrize("change, needle", [
    ("negative-qe", "spectra of channel 0 is negative"),
    ("qe-above-1", "quantum efficiency must lie in 0..1"),
    ("negative-exposure", "exposure_s must be a positive number of seconds, got -0.01"),
    ("zero-gain", "dn_per_electron must be positive"),
    ("tile-not-pattern", "does not match its pattern array"),
    ("tile-unknown-filter", "not among its channels"),
])
def test_raw_physics_refused_by_process(tmp_path, inputs, change, needle):
    with np.load(inputs["raw"]) as z:
        spectra, settings = z["spectra"], json.loads(str(z["settings_json"]))
    changes = {
        "negative-qe": {"spectra": spectra - 0.5},
        "qe-above-1": {"spectra": spectra * 10},
        "negative-exposure": {"exposure_s": np.array(-0.01)},
        "zero-gain": {"dn_per_electron": np.array(0.0)},
        "tile-not-pattern": {"settings_json": np.array(json.dumps({**settings, "cfa": {**settings["cfa"],
                                                                                        "tile": "R G / G B"}}))},
        "tile-unknown-filter": {"pattern": np.array([["G", "R"], ["B", "W"]])},
    }[change]
    bad = _raw_with(tmp_path, inputs, **changes)
    refused(tmp_path, "process", bad, "--out", tmp_path / "out.npz", needles=(needle,))


def test_good_raw_still_processes(tmp_path, inputs):
    run_cli("process", inputs["raw"], "--out", tmp_path / "ok.npz", check_rc=0)
    assert (tmp_path / "ok.npz").is_file()


# ------------------------------------------------------------------- studies


STUDY = """name = {name!r}
scenes = ["macbeth"]
cfas = ["bayer"]
demosaics = ["bilinear"]
[render.macbeth]
width = {width}
height = {height}
spp = 1
[output]
report = false
"""


def test_study_width_above_limit_refused_before_any_work(tmp_path, monkeypatch):
    cfg = tmp_path / "big.toml"
    cfg.write_text(STUDY.format(name="big", width=40000, height=40))
    proc = refused(tmp_path, "study", cfg, "--out", tmp_path / "out", needles=("render.macbeth.width", "32768"))
    assert "--width" not in proc.stderr
    monkeypatch.setenv("CFA_MITSUBA_MEMORY_LIMIT", "1G")
    cfg.write_text(STUDY.format(name="big", width=3000, height=3000))  # within the side limit, beyond the memory
    refused(tmp_path, "study", cfg, "--out", tmp_path / "out", needles=("render.macbeth", "needs about"))


def test_study_named_dot_dot_writes_nothing_outside_out(tmp_path):
    """Acceptance 5."""
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    cfg = work / "evil.toml"
    cfg.write_text(STUDY.format(name="../../x", width=60, height=40))
    proc = run_cli("study", cfg, "--out", work / "out", "--workers", 1, "--quiet")
    assert proc.returncode == 0, proc.stderr
    outside = [f for f in _files(tmp_path) if not f.startswith("a/b/out") and f != "a/b/evil.toml"]
    assert outside == ["a", "a/b"], outside
    assert (work / "out" / "metrics.csv").is_file()


def test_study_name_is_a_label_under_results(tmp_path, monkeypatch):
    """Without --out the results go to results/NAME with NAME made safe."""
    from cfa_mitsuba.cli import main
    from cfa_mitsuba.io.validate import safe_name

    monkeypatch.chdir(tmp_path)
    cfg = tmp_path / "abs.toml"
    cfg.write_text(STUDY.format(name=str(tmp_path / "elsewhere"), width=60, height=40))
    assert main(["study", str(cfg), "--workers", "1", "--quiet"]) == 0
    assert not (tmp_path / "elsewhere").exists()
    assert (tmp_path / "results" / safe_name(str(tmp_path / "elsewhere")) / "metrics.csv").is_file()
    assert safe_name("../../x") == "___.._x" and safe_name("..") == "__" and safe_name("quick") == "quick"


def test_custom_scene_name_that_is_a_path_refused(tmp_path):
    (tmp_path / "s.xml").write_text("<scene version='3.0.0'/>")
    cfg = tmp_path / "c.toml"
    cfg.write_text('cfas = ["bayer"]\ndemosaics = ["bilinear"]\n[[custom_scenes]]\nname = "../up"\nfile = "s.xml"\n')
    refused(tmp_path, "study", cfg, "--out", tmp_path / "out", needles=("custom_scenes[0].name", "label"))


def test_report_prunes_only_what_it_recorded(tmp_path):
    from cfa_mitsuba.io.owned import MANIFEST, prune_written, record_written

    for name in ("old.png", "mine.png", "keep.png"):
        (tmp_path / name).write_bytes(b"x")
    (tmp_path.parent / "victim.png").write_bytes(b"x")
    record_written(tmp_path, ["old.png", "keep.png"])
    (tmp_path / MANIFEST).write_text(json.dumps(["old.png", "keep.png", "../victim.png", "/etc/passwd"]))
    gone = prune_written(tmp_path, {"keep.png"})
    assert [p.name for p in gone] == ["old.png"]
    assert (tmp_path / "mine.png").exists() and (tmp_path.parent / "victim.png").exists()


# ------------------------------------------------------------------ band grid


def test_band_grid_that_does_not_divide_refused(tmp_path):
    refused(tmp_path, "render", "macbeth", "--bands", "400:700:7", "--out", tmp_path / "o",
            needles=("STEP 7 does not divide", "694"))
    assert cm.spectra.parse_band_grid("400:700:20").size == 16
