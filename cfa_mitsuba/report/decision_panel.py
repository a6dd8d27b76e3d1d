"""The report's decision panel, summary cards and sweep line, under one rule.

A CFA is called best (first, the winner) only when its rank interval is
exactly 1; otherwise the CFAs whose rank intervals contain 1 are named as
tied (:func:`cfa_mitsuba.study.decisions.decide`).  The panel shows the
study's ``decisions.csv``; the cards apply the same rule to Table 3's
total and per-demosaic scores.
"""

from __future__ import annotations

__all__ = ["decision_panel", "summary_cards", "sweep_lines", "read_decisions"]

from html import escape
from pathlib import Path


def _e(text) -> str:
    return escape(str(text), quote=True)


def read_decisions(root: Path):
    """decisions.csv of a results directory as a DataFrame, or None."""
    from ..io.guard import read_csv

    path = Path(root) / "decisions.csv"
    if not path.is_file():
        return None
    return read_csv(path, dtype=str, keep_default_na=False)


def intervals_cover(config: dict | None) -> str:
    """The report's sentence on what the 95 % intervals cover, from the
    study's config (``seeds``, ``render_seeds``; study/intervals.py)."""
    cfg = config or {}
    seeds, renders = int(cfg.get("seeds") or 1), int(cfg.get("render_seeds") or 1)
    sensor = f"sensor noise ({seeds} noise seed{'s' if seeds != 1 else ''} per capture)"
    if renders > 1:
        cover = (f"{sensor} and render noise ({renders} independent renders of each path-traced scene; the "
                 "charts render deterministically): metrics.csv's sensor_half_width is the part from sensor "
                 "noise alone")
    else:
        cover = f"{sensor} only: each scene is rendered once (render_seeds = 1), so render noise is not in them"
    return (f"The 95 % intervals cover {cover}. Rank intervals come from paired comparisons: the per-realisation "
            "differences of two CFAs under the same render and sensor seeds, so that noise common to both cancels.")


def decision_panel(root: Path, config: dict | None = None) -> str:
    """HTML: one row per aspect, the CFA(s) that can rank first and the verdict."""
    d = read_decisions(root)
    if d is None or d.empty:
        return ""
    rows = []
    for r in d.itertuples(index=False):
        names = r.cfas.split()
        if r.verdict == "winner":
            what = f"<b>{_e(names[0])}</b> is first: its 95 % interval lies above every other CFA's"
        elif r.verdict == "tie":
            what = f"tie for first: <b>{_e(', '.join(names))}</b> (rank intervals overlap; no single winner)"
        else:
            what = "not measured in this study"
        rows.append(f"<tr><th>{_e(r.aspect)}</th><td>{what}</td><td class=\"note\">{_e(r.detail)}</td></tr>")
    style = ("<style>table.decisions{table-layout:auto;width:100%}table.decisions td,table.decisions th"
             "{text-align:left;white-space:normal;vertical-align:top}table.decisions td.note{font-size:.85em}"
             "</style>")
    return (f'<section class="decisions">{style}<h3>Decisions (decisions.csv)</h3>'
            '<p class="note">A CFA is called first only when its rank interval is exactly 1; otherwise every CFA '
            f"whose rank interval contains 1 is listed as tied. {_e(intervals_cover(config))}</p>"
            '<table class="data decisions"><thead><tr><th>aspect</th><th>verdict</th><th>detail</th></tr></thead>'
            f"<tbody>{''.join(rows)}</tbody></table></section>")


def _card(label_win: str, label_tie: str, cfas, scores, lows, highs, ranks=None):
    from ..study.decisions import decide

    top, verdict, _ = decide(cfas, scores, lows, highs, ranks=ranks)
    if verdict == "winner":
        i = list(cfas).index(top[0])
        return (label_win, top[0], f"{scores[i]:.4f} [{lows[i]:.4f}, {highs[i]:.4f}]")
    return (label_tie, ", ".join(top), "rank intervals contain 1: tied, no single best")


def _ranks(table, prefix: str):
    """(best, worst) ranks of scores.csv's ``prefix``_best / _worst columns
    (paired comparisons), None when the table has none."""
    cols = [f"{prefix}_best", f"{prefix}_worst"]
    if not set(cols) <= set(table.columns):
        return None
    return tuple(table[c].astype(int).tolist() for c in cols)


def summary_cards(scores, luminance, demosaics) -> list[tuple]:
    """[(label, CFA(s), subtitle)]: overall and per demosaic, by the rule."""
    if scores is None or luminance is None or not len(scores):
        return []
    sl = scores[scores["luminance"] == luminance]
    per = sl.drop_duplicates(["cfa", "demosaic"])
    cards = []
    if {"total_score", "total_score_ci_low", "total_score_ci_high"} <= set(per.columns) and len(per):
        tot = per.drop_duplicates("cfa")
        cards.append(_card("Best CFA overall", "Tied first overall", tot["cfa"].tolist(),
                           tot["total_score"].astype(float).tolist(), tot["total_score_ci_low"].astype(float).tolist(),
                           tot["total_score_ci_high"].astype(float).tolist(), _ranks(tot, "total_rank")))
    if len(demosaics) > 1 and {"mean_score_ci_low", "mean_score_ci_high"} <= set(per.columns):
        for d in demosaics:
            g = per[per["demosaic"] == d]
            if len(g):
                cards.append(_card(f"Best with {d}", f"Tied first with {d}", g["cfa"].tolist(),
                                   g["mean_score"].astype(float).tolist(),
                                   g["mean_score_ci_low"].astype(float).tolist(),
                                   g["mean_score_ci_high"].astype(float).tolist(), _ranks(g, "demosaic_rank")))
    return cards


def sweep_lines(config: dict, display) -> list[str]:
    """One line per ``[[sweep]]`` of config.json (``scenes``, ``metrics``,
    ``values`` {axis: [values]}; older files: ``scene``, ``luminances``).
    ``display(metric)`` gives a metric's short name."""
    out = []
    for sw in config.get("sweeps") or []:
        if not isinstance(sw, dict):
            continue
        scenes = sw.get("scenes") or ([sw["scene"]] if sw.get("scene") else [])
        values = dict(sw.get("values") or {})
        if not values and sw.get("luminances"):
            values = {"luminance": sw["luminances"]}
        metrics = ", ".join(display(m) for m in sw.get("metrics") or []) or "every metric"
        axes = []
        for axis, vals in values.items():
            unit = " cd/m²" if axis == "luminance" else ""
            shown = ", ".join(f"{float(v):g}" if isinstance(v, (int, float)) else str(v) for v in vals)
            axes.append(f"{axis} {shown}{unit}")
        out.append(f"{metrics} on {', '.join(scenes) or 'every scene'} at {'; '.join(axes) or 'the base values'}")
    return out
