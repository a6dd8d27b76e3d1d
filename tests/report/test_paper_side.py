"""The paper side by side (issue 12, item 9): the ISETCam-way spectra sets,
the MCC colour fit, per-metric options in a study, the ISETCam-procedure
config, and docs/paper-comparison.md's generator on two tiny study runs."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pandas as pd
import pytest

from conftest import REPO, assert_one_line_error, run_cli

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.colorimetry import xyz_to_lab
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.isp.colour_matrix import colour_fit_reflectances, electrons_per_radiance_of, fit_colour_matrix
from cfa_mitsuba.report import paper_comparison, paper_data
from cfa_mitsuba.sensor.spectra_sets import FILTERS_DIR, get_spectra_set, read_curve_csv
from cfa_mitsuba.study.chain import ChainSettings
from cfa_mitsuba.study.conditions import Condition
from cfa_mitsuba.study.config import load_config, parse_config

ISETCAM_TOML = REPO / "configs" / "paper-isetcam.toml"
PAPER_TOML = REPO / "configs" / "paper.toml"


# --- spectra sets as ISETCam uses them ----------------------------------------


def test_raw_sets_take_the_filter_files_as_they_stand():
    rgb = read_curve_csv(FILTERS_DIR / "isetcam/colorfilters/RGB.csv")
    raw = get_spectra_set("isetcam-rgb-raw")
    for letter in "RGB":
        np.testing.assert_array_equal(raw.curve(letter)[1], rgb[letter][1])
    # the common model (silicon x IR cut) is what the default set adds: it cuts RGB.mat's red above 650 nm
    wl = np.array([690.0])
    assert np.interp(wl, *raw.curve("R"))[0] > 0.35
    assert np.interp(wl, *get_spectra_set("isetcam-rgb").curve("R"))[0] < 0.05
    cmy = get_spectra_set("isetcam-cmy-raw")
    c = read_curve_csv(FILTERS_DIR / "isetcam/colorfilters/cym.csv")["C"]
    np.testing.assert_array_equal(cmy.curve("C")[1], c[1])
    x = np.linspace(420, 680, 27)
    assert np.all(np.interp(x, *cmy.curve("W")) == 1.0)  # a clear pixel on a flat photodiode
    np.testing.assert_allclose(np.interp(x, *cmy.curve("C2")), np.interp(x, *c) ** 2, rtol=1e-3)
    np.testing.assert_array_equal(cmy.curve("G")[1], rgb["G"][1])
    rgbw = read_curve_csv(FILTERS_DIR / "isetcam/colorfilters/interleavedRGBW.csv")
    np.testing.assert_array_equal(get_spectra_set("isetcam-rgbw-raw").curve("W")[1], rgbw["W"][1])


def _fit_only_de76(cfa: str, spectra_set: str) -> float:
    wl = spectra.DEFAULT_WAVELENGTHS
    d65 = spectra.illuminant("D65", wl)
    refl = colour_fit_reflectances("mcc", wl)
    epr = electrons_per_radiance_of(cm.sensor.get_cfa(cfa, spectra=spectra_set).sensitivities(wl), wl)
    fit = fit_colour_matrix(epr, d65, wl, white_preserving=False, reflectances=refl)
    cam = (refl * d65) @ epr.T / (epr @ d65)
    ref = spectra.xyz_from_radiance(refl * d65, wl)
    white = spectra.xyz_from_radiance(d65, wl)
    return float(np.linalg.norm(xyz_to_lab(fit.apply(cam), white) - xyz_to_lab(ref, white), axis=1).mean())


def test_mcc_fit_of_the_raw_sets_reproduces_isetcams_fit_alone():
    """ISETCam's fit alone (research/isetcam-paper-check.md): RGBW 2.60 <
    CMY 4.36 < RGB 5.77 dE76.  Ours from the same files: the same order and
    within 20 % (measured +13, +9, +7 %: colour-science's ColorChecker N Ohta
    against ISETCam's macbethChart.mat, 10-nm box means against point samples)."""
    got = {c: _fit_only_de76(c, s) for c, s in
           (("rgbw1", "isetcam-rgbw-raw"), ("cmy1", "isetcam-cmy-raw"), ("bayer", "isetcam-rgb-raw"))}
    assert got["rgbw1"] < got["cmy1"] < got["bayer"]
    for cfa, isetcam in (("rgbw1", 2.60), ("cmy1", 4.36), ("bayer", 5.77)):
        assert abs(got[cfa] / isetcam - 1) < 0.20, (cfa, got[cfa], isetcam)


def test_mcc_fit_is_the_least_squares_fit_on_the_chart():
    wl = spectra.DEFAULT_WAVELENGTHS
    d65 = spectra.illuminant("D65", wl)
    epr = electrons_per_radiance_of(cm.sensor.get_cfa("bayer").sensitivities(wl), wl)
    mcc = colour_fit_reflectances("mcc", wl)
    ref = spectra.xyz_from_radiance(mcc * d65, wl)
    cam = (mcc * d65) @ epr.T / (epr @ d65)
    err, mats = {}, {}
    for name in ("training", "mcc"):
        fit = fit_colour_matrix(epr, d65, wl, white_preserving=False, reflectances=colour_fit_reflectances(name, wl))
        err[name] = float(np.sqrt(np.mean((fit.apply(cam) - ref) ** 2)))
        mats[name] = fit.matrix
    # the MCC fit is the least-squares minimiser on the chart (measured: 6 % below the
    # training fit's error, which generalises well), and it is another matrix
    assert err["mcc"] < 0.97 * err["training"], err
    assert np.abs(mats["mcc"] - mats["training"]).max() > 1e-3 * np.abs(mats["mcc"]).max()
    with pytest.raises(CfaMitsubaError, match="unknown colour fit"):
        colour_fit_reflectances("esser", wl)


# --- the config keys ----------------------------------------------------------


def test_paper_isetcam_config_selects_isetcams_procedure():
    cfg = load_config(ISETCAM_TOML)
    ch = cfg.chain_settings()
    assert cfg.range_policy == "paper" and cfg.exposure_program.policy == "each"
    assert dict(ch.isp) == {"white_balance": "illuminant", "white_preserving": False, "colour_fit": "mcc",
                            "regularise": False}  # ISETCam: the exact, unconstrained fit
    assert ch.options_of_metrics()["delta-e"] == {"version": "1976"}
    assert ch.options_of_metrics()["scielab"]["matrix"] == "xyz10"
    base = cfg.base_condition()
    assert [ch.spectra_for(c, base) for c in ("bayer", "cmy2", "rgbw3")] == [
        "isetcam-rgb-raw", "isetcam-cmy-raw", "isetcam-rgbw-raw"]
    assert ch.spectra_for("bayer", base.with_(spectra="nikon-d5100")) == "nikon-d5100"  # a sweep wins
    assert ChainSettings().spectra_for("bayer", Condition()) is None
    assert load_config(PAPER_TOML).chain_settings().metric_options == ()


def _data(path=PAPER_TOML) -> dict:
    return tomllib.loads(path.read_text())


@pytest.mark.parametrize("patch, needle", [
    ({"metrics": {"delta-e": {"patches": 3}}}, "metrics.delta-e.patches"),
    ({"metrics": {"delta-e": {"verson": "1976"}}}, "metrics.delta-e.verson"),
    ({"metrics": {"scielab": {"samples_per_degree": "many"}}}, "metrics.scielab.samples_per_degree"),
    ({"metrics": {"delta-l": {"version": "1976"}}}, "metrics.delta-l"),
    ({"isp": {"colour_fit": "esser"}}, "isp.colour_fit"),
    ({"sensor": {"spectra_sets": {"isetcam-rgb": "nosuch"}}}, "sensor.spectra_sets.isetcam-rgb"),
    ({"sensor": {"spectra_sets": {"nosuch": "isetcam-rgb-raw"}}}, "sensor.spectra_sets"),
])
def test_bad_keys_are_refused_with_their_path(patch, needle):
    data = _data()
    for k, v in patch.items():
        data[k] = {**data.get(k, {}), **v}
    with pytest.raises(CfaMitsubaError, match=needle.replace(".", r"\.")):
        parse_config(data, where="x.toml")


def test_bad_metric_option_on_the_command_line_is_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(ISETCAM_TOML.read_text().replace('version = "1976"', 'version = 1976'))
    assert_one_line_error(run_cli("study", bad, "--out", tmp_path / "out"), "metrics.delta-e.version")


# --- two tiny studies and the comparison page --------------------------------


def _dump(d: dict, prefix: str = "") -> str:
    lines, tables = [], []
    for k, v in d.items():
        key = k if k.replace("-", "").replace("_", "").isalnum() else json.dumps(k)
        if isinstance(v, dict):
            tables.append((f"{prefix}{key}", v))
        else:
            lines.append(f"{key} = {json.dumps(v)}")
    out = "\n".join(lines) + "\n"
    for name, t in tables:
        out += f"\n[{name}]\n" + _dump(t, f"{name}.")
    return out


def _tiny(path, name: str) -> str:
    d = _data(path)
    d.pop("sweep", None)
    d.update(name=name, cfas=["bayer", "cmy1", "rgbw1"], demosaics=["bilinear", "pocs"], seeds=2,
             output={"figures": ["png"], "thumbnails": False, "report": False},
             render={"macbeth": {"width": 240, "height": 212}, "slanted-edge": {"width": 320, "height": 288},
                     "chirp": {"width": 400, "height": 160}, "gray-bar": {"width": 250, "height": 120},
                     "puppy": {"width": 120, "height": 106, "spp": 8}})
    return _dump(d)


@pytest.fixture(scope="module")
def tiny_runs(tmp_path_factory):
    from cfa_mitsuba.study.runner import run_study

    root = tmp_path_factory.mktemp("paperside")
    out = {}
    for key, path in (("default", PAPER_TOML), ("isetcam", ISETCAM_TOML)):
        cfg_path = root / f"{key}.toml"
        cfg_path.write_text(_tiny(path, f"tiny-{key}"))
        run_study(load_config(cfg_path), root / key, workers=2, progress=False, log=lambda m: None)
        out[key] = root / key
    return out


def test_isetcam_run_uses_the_raw_sets_and_the_metric_options(tiny_runs):
    iso = pd.read_csv(tiny_runs["isetcam"] / "metrics.csv")
    default = pd.read_csv(tiny_runs["default"] / "metrics.csv")
    assert set(iso["spectra"]) == {"isetcam-rgb-raw", "isetcam-cmy-raw", "isetcam-rgbw-raw"}
    de = iso[iso["metric"] == "delta-e"]
    assert set(de["unit"]) == {"dE76"}
    np.testing.assert_allclose(de["value"].to_numpy(), iso[iso["metric"] == "delta-e76"]["value"].to_numpy())
    assert set(default[default["metric"] == "delta-e"]["unit"]) == {"dE00"}
    # ISETCam's S-CIELAB (xyz10, 41 samples/deg, circular) is not ours on the same kind of image
    s_iso = iso[(iso["metric"] == "scielab") & iso["base"]].set_index(["cfa", "demosaic"])["value"]
    s_def = default[(default["metric"] == "scielab") & default["base"]].set_index(["cfa", "demosaic"])["value"]
    assert not np.allclose(s_iso.sort_index(), s_def.sort_index(), rtol=1e-3)
    # the raw RGB set (no IR cut) and the MCC fit: Bayer's dE76 as ISETCam's 5.97 within 10 %
    bayer = de[(de["cfa"] == "bayer") & (de["demosaic"] == "bilinear")]["value"].iloc[0]
    assert abs(bayer / 5.97 - 1) < 0.10, bayer


def test_comparison_page_has_every_section(tiny_runs, tmp_path):
    out = tmp_path / "paper-comparison.md"
    assert paper_comparison.main(["--default", str(tiny_runs["default"]), "--isetcam", str(tiny_runs["isetcam"]),
                                  "--out", str(out)]) == 0
    text = out.read_text()
    for heading in ["# The paper side by side", "## The runs", "## Verdicts at a glance", "## Where the paper is wrong",
                    *[f"## {h}" for _, h, _ in paper_comparison.SECTIONS],
                    "## Table 3: mean normalised score per demosaic",
                    *[f"### {d}" for d in paper_comparison.DEMOSAICS], "## Not compared"]:
        assert heading + "\n" in text, heading
    for claim in paper_data.claims():
        assert claim["text"] in text, claim["id"]
    glance = text.split("## Verdicts at a glance")[1].split("\n## ")[0]
    assert glance.count("| paper |") + glance.count("| ISETCam |") == len(paper_data.claims())
    assert "**holds**" in text and "**differs**" in text
    # the paper's values, ISETCam's and ours with an interval sit in one row
    bayer = next(line for line in text.split("## Colour error")[1].splitlines() if line.startswith("| Bayer |"))
    assert "| 3.00 |" in bayer and "5.97 (dE76)" in bayer and bayer.count("[") == 3
    assert "0.7261 (derived)" in text  # Table 3's lost RGBW1 cell, from the text's margins


def test_verdicts_follow_the_numbers():
    def run(values: dict, metric="delta-e76"):
        rows = [{"metric": metric, "demosaic": "bilinear", "cfa": c, "value": v, "ci_low": v - h, "ci_high": v + h,
                 "unit": "dEab"} for c, (v, h) in values.items()]
        return paper_data.Run("t", "t", REPO, pd.DataFrame(rows), None, {}, {})

    claim = {"kind": "order", "metric": "delta-e76", "demosaic": "bilinear", "groups": [["rgbw1"], ["bayer"]]}
    assert paper_data.judge(run({"rgbw1": (2.0, 0.1), "bayer": (3.0, 0.1)}), claim)[0] == "holds"
    assert paper_data.judge(run({"rgbw1": (3.0, 0.1), "bayer": (2.0, 0.1)}), claim)[0] == "differs"
    assert paper_data.judge(run({"rgbw1": (2.0, 0.6), "bayer": (3.0, 0.6)}), claim)[0] == "tie"
    group = {**claim, "groups": [["rgbw1", "rgbw2"], ["bayer"]]}
    # the group mean is better, but one member is worse beyond the intervals: judged pairwise, that differs,
    # with or without the old ``strict`` key
    for strict in (False, True):
        assert paper_data.judge(run({"rgbw1": (1.0, 0.1), "rgbw2": (3.5, 0.1), "bayer": (3.0, 0.1)}),
                                {**group, "strict": strict})[0] == "differs"
    # one member better, the other within the intervals: a tie, not a hold
    assert paper_data.judge(run({"rgbw1": (1.0, 0.1), "rgbw2": (2.9, 0.2), "bayer": (3.0, 0.1)}), group)[0] == "tie"
    similar = {"kind": "similar", "metric": "delta-e76", "demosaic": "bilinear", "cfas": ["rgbw1", "bayer"],
               "max_range": 0.5}
    assert paper_data.judge(run({"rgbw1": (2.0, 0.01), "bayer": (2.4, 0.01)}), similar)[0] == "holds"
    assert paper_data.judge(run({"rgbw1": (2.0, 0.1), "bayer": (2.4, 0.1)}), similar)[0] == "tie"
    assert paper_data.judge(run({"rgbw1": (2.0, 0.01), "bayer": (2.6, 0.01)}), similar)[0] == "differs"
    at_most = {"kind": "at_most", "metric": "delta-e76", "demosaic": "bilinear", "cfas": ["rgbw1", "bayer"],
               "max_value": 1.0}
    assert paper_data.judge(run({"rgbw1": (0.5, 0.1), "bayer": (0.8, 0.1)}), at_most)[0] == "holds"
    assert paper_data.judge(run({"rgbw1": (0.5, 0.1), "bayer": (0.95, 0.1)}), at_most)[0] == "tie"
    assert paper_data.judge(run({"rgbw1": (0.5, 0.1), "bayer": (1.2, 0.1)}), at_most)[0] == "differs"


def test_paper_values_are_placed_once_per_cfa_and_metric():
    pv = paper_data.paper_values()
    for (metric, demosaic), g in pv.groupby(["metric", "demosaic"]):
        cfas = [c for row in g["cfas"] for c in row]
        assert len(cfas) == len(set(cfas)), (metric, demosaic)
        assert set(cfas) <= set(paper_comparison.CFAS)
    assert set(pv["status"]) <= {"printed", "derived", "range", "mean"}
    t3 = pv[(pv["metric"] == "score") & (pv["demosaic"] == "total")]
    assert len(t3) == 12 and t3.set_index("cfa")["number"].idxmax() == "rgbw1"
