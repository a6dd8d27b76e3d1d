"""Colour filter arrays as data: a repeating tile of filter names plus a
spectral sensitivity per filter.

The named layouts (the twelve CFAs of Bae 2020, Fig 1, and the layouts of
today's sensors) are data, ``cfa_mitsuba/data/layouts.toml``: a tile, a
default spectra set, a source.  Their curves come from a named spectra set
(:mod:`cfa_mitsuba.sensor.spectra_sets`); the paper's CFAs use their
family's ISETCam filters by default, and any set can be chosen instead
(``get_cfa("bayer", spectra="nikon-d5100")``).  Users add their own CFAs in
TOML (:mod:`cfa_mitsuba.sensor.cfa_toml`) or with :func:`register_cfa`.
Tiles are written row by row from the top-left pixel of the image, which
carries ``pattern[0, 0]``; they repeat periodically (research/cfa-demosaic.md,
s. 1, gives the source and confidence of each of the paper's tiles).

Curves stay on their source grids and are band-averaged to a render's grid
only when used (:meth:`CFA.sensitivities`).  A curve tabulated exactly on
the requested band centres is taken as band values as it stands, so a CFA
rebuilt from a raw file's ``spectra`` (:func:`cfa_from_raw`) reproduces
them bit for bit.

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
    "DEFAULT_SPECTRA_SET",
    "default_spectra_set",
    "layout_info",
    "list_layouts",
    "list_cfas",
    "register_cfa",
    "make_cfa",
    "cfa_from_raw",
    "builtin_filter_curve",
]

import functools
import warnings
from dataclasses import dataclass, field

import numpy as np

from .. import spectra as _spectra
from ..errors import CfaMitsubaError
from .spectra_sets import get_spectra_set, read_data_toml

#: The spectra set of :func:`builtin_filter_curve` (the Nikon construction).
#: A user TOML that names no ``spectra_set`` takes the set of the built-in
#: CFAs of its letters instead (:func:`default_spectra_set`), so that it is
#: compared with them on the same dyes (issue 22).
DEFAULT_SPECTRA_SET = "nikon-d5100"

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
    spectra : the spectra set the curves come from ("" when given by hand).
    """

    name: str
    pattern: np.ndarray
    channels: tuple[str, ...]
    curves: dict = field(repr=False)
    description: str = ""
    spectra: str = ""

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


def make_cfa(name: str, tile, curves: dict, description: str = "", where: str | None = None,
             spectra: str = "") -> CFA:
    """Build and validate a :class:`CFA` from a tile and ``{filter: (wl, qe)}``
    (``spectra``: the name of the set the curves come from, if any)."""
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
    return CFA(name=name, pattern=pattern, channels=channels, curves=checked, description=description,
               spectra=spectra)


# --- named layouts ----------------------------------------------------------


def builtin_filter_curve(letter: str, spectra_set: str = DEFAULT_SPECTRA_SET) -> tuple[np.ndarray, np.ndarray]:
    """``(wavelengths_nm, qe)`` of a filter of a spectra set (default the
    Nikon set: R, G, B, C, M, Y, W, the doubled dyes C2, M2, Y2 and the
    stacked pairs MY (= cmy2's R), CY (G), CM (B))."""
    return get_spectra_set(spectra_set).curve(letter)


@functools.lru_cache(maxsize=1)
def _layouts() -> dict:
    return read_data_toml("layouts.toml", "CFA layouts")


def list_layouts() -> list[str]:
    """Names of the named layouts shipped in ``data/layouts.toml``."""
    return list(_layouts())


def layout_info(name: str) -> dict:
    """A named layout's entry: ``tile``, ``spectra`` (default set),
    ``description``, ``source`` and optional ``filters`` (renames)."""
    if name not in _layouts():
        raise CfaMitsubaError(f"unknown CFA {name!r} (known: {', '.join(list_cfas())}; or a FILE.toml)")
    return dict(_layouts()[name])


def default_spectra_set(letters) -> tuple[str | None, list[str]]:
    """(the spectra set, []) a user CFA of filter ``letters`` takes by
    default: that of the first built-in CFA (``data/layouts.toml`` order:
    bayer's ``isetcam-rgb``, the CMY CFAs' ``isetcam-cmy``, the RGBW ones'
    ``isetcam-rgbw``, ...) whose set has every letter; or (None, the
    letters that the set covering most of them lacks) when none has all.

    Examples
    --------
    >>> default_spectra_set(["R", "G", "B", "W"])
    ('isetcam-rgbw', [])
    >>> default_spectra_set(["G", "R", "B", "V"])
    (None, ['V'])
    """
    want = list(dict.fromkeys(letters))
    best: tuple[int, list[str]] = (-1, want)
    for name in _layouts():
        sset = get_spectra_set(_layouts()[name]["spectra"])
        missing = [c for c in want if c not in sset.curves]
        if not missing:
            return sset.name, []
        if len(want) - len(missing) > best[0]:
            best = (len(want) - len(missing), missing)
    return None, best[1]


_REGISTRY: dict[str, CFA] = {}
_BUILT: dict[tuple[str, str], CFA] = {}


def register_cfa(cfa: CFA, *, replace: bool = False) -> CFA:
    """Add a CFA to the registry under ``cfa.name`` (a built-in name only
    with ``replace=True``; ``ideal`` never)."""
    if not isinstance(cfa, CFA):
        raise CfaMitsubaError(f"register_cfa needs a CFA, got {type(cfa).__name__}")
    if cfa.name == "ideal":
        raise CfaMitsubaError("'ideal' is reserved for the XYZ reference sensor")
    if (cfa.name in _REGISTRY or cfa.name in _layouts()) and not replace:
        raise CfaMitsubaError(f"a CFA named {cfa.name!r} is already registered")
    _REGISTRY[cfa.name] = cfa
    return cfa


def _builtin(name: str, spectra: str | None) -> CFA:
    info = layout_info(name)
    spectra = spectra or info["spectra"]
    key = (name, spectra)
    if key not in _BUILT:
        sset = get_spectra_set(spectra)
        renames = info.get("filters", {})
        letters = _order_channels(_parse_tile(info["tile"], name))
        where = f"CFA {name!r} with spectra set {spectra!r}"
        missing = [c for c in letters if renames.get(c, c) not in sset.curves]
        if missing:
            raise CfaMitsubaError(f"{where}: the set has no filter {renames.get(missing[0], missing[0])!r} "
                                  f"(it has {', '.join(sset.letters)})")
        curves = {c: sset.curve(renames.get(c, c)) for c in letters}
        _BUILT[key] = make_cfa(name, info["tile"], curves, info["description"], where, spectra=spectra)
    return _BUILT[key]


def list_cfas() -> list[str]:
    """Names of the registered CFAs: the named layouts, then user additions."""
    return list(_layouts()) + [n for n in _REGISTRY if n not in _layouts()]


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
                   where="raw file CFA", spectra=str(info.get("spectra") or ""))
    if cfa.channels != channels:
        raise CfaMitsubaError(f"raw file CFA: channels {channels} do not match the tile's {cfa.channels}")
    return cfa
