"""Parity cases: checks of this project against ISETCam's own published
values, kept as TOML data (``tests/parity/isetcam/*.toml``) and run by
``cfa-mitsuba parity PATH... [--json]`` (docs/isetcam-parity.md).

A case names the ISETCam script it comes from (``source``), the value that
script gives (``expected``, ISETCam's number, never ours), a relative
``tolerance`` and the ``mode`` to run our chain in:

* ``"default"``: this project's physics and conventions (a box pixel
  aperture of the photodiode, sfrmat3's slanted-edge analysis, ...);
* ``"isetcam"``: ISETCam's mechanisms where they differ (its scene, its
  sampling of the optical image, its ISO 12233 conventions, its SNR
  formula), each one a mechanism, not a fitted constant.

Kinds of case (``kind``, default ``"image"``):

* ``image``: a built-in scene through optics, sensor, image processing and
  one metric whose headline value is compared (:mod:`.parity_image`);
* ``snr``: a pixel's SNR curve over signal levels (:mod:`.parity_snr`);
* ``colour``: a camera's mean colour error on the ColorChecker
  (:mod:`.parity_image`).

The verdict is ``agrees`` when |value - expected| <= tolerance x |expected|,
else ``differs``.  A result in dB (an SNR) is compared in dB: the allowance
tolerance x |expected| is a number of dB, and the command line prints the
difference and the allowance in dB (a percentage of a logarithm means
nothing); other results in percent.  A case may carry ``known_difference``: the measured
cause of a difference not yet removed (docs/isetcam-parity.md).
"""

from __future__ import annotations

__all__ = ["ParityCase", "load_case", "find_cases", "run_case", "run_parity", "describe_difference", "KINDS",
           "MODES"]

import math
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CfaMitsubaError
from .checker import _Checker, read_toml

MODES = ("isetcam", "default")
KINDS = ("image", "snr", "colour")
_COMMON = {"name", "source", "mode", "kind", "expected", "tolerance", "notes", "optics", "sensor", "known_difference"}
_BY_KIND = {
    "image": {"scene", "luminance", "demosaic", "metric", "isetcam", "noise", "seed", "render"},
    "snr": {"statistic", "levels", "exposure_s", "samples"},
    "colour": {"scene", "luminance", "demosaic", "metric", "noise", "seed", "render", "isp", "metric_options"},
}


@dataclass(frozen=True)
class ParityCase:
    """One validated case (module doc); ``settings`` holds the kind's own
    keys, ``optics`` and ``sensor`` their tables as written."""

    path: str
    name: str
    source: str
    mode: str
    kind: str
    expected: float
    tolerance: float
    settings: dict = field(default_factory=dict)
    optics: dict = field(default_factory=dict)
    sensor: dict = field(default_factory=dict)
    known_difference: str = ""


def load_case(path) -> ParityCase:
    """Read and check one case file; a bad key or value is one
    :class:`CfaMitsubaError` naming the file and the key."""
    p, data = read_toml(path, "parity case")
    ck = _Checker(p.name)
    kind = ck.string(data.get("kind", "image"), "kind", KINDS)
    unknown = sorted(set(data) - _COMMON - _BY_KIND[kind])
    if unknown:
        ck.fail(unknown[0], f"unknown key for a case of kind {kind!r} (known: "
                            f"{', '.join(sorted(_COMMON | _BY_KIND[kind]))})")
    for key in ("name", "source", "mode", "expected", "tolerance"):
        if key not in data:
            ck.fail(key, "missing")
    expected = ck.number(data["expected"], "expected")
    if not math.isfinite(expected):
        ck.fail("expected", f"must be finite (got {data['expected']!r})")
    settings = {k: data[k] for k in _BY_KIND[kind] if k in data}
    for key in ("optics", "sensor"):
        if not isinstance(data.get(key, {}), dict):
            ck.fail(key, "must be a table")
    if kind in ("image", "colour"):
        for key in ("scene", "metric"):
            if key not in data:
                ck.fail(key, "missing")
        settings["luminance"] = ck.number(data.get("luminance", 100.0), "luminance", positive=True)
    return ParityCase(path=str(p), name=ck.string(data["name"], "name"), source=ck.string(data["source"], "source"),
                      mode=ck.string(data["mode"], "mode", MODES), kind=kind, expected=expected,
                      tolerance=ck.number(data["tolerance"], "tolerance", nonneg=True), settings=settings,
                      optics=dict(data.get("optics", {})), sensor=dict(data.get("sensor", {})),
                      known_difference=ck.string(data["known_difference"], "known_difference")
                      if "known_difference" in data else "")


def find_cases(paths) -> list[Path]:
    """The case files named: files as given, folders' ``*.toml`` (sorted,
    recursively).  A missing path or a folder without cases is an error."""
    out = []
    for raw in paths:
        p = Path(raw)
        if p.is_dir():
            found = sorted(p.rglob("*.toml"))
            if not found:
                raise CfaMitsubaError(f"no parity cases (*.toml) in {str(p)!r}")
            out.extend(found)
        elif p.exists():  # a FIFO or device is refused by the reader, naming what it is
            out.append(p)
        else:
            raise CfaMitsubaError(f"no such parity case or folder: {str(p)!r}")
    if not out:
        raise CfaMitsubaError("no parity case given")
    return out


def run_case(case: ParityCase) -> dict:
    """Run one case: ``name``, ``expected``, ``value``, ``tolerance``,
    ``verdict`` (``agrees``/``differs``) plus ``mode``, ``kind``, ``source``,
    ``unit``, ``relative_difference`` and ``details`` (the stage values the
    chain produced)."""
    if case.kind == "snr":
        from .parity_snr import run_snr_case as run
    else:
        from .parity_image import run_image_case as run
    value, unit, details = run(case)
    rel = (value - case.expected) / abs(case.expected) if case.expected else value - case.expected
    allowed = case.tolerance * abs(case.expected)  # in the result's unit
    agrees = abs(value - case.expected) <= allowed + 1e-12
    return {"name": case.name, "expected": case.expected, "value": float(value), "tolerance": case.tolerance,
            "verdict": "agrees" if agrees else "differs", "mode": case.mode, "kind": case.kind,
            "unit": unit, "relative_difference": float(rel), "difference": float(value - case.expected),
            "tolerance_abs": float(allowed), "source": case.source,
            "file": case.path, "known_difference": case.known_difference, "details": details}


def describe_difference(result: dict) -> tuple[str, str]:
    """(difference, tolerance) of a :func:`run_case` result as text: a
    result in dB (an SNR) in dB, its tolerance the case's relative one times
    the expected value (the allowance :func:`run_case` applies); any other
    result in percent of the expected value."""
    if result.get("unit") == "dB":
        allowed = result.get("tolerance_abs", result["tolerance"] * abs(result["expected"]))
        return f"{result['value'] - result['expected']:+.3f} dB", f"±{allowed:.3g} dB"
    return f"{100 * result['relative_difference']:+.2f} %", f"±{100 * result['tolerance']:.3g} %"


def run_parity(paths, *, progress: bool = False) -> list[dict]:
    """Load every case first (so a bad file fails before any work), then run
    them in order; returns :func:`run_case`'s results.  ``progress``: a bar
    on a terminal, one step per case."""
    from ..io.progress import progress_bar

    cases = [load_case(p) for p in find_cases(paths)]
    names = [c.name for c in cases]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise CfaMitsubaError(f"parity case name {dup[0]!r} is used by more than one file")
    bar = progress_bar(len(cases), "parity", enabled=progress, unit="case")
    out = []
    try:
        for c in cases:
            bar.set_postfix_str(c.name)
            out.append(run_case(c))
            bar.update(1)
    finally:
        bar.close()
    return out
