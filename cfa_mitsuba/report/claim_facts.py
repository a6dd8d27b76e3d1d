"""Facts in the claims' explanations, generated from a run's CSVs.

An explanation in ``data/paper/claims.toml`` (``why_holds``, ``why_differs``,
``why_tie``) states its facts only through ``{name}`` fields, each declared
in the claim's ``facts`` table and filled here from the run the verdict is
about, so a sentence can never contradict the numbers it explains (issue
46 found five that did).  Every fact is computed from metrics.csv's base
rows at the run's first luminance (:class:`.paper_data.Run`), with the
metric's own direction and decimals; the comparison words ("above",
"below", "worse than") come from the numbers too.

Kinds (each a TOML inline table with ``kind`` and its fields):

- ``means``: ``metric``, ``demosaic``, ``groups`` (two lists of CFAs),
  ``labels`` (their names) -> "RGB 0.887, above CMY and RGBW 0.765"
  (the groups' arithmetic means);
- ``spread``: ``metric``, ``demosaic``, ``cfas`` -> "0.087 (RGB4 0.300 to
  RGB3 0.387)" (the largest value minus the smallest);
- ``rank``: ``metric``, ``demosaic``, ``cfa``, ``side`` ("lowest" or
  "highest") -> "6th lowest of 12 (the lowest: CMY2 0.771)";
- ``ratio``: ``column`` (a metrics.csv column, e.g. ``exposure_s``),
  ``metric``, ``demosaic``, ``scene`` (optional), ``a``, ``b`` -> "2.2"
  (a's over b's);
- ``correlation``: ``metric``, ``other``, ``demosaic`` -> "+0.29"
  (Spearman's rho of the two metrics over the CFAs both have);
- ``compare``: ``metric``, ``demosaic``, ``a``, ``b`` -> "0.765 (worse
  than Bayer's 0.659)" (a's value against b's, "better"/"worse" by the
  metric's direction).
"""

from __future__ import annotations

__all__ = ["KINDS", "fact_text", "explanation", "ordinal"]

import string

import numpy as np

KINDS = ("means", "spread", "rank", "ratio", "correlation", "compare")


def ordinal(k: int) -> str:
    """1st, 2nd, 3rd, 4th, 11th, 12th, 21st."""
    suffix = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suffix}"


def _values(run, metric: str, demosaic: str, column: str = "value", scene: str | None = None) -> dict:
    m = run.metrics
    sel = m[(m["metric"] == metric) & (m["demosaic"] == demosaic)]
    if scene is not None:
        sel = sel[sel["scene"] == scene]
    if sel.empty:
        raise KeyError(f"no {metric} with {demosaic} in {run.path}")
    return {str(c): float(g[column].iloc[0]) for c, g in sel.groupby("cfa", sort=False)}


def fact_text(run, spec: dict) -> str:
    """The text of one fact (module docstring) on ``run`` (a :class:`.paper_data.Run`); a fact about a
    CFA or metric the run lacks reads "(not measured in this run)"."""
    from ..errors import CfaMitsubaError

    kind = spec.get("kind")
    if kind not in KINDS:
        raise CfaMitsubaError(f"claim fact: unknown kind {kind!r} (expected one of: {', '.join(KINDS)})")
    try:
        return _fact(run, spec, kind)
    except (KeyError, ValueError, ZeroDivisionError):  # a CFA or metric the run does not have
        return "(not measured in this run)"


def _fact(run, spec: dict, kind: str) -> str:
    from ..metrics import get_metric
    from .paper_data import cfa_label

    if kind == "ratio":
        v = _values(run, spec["metric"], spec["demosaic"], spec["column"], spec.get("scene"))
        return f"{v[spec['a']] / v[spec['b']]:.1f}"
    rec = get_metric(spec["metric"])
    dec = rec.decimals
    v = _values(run, spec["metric"], spec["demosaic"])
    if kind == "means":
        (ga, gb), (la, lb) = spec["groups"], spec["labels"]
        ma, mb = float(np.mean([v[c] for c in ga])), float(np.mean([v[c] for c in gb]))
        if not (np.isfinite(ma) and np.isfinite(mb)):
            raise ValueError("empty group")
        word = "above" if round(ma, dec) > round(mb, dec) else "below" if round(ma, dec) < round(mb, dec) else "equal to"
        return f"{la} {ma:.{dec}f}, {word} {lb} {mb:.{dec}f}"
    if kind == "spread":
        got = {c: v[c] for c in spec["cfas"]}
        lo, hi = min(got, key=got.get), max(got, key=got.get)
        return (f"{got[hi] - got[lo]:.{dec}f} ({cfa_label(lo)} {got[lo]:.{dec}f} to "
                f"{cfa_label(hi)} {got[hi]:.{dec}f})")
    if kind == "rank":
        low = spec.get("side", "lowest") == "lowest"
        order = sorted(v, key=v.get, reverse=not low)
        k = order.index(spec["cfa"]) + 1
        return (f"{ordinal(k)} {spec.get('side', 'lowest')} of {len(order)} (the {spec.get('side', 'lowest')}: "
                f"{cfa_label(order[0])} {v[order[0]]:.{dec}f})")
    if kind == "correlation":
        from scipy.stats import spearmanr

        w = _values(run, spec["other"], spec["demosaic"])
        both = [c for c in v if c in w]
        return f"{float(spearmanr([v[c] for c in both], [w[c] for c in both]).statistic):+.2f}"
    a, b = v[spec["a"]], v[spec["b"]]
    better = (a > b) if rec.higher_is_better else (a < b)
    word = "equal to" if round(a, dec) == round(b, dec) else "better than" if better else "worse than"
    return f"{a:.{dec}f} ({word} {cfa_label(spec['b'])}'s {b:.{dec}f})"


def explanation(run, claim: dict, verdict: str) -> str:
    """The claim's explanation for ``verdict`` with its facts filled from ``run``."""
    from ..errors import CfaMitsubaError

    key = {"holds": "why_holds", "differs": "why_differs", "tie": "why_tie"}.get(verdict, "")
    text = claim.get(key, "")
    if not text:
        return "the run's 95 % intervals cannot tell the compared values apart" if verdict == "tie" else ""
    facts = claim.get("facts") or {}
    names = [f for _, f, _, _ in string.Formatter().parse(text) if f]
    unknown = [n for n in names if n not in facts]
    if unknown:
        raise CfaMitsubaError(f"claim {claim.get('id')!r}: {key} names undeclared fact(s) {', '.join(unknown)}")
    return text.format(**{n: fact_text(run, facts[n]) for n in names})
