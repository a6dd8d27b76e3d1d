"""The units of work of a study, run in worker processes (local or Dask).

Two kinds of task, both plain functions of plain (picklable, JSON-able)
arguments so any executor can run them:

* :func:`render_task` renders one scene through the shared render cache
  (DESIGN.md: the cache lives outside the results, keyed by everything that
  determines the render, written atomically under a lock).
* :func:`evaluate_task` takes one (scene, condition, CFA): it loads the
  render and runs the camera chain (:mod:`.chain`: the optical image once per
  scene and condition in each process, the CFA captured once, every
  demosaicing method processed and measured against the ideal XYZ sensor).
  It writes its detail files (curves, maps, thumbnails) and returns the tidy
  metric rows, one column per condition axis.

Everything after the render is deterministic: the noise seed of a task is
derived from the study seed, the scene, the luminance and the realisation's
index (never from the order in which tasks run, nor from the CFA: realisation
k of every CFA has the same render seed and the same sensor seed, so
comparisons between CFAs pair), so a study gives the same numbers on one
process, on many, or on a Dask cluster, and after an interruption.
"""

from __future__ import annotations

__all__ = ["EvaluationTask", "render_task", "evaluate_task", "task_seed", "load_scene_image", "condition_columns"]

import dataclasses
import hashlib
import json
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io.sidecar import json_default
from .details_layout import ideal_folder, output_folder


@dataclass(frozen=True)
class EvaluationTask:
    """One (scene, condition, CFA) of a study: what :func:`evaluate_task` runs.

    Attributes
    ----------
    source : the render it evaluates (:func:`load_scene_image`: a cached
        render's scene and settings, or an EXR path).
    scene : the scene's name (metrics.csv's ``scene``).
    condition : the :class:`~.conditions.Condition`; its ``seed`` is the
        study seed, from which every realisation's noise seed is derived
        (:func:`realisation_seeds`: the one seed path).
    cfa, cfa_label : the CFA (a name or TOML path) and its label in tables.
    demosaics, metrics : what to process and measure.
    chain : the :class:`~.chain.ChainSettings`.
    details_dir, details_tag : where the first realisation's curves and
        thumbnails go (None: nowhere) and their file stem.
    realisations : noise realisations of the capture (rows carry
        ``realisation`` offset, offset + 1, ...).
    realisation_offset : the index of the task's first realisation (``r S``
        for render seed r of a path-traced scene with S sensor seeds).
    render_seed : the render seed index of the task's render (rows carry it
        as ``render_seed``; 0 for a scene rendered once).
    ideal_rows : also measure the ideal sensor against itself.
    base : the condition is one of the study's own (scored), not a sweep's.
    """

    source: dict[str, object]
    scene: str
    condition: object
    cfa: str
    demosaics: tuple[str, ...]
    metrics: tuple[str, ...]
    chain: object = None
    cfa_label: str | None = None
    details_dir: str | None = None
    details_tag: str | None = None
    realisations: int = 1
    ideal_rows: bool = False
    base: bool = True
    realisation_offset: int = 0
    render_seed: int = 0

    @classmethod
    def of(cls, task) -> "EvaluationTask":
        """A task from an :class:`EvaluationTask` or a dict of its fields."""
        if isinstance(task, cls):
            return task
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = set(task) - names
        if unknown:
            raise TypeError(f"EvaluationTask has no field(s) {sorted(unknown)}")
        return cls(**{**task, "demosaics": tuple(task["demosaics"]), "metrics": tuple(task["metrics"])})

    def identity(self) -> dict:
        """Everything that determines the task's rows (not where its details go)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "details_dir"}


def task_seed(study_seed: int, *parts) -> int:
    """A noise seed from the study seed and a task's identity (32 bits)."""
    text = json.dumps([int(study_seed), *[str(p) for p in parts]])
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:4], "little")


def realisation_seeds(study_seed: int, scene: str, luminance: float, n: int, offset: int = 0) -> list[int]:
    """The sensor-noise seeds of realisations ``offset .. offset + n - 1`` of
    one capture: realisation 0's is the task's own seed (:func:`task_seed`),
    the others add the realisation's index to its identity, so adding
    realisations never changes the earlier ones.  The CFA is not part of
    it: realisation k of every CFA uses the same seed (paired comparisons,
    study/intervals.py)."""
    return [task_seed(study_seed, scene, luminance) if k == 0 else task_seed(study_seed, scene, luminance, k)
            for k in range(int(offset), int(offset) + int(n))]


#: One render at a time per process: Mitsuba's variant is process-global, and
#: a Dask worker runs several tasks in threads of one process; each render
#: already uses the process's whole thread budget.
_RENDER_LOCK = threading.Lock()


def _render_kwargs(source: dict) -> dict:
    return dict(source.get("settings") or {})


def load_scene_image(source: dict):
    """The SpectralImage a task evaluates: from the render cache (rendered
    if missing) or from an EXR file."""
    from .. import io, render

    if source["kind"] == "exr":
        return io.read_spectral_exr(source["path"])
    scene = source.get("file") or source["scene"]
    with _RENDER_LOCK:
        return render.render_cached(scene, **_render_kwargs(source))


def render_task(source: dict) -> dict:
    """Render one scene into the cache (or find it there); returns a summary."""
    from .. import render

    t0 = time.perf_counter()
    scene = source.get("file") or source["scene"]
    with _RENDER_LOCK:
        img = render.render_cached(scene, **_render_kwargs(source))
    meta = img.meta
    return {
        "scene": source["scene"],
        "cache_key": meta.get("cache_key"),
        "reused": bool(meta.get("cache_reused", False)),
        "render_time_s": float(meta.get("render_time_s") or 0.0),
        "wall_s": time.perf_counter() - t0,
        "width": meta.get("width"),
        "height": meta.get("height"),
        "oversample": meta.get("oversample"),
    }


def condition_columns(cond, ideal_meta: dict) -> dict:
    """The condition axes as metrics.csv columns: the values in effect (the
    f-number the optics used when the condition left it to the scene)."""
    from .conditions import AXES

    out = {axis: getattr(cond, axis) for axis in AXES}
    if out["f_number"] is None:
        out["f_number"] = (ideal_meta.get("optics") or {}).get("f_number")
    return out


def _spectra_in_effect(cfa, cond, settings) -> str:
    """The spectra set a capture used: the condition's or the settings'
    replacement (:meth:`.chain.ChainSettings.spectra_for`), else the CFA's own."""
    chosen = settings.spectra_for(cfa, cond)
    if chosen is not None:
        return chosen
    from ..sensor import get_cfa

    return str(get_cfa(cfa).spectra or "")


def _readout_applies(cfa, cond) -> bool:
    """Whether the condition's read-out mode applies to the CFA: ``full``
    always, ``remosaic`` and ``bin`` on the block layouts only (a sweep
    over readout leaves the other CFAs out of its non-full conditions)."""
    from ..sensor import get_cfa
    from ..sensor.readout import readout_applies

    return readout_applies(get_cfa(cfa).pattern, getattr(cond, "readout", "full"))


def _block_mean(image: np.ndarray, longest: int = 240) -> np.ndarray:
    """(H, W[, C]) averaged over step x step blocks, step the smallest
    integer that brings the longer side to at most ``longest`` (the partial
    blocks at the right and bottom dropped): the report's reduced maps and
    thumbnails."""
    h, w = image.shape[:2]
    step = max(1, int(np.ceil(max(h, w) / longest)))
    hh, ww = (h // step) * step, (w // step) * step
    tail = image.shape[2:]
    c = int(np.prod(tail, dtype=np.int64))
    # The rows of a block added first (whole contiguous rows), then the columns, each by step - 1
    # whole-array adds in block order: for steps up to 8 the very sums of numpy's sum over the short
    # axis (it adds up to 8 in order), 2.5x faster than that sum (2.8 against 7.1 ms on a
    # 636 x 720 x 3 image) and 7x faster than one mean over both axes.
    band = image[:hh, :ww].reshape(hh // step, step, ww * c)
    rows = band[:, 0].copy()
    for k in range(1, step):
        rows += band[:, k]
    cols = rows.reshape(hh // step, ww // step, step, c)
    blocks = cols[:, :, 0].copy()
    for k in range(1, step):
        blocks += cols[:, :, k]
    blocks /= step * step
    return blocks.reshape(hh // step, ww // step, *tail)


def _thumbnail(rendered, path: Path, longest: int = 240) -> None:
    """The report's preview of an image: its XYZ averaged over blocks
    (:func:`_block_mean`: linear light, as a camera's downscaler averages),
    then the image's own display encoding (``cfa_mitsuba.isp.xyz_to_srgb``,
    the scene white adapted to sRGB's white, as ``RenderedImage.srgb``),
    written as an 8-bit PNG.  Encoding after the averaging costs 1/step^2 of
    encoding the whole image first, which took most of the time of a camera
    output's details (benchmarks/profile_study.py)."""
    from ..colorimetry import xyz_to_srgb8
    from ..io import write_image
    from ..isp.colour_matrix import DISPLAY_ADAPTATION

    # The 8-bit codes by xyz_to_srgb8's table, the same codes write_image rounds xyz_to_srgb's
    # encoding to (tests/test_study_tasks.py), without a power per value (5 of a thumbnail's 14 ms)
    codes = xyz_to_srgb8(_block_mean(np.asarray(rendered.xyz, dtype=np.float64), longest),
                         rendered.white_xyz, adaptation=DISPLAY_ADAPTATION)
    write_image(path, codes / 255.0)


def _save_details(folder: Path, stem: str, results: dict, rendered, extra: dict, crop=None) -> None:
    """Curves and tables as JSON, S-CIELAB map (reduced) as .npy, thumbnail PNG
    and, given a ``crop`` box, the 1:1 crop PNG (:mod:`.crops`)."""
    from ..io import atomic_output

    folder.mkdir(parents=True, exist_ok=True)
    payload = {"extra": extra}
    for name, r in results.items():
        payload[name] = r.to_dict() if hasattr(r, "to_dict") else {"metric": name, "value": float(r)}
        if name == "scielab" and "map" in getattr(r, "details", {}):
            small = _block_mean(np.asarray(r.details["map"], dtype=np.float64))
            with atomic_output(folder / f"{stem}.scielab.npy") as tmp:
                with open(tmp, "wb") as fh:
                    np.save(fh, small.astype(np.float32))
    with atomic_output(folder / f"{stem}.json") as tmp:
        tmp.write_text(json.dumps(payload, allow_nan=False, default=json_default))
    if rendered is not None:
        _thumbnail(rendered, folder / f"{stem}.png")
        if crop is not None:
            from .crops import save_crop

            save_crop(folder / f"{stem}.crop.png", rendered, crop)


def _capture_columns(raw) -> dict:
    """metrics.csv's columns of the capture (:data:`.tables.CAPTURE_COLUMNS`)."""
    st = raw.settings or {}
    return {"exposure_s": float(raw.exposure_s), "analog_gain": float(st.get("analog_gain") or 1.0),
            "digital_gain": float(st.get("digital_gain") or 1.0),
            "clipped_fraction": raw.meta.get("clipped_fraction", raw.meta.get("saturated_fraction")),
            "scene_illuminance_lux": raw.meta.get("scene_illuminance_lux"),
            "sensor_exposure_lux_s": raw.meta.get("sensor_exposure_lux_s")}


def _grey_electrons(raw, grey: float = 0.18) -> dict:
    """{channel: mean electrons per pixel} on an 18 % grey on the axis, in this capture."""
    e = np.asarray(raw.electrons_per_radiance) @ (grey * np.asarray(raw.white_radiance))
    return {str(c): float(v) for c, v in zip(raw.channels, e)}


def _details_extra(ev, raw, seed) -> dict:
    """What the report reads beside a camera output's curves."""
    isp_meta = ev.processed.meta.get("isp", {})
    return {**_capture_columns(raw), "grey_electrons": _grey_electrons(raw),
        "mean_match_scale": ev.mean_match_scale, "condition_number": isp_meta.get("condition_number"),
        "noise_gain_xyz": isp_meta.get("noise_gain_xyz"), "fit_rank": isp_meta.get("fit_rank"),
        "exposure_s": float(raw.exposure_s), "saturated_fraction": raw.meta.get("saturated_fraction"), "seed": seed,
        "saturation_rel": raw.meta.get("saturation_rel"),  # the top of the gray steps' dynamic range (steps.py)
    }


def evaluate_group(tasks) -> list[dict]:
    """:func:`evaluate_task` of each task of a group, in this process, in
    order.  The runner sends the tasks of one render and condition (every
    CFA) to one worker as a group, so that worker makes the optical and
    ideal images once and the others do not make them again."""
    return [evaluate_task(t) for t in tasks]


def evaluate_task(task) -> dict:
    """Capture one CFA of one scene under one condition and evaluate every demosaic.

    ``task``: an :class:`EvaluationTask` (or a dict of its fields).  Returns
    ``{"rows": [...], "timing": {...}, "failures": [...], "ideal_rows":
    [...]}``: a metric that could not be measured on one camera output is a
    failure record (scene, cfa, demosaic, condition, metric, error), not a row.
    """
    from .chain import CameraChain

    t = EvaluationTask.of(task)
    cond = t.condition
    chain = CameraChain(t.chain)
    scene_key = json.dumps(t.source, sort_keys=True)
    cfa_label = t.cfa_label or t.cfa
    details_dir = Path(t.details_dir) if t.details_dir else None
    tag = t.details_tag or f"L{cond.luminance:g}"
    rows, failures = [], []
    raw = ideal = None

    def image():
        return load_scene_image(t.source)

    spectra_used = _spectra_in_effect(t.cfa, cond, chain.settings)
    applies = _readout_applies(t.cfa, cond)
    if not applies and (t.ideal_rows or details_dir is not None):
        ideal = chain.ideal(chain.optical(image, cond, scene_key), cond, scene_key)
    seeds = (realisation_seeds(cond.seed, t.scene, cond.luminance, t.realisations, t.realisation_offset)
             if applies else [])
    for i, seed in enumerate(seeds):
        keep = details_dir is not None and i == 0 and t.realisation_offset == 0  # the first realisation's curves
        for raw, ideal, method, ev in chain.evaluate(image, t.cfa, t.demosaics, t.metrics, cond, seed, scene_key,
                                                     details=keep):
            base = {"scene": t.scene, "cfa": cfa_label, "demosaic": method, **condition_columns(cond, ideal.meta),
                    "spectra": spectra_used, "base": bool(t.base), "realisation": t.realisation_offset + i,
                    "render_seed": int(t.render_seed)}
            if not hasattr(ev, "results"):
                # No output to measure (a channel the scene white leaves dark) or
                # no scale for it (a black ideal interior): every metric of this
                # output is unmeasurable.
                failures.extend({**base, "metric": name, "error": str(ev)} for name in t.metrics)
                continue
            rows.extend({**base, **r, **_capture_columns(raw)} for r in _result_rows(ev.results))
            failures.extend({**base, **f} for f in ev.failures)
            if keep:
                _save_details(output_folder(details_dir, t.scene, cfa_label, method), tag, ev.results,
                              ev.processed, _details_extra(ev, raw, seed), crop=_crop(t.scene, ideal))
    return {"rows": rows, "timing": chain.timing, "failures": failures,
            "ideal_rows": _ideal_rows(t, chain, ideal, details_dir, tag)}


def _ideal_rows(t: EvaluationTask, chain, ideal, details_dir, tag) -> list[dict]:
    """The ideal sensor against itself (the anchor of the 'ideal' range
    policy), and the ideal's curves for the metrics whose records keep them."""
    from .. import metrics as m

    if ideal is None:
        return []
    cond, rows = t.condition, []
    if t.ideal_rows:
        got = m.evaluate_many(t.metrics, chain.inputs(ideal, ideal.xyz, cond), [],
                              options=chain.settings.metric_options_for(cond))
        base = {"scene": t.scene, "cfa": "ideal", "demosaic": "none", **condition_columns(cond, ideal.meta),
                "base": bool(t.base), "realisation": 0, "render_seed": 0}
        rows = [{**base, **r} for r in _result_rows(got)]
    if details_dir is not None:
        ideal_dir = ideal_folder(details_dir, t.scene)
        if not (ideal_dir / f"{tag}.png").exists():
            kept = [n for n in t.metrics if m.get_metric(n).ideal_details]
            ideal_results = m.evaluate_many(kept, chain.inputs(ideal, ideal.xyz, cond),
                                            options=chain.settings.metric_options_for(cond))
            _save_details(ideal_dir, tag, ideal_results, ideal, {"white_xyz": list(map(float, ideal.white_xyz))},
                          crop=_crop(t.scene, ideal))
    return rows


def _crop(scene: str, ideal):
    """The crop box of ``scene`` on the ideal's grid (the camera's too), or None (:mod:`.crops`)."""
    from .crops import crop_box

    return crop_box(scene, ideal.meta, ideal.xyz.shape)


def _result_rows(results: dict) -> list[dict]:
    from ..metrics import result_rows

    return result_rows(results)
