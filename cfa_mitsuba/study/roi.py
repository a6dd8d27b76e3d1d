"""Regions of interest: demosaic, colour-correct and measure only what the
metrics read.

Each metric record states the region its values read
(:attr:`~cfa_mitsuba.metrics.MetricRecord.reads`: the Macbeth's patch
interiors, the slanted edge's region, the chirp's band around its row, the
gray bar's steps; None for a metric that reads the whole image, as the
natural scenes' do).  Each demosaicing record states how far an output
pixel reads the mosaic (:attr:`~cfa_mitsuba.isp.DemosaicMethod.support`;
POCS: its start's reach plus the low-pass half-length per iteration, and
the whole image while its early stop can end the loop).  The chain captures
the whole sensor (exposure and noise are per image) and prepares the whole
mosaic (white balance, highlight clip, colour fit: isp.prepare), then
demosaics and colour-corrects only windows of it: each region widened by
the method's support, its corners moved outwards onto the CFA tile's grid
(the tile's phase is kept, whatever the tile size), overlapping windows
merged.  The windows' results are pasted into an image the size of the
sensor's, the rest of which holds the ideal image (read by no metric); the
metrics read their regions of it, bit for bit the values of the whole
image (tests/study/test_roi.py compares the two on every scene, demosaic
and several CFA families).

What needs the whole image turns the windows off (:func:`blocked_by`):
mean-matching (its scale is the whole output's interior mean), a global
ISP denoiser (the wavelet methods: their thresholds come from the whole
plane; a local one, nl-means, and the unsharp mask add their declared
reach to the margin), a binned
read-out (its up-sampling), a kept camera output (its details and
thumbnails: the first realisation of each CFA and demosaic), a metric
that reads the whole image.  ``ChainSettings(roi=False)`` or the
environment variable :data:`NO_ROI_ENV` = 1 turns them off everywhere.
"""

from __future__ import annotations

__all__ = ["NO_ROI_ENV", "metric_regions", "windows", "core", "blocked_by", "plan", "process_windows"]

import os
from dataclasses import replace

import numpy as np

#: Set to 1 to demosaic and measure whole images (benchmarks/bench_study.py's "whole" runs).
NO_ROI_ENV = "CFA_MITSUBA_NO_ROI"

#: What one more window costs, in pixels processed: its fixed cost (the
#: processing's calls, checks and meta, made once per window) over the cost
#: of a pixel, measured on the Macbeth chart at the quick study's size in
#: float32: 0.15 ms fixed and 1e-5 ms/px for 'bilinear' (15,000 px), 0.56 ms
#: and 2e-5 ms/px for 'laplacian' (27,000 px).  Two windows are merged where
#: their box costs less than the two, and windows are used only where they
#: cost less than nine tenths of the whole image.
WINDOW_COST_PX = 32768


def metric_regions(metric_names, geometry: dict, shape, options: dict, reference_xyz=None,
                   white_xyz=None) -> list | None:
    """The (y0, x0, y1, x1) rectangles the metrics ``metric_names`` read on
    an image of ``shape`` with the scene ``geometry``, per-metric
    ``options`` and the ideal image; None when one of them reads the whole image."""
    from ..metrics import get_metric

    out = []
    for name in metric_names:
        record = get_metric(name)
        if record.parent is not None:  # a value read from its parent's details: the parent's region
            record = get_metric(record.parent)
        if record.reads is None:
            return None
        rects = record.reads(geometry, tuple(shape[:2]), dict(options.get(record.name, {})), reference_xyz, white_xyz)
        if rects is None:
            return None
        out.extend(tuple(int(v) for v in r) for r in rects)
    return out


def _aligned(rect, margin: int, shape, tile) -> tuple:
    """``rect`` widened by ``margin`` and its corners moved outwards onto
    the tile grid (the end clipped at the image's edge)."""
    (h, w), (th, tw) = shape[:2], tile
    y0, x0, y1, x1 = rect
    y0, x0 = max(0, y0 - margin), max(0, x0 - margin)
    y1, x1 = min(h, y1 + margin), min(w, x1 + margin)
    return ((y0 // th) * th, (x0 // tw) * tw, min(h, -(-y1 // th) * th), min(w, -(-x1 // tw) * tw))


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _area(r) -> int:
    return (r[2] - r[0]) * (r[3] - r[1])


def windows(regions, margin: int, shape, tile) -> list:
    """The windows to demosaic: each region widened by ``margin`` and
    aligned to ``tile``; two windows merged into their bounding box where it
    costs no more than the two (:data:`WINDOW_COST_PX` a window, again until
    no pair merges).
    Empty regions are dropped.  Windows may still overlap (a row across the
    image and a column band): each is processed on its own, and only its
    core, :func:`core`, is kept."""
    out = [_aligned(r, margin, shape, tile) for r in regions if r[2] > r[0] and r[3] > r[1]]
    merged = True
    while merged:
        merged = False
        for i in range(len(out)):
            for j in range(i + 1, len(out)):
                a, b = out[i], out[j]
                box = (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))
                if _area(box) <= _area(a) + _area(b) + WINDOW_COST_PX:
                    out[i] = box
                    out.pop(j)
                    merged = True
                    break
            if merged:
                break
    return sorted(out)


def core(window, margin: int, shape) -> tuple:
    """The part of ``window`` its own processing gets right: ``margin`` in
    from each side that is not the image's edge (every region it was made
    for lies inside)."""
    (h, w), (y0, x0, y1, x1) = shape[:2], window
    return (y0 + margin if y0 > 0 else 0, x0 + margin if x0 > 0 else 0,
            y1 - margin if y1 < h else h, x1 - margin if x1 < w else w)


def blocked_by(settings, isp_options: dict, prepared, *, details: bool) -> str | None:
    """Why windows cannot give the whole image's values here (None: they can)."""
    if not getattr(settings, "roi", True) or os.environ.get(NO_ROI_ENV) == "1":
        return "turned off"
    if details:
        return "the output's details and thumbnails need the whole image"
    if settings.mean_match:
        return "mean-matching scales by the whole output's interior mean"
    if isp_margin(isp_options, prepared.cfa.pattern.shape) is None:
        return "a global ISP denoiser or sharpener (its thresholds come from the whole image)"
    if prepared.readout.get("mode") == "bin":
        return "a binned read-out is up-sampled whole"
    return None


def isp_margin(isp_options: dict, tile) -> int | None:
    """The margin (px) the ISP's denoiser and sharpener add to the
    demosaic's (their records' support, isp/denoise and isp/sharpen: a
    raw-domain denoiser's plane pixel is a tile period); None when either
    reads the whole image (the wavelet methods)."""
    from ..isp.denoise import denoise_support_px
    from ..isp.sharpen import sharpen_support_px

    d = denoise_support_px(isp_options.get("denoise", "none"), isp_options.get("denoise_options"), tile)
    s = sharpen_support_px(isp_options.get("sharpen", "none"), isp_options.get("sharpen_options"))
    return None if d is None or s is None else int(d) + int(s)


def method_margin(prepared, method: str, options: dict) -> int | None:
    """The margin (px) a window needs for ``method`` with ``options``: its
    declared support; None when it reads the whole mosaic."""
    from ..isp.demosaic import get_demosaic_record

    record = get_demosaic_record(method)
    if record.support is None:
        return None
    opts = {k: v for k, v in options.items() if k not in ("demosaic_precision", "gamut_check", "denoise",
                                                          "denoise_options", "sharpen", "sharpen_options")}
    opts.setdefault("luminance_weights", prepared.luminance_weights)
    return record.support(prepared.cfa, opts)


def process_windows(chain, prepared, method: str, cond, rects: list, fill: np.ndarray):
    """:meth:`~.chain.CameraChain.process` of each window ``rects`` (from
    :func:`plan`: ``(margin, windows)``) of ``prepared``'s mosaic, each
    window's core pasted into a copy of ``fill`` (the ideal's XYZ, the
    sensor's size): a processed image whose cores hold what the whole
    image's processing holds there."""
    from ..isp.demosaic import PRECISIONS, get_demosaic_record

    record = get_demosaic_record(method)
    extra = {}
    if record.window_options is not None:  # the whole mosaic's statistics, as the method sees the mosaic
        precision = chain.settings.isp_options(method, cond)["demosaic_precision"]
        whole = np.asarray(prepared.balanced, dtype=np.float64)
        dtype = PRECISIONS[precision]
        extra = record.window_options(whole if dtype is np.float64 else whole.astype(dtype))
    margin, rects = rects
    xyz, out = np.array(fill, dtype=np.float64, copy=True), None
    for y0, x0, y1, x1 in rects:
        part = replace(prepared, balanced=np.ascontiguousarray(prepared.balanced[y0:y1, x0:x1]))
        part.__dict__["luminance_weights"] = prepared.luminance_weights  # the capture's, not made again per window
        out = chain.process(part, method, cond, **extra)
        c0, c1, c2, c3 = core((y0, x0, y1, x1), margin, xyz.shape)
        xyz[c0:c2, c1:c3] = out.xyz[c0 - y0:c2 - y0, c1 - x0:c3 - x0]
    out.xyz = xyz
    out.__dict__.pop("_srgb", None)
    out.meta = {**out.meta, "roi": {"margin": margin, "windows": [list(r) for r in rects]}}
    return out


def plan(chain, prepared, method: str, cond, ideal, metric_names, *, details: bool) -> list | None:
    """(margin, windows): the windows of ``prepared``'s mosaic that
    ``method`` must process for ``metric_names`` to read their regions
    exactly, and its support margin; None: the whole image (something needs
    it, :func:`blocked_by`, or the windows would cover nine tenths of it)."""
    from .. import metrics as m

    isp_options = chain.settings.isp_options(method, cond)
    if blocked_by(chain.settings, isp_options, prepared, details=details) is not None:
        return None
    shape = ideal.xyz.shape
    options = chain.settings.metric_options_for(cond)
    for name, summary in m.summary_options().items():  # as CameraChain.measure passes them without details
        options[name] = {**summary, **options.get(name, {})}
    regions = metric_regions(metric_names, m.scene_geometry(ideal.meta, shape), shape, options, ideal.xyz,
                             ideal.white_xyz)
    if not regions:
        return None
    margin = method_margin(prepared, method, isp_options)
    if margin is None:
        return None
    margin += isp_margin(isp_options, prepared.cfa.pattern.shape)  # local denoiser and sharpener: their reach
    rects = windows(regions, margin, shape, prepared.cfa.pattern.shape)
    if sum(_area(r) + WINDOW_COST_PX for r in rects) >= 0.9 * shape[0] * shape[1]:
        return None  # no gain worth the windows' cost
    return margin, rects
