"""``patches.csv``: the colour error of each of the 24 ColorChecker patches,
per CFA, demosaic and condition: which patches go wrong, not only the mean
(the ``delta-e`` metric's details, :func:`cfa_mitsuba.metrics.delta_e`).

One row per (scene, CFA, demosaic, condition, patch): ``patch`` (1..24 in
the chart's reading order, dark skin ... black), ``name``, ``de00``
(CIEDE2000) and ``de76`` (CIE 1976 dE*ab), the ideal sensor's and the
camera's CIELAB (``l_ideal``, ``a_ideal``, ``b_ideal``, ``l_camera``, ...,
against the scene white) and chromaticity (``x_ideal``, ``y_ideal``,
``x_camera``, ``y_camera``), and the ideal's XYZ relative to the white
(``X_ideal`` .. ``Z_ideal``, Y of the white = 100: the swatch colours of
the report's figure).  One realisation per capture, the first
(:mod:`.detail_index`).
"""

from __future__ import annotations

__all__ = ["patch_rows", "write_patches_csv", "PATCH_COLUMNS"]

from pathlib import Path

from .detail_index import KEY_COLUMNS, detail_entries, write_table

PATCH_COLUMNS = [*KEY_COLUMNS, "patch", "name", "de00", "de76", "l_ideal", "a_ideal", "b_ideal", "l_camera",
                 "a_camera", "b_camera", "x_ideal", "y_ideal", "x_camera", "y_camera", "X_ideal", "Y_ideal",
                 "Z_ideal"]


def _names(n: int) -> list[str]:
    from ..spectra import colorchecker

    names = list(colorchecker()[0])
    return names if len(names) == n else [f"patch {i + 1}" for i in range(n)]


def _triples(values, n: int, width: int) -> list:
    if not isinstance(values, list) or len(values) != n:
        return [[None] * width] * n
    return [list(v) if isinstance(v, list) and len(v) == width else [None] * width for v in values]


def patch_rows(entries, white_y: dict | None = None) -> list[dict]:
    """The rows of :data:`PATCH_COLUMNS` for the camera outputs that hold a
    patch-mode ``delta-e`` result.  ``white_y``: {(scene, condition): the
    white's Y on the XYZ scale of the details} (from the ideal's details);
    without it the ideal's XYZ columns stay empty."""
    rows = []
    for e in entries:
        res = e.data.get("delta-e")
        if e.cfa == "ideal" or not isinstance(res, dict) or not isinstance(res.get("de2000"), list):
            continue
        de00 = res["de2000"]
        n = len(de00)
        de76 = res.get("de1976") if isinstance(res.get("de1976"), list) and len(res["de1976"]) == n else [None] * n
        lab_r, lab_t = _triples(res.get("lab_reference"), n, 3), _triples(res.get("lab_test"), n, 3)
        xy_r, xy_t = _triples(res.get("xy_reference"), n, 2), _triples(res.get("xy_test"), n, 2)
        xyz_r = _triples(res.get("xyz_reference"), n, 3)
        wy = (white_y or {}).get((e.scene, e.condition))
        for i, name in enumerate(_names(n)):
            rel = [None if (v is None or not wy) else 100.0 * float(v) / wy for v in xyz_r[i]]
            rows.append({**e.key(), "patch": i + 1, "name": name, "de00": de00[i], "de76": de76[i],
                         "l_ideal": lab_r[i][0], "a_ideal": lab_r[i][1], "b_ideal": lab_r[i][2],
                         "l_camera": lab_t[i][0], "a_camera": lab_t[i][1], "b_camera": lab_t[i][2],
                         "x_ideal": xy_r[i][0], "y_ideal": xy_r[i][1], "x_camera": xy_t[i][0],
                         "y_camera": xy_t[i][1], "X_ideal": rel[0], "Y_ideal": rel[1], "Z_ideal": rel[2]})
    return rows


def write_patches_csv(out_dir: Path, tasks, details_dir) -> Path | None:
    """Write ``out_dir/patches.csv`` from the study's details (no ColorChecker: no file)."""
    entries = list(detail_entries(tasks, details_dir))
    white_y = {}
    for e in entries:
        w = (e.data.get("extra") or {}).get("white_xyz") if e.cfa == "ideal" else None
        if isinstance(w, list) and len(w) == 3 and w[1]:
            white_y[(e.scene, e.condition)] = float(w[1])
    return write_table(Path(out_dir) / "patches.csv", patch_rows(entries, white_y), PATCH_COLUMNS)
