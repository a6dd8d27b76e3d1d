"""decisions.csv's low-light rows, decided on physics (issue 46).

Scores are the wrong quantity in low light: below the range a study scores
against, every CFA's S-CIELAB and SSIM clip to the same bound (the paper
study at 6 cd/m^2: 82 of 96 scores at 0), so a winner named on them is an
artefact of the range.  The rows here use the quantities themselves:

- ``low light``: SNR10 (study/snr.py), the scene luminance at which YSNR on
  the gray bar's mid-grey reaches 10, per realisation (each realisation's
  YSNR against light, crossed at 10), averaged over the demosaics; lower is
  better.  Its practical difference is one third of a stop (a factor
  2^(1/3)): ISO 12232:2019 states speeds in 1/3-stop steps, so a smaller
  difference does not change a camera's rated speed.  Alternatives: each
  swept scored metric's values at the lowest swept level below the base.
- ``low light: <metric>``: each swept scored metric (S-CIELAB, SSIM on the
  puppy in the paper study) on its own values at the lowest swept level
  below the base one, averaged over the demosaics, with the metric
  record's practical difference; alternatives: the same metric at each
  other level below the base.  ``clipped_share`` says how many of that
  level's scores the study's ranges clip (the reason values are used).

Every decision follows :func:`.decisions.decide`'s rule with paired rank
intervals over the realisations.  The rows are decided on the study's own
camera (every axis but luminance at its own value, :mod:`.isp_settings`);
for each other processing setting a study sweeps (``denoise =
'nl-means'``), the same rows again on that setting's rows, the aspect named
``low light with denoise nl-means``, ``low light: scielab with denoise
nl-means``.  The metrics decided at the low level are the swept ones with a
practical difference on their record (the scored metrics, and the texture
acutance a camera tuner reads against noise).
"""

from __future__ import annotations

__all__ = ["SNR10_PRACTICAL_STOPS", "snr10_per_realisation", "lowlight_rows"]

import numpy as np

#: SNR10's practical difference in stops (ISO 12232's 1/3-stop speed steps).
SNR10_PRACTICAL_STOPS = 1.0 / 3.0


def _base_level(realisations):
    base = realisations[realisations["base"].astype(str).str.lower().isin(("true", "1"))]
    return float(base["luminance"].astype(float).min()) if len(base) else None


def _first_condition(rows):
    """One row per (scene, cfa, demosaic, luminance, metric, realisation): the
    rows are one setting's already (:func:`lowlight_rows`); a study that
    reaches a level twice under the same values keeps the first."""
    return rows.drop_duplicates(["scene", "cfa", "demosaic", "luminance", "metric", "realisation"], keep="first")


def snr10_per_realisation(realisations):
    """(cfa, realisation, render_seed, snr10): each realisation's SNR10
    (cd/m^2) from its own YSNR against light, averaged over the demosaics
    (NaN where a realisation's curve does not cross 10 within the sweep)."""
    import pandas as pd

    from .snr import crossing

    y = realisations[realisations["metric"] == "ysnr"]
    if y.empty or y["luminance"].nunique() < 2:
        return pd.DataFrame(columns=["cfa", "realisation", "render_seed", "snr10"])
    y = _first_condition(y)
    rows = []
    for (cfa, dem, k), g in y.groupby(["cfa", "demosaic", "realisation"], sort=False):
        c = crossing(g["luminance"].astype(float), g["value"].astype(float))
        seed = int(g["render_seed"].max()) if "render_seed" in g else 0
        rows.append((cfa, dem, k, seed, np.nan if c is None else c))
    per = pd.DataFrame(rows, columns=["cfa", "demosaic", "realisation", "render_seed", "snr10"])
    return per.groupby(["cfa", "realisation"], sort=False).agg(
        render_seed=("render_seed", "max"), snr10=("snr10", lambda v: v.mean() if v.notna().all() else np.nan)
    ).reset_index()


def _decide_values(per, column: str, higher_is_better: bool, practical, decimals: int):
    """An :class:`.decisions.Outcome` from per-(cfa, realisation) values."""
    from .decision_rule import Outcome, decide
    from .intervals import aggregate
    from .ranking import paired_ranks

    per = per[np.isfinite(per[column].astype(float))]
    if per.empty:
        return None
    renders = dict(zip(per["realisation"], per["render_seed"].astype(int)))
    agg = aggregate(per, ["cfa"], column, groups="render_seed", pool_by=[])
    items, _, best, worst = paired_ranks(per, "cfa", column, renders, higher_is_better=higher_is_better)
    pos = [items.index(c) for c in agg["cfa"]]
    s = agg[column].to_numpy(float)
    lead = int(np.argmax(s) if higher_is_better else np.argmin(s))
    top, verdict, detail = decide(agg["cfa"], s, agg["ci_low"], agg["ci_high"], (best[pos], worst[pos]),
                                  practical=practical(s[lead]), higher_is_better=higher_is_better,
                                  decimals=decimals)
    return Outcome(top, verdict, detail, 0.0)


def _snr10_outcome(realisations):
    per = snr10_per_realisation(realisations)
    if per.empty or not np.isfinite(per["snr10"].astype(float)).any():
        return None, per
    factor = 2.0 ** SNR10_PRACTICAL_STOPS - 1.0
    return _decide_values(per, "snr10", False, lambda lead: factor * lead, 3), per


def _decided_metrics() -> list[str]:
    """The metrics decided at a low level: the scored ones and every other
    whose record gives a practical difference (the texture acutance)."""
    from ..metrics import METRICS

    return [n for n, r in METRICS.items() if r.scored or r.practical_difference]


def _metric_levels(realisations, base_lum):
    """{metric: [levels below the base, ascending]} of the swept decided metrics."""
    below = realisations[realisations["metric"].isin(_decided_metrics())
                         & (realisations["luminance"].astype(float) < base_lum)]
    return {m: sorted(g["luminance"].astype(float).unique()) for m, g in below.groupby("metric", sort=False)}


def _metric_outcome(realisations, metric: str, level: float):
    from ..metrics import get_metric

    rec = get_metric(metric)
    rows = _first_condition(realisations[(realisations["metric"] == metric)
                                         & (realisations["luminance"].astype(float) == level)])
    if rows.empty:
        return None, rows
    rows = rows.assign(value=rows["value"].astype(float),
                       render_seed=rows["render_seed"].fillna(0).astype(int) if "render_seed" in rows else 0)
    per = rows.groupby(["cfa", "realisation"], sort=False).agg(
        render_seed=("render_seed", "max"), value=("value", "mean")).reset_index()
    unit = next((u for u in rows["unit"] if isinstance(u, str)), "")
    typical = float(np.nanmedian(rows["value"]))
    pd_ = rec.practical(unit, typical) or 0.0
    return _decide_values(per, "value", rec.higher_is_better, lambda lead: pd_, rec.decimals + 1), rows


def _clipped_at(rows, ranges, metric) -> float:
    """The share of the level's scores (each CFA and demosaic's mean value) the study's range clips."""
    r = ranges.get(metric)
    if r is None or rows is None or rows.empty:
        return float("nan")
    means = rows.groupby(["cfa", "demosaic"], sort=False)["value"].mean().to_numpy(float)
    raw = np.asarray(r.normalise(means))
    return round(float(np.mean((raw < -1e-9) | (raw > 1 + 1e-9))), 4)


def lowlight_rows(realisations, ranges: dict, setting: tuple[str, str] | None = None) -> list[tuple]:
    """decisions.csv's low-light rows (module docstring), as tuples in
    :data:`.decisions.COLUMNS` order; [] without a sweep below the base.
    ``setting``: (axis, value) of a processing setting the study swept
    (:func:`.isp_settings.isp_settings`): the rows of that setting, the
    aspects named ``... with <axis> <value>``; None: the study's own."""
    from .isp_settings import at_base_axes, setting_label, with_setting

    if realisations is None or realisations.empty or "base" not in realisations:
        return []
    base_lum = _base_level(realisations)
    if base_lum is None:
        return []
    realisations = at_base_axes(realisations) if setting is None else with_setting(realisations, *setting)
    rows = _decide_lowlight(realisations, ranges, base_lum)
    if setting is None:
        return rows
    sfx = f" with {setting_label(*setting)}"
    return [(r[0] + sfx, *r[1:6], f"{r[6]}, {setting_label(*setting)}", *r[7:]) for r in rows]


def _decide_lowlight(realisations, ranges: dict, base_lum: float) -> list[tuple]:
    """:func:`lowlight_rows` on one setting's rows."""
    from .decision_rule import robustness

    levels = _metric_levels(realisations, base_lum)
    out = []
    snr, per = _snr10_outcome(realisations)
    lowest = {m: (lv[0], *_metric_outcome(realisations, m, lv[0])) for m, lv in levels.items()}
    if snr is not None:
        others = [(f"{m} at {lv:g} cd/m^2", o) for m, (lv, o, _) in lowest.items()]
        robust, depends, words = robustness(snr, others)
        n = int(per.groupby("cfa")["realisation"].nunique().max())
        out.append(("low light", " ".join(snr.cfas), snr.verdict, robust, depends, np.nan,
                    "SNR10 (cd/m^2 at which YSNR on the gray bar reaches 10; lower is better)", np.nan,
                    f"SNR10 over {n} realisation(s) of each CFA, mean over the demosaics; practical difference "
                    f"1/3 stop: {snr.detail}.{words}"))
    elif len(per):
        y = realisations[realisations["metric"] == "ysnr"]["value"].astype(float)
        where = ("is above 10 already at the sweep's lowest level" if len(y) and y.min() >= 10 else
                 "does not cross 10 within the sweep")
        out.append(("low light", "", "unmeasured", False, "", np.nan, "SNR10", np.nan,
                    f"YSNR {where} for any CFA: nothing decided (sweep further)"))
    from ..metrics import get_metric

    for m, (lv, o, rows) in lowest.items():
        if o is None:
            continue
        label = get_metric(m).label
        others = [(f"{m} at {other:g} cd/m^2", _metric_outcome(realisations, m, other)[0])
                  for other in levels[m][1:]]
        robust, depends, words = robustness(o, others)
        share = _clipped_at(rows, ranges, m)
        note = (f" (the study's ranges clip {100 * share:.0f} % of the scores at this level: the values decide)"
                if share == share and share > 0 else "")
        out.append((f"low light: {m}", " ".join(o.cfas), o.verdict, robust, depends, lv,
                    f"{label} values at {lv:g} cd/m^2, mean over the demosaics", share,
                    f"{label} at {lv:g} cd/m^2{note}: {o.detail}.{words}"))
    return out
