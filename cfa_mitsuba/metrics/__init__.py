"""metrics/: the eight image-quality metrics of Bae 2020, pure functions on arrays.

Each is named after its command-line name and looks like scikit-image's
``skimage.metrics``: arrays in, a number out, explicit keywords for whatever
changes the result.  Single-number indices (:func:`ssim`, :func:`mdsi`,
:func:`haarpsi`) return a ``float``; the others return a
:class:`MetricResult`, a ``float`` that carries ``.unit`` and ``.details``
(maps, per-patch values, curves, flags).

=============  ======================  ============  =====================
name           function                scene         headline (better)
=============  ======================  ============  =====================
delta-e        :func:`delta_e`         macbeth       mean CIEDE2000 (lower)
scielab        :func:`scielab`         puppy         mean S-CIELAB dE (lower)
ssim           :func:`ssim`            puppy         SSIM (higher)
mtf            :func:`mtf`             slanted-edge  MTF50 (higher)
moire          :func:`moire`           chirp         MSP, cy/deg (higher)
achromatic     :func:`achromatic`      gray-bar      mean abs dL* (lower)
mdsi           :func:`mdsi`            puppy         MDSI (lower)
haarpsi        :func:`haarpsi`         puppy         HaarPSI (higher)
=============  ======================  ============  =====================

Conventions and their sources: docs/metrics.md.
"""

from __future__ import annotations

from dataclasses import dataclass

from . import colour  # noqa: F401
from ._result import MetricResult
from .achromatic import achromatic
from .delta_e import delta_e
from .geometry import scene_geometry
from .haarpsi import haarpsi
from .mdsi import mdsi
from .moire import moire
from .mtf import find_edge_roi, mtf
from .preprocess import mean_match
from .scielab import scielab, scielab_filters
from .ssim import ssim

__all__ = [
    "MetricResult", "MetricInfo", "METRICS", "get_metric", "list_metrics",
    "delta_e", "scielab", "ssim", "mtf", "moire", "achromatic", "mdsi", "haarpsi",
    "mean_match", "find_edge_roi", "scielab_filters", "scene_geometry", "colour",
]


@dataclass(frozen=True)
class MetricInfo:
    """Registry entry: what a metric measures and how to read its number."""

    name: str
    function: object
    scene: str
    description: str
    unit: str
    higher_is_better: bool
    inputs: str  # 'xyz' (absolute XYZ + white), 'srgb8' (code values), 'linear' (one image)


METRICS: dict[str, MetricInfo] = {m.name: m for m in (
    MetricInfo("delta-e", delta_e, "macbeth", "colour error: mean CIEDE2000 (and dE*ab 1976) over the 24 patches",
               "dE00", False, "xyz"),
    MetricInfo("scielab", scielab, "puppy", "S-CIELAB colour reproduction error (Zhang-Wandell), mean dE00",
               "dE00", False, "xyz"),
    MetricInfo("ssim", ssim, "puppy", "structural similarity (Wang 2004) of the 8-bit sRGB luma", "", True, "srgb8"),
    MetricInfo("mtf", mtf, "slanted-edge", "ISO 12233 e-SFR: luminance MTF50, MTF at Nyquist, percent alias",
               "cy/mm", True, "linear"),
    MetricInfo("moire", moire, "chirp", "moire starting point: first frequency where block-mean C*ab > 25",
               "cy/deg", True, "xyz"),
    MetricInfo("achromatic", achromatic, "gray-bar", "achromatic reproduction error: mean |dL*| along the central row",
               "L*", False, "xyz"),
    MetricInfo("mdsi", mdsi, "puppy", "mean deviation similarity index (Nafchi 2016), 0 = identical", "", False, "srgb8"),
    MetricInfo("haarpsi", haarpsi, "puppy", "Haar wavelet perceptual similarity (Reisenhofer 2018), 1 = identical",
               "", True, "srgb8"),
)}


def get_metric(name: str) -> MetricInfo:
    """The registry entry of a metric by its CLI name (``'delta-e'``, ...)."""
    from ..errors import CfaMitsubaError

    try:
        return METRICS[name]
    except KeyError:
        raise CfaMitsubaError(f"unknown metric {name!r} (expected one of: {', '.join(METRICS)})") from None


def list_metrics() -> list[tuple[str, str]]:
    """(name, one-line description) of every metric, for ``cfa-mitsuba list metrics``."""
    return [(m.name, f"[{m.scene}] {m.description}") for m in METRICS.values()]
