"""Generated blocks of README.md and docs/*.md about decisions, their
conditions and the intervals under them (issue 46); :mod:`.docs_tables`
registers them with the others.

- ``@decision-detail RESULTS ASPECT``: one decision's detail sentence
  (decisions.csv), the numbers it was decided on and what it depends on;
- ``@conditions RESULTS``: each CFA family's exposure regime at the base
  luminance and the f-number of every scene (:mod:`.conditions`);
- ``@realisations RESULTS``: what a value's realisations are (sensor seeds x
  renders) from config.json;
- ``@practical-table``: the practical difference of each scored metric with
  its source (the metric records);
- ``@interval-widths RESULTS``: the distribution of the path-traced
  values' 95 % half widths over their sensor-only half widths, and the
  pooled render component of each scene, level and metric beside them;
- ``@calibration PATH``: the render-noise calibration benchmark's coverage
  (benchmarks/bench_render_noise_calibration.py's JSON);
- ``@protocols FOLDER``: where the exposure program and the ``bayer``
  protocol capture alike and where the ``bayer`` protocol clips more
  (docs/low-light/{program,bayer}).
"""

from __future__ import annotations

__all__ = ["GENERATORS"]

import json
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError


def _csv(repo: Path, results: str, name: str, **kw):
    import pandas as pd

    path = repo / results / name
    if not path.is_file():
        raise CfaMitsubaError(f"{results}/{name} not found")
    return pd.read_csv(path, **kw)


def decision_detail(repo: Path, results: str, aspect: str) -> str:
    d = _csv(repo, results, "decisions.csv", dtype=str, keep_default_na=False)
    row = d[d["aspect"] == aspect]
    if row.empty:
        raise CfaMitsubaError(f"{results}/decisions.csv has no {aspect!r} row")
    return row["detail"].iloc[0].rstrip(".")


def conditions_sentence(repo: Path, results: str) -> str:
    from .conditions import condition_lines

    m = _csv(repo, results, "metrics.csv")
    facts = json.loads((repo / results / "cfas.json").read_text()) if (repo / results / "cfas.json").is_file() else {}
    cfg = json.loads((repo / results / "config.json").read_text()) if (repo / results / "config.json").is_file() else {}
    lines = condition_lines(m, facts, cfg)
    if not lines:
        raise CfaMitsubaError(f"{results}/metrics.csv has no exposure or f-number columns")
    return " ".join(lines)


def realisations_sentence(repo: Path, results: str) -> str:
    cfg = json.loads((repo / results / "config.json").read_text())
    seeds, renders = int(cfg.get("seeds") or 1), int(cfg.get("render_seeds") or 1)
    if renders > 1:
        return (f"{seeds * renders} noise realisations ({seeds} sensor-noise seeds on each of {renders} "
                "independent renders of the puppy; the charts render deterministically)")
    return f"{seeds} noise realisations (sensor noise; each scene rendered once)"


def practical_table(repo: Path) -> str:
    from ..metrics import METRICS

    lines = ["| metric | practical difference | where it comes from |", "|---|---|---|"]
    for r in METRICS.values():
        if r.scored:
            amounts = ", ".join(f"{v:g} %" if u == "%" else f"{v:g} {u}".rstrip() for u, v in r.practical_difference)
            lines.append(f"| {r.name} | {amounts or '—'} | {r.practical_source or '—'} |")
    from ..study.lowlight import SNR10_PRACTICAL_STOPS

    lines.append(f"| SNR10 (low light) | {SNR10_PRACTICAL_STOPS:.3g} stop | ISO 12232:2019 states speeds in "
                 "1/3-stop steps: a smaller difference does not change a rated speed |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def interval_widths(repo: Path, results: str) -> str:
    """Percentiles of half width / sensor-only half width over the values with several renders, and per
    scene, level and metric the pooled render standard deviation beside the median sensor one."""
    from ..study.tables import NOT_POOLED, key_columns
    from ..study.variance import cell, pool_render

    m = _csv(repo, results, "metrics.csv")
    m = m[(m["render_seeds"] > 1) & (m["sensor_half_width"] > 0)]
    if m.empty:
        raise CfaMitsubaError(f"{results}: no value spans several renders")
    ratio = ((m["ci_high"] - m["ci_low"]) / 2 / m["sensor_half_width"]).to_numpy()
    q = np.percentile(ratio, [5, 25, 50, 75, 95, 100])
    head = (f"Over the {ratio.size} values that span several renders, half width over sensor-only half width: "
            f"5th percentile {q[0]:.2f}, quartiles {q[1]:.2f} / {q[2]:.2f} / {q[3]:.2f}, 95th {q[4]:.2f}, largest "
            f"{q[5]:.2f}; {int((ratio > 4).sum())} value(s) above 4x.")
    real = _csv(repo, results, "metrics_realisations.csv")
    real = real[real["render_seed"].groupby([real[k] for k in ("scene", "luminance")]).transform("nunique") > 1]
    keys = [k for k in key_columns() if k in real.columns]
    pool_keys = ["scene", "luminance", "metric"]
    lines = ["| scene | cd/m² | metric | render sd (pooled) | median sensor sd | values above 4x |", "|---|---|---|---|---|---|"]
    ratios = m.assign(r=ratio)
    for (scene, lum, metric), g in real.groupby(pool_keys, sort=False):
        cells = [cell(v["value"].to_numpy(float), v["render_seed"].to_numpy()) for _, v in g.groupby(
            [k for k in keys if k not in NOT_POOLED or k in ("cfa", "demosaic")], sort=False)]
        p = pool_render(cells)
        sensor = float(np.median([np.sqrt(c.ms_within) for c in cells if np.isfinite(c.ms_within)]))
        above = int(((ratios["scene"] == scene) & (ratios["luminance"] == lum) & (ratios["metric"] == metric)
                     & (ratios["r"] > 4)).sum())
        lines.append(f"| {scene} | {lum:g} | {metric} | {np.sqrt(p.variance):.3g} | {sensor:.3g} | {above} |")
    return f"{head}\n\n" + "\n".join(lines) + "\n\n"


def calibration_table(repo: Path, path: str) -> str:
    file = repo / path
    if not file.is_file():
        raise CfaMitsubaError(f"{path} not found (benchmarks/bench_render_noise_calibration.py --json {path})")
    d = json.loads(file.read_text())
    s = d["setup"]
    lines = ["| render_seeds | values covered | paired differences covered | half width / sensor-only: median, "
             "95th percentile |", "|---|---|---|---|"]
    for r, c in d["render_seeds"].items():
        v, dd, w = c["values"], c["differences"], c["half_width_over_sensor_only"]
        lines.append(f"| {r} | {v['covered']} of {v['total']} ({100 * v['share']:.1f} %) | {dd['covered']} of "
                     f"{dd['total']} ({100 * dd['share']:.1f} %) | {w['median']:.2f}, {w['p95']:.2f} |")
    how = (f"puppy {s['size'][0]} x {s['size'][1]} at {s['spp']} spp; {', '.join(s['cfas'])}; "
           f"{', '.join(s['demosaics'])}; {', '.join(f'{x:g}' for x in s['levels_cd_m2'])} cd/m²; "
           f"{s['sensor_seeds']} sensor seeds; {s['replicates']} replicates against a run with "
           f"{s['reference_render_seeds']} render seeds; {d['wall_s']:.0f} s")
    return "\n\n" + "\n".join(lines) + f"\n\n({how}.)\n\n"


def protocols_sentence(repo: Path, folder: str) -> str:
    a = _csv(repo, f"{folder}/program", "metrics.csv")
    b = _csv(repo, f"{folder}/bayer", "metrics.csv")
    keys = ["scene", "cfa", "demosaic", "luminance", "metric"]
    m = a.merge(b, on=keys, suffixes=("_p", "_b")).drop_duplicates(["scene", "cfa", "luminance"])
    m = m.assign(d=m["clipped_fraction_b"] - m["clipped_fraction_p"])
    by = m.groupby("luminance")["d"].max()
    same = [lum for lum, d in by.items() if d < 5e-4]
    differ = by[by >= 5e-4]
    text = (f"at {', '.join(f'{x:g}' for x in same)} cd/m² the two protocols clip the same share of every CFA's "
            "pixels (within 0.05 %)" if same else "at no level of the sweep do the two protocols clip alike")
    if len(differ):
        text += (f"; from {differ.index.min():g} cd/m² up the `bayer` protocol clips up to "
                 f"{100 * differ.max():.1f} % more of a CFA's pixels than the program "
                 f"({', '.join(f'{lum:g} cd/m²: {100 * d:.1f} %' for lum, d in differ.items())})")
    return text


GENERATORS = {
    "decision-detail": decision_detail,
    "conditions": conditions_sentence,
    "realisations": realisations_sentence,
    "practical-table": practical_table,
    "interval-widths": interval_widths,
    "calibration": calibration_table,
    "protocols": protocols_sentence,
}
