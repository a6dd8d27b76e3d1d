"""The full chain: the chosen candidates, written as CFA TOML files, and the
named CFAs through one study (:func:`cfa_mitsuba.study.runner.run_study`):
the same cached renders and optical images for every CFA, several noise
realisations per value (the study's ``seeds``), local processes or a Dask
cluster (:mod:`cfa_mitsuba.study.executors`), and resumption from the
study's ``.work/`` files.

A candidate's TOML is an ordinary user CFA (docs/sensor.md s. 5.1): the
tile, the spectra set of its letters and, for parametric filters, each
free letter's QE curve as a table of numbers.  ``cfa-mitsuba study`` on the
same TOML path, with the same study settings, reproduces the design's
numbers (the noise seeds derive from the CFA's path, so from another path
they are other realisations of the same camera: equal within the
intervals).
"""

from __future__ import annotations

__all__ = ["candidate_name", "write_cfa_toml", "run_fullchain", "objective_table"]

import dataclasses
import hashlib
import json
from pathlib import Path

import numpy as np

from ..io.validate import safe_name
from .cfa_toml import curve_line, write_lines
from .config import BEST, SNR10
from .spectra import letter_curves


def candidate_name(design_name: str, key: str) -> str:
    """A stable, unique name for a candidate: the design, the tile size and
    a hash of the candidate's key."""
    tile = key.split(":", 1)[0]
    return f"{safe_name(design_name)}-{tile}-{hashlib.sha1(key.encode()).hexdigest()[:6]}"


def _toml_str(s: str) -> str:
    return json.dumps(s)


def write_cfa_toml(path: Path, name: str, row, config) -> Path:
    """Write one candidate (a candidates.csv row) as a CFA TOML."""
    h, w = (int(x) for x in row["tile"].split("x"))
    rows = [r.strip() for r in row["tile_text"].split("/")]
    lines = [f"# cfa-mitsuba design {config.name!r}: a candidate CFA ({h}x{w}).",
             f"# proxies: aliasing {row['aliasing']:.4g}, noise {row['noise']:.4g}, "
             f"colour {row['colour']:.4g} dE00 (training fit)",
             f"name = {_toml_str(name)}",
             f"description = {_toml_str(f'designed by cfa-mitsuba design ({config.name}): {row.tile_text}')}",
             "tile = [" + ", ".join(_toml_str(r) for r in rows) + "]",
             f"spectra_set = {_toml_str(config.spectra_set)}"]
    if row.get("params"):
        params = json.loads(row["params"])
        curves = letter_curves(config.alphabet, config.spectra_set, config.spectra, params)
        used = set(rows[0].split()) | {c for r in rows for c in r.split()}
        lines.append("")
        lines.append(f"[spectra]   # {config.spectra.family}: {json.dumps(dict(zip(config.spectra.letters, params)))}")
        for letter in config.spectra.letters:
            if letter not in used:
                continue
            lines.append(curve_line(letter, *curves[letter]))
    return write_lines(path, lines)


def _one(metrics, lab, o, demosaic):
    """(mean, low, high, n) of objective ``o`` for CFA ``lab`` with ``demosaic``."""
    if o.metric == SNR10:
        from ..study.snr import snr10_table, snr_table

        sel = metrics[(metrics["cfa"] == lab) & (metrics["scene"] == o.scene) & (metrics["demosaic"] == demosaic)]
        t = snr10_table(snr_table(sel, metric=o.basis))  # the per-pixel or the area-referred YSNR rows

        def num(v):  # an interval curve that never reaches YSNR 10 in the sweep: unbounded on that side
            return float(v) if v is not None and np.isfinite(float(v)) else float("nan")

        if t.empty or not np.isfinite(num(t["snr10_cd_m2"].iloc[0])):
            return (float("nan"),) * 3 + (0,)
        r = t.iloc[0]
        n = int(sel[sel["metric"] == o.basis]["n"].min()) if "n" in sel else 0

        low, high = num(r["ci_low"]), num(r["ci_high"])
        return (float(r["snr10_cd_m2"]), low if np.isfinite(low) else 0.0,
                high if np.isfinite(high) else float("inf"), n)
    sel = metrics[(metrics["cfa"] == lab) & (metrics["scene"] == o.scene) & (metrics["demosaic"] == demosaic)
                  & (metrics["metric"] == o.metric)
                  & ((metrics["luminance"].astype(float) - o.luminance).abs() < 1e-9)]
    base = sel[sel["base"].astype(str).str.lower().isin(("true", "1"))]
    sel = base if len(base) else sel
    if sel.empty:
        return (float("nan"),) * 3 + (0,)
    r = sel.iloc[0]
    return float(r["value"]), float(r["ci_low"]), float(r["ci_high"]), int(r["n"])


def objective_table(metrics, labels, objectives, demosaics=("bilinear",), transposed=None):
    """{cfa label: {objective label: (mean, low, high, n, demosaic)}} from a
    study's metrics.csv table; an objective with ``demosaic = "best"`` takes,
    per CFA, the best mean over ``demosaics`` (the study's); one with
    ``orientation = "both"`` the worse of the CFA's value and its transposed
    tile's (``transposed``: {label: the transposed CFA's label}; a CFA not in
    it is its own transpose; design/orientation.py)."""
    from .orientation import worse

    def value(lab, o):
        tried = [(*_one(metrics, lab, o, d), d) for d in (demosaics if o.demosaic == BEST else (o.demosaic,))]
        ok = [t for t in tried if np.isfinite(t[0])]
        sign = -1.0 if o.goal == "max" else 1.0
        return min(ok, key=lambda t: sign * t[0]) if ok else tried[0]

    transposed = transposed or {}
    out = {}
    for lab in labels:
        got = {}
        for o in objectives:
            got[o.label] = value(lab, o)
            if o.orientation == "both" and lab in transposed:
                got[o.label] = worse(got[o.label], value(transposed[lab], o), o.goal)
        out[lab] = got
    return out


def run_fullchain(config, chosen, out_dir: Path, *, workers=None, scheduler=None, progress=True, log=print):
    """Write the chosen candidates' TOMLs (``out_dir/cfas/``) and run them
    with the named CFAs through the study of ``config``.

    ``chosen``: candidates.csv rows (a DataFrame).  Returns (per-CFA
    objective values, {candidate key: (name, toml path)}, StudyResult).
    """
    from ..sensor import get_cfa
    from ..study.runner import run_study
    from .orientation import own_transpose, transposed_name, write_transposed_toml

    names = {}
    for _, row in chosen.iterrows():
        name = candidate_name(config.name, row["key"])
        path = write_cfa_toml(out_dir / "cfas" / f"{name}.toml", name, row, config)
        names[row["key"]] = (name, str(path.resolve()))
    named = list(config.study.cfas)
    transposed, extra = {}, []  # orientation = "both": each tile that is not its own transpose, transposed too
    if any(o.orientation == "both" for o in (*config.objectives, *config.constraints)):
        for c in named + [p for _, p in names.values()]:
            cfa = get_cfa(c)
            if not own_transpose(cfa.pattern):
                p = write_transposed_toml(out_dir / "cfas" / "transposed" / f"{transposed_name(cfa.name)}.toml", cfa)
                transposed[cfa.name] = transposed_name(cfa.name)
                extra.append(str(p.resolve()))
    study = dataclasses.replace(config.study, name=f"{config.name}-fullchain",
                                cfas=tuple(named) + tuple(p for _, p in names.values()) + tuple(extra),
                                output={**config.study.output, "report": False},
                                workers=config.workers)  # a config's workers are capped at the cores
    result = run_study(study, out_dir / "study", workers=workers, scheduler=scheduler,
                       progress=progress, log=log)
    labels = [get_cfa(c).name for c in named] + [n for n, _ in names.values()]
    return (objective_table(result.metrics, labels, config.objectives + config.constraints, config.study.demosaics,
                            transposed),
            names, result)
