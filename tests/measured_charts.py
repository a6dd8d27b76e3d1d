"""A measured spectral image of known content, written in each format by the
library that owns it: the 24 'ColorChecker N Ohta' reflectances as a cube
(io/test_measured_formats.py and study/test_measured_scenes.py read it)."""

from __future__ import annotations

import warnings

import numpy as np

from cfa_mitsuba import spectra

P = 6  # patch side in pixels; the chart is 4 x 6 patches
NAMES, TABLES = spectra.colorchecker_tables()
D65 = spectra.illuminant_table("D65")
SRC_WL = TABLES[0][0]  # colour's Ohta tabulation, 380..780 nm at 5 nm


def _colour():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour
    return colour


def chart_cube(wl=SRC_WL) -> np.ndarray:
    """(4P, 6P, N) float32 reflectance, patch i at row i // 6, column i % 6,
    each patch's spectrum the Ohta table at ``wl``."""
    cube = np.zeros((4 * P, 6 * P, len(wl)), np.float32)
    for i, (x, r) in enumerate(TABLES):
        row, col = divmod(i, 6)
        cube[row * P:(row + 1) * P, col * P:(col + 1) * P] = np.interp(wl, x, r)
    return cube


def worst_patch_error(img) -> float:
    """Largest relative deviation, over patch interiors and bands, from the
    box mean of D65 x reflectance (colour's 5-nm tables) at the image's scale."""
    scale = img.meta["scale_from_canonical"]
    worst = 0.0
    for i in range(24):
        row, col = divmod(i, 6)
        inner = img.data[row * P + 1:(row + 1) * P - 1, col * P + 1:(col + 1) * P - 1]
        assert np.ptp(inner, axis=(0, 1)).max() <= 1e-6 * inner.max()  # every interior pixel the same
        want = spectra.band_average_product([D65, TABLES[i]], img.wavelengths) * scale
        worst = max(worst, float(np.max(np.abs(inner.mean(axis=(0, 1)) / want - 1))))
    return worst


def write_envi(d):
    import spectral.io.envi as envi

    envi.save_image(str(d / "chart.hdr"), chart_cube(), force=True,
                    metadata={"wavelength": [float(v) for v in SRC_WL], "wavelength units": "Nanometers"})
    return d / "chart.hdr"


def write_exr(d):
    colour = _colour()
    spec = colour.io.Specification_Fichet2021(is_emissive=False, attributes=None)
    assert colour.io.write_spectral_image_Fichet2021({"T": (SRC_WL, chart_cube())}, str(d / "chart.exr"),
                                                     "float32", spec)
    return d / "chart.exr"


def write_png(d, cave=False):
    """16-bit grey PNGs, one per band: named by wavelength (``chart_385nm.png``,
    colour's 5-nm grid), or in the CAVE layout (``chart_ms_01.png`` ...
    ``chart_ms_31.png`` = 400 ... 700 nm)."""
    from PIL import Image

    folder = d / ("chart_ms" if cave else "chart_png")
    folder.mkdir()
    wl = np.arange(400.0, 701.0, 10.0) if cave else SRC_WL
    cube = chart_cube(wl)
    for b, w in enumerate(wl):
        codes = np.round(cube[..., b] * 65535).astype(np.uint16)
        Image.fromarray(codes).save(folder / (f"chart_ms_{b + 1:02d}.png" if cave else f"chart_{w:g}nm.png"))
    return folder


def write_mat_v5(d):
    import scipy.io

    scipy.io.savemat(d / "chart.mat", {"refl": chart_cube().astype(np.float64), "wavelengths": SRC_WL})
    return d / "chart.mat"


def write_mat_v73(d):
    import hdf5storage

    hdf5storage.savemat(str(d / "chart73.mat"), {"refl": chart_cube().astype(np.float64), "wl": SRC_WL},
                        format="7.3", matlab_compatible=True)
    return d / "chart73.mat"


WRITERS = {"envi": write_envi, "exr": write_exr, "png": write_png, "mat-v5": write_mat_v5, "mat-v73": write_mat_v73}
