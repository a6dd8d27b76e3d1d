"""Any study axis (issue 11): a config sweeping ``f_number = [2.8, 8]`` on the
slanted edge and the puppy and ``seed = [1, 2, 3]`` gives one row per value;
MTF50 at f/8 falls below f/2.8 by the diffraction amount (the f/2.8 curve
with its diffraction OTF divided out and f/8's multiplied in, from the
analytic OTF); the seeds differ by noise only."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba import spectra
from cfa_mitsuba.optics.diffraction import diffraction_mtf

CONFIG = """
name = "sweep"
seed = 0
scenes = ["slanted-edge", "puppy"]
cfas = ["bayer"]
demosaics = ["bilinear"]

[[sweep]]
scenes = ["slanted-edge", "puppy"]
f_number = [2.8, 8]

[[sweep]]
scenes = ["slanted-edge", "puppy"]
seed = [1, 2, 3]

[render.slanted-edge]
width = 1280
height = 1152
[render.puppy]
width = 96
height = 84
spp = 16

[output]
figures = ["png"]
thumbnails = false
"""


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    from cfa_mitsuba.cli import main

    folder = tmp_path_factory.mktemp("sweep")
    cfg = folder / "sweep.toml"
    cfg.write_text(CONFIG)
    out = folder / "out"
    assert main(["study", str(cfg), "--out", str(out), "--quiet", "--workers", "1"]) == 0
    return out, pd.read_csv(out / "metrics.csv")


def test_one_row_per_axis_value(swept):
    out, m = swept
    for axis in ("luminance", "f_number", "pixel_pitch_um", "exposure", "read_noise_e", "seed", "base"):
        assert axis in m.columns, axis
    for scene, metric in (("slanted-edge", "mtf"), ("puppy", "ssim")):
        rows = m[(m.scene == scene) & (m.metric == metric)]
        # base (the study's f-number, seed 0), two f-numbers, three seeds
        assert len(rows) == 6, rows
        assert sorted(rows[rows.seed == 0].f_number.round(3)) == sorted(
            {2.8, 8.0, float(rows[rows.base].f_number.iloc[0])})
        assert sorted(rows[~rows.base].seed) == [0, 0, 1, 2, 3]
    # one f-number for every scene unless the config asks for each one's own lens (issue 46): f/4 by default
    assert float(m[(m.scene == "puppy") & m.base].f_number.iloc[0]) == 4.0
    assert float(m[(m.scene == "slanted-edge") & m.base].f_number.iloc[0]) == 4.0
    # the report draws a metric against each swept axis
    assert (out / "figures" / "sweep-f_number.png").is_file()
    assert (out / "figures" / "sweep-seed.png").is_file()
    timing = json.loads((out / "timing.json").read_text())
    assert {"puppy@f4", "puppy@f2.8", "puppy@f8"} <= set(timing["renders"])  # defocus follows the f-number


def _edge_curve(out, who, tag):
    d = json.loads((out / "details" / "slanted-edge" / who / f"{tag}.json").read_text())
    rec = d["mtf"]["records"]["lum"]
    return np.asarray(rec["freq_cy_px"], float), np.asarray(rec["mtf"], float), d["mtf"]["value"]


def _polychromatic_otf(f_cy_mm, n):
    """The diffraction OTF of a D65 edge as the MTF analysis sees it: each
    band's OTF weighted by that band's share of the analysed luminance
    (0.3 R + 0.6 G + 0.1 B of linear sRGB, ISETCam's weights)."""
    from cfa_mitsuba import colorimetry

    wl = spectra.DEFAULT_WAVELENGTHS
    rgb = spectra.cmfs_xyz(wl) @ colorimetry.XYZ_TO_SRGB.T
    w = spectra.illuminant("D65", wl) * (rgb @ np.array([0.3, 0.6, 0.1]))
    w = w / w.sum()
    return sum(wi * diffraction_mtf(f_cy_mm, lam, n) for wi, lam in zip(w, wl))


def _predicted_mtf50(freq_cy_px, mtf28, pitch_mm=2.2e-3):
    """MTF50 at f/8 from the f/2.8 curve: f/2.8's diffraction OTF divided out, f/8's multiplied in."""
    f_mm = freq_cy_px / pitch_mm
    m = mtf28 * _polychromatic_otf(f_mm, 8.0) / np.maximum(_polychromatic_otf(f_mm, 2.8), 1e-9)
    i = int(np.argmax(m < 0.5))
    return float(np.interp(0.5, [m[i], m[i - 1]], [f_mm[i], f_mm[i - 1]]))


def test_mtf50_falls_by_the_diffraction_amount(swept):
    out, m = swept
    edge = m[(m.scene == "slanted-edge") & (m.metric == "mtf") & (m.seed == 0)]
    mean28 = edge[edge.f_number.round(3) == 2.8].iloc[0]
    mean8 = edge[edge.f_number.round(3) == 8.0].iloc[0]
    assert mean8.ci_high < mean28.ci_low  # lower, beyond the noise
    # the curve in details/ is the first realisation's: compare like with like
    every = pd.read_csv(out / "metrics_realisations.csv")
    first = every[(every.scene == "slanted-edge") & (every.metric == "mtf") & (every.seed == 0)
                  & (every.realisation == 0)]
    f28 = float(first[first.f_number.round(3) == 2.8].value.iloc[0])
    f8 = float(first[first.f_number.round(3) == 8.0].value.iloc[0])
    # predict f/8 from the measured f/2.8 curve: divide out f/2.8's OTF, multiply in f/8's.  The edge
    # is rendered at the paper's size: on a 4x smaller one the ROI cuts the diffraction LSF's tails
    # and the prediction misses by 5 % (measured), an artefact of the edge analysis, not of the optics
    freq, mtf28, v28 = _edge_curve(out, "bayer/bilinear", "L100_f2.8")
    assert v28 == pytest.approx(f28)
    pred = _predicted_mtf50(freq, mtf28)
    print(f"camera MTF50 f/2.8 {f28:.1f}, f/8 measured {f8:.1f} (mean of {int(mean8.n)}: {mean8.value:.1f}), "
          f"predicted {pred:.1f} cy/mm")
    # against f/8's mean over the realisations: one realisation's MTF50 at f/8 scatters by 1.5 cy/mm (2.2 %,
    # measured: 72.1, 70.1, 69.1), more than the 2 % asked, so a single realisation passes or fails by its
    # noise seed; the mean's standard error is 0.9 % (measured 0.5 % from the prediction)
    assert mean8.value == pytest.approx(pred, rel=0.02)
    # the ideal sensor (no demosaic): the same optics through the same analysis
    freq, ideal28, _ = _edge_curve(out, "ideal", "L100_f2.8")
    _, _, ideal8 = _edge_curve(out, "ideal", "L100_f8")
    pred_ideal = _predicted_mtf50(freq, ideal28)
    print(f"ideal MTF50 f/8 measured {ideal8:.1f}, predicted {pred_ideal:.1f} cy/mm")
    assert ideal8 == pytest.approx(pred_ideal, rel=0.01)  # measured 0.2 % apart


@pytest.mark.parametrize("scene,metric", [("slanted-edge", "mtf"), ("puppy", "ssim"), ("puppy", "scielab")])
def test_seeds_differ_by_noise_only(swept, scene, metric):
    """Seeds 0 (the base) to 3, three noise realisations each: the seeds'
    means differ no more than the noise within a seed predicts (one-way
    ANOVA, p above 0.0027, the two-sided 3-sigma level), and the seeds are
    distinct draws."""
    from scipy.stats import f_oneway

    out, m = swept
    every = pd.read_csv(out / "metrics_realisations.csv")
    own_f = float(m[(m.scene == scene) & m.base].f_number.iloc[0])
    rows = every[(every.scene == scene) & (every.metric == metric) & (every.f_number == own_f)]
    groups = [g["value"].to_numpy() for _, g in rows.groupby("seed")]
    assert len(groups) == 4 and all(len(g) == 3 for g in groups)
    assert len({round(float(v), 12) for g in groups for v in g}) == 12  # twelve noise draws, not one
    p = f_oneway(*groups).pvalue
    print(f"{scene} {metric}: seed means {[round(float(g.mean()), 4) for g in groups]}, ANOVA p = {p:.3g}")
    assert p > 0.0027, p
