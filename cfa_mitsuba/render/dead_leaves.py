"""The ``dead-leaves`` chart: random occluding discs, the texture target of
Cao, Guichard and Hornung (2010), beside a flat patch for the noise.

Discs fall on the chart's square one behind another (the first drawn lies
in front), each of radius r drawn from the scale-invariant law p(r) ∝ r^-3
between :data:`RADIUS_MIN_SENSOR_PX` sensor pixels and
:data:`RADIUS_MAX_FRACTION` of the square's side (the law whose power
spectrum follows a power law close to that of natural images, Cao et al.
2010 s. 2; Lee, Mumford and Huang 2001), centre uniform over the square
widened by the largest radius (discs cut by its border count), and
reflectance drawn uniformly from :data:`PALETTE`: three measured neutral
patches of colour-science's 'ColorChecker N Ohta' set (neutral 8, 6.5 and
5: Y about 0.58 to 0.20, a contrast of about 2.9:1, below the slanted
edge's 4:1, low enough that a denoiser takes texture the edge keeps; with
neutral 3.5 added, 6.3:1, the edge and the texture lost alike).  Discs are drawn until
every cell of the square is covered.  The surround and the flat patch on
the right are 'neutral 6.5', the grey nearest the texture's mean
reflectance, so that the flat patch's noise is the texture's.

Exactness, as the other charts (:mod:`.charts`): the pattern is defined on
cells of 1/t EXR pixel (t = sqrt(spp), at most :data:`MAX_CELLS_PER_PX`),
each cell the reflectance of the front disc that covers its centre.
Mitsuba renders it as the achromatic charts are rendered, once per palette
reflectance (a layered chart, :class:`~.types.Built` ``layers``): a bitmap
of the share of that reflectance in each cell (1 or 0) on a rectangle over
the texture square (and the surround, 1 for the flat patch's reflectance),
looked up nearest-texel, under the unjittered ``stratified`` sampler (s x s
samples per pixel at the strata centres, one per cell) with a ``box``
filter, so each EXR pixel is the exact mean of its t x t cells: the box
integral of the cell pattern over the pixel.  The engine adds the layers,
each times its radiance, D65 x the reflectance as band means of the product
(as the macbeth patches).  :func:`exact_radiance` computes the same
integral in numpy, independently of Mitsuba, for the tests.

The sidecar's ``geometry`` holds the statistics (radius limits, law,
palette and its reflectances, contrast, seed, disc count), the texture
square and the flat patch (``texture_rect``, ``flat_rect``, EXR pixels,
half-open [y0, x0, y1, x1]) and ``dead_leaves`` (what
:func:`chart_luminance` needs to rebuild the ideal pattern: the texture
metrics compare the camera with it).

References
----------
F. Cao, F. Guichard, H. Hornung, "Dead leaves model for measuring texture
quality on a digital camera", Proc. SPIE 7537, Digital Photography VI
(2010) 75370E.  A. B. Lee, D. Mumford, J. Huang, "Occlusion models for
natural images", Int. J. Comput. Vis. 41 (2001) 35-59.
"""

from __future__ import annotations

__all__ = ["PALETTE", "FLAT_PATCH", "RADIUS_MIN_SENSOR_PX", "RADIUS_MAX_FRACTION", "DEAD_LEAVES_SEED", "SCENE",
           "layout", "disc_labels", "chart_luminance", "exact_radiance", "camera_example"]

import functools
import math

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError
from .charts import CHART_DISTANCE_M, _Frame
from .light import d65_white_radiance
from .types import Built, RenderConfig, Scene

#: The discs' reflectances: measured neutral patches of 'ColorChecker N Ohta'.
PALETTE = ("neutral 8 (.23 D)", "neutral 6.5 (.44 D)", "neutral 5 (.70 D)")
#: The flat patch and the surround.
FLAT_PATCH = "neutral 6.5 (.44 D)"
#: Smallest disc radius, in sensor pixels: below the pixel, so the pattern has detail up to Nyquist and past it.
RADIUS_MIN_SENSOR_PX = 0.5
#: Largest disc radius, as a fraction of the texture square's side.
RADIUS_MAX_FRACTION = 1.0 / 8.0
#: The chart's own seed (the pattern is part of the chart, not of a render's noise).
DEAD_LEAVES_SEED = 1858
#: Cells per EXR pixel along each axis, at most.
MAX_CELLS_PER_PX = 4
#: Discs drawn at most (a safety bound; a default chart needs about 10^5).
_MAX_DISCS = 20_000_000


def layout(width: int, height: int, oversample: int) -> dict:
    """The texture square and the flat patch of a ``height`` x ``width``
    EXR image with K = ``oversample`` (EXR pixels, half-open [y0, x0, y1,
    x1]): a margin m = 4 K on every side, the square of side H - 2m on the
    left, a gap of 8 K, the flat patch to the right margin (at least 16
    sensor pixels wide)."""
    k = int(oversample)
    m, gap = 4 * k, 8 * k
    side = height - 2 * m
    flat_x0 = m + side + gap
    if side < 16 * k or width - m - flat_x0 < 16 * k:
        raise CfaMitsubaError(
            f"dead-leaves needs room for a square of at least 16 sensor pixels and a flat patch of 16 beside it: "
            f"at oversample {k} that is at least {2 * m + 16 * k} px high and {m + 16 * k + gap + 16 * k + m} px "
            f"wide with the square as high as the image allows (got {width} x {height}; width >= height + "
            f"{gap + 16 * k} px)")
    return {"texture_rect": [m, m, m + side, m + side], "flat_rect": [m, flat_x0, height - m, width - m]}


@functools.lru_cache(maxsize=2)
def disc_labels(side_px: int, cells_per_px: int, r_min_px: float, r_max_px: float, n_colours: int,
                seed: int) -> tuple[np.ndarray, int]:
    """(the palette index of every cell of the square, (side t, side t)
    int8 read-only; the number of discs drawn).  Coordinates in EXR pixels
    from the square's top-left corner; radii from p(r) ∝ r^-3 on [r_min,
    r_max] by its inverse CDF r = (r_min^-2 - u (r_min^-2 - r_max^-2))^-1/2."""
    from ._dead_leaves_kernel import paint_discs  # numba: imported when a chart is drawn, not by every command

    t = int(cells_per_px)
    labels = np.full((side_px * t, side_px * t), -1, dtype=np.int8)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed)))
    bare, used = labels.size, 0
    a, b = r_min_px**-2, r_max_px**-2
    batch = 50_000
    while bare > 0:
        if used >= _MAX_DISCS:
            raise CfaMitsubaError(f"dead-leaves: {used} discs left {bare} cells bare (radii too small for the chart)")
        u = rng.random((4, batch))
        cx = -r_max_px + u[0] * (side_px + 2 * r_max_px)
        cy = -r_max_px + u[1] * (side_px + 2 * r_max_px)
        r = (a - u[2] * (a - b)) ** -0.5
        colour = np.minimum((u[3] * n_colours).astype(np.int8), n_colours - 1).astype(np.int8)
        bare, n = paint_discs(labels, cx, cy, r, colour, 1.0 / t, bare)
        used += int(n)
    labels.flags.writeable = False
    return labels, used


def _statistics(config_w: int, config_h: int, k: int, t: int, seed: int = DEAD_LEAVES_SEED) -> dict:
    rects = layout(config_w, config_h, k)
    y0, x0, y1, x1 = rects["texture_rect"]
    side = y1 - y0
    return {"side_px": side, "cells_per_px": t, "r_min_px": RADIUS_MIN_SENSOR_PX * k,
            "r_max_px": RADIUS_MAX_FRACTION * side, "palette": list(PALETTE), "flat_patch": FLAT_PATCH,
            "seed": int(seed), "texture_rect": rects["texture_rect"], "flat_rect": rects["flat_rect"],
            "width": config_w, "height": config_h, "oversample": k}


def _palette_reflectance(names, wl: np.ndarray) -> np.ndarray:
    all_names, refl = spectra.colorchecker(wl)
    return np.stack([refl[all_names.index(n)] for n in names])


def _luminance_factor(names) -> np.ndarray:
    """Y / Yw of each named patch under D65 (CIE 1931, the 400-700 nm grid)."""
    wl = spectra.DEFAULT_WAVELENGTHS if hasattr(spectra, "DEFAULT_WAVELENGTHS") else np.arange(400.0, 701.0, 10.0)
    wl = np.asarray(wl, dtype=np.float64)
    white = d65_white_radiance(wl)
    y_w = float(spectra.luminance_cd_m2(white, wl))
    return np.array([float(spectra.luminance_cd_m2(white * rho, wl)) / y_w for rho in _palette_reflectance(names, wl)])


def _fractions(labels: np.ndarray, t: int, n: int) -> np.ndarray:
    """(side, side, n): each EXR pixel's share of each palette entry (its t x t cells)."""
    s = labels.shape[0] // t
    blocks = labels.reshape(s, t, s, t)
    return np.stack([(blocks == c).mean(axis=(1, 3)) for c in range(n)], axis=-1)


def chart_luminance(record: dict) -> np.ndarray:
    """The ideal chart's luminance factor Y / Yw over the texture square,
    on the EXR pixel grid ((side, side), the exact box mean of the cell
    pattern): what the texture metrics compare a camera with.  ``record``
    is the sidecar's ``geometry['dead_leaves']``."""
    try:
        labels, _ = disc_labels(int(record["side_px"]), int(record["cells_per_px"]), float(record["r_min_px"]),
                                float(record["r_max_px"]), len(record["palette"]), int(record["seed"]))
        y = _luminance_factor(tuple(record["palette"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise CfaMitsubaError(f"the sidecar's dead_leaves record is incomplete or invalid ({exc})") from None
    return _fractions(labels, int(record["cells_per_px"]), y.size) @ y


def _radiances(wl: np.ndarray) -> dict:
    """{reflectance name: (B,) radiance} of the palette and the flat patch:
    band means of D65 x the reflectance (the product of the interpolated
    tables), at the canonical scale of the white."""
    white = d65_white_radiance(wl)
    scale = white / spectra.illuminant("D65", wl)
    names, tables = spectra.colorchecker_tables()
    d65_table = spectra.illuminant_table("D65")
    return {n: scale * spectra.band_average_product([d65_table, tables[names.index(n)]], wl)
            for n in dict.fromkeys((*PALETTE, FLAT_PATCH))}


def _cells_per_px(spp: int) -> int:
    """t: the largest divisor of s = sqrt(spp) up to :data:`MAX_CELLS_PER_PX` (one stratum per cell)."""
    s = max(1, math.isqrt(spp))
    return max(d for d in range(1, min(s, MAX_CELLS_PER_PX) + 1) if s % d == 0)


def _layers(config: RenderConfig, stats: dict, labels: np.ndarray, radiance: dict) -> tuple:
    """One achromatic layer per reflectance (module doc): (Mitsuba objects, radiance)."""
    import mitsuba as mi

    frame = _Frame(config)
    out = []
    for name, spectrum in radiance.items():
        objects = {}
        if name == FLAT_PATCH:  # the surround and the flat patch
            objects["surround"] = frame.background({"type": "uniform", "value": 1.0})
        if name in PALETTE:
            share = (labels == PALETTE.index(name)).astype(np.float32)
            # Row 0 of a bitmap lands at the bottom of a rectangle seen from +z.
            texture = {"type": "bitmap", "bitmap": mi.Bitmap(np.ascontiguousarray(np.flipud(share))[..., None]),
                       "raw": True, "filter_type": "nearest", "wrap_mode": "clamp"}
            del share
            # A hair in front of the surround so that the square wins every ray (as the macbeth patches).
            objects["square"] = {"type": "rectangle",
                                 "to_world": frame.rect(*stats["texture_rect"], z=1e-5 * frame.distance),
                                 "emitter": {"type": "area", "radiance": texture}}
        out.append((objects, spectrum))
    return tuple(out)


def exact_radiance(width: int, height: int, oversample: int, spp: int = 16, wl=None) -> np.ndarray:
    """The exact box integral over each EXR pixel of the chart's spectral
    radiance at the canonical scale, (height, width, B), in numpy: each
    pixel the mean of its cells' band radiances.  What the Mitsuba render
    must equal (up to float32); independent of Mitsuba."""
    wl = np.asarray(spectra.DEFAULT_WAVELENGTHS if wl is None else wl, dtype=np.float64)
    t = _cells_per_px(spp)
    stats = _statistics(width, height, int(oversample), t)
    labels, _ = disc_labels(stats["side_px"], t, stats["r_min_px"], stats["r_max_px"], len(PALETTE), stats["seed"])
    radiance = _radiances(wl)
    data = np.broadcast_to(radiance[FLAT_PATCH], (height, width, wl.size)).copy()
    y0, x0, y1, x1 = stats["texture_rect"]
    data[y0:y1, x0:x1] = _fractions(labels, t, len(PALETTE)) @ np.stack([radiance[n] for n in PALETTE])
    return data


def _build(scene: Scene, config: RenderConfig) -> Built:
    wl = config.wl
    k = int(config.oversample)
    t = _cells_per_px(config.spp)
    stats = _statistics(config.width, config.height, k, t)
    labels, n_discs = disc_labels(stats["side_px"], t, stats["r_min_px"], stats["r_max_px"], len(PALETTE),
                                  stats["seed"])
    white = d65_white_radiance(wl)
    y = _luminance_factor(PALETTE)
    meta = {"scene_distance_m": CHART_DISTANCE_M, "illuminant": "D65", "geometry": {
        "reflectance_set": "ColorChecker N Ohta", "palette": list(PALETTE),
        "palette_luminance_factor": y.tolist(), "flat_patch": FLAT_PATCH,
        "flat_luminance_factor": float(_luminance_factor((FLAT_PATCH,))[0]),
        "contrast": float((y.max() - y.min()) / (y.max() + y.min())), "contrast_ratio": float(y.max() / y.min()),
        "radius_law": "p(r) proportional to r^-3", "radius_px": [stats["r_min_px"], stats["r_max_px"]],
        "radius_sensor_px": [stats["r_min_px"] / k, stats["r_max_px"] / k], "seed": stats["seed"],
        "discs": int(n_discs), "cells_per_px": t,
        "texture_rect": stats["texture_rect"], "flat_rect": stats["flat_rect"], "dead_leaves": stats}}
    return Built(meta=meta, sensor=_Frame(config).sensor(config.fov_deg), white_radiance=white,
                 layers=_layers(config, stats, labels, _radiances(wl)))


#: The chart, registered by :mod:`.builtins`: 1280 x 1024 EXR pixels at K = 4
#: (a 320 x 256 sensor image, the texture square 248 sensor pixels across);
#: the field of view gives 2.2 um pixels the slanted edge's angular pitch.
SCENE = Scene(
    name="dead-leaves",
    description="dead-leaves texture chart: occluding discs, radii p(r) ~ r^-3 from 0.5 sensor px to 1/8 of the "
                "square, three measured neutral ColorChecker reflectances (2.9:1), and a flat grey patch; FOV 3.56 deg; "
                "4x the sensor's sampling",
    width=1280, height=1024, fov_deg=2.0 * 1280 / 720, spp=16, oversample=4, kind="dead-leaves",
    builder=_build, jitter=False,
)


def camera_example(width: int = 448, height: int = 320, oversample: int = 4) -> tuple[np.ndarray, dict]:
    """(the chart's luminance factor as a perfect camera sees it, the
    texture metrics' geometry keywords): each camera pixel the mean of its K
    x K render pixels (a box pixel, no optics, no noise), for the metrics'
    examples and tests."""
    stats = _statistics(width, height, oversample, MAX_CELLS_PER_PX)
    lum = np.full((height, width), float(_luminance_factor((FLAT_PATCH,))[0]))
    y0, x0, y1, x1 = stats["texture_rect"]
    lum[y0:y1, x0:x1] = chart_luminance(stats)
    k = int(oversample)
    cam = lum.reshape(height // k, k, width // k, k).mean(axis=(1, 3))

    def inward(r):
        return (math.ceil(r[0] / k), math.ceil(r[1] / k), r[2] // k, r[3] // k)

    return cam, {"texture_roi": inward(stats["texture_rect"]), "flat_roi": inward(stats["flat_rect"]),
                 "dead_leaves": stats}
