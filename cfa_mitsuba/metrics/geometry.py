"""From a render sidecar to the plain arguments the metrics take.

The metrics are pure functions of arrays, rectangles, per-column frequency
maps and samples per degree; the render sidecar describes the scene on the
EXR's pixel grid.  A camera image is the EXR's size divided by the
oversampling factor K (DESIGN.md, Sizes), so rectangles shrink by K (rounded
inwards, so they stay inside what they bound), rows are divided by K, and
per-column maps are averaged over each K EXR columns.
"""

from __future__ import annotations

__all__ = ["scene_geometry"]

import math

import numpy as np

from ..errors import CfaMitsubaError, require


def _inward(rect, k):
    y0, x0, y1, x1 = (float(v) for v in rect)
    return (math.ceil(y0 / k), math.ceil(x0 / k), math.floor(y1 / k), math.floor(x1 / k))


def scene_geometry(sidecar: dict, image_shape) -> dict:
    """Metric arguments from ``sidecar`` on the grid of an image of ``image_shape``.

    Parameters
    ----------
    sidecar : the render's sidecar dict (top-level ``width``, ``height``,
        ``fov_deg``, ``oversample``, and ``geometry``).
    image_shape : shape of the image the metric will see: the EXR's size
        (K = 1) or the camera's (EXR / K).

    Returns
    -------
    dict with whichever apply: ``oversample`` (K), ``patches`` (list of
    ``(y0, x0, y1, x1)`` patch interiors, for :func:`delta_e`), ``roi``
    (for :func:`mtf`), ``frequency_cy_per_deg`` and ``frequency_cy_per_px``
    (per image column, for :func:`moire`), ``row``, ``steps`` (gray-bar
    ``(x0, x1)``, for :func:`achromatic`), ``texture_roi``, ``flat_roi``
    and ``dead_leaves`` (the dead-leaves chart's square, flat patch and
    pattern record, for the texture metrics), ``samples_per_degree`` (image
    width / horizontal field of view, for :func:`scielab`).

    Examples
    --------
    >>> side = {"width": 8, "height": 4, "fov_deg": 2.0, "oversample": 2,
    ...         "geometry": {"row": 2, "roi": [1, 1, 4, 7], "frequency_cy_per_deg": list(range(8))}}
    >>> g = scene_geometry(side, (2, 4, 3))
    >>> g["oversample"], g["roi"], g["row"], g["frequency_cy_per_deg"].tolist(), g["samples_per_degree"]
    (2, (1, 1, 2, 3), 1, [0.5, 2.5, 4.5, 6.5], 2.0)
    """
    require(isinstance(sidecar, dict), "the sidecar must be a JSON object")
    geo = sidecar.get("geometry") or {}
    require(isinstance(geo, dict), "the sidecar's 'geometry' must be an object")
    h, w = int(image_shape[0]), int(image_shape[1])
    freq = geo.get("frequency_cy_per_deg")
    exr_w = sidecar.get("width") or (len(freq) if freq else None)
    exr_h = sidecar.get("height")
    if exr_w:
        k = max(1, int(round(float(exr_w) / w)))
        # both sides must be the scene's divided by the one K (within the partial tile at a border): an image
        # of another height would get the patches of a rescaled scene, each on the wrong pixels
        if abs(float(exr_w) / k - w) > 1 or (exr_h and abs(float(exr_h) / k - h) > 1):
            scene = f"{exr_w} x {exr_h}" if exr_h else f"{exr_w} px wide"
            raise CfaMitsubaError(f"the sidecar describes a scene of {scene} pixels; the image is {w} x {h}, which "
                                  "is not that size divided by one whole oversampling factor K")
    else:
        k = int(sidecar.get("oversample") or 1)
    out: dict = {"oversample": k}
    if "patches" in geo:
        out["patches"] = [_inward(p.get("interior_rect") or p["rect"], k) for p in geo["patches"]]
    if "roi" in geo:
        out["roi"] = _inward(geo["roi"], k)
    for key in ("frequency_cy_per_deg", "frequency_cy_per_px"):
        if geo.get(key):
            f = np.asarray(geo[key], dtype=np.float64)
            n = (f.size // k) * k
            binned = f[:n].reshape(-1, k).mean(axis=1)[:w]
            out[key] = binned * (k if key == "frequency_cy_per_px" else 1)  # cycles per *image* pixel
    if "row" in geo:
        out["row"] = min(int(geo["row"]) // k, h - 1)
    for key, name in (("texture_rect", "texture_roi"), ("flat_rect", "flat_roi")):  # the dead-leaves chart
        if key in geo:
            out[name] = _inward(geo[key], k)
    if isinstance(geo.get("dead_leaves"), dict):
        out["dead_leaves"] = geo["dead_leaves"]
    if "steps" in geo:
        out["steps"] = [(math.ceil(float(s["x0"]) / k), math.floor(float(s["x1"]) / k)) for s in geo["steps"]]
    fov = sidecar.get("fov_deg") or geo.get("fov_deg")
    if fov:
        out["samples_per_degree"] = w / float(fov)
    return out
