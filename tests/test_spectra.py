"""The band grid, band averaging and photometry against independent numbers."""

import numpy as np
import pytest

from cfa_mitsuba import spectra
from cfa_mitsuba.errors import CfaMitsubaError


def test_default_grid_is_31_bands_of_10nm():
    wl = spectra.DEFAULT_WAVELENGTHS
    assert wl.size == 31 and wl[0] == 400 and wl[-1] == 700
    np.testing.assert_allclose(spectra.band_edges(wl)[[0, -1]], [395, 705])
    np.testing.assert_allclose(spectra.band_widths(wl), 10)


def test_band_average_is_exact_box_mean_of_linear_interpolant():
    rng = np.random.default_rng(0)
    x = np.sort(rng.uniform(380, 720, 40))
    y = rng.uniform(0, 1, 40)
    wl = spectra.DEFAULT_WAVELENGTHS
    got = spectra.band_average(x, y, wl)
    # independent: dense midpoint quadrature of np.interp over each box
    for b, (lo, hi) in enumerate(zip(spectra.band_edges(wl)[:-1], spectra.band_edges(wl)[1:])):
        fine = np.linspace(lo, hi, 200001)
        mid = 0.5 * (fine[1:] + fine[:-1])
        assert got[b] == pytest.approx(np.interp(mid, x, y).mean(), abs=1e-8)


def test_band_average_is_not_a_point_sample():
    # a kink inside the box: the box mean differs from the centre value
    got = spectra.band_average([395, 400, 405], [0.0, 1.0, 0.0], [400, 410])
    assert got[0] == pytest.approx(0.5)


def test_luminance_of_equal_energy_radiance():
    # L_v = 683 * integral(ybar) * L for flat L; integral of CIE 1931 ybar
    # over 395..705 nm is about 106.8 nm (colour-science tabulation).
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    sel = (cmfs.wavelengths >= 395) & (cmfs.wavelengths <= 705)
    expect = 683 * np.trapezoid(cmfs.values[sel, 1], cmfs.wavelengths[sel])
    got = spectra.luminance_cd_m2(np.ones(31))
    assert got == pytest.approx(expect, rel=2e-4)


def test_photon_energy():
    # one joule at 555 nm is 2.794e18 photons (E = hc/lambda = 3.579e-19 J)
    assert spectra.photons_per_joule(555.0) == pytest.approx(2.7940e18, rel=1e-4)


@pytest.mark.parametrize(
    "grid, needle",
    [([500], "at least 2"), ([500, 490], "ascending"), ([300, 310, 320], "outside"), ([400, np.nan], "NaN")],
)
def test_bad_grids_are_refused(grid, needle):
    with pytest.raises(CfaMitsubaError, match=needle):
        spectra.validate_wavelengths(grid)


def test_parse_band_grid():
    assert spectra.parse_band_grid("400:700:10").tolist() == list(range(400, 701, 10))
    for bad in ("400:700", "a:b:c", "400:700:0", "700:400:10"):
        with pytest.raises(CfaMitsubaError):
            spectra.parse_band_grid(bad)


def test_data_sets_have_expected_shapes():
    names, refl = spectra.colorchecker()
    assert len(names) == 24 and refl.shape == (24, 31) and names[0] == "dark skin"
    assert spectra.training_reflectances().shape == (190, 31)
    assert spectra.camera_rgb().shape == (31, 3)
    assert spectra.camera_rgb().sum(axis=1).max() <= spectra.CAMERA_PEAK_QE + 1e-12


def test_band_average_product_is_exact_and_differs_from_product_of_means():
    import colour

    d65 = spectra.illuminant_table("D65")
    # the tables are colour-science's own data, not a copy
    assert np.array_equal(d65[0], colour.SDS_ILLUMINANTS["D65"].wavelengths)
    assert np.array_equal(d65[1], colour.SDS_ILLUMINANTS["D65"].values)
    names, tables = spectra.colorchecker_tables()
    wl = spectra.DEFAULT_WAVELENGTHS
    edges = spectra.band_edges(wl)
    worst_gap = 0.0
    for t in tables[:6]:
        got = spectra.band_average_product([d65, t], wl)
        for b, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
            x = np.linspace(lo, hi, 20001)
            x = 0.5 * (x[1:] + x[:-1])
            dense = np.mean(np.interp(x, *d65) * np.interp(x, *t))
            assert got[b] == pytest.approx(dense, rel=1e-7)
        means = spectra.band_average(*d65, wl) * spectra.band_average(*t, wl)
        worst_gap = max(worst_gap, np.max(np.abs(means / got - 1)))
    assert 1e-3 < worst_gap < 2e-2  # the two conventions really differ (at 400 nm)
