"""A capture in lux and lux-seconds (sensor/photometry.py) against the
camera equation: a uniform field of luminance L behind an f/N lens of
transmittance T gives E = pi L T / (1 + 4 N^2 (1 + |m|)^2) on the sensor;
a white of luminance Lw is lit by pi Lw lux."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cfa_mitsuba import spectra
from cfa_mitsuba.optics import OpticsParams, compute_optics
from cfa_mitsuba.sensor import capture, capture_ideal
from cfa_mitsuba.values import SpectralImage


def _flat_field(luminance: float = 50.0):
    wl = np.asarray(spectra.DEFAULT_WAVELENGTHS, dtype=float)
    d65 = spectra.illuminant("D65", wl)
    rad = d65 * (luminance / float(spectra.luminance_cd_m2(d65, wl)))
    data = np.broadcast_to(rad, (24, 24, wl.size)).copy()
    return SpectralImage(data, wl, {"white_radiance": (rad / 0.5).tolist(), "fov_deg": 2.0,
                                    "scene_distance_m": 1e6, "oversample": 1})


@pytest.mark.parametrize("f_number, transmittance", [(4.0, 1.0), (2.0, 0.8)])
def test_sensor_illuminance_is_the_camera_equation(f_number, transmittance):
    image = _flat_field(50.0)
    oi = compute_optics(image, OpticsParams(f_number=f_number, lens_transmittance=transmittance,
                                            relative_illumination=False, diffraction=False), pixel_pitch_um=2.2)
    n_w = oi.meta["optics"]["working_f_number"]
    expected = math.pi * 50.0 * transmittance / (1 + 4 * n_w ** 2)
    for raw in (capture(oi, "bayer", exposure_s=0.01, noise="off"), capture_ideal(oi, exposure_s=0.01)):
        assert raw.meta["sensor_illuminance_lux"] == pytest.approx(expected, rel=1e-9)
        assert raw.meta["sensor_exposure_lux_s"] == pytest.approx(expected * 0.01, rel=1e-9)
        # the white (reflectance 1) is twice the field's luminance here: pi x 100 cd/m^2
        assert raw.meta["scene_illuminance_lux"] == pytest.approx(math.pi * 100.0, rel=1e-9)


def test_a_brighter_scene_scales_both():
    oi = compute_optics(_flat_field(50.0), OpticsParams(relative_illumination=False, diffraction=False),
                        pixel_pitch_um=2.2)
    a = capture(oi, "bayer", exposure_s=0.01, noise="off", luminance_cd_m2=50.0)
    b = capture(oi, "bayer", exposure_s=0.01, noise="off", luminance_cd_m2=200.0)
    assert b.meta["sensor_illuminance_lux"] == pytest.approx(4 * a.meta["sensor_illuminance_lux"])
    assert b.meta["scene_illuminance_lux"] == pytest.approx(4 * a.meta["scene_illuminance_lux"])


def test_saturation_is_where_the_brightest_channel_fills_its_well():
    """saturation_rel x the white's electrons in the fullest channel = the
    clip level (the full well, or the ADC's top code, the lower)."""
    oi = compute_optics(_flat_field(50.0), OpticsParams(relative_illumination=False, diffraction=False),
                        pixel_pitch_um=2.2)
    raw = capture(oi, "bayer", exposure_s=0.01, noise="off")
    white = raw.electrons_per_radiance @ raw.white_radiance
    sensor = raw.settings["sensor"]
    clip = min(sensor["well_capacity_e"], (2 ** sensor["adc_bits"] - 1) / raw.dn_per_electron)
    assert raw.meta["saturation_rel"] * white.max() == pytest.approx(clip, rel=1e-9)


def test_each_optical_image_gets_its_own_illuminance_when_captures_alternate():
    """The mean irradiance is kept between captures of one optical image
    (capture.py's _band_mean): captures alternating between two optical
    images each read their own."""
    params = OpticsParams(relative_illumination=False, diffraction=False)
    dim, bright = (compute_optics(_flat_field(lum), params, pixel_pitch_um=2.2) for lum in (50.0, 150.0))
    lux = {}
    for oi in (dim, bright, dim, bright):
        got = capture(oi, "bayer", exposure_s=0.01, noise="off").meta["sensor_illuminance_lux"]
        assert lux.setdefault(id(oi), got) == got
    assert lux[id(bright)] == pytest.approx(3 * lux[id(dim)], rel=1e-12)
