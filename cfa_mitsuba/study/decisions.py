"""decisions.csv: which CFA to pick, how sure that is, and what the answer
depends on.

Rows (``aspect``):

- ``colour`` (the mean score of ΔE00 on the Macbeth chart and S-CIELAB on
  the puppy), ``sharpness`` (MTF50), ``moire`` (the moire starting point),
  ``overall`` (Table 3's total: every scored metric) and ``with <demosaic>``
  (Table 3's row of that demosaic), each at the base luminance, on the
  scores of every realisation (render seed x sensor seed) averaged over the
  aspect's metrics and the demosaics;
- ``low light`` (study/lowlight.py): SNR10, the scene luminance at which
  YSNR reaches 10 (lower is better), and ``low light: <metric>``: each
  swept scored metric's own values at the lowest swept luminance below the
  base one.  Low light is decided on physics, never on scores clipped to a
  range's bound.  A study that sweeps a processing setting (``denoise``)
  gets the low-light rows again for each setting,
  ``low light with denoise nl-means`` (study/isp_settings.py).

The rule, the same everywhere the project names a best CFA (the report's
panel and cards, Table 3, the paper comparison's "best" claims):

1. rank intervals from paired comparisons (:func:`.ranking.paired_ranks`);
   ``cfas`` lists every CFA whose rank interval contains 1;
2. ``winner`` only when that is one CFA with rank interval exactly 1 *and*
   its lead over the next CFA is at least the practical difference: the
   smallest difference that matters to a user, from the metric records
   (``practical_difference``); for a mean score of M metrics it is the change
   a practical difference on one of them makes to the mean (each metric's in
   score units, its practical difference over its range's width, averaged
   over the metrics and divided by M); a separated lead below it is
   ``equivalent`` (``cfas``: the leader and every CFA within the practical
   difference of it);
3. ``tie`` when several CFAs can rank first; ``clipped`` when more than
   :data:`CLIPPED_LIMIT` of the scores used (each CFA, demosaic and metric's
   mean over the realisations) lie outside their range and are clipped to
   its bound (the range no longer spans the values: nothing is decided
   from them);
   ``unmeasured`` when the study has no value for the row.

Each row is recomputed under the alternatives a reader could reasonably
choose (study/alternatives.py: each other range policy, each other
convention for censored values, each metric left out in turn; for low
light, each swept metric's values at each level): ``robust`` is true when
the answer (the winner, or no single winner) is the same under every one,
and ``depends_on`` lists those that change it (``without moire``,
``censored at best measured``, ``ranges: paper``, ``scielab at 1 cd/m^2``),
the detail saying what each gives.  ``luminance`` is the level decided at,
``quantity`` what was compared and ``clipped_share`` the share of the
scores at that level clipped to a range bound under the study's ranges.
"""

from __future__ import annotations

__all__ = ["ASPECTS", "VERDICTS", "COLUMNS", "CLIPPED_LIMIT", "Outcome", "decide", "robustness",
           "practical_threshold", "score_outcome", "decisions_table", "write_decisions"]

from pathlib import Path

import numpy as np

from .decision_rule import Outcome, decide, robustness
from .intervals import aggregate

#: (aspect, the scored metrics it averages: () every one), decided on scores at the base luminance.
ASPECTS = (("colour", ("delta-e", "scielab")), ("sharpness", ("mtf",)), ("moire", ("moire",)), ("overall", ()))
VERDICTS = ("winner", "equivalent", "tie", "clipped", "unmeasured")
COLUMNS = ["aspect", "cfas", "verdict", "robust", "depends_on", "luminance", "quantity", "clipped_share", "detail"]
#: The largest share of clipped scores a decision on scores accepts.
CLIPPED_LIMIT = 0.10


def practical_threshold(rows, ranges: dict) -> float:
    """The practical difference of a mean score of ``rows`` (per-realisation
    scored rows: metric, value, unit): what a practical difference on one of
    its M metrics makes to the mean, on average over the metrics: the mean
    of each one's practical difference (its record's, at the median value
    for a relative one) over its range's width (each at most 1), divided by
    M; a metric whose record gives none counts 0.

    >>> import pandas as pd
    >>> from cfa_mitsuba.study.scoring import ScoreRange
    >>> rows = pd.DataFrame({"metric": ["delta-e", "ssim"], "value": [2.0, 0.8], "unit": ["dE00", ""]})
    >>> round(practical_threshold(rows, {"delta-e": ScoreRange(4.0, 0.0), "ssim": ScoreRange(0.5, 1.0)}), 4)
    0.075
    """
    from ..metrics import METRICS

    out = []
    for metric, g in rows.groupby("metric", sort=False):
        rec, r = METRICS.get(metric), ranges.get(metric)
        if rec is None or r is None:
            continue
        unit = next((u for u in g["unit"] if isinstance(u, str)), "") if "unit" in g.columns else rec.unit
        pd_ = rec.practical(unit, float(np.nanmedian(g["value"].astype(float))))
        out.append(0.0 if pd_ is None else min(1.0, pd_ / abs(float(r.best) - float(r.worst))))
    return float(np.mean(out)) / len(out) if out else 0.0


def _clipped_share(rows) -> float:
    """The share of the scores used (each CFA, demosaic and metric: the mean over its realisations,
    scores.csv's ``raw_score``) that eq. 8 puts outside [0, 1], where clipping acts on the value
    itself: a range that does not span it.  A realisation of the worst CFA a hair below the worst
    mean is noise about a value inside the range, not a value outside it."""
    if rows.empty:
        return 0.0
    raw = rows.groupby(["cfa", "demosaic", "metric"], sort=False)["raw_score"].mean().to_numpy(dtype=float)
    return float(np.mean((raw < -1e-9) | (raw > 1 + 1e-9)))


def score_outcome(every, ranges: dict, metrics=(), demosaic: str | None = None) -> Outcome | None:
    """The decision on the mean score of ``metrics`` (() every one in
    ``every``) over the demosaics (or ``demosaic``'s alone), from
    per-realisation scored rows; None when there are none."""
    from .ranking import paired_ranks, realisation_renders

    rows = every if not metrics else every[every["metric"].isin(list(metrics))]
    if demosaic is not None:
        rows = rows[rows["demosaic"] == demosaic]
    if rows is None or rows.empty:
        return None
    renders = realisation_renders(rows)
    per = (rows.groupby(["cfa", "demosaic", "realisation"], sort=False)["score"].mean()
           .groupby(["cfa", "realisation"], sort=False).mean().reset_index())
    per["_render"] = per["realisation"].map(renders).fillna(0).astype(int) if renders else 0
    agg = aggregate(per, ["cfa"], "score", groups="_render", pool_by=[])
    items, _, best, worst = paired_ranks(per, "cfa", "score", renders)
    pos = [items.index(c) for c in agg["cfa"]]
    top, verdict, detail = decide(agg["cfa"], agg["score"], agg["ci_low"], agg["ci_high"], (best[pos], worst[pos]),
                                  practical=practical_threshold(rows, ranges))
    share = _clipped_share(rows)
    if share > CLIPPED_LIMIT:
        verdict = "clipped"
        detail = (f"{100 * share:.0f} % of the scores used are clipped to a range bound (more than "
                  f"{100 * CLIPPED_LIMIT:.0f} %): the ranges do not span these values, so no CFA is named; " + detail)
    return Outcome(top, verdict, detail, share)


def _score_rows(alternatives, base_luminance):
    """decisions.csv's rows decided on scores (every aspect, every demosaic)."""
    own = alternatives[0]
    every = own.every
    demosaics = list(dict.fromkeys(every["demosaic"])) if len(every) else []
    specs = [(aspect, metrics, None) for aspect, metrics in ASPECTS]
    specs += [(f"with {d}", (), d) for d in demosaics]
    out = []
    for aspect, metrics, dem in specs:
        base = score_outcome(every, own.ranges, metrics, dem) if len(every) else None
        what = _quantity(aspect, metrics)
        if base is None:
            missing = ", ".join(metrics) if metrics else "no scored metric"
            out.append((aspect, "", "unmeasured", False, "", base_luminance, what, np.nan,
                        f"the study measured none of {missing}"))
            continue
        used = list(dict.fromkeys(every[every["metric"].isin(list(metrics))]["metric"] if metrics
                                  else every["metric"]))
        others = [(alt.label, score_outcome(alt.every, alt.ranges, metrics, dem)) for alt in alternatives[1:]]
        if len(used) > 1:
            others += [(f"without {m}", score_outcome(every, own.ranges, [x for x in used if x != m], dem))
                       for m in used]
        robust, depends, words = robustness(base, others)
        out.append((aspect, " ".join(base.cfas), base.verdict, robust, depends, base_luminance, what,
                    round(base.clipped_share, 4), f"{what}: {base.detail}.{words}"))
    return out


def _quantity(aspect: str, metrics) -> str:
    if aspect == "overall":
        return "total score (Table 3, mean over the demosaics of the mean of every scored metric)"
    if aspect.startswith("with "):
        return f"mean score of every scored metric with {aspect[5:]} (Table 3's row)"
    names = {"delta-e": "dE00", "scielab": "S-CIELAB", "mtf": "MTF50", "moire": "moire starting point"}
    return "mean score of " + " and ".join(names.get(m, m) for m in metrics) + ", over the demosaics"


def decisions_table(alternatives, realisations=None, base_luminance=None, ranges=None):
    """decisions.csv as a DataFrame.

    ``alternatives``: :func:`.alternatives.score_alternatives`' list (the
    study's own scoring first; empty: no scores); ``realisations``:
    metrics_realisations.csv (the low-light rows; None: none);
    ``ranges``: the study's ranges (the low-light levels' clipped share)."""
    import pandas as pd

    from .lowlight import lowlight_rows

    rows = _score_rows(alternatives, base_luminance) if alternatives else [
        (aspect, "", "unmeasured", False, "", base_luminance, _quantity(aspect, m), np.nan, "no scores")
        for aspect, m in ASPECTS]
    rows += lowlight_rows(realisations, ranges or {})
    if realisations is not None and len(realisations):
        from .isp_settings import isp_settings

        for setting in isp_settings(realisations):  # the same low-light rows with each other processing setting
            rows += lowlight_rows(realisations, ranges or {}, setting)
    return pd.DataFrame(rows, columns=COLUMNS)


def write_decisions(out_dir: Path, realisations, alternatives, ranges) -> None:
    """Write ``out_dir/decisions.csv`` (atomically) from a study's rows."""
    from ..io import atomic_output

    base = realisations[realisations["base"].astype(str).str.lower().isin(("true", "1"))] \
        if realisations is not None and "base" in realisations else None
    lum = float(base["luminance"].astype(float).min()) if base is not None and len(base) else None
    table = decisions_table(alternatives, realisations, lum, ranges)
    with atomic_output(Path(out_dir) / "decisions.csv") as tmp:
        table.to_csv(tmp, index=False)
