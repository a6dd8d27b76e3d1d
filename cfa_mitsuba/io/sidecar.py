"""The sidecar: ``X.json`` beside ``X.exr``, the render's metadata as JSON.

Its keys (render settings, units, field of view, the scene's geometry) are
listed in docs/scenes.md; later stages read them from
``SpectralImage.meta``.  Written atomically, read with one-line errors.
"""

from __future__ import annotations

__all__ = ["sidecar_path", "read_sidecar", "write_sidecar", "json_default"]

import json
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError
from .atomic import atomic_output


def sidecar_path(exr_path) -> Path:
    """``DIR/name.json`` for ``DIR/name.exr``."""
    return Path(exr_path).with_suffix(".json")


def json_default(obj):
    """JSON encoder hook for numpy values, tuples kept as lists, paths."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON-serialisable: {type(obj).__name__}")


def write_sidecar(path, meta: dict) -> Path:
    """Write ``meta`` as indented JSON to ``path``, atomically.  NaN and
    infinities are refused (JSON has no such numbers)."""
    p = Path(path)
    try:
        text = json.dumps(meta, default=json_default, indent=1, allow_nan=False)
    except ValueError as exc:
        raise CfaMitsubaError(f"refusing to write sidecar {str(p)!r}: {exc}") from None
    with atomic_output(p) as tmp:
        tmp.write_text(text + "\n")
    return p


def read_sidecar(path) -> dict:
    """Read a sidecar JSON object; a one-line error if missing, malformed,
    nested too deeply or not of the sidecar schema (:mod:`.validate`)."""
    from .validate import check_sidecar, load_json_text

    from .guard import read_text

    p = Path(path)
    if not p.exists():
        raise CfaMitsubaError(f"no such sidecar: {str(p)!r}")
    text = read_text(p, "sidecar")  # regular file, bounded, strict UTF-8
    # bounded (size, depth), then checked against the schema of what the stages read
    return check_sidecar(load_json_text(text, f"sidecar {str(p)!r}"), f"sidecar {str(p)!r}")
