"""The camera chain, wired once: scene radiance + condition -> optical image
-> raw mosaic -> processed image -> metrics, against the ideal XYZ sensor.

The study's evaluation tasks, the convergence study and the benchmarks all
run through :class:`CameraChain`; settings travel as frozen dataclasses
(:class:`ChainSettings`, :class:`~.conditions.Condition`).  A study's task
is evaluated whole by :meth:`CameraChain.run` (the ideal image and its rows,
the spectra set and read-out in effect, every realisation, demosaic and
metric), which returns typed values (:mod:`.task_values`); the worker
(:mod:`.tasks`) only loads the render, writes the details and hands the rows
back.

The optical image does not depend on the CFA or the demosaic, so a chain
computes it once per (scene, optics-relevant condition) and keeps it, with
the ideal sensor's image per luminance and exposure, for every CFA and
demosaic evaluated in the same process (:class:`_Memo`, a small LRU: a
puppy-sized optical image is about 0.2 GB), and in a study writes both to
the study's store for its other workers (:mod:`.image_store`).  Only the
regions the metrics read are demosaiced and measured where that gives the
whole image's values (:mod:`.roi`).
"""

from __future__ import annotations

__all__ = ["ChainSettings", "CameraChain", "Evaluation", "condition_columns", "condition_applies", "capture_columns"]

import json
import os
import time
from collections import OrderedDict
from dataclasses import dataclass, field, replace

import numpy as np

from . import image_store, roi
from .axes import AXES
from .conditions import Condition
from .task_values import CameraOutput, TaskEvaluation, realisation_seeds

#: Set to 1 to recompute the optical image for every capture (what the
#: study did before the chain shared it): for benchmarks/bench_study.py only.
NO_MEMO_ENV = "CFA_MITSUBA_NO_OPTICS_MEMO"

#: The demosaicing precision of every chain unless ``[isp]
#: demosaic_precision`` says otherwise (issue 25): float32 makes the
#: methods faster and moves the paper study's values by float32 rounding,
#: far inside the run-to-run tolerances (measured in docs/study.md).
STUDY_DEMOSAIC_PRECISION = "single"


@dataclass(frozen=True)
class ChainSettings:
    """Everything after the render that is not a study axis.

    ``optics`` and ``sensor`` are :class:`~cfa_mitsuba.optics.OpticsParams`
    and :class:`~cfa_mitsuba.sensor.params.SensorParams` (their f-number,
    pitch and read noise are replaced by the condition's); ``noise`` is
    'off', 'shot' or 'all'; ``exposure_program`` how 'auto' exposure is
    chosen (:class:`~cfa_mitsuba.sensor.exposure_program.ExposureProgram`,
    passed whole to every capture; None: its defaults, the program);
    ``isp`` the processing options (white balance,
    white preserving, ...) as sorted (key, value) pairs; ``demosaic_options``
    each method's own options (``[demosaics.<name>]``);
    ``mean_match`` scales each camera output to the ideal's mean (ISETCam);
    ``spectra_sets`` maps a CFA's own spectra set to the set used instead
    (``[sensor.spectra_sets]``); ``metric_options`` the keyword options of
    each metric (``[metrics.<name>]``); both as sorted pairs.  ``roi``:
    demosaic and measure only the regions the metrics read where that gives
    the whole image's values (:mod:`.roi`; False: whole images always).
    """

    optics: object = None
    sensor: object = None
    noise: str = "all"
    exposure_program: object = None
    isp: tuple = ()
    mean_match: bool = True
    spectra_sets: tuple = ()
    metric_options: tuple = ()
    demosaic_options: tuple = ()
    roi: bool = True

    def __post_init__(self):
        from ..optics import OpticsParams
        from ..sensor.exposure_program import ExposureProgram
        from ..sensor.params import SensorParams

        if self.exposure_program is None:
            object.__setattr__(self, "exposure_program", ExposureProgram())
        if self.optics is None:
            object.__setattr__(self, "optics", OpticsParams())
        if self.sensor is None:
            object.__setattr__(self, "sensor", SensorParams())
        if isinstance(self.isp, dict):
            object.__setattr__(self, "isp", tuple(sorted(self.isp.items())))
        if isinstance(self.spectra_sets, dict):
            object.__setattr__(self, "spectra_sets", tuple(sorted(self.spectra_sets.items())))
        for name in ("metric_options", "demosaic_options"):  # {name: {option: value}} as sorted pairs
            value = getattr(self, name)
            if isinstance(value, dict):
                object.__setattr__(self, name, tuple(sorted((m, tuple(sorted(o.items()))) for m, o in value.items())))

    def options_of_metrics(self) -> dict:
        """{metric: {keyword: value}}: the options every evaluation passes:
        the metric records' ``study_options`` (S-CIELAB's single-precision
        filtering), then the config's ``[metrics.<name>]`` over them."""
        from ..metrics import study_options

        out = study_options()
        for m, o in self.metric_options:
            out[m] = {**out.get(m, {}), **dict(o)}
        return out

    def spectra_for(self, cfa, cond: Condition) -> str | None:
        """The spectra set a capture of ``cfa`` uses under ``cond`` when it
        is not the CFA's own: the condition's (a ``spectra`` sweep), else the
        replacement ``spectra_sets`` gives for the CFA's own set; None: its own."""
        if cond.spectra is not None:
            return cond.spectra
        if not self.spectra_sets:
            return None
        from ..sensor import get_cfa

        return dict(self.spectra_sets).get(get_cfa(cfa).spectra)

    def spectra_in_effect(self, cfa, cond: Condition) -> str:
        """The spectra set a capture of ``cfa`` uses under ``cond``
        (:meth:`spectra_for`), else the CFA's own ('' for none)."""
        chosen = self.spectra_for(cfa, cond)
        if chosen is not None:
            return chosen
        from ..sensor import get_cfa

        return str(get_cfa(cfa).spectra or "")

    def base_condition(self, *, luminance: float = 100.0, exposure="auto", seed: int = 0) -> Condition:
        """The condition these settings describe at ``luminance``: every
        optics, sensor, ISP and metric axis at these settings' value."""
        given = {"luminance": float(luminance), "exposure": exposure, "seed": int(seed)}
        return Condition(**{name: given[name] if name in given else axis.value_in(self)
                            for name, axis in AXES.items()})

    def _targets(self, cond: Condition, where: str) -> dict:
        """{field: value} of the condition's axes that apply to ``where``."""
        return {a.field: getattr(cond, name) for name, a in AXES.items() if a.applies_to == where}

    def for_condition(self, cond: Condition):
        """(OpticsParams, SensorParams) with the condition's values applied
        (built once per condition: the optical image, the ideal and the
        capture of one evaluation all ask)."""
        memo = self.__dict__.setdefault("_per_condition", {})
        if cond not in memo:
            memo[cond] = (replace(self.optics, **self._targets(cond, "optics")),
                          self.sensor.with_(**self._targets(cond, "sensor")))
        return memo[cond]

    def isp_options(self, method: str, cond: Condition | None = None) -> dict:
        """The keywords of :func:`cfa_mitsuba.isp.process` for ``method``: the
        ``[isp]`` options, the method's own (``[demosaics.<name>]``) and the
        condition's ISP axes, an axis whose value is a setting (``denoise =
        'nl-means:2'``) passed as the keywords its record gives
        (:attr:`.axes.Axis.isp_keywords`); the demosaicing runs in
        :data:`STUDY_DEMOSAIC_PRECISION` unless ``[isp]`` sets
        ``demosaic_precision``."""
        opts = {"demosaic_precision": STUDY_DEMOSAIC_PRECISION, **dict(self.isp),
                **dict(dict(self.demosaic_options).get(method, ()))}
        if cond is not None:
            opts.update(self._targets(cond, "isp"))
        for axis in AXES.values():
            if axis.applies_to == "isp" and axis.isp_keywords is not None and axis.field in opts:
                opts.update(axis.isp_keywords(opts.pop(axis.field)))
        return opts

    def metric_options_for(self, cond: Condition | None = None) -> dict:
        """{metric: {option: value}}: the ``[metrics.<name>]`` options with the
        condition's metric axes (``field`` = ``'metric.option'``) applied."""
        out = self.options_of_metrics()
        if cond is not None:
            for dotted, v in self._targets(cond, "metric").items():
                metric, option = dotted.split(".", 1)
                out.setdefault(metric, {})[option] = v
        return out


@dataclass
class Evaluation:
    """One camera output measured: the processed image, its metric results
    and what the report's details need."""

    demosaic: str
    processed: object
    results: dict
    failures: list
    mean_match_scale: float
    timing: dict = field(default_factory=dict)


class _Memo:
    """A small least-recently-used map (the optical and ideal images)."""

    def __init__(self, size: int):
        self.size, self.items = size, OrderedDict()

    def get(self, key, make):
        if key in self.items:
            self.items.move_to_end(key)
            return self.items[key]
        value = make()
        self.items[key] = value
        while len(self.items) > self.size:
            self.items.popitem(last=False)
        return value


#: Per process: shared by every chain (tasks of one worker reuse it).
_OPTICAL = _Memo(2)
_IDEAL = _Memo(4)


def _shared(ideal) -> dict:
    """What depends on the ideal image alone, computed once per ideal for
    every CFA, demosaic and realisation compared with it (its sRGB codes,
    S-CIELAB's filtered reference, its interior mean for mean-matching),
    kept with the ideal."""
    return ideal.__dict__.setdefault("_metric_shared", {})


def condition_columns(cond: Condition, ideal_meta: dict) -> dict:
    """The condition axes as metrics.csv columns: the values in effect (an
    axis the condition left to the scene read from the ideal image's meta,
    :meth:`.axes.Axis.in_effect`: the f-number the optics used)."""
    return {name: axis.in_effect(getattr(cond, name), ideal_meta) for name, axis in AXES.items()}


def condition_applies(cfa, cond: Condition) -> bool:
    """Whether every axis value of ``cond`` applies to ``cfa``
    (:meth:`.axes.Axis.applies`: a block read-out to the block layouts
    only, so a sweep over it leaves the other CFAs out of its conditions)."""
    from ..sensor import get_cfa

    pattern = get_cfa(cfa).pattern
    return all(axis.applies(pattern, getattr(cond, name)) for name, axis in AXES.items())


def capture_columns(raw) -> dict:
    """metrics.csv's columns of the capture (:data:`.tables.CAPTURE_COLUMNS`)."""
    st = raw.settings or {}
    return {"exposure_s": float(raw.exposure_s), "analog_gain": float(st.get("analog_gain") or 1.0),
            "digital_gain": float(st.get("digital_gain") or 1.0),
            "clipped_fraction": raw.meta.get("clipped_fraction", raw.meta.get("saturated_fraction")),
            "scene_illuminance_lux": raw.meta.get("scene_illuminance_lux"),
            "sensor_exposure_lux_s": raw.meta.get("sensor_exposure_lux_s")}


class CameraChain:
    """The chain after the render for one set of :class:`ChainSettings`.

    ``scene_key`` (any hashable, e.g. the render's cache key or a file path)
    names a scene image so its optical image can be reused; None disables
    reuse for that call.  The optical and ideal images are kept for the
    process's life under that key, so it must name the image's content,
    not the object: ``id(image)`` is reused by a later image once the first
    is freed, which then gets the first one's optical image.
    """

    def __init__(self, settings: ChainSettings | None = None, *, image_store: str | None = None):
        self.settings = settings or ChainSettings()
        self.image_store = image_store  # a study's folder of optical images (.image_store), shared by its workers
        self.timing = {"optics_s": 0.0, "capture_s": 0.0, "process_s": 0.0, "metrics_s": 0.0}

    def _timed(self, stage: str, fn, *args, **kwargs):
        t = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            self.timing[stage] += time.perf_counter() - t

    def optical(self, scene_image, cond: Condition, scene_key=None):
        """The sensor-plane irradiance of ``scene_image`` (a SpectralImage, or
        a function returning one, called only when not already computed)
        under ``cond``."""
        from ..optics import compute_optics

        optics, sensor = self.settings.for_condition(cond)

        def compute():
            image = scene_image() if callable(scene_image) else scene_image
            return compute_optics(image, optics, pixel_pitch_um=sensor.pixel_pitch_um,
                                  fill_factor=sensor.fill_factor)

        if scene_key is None or os.environ.get(NO_MEMO_ENV) == "1":
            return self._timed("optics_s", compute)
        key = (scene_key, optics, sensor.pixel_pitch_um, sensor.fill_factor)
        fields = {"scene": str(scene_key), "optics": repr(optics), "pitch_um": float(sensor.pixel_pitch_um),
                  "fill_factor": float(sensor.fill_factor)}

        def make():  # from the study's store when another worker made it (.image_store)
            return image_store.load_or_make(self.image_store, "optical", fields, compute)

        return self._timed("optics_s", _OPTICAL.get, key, make)

    def ideal(self, oi, cond: Condition, scene_key=None):
        """The ideal sensor's processed image (XYZ, noise off, no mosaic)."""
        from ..isp import process
        from ..sensor import capture_ideal

        _, sensor = self.settings.for_condition(cond)

        def compute():
            raw = capture_ideal(oi, luminance_cd_m2=cond.luminance, sensor=sensor, exposure_s=cond.exposure)
            out = process(raw)
            # compared with every camera output of its task: read-only, so the metrics check it once
            out.xyz.flags.writeable = False
            return out

        if scene_key is None or os.environ.get(NO_MEMO_ENV) == "1":
            return self._timed("optics_s", compute)
        key = (scene_key, *self.settings.for_condition(cond), cond.luminance, cond.exposure)
        fields = {"scene": str(scene_key), "optics": repr(key[1]), "sensor": repr(sensor),
                  "luminance": float(cond.luminance), "exposure": str(cond.exposure)}

        def make():  # from the study's store when another worker made it (.image_store)
            return image_store.load_or_make(self.image_store, "ideal", fields, compute)

        return self._timed("optics_s", _IDEAL.get, key, make)

    def capture(self, oi, cfa, cond: Condition, seed: int, *, noise: str | None = None):
        """The raw mosaic of ``cfa`` (a name, TOML path or CFA) under ``cond``
        (another spectra set, when the condition or the settings name one; ``noise`` overrides
        the settings' noise mode).  ``seed`` is the capture's noise seed, derived from the
        condition's study seed by :func:`~.task_values.realisation_seeds` (the one seed path:
        ``cond.seed`` is its input and is not used here)."""
        from ..sensor import capture, get_cfa

        _, sensor = self.settings.for_condition(cond)
        spectra = self.settings.spectra_for(cfa, cond)
        if spectra is not None:
            cfa = get_cfa(cfa, spectra=spectra)
        return self._timed("capture_s", capture, oi, cfa, luminance_cd_m2=cond.luminance, exposure_s=cond.exposure,
                           noise=noise or self.settings.noise, seed=seed, sensor=sensor,
                           exposure_program=self.settings.exposure_program)

    def process(self, raw, method: str, cond: Condition | None = None, **options):
        """:func:`cfa_mitsuba.isp.process` of ``raw`` (a RawImage, or a
        :class:`~cfa_mitsuba.isp.PreparedRaw` from :meth:`prepare`) by
        ``method`` with the study's ISP options."""
        from ..isp import PREPARE_KEYWORDS, PreparedRaw, process, process_prepared

        # the out-of-gamut share of each output goes into no table or figure of a study: not measured
        opts = {"gamut_check": False, **self.settings.isp_options(method, cond), **options}
        if isinstance(raw, PreparedRaw):
            kept = {k: opts.pop(k) for k in PREPARE_KEYWORDS if k in opts}
            if any(raw.settings[k] != v for k, v in kept.items()):  # this method's [isp] differs: prepare afresh
                return self._timed("process_s", process, raw.raw_image, method, **kept, **opts)
            return self._timed("process_s", process_prepared, raw, method, **opts)
        return self._timed("process_s", process, raw, method, **opts)

    def prepare(self, raw, method: str, cond: Condition | None = None):
        """The part of processing ``raw`` that every demosaicing method
        shares (:func:`cfa_mitsuba.isp.prepare`), with the ISP options of
        ``method`` under ``cond``: :meth:`process` takes it in place of
        ``raw``, for each method, with the same result."""
        from ..isp import PREPARE_KEYWORDS, prepare

        opts = self.settings.isp_options(method, cond)
        return self._timed("process_s", prepare, raw, **{k: opts[k] for k in PREPARE_KEYWORDS if k in opts})

    def inputs(self, ideal, cam_xyz, cond: Condition):
        """The :class:`~cfa_mitsuba.metrics.MetricInputs` of a camera output."""
        from .. import metrics as m

        geo = m.scene_geometry(ideal.meta, ideal.xyz.shape)
        return m.MetricInputs(ideal.xyz, cam_xyz, np.asarray(ideal.white_xyz, dtype=np.float64), geometry=geo,
                              pixel_pitch_um=cond.pixel_pitch_um, shared=_shared(ideal))

    def measure(self, ideal, processed, metric_names, cond: Condition, *, details: bool = True
                ) -> tuple[dict, list, float]:
        """(results, failures, mean-match scale) of one processed image.
        ``details`` False: the details are not kept, so the metric records'
        ``summary_options`` apply (under the config's own options): the
        results' rows are the same.  Raises CfaMitsubaError when the output
        cannot be mean-matched."""
        from .. import metrics as m

        cam, scale = processed.xyz, 1.0
        if self.settings.mean_match:
            shared = _shared(ideal)
            if "interior_mean" not in shared:
                shared["interior_mean"] = m.reference_interior_mean(ideal.xyz)
            cam, scale = m.mean_match(cam, ideal.xyz, return_scale=True, reference_mean=shared["interior_mean"])
            cam.flags.writeable = False  # a new array only the metrics read: checked by the first, not again
        failures: list = []
        options = self.settings.metric_options_for(cond)  # a new dict each call
        if not details:
            for name, summary in m.summary_options().items():
                options[name] = {**summary, **options.get(name, {})}
        results = self._timed("metrics_s", m.evaluate_many, metric_names, self.inputs(ideal, cam, cond), failures,
                              options=options)
        return results, failures, float(scale)

    def run(self, task, scene_image, *, ideal_details: bool = False) -> TaskEvaluation:
        """Evaluate one study task whole (:class:`~.task_values.EvaluationTask`):
        the CFA captured in every realisation (when the condition's read-out
        applies to it), each capture processed by every demosaic and measured
        against the ideal; the ideal against itself when the task asks
        (``ideal_rows``); the ideal's own results for the metrics that keep
        its curves when ``ideal_details``.  ``scene_image``: the render (a
        SpectralImage, or a function returning one, called only when the
        optical image is not already made).  Returns the
        :class:`~.task_values.TaskEvaluation`; the first realisation's
        outputs keep their images and curves when the task keeps details."""
        from .. import metrics as m
        from ..metrics import result_rows

        cond = task.condition
        scene_key = json.dumps(task.source, sort_keys=True)
        ideal, outputs = None, []
        if condition_applies(task.cfa, cond):
            seeds = realisation_seeds(cond.seed, task.scene, cond.luminance, task.realisations,
                                      task.realisation_offset)
            for i, seed in enumerate(seeds):
                keep = task.keeps_details and i == 0  # the first realisation's curves and images
                for raw, ideal, method, ev in self.evaluate(scene_image, task.cfa, task.demosaics, task.metrics, cond,
                                                            seed, scene_key, details=keep):
                    index = task.realisation_offset + i
                    if not hasattr(ev, "results"):
                        # No output to measure (a channel the scene white leaves dark) or no scale for it (a
                        # black ideal interior): every metric of this output is unmeasurable.
                        failed = [{"metric": name, "error": str(ev)} for name in task.metrics]
                        outputs.append(CameraOutput(method, index, seed, {}, [], failed))
                        continue
                    outputs.append(CameraOutput(method, index, seed, capture_columns(raw), result_rows(ev.results),
                                                list(ev.failures), ev if keep else None, raw if keep else None))
        elif task.ideal_rows or ideal_details:
            ideal = self.ideal(self.optical(scene_image, cond, scene_key), cond, scene_key)
        ideal_rows, ideal_results = [], None
        if ideal is not None:
            options = self.settings.metric_options_for(cond)
            if task.ideal_rows:
                ideal_rows = result_rows(m.evaluate_many(task.metrics, self.inputs(ideal, ideal.xyz, cond), [],
                                                         options=options))
            if ideal_details:
                kept = [n for n in task.metrics if m.get_metric(n).ideal_details]
                ideal_results = m.evaluate_many(kept, self.inputs(ideal, ideal.xyz, cond), options=options)
        return TaskEvaluation(task, None if ideal is None else condition_columns(cond, ideal.meta),
                              self.settings.spectra_in_effect(task.cfa, cond), outputs, ideal_rows, ideal,
                              ideal_results, self.timing)

    def evaluate(self, scene_image, cfa, demosaics, metric_names, cond: Condition, seed: int, scene_key=None, *,
                 details: bool = True):
        """Yield (raw, ideal, Evaluation | CfaMitsubaError) per demosaic: the
        whole chain for one CFA (``details``: as for :meth:`measure`)."""
        from ..errors import CfaMitsubaError

        oi = self.optical(scene_image, cond, scene_key)
        ideal = self.ideal(oi, cond, scene_key)
        raw = self.capture(oi, cfa, cond, seed)
        prepared = None
        for method in demosaics:
            try:
                if prepared is None:
                    prepared = self.prepare(raw, method, cond)  # once for every method (isp.prepare)
                # only the windows the metrics read, when that gives the whole image's values (.roi)
                rects = roi.plan(self, prepared, method, cond, ideal, metric_names, details=details)
                out = (self.process(prepared, method, cond) if rects is None
                       else roi.process_windows(self, prepared, method, cond, rects, ideal.xyz))
                results, failures, scale = self.measure(ideal, out, metric_names, cond, details=details)
            except CfaMitsubaError as exc:
                yield raw, ideal, method, exc
                continue
            yield raw, ideal, method, Evaluation(method, out, results, failures, scale)
