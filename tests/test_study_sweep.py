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
width = 320
height = 288
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
        # base (the scene's own f-number, seed 0), two f-numbers, three seeds
        assert len(rows) == 6, rows
        assert sorted(rows[rows.seed == 0].f_number.round(3)) == sorted(
            {2.8, 8.0, float(rows[rows.base].f_number.iloc[0])})
        assert sorted(rows[~rows.base].seed) == [0, 0, 1, 2, 3]
    # the puppy's base f-number is its render's own (f/2), used by diffraction too
    assert float(m[(m.scene == "puppy") & m.base].f_number.iloc[0]) == 2.0
    assert float(m[(m.scene == "slanted-edge") & m.base].f_number.iloc[0]) == 4.0
    # the report draws a metric against each swept axis
    assert (out / "figures" / "sweep-f_number.png").is_file()
    assert (out / "figures" / "sweep-seed.png").is_file()
    timing = json.loads((out / "timing.json").read_text())
    assert {"puppy", "puppy@f2.8", "puppy@f8"} <= set(timing["renders"])  # defocus follows the f-number


def _edge_curve(out, tag):
    d = json.loads((out / "details" / "slanted-edge" / "bayer" / "bilinear" / f"{tag}.json").read_text())
    rec = d["mtf"]["details"]["records"]["lum"]
    return np.asarray(rec["freq_cy_px"], float), np.asarray(rec["mtf"], float), d["mtf"]["value"]


def _polychromatic_otf(f_cy_mm, n):
    """The luminance-weighted diffraction OTF of a D65 edge at f-number n."""
    wl = spectra.DEFAULT_WAVELENGTHS
    w = spectra.illuminant("D65", wl) * spectra.cmfs_xyz(wl)[:, 1]
    w = w / w.sum()
    return sum(wi * diffraction_mtf(f_cy_mm, lam, n) for wi, lam in zip(w, wl))


def test_mtf50_falls_by_the_diffraction_amount(swept):
    out, m = swept
    edge = m[(m.scene == "slanted-edge") & (m.metric == "mtf") & (m.seed == 0)]
    f28 = float(edge[edge.f_number.round(3) == 2.8].value.iloc[0])
    f8 = float(edge[edge.f_number.round(3) == 8.0].value.iloc[0])
    assert f8 < f28
    # predict f/8 from the measured f/2.8 curve: divide out f/2.8's OTF, multiply in f/8's
    freq, mtf28, v28 = _edge_curve(out, "L100_f2.8")
    assert v28 == pytest.approx(f28)
    pitch_mm = 2.2e-3
    f_mm = freq / pitch_mm
    m_pred = mtf28 * _polychromatic_otf(f_mm, 8.0 * 1.0) / np.maximum(_polychromatic_otf(f_mm, 2.8), 1e-9)
    i = int(np.argmax(m_pred < 0.5))
    pred = np.interp(0.5, [m_pred[i], m_pred[i - 1]], [f_mm[i], f_mm[i - 1]])
    print(f"MTF50 f/2.8 {f28:.1f}, f/8 measured {f8:.1f}, predicted {pred:.1f} cy/mm")
    assert f8 == pytest.approx(pred, rel=0.05)
    assert (f28 - f8) == pytest.approx(f28 - pred, rel=0.15)


@pytest.mark.parametrize("scene,metric", [("slanted-edge", "mtf"), ("puppy", "ssim"), ("puppy", "scielab")])
def test_seeds_differ_by_noise_only(swept, scene, metric):
    _, m = swept
    rows = m[(m.scene == scene) & (m.metric == metric) & m.f_number.isin(
        m[(m.scene == scene) & m.base].f_number)]
    by_seed = rows.set_index("seed")["value"]
    others = by_seed.loc[[1, 2, 3]].to_numpy()
    assert len(set(np.round(others, 12))) == 3  # three noise realisations, not one
    sd = others.std(ddof=1)
    # seed 0 (the base row) is a fourth, independent realisation of the same camera
    assert abs(by_seed.loc[0] - others.mean()) < 3 * sd * np.sqrt(1 + 1 / 3), (by_seed.to_dict(), sd)
