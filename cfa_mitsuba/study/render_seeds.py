"""Which scenes a study renders with several sampler seeds (``render_seeds``),
and the render source of each seed (study/runner.py plans them, study/sizing.py
counts them)."""

from __future__ import annotations

__all__ = ["path_traced", "is_3d", "render_seeded"]


def path_traced(scene) -> bool:
    """Whether a study renders ``scene`` with several sampler seeds
    (``render_seeds``): the scenes that path-trace (3D: the puppy and every
    user Mitsuba scene with bounces).  The charts are seen directly and
    their renders are deterministic (measured at the quick study's sizes,
    16 spp: seeds 0 and 1 give identical Macbeth and gray-bar renders, and
    slanted-edge and chirp renders that differ by at most 1.6e-7 of their
    range, float32 rounding; the puppy's differ by 19 % rms per pixel), so
    they are rendered once; a measured image is not rendered at all."""
    return is_3d(scene)


def is_3d(scene) -> bool:
    """Whether the scene path-traces (max_depth > 1); a measured image is no
    scene file and does not."""
    from .. import render
    from ..render.measured import is_measured_image

    if is_measured_image(scene.file or scene.name):
        return False
    access = {k: scene.render[k] for k in ("allow_outside_paths", "defines", "asset_root") if k in scene.render}
    return bool(render.get_scene(scene.file or scene.name, **access).is_3d)


def render_seeded(src: dict, r: int) -> dict:
    """The source of render seed index ``r``: the sampler seed moved by r
    (r = 0 is the scene's own render, the one a study with one render seed uses)."""
    if r == 0:
        return src
    settings = dict(src["settings"])
    settings["seed"] = int(settings.get("seed") or 0) + r
    return {**src, "settings": settings}
