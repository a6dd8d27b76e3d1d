"""Generated tables and sentences of docs/metrics.md (``<!--= @NAME ARGS -->``).

- ``@bench-table PATH.json``: a benchmark's ``--json`` output (rows of
  ``metric``, ``time_s``, ``budget_s``) with how it was measured;
- ``@metric-table RESULTS METRIC DEMOSAIC [LUMINANCE]``: one metric of a
  study's metrics.csv per CFA, mean with half its 95 % interval, censored
  values marked as bounds;
- ``@censored RESULTS METRIC``: how many of a metric's values are bounds,
  and which (CFA, demosaic);
- ``@above-ideal RESULTS METRIC``: the camera outputs whose value exceeds
  the ideal sensor's (ideal.csv).
"""

from __future__ import annotations

__all__ = ["GENERATORS", "bench_table", "metric_table", "censored_sentence", "above_ideal_sentence"]

import json
from pathlib import Path

from ..errors import CfaMitsubaError


def _csv(repo: Path, results: str, name: str):
    import pandas as pd

    path = repo / results / name
    if not path.is_file():
        raise CfaMitsubaError(f"{results}/{name} not found")
    return pd.read_csv(path)


def _rows(repo: Path, results: str, metric: str, luminance: str | None):
    m = _csv(repo, results, "metrics.csv")
    m = m[m["metric"] == metric]
    # the reference luminance (100 cd/m^2) unless the metric was measured elsewhere only
    lum = float(luminance) if luminance else (100.0 if (m["luminance"] == 100.0).any() else m["luminance"].min())
    rows = m[m["luminance"] == lum]
    if rows.empty:
        raise CfaMitsubaError(f"{results}/metrics.csv has no {metric!r} rows at {lum:g} cd/m^2")
    return rows


def bench_table(repo: Path, path: str) -> str:
    """A benchmark's measured times against its budgets, with the load it ran under."""
    file = repo / path
    if not file.is_file():
        raise CfaMitsubaError(f"{path} not found (run the benchmark with --json {path})")
    d = json.loads(file.read_text())
    lines = ["| measured | time (s) | budget (s) |", "|---|---|---|"]
    for r in d["rows"]:
        budget = "" if r.get("budget_s") is None else f"{r['budget_s']:g}" + ("" if r["time_s"] < r["budget_s"]
                                                                               else " (missed)")
        lines.append(f"| {r['metric']} | {r['time_s']:.3f} | {budget} |")
    load = d.get("load_average_end")
    how = (f"median of {d.get('repeat')} runs on {d.get('cpus')} CPU(s)"
           + (f" at load average {load:.1f}" if load is not None else "") + f", {d.get('date', '?')}")
    return "\n\n" + "\n".join(lines) + f"\n\n({how}.)\n\n"


def metric_table(repo: Path, results: str, metric: str, demosaic: str, luminance: str | None = None) -> str:
    """One metric per CFA for one demosaic: mean ± half the 95 % interval; ``>=`` marks a censored bound."""
    rows = _rows(repo, results, metric, luminance)
    rows = rows[rows["demosaic"] == demosaic]
    unit = rows["unit"].iloc[0] if isinstance(rows["unit"].iloc[0], str) else ""
    lines = [f"| {demosaic} | {metric} ({unit}), mean ± half the 95 % interval | censored |", "|---|---|---|"]
    for r in rows.itertuples(index=False):
        cens = str(r.censored) == "True"
        lines.append(f"| {r.cfa} | {'>= ' if cens else ''}{r.value:.2f} ± {(r.ci_high - r.ci_low) / 2:.2f} | "
                     f"{'yes' if cens else 'no'} |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def censored_sentence(repo: Path, results: str, metric: str) -> str:
    """How many of a metric's values are censored bounds, and which."""
    rows = _rows(repo, results, metric, None)
    cens = rows[rows["censored"].astype(str) == "True"]
    by: dict = {}
    for r in cens.itertuples(index=False):
        by.setdefault(r.cfa, []).append(r.demosaic)
    n_dem = rows["demosaic"].nunique()
    parts = [f"{c} ({'every demosaic' if len(d) == n_dem else ', '.join(d)})" for c, d in by.items()]
    return f"{len(cens)} of {len(rows)} values are bounds" + (f": {'; '.join(parts)}" if parts else "")


def above_ideal_sentence(repo: Path, results: str, metric: str) -> str:
    """The camera outputs whose mean value exceeds the ideal sensor's mean (same scene, luminance)."""
    rows = _rows(repo, results, metric, None)
    ideal = _csv(repo, results, "ideal.csv")
    ideal = ideal[(ideal["metric"] == metric) & (ideal["luminance"] == rows["luminance"].iloc[0])]
    if ideal.empty:
        raise CfaMitsubaError(f"{results}/ideal.csv has no {metric!r} row")
    ref = float(ideal["value"].mean())
    above = rows[rows["value"] > ref].sort_values("value", ascending=False)
    names = ", ".join(f"{r.cfa} with {r.demosaic} ({r.value:.1f}, {100 * (r.value / ref - 1):+.1f} %)"
                      for r in above.itertuples(index=False))
    return f"the ideal sensor's {ref:.1f}; above it: " + (names or "none")


#: {name: function(repo, *args) -> Markdown}
GENERATORS = {
    "bench-table": bench_table,
    "metric-table": metric_table,
    "censored": censored_sentence,
    "above-ideal": above_ideal_sentence,
}
