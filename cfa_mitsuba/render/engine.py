"""The render engine: settings -> Mitsuba -> SpectralImage, with the cache.

Two routes, one result (band-mean spectral radiance, W/(m^2 sr nm)):

- JIT variants (``llvm_ad_spectral``, ``cuda_ad_spectral``): one render with
  the spectral-quadrature integrator (:mod:`.integrator`), every band an AOV
  of an ``hdrfilm`` with a ``box`` reconstruction filter.
- ``scalar_spectral``, where a Python integrator is impractically slow,
  and users' scenes with participating media in any variant (:mod:`.media`):
  stock plugins only, one render per band with a single-band ``specfilm``
  (a box sensitivity of height 1/width, so the value is the band mean) and
  Mitsuba's ``path`` integrator (``volpath`` or ``volpathmis`` for media),
  the scene reloaded per band (research/mitsuba-spectral.md s. 2:
  retargeting the band in place renders black).

Achromatic charts render a single "band" spanning the whole range with flat
emitter spectra (the pattern), multiplied afterwards by the white radiance.

Every render is made at the canonical scale of :mod:`.light`, rounded to
float32 (the cache's precision, so a fresh render and a cached one are the
same numbers), then scaled to the requested mean luminance (ISETCam's
sceneAdjustLuminance 'mean'): luminance is never a re-render.
"""

from __future__ import annotations

__all__ = [
    "DEFAULT_LUMINANCE_CD_M2",
    "RENDER_CODE_VERSION",
    "resolve_settings",
    "cache_key",
    "render",
    "render_cached",
    "render_canonical",
    "scale_to_luminance",
]

import dataclasses
import functools
import hashlib
import math
import time
from pathlib import Path

import numpy as np

from ..io import limits as _limits
from .. import spectra
from ..errors import CfaMitsubaError
from ..values import SpectralImage
from . import userxml as _userxml
from . import variant as _variant
from . import white as _white
from .integrator import PLUGIN_NAME
from .light import BAND_INSET, CENTRE_INSET
from .loading import load_scene
from .measured import is_measured_image, measured_cached, measured_image
from .scaling import DEFAULT_LUMINANCE_CD_M2, scale_to_luminance  # noqa: F401  (part of this module's interface)
from .registry import get_scene
from .types import MAX_FOV_DEG, Built, RenderConfig, Scene

#: ISETCam's default mean scene luminance (cd/m^2).
#: Bump when a change alters rendered numbers in a way the source digest
#: cannot see (e.g. a new Mitsuba version).
RENDER_CODE_VERSION = "1"

_INT_LIMIT = 1 << 31


# ----------------------------------------------------------------- settings

def _name(what: str) -> str:
    """A setting's name with its command-line spelling: 'width (--width)'."""
    return f"{what} (--{what.replace('_', '-')})"


def _positive_int(value, what: str, *, minimum: int = 1, maximum: int = _INT_LIMIT) -> int:
    what = _name(what)
    if isinstance(value, bool):
        raise CfaMitsubaError(f"{what} must be an integer, got {value!r}")
    try:
        as_float = float(value)
    except (TypeError, ValueError):
        raise CfaMitsubaError(f"{what} must be an integer, got {value!r}") from None
    if not math.isfinite(as_float) or as_float != int(as_float):
        raise CfaMitsubaError(f"{what} must be an integer, got {value!r}")
    n = int(as_float)
    if n < minimum:
        raise CfaMitsubaError(f"{what} must be at least {minimum}, got {n}")
    if n > maximum:
        raise CfaMitsubaError(f"{what} must be at most {maximum}, got {n}")
    return n


def _positive_float(value, what: str) -> float:
    what = _name(what)
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise CfaMitsubaError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(x) or x <= 0:
        raise CfaMitsubaError(f"{what} must be a positive number, got {value!r}")
    return x


def _wavelengths(bands) -> tuple[float, ...]:
    if bands is None:
        wl = spectra.DEFAULT_WAVELENGTHS
    elif isinstance(bands, str):
        wl = spectra.parse_band_grid(bands)
    else:
        wl = spectra.validate_wavelengths(bands)
    return tuple(float(v) for v in wl)


def resolve_settings(scene, *, width=None, height=None, spp=None, luminance=None, variant=None, seed=None,
                     bands=None, oversample=None, fov=None, max_depth=None, f_number=None, white_from=None,
                     allow_outside_paths=False, defines=None, asset_root=None) -> tuple[Scene, RenderConfig]:
    """Validate render settings and fill the scene's defaults.

    Parameters (all optional; None takes the scene's default)
    ----------
    scene : a built-in name, a path to a Mitsuba XML file, or a :class:`Scene`.
    width, height : EXR size in pixels.
    spp : samples per pixel.
    luminance : mean luminance of the result, cd/m^2 (default 100).
    variant : Mitsuba variant (default: the best available spectral one).
    seed : sampler seed (default 0).
    bands : band grid, ``"START:STOP:STEP"`` nm or a sequence of centres (nm).
    oversample : K, EXR pixels per sensor pixel per axis (recorded, and
        used by the chirp's frequency range and the edge ROI).
    fov : horizontal field of view in degrees (built-in scenes only).
    max_depth : path length for 3D scenes (1 = emitters seen directly).
    f_number : the lens's f-number.  3D scenes with a thin lens render with
        aperture radius f / (2 N) (default: the puppy's f/2, a scene file's
        own aperture); recorded in the sidecar as ``f_number`` for every
        scene, and part of the cache key only where the render depends on it.
    white_from : the white-reference rule, 'panel' (default), 'illuminant'
        or X,Y,Z in cd/m^2 (:mod:`.white`); not part of the cache key.
    allow_outside_paths : a scene file may name files outside its folder.
    defines : a scene file's parameters, ``NAME=VALUE`` strings or a table
        (``--define``, Mitsuba's ``-D``).
    asset_root : one more folder a scene file may name files in.

    The field of view of a scene file is its camera's at the render's film
    size (:func:`.userxml.fov_at`: a ``fov_axis`` other than x makes it
    depend on the aspect ratio), as Mitsuba renders it.

    Returns ``(scene, config)``.  Raises :class:`CfaMitsubaError` naming the
    first bad setting.
    """
    sc = scene if isinstance(scene, Scene) else get_scene(scene, allow_outside_paths=bool(allow_outside_paths),
                                                          defines=defines, asset_root=asset_root)
    w = _positive_int(sc.width if width is None else width, "width", maximum=_limits.MAX_SIDE)
    h = _positive_int(sc.height if height is None else height, "height", maximum=_limits.MAX_SIDE)
    n = _positive_int(sc.spp if spp is None else spp, "spp", maximum=_limits.MAX_SPP)
    # The stratified sampler needs a square count (s x s strata per pixel);
    # round up here, as Mitsuba would, so the recorded spp is the true one.
    n = math.isqrt(n - 1) + 1
    n *= n
    lum = _positive_float(DEFAULT_LUMINANCE_CD_M2 if luminance is None else luminance, "luminance")
    s = _positive_int(0 if seed is None else seed, "seed", minimum=0, maximum=(1 << 32) - 1)
    k = _positive_int(sc.oversample if oversample is None else oversample, "oversample", maximum=64)
    if fov is not None and sc.path is not None:
        raise CfaMitsubaError("--fov applies to built-in scenes; a scene file keeps its camera's field of view")
    f = _positive_float(sc.fov_deg if fov is None else fov, "fov")
    if fov is None and sc.fov_at is not None and (w, h) != (sc.width, sc.height):
        f = sc.fov_at(w, h)
        if not 0 < f < MAX_FOV_DEG:
            raise CfaMitsubaError(f"scene {sc.name!r}: its camera at {w} x {h} pixels has a horizontal field of view "
                                  f"of {f:.4g} degrees; cfa-mitsuba needs less than {MAX_FOV_DEG:g} "
                                  "(change --width / --height)")
    if f >= MAX_FOV_DEG:
        raise CfaMitsubaError(f"fov (--fov) must be below {MAX_FOV_DEG:g} degrees, got {f:g}")
    depth = _positive_int(sc.max_depth if max_depth is None else max_depth, "max_depth", maximum=64)
    if depth > 1 and not sc.is_3d:
        raise CfaMitsubaError(f"max_depth (--max-depth) applies to 3D scenes; {sc.name!r} is a chart seen directly")
    wl = _wavelengths(bands)
    _limits.check_render(w, h, n, len(wl))  # samples, film size, memory: before Mitsuba loads
    v = _variant.choose_variant(variant)
    fn = None if f_number is None else _positive_float(f_number, "f_number")
    if fn is not None and not 0.5 <= fn <= 1000:
        raise CfaMitsubaError(f"f_number (--f-number) must be between 0.5 and 1000, got {fn:g}")
    return sc, RenderConfig(width=w, height=h, spp=n, seed=s, wavelengths=wl, variant=v, oversample=k,
                            fov_deg=f, max_depth=depth, luminance_cd_m2=lum, f_number=fn,
                            white_from=_white.parse_white_from(white_from))


# -------------------------------------------------------------------- cache

#: What a render reads besides its scene: this package's render code, the
#: modules it computes with, and the colour-science data it reads (D65, the
#: CIE 1931 observer, the ColorChecker reflectances).
_CODE_FILES = ("render", "spectra.py", "values.py", "errors.py", "io/exr.py", "io/sidecar.py", "io/atomic.py")
_DATA_MODULES = ("colour.colorimetry.datasets.illuminants.sds", "colour.colorimetry.datasets.cmfs",
                 "colour.characterisation.datasets.colour_checkers.sds")


def _digest_paths() -> list[Path]:
    """The files :func:`_source_digest` hashes."""
    import importlib

    from ..colour_science import colour_science

    package = Path(__file__).resolve().parents[1]
    paths = []
    for name in _CODE_FILES:
        p = package / name
        paths += sorted(p.rglob("*.py")) if p.is_dir() else [p]
    colour_science()  # the package first, as every other import of it here (without its plotting)
    for module in _DATA_MODULES:
        paths.append(Path(importlib.import_module(module).__file__).resolve())
    return paths


@functools.lru_cache(maxsize=1)
def _source_digest() -> str:
    """Digest of everything a render depends on besides its scene and
    settings: the render package, spectra.py, values.py, the EXR and
    sidecar code, and the colour-science data files the renders read.  Any
    change to one of them invalidates cached renders by itself."""
    from ..io.guard import read_bytes

    package = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for p in _digest_paths():
        h.update(str(p.relative_to(package) if p.is_relative_to(package) else p.name).encode())
        h.update(read_bytes(p, "render code or data file"))
    return h.hexdigest()[:16]


def _key_fields(sc: Scene, cfg: RenderConfig) -> dict:
    import mitsuba

    return {
        "render_code": RENDER_CODE_VERSION,
        "source": _source_digest(),
        "mitsuba": mitsuba.__version__,
        "scene": sc.name,
        "identity": sc.identity,
        "width": cfg.width,
        "height": cfg.height,
        "spp": cfg.spp,
        "seed": cfg.seed,
        "wavelengths": list(cfg.wavelengths),
        "variant": cfg.variant,
        "oversample": cfg.oversample,
        "fov_deg": cfg.fov_deg,
        "max_depth": cfg.max_depth,
        "sampler": sc.sampler,
        "jitter": sc.jitter,
        # Only a thin lens makes the render depend on the f-number.
        "f_number": (sc.f_number if cfg.f_number is None else cfg.f_number) if sc.thin_lens else None,
    }


def cache_key(scene, **settings) -> str:
    """The render-cache key for ``scene`` rendered with ``settings`` (the
    keywords of :func:`resolve_settings`): a hash of everything that
    determines the canonical render (scene identity including the content
    of a user XML and every file it reads, size, spp, seed, bands, variant,
    K, FOV, path depth, sampler, the f-number for thin-lens scenes, Mitsuba
    version, the render code and data, :func:`_source_digest`).
    ``luminance`` and ``white_from`` are not part of it: they only scale the
    cached render and choose its white."""
    from ..io.cache import hash_key

    sc, cfg = resolve_settings(scene, **settings)
    return hash_key(_key_fields(sc, cfg))


# ------------------------------------------------------------- Mitsuba glue

def _band_boxes(cfg: RenderConfig, achromatic: bool) -> list[tuple[float, float]]:
    edges = spectra.band_edges(cfg.wl)
    if achromatic:
        return [(float(edges[0]), float(edges[-1]))]
    return [(float(a), float(b)) for a, b in zip(edges[:-1], edges[1:])]


def _render_boxes(mi, built: Built, cfg: RenderConfig, sc: Scene, boxes, *, width, height, spp,
                  sensor: dict | None = None, extra: dict | None = None, step=None):
    """Render band means over ``boxes`` ((lo, hi) nm each): (height, width,
    len(boxes)) float32, and the (last) loaded Mitsuba scene.  ``sensor``
    and ``extra`` replace the camera and add shapes (the white panels)."""
    sampler = {"type": sc.sampler, "sample_count": int(spp), "seed": int(cfg.seed), "jitter": bool(sc.jitter)}
    if _per_band(cfg, built):
        stock = {"type": built.stock_integrator or "path", "max_depth": cfg.max_depth}
        planes = []
        for i, (lo, hi) in enumerate(boxes):
            if step is not None:
                step(f"band {i + 1}/{len(boxes)}", i)
            # The same sampled range as the JIT route (light.BAND_INSET).
            lo, hi = lo + BAND_INSET * (hi - lo), hi - BAND_INSET * (hi - lo)
            film = {"type": "specfilm", "width": width, "height": height, "rfilter": {"type": "box"},
                    "component_format": "float32",
                    "band": {"type": "regular", "wavelength_min": lo, "wavelength_max": hi,
                             "values": f"{1 / (hi - lo)!r}, {1 / (hi - lo)!r}"}}
            scene = load_scene(mi, built, film, sampler, stock, sensor=sensor, extra=extra)
            img = np.array(mi.render(scene, seed=cfg.seed), dtype=np.float32)
            planes.append(img.reshape(height, width, -1)[..., 0])
        return np.stack(planes, axis=-1), scene
    edges = [boxes[0][0]] + [hi for _, hi in boxes]
    if any(abs(boxes[i][1] - boxes[i + 1][0]) > 1e-9 for i in range(len(boxes) - 1)):
        raise ValueError("band boxes must be contiguous")
    film = {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
            "pixel_format": "luminance", "component_format": "float32"}
    inset = CENTRE_INSET if built.band_constant else BAND_INSET
    integrator = {"type": PLUGIN_NAME, "band_edges": ",".join(repr(float(e)) for e in edges),
                  "band_inset": inset, "max_depth": cfg.max_depth}
    scene = load_scene(mi, built, film, sampler, integrator, sensor=sensor, extra=extra)
    img = np.array(mi.render(scene, seed=cfg.seed), dtype=np.float32)
    n = len(boxes)
    if img.ndim != 3 or img.shape[2] < n:
        raise RuntimeError(f"unexpected film output of shape {img.shape} for {n} bands")
    return img[..., -n:], scene  # the AOVs follow the film's own channels


def _per_band(cfg: RenderConfig, built: Built) -> bool:
    """Whether the render goes band by band through stock plugins (module
    docstring): in ``scalar_spectral``, and for a scene that needs a stock
    integrator (participating media)."""
    return cfg.variant.startswith("scalar") or built.stock_integrator is not None


def _white_of_3d_scene(mi, built: Built, cfg: RenderConfig, sc: Scene, scene, data: np.ndarray):
    """The canonical ``panel`` white of a 3D scene (:mod:`.white`) and its
    record; the ``illuminant`` rule on the image if no panel gets light."""
    boxes = _band_boxes(cfg, achromatic=False)

    def render_panels(sensor, extra, width):
        if not _per_band(cfg, built):
            return _render_boxes(mi, built, cfg, sc, boxes, width=width, height=1, spp=_white.PANEL_SPP,
                                 sensor=sensor, extra=extra)[0]
        # Band by band: a batch sensor does not draw wavelengths from a
        # specfilm's band (measured in scalar_spectral: band means 10x too
        # high), so one meter at a time.
        meters = [v for k, v in sensor.items() if k.startswith("meter_")]
        return np.concatenate([_render_boxes(mi, built, cfg, sc, boxes, width=1, height=1, spp=_white.PANEL_SPP,
                                             sensor={k: v for k, v in m.items() if k != "film"}, extra=extra)[0]
                               for m in meters], axis=1)

    white, info = _white.measure_panels(mi, scene, cfg.wl, render_panels)
    if white is None:
        shape = _white.bright_spectrum(data, cfg.wl)
        y = float(spectra.luminance_cd_m2(shape, cfg.wl))
        white = shape * (_white.robust_max_luminance(data, cfg.wl) / y) if y > 0 else shape
        info["rule"] = "illuminant (no white panel receives light)"
    return np.asarray(white, dtype=np.float64), info


# ---------------------------------------------------------------- rendering

def render_canonical(scene, **settings) -> SpectralImage:
    """Render at the canonical scale (see :mod:`.light`), float32-rounded,
    without the luminance fields: the form the cache stores.  Writes no
    files.  ``settings`` as :func:`resolve_settings`."""
    sc, cfg = resolve_settings(scene, **settings)
    return _render_canonical(sc, cfg)


def _render_canonical(sc: Scene, cfg: RenderConfig, progress=None) -> SpectralImage:
    """The canonical render (:func:`render_canonical`); ``progress``, when
    given, is called as ``progress(stage, done, total)`` before each stage
    (the render, or each band of a band-by-band render; the white panels of
    a 3D scene) and once at the end (done = total)."""
    from ..io.cache import hash_key

    mi = _variant.load(cfg.variant)
    key = hash_key(_key_fields(sc, cfg))
    built = sc.build(cfg)
    start = time.perf_counter()
    achromatic = built.pattern_spectrum is not None or built.layers is not None
    boxes = _band_boxes(cfg, achromatic)
    per_render = len(boxes) if _per_band(cfg, built) else 1
    layers = built.layers if built.layers is not None else ((built.objects, built.pattern_spectrum),)
    renders = per_render * len(layers)
    stages = renders + (built.white_radiance is None)  # the render (or each band's); a 3D scene's white panels
    if progress is not None:
        progress(f"render ({cfg.width} x {cfg.height}, {cfg.spp} spp)", 0, stages)
    data = None
    for n, (objects, spectrum) in enumerate(layers):  # one render, or one per layer of a layered chart
        def step(t, i, n=n):
            progress(t if len(layers) == 1 else f"layer {n + 1}/{len(layers)} {t}", n * per_render + i, stages)

        bands, scene = _render_boxes(mi, dataclasses.replace(built, objects=objects), cfg, sc, boxes,
                                     width=cfg.width, height=cfg.height, spp=cfg.spp,
                                     step=None if progress is None else step)
        if achromatic:  # the pattern times its spectrum, summed over the layers
            part = bands[..., :1].astype(np.float64) * np.asarray(spectrum, dtype=np.float64)[None, None, :]
            data = part if data is None else data + part
            del bands, part
        else:
            data = bands.astype(np.float64)
    data = data.astype(np.float32).astype(np.float64)
    bad = int(data.size - np.count_nonzero(np.isfinite(data)))
    if bad:  # a scene file with an infinite (or float32-overflowing) emitter or texture value
        raise CfaMitsubaError(
            f"the render of {sc.name!r} has {bad} NaN or infinite radiance values: check the scene's emitters "
            "and textures for infinite or huge (> 3e38) values")
    meta_extra = {}
    if built.white_radiance is not None:
        white = np.asarray(built.white_radiance, dtype=np.float64)
        meta_extra["white_reference"] = {"rule": "exact: a perfect white diffuser under the chart's light"}
    else:
        if progress is not None:
            progress("white panels", renders, stages)
        white, info = _white_of_3d_scene(mi, built, cfg, sc, scene, data)
        meta_extra["white_reference"] = info
        if "scene_distance_m" not in built.meta:
            central = [p for p in info["panels"] if p["grid"] == [0.5, 0.5]] or info["panels"]
            meta_extra["scene_distance_m"] = float(np.median([p["distance_m"] for p in central])) if central else None
    elapsed = time.perf_counter() - start
    if progress is not None:
        progress("done", stages, stages)
    if sc.path is not None and not _userxml.files_unchanged(sc):
        raise CfaMitsubaError(f"the files of scene {sc.name!r} changed while it rendered: render it again")
    wl = cfg.wl
    meta = {
        "scene": sc.name,
        "width": cfg.width,
        "height": cfg.height,
        "fov_deg": cfg.fov_deg,
        "oversample": cfg.oversample,
        "wavelengths": list(cfg.wavelengths),
        "band_edges_nm": spectra.band_edges(wl).tolist(),
        "units": "W/(m^2 sr nm)",
        "band_definition": ("band means (box averages of the linearly interpolated colour-science data) of "
                            "illuminant and reflectances, multiplied band by band" if built.band_constant else
                            "box mean over the band's edges of the linearly interpolated spectrum"),
        "band_constant_spectra": built.band_constant,
        "illuminant": "D65",
        "canonical_white_radiance": white.tolist(),
        "white_exact": built.white_radiance is not None,
        "spp": cfg.spp,
        "sampler": sc.sampler,
        "sampler_jitter": sc.jitter,
        "max_depth": cfg.max_depth,
        "variant": cfg.variant,
        "seed": cfg.seed,
        "render_time_s": round(elapsed, 3),
        "cache_key": key,
        "kind": sc.kind,
        "renderer": f"mitsuba {mi.__version__}",
        **meta_extra,
        **built.meta,
    }
    return SpectralImage(data, wl, meta)


def render(scene, *, progress=None, **settings) -> SpectralImage:
    """Render ``scene`` (a built-in name, a path to a Mitsuba 3 XML file, or
    a :class:`Scene`) to band-mean spectral radiance in W/(m^2 sr nm).

    Pure: writes no files and does not use the cache (see
    :func:`render_cached`).  ``settings`` are the keywords of
    :func:`resolve_settings`; ``progress`` as :func:`_render_canonical`'s.
    Returns a :class:`SpectralImage` whose ``meta`` is the sidecar
    (docs/scenes.md lists its keys).
    """
    if is_measured_image(scene):  # a measured spectral image: converted, not rendered
        return measured_image(scene, **settings)
    sc, cfg = resolve_settings(scene, **settings)
    return scale_to_luminance(_render_canonical(_current(sc), cfg, progress), cfg.luminance_cd_m2,
                              white_from=cfg.white_from, f_number=cfg.f_number)


def _current(sc: Scene) -> Scene:
    """A scene file's :class:`Scene` read again if any of its files changed
    since it was read, so that the cache key follows the files on disk."""
    if sc.path is not None and not _userxml.files_unchanged(sc):
        return get_scene(sc.path, allow_outside_paths=sc.allow_outside_paths, defines=sc.defines,
                         asset_root=sc.asset_root)
    return sc


def render_cached(scene, *, cache=None, progress=None, **settings) -> SpectralImage:
    """:func:`render` through the render cache: reuse the cached canonical
    render for these settings if there is one, else render and store it.

    ``cache``: a :class:`~cfa_mitsuba.io.cache.RenderCache`, a directory, or
    None for the default (``$CFA_MITSUBA_CACHE`` or ``~/.cache/cfa-mitsuba``).
    The result's ``meta["cache_reused"]`` says whether this call reused a render.
    ``progress``: as :func:`render`'s (not called for a reused render).
    Concurrent callers with the same settings render once (a per-key lock).
    """
    from ..io.cache import RenderCache, hash_key

    if is_measured_image(scene):  # a measured spectral image: converted once, cached like a render
        return measured_cached(scene, cache=cache, **settings)
    sc, cfg = resolve_settings(scene, **settings)
    sc = _current(sc)
    store = cache if isinstance(cache, RenderCache) else RenderCache(cache)
    key = hash_key(_key_fields(sc, cfg))
    canonical, hit = store.get_or_create(key, lambda: _render_canonical(sc, cfg, progress))
    out = scale_to_luminance(canonical, cfg.luminance_cd_m2, white_from=cfg.white_from, f_number=cfg.f_number)
    out.meta["cache_reused"] = hit
    return out
