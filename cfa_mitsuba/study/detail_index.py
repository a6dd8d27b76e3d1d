"""The evaluations whose details a study kept (``details/``), in the plan's
order: what :mod:`.mtf_table`, :mod:`.patches` and :mod:`.steps` turn into
tidy tables (mtf.csv, patches.csv, steps.csv).

A task keeps the curves of its first realisation only (chain.py, tasks.py;
the folders: details_layout.py), so these
tables describe one capture per (scene, CFA, demosaic, condition), the one
the report draws; metrics.csv holds every realisation's values.
"""

from __future__ import annotations

__all__ = ["DetailEntry", "detail_entries", "write_table", "KEY_COLUMNS"]

import json
from dataclasses import dataclass
from pathlib import Path

from .details_layout import ideal_folder, output_folder
from .task_values import EvaluationTask

#: The columns that name an evaluation in the detail tables.
KEY_COLUMNS = ("scene", "cfa", "demosaic", "condition", "luminance")


@dataclass(frozen=True)
class DetailEntry:
    """One evaluation's details: its scene, CFA label ('ideal' for the ideal
    sensor), demosaic ('none' for the ideal), condition label (the detail
    files' stem, e.g. ``L100`` or ``L100_f8``), luminance (cd/m^2) and the
    JSON (``{metric: result, 'extra': {...}}``)."""

    scene: str
    cfa: str
    demosaic: str
    condition: str
    luminance: float
    data: dict

    def key(self) -> dict:
        return {"scene": self.scene, "cfa": self.cfa, "demosaic": self.demosaic, "condition": self.condition,
                "luminance": self.luminance}


def _read(path: Path) -> dict | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def detail_entries(tasks, details_dir, *, ideal: bool = True):
    """Yield a :class:`DetailEntry` per evaluation of ``tasks`` whose detail
    file exists (the tasks that keep details: the first render seed's),
    camera outputs first within each task's condition, then the ideal
    sensor (once per scene and condition) when ``ideal``."""
    root = Path(details_dir)
    seen_ideal = set()
    for task in tasks:
        t = EvaluationTask.of(task)
        if t.details_dir is None:
            continue
        tag = t.details_tag or f"L{t.condition.luminance:g}"
        lum = float(t.condition.luminance)
        label = t.cfa_label or t.cfa
        for method in t.demosaics:
            data = _read(output_folder(root, t.scene, label, method) / f"{tag}.json")
            if data is not None:
                yield DetailEntry(t.scene, label, method, tag, lum, data)
        if ideal and (t.scene, tag) not in seen_ideal:
            seen_ideal.add((t.scene, tag))
            data = _read(ideal_folder(root, t.scene) / f"{tag}.json")
            if data is not None:
                yield DetailEntry(t.scene, "ideal", "none", tag, lum, data)


def write_table(path: Path, rows: list[dict], columns: list[str]) -> Path | None:
    """Write ``rows`` as a CSV (atomically; 10 significant digits); no rows:
    no file (a stale one is removed)."""
    from ..io import atomic_output

    if not rows:
        path.unlink(missing_ok=True)
        return None
    import pandas as pd

    with atomic_output(path) as tmp:
        pd.DataFrame(rows, columns=columns).to_csv(tmp, index=False, float_format="%.10g")
    return path
