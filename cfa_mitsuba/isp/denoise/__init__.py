"""Noise reduction: the registry of denoisers and the stage that applies one.

A denoiser is one module of this package declaring ``DENOISERS =
(DenoiseMethod(...),)`` beside its function, as the demosaicing methods do
(:func:`collect_denoisers` registers them when the package loads; a user's
or a test's is added with :func:`register_denoiser`).  Its function
``f(plane, *, sigma, **options) -> plane`` takes one 2-D image whose noise
has unit variance at every level and returns it denoised; ``sigma`` is the
strength in that stabilised domain.

The stage does the rest, the same for every method
(:mod:`..noise_profile`): it predicts each channel's noise from the sensor
model at the capture's gain (shot + read + DSNU + ADC: ``var = a z + b``),
stabilises each plane with the generalised Anscombe transformation (so a
sigma of 1 is one predicted noise standard deviation at every level),
calls the method with ``sigma = strength x scale`` and inverts the
transformation.  ``strength`` is the method's one tuning constant, written
in its record with the rule that chose it and its data
(``cfa_mitsuba/data/denoise_tuning.csv``, made by
``benchmarks/tune_denoise.py``): the same for every CFA, sensor and light.
``scale`` (option, default 1) lets a user turn it up or down.

A study names a denoiser and its amount in one value (the ``denoise`` axis,
``[isp] denoise``): ``NAME`` or ``NAME:SCALE``, the tuned strength times
SCALE (:func:`denoise_setting`).

Support: a record says how far an output pixel's inputs reach
(``support``, :func:`denoise_support_px`), so that a chain that processes
only a region of the image can give a local method its margin and run a
global one (whose thresholds come from the whole plane) on the whole image.

Domains: ``raw`` denoises the white-balanced mosaic before demosaicing,
each phase of the CFA tile as its own image (a Bayer tile gives four
half-size planes: samples of one colour, its noise white); ``rgb`` denoises
each demosaicked camera channel (before the colour matrix), whose noise the
demosaic has interpolated: its profile at the samples is used everywhere,
an upper bound between them.  A method lists the domains it allows, the
first its default.
"""

from __future__ import annotations

__all__ = ["DenoiseMethod", "DOMAINS", "collect_denoisers", "register_denoiser", "unregister_denoiser",
           "list_denoisers", "get_denoiser", "denoiser_parameters", "check_denoise_options", "denoise_mosaic",
           "denoise_channels", "denoise_setting", "denoise_setting_name", "denoise_support_px"]

import inspect
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ...errors import CfaMitsubaError
from ..noise_profile import NoiseProfile, gat_forward, gat_inverse

#: ``raw``: the white-balanced mosaic, per CFA phase; ``rgb``: the demosaicked channels.
DOMAINS = ("raw", "rgb")
#: Options the stage takes for every method (the rest are the method's keywords).
STAGE_OPTIONS = ("domain", "scale")


@dataclass(frozen=True, kw_only=True)
class DenoiseMethod:
    """A denoiser's declaration in its module (``DENOISERS``).

    Attributes
    ----------
    name : the command-line name.
    function : ``f(plane, *, sigma, **options) -> plane`` (module doc); None
        for ``none``.
    description : one line for ``cfa-mitsuba list denoise``.
    domains : the domains it works in, the default first (:data:`DOMAINS`).
    strength : the tuning constant: ``sigma`` in units of the predicted
        noise standard deviation (one number: never per CFA or sensor).
    tuning : the rule that chose ``strength`` and on what data.
    licence : the licence of the code it runs.
    order : its place in listings.
    support : how far an output pixel's inputs reach, in pixels of the plane
        it denoises: ``support(options) -> radius`` (the method's own options,
        defaults filled in); None: global, every output pixel depends on the
        whole plane (thresholds estimated from all of it).
    """

    name: str
    function: Callable | None
    description: str
    domains: tuple[str, ...] = ("raw", "rgb")
    strength: float = 0.0
    tuning: str = ""
    licence: str = ""
    order: int = 1000
    support: Callable[[dict], float] | None = None

    def __post_init__(self):
        if self.support is not None and not callable(self.support):
            raise CfaMitsubaError(f"denoiser {self.name!r}: support must be a function of the options or None")
        if not self.domains or any(d not in DOMAINS for d in self.domains):
            raise CfaMitsubaError(f"denoiser {self.name!r}: domains must be among {DOMAINS}, got {self.domains!r}")
        if not (isinstance(self.strength, (int, float)) and np.isfinite(self.strength) and self.strength >= 0):
            raise CfaMitsubaError(f"denoiser {self.name!r}: strength must be a number >= 0, got {self.strength!r}")


_REGISTRY: dict[str, DenoiseMethod] = {}


def collect_denoisers(package: str = __name__) -> None:
    """Register the ``DENOISERS`` of every module of ``package`` in their ``order``."""
    from ..declared import declared_records

    for m in declared_records(package, "DENOISERS"):
        if m.name not in _REGISTRY:
            register_denoiser(m)


def register_denoiser(method: DenoiseMethod, *, replace: bool = False) -> DenoiseMethod:
    """Add a denoiser (a :class:`DenoiseMethod`)."""
    if not isinstance(method, DenoiseMethod):
        raise CfaMitsubaError(f"register_denoiser takes a DenoiseMethod, got {type(method).__name__}")
    if method.function is not None and not callable(method.function):
        raise CfaMitsubaError(f"denoiser {method.name!r}: its function must be callable")
    if method.name in _REGISTRY and not replace:
        raise CfaMitsubaError(f"a denoiser named {method.name!r} is already registered")
    _REGISTRY[method.name] = method
    return method


def unregister_denoiser(name: str) -> None:
    """Remove a registered denoiser (a test's toy one)."""
    _REGISTRY.pop(name, None)


def list_denoisers() -> list[tuple[str, str]]:
    """(name, one-line description with its domains and strength) of every denoiser."""
    return [(m.name, f"[{'|'.join(m.domains)}] {m.description}"
             + (f"; strength {m.strength:g} x the predicted noise sd" if m.function is not None else ""))
            for m in _REGISTRY.values()]


def get_denoiser(name: str) -> DenoiseMethod:
    """The record of the denoiser registered under ``name``."""
    if name not in _REGISTRY:
        raise CfaMitsubaError(f"unknown denoiser {name!r} (known: {', '.join(_REGISTRY)})")
    return _REGISTRY[name]


def denoiser_parameters(name: str) -> dict:
    """{option: inspect.Parameter}: the options of a denoiser a study or the
    command line may set: ``domain`` and ``scale`` for every method, plus
    its function's keyword-only parameters other than ``sigma``."""
    m = get_denoiser(name)
    own = {} if m.function is None else {
        k: p for k, p in inspect.signature(m.function).parameters.items()
        if p.kind is inspect.Parameter.KEYWORD_ONLY and k != "sigma"}
    stage = {k: inspect.Parameter(k, inspect.Parameter.KEYWORD_ONLY, default=d)
             for k, d in (("domain", m.domains[0]), ("scale", 1.0))}
    return {**stage, **own}


def check_denoise_options(name: str, options: dict | None) -> tuple[DenoiseMethod, str, float, dict]:
    """(record, domain, scale, the method's own options), or a one-line
    error naming an unknown option, an unknown or unsupported domain or a
    bad scale."""
    m = get_denoiser(name)
    options = dict(options or {})
    known = denoiser_parameters(name)
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise CfaMitsubaError(f"denoiser {name!r} has no option {unknown[0]!r} (options: {', '.join(known)})")
    domain = options.pop("domain", m.domains[0])
    if domain not in m.domains:
        raise CfaMitsubaError(f"denoiser {name!r} works in the {' or '.join(m.domains)} domain, not {domain!r}")
    scale = options.pop("scale", 1.0)
    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not np.isfinite(scale) or scale < 0:
        raise CfaMitsubaError(f"denoiser {name!r}: scale must be a number >= 0, got {scale!r}")
    return m, domain, float(scale), options


def denoise_setting(value) -> tuple[str, dict]:
    """(name, stage options) of a study's ``denoise`` value: ``NAME`` or
    ``NAME:SCALE`` (the method's tuned strength times SCALE, a number >= 0),
    e.g. ``'nl-means:2'`` -> ``('nl-means', {'scale': 2.0})``; a one-line
    error for anything else.

    >>> denoise_setting("nl-means:2"), denoise_setting("none")
    (('nl-means', {'scale': 2.0}), ('none', {}))
    """
    if not isinstance(value, str) or not value:
        raise CfaMitsubaError(f"a denoise setting is a denoiser's name or NAME:SCALE, got {value!r}")
    name, sep, amount = value.partition(":")
    get_denoiser(name)
    if not sep:
        return name, {}
    try:
        scale = float(amount)
    except ValueError:
        scale = float("nan")
    if not np.isfinite(scale) or scale < 0:
        raise CfaMitsubaError(f"denoise {value!r}: the scale after ':' must be a number >= 0 (x the tuned strength)")
    if get_denoiser(name).function is None:
        raise CfaMitsubaError(f"denoise {value!r}: {name!r} has no strength to scale")
    return name, {"scale": scale}


def denoise_setting_name(value) -> str:
    """The one spelling of a ``denoise`` setting: ``NAME``, or
    ``NAME:SCALE`` with SCALE as ``%g`` when it is not 1."""
    name, options = denoise_setting(value)
    scale = options.get("scale", 1.0)
    return name if scale == 1.0 else f"{name}:{scale:g}"


def denoise_support_px(name: str, options: dict | None = None, tile_shape=(1, 1)) -> int | None:
    """How far (pixels of the image, each axis) an output pixel's inputs
    reach for denoiser ``name`` with ``options``; None for a global method.
    In the raw domain each plane is one phase of the CFA tile, so a plane
    pixel is a tile period: the radius is the plane's times the larger tile
    side.  ``none``: 0."""
    m, domain, scale, own = check_denoise_options(name, options)
    if m.function is None or m.strength * scale == 0:
        return 0
    if m.support is None:
        return None
    full = {k: own.get(k, p.default) for k, p in denoiser_parameters(name).items() if k not in STAGE_OPTIONS}
    radius = float(m.support(full))
    step = max(int(v) for v in tile_shape) if domain == "raw" else 1
    return int(np.ceil(radius)) * step


def _run(m: DenoiseMethod, plane: np.ndarray, a: float, b: float, sigma: float, options: dict) -> np.ndarray:
    """One plane: stabilise, denoise at ``sigma``, invert."""
    if a <= 0:  # no shot noise (noise off, or a channel without signal scale): Gaussian of variance b
        if b <= 0:
            return plane
        sd = float(np.sqrt(b))
        out = m.function(plane / sd, sigma=sigma, **options)
        return np.asarray(out, dtype=np.float64) * sd
    stab = gat_forward(plane, a, b)
    out = np.asarray(m.function(stab, sigma=sigma, **options), dtype=np.float64)
    if out.shape != plane.shape or not np.all(np.isfinite(out)):
        raise CfaMitsubaError(f"denoiser {m.name!r} returned shape {out.shape} or non-finite values "
                              f"for a {plane.shape} plane")
    return gat_inverse(out, a, b)


def _record(m, domain, scale, profile: NoiseProfile, levels) -> dict:
    """What the stage applied, for ``meta['isp']['denoise']``."""
    sigma = m.strength * scale
    return {"method": m.name, "domain": domain, "strength": m.strength, "scale": scale,
            "sigma_stabilised": sigma,
            "channel_mean_level": [float(v) for v in levels],
            "applied_sigma_at_mean": [float(sigma * profile.sigma(c, lv)) for c, lv in enumerate(levels)],
            "noise_profile": profile.as_meta()}


def denoise_mosaic(mosaic: np.ndarray, index: np.ndarray, profile: NoiseProfile, name: str,
                   options: dict | None = None) -> tuple[np.ndarray, dict]:
    """Denoise a white-balanced mosaic in the raw domain (module doc).

    ``index`` is the tile's (th, tw) channel index (``isp.mosaic.geometry(cfa).index``).
    Returns (the denoised mosaic, the record of what was applied)."""
    m, domain, scale, own = check_denoise_options(name, options)
    if domain != "raw":
        raise CfaMitsubaError(f"denoise_mosaic is the raw domain; {name!r} was asked for {domain!r}")
    th, tw = index.shape
    levels = [float(np.mean(mosaic[i::th, j::tw])) for c in range(len(profile.channels))
              for (i, j) in [tuple(np.argwhere(index == c)[0])]] if len(profile.channels) else []
    record = _record(m, domain, scale, profile, levels)
    if m.function is None or profile.noise_free or m.strength * scale == 0:
        return mosaic, record
    out = np.empty_like(mosaic, dtype=np.float64)
    sigma = m.strength * scale
    for (i, j), c in np.ndenumerate(index):
        out[i::th, j::tw] = _run(m, np.ascontiguousarray(mosaic[i::th, j::tw], dtype=np.float64),
                                 float(profile.a[c]), float(profile.b[c]), sigma, own)
    return out, record


def denoise_channels(channels: np.ndarray, profile: NoiseProfile, name: str,
                     options: dict | None = None) -> tuple[np.ndarray, dict]:
    """Denoise demosaicked camera channels (H, W, C) in the rgb domain
    (module doc).  Returns (the denoised channels, the record)."""
    m, domain, scale, own = check_denoise_options(name, options)
    if domain != "rgb":
        raise CfaMitsubaError(f"denoise_channels is the rgb domain; {name!r} was asked for {domain!r}")
    levels = [float(np.mean(channels[..., c])) for c in range(channels.shape[-1])]
    record = _record(m, domain, scale, profile, levels)
    if m.function is None or profile.noise_free or m.strength * scale == 0:
        return channels, record
    sigma = m.strength * scale
    out = np.empty(channels.shape, dtype=np.float64)
    for c in range(channels.shape[-1]):
        out[..., c] = _run(m, np.ascontiguousarray(channels[..., c], dtype=np.float64),
                           float(profile.a[c]), float(profile.b[c]), sigma, own)
    return out, record


collect_denoisers(__name__)
