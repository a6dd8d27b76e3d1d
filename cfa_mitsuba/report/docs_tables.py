"""Generated blocks of README.md and docs/*.md (``<!--= @NAME ARGS -->``).

Each generator reads a results directory (relative to the repository root)
and returns Markdown.  Sentences that name a first CFA follow the decision
rule (:func:`cfa_mitsuba.study.decisions.decide`): "first" only for a rank
interval of exactly 1, otherwise the tied set.
"""

from __future__ import annotations

__all__ = ["GENERATORS", "rank_table", "rank_summary", "timing_sentence", "decisions_table_md", "spearman_sentence",
           "claims_sentence", "monotone_table", "low_light_table", "axis_table", "render_noise"]

import json
from pathlib import Path

from ..errors import CfaMitsubaError
from .low_light import _fmt, _levels


def _scores(repo: Path, results: str):
    import pandas as pd

    path = repo / results / "scores.csv"
    if not path.is_file():
        raise CfaMitsubaError(f"{results}/scores.csv not found")
    return pd.read_csv(path)


def _rank(best: int, worst: int) -> str:
    return f"{best}" if best == worst else f"{best}–{worst}"


def _names(names: list[str]) -> str:
    names = [f"`{n}`" for n in names]
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def rank_table(repo: Path, results: str) -> str:
    """Table 3 as Markdown: per CFA (sorted by total score) each demosaic's
    mean score ± half its 95 % interval with the rank interval, and the
    mean over methods."""
    s = _scores(repo, results)
    lum = sorted(s["luminance"].unique())[0]
    s = s[s["luminance"] == lum]
    demosaics = list(dict.fromkeys(s["demosaic"]))
    per = s.drop_duplicates(["cfa", "demosaic"]).set_index(["cfa", "demosaic"])
    tot = s.drop_duplicates("cfa").sort_values("total_score", ascending=False, kind="stable")
    head = ["rank", "CFA", *demosaics, "mean over methods"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in tot.itertuples(index=False):
        cells = [_rank(r.total_rank_best, r.total_rank_worst), f"`{r.cfa}`"]
        for d in demosaics:
            p = per.loc[(r.cfa, d)]
            half = (p.mean_score_ci_high - p.mean_score_ci_low) / 2
            cells.append(f"{p.mean_score:.3f} ±{half:.3f} ({_rank(p.demosaic_rank_best, p.demosaic_rank_worst)})")
        half = (r.total_score_ci_high - r.total_score_ci_low) / 2
        cells.append(f"**{r.total_score:.4f}** ±{half:.4f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def _first(group, score: str, best: str, worst: str) -> str:
    top = group[group[best] == 1].sort_values(score, ascending=False)
    if len(top) == 1 and int(top[worst].iloc[0]) == 1:
        return f"{_names(top['cfa'].tolist())} is first"
    ranks = ", ".join(f"{_rank(int(b), int(w))}" for b, w in zip(top[best], top[worst]))
    return f"{_names(top['cfa'].tolist())} tie for first (rank intervals {ranks})"


def rank_summary(repo: Path, results: str) -> str:
    """One sentence: who is first overall and with each demosaic, by the rule."""
    s = _scores(repo, results)
    lum = sorted(s["luminance"].unique())[0]
    s = s[s["luminance"] == lum]
    tot = s.drop_duplicates("cfa")
    parts = [_first(tot, "total_score", "total_rank_best", "total_rank_worst") + " overall"]
    per = s.drop_duplicates(["cfa", "demosaic"])
    for d, g in per.groupby("demosaic", sort=False):
        parts.append(_first(g, "mean_score", "demosaic_rank_best", "demosaic_rank_worst") + f" with {d}")
    return "; ".join(parts)


def timing_sentence(repo: Path, results: str) -> str:
    """The study's run time from its timing.json."""
    path = repo / results / "timing.json"
    if not path.is_file():
        raise CfaMitsubaError(f"{results}/timing.json not found")
    t = json.loads(path.read_text())
    p = t.get("phases") or {}
    renders = t.get("renders") or {}
    reused = sum(1 for r in renders.values() if r.get("reused"))
    parts = [f"{k[:-2]} {float(v):.1f} s" for k, v in p.items() if k.endswith("_s") and k != "total_s"]
    return (f"{float(p['total_s']):.1f} s in all ({', '.join(parts)}; {len(renders) - reused} scene render(s) made, "
            f"{reused} reused from the cache)")


def decisions_table_md(repo: Path, results: str) -> str:
    """decisions.csv of a results directory as a Markdown table."""
    import pandas as pd

    path = repo / results / "decisions.csv"
    if not path.is_file():
        raise CfaMitsubaError(f"{results}/decisions.csv not found")
    d = pd.read_csv(path, dtype=str, keep_default_na=False)
    lines = ["| aspect | CFA(s) that can rank first | verdict |", "|---|---|---|"]
    for r in d.itertuples(index=False):
        lines.append(f"| {r.aspect} | {_names(r.cfas.split()) if r.cfas else '—'} | {r.verdict} |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def spearman_sentence(repo: Path, results: str, demosaic: str = "bilinear") -> str:
    """The rank correlation of a run's Table 3 column with the paper's, with its 95 % interval."""
    from .claim_verdicts import spearman_interval
    from .paper_data import load_run, paper_values

    run = load_run(repo / results, "run", "run")
    pv = paper_values()
    pv = pv[(pv["metric"] == "score") & (pv["demosaic"] == demosaic)]
    paper = dict(zip(pv["cfa"], pv["number"]))
    got = run.scores_of(demosaic)
    both = [c for c in paper if c in got]
    rho, lo, hi, n = spearman_interval([paper[c] for c in both], [got[c][0] for c in both])
    return f"Spearman {rho:+.2f} (95 % interval {lo:+.2f} to {hi:+.2f}, {n} CFAs)"


def claims_sentence(repo: Path, results: str) -> str:
    """Which of the paper's claims hold, tie and differ in a run, by the rule of claim_verdicts."""
    from .paper_data import claims, judge, load_run

    run = load_run(repo / results, "run", "run")
    by: dict = {}
    for c in claims():
        if c["source"] == "paper":
            by.setdefault(judge(run, c)[0], []).append(c["id"])
    return "; ".join(f"{v}: {len(by[v])} ({', '.join(by[v])})" for v in ("holds", "tie", "differs", "not measured")
                     if v in by)


def design_table(repo: Path, results: str) -> str:
    """A design run's fullchain.csv as Markdown: each CFA's objectives with 95 % intervals and what dominates it."""
    import pandas as pd

    path = repo / results / "fullchain.csv"
    if not path.is_file():
        raise CfaMitsubaError(f"{results}/fullchain.csv not found")
    f = pd.read_csv(path, keep_default_na=False)
    objectives = [c for c in f.columns if "@" in c and not c.endswith((" low", " high", " n", " demosaic"))]
    head = ["CFA", "tile", *[o.replace("/bilinear", "").replace("/best", " (best demosaic)") for o in objectives],
            "dominated by"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in f.to_dict("records"):
        name = f"**{r['cfa']}**" if str(r["pareto"]) == "True" else r["cfa"]
        cells = [name, r["tile_text"]] + [f"{_fmt(r[o], '.4g')} [{_fmt(r[o + ' low'], '.4g')}, {_fmt(r[o + ' high'], '.4g')}]"
                                          for o in objectives]
        dom = r["dominated_by"] or ("— (Pareto)" if str(r["pareto"]) == "True" else "—")
        lines.append("| " + " | ".join([*cells, dom]) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def design_front(repo: Path, results: str) -> str:
    """How many candidates a design run put on the Pareto front, of how many run through the full chain."""
    import pandas as pd

    f = pd.read_csv(repo / results / "fullchain.csv", keep_default_na=False)
    cand = f[f["kind"] == "candidate"]
    n_front = int((cand["pareto"].astype(str) == "True").sum())
    named = f[f["kind"] == "named"]
    beaten = sorted({d for d in cand["dominated_by"] if d})
    return (f"{n_front} Pareto candidate(s) of {len(cand)} run through the full chain beside "
            f"{', '.join(named['cfa'])}" + (f"; candidates dominated by {', '.join(beaten)}" if beaten else ""))


def design_manufacturability(repo: Path, results: str) -> str:
    """A gradient design's chosen candidates (candidates.csv ``chosen`` best)
    as Markdown: per candidate its proxy values and, per free letter, the
    curve's largest change per 10 nm, peak and nearest measured curve."""
    import pandas as pd

    c = pd.read_csv(repo / results / "candidates.csv", keep_default_na=False)
    f = pd.read_csv(repo / results / "fullchain.csv", keep_default_na=False)
    names = dict(zip(f["key"], f["cfa"]))
    lines = ["| CFA | w | proxy ΔE00 | proxy noise | letter | curve | max change per 10 nm | peak | nearest measured "
             "curve (spectral angle) | nearest set (mean angle) |", "|" + "---|" * 10]
    for r in c[c["chosen"] == "best"].sort_values("proxy_rank").to_dict("records"):
        for a, v in json.loads(r["manufacturability"]).items():
            lines.append(f"| {names.get(r['key'], r['key'][:20])} | {r['weight']:g} | {r['gradient_colour']:.3f} | "
                         f"{r['gradient_noise']:.3g} | {a} | {v['curve']} | {v['max_slope_per_10nm']:.2f} | "
                         f"{v['peak']:.2f} | {v['nearest']} ({v['angle_deg']:.1f}°) | {r['nearest_set']} "
                         f"({float(r['nearest_set_angle_deg']):.1f}°) |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def league_table(repo: Path, results: str) -> str:
    """A league's league.csv (design/league.py) as Markdown: each (CFA, kept
    demosaic) with its aspects' means and 95 % intervals and the CFA's source."""
    import pandas as pd

    path = repo / results / "league.csv"
    if not path.is_file():
        raise CfaMitsubaError(f"{results}/league.csv not found (cfa-mitsuba league configs/league.toml --out {results})")
    f = pd.read_csv(path, keep_default_na=False)
    skip = ("cfa", "demosaic", "tile", "spectra", "source", "demosaic_kept")
    cols = [c for c in f.columns if c not in skip and not c.endswith((" low", " high", "_censored"))]
    head = ["CFA", "demosaic", *cols, "source"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in f.to_dict("records"):
        cells = [(f"{_fmt(r[c], '.3g')} [{_fmt(r[c + ' low'], '.3g')}, {_fmt(r[c + ' high'], '.3g')}]"
                  + (" (bound)" if str(r.get(c + "_censored", "")) == "True" else "")) if r[c] != "" else "—"
                 for c in cols]
        lines.append("| " + " | ".join([r["cfa"], r["demosaic"], *cells, str(r["source"]).replace("|", "/")]) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def league_decisions(repo: Path, results: str) -> str:
    """A league's league_decisions.csv as Markdown: per aspect the entries whose rank interval contains 1."""
    import pandas as pd

    f = pd.read_csv(repo / results / "league_decisions.csv", keep_default_na=False)
    lines = ["| aspect | league.csv column | entries whose rank interval contains 1 | verdict |", "|---|---|---|---|"]
    lines += [f"| {r['aspect']} | {r['metric']} | {', '.join(r['entries'].split()) or '—'} | {r['verdict']} |"
              for r in f.to_dict("records")]
    return "\n\n" + "\n".join(lines) + "\n\n"


def monotone_table(repo: Path, *texts: str) -> str:
    """The colour-matrix rule before and after (docs/isp.md), from the committed
    output of ``benchmarks/monotone_colour_matrix.py`` (one text file per
    exposure policy): per CFA and rule, S-CIELAB, SSIM and the matrix's
    condition number at each luminance."""
    lines = []
    for text in texts:
        path = repo / text
        if not path.is_file():
            raise CfaMitsubaError(f"{text} not found (run benchmarks/monotone_colour_matrix.py)")
        first, header, *rows = path.read_text().splitlines()
        policy = first.split(";")[0].removeprefix("policy ").strip()
        lums = [w.removeprefix("L=").rstrip(":") for w in header.split() if w.startswith("L=")]
        if not lines:
            head = ["policy", "CFA", "colour-matrix rule", *(f"S-CIELAB / SSIM / cond at {L} cd/m^2" for L in lums)]
            lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for row in rows:
            rule, cfa, *vals = row.split()
            rule = {"capture": "capture's own (before)", "sensor": "sensor's (after)"}.get(rule, rule)
            cells = [" / ".join(vals[3 * i:3 * i + 3]) for i in range(len(lums))]
            lines.append("| " + " | ".join([policy, f"`{cfa}`", rule, *cells]) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def low_light_table(repo: Path, folder: str) -> str:
    """docs/study.md's RGBW and CMY answer, from the committed small study
    under ``folder``/<protocol>/ (``docs/low-light/run.py`` writes it): per
    protocol, demosaic and CFA, SNR10 with its 95 % interval, the
    luminances at which the CFA is better or worse than Bayer on YSNR, chroma
    SNR and S-CIELAB (intervals apart; the rest are ties: the report's
    comparison, :func:`.low_light.versus_reference`), and its ΔE00 and MTF50
    at 100 cd/m^2 beside Bayer's (the cost in colour and sharpness)."""
    import pandas as pd

    from .low_light import versus_reference

    lines = ["| protocol | demosaic | CFA | SNR10 cd/m² (95 %) | YSNR better / worse at | chroma SNR better / worse at "
             "| S-CIELAB better / worse at | ΔE00 (Bayer) | MTF50 (Bayer) |", "|---|---|---|---|---|---|---|---|---|"]
    for policy in ("program", "bayer"):
        path = repo / folder / policy
        if not (path / "metrics.csv").is_file() or not (path / "snr10.csv").is_file():
            raise CfaMitsubaError(f"{folder}/{policy}/metrics.csv or snr10.csv not found (run docs/low-light/run.py)")
        m = pd.read_csv(path / "metrics.csv")
        s10 = pd.read_csv(path / "snr10.csv").set_index(["cfa", "demosaic"])
        for d in dict.fromkeys(m["demosaic"]):
            if ("bayer", d) in s10.index:
                r = s10.loc[("bayer", d)]
                lines.append(f"| {policy} | {d} | bayer | {_fmt(r.snr10_cd_m2, '.3g')} ({_fmt(r.ci_low, '.3g')}-{_fmt(r.ci_high, '.3g')}) "
                             "| | | | | |")
        for r in versus_reference(m):
            s = s10.loc[(r["cfa"], r["demosaic"])]
            cells = [f"{_levels(r[f'{k}_wins'], '—')} / {_levels(r[f'{k}_losses'], '—')}"
                     for k in ("ysnr", "chroma_snr", "scielab")]
            cost = [f"{_fmt(r[k][0], '.3g')} ({_fmt(r[k][1], '.3g')})" if k in r else "—" for k in ("delta-e", "mtf")]
            lines.append(f"| {policy} | {r['demosaic']} | {r['cfa']} | {_fmt(s.snr10_cd_m2, '.3g')} ({_fmt(s.ci_low, '.3g')}-"
                         f"{_fmt(s.ci_high, '.3g')}) | " + " | ".join(cells + cost) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def axis_table(repo: Path, results: str, axis: str, *scene_metrics: str) -> str:
    """A swept axis as a Markdown table from a study's metrics.csv: one row
    per ``SCENE:METRIC`` given, CFA and demosaic, one column per value of
    ``axis``; each cell the mean over the realisations with half its 95 %
    interval in brackets."""
    import pandas as pd

    path = repo / results / "metrics.csv"
    if not path.is_file():
        raise CfaMitsubaError(f"{results}/metrics.csv not found")
    m = pd.read_csv(path)
    if axis not in m.columns:
        raise CfaMitsubaError(f"{results}/metrics.csv has no column {axis!r}")
    values = sorted(m[axis].unique())
    lines = ["| CFA, demosaic | " + " | ".join(f"{axis} {v:g}" for v in values) + " |",
             "|---|" + "---|" * len(values)]
    for sm in scene_metrics:
        scene, metric = sm.split(":")
        rows = m[(m["scene"] == scene) & (m["metric"] == metric)]
        if rows.empty:
            raise CfaMitsubaError(f"{results}/metrics.csv has no {metric!r} rows on {scene!r}")
        unit = rows["unit"].iloc[0]
        unit = f" ({unit})" if isinstance(unit, str) and unit else ""
        for (cfa, dem), g in rows.groupby(["cfa", "demosaic"], sort=False):
            g = g.drop_duplicates(axis).set_index(axis)
            cells = [f"{g.loc[v, 'value']:.4g} ({(g.loc[v, 'ci_high'] - g.loc[v, 'ci_low']) / 2:.2g})"
                     if v in g.index else "—" for v in values]
            lines.append(f"| {cfa}, {dem}: {scene} {metric}{unit} | " + " | ".join(cells) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"
def render_noise(repo: Path, results: str, baseline: str | None = None) -> str:
    """Render noise's share of the intervals and its effect on the ranking (:mod:`.render_noise`)."""
    from .render_noise import render_noise_md

    return render_noise_md(repo, results, baseline)


#: {name: function(repo, *args) -> Markdown}
GENERATORS = {
    "rank-table": rank_table,
    "rank-summary": rank_summary,
    "timing": timing_sentence,
    "decisions": decisions_table_md,
    "spearman": spearman_sentence,
    "claims": claims_sentence,
    "design-table": design_table,
    "design-front": design_front,
    "league-table": league_table,
    "design-manufacturability": design_manufacturability,
    "league-decisions": league_decisions,
    "monotone-table": monotone_table,
    "low-light-table": low_light_table,
    "axis-table": axis_table,
    "render-noise": render_noise,
}


def _register_more() -> None:
    """Generators kept in modules of their own (one per page), under the same names space."""
    from .docs_tables_convergence import GENERATORS as convergence
    from .docs_tables_pages import GENERATORS as pages

    GENERATORS.update(convergence)
    GENERATORS.update(pages)


_register_more()
