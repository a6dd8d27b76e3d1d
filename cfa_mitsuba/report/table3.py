"""Table 3 as the report shows it: one row per CFA, sorted by total score.

Each cell is a mean normalised score ± half its 95 % interval and its rank
interval; the CFA column carries the total's rank interval.  Rows instead
of columns keep a table of any number of CFAs inside the page's width
(at 1400 px every row of the paper study's 12 is visible), and sorting by
the total puts the tied groups next to each other.  A cell is marked best
only where the decision rule of :mod:`cfa_mitsuba.study.decisions` names it
the winner (decisions.csv's ``overall`` and ``with <demosaic>`` rows: rank
interval exactly 1 *and* a lead of at least the practical difference; an
older results folder without those rows: rank interval exactly 1); cells
whose rank interval spans more than one rank are marked as ties.
"""

from __future__ import annotations

__all__ = ["table3_rows"]

import html

import numpy as np

from .style import cfa_styles


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _heat(score: float, lo: float, hi: float) -> str:
    t = float(np.clip((score - lo) / (hi - lo), 0.0, 1.0)) * 0.55 if hi > lo else 0.3
    r, g, b = (int(round(255 + (c - 255) * t)) for c in (0x44, 0x77, 0xAA))
    return f"background:#{r:02x}{g:02x}{b:02x}"


def _span(b: int, w: int) -> str:
    return f"{b}" if b == w else f"{b}–{w}"


def _cell(v, lo_ci, hi_ci, b, w, n_cfas, lo, hi, extra="", named=None) -> str:
    """One cell; ``named``: whether the decision names this CFA the winner
    (None: no decision for this row, the rank interval alone decides)."""
    if v is None or not np.isfinite(v):
        return '<td class="na">—</td>'
    first = (b, w) == (1, 1) and n_cfas > 1
    klass = "best" if (first if named is None else named) else ""
    if b != w:
        klass += " tie"
    half = (hi_ci - lo_ci) / 2 if np.isfinite(lo_ci) and np.isfinite(hi_ci) else np.nan
    pm = f' <span class="ci">±{half:.4f}</span>' if np.isfinite(half) else ""
    tip = f"rank interval {_span(b, w)} of {n_cfas}; 95 % interval {lo_ci:.4f} … {hi_ci:.4f}"
    return (f'<td class="{klass.strip()}" style="{_heat(v, lo, hi)}" data-value="{float(v):.10g}" '
            f'title="{_e(tip)}">{v:.4f}{pm}{extra} <span class="rank">({_span(b, w)})</span></td>')


def _winners(decisions) -> dict:
    """{'total' or demosaic: the CFA decisions.csv names the winner, or ''}
    for the rows it has."""
    out = {}
    if decisions is None:
        return out
    for r in decisions.itertuples(index=False):
        key = "total" if r.aspect == "overall" else r.aspect[5:] if str(r.aspect).startswith("with ") else None
        if key is not None:
            out[key] = str(r.cfas).split()[0] if r.verdict == "winner" else ""
    return out


def table3_rows(scores, luminance: float, cfas, demosaics, decisions=None) -> str | None:
    """HTML of Table 3 at ``luminance`` from scores.csv (rows: CFAs by total
    score); ``decisions``: decisions.csv, whose winners are the cells marked best."""
    s = scores[scores["luminance"] == luminance]
    if not len(s):
        return None
    per = s.drop_duplicates(["cfa", "demosaic"]).set_index(["cfa", "demosaic"])
    tot = s.drop_duplicates("cfa")
    tot = tot[tot["cfa"].isin(cfas)].sort_values("total_score", ascending=False, kind="stable")
    demosaics = [d for d in demosaics if d in set(s["demosaic"])]
    have_ci = "mean_score_ci_low" in s.columns
    vals = per["mean_score"].to_numpy(dtype=float)
    vals = vals[np.isfinite(vals)]
    lo, hi = (float(vals.min()), float(vals.max())) if vals.size else (0.0, 1.0)
    nmet = per["n_metrics"] if "n_metrics" in per.columns else None
    uneven = nmet is not None and nmet.nunique() > 1
    cst = cfa_styles(list(cfas))
    head = "".join(f"<th>{_e(d)}</th>" for d in demosaics)
    out = ['<table class="data scores t3"><thead><tr><th>rank</th><th>CFA</th>', head,
           "<th>Total (mean over demosaics)</th></tr></thead><tbody>"]
    n = len(tot)
    winners = _winners(decisions)
    for r in tot.itertuples(index=False):
        tb, tw = (int(r.total_rank_best), int(r.total_rank_worst)) if have_ci else (int(r.total_rank),) * 2
        sw = f'<span class="swatch" style="background:{cst.get(r.cfa, {}).get("color", "#999")}"></span>'
        row = [f'<tr><td class="rank">{_span(tb, tw)}</td><th class="cfa">{sw}{_e(r.cfa)}</th>']
        for d in demosaics:
            if (r.cfa, d) not in per.index:
                row.append('<td class="na">—</td>')
                continue
            p = per.loc[(r.cfa, d)]
            b, w = ((int(p.demosaic_rank_best), int(p.demosaic_rank_worst)) if have_ci
                    else (int(p.demosaic_rank),) * 2)
            ci = (float(p.mean_score_ci_low), float(p.mean_score_ci_high)) if have_ci else (np.nan, np.nan)
            flag = ('<sup class="oor-mark">*</sup>' if uneven and int(p.n_metrics) != int(nmet.max()) else "")
            named = (winners[d] == r.cfa) if d in winners else None
            row.append(_cell(float(p.mean_score), *ci, b, w, n, lo, hi, flag, named))
        ci = ((float(r.total_score_ci_low), float(r.total_score_ci_high)) if have_ci else (np.nan, np.nan))
        named = (winners["total"] == r.cfa) if "total" in winners else None
        row.append(_cell(float(r.total_score), *ci, tb, tw, n, lo, hi, named=named))
        out.append("".join(row) + "</tr>")
    out.append("</tbody></table>")
    if uneven:
        out.append('<p class="note">* averages fewer metrics than the others (a metric is missing for this CFA '
                   "and demosaic): its mean and rank are not comparable with the rest.</p>")
    return "".join(out)
