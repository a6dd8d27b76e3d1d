"""The units of work of a study, run in worker processes (local or Dask):
the executor boundary.

Two kinds of task, both plain functions of plain (picklable) arguments so
any executor can run them:

* :func:`render_task` renders one scene through the shared render cache
  (DESIGN.md: the cache lives outside the results, keyed by everything that
  determines the render, written atomically under a lock).
* :func:`evaluate_task` takes one :class:`~.task_values.EvaluationTask`
  (scene, condition, CFA) and returns its :class:`~.task_values.TaskResult`:
  it hands the task and its render to the camera chain
  (:meth:`.chain.CameraChain.run`, which evaluates all of it: the optical
  image once per scene and condition in each process, the CFA captured once
  per realisation, every demosaicing method processed and measured against
  the ideal XYZ sensor), writes the detail files the chain kept (curves,
  maps, thumbnails) and returns the tidy metric rows, one column per
  condition axis.

Everything after the render is deterministic: the noise seed of a
realisation is derived from the study seed, the scene, the luminance and the
realisation's index (:func:`~.task_values.realisation_seeds`), so a study
gives the same numbers on one process, on many, or on a Dask cluster, and
after an interruption.
"""

from __future__ import annotations

__all__ = ["EvaluationTask", "TaskResult", "render_task", "evaluate_task", "evaluate_group", "task_seed",
           "realisation_seeds", "load_scene_image"]

import json
import threading
import time
from pathlib import Path

import numpy as np

from ..io.sidecar import json_default
from .chain import capture_columns
from .details_layout import ideal_folder, output_folder
from .task_values import EvaluationTask, TaskResult, realisation_seeds, task_seed  # noqa: F401  (the boundary's types)


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
    # encoding to (tests/study/test_tasks.py), without a power per value (5 of a thumbnail's 14 ms)
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


def _grey_electrons(raw, grey: float = 0.18) -> dict:
    """{channel: mean electrons per pixel} on an 18 % grey on the axis, in this capture."""
    e = np.asarray(raw.electrons_per_radiance) @ (grey * np.asarray(raw.white_radiance))
    return {str(c): float(v) for c, v in zip(raw.channels, e)}


def _details_extra(out, raw) -> dict:
    """What the report reads beside a camera output's curves."""
    ev = out.kept
    isp_meta = ev.processed.meta.get("isp", {})
    return {**capture_columns(raw), "grey_electrons": _grey_electrons(raw),
            "mean_match_scale": ev.mean_match_scale, "condition_number": isp_meta.get("condition_number"),
            "noise_gain_xyz": isp_meta.get("noise_gain_xyz"), "fit_rank": isp_meta.get("fit_rank"),
            "exposure_s": float(raw.exposure_s), "saturated_fraction": raw.meta.get("saturated_fraction"),
            "seed": out.seed,
            "saturation_rel": raw.meta.get("saturation_rel")}  # the top of the gray steps' dynamic range (steps.py)


def _write_details(evaluation, details_dir: Path, tag: str) -> None:
    """The detail files of the outputs the chain kept, and the ideal's."""
    t, ideal = evaluation.task, evaluation.ideal
    crop = None if ideal is None else _crop(t.scene, ideal)
    for out in evaluation.outputs:
        if out.kept is not None:
            _save_details(output_folder(details_dir, t.scene, t.label, out.demosaic), tag, out.kept.results,
                          out.kept.processed, _details_extra(out, out.raw), crop=crop)
    if ideal is not None and evaluation.ideal_results is not None:
        _save_details(ideal_folder(details_dir, t.scene), tag, evaluation.ideal_results, ideal,
                      {"white_xyz": list(map(float, ideal.white_xyz))}, crop=crop)


def _crop(scene: str, ideal):
    """The crop box of ``scene`` on the ideal's grid (the camera's too), or None (:mod:`.crops`)."""
    from .crops import crop_box

    return crop_box(scene, ideal.meta, ideal.xyz.shape)


def evaluate_group(tasks) -> list[TaskResult]:
    """:func:`evaluate_task` of each task of a group, in this process, in
    order.  The runner sends the tasks of one render and condition (every
    CFA) to one worker as a group, so that worker makes the optical and
    ideal images once and the others do not make them again."""
    return [evaluate_task(t) for t in tasks]


def evaluate_task(task) -> TaskResult:
    """Capture one CFA of one scene under one condition and evaluate every
    demosaic (:meth:`.chain.CameraChain.run`); write the details it kept.

    ``task``: an :class:`EvaluationTask` (or a dict of its fields).  A
    metric that could not be measured on one camera output is a failure
    record (scene, cfa, demosaic, condition, metric, error), not a row.
    """
    from .chain import CameraChain

    t = EvaluationTask.of(task)
    details_dir = Path(t.details_dir) if t.details_dir else None
    tag = t.details_tag or f"L{t.condition.luminance:g}"
    # the ideal's curves are written once per scene and condition, by the first task of its group to get there
    ideal_details = details_dir is not None and not (ideal_folder(details_dir, t.scene) / f"{tag}.png").exists()
    evaluation = CameraChain(t.chain, image_store=t.image_store).run(t, lambda: load_scene_image(t.source),
                                                                     ideal_details=ideal_details)
    if details_dir is not None:
        _write_details(evaluation, details_dir, tag)
    return evaluation.result()
