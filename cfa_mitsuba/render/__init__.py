"""render/: Mitsuba 3 spectral rendering of the built-in scenes and users'
scene files into a :class:`~cfa_mitsuba.values.SpectralImage` (band-mean
spectral radiance, W/(m^2 sr nm)).

Public interface::

    list_scenes()                 -> [(name, description)]
    get_scene(name_or_xml_path)   -> Scene (defaults, .kind)
    render(scene, **settings)     -> SpectralImage      (pure: no files)
    render_cached(scene, **settings) -> SpectralImage   (through the cache)
    cache_key(scene, **settings)  -> str
    resolve_settings(scene, **settings) -> (Scene, RenderConfig)
    choose_variant(requested=None) -> str

Settings: width, height, spp, luminance (cd/m^2), variant, seed, bands,
oversample, fov, max_depth, f_number, white_from, allow_outside_paths.
Mitsuba is imported lazily (only when something is rendered or a scene
file is read), so importing this package is cheap.
"""

from .types import NATURAL, Built, RenderConfig, Scene  # noqa: F401
from .registry import get_scene, list_scenes, register_scene  # noqa: F401
from . import builtins as _builtins  # noqa: F401  (registers the built-in scenes)
from .variant import SPECTRAL_VARIANTS, choose_variant, find_libllvm  # noqa: F401
from .engine import (  # noqa: F401
    DEFAULT_LUMINANCE_CD_M2,
    cache_key,
    render,
    render_cached,
    render_canonical,
    resolve_settings,
    scale_to_luminance,
)
