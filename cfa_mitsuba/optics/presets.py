"""Named optics presets, read from ``cfa_mitsuba/data/optics.toml``.

``get_optics_preset("isetcam-default")`` gives an :class:`OpticsPreset`
whose ``params`` is an :class:`~cfa_mitsuba.optics.lens.OpticsParams` and
whose ``focal_length_mm`` is the preset lens's focal length (mm), which
this project otherwise derives from the field of view.
"""

from __future__ import annotations

__all__ = ["OpticsPreset", "get_optics_preset", "list_optics_presets"]

import functools
from dataclasses import dataclass, fields
from pathlib import Path

from ..errors import CfaMitsubaError
from .lens import OpticsParams

_DATA = Path(__file__).resolve().parent.parent / "data" / "optics.toml"


@dataclass(frozen=True)
class OpticsPreset:
    """A named lens: ``params`` (OpticsParams), ``focal_length_mm`` (mm) and
    two lines of provenance."""

    name: str
    description: str
    source: str
    params: OpticsParams
    focal_length_mm: float


@functools.lru_cache(maxsize=1)
def _definitions() -> dict:
    from ..io.guard import read_toml

    try:
        return read_toml(_DATA, "optics presets")
    except CfaMitsubaError as exc:
        raise CfaMitsubaError(f"cannot read the optics presets {str(_DATA)!r}: {exc}") from None


def list_optics_presets() -> list[str]:
    """Names of the shipped optics presets (the tables of optics.toml)."""
    return sorted(_definitions())


@functools.lru_cache(maxsize=None)
def get_optics_preset(name: str) -> OpticsPreset:
    """A preset by name; an unknown name is a one-line error listing them."""
    entry = dict(_definitions().get(name) or {})
    if not entry:
        raise CfaMitsubaError(f"unknown optics preset {name!r} (known: {', '.join(list_optics_presets())})")
    meta = {k: entry.pop(k, "") for k in ("description", "source")}
    focal = entry.pop("focal_length_mm", None)
    if not isinstance(focal, (int, float)) or isinstance(focal, bool) or not focal > 0:
        raise CfaMitsubaError(f"optics preset {name!r}: focal_length_mm must be a positive number, got {focal!r}")
    known = {f.name for f in fields(OpticsParams)}
    unknown = sorted(set(entry) - known)
    if unknown:
        raise CfaMitsubaError(f"optics preset {name!r}: unknown key {unknown[0]!r}")
    return OpticsPreset(name=name, description=meta["description"], source=meta["source"],
                        params=OpticsParams(**entry), focal_length_mm=float(focal))
