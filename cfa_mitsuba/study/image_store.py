"""Optical and ideal images once per study, shared by its workers.

The optical image depends on the render and the optics (not on the CFA, the
demosaic, the luminance or the exposure), the ideal sensor's image on those
and the sensor, luminance and exposure; a study makes each once and every
worker that needs it reads it from the study's ``.work/images/`` folder:
the tasks of one render and condition go to one worker as a group
(:func:`.tasks.evaluate_group`) unless there are too few groups for the
workers, and this shares the images across split groups and the optical
image across conditions too (a luminance sweep's nine levels, spread over
the workers).  Locally and on a Dask cluster that sees the study's folder;
a worker that cannot read or write it computes the image itself (the same
values).  The folder is emptied when a study starts (:func:`fresh`), so an
image is never read from another run's renders.

Each image is one ``.npz`` (its arrays, its kind and its meta as JSON),
written to a temporary name in the folder and renamed into place (atomic:
a reader sees the whole file or none); read back, every array and meta
value is the computed one bit for bit (tests/study/test_image_store.py) (an image whose meta would not round
trip through JSON is not stored).  ``CFA_MITSUBA_NO_IMAGE_STORE=1`` turns
the store off.
"""

from __future__ import annotations

__all__ = ["FOLDER", "NO_STORE_ENV", "fresh", "load_or_make"]

import io as _io
import json
import os
import shutil
import tempfile
import zipfile
from pathlib import Path

import numpy as np

#: the store's folder inside a study's ``.work/``
FOLDER = "images"
#: Set to 1 to compute every optical image in the worker that needs it.
NO_STORE_ENV = "CFA_MITSUBA_NO_IMAGE_STORE"


def fresh(work: Path) -> Path:
    """``work`` made, its image store emptied; returns the store's folder."""
    work = Path(work)
    work.mkdir(exist_ok=True)
    shutil.rmtree(work / FOLDER, ignore_errors=True)
    return work / FOLDER


def _key(fields: dict) -> str:
    from ..io.cache import hash_key

    return hash_key(fields)


def _arrays(image) -> tuple[str, dict, dict]:
    """(kind, arrays, meta) of an optical image or a processed (ideal) image."""
    from ..values import OpticalImage

    if isinstance(image, OpticalImage):
        arrays = {"irradiance_w_m2_nm": image.irradiance_w_m2_nm, "wavelengths": image.wavelengths,
                  "sample_pitch_um": np.float64(image.sample_pitch_um)}
        if image.pixel_irradiance_w_m2_nm is not None:
            arrays["pixel_irradiance_w_m2_nm"] = image.pixel_irradiance_w_m2_nm
        return "optical", arrays, image.meta
    return "rendered", {"xyz": image.xyz, "srgb": image.srgb, "white_xyz": image.white_xyz}, image.meta


def _image(kind: str, data, meta: dict):
    from ..values import OpticalImage, RenderedImage

    if kind == "optical":
        pixel = data["pixel_irradiance_w_m2_nm"] if "pixel_irradiance_w_m2_nm" in data.files else None
        return OpticalImage(irradiance_w_m2_nm=data["irradiance_w_m2_nm"], wavelengths=data["wavelengths"],
                            sample_pitch_um=float(data["sample_pitch_um"]), meta=meta, pixel_irradiance_w_m2_nm=pixel)
    out = RenderedImage(xyz=data["xyz"], srgb=data["srgb"], white_xyz=data["white_xyz"], meta=meta)
    out.xyz.flags.writeable = False  # as the chain leaves the ideal's (compared with every camera output)
    return out


def _load(path: Path):
    try:
        with np.load(path, allow_pickle=False) as data:
            return _image(str(data["kind"]), data, json.loads(str(data["meta"])))
    except (OSError, ValueError, KeyError, zipfile.BadZipFile):  # absent, or half a file from a crashed writer
        return None


def _save(path: Path, image) -> None:
    kind, arrays, meta = _arrays(image)
    text = json.dumps(meta)
    if json.loads(text) != meta:  # would not come back the same: not stored
        return
    buf = _io.BytesIO()
    np.savez(buf, kind=np.str_(kind), meta=np.str_(text), **arrays)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".part-", suffix=".npz")
        with os.fdopen(fd, "wb") as f:
            f.write(buf.getbuffer())
        os.replace(tmp, path)
    except OSError:  # a folder this worker cannot write: the image stays its own
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)


def load_or_make(store: str | None, kind: str, fields: dict, make):
    """The image ``fields`` name (JSON-able: the render, the optics; for the
    ideal, the sensor, luminance and exposure too) from the study's store,
    else ``make()``, stored for the other workers; ``kind`` ('optical' or
    'ideal') starts its file name.  ``store`` None (no study) or
    :data:`NO_STORE_ENV` = 1: ``make()``."""
    if not store or os.environ.get(NO_STORE_ENV) == "1":
        return make()
    path = Path(store) / f"{kind}-{_key(fields)}.npz"
    got = _load(path) if path.is_file() else None
    if got is not None:
        return got
    oi = make()
    _save(path, oi)
    return oi
