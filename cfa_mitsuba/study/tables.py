"""A study's tables, from the rows its tasks returned.

    metrics_realisations.csv   one row per realisation (``realisation`` 0, 1, ...; its
                               ``render_seed``)
    metrics.csv                one row per (scene, cfa, demosaic, condition, metric):
                               the mean over realisations, ``ci_low``, ``ci_high`` (95 %,
                               render and sensor noise: study/intervals.py, the render
                               component pooled over a scene, level and metric), ``n``,
                               ``censored`` and ``censored_count`` (bounds: study/censored.py),
                               ``render_seeds`` (the renders it spans) and
                               ``sensor_half_width`` (the half width from sensor noise alone)
    ideal.csv                  the ideal sensor measured against itself (the anchor of
                               the ``ideal`` range policy)
    scores.csv                 the scored rows under the study's range policy, with
                               score and rank intervals (:mod:`.ranking`)
    decisions.csv              per aspect the CFA(s) that can rank first, ``winner`` or
                               ``tie`` (:mod:`.decisions`)
    policies.csv               for each range policy: per metric the scores clipped and
                               whether it is constant across the CFAs, and each CFA's rank
"""

from __future__ import annotations

__all__ = ["metric_columns", "order_rows", "scored_rows", "write_tables", "key_columns"]

from pathlib import Path

from ..io import atomic_output
from ..metrics import scored_metrics
from .axes import AXES

#: What each evaluation's capture was (issue 22): its exposure time (s), the
#: exposure program's analogue and digital gains, and the fraction of its
#: pixels clipped at the full well or the ADC's top code (the mean over the
#: realisations in metrics.csv); in the field's units (issue 50), the
#: scene's illuminance (lux: pi x its white's luminance) and the
#: sensor-plane exposure (lux s: the pixels' mean illuminance x the
#: exposure time), sensor/photometry.py.
CAPTURE_COLUMNS = ("exposure_s", "analog_gain", "digital_gain", "clipped_fraction", "scene_illuminance_lux",
                   "sensor_exposure_lux_s")
#: SNRs (records with ``decibels``) in dB beside the ratio: 20 log10 of the
#: value and of its interval's ends (empty for other metrics).
DB_COLUMNS = ("value_db", "ci_low_db", "ci_high_db")


#: The columns that identify a value (one per condition axis included).
def key_columns() -> list[str]:
    """The columns that identify a value: scene, CFA, demosaic, one per
    registered axis, ``base``, the metric."""
    return ["scene", "cfa", "demosaic", *AXES, "base", "metric"]


def metric_columns(*, realisations: bool = False) -> list[str]:
    """metrics.csv's columns: the keys, one per condition axis, ``base``,
    the metric, its ``value`` with ``ci_low``, ``ci_high``, ``n``,
    ``unit``, ``censored`` (the value is a bound: True when every
    realisation's is) and ``censored_count`` (how many realisations are
    bounds; with some, ``value`` is their Kaplan-Meier median:
    study/censored.py), the capture columns, ``render_seeds`` (how many
    renders its realisations span: 1 for a chart) and ``sensor_half_width``
    (the 95 % half width from sensor noise alone: how much of the interval
    is not render noise); per realisation: ``realisation``, ``value``,
    ``unit``, ``censored``, the capture columns and ``render_seed``."""
    keys = key_columns()
    if realisations:
        return [*keys[:-1], "realisation", "metric", "value", "unit", "censored", *CAPTURE_COLUMNS, "render_seed"]
    return [*keys, "value", "ci_low", "ci_high", "n", "unit", "censored", "censored_count", *CAPTURE_COLUMNS,
            "render_seeds", "sensor_half_width", *DB_COLUMNS]


#: The key columns a value's render component is not pooled over: the
#: values of one scene, condition and metric share it (study/variance.py),
#: whatever the CFA, its spectra set and the demosaic.
NOT_POOLED = ("cfa", "demosaic", "spectra")


def order_rows(rows, config_order: dict, columns: list[str] | None = None):
    """The rows as a table in the study's order: scene, condition (the
    plan's order: luminance ascending, then as named), CFA, demosaic,
    (realisation), metric."""
    import pandas as pd

    df = pd.DataFrame(rows, columns=columns or metric_columns(realisations=True))
    if df.empty:
        return df
    keys = _condition_keys(df)
    first = {k: i for i, k in reversed(list(enumerate(keys)))}  # rows come in the plan's order
    df["_cond"] = [first[k] for k in keys]
    for col in ("scene", "cfa", "demosaic", "metric"):
        order = config_order.get(col)
        if order:
            extra = [v for v in df[col].unique() if v not in order]
            df[col] = pd.Categorical(df[col], categories=list(order) + sorted(extra), ordered=True)
    by = ["scene", "luminance", "_cond", "cfa", "demosaic", "metric"]
    if "realisation" in df.columns:
        by.insert(-1, "realisation")
    df = df.sort_values(by, kind="stable")
    for col in ("scene", "cfa", "demosaic", "metric"):
        df[col] = df[col].astype(str)
    return df.drop(columns="_cond").reset_index(drop=True)


def _condition_keys(df) -> list[tuple]:
    return [tuple(str(v) for v in row) for row in df[list(AXES)[1:]].itertuples(index=False)]


def mean_table(realisations):
    """metrics.csv from the per-realisation table (the order kept)."""
    import pandas as pd

    from .intervals import aggregate, sensor_half_width

    if realisations.empty:
        return pd.DataFrame(columns=metric_columns())
    keyed = realisations.assign(exposure=realisations["exposure"].astype(str),
                                f_number=realisations["f_number"].astype(float))
    keys = key_columns()
    if "render_seed" not in keyed.columns or keyed["render_seed"].isna().all():  # a table written before render seeds
        keyed = keyed.assign(render_seed=0)
    keyed = keyed.assign(render_seed=keyed["render_seed"].fillna(0).astype(int))
    agg = aggregate(keyed, keys, "value", groups="render_seed",
                    pool_by=[k for k in keys if k not in NOT_POOLED]).drop(columns=["std"])
    spread = keyed.groupby(keys, sort=False, dropna=False).apply(
        lambda g: pd.Series({"render_seeds": int(g["render_seed"].nunique()),
                             "sensor_half_width": sensor_half_width(g["value"], g["render_seed"])}),
        include_groups=False).reset_index()
    agg = agg.merge(spread, on=keys, how="left")
    unit = keyed.drop_duplicates(keys)[keys + ["unit"]]
    out = agg.merge(unit, on=keys, how="left")
    out = _censored_values(out, keyed, keys)
    have = [c for c in CAPTURE_COLUMNS if c in keyed.columns]
    if have:
        caps = keyed[keys + have].copy()
        caps[have] = caps[have].apply(pd.to_numeric, errors="coerce")
        out = out.merge(caps.groupby(keys, sort=False, dropna=False)[have].mean().reset_index(), on=keys, how="left")
    return _with_decibels(out).reindex(columns=metric_columns())


def _with_decibels(table):
    """:data:`DB_COLUMNS` filled for the metrics whose records are SNRs
    (amplitude ratios: 20 log10; a ratio <= 0 has no dB value)."""
    import numpy as np

    from ..metrics import METRICS

    snr = table["metric"].map(lambda m: bool(getattr(METRICS.get(m), "decibels", False))).astype(bool)
    for src, dst in zip(("value", "ci_low", "ci_high"), DB_COLUMNS):
        v = np.asarray(table[src], dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            db = np.where(snr & (v > 0), 20.0 * np.log10(np.where(v > 0, v, 1.0)), np.nan)
        table[dst] = db
    return table


def _censored_values(out, keyed, keys):
    """``censored`` and ``censored_count`` for every value, and the values
    with bounds among their realisations summarised by the rule of
    study/censored.py (the Kaplan-Meier median and its interval)."""
    import pandas as pd

    from .censored import is_bound, summarise

    keyed = keyed.assign(censored=is_bound(keyed["censored"]) if "censored" in keyed.columns else False)
    counts = keyed.groupby(keys, sort=False, dropna=False)["censored"].sum().astype(int).rename("censored_count")
    out = out.merge(counts.reset_index(), on=keys, how="left")
    out["censored"] = False
    mixed = out.index[out["censored_count"] > 0]
    if len(mixed):
        some = keyed[keyed["censored"]].drop_duplicates(keys)[keys]
        for _, g in keyed.merge(some, on=keys).groupby(keys, sort=False, dropna=False):
            got = summarise(g["value"].to_numpy(float), g["censored"].to_numpy(bool))
            sel = pd.Series(True, index=out.index)
            for k in keys:
                sel &= (out[k] == g[k].iloc[0]) | (out[k].isna() & pd.isna(g[k].iloc[0]))
            for col, v in got.items():
                out.loc[sel, col] = v
    out["censored"] = out["censored"].astype(bool)
    return out


def scored_rows(metrics, builtin_scenes):
    """The rows that enter the scores: the scored metrics at the study's own
    (base) conditions, each from one scene (the built-in scene that feeds
    it, else the first other scene)."""
    import pandas as pd

    df = metrics[metrics["metric"].isin(scored_metrics()) & metrics["base"].astype(bool)]
    keep = []
    for name, group in df.groupby("metric", sort=False):
        scenes = list(dict.fromkeys(group["scene"]))
        pick = next((s for s in scenes if s in builtin_scenes), scenes[0])
        keep.append(group[group["scene"] == pick])
    return pd.concat(keep).reset_index(drop=True) if keep else df


def _ideal_values(ideal, scored) -> dict:
    """{metric: the ideal sensor's value} on the scene and luminance each
    scored metric is taken from."""
    out = {}
    if ideal is None or ideal.empty:
        return out
    base = ideal[ideal["base"].astype(str).str.lower().isin(("true", "1"))]
    for metric, g in scored.groupby("metric", sort=False):
        sel = base[(base["metric"] == metric) & (base["scene"] == g["scene"].iloc[0])
                   & base["luminance"].isin(g["luminance"].unique())]
        if len(sel):
            out[metric] = float(sel["value"].mean())
    return out


def _measured(scores, means):
    """scores.csv with metrics.csv's values and intervals in ``value``, ``ci_low``, ``ci_high`` and its
    ``censored`` and ``censored_count`` (the scores may have been computed from a bound's scoring value)."""
    if scores.empty:
        return scores
    keys = ["scene", "cfa", "demosaic", "luminance", "metric"]
    m = means[keys + ["value", "ci_low", "ci_high", "censored", "censored_count"]].copy()
    m["luminance"] = m["luminance"].astype(float)
    out = scores.drop(columns=["value", "ci_low", "ci_high"]).assign(luminance=scores["luminance"].astype(float))
    out = out.merge(m, on=keys, how="left")
    cols = list(scores.columns)
    at = cols.index("unit") + 1 if "unit" in cols else len(cols)
    cols[at:at] = ["censored", "censored_count"]
    return out[cols]


def write_tables(out_dir: Path, realisations, ideal, *, paper_ranges: dict, overrides: dict, policy: str,
                 clip: bool, builtin_scenes) -> tuple:
    """Write every table of the module docstring atomically; returns
    (metrics, scores, ranges, constant metrics)."""
    import pandas as pd

    from .alternatives import ScoringSetup, score_alternatives
    from .censored import values_for_scoring
    from .ranking import policy_summary, score_realisations

    def save(name, df):
        with atomic_output(out_dir / name) as tmp:
            df.to_csv(tmp, index=False, float_format="%.10g")

    save("metrics_realisations.csv", realisations)
    metrics = mean_table(realisations)
    save("metrics.csv", metrics)
    if ideal is not None:
        save("ideal.csv", ideal)
    scored_real = scored_rows(realisations, builtin_scenes)
    scored_mean = scored_rows(metrics, builtin_scenes)
    ranges, constant, scores, alternatives = dict(paper_ranges), [], scored_mean.iloc[0:0], []
    if len(scored_real):
        setup = ScoringSetup(paper_ranges, _ideal_values(ideal, scored_mean), policy, dict(overrides), clip)
        ranges, constant = setup.ranges(policy, scored_mean)
        every = setup.every(scored_real, ranges, constant)  # a bound scores by the stated rule (censored.py)
        per_realisation = score_realisations(None, ranges, clip=clip, constant=constant, every=every)
        scores = _measured(per_realisation, scored_mean)
        clipping, ranks = policy_summary(scored_mean, paper_ranges, setup.ideal, clip,
                                         realisations=values_for_scoring(scored_real, ranges),
                                         scored=(ranges, constant, per_realisation))
        clipping["scope"] = "clipping"
        ranks["scope"] = "rank"
        save("policies.csv", pd.concat([clipping, ranks], ignore_index=True))
        alternatives = score_alternatives(setup, scored_real, scored_mean, own=(ranges, constant, every))
    save("scores.csv", scores)
    if len(scored_real) and len(scores):
        from .decisions import write_decisions

        write_decisions(out_dir, realisations, alternatives, ranges)
    return metrics, scores, ranges, constant
