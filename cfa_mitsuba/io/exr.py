"""Spectral OpenEXR in the JCGT layout (Fichet, Pacanowski, Wilkie, "An
OpenEXR Layout for Spectral Images", JCGT 10(3), 2021).

Layout written here (research/mitsuba-spectral.md s. 6):

- one float32 channel per band, named ``S0.<wavelength in nm with a comma as
  decimal separator>nm`` (``S0.400,000000nm``), holding band-mean spectral
  radiance in W/(m^2 sr nm) (never float16: it keeps only 3 digits);
- string attributes ``spectralLayoutVersion`` = ``"1.0"`` and
  ``emissiveUnits`` = ``"W.m^-2.sr^-1"`` (the layout's unit string; it has no
  nm^-1, so our JSON says ``"units": "W/(m^2 sr nm)"`` explicitly);
- ``R``, ``G``, ``B``: a linear-sRGB preview (display white = the scene's
  white diffuser where the metadata gives it);
- ``cfaMitsuba``: our JSON metadata (the render settings and scene geometry,
  the same content as the sidecar).

The reader accepts any file of this layout, as it says (:mod:`.jcgt`):
emissive ``S0`` channels with any number format and SI-prefixed metre or
hertz unit, sorted by wavelength, in the unit ``emissiveUnits`` names;
reflective ``T.`` channels lit by an illuminant; bands outside 360..830 nm
cropped onto the band grid.  A file without our metadata gets its light
from the caller or the file, with a notice (:class:`~.cube.ReadNotice`).
"""

from __future__ import annotations

__all__ = [
    "SPECTRAL_UNITS",
    "spectral_channel_name",
    "parse_spectral_channel",
    "read_spectral_exr",
    "write_spectral_exr",
    "spectral_exr_size",
    "check_capture_file",
    "linear_srgb",
]

import json
from pathlib import Path

import numpy as np

from .. import colorimetry, spectra
from ..errors import CfaMitsubaError, one_line
from ..values import SpectralImage
from .atomic import atomic_output, write_error
from .channels import parse_spectral_channel  # noqa: F401  (re-exported: the layout's reader and writer)
from .sidecar import json_default, sidecar_path

#: Units of the band values, as our metadata states them.
SPECTRAL_UNITS = "W/(m^2 sr nm)"
#: The JCGT layout's ``emissiveUnits`` string for spectral radiance.
_EMISSIVE_UNITS = "W.m^-2.sr^-1"
#: Name of our JSON header attribute (shared with io.images).
_META_ATTRIBUTE = "cfaMitsuba"

def spectral_channel_name(wavelength_nm: float) -> str:
    """JCGT channel name of an unpolarised emissive band.

    >>> spectral_channel_name(400)
    'S0.400,000000nm'
    """
    return "S0." + f"{float(wavelength_nm):.6f}".replace(".", ",") + "nm"


def linear_srgb(data: np.ndarray, wavelengths, meta: dict) -> np.ndarray:
    """Linear sRGB (IEC 61966-2-1 primaries, D65 white) of band radiance
    (H, W, B) in W/(m^2 sr nm), scaled so that the scene's white diffuser
    (``meta['white_luminance_cd_m2']``) has Y = 1; without it, so that the
    image's mean is an 18 % grey.  No chromatic adaptation: D65 is both our
    scenes' illuminant and sRGB's white.  The matrix is the one of
    :mod:`cfa_mitsuba.colorimetry`."""
    xyz = spectra.xyz_from_radiance(data, wavelengths)
    white = meta.get("white_luminance_cd_m2")
    if not white or not np.isfinite(white) or white <= 0:
        mean_y = float(xyz[..., 1].mean())
        white = mean_y / 0.18 if mean_y > 0 else 1.0
    return colorimetry.xyz_to_linear(xyz, scale=float(white))


def write_spectral_exr(path, image: SpectralImage, *, preview: bool = True) -> Path:
    """Write ``image`` as a JCGT spectral EXR, atomically.

    ``image.data`` is (H, W, B) band-mean radiance in W/(m^2 sr nm);
    ``image.meta`` goes into the ``cfaMitsuba`` JSON attribute.  Refuses NaN
    or infinite values (a :class:`CfaMitsubaError` naming their count).
    """
    p = Path(path)
    data = np.asarray(image.data)
    wl = np.asarray(image.wavelengths, dtype=np.float64).reshape(-1)
    if wl.size < 1 or not np.all(np.isfinite(wl)) or np.any(wl <= 0) or np.any(np.diff(wl) <= 0):
        raise CfaMitsubaError("spectral image wavelengths must be positive and strictly ascending")
    if data.ndim != 3 or data.shape[2] != wl.size:
        raise CfaMitsubaError(f"spectral image of shape {data.shape} does not match its {wl.size} wavelengths")
    bad = int(data.size - np.count_nonzero(np.isfinite(data)))
    if bad:
        raise CfaMitsubaError(f"refusing to write {str(p)!r}: {bad} NaN or infinite value(s) in the spectral data")
    import OpenEXR

    meta = dict(image.meta)
    meta.setdefault("units", SPECTRAL_UNITS)
    meta["wavelengths"] = [float(v) for v in wl]
    header = {
        "compression": OpenEXR.ZIP_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        "spectralLayoutVersion": "1.0",
        "emissiveUnits": _EMISSIVE_UNITS,
        _META_ATTRIBUTE: json.dumps(meta, default=json_default),
    }
    channels = {spectral_channel_name(w): np.ascontiguousarray(data[..., b], dtype=np.float32) for b, w in enumerate(wl)}
    if preview and wl.size >= 2 and wl[0] - 0.5 * (wl[1] - wl[0]) >= 360 and wl[-1] + 0.5 * (wl[-1] - wl[-2]) <= 830:
        # (the CIE 1931 functions are defined on 360..830 nm only)
        rgb = linear_srgb(data, wl, meta)
        for i, c in enumerate("RGB"):
            channels[c] = np.ascontiguousarray(rgb[..., i], dtype=np.float32)
    with atomic_output(p) as tmp:
        with OpenEXR.File(header, channels) as f:
            try:
                f.write(str(tmp))
            except RuntimeError as exc:  # OpenEXR's C++ error on a full disk or the file-size limit
                raise write_error(tmp, exc) from None
    return p


def read_spectral_exr(path, *, illuminant=None) -> SpectralImage:
    """Read a JCGT spectral EXR into a :class:`SpectralImage`.

    Bands are the ``S0`` channels sorted by wavelength (nm), in W/(m^2 sr
    nm) after the file's ``emissiveUnits`` (:mod:`.jcgt`).  ``meta`` is the
    sidecar JSON beside the file (``X.json`` for ``X.exr``) when present,
    else the ``cfaMitsuba`` header attribute.  A file with neither (written
    by another tool) is read as it says: its light is ``illuminant`` (an
    :class:`~cfa_mitsuba.io.illuminant.Illuminant`, from a flag), else the
    file's ``illuminant`` attribute, else D65, and it sets the white
    reference; a reflective file (``T.`` channels), or one whose bands reach
    outside 360..830 nm, is put on the default band grid (reflectance x the
    light, at a mean luminance of 100 cd/m^2).  How it was read is said in
    :class:`~cfa_mitsuba.io.cube.ReadNotice` warnings.  NaN or infinite
    values are refused with a :class:`CfaMitsubaError` naming their count.
    """
    import warnings

    from .cube import ReadNotice
    from .jcgt import our_meta, read_exr_cube

    p = Path(path)
    cube, header = read_exr_cube(p)
    side = sidecar_path(p)
    meta = dict(our_meta(p, header))
    if meta and cube.quantity == "radiance":
        data = np.asarray(cube.data, dtype=np.float64) * cube.scale
        wl = np.asarray(cube.wavelengths, dtype=np.float64)
        if illuminant is not None:
            cube.notices.append(f"{p.name}: --illuminant ignored: the file's metadata gives its white")
    else:
        data, wl, foreign = _foreign(p, cube, illuminant)
        meta = {**meta, **foreign}
    for note in cube.notices:
        warnings.warn(note, ReadNotice, stacklevel=2)
    bad = int(data.size - np.count_nonzero(np.isfinite(data)))
    if bad:
        raise CfaMitsubaError(f"{str(p)!r} contains {bad} NaN or infinite value(s) in its spectral channels")
    if "wavelengths" in meta and len(meta["wavelengths"]) != wl.size:
        raise CfaMitsubaError(
            f"{str(side if side.exists() else p)!r} lists {len(meta['wavelengths'])} wavelengths "
            f"but {str(p)!r} has {wl.size} spectral channels"
        )
    meta["wavelengths"] = [float(v) for v in wl]
    meta.setdefault("height", int(data.shape[0]))
    meta.setdefault("width", int(data.shape[1]))
    return SpectralImage(data, wl, meta)


#: Mean luminance given to a reflective file lit by its illuminant (cd/m^2),
#: the render stage's default.
_REFLECTIVE_LUMINANCE_CD_M2 = 100.0


def _foreign(p: Path, cube, illuminant) -> tuple[np.ndarray, np.ndarray, dict]:
    """Radiance, wavelengths and metadata of a spectral EXR another tool wrote."""
    from .cube import choose_illuminant, cube_to_radiance, white_radiance

    grid_ok = cube.quantity == "radiance"
    if grid_ok:
        try:
            spectra.validate_wavelengths(cube.wavelengths)
        except CfaMitsubaError:
            grid_ok = False
    if grid_ok:  # the file's own bands, as stored
        data = np.asarray(cube.data, dtype=np.float64) * cube.scale  # NaN refused below; negatives by capture
        wl = np.asarray(cube.wavelengths, dtype=np.float64)
        light, said = choose_illuminant(cube, illuminant, "--illuminant")
        white, note = white_radiance(light, cube, data, wl)
        cube.notices += [said] + ([note] if note else [])
        label = light.label
    else:
        wl = np.asarray(spectra.DEFAULT_WAVELENGTHS, dtype=np.float64)
        data, white, label, notices = cube_to_radiance(cube, wl, illuminant, "--illuminant")
        cube.notices[:] = notices + [f"{p.name}: put on the band grid {wl[0]:g}-{wl[-1]:g} nm, "
                                     f"{wl.size} bands (box means of the linearly interpolated channels)"]
        if cube.quantity == "reflectance":
            factor = _REFLECTIVE_LUMINANCE_CD_M2 / max(float(spectra.luminance_cd_m2(data, wl).mean()), 1e-300)
            data, white = data * factor, white * factor
            cube.notices.append(f"{p.name}: reflectance x illuminant scaled to a mean luminance of "
                                f"{_REFLECTIVE_LUMINANCE_CD_M2:g} cd/m^2")
    meta = {
        "units": SPECTRAL_UNITS,
        "source_quantity": cube.quantity,
        "illuminant": label,
        "white_radiance": [float(v) for v in white],
        "white_luminance_cd_m2": float(spectra.luminance_cd_m2(white, wl)),
        "read_notices": list(cube.notices),
    }
    return data, wl, meta


def spectral_exr_size(path) -> tuple[int, int, int]:
    """(height, width, spectral bands) of an EXR, from its header alone."""
    import OpenEXR

    from .guard import check_regular

    check_regular(path, "OpenEXR file")  # not a FIFO or device

    try:
        with OpenEXR.File(str(path), header_only=True) as f:  # the header is the file's: read it while open
            header = f.header()
            (x0, y0), (x1, y1) = (tuple(int(v) for v in c) for c in header["dataWindow"])
            bands = sum(1 for c in header.get("channels", ()) if parse_spectral_channel(c.name) is not None)
    except Exception as exc:  # OpenEXR raises plain exceptions on bad files
        raise CfaMitsubaError(f"{str(path)!r} is not a readable OpenEXR file: {one_line(exc, 200)}") from None
    return y1 - y0 + 1, x1 - x0 + 1, bands


def check_capture_file(path) -> None:
    """Refuse to capture an EXR whose size (from its header) needs more
    memory than there is (:func:`.limits.estimate_capture_bytes`); a missing
    file is left to the reader's own message."""
    from . import limits

    p = Path(path)
    if not p.is_file():
        return
    h, w, b = spectral_exr_size(p)
    limits.require_memory(limits.estimate_capture_bytes(h, w, b), f"capturing {str(p)!r} ({w} x {h} pixels x {b} bands)")
