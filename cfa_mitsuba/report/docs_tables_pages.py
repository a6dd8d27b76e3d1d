"""Generated tables and sentences of docs/metrics.md (``<!--= @NAME ARGS -->``).

- ``@bench-table PATH.json``: a benchmark's ``--json`` output (rows of
  ``metric``, ``time_s``, ``budget_s``) with how it was measured;
- ``@metric-table RESULTS METRIC DEMOSAIC [LUMINANCE]``: one metric of a
  study's metrics.csv per CFA, mean with half its 95 % interval, censored
  values marked as bounds;
- ``@censored RESULTS METRIC``: how many of a metric's values are bounds,
  and which (CFA, demosaic);
- ``@above-ideal RESULTS METRIC``: the camera outputs whose value exceeds
  the ideal sensor's (ideal.csv);
- ``@by-demosaic PATH.csv SCENE CFA LUMINANCE METRIC...``: a tidy CSV
  (metrics.csv, quick_expected.csv) as one row per metric and one column per
  demosaic, each value with its 95 % interval where the CSV has one;
- ``@worst-demosaic PATH.csv SCENE CFA LUMINANCE METRIC...``: per metric
  the worst demosaic and whether its 95 % interval is apart from every
  other's (last) or overlaps some (tied last);
- ``@demosaic-speed PATH.json``, ``@demosaic-psnr PATH.json CFA...``,
  ``@demosaic-scielab PATH.json`` and ``@psnr-exceptions PATH.json CFA...``:
  ``benchmarks/bench_demosaic.py --json`` output as its speed, PSNR and
  S-CIELAB tables, and where a method falls below a simpler one;
- ``@colour-fit-table PATH.json CFA...`` and ``@colour-pipeline-table
  PATH.json CFA...``: ``benchmarks/bench_colour.py --json`` output as its two
  tables (CFAs whose rows are equal as printed share one row).
"""

from __future__ import annotations

__all__ = ["GENERATORS", "bench_table", "metric_table", "censored_sentence", "above_ideal_sentence", "demosaic_speed",
           "demosaic_psnr", "by_demosaic", "worst_demosaic", "demosaic_scielab", "psnr_exceptions",
           "colour_fit_table", "colour_pipeline_table"]

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
    from ..study.censored import apply_rule

    m = _csv(repo, results, "metrics.csv")
    real = repo / results / "metrics_realisations.csv"
    if "censored_count" not in m.columns and real.is_file():  # an older run, read under study/censored.py's rule
        import pandas as pd

        r = pd.read_csv(real)
        m = apply_rule(m, r[r["metric"] == metric])
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
    """One metric per CFA for one demosaic: the value ± half its 95 % interval, by the rule of
    study/censored.py: ``>=`` only when every realisation is a bound, else the count of bounds."""
    rows = _rows(repo, results, metric, luminance)
    rows = rows[rows["demosaic"] == demosaic]
    unit = rows["unit"].iloc[0] if isinstance(rows["unit"].iloc[0], str) else ""
    lines = [f"| {demosaic} | {metric} ({unit}), value ± half the 95 % interval | realisations that are bounds |",
             "|---|---|---|"]
    for r in rows.itertuples(index=False):
        count = int(getattr(r, "censored_count", 0) or 0)
        every = str(r.censored) == "True" and count >= int(r.n)
        shown = (f"{r.value:.2f} [{r.ci_low:.2f}, {r.ci_high:.2f}] (median)" if count and not every
                 else f"{'>= ' if every else ''}{r.value:.2f} ± {(r.ci_high - r.ci_low) / 2:.2f}")
        lines.append(f"| {r.cfa} | {shown} | {'every one' if every else f'{count} of {int(r.n)}' if count else 'none'} |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def censored_sentence(repo: Path, results: str, metric: str) -> str:
    """How many of a metric's values are bounds in every realisation, and which; and those bounds in some."""
    rows = _rows(repo, results, metric, None)
    count = (rows["censored_count"] if "censored_count" in rows.columns
             else (rows["censored"].astype(str) == "True") * rows["n"])
    cens = rows[(rows["censored"].astype(str) == "True") & (count >= rows["n"])]
    some = rows[(count > 0) & (count < rows["n"])]
    by: dict = {}
    for r in cens.itertuples(index=False):
        by.setdefault(r.cfa, []).append(r.demosaic)
    n_dem = rows["demosaic"].nunique()
    parts = [f"{c} ({'every demosaic' if len(d) == n_dem else ', '.join(d)})" for c, d in by.items()]
    text = f"{len(cens)} of {len(rows)} values are bounds in every realisation" + (
        f": {'; '.join(parts)}" if parts else "")
    if len(some):
        text += "; " + "; ".join(f"{r.cfa} with {r.demosaic} in {int(c)} of {int(r.n)} (its value, {r.value:.2f}, is "
                                 "the realisations' median, a measurement)"
                                 for r, c in zip(some.itertuples(index=False), count[some.index]))
    return text


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


def _bench(repo: Path, path: str) -> dict:
    file = repo / path
    if not file.is_file():
        raise CfaMitsubaError(f"{path} not found (run benchmarks/bench_demosaic.py --json {path})")
    return json.loads(file.read_text())


def _how(d: dict) -> str:
    runs = d.get("runs") or [d]
    loads = [r.get("load_average_end", float("nan")) for r in runs]
    load = f"{min(loads):.1f}" if len(runs) == 1 else f"{min(loads):.1f}-{max(loads):.1f}"
    return (f"times: best of {d.get('repeat')} on {d.get('cpus')} shared cores at load average {load}, "
            f"{', '.join(sorted({r.get('date', '?') for r in runs}))}, commit "
            f"{', '.join(sorted({r.get('commit', '?') for r in runs}))}")


def demosaic_speed(repo: Path, path: str) -> str:
    """The Bayer speed table of bench_demosaic: time per method and the ratios to colour-demosaicing."""
    d = _bench(repo, path)
    pairs = {"bilinear": "colour-demosaicing bilinear", "laplacian": "colour-demosaicing Malvar2004"}
    lines = ["| 636 x 720 Bayer mosaic | time (s) | ratio |", "|---|---|---|"]
    single = ", single precision"  # benchmarks/bench_demosaic.py's SINGLE: the method in float32
    for k, t in d["speed_s"].items():
        ratio = f"{d['speedup'][k]:.1f}x faster than {pairs[k]}" if k in pairs else ""
        if k.endswith(single) and k[:-len(single)] in d["speed_s"]:
            ratio = f"{d['speed_s'][k[:-len(single)]] / t:.1f}x faster than double precision"
        if k == "pocs":
            ratio = f"{d['pocs_iterations']} iterations to tolerance 1e-3"
        lines.append(f"| {k} | {t:.4f} | {ratio} |")
    return "\n\n" + "\n".join(lines) + f"\n\n({_how(d)}.)\n\n"


def demosaic_psnr(repo: Path, path: str, *cfas: str) -> str:
    """bench_demosaic's PSNR rows (dB per photograph, mean, time per image) of the CFAs given."""
    d = _bench(repo, path)
    photos = d["photos"]
    lines = [f"| CFA | method | {' | '.join(photos)} | mean PSNR (dB) | time per image (s) |",
             "|---|---|" + "---|" * len(photos) + "---|---|"]
    for cfa in cfas:
        if cfa not in d["psnr_db"]:
            raise CfaMitsubaError(f"{path} holds no PSNR of {cfa!r}")
        for method, v in d["psnr_db"][cfa].items():
            lines.append(f"| {cfa} | {method} | " + " | ".join(f"{v[n]:.2f}" for n in photos)
                         + f" | {v['mean']:.2f} | {d['time_per_image_s'][cfa][method]:.3f} |")
        if cfa == "bayer":  # the library's Bayer methods on the same mosaics, PSNR only
            for label, v in d.get("library_psnr_db", {}).items():
                lines.append(f"| {cfa} | *{label}* | " + " | ".join(f"{v[n]:.2f}" for n in photos) + f" | {v['mean']:.2f} | |")
    return "\n\n" + "\n".join(lines) + f"\n\n({_how(d)}.)\n\n"


LABEL = {"ssim": "SSIM", "haarpsi": "HaarPSI", "mdsi": "MDSI", "scielab": "S-CIELAB (dE00)",
         "scielab-interior": "S-CIELAB interior (dE00)"}


def by_demosaic(repo: Path, path: str, scene: str, cfa: str, luminance: str, *metrics: str) -> str:
    """Metrics (rows) against demosaics (columns) for one scene, CFA and luminance of a tidy CSV."""
    import pandas as pd

    file = repo / path
    if not file.is_file():
        raise CfaMitsubaError(f"{path} not found")
    m = pd.read_csv(file, comment="#")
    m = m[(m["scene"] == scene) & (m["cfa"] == cfa) & (m["luminance"] == float(luminance))]
    demosaics = list(dict.fromkeys(m["demosaic"]))
    lines = ["| metric | " + " | ".join(demosaics) + " |", "|---|" + "---|" * len(demosaics)]
    for metric in metrics:
        rows = m[m["metric"] == metric].set_index("demosaic")
        if rows.empty:
            raise CfaMitsubaError(f"{path} has no {metric!r} of {cfa} on {scene} at {luminance} cd/m^2")
        digits = ".3f" if metric.startswith("scielab") else ".4f"
        cells = [f"{rows.loc[d, 'value']:{digits}}" + (f" [{rows.loc[d, 'ci_low']:{digits}}, {rows.loc[d, 'ci_high']:{digits}}]"
                                                       if "ci_low" in rows.columns else "") for d in demosaics]
        lines.append(f"| {LABEL.get(metric, metric)} | " + " | ".join(cells) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


HIGHER_IS_BETTER = {"ssim": True, "haarpsi": True, "mdsi": False, "scielab": False, "scielab-interior": False}


def worst_demosaic(repo: Path, path: str, scene: str, cfa: str, luminance: str, *metrics: str) -> str:
    """Per metric: the demosaic with the worst mean, and whether its interval is apart from all others."""
    import pandas as pd

    m = pd.read_csv(repo / path, comment="#")
    m = m[(m["scene"] == scene) & (m["cfa"] == cfa) & (m["luminance"] == float(luminance))]
    parts = []
    for metric in metrics:
        rows = m[m["metric"] == metric].set_index("demosaic")
        if rows.empty or metric not in HIGHER_IS_BETTER:
            raise CfaMitsubaError(f"{path}: no {metric!r} of {cfa} on {scene} at {luminance} cd/m^2 (or no direction)")
        worst = rows["value"].idxmin() if HIGHER_IS_BETTER[metric] else rows["value"].idxmax()
        w = rows.loc[worst]
        others = rows.drop(index=worst)
        overlap = [d for d, r in others.iterrows() if r["ci_low"] <= w["ci_high"] and w["ci_low"] <= r["ci_high"]]
        name = LABEL.get(metric, metric).split(" (")[0]
        parts.append(f"{name}: {worst} last, its interval apart from every other method's" if not overlap else
                     f"{name}: {worst} lowest-scoring but tied with {', '.join(overlap)} (overlapping intervals)")
    return "; ".join(parts)


def demosaic_scielab(repo: Path, path: str) -> str:
    """Mean S-CIELAB dE00 of the four methods on the photographs at each viewing geometry, with bilinear's ranks."""
    d = _bench(repo, path)
    tables = d.get("scielab_de00")
    if not tables:
        raise CfaMitsubaError(f"{path} holds no S-CIELAB table (run bench_demosaic.py --scielab-only --json {path})")
    spds = list(tables)
    methods = list(tables[spds[0]])
    lines = ["| method | " + " | ".join(f"{spd} samples/deg" for spd in spds) + " |", "|---|" + "---|" * len(spds)]
    for m in methods:
        cells = []
        for spd in spds:
            t = tables[spd]
            cell = f"{t[m]['mean']:.3f}"
            if m == "bilinear":
                worst = sum(all(t[m][ph] >= t[o][ph] for o in methods) for ph in d["photos"])
                best = sum(all(t[m][ph] <= t[o][ph] for o in methods) for ph in d["photos"])
                cell = f"**{cell}** (worst on {worst} of {len(d['photos'])} photographs; best on {best})"
            cells.append(cell)
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def psnr_exceptions(repo: Path, path: str, *cfas: str) -> str:
    """Bullets: where a cross-channel method's PSNR falls below bilinear on a photograph, adaptive below
    laplacian on the mean, or POCS below laplacian on the mean (the expected order reversed)."""
    d = _bench(repo, path)
    out = []
    for cfa in cfas:
        if cfa not in d["psnr_db"]:
            raise CfaMitsubaError(f"{path} holds no PSNR of {cfa!r}")
        p = d["psnr_db"][cfa]
        found = [f"{m} below bilinear on {ph} ({p[m][ph]:.2f} vs {p['bilinear'][ph]:.2f} dB)"
                 for m in ("laplacian", "adaptive-laplacian") for ph in d["photos"] if p[m][ph] < p["bilinear"][ph]]
        found += [f"{m} below laplacian on the mean ({p[m]['mean']:.2f} vs {p['laplacian']['mean']:.2f} dB)"
                  for m in ("adaptive-laplacian", "pocs") if p[m]["mean"] < p["laplacian"]["mean"]]
        if found:
            out.append(f"* {cfa}: " + "; ".join(found) + ".")
    return "\n\n" + ("\n".join(out) or "* none: every CFA keeps bilinear < laplacian <= adaptive, POCS.") + "\n\n"


def _colour(repo: Path, path: str, table: str, cfas) -> list:
    file = repo / path
    if not file.is_file():
        raise CfaMitsubaError(f"{path} not found (run benchmarks/bench_colour.py --json {path})")
    rows = [r for r in json.loads(file.read_text())[table] if r["cfa"] in cfas]
    missing = set(cfas) - {r["cfa"] for r in rows}
    if missing:
        raise CfaMitsubaError(f"{path} holds no {table} row of {', '.join(sorted(missing))}")
    return rows


def _grouped(rows: list[tuple[str, str]]) -> list[str]:
    """(cfa, printed cells) -> one line per distinct cells, its CFAs joined, in first-seen order."""
    by: dict = {}
    for cfa, cells in rows:
        by.setdefault(cells, []).append(cfa)
    return [f"| {', '.join(names)} | {cells} |" for cells, names in by.items()]


def colour_fit_table(repo: Path, path: str, *cfas: str) -> str:
    """CIEDE2000 of each CFA's colour matrix fitted on one reflectance set and tested on the other."""
    rows = []
    for r in _colour(repo, path, "spectral", cfas):
        t, c = r["fit_train"], r["fit_chart"]
        rows.append((r["cfa"], f"{r['channels']} | {r['fit']} | {r['condition_number']:.2f} | "
                     + ", ".join(f"{g:.2f}" for g in r["noise_gain_xyz"])
                     + f" | {t['own_mean']:.2f} / {t['own_max']:.2f} | **{t['other_mean']:.2f}** / {t['other_max']:.2f}"
                     + f" | {c['own_mean']:.2f} / {c['own_max']:.2f} | **{c['other_mean']:.2f}** / {c['other_max']:.2f}"))
    head = ("| CFA | N | fit | cond | noise gain X, Y, Z | fitted on train: train mean/max | -> chart mean/max "
            "| fitted on chart: chart mean/max | -> train mean/max |\n|---|---|---|---|---|---|---|---|---|")
    return "\n\n" + head + "\n" + "\n".join(_grouped(rows)) + "\n\n"


def colour_pipeline_table(repo: Path, path: str, *cfas: str) -> str:
    """CIEDE2000 of the whole pipeline (noise off) against the ideal sensor per CFA and demosaic."""
    methods = ("bilinear", "laplacian", "adaptive-laplacian", "pocs")
    rows = [(r["cfa"], " | ".join(f"{r[m]['mean']:.2f} / {r[m]['max']:.2f}" for m in methods)
             + f" | {r['grey_max_bilinear']:.2f}") for r in _colour(repo, path, "pipeline", cfas)]
    head = ("| CFA | " + " | ".join(f"{m} mean / max" for m in methods) + " | grey row (patches 19-24) max, bilinear |"
            "\n|---|" + "---|" * len(methods) + "---|")
    return "\n\n" + head + "\n" + "\n".join(_grouped(rows)) + "\n\n"


#: {name: function(repo, *args) -> Markdown}
GENERATORS = {
    "bench-table": bench_table,
    "metric-table": metric_table,
    "censored": censored_sentence,
    "above-ideal": above_ideal_sentence,
    "demosaic-speed": demosaic_speed,
    "demosaic-psnr": demosaic_psnr,
    "demosaic-scielab": demosaic_scielab,
    "psnr-exceptions": psnr_exceptions,
    "colour-fit-table": colour_fit_table,
    "colour-pipeline-table": colour_pipeline_table,
    "by-demosaic": by_demosaic,
    "worst-demosaic": worst_demosaic,
}
