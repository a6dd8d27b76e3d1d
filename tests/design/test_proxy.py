"""design/: symmetry folding, density bounds, the proxy's formulas and the
parametric spectra, each against an independent count or number."""

import itertools

import numpy as np
import pytest

from cfa_mitsuba import spectra
from cfa_mitsuba.design import layouts as L
from cfa_mitsuba.design import proxy as P
from cfa_mitsuba.design.spectra import GRID_NM, bandpass_qe, mixture_qe
from cfa_mitsuba.sensor import get_spectra_set


def _brute_classes(h, w, k, mirrors=True):
    """Distinct classes by brute force: every tile's orbit as a set of tuples."""
    seen, classes = set(), []
    for t in itertools.product(range(k), repeat=h * w):
        if t in seen or len(set(t)) < k:
            continue
        grid = np.array(t).reshape(h, w)
        orbit = set()
        for g in (grid, grid[::-1], grid[:, ::-1], grid[::-1, ::-1]) if mirrors else (grid,):
            for dr in range(h):
                for dc in range(w):
                    orbit.add(tuple(np.roll(g, (dr, dc), axis=(0, 1)).ravel()))
        seen |= orbit
        classes.append(t)
    return len(classes)


@pytest.mark.parametrize("h,w,k", [(2, 2, 3), (2, 3, 3), (3, 3, 2), (2, 4, 3), (3, 3, 3)])
def test_enumeration_counts_match_brute_force_orbits(h, w, k):
    lo, hi = np.ones(k, int), np.full(k, h * w)
    got = L.enumerate_layouts(h, w, k, lo, hi)
    assert len(got) == _brute_classes(h, w, k)
    # canonical and distinct
    assert np.array_equal(L.canonical(got, h, w, k), got)
    assert len({tuple(x) for x in got}) == len(got)


def test_no_mirrors_folds_translations_only():
    lo, hi = np.ones(3, int), np.full(3, 6)
    assert len(L.enumerate_layouts(2, 3, 3, lo, hi, mirrors=False)) == _brute_classes(2, 3, 3, mirrors=False)


def test_2x2_rgb_has_nine_layouts_and_bayer_is_one():
    got = L.enumerate_layouts(2, 2, 3, np.ones(3, int), np.full(3, 4))
    texts = {L.tile_text(x, 2, 2, "RGB") for x in got}
    assert len(got) == 9
    bayer = L.canonical(np.array([[1, 0, 2, 1]]), 2, 2, 3)[0]  # G R / B G
    assert L.tile_text(bayer, 2, 2, "RGB") in texts


def test_density_bounds_and_smaller_periods():
    lo, hi = L.density_limits({"W": (0.5, 0.5)}, ["R", "G", "B", "W"], 4)
    assert lo.tolist() == [1, 1, 1, 2] and hi.tolist() == [4, 4, 4, 2]
    # W exactly half of a 2x2 with R, G, B present cannot be: 2 + 3 > 4
    assert len(L.enumerate_layouts(2, 2, 4, lo, hi)) == 0
    # 4x4 tiles that repeat a 2x2 are dropped when 2x2 is searched too
    lo, hi = np.ones(2, int), np.full(2, 16)
    with_small = L.enumerate_chunk(0, 2, 4, 2, lo, hi, True, {(2, 2), (2, 4)})
    alone = L.enumerate_chunk(0, 2, 4, 2, lo, hi, True, {(2, 4)})
    assert len(alone) - len(with_small) == len(L.enumerate_layouts(2, 2, 2, lo, np.full(2, 4)))


def _bands(set_name, letters):
    s = get_spectra_set(set_name)
    return np.stack([spectra.band_average(*s.curve(a), spectra.DEFAULT_WAVELENGTHS) for a in letters])


def test_an_xyz_sensor_is_colorimetric():
    wl = spectra.DEFAULT_WAVELENGTHS
    # QE whose electrons per joule are the CMFs (photons per joule grow with wavelength)
    m = P.colour_model(spectra.cmfs_xyz(wl).T / wl[None, :] * 200.0)
    assert m.vora_trussell == pytest.approx(1.0, abs=1e-9)
    assert m.colour_de00 < 1e-6
    rgb = P.colour_model(_bands("isetcam-rgb", "RGB"))
    assert 0.5 < rgb.vora_trussell < 1.0 and rgb.colour_de00 > 0.5
    assert np.allclose(rgb.matrix_rel.sum(axis=0), 1.0)  # white preserved


def test_frequency_weights_follow_the_system_mtf():
    s = P.frequency_weights(2, 2, 4.0, 2.2)
    # (0.5, 0) cycles/px: diffraction at 227 cy/mm (0.391 at 550 nm, f/4) times the pixel sinc(0.5)
    from cfa_mitsuba.optics.diffraction import diffraction_mtf

    otf = diffraction_mtf(0.5 / 2.2e-3, 550, 4.0) * np.sinc(0.5)
    assert s[1, 0] == pytest.approx(otf ** 2 / (0.25 + 0.05 ** 2), rel=1e-12)
    assert s[0, 0] == 0.0 and s[1, 1] < s[1, 0]


def test_bayer_has_the_least_aliasing_of_the_2x2_rgb_layouts():
    qe = _bands("isetcam-rgb", "RGB")
    got = L.enumerate_layouts(2, 2, 3, np.ones(3, int), np.full(3, 4))
    out = P.evaluate_layouts(got, 2, 2, lambda idx: P.colour_model(qe[list(idx)]), P.ProxySettings())
    best = got[int(np.argmin(out["aliasing"]))]
    assert L.tile_text(best, 2, 2, "RGB") in {"B G / G R", "G B / R G", "G R / B G", "R G / G B"}
    # G doubled on the diagonal: carriers only at the corner and the axes' R-B difference
    assert np.all(out["aliasing"] >= out["crosstalk"])


def test_the_noise_proxy_follows_light_and_read_noise():
    qe = _bands("isetcam-rgb", "RGB")
    lay = np.array([[1, 0, 2, 1]], np.uint8)
    model = lambda idx: P.colour_model(qe[list(idx)])  # noqa: E731
    bright = P.evaluate_layouts(lay, 2, 2, model, P.ProxySettings(read_noise_e=0.0))["noise"][0]
    dim = P.evaluate_layouts(lay, 2, 2, model, P.ProxySettings(read_noise_e=0.0, luminance_ratio=0.25))["noise"][0]
    assert dim == pytest.approx(2 * bright, rel=1e-9)  # shot noise: 4x fewer electrons, 2x the relative noise
    rn = P.evaluate_layouts(lay, 2, 2, model, P.ProxySettings(read_noise_e=20.0, luminance_ratio=0.25))["noise"][0]
    assert rn > dim


def test_bandpass_dye_has_its_width_and_sits_on_the_sensor_model():
    from cfa_mitsuba.sensor.spectra_sets import ir_cut, silicon_qe

    q = bandpass_qe(550, 100, 0.8)
    t = q / (np.interp(GRID_NM, *ir_cut()) * np.interp(GRID_NM, *silicon_qe()))
    ok = np.isfinite(t) & (GRID_NM > 420) & (GRID_NM < 680)
    half = GRID_NM[ok][t[ok] >= 0.4]
    assert half.min() == pytest.approx(500, abs=2) and half.max() == pytest.approx(600, abs=2)
    assert mixture_qe("isetcam-rgb", [1, 1, 1]).max() <= 1.0

