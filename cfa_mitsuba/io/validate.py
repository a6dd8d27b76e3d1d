"""Checks at the edge: every file the project reads is validated by its
content before anything is built from it.

* JSON documents (render sidecars, a metric's ``--geometry``, the JSON held
  in raw files) are bounded in size and nesting depth before they are parsed
  (a document nested 100000 deep would exhaust Python's recursion), refuse
  NaN and infinity (not JSON), and sidecars are checked against a JSON
  Schema (:data:`SIDECAR_SCHEMA`: types, ranges, shapes), so a field such as
  ``"white_radiance": "lots"`` is refused by name instead of failing deep
  inside the optics.
* ``.npy`` / ``.npz`` files are recognised by their bytes (the ``\\x93NUMPY``
  magic, a zip archive), not by their name, and every array's header is read
  (``numpy.lib.format``) before any data: an object array (a pickle) is
  refused without being unpickled, and the header-declared shape is checked
  against the memory available before the array is loaded.
* raw captures are checked for physical sense: quantum efficiency in 0..1,
  positive exposure and gain, a tile made of the file's channels and equal
  to the tile its settings record.

Every refusal is a one-line :class:`~cfa_mitsuba.errors.CfaMitsubaError`.
"""

from __future__ import annotations

__all__ = [
    "MAX_JSON_BYTES",
    "MAX_JSON_DEPTH",
    "SIDECAR_SCHEMA",
    "load_json_text",
    "check_sidecar",
    "numpy_arrays",
    "check_raw_arrays",
    "check_process_file",
    "safe_name",
]

import math
import re
import zipfile
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError, one_line
from .guard import MAX_JSON_BYTES, MAX_JSON_DEPTH, load_json_text  # noqa: F401 (re-exported)

_NUM = {"type": "number"}
_RECT = {"type": "array", "items": _NUM, "minItems": 4, "maxItems": 4}
_NUMBERS = {"type": "array", "items": _NUM}
_NON_NEGATIVE = {"type": "array", "items": {"type": "number", "minimum": 0}, "minItems": 1}

#: JSON Schema (draft 2020-12) of the sidecar keys the stages read; other
#: keys are free (a sidecar records more than is read back).
SIDECAR_SCHEMA = {
    "type": "object",
    "properties": {
        "scene": {"type": "string"},
        "width": {"type": "integer", "minimum": 1},
        "height": {"type": "integer", "minimum": 1},
        "oversample": {"type": "integer", "minimum": 1},
        "fov_deg": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 180},
        "f_number": {"type": "number", "exclusiveMinimum": 0},
        "scene_distance_m": {"anyOf": [{"type": "number", "exclusiveMinimum": 0},
                                       {"enum": ["inf", "infinity", "Infinity", "INF"]}]},
        "wavelengths": {"type": "array", "items": {"type": "number", "exclusiveMinimum": 0}, "minItems": 1},
        "band_edges_nm": _NUMBERS,
        "white_radiance": _NON_NEGATIVE,
        "canonical_white_radiance": _NON_NEGATIVE,
        "luminance_cd_m2": {"type": "number", "minimum": 0},
        "white_luminance_cd_m2": {"type": "number", "minimum": 0},
        "illuminant": {"type": "string"},
        "units": {"type": "string"},
        "metrics": {"type": "array", "items": {"type": "string"}},
        "spp": {"type": "integer", "minimum": 1},
        "seed": {"type": "integer", "minimum": 0},
        "geometry": {
            "type": "object",
            "properties": {
                "patches": {"type": "array", "items": {
                    "type": "object", "required": ["rect"],
                    "properties": {"rect": _RECT, "interior_rect": _RECT}}},
                "roi": _RECT,
                "row": {"type": "integer", "minimum": 0},
                "steps": {"type": "array", "items": {
                    "type": "object", "required": ["x0", "x1"], "properties": {"x0": _NUM, "x1": _NUM}}},
                "frequency_cy_per_deg": _NUMBERS,
                "frequency_cy_per_px": _NUMBERS,
                "fov_deg": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 180},
                "f_number": {"type": "number", "exclusiveMinimum": 0},
            },
        },
    },
}

def _where(path) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def check_sidecar(doc, what: str) -> dict:
    """Validate a parsed sidecar against :data:`SIDECAR_SCHEMA`; returns it."""
    import jsonschema

    if not isinstance(doc, dict):
        raise CfaMitsubaError(f"{what} is not a JSON object")
    err = jsonschema.exceptions.best_match(jsonschema.Draft202012Validator(SIDECAR_SCHEMA).iter_errors(doc))
    if err is not None:
        value = repr(err.instance)
        value = value if len(value) <= 60 else value[:57] + "..."
        reason = err.message if len(err.message) <= 120 else f"{value} is not allowed here ({err.validator})"
        raise CfaMitsubaError(f"{what}: {_where(err.absolute_path)}: {reason}")
    return doc


# ------------------------------------------------------------------ numpy


def _header(fh, where: str):
    from numpy.lib import format as npf

    try:
        version = npf.read_magic(fh)
        if version == (1, 0):
            return npf.read_array_header_1_0(fh)
        if version == (2, 0):
            return npf.read_array_header_2_0(fh)
        return npf._read_array_header(fh, version)  # 3.0: utf-8 field names; no public reader
    except (ValueError, OSError, EOFError, SyntaxError, TypeError) as exc:
        raise CfaMitsubaError(f"{where}: not a readable numpy array header ({one_line(exc, 120)})")


def _kind(path: Path) -> str:
    from .guard import open_regular

    with open_regular(path, "numpy file") as fh:  # not a FIFO or device
        magic = fh.read(6)
    if magic == b"\x93NUMPY":
        return "npy"
    if magic[:4] in (b"PK\x03\x04", b"PK\x05\x06"):
        return "npz"
    return "neither"


def numpy_arrays(path, expect: str) -> dict:
    """The arrays a ``.npy`` (``expect='npy'``) or ``.npz`` file holds, by
    content, from their headers alone: ``{name: (shape, dtype)}`` (a
    ``.npy``'s one array is named ``''``).

    Refuses a file whose bytes are not of the ``expect``-ed kind, an object
    (pickled) array, and arrays whose declared size (as float64, as every
    reader converts them) does not fit in the memory available.
    """
    from . import limits

    p = Path(path)
    kind = _kind(p)
    if kind != expect:
        found = {"npy": "a .npy array", "npz": "an .npz (zip) archive"}.get(kind, "neither a .npy array nor an .npz archive")
        want = "a valid .npy array" if expect == "npy" else "a valid .npz archive"
        raise CfaMitsubaError(f"{str(p)!r} is not {want}: its content is {found}")
    arrays = {}
    if kind == "npy":
        with open(p, "rb") as fh:
            shape, _, dtype = _header(fh, repr(str(p)))
        arrays[""] = (shape, dtype)
    else:
        try:
            with zipfile.ZipFile(p) as zf:
                for info in zf.infolist():
                    name = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
                    with zf.open(info) as fh:
                        shape, _, dtype = _header(fh, f"{str(p)!r}, array {name!r}")
                    arrays[name] = (shape, dtype)
        except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, RuntimeError) as exc:
            raise CfaMitsubaError(f"{str(p)!r} is not a readable .npz archive ({exc})") from None
    need = 0
    for name, (shape, dtype) in arrays.items():
        label = f"{str(p)!r}" + (f", array {name!r}," if name else "")
        if dtype.hasobject:
            raise CfaMitsubaError(f"{label} holds Python objects (a pickle): refused without unpickling; "
                                  "store numbers or strings")
        n = math.prod(int(s) for s in shape)
        need += n * (dtype.itemsize + 8)  # the stored array and its float64 copy
    limits.require_memory(need + (64 << 20), f"reading {str(p)!r} (arrays of {', '.join(str(s) for s, _ in arrays.values())})")
    return arrays


def check_process_file(raw_path) -> None:
    """Refuse to process a raw file whose mosaic (its header-declared shape)
    needs more memory than there is (:func:`.limits.estimate_process_bytes`)."""
    from . import limits

    path = Path(raw_path)
    if not path.is_file():
        return
    arrays = numpy_arrays(path, "npz")
    shape = arrays.get("raw", ((0, 0), None))[0]
    channels = arrays.get("channels", ((3,), None))[0]
    if len(shape) >= 2:
        c = int(channels[0]) if channels else 1
        limits.require_memory(limits.estimate_process_bytes(shape[0], shape[1], c),
                              f"processing {str(path)!r} ({shape[1]} x {shape[0]} pixels, {c} channels)")


# ------------------------------------------------------------- raw files


def _scalar(d: dict, key: str) -> float:
    v = np.asarray(d[key])
    if v.size != 1 or v.dtype.kind not in "biuf":
        raise CfaMitsubaError(f"{key} must be one number, got an array of shape {v.shape} ({v.dtype})")
    return float(v.reshape(()))


def check_raw_arrays(d: dict, settings: dict, where: str) -> None:
    """Physical sense of a raw capture's arrays (``d``: name -> array, as
    :mod:`.raw_npz` stores them); ``settings`` its parsed settings JSON."""
    def fail(msg):
        raise CfaMitsubaError(f"{where}: {msg}")

    try:
        exposure, gain, black, _ = (_scalar(d, k) for k in ("exposure_s", "dn_per_electron", "black_level_dn", "seed"))
    except CfaMitsubaError as exc:
        fail(str(exc))
    if not (math.isfinite(exposure) and exposure > 0):
        fail(f"exposure_s must be a positive number of seconds, got {exposure:g}")
    if not (math.isfinite(gain) and gain > 0):
        fail(f"dn_per_electron must be positive, got {gain:g}")
    if not (math.isfinite(black) and black >= 0):
        fail(f"black_level_dn must not be negative, got {black:g}")
    for key in ("spectra", "wavelengths", "electrons_per_radiance", "white_radiance", "raw"):
        if np.asarray(d[key]).dtype.kind not in "biuf":
            fail(f"{key} must be numeric, got {np.asarray(d[key]).dtype}")
    wl = np.asarray(d["wavelengths"], dtype=np.float64).reshape(-1)
    if wl.size < 1 or not np.all(np.isfinite(wl)) or np.any(wl <= 0) or np.any(np.diff(wl) <= 0):
        fail("wavelengths must be positive, finite and strictly ascending")
    for key in ("spectra", "electrons_per_radiance", "white_radiance"):
        a = np.asarray(d[key], dtype=np.float64)
        for bad, what in ((~np.isfinite(a), "is not finite"), (a < 0, "is negative")):
            if np.any(bad):
                at = np.argwhere(bad)[0]
                where_ = f" of channel {int(at[0])}" if a.ndim == 2 else ""
                fail(f"{key}{where_} {what} ({a[tuple(at)]:g}); it must be finite and non-negative")
    pattern = np.asarray(d["pattern"])
    channels = [str(c) for c in np.asarray(d["channels"]).reshape(-1)]
    if pattern.ndim != 2 or pattern.size == 0 or pattern.dtype.kind not in "US":
        fail(f"pattern must be a 2-D array of filter names, got shape {pattern.shape} ({pattern.dtype})")
    names = [[str(v) for v in row] for row in pattern.tolist()]
    ideal = names == [["XYZ"]]
    if not ideal:
        qe = np.asarray(d["spectra"], dtype=np.float64)
        if qe.size and qe.max() > 1:
            c = int(np.argmax(qe.max(axis=-1))) if qe.ndim == 2 else 0
            fail(f"quantum efficiency must lie in 0..1; channel {channels[c] if c < len(channels) else c!r} "
                 f"reaches {qe.max():g}")
        unknown = sorted({v for row in names for v in row} - set(channels))
        if unknown:
            fail(f"the tile names filter(s) {', '.join(map(repr, unknown))} that are not among its channels "
                 f"({', '.join(channels)})")
    tile = " / ".join(" ".join(row) for row in names)
    cfa = settings.get("cfa") if isinstance(settings, dict) else None
    recorded = cfa.get("tile") if isinstance(cfa, dict) else None
    if recorded is not None and " ".join(str(recorded).split()) != tile:
        fail(f"the tile recorded in its settings ({recorded!r}) does not match its pattern array ({tile!r})")


# ------------------------------------------------------------------ names


def safe_name(label: str, default: str = "study") -> str:
    """A label as one file-name component: letters, digits, ``-``, ``_`` and
    inner ``.`` kept, anything else (``/``, ``..``, spaces) made ``_``;
    never empty, ``.`` or ``..``, at most 100 characters.

    >>> safe_name("../../x"), safe_name("/etc"), safe_name("paper v2"), safe_name("..")
    ('___.._x', '_etc', 'paper_v2', '__')
    """
    text = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in str(label))[:100]
    text = re.sub(r"^\.+", lambda m: "_" * len(m.group()), text)
    return text or default
