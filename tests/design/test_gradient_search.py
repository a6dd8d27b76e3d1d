"""The gradient method (cfa_mitsuba/design/gradient_search.py): its config
is checked with one-line errors, the B-spline family bounds the dye in
[0, 1] and its band values are what the emitted curve gives, and L-BFGS-B
lowers the weighted objective from every start within the bounds."""

from __future__ import annotations

import dataclasses
import json
import tomllib

import numpy as np
import pytest

from cfa_mitsuba import spectra
from cfa_mitsuba.design.config import load_design, parse_design
from cfa_mitsuba.errors import CfaMitsubaError
from conftest import REPO

WL = spectra.DEFAULT_WAVELENGTHS

GOOD = """
name = "g"
seed = 2
[design]
method = "gradient"
[layout]
tiles = ["2x2"]
alphabet = ["R", "G", "B"]
[spectra]
family = "spline"
knots = 8
[gradient]
layout = "G R / B G"
weights = [0.5]
starts = 2
max_iter = 8
[[objective]]
metric = "delta-e"
demosaic = "bilinear"
[[objective]]
metric = "snr10"
scene = "gray-bar"
demosaic = "bilinear"
[study]
scenes = ["macbeth", "gray-bar"]
cfas = ["bayer"]
demosaics = ["bilinear"]
[study.sensor]
exposure_policy = "program"
"""


def test_the_shipped_gradient_config_loads():
    cfg = load_design(REPO / "configs" / "design-gradient.toml")
    assert cfg.method == "gradient" and cfg.spectra.family == "spline" and cfg.gradient.layout == "G R / B G"
    assert len(cfg.study.cfas) == 18  # ISETCam's RGB and the 17 camera sets


BAD = [
    ('layout = "G R / B G"', 'layout = "G R / B Q"', "gradient.layout"),
    ('layout = "G R / B G"', 'layout = "G R B / B G R"', "gradient.layout"),
    ('family = "spline"\nknots = 8', 'family = "bandpass"', "spectra.family"),
    ('knots = 8', 'knots = 3', "spectra.knots"),
    ('weights = [0.5]', 'weights = [1.5]', "gradient.weights"),
    ('demosaic = "bilinear"\n[[objective]]', 'demosaic = "laplacian"\n[[objective]]', "objective[0].demosaic"),
    ('metric = "snr10"', 'metric = "mtf"', "objective"),
    ('method = "gradient"', 'method = "steepest"', "design.method"),
    ('[gradient]', '[gradient]\nstep = 1', "gradient.step"),
]


@pytest.mark.parametrize("old, new, key", BAD)
def test_bad_gradient_configs_name_the_key(old, new, key):
    assert old in GOOD
    text = GOOD.replace(old, new, 1)
    if key == "objective[0].demosaic":
        text = text.replace('demosaics = ["bilinear"]', 'demosaics = ["bilinear", "laplacian"]')
    with pytest.raises(CfaMitsubaError) as e:
        parse_design(tomllib.loads(text))
    msg = str(e.value)
    assert key in msg and "\n" not in msg, msg


def test_spline_dyes_are_bounded_and_their_bands_are_the_emitted_curves():
    from cfa_mitsuba.design.spectra import GRID_NM, basis_matrices, common_qe, spline_basis, spline_qe

    spec = parse_design(tomllib.loads(GOOD)).spectra
    b = spline_basis(spec.knots)
    assert b.min() >= 0 and np.allclose(b.sum(axis=1), 1.0)
    rng = np.random.default_rng(0)
    c = rng.uniform(0, 1, spec.knots)
    t = b @ c
    assert 0.0 <= t.min() and t.max() <= 1.0
    grid, bands = basis_matrices(spec)
    assert np.allclose(grid @ c, spline_qe(c)) and np.allclose(spline_qe(c), t * common_qe())
    assert np.allclose(bands @ c, spectra.band_average(GRID_NM, spline_qe(c), WL), rtol=1e-12)


def test_lbfgsb_lowers_the_objective_within_the_bounds(tmp_path):
    from cfa_mitsuba.design.gradient import make_gradient_proxy
    from cfa_mitsuba.design.gradient_search import _Problem, run_gradient
    from cfa_mitsuba.design.search import proxy_settings

    cfg = parse_design(tomllib.loads(GOOD))
    res = run_gradient(cfg, tmp_path, log=lambda *a: None)
    cands = res.candidates
    assert res.evaluated == 2 and len(cands) >= 1
    gp = make_gradient_proxy(np.array([[1, 0], [2, 1]]), 3, proxy_settings(cfg))
    problem = _Problem(cfg, ["R", "G", "B"], gp)
    for _, row in cands.iterrows():
        theta = np.concatenate([p["coefficients"] for p in json.loads(row["params"])])
        assert theta.min() >= 1e-4 - 1e-12 and theta.max() <= 1.0
        x0 = problem.starts(cfg.gradient.starts, cfg.seed)[int(row["start"])]
        before, after = problem.loss(x0, 0.5, "snr10"), problem.loss(theta, 0.5, "snr10")
        assert after < before, (before, after)
        # the candidate's own proxies are those of its emitted curves
        assert row["snr10"] == pytest.approx(row["gradient_noise"], rel=1e-4)
    assert {"max_slope_per_10nm", "peak", "nearest_set", "nearest_set_angle_deg"} <= set(cands.columns)


def test_a_gradient_config_is_sized_by_its_runs():
    from cfa_mitsuba.design.sizing import design_size

    cfg = parse_design(tomllib.loads(GOOD))
    n, seconds, _, text = design_size(cfg)
    assert n == 1 * 2 * 8 and seconds > 0 and "L-BFGS-B" in text
    cfg = dataclasses.replace(cfg, gradient=dataclasses.replace(cfg.gradient, starts=4))
    assert design_size(cfg)[0] == 32


def test_a_dye_library_mixture_stays_within_its_bounds_and_below_qe_1(tmp_path):
    from cfa_mitsuba.design.gradient_search import run_gradient
    from cfa_mitsuba.design.spectra import basis_matrices, library

    text = GOOD.replace('family = "spline"\nknots = 8',
                        'family = "mixture"\nbasis = ["isetcam-rgb", "pbrt-sony-ilce-9"]\nweight = [0, 2]')
    cfg = parse_design(tomllib.loads(text))
    assert cfg.spectra.basis == ("isetcam-rgb", "pbrt-sony-ilce-9")
    n = len(library(cfg.spectra.basis))
    cands = run_gradient(cfg, tmp_path, log=lambda *a: None).candidates
    for _, row in cands.iterrows():
        for p in json.loads(row["params"]):
            w = np.asarray(p["weights"])
            assert w.size == n and w.min() >= 0 and w.max() <= 2
            # the penalty holds the unscaled mixture near QE 1 (mixture_qe scales any excess away)
            assert (basis_matrices(cfg.spectra)[0] @ w).max() <= 1.05
        assert np.isfinite(row["gradient_colour"]) and row["peak"] <= 1.0 + 1e-9
