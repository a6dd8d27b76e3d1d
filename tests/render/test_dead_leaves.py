"""The dead-leaves chart: its pattern, its exact pixel means, its sidecar."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.render import dead_leaves as dl


@pytest.fixture(scope="module")
def chart():
    return cm.render.render("dead-leaves", width=448, height=320)


def test_sidecar_states_the_statistics(chart):
    g = chart.meta["geometry"]
    assert g["radius_law"] == "p(r) proportional to r^-3" and g["reflectance_set"] == "ColorChecker N Ohta"
    assert g["radius_sensor_px"][0] == dl.RADIUS_MIN_SENSOR_PX and g["seed"] == dl.DEAD_LEAVES_SEED
    assert g["palette"] == list(dl.PALETTE) and g["discs"] > 1000 and chart.meta["kind"] == "dead-leaves"
    assert 2.5 < g["contrast_ratio"] < 3.5  # below the slanted edge's 4:1
    assert set(cm.metrics.metrics_for_scene("dead-leaves")) == {"texture-mtf", "texture-mtf-cross", "texture-mtf50",
                                                               "texture-acutance"}


def test_every_pixel_is_the_mean_of_its_cells(chart):
    g = chart.meta["geometry"]
    rec = g["dead_leaves"]
    labels, _ = dl.disc_labels(rec["side_px"], rec["cells_per_px"], rec["r_min_px"], rec["r_max_px"], len(dl.PALETTE), rec["seed"])
    assert labels.min() == 0 and labels.max() == len(dl.PALETTE) - 1  # every cell covered, every reflectance used
    names, refl = cm.spectra.colorchecker(chart.wavelengths)
    rho = np.stack([refl[names.index(n)] for n in dl.PALETTE])
    t, y0, x0 = rec["cells_per_px"], *g["texture_rect"][:2]
    white = np.asarray(chart.meta["white_radiance"])
    for (i, j) in [(0, 0), (17, 101), (200, 33)]:
        cells = labels[i * t:(i + 1) * t, j * t:(j + 1) * t].ravel()
        expected = white * rho[cells].mean(axis=0)  # band means of D65 x rho, averaged over the cells
        assert np.allclose(chart.data[y0 + i, x0 + j], expected, rtol=0.01)
    # the flat patch is one reflectance
    fy0, fx0, fy1, fx1 = g["flat_rect"]
    flat = chart.data[fy0:fy1, fx0:fx1]
    assert np.allclose(flat, flat[0, 0], rtol=1e-6)


def test_mitsuba_renders_the_exact_box_integral(chart):
    """Rendered through Mitsuba as the other charts are (layers of exact
    cell shares, nearest texel, unjittered strata, box filter), every band
    of every pixel is the exact integral that numpy computes independently
    (dead_leaves.exact_radiance), up to float32 rounding."""
    assert chart.meta["renderer"].startswith("mitsuba")
    exact = dl.exact_radiance(448, 320, chart.meta["oversample"], chart.meta["spp"], chart.wavelengths)
    canonical = chart.data / chart.meta["scale_from_canonical"]
    err = np.abs(canonical - exact) / exact.max()
    assert err.max() < 1e-6, err.max()  # measured 1.2e-7: float32
    # the texture is there: every reflectance of the palette fills some pixel whole
    y0, x0, y1, x1 = chart.meta["geometry"]["texture_rect"]
    assert np.unique(np.round(exact[y0:y1, x0:x1, 15], 6)).size > 100


def test_radii_follow_the_inverse_cube_law():
    # the disc sizes leave their mark in the share of cells per disc colour run: check the law itself instead,
    # drawing radii as the painter does and comparing with p(r) ~ r^-3's CDF (Kolmogorov-Smirnov)
    from scipy import stats

    rmin, rmax = 2.0, 40.0
    u = np.random.default_rng(0).random(20000)
    r = (rmin**-2 - u * (rmin**-2 - rmax**-2)) ** -0.5
    cdf = lambda x: (rmin**-2 - np.asarray(x) ** -2) / (rmin**-2 - rmax**-2)  # noqa: E731
    assert stats.kstest(r, cdf).pvalue > 0.01


def test_too_small_a_chart_is_a_one_line_error():
    with pytest.raises(CfaMitsubaError, match="dead-leaves needs room"):
        cm.render.render("dead-leaves", width=300, height=300)
