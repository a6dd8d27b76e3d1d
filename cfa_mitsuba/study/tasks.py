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
derived from the study seed and the task's identity (never from the order
in which tasks run), so a study gives the same numbers on one process, on
many, or on a Dask cluster, and after an interruption.
"""

from __future__ import annotations

__all__ = ["render_task", "evaluate_task", "task_seed", "load_scene_image", "condition_columns", "safe_label"]

import hashlib
import json
import threading
import time
from pathlib import Path

import numpy as np

from ..io.sidecar import json_default


def task_seed(study_seed: int, *parts) -> int:
    """A noise seed from the study seed and a task's identity (32 bits)."""
    text = json.dumps([int(study_seed), *[str(p) for p in parts]])
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:4], "little")


def realisation_seeds(study_seed: int, scene: str, cfa: str, luminance: float, n: int) -> list[int]:
    """The noise seeds of ``n`` realisations of one capture: the first is the
    task's own seed (:func:`task_seed`), the others add the realisation's
    index to its identity, so adding realisations never changes the first."""
    first = task_seed(study_seed, scene, cfa, luminance)
    return [first] + [task_seed(study_seed, scene, cfa, luminance, i) for i in range(1, int(n))]


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


def _thumbnail(srgb: np.ndarray, path: Path, longest: int = 240) -> None:
    from ..io import write_image

    h, w = srgb.shape[:2]
    step = max(1, int(np.ceil(max(h, w) / longest)))
    hh, ww = (h // step) * step, (w // step) * step
    small = srgb[:hh, :ww].reshape(hh // step, step, ww // step, step, 3).mean(axis=(1, 3))
    write_image(path, small)


def _save_details(folder: Path, stem: str, results: dict, rendered, extra: dict) -> None:
    """Curves and tables as JSON, S-CIELAB map (reduced) as .npy, thumbnail PNG."""
    from ..io import atomic_output

    folder.mkdir(parents=True, exist_ok=True)
    payload = {"extra": extra}
    for name, r in results.items():
        payload[name] = r.to_dict() if hasattr(r, "to_dict") else {"metric": name, "value": float(r)}
        if name == "scielab" and "map" in getattr(r, "details", {}):
            dmap = np.asarray(r.details["map"], dtype=np.float64)
            step = max(1, int(np.ceil(max(dmap.shape) / 240)))
            hh, ww = (dmap.shape[0] // step) * step, (dmap.shape[1] // step) * step
            small = dmap[:hh, :ww].reshape(hh // step, step, ww // step, step).mean(axis=(1, 3))
            with atomic_output(folder / f"{stem}.scielab.npy") as tmp:
                with open(tmp, "wb") as fh:
                    np.save(fh, small.astype(np.float32))
    with atomic_output(folder / f"{stem}.json") as tmp:
        tmp.write_text(json.dumps(payload, allow_nan=False, default=json_default))
    if rendered is not None:
        _thumbnail(rendered.srgb, folder / f"{stem}.png")


def evaluate_task(task: dict) -> dict:
    """Capture one CFA of one scene under one condition and evaluate every demosaic.

    ``task`` keys: ``source`` (see :func:`load_scene_image`), ``scene``,
    ``condition`` (:class:`~.conditions.Condition`), ``cfa``, ``cfa_label``,
    ``demosaics``, ``metrics``, ``chain`` (:class:`~.chain.ChainSettings`),
    ``details_dir`` (or None), ``details_tag`` (the file stem of its details),
    ``realisations`` (noise realisations of each capture, default 1; rows
    carry ``realisation`` 0, 1, ...; details are kept of the first).

    Returns ``{"rows": [...], "timing": {...}, "failures": [...]}``: a
    metric that could not be measured on one camera output is a failure
    record (scene, cfa, demosaic, condition, metric, error), not a row.
    """
    from .chain import CameraChain

    cond = task["condition"]
    chain = CameraChain(task["chain"])
    scene_key = json.dumps(task["source"], sort_keys=True)
    cfa_label = task.get("cfa_label", task["cfa"])
    details_dir = Path(task["details_dir"]) if task.get("details_dir") else None
    tag = task.get("details_tag") or f"L{cond.luminance:g}"
    rows, failures = [], []
    raw = ideal = None

    def image():
        return load_scene_image(task["source"])

    spectra_used = _spectra_in_effect(task["cfa"], cond, chain.settings)
    applies = _readout_applies(task["cfa"], cond)
    if not applies and (task.get("ideal_rows") or details_dir is not None):
        ideal = chain.ideal(chain.optical(image, cond, scene_key), cond, scene_key)
    seeds = realisation_seeds(cond.seed, task["scene"], task["cfa"], cond.luminance,
                              int(task.get("realisations", 1))) if applies else []
    for i, seed in enumerate(seeds):
        for raw, ideal, method, ev in chain.evaluate(image, task["cfa"], task["demosaics"], task["metrics"], cond,
                                                     seed, scene_key):
            base = {"scene": task["scene"], "cfa": cfa_label, "demosaic": method,
                    **condition_columns(cond, ideal.meta), "spectra": spectra_used,
                    "base": bool(task.get("base", True)), "realisation": i}
            if not hasattr(ev, "results"):
                # No output to measure (a channel the scene white leaves dark) or
                # no scale for it (a black ideal interior): every metric of this
                # output is unmeasurable.
                failures.extend({**base, "metric": name, "error": str(ev)} for name in task["metrics"])
                continue
            rows.extend({**base, **r} for r in _result_rows(ev.results))
            failures.extend({**base, **f} for f in ev.failures)
            if details_dir is not None and i == 0:  # curves and thumbnails of the first realisation
                isp_meta = ev.processed.meta.get("isp", {})
                extra = {
                    "mean_match_scale": ev.mean_match_scale,
                    "condition_number": isp_meta.get("condition_number"),
                    "noise_gain_xyz": isp_meta.get("noise_gain_xyz"),
                    "fit_rank": isp_meta.get("fit_rank"),
                    "exposure_s": float(raw.exposure_s),
                    "saturated_fraction": raw.meta.get("saturated_fraction"),
                    "seed": seed,
                }
                _save_details(details_dir / task["scene"] / safe_label(cfa_label) / method, tag, ev.results,
                              ev.processed, extra)
    ideal_rows = []
    if task.get("ideal_rows") and ideal is not None:
        # the ideal sensor against itself: the anchor of the 'ideal' range policy
        from .. import metrics as m

        got = m.evaluate_many(task["metrics"], chain.inputs(ideal, ideal.xyz, cond), [],
                              options=chain.settings.options_of_metrics())
        base = {"scene": task["scene"], "cfa": "ideal", "demosaic": "none", **condition_columns(cond, ideal.meta),
                "base": bool(task.get("base", True)), "realisation": 0}
        ideal_rows = [{**base, **r} for r in _result_rows(got)]
    if details_dir is not None and ideal is not None:
        ideal_dir = details_dir / task["scene"] / "ideal"
        if not (ideal_dir / f"{tag}.png").exists():
            from .. import metrics as m

            mtf_only = [n for n in task["metrics"] if n in ("mtf",)]
            ideal_results = m.evaluate_many(mtf_only, chain.inputs(ideal, ideal.xyz, cond),
                                            options=chain.settings.options_of_metrics())
            _save_details(ideal_dir, tag, ideal_results, ideal, {"white_xyz": list(map(float, ideal.white_xyz))})
    return {"rows": rows, "timing": chain.timing, "failures": failures, "ideal_rows": ideal_rows}


def _result_rows(results: dict) -> list[dict]:
    from ..metrics import result_rows

    return result_rows(results)


def safe_label(label: str) -> str:
    """The file-name-safe form of a label: the folder a CFA gets under
    ``details/`` (TOML CFAs are labelled by their name, which may hold any
    character); the report reads the same folders."""
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in str(label))
