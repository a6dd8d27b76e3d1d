"""How much render noise adds to a study's intervals, and what it changes in the ranking.

From a finished study's CSVs (``render_seeds`` > 1; study/intervals.py):

- per metric, the median and largest ratio of a value's 95 % half width
  (render and sensor noise) to its sensor-noise-only half width
  (metrics.csv ``sensor_half_width``), over the values whose realisations
  span several renders (``render_seeds`` > 1: the path-traced scenes; a
  chart's ratio is 1 by construction).  The render component is pooled over
  a scene, level and metric's values (study/variance.py), so a ratio is 1
  where that pool finds no render noise and grows with the pooled render
  variance against the value's own sensor variance;
- the overall rank intervals (Table 3's total) with render noise, from
  scores.csv, against those with sensor noise only: the same realisations
  restricted to render seed 0 and scored again (needs
  ``metrics_realisations.csv``), or, without it, a baseline results
  directory's scores.csv (a study run with one render seed).

``python3 -m cfa_mitsuba.report.render_noise RESULTS [BASELINE]`` prints the
Markdown; docs use it as ``<!--= @render-noise RESULTS [BASELINE] -->``
(:mod:`.docs_numbers`).
"""

from __future__ import annotations

__all__ = ["half_width_ratios", "sensor_only_ranks", "rank_changes", "render_noise_md", "main"]

import sys
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError


def _read(root: Path, name: str, **kw):
    from ..io.guard import read_csv

    path = root / name
    if not path.exists():
        raise CfaMitsubaError(f"{path}: not found")
    return read_csv(path, **kw)


def half_width_ratios(root: Path):
    """Per metric: ``values`` (with several renders), ``median_ratio``,
    ``max_ratio`` of half width with render noise to sensor-noise-only, and
    the median half widths themselves (``median_half``, ``median_sensor_half``)."""
    import pandas as pd

    m = _read(root, "metrics.csv")
    missing = {"render_seeds", "sensor_half_width"} - set(m.columns)
    if missing:
        raise CfaMitsubaError(f"{root / 'metrics.csv'} has no {', '.join(sorted(missing))} column: it was written "
                              "before render seeds; run the study again")
    m = m[(m["render_seeds"] > 1) & (m["sensor_half_width"] > 0)]
    if m.empty:
        raise CfaMitsubaError(f"{root}: no value spans several renders (render_seeds = 1, or no path-traced scene)")
    half = (m["ci_high"] - m["ci_low"]) / 2
    m = m.assign(half=half, ratio=half / m["sensor_half_width"])
    rows = [(metric, len(g), float(g["ratio"].median()), float(g["ratio"].max()), float(g["half"].median()),
             float(g["sensor_half_width"].median())) for metric, g in m.groupby("metric", sort=False)]
    return pd.DataFrame(rows, columns=["metric", "values", "median_ratio", "max_ratio", "median_half",
                                       "median_sensor_half"])


def sensor_only_ranks(root: Path, render_seed: int | None = 0):
    """Overall (cfa, luminance, total_score, total_rank, total_rank_best,
    total_rank_worst) with sensor noise only: the study's realisations of
    ``render_seed``, scored as the study scored them (its ranges.json);
    ``render_seed`` None: every realisation (scores.csv's totals again)."""
    from ..study.censored import values_for_scoring
    from ..study.ranking import score_realisations
    from ..study.scoring import ScoreRange
    from ..study.tables import scored_rows

    every = _read(root, "metrics_realisations.csv")
    from ..io.guard import read_json

    config = read_json(root / "config.json", allow_nan=True) if (root / "config.json").exists() else {}
    raw = read_json(root / "ranges.json", allow_nan=True)
    ranges = {k: ScoreRange(float(v[0]), float(v[1]), ()) for k, v in raw.items() if not k.startswith("_")}
    constant = list(raw.get("_constant") or [])
    builtin = {s.get("name") for s in config.get("scenes") or [] if isinstance(s, dict) and not s.get("file")}
    one = every if render_seed is None or "render_seed" not in every.columns else \
        every[every["render_seed"] == render_seed]
    scored = values_for_scoring(scored_rows(one, builtin), ranges)
    cols = ["scene", "cfa", "demosaic", "luminance", "metric", "value", "unit", "realisation", "render_seed"]
    s = score_realisations(scored[[c for c in cols if c in scored.columns]], ranges,
                           clip=bool(config.get("clip_scores", True)), constant=constant)
    return s.drop_duplicates(["cfa", "luminance"])[["cfa", "luminance", "total_score", "total_rank",
                                                     "total_rank_best", "total_rank_worst"]]


def _totals(scores):
    return scores.drop_duplicates(["cfa", "luminance"])[["cfa", "luminance", "total_score", "total_rank",
                                                          "total_rank_best", "total_rank_worst"]]


def rank_changes(root: Path, baseline: Path | None = None):
    """(per-CFA table of the overall rank with render noise and with sensor
    noise only, where the sensor-only ranks come from); the study's base
    (lowest) luminance."""
    with_render = _totals(_read(root, "scores.csv"))
    if baseline is not None:
        before, source = _totals(_read(baseline, "scores.csv")), f"{baseline}/scores.csv"
    else:
        before, source = sensor_only_ranks(root), "render seed 0 of metrics_realisations.csv"
    lum = float(with_render["luminance"].min())
    a = with_render[with_render["luminance"] == lum].drop(columns="luminance")
    b = before[before["luminance"].astype(float) == lum].drop(columns="luminance")
    t = a.merge(b, on="cfa", suffixes=("", "_sensor")).set_index("cfa")
    return t.sort_values("total_score", ascending=False, kind="stable"), source


def _span(best, worst) -> str:
    return f"{int(best)}" if int(best) == int(worst) else f"{int(best)}–{int(worst)}"


def render_noise_md(repo: Path, results: str, baseline: str | None = None) -> str:
    """Markdown: the half-width ratios per metric and the overall rank
    intervals with and without render noise (a docs generator)."""
    root = Path(repo) / results
    r = half_width_ratios(root)
    lines = ["| metric | values | median half width: render + sensor | sensor only | median ratio | largest ratio |",
             "|---|---|---|---|---|---|"]
    for x in r.itertuples(index=False):
        lines.append(f"| {x.metric} | {x.values} | {x.median_half:.4g} | {x.median_sensor_half:.4g} | "
                     f"{x.median_ratio:.2f} | {x.max_ratio:.2f} |")
    t, source = rank_changes(root, Path(repo) / baseline if baseline else None)
    changed = [c for c, x in t.iterrows() if (x.total_rank_best, x.total_rank_worst)
               != (x.total_rank_best_sensor, x.total_rank_worst_sensor)]
    lines += ["", "| CFA | total score | rank interval, render + sensor noise | sensor noise only |", "|---|---|---|---|"]
    for c, x in t.iterrows():
        lines.append(f"| `{c}` | {x.total_score:.4f} | {_span(x.total_rank_best, x.total_rank_worst)} | "
                     f"{_span(x.total_rank_best_sensor, x.total_rank_worst_sensor)} |")
    ratio = float(np.median(r["median_ratio"]))
    first = [c for c, x in t.iterrows() if x.total_rank_best == 1]
    first_sensor = [c for c, x in t.iterrows() if x.total_rank_best_sensor == 1]
    said = (f"Render noise widens the path-traced scenes' half widths by a median factor of {ratio:.2f} over the "
            f"metrics (per metric above); {len(changed)} of {len(t)} CFAs' overall rank intervals change "
            f"(sensor noise only: {source}); CFAs that can rank first: {', '.join(first)} "
            f"(sensor noise only: {', '.join(first_sensor)}).")
    return "\n\n" + "\n".join(lines) + "\n\n" + said + "\n\n"


def main(argv=None) -> int:
    """``python3 -m cfa_mitsuba.report.render_noise RESULTS [BASELINE]``: print the Markdown; 2 on bad input."""
    import argparse

    ap = argparse.ArgumentParser(prog="python3 -m cfa_mitsuba.report.render_noise",
                                 description="Render noise's share of a study's intervals and its effect on the ranking.")
    ap.add_argument("results", type=Path, help="a finished study's results folder (render_seeds > 1)")
    ap.add_argument("baseline", type=Path, nargs="?", help="a study with one render seed to compare the ranks with "
                    "(default: render seed 0 of RESULTS/metrics_realisations.csv)")
    args = ap.parse_args(argv)
    root = args.results.resolve()
    baseline = str(args.baseline.resolve()) if args.baseline else None
    try:
        text = render_noise_md(root.parent, root.name, baseline)
    except CfaMitsubaError as exc:
        ap.exit(2, f"{ap.prog}: error: {exc}\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
