"""Registers the built-in scenes (the charts and the puppy).

The one module that imports the scenes; the package imports it, so the
registry is filled whenever anything in ``cfa_mitsuba.render`` is used,
and the registry itself imports no scene (no import cycles).
"""

from __future__ import annotations

__all__ = ["BUILTIN_SCENES"]

from . import charts, dead_leaves, puppy
from .registry import register_scene

#: The built-in scenes, in the order ``cfa-mitsuba list scenes`` shows them.
BUILTIN_SCENES = (*charts.SCENES, dead_leaves.SCENE, puppy.SCENE)

for _scene in BUILTIN_SCENES:
    register_scene(_scene)
