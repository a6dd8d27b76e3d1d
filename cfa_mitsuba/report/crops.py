"""The crop grid (issue 50): for each scene with a crop region (the chirp,
the slanted edge, the puppy: study/crops.py), the same pixels of every
camera output at 1:1 and magnified 4:1 by nearest neighbour, a CFA per row
and a demosaicing method per column, the ideal sensor at the top left.

Drawn from ``details/<scene>/<cfa>/<demosaic>/<tag>.crop.png`` (the study
saves them); the sheet is composed at the crops' own pixels (no
resampling but the integer 4x repeat) and embedded losslessly, so a
demosaicing artefact of one pixel stays one pixel (four on the 4:1 panel).
"""

from __future__ import annotations

__all__ = ["crop_sheet", "crop_sheets", "crop_cell", "ZOOM"]

import numpy as np

from .figure import Absent, ReportFigure
from .results import Results

#: The magnification of the second panel (nearest neighbour).
ZOOM = 4
_GAP = 6


def _zoom_px() -> int:
    from ..study.crops import crop_settings

    return int(crop_settings().get("defaults", {}).get("zoom_px", 32))


def crop_cell(crop: np.ndarray, zoom_px: int | None = None) -> np.ndarray:
    """One cell of the grid: the 1:1 crop and, to its right, its central
    ``zoom_px`` x ``zoom_px`` pixels repeated :data:`ZOOM` times each way,
    on a white ground (uint8 RGB)."""
    z = min(int(zoom_px or _zoom_px()), crop.shape[0], crop.shape[1])
    cy, cx = (crop.shape[0] - z) // 2, (crop.shape[1] - z) // 2
    big = np.repeat(np.repeat(crop[cy:cy + z, cx:cx + z, :3], ZOOM, axis=0), ZOOM, axis=1)
    h = max(crop.shape[0], big.shape[0])
    cell = np.full((h, crop.shape[1] + _GAP + big.shape[1], 3), 255, dtype=np.uint8)
    top = (h - crop.shape[0]) // 2
    cell[top:top + crop.shape[0], :crop.shape[1]] = crop[..., :3]
    cell[(h - big.shape[0]) // 2:(h - big.shape[0]) // 2 + big.shape[0], crop.shape[1] + _GAP:] = big
    return cell


def _read(path):
    from .figures_detail import _read_png

    return _read_png(path) if path is not None and path.is_file() else None


def crop_sheet(res: Results, scene: str, lum: float):
    """The crop grid of one scene at luminance ``lum`` (module doc), or an
    :class:`Absent` when the study saved no crops of it."""
    from .sheets import compose_sheet

    title = "Crops at 1:1 and 4:1"
    crops = {}
    for c in res.cfas:
        for d in res.demosaics:
            img = _read(res.detail_path(scene, c, d, lum, ".crop.png"))
            if img is not None:
                crops[(c, d)] = img
    if not crops:
        return Absent("crops", f"{title}: {scene}", f"no crops of {scene!r} at {lum:g} cd/m² under details/ "
                      "(the study saves them for the chirp, the slanted edge and the puppy)")
    z = _zoom_px()
    cells = {k: crop_cell(v, z) for k, v in crops.items()}
    ideal = _read(res.detail_path(scene, None, None, lum, ".crop.png"))
    cfas = [c for c in res.cfas if any((c, d) in cells for d in res.demosaics)]
    dems = [d for d in res.demosaics if any((c, d) in cells for c in cfas)]
    img = compose_sheet(cfas, dems, cells, corner=("ideal sensor", crop_cell(ideal, z)) if ideal is not None
                        else None)
    side = next(iter(crops.values())).shape[:2]
    cap = (f"{scene} at {lum:g} cd/m²: the same {side[1]} × {side[0]} sensor pixels of every camera output (rows: "
           f"CFAs, columns: demosaicing methods) and of the ideal sensor (top left), at 1:1, and the central "
           f"{min(z, side[0])} × {min(z, side[1])} of them magnified {ZOOM}:1 by nearest neighbour (each pixel a "
           f"{ZOOM} × {ZOOM} block; no interpolation, no sharpening). sRGB as the thumbnails, each output against "
           f"its own white; one noise realisation. The page shows the grid at its own pixels (a narrow window "
           f"scrolls it rather than scaling it).")
    return ReportFigure(f"crops-{scene}", "crops", title, cap, None, raster=True, group=scene, image=img,
                        lossless=True)


def crop_sheets(res: Results) -> list:
    """:func:`crop_sheet` of every scene of the study that has crops, at the primary luminance."""
    lum = res.primary_luminance
    if lum is None:
        return []
    out = [crop_sheet(res, s, lum) for s in res.scenes]
    drawn = [f for f in out if isinstance(f, ReportFigure)]
    if drawn:
        return drawn
    from ..study.crops import crop_settings

    named = [s for s in res.scenes if s in crop_settings()]
    if not named:
        return [Absent("crops", title_none(), "the study has none of the scenes with a crop region (chirp, "
                       "slanted-edge, puppy)", not_in_study=True)]
    return [a for a in out if isinstance(a, Absent) and any(s in a.title for s in named)]


def title_none() -> str:
    return "Crops at 1:1 and 4:1"
