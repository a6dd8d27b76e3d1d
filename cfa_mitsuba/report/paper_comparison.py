"""docs/paper-comparison.md: the paper, ISETCam and our two runs side by side.

    python -m cfa_mitsuba.report.paper_comparison \\
        --default results/paper --isetcam results/paper-isetcam --out docs/paper-comparison.md

``--default`` is a run of configs/paper.toml (our defaults), ``--isetcam``
one of configs/paper-isetcam.toml (the paper's procedure as ISETCam does
it); either may be left out.  For every metric and for Table 3 the page
gives the paper's value (``data/paper/bae2020_values.csv``, with the table
and row it comes from), ISETCam's where known (``isetcam_paper_check.csv``),
ours with its 95 % interval, and the verdict on each of the paper's claims
(``claims.toml``; :mod:`.paper_data` says how a verdict is reached).

It lives in the report stage, not in benchmarks/, because it is a report
of study results: it reads the tables a study writes, ships its paper data
with the package, and is tested like the rest of the report.
"""

from __future__ import annotations

__all__ = ["SECTIONS", "comparison_markdown", "write_comparison", "main"]

import argparse
import sys
from pathlib import Path


from ..errors import CfaMitsubaError
from ..metrics import get_metric
from .claim_facts import explanation
from .claim_verdicts import spearman_interval
from .paper_data import Run, cfa_label, claims, isetcam_values, judge, load_run, paper_values

#: (paper metric, heading, our metrics shown beside it), in the paper's order.
SECTIONS = (
    ("delta-e76", "Colour error on the Macbeth chart, mean dE (Table 1, Fig 8)", ("delta-e76", "delta-e")),
    ("delta-l", "Grey-patch lightness error, mean dL (Table 1)", ("delta-l",)),
    ("scielab", "S-CIELAB on the puppy (Fig 10)", ("scielab",)),
    ("ssim", "SSIM on the puppy (Fig 10)", ("ssim",)),
    ("mtf", "MTF50 of the slanted edge (Fig 11)", ("mtf",)),
    ("moire", "Moire starting point on the chirp (Figs 12-13)", ("moire",)),
    ("achromatic", "Achromatic reproduction error on the gray bar (Fig 14)", ("achromatic",)),
    ("mdsi", "MDSI on the puppy (Fig 15)", ("mdsi",)),
    ("haarpsi", "HaarPSI on the puppy (Fig 15)", ("haarpsi",)),
)
CFAS = ("bayer", "rgb1", "rgb2", "rgb3", "rgb4", "rgb5", "cmy1", "cmy2", "cmy3", "rgbw1", "rgbw2", "rgbw3")
DEMOSAICS = ("bilinear", "laplacian", "adaptive-laplacian", "pocs", "total")
_MARK = {"holds": "**holds**", "differs": "**differs**", "tie": "tie", "not measured": "not measured"}


def _table(header, rows) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return out + [""]


def _ours(run: Run, metric: str, cfa: str, demosaic: str = "bilinear") -> str:
    v = run.value(metric, demosaic, cfa)
    if v is None:
        return "-"
    d = get_metric(metric).decimals
    row = run.row(metric, demosaic, cfa)
    if run.is_bound(metric, demosaic, cfa):
        return f">= {v[0]:.{d}f} (no moire up to the chirp's top in any realisation)"
    k = int(row["censored_count"]) if row is not None and "censored_count" in row else 0
    some = f" ({k} of {int(row['n'])} realisations bounds: their median)" if k else ""
    return f"{v[0]:.{d}f} [{v[1]:.{d}f}, {v[2]:.{d}f}]{some}"


def _paper_cell(rows, cfa: str) -> str:
    for _, r in rows.iterrows():
        if cfa not in r["cfas"]:
            continue
        if r["status"] == "range":
            return f"{r['low']}-{r['high']} (range)"
        mark = " (derived)" if r["status"] == "derived" else " (group mean)" if r["status"] == "mean" else ""
        return f"{r['value']}{mark}"
    return "-"


def _isetcam_cell(iset, metrics, cfa: str) -> str:
    got = []
    for m in metrics:
        sel = iset[(iset["cfa"] == cfa) & (iset["metric"] == m) & (iset["noise"] == "on")]
        if len(sel):
            got.append(f"{sel['value'].iloc[0]} ({get_metric(m).unit if m != 'delta-e76' else 'dE76'})")
    return " / ".join(got) or "-"


def _run_columns(run: Run, metrics) -> list[str]:
    """The metrics worth a column for this run: each shown once (the isetcam
    run's delta-e is already dE76, the same numbers as delta-e76)."""
    cols, seen = [], []
    for m in metrics:
        vals = tuple(run.value(m, "bilinear", c) for c in CFAS)
        key = tuple(None if v is None else round(v[0], 9) for v in vals)
        if all(v is None for v in vals) or key in seen:
            continue
        seen.append(key)
        cols.append(m)
    return cols


def _claim_lines(claim: dict, runs) -> list[str]:
    out = [f"*Claim* ({'the paper' if claim['source'] == 'paper' else 'ISETCam'}): {claim['text']}", ""]
    for run in runs:
        verdict, detail = judge(run, claim)
        why = explanation(run, claim, verdict)
        out.append(f"- {run.label}: {_MARK[verdict]}. Measured: {detail}." + (f" Why: {why}" if why else ""))
    return out + [""]


def _section(paper_metric: str, heading: str, metrics, runs, paper, iset) -> list[str]:
    rows = paper[paper["metric"] == paper_metric]
    out = [f"## {heading}", ""]
    unit = next((u for u in rows["unit"] if u), "")
    out += [f"The paper's values (bilinear{', ' + unit if unit else ''}) from: "
            f"{', '.join(dict.fromkeys(rows['source']))}.", ""]
    iset_metrics = [m for m in metrics if m in set(iset["metric"])]
    header = ["CFA", "paper"] + (["ISETCam (noise on)"] if iset_metrics else [])
    cols = []
    for run in runs:
        for m in _run_columns(run, metrics):
            u = next((v[3] for c in CFAS if (v := run.value(m, "bilinear", c))), "")
            header.append(f"{run.label}: {get_metric(m).label}" + (f" ({u})" if u else ""))
            cols.append((run, m))
    table = []
    for cfa in CFAS:
        row = [cfa_label(cfa), _paper_cell(rows, cfa)]
        if iset_metrics:
            row.append(_isetcam_cell(iset, iset_metrics, cfa))
        row += [_ours(run, m, cfa) for run, m in cols]
        table.append(row)
    out += _table(header, table)
    notes = [f"- {', '.join(cfa_label(c) for c in r['cfas'])} ({r['source']}): {r['note']}"
             for _, r in rows.iterrows() if r["note"]]
    if notes:
        out += ["Notes on the paper's values:", ""] + notes + [""]
    for claim in claims():
        if claim["metric"] in metrics and claim["kind"] != "best":
            out += _claim_lines(claim, runs)
    return out


def _fit_only(iset, runs) -> list[str]:
    """The colour fit alone (no optics, mosaic or noise) against ISETCam's:
    a check of the *-raw filter sets and the MCC fit that needs no render,
    read from the ISETCam-procedure run's cfas.json (study/cfa_facts.py)."""
    facts = next((run.cfa_facts for run in runs if run.key == "isetcam" and run.cfa_facts), {})
    rows = []
    for cfa in ("rgbw1", "cmy1", "bayer"):
        f = facts.get(cfa, {})
        sel = iset[(iset["cfa"] == cfa) & (iset["metric"] == "fit-only-e76")]
        ours = f"{f['mcc_fit_de76']:.2f}" if "mcc_fit_de76" in f else "-"
        rows.append((cfa_label(cfa), f.get("spectra", "-"), sel["value"].iloc[0] if len(sel) else "-", ours))
    return (["The colour fit alone, without optics, mosaic or noise (the MCC's responses under D65 -> "
             "least-squares matrix on the same 24 patches -> XYZ, mean dE*ab against the chart): "
             "a check of the `*-raw` filter sets and the MCC fit that needs no render. "
             "Ours uses colour-science's ColorChecker (N Ohta) and 10-nm box means, ISETCam its "
             "`macbethChart.mat` and point samples.", ""]
            + _table(["CFA", "spectra set", "ISETCam", "ours"], rows))


def _table3(runs, paper) -> list[str]:
    out = ["## Table 3: mean normalised score per demosaic", "",
           "The paper's scores use its eq. 8 ranges on its own values; ours use each run's range policy "
           "(the defaults: anchored on the ideal sensor; the ISETCam-procedure run: the paper's ranges), so "
           "compare ranks, not levels. Rank intervals: the ranks each CFA can take within the 95 % intervals "
           "of the scores. A derived paper cell is the winner's cell the text extraction lost, computed from "
           "the margins the text gives (data/paper/bae2020_values.csv).", ""]
    rows = paper[paper["metric"] == "score"]
    for demosaic in DEMOSAICS:
        sel = rows[rows["demosaic"] == demosaic]
        pv = {r["cfa"]: (r["number"], r["status"]) for _, r in sel.iterrows()}
        prank = {c: 1 + sum(v[0] > pv[c][0] for v in pv.values()) for c in pv}
        ours = [run.scores_of(demosaic) for run in runs]
        header = ["CFA", "paper (rank)"] + [f"{run.label} (rank, interval)" for run in runs]
        table = []
        for cfa in CFAS:
            row = [cfa_label(cfa)]
            row.append(f"{pv[cfa][0]:.4f}{' (derived)' if pv[cfa][1] == 'derived' else ''} ({prank[cfa]})"
                       if cfa in pv else "-")
            for got in ours:
                s = got.get(cfa)
                row.append(f"{s[0]:.4f} [{s[1]:.4f}, {s[2]:.4f}] ({s[3]}, {s[4]}-{s[5]})" if s else "-")
            table.append(row)
        out += [f"### {demosaic}", ""] + _table(header, table)
        for run, got in zip(runs, ours):
            both = [c for c in pv if c in got]
            if len(both) >= 5:
                rho, lo, hi, n = spearman_interval([pv[c][0] for c in both], [got[c][0] for c in both])
                out.append(f"- {run.label}: Spearman rank correlation with the paper over {n} CFAs: "
                           f"{rho:+.2f} (95 % interval {lo:+.2f} to {hi:+.2f}; two runs' correlations are "
                           "told apart only where their intervals do not overlap).")
        out.append("")
        for claim in claims():
            if claim["kind"] == "best" and claim["demosaic"] == demosaic:
                out += _claim_lines(claim, runs)
    return out


def _runs_table(runs) -> list[str]:
    rows = []
    for run in runs:
        cfg = run.config
        cap, isp = cfg.get("capture", {}), cfg.get("isp", {})
        sensor = cfg.get("sensor", {})
        sets = ", ".join(dict.fromkeys(str(s) for s in run.metrics.get("spectra", []) if isinstance(s, str)))
        opts = cfg.get("metric_options", {}) or {}
        total = (run.timing.get("phases") or {}).get("total_s")
        rows.append((run.label, f"`{cfg.get('name', run.path.name)}`", cfg.get("seeds", "-"), sets or "-",
                     f"well {sensor.get('well_capacity_e', 6200):g} e-, read {sensor.get('read_noise_e', 6.2):g} e-",
                     cap.get("exposure_policy", "reference"), isp.get("colour_fit", "training"),
                     "white-preserving" if isp.get("white_preserving", True) else "plain least squares",
                     "dE" + str((opts.get("delta-e") or {}).get("version", "2000"))[-2:],
                     ", ".join(f"{k} {v}" for k, v in (opts.get("scielab") or {}).items()) or "ours (xyz2, spd of the scene, symmetric)",
                     cfg.get("range_policy", "-"), f"{total:.0f} s" if total else "-"))
    return _table(["run", "config", "seeds", "spectra sets", "pixel", "exposure", "colour fit", "fit",
                   "dE headline", "S-CIELAB", "ranges", "time"], rows)


def _glance(runs) -> list[str]:
    rows = [(c["text"], "paper" if c["source"] == "paper" else "ISETCam",
             *[_MARK[judge(run, c)[0]] for run in runs]) for c in claims()]
    return _table(["claim", "source"] + [run.label for run in runs], rows)


def comparison_markdown(runs) -> str:
    """The whole page for ``runs`` (:class:`~.paper_data.Run`, one or two)."""
    if not runs:
        raise CfaMitsubaError("paper comparison: give at least one study run")
    paper, iset = paper_values(), isetcam_values()
    out = ["# The paper side by side", "",
           "Generated by `python -m cfa_mitsuba.report.paper_comparison` from the study runs below; do not "
           "edit by hand. Bae 2020 (PLoS ONE 15(5): e0232583) built its study on ISETCam; "
           "ISETCam itself was run on the paper's colour table (research/isetcam-paper-check.md). "
           "Values are bilinear at 100 cd/m^2 unless a table says otherwise (the paper's Figs 8-15 "
           "and Table 1 are bilinear); ours are the mean over noise realisations with the 95 % interval "
           "in brackets. Our scenes are rendered, not the paper's images, so levels differ for that "
           "reason alone: the verdicts test the paper's *claims* (orders, groups, winners), each in "
           "data/paper/claims.toml with the reason printed for its verdict.", "",
           "## The runs", ""] + _runs_table(runs)
    out += ["## How a verdict is reached", "",
            "Each claim makes comparisons, and each comparison is judged on the run's 95 % intervals "
            "(cfa_mitsuba/report/claim_verdicts.py): a claim **holds** only when every comparison it makes is "
            "separated in the claimed direction; it is a **tie** when none is reversed but some are not "
            "separated; it **differs** when one is separated the other way. Two CFAs are compared through "
            "their paired difference (the same render and sensor seeds; its 95 % interval, the render "
            "component pooled over every pair of that metric and demosaic, must exclude 0), as the study's "
            "rank intervals are; a run without its realisations falls back on the two marginal intervals. "
            "Group claims are judged pairwise, every CFA of a group against every CFA of the other, never on "
            "group means. \"X has the best score\" holds only when the study's decision rule names X: its rank "
            "interval is exactly 1 and its lead is at least the practical difference (decisions.csv; a run "
            "written before that rule: rank interval exactly 1). A spread or a bound is compared with the "
            "intervals' ends. An MSP is printed as >= only when every realisation is a bound. Spearman "
            "correlations carry their 95 % interval (Fisher z). Every number in an explanation is generated from "
            "the run it explains (cfa_mitsuba/report/claim_facts.py). tests/test_claim_verdicts.py recomputes "
            "every verdict and every explanation's facts from the committed CSVs.", ""]
    out += ["## Verdicts at a glance", ""] + _glance(runs)
    # a claim the data marks as physically wrong is listed when every run contradicts it
    wrong = [c for c in claims() if c.get("wrong") and all(judge(run, c)[0] == "differs" for run in runs)]
    out += ["## Where the paper is wrong", ""] + [f"- {c['wrong']}" for c in wrong] + [
        "- The moire starting point is printed in 'cpd' but is a pixel position on the 500-px chirp "
        "(ISETCam's moire code returns a column index under that name; docs/metrics.md).", ""]
    for metric, heading, ours in SECTIONS:
        out += _section(metric, heading, ours, runs, paper, iset)
        if metric == "delta-e76":
            out += _fit_only(iset, runs)
    out += _table3(runs, paper)
    out += ["## Not compared", "",
            "- Table 2 beyond the cells placed above: the text extraction of the PDF drops the best cell of "
            "each row and merges rows, so most cells cannot be assigned to a CFA.",
            "- The adaptive-laplacian row of Table 3 except Bayer's derived cell (ten cells for eleven CFAs).",
            "- The luminance sweep (3-400 cd/m^2) of S-CIELAB and SSIM: the paper gives it as figures "
            "without numbers; each run's report.html draws ours.", ""]
    return "\n".join(out).rstrip() + "\n"


def write_comparison(out_path, default=None, isetcam=None) -> Path:
    """Write the page from a default and/or an ISETCam-procedure results folder."""
    from ..io import atomic_output

    runs = []
    if default is not None:
        runs.append(load_run(default, "default", "ours, defaults"))
    if isetcam is not None:
        runs.append(load_run(isetcam, "isetcam", "ours, ISETCam procedure"))
    text = comparison_markdown(runs)
    out = Path(out_path)
    with atomic_output(out) as tmp:
        tmp.write_text(text)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m cfa_mitsuba.report.paper_comparison",
                                 description="Write docs/paper-comparison.md from study runs.")
    ap.add_argument("--default", help="results folder of configs/paper.toml")
    ap.add_argument("--isetcam", help="results folder of configs/paper-isetcam.toml")
    ap.add_argument("--out", default="docs/paper-comparison.md")
    args = ap.parse_args(argv)
    if not (args.default or args.isetcam):
        ap.error("give --default and/or --isetcam")
    try:
        print(write_comparison(args.out, args.default, args.isetcam))
    except CfaMitsubaError as exc:
        print(f"{ap.prog}: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
