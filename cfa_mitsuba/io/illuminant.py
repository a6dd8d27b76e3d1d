"""Illuminants named by users and files: a colour-science name, a CSV of
(nm, relative power), or a JCGT spectrum attribute.

A measured reflectance cube becomes radiance only under a light, and the
white balance of an emissive image needs the light it was lit by; both come
from here, with a label saying where the spectrum came from (printed as a
notice, so no illuminant is assumed silently).
"""

from __future__ import annotations

__all__ = ["Illuminant", "resolve_illuminant", "illuminant_from_attribute", "default_illuminant"]

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError


@dataclass(frozen=True)
class Illuminant:
    """A light's spectrum as tabulated: ``wavelengths`` (N,) nm ascending,
    ``values`` (N,) relative power (or, with ``absolute``, the radiance of
    a perfect white diffuser in the cube's own units, as ISETCam stores a
    scene's illuminant), ``label`` where it came from (for notices and the
    sidecar's ``illuminant``)."""

    wavelengths: np.ndarray
    values: np.ndarray
    label: str
    absolute: bool = False


def _checked(wl, values, where: str, label: str, absolute: bool = False) -> Illuminant:
    wl = np.asarray(wl, dtype=np.float64).reshape(-1)
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    if wl.size < 2 or wl.size != v.size:
        raise CfaMitsubaError(f"{where}: needs at least 2 (wavelength, value) pairs, one value per wavelength")
    if not (np.all(np.isfinite(wl)) and np.all(np.isfinite(v))):
        raise CfaMitsubaError(f"{where}: NaN or infinite wavelengths or values")
    if not np.all(np.diff(wl) > 0):
        raise CfaMitsubaError(f"{where}: wavelengths must be strictly ascending")
    if np.any(v < 0) or not np.any(v > 0):
        raise CfaMitsubaError(f"{where}: power must be non-negative and not all zero")
    return Illuminant(wl, v, label, absolute)


def default_illuminant() -> Illuminant:
    """CIE D65 as colour-science tabulates it (300-780 nm at 5 nm)."""
    wl, v = spectra.illuminant_table("D65")
    return Illuminant(wl, v, "D65")


def resolve_illuminant(spec, base: Path | None = None) -> Illuminant:
    """An illuminant from a colour-science name (``D65``, ``A``, ``FL2``,
    ...) or a CSV file of ``wavelength_nm,relative_power`` rows (a header
    line is allowed); a relative path is taken from ``base``.  Refused in one
    line: unknown names, unreadable or malformed files."""
    text = str(spec).strip()
    colour = spectra._colour()
    if text in colour.SDS_ILLUMINANTS:
        wl, v = spectra.illuminant_table(text)
        return Illuminant(wl, v, text)
    p = Path(text)
    if base is not None and not p.is_absolute():
        p = base / p
    if p.suffix.lower() != ".csv" or not p.exists():
        known = ", ".join(sorted(colour.SDS_ILLUMINANTS)[:10])
        raise CfaMitsubaError(f"unknown illuminant {text!r}: not a colour-science name (e.g. {known}, ...) "
                              "nor an existing .csv file")
    from .guard import read_text

    lines = read_text(p, "illuminant file").splitlines()  # regular file, bounded, strict UTF-8
    rows = []
    for i, line in enumerate(lines):
        cells = [c.strip() for c in re.split(r"[,;\t]", line) if c.strip()]
        if not cells or line.lstrip().startswith("#"):
            continue
        try:
            rows.append((float(cells[0]), float(cells[1])))
        except (ValueError, IndexError):
            if rows or i > 1:
                raise CfaMitsubaError(f"illuminant file {str(p)!r}, line {i + 1}: expected 'wavelength_nm,value'") from None
    if not rows:
        raise CfaMitsubaError(f"illuminant file {str(p)!r} has no 'wavelength_nm,value' rows")
    wl, v = zip(*rows)
    return _checked(wl, v, f"illuminant file {str(p)!r}", f"{p.name} (CSV)")


_PAIR = re.compile(r"^\s*([-+0-9.,eE]+)\s*nm\s*:\s*([-+0-9.eE]+)\s*$")


def illuminant_from_attribute(text: str, where: str) -> Illuminant | None:
    """The ``illuminant`` header attribute colour-science writes into a
    spectral EXR (``"300.0000000nm:0.0341000;305.0000000nm:..."``), or None
    when ``text`` is not in that form."""
    pairs = []
    for item in str(text).split(";"):
        if not item.strip():
            continue
        m = _PAIR.match(item)
        if m is None:
            return None
        try:
            pairs.append((float(m[1].replace(",", ".")), float(m[2])))
        except ValueError:
            return None
    if len(pairs) < 2:
        return None
    wl, v = zip(*pairs)
    light = _checked(wl, v, f"{where}: 'illuminant' attribute", "the file's 'illuminant' attribute")
    name = _known_name(light)
    return Illuminant(light.wavelengths, light.values, f"{name} (the file's 'illuminant' attribute)") if name else light


def _known_name(light: Illuminant) -> str | None:
    """The colour-science illuminant a tabulated light equals (to 0.1 % of
    its peak, on its own wavelengths inside the table's range), if any."""
    colour = spectra._colour()
    for name in ("D65", "A", "D50", "E", *sorted(colour.SDS_ILLUMINANTS)):
        sd = colour.SDS_ILLUMINANTS[name]
        wl, ref = np.asarray(sd.wavelengths, float), np.asarray(sd.values, float)
        inside = (light.wavelengths >= wl[0]) & (light.wavelengths <= wl[-1])
        if inside.sum() < 2:
            continue
        mine = light.values[inside]
        theirs = np.interp(light.wavelengths[inside], wl, ref)
        k = float(theirs @ mine) / max(float(theirs @ theirs), 1e-300)
        if np.max(np.abs(mine - k * theirs)) <= 1e-3 * float(mine.max()):
            return name
    return None
