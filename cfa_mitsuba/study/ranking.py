"""Scores and ranks with their uncertainty, under a stated range policy.

Range policies (``[normalisation] policy``), the (worst, best) ends of
eq. 8 for each scored metric:

- ``paper``: the paper's printed ranges (:func:`.scoring.default_ranges`,
  the MSP in our cycles per degree, MTF50 moved to the pixel pitch);
- ``study``: fitted to the compared set: the worst and the best mean value
  over the study's CFAs and demosaics, so the scores span 0..1;
- ``ideal`` (default): anchored on the ideal sensor (same optics and
  pixel, noise off, no mosaic): the ideal's own value scores 1 (dE 0,
  SSIM 1, the ideal's MTF50, the chirp's top frequency for the MSP) and the
  worst mean value of the compared set scores 0.  A camera past the ideal
  (an MTF50 raised by sharpening overshoot) is clipped at 1: overshoot is
  not rewarded.

Under any policy a metric whose values are the same for every CFA cannot
rank them: it is reported as such (``constant``) and left out of the mean
scores rather than scored as a tie of ones.  Each realisation (render seed
x sensor seed) is scored on its own; the tables carry the mean and 95 %
interval over realisations (:func:`.intervals.nested_interval`, the render
component pooled over the values of one level: :mod:`.variance`), and rank
intervals from paired comparisons: realisation k of every CFA has the same
render and sensor seed, so two CFAs are compared through their
per-realisation score differences (:func:`.intervals.paired_rank_interval`).
"""

from __future__ import annotations

__all__ = ["POLICIES", "DEFAULT_POLICY", "policy_ranges", "score_realisations", "policy_summary"]

import numpy as np

from ..errors import CfaMitsubaError
from .intervals import aggregate, paired_rank_interval
from .scoring import ScoreRange, score

POLICIES = ("paper", "study", "ideal")
DEFAULT_POLICY = "ideal"
_KEYS = ["scene", "cfa", "demosaic", "luminance", "metric"]


def _direction(metric: str) -> bool:
    from ..metrics import get_metric

    return get_metric(metric).higher_is_better


def policy_ranges(policy: str, means, paper: dict, ideal: dict) -> tuple[dict, list[str]]:
    """({metric: ScoreRange}, [constant metrics]) for ``policy``.

    ``means``: the scored rows (mean over realisations: scene, cfa,
    demosaic, luminance, metric, value); ``paper``: the paper's ranges;
    ``ideal``: {metric: the ideal sensor's value}.
    """
    if policy not in POLICIES:
        raise CfaMitsubaError(f"unknown range policy {policy!r} (expected one of: {', '.join(POLICIES)})")
    ranges, constant = {}, []
    for metric, g in means.groupby("metric", sort=False):
        v = g["value"].to_numpy(dtype=float)
        hib = _direction(metric)
        spread = float(np.nanmax(v) - np.nanmin(v)) if v.size else 0.0
        if spread <= 1e-12 * max(1.0, float(np.nanmax(np.abs(v)))):
            constant.append(metric)
        unit = tuple(dict.fromkeys(g["unit"].fillna("").astype(str)))
        worst_seen = float(np.nanmin(v) if hib else np.nanmax(v))
        best_seen = float(np.nanmax(v) if hib else np.nanmin(v))
        if policy == "paper":
            ranges[metric] = paper[metric]
        elif policy == "study":
            if metric not in constant:
                ranges[metric] = ScoreRange(worst_seen, best_seen, unit)
        else:
            best = ideal.get(metric, best_seen)
            if not np.isfinite(best):
                best = best_seen
            if abs(best - worst_seen) > 0 and metric not in constant:
                ranges[metric] = ScoreRange(worst_seen, float(best), unit)
            elif metric not in constant:
                constant.append(metric)
    return ranges, constant


def _realisation_scores(rows, ranges, clip):
    import pandas as pd

    if "render_seed" not in rows.columns:  # rows written before render seeds: one render
        rows = rows.assign(render_seed=0)
    parts = []
    for r, g in rows.groupby("realisation", sort=True):
        s = score(g.drop(columns=["realisation"]), ranges, clip=clip)
        s["realisation"] = r
        parts.append(s)
    return pd.concat(parts, ignore_index=True)


def realisation_renders(every) -> dict:
    """{realisation: its render seed} of a study's scored rows: the highest
    ``render_seed`` among its rows (a chart's rows say 0, as their render is
    shared by every render seed; a path-traced scene's say which)."""
    if "render_seed" not in every.columns:
        return {}
    return every.groupby("realisation")["render_seed"].max().astype(int).to_dict()


def paired_ranks(frame, item: str, column: str, renders: dict, *, higher_is_better: bool = True):
    """(items in ``frame``'s order, rank, best rank, worst rank) of ``item``
    by the per-realisation ``column`` (one row per item and realisation),
    from paired comparisons (:func:`.intervals.paired_rank_interval`)."""
    wide = frame.pivot_table(index=item, columns="realisation", values=column, aggfunc="mean", sort=False)
    items = list(dict.fromkeys(frame[item]))
    wide = wide.reindex(index=items)
    groups = [renders.get(k, 0) for k in wide.columns]
    r, b, w = paired_rank_interval(wide.to_numpy(dtype=float), groups, higher_is_better=higher_is_better)
    return items, r, b, w


def _set_ranks(table, g, item, names, got, ranked_on=None):
    """Write ``got`` = (items, rank, best, worst) into ``table`` at ``g``'s rows
    under ``names``; the rank itself from ``ranked_on`` when given (the
    unclipped score of a metric)."""
    items, r, b, w = got
    pos = {c: i for i, c in enumerate(items)}
    idx = [pos[c] for c in g[item]]
    if ranked_on is not None:
        m = ranked_on.to_numpy(dtype=float)
        r = np.array([1 + int(np.sum(m > x)) for x in m])
        idx_r = list(range(len(m)))
    else:
        idx_r = idx
    table.loc[g.index, names] = np.stack([np.asarray(r)[idx_r], np.asarray(b)[idx], np.asarray(w)[idx]], 1)


def score_realisations(rows, ranges: dict, *, clip: bool = True, constant=(), every=None):
    """scores.csv: per-realisation scores averaged, with intervals and rank intervals.

    ``rows``: the scored metric rows of every realisation (columns of
    :data:`.scoring.METRIC_COLUMNS` plus ``realisation``); ``ranges``: the
    policy's ranges; ``constant``: metrics left out (they cannot rank);
    ``every``: those rows already scored per realisation (then ``rows`` is
    not read).
    """
    import pandas as pd

    if every is None:
        rows = rows[~rows["metric"].isin(list(constant))]
        if rows.empty:
            return rows
        every = _realisation_scores(rows, ranges, clip)
    elif every.empty:
        return every
    every = every.copy()
    renders = realisation_renders(every)
    every["_render"] = every["realisation"].map(renders).fillna(0).astype(int)
    pool = ["scene", "luminance", "metric"]  # the render component: one per scene, level and metric (variance.py)
    out = aggregate(every, _KEYS, "value", groups="render_seed", pool_by=pool)
    out = out.merge(aggregate(every, _KEYS, "score", prefix="score_", groups="render_seed", pool_by=pool).rename(
        columns={"score_score": "score"}), on=_KEYS)
    first = every.drop_duplicates(_KEYS).set_index(_KEYS)[["unit", "worst", "best"]]
    out = out.join(first, on=_KEYS)
    raw = every.groupby(_KEYS, sort=False)["raw_score"].mean().rename("raw_score")
    out = out.join(raw, on=_KEYS)
    # past an end by more than rounding (a mean at an end of a fitted range is exactly there)
    out["out_of_range"] = (out["raw_score"] < -1e-9) | (out["raw_score"] > 1 + 1e-9)
    out = out.drop(columns=["std", "score_std", "score_n"])
    # per metric: rank of the mean unclipped score, intervals from the paired (clipped) score differences
    for col in ("metric_rank", "metric_rank_best", "metric_rank_worst"):
        out[col] = 0
    for (d, lum, metric), g in out.groupby(["demosaic", "luminance", "metric"], sort=False):
        sub = every[(every["demosaic"] == d) & (every["luminance"] == lum) & (every["metric"] == metric)]
        _set_ranks(out, g, "cfa", ["metric_rank", "metric_rank_best", "metric_rank_worst"],
                   paired_ranks(sub, "cfa", "score", renders), ranked_on=g["raw_score"])
    # per (cfa, demosaic, luminance): the mean score and its interval over realisations
    per = every.drop_duplicates(["cfa", "demosaic", "luminance", "realisation"])
    per_agg = aggregate(per, ["cfa", "demosaic", "luminance"], "mean_score", prefix="mean_score_", groups="_render",
                        pool_by=["luminance"])
    per_agg = per_agg.rename(columns={"mean_score_mean_score": "mean_score"}).drop(
        columns=["mean_score_std", "mean_score_n"])
    per_agg = per_agg.merge(per.groupby(["cfa", "demosaic", "luminance"])["n_metrics"].max().reset_index(),
                            on=["cfa", "demosaic", "luminance"])
    for col in ("demosaic_rank", "demosaic_rank_best", "demosaic_rank_worst"):
        per_agg[col] = 0
    for (d, lum), g in per_agg.groupby(["demosaic", "luminance"], sort=False):
        sub = per[(per["demosaic"] == d) & (per["luminance"] == lum)]
        _set_ranks(per_agg, g, "cfa", ["demosaic_rank", "demosaic_rank_best", "demosaic_rank_worst"],
                   paired_ranks(sub, "cfa", "mean_score", renders))
    tot = every.drop_duplicates(["cfa", "luminance", "realisation"])
    tot_agg = aggregate(tot, ["cfa", "luminance"], "total_score", prefix="total_score_", groups="_render",
                        pool_by=["luminance"])
    tot_agg = tot_agg.rename(columns={"total_score_total_score": "total_score"}).drop(
        columns=["total_score_std", "total_score_n"])
    for col in ("total_rank", "total_rank_best", "total_rank_worst"):
        tot_agg[col] = 0
    for lum, g in tot_agg.groupby("luminance", sort=False):
        _set_ranks(tot_agg, g, "cfa", ["total_rank", "total_rank_best", "total_rank_worst"],
                   paired_ranks(tot[tot["luminance"] == lum], "cfa", "total_score", renders))
    out = out.merge(per_agg, on=["cfa", "demosaic", "luminance"], how="left")
    out = out.merge(tot_agg, on=["cfa", "luminance"], how="left")
    ints = [c for c in out.columns if c.endswith(("_rank", "_rank_best", "_rank_worst")) or c in ("n", "n_metrics")]
    out[ints] = out[ints].astype(int)
    return pd.DataFrame(out)


def policy_summary(means, paper: dict, ideal: dict, clip: bool = True, realisations=None, scored=None):
    """For every policy: per metric how many scores are clipped and whether
    the metric is constant, and each CFA's overall rank (per luminance).

    With ``realisations`` (the scored rows per noise realisation) the totals
    are scored per realisation and averaged, as scores.csv's are, so the
    study's own policy gives scores.csv's totals and ranks exactly; without
    them, the mean values are scored.  ``scored``: optionally (ranges,
    constant, :func:`score_realisations` of ``realisations`` under them), a
    table already made; a policy whose ranges and constant metrics are
    those takes it instead of scoring the realisations again (the study's
    own policy, when its config overrides no range: a speed-up only).

    Returns (clipping table, rank table) as DataFrames: ``policy, metric,
    scores, clipped, constant`` and ``policy, cfa, luminance, total_score,
    total_rank``."""
    import pandas as pd

    clip_rows, rank_rows = [], []
    for policy in POLICIES:
        ranges, constant = policy_ranges(policy, means, paper, ideal)
        kept = means[~means["metric"].isin(constant)]
        for metric, g in means.groupby("metric", sort=False):
            if metric in constant or metric not in ranges:
                clip_rows.append((policy, metric, len(g), 0, True))
                continue
            raw = ranges[metric].normalise(g["value"].to_numpy(dtype=float))
            clip_rows.append((policy, metric, len(g), int(np.sum((raw < -1e-9) | (raw > 1 + 1e-9))), False))
        if kept.empty:
            continue
        if realisations is not None and len(realisations):
            if scored is not None and scored[0] == ranges and list(scored[1]) == list(constant):
                s = scored[2]
            else:
                cols = ["scene", "cfa", "demosaic", "luminance", "metric", "value", "unit", "realisation"]
                cols += ["render_seed"] if "render_seed" in realisations.columns else []
                s = score_realisations(realisations[cols], ranges, clip=clip, constant=constant)
        else:
            s = score(kept, ranges, clip=clip)
        for _, r in s.drop_duplicates(["cfa", "luminance"]).iterrows():
            rank_rows.append((policy, r["cfa"], float(r["luminance"]), float(r["total_score"]), int(r["total_rank"])))
    return (pd.DataFrame(clip_rows, columns=["policy", "metric", "scores", "clipped", "constant"]),
            pd.DataFrame(rank_rows, columns=["policy", "cfa", "luminance", "total_score", "total_rank"]))
