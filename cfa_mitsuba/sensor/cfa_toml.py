"""User CFAs in TOML files (docs/sensor.md s. 5.1).

A file gives a tile and, per filter, a spectrum: a filter of a spectra set
(the file's ``spectra_set``, default :data:`~cfa_mitsuba.sensor.cfa.DEFAULT_SPECTRA_SET`),
a CSV file, a colour-science camera channel or a table of numbers.
"""

from __future__ import annotations

__all__ = ["load_cfa_toml"]

from pathlib import Path

import numpy as np

from .. import spectra as _spectra
from ..errors import CfaMitsubaError
from ..io import guard as _guard
from .cfa import DEFAULT_SPECTRA_SET, CFA, _check_curve, _order_channels, _parse_tile, default_spectra_set, make_cfa
from .spectra_sets import get_spectra_set


def _read_csv_curve(path: Path, where: str):
    try:  # regular file, bounded, strict UTF-8, byte-order mark removed
        text = _guard.read_text(path, "spectrum file")
    except CfaMitsubaError as exc:
        raise CfaMitsubaError(f"{where}: {exc}") from None
    rows = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = [p for p in line.replace(";", ",").replace("\t", ",").split(",") if p.strip()]
        try:
            rows.append([float(p) for p in parts[:2]])
        except ValueError:
            if rows:  # a header is allowed only before the data
                raise CfaMitsubaError(f"{where}: {str(path)!r}: non-numeric line {line!r}") from None
            continue
        if len(rows[-1]) != 2:
            raise CfaMitsubaError(f"{where}: {str(path)!r}: expected 'wavelength_nm, value' per line")
    if not rows:
        raise CfaMitsubaError(f"{where}: {str(path)!r} holds no data")
    arr = np.array(rows)
    return arr[:, 0], arr[:, 1]


def _colour_curve(spec: str, where: str):
    """``colour:<camera sensitivities name>/<label>``, e.g.
    ``colour:Nikon 5100 (NPL)/green``; values as published (peak 1 for the
    NPL sets), so give a ``scale`` to make them quantum efficiencies."""
    colour = _spectra._colour()
    body = spec[len("colour:"):]
    name, _, label = body.rpartition("/")
    msds = colour.MSDS_CAMERA_SENSITIVITIES
    if name not in msds:
        raise CfaMitsubaError(f"{where}: unknown colour-science camera {name!r} (known: {', '.join(msds)})")
    labels = list(msds[name].labels)
    if label not in labels:
        raise CfaMitsubaError(f"{where}: camera {name!r} has no channel {label!r} (known: {', '.join(labels)})")
    m = msds[name]
    return np.asarray(m.wavelengths, float), np.asarray(m.values[:, labels.index(label)], float)


def _curve_from_toml(letter: str, spec, base: Path, where: str, sset):
    scale = 1.0
    if isinstance(spec, dict):
        unknown = set(spec) - {"source", "scale", "wavelengths", "values"}
        if unknown:
            raise CfaMitsubaError(f"{where}: spectra.{letter}: unknown key {sorted(unknown)[0]!r}")
        scale = spec.get("scale", 1.0)
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not scale > 0:
            raise CfaMitsubaError(f"{where}: spectra.{letter}.scale must be a positive number")
        if "wavelengths" in spec or "values" in spec:
            try:
                wl = np.asarray(spec.get("wavelengths", []), dtype=np.float64)
                qe = np.asarray(spec.get("values", []), dtype=np.float64) * scale
            except (TypeError, ValueError):
                raise CfaMitsubaError(f"{where}: spectra.{letter}: wavelengths and values must be lists of numbers") from None
            return _check_curve(letter, wl, qe, where)
        if "source" not in spec:
            raise CfaMitsubaError(f"{where}: spectra.{letter} needs 'source' or 'wavelengths' and 'values'")
        spec = spec["source"]
    if not isinstance(spec, str):
        raise CfaMitsubaError(f"{where}: spectra.{letter} must be a string (built-in filter, .csv file or "
                              "'colour:CAMERA/LABEL') or a table")
    if spec.startswith("colour:"):
        wl, qe = _colour_curve(spec, where)
    elif spec.lower().endswith(".csv"):
        p = Path(spec)
        wl, qe = _read_csv_curve(p if p.is_absolute() else base / p, where)
    else:
        if spec not in sset.curves:
            raise CfaMitsubaError(
                f"{where}: spectra.{letter} = {spec!r} is not a filter of spectra set {sset.name!r}, a .csv file "
                "or 'colour:NAME/LABEL'"
            )
        wl, qe = sset.curve(spec)
    return _check_curve(letter, wl, np.asarray(qe, float) * scale, where)


def _default_set(pattern, given: dict, where: str) -> str:
    """The set of the built-in CFAs of the tile's letters not under
    ``[spectra]`` (all the letters when every one is given); a one-line
    refusal naming the letters no such set has."""
    letters = _order_channels(pattern)
    need = [c for c in letters if c not in given]
    named = [v for v in given.values() if isinstance(v, str) and not v.lower().endswith(".csv") and ":" not in v]
    name, missing = default_spectra_set([*need, *named] or letters)  # [spectra] W = "W": the set's W too
    if name is not None:
        return name
    if not need:
        return DEFAULT_SPECTRA_SET  # every spectrum given: the set names no filter used
    plural = "s" if len(missing) > 1 else ""
    raise CfaMitsubaError(
        f"{where}: unknown filter{plural} {', '.join(map(repr, missing))} in the tile: no built-in CFA's spectra set "
        f"has {'them' if plural else 'it'} beside the other letters; give {'their' if plural else 'its'} spectr"
        f"{'a' if plural else 'um'} under [spectra] or name a spectra_set (cfa-mitsuba list spectra)")


def load_cfa_toml(path, spectra: str | None = None) -> CFA:
    """Read a user CFA.

    Format (``configs/cfas/`` has complete files; docs/sensor.md)::

        name = "rgbw-alt"              # optional, defaults to the file stem
        description = "..."            # optional
        tile = ["W R", "B W"]          # or "W R / B W", or [["W","R"],["B","W"]]
        spectra_set = "isetcam-rgbw"   # optional: the set of the letters not
                                       # given below (default: the set of the
                                       # built-in CFAs of those letters)
        [spectra]                      # optional for the set's letters
        W = "W"                        # a filter of the spectra set
        R = "my_red.csv"               # CSV: wavelength_nm, qe (relative to this file)
        B = { source = "colour:Nikon 5100 (NPL)/blue", scale = 0.4 }
        X = { wavelengths = [400, 550, 700], values = [0.1, 0.5, 0.1] }

    ``spectra`` overrides the file's ``spectra_set``.  Without either, the
    letters not given under ``[spectra]`` take the set of the built-in CFAs
    of those letters (:func:`~.cfa.default_spectra_set`: R, G, B from
    ``isetcam-rgb``, C, M, Y from ``isetcam-cmy``, R, G, B, W from
    ``isetcam-rgbw``), so a user CFA is compared with the built-in ones on
    the same dyes; a tile whose letters no built-in CFA's set has together
    is refused, naming the letters.
    """
    p = Path(path)
    where = str(p)
    data = _guard.read_toml(p, "CFA file")  # regular file, bounded, UTF-8, nesting the parser survives
    unknown = set(data) - {"name", "description", "tile", "spectra", "spectra_set"}
    if unknown:
        raise CfaMitsubaError(f"{where}: unknown key {sorted(unknown)[0]!r} "
                              "(expected name, description, tile, spectra_set, spectra)")
    if "tile" not in data:
        raise CfaMitsubaError(f"{where}: missing 'tile'")
    name = data.get("name", p.stem)
    if not isinstance(name, str) or not name:
        raise CfaMitsubaError(f"{where}: 'name' must be a non-empty string")
    pattern = _parse_tile(data["tile"], where)
    given = data.get("spectra", {})
    if not isinstance(given, dict):
        raise CfaMitsubaError(f"{where}: 'spectra' must be a table of filter = spectrum")
    set_name = spectra or data.get("spectra_set") or _default_set(pattern, given, where)
    if not isinstance(set_name, str):
        raise CfaMitsubaError(f"{where}: 'spectra_set' must be the name of a spectra set")
    try:
        sset = get_spectra_set(set_name)
    except CfaMitsubaError as exc:
        raise CfaMitsubaError(f"{where}: {exc}") from None
    curves = {}
    for letter in _order_channels(pattern):
        if letter in given:
            continue
        if letter not in sset.curves:
            raise CfaMitsubaError(
                f"{where}: unknown filter {letter!r} in the tile: give its spectrum under [spectra] "
                f"(filters of spectra set {sset.name!r}: {', '.join(sset.letters)})"
            )
        curves[letter] = sset.curve(letter)
    for letter, spec in given.items():
        curves[letter] = _curve_from_toml(letter, spec, p.parent, where, sset)
    used = sset.name if len(given) < len(curves) else ""
    return make_cfa(name, pattern.tolist(), curves, str(data.get("description", "")), where, spectra=used)
