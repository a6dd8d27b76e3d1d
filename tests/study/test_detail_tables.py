"""mtf.csv, patches.csv and steps.csv (issue 50): a small study writes them
with the columns named in docs/study.md, and each agrees with the values
metrics_realisations.csv holds for the same capture (the tables describe the
first realisation, whose details the study keeps); metrics.csv carries the
lux and dB columns."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

CONFIG = """
name = "tables"
seed = 3
seeds = 2
scenes = ["macbeth", "slanted-edge", "gray-bar"]
cfas = ["bayer", "rgbw1"]
demosaics = ["bilinear", "laplacian"]
luminances = [100]

[[sweep]]
scene = "gray-bar"
metrics = ["ysnr"]
luminances = [5, 100]

[render.macbeth]
width = 120
height = 106
[render.slanted-edge]
width = 320
height = 288
[render.gray-bar]
width = 250
height = 60

[output]
report = false
"""


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    from cfa_mitsuba.cli import main

    folder = tmp_path_factory.mktemp("tables")
    cfg = folder / "tables.toml"
    cfg.write_text(CONFIG)
    out = folder / "out"
    assert main(["study", str(cfg), "--out", str(out), "--quiet", "--workers", "1"]) == 0
    return out


def _first(out, metric):
    r = pd.read_csv(out / "metrics_realisations.csv")
    return r[(r["metric"] == metric) & (r["realisation"] == 0)]


def test_the_columns_named_in_the_docs(out):
    mtf, patches, steps = (pd.read_csv(out / f) for f in ("mtf.csv", "patches.csv", "steps.csv"))
    key = ["scene", "cfa", "demosaic", "condition", "luminance"]
    assert list(mtf.columns) == key + ["frequency_cy_px", "frequency_cy_mm", "mtf", "mtf_r", "mtf_g", "mtf_b"]
    assert {"patch", "name", "de00", "de76", "l_ideal", "l_camera", "x_camera"} <= set(patches.columns)
    assert {"step", "reflectance", "luminance_cd_m2", "snr", "snr_db", "dynamic_range", "dynamic_range_db",
            "dynamic_range_ev", "snr1_extrapolated"} <= set(steps.columns)
    assert set(mtf["cfa"]) == {"bayer", "rgbw1", "ideal"} and len(patches) == 2 * 2 * 24
    assert set(steps["luminance"]) == {5.0, 100.0} and len(steps) == 2 * 2 * 2 * 10
    m = pd.read_csv(out / "metrics.csv")
    assert {"scene_illuminance_lux", "sensor_exposure_lux_s", "value_db", "ci_low_db", "ci_high_db"} <= set(m.columns)


def test_mtf_curve_gives_the_rows_mtf50(out):
    """The first crossing of 0.5 on mtf.csv's luminance curve, interpolated
    linearly, is the realisation's MTF50 in cy/px; cy/mm is cy/px x 1000 /
    2.2 um; the curve starts at 1."""
    mtf = pd.read_csv(out / "mtf.csv")
    rows = _first(out, "mtf50-cy-px")
    for (cfa, dem), g in mtf[mtf["cfa"] != "ideal"].groupby(["cfa", "demosaic"]):
        f, m = g["frequency_cy_px"].to_numpy(), g["mtf"].to_numpy()
        i = int(np.flatnonzero(m < 0.5)[0])
        cross = f[i - 1] + (m[i - 1] - 0.5) * (f[i] - f[i - 1]) / (m[i - 1] - m[i])
        want = rows[(rows["cfa"] == cfa) & (rows["demosaic"] == dem)]["value"].iloc[0]
        assert cross == pytest.approx(want, rel=1e-6)
        assert m[0] == pytest.approx(1.0) and f.max() <= 1.0
        assert np.allclose(g["frequency_cy_mm"], f * 1000 / 2.2)


def test_patches_mean_is_the_rows_delta_e(out):
    patches = pd.read_csv(out / "patches.csv")
    rows = _first(out, "delta-e")
    for (cfa, dem), g in patches.groupby(["cfa", "demosaic"]):
        want = rows[(rows["cfa"] == cfa) & (rows["demosaic"] == dem)]["value"].iloc[0]
        assert g["de00"].mean() == pytest.approx(want, rel=1e-9)
        assert list(g["patch"]) == list(range(1, 25)) and g["name"].iloc[0] == "dark skin"
    # the white patch reads less than the chart's white: its reflectance (0.9) and the lens's falloff
    white = patches[patches["name"].str.startswith("white")]
    assert (white["Y_ideal"] > 60).all() and (white["Y_ideal"] < 91).all()


def test_steps_snr_at_mid_grey_is_ysnr(out):
    """The step the ysnr metric measures (nearest an 18 % grey) has its SNR;
    luminance = reflectance x scene illuminance / pi (a white of reflectance
    1 under E lux has E / pi cd/m^2)."""
    steps = pd.read_csv(out / "steps.csv")
    rows = _first(out, "ysnr")
    m = pd.read_csv(out / "metrics.csv")
    for (cfa, dem, lum), g in steps.groupby(["cfa", "demosaic", "luminance"]):
        mid = g.iloc[int(np.argmin(np.abs(g["reflectance"] - 0.18)))]
        want = rows[(rows["cfa"] == cfa) & (rows["demosaic"] == dem) & (rows["luminance"] == lum)]["value"].iloc[0]
        assert mid["snr"] == pytest.approx(want, rel=1e-9)
        assert mid["snr_db"] == pytest.approx(20 * math.log10(want), rel=1e-9)
        lux = m[(m["scene"] == "gray-bar") & (m["cfa"] == cfa) & (m["luminance"] == lum)]["scene_illuminance_lux"]
        assert np.allclose(g["luminance_cd_m2"], g["reflectance"] * lux.iloc[0] / math.pi, rtol=1e-6)
        dr = g["dynamic_range"].iloc[0]
        assert 10 < dr < 1e5 and g["dynamic_range_db"].iloc[0] == pytest.approx(20 * math.log10(dr))
        assert g["saturation_luminance_cd_m2"].iloc[0] / g["snr1_luminance_cd_m2"].iloc[0] == pytest.approx(dr)


def test_less_light_less_dynamic_range_headroom(out):
    """At 5 cd/m^2 the exposure program runs at its longest time and gains
    up: the SNR on every step is lower than at 100 cd/m^2."""
    steps = pd.read_csv(out / "steps.csv")
    for (cfa, dem), g in steps.groupby(["cfa", "demosaic"]):
        lo, hi = g[g["luminance"] == 5.0]["snr"].to_numpy(), g[g["luminance"] == 100.0]["snr"].to_numpy()
        assert (lo < hi).all()


def test_db_columns_are_20_log10_of_snrs_only(out):
    m = pd.read_csv(out / "metrics.csv")
    snr = m[m["metric"].isin(["ysnr", "chroma_snr", "ysnr-area"]) & (m["value"] > 0)]
    assert len(snr) and np.allclose(snr["value_db"], 20 * np.log10(snr["value"]))
    pos = snr[snr["ci_low"] > 0]  # an interval reaching below 0 has no dB lower end
    assert len(pos) and np.allclose(pos["ci_low_db"], 20 * np.log10(pos["ci_low"]))
    assert snr[snr["ci_low"] <= 0]["ci_low_db"].isna().all()
    assert m[~m["metric"].isin(["ysnr", "chroma_snr", "ysnr-area"])]["value_db"].isna().all()


def test_exposure_in_lux_seconds_is_illuminance_times_time(out):
    """sensor_exposure_lux_s / exposure_s is the pixels' mean illuminance:
    about pi L T / (1 + 4 N^2) at f/4 (T = 1; the lens's falloff lowers the
    mean a little), whatever the CFA; the scene illuminance is pi x the white's luminance."""
    m = pd.read_csv(out / "metrics.csv")
    g = m[(m["scene"] == "macbeth") & (m["metric"] == "delta-e")]
    e = g["sensor_exposure_lux_s"] / g["exposure_s"]
    on_axis = math.pi * 100.0 / (1 + 4 * 4.0 ** 2)
    assert ((e > 0.85 * on_axis) & (e <= on_axis * 1.001)).all()
    assert np.allclose(e, e.iloc[0], rtol=1e-9)
    assert (g["scene_illuminance_lux"] > math.pi * 100).all()  # the white is brighter than the mean
