"""Turning a :class:`~.types.Built` into a loaded Mitsuba scene.

Built-in scenes are Mitsuba dicts; users' XML scenes bring their own loader
(:mod:`.userxml`).  Either way the film, sampler and integrator are ours,
and the white panels (:mod:`.white`) may replace the camera with their
radiance meters and add their shapes.
"""

from __future__ import annotations

__all__ = ["load_scene", "inspect_settings"]

from ..errors import CfaMitsubaError, one_line
from .types import Built


def load_scene(mi, built: Built, film: dict, sampler: dict, integrator: dict, *, sensor: dict | None = None,
               extra: dict | None = None):
    """A Mitsuba scene of ``built`` with our ``film``, ``sampler`` and
    ``integrator`` (plugin dicts); ``sensor`` (a dict without film and
    sampler) replaces the scene's camera, ``extra`` ({name: shape dict})
    adds shapes."""
    if built.loader is not None:
        return built.loader(mi, film, sampler, integrator, sensor=sensor, extra=extra)
    cam = built.sensor if sensor is None else sensor
    d = {"type": "scene", **built.objects, **(extra or {}), "integrator": integrator,
         "sensor": {**cam, "film": film, "sampler": sampler}}
    try:
        return mi.load_dict(d)
    except Exception as exc:  # pragma: no cover - built-in scenes load
        raise CfaMitsubaError(f"Mitsuba cannot load the scene: {one_line(exc, 300)}") from None


def inspect_settings(width: int, height: int) -> tuple[dict, dict, dict]:
    """Film, sampler and integrator for loading a scene only to inspect it
    (first hits, light directions): stock plugins, valid in every variant."""
    return ({"type": "hdrfilm", "width": int(width), "height": int(height), "rfilter": {"type": "box"}},
            {"type": "independent", "sample_count": 1},
            {"type": "path", "max_depth": 2})
