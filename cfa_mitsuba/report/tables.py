"""The paper's Tables 1-3 for a study's results, as HTML.

- Table 1: mean dE over the 24 patches and mean dL over the 6 grey patches
  per CFA (the paper gives bilinear only; here one row group per demosaic);
- Table 2: every scored metric per CFA per demosaic, the best value per
  metric and demosaic boxed (the paper's red boxes; by value, as clipped
  scores tie at 1 beyond a range's best end);
- Table 3: mean normalised score per CFA (rows, by total score) and
  demosaic, their mean ('total'), with intervals and rank intervals
  (:mod:`.table3`).

Every value cell carries the full-precision number from the CSV in
``data-value`` and its score and rank in a tooltip.
"""

from __future__ import annotations

__all__ = ["table1", "table2", "table3", "other_table", "sweep_table", "ranges_table", "policy_table"]

import html

import numpy as np

from .results import SCORED_METRICS, Results
from .style import cfa_styles, fmt_value, metric_display


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _num(v) -> str:
    return f"{float(v):.10g}"


def _tr(i: int) -> str:
    """A table row opening; the first row of a group gets a rule above it."""
    return '<tr class="group-start">' if i == 0 else "<tr>"


def _head(res: Results, cfas, first_cols) -> str:
    cst = cfa_styles(res.cfas)
    cells = "".join(f"<th>{_e(c)}</th>" for c in first_cols)
    cells += "".join(f'<th class="cfa"><span class="swatch" style="background:{cst[c]["color"]}"></span>'
                     f"{_e(c)}</th>" for c in cfas)
    return f"<thead><tr>{cells}</tr></thead>"


def _direction(metric: str, res: Results) -> bool:
    """True when higher is better (from the score range, else the metric's nature)."""
    r = res.ranges.get(metric)
    if r is not None and r[0] != r[1]:
        return r[1] > r[0]
    return metric_display(metric).higher_better


def _metric_label(metric: str, res: Results) -> str:
    info = metric_display(metric)
    arrow = "↑" if _direction(metric, res) else "↓"
    unit = f' <span class="unit">({_e(info.unit)})</span>' if info.unit and info.unit not in info.short else ""
    return f'<span title="{_e(info.long)}">{_e(info.short)}</span>{unit} <span class="dir">{arrow}</span>'


def _best(values: dict, higher: bool, decimals: int | None = None) -> set:
    """The keys of the best value; with ``decimals``, every value equal to it
    as printed is best too (a reader sees a tie, so the table shows one)."""
    finite = {k: v for k, v in values.items() if v is not None and np.isfinite(v)}
    if not finite:
        return set()
    if decimals is not None:
        finite = {k: float(f"{v:.{decimals}f}") for k, v in finite.items()}  # as fmt_value prints it
    target = max(finite.values()) if higher else min(finite.values())
    return {k for k, v in finite.items() if v == target}


def _intervals(res: Results) -> dict:
    """{(scene, cfa, demosaic, luminance, metric): (ci_low, ci_high)} of metrics.csv's base rows."""
    m = res.metrics
    if m is None or not len(m) or "ci_low" not in m.columns:
        return {}
    return {(r.scene, r.cfa, r.demosaic, float(r.luminance), r.metric): (float(r.ci_low), float(r.ci_high))
            for r in m.itertuples(index=False)}


def _pm(ci, metric: str) -> str:
    """``±half`` of a 95 % interval, small, on a line of its own under the value
    (the column stays as wide as the values), one decimal more than the value."""
    if ci is None or not all(np.isfinite(ci)):
        return ""
    return f'<br><span class="ci">±{(ci[1] - ci[0]) / 2:.{metric_display(metric).decimals + 1}f}</span>'


def _separated(best: set, cis: dict) -> set:
    """The best-valued keys whose 95 % interval overlaps no other key's: only
    those are boxed as best; a best value inside another's interval is a tie."""
    out = set()
    for k in best:
        mine = cis.get(k)
        if mine is None or len(best) > 1:
            continue
        if all(o is None or o[1] < mine[0] or o[0] > mine[1] for j, o in cis.items() if j != k):
            out.add(k)
    return out


def table1(res: Results) -> str | None:
    """Mean dE00 (and dE*ab) over the 24 patches and mean |dL*| of the 6 grey
    patches, per CFA, one row group per demosaic (the paper's Table 1)."""
    lum = res.primary_luminance
    scene = res.scene_for("delta-e")
    if scene is None or lum is None:
        return None
    rows_metrics = [m for m in ("delta-e", "delta-e76", "delta-l") if res.has_metric(m, lum)]
    cfas = [c for c in res.cfas if any(res.value(scene, c, d, lum, "delta-e") is not None for d in res.demosaics)]
    out = ['<table class="data">', _head(res, cfas, ["demosaic", "measure"]), "<tbody>"]
    ints = _intervals(res)
    for d in res.demosaics:
        present = [m for m in rows_metrics if any(res.value(scene, c, d, lum, m) is not None for c in cfas)]
        for i, m in enumerate(present):
            vals = {c: res.value(scene, c, d, lum, m) for c in cfas}
            cis = {c: ints.get((scene, c, d, float(lum), m)) for c in cfas}
            by_value = _best(vals, higher=False, decimals=metric_display(m).decimals)
            best = _separated(by_value, cis)
            row = [_tr(i)]
            if i == 0:
                row.append(f'<th rowspan="{len(present)}" class="rowgroup">{_e(d)}</th>')
            row.append(f'<th class="metric">{_metric_label(m, res)}</th>')
            for c in cfas:
                v = vals[c]
                if v is None:
                    row.append('<td class="na">—</td>')
                    continue
                klass = ("best" if c in best else "besttie" if c in by_value else "") if len(cfas) > 1 else ""
                row.append(f'<td class="{klass}" data-value="{_num(v)}">{fmt_value(m, v)}{_pm(cis[c], m)}</td>')
            row.append("</tr>")
            out.append("".join(row))
    out.append("</tbody></table>")
    return "".join(out)


def table2(res: Results, luminance: float) -> str | None:
    """Every scored metric per CFA per demosaic at ``luminance``, the best CFA
    per metric and demosaic boxed (the paper's Table 2)."""
    s = res.scores
    if s is None:
        return _table2_from_metrics(res, luminance)
    s = s[s["luminance"] == luminance]
    if not len(s):
        return None
    metrics = [m for m in SCORED_METRICS if m in set(s["metric"])]
    metrics += [m for m in dict.fromkeys(s["metric"]) if m not in metrics]
    cfas = [c for c in res.cfas if c in set(s["cfa"])]
    n_cfa = len(cfas)
    by = {(r.cfa, r.demosaic, r.metric): r for r in s.itertuples(index=False)}
    out = ['<table class="data">', _head(res, cfas, ["demosaic", "metric"]), "<tbody>"]
    for d in res.demosaics:
        present = [m for m in metrics if any((c, d, m) in by for c in cfas)]
        for i, m in enumerate(present):
            row = [_tr(i)]
            if i == 0:
                row.append(f'<th rowspan="{len(present)}" class="rowgroup">{_e(d)}</th>')
            row.append(f'<th class="metric">{_metric_label(m, res)}</th>')
            # the best value, not metric_rank 1: clipped scores tie at 1 for every value beyond the best end
            by_value = _best({c: float(by[(c, d, m)].value) for c in cfas if (c, d, m) in by},
                             _direction(m, res), metric_display(m).decimals)
            cis = {c: (float(by[(c, d, m)].ci_low), float(by[(c, d, m)].ci_high))
                   if (c, d, m) in by and hasattr(by[(c, d, m)], "ci_low") else None for c in cfas}
            best = _separated(by_value, cis)
            if all(hasattr(by[(c, d, m)], "metric_rank_worst") for c in by_value):
                # paired comparisons (scores.csv's metric rank interval): first against every other CFA
                best = {c for c in by_value if len(by_value) == 1 and int(by[(c, d, m)].metric_rank_worst) == 1}
            for c in cfas:
                r = by.get((c, d, m))
                if r is None:
                    row.append('<td class="na">—</td>')
                    continue
                klass = []
                if c in by_value and n_cfa > 1:
                    klass.append("best" if c in best else "besttie")
                oor = bool(getattr(r, "out_of_range", False))
                if oor:
                    klass.append("oor")
                tip = (f"score {float(r.score):.3f}" + (f" (eq. 8 gives {float(r.raw_score):.3f}, outside "
                       f"[0, 1])" if oor and hasattr(r, "raw_score") else "")
                       + (f"; rank {int(r.metric_rank)} of {n_cfa}" if hasattr(r, "metric_rank") else ""))
                mark = '<sup class="oor-mark">†</sup>' if oor else ""
                ge, some, why = _bound_mark(res, r)
                tip += why
                value = r.value
                if some:  # bounds in some realisations: metrics.csv's value under the rule (their median)
                    value, cis[c] = _metrics_value(res, r)
                row.append(f'<td class="{" ".join(klass)}" data-value="{_num(value)}" title="{_e(tip)}">'
                           f"{ge}{fmt_value(m, value)}{mark}{some}{_pm(cis[c], m)}</td>")
            row.append("</tr>")
            out.append("".join(row))
    out.append("</tbody></table>")
    return "".join(out)


def _metrics_value(res: Results, row):
    """(value, (ci_low, ci_high)) of metrics.csv for a scores.csv row (read under study/censored.py's rule)."""
    m = res.metrics
    r = m[(m["scene"] == row.scene) & (m["cfa"] == row.cfa) & (m["demosaic"] == row.demosaic)
          & (m["luminance"] == row.luminance) & (m["metric"] == row.metric)].iloc[0]
    return float(r["value"]), (float(r["ci_low"]), float(r["ci_high"]))


def _bound_mark(res: Results, row) -> tuple[str, str, str]:
    """(prefix, mark, tooltip words) of a value under the rule of
    study/censored.py: "≥" only when every realisation is a bound (no moiré
    up to the chirp's top); a value with bounds in some realisations is
    their median, marked with how many."""
    m = res.metrics
    sel = m[(m["scene"] == row.scene) & (m["cfa"] == row.cfa) & (m["demosaic"] == row.demosaic)
            & (m["luminance"] == row.luminance) & (m["metric"] == row.metric)]
    if not len(sel) or "censored_count" not in sel.columns:
        return "", "", ""
    r = sel.iloc[0]
    count, n = int(r["censored_count"]), int(r["n"]) if "n" in r and r["n"] == r["n"] else 0
    if count and count >= n and str(r["censored"]).lower() in ("true", "1"):
        return "≥", "", "; no moiré up to the chirp's top frequency in any realisation: a lower bound"
    if count:
        return ("", f'<sup class="oor-mark">{count}/{n}≥</sup>',
                f"; {count} of {n} realisations saw no moiré up to the chirp's top: the value is the "
                "realisations' Kaplan-Meier median, a measurement")
    return "", "", ""


def _table2_from_metrics(res: Results, luminance: float) -> str | None:
    m = res.metrics
    m = m[(m["luminance"] == luminance) & m["metric"].isin(SCORED_METRICS)]
    if not len(m):
        return None
    cfas = [c for c in res.cfas if c in set(m["cfa"])]
    out = ['<table class="data">', _head(res, cfas, ["demosaic", "metric"]), "<tbody>"]
    for d in res.demosaics:
        md = m[m["demosaic"] == d]
        present = [k for k in SCORED_METRICS if k in set(md["metric"])]
        for i, k in enumerate(present):
            scene = res.scene_for(k)
            vals = {c: res.value(scene, c, d, luminance, k) for c in cfas}
            best = _best(vals, _direction(k, res), metric_display(k).decimals)
            row = [_tr(i)]
            if i == 0:
                row.append(f'<th rowspan="{len(present)}" class="rowgroup">{_e(d)}</th>')
            row.append(f'<th class="metric">{_metric_label(k, res)}</th>')
            for c in cfas:
                v = vals[c]
                if v is None:
                    row.append('<td class="na">—</td>')
                else:
                    klass = "best" if c in best and len(cfas) > 1 else ""
                    row.append(f'<td class="{klass}" data-value="{_num(v)}">{fmt_value(k, v)}</td>')
            row.append("</tr>")
            out.append("".join(row))
    out.append("</tbody></table>")
    return "".join(out)


def table3(res: Results, luminance: float) -> str | None:
    """Mean normalised score per CFA (rows, sorted by total score) and
    demosaic (columns), their mean over demosaics ('total'), each with its
    interval and rank interval (the paper's Table 3 and Fig 17;
    :mod:`.table3`)."""
    from .decision_panel import read_decisions
    from .table3 import table3_rows

    s = res.scores
    if s is None or not len(s[s["luminance"] == luminance]):
        return None
    first = luminance == min(res.base_luminances) if res.base_luminances else True
    return table3_rows(s, luminance, res.cfas, res.demosaics, read_decisions(res.root) if first else None)


def policy_table(res: Results) -> str | None:
    """Per scored metric and range policy: how many scores eq. 8 clips, or
    that the metric cannot rank the CFAs (constant); then each CFA's overall
    rank under each policy (policies.csv)."""
    p = res.policies
    if p is None or not len(p):
        return None
    clip = p[p["scope"] == "clipping"]
    rank = p[p["scope"] == "rank"]
    policies = list(dict.fromkeys(clip["policy"]))
    out = ['<table class="data policies"><thead><tr><th>metric</th>'
           + "".join(f"<th>{_e(q)}{' (used)' if q == res.range_policy else ''}</th>" for q in policies)
           + "</tr></thead><tbody>"]
    for m in [k for k in SCORED_METRICS if k in set(clip["metric"])]:
        cells = []
        for q in policies:
            r = clip[(clip["policy"] == q) & (clip["metric"] == m)]
            if not len(r):
                cells.append('<td class="na">—</td>')
                continue
            r = r.iloc[0]
            if str(r["constant"]).lower() == "true":
                cells.append('<td class="warn">constant: cannot rank</td>')
            else:
                n, k = int(r["scores"]), int(r["clipped"])
                cells.append(f'<td{" class=warn" if k else ""}>{k} of {n} clipped</td>')
        out.append(f'<tr><th class="metric">{_metric_label(m, res)}</th>{"".join(cells)}</tr>')
    out.append("</tbody></table>")
    if len(rank):
        lum = res.primary_luminance if res.primary_luminance in set(rank["luminance"]) else rank["luminance"].iloc[0]
        rank = rank[rank["luminance"] == lum]
        out.append('<table class="data policies"><thead><tr><th>CFA</th>'
                   + "".join(f"<th>rank, {_e(q)}</th>" for q in policies) + "</tr></thead><tbody>")
        for c in [c for c in res.cfas if c in set(rank["cfa"])]:
            cells = []
            for q in policies:
                r = rank[(rank["policy"] == q) & (rank["cfa"] == c)]
                cells.append(f"<td>{int(r['total_rank'].iloc[0])} ({float(r['total_score'].iloc[0]):.3f})</td>"
                             if len(r) else '<td class="na">—</td>')
            out.append(f'<tr><th>{_e(c)}</th>{"".join(cells)}</tr>')
        out.append("</tbody></table>")
    return "".join(out)


def other_table(res: Results) -> str | None:
    """Measurements that are reported but not scored (dE*ab, grey-patch dL,
    interior S-CIELAB, any further metric) at the primary luminance."""
    lum = res.primary_luminance
    m = res.metrics
    m = m[(m["luminance"] == lum) & ~m["metric"].isin(SCORED_METRICS)]
    if not len(m):
        return None
    metrics = list(dict.fromkeys(m["metric"]))
    cfas = [c for c in res.cfas if c in set(m["cfa"])]
    out = ['<table class="data">', _head(res, cfas, ["demosaic", "measure", "scene"]), "<tbody>"]
    for d in res.demosaics:
        md = m[m["demosaic"] == d]
        present = [(k, s) for k in metrics for s in dict.fromkeys(md[md["metric"] == k]["scene"])]
        for i, (k, scene) in enumerate(present):
            row = [_tr(i)]
            if i == 0:
                row.append(f'<th rowspan="{len(present)}" class="rowgroup">{_e(d)}</th>')
            row.append(f'<th class="metric">{_metric_label(k, res)}</th><td class="scene">{_e(scene)}</td>')
            for c in cfas:
                v = res.value(scene, c, d, lum, k)
                row.append('<td class="na">—</td>' if v is None else
                           f'<td data-value="{_num(v)}">{fmt_value(k, v)}{_db(k, v)}</td>')
            row.append("</tr>")
            out.append("".join(row))
    out.append("</tbody></table>")
    return "".join(out)


def _db(metric: str, value: float) -> str:
    """An SNR's value in dB beside the ratio (records with ``decibels``)."""
    from ..metrics import METRICS

    rec = METRICS.get(metric)
    if rec is None or not getattr(rec, "decibels", False) or not value > 0:
        return ""
    return f' <span class="unit">({20 * np.log10(value):.1f} dB)</span>'


def sweep_table(res: Results) -> str | None:
    """The values behind the luminance-sweep figure: one row per (metric,
    demosaic, luminance), one column per CFA."""
    m = res.metrics
    parts = []
    for (scene, metric), g in m.groupby(["scene", "metric"], sort=False):
        if g["luminance"].nunique() > 1 and metric in SCORED_METRICS:
            parts.append((scene, metric, g))
    if not parts:
        return None
    cfas = [c for c in res.cfas if c in set(m["cfa"])]
    ints = _intervals(res)
    out = ['<table class="data">', _head(res, cfas, ["metric", "demosaic", "cd/m²"]), "<tbody>"]
    for scene, metric, g in parts:
        for d in res.demosaics:
            gd = g[g["demosaic"] == d]
            lums = sorted(gd["luminance"].unique())
            for i, lum in enumerate(lums):
                row = [_tr(i)]
                if i == 0:
                    row.append(f'<th rowspan="{len(lums)}" class="metric">{_metric_label(metric, res)}'
                               f'<br><span class="unit">{_e(scene)}</span></th>'
                               f'<th rowspan="{len(lums)}" class="rowgroup">{_e(d)}</th>')
                row.append(f'<td class="lum">{lum:g}</td>')
                for c in cfas:
                    v = res.value(scene, c, d, lum, metric)
                    ci = ints.get((scene, c, d, float(lum), metric))
                    row.append('<td class="na">—</td>' if v is None else
                               f'<td data-value="{_num(v)}">{fmt_value(metric, v)}{_pm(ci, metric)}</td>')
                row.append("</tr>")
                out.append("".join(row))
    out.append("</tbody></table>")
    return "".join(out)


def ranges_table(res: Results) -> str | None:
    """The score ranges (eq. 8's worst and best ends) and how many scored
    values fell outside each."""
    s = res.scores
    if not res.ranges and s is None:
        return None
    metrics = [m for m in SCORED_METRICS if s is not None and m in set(s["metric"])]
    if not metrics:
        return None
    out = ['<table class="data ranges"><thead><tr><th>metric</th><th>scene</th><th>worst (score 0)</th>'
           "<th>best (score 1)</th><th>measured (min … max)</th><th>outside the range</th></tr></thead><tbody>"]
    for m in metrics:
        r = res.ranges.get(m)
        if r is None and s is not None and m in set(s["metric"]):
            g0 = s[s["metric"] == m].iloc[0]
            r = (float(g0["worst"]), float(g0["best"]))
        g = s[s["metric"] == m] if s is not None else None
        n = len(g) if g is not None else 0
        if g is not None and n:
            vmin, vmax = float(g["value"].min()), float(g["value"].max())
            meas = f"{fmt_value(m, vmin)} … {fmt_value(m, vmax)}"
            n_oor = int(g["out_of_range"].sum()) if "out_of_range" in g.columns else 0
            oor = f"{n_oor} of {n}" if n_oor else "none"
            klass = ' class="warn"' if n_oor else ""
        else:
            meas, oor, klass = "not measured", "—", ""
        info = metric_display(m)
        unit = f" {info.unit}" if info.unit else ""
        w, b = (fmt_value(m, r[0]) + unit, fmt_value(m, r[1]) + unit) if r else ("—", "—")
        out.append(f'<tr><th class="metric">{_metric_label(m, res)}</th>'
                   f'<td class="scene">{_e(res.scene_for(m) or "—")}</td>'
                   f"<td>{_e(w)}</td><td>{_e(b)}</td><td>{_e(meas)}</td><td{klass}>{_e(oor)}</td></tr>")
    out.append("</tbody></table>")
    return "".join(out)
