"""``cfa-mitsuba design``: search, proxy, full chain, front, report.

    OUT/
      candidates.csv   every candidate: tile, densities, proxies, proxy score and rank,
                       ``chosen`` (best | sample | '') for the full chain
      fullchain.csv    every CFA through the full chain (candidates and the named CFAs):
                       per objective and constraint the mean and its 95 % interval,
                       feasibility, ``dominated_by``, ``pareto``
      pareto.csv       the Pareto candidates (the rows of fullchain.csv on the front)
      cfas/*.toml      one CFA TOML per candidate run through the full chain
      agreement.json   the proxy's rank agreement with the full chain
      design.html, figures/   the report (design/report.py)
      study/           the full chain's study (metrics.csv, scores.csv, ...)
      .design/         the search's saved state (resumption)
"""

from __future__ import annotations

__all__ = ["run_design", "DesignResult"]

import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io import atomic_output, check_writable_dir
from .proxy import PROXY_NAMES


@dataclass
class DesignResult:
    out_dir: Path
    candidates: object
    fullchain: object
    pareto: object
    agreement: dict
    timing: dict
    search: object


def _save_csv(path: Path, df) -> None:
    with atomic_output(path) as tmp:
        df.to_csv(tmp, index=False, float_format="%.8g")


def _bound(c, table_row, values) -> float:
    return float(values[c.bound][c.label][0]) if isinstance(c.bound, str) else float(c.bound)


def _fullchain_table(config, search, values, names, named_proxies, out):
    """fullchain.csv: one row per CFA run through the full chain; a
    candidate's ``toml`` relative to the output folder ``out``."""
    import pandas as pd

    from ..io.portable import relative_path

    cands = search.set_index("key")
    rows = []
    for cfa in [c for c in values if c not in {n for n, _ in names.values()}]:
        rows.append({"cfa": cfa, "kind": "named", "key": "", "toml": "", "tile_text": named_proxies[cfa]["tile_text"],
                     **{p: named_proxies[cfa].get(p) for p in PROXY_NAMES}, "proxy_score": np.nan})
    for key, (name, path) in names.items():
        c = cands.loc[key]
        extra = {k: c[k] for k in ("gradient_colour", "gradient_noise") if k in c}  # the gradient method's
        rows.append({"cfa": name, "kind": "candidate", "key": key, "toml": relative_path(path, out),
                     "tile_text": c["tile_text"], **{p: c[p] for p in PROXY_NAMES}, **extra,
                     "proxy_score": c["proxy_score"], "proxy_rank": int(c["proxy_rank"]), "chosen": c["chosen"]})
    table = pd.DataFrame(rows)
    for o in (*config.objectives, *config.constraints):
        got = [values[c][o.label] for c in table["cfa"]]
        table[o.label] = [g[0] for g in got]
        table[f"{o.label} low"] = [g[1] for g in got]
        table[f"{o.label} high"] = [g[2] for g in got]
        table[f"{o.label} n"] = [g[3] for g in got]
        if o.demosaic == "best":
            table[f"{o.label} demosaic"] = [g[4] for g in got]
    feasible = np.ones(len(table), bool)
    for c in config.constraints:
        bound = _bound(c, None, values)
        v = table[c.label].to_numpy(dtype=float)
        feasible &= (v <= bound + 1e-12) if c.goal == "max" else (v >= bound - 1e-12)
    table["feasible"] = feasible
    return table


def run_design(config, out_dir, *, workers=None, scheduler=None, progress=True, log=print,
               force: bool = False) -> DesignResult:
    """Run a design (a :class:`~.config.DesignConfig`) into ``out_dir``;
    ``force`` starts a search above the size limits (design.sizing)."""
    from ..sensor import get_cfa
    from . import front
    from .fullchain import run_fullchain
    from .report import build_design_report
    from .search import cfa_proxies, proxy_settings, run_search, used_proxies

    from .sizing import check_design_size

    check_design_size(config, force=force, log=log)  # issue 27: sized before anything is written
    out = check_writable_dir(out_dir)
    t0 = time.perf_counter()
    timing = {}
    log(f"design {config.name!r}: {', '.join(f'{h}x{w}' for h, w in config.tiles)} tiles of "
        f"{' '.join(config.alphabet)} ({config.spectra_set}"
        + (f"; {config.spectra.family} spectra for {' '.join(config.spectra.letters)}" if config.spectra else "")
        + f"); {len(config.objectives)} objective(s), {len(config.constraints)} constraint(s)")
    if config.method == "gradient":
        from .gradient_search import gradient_selection, run_gradient

        res = run_gradient(config, out, log=log)
    else:
        res = run_search(config, out, log=log, progress=progress)
    cands = res.candidates
    timing["search_s"] = time.perf_counter() - t0
    log(f"proxy: {len(cands):,} candidates ({res.evaluated:,} evaluated now, {res.reused:,} taken from saved state) "
        f"in {timing['search_s']:.1f} s")

    selection = used_proxies(config)
    if config.method == "gradient":  # the front of the gradient's own two objectives
        cands["proxy_score"], selection = gradient_selection(cands)
    else:
        cands["proxy_score"] = front.proxy_scores(cands, config.objectives)
    order = np.argsort(cands["proxy_score"].to_numpy(), kind="stable")
    rank = np.empty(len(cands), int)
    rank[order] = np.arange(1, len(cands) + 1)
    cands["proxy_rank"] = rank
    best, sample = front.select(cands, selection, config.full_chain, config.agreement_sample, config.seed)
    chosen = np.array([""] * len(cands), dtype=object)
    chosen[best], chosen[sample] = "best", "sample"
    cands["chosen"] = chosen
    settings = proxy_settings(config)
    named_proxies = {}
    for c in config.study.cfas:
        cfa = get_cfa(c)
        named_proxies[cfa.name] = {**cfa_proxies(cfa, settings), "tile_text": cfa.tile_text()}
    _save_csv(out / "candidates.csv", cands.sort_values("proxy_rank", kind="stable"))

    t1 = time.perf_counter()
    picked = cands.iloc[best + sample]
    log(f"full chain: {len(best)} best and {len(sample)} sampled candidate(s) with {len(config.study.cfas)} "
        f"named CFA(s), {config.study.seeds} noise realisation(s) each")
    values, names, study = run_fullchain(config, picked, out, workers=workers, scheduler=scheduler,
                                         progress=progress, log=log)
    timing["fullchain_s"] = time.perf_counter() - t1
    table = _fullchain_table(config, cands, values, names, named_proxies, out)
    table["dominated_by"] = front.pareto(table, config.objectives)
    table["pareto"] = (table["kind"] == "candidate") & table["feasible"] & (table["dominated_by"] == "")
    table["score"] = front.fullchain_scores(table, config.objectives)
    if config.method == "gradient":  # predicted by what the gradient optimised
        from .gradient_search import gradient_objectives

        agree = front.agreement(table, gradient_objectives(config))
    else:
        agree = front.agreement(table, config.objectives)
    n_cand = int((table["kind"] == "candidate").sum())
    agree["fullchain_s_per_candidate"] = timing["fullchain_s"] / max(1, n_cand + len(config.study.cfas))
    _save_csv(out / "fullchain.csv", table)
    front_rows = table[table["pareto"]]
    _save_csv(out / "pareto.csv", front_rows)
    with atomic_output(out / "agreement.json") as tmp:
        tmp.write_text(json.dumps(agree, indent=1))
    t2 = time.perf_counter()
    build_design_report(out, config, cands, table, agree, named_proxies, study.out_dir)
    timing["report_s"] = time.perf_counter() - t2
    timing["total_s"] = time.perf_counter() - t0
    with atomic_output(out / "timing.json") as tmp:
        tmp.write_text(json.dumps(timing, indent=1))
    comb = agree.get("combined")
    log(f"front: {len(front_rows)} Pareto candidate(s) of {n_cand}; proxy agreement (Spearman, combined): "
        + ("n/a" if comb is None else f"{comb:+.2f}") + f"; done in {timing['total_s']:.1f} s "
        f"(search {timing['search_s']:.1f} s, full chain {timing['fullchain_s']:.1f} s, report {timing['report_s']:.1f} s)")
    return DesignResult(out, cands, table, front_rows, agree, timing, res)
