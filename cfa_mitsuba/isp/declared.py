"""The records an ISP registry's modules declare: one discovery for the
demosaics, denoisers and sharpeners (each registry then adds them its way)."""

from __future__ import annotations

import importlib
import pkgutil


def declared_records(package: str, attribute: str) -> list:
    """The records every public module of ``package`` lists under ``attribute``
    (``DEMOSAICS``, ``DENOISERS``, ``SHARPENERS``), in their ``order``."""
    found = []
    for info in pkgutil.iter_modules(importlib.import_module(package).__path__):
        if not info.name.startswith("_"):
            found.extend(getattr(importlib.import_module(f"{package}.{info.name}"), attribute, ()))
    return sorted(found, key=lambda m: m.order)
