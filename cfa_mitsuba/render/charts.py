"""The flat test charts: ``macbeth``, ``slanted-edge``, ``chirp``, ``gray-bar``.

Every chart is a plane facing a pinhole (perspective) camera at
:data:`CHART_DISTANCE_M` (ISETCam's default scene distance) that fills the
horizontal field of view, seen directly as an emitter: the chart's radiance
is D65 x reflectance, so there is no lighting to sample and no noise from it
(DESIGN.md: leave out what a scene does not need).  Because the plane is
parallel to the image, positions on it map linearly to pixels, and the
charts are laid out in EXR pixel coordinates: column x and row y (0-based,
y down), pixel (y, x) covering [y, y+1) x [x, x+1).

- ``macbeth``: the 24 'ColorChecker N Ohta' patches (colour-science) in the
  standard 4 x 6 reading order, square patches on a dark (2 %) surround,
  every patch edge on a pixel boundary; rendered band by band.
- ``slanted-edge``, ``chirp``, ``gray-bar``: achromatic, so Mitsuba renders
  one spatial channel (an emitter with a flat spectrum whose value is the
  reflectance) and the engine multiplies by the white radiance (D65).  The
  pattern is a bitmap of its exact averages over sub-pixel cells (the
  edge: 1/4 pixel squares, closed-form; the chirp and the steps: one row of
  1/s-pixel columns, the chirp through the Fresnel integral), looked up
  nearest-texel.  The ``stratified`` sampler puts s x s samples in each
  pixel (spp = s^2), unjittered, at the strata centres, and the cells are
  chosen so that every stratum lies inside one cell; with the ``box``
  reconstruction filter each pixel is then the mean of its cells, i.e. the
  exact box integral of the pattern over the pixel, whatever the frequency
  (the chirp above the sensor's Nyquist included), up to float32 rounding.
  (Jittered samples would land within float rounding of a cell boundary now
  and then and read the neighbouring cell: measured 1 % errors at single
  pixels of the chirp.)  :func:`exact_reflectance` computes
  that integral independently of Mitsuba, for the tests.
"""

from __future__ import annotations

__all__ = [
    "CHART_DISTANCE_M",
    "SURROUND_REFLECTANCE",
    "EDGE_ANGLE_DEG",
    "EDGE_REFLECTANCES",
    "CHIRP_REFLECTANCES",
    "GRAY_L_STAR",
    "macbeth_layout",
    "gray_steps",
    "chirp_rate",
    "exact_reflectance",
]

import math

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError
from .light import band_spectrum, d65_white_radiance
from .types import Built, RenderConfig, Scene

#: Distance (m) from the camera to every chart: ISETCam's sceneInitGeometry default.
CHART_DISTANCE_M = 1.2
#: Reflectance of the macbeth chart's surround (a matte black card), flat.
SURROUND_REFLECTANCE = 0.02
#: Slanted edge: angle from vertical (degrees; ISO 12233 recommends about 5).
EDGE_ANGLE_DEG = 5.0
#: Slanted edge: (dark, bright) reflectance, the 4:1 contrast of ISO 12233:2017.
EDGE_REFLECTANCES = (0.15, 0.60)
#: Chirp: (black, white) reflectance of the sinusoid.
CHIRP_REFLECTANCES = (0.01, 0.90)
#: Gray bar: CIE L* of the steps, white to near black in equal L* steps
#: (ISETCam's 'lstar' scene has the same values, dark to light).
GRAY_L_STAR = tuple(float(v) for v in range(95, 0, -10))
#: Margin (EXR pixels) by which chart planes overhang the frame, so that no
#: camera ray at the image border misses them through rounding.
_MARGIN_PX = 2


# ----------------------------------------------------------------- geometry

class _Frame:
    """The chart plane z = 0 seen from (0, 0, distance): pixel <-> metres."""

    def __init__(self, config: RenderConfig, distance_m: float = CHART_DISTANCE_M):
        self.w, self.h = config.width, config.height
        self.distance = distance_m
        self.half_width = distance_m * math.tan(math.radians(config.fov_deg) / 2)
        self.pitch = 2 * self.half_width / self.w  # metres per EXR pixel on the chart

    def rect(self, y0, x0, y1, x1, z=0.0):
        """Transform of Mitsuba's [-1, 1]^2 rectangle onto pixel rectangle
        [y0, y1) x [x0, x1) (continuous pixel coordinates)."""
        import mitsuba as mi

        cx = (0.5 * (x0 + x1) - self.w / 2) * self.pitch
        cy = (self.h / 2 - 0.5 * (y0 + y1)) * self.pitch  # rows grow downwards, y up
        return mi.ScalarTransform4f().translate([cx, cy, z]).scale(
            [0.5 * (x1 - x0) * self.pitch, 0.5 * (y1 - y0) * self.pitch, 1.0]
        )

    def sensor(self, fov_deg: float) -> dict:
        import mitsuba as mi

        return {
            "type": "perspective",
            "fov": float(fov_deg),
            "fov_axis": "x",
            "near_clip": 0.01 * self.distance,
            "far_clip": 10.0 * self.distance,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, self.distance], target=[0, 0, 0], up=[0, 1, 0]),
        }

    def background(self, radiance: dict, z=0.0) -> dict:
        m = _MARGIN_PX
        return {"type": "rectangle", "to_world": self.rect(-m, -m, self.h + m, self.w + m, z),
                "emitter": {"type": "area", "radiance": radiance}}


def _texels_per_stratum_grid(spp: int, cap: int) -> int:
    """Texels per pixel (per axis) for a pattern bitmap rendered with the
    ``stratified`` sampler at ``spp`` = s^2 samples: the largest divisor of s
    not above ``cap``, so that every stratum lies inside one texel and each
    pixel's mean over its samples is exactly the mean of its texels."""
    s = max(1, math.isqrt(spp))
    return max(d for d in range(1, min(s, cap) + 1) if s % d == 0)


def _common_meta() -> dict:
    return {"scene_distance_m": CHART_DISTANCE_M, "illuminant": "D65"}


# ------------------------------------------------------------------ macbeth

def macbeth_layout(width: int, height: int) -> list[dict]:
    """Patch rectangles for a ``height`` x ``width`` macbeth render.

    Square patches of side p with gaps g = max(1, round(p / 5)) (the real
    chart's 40 mm patches and 8 mm gaps have about that ratio), the 4 x 6
    block centred with at least about one gap of surround on every side:
    p = floor(min(W / 7.4, H / 5)).  Returns 24 dicts in reading order with
    ``row``, ``col``, ``rect`` and ``interior_rect`` ([y0, x0, y1, x1],
    half-open, EXR pixels); the interior is the patch inset by
    max(1, round(0.15 p)) pixels, clear of the blur the optics add at edges.
    """
    p = int(min(width / 7.4, height / 5.0))
    if p < 4:
        raise CfaMitsubaError(f"macbeth needs at least 30 x 20 pixels (got {width} x {height})")
    g = max(1, round(p / 5))
    chart_w, chart_h = 6 * p + 5 * g, 4 * p + 3 * g
    x_start, y_start = (width - chart_w) // 2, (height - chart_h) // 2
    inset = max(1, round(0.15 * p))
    out = []
    for i in range(24):
        r, c = divmod(i, 6)
        y0, x0 = y_start + r * (p + g), x_start + c * (p + g)
        out.append({
            "row": r, "col": c,
            "rect": [y0, x0, y0 + p, x0 + p],
            "interior_rect": [y0 + inset, x0 + inset, y0 + p - inset, x0 + p - inset],
        })
    return out


def _build_macbeth(scene: Scene, config: RenderConfig) -> Built:
    wl = config.wl
    frame = _Frame(config)
    white = d65_white_radiance(wl)
    names, tables = spectra.colorchecker_tables()
    # Each patch emits the exact band means of D65(l) x rho(l) (the product
    # of the interpolated tables), not the product of the two band means.
    scale = white / spectra.illuminant("D65", wl)
    d65_table = spectra.illuminant_table("D65")
    radiance = [scale * spectra.band_average_product([d65_table, t], wl) for t in tables]
    objects = {"surround": frame.background(band_spectrum(config, white * SURROUND_REFLECTANCE))}
    patches = macbeth_layout(config.width, config.height)
    for i, patch in enumerate(patches):
        patch["name"] = names[i]
        patch["index"] = i
        # A hair in front of the surround so that the patch wins every ray.
        objects[f"patch{i:02d}"] = {
            "type": "rectangle",
            "to_world": frame.rect(*patch["rect"], z=1e-5 * frame.distance),
            "emitter": {"type": "area", "radiance": band_spectrum(config, radiance[i])},
        }
    meta = _common_meta()
    meta["geometry"] = {
        "reflectance_set": "ColorChecker N Ohta",
        "surround_reflectance": SURROUND_REFLECTANCE,
        "patches": patches,
        "gray_patches": list(range(18, 24)),
    }
    return Built(meta=meta, objects=objects, sensor=frame.sensor(config.fov_deg), white_radiance=white)


# ------------------------------------------------------------- slanted edge

def _edge_geometry(width: int, height: int, oversample: int) -> dict:
    k = oversample
    cy, cx = height / 2, width / 2
    # ROI: the middle 60 % of the rows, a quarter of the width around the
    # edge, snapped to whole sensor pixels (multiples of K).
    def snap(v):
        return int(k * round(v / k))
    roi = [snap(0.2 * height), snap(cx - width / 8), snap(0.8 * height), snap(cx + width / 8)]
    return {
        "edge_angle_deg": EDGE_ANGLE_DEG,
        "edge_direction": "moving up one row, the edge shifts right by tan(edge_angle_deg) columns",
        "edge_center_px": [cy, cx],
        "polarity": "dark-to-bright",
        "bright_side": "right",
        "low_reflectance": EDGE_REFLECTANCES[0],
        "high_reflectance": EDGE_REFLECTANCES[1],
        "roi": roi,
    }


def _edge_fraction(height: int, width: int, angle_deg: float, center, cell: float = 1.0,
                   origin=(0.0, 0.0)) -> np.ndarray:
    """Exact fraction of each cell on the bright side of the edge.

    Cells are squares of side ``cell`` (pixels) whose top-left corners are at
    ``origin + cell * (i, j)``, for i < height, j < width (rows, columns).
    The bright side is n . (p - c) > 0 with n = (cos a, sin a) in (x, y-down)
    pixel coordinates.  Over a cell, n . p is s0 + U + V with U uniform on
    [0, cell cos a] and V on [0, cell sin a]; the CDF of that sum (a
    trapezoid density, the convolution of two boxes) is closed-form.
    """
    a = math.radians(angle_deg)
    ca, sa = math.cos(a), math.sin(a)
    lo_w, hi_w = sorted((abs(ca) * cell, abs(sa) * cell))
    y = origin[0] + cell * np.arange(height, dtype=np.float64)[:, None]
    x = origin[1] + cell * np.arange(width, dtype=np.float64)[None, :]
    # The cell corner that minimises n . p.
    s0 = (x + (0 if ca >= 0 else cell) - center[1]) * ca + (y + (0 if sa >= 0 else cell) - center[0]) * sa
    t = -s0  # fraction bright = P(U + V > t)
    if lo_w < 1e-12 * cell:  # axis-aligned: a single box
        cdf = np.clip(t / hi_w, 0.0, 1.0)
    else:
        cdf = np.select(
            [t <= 0, t < lo_w, t < hi_w, t < lo_w + hi_w],
            [0.0, t * t / (2 * lo_w * hi_w), (2 * t - lo_w) / (2 * hi_w), 1 - (lo_w + hi_w - t) ** 2 / (2 * lo_w * hi_w)],
            1.0,
        )
    return 1.0 - cdf


def _edge_reflectance(height, width, cell=1.0, origin=(0.0, 0.0), image=None):
    h_img, w_img = image if image is not None else (height, width)
    lo, hi = EDGE_REFLECTANCES
    frac = _edge_fraction(height, width, EDGE_ANGLE_DEG, (h_img / 2, w_img / 2), cell, origin)
    return lo + (hi - lo) * frac


def _build_edge(scene: Scene, config: RenderConfig) -> Built:
    import mitsuba as mi

    frame = _Frame(config)
    t = _texels_per_stratum_grid(config.spp, cap=4)
    m = _MARGIN_PX
    cells = _edge_reflectance((config.height + 2 * m) * t, (config.width + 2 * m) * t, 1.0 / t, (-m, -m),
                              image=(config.height, config.width))
    # Row 0 of a bitmap lands at the bottom of a rectangle seen from +z.
    texture = {"type": "bitmap", "bitmap": mi.Bitmap(np.flipud(cells).astype(np.float32)[..., None]),
               "raw": True, "filter_type": "nearest", "wrap_mode": "clamp"}
    meta = _common_meta()
    meta["geometry"] = _edge_geometry(config.width, config.height, config.oversample)
    white = d65_white_radiance(config.wl)
    return Built(meta=meta, objects={"chart": frame.background(texture)}, sensor=frame.sensor(config.fov_deg),
                 pattern_spectrum=white, white_radiance=white)


# -------------------------------------------------------------------- chirp

def chirp_rate(width: int, oversample: int) -> float:
    """Chirp rate a (cycles per pixel^2): local frequency a x at position x
    (EXR pixels from the left edge), reaching 1/K cycles per EXR pixel
    (twice the sensor's Nyquist) exactly at the centre of the last column."""
    return 1.0 / (oversample * (width - 0.5))


def _chirp_integral(x, a):
    """Integral from 0 to x of (1 + cos(pi a t^2)) / 2 dt, via the Fresnel
    integral C(z) = int_0^z cos(pi s^2 / 2) ds with z = x sqrt(2a)."""
    from scipy.special import fresnel

    k = math.sqrt(2 * a)
    _, c = fresnel(np.asarray(x, dtype=np.float64) * k)
    return 0.5 * np.asarray(x, dtype=np.float64) + 0.5 * c / k


def _chirp_geometry(width, height, fov_deg, oversample) -> dict:
    a = chirp_rate(width, oversample)
    centres = np.arange(width) + 0.5
    f_px = a * centres
    # Degrees per pixel at each column of a pinhole camera (tan mapping).
    t = math.tan(math.radians(fov_deg) / 2)
    u = (2 * centres / width - 1) * t
    deg_per_px = np.degrees(2 * t / width / (1 + u * u))
    lo, hi = CHIRP_REFLECTANCES
    return {
        "definition": "reflectance(x) = low + (high - low) * (1 + cos(pi * a * x^2)) / 2, "
                      "x in EXR pixels from the image's left edge, constant down the columns",
        "chirp_rate_cy_per_px2": a,
        "low_reflectance": lo,
        "high_reflectance": hi,
        "row": height // 2,
        "frequency_cy_per_px": f_px.tolist(),
        "frequency_cy_per_deg": (f_px / deg_per_px).tolist(),
        "max_frequency_cy_per_px": float(f_px[-1]),
        "sensor_nyquist_cy_per_px": 0.5 / oversample,
    }


# ------------------------------------------------------------------ gray bar

def gray_steps(width: int) -> list[dict]:
    """The gray-bar steps: [x0, x1) column ranges (pixel boundaries at
    round(i W / N)), reflectance (CIE 1976 Y/Yn of the step's L*) and L*."""
    from ..colour_science import colour_science

    colour = colour_science()
    n = len(GRAY_L_STAR)
    if width < n:
        raise CfaMitsubaError(f"gray-bar needs at least {n} pixels across (got {width})")
    bounds = [round(i * width / n) for i in range(n + 1)]
    return [
        {"x0": bounds[i], "x1": bounds[i + 1], "L_star": L,
         "reflectance": float(colour.colorimetry.luminance_CIE1976(L)) / 100.0}
        for i, L in enumerate(GRAY_L_STAR)
    ]


def _row_pattern_bitmap(width: int, cell_integral, texels_per_px: int) -> np.ndarray:
    """One-row float32 bitmap over [-margin, width + margin] pixels holding
    the pattern's exact mean over each 1/texels_per_px-pixel cell;
    ``cell_integral(x)`` is the pattern's integral from 0 to x."""
    m, k = _MARGIN_PX, texels_per_px
    edges = -m + np.arange((width + 2 * m) * k + 1) / k
    cells = np.diff(cell_integral(edges)) * k
    return cells.astype(np.float32)[None, :, None]


def _build_row_pattern(scene: Scene, config: RenderConfig, bitmap: np.ndarray, geometry: dict) -> Built:
    import mitsuba as mi

    frame = _Frame(config)
    texture = {"type": "bitmap", "bitmap": mi.Bitmap(bitmap), "raw": True,
               "filter_type": "nearest", "wrap_mode": "clamp"}
    objects = {"chart": frame.background(texture)}
    meta = _common_meta()
    meta["geometry"] = geometry
    white = d65_white_radiance(config.wl)
    return Built(meta=meta, objects=objects, sensor=frame.sensor(config.fov_deg),
                 pattern_spectrum=white, white_radiance=white)


def _build_chirp(scene: Scene, config: RenderConfig) -> Built:
    a = chirp_rate(config.width, config.oversample)
    lo, hi = CHIRP_REFLECTANCES
    t = _texels_per_stratum_grid(config.spp, cap=64)
    bitmap = _row_pattern_bitmap(config.width, lambda x: lo * x + (hi - lo) * _chirp_integral(x, a), t)
    geometry = _chirp_geometry(config.width, config.height, config.fov_deg, config.oversample)
    return _build_row_pattern(scene, config, bitmap, geometry)


def _steps_integral(steps):
    x_b = np.array([s["x0"] for s in steps] + [steps[-1]["x1"]], dtype=np.float64)
    refl = np.array([s["reflectance"] for s in steps])
    # Piecewise-constant reflectance, held at the end values beyond the chart.
    cum = np.concatenate(([0.0], np.cumsum(refl * np.diff(x_b))))

    def integral(x):
        x = np.asarray(x, dtype=np.float64)
        i = np.clip(np.searchsorted(x_b, x, side="right") - 1, 0, len(refl) - 1)
        return cum[i] + refl[i] * (x - x_b[i])

    return integral


def _build_gray(scene: Scene, config: RenderConfig) -> Built:
    steps = gray_steps(config.width)
    bitmap = _row_pattern_bitmap(config.width, _steps_integral(steps), _texels_per_stratum_grid(config.spp, cap=64))
    return _build_row_pattern(scene, config, bitmap, {"steps": steps})


# ---------------------------------------------------------- exact references

def exact_reflectance(name: str, width: int, height: int, oversample: int | None = None) -> np.ndarray:
    """The exact box integral over each EXR pixel of an achromatic chart's
    reflectance pattern, shape (height, width): what an alias-free render
    divided by its white radiance must equal.  Independent of Mitsuba."""
    from .registry import get_scene

    k = oversample if oversample is not None else get_scene(name).oversample
    if name == "slanted-edge":
        return _edge_reflectance(height, width)
    if name == "chirp":
        a = chirp_rate(width, k)
        lo, hi = CHIRP_REFLECTANCES
        x = np.arange(width + 1, dtype=np.float64)
        row = lo + (hi - lo) * np.diff(_chirp_integral(x, a))
    elif name == "gray-bar":
        row = np.diff(_steps_integral(gray_steps(width))(np.arange(width + 1, dtype=np.float64)))
    else:
        raise CfaMitsubaError(f"no exact reflectance pattern for scene {name!r}")
    return np.broadcast_to(row, (height, width)).copy()


# ----------------------------------------------------------------- registry

#: Default K for scenes with detail above the sensor's Nyquist: the EXR grid
#: must carry the f/4 diffraction OTF up to its cutoff 1/(lambda N) = 625
#: cy/mm at 400 nm; with the 2.2 um sensor pitch (Nyquist 227 cy/mm) the EXR
#: Nyquist is K x 227 cy/mm, so K >= 2.75.  K = 4 (908 cy/mm) is the smallest
#: that also divides every default size (636, 720, 500) and 48 x 64.
SUPER_NYQUIST_OVERSAMPLE = 4
#: Default K of the chirp: its pattern has no frequency above its end, twice
#: the sensor's Nyquist (1 cy per sensor pixel = 454 cy/mm), so an EXR
#: Nyquist of 2 x 227 cy/mm already carries all of it through the OTF and the
#: pixel integration exactly (the box integrals over EXR pixels add up to the
#: sensor pixel's).  K = 2 keeps 250 camera pixels across the chirp (K = 4
#: would leave 125, coarse beside the 15-pixel block of the moire metric).
CHIRP_OVERSAMPLE = 2

#: The charts, registered by :mod:`.builtins`.
SCENES = (
    Scene(
        name="macbeth",
        description="ColorChecker (24 'ColorChecker N Ohta' reflectances, 4 x 6) under D65 on a dark surround; FOV 30 deg",
        width=720, height=636, fov_deg=30.0, spp=16, oversample=1, kind="macbeth",
        builder=_build_macbeth, jitter=False,
    ),
    Scene(
        name="slanted-edge",
        description="ISO 12233 edge, 5 deg from vertical, 4:1 contrast, dark left; FOV 2 deg; rendered at 4x the sensor's sampling",
        width=720, height=636, fov_deg=2.0, spp=16, oversample=SUPER_NYQUIST_OVERSAMPLE, kind="slanted-edge",
        builder=_build_edge, jitter=False,
    ),
    Scene(
        name="chirp",
        description="black-and-white linear chirp along the row, 0 to twice the sensor Nyquist; FOV 10 deg; 2x the sensor's sampling",
        width=500, height=500, fov_deg=10.0, spp=16, oversample=CHIRP_OVERSAMPLE, kind="chirp",
        builder=_build_chirp, jitter=False,
    ),
    Scene(
        name="gray-bar",
        description="10 achromatic steps in equal L* (95 to 5), white to near black along the row; FOV 10 deg",
        width=500, height=500, fov_deg=10.0, spp=16, oversample=1, kind="gray-bar",
        builder=_build_gray, jitter=False,
    ),
)
