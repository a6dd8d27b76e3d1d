"""The processing settings a study compares, and the rows of each.

A study's image processor has axes of its own (:mod:`.axes` records whose
``applies_to`` is ``isp``: ``denoise``, ``sharpen``): swept in a
``[[sweep]]``, each value is a camera with other processing, compared with
the study's own (its ``[isp]`` value, the base).  The tables that answer
"with noise reduction" (snr.csv and snr10.csv per setting, decisions.csv's
rows per setting, the report's section) read the rows of one setting at a
time: that axis at that value, every other axis but luminance at the
study's own value, so that a sweep of another axis never mixes in.

The study's own value of an axis is read per (scene, CFA) from the rows a
study marks ``base`` (metrics.csv's column): a base condition carries every
axis at its ``[optics]``, ``[sensor]``, ``[isp]`` value.
"""

from __future__ import annotations

__all__ = ["isp_axes", "other_axes", "at_base_axes", "with_setting", "isp_settings", "setting_label"]

import numpy as np

from .axes import AXES


def isp_axes(columns) -> list[str]:
    """The ISP axes (``applies_to == 'isp'``) among ``columns``, in :data:`.axes.AXES` order."""
    cols = set(columns)
    return [name for name, a in AXES.items() if a.applies_to == "isp" and name in cols]


def other_axes(columns, *but) -> list[str]:
    """The axes among ``columns`` other than luminance and ``but``."""
    cols = set(columns)
    return [name for name in list(AXES)[1:] if name in cols and name not in but]


def _is_base(rows) -> np.ndarray:
    return rows["base"].astype(str).str.lower().isin(("true", "1")).to_numpy()


def _base_values(rows, axes) -> dict:
    """{(scene, cfa): (value of each axis as text)} of the base rows."""
    base = rows[_is_base(rows)]
    out = {}
    for key, g in base.groupby(["scene", "cfa"], sort=False):
        out[key] = tuple(str(g[a].iloc[0]) for a in axes)
    return out


def _matching(rows, axes, want) -> np.ndarray:
    """Rows whose ``axes`` equal ``want[(scene, cfa)]`` (as text)."""
    if not axes:
        return np.ones(len(rows), dtype=bool)
    keys = zip(rows["scene"], rows["cfa"], *(rows[a].astype(str) for a in axes))
    return np.fromiter((want.get((s, c)) == tuple(v) for s, c, *v in keys), dtype=bool, count=len(rows))


def at_base_axes(rows):
    """The rows at the study's own value of every axis but luminance (a
    table without ``base`` or axis columns: all of it)."""
    axes = other_axes(rows.columns)
    if not axes or "base" not in rows.columns or rows.empty:
        return rows
    return rows[_matching(rows, axes, _base_values(rows, axes))]


def with_setting(rows, axis: str, value):
    """The rows where ``axis`` is ``value`` and every other axis but
    luminance is at the study's own value."""
    if axis not in rows.columns or rows.empty:
        return rows.iloc[0:0]
    axes = other_axes(rows.columns, axis)
    if "base" not in rows.columns:
        return rows[rows[axis].astype(str) == str(value)]
    keep = _matching(rows, axes, _base_values(rows, axes)) & (rows[axis].astype(str) == str(value)).to_numpy()
    return rows[keep]


def isp_settings(rows) -> list[tuple[str, str]]:
    """(axis, value) of every value of an ISP axis that some row holds
    other than the study's own, in the order the rows give them."""
    if "base" not in rows.columns or rows.empty:
        return []
    out = []
    for axis in isp_axes(rows.columns):
        own = set(rows.loc[_is_base(rows), axis].astype(str))
        out += [(axis, v) for v in dict.fromkeys(rows[axis].astype(str)) if v not in own]
    return out


def setting_label(axis: str, value) -> str:
    """'denoise nl-means': how tables and decisions name a setting."""
    return f"{axis} {value}"
