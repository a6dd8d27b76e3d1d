"""The convergence study's settings: what is measured at which quality
(:class:`ConvergencePlan`, :func:`make_plan`) and the result's container.
See :mod:`.convergence` for the study itself."""

from __future__ import annotations

__all__ = ["CSV_COLUMNS", "ConvergencePlan", "ConvergenceResult", "make_plan", "default_spp_levels",
           "REFERENCE_FACTOR", "FLOOR_FACTOR", "FLOAT_FLOOR", "DEFAULT_COMPARE_CFAS", "WELL_BELOW"]

import math
from dataclasses import asdict, dataclass, field

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
    from ..metrics import get_metric, metrics_for_scene
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
        metrics=tuple(m for m in metrics_for_scene(sc.kind) if get_metric(m).scored),  # the scored ones
        is_3d=sc.is_3d, default_spp=_square_up(sc.spp), spp_levels=levels,
        reference_spp=ref, pocs_iterations=its, pocs_reference_iterations=pocs_ref, cfa=str(cfa),
        demosaic=str(demosaic), seed=cfg.seed, luminance_cd_m2=cfg.luminance_cd_m2, render_noise=render_noise,
        repeat=repeat, compare_cfas=tuple(compare_cfas), noise_seeds=noise_seeds,
        default_seeds=default_seeds if _square_up(sc.spp) in levels else 0, variant=variant,
    )


# ------------------------------------------------------------ measurements
