"""Edge objectives in both directions (``[[objective]] orientation = "both"``).

The slanted-edge chart is one near-vertical edge: its super-sampled edge
spread function varies along x only, so its MTF50 (and information
capacity) sees horizontal frequencies alone.  A layout with a channel in
full rows (G G / B R) is as sharp as Bayer across that edge and blurrier
along the other axis, which this chart never measures; ISO 12233 measures
resolution on a near-vertical and a near-horizontal edge and reports both.

The near-horizontal edge needs no second chart: the optics (a circular
pupil) and the square pixel aperture are symmetric under the transpose
x <-> y, so a near-horizontal edge seen through a tile T gives, exactly,
the transpose of the image a near-vertical edge gives through T's
transpose, and the same MTF.  So the full chain runs each CFA's transposed
tile as well (same filters), and an objective with ``orientation = "both"``
takes, per CFA, the worse of the two values with that value's interval.  A
tile whose transpose is a translation of itself (Bayer, any layout
symmetric about a diagonal up to a shift) is its own transpose up to where
the image starts and is not run twice.
"""

from __future__ import annotations

__all__ = ["transposed_pattern", "own_transpose", "write_transposed_toml", "transposed_name", "worse"]

import json
from pathlib import Path

import numpy as np

from .cfa_toml import curve_line, write_lines


def transposed_pattern(pattern) -> np.ndarray:
    """The tile transposed (an (h, w) array of filter names -> (w, h))."""
    return np.asarray(pattern).T


def own_transpose(pattern) -> bool:
    """Whether the transposed tile is a cyclic translation of the tile: the
    same CFA up to where the image starts, so the same MTF both ways."""
    p = np.asarray(pattern)
    t = p.T
    if t.shape != p.shape:
        return False
    h, w = p.shape
    return any(np.array_equal(np.roll(p, (dy, dx), axis=(0, 1)), t) for dy in range(h) for dx in range(w))


def transposed_name(name: str) -> str:
    return f"{name}-transposed"


def write_transposed_toml(path: Path, cfa) -> Path:
    """Write ``cfa`` (a built :class:`~cfa_mitsuba.sensor.CFA`) with its tile
    transposed as a CFA TOML: the same filters, each letter's QE curve (filter
    x silicon) written as a table, so a named CFA's measured curves travel too."""
    rows = [" ".join(r) for r in transposed_pattern(cfa.pattern).tolist()]
    text = " / ".join(rows)
    lines = [f"# cfa-mitsuba design: {cfa.name!r} with its tile transposed (the near-horizontal edge's view).",
             f"name = {json.dumps(transposed_name(cfa.name))}",
             f"description = {json.dumps(cfa.name + ' transposed: ' + text)}",
             "tile = [" + ", ".join(json.dumps(r) for r in rows) + "]",
             "", "[spectra]"]
    lines += [curve_line(letter, *cfa.curves[letter], digits=9) for letter in cfa.channels]
    return write_lines(path, lines)


def worse(a: tuple, b: tuple, goal: str) -> tuple:
    """Of two (mean, low, high, n, ...) values, the worse for ``goal``
    ('max': the lower mean); a missing (NaN) one is never the worse."""
    if not np.isfinite(a[0]):
        return b
    if not np.isfinite(b[0]):
        return a
    return (b if b[0] < a[0] else a) if goal == "max" else (b if b[0] > a[0] else a)
