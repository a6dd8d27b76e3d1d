"""The stepping of :func:`~cfa_mitsuba.sensor.noise.poisson_quantile` in
compiled passes (Numba), written by hand for speed only: scipy has the exact
CDF (``pdtr``, an incomplete gamma function, about 150-200 ns a pixel) but
no Poisson quantile that is fast on a whole image.

First attempt (:func:`_first_attempt`), where at least half the means lie
in :data:`PP_MEANS`: the same start and the same two decisions at the start
(the count, or the count below) for every pixel at once, in passes without
a branch or a logarithm around numpy's SIMD logarithms, so that the loops
vectorise; where the start is certainly the count (nearly every such pixel)
it is kept, the rest go through the first pass.  It halves this stage on a
well-exposed image.

First pass (:func:`start_and_settle`): from the Cornish-Fisher start (its
normal quantile by :func:`_start_z`, in the same pass), each step is
decided by Peizer and Pratt's normal approximation of the CDF where ``u``
is farther from it than :func:`pp_guard`, a bound several times the
approximation's largest error; such a decision is the exact CDF's.  Below
those means (:data:`PP_MEANS`), each count is found by counting up from 0, the CDF summed from
the mass's recurrence (below), decided where ``u`` is not within
:data:`NEAR` of a CDF on the way.

Second pass (:func:`settle`), for the pixels left: after one exact CDF, the
neighbouring CDFs come from the probability mass by its recurrence.  With
F(k) = P(X <= k) and p(k) = P(X = k) of Poisson(lam):
F(k + 1) = F(k) + p(k + 1), p(k + 1) = p(k) lam / (k + 1), and
F(k - 1) = F(k) - p(k), p(k - 1) = p(k) k / lam.  These carry rounding
errors of about 1e-11 relative at the largest means a sensor collects, far
inside the band of 1e-9 relative in which a pixel is handed back to the
exact CDF, so the counts are those of exact inversion.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py

_SQRT_HALF = math.sqrt(0.5)

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


#: means where :func:`_pp_cdf` decides a count: below, its error grows (1e-3 at a mean of 3); above,
#: rounding in it grows (1e-7 at 1e7) and the counts are far beyond any well
PP_MEANS = (10.0, 1e6)


@nb.njit(inline="always")
def pp_guard(lam):
    """How far (absolute) u must be from :func:`_pp_cdf` for a decision at
    mean ``lam``: 2e-4 (10 / lam)^1.5, at least 5e-10.  At least 8x the
    approximation's largest error at every mean of :data:`PP_MEANS` (2.4e-5
    at 10, 2.2e-7 at 100, 1.6e-8 at 500, 1e-11 at 1e5, 3.7e-11 up to 1e6:
    measured against ``scipy.special.pdtr`` at every count within 12 sd of
    the mean, ``python benchmarks/poisson_pp_error.py``; asserted in
    tests/sensor/test_noise.py)."""
    r = 10.0 / lam
    return max(2e-4 * r * math.sqrt(r), 5e-10)


@nb.njit(inline="always")
def _pp_z_of_log(k, lam, t, log_t):
    """:func:`_pp_z` given t = (k + 1/2) / lam and its logarithm ``log_t``.
    Peizer and Pratt's g(t) = (1 - t^2 + 2 t ln t) / (1 - t)^2 by its
    series -d/3 + d^2/6 - d^3/10 (d = t - 1) near t = 1, where the quotient
    loses digits; the series is chosen by a select, not a branch, so a loop
    around this vectorises (:func:`_start_is_the_count`)."""
    d = t - 1.0
    series = d * (-1.0 / 3.0 + d * (1.0 / 6.0 - d / 10.0))
    g = series if abs(d) < 1e-3 else (1.0 - t * t + 2.0 * t * log_t) / (d * d)
    return (k - lam + 2.0 / 3.0 + 0.02 / (k + 1.0)) * math.sqrt((1.0 + g) / lam)


@nb.njit(inline="always")
def _pp_z(k, lam):
    """Peizer and Pratt's normal deviate of P(X <= k) for Poisson(lam):
    (k - lam + 2/3 + 0.02 / (k + 1)) sqrt((1 + g((k + 1/2) / lam)) / lam)
    (:func:`_pp_z_of_log`)."""
    t = (k + 0.5) / lam
    return _pp_z_of_log(k, lam, t, math.log(t))


@nb.njit(inline="always")
def _pp_cdf(k, lam):
    """P(X <= k) of Poisson(lam), Peizer and Pratt's normal approximation:
    Phi(:func:`_pp_z`)."""
    return 0.5 * math.erfc(-_pp_z(k, lam) * _SQRT_HALF)


#: Acklam's rational approximation of the normal quantile (relative error
#: below 1.2e-9): the central region's numerator and denominator, the
#: tails', and where the tails begin
_Q_A = (-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
        1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00)
_Q_B = (-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
        6.680131188771972e+01, -1.328068155288572e+01)
_Q_C = (-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
        -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00)
_Q_D = (7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00)
_Q_TAIL = 0.02425


@nb.njit(inline="always")
def _start_z(u):
    """The normal quantile of ``u`` (0 < u < 1) for the Cornish-Fisher start
    only, by P. J. Acklam's rational approximation (relative error below
    1.2e-9; tests/sensor/test_noise.py compares it with ``scipy.special.ndtri``).
    Written here because the start needs no more: every count is then
    decided by a CDF, so the counts do not depend on it (a start one count
    off costs one step), and it takes a few ns in this pass where
    ``ndtri`` took a whole-image pass of 26 ns a pixel."""
    c, d = _Q_C, _Q_D
    if u < _Q_TAIL or u > 1.0 - _Q_TAIL:
        q = math.sqrt(-2.0 * math.log(min(u, 1.0 - u)))
        x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) / \
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0)
        return x if u < 0.5 else -x
    return _central_z(u)


@nb.njit(inline="always")
def _central_z(u):
    """:func:`_start_z` in Acklam's central region (_Q_TAIL <= u <= 1 - _Q_TAIL): no logarithm."""
    a, b = _Q_A, _Q_B
    q = u - 0.5
    r = q * q
    return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q / \
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0)


#: relative error allowed for :func:`_start_z` where it bounds a decision
#: (:func:`_z_below`, :func:`_z_above`): Acklam's stated 1.15e-9, with room
Z_SLACK = 2e-9


@nb.njit(inline="always")
def _z_below(v):
    """A normal deviate at most Phi^-1(v) (v < 1): -inf for v <= 0 (no
    deviate has a CDF below 0), else :func:`_start_z` less :data:`Z_SLACK`
    of itself."""
    if v <= 0.0:
        return -math.inf
    z = _start_z(v)
    return z - Z_SLACK * abs(z)


@nb.njit(inline="always")
def _z_above(w):
    """A normal deviate at least Phi^-1(w) (w > 0): +inf for w >= 1, else
    :func:`_start_z` plus :data:`Z_SLACK` of itself."""
    if w >= 1.0:
        return math.inf
    z = _start_z(w)
    return z + Z_SLACK * abs(z)


@nb.njit(cache=True, nogil=True)
def _start_zs(u, out):  # pragma: no cover - compiled
    for i in range(u.shape[0]):
        out[i] = _start_z(u[i])


def start_z(u: np.ndarray) -> np.ndarray:
    """:func:`_start_z` of each ``u`` (1-D float64, each in (0, 1)), for tests."""
    u = np.ascontiguousarray(u, dtype=np.float64)
    out = np.empty_like(u)
    _start_zs(u, out)
    return out


@nb.njit(inline="always")
def _count_up(lam, u, i, k, decided):
    """A mean below :data:`PP_MEANS`: count up from 0 with the mass's
    recurrence (F(0) = p(0) = exp(-lam), p(k + 1) = p(k) lam / (k + 1)),
    about lam + 1 steps, to the first count whose CDF reaches u; returns
    whether it decided (sets ``k[i]`` and ``decided[i]``).  Not decided
    where u lies within :data:`NEAR` (relative) of a CDF on the way or
    :data:`MAX_STEPS` are not enough: those get the Cornish-Fisher start
    for the exact path."""
    p = math.exp(-lam)
    f = p
    kk = 0.0
    for _ in range(MAX_STEPS):
        if abs(f - u) <= NEAR * f:
            return False
        if f >= u:
            k[i] = kk
            decided[i] = True
            return True
        kk += 1.0
        p = p * lam / kk
        f = f + p
    return False


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _start_and_settle(lam, u, k, decided):  # pragma: no cover - compiled
    lo, hi = PP_MEANS
    for i in range(k.shape[0]):
        ll = lam[i]
        uu = u[i]
        if ll == 0.0 or uu == 0.0:  # u = 0 (one draw in 2^53): z = -inf, and the answer is 0
            k[i] = 0.0
            decided[i] = True
            continue
        if ll < lo and _count_up(ll, uu, i, k, decided):
            continue  # decided: no start needed
        z = _start_z(uu)
        kk = math.floor(ll + math.sqrt(ll) * z + (z * z - 1.0) / 6.0 + 0.5)  # Cornish-Fisher
        kk = max(kk, 0.0)
        k[i] = kk
        if ll < lo or ll > hi:  # left for the exact path, from the start
            continue
        # Decided in deviates, not probabilities: Phi(z) < u - guard where z <
        # z_lo, Phi(z) >= u + guard where z >= z_hi (bounds of the two
        # quantiles, _z_below/_z_above), so no erfc per step; the same tests
        # as comparing u with _pp_cdf, a hair stricter by the bounds' slack.
        guard = pp_guard(ll)
        z_lo = _z_below(uu - guard)
        z_hi = _z_above(uu + guard)
        for _ in range(MAX_STEPS):
            z = _pp_z(kk, ll)
            if z < z_lo:  # F(k) < u for certain: up
                kk += 1.0
                continue
            if z < z_hi:  # too near to call
                break
            if kk == 0.0:  # F(0) >= u for certain
                k[i] = kk
                decided[i] = True
                break
            z = _pp_z(kk - 1.0, ll)
            if z >= z_hi:  # F(k - 1) >= u for certain: down
                kk -= 1.0
                continue
            if z < z_lo:  # F(k - 1) < u <= F(k) for certain: k
                k[i] = kk
                decided[i] = True
            break


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _central_starts(lam, u, k, z_lo, z_hi, t_up, t_down, ok):  # pragma: no cover - compiled
    """The first attempt's first half, for every pixel at once: where the
    mean lies in :data:`PP_MEANS` and u and u +- the guard lie in Acklam's
    central region (``ok``), the Cornish-Fisher start ``k``, the bounds
    ``z_lo``, ``z_hi`` (:func:`_z_below`, :func:`_z_above`) and the
    arguments (k +- 1/2) / lam of Peizer and Pratt's g at k and k - 1.  No
    branch and no logarithm, so the loop vectorises; the values are the
    scalar pass's (the same operations)."""
    lo, hi = PP_MEANS
    for i in range(k.shape[0]):
        ll = lam[i]
        uu = u[i]
        guard = pp_guard(ll)
        v = uu - guard
        w = uu + guard
        ok[i] = (ll >= lo) & (ll <= hi) & (v >= _Q_TAIL) & (w <= 1.0 - _Q_TAIL)
        z = _central_z(uu)
        zv = _central_z(v)
        zw = _central_z(w)
        z_lo[i] = zv - Z_SLACK * abs(zv)
        z_hi[i] = zw + Z_SLACK * abs(zw)
        kk = max(math.floor(ll + math.sqrt(ll) * z + (z * z - 1.0) / 6.0 + 0.5), 0.0)
        k[i] = kk
        t_up[i] = (kk + 0.5) / ll
        t_down[i] = (kk - 0.5) / ll


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _start_is_the_count(lam, k, z_lo, z_hi, t_up, log_up, t_down, log_down, ok, decided):  # pragma: no cover
    """The first attempt's second half: ``decided`` where ``ok`` and the
    start is certainly the count (F(k - 1) < u <= F(k) by the bounds, k >
    0), the scalar pass's last test; the logarithms come from numpy's SIMD
    ufunc, a few units in the last place from libm's, far inside the bounds'
    slack, so a pixel this decides is decided alike by the scalar pass."""
    for i in range(k.shape[0]):
        kk = k[i]
        ll = lam[i]
        up = _pp_z_of_log(kk, ll, t_up[i], log_up[i])
        down = _pp_z_of_log(kk - 1.0, ll, t_down[i], log_down[i])
        decided[i] = ok[i] & (kk > 0.0) & (up >= z_hi[i]) & (down < z_lo[i])


#: pixels a block of the first attempt: its eight arrays stay in the core's cache
_BLOCK = 8192
#: the share of pixels with means in :data:`PP_MEANS` from which the first
#: attempt runs: it costs about 18 ns a pixel on every pixel and spares the
#: scalar pass the pixels it decides (measured on 636 x 720 images: means of
#: 200-3000, 28 -> 12 ms; 0-20, half of them in range, 32 -> 34 ms; 0-5,
#: none, 19 -> 30 ms, so below this share it is left out)
FIRST_ATTEMPT_SHARE = 0.5


def _first_attempt(lam: np.ndarray, u: np.ndarray, k: np.ndarray, decided: np.ndarray) -> None:
    """Fill ``k`` and ``decided`` where the Cornish-Fisher start is
    certainly the count (most pixels at means of 10 to 1e6), block by
    block: the two passes above around numpy's logarithms."""
    n = min(_BLOCK, k.shape[0])
    z_lo, z_hi, t_up, t_down, log_up, log_down = np.empty((6, n))
    ok = np.empty(n, dtype=np.bool_)
    with np.errstate(invalid="ignore", divide="ignore"):  # logs of pixels not ok (t <= 0): not used
        for start in range(0, k.shape[0], n):
            stop = min(start + n, k.shape[0])
            m = stop - start
            sl = slice(start, stop)
            _central_starts(lam[sl], u[sl], k[sl], z_lo[:m], z_hi[:m], t_up[:m], t_down[:m], ok[:m])
            np.log(t_up[:m], out=log_up[:m])
            np.log(t_down[:m], out=log_down[:m])
            _start_is_the_count(lam[sl], k[sl], z_lo[:m], z_hi[:m], t_up[:m], log_up[:m], t_down[:m],
                                log_down[:m], ok[:m], decided[sl])


def start_and_settle(lam: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(counts, decided) for means ``lam`` and uniforms ``u`` (1-D float64):
    each count starts at the Cornish-Fisher quantile lam + sqrt(lam) z +
    (z^2 - 1)/6, z the normal quantile of ``u`` (rounded, at least 0; 0 where
    ``lam`` or ``u`` is 0, decided) and moves to the smallest count whose
    CDF reaches ``u`` where Peizer and Pratt's approximation decides it
    (means within :data:`PP_MEANS`, ``u`` farther than :func:`pp_guard` from
    the approximate CDF of the answer and of the count below): those are
    ``decided``; the others keep their start."""
    k = np.empty(lam.shape, dtype=np.float64)
    decided = np.zeros(lam.shape, dtype=np.bool_)
    lo, hi = PP_MEANS
    if np.count_nonzero((lam >= lo) & (lam <= hi)) >= FIRST_ATTEMPT_SHARE * lam.size:
        _first_attempt(lam, u, k, decided)
    rest = np.flatnonzero(~decided)
    if rest.size == k.size:
        _start_and_settle(lam, u, k, decided)
    elif rest.size:
        kr, dr = k[rest], decided[rest]
        _start_and_settle(lam[rest], u[rest], kr, dr)
        k[rest], decided[rest] = kr, dr
    return k, decided
