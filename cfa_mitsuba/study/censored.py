"""How a bound is scored: the rule for censored values (an MSP with no moire
up to the chirp's top frequency).

A censored value is not a measurement: the camera showed no moire up to the
chirp's top frequency, so its MSP is *at least* that frequency, which is
also the ideal sensor's value.  Scoring the bound as the value would give
the camera the ideal's score 1 for a number the chart could not measure.
The rule: a censored value is scored as the midpoint between the best
uncensored value of the same metric in the study (at the same luminance)
and the range's best end.  It so scores above every measured value, as a
bound at the top must, and below the ideal's 1, by half the gap the chart
cannot resolve.  When no value of the metric is uncensored the metric is
left as it is (every CFA then has the same bound, the metric cannot rank
them, and the range policy drops it as constant).  scores.csv keeps the
measured bound in ``value`` (with ``censored``); only ``score`` follows the
rule.
"""

from __future__ import annotations

__all__ = ["values_for_scoring"]

import numpy as np


def values_for_scoring(rows, ranges: dict):
    """A copy of ``rows`` (scene, cfa, demosaic, luminance, metric, value,
    censored, ...) whose censored values are replaced by the value the rule
    scores them at; rows without a ``censored`` column are returned as they are.

    >>> import pandas as pd
    >>> from cfa_mitsuba.study.scoring import ScoreRange
    >>> rows = pd.DataFrame({"metric": ["moire"] * 3, "luminance": [100] * 3, "value": [4.0, 6.0, 24.0],
    ...                      "censored": [False, False, True]})
    >>> values_for_scoring(rows, {"moire": ScoreRange(2.0, 24.0, ())})["value"].tolist()
    [4.0, 6.0, 15.0]
    """
    if "censored" not in rows.columns:
        return rows
    out = rows.copy()
    bound = out["censored"].fillna(False).astype(str).str.lower().isin(("true", "1"))
    if not bound.any():
        return out
    for (metric, lum), g in out[bound].groupby(["metric", "luminance"], sort=False):
        r = ranges.get(metric)
        measured = out[(out["metric"] == metric) & (out["luminance"] == lum) & ~bound]["value"].astype(float)
        if r is None or measured.empty:
            continue
        best_end = float(r.best)
        higher = best_end > float(r.worst)
        best_measured = float(measured.max() if higher else measured.min())
        out.loc[g.index, "value"] = 0.5 * (best_measured + best_end) if np.isfinite(best_measured) else best_end
    return out
