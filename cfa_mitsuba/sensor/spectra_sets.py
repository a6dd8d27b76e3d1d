"""Spectra sets: named sets of filter spectra, read from package data.

A spectra set maps filter letters (R, G, B, C, M, Y, W, the stacked C2 ...)
to a quantum efficiency curve ``(wavelengths_nm, qe)``: electrons per
photon of a whole pixel, filter x IR-cut filter x silicon.  The sets are
defined in ``cfa_mitsuba/data/spectra_sets.toml`` over CSV files copied
verbatim from ISETCam and pbrt-v4 (``cfa_mitsuba/data/filters/README.md``)
and over colour-science's camera data.

Same footing (docs/sensor.md s. 5.2): each source curve says what it
includes, and what it lacks is multiplied in from one common model, the
silicon QE of ISETCam's ``cmosPhotodetectorQE`` and the IR-cut filter of
ISETCam's ``ircf_public`` (Largan K098):

* ``dye`` (a filter's transmittance alone): T x IR x silicon;
* ``pixel`` (filter x silicon, no IR cut): Q x IR;
* ``camera`` (the whole camera): Q.

A set with ``model = "flat"`` is used as ISETCam uses its filter files:
photodiode QE 1 and no IR-cut filter at every wavelength (ISETCam's
``pixelCreate`` and ``sensorCreate`` defaults), so each curve is taken as
it stands and a clear pixel is 1 everywhere (the ``*-raw`` sets).

Peak-normalised ("relative") sets get one factor per set, so that the sum
of their effective R, G, B peaks at :data:`cfa_mitsuba.spectra.CAMERA_PEAK_QE`.
A product or sum of curves on different grids is tabulated on the union of
their points and a 1-nm grid (the linear interpolants' product between
those points differs from the exact one by < 1e-4); curves on one grid stay
on it.  Curves are band-averaged only when a CFA is used
(:meth:`cfa_mitsuba.sensor.cfa.CFA.sensitivities`).

Defects of the source files (filters/README.md) are handled where the
files are read (:func:`read_curve_csv`): rows are sorted by wavelength
(``cym.csv`` is stored from 780 down to 379 nm, ``cmosPhotodetectorQE.csv``
in digitising order); a NaN is a missing sample, left out of its column;
``unit = "percent"`` is divided by 100 (and refused if the data are not in
percent); a wavelength listed twice is kept once when both rows agree and
refused when they do not; round-off below zero (|value| < 1e-9 of the
column's peak, ``NikonD2xsNikon50mm.csv``) is set to 0, a larger negative
value refused.  Duplicated datasets are not shipped twice: a set
reuses the other set's letters (``borrow``).
"""

from __future__ import annotations

__all__ = ["SpectraSet", "list_spectra_sets", "get_spectra_set", "read_curve_csv", "silicon_qe", "ir_cut", "common_ir_letters",
           "DATA_DIR", "FILTERS_DIR"]

import csv
import functools
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import spectra as _spectra
from ..errors import CfaMitsubaError
from ..io import guard as _guard

DATA_DIR = Path(__file__).resolve().parents[1] / "data"
FILTERS_DIR = DATA_DIR / "filters"
_SETS_FILE = DATA_DIR / "spectra_sets.toml"

_CURVES = ("dye", "pixel", "camera")
_MODELS = ("common", "flat")
#: ISETCam's default pixel: photodiode QE 1, IR filter 1 (``model = "flat"``).
_FLAT = (np.array([300.0, 1100.0]), np.array([1.0, 1.0]))
_DERIVES = ("block-dyes", "clear", "stacks")
_STACKS = {"C2": "CC", "M2": "MM", "Y2": "YY", "MY": "MY", "CY": "CY", "CM": "CM"}


@dataclass(frozen=True, eq=False)
class SpectraSet:
    """A named set of filter curves.

    Attributes
    ----------
    name : registry name (``"isetcam-rgb"``).
    description, source : one line each: what the curves are, where they
        come from (file, repository, licence).
    family : the CFA family it was made for (``rgb``, ``cmy``, ``rgbw``,
        ``any``, ...).
    curves : letter -> ``(wavelengths_nm, qe)``, whole-pixel QE.
    """

    name: str
    description: str
    source: str
    family: str
    curves: dict = field(repr=False)

    @property
    def letters(self) -> tuple[str, ...]:
        return tuple(self.curves)

    def curve(self, letter: str) -> tuple[np.ndarray, np.ndarray]:
        """``(wavelengths_nm, qe)`` of one filter, or a one-line error."""
        if letter not in self.curves:
            raise CfaMitsubaError(f"spectra set {self.name!r} has no filter {letter!r} "
                                  f"(it has {', '.join(self.curves)})")
        return self.curves[letter]


def read_curve_csv(path, columns=None, unit: str = "fraction", where: str | None = None) -> dict:
    """Columns of a spectral CSV (``wavelength_nm, NAME, ...``; one header
    line) as ``{name: (wavelengths_nm, values)}``, each ascending.

    Rows are sorted by wavelength; a NaN leaves that sample out of its
    column; a wavelength given twice is kept once if the rows agree and
    refused otherwise; negative round-off (above -1e-9 x the column's
    peak) becomes 0, other negatives are refused; ``unit="percent"`` divides by 100 and refuses data
    whose maximum is not above 1 (then they are not percent).
    """
    p = Path(path)
    where = where or p.name
    try:  # regular file, bounded, strict UTF-8, byte-order mark removed
        text = _guard.read_text(p, "spectrum file")
    except CfaMitsubaError as exc:
        raise CfaMitsubaError(f"{where}: {exc}") from None
    rows = [r for r in csv.reader(io.StringIO(text, newline="")) if r and not r[0].lstrip().startswith("#")]
    if len(rows) < 3:
        raise CfaMitsubaError(f"{where}: {p.name} holds fewer than 2 data rows")
    header = [h.strip() for h in rows[0]]
    try:
        data = np.array([[float(v) for v in r] for r in rows[1:]], dtype=np.float64)
    except ValueError:
        raise CfaMitsubaError(f"{where}: {p.name}: non-numeric data after the header") from None
    if data.ndim != 2 or data.shape[1] != len(header):
        raise CfaMitsubaError(f"{where}: {p.name}: rows do not all have {len(header)} fields")
    data = data[np.argsort(data[:, 0], kind="stable")]
    wl = data[:, 0]
    if not np.all(np.isfinite(wl)):
        raise CfaMitsubaError(f"{where}: {p.name}: a wavelength is NaN or infinite")
    same = np.flatnonzero(np.diff(wl) == 0)
    if same.size:
        agree = np.all((data[same] == data[same + 1]) | (np.isnan(data[same]) & np.isnan(data[same + 1])), axis=1)
        if not np.all(agree):
            bad = wl[same[~agree][0]]
            raise CfaMitsubaError(f"{where}: {p.name}: {bad:g} nm is listed twice with different values")
        keep = np.ones(wl.size, bool)
        keep[same + 1] = False
        data, wl = data[keep], wl[keep]
    if unit not in ("fraction", "percent"):
        raise CfaMitsubaError(f"{where}: unit must be 'fraction' or 'percent', got {unit!r}")
    wanted = columns if columns is not None else header[1:]
    out = {}
    for name in wanted:
        if name not in header[1:]:
            raise CfaMitsubaError(f"{where}: {p.name} has no column {name!r} (it has {', '.join(header[1:])})")
        y = data[:, header.index(name)]
        ok = np.isfinite(y)
        if np.count_nonzero(ok) < 2:
            raise CfaMitsubaError(f"{where}: {p.name}: column {name!r} has fewer than 2 finite values")
        y = y[ok]
        tiny = (y < 0) & (y >= -1e-9 * np.abs(y).max())
        if np.any(y[~tiny] < 0):
            raise CfaMitsubaError(f"{where}: {p.name}: column {name!r} has negative values down to {y.min():g}")
        y = np.where(tiny, 0.0, y)  # round-off below zero (NikonD2xs: -2e-19 against a peak of 7e5)
        if unit == "percent":
            if y.max() <= 1.0:
                raise CfaMitsubaError(f"{where}: {p.name}: column {name!r} is declared in percent but peaks "
                                      f"at {y.max():g}")
            y = y / 100.0
        out[name] = (wl[ok].copy(), y)
    return out


def _combine(curves, op) -> tuple[np.ndarray, np.ndarray]:
    """Pointwise sum or product of linearly interpolated curves (module doc)."""
    grids = [c[0] for c in curves]
    if all(g.shape == grids[0].shape and np.array_equal(g, grids[0]) for g in grids):
        x = grids[0]
    else:
        lo, hi = min(g[0] for g in grids), max(g[-1] for g in grids)
        x = np.unique(np.concatenate(grids + [np.arange(np.ceil(lo), np.floor(hi) + 1.0)]))
    vals = [np.interp(x, wl, y) for wl, y in curves]
    out = vals[0].copy()
    for v in vals[1:]:
        out = op(out, v)
    return x, out


def _product(*curves):
    return _combine(curves, np.multiply)


def _sum(*curves):
    return _combine(curves, np.add)


def _ratio(num, den):
    """A dye's transmittance: its curve over the clear pixel's (0 where the
    clear pixel sees nothing)."""
    return _combine([num, den], lambda n, d: np.divide(n, d, out=np.zeros_like(n), where=d > 1e-12))


def read_data_toml(name: str, what: str) -> dict:
    """A TOML file shipped in the package's data folder (``what`` names it in
    the error: a missing or broken one is a broken installation, not a user
    error)."""
    path = DATA_DIR / name
    try:
        return _guard.read_toml(path, what)
    except CfaMitsubaError as exc:
        raise CfaMitsubaError(f"cannot read the {what} {str(path)!r}: {exc}") from None


@functools.lru_cache(maxsize=1)
def _definitions() -> dict:
    return read_data_toml(_SETS_FILE.name, "spectra sets")


def _model_curve(key: str):
    spec = _definitions()["model"][key]
    cols = read_curve_csv(FILTERS_DIR / spec["file"], [spec["column"]], spec.get("unit", "fraction"),
                          where=f"spectra model {key}")
    return cols[spec["column"]]


@functools.lru_cache(maxsize=1)
def silicon_qe() -> tuple[np.ndarray, np.ndarray]:
    """The common silicon photodiode QE (electrons per photon), ascending nm."""
    return _model_curve("silicon")


@functools.lru_cache(maxsize=1)
def ir_cut() -> tuple[np.ndarray, np.ndarray]:
    """The common IR-cut filter's transmittance, ascending nm."""
    return _model_curve("ir_cut")


def _all_specs() -> dict:
    d = _definitions()
    specs = dict(d.get("sets", {}))
    pbrt = d.get("pbrt", {})
    for cam in pbrt.get("cameras", []):
        specs["pbrt-" + cam.replace("_", "-")] = {
            "family": "any", "file": f"pbrt-v4/{cam}.csv", "curve": "camera", "scale": "relative",
            "derive": ["block-dyes", "stacks"], "source": pbrt["source"],
            "description": f"pbrt-v4 camera '{cam}' (whole camera, relative); C M Y W derived",
        }
    return specs


def _raw_columns(name: str, spec: dict) -> dict:
    where = f"spectra set {name!r}"
    columns = spec.get("columns")  # letter -> column name in the source
    if "colour" in spec:
        colour = _spectra._colour()
        msds = colour.MSDS_CAMERA_SENSITIVITIES[spec["colour"]]
        labels = list(msds.labels)
        wl = np.asarray(msds.wavelengths, dtype=np.float64)
        return {k: (wl, np.asarray(msds.values[:, labels.index(c)], dtype=np.float64)) for k, c in columns.items()}
    if "file" in spec:
        got = read_curve_csv(FILTERS_DIR / spec["file"], list(columns.values()) if columns else None,
                             spec.get("unit", "fraction"), where)
        if columns:
            return {k: got[c] for k, c in columns.items()}
        return got
    return {}


def _build(name: str, spec: dict) -> SpectraSet:
    where = f"spectra set {name!r}"
    raw = _raw_columns(name, spec)
    model = spec.get("model", "common")
    if model not in _MODELS:
        raise CfaMitsubaError(f"{where}: model must be one of {', '.join(_MODELS)}, got {model!r}")
    si, ir = (silicon_qe(), ir_cut()) if model == "common" else (_FLAT, _FLAT)
    by_letter = spec.get("curve_by_letter", {})
    curves = {}
    for letter, c in raw.items():
        kind = by_letter.get(letter, spec.get("curve", "camera"))
        if kind not in _CURVES:
            raise CfaMitsubaError(f"{where}: curve must be one of {', '.join(_CURVES)}, got {kind!r}")
        if model == "flat":  # ISETCam: filter x 1 x 1, whatever the curve includes
            curves[letter] = c
            continue
        curves[letter] = {"dye": lambda: _product(c, ir, si), "pixel": lambda: _product(c, ir),
                          "camera": lambda: c}[kind]()
    if raw and spec.get("scale", "absolute") == "relative":
        if not all(k in curves for k in "RGB"):
            raise CfaMitsubaError(f"{where}: a relative set needs R, G and B to set its scale")
        peak = float(np.max(_sum(curves["R"], curves["G"], curves["B"])[1]))
        curves = {k: (wl, y * (_spectra.CAMERA_PEAK_QE / peak)) for k, (wl, y) in curves.items()}
    derive = spec.get("derive", [])
    unknown = [d for d in derive if d not in _DERIVES]
    if unknown:
        raise CfaMitsubaError(f"{where}: unknown derivation {unknown[0]!r} (known: {', '.join(_DERIVES)})")
    if "block-dyes" in derive:
        r, g, b = curves["R"], curves["G"], curves["B"]
        curves.update(C=_sum(g, b), M=_sum(r, b), Y=_sum(r, g), W=_sum(r, g, b))
    if "clear" in derive:
        curves["W"] = _product(ir, si) if model == "common" else _FLAT
    for letter, ref in spec.get("borrow", {}).items():
        other, _, src = ref.partition(":")
        curves[letter] = get_spectra_set(other).curve(src or letter)
    if "stacks" in derive:
        w = curves["W"]
        t = {k: _ratio(curves[k], w) for k in "CMY"}
        for letter, (a, b) in _STACKS.items():
            curves[letter] = _product(t[a], t[b], w)
    frozen = {}
    for letter, (wl, y) in curves.items():
        wl, y = np.array(wl, dtype=np.float64), np.array(y, dtype=np.float64)
        wl.flags.writeable = y.flags.writeable = False
        frozen[letter] = (wl, y)
    return SpectraSet(name=name, description=str(spec.get("description", "")), source=str(spec.get("source", "")),
                      family=str(spec.get("family", "any")), curves=frozen)


def list_spectra_sets() -> list[str]:
    """Names of the shipped spectra sets (``cfa-mitsuba list spectra``)."""
    return list(_all_specs())


@functools.lru_cache(maxsize=None)
def get_spectra_set(name: str) -> SpectraSet:
    """A spectra set by name, built on first use and cached."""
    if isinstance(name, SpectraSet):
        return name
    specs = _all_specs()
    if name not in specs:
        raise CfaMitsubaError(f"unknown spectra set {name!r} (known: {', '.join(specs)})")
    return _build(name, specs[name])


@functools.lru_cache(maxsize=None)
def common_ir_letters(name: str) -> frozenset:
    """The letters of a set whose curve carries the common IR-cut filter
    (:func:`ir_cut`): the ``dye`` and ``pixel`` curves, a ``clear`` W, sums
    and stacks of such letters, and borrowed letters that carry it where
    they come from.  A ``camera`` curve has the camera's own IR cut."""
    specs = _all_specs()
    if name not in specs:
        raise CfaMitsubaError(f"unknown spectra set {name!r} (known: {', '.join(specs)})")
    spec = specs[name]
    by_letter = spec.get("curve_by_letter", {})
    out = {k for k in _raw_columns(name, spec) if by_letter.get(k, spec.get("curve", "camera")) in ("dye", "pixel")}
    derive = spec.get("derive", [])
    if "block-dyes" in derive and {"R", "G", "B"} <= out:
        out |= {"C", "M", "Y", "W"}
    if "clear" in derive:
        out.add("W")
    for letter, ref in spec.get("borrow", {}).items():
        other, _, src = ref.partition(":")
        (out.add if (src or letter) in common_ir_letters(other) else out.discard)(letter)
    if "stacks" in derive and "W" in out:
        out |= set(_STACKS)
    return frozenset(out)
