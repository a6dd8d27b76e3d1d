"""The four phases of the Bayer tile as CFAs of the paper's RGB filters, and
colour-demosaicing (the independent oracle for Bayer demosaicing)."""

from __future__ import annotations

import warnings

from cfa_mitsuba.sensor.cfa import builtin_filter_curve, make_cfa

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import colour_demosaicing as cdm  # noqa: F401  (the oracle the demosaic tests import from here)

PHASES = ("RGGB", "BGGR", "GRBG", "GBRG")


def bayer(pattern: str):
    """A Bayer CFA with ``pattern`` (RGGB, BGGR, GRBG, GBRG) read row by row."""
    tile = f"{pattern[0]} {pattern[1]} / {pattern[2]} {pattern[3]}"
    return make_cfa(f"bayer-{pattern.lower()}", tile, {c: builtin_filter_curve(c) for c in "RGB"})
