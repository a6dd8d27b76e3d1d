"""The HTML page: one self-contained file (CSS inline, figures embedded as
data URIs, no script, no external fonts or links), so it opens offline and
can be mailed or archived on its own.

Figures of one section that come per demosaic (or per scene) sit in tabs
made of radio buttons and CSS alone; printing shows every tab.
"""

from __future__ import annotations

__all__ = ["render_page"]

import base64
import html
from pathlib import Path

from .._version import __version__
from .results import Results
from .style import cfa_styles, metric_display

#: Report sections in page order: (id, heading, paper figures, intro).
SECTIONS = (
    ("scores", "Scores and ranks", "Figs 16-17",
     "The eight metrics normalised to scores (eq. 8) and their means, as radar plots and rank charts."),
    ("colour", "Colour accuracy: ColorChecker", "Figs 8-9",
     "Where each patch lands in colour space, camera against the ideal sensor."),
    ("scielab", "Colour reproduction: S-CIELAB", "Fig 10",
     "Where in the image the colour errors are, after the eye's spatial filtering."),
    ("mtf", "Sharpness: slanted-edge MTF", "Figs 6, 11",
     "How contrast falls with spatial frequency, per colour channel."),
    ("moire", "Moiré: linear chirp", "Fig 13",
     "False colour on a black-and-white chirp and the frequency where it starts."),
    ("achromatic", "Achromatic reproduction: gray bar", "Fig 14",
     "Lightness along the gray bar and its error per step."),
    ("noise", "Noise per gray step and dynamic range", "ISO 15739",
     "The luminance SNR on each step of the gray bar, and the dynamic range read from it."),
    ("sweep", "Low light: metrics against luminance", "s. 3: S-CIELAB, SSIM at 3-400 cd/m²",
     "How the image metrics degrade as the scene gets darker."),
    ("processing", "With noise reduction: the processing settings compared", "beyond the paper",
     "The same captures through another processing setting (noise reduction, sharpening), beside the plain "
     "processing: the noise it removes, the texture it takes, the sharpness and colour it keeps, and how the "
     "low-light answer changes."),
    ("crops", "Crops: 1:1 and 4:1", "beyond the paper",
     "The same pixels of the chirp, the slanted edge and the puppy from every CFA and demosaicing method, at the "
     "sensor's pixels and magnified by nearest neighbour: where demosaicing artefacts can be judged."),
    ("outputs", "Camera outputs", "Figs 10, 12, 14 (images)",
     "The rendered sRGB images, every CFA and demosaicing method next to the ideal sensor."),
    ("sensor", "Sensors: spectra of the compared CFAs", "sensor_curves.csv",
     "Each CFA's channel quantum efficiencies as the study captured them."),
)

_CSS = """
:root{--ink:#1f2328;--muted:#59636e;--rule:#d0d7de;--soft:#f6f8fa;--accent:#4477AA;--best:#CC3311;--warn:#b35900}
*{box-sizing:border-box}
body{margin:0;font:14px/1.5 -apple-system,"Segoe UI",Helvetica,Arial,"DejaVu Sans",sans-serif;color:var(--ink);
background:#fff}
header{background:#24292f;color:#fff;padding:18px 28px}
header h1{margin:0;font-size:22px;font-weight:600}
header p{margin:4px 0 0;color:#d0d7de}
nav{position:sticky;top:0;z-index:5;background:#fff;border-bottom:1px solid var(--rule);padding:6px 28px;
font-size:13px;white-space:nowrap;overflow-x:auto}
nav a{color:var(--accent);text-decoration:none;margin-right:14px}
nav a:hover{text-decoration:underline}
main{padding:8px 28px 40px;max-width:1500px}
h2{font-size:19px;margin:34px 0 6px;padding-bottom:4px;border-bottom:1px solid var(--rule)}
h3{font-size:15px;margin:22px 0 6px}
.paper{color:var(--muted);font-weight:normal;font-size:13px}
p.intro,p.note,.caption{color:var(--muted)}
.caption{font-size:13px;max-width:1100px;margin:4px 0 16px}
.cards{display:flex;flex-wrap:wrap;gap:12px;margin:14px 0}
.card{border:1px solid var(--rule);border-radius:6px;padding:10px 14px;min-width:180px;background:var(--soft)}
.card .k{font-size:12px;color:var(--muted);text-transform:uppercase;letter-spacing:.03em}
.card .v{font-size:18px;font-weight:600}
.card .s{font-size:12px;color:var(--muted)}
dl.run{display:grid;grid-template-columns:max-content 1fr;gap:2px 14px;margin:8px 0}
dl.run dt{color:var(--muted)}dl.run dd{margin:0}
.tablewrap{overflow-x:auto;margin:6px 0 4px}
table.data.wraphead thead th{white-space:normal;max-width:190px}
table.data{border-collapse:collapse;font-size:12.5px;font-variant-numeric:tabular-nums}
table.data th,table.data td{border-bottom:1px solid #eaeef2;padding:3px 8px;text-align:right;white-space:nowrap}
table.data thead th{position:sticky;top:0;background:var(--soft);border-bottom:2px solid var(--rule);
text-align:center;font-weight:600}
table.data th.rowgroup,table.data th.metric,table.data td.scene{text-align:left;font-weight:600}
table.data th.metric,table.data td.scene{font-weight:normal}
table.data tr.group-start>*{border-top:2px solid var(--rule)}
table.data tr.total>*{border-top:2px solid #8c959f;font-weight:600}
table.data td.best{outline:2px solid var(--best);outline-offset:-2px;font-weight:700}
table.data td.besttie{outline:2px dashed var(--best);outline-offset:-2px}
table.data td.na{color:#aab}
table.data td.oor{color:var(--warn)}
table.data td.warn{color:var(--warn);font-weight:600}
table.data td.lum{text-align:right;color:var(--muted)}
.unit{color:var(--muted);font-size:11.5px}
.dir{color:var(--muted)}
.rank{color:var(--muted);font-size:11.5px}
.ci{color:var(--muted);font-size:11px}
td.tie .rank{font-style:italic;color:#aa3377}
.oor-mark{color:var(--warn)}
.swatch{display:inline-block;width:9px;height:9px;border-radius:2px;margin-right:4px;vertical-align:baseline}
figure{margin:10px 0 6px}
figure img{max-width:100%;height:auto;display:block;border:1px solid #eef0f2}
figure img.raster{image-rendering:auto}
figure img.pixels{image-rendering:pixelated;max-width:none}
.pixelwrap{overflow-x:auto}
.absent{border-left:4px solid var(--warn);background:#fff8f0;padding:6px 12px;margin:8px 0;font-size:13px}
.absent b{color:var(--warn)}
.tabs{margin:8px 0}
.tabs>input{position:absolute;opacity:0;pointer-events:none}
.tabs>label{display:inline-block;padding:4px 12px;margin:0 4px 0 0;border:1px solid var(--rule);
border-bottom:none;border-radius:6px 6px 0 0;background:var(--soft);cursor:pointer;font-size:13px}
.tabs>input:checked+label{background:#fff;font-weight:600;border-color:#8c959f;position:relative;top:1px}
.tabs>input:focus-visible+label{outline:2px solid var(--accent)}
.tabs>.panel{display:none;border-top:1px solid #8c959f;padding-top:6px}
/*TAB_RULES*/
details.more summary{cursor:pointer;color:var(--accent);margin:6px 0}
footer{color:var(--muted);font-size:12px;border-top:1px solid var(--rule);padding:10px 28px}
ul.tight{margin:4px 0;padding-left:20px}
code{background:var(--soft);padding:0 4px;border-radius:4px;font-size:12.5px}
@media print{nav{display:none}.tabs>.panel{display:block!important}.tabs>label{display:none}}
"""


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _tab_rules(n: int) -> str:
    return "\n".join(f".tabs>input:nth-of-type({k}):checked~.panel:nth-of-type({k}){{display:block}}"
                     for k in range(1, n + 1))


#: Display scale of vector figures: CSS px per figure inch (as the PNGs' dpi).
_SVG_PX_PER_INCH = 125


def _img(fig, data: bytes, mime: str) -> str:
    b64 = base64.b64encode(data).decode("ascii")
    klass = ' class="raster pixels"' if getattr(fig, "lossless", False) else ' class="raster"' if fig.raster else ""
    size = ""
    inches, pixels = fig.size_inches(), fig.size_pixels()
    if inches is not None and mime == "image/svg+xml":
        w_in, h_in = inches
        size = f' width="{round(w_in * _SVG_PX_PER_INCH)}" height="{round(h_in * _SVG_PX_PER_INCH)}"'
    elif pixels is not None:
        size = f' width="{pixels[0]}" height="{pixels[1]}"'
    return (f'<img{klass} src="data:{mime};base64,{b64}" alt="{_e(fig.title)}"{size} '
            f'data-figure="{_e(fig.key)}">')


def _figure_html(fig, data: bytes, mime: str, show_title: bool = True) -> str:
    img = _img(fig, data, mime)
    if getattr(fig, "lossless", False):  # at its own pixels: a narrow window scrolls it, never scales it
        img = f'<div class="pixelwrap">{img}</div>'
    return (f'<figure id="fig-{_e(fig.key)}">{img}'
            f'<figcaption class="caption">{_e(fig.caption)}</figcaption></figure>')


def _section_figures(sec: str, items: list, embeds: dict) -> str:
    """The figures of one section: plain when ungrouped, tabs when grouped."""
    out = []
    plain = [f for f in items if f.group is None]
    grouped = [f for f in items if f.group is not None]
    for f in plain:
        out.append(f"<h3>{_e(f.title)}</h3>")
        out.append(_figure_html(f, *embeds[f.key]))
    by_title: dict = {}
    for f in grouped:
        by_title.setdefault(f.title, []).append(f)
    for title, figs in by_title.items():
        out.append(f"<h3>{_e(title)}</h3>")
        if len(figs) == 1:
            out.append(f'<p class="note">{_e(figs[0].group)}</p>' if figs[0].section == "outputs" else "")
            out.append(_figure_html(figs[0], *embeds[figs[0].key]))
            continue
        name = f"tabs-{figs[0].key.split('-')[0]}-{sec}"
        tab = ['<div class="tabs">']
        for k, f in enumerate(figs):
            tid = f"{name}-{k}"
            checked = " checked" if k == 0 else ""
            tab.append(f'<input type="radio" name="{_e(name)}" id="{_e(tid)}"{checked}>'
                       f'<label for="{_e(tid)}">{_e(f.group)}</label>')
        for f in figs:
            tab.append(f'<div class="panel">{_figure_html(f, *embeds[f.key])}</div>')
        tab.append("</div>")
        out.append("".join(tab))
    return "".join(out)


def _summary(res: Results, facts: dict, not_run: list) -> str:
    cfg = res.config
    cst = cfa_styles(res.cfas)
    parts = []
    cards = []
    from .decision_panel import decision_panel, summary_cards, sweep_lines

    from .decision_panel import read_decisions

    parts.append(decision_panel(res.root, res.config))
    from .conditions import condition_lines

    lines = condition_lines(res.all_metrics if res.all_metrics is not None else res.metrics, res.cfa_facts, cfg)
    if lines:
        parts.append('<p class="note"><b>Conditions of these answers.</b> ' + " ".join(_e(x) for x in lines) + "</p>")
    for label, c, sub in summary_cards(res.scores, res.primary_luminance, res.demosaics, read_decisions(res.root)):
        cards.append((label, c, sub, cst.get(c, {}).get("color")))
    if cards:
        parts.append('<div class="cards">')
        for k, v, s, colour in cards:
            sw = f'<span class="swatch" style="background:{colour}"></span>' if colour else ""
            parts.append(f'<div class="card"><div class="k">{_e(k)}</div><div class="v">{sw}{_e(v)}</div>'
                         f'<div class="s">{_e(s)}</div></div>')
        parts.append("</div>")
    rows = []
    scenes = []
    for s in cfg.get("scenes") or []:
        if isinstance(s, dict):
            r = s.get("render") or {}
            size = f" {r['width']}×{r['height']}" if r.get("width") and r.get("height") else ""
            mets = ", ".join(metric_display(m).short for m in s.get("metrics") or [])
            src = f", {Path(str(s['file'])).name}" if s.get("file") else ""
            scenes.append(f"{s.get('name')}{size}{src} ({mets})" if mets else f"{s.get('name')}{size}{src}")
    if not scenes:
        scenes = res.scenes
    rows.append(("Scenes", "; ".join(scenes) or "none"))
    rows.append(("CFAs", f"{len(res.cfas)}: " + ", ".join(res.cfas)))
    if facts.get("spectra_note"):
        rows.append(("Spectra", facts["spectra_note"]))
    rows.append(("Demosaicing", f"{len(res.demosaics)}: " + ", ".join(res.demosaics)))
    lums = ", ".join(f"{v:g}" for v in res.base_luminances) or "—"
    rows.append(("Luminance", f"{lums} cd/m² (every metric)"))
    sweeps = sweep_lines(cfg, lambda m: metric_display(m).short)
    if sweeps:
        rows.append(("Sweeps", "; ".join(sweeps)))
    n_eval = len(res.metrics.drop_duplicates(["scene", "cfa", "demosaic", "luminance"])) if len(res.metrics) else 0
    rows.append(("Evaluations", f"{n_eval} (scene, CFA, demosaic, luminance) combinations, "
                 f"{len(res.metrics)} rows in metrics.csv"))
    if facts.get("timing"):
        rows.append(("Run time", facts["timing"]))
    if cfg.get("seed") is not None:
        rows.append(("Seed", str(cfg.get("seed"))))
    if cfg.get("clip_scores") is not None:
        rows.append(("Scores", "clipped to [0, 1]" if cfg.get("clip_scores") else
                     "not clipped (values outside a range score below 0 or above 1)"))
    parts.append('<dl class="run">' + "".join(f"<dt>{_e(k)}</dt><dd>{_e(v)}</dd>" for k, v in rows) + "</dl>")
    if not_run:
        rows_nr = "; ".join(a.reason for a in not_run)
        parts.append(f'<p class="note">Not in this study, so not in this report: {_e(rows_nr)}.</p>')
    if not len(res.metrics):
        parts.append('<div class="absent"><b>metrics.csv holds no measurements:</b> the study wrote no rows, '
                     "so there is nothing to report.</div>")
    if res.notes:
        parts.append('<ul class="tight">' + "".join(f'<li class="note">{_e(n)}</li>' for n in res.notes) + "</ul>")
    return "".join(parts)


def _conventions(res: Results) -> str:
    from .conventions import convention_items

    return '<ul class="tight">' + "".join(f"<li>{i}</li>" for i in convention_items(res)) + "</ul>"


def render_page(res: Results, *, figures: list, absents: list, embeds: dict, tables: dict, facts: dict) -> str:
    """The whole report as one HTML string.

    ``figures``: ReportFigure list; ``embeds``: {key: (bytes, mime)};
    ``absents``: Absent list; ``tables``: {'table1': html|None, ...};
    ``facts``: summary numbers (best CFAs, timing text, luminances).
    """
    title = f"CFA image-quality report: {res.name}"
    desc = res.config.get("description") or ""
    nav = [("summary", "Summary"), ("tables", "Tables 1-3"), ("ranges", "Score ranges")]
    body = []
    # a section the study did not run at all is named once in the summary, not shown empty
    by_sec: dict = {}
    for a in absents:
        by_sec.setdefault(a.section, []).append(a)
    skipped = {sec for sec, items in by_sec.items()
               if all(a.not_in_study for a in items) and not any(f.section == sec for f in figures)}
    not_run = [items[0] for sec, items in by_sec.items() if sec in skipped]
    absents = [a for a in absents if a.section not in skipped]
    body.append(f'<section id="summary"><h2>Summary</h2>{_summary(res, facts, not_run)}</section>')

    body.append(_tables_section(res, tables))
    body.append(_ranges_section(res, tables, facts))
    n_tabs = _figure_sections(body, nav, figures, absents, embeds, tables)
    nav.append(("conventions", "Units"))
    body.append(f'<section id="conventions"><h2>Units and conventions</h2>{_conventions(res)}</section>')

    nav_html = "".join(f'<a href="#{k}">{_e(v)}</a>' for k, v in nav)
    css = _CSS.replace("/*TAB_RULES*/", _tab_rules(n_tabs))
    sub = _e(desc) if desc else "Bae 2020 (PLoS ONE 15(5): e0232583) image-quality metric system, re-created"
    return (
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
        f"<title>{_e(title)}</title><style>{css}</style></head><body>"
        f"<header><h1>{_e(title)}</h1><p>{sub}</p></header>"
        f"<nav>{nav_html}</nav><main>{''.join(body)}</main>"
        f"<footer>cfa-mitsuba {_e(__version__)} · built from <code>{_e(res.root.name)}/</code> "
        "(metrics.csv, scores.csv, details/) · metric system of Bae 2020, PLoS ONE 15(5): e0232583"
        "</footer></body></html>\n"
    )


def _tables_section(res: Results, tables: dict) -> str:
    """Tables 1-3 and the unscored and sweep tables."""
    from .decision_panel import intervals_cover

    t = ['<section id="tables"><h2>Tables</h2>']
    lum = res.primary_luminance
    t.append('<h3 id="table1">Table 1. Mean colour error over the 24 patches and lightness error of the 6 grey '
             'patches <span class="paper">(paper Table 1)</span></h3>')
    if tables.get("table1"):
        t.append(f'<div class="tablewrap">{tables["table1"]}</div>')
        t.append(f'<p class="note">ColorChecker at {lum:g} cd/m². Each value ± half its 95 % interval over the noise '
                 "realisations. Boxed: the lowest value in the row when its interval overlaps no other's; dashed: "
                 "the lowest value, tied within the intervals.</p>")
    else:
        t.append('<div class="absent"><b>Not available:</b> no ColorChecker (macbeth) scene in this study.</div>')
    for L, tab in tables.get("table2", []):
        sfx = f" at {L:g} cd/m²" if len(tables.get("table2", [])) > 1 else ""
        t.append(f'<h3 id="table2">Table 2. Every metric per CFA and demosaicing method{_e(sfx)} '
                 '<span class="paper">(paper Table 2)</span></h3>')
        if tab:
            t.append(f'<div class="tablewrap">{tab}</div>')
            t.append('<p class="note">Boxed: the best value of the metric for the demosaic (the paper\'s red '
                     "boxes) when its paired difference with every other CFA is separated (rank interval exactly 1); "
                     "dashed: the best value, but tied with another CFA. Each value ± half its 95 % interval. ↑ higher / "
                     "↓ lower is better; † outside the metric's score range (see below); ≥ an MSP where no moiré was "
                     "found up to the chirp's top frequency in any realisation; k/n≥ a value whose realisations "
                     "include k such bounds (their median, a measurement). Hover a cell for its score and rank.</p>")
    if not tables.get("table2"):
        t.append('<div class="absent"><b>Not available:</b> nothing was scored.</div>')
    for L, tab in tables.get("table3", []):
        sfx = f" at {L:g} cd/m²" if len(tables.get("table3", [])) > 1 else ""
        t.append(f'<h3 id="table3">Table 3. Mean normalised score and rank{_e(sfx)} '
                 '<span class="paper">(paper Table 3, Fig 17)</span></h3>')
        if tab:
            t.append(f'<div class="tablewrap">{tab}</div>')
            t.append('<p class="note">Each cell: the mean of the CFA\'s normalised metric scores for that method, '
                     "± half its 95 % interval over the noise realisations, and its rank in brackets (1 = best); "
                     "a range such as (1–3) is a rank interval: CFAs whose paired score difference interval contains 0 "
                     "are tied, and a tie is not a ranking. 'Total' is the mean over the methods; rows are sorted by "
                     "it. Boxed: the winner decisions.csv names (rank interval exactly 1 and a lead of at least the "
                     "practical difference; see the decisions above). Shading follows the "
                     f"score. {_e(intervals_cover(res.config))}</p>")
    if not tables.get("table3"):
        t.append('<div class="absent"><b>Not available:</b> nothing was scored.</div>')
    if tables.get("other"):
        t.append('<details class="more"><summary>Measurements reported but not scored (ΔE*ab, grey ΔL, '
                 "interior S-CIELAB)</summary>")
        t.append(f'<div class="tablewrap">{tables["other"]}</div></details>')
    if tables.get("moire_thresholds"):
        t.append('<details class="more"><summary>Moiré starting point at C*ab thresholds 20, 25 and 30 (how much '
                 "the MSP ranking turns on the paper's threshold)</summary>")
        t.append(f'<div class="tablewrap">{tables["moire_thresholds"]}</div><p class="note">From each camera\'s '
                 "block-mean chroma curve (first noise realisation), by the metric's own rule; ≥: no moiré up to "
                 "the chirp's top frequency (a bound); shaded rows move by more than 10 % between 20 and 30.</p>"
                 "</details>")
    if tables.get("sweep"):
        t.append('<details class="more"><summary>The luminance sweep\'s values</summary>')
        t.append(f'<div class="tablewrap">{tables["sweep"]}</div></details>')
    if tables.get("low_light"):  # issue 22: SNR10, exposure and gains, electrons, spectra sets
        t.append('<details class="more" open><summary>Low light: SNR10, exposure, gain, electrons, spectra sets'
                 f'</summary><div class="tablewrap">{tables["low_light"]}</div></details>')
    t.append("</section>")
    return "".join(t)


def _ranges_section(res: Results, tables: dict, facts: dict) -> str:
    """The score ranges, the policies compared, the values outside their range."""
    policy_text = {
        "paper": "the paper's printed ranges, with the MSP range moved to true cycles per degree for this "
                 "study's chirp and the MTF50 range to its pixel pitch",
        "study": "fitted to the compared set: each metric's worst and best mean value over the CFAs and methods",
        "ideal": "anchored on the ideal sensor: its own value scores 1 (an MTF50 past the ideal's, overshoot from "
                 "sharpening, is clipped at 1, not rewarded) and the worst CFA's value scores 0",
    }.get(res.range_policy or "paper", "")
    r = ['<section id="ranges"><h2>Score ranges</h2>',
         '<p class="intro">Eq. 8 maps each metric linearly from its range\'s worst end (score 0) to its best '
         f"end (score 1). Range policy <b>{_e(res.range_policy or 'paper')}</b>: {_e(policy_text)} (ranges.json). "
         "A value outside its range means the range does not span the CFAs compared; such scores are "
         + ("clipped to [0, 1]" if res.config.get("clip_scores", True) else "left unclipped in this study")
         + ".</p>"]
    if res.constant_metrics:
        r.append('<p class="note warn">Not scored, because every CFA gave the same value (a metric that cannot '
                 "tell the candidates apart is shown as such, not scored as a tie): "
                 + ", ".join(_e(m) for m in res.constant_metrics) + ".</p>")
    if tables.get("ranges"):
        r.append(f'<div class="tablewrap">{tables["ranges"]}</div>')
    if tables.get("policies"):
        r.append('<h3>The three range policies side by side</h3><p class="note">Per metric, how many scores '
                 "each policy clips (or that the metric is constant across the CFAs), then each CFA's overall "
                 "rank and score under each policy (policies.csv): how much of the ranking is the choice of "
                 "ranges.</p>")
        r.append(f'<div class="tablewrap">{tables["policies"]}</div>')
    if facts.get("oor_lines"):
        r.append('<p class="note">Values outside their range:</p><ul class="tight">'
                 + "".join(f"<li>{_e(x)}</li>" for x in facts["oor_lines"]) + "</ul>")
    r.append("</section>")
    return "".join(r)


def _figure_sections(body: list, nav: list, figures: list, absents: list, embeds: dict,
                     tables: dict | None = None) -> int:
    """One section per figure group (appended to ``body`` and ``nav``), with
    the section's own tables (``tables['section:<id>']``, HTML) after its
    figures; returns the most tabs a figure group needs."""
    n_tabs = 1
    for sec, heading, paper, intro in SECTIONS:
        items = [f for f in figures if f.section == sec]
        missing = [a for a in absents if a.section == sec]
        extra = (tables or {}).get(f"section:{sec}")
        if not items and not missing and not extra:
            continue
        nav.append((sec, heading.split(":")[0]))
        s = [f'<section id="{sec}"><h2>{_e(heading)} <span class="paper">({_e(paper)})</span></h2>',
             f'<p class="intro">{_e(intro)}</p>']
        for a in missing:
            s.append(f'<div class="absent"><b>{_e(a.title)}: not drawn.</b> {_e(a.reason)}</div>')
        s.append(_section_figures(sec, items, embeds))
        if extra:
            s.append(extra)
        groups: dict = {}
        for f in items:
            if f.group is not None:
                groups.setdefault(f.title, 0)
                groups[f.title] += 1
        n_tabs = max([n_tabs] + list(groups.values()))
        s.append("</section>")
        body.append("".join(s))
    return n_tabs
