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
scores rather than scored as a tie of ones.  Each realisation (noise seed)
is scored on its own; the tables carry the mean and 95 % interval over
realisations, and rank intervals (:func:`.intervals.rank_interval`).
"""

from __future__ import annotations

__all__ = ["POLICIES", "DEFAULT_POLICY", "policy_ranges", "score_realisations", "policy_summary"]

import numpy as np

from ..errors import CfaMitsubaError
from .intervals import aggregate, rank_interval
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

    parts = []
    for r, g in rows.groupby("realisation", sort=True):
        s = score(g.drop(columns=["realisation"]), ranges, clip=clip)
        s["realisation"] = r
        parts.append(s)
    return pd.concat(parts, ignore_index=True)


def score_realisations(rows, ranges: dict, *, clip: bool = True, constant=()):
    """scores.csv: per-realisation scores averaged, with intervals and rank intervals.

    ``rows``: the scored metric rows of every realisation (columns of
    :data:`.scoring.METRIC_COLUMNS` plus ``realisation``); ``ranges``: the
    policy's ranges; ``constant``: metrics left out (they cannot rank).
    """
    import pandas as pd

    rows = rows[~rows["metric"].isin(list(constant))]
    if rows.empty:
        return rows
    every = _realisation_scores(rows, ranges, clip)
    out = aggregate(every, _KEYS, "value")
    out = out.merge(aggregate(every, _KEYS, "score", prefix="score_").rename(columns={"score_score": "score"}),
                    on=_KEYS)
    first = every.drop_duplicates(_KEYS).set_index(_KEYS)[["unit", "worst", "best"]]
    out = out.join(first, on=_KEYS)
    raw = every.groupby(_KEYS, sort=False)["raw_score"].mean().rename("raw_score")
    out = out.join(raw, on=_KEYS)
    # past an end by more than rounding (a mean at an end of a fitted range is exactly there)
    out["out_of_range"] = (out["raw_score"] < -1e-9) | (out["raw_score"] > 1 + 1e-9)
    out = out.drop(columns=["std", "score_std", "score_n"])
    # per metric: rank of the mean score, intervals from the score intervals
    for col in ("metric_rank", "metric_rank_best", "metric_rank_worst"):
        out[col] = 0
    for _, g in out.groupby(["demosaic", "luminance", "metric"], sort=False):
        r, b, w = rank_interval(g["raw_score"], g["score_ci_low"], g["score_ci_high"])
        out.loc[g.index, ["metric_rank", "metric_rank_best", "metric_rank_worst"]] = np.stack([r, b, w], 1)
    # per (cfa, demosaic, luminance): the mean score and its interval over realisations
    per = every.drop_duplicates(["cfa", "demosaic", "luminance", "realisation"])
    per_agg = aggregate(per, ["cfa", "demosaic", "luminance"], "mean_score", prefix="mean_score_")
    per_agg = per_agg.rename(columns={"mean_score_mean_score": "mean_score"}).drop(
        columns=["mean_score_std", "mean_score_n"])
    per_agg = per_agg.merge(per.groupby(["cfa", "demosaic", "luminance"])["n_metrics"].max().reset_index(),
                            on=["cfa", "demosaic", "luminance"])
    for col in ("demosaic_rank", "demosaic_rank_best", "demosaic_rank_worst"):
        per_agg[col] = 0
    for _, g in per_agg.groupby(["demosaic", "luminance"], sort=False):
        r, b, w = rank_interval(g["mean_score"], g["mean_score_ci_low"], g["mean_score_ci_high"])
        per_agg.loc[g.index, ["demosaic_rank", "demosaic_rank_best", "demosaic_rank_worst"]] = np.stack([r, b, w], 1)
    tot = every.drop_duplicates(["cfa", "luminance", "realisation"])
    tot_agg = aggregate(tot, ["cfa", "luminance"], "total_score", prefix="total_score_")
    tot_agg = tot_agg.rename(columns={"total_score_total_score": "total_score"}).drop(
        columns=["total_score_std", "total_score_n"])
    for col in ("total_rank", "total_rank_best", "total_rank_worst"):
        tot_agg[col] = 0
    for _, g in tot_agg.groupby("luminance", sort=False):
        r, b, w = rank_interval(g["total_score"], g["total_score_ci_low"], g["total_score_ci_high"])
        tot_agg.loc[g.index, ["total_rank", "total_rank_best", "total_rank_worst"]] = np.stack([r, b, w], 1)
    out = out.merge(per_agg, on=["cfa", "demosaic", "luminance"], how="left")
    out = out.merge(tot_agg, on=["cfa", "luminance"], how="left")
    ints = [c for c in out.columns if c.endswith(("_rank", "_rank_best", "_rank_worst")) or c in ("n", "n_metrics")]
    out[ints] = out[ints].astype(int)
    return pd.DataFrame(out)


def policy_summary(means, paper: dict, ideal: dict, clip: bool = True, realisations=None):
    """For every policy: per metric how many scores are clipped and whether
    the metric is constant, and each CFA's overall rank (per luminance).

    With ``realisations`` (the scored rows per noise realisation) the totals
    are scored per realisation and averaged, as scores.csv's are, so the
    study's own policy gives scores.csv's totals and ranks exactly; without
    them, the mean values are scored.

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
            cols = ["scene", "cfa", "demosaic", "luminance", "metric", "value", "unit", "realisation"]
            s = score_realisations(realisations[cols], ranges, clip=clip, constant=constant)
        else:
            s = score(kept, ranges, clip=clip)
        for _, r in s.drop_duplicates(["cfa", "luminance"]).iterrows():
            rank_rows.append((policy, r["cfa"], float(r["luminance"]), float(r["total_score"]), int(r["total_rank"])))
    return (pd.DataFrame(clip_rows, columns=["policy", "metric", "scores", "clipped", "constant"]),
            pd.DataFrame(rank_rows, columns=["policy", "cfa", "luminance", "total_score", "total_rank"]))
