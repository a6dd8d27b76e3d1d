"""Colour filter arrays as data: a repeating tile of filter names plus a
spectral sensitivity per filter.

The twelve CFAs of Bae 2020 (Fig 1) ship as named entries; users add their
own in TOML (:func:`load_cfa_toml`) or with :func:`register_cfa`.  Tiles are
written row by row from the top-left pixel of the image, which carries
``pattern[0, 0]``; they repeat periodically (research/cfa-demosaic.md, s. 1,
gives the source and confidence of each tile).

Spectra (research/cfa-demosaic.md, s. 2.3, option A): R, G, B are the
quantum efficiencies of colour-science's 'Nikon 5100 (NPL)' camera
(:func:`cfa_mitsuba.spectra.camera_rgb`); the complementary and panchromatic
filters are built from them, C = G + B, M = R + B, Y = R + G, W = R + G + B
(ideal block dyes on the same silicon).  Stacked dyes (cmy2) multiply dye
transmittances, a dye's transmittance being its sensitivity divided by W's,
so that the silicon's QE counts once: C2 = (C/W)^2 W, R = (M/W)(Y/W) W, ...
All curves are built on the camera data's native 5-nm grid and band-averaged
to a render's grid only when used (:meth:`CFA.sensitivities`).  A curve
tabulated exactly on the requested band centres is taken as band values
as it stands, so a CFA rebuilt from a raw file's ``spectra``
(:func:`cfa_from_raw`) reproduces them bit for bit.

A CFA is refused, with one line naming the problem, when its tile is empty
or ragged, a filter name is invalid or has no spectrum, a spectrum is given
for a filter the tile does not use, or a spectrum is NaN, infinite,
negative, zero everywhere, above 1 (quantum efficiencies are electrons per
photon) or not on ascending wavelengths.
"""

from __future__ import annotations

__all__ = [
    "CFA",
    "CANONICAL_ORDER",
    "get_cfa",
    "list_cfas",
    "register_cfa",
    "load_cfa_toml",
    "make_cfa",
    "cfa_from_raw",
    "builtin_filter_curve",
]

import functools
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import spectra as _spectra
from ..errors import CfaMitsubaError

#: Channel order of every CFA: these letters first, in this order, then any
#: other filter names in order of first appearance in the tile (row by row).
CANONICAL_ORDER = ("R", "G", "B", "C", "M", "Y", "W")


@dataclass(frozen=True, eq=False)
class CFA:
    """A colour filter array.

    Attributes
    ----------
    name : registry name (``"bayer"``) or the TOML's ``name``.
    pattern : (tile height, tile width) numpy array of filter names (str).
    channels : the distinct filter names in a fixed order
        (:data:`CANONICAL_ORDER` first), e.g. ``('R', 'G', 'B')``.
    curves : per channel, ``(wavelengths_nm, qe)``: a tabulated quantum
        efficiency (electrons per photon, filter x silicon), linearly
        interpolated between points.
    description : one line for ``list cfas`` and the report.
    """

    name: str
    pattern: np.ndarray
    channels: tuple[str, ...]
    curves: dict = field(repr=False)
    description: str = ""

    @property
    def tile_shape(self) -> tuple[int, int]:
        return tuple(self.pattern.shape)  # type: ignore[return-value]

    @property
    def densities(self) -> dict[str, float]:
        """Fraction of pixels carrying each channel."""
        n = self.pattern.size
        return {c: float(np.count_nonzero(self.pattern == c)) / n for c in self.channels}

    def sensitivities(self, wavelengths=_spectra.DEFAULT_WAVELENGTHS) -> np.ndarray:
        """Band-averaged quantum efficiencies, shape (C, B), rows in
        ``channels`` order, electrons per photon.  A curve tabulated exactly
        on ``wavelengths`` is returned as it stands (module doc)."""
        wl = _spectra.validate_wavelengths(wavelengths)
        key = tuple(wl.tolist())
        cache = self.__dict__.setdefault("_band_cache", {})
        if key not in cache:
            rows = []
            for c in self.channels:
                cwl, cqe = self.curves[c]
                if cwl.shape == wl.shape and np.array_equal(cwl, wl):
                    rows.append(np.array(cqe, dtype=np.float64))
                else:
                    rows.append(_spectra.band_average(cwl, cqe, wl))
            out = np.stack(rows)
            out.flags.writeable = False
            cache[key] = out
        return cache[key].copy()

    def channel_index(self, shape: tuple[int, int]) -> np.ndarray:
        """(H, W) int array: the index into ``channels`` of each pixel's filter."""
        h, w = int(shape[0]), int(shape[1])
        th, tw = self.tile_shape
        lut = {c: i for i, c in enumerate(self.channels)}
        tile = np.vectorize(lut.__getitem__, otypes=[np.intp])(self.pattern)
        return tile[np.arange(h)[:, None] % th, np.arange(w)[None, :] % tw]

    def masks(self, shape: tuple[int, int]) -> np.ndarray:
        """(C, H, W) bool: where each channel is sampled."""
        idx = self.channel_index(shape)
        return np.stack([idx == i for i in range(len(self.channels))])

    def tile_text(self) -> str:
        """The tile as ``"G R / B G"``."""
        return " / ".join(" ".join(row) for row in self.pattern.tolist())


def _order_channels(pattern: np.ndarray) -> tuple[str, ...]:
    seen = list(dict.fromkeys(pattern.ravel().tolist()))
    first = [c for c in CANONICAL_ORDER if c in seen]
    return tuple(first + [c for c in seen if c not in CANONICAL_ORDER])


def _parse_tile(tile, where: str) -> np.ndarray:
    """A tile from ``"G R / B G"``, ``["G R", "B G"]`` or ``[["G","R"],["B","G"]]``."""
    if isinstance(tile, str):
        rows = [r.split() for r in tile.split("/")]
    elif isinstance(tile, (list, tuple)):
        rows = [r.split() if isinstance(r, str) else list(r) for r in tile]
    else:
        raise CfaMitsubaError(f"{where}: tile must be a string like 'G R / B G' or a list of rows")
    if not rows or not rows[0]:
        raise CfaMitsubaError(f"{where}: tile is empty")
    widths = {len(r) for r in rows}
    if len(widths) != 1:
        raise CfaMitsubaError(f"{where}: ragged tile, rows have {sorted(widths)} entries")
    for r in rows:
        for c in r:
            if not isinstance(c, str) or not c.strip() or not c.replace("_", "").isalnum():
                raise CfaMitsubaError(f"{where}: invalid filter name {c!r} in tile")
    return np.array(rows, dtype=str)


def _check_curve(name: str, wl, qe, where: str):
    wl = np.asarray(wl, dtype=np.float64).reshape(-1)
    qe = np.asarray(qe, dtype=np.float64).reshape(-1)
    if wl.size != qe.size or wl.size < 2:
        raise CfaMitsubaError(f"{where}: spectrum of {name!r} needs matching wavelengths and values, at least 2")
    if not (np.all(np.isfinite(wl)) and np.all(np.isfinite(qe))):
        raise CfaMitsubaError(f"{where}: spectrum of {name!r} contains NaN or infinite values")
    if not np.all(np.diff(wl) > 0):
        raise CfaMitsubaError(f"{where}: spectrum of {name!r} needs strictly ascending wavelengths")
    if np.any(qe < 0):
        raise CfaMitsubaError(f"{where}: spectrum of {name!r} has negative values")
    if not np.any(qe > 0):
        raise CfaMitsubaError(f"{where}: spectrum of {name!r} is zero everywhere")
    if np.any(qe > 1.0 + 1e-9):
        raise CfaMitsubaError(
            f"{where}: spectrum of {name!r} peaks at {qe.max():g}, above 1: give a quantum efficiency "
            "(electrons per photon), e.g. with 'scale'"
        )
    if wl[0] > 400.0 or wl[-1] < 700.0:
        warnings.warn(
            f"{where}: spectrum of {name!r} covers only {wl[0]:g}..{wl[-1]:g} nm; "
            "it is held at its end values outside that range",
            stacklevel=3,
        )
    return wl, qe


def make_cfa(name: str, tile, curves: dict, description: str = "", where: str | None = None) -> CFA:
    """Build and validate a :class:`CFA` from a tile and ``{filter: (wl, qe)}``."""
    where = where or f"CFA {name!r}"
    pattern = _parse_tile(tile, where)
    channels = _order_channels(pattern)
    missing = [c for c in channels if c not in curves]
    if missing:
        raise CfaMitsubaError(
            f"{where}: no spectrum for filter {missing[0]!r} (built-in filters: {', '.join(CANONICAL_ORDER)})"
        )
    unused = [c for c in curves if c not in channels]
    if unused:
        raise CfaMitsubaError(f"{where}: channel {unused[0]!r} has a spectrum but no samples in the tile")
    checked = {c: _check_curve(c, *curves[c], where) for c in channels}
    return CFA(name=name, pattern=pattern, channels=channels, curves=checked, description=description)


# --- built-in filters -------------------------------------------------------


@functools.lru_cache(maxsize=1)
def _native_rgb():
    """R, G, B QE of 'Nikon 5100 (NPL)' on its native grid, scaled as in
    :func:`cfa_mitsuba.spectra.camera_rgb`."""
    colour = _spectra._colour()
    msds = colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]
    values = msds.values * (_spectra.CAMERA_PEAK_QE / msds.values.sum(axis=1).max())
    return np.asarray(msds.wavelengths, dtype=np.float64), values


def _dye(qe: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Transmittance of a dye from its sensitivity on the same silicon."""
    return np.divide(qe, w, out=np.zeros_like(qe), where=w > 1e-12)


@functools.lru_cache(maxsize=1)
def _builtin_curves() -> dict:
    wl, rgb = _native_rgb()
    r, g, b = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    c, m, y, w = g + b, r + b, r + g, r + g + b
    tc, tm, ty = _dye(c, w), _dye(m, w), _dye(y, w)
    curves = {
        "R": r, "G": g, "B": b, "C": c, "M": m, "Y": y, "W": w,
        # cmy2: two stacked dye layers (Sajadi et al. 2011).
        "C2": tc * tc * w, "M2": tm * tm * w, "Y2": ty * ty * w,
        "MY": tm * ty * w, "CY": tc * ty * w, "CM": tc * tm * w,
    }
    return {k: (wl, v) for k, v in curves.items()}


def builtin_filter_curve(letter: str) -> tuple[np.ndarray, np.ndarray]:
    """``(wavelengths_nm, qe)`` of a built-in filter: R, G, B, C, M, Y, W,
    the doubled dyes C2, M2, Y2, or the stacked pairs MY (= cmy2's R), CY
    (G), CM (B)."""
    curves = _builtin_curves()
    if letter not in curves:
        raise CfaMitsubaError(f"unknown built-in filter {letter!r} (known: {', '.join(curves)})")
    return curves[letter]


#: name -> (tile, {filter: built-in curve name}, description)
_BUILTINS: dict[str, tuple[str, dict, str]] = {
    "bayer": ("G R / B G", {}, "Bayer (GRBG phase, ISETCam's default); G 1/2, R 1/4, B 1/4"),
    "rgb1": ("G R G B / G B G R", {}, "Yamanaka: G in full columns, R/B checkerboard in the others"),
    "rgb2": ("G R / G B / R G / B G", {}, "Lukac: G pairs vertically, R and B rows shifted every two rows"),
    "rgb3": ("R G B", {}, "vertical stripes R, G, B"),
    "rgb4": ("R G B / B R G / G B R", {}, "diagonal stripes"),
    "rgb5": ("G R G B / B G R G / G B G R / R G B G", {}, "modified Bayer: G quincunx, R and B in every row and column"),
    "cmy1": ("Y C / M Y", {}, "CMY Bayer-type: Y quincunx, C and M"),
    "cmy2": (
        "C2 M2 Y2 / R G B",
        {"R": "MY", "G": "CY", "B": "CM"},
        "switchable primaries (RGB+CMY mode): doubled dyes over stacked pairs",
    ),
    "cmy3": ("C Y / G M", {}, "CYGM"),
    "rgbw1": ("G R / B W", {}, "Bayer with the second G replaced by W"),
    "rgbw2": ("W B W G / B W G W / W G W R / G W R W", {}, "Kodak CFA 2.0: W checkerboard, colours on diagonals"),
    "rgbw3": ("W R W B / G W G W", {}, "W checkerboard; one line R and B, the other G"),
}

_REGISTRY: dict[str, CFA] = {}


def register_cfa(cfa: CFA, *, replace: bool = False) -> CFA:
    """Add a CFA to the registry under ``cfa.name`` (a built-in name only
    with ``replace=True``; ``ideal`` never)."""
    if not isinstance(cfa, CFA):
        raise CfaMitsubaError(f"register_cfa needs a CFA, got {type(cfa).__name__}")
    if cfa.name == "ideal":
        raise CfaMitsubaError("'ideal' is reserved for the XYZ reference sensor")
    if (cfa.name in _REGISTRY or cfa.name in _BUILTINS) and not replace:
        raise CfaMitsubaError(f"a CFA named {cfa.name!r} is already registered")
    _REGISTRY[cfa.name] = cfa
    return cfa


def _builtin(name: str) -> CFA:
    tile, renames, description = _BUILTINS[name]
    letters = _order_channels(_parse_tile(tile, name))
    curves = {c: builtin_filter_curve(renames.get(c, c)) for c in letters}
    return make_cfa(name, tile, curves, description)


def list_cfas() -> list[str]:
    """Names of the registered CFAs: the 12 built-ins, then user additions."""
    return list(_BUILTINS) + [n for n in _REGISTRY if n not in _BUILTINS]


def get_cfa(name) -> CFA:
    """A CFA by registry name (``"bayer"``, ``"rgbw2"``, ...) or from a TOML
    file (a path ending in ``.toml``)."""
    if isinstance(name, CFA):
        return name
    key = str(name)
    if key.lower().endswith(".toml"):
        return load_cfa_toml(key)
    if key not in _REGISTRY and key in _BUILTINS:
        _REGISTRY[key] = _builtin(key)
    if key not in _REGISTRY:
        if key == "ideal":
            raise CfaMitsubaError("'ideal' is not a CFA: it is the XYZ reference sensor (sensor.capture_ideal)")
        raise CfaMitsubaError(f"unknown CFA {key!r} (known: {', '.join(list_cfas())}; or a FILE.toml)")
    return _REGISTRY[key]


# --- TOML -------------------------------------------------------------------


def _read_csv_curve(path: Path, where: str):
    try:
        text = path.read_text()
    except OSError as exc:
        raise CfaMitsubaError(f"{where}: cannot read spectrum file {str(path)!r}: {exc.strerror}") from None
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


def _curve_from_toml(letter: str, spec, base: Path, where: str):
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
        try:
            wl, qe = builtin_filter_curve(spec)
        except CfaMitsubaError:
            raise CfaMitsubaError(
                f"{where}: spectra.{letter} = {spec!r} is not a built-in filter, a .csv file or 'colour:NAME/LABEL'"
            ) from None
    return _check_curve(letter, wl, np.asarray(qe, float) * scale, where)


def load_cfa_toml(path) -> CFA:
    """Read a user CFA.

    Format (``configs/cfas/`` has complete files; docs/sensor.md)::

        name = "rgbw-alt"              # optional, defaults to the file stem
        description = "..."            # optional
        tile = ["W R", "B W"]          # or "W R / B W", or [["W","R"],["B","W"]]
        [spectra]                      # optional for the built-in filters
                                       # R G B C M Y W C2 M2 Y2 MY CY CM
        W = "W"                        # a built-in filter
        R = "my_red.csv"               # CSV: wavelength_nm, qe (relative to this file)
        B = { source = "colour:Nikon 5100 (NPL)/blue", scale = 0.4 }
        X = { wavelengths = [400, 550, 700], values = [0.1, 0.5, 0.1] }
    """
    p = Path(path)
    where = str(p)
    try:
        data = tomllib.loads(p.read_text())
    except OSError as exc:
        raise CfaMitsubaError(f"cannot read CFA file {where!r}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise CfaMitsubaError(f"{where}: invalid TOML: {exc}") from None
    unknown = set(data) - {"name", "description", "tile", "spectra"}
    if unknown:
        raise CfaMitsubaError(f"{where}: unknown key {sorted(unknown)[0]!r} (expected name, description, tile, spectra)")
    if "tile" not in data:
        raise CfaMitsubaError(f"{where}: missing 'tile'")
    name = data.get("name", p.stem)
    if not isinstance(name, str) or not name:
        raise CfaMitsubaError(f"{where}: 'name' must be a non-empty string")
    pattern = _parse_tile(data["tile"], where)
    given = data.get("spectra", {})
    if not isinstance(given, dict):
        raise CfaMitsubaError(f"{where}: 'spectra' must be a table of filter = spectrum")
    curves = {}
    for letter in _order_channels(pattern):
        if letter in given:
            continue
        if letter not in _builtin_curves():
            raise CfaMitsubaError(
                f"{where}: unknown filter {letter!r} in the tile: give its spectrum under [spectra] "
                f"(built-in filters: {', '.join(_builtin_curves())})"
            )
        curves[letter] = builtin_filter_curve(letter)
    for letter, spec in given.items():
        curves[letter] = _curve_from_toml(letter, spec, p.parent, where)
    return make_cfa(name, pattern.tolist(), curves, str(data.get("description", "")), where)


def cfa_from_raw(raw) -> CFA:
    """The CFA a :class:`~cfa_mitsuba.values.RawImage` was captured with,
    rebuilt from its ``pattern``, ``channels``, ``spectra`` and
    ``wavelengths`` (what a raw file holds); ``sensitivities(wavelengths)``
    returns ``spectra`` exactly."""
    if getattr(raw, "is_ideal", False):
        raise CfaMitsubaError("the ideal sensor's raw image has no CFA (it is XYZ at every pixel)")
    pattern = np.asarray(raw.pattern, dtype=str)
    spectra = np.asarray(raw.spectra, dtype=np.float64)
    wl = np.asarray(raw.wavelengths, dtype=np.float64)
    channels = tuple(str(c) for c in raw.channels)
    if spectra.shape != (len(channels), wl.size):
        raise CfaMitsubaError(f"raw spectra have shape {spectra.shape}, expected ({len(channels)}, {wl.size})")
    info = (getattr(raw, "settings", None) or {}).get("cfa", {}) or {}
    cfa = make_cfa(str(info.get("name") or "custom"), pattern.tolist(),
                   {c: (wl, spectra[i]) for i, c in enumerate(channels)}, str(info.get("description") or ""),
                   where="raw file CFA")
    if cfa.channels != channels:
        raise CfaMitsubaError(f"raw file CFA: channels {channels} do not match the tile's {cfa.channels}")
    return cfa
