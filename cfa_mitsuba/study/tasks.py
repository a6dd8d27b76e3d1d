"""The units of work of a study, run in worker processes (local or Dask).

Two kinds of task, both plain functions of plain (picklable, JSON-able)
arguments so any executor can run them:

* :func:`render_task` renders one scene through the shared render cache
  (DESIGN.md: the cache lives outside the results, keyed by everything that
  determines the render, written atomically under a lock).
* :func:`evaluate_task` takes one (scene, luminance, CFA): it loads the
  render, computes the optics once per scene and process (memoised), captures
  the CFA once, then for every demosaicing method processes the raw image
  and computes the metrics the scene feeds, against the ideal XYZ sensor
  (same optics and pixel, noise off, no mosaic).  It writes its detail files
  (curves, maps, thumbnails) and returns the tidy metric rows.

Everything after the render is deterministic: the noise seed of a task is
derived from the study seed and the task's identity (never from the order
in which tasks run), so a study gives the same numbers on one process, on
many, or on a Dask cluster, and after an interruption.
"""

from __future__ import annotations

__all__ = ["render_task", "evaluate_task", "task_seed", "load_scene_image", "metric_results", "metric_rows", "safe_label"]

import functools
import hashlib
import json
import threading
import time
from pathlib import Path

import numpy as np

#: Rows added beside each scene's headline metric: name -> (detail key, unit).
#: They go to metrics.csv (Table 1 needs mean dL; the report plots the rest)
#: but are not scored.
SECONDARY = {
    "delta-e": {"delta-e76": ("mean_de1976", "dEab"), "delta-l": ("mean_dl_grey", "L*")},
    "scielab": {"scielab-interior": ("mean_interior", "dE00")},
}


def task_seed(study_seed: int, *parts) -> int:
    """A noise seed from the study seed and a task's identity (32 bits)."""
    text = json.dumps([int(study_seed), *[str(p) for p in parts]])
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:4], "little")


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


# --- per-process memo: the optics and the ideal image of the scene in hand --


@functools.lru_cache(maxsize=2)
def _optical(source_json: str, optics_json: str, sensor_json: str):
    from ..optics import OpticsParams, compute_optics
    from ..sensor.params import SensorParams

    source = json.loads(source_json)
    optics = json.loads(optics_json)
    sensor = SensorParams(**json.loads(sensor_json))
    if isinstance(optics.get("lens_transmittance"), list):
        optics["lens_transmittance"] = tuple(optics["lens_transmittance"])
    scene = load_scene_image(source)
    oi = compute_optics(scene, OpticsParams(**optics), pixel_pitch_um=sensor.pixel_pitch_um,
                        fill_factor=sensor.fill_factor)
    return oi


@functools.lru_cache(maxsize=4)
def _ideal(source_json: str, optics_json: str, sensor_json: str, luminance: float, capture_json: str):
    from ..isp import process
    from ..sensor import capture_ideal
    from ..sensor.params import SensorParams

    oi = _optical(source_json, optics_json, sensor_json)
    cap = json.loads(capture_json)
    raw = capture_ideal(oi, luminance_cd_m2=luminance, sensor=SensorParams(**json.loads(sensor_json)),
                        exposure_s=cap.get("exposure", "auto"))
    return process(raw)


def _linear_rgb(xyz: np.ndarray, white_xyz: np.ndarray) -> np.ndarray:
    """Linear sRGB (IEC 61966-2-1 matrix), white mapped to 1: the linear
    data the slanted-edge analysis needs (an MTF is scale-invariant)."""
    from ..metrics import colour as mcolour

    return mcolour.xyz_to_linear(xyz, scale=float(white_xyz[1]))


def _srgb8(xyz: np.ndarray, white_xyz: np.ndarray) -> np.ndarray:
    from ..metrics import colour as mcolour

    return mcolour.xyz_to_srgb8(xyz, white_xyz)


def metric_results(metric_names, ideal_xyz, cam_xyz, white_xyz, geo: dict, pitch_um: float,
                    failures: list | None = None) -> dict:
    """Run the requested metrics of one scene; returns {name: MetricResult|float}.

    A metric that cannot be computed on this image (a user-facing
    CfaMitsubaError, e.g. an edge the analysis cannot locate) is left out of
    the result and its message appended to ``failures`` (when given), so one
    unmeasurable camera does not end a study; without ``failures`` it raises.
    """
    from ..errors import CfaMitsubaError

    out = {}
    srgb_pair = [None]
    for name in metric_names:
        try:
            out[name] = _one_metric(name, ideal_xyz, cam_xyz, white_xyz, geo, pitch_um, srgb_pair)
        except CfaMitsubaError as exc:
            if failures is None:
                raise
            failures.append({"metric": name, "error": str(exc)})
    return out


#: Sidecar geometry a metric cannot run without (the others fall back to
#: the whole image or to a default).
_NEEDS_GEOMETRY = {"moire": ("frequency_cy_per_deg", "the chirp's frequency per column"),
                   "scielab": ("samples_per_degree", "the field of view (fov_deg)")}


def _one_metric(name, ideal_xyz, cam_xyz, white_xyz, geo, pitch_um, srgb_pair):
    from .. import metrics as m
    from ..errors import CfaMitsubaError

    if name in _NEEDS_GEOMETRY and geo.get(_NEEDS_GEOMETRY[name][0]) is None:
        key, what = _NEEDS_GEOMETRY[name]
        raise CfaMitsubaError(f"{name} needs {what} in the render's sidecar ('{key}'); this scene has none")

    if name == "delta-e":
        return m.delta_e(ideal_xyz, cam_xyz, white_xyz, patches=geo.get("patches"))
    if name == "scielab":
        return m.scielab(ideal_xyz, cam_xyz, white_xyz, samples_per_degree=geo["samples_per_degree"])
    if name == "mtf":
        return m.mtf(_linear_rgb(cam_xyz, white_xyz), roi=geo.get("roi"), pixel_pitch_um=pitch_um,
                     reference=_linear_rgb(ideal_xyz, white_xyz))
    if name == "moire":
        return m.moire(ideal_xyz, cam_xyz, white_xyz, frequency_cy_per_deg=geo["frequency_cy_per_deg"],
                       row=geo.get("row"))
    if name == "achromatic":
        return m.achromatic(ideal_xyz, cam_xyz, white_xyz, row=geo.get("row"), steps=geo.get("steps"))
    if name in ("ssim", "mdsi", "haarpsi"):
        if srgb_pair[0] is None:
            srgb_pair[0] = (_srgb8(ideal_xyz, white_xyz), _srgb8(cam_xyz, white_xyz))
        fn = {"ssim": m.ssim, "mdsi": m.mdsi, "haarpsi": m.haarpsi}[name]
        return fn(*srgb_pair[0])
    raise ValueError(f"unknown metric {name!r}")  # pragma: no cover - the config validator refuses it


def metric_rows(base: dict, results: dict) -> list[dict]:
    from ..metrics import get_metric

    rows = []
    for name, r in results.items():
        unit = getattr(r, "unit", None)
        if unit is None:
            unit = get_metric(name).unit
        rows.append({**base, "metric": name, "value": float(r), "unit": unit})
        for sec, (key, sec_unit) in SECONDARY.get(name, {}).items():
            v = getattr(r, "details", {}).get(key)
            if v is not None and np.isfinite(v):
                rows.append({**base, "metric": sec, "value": float(v), "unit": sec_unit})
    return rows


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
        tmp.write_text(json.dumps(payload, allow_nan=False, default=_json_default))
    if rendered is not None:
        _thumbnail(rendered.srgb, folder / f"{stem}.png")


def _json_default(obj):
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(type(obj).__name__)


def evaluate_task(task: dict) -> dict:
    """Capture one CFA of one scene at one luminance and evaluate every demosaic.

    ``task`` keys: ``source`` (see :func:`load_scene_image`), ``scene``,
    ``luminance``, ``cfa``, ``demosaics``, ``metrics``, ``optics``,
    ``sensor``, ``capture`` (noise, exposure, reference luminance), ``isp``
    (white balance, white preserving, pocs iterations), ``mean_match``,
    ``seed`` (the study seed), ``details_dir`` (or None).

    Returns ``{"rows": [...], "timing": {...}, "failures": [...]}``: a
    metric that could not be measured on one camera output is a failure
    record (scene, cfa, demosaic, luminance, metric, error), not a row.
    """
    from .. import metrics as m
    from ..errors import CfaMitsubaError
    from ..isp import process
    from ..sensor import capture
    from ..sensor.params import SensorParams

    timing = {"optics_s": 0.0, "capture_s": 0.0, "process_s": 0.0, "metrics_s": 0.0}
    src_json = json.dumps(task["source"], sort_keys=True)
    opt_json = json.dumps(task["optics"], sort_keys=True)
    sen_json = json.dumps(task["sensor"], sort_keys=True)
    cap_json = json.dumps(task["capture"], sort_keys=True)
    lum = float(task["luminance"])

    t = time.perf_counter()
    oi = _optical(src_json, opt_json, sen_json)
    ideal = _ideal(src_json, opt_json, sen_json, lum, cap_json)
    timing["optics_s"] = time.perf_counter() - t

    sensor = SensorParams(**task["sensor"])
    cap = task["capture"]
    seed = task_seed(task["seed"], task["scene"], task["cfa"], lum)
    t = time.perf_counter()
    raw = capture(oi, task["cfa"], luminance_cd_m2=lum, exposure_s=cap.get("exposure", "auto"),
                  noise=cap.get("noise", "all"), seed=seed, sensor=sensor,
                  reference_luminance_cd_m2=cap.get("reference_luminance_cd_m2", 100.0))
    timing["capture_s"] = time.perf_counter() - t

    geo = m.scene_geometry(ideal.meta, ideal.xyz.shape)
    white = np.asarray(ideal.white_xyz, dtype=np.float64)
    pitch = sensor.pixel_pitch_um
    cfa_label = task.get("cfa_label", task["cfa"])
    isp_opts = dict(task.get("isp") or {})
    pocs_iterations = isp_opts.pop("pocs_iterations", None)
    rows, failures = [], []
    details_dir = Path(task["details_dir"]) if task.get("details_dir") else None
    lum_tag = f"L{lum:g}"
    for method in task["demosaics"]:
        opts = dict(isp_opts)
        if method == "pocs" and pocs_iterations is not None:
            opts["iterations"] = pocs_iterations
        base = {"scene": task["scene"], "cfa": cfa_label, "demosaic": method, "luminance": lum}
        try:
            t = time.perf_counter()
            out = process(raw, method, **opts)
            timing["process_s"] += time.perf_counter() - t
            cam, scale = out.xyz, 1.0
            if task.get("mean_match", True):
                cam, scale = m.mean_match(cam, ideal.xyz, return_scale=True)
        except CfaMitsubaError as exc:
            # No output to measure (a channel the scene white leaves dark) or
            # no scale for it (a black ideal interior): every metric of this
            # output is unmeasurable.
            failures.extend({**base, "metric": name, "error": str(exc)} for name in task["metrics"])
            continue
        t = time.perf_counter()
        failed: list[dict] = []
        results = metric_results(task["metrics"], ideal.xyz, cam, white, geo, pitch, failed)
        timing["metrics_s"] += time.perf_counter() - t
        rows.extend(metric_rows(base, results))
        failures.extend({**base, **f} for f in failed)
        if details_dir is not None:
            isp_meta = out.meta.get("isp", {})
            extra = {
                "mean_match_scale": float(scale),
                "condition_number": isp_meta.get("condition_number"),
                "noise_gain_xyz": isp_meta.get("noise_gain_xyz"),
                "fit_rank": isp_meta.get("fit_rank"),
                "exposure_s": float(raw.exposure_s),
                "saturated_fraction": raw.meta.get("saturated_fraction"),
                "seed": seed,
            }
            _save_details(details_dir / task["scene"] / safe_label(cfa_label) / method, lum_tag, results, out, extra)
    if details_dir is not None:
        ideal_dir = details_dir / task["scene"] / "ideal"
        if not (ideal_dir / f"{lum_tag}.png").exists():
            ideal_results = metric_results(
                [n for n in task["metrics"] if n in ("mtf",)], ideal.xyz, ideal.xyz, white, geo, pitch)
            _save_details(ideal_dir, lum_tag, ideal_results, ideal, {"white_xyz": white.tolist()})
    return {"rows": rows, "timing": timing, "failures": failures}


def safe_label(label: str) -> str:
    """The file-name-safe form of a label: the folder a CFA gets under
    ``details/`` (TOML CFAs are labelled by their name, which may hold any
    character); the report reads the same folders."""
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in str(label))
