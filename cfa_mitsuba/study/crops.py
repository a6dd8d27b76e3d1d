"""Crops an engineer can judge (issue 50): the same region of every camera
output and of the ideal sensor, at the sensor's own pixels, saved beside
each evaluation's thumbnail as ``details/<scene>/<cfa>/<demosaic>/<tag>.crop.png``
(the ideal's under ``details/<scene>/ideal/``), for the report's crop grid
(report/crops.py: 1:1 and 4:1 by nearest neighbour, a CFA per row).

Where each scene's region sits is data (``cfa_mitsuba/data/crops.toml``):
the chirp at the column of a given local frequency on its analysed row, the
slanted edge at its analysis region's centre, the puppy at a fixed place
(its test card).  A scene the file does not name gets no crop.  The PNG is
the output's XYZ, scaled as the metrics see it (mean-matched to the ideal)
and encoded as the thumbnails are (:func:`cfa_mitsuba.colorimetry.xyz_to_srgb8`,
the scene white adapted to sRGB's), 8 bits, not resampled.
"""

from __future__ import annotations

__all__ = ["crop_box", "save_crop", "crop_settings"]

import functools
import tomllib
from pathlib import Path

import numpy as np


@functools.lru_cache(maxsize=1)
def crop_settings() -> dict:
    """The parsed ``data/crops.toml`` ({scene: {...}, 'defaults': {...}})."""
    path = Path(__file__).resolve().parents[1] / "data" / "crops.toml"
    return tomllib.loads(path.read_text())


def crop_box(scene: str, meta: dict, shape) -> tuple[int, int, int, int] | None:
    """``(y0, x0, y1, x1)`` of ``scene``'s crop on an image of ``shape``
    whose render sidecar is ``meta`` (the ideal's: it holds the scene
    geometry), or None for a scene without a region."""
    spec = crop_settings().get(scene)
    if not isinstance(spec, dict):
        return None
    defaults = crop_settings().get("defaults", {})
    h, w = int(shape[0]), int(shape[1])
    size = min(int(spec.get("size_px", defaults.get("size_px", 96))), h, w)
    if size < 4:
        return None
    cy, cx = h / 2.0, w / 2.0
    geo = {}
    if "frequency_cy_px" in spec or spec.get("edge"):
        from ..metrics import scene_geometry

        geo = scene_geometry(meta, shape)
    if "frequency_cy_px" in spec and geo.get("frequency_cy_per_px") is not None:
        f = np.asarray(geo["frequency_cy_per_px"], dtype=float)
        above = np.flatnonzero(f >= float(spec["frequency_cy_px"]))
        cx = float(above[0]) if above.size else w - size / 2.0
        cy = float(geo.get("row", h // 2))
    elif spec.get("edge") and geo.get("roi"):
        y0, x0, y1, x1 = geo["roi"]
        cy, cx = (y0 + y1) / 2.0, (x0 + x1) / 2.0
    elif "centre" in spec:
        cy, cx = float(spec["centre"][0]) * h, float(spec["centre"][1]) * w
    y0 = int(np.clip(round(cy - size / 2.0), 0, h - size))
    x0 = int(np.clip(round(cx - size / 2.0), 0, w - size))
    return y0, x0, y0 + size, x0 + size


def save_crop(path: Path, rendered, box, scale: float = 1.0) -> None:
    """Write ``rendered``'s (a RenderedImage) ``box`` as an 8-bit sRGB PNG,
    its XYZ times ``scale`` (the mean-match scale of a camera output)."""
    from ..colorimetry import xyz_to_srgb8
    from ..io import write_image
    from ..isp.colour_matrix import DISPLAY_ADAPTATION

    y0, x0, y1, x1 = box
    xyz = np.asarray(rendered.xyz[y0:y1, x0:x1], dtype=np.float64) * float(scale)
    codes = xyz_to_srgb8(xyz, rendered.white_xyz, adaptation=DISPLAY_ADAPTATION)
    write_image(path, codes / 255.0)
