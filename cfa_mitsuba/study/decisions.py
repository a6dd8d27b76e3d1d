"""decisions.csv: which CFA to pick for each aspect, and how sure that is.

One row per aspect (``aspect``, ``cfas``, ``verdict``, ``detail``):

- ``colour``: the mean score of ΔE00 (Macbeth) and S-CIELAB (puppy);
- ``sharpness``: MTF50 (slanted edge);
- ``moire``: the moire starting point (chirp);
- ``low light``: S-CIELAB and SSIM at the lowest swept luminance below
  the base one at which the CFAs' scores differ (scored with the study's
  ranges; lower levels, where every CFA clips to the range's bound, are
  passed over and named in the detail);
- ``overall``: the total score of Table 3 (scores.csv's ``total_rank``).

Each aspect's score of a CFA is the mean, over the study's demosaics and
the aspect's metrics, of its scores, computed per realisation (render seed
x sensor seed); its 95 % interval is :func:`.intervals.nested_interval`'s and
its rank interval comes from paired comparisons: the per-realisation score
differences of two CFAs under the same render and sensor seeds
(:func:`.intervals.paired_rank_interval`).  The rule, the same
everywhere the project names a best CFA: ``cfas`` lists every CFA whose
rank interval contains 1; ``verdict`` is ``winner`` only when that is one
CFA with rank interval exactly 1 (its interval lies wholly above every
other's), else ``tie``; ``unmeasured`` when the study has no value for the
aspect (no luminance below the base: no low-light row).
"""

from __future__ import annotations

__all__ = ["ASPECTS", "VERDICTS", "decide", "decisions_table", "write_decisions"]

from pathlib import Path

import numpy as np

from .intervals import nested_interval, rank_interval

#: (aspect, the scored metrics it averages); ``low light`` reads the sweep's lowest luminance.
ASPECTS = (("colour", ("delta-e", "scielab")), ("sharpness", ("mtf",)), ("moire", ("moire",)),
           ("low light", ("scielab", "ssim")), ("overall", ()))
VERDICTS = ("winner", "tie", "unmeasured")
COLUMNS = ["aspect", "cfas", "verdict", "detail"]


def decide(cfas, scores, lows, highs, ranks=None) -> tuple[list[str], str, str]:
    """(the CFAs whose rank interval contains 1, verdict, plain-words detail).

    ``scores``, ``lows``, ``highs``: each CFA's score (higher is better) and
    its 95 % interval; ``ranks``: (best ranks, worst ranks) from paired
    comparisons (:func:`.ranking.paired_ranks`); without them the rank
    intervals follow from the marginal intervals (:func:`.intervals.rank_interval`).

    >>> decide(["a", "b", "c"], [0.9, 0.85, 0.5], [0.88, 0.80, 0.45], [0.92, 0.89, 0.55])[:2]
    (['a', 'b'], 'tie')
    >>> decide(["a", "b"], [0.9, 0.5], [0.88, 0.45], [0.92, 0.55])[:2]
    (['a'], 'winner')
    """
    cfas = list(cfas)
    s, lo, hi = (np.asarray(x, dtype=float) for x in (scores, lows, highs))
    if ranks is None:
        _, best, worst = rank_interval(s, lo, hi)
    else:
        best, worst = (np.asarray(x, dtype=int) for x in ranks)
    order = [i for i in np.argsort(-s, kind="stable") if best[i] == 1]
    top = [cfas[i] for i in order]
    verdict = "winner" if len(order) == 1 and worst[order[0]] == 1 else "tie"

    def one(i):
        rank = f"rank {best[i]}" if best[i] == worst[i] else f"ranks {best[i]}-{worst[i]}"
        return f"{cfas[i]} {s[i]:.3f} [{lo[i]:.3f}, {hi[i]:.3f}] ({rank})"

    if verdict == "winner":
        detail = (f"{one(order[0])}: its score lies above every other CFA's (paired differences, 95 % intervals "
                  "above 0)" if ranks is not None else f"{one(order[0])}: its interval lies above every other CFA's")
    else:
        detail = f"{len(order)} CFA(s) can rank first within their 95 % intervals: " + "; ".join(one(i) for i in order)
    return top, verdict, detail


def _aspect_rows(aspect, metrics, scored_every, lowlight_every):
    from .ranking import paired_ranks, realisation_renders

    if aspect == "low light":
        rows = lowlight_every
    else:
        rows = scored_every[scored_every["metric"].isin(metrics)]
    if rows is None or rows.empty:
        return None
    renders = realisation_renders(rows)
    per = rows.groupby(["cfa", "realisation"], sort=False)["score"].mean().reset_index()
    cfas, s, lo, hi = [], [], [], []
    for cfa, g in per.groupby("cfa", sort=False):
        mean, low, high, _, _ = nested_interval(g["score"], g["realisation"].map(renders).fillna(0) if renders else None)
        cfas.append(cfa), s.append(mean), lo.append(low), hi.append(high)
    items, _, best, worst = paired_ranks(per, "cfa", "score", renders)
    pos = [items.index(c) for c in cfas]
    return cfas, s, lo, hi, (best[pos], worst[pos])


def decisions_table(scores, scored_every, lowlight_every=None, lowlight_luminance=None, lowlight_skipped=()):
    """decisions.csv as a DataFrame.

    ``scores``: scores.csv; ``scored_every``: the scored rows per
    realisation (``cfa``, ``metric``, ``realisation``, ``score``), at the
    base luminance; ``lowlight_every``: the same for the low-light rows
    (None: the study has none) at ``lowlight_luminance`` cd/m^2;
    ``lowlight_skipped``: the lower levels passed over, where every CFA
    scored the same bound.
    """
    import pandas as pd

    out = []
    for aspect, metrics in ASPECTS:
        if aspect == "overall":
            if scores is None or scores.empty:
                out.append((aspect, "", "unmeasured", "no scores"))
                continue
            tot = scores.drop_duplicates("cfa")
            cfas, verdict, detail = decide(tot["cfa"], tot["total_score"], tot["total_score_ci_low"],
                                           tot["total_score_ci_high"],
                                           ranks=(tot["total_rank_best"], tot["total_rank_worst"]))
            # the rank intervals of scores.csv are the same computation: keep them the one source
            top = tot[tot["total_rank_best"] == 1].sort_values("total_score", ascending=False)["cfa"].tolist()
            assert sorted(top) == sorted(cfas), (top, cfas)
            out.append((aspect, " ".join(top), verdict, "Table 3's total score: " + detail))
            continue
        got = _aspect_rows(aspect, metrics, scored_every, lowlight_every)
        if got is None:
            why = ("no luminance below the base one" if aspect == "low light"
                   else f"the study measured none of {', '.join(metrics)}")
            out.append((aspect, "", "unmeasured", why))
            continue
        cfas, verdict, detail = decide(*got)
        what = {"colour": "mean score of dE00 and S-CIELAB", "sharpness": "MTF50 score",
                "moire": "moire starting point score",
                "low light": f"mean score of S-CIELAB and SSIM at {lowlight_luminance:g} cd/m^2"
                + (f" (the lowest level at which the CFAs' scores differ; at "
                   f"{', '.join(f'{v:g}' for v in lowlight_skipped)} cd/m^2 every CFA scores the range's bound)"
                   if lowlight_skipped else "")
                if lowlight_luminance is not None else ""}[aspect]
        out.append((aspect, " ".join(cfas), verdict, f"{what}, over the demosaics: {detail}"))
    return pd.DataFrame(out, columns=COLUMNS)


def _lowlight(realisations, ranges, clip, scored_metrics_):
    """(per-realisation scored rows at the low-light level, that luminance,
    the lower levels passed over) or (None, None, ()).

    The level is the lowest swept luminance below the base one at which the
    CFAs' scores differ: below the range the study scores against, every
    CFA's S-CIELAB and SSIM clip to the same bound (0), a tie that says
    nothing about the CFAs, so such levels are passed over and named."""
    from .scoring import normalise

    none = None, None, ()
    if realisations is None or realisations.empty or "base" not in realisations:
        return none
    base = realisations[realisations["base"].astype(bool)]
    if base.empty:
        return none
    base_lum = float(base["luminance"].astype(float).min())
    metrics = [m for m in ("scielab", "ssim") if m in ranges and m in scored_metrics_]
    below = realisations[realisations["metric"].isin(metrics)
                         & (realisations["luminance"].astype(float) < base_lum)]
    if below.empty:
        return none
    cols = ["scene", "cfa", "demosaic", "luminance", "metric", "value", "unit", "realisation"]
    cols += ["render_seed"] if "render_seed" in below.columns else []
    import pandas as pd

    def scored(lum):
        low = below[below["luminance"].astype(float) == lum]
        # only the other axes at their base values: a sweep over luminance alone
        low = low.drop_duplicates(["scene", "cfa", "demosaic", "metric", "realisation"])
        parts = [normalise(g[cols].drop(columns="realisation"), ranges, clip=clip).assign(realisation=r)
                 for r, g in low.groupby("realisation", sort=True)]
        return pd.concat(parts, ignore_index=True)

    levels = sorted(below["luminance"].astype(float).unique())
    for i, lum in enumerate(levels):
        rows = scored(lum)
        per_cfa = rows.groupby("cfa")["score"].mean()
        if per_cfa.max() - per_cfa.min() > 1e-12:
            return rows, lum, tuple(levels[:i])
    return scored(levels[0]), levels[0], ()  # no level tells the CFAs apart: the lowest, a tie


def write_decisions(out_dir: Path, realisations, scored_real, scores, ranges, *, clip: bool, constant=()) -> None:
    """Write ``out_dir/decisions.csv`` (atomically) from a study's rows."""
    from ..io import atomic_output
    from ..metrics import scored_metrics
    from .ranking import _realisation_scores

    cols = ["scene", "cfa", "demosaic", "luminance", "metric", "value", "unit", "realisation"]
    cols += ["render_seed"] if "render_seed" in scored_real.columns else []
    kept = scored_real[~scored_real["metric"].isin(list(constant))]
    every = _realisation_scores(kept[cols], ranges, clip) if len(kept) else kept
    low, lum, skipped = _lowlight(realisations, ranges, clip, set(scored_metrics()) - set(constant))
    table = decisions_table(scores, every, low, lum, skipped)
    with atomic_output(Path(out_dir) / "decisions.csv") as tmp:
        table.to_csv(tmp, index=False)
