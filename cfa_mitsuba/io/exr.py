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

The reader accepts any file of this layout: emissive ``S0`` channels with any
number format and SI-prefixed metre or hertz unit, sorted by wavelength.
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
import re
from pathlib import Path

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError
from ..values import SpectralImage
from .atomic import atomic_output
from .sidecar import json_default, read_sidecar, sidecar_path
from .validate import check_sidecar, load_json_text

#: Units of the band values, as our metadata states them.
SPECTRAL_UNITS = "W/(m^2 sr nm)"
#: The JCGT layout's ``emissiveUnits`` string for spectral radiance.
_EMISSIVE_UNITS = "W.m^-2.sr^-1"
#: Name of our JSON header attribute (shared with io.images).
_META_ATTRIBUTE = "cfaMitsuba"

# JCGT 2021, s. 3: S<stokes>.<value><SI prefix><m|Hz>, comma as decimal mark.
_CHANNEL_RE = re.compile(
    r"^S0\.(?P<value>\d*,?\d*(?:[Ee][+-]?\d+)?)(?P<prefix>Y|Z|E|P|T|G|M|k|h|da|d|c|m|u|n|p)?(?P<unit>m|Hz)$"
)
# SI prefix -> power of ten relative to the unit.
_PREFIX_EXP = {
    "Y": 24, "Z": 21, "E": 18, "P": 15, "T": 12, "G": 9, "M": 6, "k": 3, "h": 2,
    "da": 1, None: 0, "d": -1, "c": -2, "m": -3, "u": -6, "n": -9, "p": -12,
}


def spectral_channel_name(wavelength_nm: float) -> str:
    """JCGT channel name of an unpolarised emissive band.

    >>> spectral_channel_name(400)
    'S0.400,000000nm'
    """
    return "S0." + f"{float(wavelength_nm):.6f}".replace(".", ",") + "nm"


def parse_spectral_channel(name: str) -> float | None:
    """Wavelength in nm of a JCGT ``S0`` channel name, or None if ``name`` is
    not one (other Stokes components, reflective ``T.`` channels, R/G/B).

    >>> parse_spectral_channel('S0.550,0nm'), parse_spectral_channel('S0.5.5E-7m')
    (550.0, None)
    >>> parse_spectral_channel('S0.0,55um')
    550.0
    """
    m = _CHANNEL_RE.match(name)
    if m is None or not any(ch.isdigit() for ch in m["value"]):
        return None
    value = float(m["value"].replace(",", "."))
    exp = _PREFIX_EXP[m["prefix"]]
    if m["unit"] == "Hz":
        hertz = value * 10.0**exp
        return spectra.LIGHT_SPEED_M_S / hertz * 1e9 if hertz > 0 else None
    # Scale by an exact power of ten so that 'S0.400,000000nm' gives 400.0 exactly.
    return value * 10.0 ** (exp + 9) if exp + 9 >= 0 else value / 10.0 ** (-(exp + 9))


def linear_srgb(data: np.ndarray, wavelengths, meta: dict) -> np.ndarray:
    """Linear sRGB (IEC 61966-2-1 primaries, D65 white) of band radiance
    (H, W, B) in W/(m^2 sr nm), scaled so that the scene's white diffuser
    (``meta['white_luminance_cd_m2']``) has Y = 1; without it, so that the
    image's mean is an 18 % grey.  No chromatic adaptation: D65 is both our
    scenes' illuminant and sRGB's white."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour

    xyz = spectra.xyz_from_radiance(data, wavelengths)
    white = meta.get("white_luminance_cd_m2")
    if not white or not np.isfinite(white) or white <= 0:
        mean_y = float(xyz[..., 1].mean())
        white = mean_y / 0.18 if mean_y > 0 else 1.0
    m = np.asarray(colour.models.RGB_COLOURSPACE_sRGB.matrix_XYZ_to_RGB)
    return (xyz / white) @ m.T


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
            f.write(str(tmp))
    return p


def _decode(value):
    return value.decode() if isinstance(value, bytes) else value


def read_spectral_exr(path) -> SpectralImage:
    """Read a JCGT spectral EXR into a :class:`SpectralImage`.

    Bands are the ``S0`` channels sorted by wavelength (nm).  ``meta`` is the
    sidecar JSON beside the file (``X.json`` for ``X.exr``) when present, else
    the ``cfaMitsuba`` header attribute, else a minimal dict; its
    ``wavelengths`` always match the file.  NaN or infinite values are
    refused with a :class:`CfaMitsubaError` naming their count.
    """
    p = Path(path)
    if not p.exists():
        raise CfaMitsubaError(f"no such file: {str(p)!r}")
    if p.is_dir():
        raise CfaMitsubaError(f"{str(p)!r} is a directory, not a spectral EXR")
    import OpenEXR

    try:
        with OpenEXR.File(str(p), separate_channels=True) as f:
            header = {k: _decode(v) for k, v in f.header().items()}
            bands = []
            for name, ch in f.channels().items():
                wl = parse_spectral_channel(name)
                if wl is not None:
                    bands.append((wl, name, np.asarray(ch.pixels, dtype=np.float64)))
    except CfaMitsubaError:
        raise
    except Exception as exc:  # OpenEXR raises plain exceptions on bad files
        raise CfaMitsubaError(f"{str(p)!r} is not a readable OpenEXR file: {' '.join(str(exc).split())}") from None
    if not bands:
        raise CfaMitsubaError(f"{str(p)!r} has no emissive spectral channels (S0.<wavelength>nm): not a spectral EXR")
    bands.sort(key=lambda t: t[0])
    wl = np.array([b[0] for b in bands])
    if np.any(np.diff(wl) <= 0):
        raise CfaMitsubaError(f"{str(p)!r}: two spectral channels have the same wavelength")
    data = np.stack([b[2] for b in bands], axis=-1)
    bad = int(data.size - np.count_nonzero(np.isfinite(data)))
    if bad:
        raise CfaMitsubaError(f"{str(p)!r} contains {bad} NaN or infinite value(s) in its spectral channels")

    side = sidecar_path(p)
    if side.exists():
        meta = read_sidecar(side)
    else:
        raw = header.get(_META_ATTRIBUTE)
        what = f"{str(p)!r}'s {_META_ATTRIBUTE} attribute"
        meta = check_sidecar(load_json_text(raw, what), what) if isinstance(raw, str) else {}
    if not meta:
        meta = {"units": SPECTRAL_UNITS if header.get("emissiveUnits", _EMISSIVE_UNITS) == _EMISSIVE_UNITS else header.get("emissiveUnits")}
    if "wavelengths" in meta and len(meta["wavelengths"]) != wl.size:
        raise CfaMitsubaError(
            f"{str(side if side.exists() else p)!r} lists {len(meta['wavelengths'])} wavelengths "
            f"but {str(p)!r} has {wl.size} spectral channels"
        )
    meta["wavelengths"] = [float(v) for v in wl]
    meta.setdefault("height", int(data.shape[0]))
    meta.setdefault("width", int(data.shape[1]))
    return SpectralImage(data, wl, meta)


def spectral_exr_size(path) -> tuple[int, int, int]:
    """(height, width, spectral bands) of an EXR, from its header alone."""
    import OpenEXR

    try:
        with OpenEXR.File(str(path), header_only=True) as f:  # the header is the file's: read it while open
            header = f.header()
            (x0, y0), (x1, y1) = (tuple(int(v) for v in c) for c in header["dataWindow"])
            bands = sum(1 for c in header.get("channels", ()) if parse_spectral_channel(c.name) is not None)
    except Exception as exc:  # OpenEXR raises plain exceptions on bad files
        raise CfaMitsubaError(f"{str(path)!r} is not a readable OpenEXR file: {' '.join(str(exc).split())[:200]}") from None
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
