"""Ranking and fronts: the proxy's combined score and the choice of the
candidates for the full chain; the full chain's Pareto front with
intervals; the proxy's agreement with the full chain.

Proxy score (lower is better): each objective is predicted by its proxies
(:data:`.config.PROXIES_OF`); each proxy is min-max normalised over the
candidates (0 best, 1 worst), an objective's prediction is the mean of its
proxies, and the score the mean over the objectives.  Candidates for the
full chain: the proxy Pareto front (non-dominated on the proxies the
objectives use; pymoo's non-dominated sorting), best score first, filled
up with the next best scores when the front is smaller; and a seeded
random sample of the rest, spread over the proxy ranks, to measure how well
the proxy predicts the full chain.

Full-chain dominance, within intervals: A dominates B when on no objective
A's 95 % interval lies wholly on the worse side of B's, and on at least
one it lies wholly on the better side.  The Pareto front is the feasible
candidates that no other evaluated CFA (named or candidate) dominates so.
Two CFAs whose intervals overlap everywhere are ties: both stay.
"""

from __future__ import annotations

__all__ = ["proxy_scores", "select", "dominates", "pareto", "separating", "fullchain_scores", "agreement",
           "spearman_interval", "objective_prediction", "AGREEMENT_TARGET"]

import numpy as np


def _normalise(v: np.ndarray) -> np.ndarray:
    lo, hi = np.nanmin(v), np.nanmax(v)
    return np.zeros_like(v) if hi - lo <= 1e-12 * max(1.0, abs(hi)) else (v - lo) / (hi - lo)


def proxy_scores(df, objectives) -> np.ndarray:
    """(N,) the combined proxy score of each candidate (module doc)."""
    return np.mean([objective_prediction(df, o) for o in objectives], axis=0)


def select(df, proxies, n_best: int, n_sample: int, seed: int) -> tuple[list[int], list[int]]:
    """(best, sample): row positions of the candidates for the full chain.
    ``df`` must hold ``proxy_score``; ``proxies`` the proxy columns used."""
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    order = np.argsort(df["proxy_score"].to_numpy(), kind="stable")
    pool = order[:2000]
    f = df[list(proxies)].to_numpy(dtype=float)[pool]
    front = NonDominatedSorting().do(f, only_non_dominated_front=True) if len(pool) else []
    in_front = set(pool[np.asarray(front, dtype=int)].tolist())
    best = [int(i) for i in order if i in in_front][:n_best]
    best += [int(i) for i in order if int(i) not in best][:max(0, n_best - len(best))]
    rest = np.array([i for i in order if int(i) not in best])
    sample: list[int] = []
    if n_sample and len(rest):
        rng = np.random.default_rng(seed)
        strata = np.array_split(rest, min(n_sample, len(rest)))
        sample = [int(rng.choice(s)) for s in strata if len(s)]
    return best, sample


def dominates(a: dict, b: dict, objectives) -> bool:
    """Whether CFA ``a`` dominates ``b`` within intervals (module doc); each
    is {label: (mean, low, high)}."""
    strictly = False
    for o in objectives:
        ma, la, ha = a[o.label]
        mb, lb, hb = b[o.label]
        worse = (la > hb) if o.goal == "min" else (ha < lb)
        better = (ha < lb) if o.goal == "min" else (la > hb)
        if worse:
            return False
        strictly = strictly or better
    return strictly


def _values(row, objectives) -> dict:
    return {o.label: (row[o.label], row[f"{o.label} low"], row[f"{o.label} high"]) for o in objectives}


def pareto(table, objectives) -> list:
    """For each row of ``table`` (kind, cfa, feasible, and per objective the
    mean, low and high), the label of a CFA that dominates it within
    intervals ('' when none)."""
    vals = [_values(r, objectives) for _, r in table.iterrows()]
    labels = table["cfa"].tolist()
    out = []
    for i in range(len(vals)):
        by = next((labels[j] for j in range(len(vals))
                   if j != i and table["feasible"].iloc[j] and dominates(vals[j], vals[i], objectives)), "")
        out.append(by)
    return out


def separating(table, o) -> bool:
    """Whether objective ``o`` tells the evaluated CFAs apart: the spread of
    their means exceeds the median width of their 95 % intervals."""
    v = table[o.label].to_numpy(dtype=float)
    width = (table[f"{o.label} high"] - table[f"{o.label} low"]).to_numpy(dtype=float)
    return bool(np.nanmax(v) - np.nanmin(v) > np.nanmedian(width))


def fullchain_scores(table, objectives) -> np.ndarray:
    """(N,) combined full-chain score, higher is better: each objective's
    mean min-max normalised over the evaluated CFAs (1 best), averaged over
    the objectives that separate the CFAs (:func:`separating`; an objective
    whose differences are all within the noise would only add noise to the
    score, as the study leaves a constant metric out); all of them if none
    does."""
    keep = [o for o in objectives if separating(table, o)] or list(objectives)
    per = []
    for o in keep:
        v = table[o.label].to_numpy(dtype=float)
        n = _normalise(v)
        per.append(1.0 - n if o.goal == "min" else n)
    return np.mean(per, axis=0)


#: The agreement a design aims for on every objective (issue 26).
AGREEMENT_TARGET = 0.8


def spearman_interval(rho: float | None, n: int, level: float = 0.95) -> list | None:
    """[low, high]: the interval of a Spearman correlation by Fisher's z with
    the Fieller-Hartley-Pearson variance 1.06 / (n - 3) (Fieller, Hartley &
    Pearson, Biometrika 44 (1957) 470-481); None when n <= 3 or rho is None."""
    from scipy.stats import norm

    if rho is None or n <= 3:
        return None
    z = np.arctanh(np.clip(rho, -0.999999, 0.999999))
    half = norm.ppf(0.5 + level / 2) * np.sqrt(1.06 / (n - 3))
    return [float(np.tanh(z - half)), float(np.tanh(z + half))]


def objective_prediction(df, o) -> np.ndarray:
    """(N,) the proxy's prediction of objective ``o`` (lower is better): the
    mean of its proxies, each min-max normalised over ``df``'s rows."""
    return np.mean([_normalise(df[p].to_numpy(dtype=float)) for p in o.proxies], axis=0)


def agreement(table, objectives) -> dict:
    """Spearman rank correlations between proxy and full chain over the
    evaluated candidates: the combined scores (proxy score against minus the
    full-chain score, so +1 is perfect agreement) and per objective (its
    proxy prediction against the value, oriented the same way), each with
    its 95 % interval (:func:`spearman_interval`), the target
    (:data:`AGREEMENT_TARGET`), whether each objective separates the
    candidates (:func:`separating`) and whether every separating objective
    meets the target."""
    from scipy.stats import spearmanr

    cand = table[table["kind"] == "candidate"]
    n = int(len(cand))
    out = {"n": n, "target": AGREEMENT_TARGET}
    if n < 3:
        out["combined"] = None
        return out

    def rho(a, b):
        r = spearmanr(a, b).statistic
        return None if not np.isfinite(r) else float(r)

    ok = np.isfinite(cand["score"].to_numpy(dtype=float))  # a CFA whose objective was not measured has no score
    out["combined"] = rho(-cand["proxy_score"].to_numpy()[ok], cand["score"].to_numpy()[ok]) if ok.sum() >= 3 else None
    out["combined_interval"] = spearman_interval(out["combined"], int(ok.sum()))
    per, ci, sep = {}, {}, {}
    for o in objectives:
        sep[o.label] = separating(cand, o)
        val = cand[o.label].to_numpy(dtype=float)
        ok = np.isfinite(val)
        pred = objective_prediction(cand, o)
        per[o.label] = rho(-pred[ok], (-val if o.goal == "min" else val)[ok]) if ok.sum() >= 3 else None
        ci[o.label] = spearman_interval(per[o.label], int(ok.sum()))
    out["per_objective"] = per
    out["per_objective_interval"] = ci
    # an objective whose candidates differ by less than their own intervals
    # has no order for a proxy to predict: its rank correlation is noise
    out["separating"] = sep
    judged = [k for k in per if sep[k]]
    out["meets_target"] = bool(judged) and all(per[k] is not None and per[k] >= AGREEMENT_TARGET for k in judged)
    return out
