"""Error against run time: what render quality (samples per pixel) and
processing quality (POCS iterations) buy, measured against a reference.

For one scene, :func:`run_convergence`

1. renders a **reference** as the mean of two independent renders (seeds
   ``seed + 1`` and ``seed + 2``) at ``reference_spp`` each; half their
   difference is the reference's own noise, measured, not assumed;
2. renders the scene at each **spp level** (seed ``seed``), timing the whole
   :func:`cfa_mitsuba.render.render` call (scene build, Mitsuba load, kernel
   compile, render, white probe); with ``repeat`` > 1 the fastest of the runs
   counts (the first run of a new spp compiles a kernel: 2-4 s on the puppy);
3. reports, per level and per band, the **radiance error**: the rms over the
   image of (level - reference), divided by the reference's mean, and the
   same over the scene's most uniform window (:func:`uniform_region`);
4. runs every level and the reference through the study's chain (optics,
   capture with the CFA, processing with the demosaic, the scene's metrics
   against the ideal XYZ sensor: :mod:`cfa_mitsuba.study.tasks`) and reports
   each **metric's deviation** from the reference's value.  The capture is
   noise-free by default (``render_noise='off'``): the sensor's Poisson
   sampler draws a new realisation whenever the mean signal changes at all
   (a 1e-4 relative change of the radiance re-draws 95 % of the pixels), so
   a fixed noise seed does not freeze the sensor noise across renders and
   would bury the render-induced deviation under seed-to-seed noise.  A
   deviation from one render is one draw of a random variable (it crosses
   zero now and then), so the default spp is rendered with a few more seeds
   and the check uses the rms over them;
5. on the processing side, captures the reference once with sensor noise
   (the study's seed for this scene and CFA) and processes it with POCS at
   each iteration count (tolerance 0, so exactly that many iterations),
   reporting each metric's deviation from a converged POCS
   (``pocs_reference_iterations``, tolerance 0) against the processing time;
6. puts the deviations in context: each metric's spread across a few CFAs
   (the differences a study reports; the study's noise seeds) and its
   seed-to-seed sensor-noise standard deviation.

Results are a tidy table (:data:`CSV_COLUMNS`) and a summary dict with the
fitted convergence rates (:func:`fit_rate`); :func:`write_outputs` writes
``convergence_<scene>.csv`` and ``.json``; the plot (``.png``, ``.svg``) is
drawn by :mod:`cfa_mitsuba.report.convergence`.
"""

from __future__ import annotations

__all__ = [
    "CSV_COLUMNS",
    "ConvergencePlan",
    "ConvergenceResult",
    "make_plan",
    "default_spp_levels",
    "run_convergence",
    "uniform_region",
    "relative_rms_per_band",
    "fit_rate",
    "write_outputs",
    "format_table",
    "rows_frame",
    "radiance_series",
    "rate_text",
]

import json
import math
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError

#: Columns of ``convergence_<scene>.csv``.  ``stage``: ``render`` (quality =
#: spp), ``render-seeds`` (the default spp rendered with other seeds),
#: ``pocs`` (quality = iterations), ``reference`` (the reference's own
#: error; quality = its spp per render), ``reference-pocs`` (the converged
#: POCS's values, error 0), ``sensor-noise`` (a metric's standard deviation
#: over noise seeds; quality = number of seeds), ``cfa-spread`` and
#: ``cfa-gap`` (a metric's max - min, and smallest difference between two of
#: the compared CFAs, with the render stage's demosaic; quality = number of
#: CFAs), ``pocs-cfa-spread``, ``pocs-cfa-gap`` (the same with POCS),
#: ``cfa-pairs`` (rms change, from the reference to the default spp's
#: renders, of the difference between two CFAs: what can reorder them;
#: sensor noise as the render stage's) and ``cfa-common`` (rms shift
#: common to all CFAs).
#: ``error``: relative rms
#: (radiance rows, unit ``relative``) or absolute deviation in the metric's
#: unit.  ``value``: the metric's value at that quality (empty for radiance).
CSV_COLUMNS = ("scene", "stage", "quality", "wall_s", "quantity", "error", "unit", "value")

#: Reference spp = this x the scene's default spp (rounded up to a square).
REFERENCE_FACTOR = 16
#: Path-traced (3D) scenes are swept at 1/DIVISOR of their default width and
#: height unless told otherwise (a reference at 16x the default spp at full
#: size takes hours on 2 cores).
REDUCED_3D_DIVISOR = 3
#: Points whose error is below this many times the noise floor are left out
#: of the rate fits (error^2 = own^2 + floor^2: at 2x the floor the floor
#: adds 12 % to the error).
FLOOR_FACTOR = 2.0
#: Relative radiance errors below this are float32 rounding (renders are
#: stored as float32: 2^-24 = 6e-8 per value), not convergence.
FLOAT_FLOOR = 1e-6
#: CFAs whose spread puts a metric's render error in context (the brief's
#: small study: one per family).
DEFAULT_COMPARE_CFAS = ("bayer", "rgb3", "cmy1", "rgbw1")
#: "Well below": render-induced deviation at most this fraction of the CFA spread.
WELL_BELOW = 0.1


@dataclass(frozen=True)
class ConvergencePlan:
    """Validated settings of one convergence run (see :func:`make_plan`)."""

    scene: str                      # built-in name or path of a Mitsuba XML file
    name: str                       # the scene's name (file stems)
    width: int                      # EXR pixels
    height: int
    oversample: int                 # K, EXR pixels per sensor pixel
    size_note: str                  # why this size
    metrics: tuple[str, ...]
    is_3d: bool
    default_spp: int
    spp_levels: tuple[int, ...]     # true spp (squares: the stratified sampler's s x s)
    reference_spp: int              # per reference render (two of them)
    pocs_iterations: tuple[int, ...]
    pocs_reference_iterations: int = 50
    pocs_default_iterations: int = 10
    cfa: str = "bayer"
    demosaic: str = "bilinear"
    seed: int = 0
    luminance_cd_m2: float = 100.0
    render_noise: str = "off"
    repeat: int = 2
    compare_cfas: tuple[str, ...] = DEFAULT_COMPARE_CFAS
    noise_seeds: int = 4
    default_seeds: int = 3
    variant: str | None = None

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class ConvergenceResult:
    """``rows``: the tidy table (list of dicts, :data:`CSV_COLUMNS`);
    ``summary``: plan, reference, uniform region, rates, checks, timings."""

    plan: ConvergencePlan
    rows: list[dict]
    summary: dict = field(default_factory=dict)


# --------------------------------------------------------------- planning

def _square_up(n: int) -> int:
    s = math.isqrt(n - 1) + 1
    return s * s


def default_spp_levels(default_spp: int) -> tuple[int, ...]:
    """Powers of 4 from 1 up to 4x the default, plus the default itself."""
    levels = {default_spp}
    v = 1
    while v <= 4 * default_spp:
        levels.add(v)
        v *= 4
    return tuple(sorted(levels))


def _check_levels(values, what: str, *, square: bool) -> tuple[int, ...]:
    vals = []
    for v in values:
        try:
            ok = not isinstance(v, bool) and float(v).is_integer() and int(float(v)) >= 1
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise CfaMitsubaError(f"{what}: every value must be a positive whole number, got {v!r}")
        vals.append(int(float(v)))
    if not vals:
        raise CfaMitsubaError(f"{what}: give at least one value")
    for a, b in zip(vals, vals[1:]):
        if b <= a:
            raise CfaMitsubaError(f"{what} must increase strictly, got {a} then {b}")
    if square:
        rounded = [_square_up(v) for v in vals]
        for (a, ra), (b, rb) in zip(zip(vals, rounded), zip(vals[1:], rounded[1:])):
            if ra == rb:
                raise CfaMitsubaError(f"{what}: {a} and {b} both round up to {ra} samples per pixel "
                                      f"(the stratified sampler takes s x s samples)")
        vals = rounded
    return tuple(vals)


def make_plan(scene, *, width=None, height=None, spp=None, reference_spp=None, pocs_iterations=None,
              pocs_reference_iterations: int = 50, cfa: str = "bayer", demosaic: str = "bilinear",
              seed: int = 0, luminance: float = 100.0, render_noise: str = "off", repeat: int = 2,
              compare_cfas=DEFAULT_COMPARE_CFAS, noise_seeds: int = 4, default_seeds: int = 3,
              variant=None) -> ConvergencePlan:
    """Check the settings of a convergence run and fill the defaults.

    Parameters
    ----------
    scene : a built-in scene name or a Mitsuba 3 XML file.
    width, height : EXR size in pixels (default: the scene's; path-traced
        scenes 1/:data:`REDUCED_3D_DIVISOR` of it, rounded to whole sensor
        pixels).
    spp : increasing samples-per-pixel levels (default
        :func:`default_spp_levels`); each is rounded up to a square as the
        stratified sampler does, and the recorded level is the true count.
    reference_spp : spp of each of the two reference renders (default
        :data:`REFERENCE_FACTOR` x the scene's default); must exceed every level.
    pocs_iterations : increasing POCS iteration counts (default 1, 2, 4, 8,
        10, 16, 32), each below ``pocs_reference_iterations``.
    cfa, demosaic : the camera of the render stage (and the POCS stage's CFA).
    seed : seed of the levels' renders and of the study-style noise seeds.
    luminance : mean scene luminance, cd/m^2.
    render_noise : sensor noise of the render stage's captures (``off``,
        ``shot``, ``all``; module docstring, step 4).
    repeat : renders per level for timing (the fastest counts).
    compare_cfas : CFAs whose metric spread is reported (empty: none).
    noise_seeds : sensor-noise seeds for the metric's noise spread (0: none).
    default_seeds : extra renders of the default spp (seeds ``seed + 3``
        ...): a metric's deviation at one render is one draw of a random
        variable (it can cross zero), so the check uses the rms over these
        and the level's render (0: the level's render alone).
    variant : Mitsuba variant (default: the best available).

    Raises :class:`CfaMitsubaError` naming the first bad setting.
    """
    from .. import render
    from ..isp.demosaic import get_demosaic
    from ..sensor import get_cfa
    from ..sensor.params import NOISE_MODES

    sc = render.get_scene(scene)
    get_cfa(cfa)
    get_demosaic(demosaic)
    get_demosaic("pocs")
    for c in compare_cfas:
        get_cfa(c)
    if render_noise not in NOISE_MODES:
        raise CfaMitsubaError(f"render noise must be one of {', '.join(NOISE_MODES)}, got {render_noise!r}")
    levels = _check_levels(spp if spp is not None else default_spp_levels(sc.spp), "--spp", square=True)
    if reference_spp is not None:
        ref = _check_levels([reference_spp], "--reference-spp", square=True)[0]
    else:
        ref = _square_up(REFERENCE_FACTOR * sc.spp)
    if ref <= levels[-1]:
        raise CfaMitsubaError(f"--reference-spp ({ref}) must exceed the highest level ({levels[-1]})")
    pocs_ref = _check_levels([pocs_reference_iterations], "--pocs-reference", square=False)[0]
    its = _check_levels(pocs_iterations if pocs_iterations is not None else (1, 2, 4, 8, 10, 16, 32),
                        "--pocs-iterations", square=False)
    its = tuple(i for i in its if i < pocs_ref) if pocs_iterations is None else its
    if its[-1] >= pocs_ref:
        raise CfaMitsubaError(f"--pocs-iterations must stay below the converged reference ({pocs_ref} iterations)")
    k = sc.oversample
    if width is None and height is None and sc.is_3d:
        w = max(k, (sc.width // REDUCED_3D_DIVISOR) // k * k)
        h = max(k, (sc.height // REDUCED_3D_DIVISOR) // k * k)
        note = (f"1/{REDUCED_3D_DIVISOR} of the default {sc.width} x {sc.height} per side: a path-traced scene's "
                f"reference at {REFERENCE_FACTOR}x its default spp takes hours at full size on 2 cores")
    else:
        w = sc.width if width is None else width
        h = sc.height if height is None else height
        note = "the scene's default size" if width is None and height is None else "as requested"
    # Validate the size (and the rest) the way a render would.
    _, cfg = render.resolve_settings(sc, width=w, height=h, spp=1, seed=seed, luminance=luminance, variant=variant)
    if cfg.width % k or cfg.height % k:
        raise CfaMitsubaError(f"width and height must be multiples of the scene's oversampling K = {k} "
                              f"(got {cfg.width} x {cfg.height})")
    if not (isinstance(repeat, int) and repeat >= 1):
        raise CfaMitsubaError(f"--repeat must be a whole number >= 1, got {repeat!r}")
    if not (isinstance(noise_seeds, int) and (noise_seeds == 0 or noise_seeds >= 2)):
        raise CfaMitsubaError(f"--noise-seeds must be 0 or at least 2, got {noise_seeds!r}")
    if not (isinstance(default_seeds, int) and default_seeds >= 0):
        raise CfaMitsubaError(f"--default-seeds must be a whole number >= 0, got {default_seeds!r}")
    return ConvergencePlan(
        scene=str(scene), name=sc.name, width=cfg.width, height=cfg.height, oversample=k, size_note=note,
        metrics=tuple(sc.metrics), is_3d=sc.is_3d, default_spp=_square_up(sc.spp), spp_levels=levels,
        reference_spp=ref, pocs_iterations=its, pocs_reference_iterations=pocs_ref, cfa=str(cfa),
        demosaic=str(demosaic), seed=cfg.seed, luminance_cd_m2=cfg.luminance_cd_m2, render_noise=render_noise,
        repeat=repeat, compare_cfas=tuple(compare_cfas), noise_seeds=noise_seeds,
        default_seeds=default_seeds if _square_up(sc.spp) in levels else 0, variant=variant,
    )


# ------------------------------------------------------------ measurements

def relative_rms_per_band(test: np.ndarray, reference: np.ndarray, region=None) -> np.ndarray:
    """Per band: rms over the pixels of (test - reference) / mean(reference).

    ``test``, ``reference``: (H, W, B) radiance; ``region``: (y0, x0, y1, x1)
    half-open pixel rectangle, or None for the whole image.  Returns (B,),
    dimensionless (0.01 = 1 %); a band whose reference mean is 0 gives NaN.
    """
    t, r = np.asarray(test, dtype=np.float64), np.asarray(reference, dtype=np.float64)
    if region is not None:
        y0, x0, y1, x1 = region
        t, r = t[y0:y1, x0:x1], r[y0:y1, x0:x1]
    d = (t - r).reshape(-1, t.shape[-1])
    rms = np.sqrt(np.mean(d * d, axis=0))
    mean = r.reshape(-1, r.shape[-1]).mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mean > 0, rms / mean, np.nan)


def uniform_region(luminance: np.ndarray, *, side: int | None = None) -> tuple[int, int, int, int]:
    """The square window where ``luminance`` (H, W) varies least.

    Windows of ``side`` pixels (default a tenth of the shorter image side,
    at least 4) on a half-window grid; the one with the lowest coefficient
    of variation (std / mean) wins, the brighter on a tie.  Returns
    (y0, x0, y1, x1), half-open.  Used on the reference render: the
    window's render error is then noise, not detail.
    """
    lum = np.asarray(luminance, dtype=np.float64)
    h, w = lum.shape
    s = side or max(4, min(h, w) // 10)
    s = min(s, h, w)
    step = max(1, s // 2)
    best, best_key = (0, 0, s, s), (math.inf, 0.0)
    for y in range(0, h - s + 1, step):
        for x in range(0, w - s + 1, step):
            win = lum[y:y + s, x:x + s]
            m = float(win.mean())
            if m <= 0:
                continue
            cv = float(win.std()) / m
            key = (round(cv, 12), -m)
            if key < best_key:
                best, best_key = (y, x, y + s, x + s), key
    return best


def fit_rate(x, y, floor=None) -> dict:
    """Least-squares slope of log(y) against log(x).

    Points with y <= 0, or at or below :data:`FLOOR_FACTOR` x ``floor``
    (scalar or per point), are left out.  Returns ``{"rate": slope or
    None, "points": n used}``; two distinct x are needed.
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    keep = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    if floor is not None:
        f = np.broadcast_to(np.asarray(floor, dtype=np.float64), y.shape)
        keep &= ~(np.isfinite(f) & (y <= FLOOR_FACTOR * f))
    n = int(keep.sum())
    if n < 2 or np.unique(x[keep]).size < 2:
        return {"rate": None, "points": n}
    slope = np.polyfit(np.log(x[keep]), np.log(y[keep]), 1)[0]
    return {"rate": float(slope), "points": n}


class _Chain:
    """The study's chain after the render, for one scene (tasks.evaluate_task's steps)."""

    def __init__(self, plan: ConvergencePlan):
        from ..optics import OpticsParams
        from ..sensor.params import SensorParams

        self.plan = plan
        self.optics = OpticsParams()
        self.sensor = SensorParams()

    def optical(self, img):
        from ..optics import compute_optics

        return compute_optics(img, self.optics, pixel_pitch_um=self.sensor.pixel_pitch_um,
                              fill_factor=self.sensor.fill_factor)

    def ideal(self, oi):
        from ..isp import process
        from ..sensor import capture_ideal

        raw = capture_ideal(oi, luminance_cd_m2=self.plan.luminance_cd_m2, sensor=self.sensor, exposure_s="auto")
        return process(raw)

    def capture(self, oi, cfa: str, noise: str, seed: int):
        from ..sensor import capture

        return capture(oi, cfa, luminance_cd_m2=self.plan.luminance_cd_m2, exposure_s="auto", noise=noise,
                       seed=seed, sensor=self.sensor, reference_luminance_cd_m2=100.0)

    def metrics(self, ideal, raw, method: str, **opts) -> tuple[dict, dict, float]:
        """({metric: value}, {metric: unit}, processing wall time s)."""
        from .. import metrics as m
        from ..isp import process
        from .tasks import metric_results, metric_rows

        t = time.perf_counter()
        out = process(raw, method, **opts)
        dt = time.perf_counter() - t
        cam = m.mean_match(out.xyz, ideal.xyz)
        geo = m.scene_geometry(ideal.meta, ideal.xyz.shape)
        white = np.asarray(ideal.white_xyz, dtype=np.float64)
        res = metric_results(self.plan.metrics, ideal.xyz, cam, white, geo, self.sensor.pixel_pitch_um)
        rows = metric_rows({}, res)
        return {r["metric"]: r["value"] for r in rows}, {r["metric"]: r["unit"] for r in rows}, dt

    def evaluate(self, img, cfa: str, method: str, noise: str, seed: int):
        oi = self.optical(img)
        ideal = self.ideal(oi)
        return self.metrics(ideal, self.capture(oi, cfa, noise, seed), method)


def _timed_render(plan: ConvergencePlan, spp: int, seed: int, runs: int):
    from .. import render

    times, img = [], None
    for _ in range(runs):
        t = time.perf_counter()
        img = render.render(plan.scene, width=plan.width, height=plan.height, spp=spp, seed=seed,
                            luminance=plan.luminance_cd_m2, variant=plan.variant)
        times.append(time.perf_counter() - t)
    return img, min(times), times


def _luminance(img) -> np.ndarray:
    from .. import spectra

    return spectra.luminance_cd_m2(img.data, img.wavelengths)


def _band_names(wl) -> list[str]:
    return [f"{w:g}nm" for w in np.asarray(wl, dtype=np.float64)]


def _summ(a) -> dict:
    a = np.asarray(a, dtype=np.float64)
    return {"median": float(np.nanmedian(a)), "max": float(np.nanmax(a))}


def run_convergence(plan: ConvergencePlan, *, log=None) -> ConvergenceResult:
    """Measure error against run time for ``plan`` (module docstring).
    ``log``: a callable for progress lines (default: stderr)."""
    from ..values import SpectralImage
    from .tasks import task_seed

    log = log or (lambda msg: print(msg, file=sys.stderr, flush=True))
    p = plan
    chain = _Chain(p)
    rows: list[dict] = []
    units: dict[str, str] = {}
    t_start = time.perf_counter()

    def row(stage, quality, wall_s, quantity, error, unit, value=None):
        rows.append({"scene": p.name, "stage": stage, "quality": quality, "wall_s": wall_s, "quantity": quantity,
                     "error": float(error), "unit": unit, "value": None if value is None else float(value)})

    # 1. The reference: two independent renders.
    log(f"convergence {p.name}: {p.width} x {p.height}, spp {', '.join(map(str, p.spp_levels))}; "
        f"reference 2 x {p.reference_spp} spp")
    refs, ref_times = [], []
    for i in (1, 2):
        log(f"  reference render {i}/2 ({p.reference_spp} spp, seed {p.seed + i}) ...")
        img, dt, _ = _timed_render(p, p.reference_spp, p.seed + i, 1)
        refs.append(img)
        ref_times.append(dt)
        log(f"    {dt:.1f} s")
    r1, r2 = refs
    wl = np.asarray(r1.wavelengths, dtype=np.float64)
    bands = _band_names(wl)
    ref = SpectralImage(0.5 * (r1.data + r2.data), wl, {**r1.meta, "spp": 2 * p.reference_spp,
                                                         "seed": [p.seed + 1, p.seed + 2]})
    region = uniform_region(_luminance(ref))
    own_img = 0.5 * relative_rms_per_band(r1.data, r2.data) * _mean_ratio(r2.data, ref.data)
    own_reg = 0.5 * relative_rms_per_band(r1.data, r2.data, region) * _mean_ratio(r2.data, ref.data, region)
    for b, e_i, e_r in zip(bands, own_img, own_reg):
        row("reference", p.reference_spp, sum(ref_times), f"radiance:{b}", e_i, "relative")
        row("reference", p.reference_spp, sum(ref_times), f"uniform:{b}", e_r, "relative")
    exact = _exact_error(p, ref)

    log("  metrics of the reference ...")
    ref_vals, u, _ = chain.evaluate(ref, p.cfa, p.demosaic, p.render_noise, p.seed)
    units.update(u)
    half = [chain.evaluate(r, p.cfa, p.demosaic, p.render_noise, p.seed)[0] for r in (r1, r2)]
    metric_floor = {k: 0.5 * abs(half[0][k] - half[1][k]) for k in ref_vals}
    for k, v in ref_vals.items():
        row("reference", p.reference_spp, sum(ref_times), k, metric_floor[k], units[k], v)
    del refs, r1, r2, half

    # 2. The levels.
    level_times = {}
    default_imgs = []  # the default spp's renders, for the CFA differences below
    for n, spp in enumerate(p.spp_levels, 1):
        img, dt, times = _timed_render(p, spp, p.seed, p.repeat)
        level_times[spp] = times
        if spp == p.default_spp:
            default_imgs.append(img)
        e_img = relative_rms_per_band(img.data, ref.data)
        e_reg = relative_rms_per_band(img.data, ref.data, region)
        for b, a, c in zip(bands, e_img, e_reg):
            row("render", spp, dt, f"radiance:{b}", a, "relative")
            row("render", spp, dt, f"uniform:{b}", c, "relative")
        vals, _, _ = chain.evaluate(img, p.cfa, p.demosaic, p.render_noise, p.seed)
        for k, v in vals.items():
            row("render", spp, dt, k, abs(v - ref_vals[k]), units[k], v)
        log(f"  render {n}/{len(p.spp_levels)}: {spp} spp, {dt:.2f} s"
            + (f" (runs {', '.join(f'{t:.2f}' for t in times)})" if len(times) > 1 else "")
            + f"; radiance error median band {100 * np.nanmedian(e_img):.3g} %")

    # The default spp again with other seeds: the spread of its deviation.
    if p.default_seeds:
        for i in range(p.default_seeds):
            s_i = p.seed + 3 + i
            log(f"  default {p.default_spp} spp, seed {s_i} ({i + 1}/{p.default_seeds}) ...")
            img, dt, _ = _timed_render(p, p.default_spp, s_i, 1)
            default_imgs.append(img)
            vals, _, _ = chain.evaluate(img, p.cfa, p.demosaic, p.render_noise, p.seed)
            for k, v in vals.items():
                row("render-seeds", p.default_spp, dt, k, abs(v - ref_vals[k]), units[k], v)
    del img

    # 3. POCS on the reference's noisy capture (the study's seed).
    study_seed = task_seed(p.seed, p.name, p.cfa, p.luminance_cd_m2)
    oi = chain.optical(ref)
    ideal = chain.ideal(oi)
    raw = chain.capture(oi, p.cfa, "all", study_seed)
    log(f"  POCS: converged reference ({p.pocs_reference_iterations} iterations) ...")
    pocs_ref, _, pocs_ref_s = chain.metrics(ideal, raw, "pocs", iterations=p.pocs_reference_iterations,
                                            tolerance=0.0)
    for k, v in pocs_ref.items():
        row("reference-pocs", p.pocs_reference_iterations, pocs_ref_s, k, 0.0, units[k], v)
    for it in p.pocs_iterations:
        times, vals = [], None
        for _ in range(max(p.repeat, 3)):  # cheap, and timing on a shared machine is noisy
            vals, _, dt = chain.metrics(ideal, raw, "pocs", iterations=it, tolerance=0.0)
            times.append(dt)
        for k, v in vals.items():
            row("pocs", it, min(times), k, abs(v - pocs_ref[k]), units[k], v)
        log(f"  POCS {it} iterations: {min(times):.2f} s")
    info: dict = {}
    default_vals, _, default_s = chain.metrics(ideal, raw, "pocs", info=info)
    pocs_default = {"iterations_done": info.get("iterations"), "wall_s": default_s,
                    "deviation": {k: abs(v - pocs_ref[k]) for k, v in default_vals.items()},
                    "value": default_vals}

    # 4. Context: sensor-noise spread and the spread between CFAs.
    noise_std = {}
    if p.noise_seeds:
        log(f"  sensor noise: {p.noise_seeds} seeds ...")
        per_seed = [chain.metrics(ideal, chain.capture(oi, p.cfa, "all", study_seed + i), p.demosaic)[0]
                    for i in range(p.noise_seeds)]
        for k in ref_vals:
            noise_std[k] = float(np.std([s[k] for s in per_seed], ddof=1))
            row("sensor-noise", p.noise_seeds, None, k, noise_std[k], units[k],
                float(np.mean([s[k] for s in per_seed])))
    cfa_values: dict[str, dict] = {}
    if p.compare_cfas:
        methods = list(dict.fromkeys([p.demosaic, "pocs"]))
        log(f"  CFA spread: {', '.join(p.compare_cfas)} ({', '.join(methods)}) ...")
        for c in p.compare_cfas:
            raw_c = chain.capture(oi, c, "all", task_seed(p.seed, p.name, c, p.luminance_cd_m2))
            for method in methods:
                cfa_values.setdefault(method, {})[c] = chain.metrics(ideal, raw_c, method)[0]
        for method in methods:
            prefix = "" if method == p.demosaic else "pocs-"
            for k in ref_vals:
                v = sorted(cfa_values[method][c][k] for c in p.compare_cfas)
                gap = min((b - a for a, b in zip(v, v[1:])), default=float("nan"))
                row(f"{prefix}cfa-spread", len(v), None, k, v[-1] - v[0], units[k])
                row(f"{prefix}cfa-gap", len(v), None, k, gap, units[k])
        if len(p.compare_cfas) >= 2 and default_imgs:
            log(f"  CFA differences at {p.default_spp} spp ({len(default_imgs)} render(s)) vs the reference ...")
            pair, common = _difference_deviation(chain, p, ref, default_imgs, list(ref_vals))
            for k in ref_vals:
                row("cfa-pairs", p.default_spp, None, k, pair[k], units[k])
                row("cfa-common", p.default_spp, None, k, common[k], units[k])
    del default_imgs

    summary = _summarise(p, rows, units, ref_vals, metric_floor, region, exact, ref_times, level_times,
                         pocs_default, noise_std, cfa_values, time.perf_counter() - t_start)
    return ConvergenceResult(p, rows, summary)


def _difference_deviation(chain, p, ref, renders, metrics) -> tuple[dict, dict]:
    """How the default spp's render error moves the differences between CFAs.

    Each CFA in ``p.compare_cfas`` is captured (sensor noise as the render
    stage's, ``p.render_noise``) from the reference and from each default-spp render, processed with ``p.demosaic``, and
    measured.  With d_c = m_c(render) - m_c(reference): returns per metric
    (rms over renders and CFA pairs of d_a - d_b, which is what can reorder
    two CFAs; rms over renders of the mean over CFAs of d_c, a shift common
    to every CFA, which cannot).
    """
    from .tasks import task_seed

    def values(img):
        oi = chain.optical(img)
        ideal = chain.ideal(oi)
        return {c: chain.metrics(ideal, chain.capture(oi, c, p.render_noise,
                                                     task_seed(p.seed, p.name, c, p.luminance_cd_m2)),
                                 p.demosaic)[0] for c in p.compare_cfas}

    at_ref = values(ref)
    pair_sq, common_sq = {k: [] for k in metrics}, {k: [] for k in metrics}
    for img in renders:
        got = values(img)
        for k in metrics:
            d = np.array([got[c][k] - at_ref[c][k] for c in p.compare_cfas])
            common_sq[k].append(float(d.mean()) ** 2)
            pair_sq[k].extend(float(a - b) ** 2 for i, a in enumerate(d) for b in d[i + 1:])
    return ({k: float(np.sqrt(np.mean(v))) for k, v in pair_sq.items()},
            {k: float(np.sqrt(np.mean(v))) for k, v in common_sq.items()})


def _mean_ratio(a, b, region=None):
    """mean(a) / mean(b) per band (turns 'relative to a' into 'relative to b')."""
    if region is not None:
        y0, x0, y1, x1 = region
        a, b = a[y0:y1, x0:x1], b[y0:y1, x0:x1]
    ma = a.reshape(-1, a.shape[-1]).mean(axis=0)
    mb = b.reshape(-1, b.shape[-1]).mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mb > 0, ma / mb, np.nan)


def _exact_error(plan: ConvergencePlan, ref) -> dict | None:
    """The reference's error against the exact box integral of a built-in
    chart's pattern (None for other scenes): relative rms per band."""
    from ..render import charts

    name = plan.name
    if plan.is_3d or name not in ("slanted-edge", "chirp", "gray-bar", "macbeth") or Path(plan.scene).suffix:
        return None
    white = np.asarray(ref.meta["white_radiance"], dtype=np.float64)  # at the render's luminance
    if name == "macbeth":
        from .. import spectra

        # A patch's band value is the box mean of D65(l) rho(l) (the product of
        # the interpolated colour-science tables), scaled as the white is.
        wl = np.asarray(ref.wavelengths, dtype=np.float64)
        _, tables = spectra.colorchecker_tables()
        scale = white / spectra.illuminant("D65", wl)
        d65 = spectra.illuminant_table("D65")
        exact = np.broadcast_to(white * charts.SURROUND_REFLECTANCE, ref.data.shape).copy()
        for table, patch in zip(tables, charts.macbeth_layout(plan.width, plan.height)):
            y0, x0, y1, x1 = patch["rect"]
            exact[y0:y1, x0:x1] = scale * spectra.band_average_product([d65, table], wl)
    else:
        pattern = charts.exact_reflectance(name, plan.width, plan.height, plan.oversample)
        exact = pattern[..., None] * white[None, None, :]
    e = relative_rms_per_band(ref.data, exact)
    return {"what": "reference vs the exact box integral of the chart (independent of Mitsuba)",
            "relative_rms_median_band": float(np.nanmedian(e)), "relative_rms_worst_band": float(np.nanmax(e))}


# -------------------------------------------------------------- summaries

def rows_frame(rows):
    """The measurement rows as a DataFrame with :data:`CSV_COLUMNS`."""
    import pandas as pd

    return pd.DataFrame(rows, columns=list(CSV_COLUMNS))


def radiance_series(df, stage: str, prefix: str):
    """Per quality: (wall_s, median over bands, max over bands, quality) of a radiance kind."""
    sub = df[(df["stage"] == stage) & df["quantity"].str.startswith(prefix + ":")]
    g = sub.groupby("quality", sort=True)
    return (g["wall_s"].first().to_numpy(dtype=float), g["error"].median().to_numpy(dtype=float),
            g["error"].max().to_numpy(dtype=float), g["error"].size().index.to_numpy(dtype=float))


def _summarise(p, rows, units, ref_vals, metric_floor, region, exact, ref_times, level_times, pocs_default,
               noise_std, cfa_values, total_s) -> dict:
    df = rows_frame(rows)
    rates: dict = {"render": {}, "pocs": {}}
    floors = {}
    own_rows = df[(df["stage"] == "reference") & df["quantity"].str.startswith("radiance:")]["error"]
    own_measured = _summ(own_rows)
    for prefix, label in (("radiance", "image"), ("uniform", "uniform region")):
        _, own_med, own_max, _ = radiance_series(df, "reference", prefix)
        t, med, mx, q = radiance_series(df, "render", prefix)
        for agg, y, f in (("median band", med, own_med[0]), ("worst band", mx, own_max[0])):
            key = f"radiance, {label}, {agg}"
            floor = max(f, FLOAT_FLOOR)
            floors[key] = floor
            r_t = fit_rate(t, y, floor)
            r_q = fit_rate(q, y, floor)
            rates["render"][key] = {"per_wall_time": r_t["rate"], "per_spp": r_q["rate"], "points": r_t["points"],
                                    "unit": "relative", "floor": floor}
    for stage, floor_of in (("render", metric_floor), ("pocs", {})):
        for k in ref_vals:
            sub = df[(df["stage"] == stage) & (df["quantity"] == k)].sort_values("quality")
            # Renders are float32: metric changes below FLOAT_FLOOR of the value are rounding.
            floor = max(floor_of.get(k, 0.0), FLOAT_FLOOR * max(abs(ref_vals[k]), 1.0))
            r_t = fit_rate(sub["wall_s"], sub["error"], floor)
            r_q = fit_rate(sub["quality"], sub["error"], floor)
            rates[stage][k] = {"per_wall_time": r_t["rate"], "per_spp" if stage == "render" else "per_iteration":
                               r_q["rate"], "points": r_t["points"], "unit": units[k], "floor": floor}
    # The default spp: its error and time (interpolated in log-log if it was not a level).
    d = p.default_spp
    at_default: dict = {"spp": d}
    lev = df[(df["stage"] == "render") & (df["quality"] == d)]
    if len(lev):
        at_default["wall_s"] = float(lev["wall_s"].iloc[0])
        for prefix, label in (("radiance", "image"), ("uniform", "uniform region")):
            e = lev[lev["quantity"].str.startswith(prefix + ":")]["error"]
            at_default[f"radiance {label} median band"] = float(e.median())
            at_default[f"radiance {label} worst band"] = float(e.max())
        one = {k: float(lev[lev["quantity"] == k]["error"].iloc[0]) for k in ref_vals}
        seeds = df[df["stage"] == "render-seeds"]
        at_default["metric_deviation_one_render"] = one
        at_default["renders"] = 1 + int(p.default_seeds)
        # rms over the level's render and the extra seeds: the deviation a study's render carries
        at_default["metric_deviation"] = {
            k: float(np.sqrt(np.mean(np.square([one[k], *seeds[seeds["quantity"] == k]["error"].astype(float)]))))
            for k in ref_vals}
        at_default["metric_deviation_max"] = {
            k: float(max([one[k], *seeds[seeds["quantity"] == k]["error"].astype(float)])) for k in ref_vals}
    checks = {}
    pocs_checks = {}

    def by_metric(stage):
        sub = df[df["stage"] == stage]
        return dict(zip(sub["quantity"], sub["error"].astype(float)))

    def compare(c: dict, dev, spread, gap):
        c.update(cfa_spread=spread, cfa_smallest_gap=gap)
        if dev is not None and spread is not None:
            c["ratio_to_spread"] = dev / spread if spread > 0 else None
            c["ratio_to_smallest_gap"] = dev / gap if gap and gap > 0 else None
            c["well_below_spread"] = bool(spread > 0 and dev <= WELL_BELOW * spread)
            c["below_smallest_gap"] = bool(gap is not None and gap > 0 and dev < gap)
        return c

    spread, gap = by_metric("cfa-spread"), by_metric("cfa-gap")
    pairs, common = by_metric("cfa-pairs"), by_metric("cfa-common")
    pocs_spread, pocs_gap = by_metric("pocs-cfa-spread"), by_metric("pocs-cfa-gap")
    if p.demosaic == "pocs":
        pocs_spread, pocs_gap = spread, gap
    for k in ref_vals:
        dev = at_default.get("metric_deviation", {}).get(k)
        checks[k] = compare({"render_deviation_at_default": dev, "renders": at_default.get("renders"),
                             "render_deviation_max": at_default.get("metric_deviation_max", {}).get(k),
                             "unit": units[k], "reference_value": ref_vals[k],
                             "reference_noise": metric_floor[k], "sensor_noise_std": noise_std.get(k)},
                            dev, spread.get(k), gap.get(k))
        if k in pairs:
            checks[k].update(cfa_difference_deviation=pairs[k], cfa_common_shift=common[k],
                             difference_below_smallest_gap=bool(gap.get(k) and pairs[k] < gap[k]),
                             difference_well_below_spread=bool(spread.get(k) and pairs[k] <= WELL_BELOW * spread[k]))
        pdev = pocs_default["deviation"][k]
        pocs_checks[k] = compare({"pocs_default_deviation": pdev, "unit": units[k]}, pdev, pocs_spread.get(k),
                                 pocs_gap.get(k))
    return {
        "scene": p.name,
        "plan": p.to_dict(),
        "reference": {
            "spp_per_render": p.reference_spp, "renders": 2, "seeds": [p.seed + 1, p.seed + 2],
            "wall_s": ref_times,
            "own_noise": "half the rms difference of the two renders, relative to the reference's mean, per band",
            "own_noise_measured_median_band": own_measured["median"],
            "own_noise_measured_worst_band": own_measured["max"],
            "own_noise_image_median_band": floors["radiance, image, median band"],
            "own_noise_image_worst_band": floors["radiance, image, worst band"],
            "floor_definition": f"max(the reference's own noise, {FLOAT_FLOOR:g} float32 rounding)",
            "exact_check": exact,
            "metric_values": ref_vals,
            "metric_noise": {k: metric_floor[k] for k in ref_vals},
        },
        "uniform_region": {"rect_yx": list(region),
                           "how": "square window of the reference where luminance varies least (lowest std/mean)"},
        "level_wall_s": {str(k): v for k, v in level_times.items()},
        "at_default": at_default,
        "pocs_default": pocs_default,
        "rates": rates,
        "rate_definition": "least-squares slope of log(error) against log(wall time) (and against log(spp) or "
                           f"log(iterations)) over the points above {FLOOR_FACTOR:g}x the noise floor",
        "cfa_values": cfa_values,
        "checks": checks,
        "pocs_checks": pocs_checks,
        "well_below": f"render-induced deviation at the default spp <= {WELL_BELOW:g} x the CFA spread",
        "total_wall_s": total_s,
        "cores": _cores(),
        "code": _code_version(),
    }


def _code_version() -> dict:
    """The package version and, in a git checkout, the commit and whether
    the working tree had changes (results depend on the code they ran)."""
    import subprocess

    from .. import __version__

    out = {"cfa_mitsuba": __version__}
    root = Path(__file__).resolve().parents[2]
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, timeout=10)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, timeout=10)
        if commit.returncode == 0:
            out["git_commit"] = commit.stdout.strip()
            out["git_dirty"] = bool(dirty.stdout.strip())
    except (OSError, subprocess.SubprocessError):
        pass
    return out


def _cores() -> int:
    import os

    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


# ----------------------------------------------------------------- output

def _fmt(x, digits=3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    if x == 0:
        return "0"
    return f"{x:.{digits}g}"


def rate_text(r) -> str:
    return "n/a" if r is None else f"{r:+.2f}"


def format_table(result: ConvergenceResult) -> str:
    """The short stdout table: one line per spp level and POCS count, the
    rates, the reference's own noise and the check against the CFA spread."""
    p, s = result.plan, result.summary
    df = rows_frame(result.rows)
    metrics = list(s["reference"]["metric_values"])
    out = [f"{p.name}: {p.width} x {p.height} EXR px (K = {p.oversample}), {p.cfa} + {p.demosaic}, "
           f"reference 2 x {p.reference_spp} spp (own noise: median band "
           f"{100 * s['reference']['own_noise_measured_median_band']:.2g} %)"]
    head = ["spp", "wall s", "rad med %", "rad max %", "unif med %"] + [f"d {m}" for m in metrics]
    lines = [head]
    for q in sorted(df[df["stage"] == "render"]["quality"].unique()):
        lev = df[(df["stage"] == "render") & (df["quality"] == q)]
        rad = lev[lev["quantity"].str.startswith("radiance:")]["error"]
        uni = lev[lev["quantity"].str.startswith("uniform:")]["error"]
        mark = "*" if q == p.default_spp else ""
        lines.append([f"{int(q)}{mark}", f"{lev['wall_s'].iloc[0]:.2f}", _fmt(100 * rad.median()),
                      _fmt(100 * rad.max()), _fmt(100 * uni.median())]
                     + [_fmt(float(lev[lev["quantity"] == m]["error"].iloc[0])) for m in metrics])
    out.append(_columns(lines))
    rr = s["rates"]["render"]
    out.append("rates (slope of log error vs log wall time): " + "; ".join(
        f"{k}: {rate_text(v['per_wall_time'])}" for k, v in rr.items()
        if k.endswith("median band") or k in metrics))
    lines = [["pocs it", "wall s"] + [f"d {m}" for m in metrics]]
    for q in sorted(df[df["stage"] == "pocs"]["quality"].unique()):
        lev = df[(df["stage"] == "pocs") & (df["quality"] == q)]
        lines.append([str(int(q)), f"{lev['wall_s'].iloc[0]:.2f}"]
                     + [_fmt(float(lev[lev["quantity"] == m]["error"].iloc[0])) for m in metrics])
    pd_ = s["pocs_default"]
    lines.append([f"{pd_['iterations_done']}*", f"{pd_['wall_s']:.2f}"]
                 + [_fmt(pd_["deviation"][m]) for m in metrics])
    out.append(_columns(lines))
    out.append("(* the default; d = |deviation| from the reference, in the metric's unit)")
    for m, c in s["checks"].items():
        if c.get("cfa_spread") is None:
            continue
        if c["render_deviation_at_default"] is None:
            verdict = "not measured (the default spp was not among the levels)"
        elif c.get("well_below_spread"):
            verdict = f"well below (<= {WELL_BELOW:g} x the spread)"
        else:
            verdict = f"NOT well below (> {WELL_BELOW:g} x the spread)"
        if c.get("cfa_difference_deviation") is not None:
            out.append(f"check {m}: at {p.default_spp} spp the differences between CFAs move by "
                       f"{_fmt(c['cfa_difference_deviation'])} {c['unit']} rms (common shift "
                       f"{_fmt(c['cfa_common_shift'])}) vs the smallest gap {_fmt(c['cfa_smallest_gap'])}: "
                       + ("below" if c["difference_below_smallest_gap"] else "NOT below"))
        out.append(f"check {m}: render-induced deviation at {p.default_spp} spp (rms of {c['renders']} renders) "
                   f"{_fmt(c['render_deviation_at_default'])}"
                   f" {c['unit']} vs CFA spread {_fmt(c['cfa_spread'])} (smallest gap {_fmt(c['cfa_smallest_gap'])}, "
                   f"sensor-noise std {_fmt(c['sensor_noise_std'])}): {verdict}")
    for m, c in s.get("pocs_checks", {}).items():
        if c.get("cfa_spread") is None:
            continue
        verdict = "well below" if c.get("well_below_spread") else "NOT well below"
        out.append(f"check {m} (POCS default, {s['pocs_default']['iterations_done']} iterations): deviation from "
                   f"converged {_fmt(c['pocs_default_deviation'])} {c['unit']} vs CFA spread with POCS "
                   f"{_fmt(c['cfa_spread'])} (smallest gap {_fmt(c['cfa_smallest_gap'])}): {verdict}")
    return "\n".join(out)


def _columns(lines) -> str:
    widths = [max(len(r[i]) for r in lines) for i in range(len(lines[0]))]
    return "\n".join("  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in lines)


def write_outputs(result: ConvergenceResult, out_dir) -> dict:
    """Write ``convergence_<scene>.csv`` (tidy) and ``.json`` (summary);
    returns {kind: path}.  The plot is the report stage's
    (:func:`cfa_mitsuba.report.convergence.write_convergence` writes all)."""
    from ..io import atomic_output, check_writable_dir
    from .tasks import safe_label

    out = check_writable_dir(out_dir)
    stem = f"convergence_{safe_label(result.plan.name)}"
    paths = {"csv": out / f"{stem}.csv", "json": out / f"{stem}.json"}
    df = rows_frame(result.rows)
    with atomic_output(paths["csv"]) as tmp:
        df.to_csv(tmp, index=False, float_format="%.6g")
    with atomic_output(paths["json"]) as tmp:
        tmp.write_text(json.dumps(_jsonable(result.summary), indent=1, allow_nan=False))
    return paths


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj
