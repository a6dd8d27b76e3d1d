"""The stepping of :func:`~cfa_mitsuba.sensor.noise.poisson_quantile` in one
compiled pass (Numba), written by hand for speed only: after one exact CDF
per pixel, the neighbouring CDFs come from the probability mass by its
recurrence instead of one more incomplete gamma function each.

With F(k) = P(X <= k) and p(k) = P(X = k) of Poisson(lam):
F(k + 1) = F(k) + p(k + 1), p(k + 1) = p(k) lam / (k + 1), and
F(k - 1) = F(k) - p(k), p(k - 1) = p(k) k / lam.  These carry rounding
errors of about 1e-11 relative at the largest means a sensor collects, far
inside the band of 1e-9 relative in which a pixel is handed back to the
exact path, so the counts are those of exact inversion.
"""

from __future__ import annotations

import numba as nb
import numpy as np

#: a pixel whose u lies this close (relative) to a CDF taken by recurrence
#: goes back to the exact incomplete gamma function
NEAR = 1e-9
#: steps from the normal-approximation start before a pixel goes back to the exact path
MAX_STEPS = 64


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _settle(lam, u, k, cdf, pmf, exact):  # pragma: no cover - compiled
    for i in range(k.shape[0]):
        ll = lam[i]
        uu = u[i]
        if ll == 0.0 or uu == 0.0:
            continue
        kk = k[i]
        f = cdf[i]
        p = pmf[i]
        if f < uu:  # step up until F(k) reaches u
            settled = False
            for _ in range(MAX_STEPS):
                p = p * ll / (kk + 1.0)
                f = f + p
                kk += 1.0
                if abs(f - uu) <= NEAR * f:
                    break
                if f >= uu:
                    settled = True
                    break
            if not settled:
                exact[i] = True
                continue
        else:  # step down while F(k - 1) still reaches u
            for _ in range(MAX_STEPS):
                if kk == 0.0:
                    break
                lower = f - p
                if abs(lower - uu) <= NEAR * f:
                    exact[i] = True
                    break
                if lower < uu:
                    break
                p = p * kk / ll
                kk -= 1.0
                f = lower
            else:
                exact[i] = True
            if exact[i]:
                continue
        k[i] = kk


def settle(lam: np.ndarray, u: np.ndarray, k: np.ndarray, cdf: np.ndarray, pmf: np.ndarray) -> np.ndarray:
    """Move each start ``k`` (float64 counts, changed in place) to the
    smallest count whose CDF reaches ``u``, given ``cdf`` = F(k) and ``pmf``
    = p(k) at the start (all 1-D float64 of one length; pixels with ``lam``
    or ``u`` of 0 are left as they are).  Returns the mask of the pixels
    left undecided (``u`` within :data:`NEAR` of a CDF, or more than
    :data:`MAX_STEPS` steps): their ``k`` is unchanged and the caller
    settles them with the exact CDF."""
    exact = np.zeros(k.shape, dtype=np.bool_)
    _settle(lam, u, k, cdf, pmf, exact)
    return exact
