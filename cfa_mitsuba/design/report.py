"""design.html: the Pareto front against the named CFAs, the proxy space,
the proxy's agreement with the full chain, a card (tile in colour, QE
curves) per Pareto candidate, and the side-by-side of Bayer, the best
named CFA and the best candidates with their camera outputs.  Figures are
written under ``figures/`` (PNG) and linked from the page."""

from __future__ import annotations

__all__ = ["build_design_report", "headline"]

import html
from pathlib import Path

import numpy as np

from ..io import atomic_output
from ..report.figure import RC, figure_bytes
from . import figures as F

_CSS = """body{font:14px/1.5 'DejaVu Sans',Helvetica,Arial,sans-serif;color:#1f2328;margin:0 28px 40px;max-width:1400px}
h1{font-size:22px}h2{font-size:18px;border-bottom:1px solid #d0d7de;margin-top:30px}
table{border-collapse:collapse;font-size:12px;margin:8px 0}td,th{border:1px solid #d0d7de;padding:3px 7px;
text-align:right}th{background:#f6f8fa}td.l{text-align:left;font-family:monospace}
.note{color:#59636e}.side{display:flex;flex-wrap:wrap;gap:14px}.side div{border:1px solid #d0d7de;padding:6px}
tr.front td{background:#fff4e5}img{max-width:100%}
.answer{font-size:15px;border-left:4px solid #CC3311;padding:6px 10px;background:#fff8f5}"""


def _save(out: Path, key: str, fig) -> str:
    import matplotlib as mpl

    with mpl.rc_context(RC):
        data = figure_bytes(fig, "png")
    path = out / "figures" / f"{key}.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(path) as tmp:
        tmp.write_bytes(data)
    return f"figures/{key}.png"


def _e(x) -> str:
    return html.escape(str(x))


def _fmt(v, lo, hi) -> str:
    if not np.isfinite(v):
        return "—"
    return f"{v:.4g} <span class=note>[{lo:.4g}, {hi:.4g}]</span>"


def _values_table(table, objectives, constraints) -> str:
    cols = [*objectives, *constraints]
    head = "".join(f"<th>{_e(getattr(o, 'title', o.label))}{' (constraint)' if o in constraints else ''}</th>"
                   for o in cols)
    rows = []
    order = table.sort_values(["kind", "score"], ascending=[False, False])
    for _, r in order.iterrows():
        cls = " class=front" if r["pareto"] else ""
        cells = "".join(f"<td>{_fmt(r[o.label], r[f'{o.label} low'], r[f'{o.label} high'])}</td>" for o in cols)
        rows.append(f"<tr{cls}><td class=l>{_e(r['cfa'])}</td><td>{_e(r['kind'])}</td><td class=l>"
                    f"{_e(r['tile_text'])}</td>{cells}<td>{r['score']:.3f}</td><td class=l>"
                    f"{_e(r['dominated_by'] or ('Pareto' if r['pareto'] else ''))}</td></tr>")
    return (f"<table><tr><th>CFA</th><th>kind</th><th>tile</th>{head}<th>score</th><th>dominated by</th></tr>"
            + "".join(rows) + "</table>")


def _thumb(study_dir: Path, out: Path, config, label: str) -> str:
    """The camera output of ``label`` on the first natural scene (or the first
    scene) at the first objective's luminance and demosaic, if the study kept it."""
    from ..study.details_layout import output_folder

    o = config.objectives[0]
    scenes = [s.name for s in config.study.scenes if "ssim" in s.metrics] or [o.scene]
    demosaic = config.study.demosaics[0] if o.demosaic == "best" else o.demosaic
    p = output_folder(study_dir / "details", scenes[0], label, demosaic) / f"L{o.luminance:g}.png"
    if not p.exists():
        return ""
    return f"<br><img src='{_e(p.relative_to(out))}' style='width:300px' alt='camera output'>"


def _vals(r, objectives) -> str:
    return "; ".join(f"{_e(getattr(o, 'title', o.label))} {_fmt(r[o.label], r[f'{o.label} low'], r[f'{o.label} high'])}"
                     for o in objectives)


def _better(a, b, o) -> bool:
    """a's interval wholly on the better side of b's on objective o."""
    return bool(a[f"{o.label} high"] < b[f"{o.label} low"]) if o.goal == "min" else \
        bool(a[f"{o.label} low"] > b[f"{o.label} high"])


def _versus(row, ref_row, ref_name, objectives) -> str:
    """Where ``row`` is better and worse than ``ref_row`` with separated intervals."""
    if ref_row is None:
        return ""
    wins = [getattr(o, "title", o.label) for o in objectives if _better(row, ref_row, o)]
    losses = [getattr(o, "title", o.label) for o in objectives if _better(ref_row, row, o)]
    return (f" Against {ref_name}, intervals separated: better on {_e(', '.join(wins) or 'none')}; worse on "
            f"{_e(', '.join(losses) or 'none')}.")


def headline(table, objectives) -> str:
    """The answer first: whether any candidate beat the named CFAs, with numbers."""
    named = table[table["kind"] == "named"]
    cand = table[table["kind"] == "candidate"]
    pareto = table[table["pareto"]].sort_values("score", ascending=False)
    ref = named[named["cfa"] == "bayer"]
    ref_name = "Bayer" if len(ref) else "the best named CFA"
    ref_row = ref.iloc[0] if len(ref) else (named.sort_values("score", ascending=False).iloc[0] if len(named) else None)
    ref_txt = "" if ref_row is None else f" {_e(ref_row['cfa'])}: {_vals(ref_row, objectives)}."
    if pareto.empty:
        by = sorted({str(d) for d in cand["dominated_by"] if str(d) and str(d) != "nan"})
        named_by = [d for d in by if d in set(named["cfa"])]
        who = "Bayer" if named_by == ["bayer"] and len(ref) else "the named CFAs"
        best = cand.sort_values("score", ascending=False).iloc[0] if len(cand) else None
        best_txt = ""
        if best is not None:
            best_txt = (f" The best candidate by full-chain score, {_e(best['cfa'])} ({_e(best['tile_text'])}): "
                        f"{_vals(best, objectives)}.{_versus(best, ref_row, ref_name, objectives)}")
            dom = table[table["cfa"] == best["dominated_by"]]
            if len(dom) and dom.iloc[0]["cfa"] != (None if ref_row is None else ref_row["cfa"]):
                best_txt += f" It is dominated by {_e(dom.iloc[0]['cfa'])}: {_vals(dom.iloc[0], objectives)}."
        return (f"<p class=answer><b>Nothing beat {who}</b>: every one of the {len(cand)} candidates run through "
                f"the full chain is dominated within 95 % intervals (by {_e(', '.join(by))}).{ref_txt}"
                f"{best_txt}</p>")
    top = pareto.iloc[0]
    return (f"<p class=answer><b>{len(pareto)} candidate(s) on the front</b> (no evaluated CFA dominates them "
            f"within 95 % intervals). Best by full-chain score: {_e(top['cfa'])} ({_e(top['tile_text'])}): "
            f"{_vals(top, objectives)}.{ref_txt}{_versus(top, ref_row, ref_name, objectives)}</p>")


def _agreement_html(agree) -> str:
    per = agree.get("per_objective", {})
    ci = agree.get("per_objective_interval", {})
    sep = agree.get("separating", {})
    items = []
    for k, v in per.items():
        c = ci.get(k)
        txt = "n/a" if v is None else f"{v:+.2f}" + (f" [{c[0]:+.2f}, {c[1]:+.2f}]" if c else "")
        if not sep.get(k, True):
            txt += " (the candidates' values differ by less than their intervals: no order to predict)"
        items.append(f"<li>{_e(k)}: {txt}</li>")
    target = agree.get("target")
    met = agree.get("meets_target")
    verdict = "" if target is None else (f"<p>Target: at least {target:+.2f} on every objective that separates the "
                                         f"candidates: <b>{'met' if met else 'not met'}</b>.</p>")
    return (f"<p>{_e(F.agreement_text(agree))} (combined scores; +1: the proxy orders the candidates as the full "
            f"chain does); per objective, with 95 % intervals:</p><ul>{''.join(items)}</ul>{verdict}")


def _proxy_axes(objectives) -> tuple:
    """The proxies the objectives use, the non-noise ones first."""
    used = list(dict.fromkeys(p for o in objectives for p in o.proxies if p != "colour"))
    return tuple(sorted(used, key=lambda p: p in ("noise", "noise_area", "snr10", "snr10_area")))


def build_design_report(out: Path, config, cands, table, agree, named_proxies, study_dir) -> Path:
    """Write ``out/design.html`` and its figures; returns the page's path."""
    from ..sensor import get_cfa

    objectives, constraints = list(config.objectives), list(config.constraints)
    figs = {
        "front": _save(out, "front", F.front_figure(table, objectives)),
        "proxy": _save(out, "proxy", F.proxy_figure(cands, named_proxies, _proxy_axes(objectives))),
        "agreement": _save(out, "agreement", F.agreement_figure(table, agree)),
    }
    named = table[table["kind"] == "named"].sort_values("score", ascending=False)
    pareto = table[table["pareto"]].sort_values("score", ascending=False)
    side = []
    show = []
    if "bayer" in set(named["cfa"]):
        show.append(("bayer", get_cfa("bayer")))
    best_named = next((c for c in named["cfa"] if c != "bayer"), None)
    if best_named is not None:
        spec = next(c for c in config.study.cfas if get_cfa(c).name == best_named)
        show.append((f"best named: {best_named}", get_cfa(spec)))
    for _, r in pareto.head(4).iterrows():
        show.append((r["cfa"], get_cfa(str(Path(out) / r["toml"]))))  # recorded relative to the output folder
    for title, cfa in show:
        key = "card-" + "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in cfa.name)
        src = _save(out, key, F.card_figure(cfa, title))
        row = table[table["cfa"] == cfa.name]
        vals = ""
        if len(row):
            r = row.iloc[0]
            vals = "<br>".join(f"{_e(getattr(o, 'title', o.label))}: "
                               f"{_fmt(r[o.label], r[f'{o.label} low'], r[f'{o.label} high'])}" for o in objectives)
        side.append(f"<div><img src='{src}' style='width:460px'><br><b>{_e(title)}</b> "
                    f"<span class=note>{_e(cfa.tile_text())}</span><br>{vals}"
                    f"{_thumb(Path(study_dir), out, config, cfa.name)}</div>")
    agree_txt = _agreement_html(agree)
    grad_txt = ""
    if getattr(config, "method", "search") == "gradient":
        from .gradient_report import gradient_html

        grad_txt = gradient_html(config, cands, table, lambda key, fig: _save(out, key, fig))
    n_best = int((cands["chosen"] == "best").sum())
    page = f"""<!doctype html><html><head><meta charset=utf-8><title>design {_e(config.name)}</title>
<style>{_CSS}</style></head><body>
<h1>CFA design: {_e(config.name)}</h1><p class=note>{_e(config.description)}</p>
{headline(table, objectives)}
<p>{len(cands):,} candidate layouts ({', '.join(f'{h}x{w} by {config.engine[(h, w)]}' for h, w in config.tiles)};
alphabet {' '.join(config.alphabet)}, spectra {_e(config.spectra_set)}{'; ' + _e(config.spectra.family) + ' filters for '
 + ' '.join(config.spectra.letters) if config.spectra else ''}) ranked by the proxy; the {n_best} best and
{int((cands['chosen'] == 'sample').sum())} sampled ones through the full chain with {', '.join(map(_e, named['cfa']))},
{config.study.seeds} noise realisations each (95 % intervals). <b>{len(pareto)}</b> Pareto candidate(s).</p>
<h2>Pareto front against the named CFAs</h2><img src='{figs['front']}'>
<p class=note>A CFA is dominated when another CFA's interval is wholly better on one objective and wholly worse
on none; the front is the feasible candidates nobody dominates so.</p>
{_values_table(table, objectives, constraints)}
{grad_txt}
<h2>Side by side: Bayer, the best named CFA, the best Pareto candidates</h2><div class=side>{''.join(side)}</div>
<h2>The proxy</h2><img src='{figs['proxy']}' style='width:640px'>
<h2>Proxy against full chain</h2>{agree_txt}<img src='{figs['agreement']}' style='width:460px'>
<p class=note>Files: candidates.csv, fullchain.csv, pareto.csv, cfas/*.toml, agreement.json, study/.</p>
</body></html>"""
    path = out / "design.html"
    with atomic_output(path) as tmp:
        tmp.write_text(page)
    return path
