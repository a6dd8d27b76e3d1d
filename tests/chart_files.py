"""A small spectral EXR of the ColorChecker under D65 (a fixture the sensor tests share)."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm


@pytest.fixture(scope="module")
def chart_exr(tmp_path_factory):
    wl = cm.spectra.DEFAULT_WAVELENGTHS
    refl = cm.spectra.colorchecker(wl)[1]
    idx = np.arange(24).reshape(4, 6).repeat(8, 0).repeat(8, 1)
    path = tmp_path_factory.mktemp("presets") / "chart.exr"
    cm.io.write_spectral_exr(path, cm.values.SpectralImage(refl[idx] * cm.spectra.illuminant("D65", wl) * 1e-3, wl,
                                                           {"fov_deg": 10.0}))
    return path
