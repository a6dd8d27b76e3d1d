"""Sharpening: the registry of sharpeners and the stage that applies one.

A sharpener is one module of this package declaring ``SHARPENERS =
(SharpenMethod(...),)`` beside its function ``f(image, **options) ->
image`` on an (H, W, 3) linear image, registered like the demosaics and
the denoisers (:func:`collect_sharpeners`; at run time
:func:`register_sharpener`).  The stage runs after demosaicing and the
colour matrix, on the XYZ image; the default is ``none``, so results
without it stand.  A linear sharpener (the unsharp mask) acting on every
channel alike commutes with the colour matrix, so applying it to the
camera channels or to XYZ is the same.

A study names a sharpener and its amount in one value (the ``sharpen``
axis, ``[isp] sharpen``): ``NAME`` or ``NAME:AMOUNT``, AMOUNT the
sharpener's ``amount`` option (:func:`sharpen_setting`).  A record's
``support`` says how far an output pixel's inputs reach
(:func:`sharpen_support_px`).
"""

from __future__ import annotations

__all__ = ["SharpenMethod", "collect_sharpeners", "register_sharpener", "unregister_sharpener", "list_sharpeners",
           "get_sharpener", "sharpener_parameters", "sharpen_image", "sharpen_setting", "sharpen_setting_name",
           "sharpen_support_px"]

import inspect
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ...errors import CfaMitsubaError


@dataclass(frozen=True, kw_only=True)
class SharpenMethod:
    """A sharpener's declaration in its module (``SHARPENERS``): name,
    function (None for ``none``), one-line description, licence, order, and
    ``support``: ``support(options) -> radius`` in pixels, how far an
    output pixel's inputs reach (the options with their defaults filled
    in); None: global."""

    name: str
    function: Callable | None
    description: str
    licence: str = ""
    order: int = 1000
    support: Callable[[dict], float] | None = None


_REGISTRY: dict[str, SharpenMethod] = {}


def collect_sharpeners(package: str = __name__) -> None:
    """Register the ``SHARPENERS`` of every module of ``package`` in their ``order``."""
    from ..declared import declared_records

    for m in declared_records(package, "SHARPENERS"):
        if m.name not in _REGISTRY:
            register_sharpener(m)


def register_sharpener(method: SharpenMethod, *, replace: bool = False) -> SharpenMethod:
    """Add a sharpener (a :class:`SharpenMethod`)."""
    if not isinstance(method, SharpenMethod):
        raise CfaMitsubaError(f"register_sharpener takes a SharpenMethod, got {type(method).__name__}")
    if method.name in _REGISTRY and not replace:
        raise CfaMitsubaError(f"a sharpener named {method.name!r} is already registered")
    _REGISTRY[method.name] = method
    return method


def unregister_sharpener(name: str) -> None:
    _REGISTRY.pop(name, None)


def list_sharpeners() -> list[tuple[str, str]]:
    """(name, one-line description) of every sharpener."""
    return [(m.name, m.description) for m in _REGISTRY.values()]


def get_sharpener(name: str) -> SharpenMethod:
    if name not in _REGISTRY:
        raise CfaMitsubaError(f"unknown sharpener {name!r} (known: {', '.join(_REGISTRY)})")
    return _REGISTRY[name]


def sharpener_parameters(name: str) -> dict:
    """{option: inspect.Parameter}: the keyword-only options of a sharpener."""
    m = get_sharpener(name)
    if m.function is None:
        return {}
    return {k: p for k, p in inspect.signature(m.function).parameters.items()
            if p.kind is inspect.Parameter.KEYWORD_ONLY}


def sharpen_setting(value) -> tuple[str, dict]:
    """(name, options) of a study's ``sharpen`` value: ``NAME`` or
    ``NAME:AMOUNT`` (the sharpener's ``amount`` option), e.g.
    ``'unsharp:1'`` -> ``('unsharp', {'amount': 1.0})``; a one-line error
    for anything else.

    >>> sharpen_setting("unsharp:1"), sharpen_setting("none")
    (('unsharp', {'amount': 1.0}), ('none', {}))
    """
    if not isinstance(value, str) or not value:
        raise CfaMitsubaError(f"a sharpen setting is a sharpener's name or NAME:AMOUNT, got {value!r}")
    name, sep, amount = value.partition(":")
    get_sharpener(name)
    if not sep:
        return name, {}
    if "amount" not in sharpener_parameters(name):
        raise CfaMitsubaError(f"sharpen {value!r}: {name!r} takes no amount")
    try:
        x = float(amount)
    except ValueError:
        x = float("nan")
    if not np.isfinite(x) or x < 0:
        raise CfaMitsubaError(f"sharpen {value!r}: the amount after ':' must be a number >= 0")
    return name, {"amount": x}


def sharpen_setting_name(value) -> str:
    """The one spelling of a ``sharpen`` setting: ``NAME``, or
    ``NAME:AMOUNT`` with AMOUNT as ``%g`` when it is not the sharpener's default."""
    name, options = sharpen_setting(value)
    if "amount" not in options or options["amount"] == sharpener_parameters(name)["amount"].default:
        return name
    return f"{name}:{options['amount']:g}"


def sharpen_support_px(name: str, options: dict | None = None) -> int | None:
    """How far (pixels, each axis) an output pixel's inputs reach for
    sharpener ``name`` with ``options``; None for a global method; 0 for ``none``."""
    m = get_sharpener(name)
    if m.function is None:
        return 0
    if m.support is None:
        return None
    known = sharpener_parameters(name)
    full = {k: dict(options or {}).get(k, p.default) for k, p in known.items()}
    return int(np.ceil(float(m.support(full))))


def sharpen_image(image: np.ndarray, name: str = "none", options: dict | None = None) -> tuple[np.ndarray, dict]:
    """(the sharpened (H, W, C) image, the record of what was applied), or
    a one-line error for an unknown sharpener or option."""
    m = get_sharpener(name)
    options = dict(options or {})
    known = sharpener_parameters(name)
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise CfaMitsubaError(f"sharpener {name!r} has no option {unknown[0]!r}"
                              + (f" (options: {', '.join(known)})" if known else " (it takes none)"))
    record = {"method": name, **{k: options.get(k, p.default) for k, p in known.items()}}
    if m.function is None:
        return image, record
    out = np.asarray(m.function(np.asarray(image, dtype=np.float64), **options), dtype=np.float64)
    if out.shape != image.shape or not np.all(np.isfinite(out)):
        raise CfaMitsubaError(f"sharpener {name!r} returned shape {out.shape} or non-finite values")
    return out, record


collect_sharpeners(__name__)
