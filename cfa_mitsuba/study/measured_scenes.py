"""``[[custom_scenes]] image = "PATH"``: a measured spectral image in a study.

The entry's keys are the render command's measured-image flags (docs/scenes.md)::

    [[custom_scenes]]
    name = "balloons"
    image = "data/balloons_ms"        # .exr, .hdr, .mat, or a folder of PNGs
    illuminant = "D65"                # a colour-science name or a CSV (relative to the config)
    quantity = "reflectance"          # radiance | reflectance | photons
    wavelengths = "400:700:10"        # or a list of numbers (nm)
    fov = 10.0                        # degrees; distance in m
    oversample = 1
    mat_cube = "scene.data.photons"   # MATLAB variable names
    mat_wavelengths = "scene.spectrum.wave"

The image feeds the full-reference image metrics (S-CIELAB, SSIM, MDSI,
HaarPSI); it is converted once into the render cache
(:mod:`cfa_mitsuba.render.measured`).
"""

from __future__ import annotations

__all__ = ["IMAGE_KEYS", "image_scene_spec"]

from pathlib import Path
from ..errors import CfaMitsubaError

#: The keys of an image entry (``name`` and ``image`` required).
IMAGE_KEYS = ("name", "image", "illuminant", "quantity", "wavelengths", "fov", "distance", "oversample", "mat_cube",
              "mat_wavelengths")


def image_scene_spec(ck, entry: dict, key: str, base: Path, taken) -> tuple[str, str, dict]:
    """Check one ``[[custom_scenes]]`` entry with an ``image`` key (``ck`` is
    the config's checker, ``taken`` the scene names already used) and
    return (name, the image's resolved path, its render options) for the
    config's :class:`~cfa_mitsuba.study.config.SceneSpec`."""
    from ..io.hyperspectral import is_measured_path
    from ..io.illuminant import resolve_illuminant

    ck.table(entry, key, dict.fromkeys(IMAGE_KEYS))
    name = ck.string(entry.get("name"), f"{key}.name")
    if name in taken:
        ck.fail(f"{key}.name", f"{name!r} is already a scene name")
    path = base / ck.string(entry["image"], f"{key}.image")
    if not path.exists() or not is_measured_path(path):
        ck.fail(f"{key}.image", f"no measured image {str(path)!r} (a .exr, .hdr or .mat file, or a folder of PNGs)")
    opts = {}
    if "illuminant" in entry:
        text = ck.string(entry["illuminant"], f"{key}.illuminant")
        local = base / text
        opts["illuminant"] = str(local.resolve()) if text.lower().endswith(".csv") and local.exists() else text
        try:
            resolve_illuminant(opts["illuminant"])
        except CfaMitsubaError as exc:
            ck.fail(f"{key}.illuminant", str(exc))
    if "quantity" in entry:
        opts["quantity"] = ck.string(entry["quantity"], f"{key}.quantity", ("radiance", "reflectance", "photons"))
    if "wavelengths" in entry:
        wl = entry["wavelengths"]
        if isinstance(wl, str):
            opts["wavelengths"] = ck.string(wl, f"{key}.wavelengths")
        elif isinstance(wl, list):
            opts["wavelengths"] = [ck.number(v, f"{key}.wavelengths[{i}]", positive=True) for i, v in enumerate(wl)]
        else:
            ck.fail(f"{key}.wavelengths", "must be a string (START:STOP:STEP) or a list of numbers")
    for k in ("fov", "distance"):
        if k in entry:
            opts[k] = ck.number(entry[k], f"{key}.{k}", positive=True, maximum=169.0 if k == "fov" else None)
    if "oversample" in entry:
        opts["oversample"] = ck.integer(entry["oversample"], f"{key}.oversample", 1)
    for k in ("mat_cube", "mat_wavelengths"):
        if k in entry:
            opts[k] = ck.string(entry[k], f"{key}.{k}")
    return name, str(path.resolve()), opts
