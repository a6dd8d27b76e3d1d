"""Generated tables and numbers of docs/convergence.md (``<!--= @convergence-... -->``).

Each reads the committed output of ``cfa-mitsuba convergence`` under
``docs/images/convergence/`` (``convergence_<run>.csv`` and ``.json``,
written by :func:`cfa_mitsuba.study.convergence.write_outputs`), so the
page's tables and numbers are those of the runs whose plots it shows.

- ``@convergence-levels RUN``: error against spp (one row per level);
- ``@convergence-charts RUN...``: the flat charts' summary (one row per run);
- ``@convergence-check RUN``: the render-induced deviation at the default
  against the spread and gaps between CFAs;
- ``@convergence-pocs RUN...``: the default POCS against the converged one;
- ``@convergence RUN KEY [FORMAT]``: one number.  ``KEY`` is a dotted path
  into the run's JSON (``+`` stands for a space in a key:
  ``at_default.radiance+image+median+band``) or a derived quantity of the
  CSV: ``SPP.wall`` (the level's best wall time, s), ``SPP.radiance-median``,
  ``SPP.radiance-worst``, ``SPP.uniform-median`` (relative rms over bands),
  ``SPP.METRIC`` (one render's deviation).  A ``FORMAT`` ending in ``%``
  prints a fraction as percent with a space before the sign (``.2%``:
  ``0.20 %``).
"""

from __future__ import annotations

__all__ = ["GENERATORS", "levels_table", "charts_table", "check_table", "pocs_table", "convergence_number"]

import json
from pathlib import Path

from ..errors import CfaMitsubaError

FOLDER = "docs/images/convergence"

#: headline label and unit of each metric the runs measure
LABELS = {"scielab": "dS-CIELAB (dE00)", "scielab-interior": "dS-CIELAB interior (dE00)", "ssim": "dSSIM",
          "mdsi": "dMDSI", "haarpsi": "dHaarPSI", "delta-e": "dE00", "delta-e76": "dE*ab", "delta-l": "dL*",
          "mtf": "MTF50", "moire": "MSP", "achromatic": "AR"}
NAMES = {"scielab": "S-CIELAB (dE00)", "scielab-interior": "S-CIELAB interior (dE00)", "ssim": "SSIM",
         "mdsi": "MDSI", "haarpsi": "HaarPSI", "delta-e": "dE00", "delta-e76": "dE*ab", "delta-l": "dL*",
         "mtf": "MTF50", "moire": "MSP", "achromatic": "AR"}


def _load(repo: Path, run: str):
    import pandas as pd

    base = repo / FOLDER / f"convergence_{run}"
    if not base.with_suffix(".json").is_file() or not base.with_suffix(".csv").is_file():
        raise CfaMitsubaError(f"{FOLDER}/convergence_{run}.json or .csv not found (run cfa-mitsuba convergence)")
    return json.loads(base.with_suffix(".json").read_text()), pd.read_csv(base.with_suffix(".csv"))


def _levels(csv) -> dict:
    """{spp: {wall, radiance-median, radiance-worst, uniform-median, METRIC...}} of the render levels."""
    out = {}
    for spp, g in csv[csv["stage"] == "render"].groupby("quality"):
        q = g["quantity"].astype(str)
        rad, uni = g[q.str.startswith("radiance:")]["error"], g[q.str.startswith("uniform:")]["error"]
        row = {"wall": float(g["wall_s"].min()), "radiance-median": float(rad.median()),
               "radiance-worst": float(rad.max()), "uniform-median": float(uni.median())}
        for r in g[~q.str.contains(":")].itertuples():
            row[r.quantity] = float(r.error)
        out[int(spp)] = row
    return out


def _fmt(value, spec: str) -> str:
    if spec.endswith("%"):
        return format(float(value) * 100, spec[:-1] + "f") + " %"
    return format(value, spec)


def _g(v: float, digits: int = 2) -> str:
    """A deviation: 0 as 0, else ``digits`` significant figures, small ones in e-notation."""
    if v == 0:
        return "0"
    return f"{v:.{digits - 1}e}" if abs(v) < 1e-4 else f"{v:.{digits}g}"


def levels_table(repo: Path, run: str) -> str:
    """Error against spp: per level the best wall time, the radiance error
    (median / worst band over the image, median band over the uniform
    window, %) and each metric's deviation from the reference; the default
    level in bold, its metric deviations the rms over its renders."""
    data, csv = _load(repo, run)
    levels, default = _levels(csv), int(data["plan"]["default_spp"])
    metrics = list(data["reference"]["metric_values"])
    head = ["spp", "wall s", "radiance error, median / worst band (%)", "uniform window, median band (%)",
            *(LABELS.get(m, m) for m in metrics)]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for spp, r in levels.items():
        dev = data["at_default"]["metric_deviation"] if spp == default else r
        cells = [str(spp), f"{r['wall']:.3g}", f"{100 * r['radiance-median']:.3g} / {100 * r['radiance-worst']:.3g}",
                 f"{100 * r['uniform-median']:.2g}", *(_g(dev[m]) for m in metrics)]
        if spp == default:
            cells = [f"**{c}**" for c in cells]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def charts_table(repo: Path, *runs: str) -> str:
    """The flat charts: size, render wall time at each level, the radiance
    error at the default, the reference against the exact box integral,
    every metric's deviation at the default."""
    lines = ["| scene | EXR px | render wall time at each spp level (s; * the default) | radiance error at the "
             "default (median band) | reference vs exact pattern | metric deviation at the default |",
             "|---|---|---|---|---|---|"]
    for run in runs:
        data, csv = _load(repo, run)
        p, levels = data["plan"], _levels(csv)
        size = f"{p['width']} x {p['height']}" + (f" (K {p['oversample']})" if p["oversample"] != 1 else "")
        walls = " / ".join(f"{spp}{'*' if spp == p['default_spp'] else ''}: {r['wall']:.2f}" for spp, r in levels.items())
        exact = (data["reference"].get("exact_check") or {}).get("relative_rms_median_band")
        dev = data["at_default"]["metric_deviation"]
        units = {m: c.get("unit", "") for m, c in data["checks"].items()}
        devs = ", ".join(f"{NAMES.get(m, m)} {_g(v, 1)}" + (f" {units[m]}" if units.get(m) and m in ("mtf", "moire")
                                                             else "") for m, v in dev.items())
        lines.append(f"| `{run}` | {size} | {walls} | {_g(data['at_default']['radiance image median band'])} | "
                     f"{'—' if exact is None else _g(exact)} | {devs} |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def check_table(repo: Path, run: str) -> str:
    """The render-induced deviation at the default spp against the
    differences between the compared CFAs (``checks`` of the run's JSON)."""
    data, _ = _load(repo, run)
    n, cfas = data["at_default"]["renders"], ", ".join(data["plan"]["compare_cfas"])
    head = ["metric", "reference value", f"render-induced deviation (rms, {n} renders)",
            "change of the differences between CFAs (rms)", f"spread between {cfas}", "deviation / spread",
            "differences / spread", "smallest gap", "sensor-noise std (one seed to another)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for m, c in data["checks"].items():
        diff = c["cfa_difference_deviation"] / c["cfa_spread"]
        cells = [NAMES.get(m, m), f"{c['reference_value']:.3g}", _g(c["render_deviation_at_default"]),
                 _g(c["cfa_difference_deviation"]), f"{c['cfa_spread']:.2g}", f"{c['ratio_to_spread']:.2f}",
                 f"**{diff:.2f}**" if diff > 0.1 else f"{diff:.2f}", _g(c["cfa_smallest_gap"]),
                 _g(c["sensor_noise_std"])]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def pocs_table(repo: Path, *runs: str) -> str:
    """The default POCS (its iteration cap and tolerance) against the
    converged one: iterations run, time, deviation, the spread between the
    CFAs with POCS, their ratio, the fitted rate per iteration."""
    lines = ["| scene | iterations run | processing time (s) | deviation | spread between the CFAs with POCS "
             "| deviation / spread | rate per iteration |", "|---|---|---|---|---|---|---|"]
    for run in runs:
        data, _ = _load(repo, run)
        pd_, checks, rates = data["pocs_default"], data["pocs_checks"], data["rates"].get("pocs", {})
        size = f" ({data['plan']['width']} x {data['plan']['height']})" if data["plan"]["is_3d"] else ""
        dev = ", ".join(f"{NAMES.get(m, m)} {_g(c['pocs_default_deviation'])}" for m, c in checks.items())
        spread = ", ".join(f"{c['cfa_spread']:.2g}" for c in checks.values())
        ratio = ", ".join(f"{c['ratio_to_spread']:.2g}" for c in checks.values())
        rate = [rates.get(m, {}).get("per_iteration") for m in checks]
        rate = "(all 0)" if all(r is None for r in rate) else ", ".join("n/a" if r is None else f"{r:.2g}" for r in rate)
        lines.append(f"| `{run}`{size} | {pd_['iterations_done']} | {pd_['wall_s']:.2g} | {dev} | {spread} | "
                     f"{ratio} | {rate} |")
    return "\n\n" + "\n".join(lines) + "\n\n"


def convergence_number(repo: Path, run: str, key: str, spec: str = "") -> str:
    """One number of a convergence run (see the module docstring for ``KEY``)."""
    data, csv = _load(repo, run)
    head, _, rest = key.partition(".")
    if head.isdigit():
        levels = _levels(csv)
        if int(head) not in levels or rest not in levels[int(head)]:
            raise CfaMitsubaError(f"convergence_{run}: no {rest!r} at {head} spp")
        value = levels[int(head)][rest]
    else:
        value = data
        for part in key.split("."):
            part = part.replace("+", " ")
            if isinstance(value, list) and part.isdigit():
                value = value[int(part)]
            elif isinstance(value, dict) and part in value:
                value = value[part]
            else:
                raise CfaMitsubaError(f"convergence_{run}.json has no {key!r}")
    return _fmt(value, spec) if spec else str(value)


#: {name: function(repo, *args) -> Markdown}
GENERATORS = {
    "convergence-levels": levels_table,
    "convergence-charts": charts_table,
    "convergence-check": check_table,
    "convergence-pocs": pocs_table,
    "convergence": convergence_number,
}
