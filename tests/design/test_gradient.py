"""The differentiable proxy (cfa_mitsuba/design/gradient.py): its values are
the proxy's, its CIELAB and CIEDE2000 the project's, its noise forms the
demosaic's noise gains, and its gradient agrees with central finite
differences within 1e-4 relative on random smooth spectra."""

from __future__ import annotations

import numpy as np
import pytest
from autograd import grad

import cfa_mitsuba as cm
from cfa_mitsuba import colorimetry, spectra
from cfa_mitsuba.design import gradient as G
from cfa_mitsuba.design import proxy as P
from cfa_mitsuba.sensor import ExposureProgram
from cfa_mitsuba.design.spectra import GRID_NM, spline_qe

WL = spectra.DEFAULT_WAVELENGTHS
SETTINGS = P.ProxySettings(4.0, 2.2, 6200.0, 6.2, 0.1, exposure=ExposureProgram("program"), luminance_cd_m2=10.0,
                           demosaics=("bilinear",))


def _cfa(name):
    cfa = cm.sensor.get_cfa(name)
    lut = {c: i for i, c in enumerate(cfa.channels)}
    return cfa.sensitivities(WL), np.array([[lut[c] for c in r] for r in cfa.pattern])


def _smooth_qe(rng, n_channels=3):
    """Random smooth whole-pixel QE: 12 random B-spline coefficients per channel."""
    return np.stack([spectra.band_average(GRID_NM, spline_qe(rng.uniform(0.05, 0.95, 12)), WL)
                     for _ in range(n_channels)])


@pytest.mark.parametrize("cfa", ["bayer", "rgbw1", "cmy1"])
def test_values_are_the_proxys(cfa):
    qe, layout = _cfa(cfa)
    got = P.evaluate_layouts(layout.ravel()[None, :].astype(np.uint8), *layout.shape,
                             lambda idx: P.colour_model(qe[list(idx)], well_e=SETTINGS.well_e,
                                                        read_noise_e=SETTINGS.read_noise_e), SETTINGS)
    gp = G.make_gradient_proxy(layout, qe.shape[0], SETTINGS, chart="training")
    for name in G.OBJECTIVES:
        assert float(gp.objective(name, qe)) == pytest.approx(float(got[name][0]), rel=1e-7), name


def test_lab_and_ciede2000_are_the_projects():
    rng = np.random.default_rng(3)
    white = spectra.xyz_from_radiance(spectra.illuminant("D65", WL), WL)
    xyz = rng.uniform(0.0005, 1.1, (200, 3)) * white
    assert np.allclose(G.lab(xyz, white), colorimetry.xyz_to_lab(xyz, white), atol=1e-9)
    a, b = G.lab(xyz[:100], white), G.lab(xyz[100:], white)
    assert np.allclose(G.ciede2000(a, b), colorimetry.delta_e_2000(a, b), rtol=1e-9, atol=1e-6)
    # Sharma, Wu & Dalal's pair 1 (their Table 1): 2.0425
    pair = G.ciede2000(np.array([[50.0, 2.6772, -79.7751]]), np.array([[50.0, 0.0, -82.7485]]))
    assert float(pair[0]) == pytest.approx(2.0425, abs=5e-5)


@pytest.mark.parametrize("cfa", ["bayer", "rgbw1", "rgbw2"])
def test_noise_forms_give_the_demosaics_noise_gains(cfa):
    qe, layout = _cfa(cfa)
    rng = np.random.default_rng(5)
    m = rng.normal(size=(qe.shape[0], 3)) + 1.0
    names = tuple(str(i) for i in range(qe.shape[0]))
    pix, area = G.noise_forms(layout, qe.shape[0])
    want = P.demosaic_noise_gains(layout, names, m, "bilinear")
    want_area = P.demosaic_area_noise_gains(layout, names, m, "bilinear")
    for j in range(3):
        assert np.allclose([m[:, j] @ pix[c] @ m[:, j] for c in range(qe.shape[0])], want[:, j], rtol=1e-10)
        assert np.allclose([m[:, j] @ area[c] @ m[:, j] for c in range(qe.shape[0])], want_area[:, j], rtol=1e-10)


def _central(f, q, h=1e-6):
    g = np.zeros_like(q)
    for idx in np.ndindex(q.shape):
        step = np.zeros_like(q)
        step[idx] = h
        g[idx] = (f(q + step) - f(q - step)) / (2 * h)
    return g


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("name", G.OBJECTIVES)
def test_gradient_agrees_with_central_differences(name, seed):
    """Acceptance 2 of issue 52: on random smooth spectra (12 random cubic
    B-spline coefficients per channel), the autograd gradient with respect
    to the (3, 31) band QE matches central differences (h = 1e-6) within
    1e-4 of the gradient's largest component, in every component."""
    _, layout = _cfa("bayer")
    gp = G.make_gradient_proxy(layout, 3, SETTINGS, chart="macbeth")
    q = _smooth_qe(np.random.default_rng(seed))

    def f(x):
        return gp.objective(name, x)

    got = grad(f)(q)
    fd = _central(lambda x: float(f(x)), q)
    assert np.all(np.isfinite(got)) and np.abs(fd).max() > 0
    assert np.abs(got - fd).max() <= 1e-4 * np.abs(fd).max(), (name, np.abs(got - fd).max(), np.abs(fd).max())


def test_four_channels_differentiate_too():
    _, layout = _cfa("rgbw1")
    gp = G.make_gradient_proxy(layout, 4, SETTINGS)
    q = _smooth_qe(np.random.default_rng(9), 4)
    for name in ("colour", "snr10_area"):
        got = grad(lambda x: gp.objective(name, x))(q)
        fd = _central(lambda x: float(gp.objective(name, x)), q)
        assert np.abs(got - fd).max() <= 1e-4 * np.abs(fd).max(), name
