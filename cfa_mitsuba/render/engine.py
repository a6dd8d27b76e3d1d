"""The render engine: settings -> Mitsuba -> SpectralImage, with the cache.

Two routes, one result (band-mean spectral radiance, W/(m^2 sr nm)):

- JIT variants (``llvm_ad_spectral``, ``cuda_ad_spectral``): one render with
  the spectral-quadrature integrator (:mod:`.integrator`), every band an AOV
  of an ``hdrfilm`` with a ``box`` reconstruction filter.
- ``scalar_spectral``, where a Python integrator is impractically slow:
  stock plugins only, one render per band with a single-band ``specfilm``
  (a box sensitivity of height 1/width, so the value is the band mean) and
  Mitsuba's ``path`` integrator, the scene reloaded per band
  (research/mitsuba-spectral.md s. 2: retargeting the band in place renders
  black).

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
from . import variant as _variant
from .integrator import PLUGIN_NAME
from .light import BAND_INSET, CENTRE_INSET
from .measured import is_measured_image, measured_cached, measured_image
from .registry import Built, RenderConfig, Scene, get_scene

#: ISETCam's default mean scene luminance (cd/m^2).
DEFAULT_LUMINANCE_CD_M2 = 100.0
#: Bump when a change alters rendered numbers in a way the source digest
#: cannot see (e.g. a new Mitsuba version).
RENDER_CODE_VERSION = "1"
#: Samples for the white-diffuser probe of 3D scenes.
WHITE_PROBE_SPP = 16384

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
                     bands=None, oversample=None, fov=None, max_depth=None) -> tuple[Scene, RenderConfig]:
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

    Returns ``(scene, config)``.  Raises :class:`CfaMitsubaError` naming the
    first bad setting.
    """
    sc = scene if isinstance(scene, Scene) else get_scene(scene)
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
    if f >= 170:
        raise CfaMitsubaError(f"fov (--fov) must be below 170 degrees, got {f:g}")
    depth = _positive_int(sc.max_depth if max_depth is None else max_depth, "max_depth", maximum=64)
    if depth > 1 and not sc.is_3d:
        raise CfaMitsubaError(f"max_depth (--max-depth) applies to 3D scenes; {sc.name!r} is a chart seen directly")
    wl = _wavelengths(bands)
    _limits.check_render(w, h, n, len(wl))  # samples, film size, memory: before Mitsuba loads
    v = _variant.choose_variant(variant)
    return sc, RenderConfig(width=w, height=h, spp=n, seed=s, wavelengths=wl, variant=v, oversample=k,
                            fov_deg=f, max_depth=depth, luminance_cd_m2=lum)


# -------------------------------------------------------------------- cache

@functools.lru_cache(maxsize=1)
def _source_digest() -> str:
    """Digest of this package's source: any change to how scenes are built
    or rendered invalidates cached renders by itself."""
    h = hashlib.sha256()
    for p in sorted(Path(__file__).parent.rglob("*.py")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
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
    }


def cache_key(scene, **settings) -> str:
    """The render-cache key for ``scene`` rendered with ``settings`` (the
    keywords of :func:`resolve_settings`): a hash of everything that
    determines the canonical render (scene identity including a user XML's
    content and referenced files, size, spp, seed, bands, variant, K, FOV,
    path depth, sampler, Mitsuba version, this package's render source).
    ``luminance`` is not part of it: it only scales the cached render."""
    from ..io.cache import hash_key

    sc, cfg = resolve_settings(scene, **settings)
    return hash_key(_key_fields(sc, cfg))


# ------------------------------------------------------------- Mitsuba glue

def _xml_element(tag: str, d: dict, name: str | None = None) -> str:
    """Serialise a flat Mitsuba plugin dict (nested dicts allowed) as XML."""
    nested_tag = {"rfilter": "rfilter", "film": "film", "sampler": "sampler"}
    attrs = f' type="{d["type"]}"' + (f' name="{name}"' if name else "")
    parts = []
    for k, v in d.items():
        if k == "type":
            continue
        if isinstance(v, dict):
            parts.append(_xml_element(nested_tag.get(k, "spectrum"), v, k))
        elif isinstance(v, bool):
            parts.append(f'<boolean name="{k}" value="{str(v).lower()}"/>')
        elif isinstance(v, int):
            parts.append(f'<integer name="{k}" value="{v}"/>')
        elif isinstance(v, float):
            parts.append(f'<float name="{k}" value="{v!r}"/>')
        else:
            parts.append(f'<string name="{k}" value="{v}"/>')
    return f"<{tag}{attrs}>" + "".join(parts) + f"</{tag}>"


def _probe_parts(mi, probe: dict, as_xml: bool):
    """The white probe's radiance-meter sensor and white square (dict or XML)."""
    c, o, h = (list(map(float, probe["center"])), list(map(float, probe["camera"])), float(probe["half_size"]))
    d = np.subtract(c, o)
    up = [0.0, 1.0, 0.0] if abs(d[1]) < 0.9 * np.linalg.norm(d) else [1.0, 0.0, 0.0]
    if as_xml:
        def v(x):
            return ",".join(repr(float(t)) for t in x)
        sensor = (f'<sensor type="radiancemeter"><transform name="to_world"><lookat origin="{v(o)}" target="{v(c)}" '
                  f'up="{v(up)}"/></transform><!--cfa:film--><!--cfa:sampler--></sensor>')
        shape = (f'<shape type="rectangle"><transform name="to_world"><scale value="{h!r}"/><lookat origin="{v(c)}" '
                 f'target="{v(o)}" up="{v(up)}"/></transform><bsdf type="diffuse"><spectrum name="reflectance" value="1"/>'
                 f'</bsdf></shape>')
        return sensor + shape
    T = mi.ScalarTransform4f
    sensor = {"type": "radiancemeter", "to_world": T().look_at(origin=o, target=c, up=up)}
    shape = {"type": "rectangle", "to_world": T().look_at(origin=c, target=o, up=up).scale(h),
             "bsdf": {"type": "diffuse", "reflectance": {"type": "uniform", "value": 1.0}}}
    return sensor, {"cfa_white_probe": shape}


def _load(mi, built: Built, film: dict, sampler: dict, integrator: dict, probe: dict | None = None):
    """A Mitsuba scene of ``built`` with our film, sampler and integrator;
    with ``probe``, the white probe's radiance meter replaces the camera."""
    if built.xml is not None:
        sensor = _probe_parts(mi, probe, True) if probe is not None else built.xml_sensor
        xml = (built.xml.replace("<!--cfa:sensor-->", sensor)
               .replace("<!--cfa:film-->", _xml_element("film", film))
               .replace("<!--cfa:sampler-->", _xml_element("sampler", sampler))
               .replace("<!--cfa:integrator-->", _xml_element("integrator", integrator)))
        resolver = mi.Thread.thread().file_resolver()
        if built.xml_dir is not None and str(built.xml_dir) not in [str(p) for p in resolver]:
            resolver.prepend(str(built.xml_dir))
        try:
            return mi.load_string(xml)
        except Exception as exc:  # Mitsuba reports parse/plugin errors as RuntimeError
            raise CfaMitsubaError(f"Mitsuba cannot load the scene: {_first_line(exc)}") from None
    sensor, extra = _probe_parts(mi, probe, False) if probe is not None else (built.sensor, {})
    d = {"type": "scene", **built.objects, **extra, "integrator": integrator,
         "sensor": {**sensor, "film": film, "sampler": sampler}}
    return mi.load_dict(d)


def _probe_load_settings(width: int, height: int) -> tuple[dict, dict, dict]:
    """Film, sampler and integrator for loading a scene only to inspect it
    (field of view, first hits): stock plugins, valid in every variant."""
    return ({"type": "hdrfilm", "width": int(width), "height": int(height), "rfilter": {"type": "box"}},
            {"type": "independent", "sample_count": 1},
            {"type": "path", "max_depth": 2})


def _first_line(exc: Exception) -> str:
    text = " ".join(str(exc).split())
    return text[:300]


def _band_boxes(cfg: RenderConfig, achromatic: bool) -> list[tuple[float, float]]:
    edges = spectra.band_edges(cfg.wl)
    if achromatic:
        return [(float(edges[0]), float(edges[-1]))]
    return [(float(a), float(b)) for a, b in zip(edges[:-1], edges[1:])]


def _render_boxes(mi, built: Built, cfg: RenderConfig, sc: Scene, boxes, *, width, height, spp,
                  probe: dict | None = None) -> np.ndarray:
    """Render band means over ``boxes`` ((lo, hi) nm each): (height, width, len(boxes)) float32."""
    sampler = {"type": sc.sampler, "sample_count": int(spp), "seed": int(cfg.seed), "jitter": bool(sc.jitter)}
    if cfg.variant.startswith("scalar"):
        planes = []
        for lo, hi in boxes:
            # The same sampled range as the JIT route (light.BAND_INSET).
            lo, hi = lo + BAND_INSET * (hi - lo), hi - BAND_INSET * (hi - lo)
            film = {"type": "specfilm", "width": width, "height": height, "rfilter": {"type": "box"},
                    "component_format": "float32",
                    "band": {"type": "regular", "wavelength_min": lo, "wavelength_max": hi,
                             "values": f"{1 / (hi - lo)!r}, {1 / (hi - lo)!r}"}}
            scene = _load(mi, built, film, sampler, {"type": "path", "max_depth": cfg.max_depth}, probe)
            img = np.array(mi.render(scene, seed=cfg.seed), dtype=np.float32)
            planes.append(img.reshape(height, width, -1)[..., 0])
        return np.stack(planes, axis=-1)
    edges = [boxes[0][0]] + [hi for _, hi in boxes]
    if any(abs(boxes[i][1] - boxes[i + 1][0]) > 1e-9 for i in range(len(boxes) - 1)):
        raise ValueError("band boxes must be contiguous")
    film = {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
            "pixel_format": "luminance", "component_format": "float32"}
    inset = CENTRE_INSET if built.band_constant else BAND_INSET
    integrator = {"type": PLUGIN_NAME, "band_edges": ",".join(repr(float(e)) for e in edges),
                  "band_inset": inset, "max_depth": cfg.max_depth}
    scene = _load(mi, built, film, sampler, integrator, probe)
    img = np.array(mi.render(scene, seed=cfg.seed), dtype=np.float32)
    n = len(boxes)
    if img.ndim != 3 or img.shape[2] < n:
        raise RuntimeError(f"unexpected film output of shape {img.shape} for {n} bands")
    return img[..., -n:]  # the AOVs follow the film's own channels


def _measure_white(mi, built: Built, cfg: RenderConfig, sc: Scene) -> np.ndarray:
    """Radiance of the white probe patch (3D scenes), (B,) W/(m^2 sr nm).

    Direct light only (a path depth of 2): the reference white is the
    scene's lights as they reach the subject, not tinted by what nearby
    surfaces reflect (that is the scene's content, which the camera must
    reproduce, not balance away)."""
    import dataclasses

    boxes = _band_boxes(cfg, achromatic=False)
    direct = dataclasses.replace(cfg, max_depth=2)
    out = _render_boxes(mi, built, direct, sc, boxes, width=1, height=1, spp=WHITE_PROBE_SPP, probe=built.white_probe)
    return out.reshape(-1).astype(np.float64)


# ---------------------------------------------------------------- rendering

def render_canonical(scene, **settings) -> SpectralImage:
    """Render at the canonical scale (see :mod:`.light`), float32-rounded,
    without the luminance fields: the form the cache stores.  Writes no
    files.  ``settings`` as :func:`resolve_settings`."""
    sc, cfg = resolve_settings(scene, **settings)
    return _render_canonical(sc, cfg)


def _render_canonical(sc: Scene, cfg: RenderConfig) -> SpectralImage:
    from ..io.cache import hash_key

    mi = _variant.load(cfg.variant)
    key = hash_key(_key_fields(sc, cfg))
    built = sc.build(cfg)
    start = time.perf_counter()
    achromatic = built.pattern_spectrum is not None
    bands = _render_boxes(mi, built, cfg, sc, _band_boxes(cfg, achromatic), width=cfg.width,
                          height=cfg.height, spp=cfg.spp)
    if achromatic:
        data = bands[..., :1].astype(np.float64) * np.asarray(built.pattern_spectrum)[None, None, :]
    else:
        data = bands.astype(np.float64)
    white = built.white_radiance if built.white_radiance is not None else _measure_white(mi, built, cfg, sc)
    elapsed = time.perf_counter() - start
    data = data.astype(np.float32).astype(np.float64)
    bad = int(data.size - np.count_nonzero(np.isfinite(data)))
    if bad:  # a scene file with an infinite (or float32-overflowing) emitter or texture value
        raise CfaMitsubaError(
            f"the render of {sc.name!r} has {bad} NaN or infinite radiance values: check the scene's emitters "
            "and textures for infinite or huge (> 3e38) values")
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
        "canonical_white_radiance": np.asarray(white, dtype=np.float64).tolist(),
        "spp": cfg.spp,
        "sampler": sc.sampler,
        "sampler_jitter": sc.jitter,
        "max_depth": cfg.max_depth,
        "variant": cfg.variant,
        "seed": cfg.seed,
        "render_time_s": round(elapsed, 3),
        "cache_key": key,
        "metrics": list(sc.metrics),
        "renderer": f"mitsuba {mi.__version__}",
        **built.meta,
    }
    return SpectralImage(data, wl, meta)


def scale_to_luminance(canonical: SpectralImage, luminance_cd_m2: float) -> SpectralImage:
    """Scale a canonical render so that its mean luminance is
    ``luminance_cd_m2`` (ISETCam sceneAdjustLuminance, 'mean'), scaling the
    white radiance by the same factor (reflectances are preserved)."""
    wl = canonical.wavelengths
    mean = float(spectra.luminance_cd_m2(canonical.data, wl).mean())
    if not mean > 0:
        raise CfaMitsubaError(
            f"scene {canonical.meta.get('scene')!r} renders black (mean luminance 0): no light reaches the camera"
        )
    factor = float(luminance_cd_m2) / mean
    meta = dict(canonical.meta)
    white = np.asarray(meta.pop("canonical_white_radiance"), dtype=np.float64) * factor
    meta.update({
        "luminance_cd_m2": float(luminance_cd_m2),
        "white_radiance": white.tolist(),
        "white_luminance_cd_m2": float(spectra.luminance_cd_m2(white, wl)),
        "scale_from_canonical": factor,
    })
    return SpectralImage(canonical.data * factor, np.asarray(wl, dtype=np.float64), meta)


def render(scene, **settings) -> SpectralImage:
    """Render ``scene`` (a built-in name, a path to a Mitsuba 3 XML file, or
    a :class:`Scene`) to band-mean spectral radiance in W/(m^2 sr nm).

    Pure: writes no files and does not use the cache (see
    :func:`render_cached`).  ``settings`` are the keywords of
    :func:`resolve_settings`.  Returns a :class:`SpectralImage` whose
    ``meta`` is the sidecar (docs/scenes.md lists its keys).
    """
    if is_measured_image(scene):  # a measured spectral image: converted, not rendered
        return measured_image(scene, **settings)
    sc, cfg = resolve_settings(scene, **settings)
    return scale_to_luminance(_render_canonical(sc, cfg), cfg.luminance_cd_m2)


def render_cached(scene, *, cache=None, **settings) -> SpectralImage:
    """:func:`render` through the render cache: reuse the cached canonical
    render for these settings if there is one, else render and store it.

    ``cache``: a :class:`~cfa_mitsuba.io.cache.RenderCache`, a directory, or
    None for the default (``$CFA_MITSUBA_CACHE`` or ``~/.cache/cfa-mitsuba``).
    The result's ``meta["cache_reused"]`` says whether this call reused a render.
    Concurrent callers with the same settings render once (a per-key lock).
    """
    from ..io.cache import RenderCache, hash_key

    if is_measured_image(scene):  # a measured spectral image: converted once, cached like a render
        return measured_cached(scene, cache=cache, **settings)
    sc, cfg = resolve_settings(scene, **settings)
    store = cache if isinstance(cache, RenderCache) else RenderCache(cache)
    key = hash_key(_key_fields(sc, cfg))
    canonical, hit = store.get_or_create(key, lambda: _render_canonical(sc, cfg))
    out = scale_to_luminance(canonical, cfg.luminance_cd_m2)
    out.meta["cache_reused"] = hit
    return out
