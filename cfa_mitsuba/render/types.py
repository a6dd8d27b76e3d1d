"""The render stage's value types: a scene, its resolved settings, and what
a scene builder hands to the engine.

Kept apart from the registry and the scenes so that every render module can
import them without import cycles (registry -> userxml -> types; charts,
puppy -> types; builtins -> charts, puppy, registry).
"""

from __future__ import annotations

__all__ = ["Scene", "Built", "RenderConfig", "NATURAL", "LENS_PIXEL_PITCH_M", "MAX_FOV_DEG", "focal_length_m"]

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..values import NATURAL  # noqa: F401  (the scenes' natural kind, shared with the metric records)

#: Sensor pixel pitch (m) that defines a 3D scene's lens: the focal length
#: that images the scene's field of view onto its film width in pixels of
#: this pitch (the optics stage's default pitch, 2.2 um).
LENS_PIXEL_PITCH_M = 2.2e-6
#: Horizontal fields of view from this (degrees) up are refused: Mitsuba's
#: perspective and thin-lens cameras take (0, 180) (``parse_fov``,
#: src/render/sensor.cpp), and so do the optics stage and the sidecar schema.
#: Up to it every quantity derived from the field of view stays finite: the
#: focal length (w p / 2) / tan(fov / 2) > 0 and relative illumination,
#: whose tan^2 of the field angle is finite (:func:`focal_length_m`).
MAX_FOV_DEG = 180.0


def focal_length_m(width_px: int, fov_deg: float) -> float:
    """Focal length (m) imaging a horizontal field of ``fov_deg`` degrees
    onto ``width_px`` pixels of :data:`LENS_PIXEL_PITCH_M`: f = (w p / 2) /
    tan(fov / 2)."""
    return 0.5 * width_px * LENS_PIXEL_PITCH_M / math.tan(math.radians(fov_deg) / 2)



@dataclass(frozen=True)
class RenderConfig:
    """Resolved, validated render settings (see :func:`.engine.resolve_settings`).

    Sizes are EXR pixels; ``fov_deg`` is horizontal; ``oversample`` is K,
    EXR pixels per sensor pixel along each axis; ``wavelengths`` are band
    centres in nm; ``luminance_cd_m2`` is the requested mean luminance;
    ``f_number`` the requested thin-lens f-number (None: the scene's own);
    ``white_from`` the white-reference rule ('panel', 'illuminant' or an
    (X, Y, Z) in cd/m^2, see :mod:`.white`).
    """

    width: int
    height: int
    spp: int
    seed: int
    wavelengths: tuple[float, ...]
    variant: str
    oversample: int
    fov_deg: float
    max_depth: int
    luminance_cd_m2: float
    f_number: float | None = None
    white_from: str | tuple[float, float, float] = "panel"

    @property
    def wl(self) -> np.ndarray:
        return np.asarray(self.wavelengths, dtype=np.float64)


@dataclass
class Built:
    """What a scene builder hands to the engine.

    Exactly one of ``objects`` (Mitsuba dict entries: shapes, emitters; plus
    ``sensor``, a sensor dict without film and sampler) or ``loader`` (users'
    XML scenes: ``loader(mi, film, sampler, integrator, sensor=None,
    extra=None) -> mitsuba.Scene``, the scene with our film, sampler and
    integrator, optionally another sensor and extra shapes) is set.

    ``pattern_spectrum``: for achromatic charts, the (B,) radiance in
    W/(m^2 sr nm) of pattern value 1; Mitsuba then renders one spatial
    channel (emitters with flat spectra whose value is the pattern) and the
    engine multiplies.  None for spectral scenes, rendered band by band.

    ``white_radiance``: (B,) radiance of a perfect white diffuser under the
    scene's light, W/(m^2 sr nm), at the render's canonical scale, where it
    is known exactly (the charts); None means measure it with white panels
    (3D scenes, :mod:`.white`).

    ``band_constant``: every spectrum is constant inside each band (built-in
    scenes, :mod:`.light`), so bands are evaluated at their box centres;
    False for users' scenes, whose bands are jittered across their boxes.

    ``stock_integrator``: the name of a Mitsuba integrator (``volpath``,
    ``volpathmis``) that the scene needs instead of the all-band integrator
    (a user's scene with participating media, :mod:`.media`); the engine
    then renders it band by band with a single-band ``specfilm``, in any
    variant.  None: the engine's usual route.

    ``layers``: a flat chart made of several achromatic patterns, each
    with its own spectrum: ((objects, spectrum (B,)), ...).  Each layer's
    ``objects`` (with ``sensor``) is rendered as an achromatic chart (one
    spatial channel, emitter values = the pattern) and the engine sums the
    layers' patterns times their spectra: the dead-leaves chart
    (:mod:`.dead_leaves`), whose 10^5 discs of three reflectances are three
    bitmaps of exact cell shares.  None for every other scene.
    """

    meta: dict[str, Any]
    objects: dict[str, Any] | None = None
    sensor: dict[str, Any] | None = None
    loader: Callable[..., Any] | None = None
    band_constant: bool = True
    pattern_spectrum: np.ndarray | None = None
    white_radiance: np.ndarray | None = None
    stock_integrator: str | None = None
    layers: tuple | None = None


@dataclass(frozen=True)
class Scene:
    """A renderable scene and its defaults.

    Attributes
    ----------
    name : the CLI name (``macbeth``) or the XML file's stem.
    description : one line for ``cfa-mitsuba list scenes``.
    width, height : default EXR size (pixels).
    fov_deg : default horizontal field of view (degrees).
    spp : default samples per pixel.
    oversample : default K (EXR pixels per sensor pixel, per axis).
    kind : what the scene is, for the metrics it feeds: a chart's own kind
        (``'macbeth'``, ...) or :data:`NATURAL`.
    max_depth : path length (1: emitters seen directly; flat charts).
    sampler : Mitsuba sampler plugin used (``stratified``: spp is rounded
        up to a square, s x s strata per pixel).
    jitter : whether samples are jittered inside their strata (False: at
        the strata centres, the flat charts' exact cell quadrature).
    builder : ``builder(scene, config) -> Built``.
    path : the XML file for users' scenes, else None.
    identity : what the cache key needs beyond the settings (a user XML's
        files and their content hashes).
    thin_lens : the render depends on the f-number (a thin-lens camera), so
        ``f_number`` is part of the cache key.
    f_number : the thin lens's default f-number (None: set by the scene
        file's aperture).
    allow_outside_paths : a user XML may name files outside its folder.
    defines : ((name, value), ...) scene parameters given to a user XML
        (``render --define``, Mitsuba's ``-D``), overriding its ``<default>``s.
    asset_root : one more folder a user XML may name files in (besides its
        own), or None.
    fov_at : ``fov_at(width, height)`` -> the horizontal field of view
        (degrees) the camera has on a film of that size, where it depends
        on the size (a user XML's ``fov_axis``); None: ``fov_deg`` always.
    """

    name: str
    description: str
    width: int
    height: int
    fov_deg: float
    spp: int
    oversample: int
    kind: str
    builder: Callable[["Scene", RenderConfig], Built] = field(repr=False, compare=False)
    max_depth: int = 1
    sampler: str = "stratified"
    jitter: bool = True
    path: Path | None = None
    identity: dict[str, Any] = field(default_factory=dict, compare=False)
    thin_lens: bool = False
    f_number: float | None = None
    allow_outside_paths: bool = False
    defines: tuple[tuple[str, str], ...] = ()
    asset_root: str | None = None
    fov_at: Callable[[int, int], float] | None = field(default=None, repr=False, compare=False)

    @property
    def is_3d(self) -> bool:
        return self.max_depth > 1

    def build(self, config: RenderConfig) -> Built:
        return self.builder(self, config)


