"""The scene registry: built-in scenes by name, users' Mitsuba XML by path.

Each scene is a :class:`Scene` declaring its defaults (size, field of view,
samples per pixel, oversampling) and the metrics it feeds, plus a builder
that turns resolved render settings into Mitsuba scene content
(:class:`Built`).  Adding a scene is one :func:`register_scene` call
(STYLE.md: registries keyed by name, not chains of ifs).
"""

from __future__ import annotations

__all__ = ["Scene", "Built", "RenderConfig", "register_scene", "get_scene", "list_scenes", "FULL_REFERENCE_METRICS"]

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import CfaMitsubaError

#: The metrics a natural (3D) scene feeds: full-reference image comparisons.
FULL_REFERENCE_METRICS = ("scielab", "ssim", "mdsi", "haarpsi")


@dataclass(frozen=True)
class RenderConfig:
    """Resolved, validated render settings (see :func:`.engine.resolve_settings`).

    Sizes are EXR pixels; ``fov_deg`` is horizontal; ``oversample`` is K,
    EXR pixels per sensor pixel along each axis; ``wavelengths`` are band
    centres in nm; ``luminance_cd_m2`` is the requested mean luminance.
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

    @property
    def wl(self) -> np.ndarray:
        return np.asarray(self.wavelengths, dtype=np.float64)


@dataclass
class Built:
    """What a scene builder hands to the engine.

    Exactly one of ``objects`` (Mitsuba dict entries: shapes, emitters; plus
    ``sensor``, a sensor dict without film and sampler) or ``xml`` (a whole
    scene file with the placeholders ``<!--cfa:film-->``,
    ``<!--cfa:sampler-->`` inside its sensor and ``<!--cfa:integrator-->``)
    is set.

    ``pattern_spectrum``: for achromatic charts, the (B,) radiance in
    W/(m^2 sr nm) of pattern value 1; Mitsuba then renders one spatial
    channel (emitters with flat spectra whose value is the pattern) and the
    engine multiplies.  None for spectral scenes, rendered band by band.

    ``white_radiance``: (B,) radiance of a perfect white diffuser under the
    scene's light, W/(m^2 sr nm), at the render's canonical scale; None means
    measure it: ``white_probe`` = {"center", "camera", "half_size"} places a
    perfect white Lambertian square at ``center`` facing ``camera`` (scene
    units), whose radiance a radiance meter at ``camera`` measures.

    ``band_constant``: every spectrum is constant inside each band (built-in
    scenes, :mod:`.light`), so bands are evaluated at their box centres;
    False for users' scenes, whose bands are jittered across their boxes.

    ``xml_sensor``: for XML scenes, the user's sensor element (with the film
    and sampler placeholders); ``xml`` holds ``<!--cfa:sensor-->`` in its
    place, so that the white probe can swap in a radiance meter.
    """

    meta: dict[str, Any]
    objects: dict[str, Any] | None = None
    sensor: dict[str, Any] | None = None
    xml: str | None = None
    xml_sensor: str | None = None
    xml_dir: Path | None = None
    band_constant: bool = True
    pattern_spectrum: np.ndarray | None = None
    white_radiance: np.ndarray | None = None
    white_probe: dict[str, Any] | None = None


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
    metrics : the CLI metric names this scene feeds.
    max_depth : path length (1: emitters seen directly; flat charts).
    sampler : Mitsuba sampler plugin used (``stratified``: spp is rounded
        up to a square, s x s strata per pixel).
    jitter : whether samples are jittered inside their strata (False: at
        the strata centres, the flat charts' exact cell quadrature).
    builder : ``builder(scene, config) -> Built``.
    path : the XML file for users' scenes, else None.
    """

    name: str
    description: str
    width: int
    height: int
    fov_deg: float
    spp: int
    oversample: int
    metrics: tuple[str, ...]
    builder: Callable[["Scene", RenderConfig], Built] = field(repr=False, compare=False)
    max_depth: int = 1
    sampler: str = "stratified"
    jitter: bool = True
    path: Path | None = None
    identity: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def is_3d(self) -> bool:
        return self.max_depth > 1

    def build(self, config: RenderConfig) -> Built:
        return self.builder(self, config)


_REGISTRY: dict[str, Scene] = {}


def register_scene(scene: Scene) -> Scene:
    """Add (or replace) a built-in scene."""
    _REGISTRY[scene.name] = scene
    return scene


def _load_builtins() -> None:
    from . import charts, puppy  # noqa: F401  (they register themselves on import)


def list_scenes() -> list[tuple[str, str]]:
    """(name, one-line description) of each built-in scene (every name is
    valid for :func:`get_scene`; a Mitsuba XML path is accepted as well)."""
    _load_builtins()
    return [(s.name, s.description) for s in _REGISTRY.values()]


def get_scene(name) -> Scene:
    """A built-in scene by name, or a user's scene from a path to a ``.xml``
    Mitsuba 3 scene file (validated: see :mod:`.userxml`)."""
    _load_builtins()
    key = str(name)
    if key in _REGISTRY:
        return _REGISTRY[key]
    if key.lower().endswith(".xml") or Path(key).suffix or "/" in key:
        from .userxml import user_scene

        return user_scene(Path(key))
    known = ", ".join(_REGISTRY)
    raise CfaMitsubaError(f"unknown scene {key!r} (built-in scenes: {known}; or a Mitsuba scene FILE.xml)")
