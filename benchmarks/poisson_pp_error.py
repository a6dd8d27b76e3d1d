"""The error of Peizer and Pratt's Poisson CDF (cfa_mitsuba/sensor/_poisson_kernel.py)
against scipy.special.pdtr, by band of means, beside the guard the Poisson
draws keep from it:

    python benchmarks/poisson_pp_error.py [--per-band 3000]

For each band, means log-uniform in it and every count within 12 standard
deviations of each; prints the largest absolute error and the smallest
ratio guard / error over the band (the guard is evaluated at each point's
own mean).  The guard (``pp_guard``) must stay well above 1 x the error:
the draws are exact only while it does.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

EDGES = (10, 20, 30, 50, 100, 200, 500, 1e3, 3e3, 1e4, 3e4, 1e5, 3e5, 1e6)


def band_errors(lo: float, hi: float, n_means: int, seed: int = 0):
    """(largest |PP - pdtr|, smallest guard / error, points) over a band of means."""
    import numba as nb
    from scipy import special

    from cfa_mitsuba.sensor._poisson_kernel import _pp_cdf, pp_guard

    @nb.njit
    def evaluate(k, lam, cdf, guard):
        for i in range(k.size):
            cdf[i] = _pp_cdf(k[i], lam[i])
            guard[i] = pp_guard(lam[i])

    rng = np.random.default_rng(seed)
    means = np.exp(rng.uniform(np.log(lo), np.log(hi), n_means))
    counts = [np.arange(max(0, int(m - 12 * np.sqrt(m) - 5)), int(m + 12 * np.sqrt(m) + 10), dtype=float)
              for m in means]
    k = np.concatenate(counts)
    lam = np.repeat(means, [c.size for c in counts])
    cdf, guard = np.empty_like(k), np.empty_like(k)
    evaluate(k, lam, cdf, guard)
    err = np.abs(cdf - special.pdtr(k, lam))
    return float(err.max()), float(np.min(guard / np.maximum(err, 1e-300))), k.size


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-band", type=int, default=3000, help="means per band (default 3000)")
    args = ap.parse_args(argv)
    print(f"{'means':>16}  {'max error':>10}  {'guard/error':>11}  {'points':>9}")
    for lo, hi in zip(EDGES[:-1], EDGES[1:]):
        err, ratio, n = band_errors(lo, hi, args.per_band if hi <= 1e4 else max(args.per_band // 5, 50))
        print(f"{lo:>7g} - {hi:<6g}  {err:10.2e}  {ratio:11.1f}  {n:9d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
