"""The decision rule itself (study/decisions.py states it in full): who is
named from a set of values, their 95 % intervals and paired rank intervals,
with the practical difference; and whether an answer survives the
alternatives it was recomputed under."""

from __future__ import annotations

__all__ = ["Outcome", "decide", "robustness"]

from dataclasses import dataclass

import numpy as np

from .intervals import rank_interval


@dataclass
class Outcome:
    """One decision: ``cfas`` (in score order), ``verdict``, ``detail``,
    ``clipped_share``; ``answer`` is the winner's name, "" without one."""

    cfas: list
    verdict: str
    detail: str
    clipped_share: float = 0.0

    @property
    def answer(self) -> str:
        return self.cfas[0] if self.verdict == "winner" else ""


def decide(cfas, scores, lows, highs, ranks=None, *, practical: float = 0.0, higher_is_better: bool = True,
           decimals: int = 3) -> tuple[list[str], str, str]:
    """(the CFAs named, verdict, plain-words detail) by the rule of the module docstring.

    ``scores``, ``lows``, ``highs``: each CFA's value and its 95 % interval;
    ``ranks``: (best ranks, worst ranks) from paired comparisons (without
    them, from the marginal intervals: :func:`.intervals.rank_interval`);
    ``practical``: the smallest lead that matters, in the scores' units.

    >>> decide(["a", "b", "c"], [0.9, 0.85, 0.5], [0.88, 0.80, 0.45], [0.92, 0.89, 0.55])[:2]
    (['a', 'b'], 'tie')
    >>> decide(["a", "b"], [0.9, 0.5], [0.88, 0.45], [0.92, 0.55])[:2]
    (['a'], 'winner')
    >>> decide(["a", "b"], [0.9, 0.85], [0.89, 0.84], [0.91, 0.86], practical=0.1)[:2]
    (['a', 'b'], 'equivalent')
    """
    cfas = list(cfas)
    s, lo, hi = (np.asarray(x, dtype=float) for x in (scores, lows, highs))
    sign = 1.0 if higher_is_better else -1.0
    if ranks is None:
        _, best, worst = rank_interval(s, lo, hi, higher_is_better=higher_is_better)
    else:
        best, worst = (np.asarray(x, dtype=int) for x in ranks)
    order = [int(i) for i in np.argsort(-sign * s, kind="stable") if best[i] == 1]

    def one(i):
        rank = f"rank {best[i]}" if best[i] == worst[i] else f"ranks {best[i]}-{worst[i]}"
        return f"{cfas[i]} {s[i]:.{decimals}f} [{lo[i]:.{decimals}f}, {hi[i]:.{decimals}f}] ({rank})"

    if not (len(order) == 1 and worst[order[0]] == 1):
        detail = (f"{len(order)} CFA(s) can rank first within their 95 % intervals: "
                  + "; ".join(one(i) for i in order))
        return [cfas[i] for i in order], "tie", detail
    lead_i = order[0]
    gaps = {j: sign * (s[lead_i] - s[j]) for j in range(len(cfas)) if j != lead_i and np.isfinite(s[j])}
    nxt = min(gaps, key=gaps.get) if gaps else None
    lead = gaps[nxt] if nxt is not None else np.inf
    sep = f"{one(lead_i)}: separated from every other CFA (paired differences, 95 % intervals clear of 0)"
    if nxt is None or lead >= practical - 1e-12:
        how = (f"; it leads the next, {cfas[nxt]}, by {lead:.{decimals}f}, at least the practical difference "
               f"{practical:.{decimals}f}" if nxt is not None else "")
        return [cfas[lead_i]], "winner", sep + how
    within = sorted((j for j, g in gaps.items() if g < practical), key=lambda j: gaps[j])
    detail = (f"{sep}, but its lead over {cfas[nxt]}, {lead:.{decimals}f}, is less than the practical difference "
              f"{practical:.{decimals}f}: equivalent to " + ", ".join(cfas[j] for j in within))
    return [cfas[lead_i], *(cfas[j] for j in within)], "equivalent", detail


def _answer_words(o: Outcome | None) -> str:
    if o is None:
        return "nothing measured"
    return o.answer or {"tie": "a tie", "equivalent": "no practical winner", "clipped": "clipped scores"}.get(
        o.verdict, o.verdict) + (f" ({', '.join(o.cfas)})" if o.cfas else "")


def robustness(base: Outcome, others) -> tuple[bool, str, str]:
    """(robust, depends_on, the sentence naming what each changes) of a
    decision against [(label, Outcome)] alternatives."""
    changed = [(label, o) for label, o in others if (o.answer if o is not None else "") != base.answer]
    if not changed:
        n = len(others)
        return True, "", (f" Robust: the same answer under all {n} alternatives checked." if n else "")
    words = "; ".join(f"{label}: {_answer_words(o)}" for label, o in changed)
    return False, "; ".join(label for label, _ in changed), f" Depends on: {words}."


