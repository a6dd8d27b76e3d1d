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

Each metric module holds its function and, beside it, its record
(:class:`MetricRecord`: scenes, inputs, unit, direction, scoring, default
range, label); :mod:`.registry` collects the records and :func:`evaluate`
computes any metric by name.
Conventions and their sources: docs/metrics.md.
"""

from __future__ import annotations

from . import colourspace  # noqa: F401
from ._result import MetricResult
from .achromatic import achromatic
from .delta_e import delta_e
from .geometry import scene_geometry
from .haarpsi import haarpsi
from .mdsi import mdsi
from .moire import moire
from .mtf import find_edge_roi, mtf
from .preprocess import mean_match, reference_interior_mean
from .inputs import MetricInputs
from .record import NATURAL, MetricRecord
from .registry import (METRICS, evaluate, evaluate_many, get_metric, list_metrics, metric_names, metric_parameters,
                       metrics_for_scene, record_json, register_metric, result_rows, scored_metrics, study_options,
                       summary_options, unregister_metric)
from .scielab import scielab, scielab_filters
from .ssim import ssim

__all__ = [
    "MetricResult", "MetricRecord", "MetricInputs", "register_metric", "unregister_metric", "metric_parameters", "METRICS", "NATURAL", "get_metric",
    "list_metrics", "metric_names", "scored_metrics", "metrics_for_scene", "record_json", "evaluate",
    "evaluate_many", "result_rows", "study_options", "summary_options",
    "delta_e", "scielab", "ssim", "mtf", "moire", "achromatic", "mdsi", "haarpsi",
    "mean_match", "reference_interior_mean", "find_edge_roi", "scielab_filters", "scene_geometry", "colourspace",
]

# Every registered metric's function is reachable as cm.metrics.<function>,
# a module added later too (importing a submodule binds the package attribute
# to the module; the function is what users call).
for _record in METRICS.values():
    if _record.function is not None:
        globals()[_record.function.__name__] = _record.function
del _record
