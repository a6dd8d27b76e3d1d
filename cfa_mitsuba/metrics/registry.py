"""The metric registry: the records that the metric modules define, collected,
and one generic adapter that computes any of them by name.

A metric is one module of this package holding its pure function and, beside
it, ``RECORDS = (MetricRecord(...), ...)`` (:mod:`.record`).  This module
imports every module of the package and collects those records, so adding a
metric edits nothing here; :func:`register_metric` adds one at run time (a
user's plug-in, a test's toy metric).  :func:`evaluate` passes each function
what it takes, by name (colour-science's ``filter_kwargs``): its images by
the record's ``inputs``, the options given, and any keyword the scene
geometry holds (``patches``, ``roi``, ``row``, ``steps``,
``samples_per_degree``, ``frequency_cy_per_deg``) or the pixel pitch.
"""

from __future__ import annotations

__all__ = ["METRICS", "study_options", "summary_options", "register_metric", "unregister_metric", "get_metric", "metric_names", "scored_metrics", "metrics_for_scene",
           "list_metrics", "record_json", "evaluate", "evaluate_many", "result_rows", "metric_parameters",
           "GEOMETRY_KEYWORDS"]

import importlib
import inspect
import pkgutil
from functools import lru_cache

import numpy as np

from ..errors import CfaMitsubaError
from ._result import MetricResult
from .inputs import MetricInputs
from .record import MetricRecord

#: Keywords the adapter fills from the scene geometry or the camera, each with
#: what a scene must provide for it: a config cannot set them.
GEOMETRY_KEYWORDS = {
    "patches": "the chart's patch rectangles", "grey_patches": "the chart's grey patches",
    "roi": "the edge's region of interest", "row": "the chart's measuring row", "steps": "the gray bar's steps",
    "frequency_cy_per_deg": "the chirp's frequency per column", "samples_per_degree": "the field of view (fov_deg)",
    "pixel_pitch_um": "the sensor's pixel pitch", "reference": "the ideal sensor's image",
    "texture_roi": "the dead-leaves chart's texture square", "flat_roi": "the dead-leaves chart's flat patch",
    "dead_leaves": "the dead-leaves chart's pattern record",
}

#: Of those, the ones a study may still set (ISETCam's S-CIELAB settings name
#: the samples per degree): the option wins over the geometry.
SETTABLE_GEOMETRY = frozenset({"samples_per_degree"})

#: The registry, filled by :func:`_collect` (in the records' ``order``).
METRICS: dict[str, MetricRecord] = {}


def register_metric(record: MetricRecord, *, replace: bool = False) -> MetricRecord:
    """Add ``record`` to the registry (``replace`` to overwrite one of the same name)."""
    if not isinstance(record, MetricRecord):
        raise TypeError(f"register_metric takes a MetricRecord, got {type(record).__name__}")
    if record.name in METRICS and not replace:
        raise CfaMitsubaError(f"a metric named {record.name!r} is already registered")
    if record.parent is not None and record.parent not in METRICS:
        raise CfaMitsubaError(f"metric {record.name!r} reads {record.parent!r}'s details; register that first")
    METRICS[record.name] = record
    ordered = sorted(METRICS.values(), key=lambda r: r.order)  # stable: ties keep registration order
    METRICS.clear()
    METRICS.update((r.name, r) for r in ordered)
    return record


def unregister_metric(name: str) -> None:
    """Remove a registered metric and the values read from its details (a test's toy one)."""
    for n in [n for n, r in METRICS.items() if n == name or r.parent == name]:
        del METRICS[n]


def _collect() -> None:
    """Import every module of the package and register the records it defines."""
    found = []
    for info in pkgutil.iter_modules(importlib.import_module(__package__).__path__):
        if info.name.startswith("_") or info.name in ("registry", "record", "inputs"):
            continue
        found.extend(getattr(importlib.import_module(f"{__package__}.{info.name}"), "RECORDS", ()))
    for r in sorted(found, key=lambda r: (r.parent is not None, r.order)):  # parents before their values
        register_metric(r)


def get_metric(name: str) -> MetricRecord:
    """The record of a metric by its command-line name (``'delta-e'``, ...)."""
    try:
        return METRICS[name]
    except KeyError:
        known = ", ".join(r.name for r in METRICS.values() if not r.secondary)
        raise CfaMitsubaError(f"unknown metric {name!r} (expected one of: {known})") from None


def metric_names(*, secondary: bool = False) -> tuple[str, ...]:
    """The computable metrics (and, with ``secondary``, the derived values too)."""
    return tuple(r.name for r in METRICS.values() if secondary or not r.secondary)


def scored_metrics() -> tuple[str, ...]:
    """The metrics that enter the normalised scores, in the paper's order."""
    return tuple(r.name for r in METRICS.values() if r.scored)


def metrics_for_scene(kind: str) -> tuple[str, ...]:
    """The computable metrics a scene of ``kind`` feeds (``render.Scene.kind``:
    a chart's own kind, or :data:`~.record.NATURAL`).

    >>> metrics_for_scene("macbeth")[0]
    'delta-e'
    >>> {"scielab", "ssim", "mdsi", "haarpsi"} <= set(metrics_for_scene("natural"))
    True"""
    return tuple(r.name for r in METRICS.values() if not r.secondary and kind in r.scenes)


def list_metrics() -> list[tuple[str, str]]:
    """(name, one-line description) of every computable metric, for ``cfa-mitsuba list metrics``."""
    return [(r.name, f"[{', '.join(r.scenes)}] {r.description}") for r in METRICS.values() if not r.secondary]


def record_json(r: MetricRecord) -> dict:
    """A record as JSON (``cfa-mitsuba list metrics --json``)."""
    fn = None if r.function is None else f"{r.function.__module__.rsplit('.', 1)[0]}.{r.function.__name__}"
    return {
        "name": r.name, "scenes": list(r.scenes), "inputs": r.inputs, "unit": r.unit,
        "higher_is_better": r.higher_is_better, "scored": r.scored, "identical_value": r.identical_value,
        "score_range": None if r.score_range is None else {"worst": r.score_range[0], "best": r.score_range[1],
                                                           "scaling": r.range_scaling},
        "label": r.label, "description": r.description, "paper": r.paper,
        "derived_from": r.parent, "censored_key": r.censored_key, "function": fn,
        "study_options": dict(r.study_options), "summary_options": dict(r.summary_options),
        "practical_difference": dict(r.practical_difference), "practical_source": r.practical_source,
    }


@lru_cache(maxsize=None)
def _parameters(fn) -> dict:
    return dict(inspect.signature(fn).parameters)


def study_options() -> dict[str, dict]:
    """{metric: {keyword: value}}: the records' ``study_options``, which a
    study passes unless its config sets them."""
    return {r.name: dict(r.study_options) for r in METRICS.values() if r.study_options}


def summary_options() -> dict[str, dict]:
    """{metric: {keyword: value}}: the records' ``summary_options``, which a
    study passes for the camera outputs whose details it does not keep."""
    return {r.name: dict(r.summary_options) for r in METRICS.values() if r.summary_options}


def metric_parameters(name: str) -> dict[str, inspect.Parameter]:
    """The options a study or the command line may set for a metric: its
    function's keyword-only parameters that the adapter does not fill."""
    r = get_metric(name)
    return {k: p for k, p in _parameters(r.function).items()
            if p.kind is inspect.Parameter.KEYWORD_ONLY and (k not in GEOMETRY_KEYWORDS or k in SETTABLE_GEOMETRY)
            and k != _reference_keyword(r)}


def _reference_keyword(r: MetricRecord) -> str | None:
    return None if r.reference_cache is None else r.reference_cache[0]


def _images(r: MetricRecord, inp: MetricInputs) -> tuple:
    """The positional arguments of ``r.function`` by the record's ``inputs``."""
    if r.inputs == "xyz":
        if inp.reference_xyz is None or inp.test_xyz is None or inp.white_xyz is None:
            raise CfaMitsubaError(f"{r.name} compares two XYZ images with a white point; one is missing")
        return inp.reference_xyz, inp.test_xyz, inp.white_xyz
    if r.inputs == "srgb8":
        a, b = inp.srgb8("reference"), inp.srgb8("test")
        if a is None or b is None:
            raise CfaMitsubaError(f"{r.function.__name__} compares two images; one is missing")
        return a, b
    return (inp.linear("test"),)


def _keywords(r: MetricRecord, inp: MetricInputs, options: dict) -> dict:
    """The keywords of ``r.function``: the options it takes (None: not given),
    then what the geometry, the pixel pitch or the reference image supply."""
    params = _parameters(r.function)
    kw = {k: v for k, v in options.items() if k in params and v is not None}
    supplied = {**inp.geometry, "pixel_pitch_um": inp.pixel_pitch_um}
    if r.inputs == "linear":
        supplied["reference"] = inp.linear("reference")
    for k, p in params.items():
        if p.kind is not inspect.Parameter.KEYWORD_ONLY or k in kw:
            continue
        if k in GEOMETRY_KEYWORDS and supplied.get(k) is not None:
            kw[k] = supplied[k]
        elif p.default is inspect.Parameter.empty:
            what = GEOMETRY_KEYWORDS.get(k, f"the option '{k}'")
            raise CfaMitsubaError(f"{r.name} needs {what} in the render's sidecar ('{k}'); this scene has none")
    return kw


def _reference_part(r: MetricRecord, inp: MetricInputs, images: tuple, kw: dict) -> dict:
    """What depends on the reference alone, computed once per ideal image and
    option set (kept in ``inp.shared``) and passed as the record's keyword."""
    keyword, fn = r.reference_cache
    taken = _parameters(fn)
    ref_kw = {k: v for k, v in kw.items() if k in taken}
    key = (r.name, tuple(sorted((k, float(v) if isinstance(v, (int, float)) else v) for k, v in ref_kw.items())))
    if key not in inp.shared:
        inp.shared[key] = fn(images[0], *images[2:], **ref_kw)  # the reference (and the white, for XYZ)
    return {keyword: inp.shared[key]}


def evaluate(name: str, inputs: MetricInputs, **options):
    """Compute one metric by name.

    ``options`` are the metric function's own keywords (``version``,
    ``block``, ``threshold``, ``roi``, ``samples_per_degree``, ...); those a
    metric does not take are ignored.  Returns a :class:`MetricResult` (the
    single-number indices are wrapped so every result has a unit).  Raises
    :class:`CfaMitsubaError` when the scene geometry it needs is missing.
    """
    r = get_metric(name)
    if r.secondary:
        raise CfaMitsubaError(f"{name} is read from {r.parent}'s result; evaluate {r.parent}")
    kw = _keywords(r, inputs, options)
    images = _images(r, inputs)
    if r.reference_cache is not None and _reference_keyword(r) not in kw:
        kw.update(_reference_part(r, inputs, images, kw))
    out = r.function(*images, **kw)
    if not isinstance(out, MetricResult):
        out = MetricResult(out, name=name, unit=r.unit)
    return out


def evaluate_many(names, inputs: MetricInputs, failures: list | None = None, *, options: dict | None = None) -> dict:
    """{name: MetricResult} for each name.  A metric that cannot be computed
    on this image (a user-facing :class:`CfaMitsubaError`, e.g. an edge the
    analysis cannot locate) is left out and its message appended to
    ``failures`` when given, so one unmeasurable camera does not end a
    study; without ``failures`` it raises.  ``options``: {name: {keyword:
    value}} passed to :func:`evaluate` (a study's ``[metrics.<name>]``)."""
    out = {}
    options = options or {}
    for name in names:
        try:
            out[name] = evaluate(name, inputs, **options.get(name, {}))
        except CfaMitsubaError as exc:
            if failures is None:
                raise
            failures.append({"metric": name, "error": str(exc)})
    return out


def result_rows(results: dict) -> list[dict]:
    """Tidy rows ``{metric, value, unit, censored}`` for results of
    :func:`evaluate_many`: each headline value, then the secondary values its
    details hold.  ``censored`` is True where the value is a bound, not a
    measurement (the record's ``censored_key``: an MSP with no moire up to
    the chirp's top frequency)."""
    rows = []
    for name, res in results.items():
        rec = METRICS[name]
        details = getattr(res, "details", {}) or {}
        censored = bool(details.get(rec.censored_key, False)) if rec.censored_key else False
        rows.append({"metric": name, "value": float(res), "unit": getattr(res, "unit", None) or rec.unit,
                     "censored": censored})
        for sec in METRICS.values():
            if sec.parent != name:
                continue
            v = details.get(sec.detail_key)
            if v is not None and np.isfinite(v):
                rows.append({"metric": sec.name, "value": float(v), "unit": sec.unit, "censored": False})
    return rows


_collect()
