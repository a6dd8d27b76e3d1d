"""A capture in the field's photometric units, beside the radiometry the
chain runs on: the scene's illuminance in lux and the sensor-plane
illuminance and exposure in lux and lux-seconds (ISO 12232's H).

References: CIE 15:2018 (photometric quantities, K_m = 683 lm/W); a
Lambertian reflector of reflectance 1 has luminance L = E / pi.
"""

from __future__ import annotations

__all__ = ["add_photometry", "band_mean_irradiance", "saturation_rel"]

import math

import numpy as np

from .. import spectra as _spectra


def band_mean_irradiance(pix: np.ndarray) -> np.ndarray:
    """(B,) the mean over the pixels of ``pix`` (..., B), W/(m^2 nm): what
    :func:`add_photometry` reads of the pixel irradiance (the same for every
    capture of one optical image, so a caller may keep it)."""
    return pix.reshape(-1, pix.shape[-1]).mean(axis=0)


def add_photometry(meta: dict, band_mean: np.ndarray, wl: np.ndarray, s: float, exposure_s: float) -> None:
    """The field's units of a capture, added to ``meta`` (s: the luminance
    scale, ``band_mean`` the pixel irradiance before it averaged over the
    pixels, (B,) W/(m^2 nm): :func:`band_mean_irradiance`):

    * ``scene_illuminance_lux``: the illuminance on the scene that gives its
      white the captured luminance, E = pi L_white (a perfect white diffuser,
      Lambertian, has L = E / pi; charts: the chart's light, D65; a 3D scene:
      the light its white panel receives, the sidecar's ``white_reference``);
    * ``sensor_illuminance_lux``: the mean illuminance on the pixels, 683 lm/W
      x sum of ybar(l) E(l) dl over the sensor-plane irradiance (lens
      transmittance, relative illumination and diffraction included);
    * ``sensor_exposure_lux_s``: that illuminance times the exposure time
      (the photometric exposure H of ISO 12232)."""
    y = _spectra.cmfs_xyz(wl)[:, 1] * _spectra.band_widths(wl) * _spectra.KM_LM_W
    illuminance = float(band_mean @ y) * s
    meta["scene_illuminance_lux"] = math.pi * float(meta["white_luminance_cd_m2"])
    meta["sensor_illuminance_lux"] = illuminance
    meta["sensor_exposure_lux_s"] = illuminance * float(exposure_s)


def saturation_rel(electrons_per_radiance, white_radiance, clip_e: float) -> float | None:
    """The scene Y / Yw at which a neutral first clips, on the axis: the
    clip level ``clip_e`` (electrons: the full well, or the ADC's top code
    above the black level, the lower) over the most electrons a channel
    collects from the scene white (``electrons_per_radiance`` (C, B) @
    ``white_radiance`` (B,)); None for a black white.  The top of ISO
    15739's dynamic range (study/steps.py)."""
    white = np.asarray(electrons_per_radiance, dtype=float) @ np.asarray(white_radiance, dtype=float)
    top = float(np.max(white)) if white.size else 0.0
    return float(clip_e) / top if top > 0 and clip_e > 0 else None
