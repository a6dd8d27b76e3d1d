"""Thin-lens geometry, radiance-to-irradiance factor and relative illumination.

The camera is a thin lens with its pupil at the lens, focused on the scene
plane.  The scene's horizontal field of view must fill the sensor's width
(sensor pixels x pitch), which fixes the image distance; the scene distance
then fixes the magnification and the focal length.  So a chart rendered with
a given FOV always lands on the same sensor pixels, whatever the pitch.

References
----------
ISETCam ``opticalimage/oiCalculateIrradiance.m`` (the on-axis factor),
``opticalimage/optics/cos4th.m`` (relative illumination), ``opticsGet``
'magnification' (lensmaker equation).  research/isetcam.md, s. 2.2-2.5.
"""

from __future__ import annotations

__all__ = [
    "OpticsParams",
    "LensGeometry",
    "lens_geometry",
    "on_axis_factor",
    "relative_illumination",
    "DEFAULT_FOV_DEG",
    "DEFAULT_SCENE_DISTANCE_M",
    "DEFAULT_F_NUMBER",
    "MIN_F_NUMBER",
]

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import CfaMitsubaError, require

#: Fallbacks for an EXR without a sidecar: ISETCam's default scene
#: (``sceneInitSpatial.m``: 10 deg horizontal FOV; ``sceneInitGeometry.m``:
#: 1.2 m distance), research/isetcam.md s. 2.5.
DEFAULT_FOV_DEG = 10.0
DEFAULT_SCENE_DISTANCE_M = 1.2
#: ISETCam's default optics (``opticsCreate.m``, 'standard (1/4-inch)'): f/4.
DEFAULT_F_NUMBER = 4.0
#: The fastest f-number a lens in air can have: N = 1 / (2 NA) for an
#: aplanatic lens focused at infinity, and NA = n sin(theta) <= 1 in air
#: (Born & Wolf, Principles of Optics, s. 8.6.3); the fastest made are f/0.7.
MIN_F_NUMBER = 0.5


@dataclass(frozen=True)
class OpticsParams:
    """Settings of the diffraction-limited thin lens.

    Attributes
    ----------
    f_number : N = focal length / aperture diameter.  None (default): the
        sidecar's ``f_number`` (top level, else under ``geometry``, as a
        thin-lens render that modelled defocus at that aperture records
        it), else :data:`DEFAULT_F_NUMBER`; a number overrides the sidecar.
    lens_transmittance : T, a scalar or one value per band in (0, 1].
        Default 1 (ISETCam: transmittance 1 over 370-730 nm).
    relative_illumination : apply the off-axis falloff of a uniform
        circular exit pupil (:func:`relative_illumination`).  Default on
        (ISETCam's ``offAxisMethod 'cos4th'``).
    diffraction : apply the per-wavelength diffraction-limited OTF.
        Default on (ISETCam's ``otfMethod 'dlmtf'``).
    fov_deg : horizontal field of view (deg).  None (default): the
        sidecar's ``fov_deg``, else :data:`DEFAULT_FOV_DEG`; a number
        overrides the sidecar.
    scene_distance_m : object distance (m).  None (default): the sidecar's
        ``scene_distance_m``, else :data:`DEFAULT_SCENE_DISTANCE_M`; a number
        overrides it; ``math.inf`` focuses at infinity (magnification 0).
    """

    f_number: float | None = None
    lens_transmittance: float | tuple = 1.0
    relative_illumination: bool = True
    diffraction: bool = True
    fov_deg: float | None = None
    scene_distance_m: float | None = None

    def __post_init__(self):
        require(
            self.f_number is None
            or (isinstance(self.f_number, (int, float)) and math.isfinite(self.f_number) and self.f_number > 0),
            f"f-number must be a positive number, got {self.f_number!r}",
        )
        require(
            self.f_number is None or self.f_number >= MIN_F_NUMBER,
            f"f-number {self.f_number!r} is below f/{MIN_F_NUMBER:g}, the fastest a lens in air can be: N = 1 / (2 NA) "
            "and a numerical aperture cannot exceed 1 (the refractive index of air)",
        )
        t = np.asarray(self.lens_transmittance, dtype=np.float64)
        require(t.ndim <= 1 and t.size >= 1, "lens transmittance must be a number or one value per band")
        require(
            bool(np.all(np.isfinite(t)) and np.all(t > 0) and np.all(t <= 1)),
            "lens transmittance must lie in (0, 1]",
        )
        if t.ndim == 1:  # keep it hashable and JSON-able
            object.__setattr__(self, "lens_transmittance", tuple(float(v) for v in t))
        require(
            self.fov_deg is None or (isinstance(self.fov_deg, (int, float)) and 0 < self.fov_deg < 180),
            f"field of view must lie in (0, 180) degrees, got {self.fov_deg!r}",
        )
        require(
            self.scene_distance_m is None
            or (isinstance(self.scene_distance_m, (int, float)) and self.scene_distance_m > 0),
            f"scene distance must be positive (inf for infinity), got {self.scene_distance_m!r}",
        )

    def transmittance(self, n_bands: int) -> np.ndarray:
        """T per band, shape (n_bands,)."""
        t = np.asarray(self.lens_transmittance, dtype=np.float64)
        if t.ndim == 0:
            return np.full(n_bands, float(t))
        if t.size != n_bands:
            raise CfaMitsubaError(f"lens transmittance has {t.size} values for {n_bands} bands")
        return t

    def to_dict(self) -> dict:
        return {
            "lens_transmittance": (
                list(self.lens_transmittance)
                if isinstance(self.lens_transmittance, tuple)
                else float(self.lens_transmittance)
            ),
            "relative_illumination": bool(self.relative_illumination),
            "diffraction": bool(self.diffraction),
        }


@dataclass(frozen=True)
class LensGeometry:
    """The lens as it must be for the scene to fill the sensor.

    Attributes (SI units)
    ---------------------
    sensor_width_m : sensor pixels across x pixel pitch.
    fov_deg : horizontal field of view.
    scene_distance_m : object distance (``inf`` allowed).
    image_distance_m : lens to sensor, d = w / (2 tan(FOV/2)).
    magnification : |m| = d / s (0 at infinity).
    focal_length_m : f from 1/f = 1/s + 1/d.
    f_number : N.
    working_f_number : N (1 + |m|), the image-side f-number that sets both
        the irradiance (ISETCam's 1 + 4 N^2 (1+|m|)^2) and the diffraction
        cutoff 1 / (lambda N (1 + |m|)) (ISETCam ``dlMTF.m``: D / (lambda d)).
    """

    sensor_width_m: float
    fov_deg: float
    scene_distance_m: float
    image_distance_m: float
    magnification: float
    focal_length_m: float
    f_number: float
    working_f_number: float
    extra: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        return {
            "sensor_width_mm": self.sensor_width_m * 1e3,
            "fov_deg": self.fov_deg,
            "scene_distance_m": self.scene_distance_m if math.isfinite(self.scene_distance_m) else "inf",
            "image_distance_mm": self.image_distance_m * 1e3,
            "focal_length_mm": self.focal_length_m * 1e3,
            "magnification": self.magnification,
            "f_number": self.f_number,
            "working_f_number": self.working_f_number,
        }


def lens_geometry(sensor_width_px: int, pixel_pitch_um: float, fov_deg: float,
                  scene_distance_m: float, f_number: float) -> LensGeometry:
    """Thin-lens geometry that maps the scene's horizontal FOV onto the sensor.

    Parameters
    ----------
    sensor_width_px : sensor pixels across (EXR width / oversampling).
    pixel_pitch_um : sensor pixel pitch (um).
    fov_deg : horizontal field of view of the scene (deg).
    scene_distance_m : object distance (m); ``inf`` for a distant scene.
    f_number : N.

    Examples
    --------
    720 pixels of 2.2 um behind a 10 degree field at 1.2 m:

    >>> g = lens_geometry(720, 2.2, 10.0, 1.2, 4.0)
    >>> round(g.image_distance_m * 1e3, 4), round(g.focal_length_m * 1e3, 4)
    (9.0526, 8.9848)
    """
    w = float(sensor_width_px) * float(pixel_pitch_um) * 1e-6
    d = w / (2.0 * math.tan(math.radians(float(fov_deg)) / 2.0))
    s = float(scene_distance_m)
    if math.isinf(s):
        m, f = 0.0, d
    else:
        require(s > d, f"scene distance {s:g} m is inside the image distance {d:g} m: no real image")
        m = d / s
        f = d * s / (d + s)
    return LensGeometry(
        sensor_width_m=w, fov_deg=float(fov_deg), scene_distance_m=s, image_distance_m=d,
        magnification=m, focal_length_m=f, f_number=float(f_number),
        working_f_number=float(f_number) * (1.0 + m),
    )


def on_axis_factor(f_number: float, magnification: float, transmittance=1.0) -> np.ndarray:
    """E / L on the optical axis: pi T / (1 + 4 N^2 (1 + |m|)^2), in sr.

    Irradiance (W/(m^2 nm)) of the image of a uniform Lambertian radiance L
    (W/(m^2 sr nm)) through an aberration-free lens whose exit pupil, seen
    from the axial image point, subtends a cone of half-angle theta with
    sin^2(theta) = 1 / (1 + 4 N_w^2) (ISETCam ``oiCalculateIrradiance.m``).

    >>> round(float(on_axis_factor(4.0, 0.0)), 6)   # pi / 65
    0.048332
    """
    n_w = float(f_number) * (1.0 + abs(float(magnification)))
    return np.pi * np.asarray(transmittance, dtype=np.float64) / (1.0 + 4.0 * n_w * n_w)


def relative_illumination(shape: tuple[int, int], sample_pitch_m: float, image_distance_m: float,
                          working_f_number: float) -> np.ndarray:
    """Off-axis irradiance relative to the axis, shape (H, W), 1 on the axis.

    The irradiance at field angle phi (tan phi = r / d, r the distance of the
    sample centre from the image centre, d the image distance) from a
    uniform Lambertian disk (the exit pupil, half-angle theta on the axis,
    tan theta = 1 / (2 N_w)) in a plane parallel to the sensor:

        E(phi) = (pi L / 2) [1 - (1 + a - b) / sqrt((1 + a + b)^2 - 4 a b)],
        a = tan^2 phi, b = tan^2 theta,

    divided by its on-axis value pi L sin^2 theta.  It tends to cos^4 phi for
    a small pupil (b -> 0).  This is the closed form of ISETCam's
    ``cos4th.m`` (its "close image" branch); ISETCam passes sin^2 theta where
    the formula wants sin theta, which shrinks its cone to nearly a point and
    so gives almost plain cos^4 phi; we use the pupil's true angle.
    """
    h, w = int(shape[0]), int(shape[1])
    y = (np.arange(h) + 0.5 - h / 2.0) * sample_pitch_m
    x = (np.arange(w) + 0.5 - w / 2.0) * sample_pitch_m
    a = (y[:, None] ** 2 + x[None, :] ** 2) / (image_distance_m * image_distance_m)
    b = 1.0 / (4.0 * working_f_number * working_f_number)
    e = 0.5 * (1.0 - (1.0 + a - b) / np.sqrt((1.0 + a + b) ** 2 - 4.0 * a * b))
    return e / (b / (1.0 + b))
