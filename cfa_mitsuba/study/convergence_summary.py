"""The convergence study's numerics and outputs: per-band errors, uniform
regions, convergence rates, the summary of a run, its table, CSV and JSON."""

from __future__ import annotations

__all__ = ["relative_rms_per_band", "uniform_region", "fit_rate", "rows_frame", "radiance_series", "summarise",
           "rate_text", "format_table", "write_outputs"]

import json
import math
from pathlib import Path

import numpy as np

from .convergence_plan import CSV_COLUMNS, FLOAT_FLOOR, FLOOR_FACTOR, WELL_BELOW, ConvergenceResult


def relative_rms_per_band(test: np.ndarray, reference: np.ndarray, region=None) -> np.ndarray:
    """Per band: rms over the pixels of (test - reference) / mean(reference).

    ``test``, ``reference``: (H, W, B) radiance; ``region``: (y0, x0, y1, x1)
    half-open pixel rectangle, or None for the whole image.  Returns (B,),
    dimensionless (0.01 = 1 %); a band whose reference mean is 0 gives NaN.
    """
    t, r = np.asarray(test, dtype=np.float64), np.asarray(reference, dtype=np.float64)
    if region is not None:
        y0, x0, y1, x1 = region
        t, r = t[y0:y1, x0:x1], r[y0:y1, x0:x1]
    d = (t - r).reshape(-1, t.shape[-1])
    rms = np.sqrt(np.mean(d * d, axis=0))
    mean = r.reshape(-1, r.shape[-1]).mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mean > 0, rms / mean, np.nan)


def uniform_region(luminance: np.ndarray, *, side: int | None = None) -> tuple[int, int, int, int]:
    """The square window where ``luminance`` (H, W) varies least.

    Windows of ``side`` pixels (default a tenth of the shorter image side,
    at least 4) on a half-window grid; the one with the lowest coefficient
    of variation (std / mean) wins, the brighter on a tie.  Returns
    (y0, x0, y1, x1), half-open.  Used on the reference render: the
    window's render error is then noise, not detail.
    """
    lum = np.asarray(luminance, dtype=np.float64)
    h, w = lum.shape
    s = side or max(4, min(h, w) // 10)
    s = min(s, h, w)
    step = max(1, s // 2)
    best, best_key = (0, 0, s, s), (math.inf, 0.0)
    for y in range(0, h - s + 1, step):
        for x in range(0, w - s + 1, step):
            win = lum[y:y + s, x:x + s]
            m = float(win.mean())
            if m <= 0:
                continue
            cv = float(win.std()) / m
            key = (round(cv, 12), -m)
            if key < best_key:
                best, best_key = (y, x, y + s, x + s), key
    return best


def fit_rate(x, y, floor=None) -> dict:
    """Least-squares slope of log(y) against log(x).

    Points with y <= 0, or at or below :data:`FLOOR_FACTOR` x ``floor``
    (scalar or per point), are left out.  Returns ``{"rate": slope or
    None, "points": n used}``; two distinct x are needed.
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    keep = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    if floor is not None:
        f = np.broadcast_to(np.asarray(floor, dtype=np.float64), y.shape)
        keep &= ~(np.isfinite(f) & (y <= FLOOR_FACTOR * f))
    n = int(keep.sum())
    if n < 2 or np.unique(x[keep]).size < 2:
        return {"rate": None, "points": n}
    slope = np.polyfit(np.log(x[keep]), np.log(y[keep]), 1)[0]
    return {"rate": float(slope), "points": n}



def _summ(a) -> dict:
    a = np.asarray(a, dtype=np.float64)
    return {"median": float(np.nanmedian(a)), "max": float(np.nanmax(a))}



def rows_frame(rows):
    """The measurement rows as a DataFrame with :data:`CSV_COLUMNS`."""
    import pandas as pd

    return pd.DataFrame(rows, columns=list(CSV_COLUMNS))


def radiance_series(df, stage: str, prefix: str):
    """Per quality: (wall_s, median over bands, max over bands, quality) of a radiance kind."""
    sub = df[(df["stage"] == stage) & df["quantity"].str.startswith(prefix + ":")]
    g = sub.groupby("quality", sort=True)
    return (g["wall_s"].first().to_numpy(dtype=float), g["error"].median().to_numpy(dtype=float),
            g["error"].max().to_numpy(dtype=float), g["error"].size().index.to_numpy(dtype=float))


def summarise(p, rows, units, ref_vals, metric_floor, region, exact, ref_times, level_times, pocs_default,
               noise_std, cfa_values, total_s) -> dict:
    df = rows_frame(rows)
    rates: dict = {"render": {}, "pocs": {}}
    floors = {}
    own_rows = df[(df["stage"] == "reference") & df["quantity"].str.startswith("radiance:")]["error"]
    own_measured = _summ(own_rows)
    for prefix, label in (("radiance", "image"), ("uniform", "uniform region")):
        _, own_med, own_max, _ = radiance_series(df, "reference", prefix)
        t, med, mx, q = radiance_series(df, "render", prefix)
        for agg, y, f in (("median band", med, own_med[0]), ("worst band", mx, own_max[0])):
            key = f"radiance, {label}, {agg}"
            floor = max(f, FLOAT_FLOOR)
            floors[key] = floor
            r_t = fit_rate(t, y, floor)
            r_q = fit_rate(q, y, floor)
            rates["render"][key] = {"per_wall_time": r_t["rate"], "per_spp": r_q["rate"], "points": r_t["points"],
                                    "unit": "relative", "floor": floor}
    for stage, floor_of in (("render", metric_floor), ("pocs", {})):
        for k in ref_vals:
            sub = df[(df["stage"] == stage) & (df["quantity"] == k)].sort_values("quality")
            # Renders are float32: metric changes below FLOAT_FLOOR of the value are rounding.
            floor = max(floor_of.get(k, 0.0), FLOAT_FLOOR * max(abs(ref_vals[k]), 1.0))
            r_t = fit_rate(sub["wall_s"], sub["error"], floor)
            r_q = fit_rate(sub["quality"], sub["error"], floor)
            rates[stage][k] = {"per_wall_time": r_t["rate"], "per_spp" if stage == "render" else "per_iteration":
                               r_q["rate"], "points": r_t["points"], "unit": units[k], "floor": floor}
    # The default spp: its error and time (interpolated in log-log if it was not a level).
    d = p.default_spp
    at_default: dict = {"spp": d}
    lev = df[(df["stage"] == "render") & (df["quality"] == d)]
    if len(lev):
        at_default["wall_s"] = float(lev["wall_s"].iloc[0])
        for prefix, label in (("radiance", "image"), ("uniform", "uniform region")):
            e = lev[lev["quantity"].str.startswith(prefix + ":")]["error"]
            at_default[f"radiance {label} median band"] = float(e.median())
            at_default[f"radiance {label} worst band"] = float(e.max())
        one = {k: float(lev[lev["quantity"] == k]["error"].iloc[0]) for k in ref_vals}
        seeds = df[df["stage"] == "render-seeds"]
        at_default["metric_deviation_one_render"] = one
        at_default["renders"] = 1 + int(p.default_seeds)
        # rms over the level's render and the extra seeds: the deviation a study's render carries
        at_default["metric_deviation"] = {
            k: float(np.sqrt(np.mean(np.square([one[k], *seeds[seeds["quantity"] == k]["error"].astype(float)]))))
            for k in ref_vals}
        at_default["metric_deviation_max"] = {
            k: float(max([one[k], *seeds[seeds["quantity"] == k]["error"].astype(float)])) for k in ref_vals}
    checks = {}
    pocs_checks = {}

    def by_metric(stage):
        sub = df[df["stage"] == stage]
        return dict(zip(sub["quantity"], sub["error"].astype(float)))

    def compare(c: dict, dev, spread, gap):
        c.update(cfa_spread=spread, cfa_smallest_gap=gap)
        if dev is not None and spread is not None:
            c["ratio_to_spread"] = dev / spread if spread > 0 else None
            c["ratio_to_smallest_gap"] = dev / gap if gap and gap > 0 else None
            c["well_below_spread"] = bool(spread > 0 and dev <= WELL_BELOW * spread)
            c["below_smallest_gap"] = bool(gap is not None and gap > 0 and dev < gap)
        return c

    spread, gap = by_metric("cfa-spread"), by_metric("cfa-gap")
    pairs, common = by_metric("cfa-pairs"), by_metric("cfa-common")
    pocs_spread, pocs_gap = by_metric("pocs-cfa-spread"), by_metric("pocs-cfa-gap")
    if p.demosaic == "pocs":
        pocs_spread, pocs_gap = spread, gap
    for k in ref_vals:
        dev = at_default.get("metric_deviation", {}).get(k)
        checks[k] = compare({"render_deviation_at_default": dev, "renders": at_default.get("renders"),
                             "render_deviation_max": at_default.get("metric_deviation_max", {}).get(k),
                             "unit": units[k], "reference_value": ref_vals[k],
                             "reference_noise": metric_floor[k], "sensor_noise_std": noise_std.get(k)},
                            dev, spread.get(k), gap.get(k))
        if k in pairs:
            checks[k].update(cfa_difference_deviation=pairs[k], cfa_common_shift=common[k],
                             difference_below_smallest_gap=bool(gap.get(k) and pairs[k] < gap[k]),
                             difference_well_below_spread=bool(spread.get(k) and pairs[k] <= WELL_BELOW * spread[k]))
        pdev = pocs_default["deviation"][k]
        pocs_checks[k] = compare({"pocs_default_deviation": pdev, "unit": units[k]}, pdev, pocs_spread.get(k),
                                 pocs_gap.get(k))
    return {
        "scene": p.name,
        "plan": p.to_dict(),
        "reference": {
            "spp_per_render": p.reference_spp, "renders": 2, "seeds": [p.seed + 1, p.seed + 2],
            "wall_s": ref_times,
            "own_noise": "half the rms difference of the two renders, relative to the reference's mean, per band",
            "own_noise_measured_median_band": own_measured["median"],
            "own_noise_measured_worst_band": own_measured["max"],
            "own_noise_image_median_band": floors["radiance, image, median band"],
            "own_noise_image_worst_band": floors["radiance, image, worst band"],
            "floor_definition": f"max(the reference's own noise, {FLOAT_FLOOR:g} float32 rounding)",
            "exact_check": exact,
            "metric_values": ref_vals,
            "metric_noise": {k: metric_floor[k] for k in ref_vals},
        },
        "uniform_region": {"rect_yx": list(region),
                           "how": "square window of the reference where luminance varies least (lowest std/mean)"},
        "level_wall_s": {str(k): v for k, v in level_times.items()},
        "at_default": at_default,
        "pocs_default": pocs_default,
        "rates": rates,
        "rate_definition": "least-squares slope of log(error) against log(wall time) (and against log(spp) or "
                           f"log(iterations)) over the points above {FLOOR_FACTOR:g}x the noise floor",
        "cfa_values": cfa_values,
        "checks": checks,
        "pocs_checks": pocs_checks,
        "well_below": f"render-induced deviation at the default spp <= {WELL_BELOW:g} x the CFA spread",
        "total_wall_s": total_s,
        "cores": _cores(),
        "code": _code_version(),
    }


def _code_version() -> dict:
    """The package version and, in a git checkout, the commit and whether
    the working tree had changes (results depend on the code they ran)."""
    import subprocess

    from .._version import __version__

    out = {"cfa_mitsuba": __version__}
    root = Path(__file__).resolve().parents[2]
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, timeout=10)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, timeout=10)
        if commit.returncode == 0:
            out["git_commit"] = commit.stdout.strip()
            out["git_dirty"] = bool(dirty.stdout.strip())
    except (OSError, subprocess.SubprocessError):
        pass
    return out


def _cores() -> int:
    import os

    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


# ----------------------------------------------------------------- output

def _fmt(x, digits=3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    if x == 0:
        return "0"
    return f"{x:.{digits}g}"


def rate_text(r) -> str:
    return "n/a" if r is None else f"{r:+.2f}"


def format_table(result: ConvergenceResult) -> str:
    """The short stdout table: one line per spp level and POCS count, the
    rates, the reference's own noise and the check against the CFA spread."""
    p, s = result.plan, result.summary
    df = rows_frame(result.rows)
    metrics = list(s["reference"]["metric_values"])
    out = [f"{p.name}: {p.width} x {p.height} EXR px (K = {p.oversample}), {p.cfa} + {p.demosaic}, "
           f"reference 2 x {p.reference_spp} spp (own noise: median band "
           f"{100 * s['reference']['own_noise_measured_median_band']:.2g} %)"]
    head = ["spp", "wall s", "rad med %", "rad max %", "unif med %"] + [f"d {m}" for m in metrics]
    lines = [head]
    for q in sorted(df[df["stage"] == "render"]["quality"].unique()):
        lev = df[(df["stage"] == "render") & (df["quality"] == q)]
        rad = lev[lev["quantity"].str.startswith("radiance:")]["error"]
        uni = lev[lev["quantity"].str.startswith("uniform:")]["error"]
        mark = "*" if q == p.default_spp else ""
        lines.append([f"{int(q)}{mark}", f"{lev['wall_s'].iloc[0]:.2f}", _fmt(100 * rad.median()),
                      _fmt(100 * rad.max()), _fmt(100 * uni.median())]
                     + [_fmt(float(lev[lev["quantity"] == m]["error"].iloc[0])) for m in metrics])
    out.append(_columns(lines))
    rr = s["rates"]["render"]
    out.append("rates (slope of log error vs log wall time): " + "; ".join(
        f"{k}: {rate_text(v['per_wall_time'])}" for k, v in rr.items()
        if k.endswith("median band") or k in metrics))
    lines = [["pocs it", "wall s"] + [f"d {m}" for m in metrics]]
    for q in sorted(df[df["stage"] == "pocs"]["quality"].unique()):
        lev = df[(df["stage"] == "pocs") & (df["quality"] == q)]
        lines.append([str(int(q)), f"{lev['wall_s'].iloc[0]:.2f}"]
                     + [_fmt(float(lev[lev["quantity"] == m]["error"].iloc[0])) for m in metrics])
    pd_ = s["pocs_default"]
    lines.append([f"{pd_['iterations_done']}*", f"{pd_['wall_s']:.2f}"]
                 + [_fmt(pd_["deviation"][m]) for m in metrics])
    out.append(_columns(lines))
    out.append("(* the default; d = |deviation| from the reference, in the metric's unit)")
    for m, c in s["checks"].items():
        if c.get("cfa_spread") is None:
            continue
        if c["render_deviation_at_default"] is None:
            verdict = "not measured (the default spp was not among the levels)"
        elif c.get("well_below_spread"):
            verdict = f"well below (<= {WELL_BELOW:g} x the spread)"
        else:
            verdict = f"NOT well below (> {WELL_BELOW:g} x the spread)"
        if c.get("cfa_difference_deviation") is not None:
            out.append(f"check {m}: at {p.default_spp} spp the differences between CFAs move by "
                       f"{_fmt(c['cfa_difference_deviation'])} {c['unit']} rms (common shift "
                       f"{_fmt(c['cfa_common_shift'])}) vs the smallest gap {_fmt(c['cfa_smallest_gap'])}: "
                       + ("below" if c["difference_below_smallest_gap"] else "NOT below"))
        measured = (f"(rms of {c['renders']} renders) {_fmt(c['render_deviation_at_default'])} {c['unit']}"
                    if c["render_deviation_at_default"] is not None and c.get("renders") else "not measured")
        out.append(f"check {m}: render-induced deviation at {p.default_spp} spp {measured}"
                   f" vs CFA spread {_fmt(c['cfa_spread'])} (smallest gap {_fmt(c['cfa_smallest_gap'])}, "
                   f"sensor-noise std {_fmt(c['sensor_noise_std'])}): {verdict}")
    for m, c in s.get("pocs_checks", {}).items():
        if c.get("cfa_spread") is None:
            continue
        verdict = "well below" if c.get("well_below_spread") else "NOT well below"
        out.append(f"check {m} (POCS default, {s['pocs_default']['iterations_done']} iterations): deviation from "
                   f"converged {_fmt(c['pocs_default_deviation'])} {c['unit']} vs CFA spread with POCS "
                   f"{_fmt(c['cfa_spread'])} (smallest gap {_fmt(c['cfa_smallest_gap'])}): {verdict}")
    return "\n".join(out)


def _columns(lines) -> str:
    widths = [max(len(r[i]) for r in lines) for i in range(len(lines[0]))]
    return "\n".join("  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in lines)


def write_outputs(result: ConvergenceResult, out_dir) -> dict:
    """Write ``convergence_<scene>.csv`` (tidy) and ``.json`` (summary);
    returns {kind: path}.  The plot is the report stage's
    (:func:`cfa_mitsuba.report.convergence.write_convergence` writes all)."""
    from ..io import atomic_output, check_writable_dir
    from .details_layout import safe_label

    out = check_writable_dir(out_dir)
    stem = f"convergence_{safe_label(result.plan.name)}"
    paths = {"csv": out / f"{stem}.csv", "json": out / f"{stem}.json"}
    df = rows_frame(result.rows)
    with atomic_output(paths["csv"]) as tmp:
        df.to_csv(tmp, index=False, float_format="%.6g")
    with atomic_output(paths["json"]) as tmp:
        tmp.write_text(json.dumps(_jsonable(result.summary), indent=1, allow_nan=False))
    return paths


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj
