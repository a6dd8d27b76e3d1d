"""The value objects passed from stage to stage.

    SpectralImage  (render/, io/)  scene radiance, W/(m^2 sr nm)
    OpticalImage   (optics/)       sensor-plane spectral irradiance, W/(m^2 nm)
    RawImage       (sensor/)       a raw mosaic in digital numbers (or the
                                   ideal sensor's full XYZ image)
    RenderedImage  (isp/)          demosaicked, colour-corrected XYZ and sRGB

Each stage is a function from one of these to the next (ISETCam's scene ->
optical image -> sensor -> image processor, STYLE.md).  They are plain
dataclasses holding numpy arrays plus a ``meta`` dict that carries the scene
geometry (the render sidecar) downstream, so later stages never need to go
back to a file.
"""

from __future__ import annotations

__all__ = ["SpectralImage", "OpticalImage", "RawImage", "RenderedImage", "NATURAL"]

from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: The kind of a natural scene (the puppy, a user's Mitsuba XML, a measured
#: image); each chart is a kind of its own.  A scene declares its kind
#: (``render.Scene.kind``), a metric record the kinds that feed it
#: (``metrics.MetricRecord.scenes``): a value both stages read, so it lives
#: with the values passed between them, not in either stage.
NATURAL = "natural"


@dataclass
class SpectralImage:
    """Spectral radiance of a scene as seen by the camera.

    Attributes
    ----------
    data : (H, W, B) float64, band-mean spectral radiance in W/(m^2 sr nm).
    wavelengths : (B,) band centres in nm, ascending.
    meta : the sidecar: render settings, units, field of view, the scene's
        geometry (patch rectangles, edge, chirp frequencies, ...).
    """

    data: np.ndarray
    wavelengths: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.data.shape)  # type: ignore[return-value]


@dataclass
class OpticalImage:
    """Spectral irradiance on the sensor plane, at the scene image's sampling.

    Attributes
    ----------
    irradiance_w_m2_nm : (H, W, B) float64, band-mean spectral irradiance in
        W/(m^2 nm) after the lens (f-number, transmittance, relative
        illumination, diffraction OTF).
    wavelengths : (B,) nm.
    sample_pitch_um : spacing of the samples on the sensor plane (um); the
        sensor pitch divided by the oversampling factor.
    meta : the scene's meta plus the optics settings used.
    pixel_irradiance_w_m2_nm : optional (H/K, W/K, B): the irradiance
        averaged over each sensor pixel's photosensitive area (fill factor
        ``meta['fill_factor']``), computed once so that every CFA captured
        from this image reuses it; None until computed.
    """

    irradiance_w_m2_nm: np.ndarray
    wavelengths: np.ndarray
    sample_pitch_um: float
    meta: dict[str, Any] = field(default_factory=dict)
    pixel_irradiance_w_m2_nm: np.ndarray | None = None


@dataclass
class RawImage:
    """What a sensor records: the raw mosaic and everything needed to process it.

    Attributes
    ----------
    raw : (H, W) float64 digital numbers for a CFA sensor; (H, W, 3) for the
        ideal sensor (X, Y, Z, no mosaic, no noise).
    pattern : (th, tw) array of filter names (the CFA tile); for the ideal
        sensor a 1 x 1 tile ``[['XYZ']]``.
    channels : channel names, in the order of ``spectra`` rows.
    spectra : (C, B) each channel's quantum efficiency (electrons per photon,
        filter x silicon) on ``wavelengths``.
    wavelengths : (B,) nm.
    electrons_per_radiance : (C, B) electrons one pixel on the optical axis
        collects, per unit band radiance of the scene in W/(m^2 sr nm), during
        this exposure: optics factor x pixel area x fill factor x exposure x
        photons per joule x band width x QE.  With it the image processor can
        predict the response to any spectrum (white balance, colour fit).
    white_radiance : (B,) radiance of a perfect white diffuser under the
        scene's illuminant at the scene's scale, W/(m^2 sr nm).
    exposure_s, dn_per_electron, black_level_dn, seed : as named.
    settings : every sensor and optics setting used (JSON-able).
    meta : the scene's meta (sidecar) carried downstream.
    """

    raw: np.ndarray
    pattern: np.ndarray
    channels: tuple[str, ...]
    spectra: np.ndarray
    wavelengths: np.ndarray
    electrons_per_radiance: np.ndarray
    white_radiance: np.ndarray
    exposure_s: float
    dn_per_electron: float
    black_level_dn: float = 0.0
    seed: int | None = None
    settings: dict[str, Any] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def is_ideal(self) -> bool:
        return self.raw.ndim == 3


@dataclass
class RenderedImage:
    """The camera's output image.

    Attributes
    ----------
    xyz : (H, W, 3) float64 CIE 1931 XYZ on the ideal sensor's absolute
        scale: Y in cd/m^2 of the scene (a perfect white at the scene's
        white luminance reads Y = that luminance).
    srgb : (H, W, 3) float64 display sRGB in 0..1 (IEC 61966-2-1 encoding),
        white-point ``white_xyz`` mapped to 1.
    white_xyz : (3,) XYZ of the scene's white (cd/m^2 scale).
    meta : CFA, demosaic, colour matrix, its condition number, the scene's
        meta.
    """

    xyz: np.ndarray
    srgb: np.ndarray
    white_xyz: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)
