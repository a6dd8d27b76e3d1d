"""The paper's numbers, ISETCam's, the claims, and two study runs to test
them on (docs/paper-comparison.md, :mod:`.paper_comparison`).

Data (``cfa_mitsuba/data/paper/``): ``bae2020_values.csv`` (Tables 1-3 and
the numbers in the text of Bae 2020, each with its table and status),
``isetcam_paper_check.csv`` (ISETCam itself run on the paper's colour
table, research/isetcam-paper-check.md) and ``claims.toml`` (the claims,
with the reason to print for each verdict).

Verdicts (:mod:`.claim_verdicts` states the rule): a claim *holds* when
every comparison it makes is separated in the claimed direction by the
run's 95 % intervals, *differs* when one is separated the other way, and
is a *tie* when none is reversed but some intervals overlap.  Group claims
are judged pairwise, CFA against CFA.
"""

from __future__ import annotations

__all__ = ["PAPER_DIR", "Run", "load_run", "paper_values", "isetcam_values", "claims", "judge", "family",
           "cfa_label"]

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError
from ..io.guard import read_csv, read_json, read_toml
from ..metrics import get_metric
from ..study.details_layout import output_folder
from .claim_verdicts import at_most_verdict, best_verdict, order_verdict, spread_verdict

PAPER_DIR = Path(__file__).resolve().parents[1] / "data" / "paper"
_FAMILIES = (("rgbw", "RGBW"), ("cmy", "CMY"), ("rgb", "RGB"), ("bayer", "RGB"))


def family(cfa: str) -> str:
    """RGB, CMY or RGBW for the paper's CFAs ('' for any other)."""
    return next((f for p, f in _FAMILIES if cfa.startswith(p)), "")


def cfa_label(cfa: str) -> str:
    """The paper's spelling: Bayer, RGB1, CMY2, RGBW3."""
    return "Bayer" if cfa == "bayer" else cfa.upper()


def _csv(name: str):
    return read_csv(PAPER_DIR / name, comment="#", dtype=str, keep_default_na=False)


def paper_values():
    """bae2020_values.csv as a DataFrame of text, as printed (``cfas``: the
    CFAs of each row; ``number``: the value as a float, NaN for a range)."""
    df = _csv("bae2020_values.csv")
    df["cfas"] = df["cfa"].str.split()
    df["number"] = [float(v) if v else float("nan") for v in df["value"]]
    return df


def isetcam_values():
    """isetcam_paper_check.csv as a DataFrame."""
    return _csv("isetcam_paper_check.csv")


def claims() -> list[dict]:
    """The claims of claims.toml, in order."""
    return read_toml(PAPER_DIR / "claims.toml", "paper claims")["claim"]


@dataclass
class Run:
    """One study's results: base rows at its first luminance, the scores,
    its config and timing."""

    key: str
    label: str
    path: Path
    metrics: object
    scores: object
    config: dict
    timing: dict
    cfa_facts: dict = field(default_factory=dict)
    realisations: object = None
    decisions: object = None
    _wide: dict = field(default_factory=dict, repr=False)

    def _comparison(self, metric: str, demosaic: str):
        """(cfas x realisations values, render seeds, pooled render component
        of every pair's differences) of one metric and demosaic, or None."""
        key = (metric, demosaic)
        if key not in self._wide:
            from ..study.intervals import difference_pool

            r = self.realisations
            sel = r[(r["metric"] == metric) & (r["demosaic"] == demosaic)]
            if sel.empty:
                self._wide[key] = None
            else:
                wide = sel.pivot_table(index="cfa", columns="realisation", values="value", aggfunc="mean")
                seeds = (sel.groupby("realisation")["render_seed"].max().reindex(wide.columns).fillna(0).astype(int)
                         if "render_seed" in sel.columns else None)
                groups = None if seeds is None else seeds.to_numpy()
                self._wide[key] = (wide, groups, difference_pool(wide.to_numpy(float), groups))
        return self._wide[key]

    def paired(self, metric: str, demosaic: str, a: str, b: str):
        """(lo, hi) of the 95 % interval of CFA ``a``'s value minus ``b``'s over
        paired realisations, the render component pooled over every pair of
        CFAs of that metric and demosaic, as the study's rank intervals
        (study/intervals.py); None without realisations."""
        r = self.realisations
        if r is None or r.empty:
            return None
        from ..study.intervals import paired_difference

        got = self._comparison(metric, demosaic)
        if got is None or a not in got[0].index or b not in got[0].index:
            return None
        wide, groups, pool = got
        _, lo, hi, n = paired_difference(wide.loc[a].to_numpy(float), wide.loc[b].to_numpy(float), groups, pool)
        return (lo, hi) if n else None

    def decision(self, demosaic: str):
        """decisions.csv's row for a demosaic or 'total' ('overall'), None
        when the run's decisions.csv has none (written before issue 46)."""
        d = self.decisions
        if d is None or "robust" not in d.columns:
            return None
        aspect = "overall" if demosaic == "total" else f"with {demosaic}"
        sel = d[d["aspect"] == aspect]
        return None if sel.empty else sel.iloc[0]

    def value(self, metric: str, demosaic: str, cfa: str):
        """(value, ci_low, ci_high, unit) of one CFA, or None."""
        m = self.metrics
        sel = m[(m["metric"] == metric) & (m["demosaic"] == demosaic) & (m["cfa"] == cfa)]
        if sel.empty:
            return None
        r = sel.iloc[0]
        lo = r["ci_low"] if "ci_low" in r and np.isfinite(r["ci_low"]) else r["value"]
        hi = r["ci_high"] if "ci_high" in r and np.isfinite(r["ci_high"]) else r["value"]
        return float(r["value"]), float(lo), float(hi), str(r["unit"]) if isinstance(r["unit"], str) else ""

    def row(self, metric: str, demosaic: str, cfa: str):
        """metrics.csv's row of one CFA (a pandas Series), or None."""
        m = self.metrics
        sel = m[(m["metric"] == metric) & (m["demosaic"] == demosaic) & (m["cfa"] == cfa)]
        return None if sel.empty else sel.iloc[0]

    def is_bound(self, metric: str, demosaic: str, cfa: str) -> bool:
        """Whether a value is a bound, not a measurement (the MSP of a chirp
        with no moire up to its top in every realisation): metrics.csv's
        ``censored`` column (read under study/censored.py's rule) where the
        study wrote one, else the first realisation's ``passed`` flag."""
        m = self.metrics
        sel = m[(m["metric"] == metric) & (m["demosaic"] == demosaic) & (m["cfa"] == cfa)]
        if not len(sel):
            return False
        if "censored" in m.columns:
            return str(sel["censored"].iloc[0]).lower() in ("true", "1")
        if get_metric(metric).censored_key is None:  # a metric always measured
            return False
        # a table written before the censored column: the first realisation's details, on the scene of the row
        row = sel.iloc[0]
        f = output_folder(self.path / "details", row["scene"], cfa, demosaic) / f"L{float(row['luminance']):g}.json"
        try:
            return read_json(f, allow_nan=True)[metric].get("passed") is False
        except (OSError, ValueError, KeyError, AttributeError, CfaMitsubaError):
            return False

    def scores_of(self, demosaic: str):
        """{cfa: (score, lo, hi, rank, rank_best, rank_worst)} for a demosaic or 'total'."""
        s = self.scores
        if s is None or s.empty:
            return {}
        if demosaic == "total":
            cols = ["total_score", "total_score_ci_low", "total_score_ci_high", "total_rank", "total_rank_best",
                    "total_rank_worst"]
            rows = s.drop_duplicates("cfa")
        else:
            cols = ["mean_score", "mean_score_ci_low", "mean_score_ci_high", "demosaic_rank", "demosaic_rank_best",
                    "demosaic_rank_worst"]
            rows = s[s["demosaic"] == demosaic].drop_duplicates("cfa")
        return {r["cfa"]: tuple(float(r[c]) if "score" in c else int(r[c]) for c in cols) for _, r in rows.iterrows()}


def load_run(path, key: str, label: str) -> Run:
    """A study's results folder (metrics.csv, scores.csv, config.json, timing.json)."""
    from ..study.censored import apply_rule

    p = Path(path)
    if not (p / "metrics.csv").is_file():
        raise CfaMitsubaError(f"{str(p)!r} holds no metrics.csv: not a study's results folder")
    m = read_csv(p / "metrics.csv")
    all_real = read_csv(p / "metrics_realisations.csv") if (p / "metrics_realisations.csv").is_file() else None
    m = apply_rule(m, all_real)  # an older metrics.csv read under one rule for bounds
    base = m[m["base"].astype(str).str.lower().isin(("true", "1"))]
    base = base[base["luminance"] == base["luminance"].min()]
    scores = read_csv(p / "scores.csv") if (p / "scores.csv").is_file() else None
    if scores is not None and not scores.empty:
        scores = scores[scores["luminance"] == scores["luminance"].min()]

    def read(name):
        f = p / name
        return read_json(f, allow_nan=True) if f.is_file() else {}

    every = None
    if all_real is not None:  # paired comparisons for the claims
        every = all_real[all_real["base"].astype(str).str.lower().isin(("true", "1"))]
        every = every[every["luminance"] == every["luminance"].min()].reset_index(drop=True)
    decisions = (read_csv(p / "decisions.csv", dtype=str, keep_default_na=False)
                 if (p / "decisions.csv").is_file() else None)
    return Run(key, label, p, base.reset_index(drop=True), scores, read("config.json"), read("timing.json"),
               read("cfas.json"), every, decisions)


def _group(run: Run, metric: str, demosaic: str, cfas) -> list[tuple]:
    out = []
    for c in cfas:
        v = run.value(metric, demosaic, c)
        if v is not None:
            out.append((c, *v[:3]))
    return out


def _group_name(cfas) -> str:
    fams = {family(c) for c in cfas}
    if "" not in fams and ((len(fams) == 1 and len(cfas) >= 3) or (len(fams) == 2 and len(cfas) > 3)):
        return "+".join(sorted(fams, key=["RGB", "CMY", "RGBW"].index))
    return ", ".join(cfa_label(c) for c in cfas)


def _fmt(v: float, decimals: int) -> str:
    return f"{v:.{decimals}f}"


def _order(run: Run, claim: dict) -> tuple[str, str]:
    """Every CFA of an earlier group against every CFA of each later one (:mod:`.claim_verdicts`)."""
    metric, demosaic = claim["metric"], claim["demosaic"]
    hib = get_metric(metric).higher_is_better
    dec = get_metric(metric).decimals + 1
    groups = [_group(run, metric, demosaic, g) for g in claim["groups"]]
    if any(not g for g in groups):
        return "not measured", "a group has no value in this run"
    parts = []
    for names, g in zip(claim["groups"], groups):
        ranked = sorted(g, key=lambda r: r[1], reverse=hib)
        parts.append(f"{_group_name(names)} from {cfa_label(ranked[0][0])} {_fmt(ranked[0][1], dec)} "
                     f"to {cfa_label(ranked[-1][0])} {_fmt(ranked[-1][1], dec)}" if len(g) > 1 else
                     f"{cfa_label(g[0][0])} {_fmt(g[0][1], dec)} [{_fmt(g[0][2], dec)}, {_fmt(g[0][3], dec)}]")
    labelled = [[(cfa_label(r[0]), *r[1:]) for r in g] for g in groups]
    cfa_of = {cfa_label(r[0]): r[0] for g in groups for r in g}
    paired = None
    if run.realisations is not None:
        def paired(a, b):
            return run.paired(metric, demosaic, cfa_of[a], cfa_of[b])
    verdict, words = order_verdict(labelled, hib, paired)
    return verdict, "; ".join(parts) + f" ({'higher' if hib else 'lower'} is better; {words})"


def _similar(run: Run, claim: dict) -> tuple[str, str]:
    g = _group(run, claim["metric"], claim["demosaic"], claim["cfas"])
    if not g:
        return "not measured", "no value in this run"
    vals = [r[1] for r in g]
    dec = get_metric(claim["metric"]).decimals + 1
    spread = max(vals) - min(vals)
    lo_c, hi_c = min(g, key=lambda r: r[1])[0], max(g, key=lambda r: r[1])[0]
    detail = (f"{_fmt(min(vals), dec)} ({cfa_label(lo_c)}) to {_fmt(max(vals), dec)} ({cfa_label(hi_c)}): "
              f"spread {_fmt(spread, dec)} (intervals' outer ends {_fmt(max(r[3] for r in g) - min(r[2] for r in g), dec)}, "
              f"inner ends {_fmt(max(r[2] for r in g) - min(r[3] for r in g), dec)}) against at most {claim['max_range']:g}")
    return spread_verdict(g, claim["max_range"]), detail


def _at_most(run: Run, claim: dict) -> tuple[str, str]:
    g = _group(run, claim["metric"], claim["demosaic"], claim["cfas"])
    if not g:
        return "not measured", "no value in this run"
    dec = get_metric(claim["metric"]).decimals + 1
    top = max(g, key=lambda r: r[3])
    detail = (f"every CFA's interval below {_fmt(top[3], dec)} (the highest: {cfa_label(top[0])} "
              f"{_fmt(top[1], dec)}) against at most {claim['max_value']:g}")
    return at_most_verdict(g, claim["max_value"]), detail


def _best(run: Run, claim: dict) -> tuple[str, str]:
    """A "best" claim by the one decision rule (study/decisions.py): decisions.csv's
    row of the demosaic (or 'overall') where the run has it, else the rank
    intervals alone (a run written before the rule had a practical difference)."""
    got = run.scores_of(claim["demosaic"])
    if claim["cfa"] not in got:
        return "not measured", "no score in this run"
    s = got[claim["cfa"]]
    row = run.decision(claim["demosaic"])
    if row is not None:
        named = str(row["cfas"]).split()
        verdict = ("holds" if row["verdict"] == "winner" and named == [claim["cfa"]]
                   else "tie" if claim["cfa"] in named and row["verdict"] != "winner" else "differs")
        detail = (f"{cfa_label(claim['cfa'])} rank {s[3]} (interval {s[4]}-{s[5]}) of {len(got)}, score {s[0]:.4f}; "
                  f"decision: {row['verdict']} ({', '.join(cfa_label(c) for c in named) or 'none'})")
        return verdict, detail
    can_be_first = [cfa_label(c) for c, r in sorted(got.items(), key=lambda kv: -kv[1][0]) if r[4] == 1]
    detail = (f"{cfa_label(claim['cfa'])} rank {s[3]} (interval {s[4]}-{s[5]}) of {len(got)}, score {s[0]:.4f}; "
              f"rank interval containing 1: {', '.join(can_be_first)}")
    return best_verdict(s[4], s[5]), detail


def judge(run: Run, claim: dict) -> tuple[str, str]:
    """(verdict, what the run measured) of one claim on one run."""
    kind = claim.get("kind")
    if kind == "order":
        return _order(run, claim)
    if kind == "similar":
        return _similar(run, claim)
    if kind == "at_most":
        return _at_most(run, claim)
    if kind == "best":
        return _best(run, claim)
    raise CfaMitsubaError(f"claim {claim.get('id')!r}: unknown kind {kind!r}")
