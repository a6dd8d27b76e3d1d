"""The scenes of a study config: ``scenes`` (built-in names),
``[[custom_scenes]]`` (a user's Mitsuba XML or a measured spectral image)
and the ``[render]`` table, each scene with the metrics its kind feeds."""

from __future__ import annotations

__all__ = ["SceneSpec", "IMAGE_METRICS", "parse_scenes", "render_common"]

from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CfaMitsubaError
from ..io.validate import safe_name
from ..metrics import NATURAL, metrics_for_scene
from .checker import _Checker

#: Metrics a user scene feeds (the image metrics of DESIGN.md), from the metric records.
IMAGE_METRICS = metrics_for_scene(NATURAL)


@dataclass(frozen=True)
class SceneSpec:
    """One scene of a study: a built-in name or a user's Mitsuba XML.

    ``render`` holds the render settings that differ from the scene's
    defaults (width, height, spp, oversample, seed, ...), passed to the
    render stage as keywords.
    """

    name: str
    file: str | None = None
    render: dict = field(default_factory=dict)
    metrics: tuple[str, ...] = ()


# Render settings a config may override per scene, with their checks.
_RENDER_KEYS = {
    "width": ("integer", 1), "height": ("integer", 1), "spp": ("integer", 1),
    "oversample": ("integer", 1), "seed": ("integer", 0), "fov": ("number", None), "max_depth": ("integer", 1),
}


def _render_overrides(ck: _Checker, data, key: str) -> dict:
    ck.table(data, key, _RENDER_KEYS)
    out = {}
    for k, v in data.items():
        kind, lo = _RENDER_KEYS[k]
        if kind == "integer":
            out[k] = ck.integer(v, f"{key}.{k}", lo)
        else:
            out[k] = ck.number(v, f"{key}.{k}", positive=True, maximum=179.0)
    return out


def render_common(ck: _Checker, render_cfg, known_scenes) -> dict:
    """``[render]``: the variant and band grid every scene uses (per-scene
    tables are read with the scenes)."""
    ck.table(render_cfg, "render", {"variant": None, "bands": None, **{s: None for s in known_scenes}})
    out = {}
    if "variant" in render_cfg:
        out["variant"] = ck.string(render_cfg["variant"], "render.variant",
                                   ("auto", "cuda_ad_spectral", "llvm_ad_spectral", "scalar_spectral"))
        if out["variant"] == "auto":
            del out["variant"]
    if "bands" in render_cfg:
        from ..spectra import parse_band_grid

        try:
            out["bands"] = ck.string(render_cfg["bands"], "render.bands")
            parse_band_grid(out["bands"])
        except CfaMitsubaError as exc:
            ck.fail("render.bands", str(exc))
    return out


def _scene_access(ck, c: dict, key: str, base: Path) -> dict:
    """A custom scene's ``defines`` (a table of its ``$name`` parameters, as
    ``render --define``) and ``asset_root`` (one shared folder its files may
    be in, relative to the config, as ``render --asset-root``)."""
    from ..render.xmlscan import check_asset_root, parse_defines

    out = {}
    try:
        if "defines" in c:
            if not isinstance(c["defines"], dict):
                ck.fail(f"{key}.defines", "must be a table of NAME = value")
            out["defines"] = dict(parse_defines(c["defines"]))
        if "asset_root" in c:
            out["asset_root"] = check_asset_root(base / ck.string(c["asset_root"], f"{key}.asset_root"))
    except CfaMitsubaError as exc:
        ck.fail(f"{key}.{'asset_root' if 'asset-root' in str(exc) else 'defines'}", str(exc))
    return out


def _user_scene(ck: _Checker, c, key: str, base: Path, taken: list) -> SceneSpec:
    """One ``[[custom_scenes]]`` entry naming a Mitsuba XML file."""
    ck.table(c, key, {"name": None, "file": None, "allow_outside_paths": None, "defines": None, "asset_root": None,
                      **_RENDER_KEYS})
    cname = ck.string(c.get("name"), f"{key}.name")
    if safe_name(cname) != cname:  # it names folders under details/: a label, never a path
        ck.fail(f"{key}.name", f"must be a label of letters, digits, '-', '_' and inner '.' (got {cname!r})")
    if "file" not in c:
        ck.fail(f"{key}.file", "missing (the scene's Mitsuba XML file, or image = a measured spectral image)")
    f = base / ck.string(c["file"], f"{key}.file")
    if not f.is_file():
        ck.fail(f"{key}.file", f"no such file {str(f)!r}")
    if cname in taken:
        ck.fail(f"{key}.name", f"{cname!r} is already a scene name")
    access = ("name", "file", "allow_outside_paths", "defines", "asset_root")
    over = _render_overrides(ck, {k: v for k, v in c.items() if k not in access}, key)
    over.update(_scene_access(ck, c, key, base))
    if "allow_outside_paths" in c:  # the scene may name files outside its folder
        if not isinstance(c["allow_outside_paths"], bool):
            ck.fail(f"{key}.allow_outside_paths", "must be true or false")
        over["allow_outside_paths"] = c["allow_outside_paths"]
    return SceneSpec(cname, str(f.resolve()), over, IMAGE_METRICS)


def parse_scenes(ck: _Checker, data: dict, render_cfg: dict, render_common: dict, base: Path) -> list[SceneSpec]:
    """``scenes`` (built-in names) and ``[[custom_scenes]]`` (user XML files
    and measured images), each with the metrics its kind feeds."""
    from .. import render
    from .budget import check_scenes
    from .measured_scenes import image_scene_spec

    known_scenes = [n for n, _ in render.list_scenes()]
    scenes = []
    for i, s in enumerate(ck.string_list(data.get("scenes", []), "scenes", allow_empty=True)):
        if s not in known_scenes:
            ck.fail(f"scenes[{i}]", f"unknown scene {s!r} (known: {', '.join(known_scenes)}; "
                                    "user XML scenes go under [[custom_scenes]])")
        over = _render_overrides(ck, render_cfg.get(s, {}), f"render.{s}")
        scenes.append(SceneSpec(s, None, over, metrics_for_scene(render.get_scene(s).kind)))
    custom = data.get("custom_scenes", [])
    if not isinstance(custom, list):
        ck.fail("custom_scenes", "must be an array of tables ([[custom_scenes]])")
    for i, c in enumerate(custom):
        key = f"custom_scenes[{i}]"
        taken = [*known_scenes, *(s.name for s in scenes)]
        if isinstance(c, dict) and "image" in c:  # a measured spectral image (study/measured_scenes.py)
            iname, image, opts = image_scene_spec(ck, c, key, base, taken)
            scenes.append(SceneSpec(iname, image, opts, IMAGE_METRICS))
        else:
            scenes.append(_user_scene(ck, c, key, base, taken))
    if not scenes:
        ck.fail("scenes", "no scenes to run")
    check_scenes(ck.fail, scenes, render_common)  # renders and tasks within the limits, before any work
    return scenes
