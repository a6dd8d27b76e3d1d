"""The report's decision panel, summary cards and sweep line, under one rule.

A CFA is called best (first, the winner) only when its rank interval is
exactly 1 and its lead is at least the practical difference; otherwise the
CFAs that can rank first are tied, or the leader and those within the
practical difference are equivalent (:func:`cfa_mitsuba.study.decisions.decide`).
The panel shows the study's ``decisions.csv`` with what each answer depends
on; the cards are its ``overall`` and ``with <demosaic>`` rows (a results
folder written before decisions.csv had them: the rank intervals alone).
"""

from __future__ import annotations

__all__ = ["decision_panel", "summary_cards", "sweep_lines", "read_decisions", "answer_words", "depends_words"]

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
        cover = (f"{sensor} and render noise ({renders} independent renders of each path-traced scene, its "
                 "variance estimated from every value of one scene, level and metric together; the charts "
                 "render deterministically): metrics.csv's sensor_half_width is the part from sensor noise alone")
    else:
        cover = f"{sensor} only: each scene is rendered once (render_seeds = 1), so render noise is not in them"
    return (f"The 95 % intervals cover {cover}. Rank intervals come from paired comparisons: the per-realisation "
            "differences of two CFAs under the same render and sensor seeds, so that noise common to both cancels.")


#: How the panel names each kind of alternative (decisions.csv's depends_on).
_KINDS = (("censored at", "how moiré bounds are scored"), ("ranges:", "the range policy"),
          ("without ", "which metrics count"), (" cd/m^2", "the level and quantity"))


def depends_words(depends_on: str) -> str:
    """decisions.csv's ``depends_on`` in words: the alternatives grouped by the kind of choice they are.

    >>> depends_words("without moire; censored at best measured; without ssim")
    'without moire, without ssim (which metrics count); censored at best measured (how moiré bounds are scored)'
    """
    groups: dict = {}
    for label in [x.strip() for x in str(depends_on or "").split(";") if x.strip()]:
        kind = next((k for key, k in _KINDS if key in label), "")
        groups.setdefault(kind, []).append(label)
    return "; ".join(", ".join(labels) + (f" ({kind})" if kind else "") for kind, labels in groups.items())


def _flag(value) -> bool:
    return str(value).strip().lower() in ("true", "1")


def answer_words(r) -> str:
    """One decision in plain words, with what it depends on."""
    names = str(r.cfas).split()
    dep = depends_words(getattr(r, "depends_on", ""))
    tail = ("" if not hasattr(r, "robust") else
            ", robust to every alternative checked" if _flag(r.robust) else f", depends on: {dep}")
    if r.verdict == "winner":
        return f"{names[0]}, rank 1{tail}"
    if r.verdict == "equivalent":
        return f"no practical winner: {', '.join(names)} within the practical difference of {names[0]}{tail}"
    if r.verdict == "tie":
        return f"tie for first: {', '.join(names)}{tail}"
    if r.verdict == "clipped":
        return "nothing decided: too many of the scores used are clipped to a range bound"
    return "not measured in this study"


def decision_panel(root: Path, config: dict | None = None) -> str:
    """HTML: one row per decision: the answer, what it depends on, the level,
    the quantity, the share of clipped scores and the detail."""
    d = read_decisions(root)
    if d is None or d.empty:
        return ""
    rows = []
    for r in d.itertuples(index=False):
        what = _e(answer_words(r))
        if r.verdict == "winner":
            what = f"<b>{_e(str(r.cfas).split()[0])}</b>{what[len(str(r.cfas).split()[0]):]}"
        level = getattr(r, "luminance", "")
        level = f"{float(level):g} cd/m²" if str(level).strip() not in ("", "nan") else ""
        clip = getattr(r, "clipped_share", "")
        clip = f"{100 * float(clip):.0f} %" if str(clip).strip() not in ("", "nan") else ""
        rows.append(f"<tr><th>{_e(r.aspect)}</th><td>{what}</td><td>{_e(level)}</td><td>{_e(clip)}</td>"
                    f"<td class=\"note\">{_e(r.detail)}</td></tr>")
    style = ("<style>table.decisions{table-layout:auto;width:100%}table.decisions td,table.decisions th"
             "{text-align:left;white-space:normal;vertical-align:top}table.decisions td.note{font-size:.85em}"
             "</style>")
    return (f'<section class="decisions">{style}<h3>Decisions (decisions.csv)</h3>'
            '<p class="note">A CFA is named first only when its rank interval is exactly 1 and its lead is at '
            "least the practical difference (the smallest difference that matters, from each metric's record); "
            "a separated lead below it is 'no practical winner'; several CFAs whose rank intervals contain 1 are "
            "a tie; nothing is decided where more than 10 % of the scores used (each CFA, demosaic and metric's "
            "mean) lie outside their range and are clipped to its bound. Each "
            "answer was recomputed under the other range policies, the other ways of scoring a moiré bound and "
            "with each metric left out; 'depends on' names those that change it. Low light is decided on SNR10 "
            f"and on the swept metrics' own values, not on scores. {_e(intervals_cover(config))}</p>"
            '<table class="data decisions"><thead><tr><th>decision</th><th>answer</th><th>level</th>'
            "<th>scores clipped</th><th>what was compared, and the detail</th></tr></thead>"
            f"<tbody>{''.join(rows)}</tbody></table></section>")


def _card(label_win: str, label_tie: str, cfas, scores, lows, highs, ranks=None):
    from ..study.decisions import decide

    top, verdict, _ = decide(cfas, scores, lows, highs, ranks=ranks)
    if verdict == "winner":
        i = list(cfas).index(top[0])
        return (label_win, top[0], f"{scores[i]:.4f} [{lows[i]:.4f}, {highs[i]:.4f}]")
    return (label_tie, ", ".join(top), "rank intervals contain 1: tied, no single best")


def _card_of(row, what: str, scores: dict):
    """A card from a decisions.csv row (``what``: 'overall' or 'with bilinear')."""
    names = str(row.cfas).split()
    label = {"winner": f"Best CFA {what}" if what == "overall" else f"Best {what}",
             "equivalent": f"Equivalent first {what}", "tie": f"Tied first {what}",
             "clipped": f"Nothing decided {what}"}.get(row.verdict, f"Not measured {what}")
    dep = ("robust to every alternative checked" if _flag(getattr(row, "robust", False))
           else f"depends on: {row.depends_on}" if str(getattr(row, "depends_on", "")).strip() not in ("", "nan")
           else "")
    if row.verdict == "winner":
        sc = scores.get(names[0])
        sub = (f"{sc[0]:.4f} [{sc[1]:.4f}, {sc[2]:.4f}]; " if sc else "") + dep
        return (label, names[0], sub)
    why = {"equivalent": "separated, but the lead is below the practical difference",
           "tie": "rank intervals contain 1: tied, no single best",
           "clipped": "too many clipped scores"}.get(row.verdict, "")
    return (label, ", ".join(names), "; ".join(x for x in (why, dep) if x))


def _ranks(table, prefix: str):
    """(best, worst) ranks of scores.csv's ``prefix``_best / _worst columns
    (paired comparisons), None when the table has none."""
    cols = [f"{prefix}_best", f"{prefix}_worst"]
    if not set(cols) <= set(table.columns):
        return None
    return tuple(table[c].astype(int).tolist() for c in cols)


def summary_cards(scores, luminance, demosaics, decisions=None) -> list[tuple]:
    """[(label, CFA(s), subtitle)]: overall and per demosaic, by the rule:
    decisions.csv's rows where ``decisions`` has them, else the rank
    intervals of scores.csv alone (an older results folder)."""
    if scores is None or luminance is None or not len(scores):
        return []
    sl = scores[scores["luminance"] == luminance]
    per = sl.drop_duplicates(["cfa", "demosaic"])
    rows = {} if decisions is None else {r.aspect: r for r in decisions.itertuples(index=False)}
    cards = []
    if {"total_score", "total_score_ci_low", "total_score_ci_high"} <= set(per.columns) and len(per):
        tot = per.drop_duplicates("cfa")
        if "overall" in rows:
            sc = {r.cfa: (r.total_score, r.total_score_ci_low, r.total_score_ci_high) for r in tot.itertuples()}
            cards.append(_card_of(rows["overall"], "overall", sc))
        else:
            cards.append(_card("Best CFA overall", "Tied first overall", tot["cfa"].tolist(),
                               tot["total_score"].astype(float).tolist(),
                               tot["total_score_ci_low"].astype(float).tolist(),
                               tot["total_score_ci_high"].astype(float).tolist(), _ranks(tot, "total_rank")))
    if len(demosaics) > 1 and {"mean_score_ci_low", "mean_score_ci_high"} <= set(per.columns):
        for d in demosaics:
            g = per[per["demosaic"] == d]
            if not len(g):
                continue
            if f"with {d}" in rows:
                sc = {r.cfa: (r.mean_score, r.mean_score_ci_low, r.mean_score_ci_high) for r in g.itertuples()}
                cards.append(_card_of(rows[f"with {d}"], f"with {d}", sc))
                continue
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
