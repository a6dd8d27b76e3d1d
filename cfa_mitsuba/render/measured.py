"""Measured spectral images as scenes: a file or folder -> a SpectralImage.

Nothing is rendered: the cube (any format of :mod:`cfa_mitsuba.io.hyperspectral`)
is put on the band grid (:func:`cfa_mitsuba.io.cube.cube_to_radiance`: exact
box means of the linearly interpolated source, times the illuminant for a
reflectance cube) and given the sidecar a render has (field of view,
distance, oversampling, white radiance, its kind: natural), then
scaled to the requested mean luminance as renders are
(:func:`.engine.scale_to_luminance`).  Through :func:`measured_cached` the
canonical image is kept in the render cache, keyed by the file's content and
every option, so a study converts each image once.
"""

from __future__ import annotations

__all__ = ["MEASURED_OPTIONS", "is_measured_image", "measured_canonical", "measured_image", "measured_cached",
           "measured_key"]

import hashlib
import time
from pathlib import Path

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError
from ..io.hyperspectral import is_measured_path
from ..values import SpectralImage
from .types import MAX_FOV_DEG, NATURAL

#: Options of a measured image (the render command's flags, a study's keys).
MEASURED_OPTIONS = ("bands", "illuminant", "fov", "distance", "oversample", "wavelengths", "quantity", "mat_cube",
                    "mat_wavelengths", "width", "height")
#: Render settings that mean nothing for a measured image (no Mitsuba run).
_RENDER_ONLY = ("spp", "seed", "variant", "max_depth")
#: The optics stage's defaults (docs/sensor.md), used when neither a flag
#: nor the file gives the field of view or the distance.
_DEFAULT_FOV_DEG, _DEFAULT_DISTANCE_M = 10.0, 1.2
#: Bump when a change alters converted numbers in a way the source digest cannot see.
_CODE_VERSION = "1"


def is_measured_image(scene) -> bool:
    """Whether ``scene`` names a measured image (a .exr, .hdr or .mat file,
    or a folder) rather than a built-in scene or a Mitsuba XML; a built-in
    name wins over a folder of that name in the working directory."""
    from .registry import list_scenes

    if not isinstance(scene, (str, Path)) or str(scene) in {n for n, _ in list_scenes()}:
        return False
    return is_measured_path(scene)


def _source_files(p: Path) -> list[Path]:
    if p.is_dir():
        return sorted(f for f in p.iterdir() if f.suffix.lower() == ".png" and f.is_file())
    files = [p]
    if p.suffix.lower() == ".hdr":  # the ENVI data file beside it
        files += sorted(f for f in p.parent.glob(p.stem + ".*") if f != p and f.suffix.lower() != ".json")
    elif p.suffix.lower() == ".exr" and p.with_suffix(".json").exists():
        files.append(p.with_suffix(".json"))
    return files


def _digest(files: list[Path]) -> str:
    from ..io.guard import open_regular

    h = hashlib.sha256()
    for f in files:
        h.update(f.name.encode())
        with open_regular(f, "measured image file") as fh:  # a FIFO beside an ENVI header is refused, not read
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                h.update(chunk)
    return h.hexdigest()


def _code_digest() -> str:
    from ..io.guard import read_bytes

    h = hashlib.sha256(_CODE_VERSION.encode())
    io_dir = Path(__file__).parents[1] / "io"
    for f in [Path(__file__), Path(__file__).parents[1] / "spectra.py",
              *(io_dir / n for n in ("cube.py", "hyperspectral.py", "jcgt.py", "envi.py", "png_bands.py", "matlab.py",
                                     "illuminant.py"))]:
        h.update(read_bytes(f, "package file"))
    return h.hexdigest()[:16]


def _resolve(path, options: dict) -> tuple[Path, dict]:
    """Check the options; returns the path and the options with the
    illuminant resolved (an Illuminant or None) and the grid as a tuple."""
    from ..io.illuminant import Illuminant, resolve_illuminant

    unknown = sorted(set(options) - set(MEASURED_OPTIONS) - set(_RENDER_ONLY) - {"luminance"})
    if unknown:
        raise CfaMitsubaError(f"unknown option(s) for a measured image: {', '.join(unknown)}")
    p = Path(path)
    if not p.exists():
        raise CfaMitsubaError(f"no such file or folder: {str(p)!r}")
    opts = {k: options.get(k) for k in MEASURED_OPTIONS}
    bands = opts["bands"]
    grid = spectra.parse_band_grid(bands) if isinstance(bands, str) else spectra.validate_wavelengths(
        spectra.DEFAULT_WAVELENGTHS if bands is None else bands)
    opts["bands"] = tuple(float(v) for v in grid)
    ill = opts["illuminant"]
    if ill is not None and not isinstance(ill, Illuminant):
        opts["illuminant"] = resolve_illuminant(ill)
    for k in ("fov", "distance"):
        v = opts[k]
        if v is not None and not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
            raise CfaMitsubaError(f"--{k} must be a positive number, got {v!r}")
    if opts["fov"] is not None and opts["fov"] >= MAX_FOV_DEG:
        raise CfaMitsubaError(f"--fov must be below {MAX_FOV_DEG:g} degrees, got {opts['fov']:g}")
    k = opts["oversample"]
    if k is not None and (isinstance(k, bool) or not isinstance(k, int) or not 1 <= k <= 64):
        raise CfaMitsubaError(f"--oversample must be an integer in 1..64, got {k!r}")
    return p, opts


def measured_key(path, **options) -> str:
    """The cache key of a measured image: its files' content, every option
    and this conversion's source code."""
    from ..io.cache import hash_key

    p, opts = _resolve(path, options)
    ill = opts.pop("illuminant")
    fields = {"kind": "measured", "code": _code_digest(), "files": _digest(_source_files(p)), **opts,
              "wavelengths": None if opts["wavelengths"] is None else str(opts["wavelengths"]),
              "illuminant": None if ill is None else [ill.label, ill.wavelengths.tolist(), ill.values.tolist()]}
    return hash_key(fields)


def measured_canonical(path, **options) -> SpectralImage:
    """The measured image on the band grid, before luminance scaling (the
    form the cache stores; ``meta['canonical_white_radiance']``)."""
    from ..io.cube import cube_to_radiance, on_grid
    from ..io.hyperspectral import load_cube

    p, o = _resolve(path, options)
    t0 = time.perf_counter()
    cube = load_cube(p, wavelengths=o["wavelengths"], quantity=o["quantity"], mat_cube=o["mat_cube"],
                     mat_wavelengths=o["mat_wavelengths"], illuminant_given=o["illuminant"] is not None)
    h, w = int(cube.data.shape[0]), int(cube.data.shape[1])
    for name, given, real in (("width", o["width"], w), ("height", o["height"], h)):
        if given is not None and int(given) != real:
            raise CfaMitsubaError(f"--{name} {given}: a measured image keeps its size ({w} x {h}); crop or bin it first")
    grid = np.asarray(o["bands"])
    radiance, white, label, notices = cube_to_radiance(cube, grid, o["illuminant"], "--illuminant")
    radiance = radiance.astype(np.float32).astype(np.float64)  # the cache's precision: fresh == cached
    if not float(spectra.luminance_cd_m2(radiance, grid).mean()) > 0:
        raise CfaMitsubaError(f"{cube.source}: the image is black (mean luminance 0)")
    fov, fov_from = next((v, s) for v, s in ((o["fov"], "--fov"), (cube.fov_deg, "the file"),
                                             (_DEFAULT_FOV_DEG, "default; pass --fov")) if v is not None)
    dist, dist_from = next((v, s) for v, s in ((o["distance"], "--distance"), (cube.distance_m, "the file"),
                                               (_DEFAULT_DISTANCE_M, "default; pass --distance")) if v is not None)
    notices.append(f"field of view {fov:g} deg ({fov_from}), distance {dist:g} m ({dist_from})")
    k = o["oversample"] or 1
    product = " times the illuminant's (box mean of the product)" if cube.quantity == "reflectance" else ""
    meta = {
        "scene": p.stem if not p.is_dir() else p.name,
        "width": w,
        "height": h,
        "fov_deg": float(fov),
        "oversample": int(k),
        "wavelengths": [float(v) for v in grid],
        "band_edges_nm": spectra.band_edges(grid).tolist(),
        "units": "W/(m^2 sr nm)",
        "band_definition": ("the source's own samples at the band centres (band values, passed through "
                            "unchanged)" + product.replace("(box mean of the product)", "band means")
                            if on_grid(np.asarray(cube.wavelengths, dtype=np.float64), grid) is not None else
                            "box mean over the band's edges of the source spectrum linearly interpolated between "
                            "its tabulated wavelengths" + product),
        "band_constant_spectra": False,
        "illuminant": label,
        "canonical_white_radiance": [float(v) for v in white],
        "scene_distance_m": float(dist),
        "renderer": "measured spectral image (no rendering)",
        "source": {"path": str(p.resolve()), "what": cube.source, "quantity": cube.quantity,
                   "bands": int(cube.data.shape[2]), "wavelengths_nm": [float(cube.wavelengths[0]),
                                                                          float(cube.wavelengths[-1])]},
        "read_notices": notices,
        "render_time_s": round(time.perf_counter() - t0, 3),
        "kind": NATURAL,
        "geometry": {},
    }
    return SpectralImage(radiance, grid.copy(), meta)


def measured_image(path, *, luminance=None, **options) -> SpectralImage:
    """:func:`measured_canonical` scaled to a mean luminance (cd/m^2, default
    100), as :func:`.engine.render`; writes no files."""
    from .scaling import DEFAULT_LUMINANCE_CD_M2, scale_to_luminance

    img = measured_canonical(path, **options)
    img.meta["cache_key"] = measured_key(path, **options)
    return scale_to_luminance(img, DEFAULT_LUMINANCE_CD_M2 if luminance is None else float(luminance))


def measured_cached(path, *, cache=None, luminance=None, **options) -> SpectralImage:
    """:func:`measured_image` through the render cache (a
    :class:`~cfa_mitsuba.io.cache.RenderCache`, a directory or None for the
    default); ``meta['cache_reused']`` says whether the cache had it."""
    from ..io.cache import RenderCache
    from .scaling import DEFAULT_LUMINANCE_CD_M2, scale_to_luminance

    lum = DEFAULT_LUMINANCE_CD_M2 if luminance is None else float(luminance)
    if not (np.isfinite(lum) and lum > 0):
        raise CfaMitsubaError(f"luminance (--luminance) must be a positive number, got {luminance!r}")
    key = measured_key(path, **options)
    store = cache if isinstance(cache, RenderCache) else RenderCache(cache)

    def make():
        img = measured_canonical(path, **options)
        img.meta["cache_key"] = key
        return img

    canonical, hit = store.get_or_create(key, make)
    out = scale_to_luminance(canonical, lum)
    out.meta["cache_reused"] = hit
    return out
