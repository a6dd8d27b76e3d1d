"""Reading any JCGT spectral EXR (Fichet, Pacanowski, Wilkie 2021) as it says.

Emissive files (``S0.<wavelength>`` channels) hold spectral radiance in the
unit named by the ``emissiveUnits`` attribute: ``W.m^-2.sr^-1`` (the
layout's string; pbrt, ART, colour-science and ours write it), with or
without ``.nm^-1``, and with an SI prefix on the watt (``mW.m^-2.sr^-1``).
Any other unit is refused in one line; a file without the attribute is read
as W/(m^2 sr nm), with a notice.  Reflective files (``T.<wavelength>``
channels) hold reflectance; the light comes from the caller, else from the
file's ``illuminant`` attribute (colour-science writes one), else D65 with a
notice.  Polarisation (S1-S3) and bispectral re-radiation channels are left
out, with a notice.
"""

from __future__ import annotations

__all__ = ["emissive_unit_scale", "read_exr_cube"]

import re
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError, one_line
from .cube import SourceCube, check_memory
from .illuminant import illuminant_from_attribute

_SI = {"Y": 24, "Z": 21, "E": 18, "P": 15, "T": 12, "G": 9, "M": 6, "k": 3, "h": 2, "da": 1, "": 0,
       "d": -1, "c": -2, "m": -3, "u": -6, "\u00b5": -6, "\u03bc": -6, "n": -9, "p": -12, "f": -15}
_UNIT_RE = re.compile(r"^(?P<prefix>da|[YZEPTGMkhdcmu\u00b5\u03bcnpf])?W\.m\^-2\.sr\^-1(?:\.nm\^-1)?$")


def emissive_unit_scale(text, where: str) -> float:
    """Factor from a JCGT ``emissiveUnits`` string to W/(m^2 sr nm).

    >>> emissive_unit_scale("mW.m^-2.sr^-1", "x.exr")
    0.001
    """
    m = _UNIT_RE.match(str(text).strip())
    if m is None:
        raise CfaMitsubaError(f"{where}: unknown emissiveUnits {str(text)!r} (known: an SI-prefixed watt per "
                              "m^2 sr [nm], e.g. W.m^-2.sr^-1, mW.m^-2.sr^-1, uW.m^-2.sr^-1.nm^-1)")
    exp = _SI[m["prefix"] or ""]
    return 10.0**exp if exp >= 0 else 1.0 / 10.0 ** (-exp)


def _decode(value):
    return value.decode() if isinstance(value, bytes) else value


def read_exr_cube(path) -> tuple[SourceCube, dict]:
    """Read a JCGT spectral EXR into a :class:`SourceCube` without changing
    its bands; returns ``(cube, header)`` (the header's strings decoded).

    The cube's ``scale`` carries ``emissiveUnits`` (emissive) and its
    ``illuminant`` the file's ``illuminant`` attribute where it parses.
    """
    from .channels import parse_spectral_channel

    p = Path(path)
    where = repr(str(p))
    if not p.exists():
        raise CfaMitsubaError(f"no such file: {where}")
    if p.is_dir():
        raise CfaMitsubaError(f"{where} is a directory, not a spectral EXR")
    from .guard import check_regular

    check_regular(p, "OpenEXR file")  # not a FIFO or device
    import OpenEXR

    def kind(name: str):
        if name.startswith("T."):
            wl = parse_spectral_channel("S0." + name[2:])
            return ("T", wl) if wl is not None else None
        wl = parse_spectral_channel(name)
        return ("S0", wl) if wl is not None else None

    try:
        with OpenEXR.File(str(p), header_only=True) as f:
            header = {k: _decode(v) for k, v in f.header().items()}
        (x0, y0), (x1, y1) = (tuple(int(v) for v in c) for c in header["dataWindow"])
        names = [c.name if hasattr(c, "name") else str(c) for c in header.get("channels", [])]
        n = sum(1 for nm in names if kind(nm)) or 1
        check_memory((y1 - y0 + 1, x1 - x0 + 1, n), where)
        with OpenEXR.File(str(p), separate_channels=True) as f:
            found = {"S0": [], "T": []}
            other = []
            for name, ch in f.channels().items():
                k = kind(name)
                if k is None:
                    other.append(name)
                else:
                    found[k[0]].append((k[1], np.asarray(ch.pixels)))
    except CfaMitsubaError:
        raise
    except Exception as exc:  # OpenEXR raises plain exceptions on bad files
        raise CfaMitsubaError(f"{where} is not a readable OpenEXR file: {one_line(exc)}") from None

    notices = []
    if found["S0"]:
        comp, quantity = "S0", "radiance"
        units = header.get("emissiveUnits")
        if units is None:
            scale = 1.0
            notices.append(f"{p.name}: no emissiveUnits attribute: values read as W/(m^2 sr nm)")
        else:
            scale = emissive_unit_scale(units, where)
            if scale != 1.0:
                notices.append(f"{p.name}: emissiveUnits {units}: values x {scale:g} to W/(m^2 sr nm)")
        if found["T"]:
            notices.append(f"{p.name}: reflective T. channels left out (the emissive S0 channels are used)")
    elif found["T"]:
        comp, quantity, scale = "T", "reflectance", 1.0
    else:
        raise CfaMitsubaError(f"{where} has no spectral channels (S0.<wavelength>nm emissive or T.<wavelength>nm "
                              "reflective): not a spectral EXR")
    extra = [nm for nm in other if re.match(r"^(S[1-3]\.|T\.)", nm)]
    if extra:
        notices.append(f"{p.name}: {len(extra)} polarisation or bispectral channel(s) left out")
    bands = sorted(found[comp], key=lambda t: t[0])
    wl = np.array([b[0] for b in bands])
    if np.any(np.diff(wl) <= 0):
        raise CfaMitsubaError(f"{where}: two spectral channels have the same wavelength")
    data = np.stack([b[1] for b in bands], axis=-1)
    light, unreadable = None, ""
    if "illuminant" in header:
        text = header["illuminant"]
        light = illuminant_from_attribute(text, where) if isinstance(text, str) else None
        if light is None:  # issue 27: say so, not "the file names none"
            unreadable = f"'illuminant' attribute ({str(text)[:40]!r})"
    cube = SourceCube(data, wl, quantity, f"spectral EXR {where}", scale=scale, illuminant=light, notices=notices,
                      illuminant_unreadable=unreadable)
    ours = our_meta(p, header)
    cube.fov_deg, cube.distance_m = _number(ours.get("fov_deg")), _number(ours.get("scene_distance_m"))
    return cube, header


def _number(v) -> float | None:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) and v > 0 else None


def our_meta(p: Path, header: dict) -> dict:
    """Our metadata of a file we wrote (the sidecar, else the header's JSON),
    or {}; either is bounded and checked against the sidecar schema
    (:mod:`.validate`): a malformed one is a one-line refusal."""
    from .sidecar import read_sidecar, sidecar_path
    from .validate import check_sidecar, load_json_text

    if sidecar_path(p).exists():
        return read_sidecar(sidecar_path(p))
    raw = header.get("cfaMitsuba")
    if not isinstance(raw, str):
        return {}
    what = f"{str(p)!r}'s cfaMitsuba attribute"
    return check_sidecar(load_json_text(raw, what), what)
