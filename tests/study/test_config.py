"""Study configs: the shipped ones load; every kind of bad config is refused
before any work starts, with exit 2 and the offending key named."""

import textwrap
from pathlib import Path

import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.study.config import load_config
from conftest import REPO, assert_one_line_error, run_cli

GOOD = """
name = "t"
scenes = ["macbeth", "puppy"]
cfas = ["bayer", "rgbw1"]
demosaics = ["bilinear"]
luminances = [100]
"""


def write(tmp_path: Path, text: str, name="c.toml") -> Path:
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


@pytest.mark.parametrize("name", ["quick.toml", "paper.toml", "paper-denoise.toml", "examples/custom_cfa.toml",
                                  "examples/custom_scene.toml"])
def test_shipped_configs_load(name):
    cfg = load_config(REPO / "configs" / name)
    assert cfg.scenes and cfg.cfas and cfg.demosaics


def test_paper_denoise_config_compares_the_papers_cfas_with_and_without_noise_reduction():
    cfg = load_config(REPO / "configs" / "paper-denoise.toml")
    assert cfg.cfas == load_config(REPO / "configs" / "paper.toml").cfas
    assert {"dead-leaves", "puppy", "gray-bar", "slanted-edge"} <= {s.name for s in cfg.scenes}
    swept = {s.scenes[0]: s.values for s in cfg.sweeps}
    assert all(tuple(v["denoise"]) == ("none", "nl-means") for v in swept.values())
    assert min(swept["puppy"]["luminance"]) == 3 and max(swept["puppy"]["luminance"]) == 400


def test_paper_config_is_the_papers_study():
    from cfa_mitsuba.report.paper_data import paper_values

    cfg = load_config(REPO / "configs" / "paper.toml")
    paper = paper_values()  # the paper's own tables: its 12 CFAs and the four methods it reports
    assert set(cfg.cfas) == {c for cs in paper["cfas"] for c in cs} and len(cfg.cfas) == 12
    assert set(cfg.demosaics) == set(paper["demosaic"]) - {"total"}  # "total": a row over every demosaic
    assert {s.name for s in cfg.scenes} == {"macbeth", "slanted-edge", "chirp", "gray-bar", "puppy"}
    sweep, snr = cfg.sweeps
    assert sweep.scenes == ("puppy",) and set(sweep.metrics) == {"scielab", "ssim"}
    assert sweep.values["luminance"] == (0.3, 1, 3, 6, 12, 50, 100, 200, 400)  # the paper's 3..400, and lower (issue 22)
    assert snr.scenes == ("gray-bar",) and snr.metrics == ("ysnr",) and snr.values["luminance"] == sweep.values["luminance"]
    assert cfg.chain_settings().exposure_program.policy == "program"


def test_exposure_policies_set_where_auto_exposure_is_chosen(tmp_path):
    from cfa_mitsuba.sensor import ExposureProgram

    each = load_config(write(tmp_path, GOOD + '[sensor]\nexposure_policy = "each"\n'))
    assert each.exposure_program.policy == "each"  # ISETCam's auto exposure at every luminance
    program = load_config(write(tmp_path, GOOD))
    # the config's one value reaches the chain whole, the program's defaults where [sensor] names none
    assert program.chain_settings().exposure_program is program.exposure_program == ExposureProgram()
    assert (program.exposure_program.max_exposure_s, program.exposure_program.max_analog_gain) == (1 / 30, 16.0)
    ref = load_config(write(tmp_path, GOOD + '[sensor]\nexposure_policy = "reference"\n')).exposure_program
    assert (ref.policy, ref.reference_luminance_cd_m2) == ("reference", 100.0)
    bayer = load_config(write(tmp_path, GOOD + '[sensor]\nexposure_policy = "bayer"\nmax_analog_gain = 8\n'))
    assert bayer.chain_settings().exposure_program == ExposureProgram("bayer", max_analog_gain=8.0)
    # config.json holds the program's keys that its policy reads
    assert bayer.to_dict()["capture"] == {"exposure_policy": "bayer", "max_exposure_s": 1 / 30, "max_analog_gain": 8.0}
    isetcam = load_config(REPO / "configs" / "paper-isetcam.toml").chain_settings()
    assert isetcam.exposure_program.policy == "each"  # ISETCam's own rule, chosen explicitly
    fixed = load_config(write(tmp_path, GOOD + '[sensor]\nexposure_policy = "fixed"\nexposure = 0.02\n'))
    assert fixed.base_condition().exposure == 0.02 and fixed.exposure_program.policy == "fixed"
    with pytest.raises(cm.CfaMitsubaError, match=r"sweep\[0\].exposure: 'auto' needs an exposure policy"):
        load_config(write(tmp_path, GOOD + '[sensor]\nexposure_policy = "fixed"\nexposure = 0.02\n'
                          '[[sweep]]\nscene = "macbeth"\nexposure = ["auto", 0.01]\n'))


def test_the_chain_settings_are_built_once_per_study(tmp_path):
    cfg = load_config(write(tmp_path, GOOD))
    assert cfg.chain_settings() is cfg.chain_settings()
    from cfa_mitsuba.study.runner import plan_study

    _, tasks = plan_study(cfg, None)
    assert all(t.chain is cfg.chain_settings() for t in tasks)


def test_one_f_number_for_every_scene_unless_the_config_asks_for_the_scenes_own(tmp_path):
    """Issue 46: the puppy (f/2 in its own render) and the charts are captured
    at one f-number, [optics] f_number or f/4; "scene" asks for each scene's
    own lens; a user's scene is treated like a built-in one."""
    from cfa_mitsuba.study.runner import plan_study

    def renders(text):
        cfg = load_config(write(tmp_path, GOOD + text))
        sources, _ = plan_study(cfg, None)
        return cfg.base_condition().f_number, {s["scene"]: s["settings"].get("f_number") for s in sources}

    assert renders("") == (4.0, {"macbeth": None, "puppy": 4.0})  # a chart's render does not depend on it
    assert renders("[optics]\nf_number = 2.8\n") == (2.8, {"macbeth": None, "puppy": 2.8})
    assert renders('[optics]\nf_number = "scene"\n') == (None, {"macbeth": None, "puppy": None})
    custom = load_config(REPO / "configs" / "examples" / "custom_scene.toml")
    assert custom.base_condition().f_number == (custom.optics.get("f_number") or 4.0)


def test_good_config_values(tmp_path):
    cfg = load_config(write(tmp_path, GOOD + '[sensor]\npixel_pitch_um = 1.4\nnoise = "shot"\n'))
    assert cfg.sensor == {"pixel_pitch_um": 1.4} and cfg.capture == {"noise": "shot"}
    # each scene feeds what the metric records name for its kind (the paper's ones among them)
    assert [s.metrics for s in cfg.scenes] == [cm.metrics.metrics_for_scene(k) for k in ("macbeth", "natural")]
    assert cfg.scenes[0].metrics[0] == "delta-e"
    assert {"scielab", "ssim", "mdsi", "haarpsi"} <= set(cfg.scenes[1].metrics)


BAD = [
    # (extra text, key named in the error, reason fragment)
    ("colour = 1\n", "colour", "unknown key"),
    ("[sensor]\npixel_pich_um = 2\n", "sensor.pixel_pich_um", "unknown key"),
    ("[sensor]\npixel_pitch_um = -1\n", "sensor", "positive"),
    ("[sensor]\npixel_pitch_um = \"big\"\n", "sensor.pixel_pitch_um", "number"),
    ("[sensor]\nnoise = \"loud\"\n", "sensor.noise", "one of"),
    ("[sensor]\nexposure = 0\n", "sensor.exposure", "positive"),
    ("[optics]\nf_number = 0\n", "optics", "f-number"),
    ("[render.puppy]\nspp = 0\n", "render.puppy.spp", "at least 1"),
    ("[render.puppy]\nwidth = 12.5\n", "render.puppy.width", "integer"),
    ("[render]\nbands = \"700:400:10\"\n", "render.bands", "band grid"),
    ("[render]\nvariant = \"gpu\"\n", "render.variant", "one of"),
    ("[normalisation.ranges]\nssim = [1, 1]\n", "normalisation.ranges.ssim", "differ"),
    ("[normalisation.ranges]\nsharpness = [0, 1]\n", "normalisation.ranges.sharpness", "unknown key"),
    ("[isp]\nwhite_balance = \"auto\"\n", "isp.white_balance", "one of"),
    ("[[sweep]]\nscene = \"macbeth\"\nmetrics = [\"ssim\"]\nluminances = [10]\n", "sweep[0].metrics[0]",
     "does not feed"),
    ("[[sweep]]\nscene = \"chirp\"\nluminances = [10]\n", "sweep[0].scene", "not one of"),
    ("[output]\nfigures = [\"jpg\"]\n", "output.figures[0]", "png or svg"),
    ("[sensor]\nexposure_policy = \"sometimes\"\n", "sensor.exposure_policy", "one of"),
    ("[sensor]\nreference_luminance_cd_m2 = 50\n", "sensor.reference_luminance_cd_m2", "reference"),
    ("[sensor]\nmax_analog_gain = 0.5\n", "sensor.max_analog_gain", "at least 1"),
    ("[sensor]\nmax_exposure_s = -1\n", "sensor.max_exposure_s", "positive"),
    ("[sensor]\nexposure_policy = \"each\"\nmax_exposure_s = 0.1\n", "sensor.max_exposure_s", "program"),
    ("[sensor]\nexposure_policy = \"fixed\"\n", "sensor.exposure", "needs an exposure time"),
    ("[sensor]\nexposure = 0.01\n", "sensor.exposure_policy", "fixed"),
    ("[sensor]\nexposure_policy = \"each\"\nreference_luminance_cd_m2 = 50\n",
     "sensor.reference_luminance_cd_m2", "does not apply"),
    ("seeds = 0\n", "seeds", "at least 1"),
    ("[normalisation]\npolicy = \"best\"\n", "normalisation.policy", "one of"),
    ("[[sweep]]\nscene = \"macbeth\"\nf_number = [0]\n", "sweep[0].f_number[0]", "positive"),
    ("[[sweep]]\nscene = \"macbeth\"\nspectra = [\"sepia\"]\n", "sweep[0].spectra[0]", "one of"),
    ("[[sweep]]\nscene = \"macbeth\"\nseed = [1, 1]\n", "sweep[0].seed", "twice"),
    ("[[sweep]]\nscene = \"macbeth\"\nmetrics = [\"delta-e\"]\n", "sweep[0]", "sweeps no axis"),
]


@pytest.mark.parametrize("extra, key, reason", BAD)
def test_bad_values_are_refused_with_the_key(tmp_path, extra, key, reason):
    p = write(tmp_path, GOOD + extra)
    with pytest.raises(CfaMitsubaError) as err:
        load_config(p)
    msg = str(err.value)
    assert f": {key}:" in msg and reason.lower() in msg.lower(), msg


@pytest.mark.parametrize("text, key", [
    (GOOD.replace('"macbeth", ', '"macbeth", "kitchen", '), "scenes[1]"),
    (GOOD.replace('"rgbw1"', '"rgbw9"'), "cfas[1]"),
    (GOOD.replace('"rgbw1"', '"nothere.toml"'), "cfas[1]"),
    (GOOD.replace('["bilinear"]', '["bilinear", "no-such-method"]'), "demosaics[1]"),
    (GOOD.replace("[100]", "[100, -3]"), "luminances[1]"),
    (GOOD.replace("[100]", "[100, 100]"), "luminances"),
    (GOOD.replace('cfas = ["bayer", "rgbw1"]\n', ""), "cfas"),
    (GOOD.replace('["bilinear"]', '"bilinear"'), "demosaics"),
    (GOOD + "[[custom_scenes]]\nname = \"room\"\nfile = \"missing.xml\"\n", "custom_scenes[0].file"),
])
def test_bad_lists_and_names(tmp_path, text, key):
    with pytest.raises(CfaMitsubaError) as err:
        load_config(write(tmp_path, text))
    assert f": {key}:" in str(err.value), str(err.value)


def test_invalid_toml_and_missing_file(tmp_path):
    with pytest.raises(CfaMitsubaError, match="invalid TOML"):
        load_config(write(tmp_path, "scenes = [\n"))
    with pytest.raises(CfaMitsubaError, match="no such config"):
        load_config(tmp_path / "none.toml")


def test_cli_refuses_before_any_work(tmp_path):
    p = write(tmp_path, GOOD + "[sensor]\nwell_capacity_e = 0\n")
    out = tmp_path / "out"
    proc = run_cli("study", p, "--out", out)
    assert_one_line_error(proc, "sensor", "well_capacity_e")
    assert not out.exists()  # nothing was started, no results folder
