"""One record per metric: everything the rest of the program needs to know
about a metric, in one place.

A :class:`MetricRecord` says what a metric is called, which scenes feed it,
what inputs it reads, its unit, which direction is better, whether it enters
the scores and with which default range (eq. 8 of Bae 2020), and how it is
labelled in tables and plots.  :func:`evaluate` computes any metric by name
from a :class:`MetricInputs` (the study, the ``metric`` command and the
convergence study all go through it); the report reads the same records.

Adding a metric is its module (a pure function in ``metrics/``) plus one
entry in :data:`METRICS` below (docs/metrics.md walks through it).  The
pattern is colour-science's ``DELTA_E_METHODS`` + ``filter_kwargs``: one
table maps names to functions, one dispatcher passes each only the keywords
it takes.
"""

from __future__ import annotations

__all__ = ["MetricRecord", "MetricInputs", "METRICS", "NATURAL", "get_metric", "list_metrics", "metric_names",
           "scored_metrics", "metrics_for_scene", "evaluate", "evaluate_many", "result_rows", "record_json"]

import inspect
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..errors import CfaMitsubaError
from . import colour as mcolour
from ._result import MetricResult
from .achromatic import achromatic
from .delta_e import delta_e
from .haarpsi import haarpsi
from .mdsi import mdsi
from .moire import moire
from .mtf import mtf
from .scielab import scielab, scielab_reference_lab
from .ssim import ssim

#: The scene kind of a natural (3D or measured) scene: the built-in puppy, a
#: user's Mitsuba XML, a measured spectral image.  The charts are their own kinds.
NATURAL = "natural"


class MetricInputs:
    """What a metric may read, built once per camera output and shared by
    every metric computed on it (conversions are made on first use).

    Parameters
    ----------
    reference_xyz, test_xyz : (H, W, 3) absolute CIE XYZ of the ideal sensor
        and of the camera (same scale as ``white_xyz``); None where a caller
        has only display images.
    white_xyz : (3,) XYZ of the scene white.
    geometry : the scene geometry (:func:`~cfa_mitsuba.metrics.scene_geometry`):
        patches, roi, row, steps, samples_per_degree, frequency_cy_per_deg.
    pixel_pitch_um : the sensor's pixel pitch (um), for MTF in cy/mm.
    reference_srgb8, test_srgb8 : 8-bit sRGB code values (0..255 floats),
        given directly or derived from XYZ (white -> 255).
    reference_linear, test_linear : linear sRGB with the white at 1, given
        directly or derived from XYZ.
    shared : a dict kept with the reference image (the caller's: one per
        ideal image), where what depends on the reference alone (its sRGB
        codes, S-CIELAB's filtered reference) is computed once for every
        camera output compared with it.
    """

    def __init__(self, reference_xyz=None, test_xyz=None, white_xyz=None, *, geometry: dict | None = None,
                 pixel_pitch_um: float | None = None, reference_srgb8=None, test_srgb8=None,
                 reference_linear=None, test_linear=None, shared: dict | None = None):
        self.reference_xyz = reference_xyz
        self.test_xyz = test_xyz
        self.white_xyz = None if white_xyz is None else np.asarray(white_xyz, dtype=np.float64)
        self.geometry = dict(geometry or {})
        self.pixel_pitch_um = pixel_pitch_um
        self.shared = shared if shared is not None else {}
        self._srgb8 = {"reference": reference_srgb8 if reference_srgb8 is not None
                       else self.shared.get("srgb8_reference"), "test": test_srgb8}
        self._linear = {"reference": reference_linear if reference_linear is not None
                        else self.shared.get("linear_reference"), "test": test_linear}

    def _xyz(self, which: str):
        return self.reference_xyz if which == "reference" else self.test_xyz

    def srgb8(self, which: str):
        """8-bit sRGB code values of ``which`` ('reference' or 'test'), quantised."""
        if self._srgb8[which] is None and self._xyz(which) is not None:
            self._srgb8[which] = mcolour.xyz_to_srgb8(self._xyz(which), self.white_xyz)
            if which == "reference":
                self.shared["srgb8_reference"] = self._srgb8[which]
        return self._srgb8[which]

    def linear(self, which: str):
        """Linear sRGB of ``which`` with the scene white at 1 (None if absent)."""
        if self._linear[which] is None and self._xyz(which) is not None:
            self._linear[which] = mcolour.xyz_to_linear(self._xyz(which), scale=float(self.white_xyz[1]))
            if which == "reference":
                self.shared["linear_reference"] = self._linear[which]
        return self._linear[which]


@dataclass(frozen=True)
class MetricRecord:
    """A metric, as the study, the command line and the report see it.

    Attributes
    ----------
    name : the command-line name (``'delta-e'``).
    function : the pure metric function (``metrics.delta_e``), or None for a
        value read from another metric's details (``parent``, ``detail_key``).
    scenes : the scenes that feed it: built-in scene names, or :data:`NATURAL`
        for any natural scene (puppy, user XML, measured image).
    inputs : ``'xyz'`` (absolute XYZ + white), ``'srgb8'`` (8-bit code values)
        or ``'linear'`` (one linear image, the edge).
    unit : unit of the headline value ('' for unitless indices).
    higher_is_better : direction of "better".
    scored : whether it enters the normalised scores (the paper's eight).
    score_range : eq. 8's default (worst, best), the paper's printed range;
        None for unscored metrics.
    range_units : the units the range applies to (default: ``unit``).
    range_scaling : how the default range follows the study's geometry:
        None (as printed); ``'pixel_pitch'`` (printed at 2.2 um, moved so the
        same cycles per pixel score the same); ``'chirp_cy_px'`` (the range
        is in cycles per camera pixel, times the chirp's samples per degree).
    label, description, decimals, paper : how tables and plots show it.
    needs : geometry keys it cannot run without, each with what it means.
    parent, detail_key : for a secondary value (``delta-l``): the metric
        whose details hold it and the key.
    censored_key : the details key (a bool) that says the headline is a
        bound, not a measurement (``moire``: no moire found up to the chirp's
        top frequency, so the MSP is at least that); None for metrics whose
        value is always measured.
    """

    name: str
    function: Callable | None
    scenes: tuple[str, ...]
    inputs: str
    unit: str
    higher_is_better: bool
    scored: bool
    label: str
    description: str
    decimals: int = 3
    paper: str = "—"
    score_range: tuple[float, float] | None = None
    range_scaling: str | None = None
    range_units: tuple[str, ...] | None = None
    needs: dict = field(default_factory=dict)
    parent: str | None = None
    detail_key: str | None = None
    censored_key: str | None = None
    compute: Callable[["MetricInputs", dict], Any] | None = field(default=None, repr=False)

    @property
    def secondary(self) -> bool:
        return self.parent is not None


def _accepted(fn: Callable, options: dict) -> dict:
    """The options ``fn`` takes (colour-science's ``filter_kwargs``)."""
    params = inspect.signature(fn).parameters
    return {k: v for k, v in options.items() if k in params and v is not None}


def _xyz_pair(inp: MetricInputs, name: str):
    if inp.reference_xyz is None or inp.test_xyz is None or inp.white_xyz is None:
        raise CfaMitsubaError(f"{name} compares two XYZ images with a white point; one is missing")
    return inp.reference_xyz, inp.test_xyz, inp.white_xyz


def _delta_e(inp, opts):
    return delta_e(*_xyz_pair(inp, "delta-e"), patches=inp.geometry.get("patches"), **_accepted(delta_e, opts))


def _scielab(inp, opts):
    spd = opts.pop("samples_per_degree", None) or inp.geometry.get("samples_per_degree")
    ref, test, white = _xyz_pair(inp, "scielab")
    kw = _accepted(scielab, opts)
    ref_kw = {k: v for k, v in kw.items() if k in ("matrix", "parameters", "lab_constants", "boundary")}
    key = ("scielab_reference_lab", float(spd), tuple(sorted(ref_kw.items())))
    if key not in inp.shared:
        inp.shared[key] = scielab_reference_lab(ref, white, samples_per_degree=spd, **ref_kw)
    return scielab(ref, test, white, samples_per_degree=spd, reference_lab=inp.shared[key], **kw)


def _mtf(inp, opts):
    roi = opts.pop("roi", None) or inp.geometry.get("roi")
    return mtf(inp.linear("test"), roi=roi, pixel_pitch_um=inp.pixel_pitch_um, reference=inp.linear("reference"),
               **_accepted(mtf, opts))


def _moire(inp, opts):
    freq = opts.pop("frequency_cy_per_deg", None)
    if freq is None:
        freq = inp.geometry.get("frequency_cy_per_deg")
    return moire(*_xyz_pair(inp, "moire"), frequency_cy_per_deg=freq, row=inp.geometry.get("row"),
                 **_accepted(moire, opts))


def _achromatic(inp, opts):
    return achromatic(*_xyz_pair(inp, "achromatic"), row=inp.geometry.get("row"), steps=inp.geometry.get("steps"),
                      **_accepted(achromatic, opts))


def _display(fn):
    def compute(inp, opts):
        a, b = inp.srgb8("reference"), inp.srgb8("test")
        if a is None or b is None:
            raise CfaMitsubaError(f"{fn.__name__} compares two images; one is missing")
        return fn(a, b, **_accepted(fn, opts))
    return compute


_GEOMETRY_NEEDS = {
    "moire": {"frequency_cy_per_deg": "the chirp's frequency per column"},
    "scielab": {"samples_per_degree": "the field of view (fov_deg)"},
}

#: The registry: one record per metric, in the paper's order (s. 2.2).
METRICS: dict[str, MetricRecord] = {r.name: r for r in (
    MetricRecord("delta-e", delta_e, ("macbeth",), "xyz", "dE00", False, True, "ΔE00",
                 "colour error, mean CIEDE2000 over the 24 ColorChecker patches", 2, "ΔE (s. 2.2.1, Fig 8)",
                 (6.0, 2.2), range_units=("dE00", "dE76"), compute=_delta_e),
    MetricRecord("scielab", scielab, (NATURAL,), "xyz", "dE00", False, True, "S-CIELAB",
                 "colour reproduction error, mean S-CIELAB ΔE00 over the image (Zhang-Wandell)", 2,
                 "ΔEs (s. 2.2.2, Fig 10)", (9.5, 2.5), range_units=("dE00", "dE76"), needs=_GEOMETRY_NEEDS["scielab"], compute=_scielab),
    MetricRecord("ssim", ssim, (NATURAL,), "srgb8", "", True, True, "SSIM",
                 "structural similarity (Wang 2004) of the 8-bit sRGB luma", 3, "SSIM (s. 2.2.3, Fig 10)",
                 (0.0, 1.0), compute=_display(ssim)),
    MetricRecord("mtf", mtf, ("slanted-edge",), "linear", "cy/mm", True, True, "MTF50",
                 "luminance MTF50 of the slanted edge (ISO 12233 e-SFR)", 1, "MTF50 (s. 2.2.4, Figs 6, 11)",
                 (30.0, 110.0), "pixel_pitch", compute=_mtf),
    MetricRecord("moire", moire, ("chirp",), "xyz", "cy/deg", True, True, "MSP",
                 "moiré starting point: first frequency where the block-mean C*ab passes 25", 2,
                 "MSP (s. 2.2.5, Figs 12-13)", (0.04, 0.30), "chirp_cy_px", needs=_GEOMETRY_NEEDS["moire"],
                 censored_key="censored", compute=_moire),
    MetricRecord("achromatic", achromatic, ("gray-bar",), "xyz", "L*", False, True, "AR error",
                 "achromatic reproduction error, mean |ΔL*| along the gray bar", 3, "ΔR (s. 2.2.6, Fig 14)",
                 (1.0, 0.5), compute=_achromatic),
    MetricRecord("mdsi", mdsi, (NATURAL,), "srgb8", "", False, True, "MDSI",
                 "mean deviation similarity index (Nafchi 2016), 0 = identical", 3, "MDSI (s. 2.2.7, Fig 15)",
                 (0.5, 0.0), compute=_display(mdsi)),
    MetricRecord("haarpsi", haarpsi, (NATURAL,), "srgb8", "", True, True, "HaarPSI",
                 "Haar wavelet perceptual similarity (Reisenhofer 2018), 1 = identical", 3,
                 "HaarPSI (s. 2.2.8, Fig 15)", (0.0, 1.0), compute=_display(haarpsi)),
    # Values read from a scored metric's details: reported, not scored.
    MetricRecord("delta-e76", None, ("macbeth",), "xyz", "dEab", False, False, "ΔE*ab",
                 "colour error, mean CIE 1976 ΔE*ab over the 24 patches", 2, parent="delta-e",
                 detail_key="mean_de1976"),
    MetricRecord("delta-l", None, ("macbeth",), "xyz", "L*", False, False, "ΔL grey",
                 "mean |ΔL*| over the six grey patches (the paper's Table 1 'Mean ΔL')", 2, "Table 1",
                 parent="delta-e", detail_key="mean_dl_grey"),
    MetricRecord("mtf50p", None, ("slanted-edge",), "linear", "cy/mm", True, False, "MTF50P",
                 "luminance MTF50P: where the MTF falls to half its peak (Imatest; not raised by overshoot)", 1,
                 parent="mtf", detail_key="mtf50p_cy_mm"),
    MetricRecord("mtf-peak", None, ("slanted-edge",), "linear", "", False, False, "MTF peak",
                 "peak of the luminance MTF up to Nyquist (1 without overshoot; above 1: sharpening)", 3,
                 parent="mtf", detail_key="mtf_peak"),
    MetricRecord("scielab-interior", None, (NATURAL,), "xyz", "dE00", False, False, "S-CIELAB interior",
                 "S-CIELAB mean ΔE00 away from the image border", 2, parent="scielab", detail_key="mean_interior"),
)}


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


def metrics_for_scene(scene: str, *, natural: bool = False) -> tuple[str, ...]:
    """The computable metrics a scene feeds: those naming it, or, for a
    natural scene (``natural=True``, or the built-in ``puppy``), those naming
    :data:`NATURAL`."""
    return tuple(r.name for r in METRICS.values()
                 if not r.secondary and (scene in r.scenes or (NATURAL in r.scenes and (natural or scene == "puppy"))))


def list_metrics() -> list[tuple[str, str]]:
    """(name, one-line description) of every computable metric, for ``cfa-mitsuba list metrics``."""
    return [(r.name, f"[{', '.join(r.scenes)}] {r.description}") for r in METRICS.values() if not r.secondary]


def record_json(r: MetricRecord) -> dict:
    """A record as JSON (``cfa-mitsuba list metrics --json``)."""
    return {
        "name": r.name, "scenes": list(r.scenes), "inputs": r.inputs, "unit": r.unit,
        "higher_is_better": r.higher_is_better, "scored": r.scored,
        "score_range": None if r.score_range is None else {"worst": r.score_range[0], "best": r.score_range[1],
                                                           "scaling": r.range_scaling},
        "label": r.label, "description": r.description, "paper": r.paper,
        "derived_from": r.parent, "censored_key": r.censored_key, "function": None if r.function is None else f"cfa_mitsuba.metrics.{r.function.__name__}",
    }


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
    for key, what in r.needs.items():
        if options.get(key) is None and inputs.geometry.get(key) is None:
            raise CfaMitsubaError(f"{name} needs {what} in the render's sidecar ('{key}'); this scene has none")
    out = r.compute(inputs, dict(options))
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
