"""The layouts of today's sensors (issue 16, deliverable 1): tiles typed
from their sources, densities, spectra sets, and every demosaicing method
on a real capture of each (finite, right shape)."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.sensor import get_cfa
from cfa_mitsuba.values import SpectralImage

from conftest import run_cli

#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in cm.isp.list_demosaics())


def _blocks(b):
    """Bayer GRBG with every pixel a b x b block."""
    bayer = [["G", "R"], ["B", "G"]]
    return [[bayer[i // b][j // b] for j in range(2 * b)] for i in range(2 * b)]


# research/cfa-design.md: X-Trans rows with 0 = R, 1 = G, 2 = B
_XT = ["110112", "112110", "201021", "112110", "110112", "021201"]

EXPECTED = {
    "quad-bayer": _blocks(2),
    "nona": _blocks(3),
    "tetra2": _blocks(4),
    "ryyb": [["Y", "R"], ["B", "Y"]],
    "rccb": [["W", "R"], ["B", "W"]],
    "rccc": [["W", "W"], ["W", "R"]],
    "xtrans": [["RGB"[int(c)] for c in row] for row in _XT],
    "kodak-cfa3": [list("WWWW"), list("WRWG"), list("WWWW"), list("WGWB")],
    "sony-rgbw": [list("WRWG"), list("BWGW"), list("WGWR"), list("GWBW")],  # research/cfa-demosaic.md s. 1
    "mono": [["W"]],
}
SPECTRA = {"quad-bayer": "isetcam-rgb", "nona": "isetcam-rgb", "tetra2": "isetcam-rgb", "ryyb": "isetcam-ryyb",
           "rccb": "mt9v024-rgbw", "rccc": "mt9v024-rccc", "xtrans": "isetcam-rgb", "kodak-cfa3": "isetcam-rgbw",
           "sony-rgbw": "isetcam-rgbw", "mono": "mt9v024-mono"}


@pytest.mark.parametrize("name", list(EXPECTED))
def test_tiles_and_spectra(name):
    cfa = get_cfa(name)
    assert cfa.pattern.tolist() == EXPECTED[name]
    assert cfa.spectra == SPECTRA[name]
    assert name in cm.sensor.list_cfas()


def test_published_densities():
    assert get_cfa("quad-bayer").tile_shape == (4, 4) and get_cfa("nona").tile_shape == (6, 6)
    assert get_cfa("tetra2").tile_shape == (8, 8)
    for name in ("quad-bayer", "nona", "tetra2"):
        assert get_cfa(name).densities == get_cfa("bayer").densities
    assert get_cfa("kodak-cfa3").densities == {"R": 0.0625, "G": 0.125, "B": 0.0625, "W": 0.75}
    xt = get_cfa("xtrans")
    assert {c: round(d * 36) for c, d in xt.densities.items()} == {"R": 8, "G": 20, "B": 8}
    for line in list(xt.pattern) + list(xt.pattern.T):  # every row and column holds all three
        assert set(line) == {"R", "G", "B"}
    assert get_cfa("rccc").densities == {"R": 0.25, "W": 0.75}
    assert get_cfa("sony-rgbw").densities == {"R": 0.125, "G": 0.25, "B": 0.125, "W": 0.5}


def test_ryyb_yellow_passes_more_light_than_green():
    """RYYB's case (Huawei: about +40 % light): its Y collects more than a
    Bayer G under D65 (measured 3.6x: ISETCam's RGB G peaks at 0.35, the
    yellow dye on the common silicon at 0.65 over twice the width)."""
    wl = cm.spectra.DEFAULT_WAVELENGTHS
    d65 = cm.spectra.illuminant("D65", wl) * cm.spectra.photons_per_joule(wl)
    y = get_cfa("ryyb").sensitivities()[get_cfa("ryyb").channels.index("Y")] @ d65
    g = get_cfa("bayer").sensitivities()[1] @ d65
    assert y / g > 1.3


@pytest.fixture(scope="module")
def chart_oi():
    wl = cm.spectra.DEFAULT_WAVELENGTHS
    refl = cm.spectra.colorchecker(wl)[1]
    idx = np.arange(24).reshape(4, 6).repeat(12, 0).repeat(12, 1)
    return cm.optics.compute_optics(SpectralImage(refl[idx] * cm.spectra.illuminant("D65", wl), wl,
                                                  {"fov_deg": 10.0}))


@pytest.mark.parametrize("name", list(EXPECTED))
def test_every_method_on_a_capture(chart_oi, name):
    raw = cm.sensor.capture(chart_oi, name, luminance_cd_m2=50.0, seed=3)
    assert raw.raw.shape == (48, 72) and raw.settings["cfa"]["spectra"] == SPECTRA[name]
    for method in METHODS:
        out = cm.isp.process(raw, method)
        assert out.xyz.shape == (48, 72, 3), (name, method)
        assert np.all(np.isfinite(out.xyz)) and np.all(np.isfinite(out.srgb)), (name, method)
        mosaic = cm.isp.demosaic(raw.raw - raw.black_level_dn, cm.sensor.cfa_from_raw(raw), method)
        assert mosaic.shape == (48, 72, len(raw.channels))


def test_list_cfas_names_source_and_spectra():
    lines = run_cli("list", "cfas", check_rc=0).stdout.splitlines()
    for name in EXPECTED:
        line = next(l for l in lines if l.split()[0] == name)
        assert f"spectra {SPECTRA[name]}" in line and "source: " in line, line
