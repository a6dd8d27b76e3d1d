"""``cfa-mitsuba league CONFIG.toml --out DIR``: every CFA through the full
chain with the demosaics that suit it, and the best per aspect by the
project's decision rule (docs/design.md, "The league").

The config is an ordinary study config (configs/league.toml); the study
runs every CFA with every demosaic of it into ``DIR/study/``, then the
league keeps, per CFA, the demosaics that *suit* it: those within
:data:`~cfa_mitsuba.isp.suitability.SUITS_WITHIN_DB` of the best PSNR
measured on that layout (``cfa_mitsuba/data/demosaic_psnr.toml``; a layout
none of the study's demosaics suits keeps its best measured one; a layout
never measured keeps them all, and says so).  Each kept (CFA, demosaic)
pair is one entry of the league:

    DIR/league.csv            one row per entry: the CFA's tile, filter set,
                              source and why the demosaic was kept; per
                              aspect metric the mean and its 95 % interval
    DIR/league_decisions.csv  per aspect: the entries whose rank interval
                              contains 1, ``winner`` only when that is one
                              entry ranked exactly 1 (study/decisions.py's
                              ``decide``, on the entries' 95 % intervals)
    DIR/league.html           the two tables
    DIR/study/                the study's tables (metrics.csv, snr10.csv, scores.csv, ...)

The learned CFAs are judged here with this project's demosaics, not with
the networks they were trained with.
"""

from __future__ import annotations

__all__ = ["ASPECTS", "suited_demosaics", "league_table", "aspect_labels", "league_decisions", "run_league"]

import html
import time
from pathlib import Path

import numpy as np

from ..io import atomic_output, check_writable_dir

#: (aspect, metric, scene, luminance or None for the study's lowest swept one, label)
ASPECTS = (
    ("colour", "delta-e", "macbeth", 100.0, "ColorChecker ΔE00 at 100 cd/m²"),
    ("colour in a scene", "scielab", "puppy", 100.0, "puppy S-CIELAB ΔE00 at 100 cd/m²"),
    ("sharpness", "mtf", "slanted-edge", 100.0, "MTF50 at 100 cd/m²"),
    ("detail", "info-capacity", "slanted-edge", 100.0, "information capacity at 100 cd/m²"),
    ("moire", "moire", "chirp", 100.0, "moire start at 100 cd/m²"),
    ("low light", "snr10", "gray-bar", None, "SNR10: luminance of YSNR 10"),
    ("low-light colour", "scielab", "puppy", None, "puppy S-CIELAB ΔE00 at the lowest luminance"),
    ("overall", "mean_score", "", None, "mean score over the metrics (Table 3's per-demosaic score)"),
)


def suited_demosaics(cfa, demosaics) -> tuple[list[str], str]:
    """(the study's demosaics kept for ``cfa`` (a CFA), why) by the measured PSNR (module doc)."""
    from ..isp.suitability import SUITS_WITHIN_DB, demosaic_psnr

    by = demosaic_psnr().get(cfa.name)
    demosaics = list(demosaics)
    if len(cfa.channels) == 1:  # mono: nothing to interpolate, every method gives the raw image
        return demosaics[:1], "one channel: every demosaic is the raw image"
    if not by:
        return demosaics, "not measured: every demosaic"
    best = max(by.values())
    kept = [d for d in demosaics if d in by and by[d] >= best - SUITS_WITHIN_DB]
    if kept:
        return kept, f"within {SUITS_WITHIN_DB:g} dB of the best measured PSNR"
    top = max((d for d in demosaics if d in by), key=lambda d: by[d])
    return [top], f"none within {SUITS_WITHIN_DB:g} dB: the best measured of the study's"


def _goal(metric: str) -> str:
    from ..metrics import get_metric

    if metric in ("snr10",):
        return "min"
    if metric == "mean_score":
        return "max"
    return "max" if get_metric(metric).higher_is_better else "min"


def league_table(study_dir, config):
    """league.csv as a DataFrame (module doc) from a finished study's tables."""
    import pandas as pd

    from ..sensor import get_cfa
    from ..sensor.cfa import layout_info

    from ..io.guard import read_csv

    d = Path(study_dir)  # a results folder: each table read as a bounded regular file
    metrics = read_csv(d / "metrics.csv")
    snr10 = read_csv(d / "snr10.csv") if (d / "snr10.csv").is_file() else pd.DataFrame()
    scores = read_csv(d / "scores.csv")
    low = float(metrics["luminance"].astype(float).min())
    rows = []
    for name in config.cfas:
        cfa = get_cfa(name)
        info = layout_info(cfa.name)
        kept, why = suited_demosaics(cfa, config.demosaics)
        for dem in kept:
            row = {"cfa": cfa.name, "demosaic": dem, "tile": cfa.tile_text(), "spectra": cfa.spectra,
                   "source": info.get("source", ""), "demosaic_kept": why}
            for aspect, metric, scene, lum, _ in ASPECTS:
                label = _label(metric, scene, lum if lum is not None else low)
                got = _value(metrics, snr10, scores, cfa.name, dem, metric, scene, lum if lum is not None else low)
                row[label], row[f"{label} low"], row[f"{label} high"] = got[:3]
                if len(got) > 3:  # a metric read at the end of its range: a bound, not a measurement
                    row[f"{label}_censored"] = got[3]
            rows.append(row)
    return pd.DataFrame(rows)


def _label(metric, scene, lum) -> str:
    if metric == "snr10":
        return "snr10@gray-bar"
    if metric == "mean_score":
        return "mean_score"
    return f"{metric}@{scene}/L{lum:g}"


def _value(metrics, snr10, scores, cfa, dem, metric, scene, lum):
    nan = (float("nan"),) * 3
    if metric == "snr10":
        r = snr10[(snr10["cfa"] == cfa) & (snr10["demosaic"] == dem)] if len(snr10) else snr10
        return tuple(float(r.iloc[0][k]) for k in ("snr10_cd_m2", "ci_low", "ci_high")) if len(r) else nan
    if metric == "mean_score":
        r = scores[(scores["cfa"] == cfa) & (scores["demosaic"] == dem)]
        return tuple(float(r.iloc[0][k]) for k in ("mean_score", "mean_score_ci_low", "mean_score_ci_high")) \
            if len(r) else nan
    r = metrics[(metrics["cfa"] == cfa) & (metrics["demosaic"] == dem) & (metrics["metric"] == metric)
                & (metrics["scene"] == scene) & ((metrics["luminance"].astype(float) - lum).abs() < 1e-9)]
    if not len(r):
        return nan + (False,)
    cens = str(r.iloc[0].get("censored", False)).lower() in ("true", "1")
    return tuple(float(r.iloc[0][k]) for k in ("value", "ci_low", "ci_high")) + (cens,)


def aspect_labels(table) -> list[tuple[str, str, str, str]]:
    """(aspect, league.csv column, goal, what) of each :data:`ASPECTS` entry
    present in ``table``; an aspect at the lowest luminance reads the
    lowest one the table holds for its metric and scene."""
    out = []
    for aspect, metric, scene, lum, what in ASPECTS:
        if lum is None and metric not in ("snr10", "mean_score"):
            cols = [c for c in table.columns if c.startswith(f"{metric}@{scene}/L")
                    and not c.endswith((" low", " high", "_censored"))]
            lums = sorted(float(c.rsplit("/L", 1)[1]) for c in cols)
            label = _label(metric, scene, lums[0]) if lums else ""
        else:
            label = _label(metric, scene, lum or 0.0)
        if label in table.columns:
            out.append((aspect, label, _goal(metric), what))
    return out


def league_decisions(table):
    """league_decisions.csv: per aspect, the project's rule on the entries
    (``decide``: higher-is-better scores, so a lower-is-better metric enters
    negated with its interval swapped, and its numbers are shown negated)."""
    import pandas as pd

    from ..study.decisions import decide

    out = []
    for aspect, label, goal, what in aspect_labels(table):
        t = table[np.isfinite(table[label].to_numpy(dtype=float))]
        if t.empty:
            out.append((aspect, label, "", "unmeasured", f"{what}: no values"))
            continue
        names = [f"{c}/{d}" for c, d in zip(t["cfa"], t["demosaic"])]
        v, lo, hi = (t[k].to_numpy(dtype=float) for k in (label, f"{label} low", f"{label} high"))
        if goal == "min":
            v, lo, hi = -v, -hi, -lo
        cfas, verdict, detail = decide(names, v, lo, hi)
        note = " (lower is better: values shown negated)" if goal == "min" else ""
        if f"{label}_censored" in t and t[f"{label}_censored"].astype(bool).any():
            note += (f"; {int(t[f'{label}_censored'].astype(bool).sum())} of {len(t)} entries read at the end "
                     "of the metric's range (a bound: they tie there)")
        out.append((aspect, label, " ".join(cfas), verdict, f"{what}: {detail}{note}"))
    return pd.DataFrame(out, columns=["aspect", "metric", "entries", "verdict", "detail"])


def _html(table, decisions, config, timing) -> str:
    e = html.escape
    labels = [c for c in table.columns if c not in ("cfa", "demosaic", "tile", "spectra", "source", "demosaic_kept")
              and not c.endswith((" low", " high", "_censored"))]
    head = "".join(f"<th>{e(c)}</th>" for c in labels)
    rows = []
    for _, r in table.iterrows():
        cells = "".join("<td>—</td>" if not np.isfinite(r[c]) else
                        f"<td>{r[c]:.4g} <span class=n>[{r[c + ' low']:.4g}, {r[c + ' high']:.4g}]</span></td>"
                        for c in labels)
        rows.append(f"<tr><td class=l>{e(r['cfa'])}</td><td class=l>{e(r['demosaic'])}</td>{cells}"
                    f"<td class=l>{e(r['tile'])}</td><td class=l>{e(r['spectra'])}</td>"
                    f"<td class=l>{e(r['source'])}</td></tr>")
    dec = "".join(f"<tr><td class=l>{e(a)}</td><td class=l>{e(m)}</td><td class=l>{e(c)}</td><td>{e(v)}</td>"
                  f"<td class=l>{e(d)}</td></tr>" for a, m, c, v, d in decisions.itertuples(index=False))
    return f"""<!doctype html><html><head><meta charset=utf-8><title>CFA league</title><style>
body{{font:13px/1.45 'DejaVu Sans',Helvetica,Arial,sans-serif;margin:0 24px 40px}}table{{border-collapse:collapse;
font-size:11px}}td,th{{border:1px solid #d0d7de;padding:2px 6px;text-align:right;vertical-align:top}}th{{background:
#f6f8fa}}td.l{{text-align:left}}.n{{color:#59636e}}</style></head><body><h1>CFA league: {e(config.name)}</h1>
<p>{len(set(table['cfa']))} CFAs, {len(table)} (CFA, demosaic) entries: each CFA with the demosaics that suit it
(within 1 dB of its best measured PSNR), under the exposure program, {config.seeds} noise realisations per value
(95 % intervals). The learned CFAs are judged with this project's demosaics, not the networks they were trained
with. Study: {timing.get('study_s', 0):.0f} s.</p><h2>Decisions</h2><table><tr><th>aspect</th><th>metric</th>
<th>entries whose rank interval contains 1</th><th>verdict</th><th>detail</th></tr>{dec}</table>
<h2>Entries</h2><table><tr><th>CFA</th><th>demosaic</th>{head}<th>tile</th><th>filters</th><th>source</th></tr>
{''.join(rows)}</table></body></html>"""


def run_league(config_path, out_dir, *, workers=None, scheduler=None, progress=True, log=print) -> Path:
    """Run the league of ``config_path`` (a study config) into ``out_dir`` (module doc)."""
    import json

    from ..study.config import load_config
    from ..study.runner import run_study

    config = load_config(config_path)
    out = check_writable_dir(out_dir)
    t0 = time.perf_counter()
    run_study(config, out / "study", workers=workers, scheduler=scheduler, progress=progress, log=log)
    timing = {"study_s": time.perf_counter() - t0}
    table = league_table(out / "study", config)
    decisions = league_decisions(table)
    for name, df in (("league.csv", table), ("league_decisions.csv", decisions)):
        with atomic_output(out / name) as tmp:
            df.to_csv(tmp, index=False, float_format="%.8g")
    timing["total_s"] = time.perf_counter() - t0
    with atomic_output(out / "league.html") as tmp:
        tmp.write_text(_html(table, decisions, config, timing))
    with atomic_output(out / "timing.json") as tmp:
        tmp.write_text(json.dumps(timing, indent=1))
    log(f"league: {len(set(table['cfa']))} CFAs, {len(table)} entries; " + "; ".join(
        f"{a}: {c or '-'} ({v})" for a, _, c, v, _ in decisions.itertuples(index=False)))
    return out / "league.html"
