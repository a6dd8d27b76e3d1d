"""The study writes each compared sensor's QE curves (sensor_curves.csv) and
the report plots them and says when the compared CFAs use different
spectra sets (issue 28, "a sensor in")."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest

import cfa_mitsuba as cm

from conftest import REPO

SENSOR_FILE = REPO / "configs" / "sensors" / "mt9v024-rgb.toml"


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import run_study

    base = tmp_path_factory.mktemp("curves")
    cfg = base / "study.toml"
    cfg.write_text(f'name = "curves"\nscenes = ["gray-bar"]\ncfas = ["bayer", "cmy1", "{SENSOR_FILE}"]\n'
                   'demosaics = ["bilinear"]\nluminances = [100]\nsensor = "imx363"\n'
                   '[render.gray-bar]\nwidth = 96\nheight = 64\n')
    out = base / "results"
    run_study(load_config(cfg), out, workers=1, progress=False, log=lambda msg: None)
    return out


def test_the_study_writes_the_curves_it_captured_with(results):
    t = pd.read_csv(results / "sensor_curves.csv", dtype={"cfa": str, "channel": str})
    wl = cm.spectra.DEFAULT_WAVELENGTHS
    sets = t.drop_duplicates("cfa").set_index("cfa")["spectra"].to_dict()
    assert sets == {"bayer": "isetcam-rgb", "cmy1": "isetcam-cmy", "mt9v024-rgb-file": "own"}
    assert set(t["sensor"]) == {"imx363"}
    for name, cfa in (("cmy1", cm.sensor.get_cfa("cmy1")), ("mt9v024-rgb-file", cm.sensor.get_cfa(str(SENSOR_FILE)))):
        for i, ch in enumerate(cfa.channels):
            g = t[(t["cfa"] == name) & (t["channel"] == ch)]
            assert np.allclose(g["wavelength_nm"], wl)
            assert np.allclose(g["qe"], cfa.sensitivities(wl)[i], rtol=1e-8, atol=0)
    metrics = pd.read_csv(results / "metrics.csv", dtype={"cfa": str})
    assert set(metrics["cfa"]) == set(sets)  # the same labels as metrics.csv


def test_the_report_plots_them_and_names_the_different_sets(results):
    from cfa_mitsuba.report import build_report

    text = build_report(results, formats=("png",)).read_text(encoding="utf-8")
    assert 'id="sensor"' in text and (results / "figures" / "sensor-curves.png").is_file()
    note = re.search(r"use 3 different spectra sets \(([^)]*)\)", text)
    assert note and "isetcam-cmy: cmy1" in note.group(1) and "own: mt9v024-rgb-file" in note.group(1)


def test_no_note_when_every_cfa_uses_one_set(results, tmp_path):
    import shutil

    from cfa_mitsuba.report import build_report

    copy = tmp_path / "r"
    shutil.copytree(results, copy)
    t = pd.read_csv(copy / "sensor_curves.csv", dtype={"cfa": str, "channel": str})
    t["spectra"] = "isetcam-rgb"
    t.to_csv(copy / "sensor_curves.csv", index=False)
    text = build_report(copy, formats=()).read_text(encoding="utf-8")
    assert 'id="sensor"' in text and "different spectra sets" not in text
    (copy / "sensor_curves.csv").unlink()
    text = build_report(copy, formats=()).read_text(encoding="utf-8")
    assert "sensor_curves.csv is absent" in text
