"""The rule that turns a claim and a run's 95 % intervals into a verdict.

Every claim makes comparisons; each comparison is judged on the intervals:

- *holds*: every comparison the claim makes is separated (the intervals do
  not overlap) in the claimed direction;
- *differs*: at least one comparison is separated the other way;
- *tie*: no comparison is reversed, but at least one pair of intervals
  overlaps, so the run cannot tell them apart.

Where the run kept its realisations (metrics_realisations.csv), a
comparison is judged on the paired difference of the two CFAs (the same
render and sensor seeds, study/intervals.py ``paired_difference``):
separated when its 95 % interval excludes 0, as the study's rank intervals
are; otherwise on the two marginal intervals.

Group claims are judged pairwise: "A, B better than C, D" makes the four
comparisons A-C, A-D, B-C, B-D (and, for three groups, every earlier group
against every later one), never a comparison of group means.  A "best"
claim makes the comparison of its CFA with every other: it holds only when
its rank interval is exactly 1.  "similar" (a spread of at most a value)
and "at most" compare interval ends with the stated number the same way.

Rank correlations (Spearman's rho between the paper's ranking and ours)
carry a 95 % interval from Fisher's z with the standard error
sqrt(1.06 / (n - 3)) (Fieller, Hartley & Pearson 1957, Biometrika 44:470).
"""

from __future__ import annotations

__all__ = ["VERDICTS", "pairwise", "order_verdict", "best_verdict", "spread_verdict", "at_most_verdict",
           "spearman_interval"]

import numpy as np

VERDICTS = ("holds", "tie", "differs")


def _separation(a, b, higher_is_better: bool, paired) -> int:
    """+1: a better than b beyond the intervals, -1: b better, 0: a tie."""
    diff = paired(a[0], b[0]) if paired is not None else None
    if diff is not None:  # (lo, hi) of a - b over paired realisations
        lo, hi = diff if higher_is_better else (-diff[1], -diff[0])
        return 1 if lo > 0 else -1 if hi < 0 else 0
    a_lo, a_hi, b_lo, b_hi = a[2], a[3], b[2], b[3]
    if not higher_is_better:  # lower is better: flip to "higher is better"
        a_lo, a_hi, b_lo, b_hi = -a_hi, -a_lo, -b_hi, -b_lo
    return 1 if a_lo > b_hi else -1 if b_lo > a_hi else 0


def pairwise(better, worse, higher_is_better: bool, paired=None) -> tuple[int, int, int, list]:
    """(separated as claimed, overlapping, separated the other way, reversed pairs).

    ``better``, ``worse``: [(name, value, lo, hi)] of the side the claim
    says is better and of the other side; ``paired(name_a, name_b)``: the
    95 % interval (lo, hi) of the paired difference a - b, or None where
    there is none (then the marginal intervals decide).

    >>> pairwise([("a", 2.0, 1.9, 2.1)], [("b", 1.0, 0.9, 1.1)], True)[:3]
    (1, 0, 0)
    >>> pairwise([("a", 2.0, 1.0, 3.0)], [("b", 1.9, 0.9, 2.9)], True, lambda a, b: (0.05, 0.15))[:3]
    (1, 0, 0)
    """
    ok = tie = rev = 0
    reversed_pairs = []
    for a in better:
        for b in worse:
            sep = _separation(a, b, higher_is_better, paired)
            if sep > 0:
                ok += 1
            elif sep < 0:
                rev += 1
                reversed_pairs.append((a, b))
            else:
                tie += 1
    return ok, tie, rev, reversed_pairs


def _verdict(ok: int, tie: int, rev: int) -> str:
    return "differs" if rev else "tie" if tie else "holds"


def order_verdict(groups, higher_is_better: bool, paired=None) -> tuple[str, str]:
    """(verdict, counts in words) of "group 0 better than group 1 better than ...".

    >>> order_verdict([[("a", 2.0, 1.9, 2.1)], [("b", 1.0, 0.9, 1.1)]], True)[0]
    'holds'
    >>> order_verdict([[("a", 2.0, 1.0, 3.0)], [("b", 1.0, 0.9, 1.1)]], True)[0]
    'tie'
    """
    ok = tie = rev = 0
    reversed_pairs = []
    for i in range(len(groups)):
        for j in range(i + 1, len(groups)):
            o, t, r, rp = pairwise(groups[i], groups[j], higher_is_better, paired)
            ok, tie, rev = ok + o, tie + t, rev + r
            reversed_pairs += rp
    n = ok + tie + rev
    how = " (paired differences)" if paired is not None else ""
    words = f"pairwise{how}: {ok} of {n} comparisons separated as claimed, {tie} overlapping, {rev} separated the other way"
    if reversed_pairs:
        a, b = reversed_pairs[0]
        words += f" (e.g. {a[0]} {a[1]:.4g} [{a[2]:.4g}, {a[3]:.4g}] against {b[0]} {b[1]:.4g} [{b[2]:.4g}, {b[3]:.4g}])"
    return _verdict(ok, tie, rev), words


def best_verdict(rank_best: int, rank_worst: int) -> str:
    """A "CFA X is best" claim: holds for a rank interval of exactly 1, tie
    when the interval contains 1 and more, differs when it excludes 1."""
    if rank_best > 1:
        return "differs"
    return "holds" if rank_worst == 1 else "tie"


def spread_verdict(rows, max_range: float) -> str:
    """"The values span at most ``max_range``": holds when even the
    intervals' outer ends do, differs when even their inner ends do not."""
    lo = np.array([r[2] for r in rows])
    hi = np.array([r[3] for r in rows])
    if hi.max() - lo.min() <= max_range:
        return "holds"
    if lo.max() - hi.min() > max_range:
        return "differs"
    return "tie"


def at_most_verdict(rows, max_value: float) -> str:
    """"Every value is at most ``max_value``": holds when every interval's
    top is, differs when some interval lies wholly above it."""
    if all(r[3] <= max_value for r in rows):
        return "holds"
    if any(r[2] > max_value for r in rows):
        return "differs"
    return "tie"


def spearman_interval(a, b) -> tuple[float, float, float, int]:
    """(rho, lo, hi, n): Spearman's rank correlation with its 95 % interval
    (Fisher z, standard error sqrt(1.06 / (n - 3)); Fieller et al. 1957).

    >>> rho, lo, hi, n = spearman_interval(range(12), [0, 2, 1, 3, 5, 4, 6, 8, 7, 11, 9, 10])
    >>> round(rho, 3), n
    (0.958, 12)
    """
    from scipy.stats import norm, spearmanr

    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    n = int(a.size)
    rho = float(spearmanr(a, b).statistic)
    if n <= 3 or abs(rho) >= 1:
        return rho, rho, rho, n
    half = norm.ppf(0.975) * np.sqrt(1.06 / (n - 3))
    z = np.arctanh(rho)
    return rho, float(np.tanh(z - half)), float(np.tanh(z + half)), n
