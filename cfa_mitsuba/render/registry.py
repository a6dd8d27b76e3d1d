"""The scene registry: built-in scenes by name, users' Mitsuba XML by path.

Each scene is a :class:`~.types.Scene` declaring its defaults (size, field
of view, samples per pixel, oversampling) and its kind (what it feeds), plus a
builder that turns resolved render settings into Mitsuba scene content.
Adding a scene is one :func:`register_scene` call (STYLE.md: registries
keyed by name, not chains of ifs).  The registry imports no scene: the
built-in ones are registered by :mod:`.builtins`, which the package imports.
"""

from __future__ import annotations

__all__ = ["Scene", "Built", "RenderConfig", "register_scene", "get_scene", "list_scenes", "NATURAL"]

from pathlib import Path

from ..errors import CfaMitsubaError
from .types import NATURAL, Built, RenderConfig, Scene
from .userxml import user_scene

_REGISTRY: dict[str, Scene] = {}


def register_scene(scene: Scene) -> Scene:
    """Add (or replace) a built-in scene."""
    _REGISTRY[scene.name] = scene
    return scene


def list_scenes() -> list[tuple[str, str]]:
    """(name, one-line description) of each built-in scene (every name is
    valid for :func:`get_scene`; a Mitsuba XML path is accepted as well)."""
    return [(s.name, s.description) for s in _REGISTRY.values()]


def get_scene(name, *, allow_outside_paths: bool = False, defines=None, asset_root=None) -> Scene:
    """A built-in scene by name, or a user's scene from a path to a ``.xml``
    Mitsuba 3 scene file (read and checked: see :mod:`.userxml`; with
    ``allow_outside_paths`` it may name files outside its folder, with
    ``asset_root`` files in that one folder too; ``defines`` sets its
    parameters, as Mitsuba's ``-D NAME=VALUE``)."""
    key = str(name)
    if key in _REGISTRY:
        if defines or asset_root is not None:
            what = "--define" if defines else "--asset-root"
            raise CfaMitsubaError(f"{what} applies to a scene FILE.xml, not to the built-in scene {key!r}")
        return _REGISTRY[key]
    if key.lower().endswith(".xml") or Path(key).suffix or "/" in key:
        return user_scene(Path(key), allow_outside_paths=allow_outside_paths, defines=defines, asset_root=asset_root)
    known = ", ".join(_REGISTRY)
    raise CfaMitsubaError(f"unknown scene {key!r} (built-in scenes: {known}; or a Mitsuba scene FILE.xml)")
