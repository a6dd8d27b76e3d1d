"""Which demosaicing method suits which layout, from measured PSNR
(``cfa_mitsuba/data/demosaic_psnr.toml``: scikit-image photographs,
benchmarks/bench_demosaic.py; docs/isp.md and docs/sensor.md s. 5).

A method *suits* a layout when its mean PSNR is within
:data:`SUITS_WITHIN_DB` of the best method's there; it is *to avoid* when
plain bilinear interpolation beats it (the cross-channel methods on nona
and tetra2, whose 3 x 3 and 4 x 4 same-colour blocks leave no other
colour within a pixel or two).  A block layout read with ``readout =
"remosaic"`` or ``"bin"`` hands the demosaicker a Bayer mosaic, where
every method is measured on ``bayer``.
"""

from __future__ import annotations

__all__ = ["SUITS_WITHIN_DB", "demosaic_psnr", "suitability"]

import functools
from pathlib import Path

#: A method suits a layout within this many dB of the layout's best method.
SUITS_WITHIN_DB = 1.0
_FILE = Path(__file__).resolve().parents[1] / "data" / "demosaic_psnr.toml"


@functools.lru_cache(maxsize=1)
def demosaic_psnr() -> dict:
    """{layout: {method: mean PSNR dB}} as measured."""
    from ..io.guard import read_toml

    data = read_toml(_FILE, "demosaic PSNR table")
    methods = data["methods"]
    return {layout: dict(zip(methods, values)) for layout, values in data["psnr_db"].items()}


def suitability(method: str) -> tuple[list[str], list[tuple[str, float]]]:
    """(layouts the method suits, [(layout, dB it loses to bilinear)] where
    bilinear beats it); empty for a method that was not measured."""
    suits, avoid = [], []
    for layout, by in demosaic_psnr().items():
        if method not in by:
            continue
        if by[method] >= max(by.values()) - SUITS_WITHIN_DB:
            suits.append(layout)
        if method != "bilinear" and by["bilinear"] > by[method]:
            avoid.append((layout, by["bilinear"] - by[method]))
    return suits, avoid
