"""Raw captures as ``.npz``: everything ``process`` needs, no pickles.

Arrays (``numpy.load(path, allow_pickle=False)`` reads them all):

==========================  ==================================================
``format``                  ``"cfa-mitsuba raw 1"``
``raw``                     (H, W) float64 DN of the mosaic; (H, W, 3) XYZ for
                            the ideal sensor (Y in cd/m^2)
``pattern``                 (th, tw) str, the CFA tile (``[['XYZ']]`` ideal)
``channels``                (C,) str, channel order of ``spectra``
``spectra``                 (C, B) quantum efficiency per channel (the CIE
                            colour-matching functions for the ideal sensor)
``wavelengths``             (B,) band centres, nm
``electrons_per_radiance``  (C, B) electrons of an on-axis pixel per unit band
                            radiance, W/(m^2 sr nm), in this exposure
``white_radiance``          (B,) a perfect white diffuser under the scene's
                            light, at the captured scale, W/(m^2 sr nm)
``exposure_s``              () seconds
``dn_per_electron``         () DN per electron (analog gain included)
``black_level_dn``          () DN (0 unless noise ``all``)
``seed``                    () int, -1 when none (ideal sensor)
``settings_json``           () str, JSON: noise, exposure mode, luminance,
                            sensor, optics, CFA name/description/tile
``meta_json``               () str, JSON: the scene's sidecar plus optics
                            geometry, ``oversample``, ``pixel_pitch_um``,
                            ``luminance_cd_m2`` used, ``white_source``
==========================  ==================================================
"""

from __future__ import annotations

__all__ = ["RAW_FORMAT", "save_raw_npz", "load_raw_npz"]

import json
import math
import zipfile
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError
from ..values import RawImage
from .atomic import atomic_output

RAW_FORMAT = "cfa-mitsuba raw 1"
_ARRAYS = ("raw", "pattern", "channels", "spectra", "wavelengths", "electrons_per_radiance", "white_radiance",
           "exposure_s", "dn_per_electron", "black_level_dn", "seed", "settings_json", "meta_json")


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else str(v)  # "inf", "nan": strict JSON
    if isinstance(obj, Path):
        return str(obj)
    return obj


def save_raw_npz(path, raw: RawImage, *, compress: bool = True) -> Path:
    """Write ``raw`` to ``path`` (.npz) atomically; returns the path."""
    target = Path(path)
    if target.suffix.lower() != ".npz":
        raise CfaMitsubaError(f"raw output {str(target)!r} must end with .npz")
    if target.is_dir():
        raise CfaMitsubaError(f"raw output {str(target)!r} is a directory")
    arrays = {
        "format": np.array(RAW_FORMAT),
        "raw": np.asarray(raw.raw, dtype=np.float64),
        "pattern": np.asarray(raw.pattern, dtype=str),
        "channels": np.asarray(list(raw.channels), dtype=str),
        "spectra": np.asarray(raw.spectra, dtype=np.float64),
        "wavelengths": np.asarray(raw.wavelengths, dtype=np.float64),
        "electrons_per_radiance": np.asarray(raw.electrons_per_radiance, dtype=np.float64),
        "white_radiance": np.asarray(raw.white_radiance, dtype=np.float64),
        "exposure_s": np.array(float(raw.exposure_s)),
        "dn_per_electron": np.array(float(raw.dn_per_electron)),
        "black_level_dn": np.array(float(raw.black_level_dn)),
        "seed": np.array(-1 if raw.seed is None else int(raw.seed), dtype=np.int64),
        "settings_json": np.array(json.dumps(_jsonable(raw.settings), sort_keys=True)),
        "meta_json": np.array(json.dumps(_jsonable(raw.meta), sort_keys=True)),
    }
    with atomic_output(target) as tmp:
        with open(tmp, "wb") as fh:  # a file object: np.savez would append .npz to a path
            (np.savez_compressed if compress else np.savez)(fh, **arrays)
    return target


def load_raw_npz(path) -> RawImage:
    """Read a raw file written by :func:`save_raw_npz`."""
    from .raw_content import check_raw_content
    from .validate import check_raw_arrays, load_json_text, numpy_arrays

    p = Path(path)
    if p.is_dir():
        raise CfaMitsubaError(f"raw file {str(p)!r} is a directory")
    if not p.exists():
        raise CfaMitsubaError(f"raw file {str(p)!r} does not exist")
    numpy_arrays(p, "npz")  # by content: an archive, no pickled arrays, sizes that fit in memory
    from .guard import open_regular

    try:
        with open_regular(p, "raw file") as fh, np.load(fh, allow_pickle=False) as z:
            missing = [k for k in _ARRAYS if k not in z.files]
            if missing:
                raise CfaMitsubaError(f"{str(p)!r} is not a cfa-mitsuba raw file (no {missing[0]!r})")
            d = {k: z[k] for k in _ARRAYS}
            fmt = str(z["format"]) if "format" in z.files else "?"
    except FileNotFoundError:
        raise CfaMitsubaError(f"raw file {str(p)!r} does not exist") from None
    except IsADirectoryError:
        raise CfaMitsubaError(f"raw file {str(p)!r} is a directory") from None
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        if isinstance(exc, CfaMitsubaError):
            raise
        raise CfaMitsubaError(f"cannot read raw file {str(p)!r}: not a valid .npz ({exc})") from None
    if fmt != RAW_FORMAT:
        raise CfaMitsubaError(f"{str(p)!r}: unknown raw format {fmt!r} (expected {RAW_FORMAT!r})")
    settings = load_json_text(str(d["settings_json"]), f"{str(p)!r}: settings_json")
    meta = load_json_text(str(d["meta_json"]), f"{str(p)!r}: meta_json")
    if not isinstance(settings, dict) or not isinstance(meta, dict):
        raise CfaMitsubaError(f"{str(p)!r}: settings_json and meta_json must be JSON objects")
    check_raw_arrays(d, settings, repr(str(p)))  # QE in 0..1, positive exposure, tile = pattern
    check_raw_content(d, settings, repr(str(p)))  # the pixels against the tile and the recorded settings
    seed = int(d["seed"])
    raw = RawImage(
        raw=d["raw"], pattern=d["pattern"], channels=tuple(str(c) for c in d["channels"]), spectra=d["spectra"],
        wavelengths=d["wavelengths"], electrons_per_radiance=d["electrons_per_radiance"],
        white_radiance=d["white_radiance"], exposure_s=float(d["exposure_s"]),
        dn_per_electron=float(d["dn_per_electron"]), black_level_dn=float(d["black_level_dn"]),
        seed=None if seed < 0 else seed, settings=settings, meta=meta,
    )
    c, b = len(raw.channels), raw.wavelengths.size
    if raw.spectra.shape != (c, b) or raw.electrons_per_radiance.shape != (c, b) or raw.white_radiance.shape != (b,):
        raise CfaMitsubaError(f"{str(p)!r}: inconsistent array shapes for {c} channels and {b} bands")
    if raw.raw.ndim not in (2, 3):
        raise CfaMitsubaError(f"{str(p)!r}: raw must be 2-D (mosaic) or 3-D (ideal XYZ), got {raw.raw.shape}")
    return raw
