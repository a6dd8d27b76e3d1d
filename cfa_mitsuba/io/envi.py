"""ENVI cubes (a ``.hdr`` text header beside a raw data file), read with
the ``spectral`` package (Spectral Python).

The header's ``wavelength`` list gives the band centres, in its
``wavelength units`` (nanometres or micrometres; without units, values
below 30 are taken as micrometres, with a notice); ``--wavelengths``
overrides them.  A ``reflectance scale factor`` divides the stored values.
ENVI does not say whether values are radiance or reflectance
(:mod:`.hyperspectral` decides).
"""

from __future__ import annotations

__all__ = ["read_envi"]

import warnings
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError, one_line
from . import guard
from .cube import SourceCube, check_memory, check_wavelengths

_UNITS_NM = {"nanometers": 1.0, "nanometer": 1.0, "nm": 1.0, "micrometers": 1e3, "micrometer": 1e3, "microns": 1e3,
             "micron": 1e3, "um": 1e3, "\u00b5m": 1e3, "millimeters": 1e6, "mm": 1e6}


def _header_wavelengths(meta: dict, n: int, where: str, notices: list) -> np.ndarray | None:
    raw = meta.get("wavelength")
    if raw is None:
        return None
    try:
        wl = np.array([float(v) for v in raw])
    except (TypeError, ValueError):
        raise CfaMitsubaError(f"{where}: header 'wavelength' holds non-numbers") from None
    units = str(meta.get("wavelength units", "")).strip().lower()
    if units in _UNITS_NM:
        return wl * _UNITS_NM[units]
    if units not in ("", "unknown"):
        raise CfaMitsubaError(f"{where}: unknown 'wavelength units' {meta['wavelength units']!r} "
                              "(nanometers or micrometers)")
    if wl.size and np.nanmax(wl) < 30:
        notices.append(f"{where}: no wavelength units; values below 30 read as micrometres")
        return wl * 1e3
    return wl


def _check_header_against_data(img, where: str) -> None:
    """Refuse a header that contradicts its data file: an interleave other
    than bsq, bil or bip, or a data file whose size is not the header's
    offset plus lines x samples x bands x bytes per sample (ENVI header
    format: ``header offset``, ``lines``, ``samples``, ``bands``,
    ``data type``, ``interleave``)."""
    interleave = str(img.metadata.get("interleave", "bsq")).strip().lower()
    if interleave not in ("bsq", "bil", "bip"):
        raise CfaMitsubaError(f"{where}: header 'interleave = {interleave}' is none of bsq, bil, bip")
    data_file = Path(img.filename)
    size = guard.check_regular(data_file, "ENVI data file").st_size
    rows, cols, n = (int(v) for v in img.shape)
    expect = int(img.offset) + rows * cols * n * int(img.sample_size)
    if size != expect:
        raise CfaMitsubaError(
            f"{where}: the header declares {rows} lines x {cols} samples x {n} bands of {img.sample_size} bytes "
            f"(+ {img.offset} offset) = {expect} bytes, but the data file {data_file.name!r} holds {size}")


def read_envi(path, wavelengths=None) -> SourceCube:
    """Read an ENVI cube by its ``.hdr`` header (module doc); ``wavelengths``
    (nm) replaces the header's list."""
    import spectral.io.envi as envi

    p = Path(path)
    where = f"ENVI cube {str(p)!r}"
    guard.read_text(p, "ENVI header", limit=1 << 20)  # a regular text file (UTF-8), bounded: before spectral parses it
    try:
        img = envi.open(str(p))
    except Exception as exc:  # spectral raises its own exception types, FileNotFoundError included
        raise CfaMitsubaError(f"{where}: cannot open: {one_line(exc)}") from None
    rows, cols, n = (int(v) for v in img.shape)
    notices: list[str] = []
    header_wl = _header_wavelengths(img.metadata, n, where, notices)
    wl = check_wavelengths(header_wl if wavelengths is None else wavelengths, n, where,
                           "the header has no 'wavelength' list: pass --wavelengths")
    check_memory((rows, cols, n), where)
    _check_header_against_data(img, where)
    try:
        with warnings.catch_warnings():  # spectral warns of NaN; check_values refuses them in one line
            warnings.simplefilter("ignore")
            data = np.asarray(img.load())
    except MemoryError:
        raise CfaMitsubaError(f"{where}: too large for memory") from None
    except Exception as exc:  # a data file shorter than the header says
        raise CfaMitsubaError(f"{where}: cannot read its data file: {one_line(exc)}") from None
    scale = 1.0
    factor = img.metadata.get("reflectance scale factor")
    if factor is not None:
        try:
            scale = 1.0 / float(factor)
        except (TypeError, ValueError, ZeroDivisionError):
            raise CfaMitsubaError(f"{where}: bad 'reflectance scale factor' {factor!r}") from None
    return SourceCube(data, wl, "radiance", where, scale=scale, notices=notices)
