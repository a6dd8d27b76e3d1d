"""A study's sizes checked while its config is validated, before any work.

Each scene's render (width x height x spp x bands, from the config's
overrides over the scene's defaults) must be within the renderer's limits
and, like the study's largest evaluation task on that render, fit in the
memory available (:mod:`cfa_mitsuba.io.limits`).  A refusal names the config
key (``render.macbeth.width``, ``custom_scenes[0].spp``), not a
command-line option, and comes before ``config.json`` or anything else is
written.

A user scene's film size is in its XML; unless the config overrides width
and height, its render is checked when it is loaded (the render stage
refuses it then, still before Mitsuba allocates).
"""

from __future__ import annotations

__all__ = ["check_scenes"]

import math

from ..io import limits
from ..errors import CfaMitsubaError


def _bands(render_common: dict) -> int:
    from ..spectra import DEFAULT_WAVELENGTHS, parse_band_grid

    grid = render_common.get("bands")
    return int(len(parse_band_grid(grid)) if grid else len(DEFAULT_WAVELENGTHS))


def check_scenes(fail, scenes, render_common: dict) -> None:
    """Refuse (through ``fail(key, reason)``, the config checker's) a scene
    whose render or evaluation task is beyond the limits."""
    from ..render import get_scene

    n_bands = _bands(render_common)
    custom = 0
    for spec in scenes:
        over = spec.render
        if spec.file is None:
            prefix = f"render.{spec.name}"
            default = get_scene(spec.name)
            w, h, spp = over.get("width", default.width), over.get("height", default.height), over.get("spp", default.spp)
        else:
            prefix = f"custom_scenes[{custom}]"
            custom += 1
            if "width" not in over or "height" not in over:
                continue
            w, h, spp = over["width"], over["height"], over.get("spp", 1)
        for key, value, top in (("width", w, limits.MAX_SIDE), ("height", h, limits.MAX_SIDE),
                                ("spp", spp, limits.MAX_SPP)):
            if value > top:
                fail(f"{prefix}.{key}", f"must be at most {top} (got {value})")
        spp = (math.isqrt(spp - 1) + 1) ** 2  # the stratified sampler's square, as the render stage rounds
        try:
            limits.check_render(w, h, spp, n_bands, name=lambda k: f"{prefix}.{k}")
            limits.require_memory(limits.estimate_task_bytes(h, w, n_bands),
                                  f"evaluating {spec.name!r} ({w} x {h} pixels x {n_bands} bands, one task)",
                                  f"lower {prefix}.width / height")
        except CfaMitsubaError as exc:
            fail(prefix, str(exc))
