"""Acceptance 2 (noise) and 5 (extreme light): each noise source shows its
set value on a large field, photon noise is exactly Poisson (scipy.stats),
seeds reproduce, and 0.01..100000 cd/m^2 gives finite raw data."""

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

import cfa_mitsuba as cm
from cfa_mitsuba.optics import OpticsParams, compute_optics
from cfa_mitsuba.sensor import SensorParams, capture, collect_electrons
from cfa_mitsuba.sensor.noise import temporal_rng
from cfa_mitsuba.values import SpectralImage

WL = cm.spectra.DEFAULT_WAVELENGTHS
REPO = Path(__file__).resolve().parents[2]
FLAT = OpticsParams(relative_illumination=False)
MONO = cm.sensor.make_cfa("mono", "W", {"W": (np.array([300.0, 800.0]), np.array([0.5, 0.5]))})
N = 512  # 262 144 pixels: a variance is then known to 0.3 %


def _oi(luminance=100.0, n=N):
    d65 = cm.spectra.illuminant("D65")
    rad = d65 * luminance / cm.spectra.luminance_cd_m2(d65)
    return compute_optics(SpectralImage(np.broadcast_to(rad, (n, n, 31)).copy(), WL, {"fov_deg": 10.0}), FLAT)


@pytest.fixture(scope="module")
def bright():
    return _oi(100.0)


@pytest.fixture(scope="module")
def dark():
    return compute_optics(SpectralImage(np.zeros((N, N, 31)), WL, {"fov_deg": 10.0}), FLAT)


def _electrons(raw):
    return (raw.raw - raw.black_level_dn) / raw.dn_per_electron


def test_shot_noise_variance_equals_the_mean(bright):
    for t in (2e-4, 2e-3):  # about 26 and 260 electrons
        r = capture(bright, MONO, exposure_s=t, noise="shot", seed=3)
        e = _electrons(r)
        ratio = e.var() / e.mean()
        print(f"shot: mean {e.mean():.2f} e-, variance / mean {ratio:.4f}")
        assert ratio == pytest.approx(1.0, abs=0.03)
        assert np.allclose(e, np.round(e))  # whole electrons


def test_photon_noise_is_exactly_poisson(bright):
    # a mean of 2.5 e-, where the Gaussian approximation would be plainly wrong
    t = 2.5 * 1e-4 / _electrons(capture(bright, MONO, exposure_s=1e-4, noise="off")).mean()
    e = _electrons(capture(bright, MONO, exposure_s=t, noise="shot", seed=4)).round().astype(int).ravel()
    k = np.arange(12)
    observed = np.array([np.count_nonzero(e == v) for v in k[:-1]] + [np.count_nonzero(e >= k[-1])])
    pmf = stats.poisson.pmf(k[:-1], 2.5)
    expected = np.append(pmf, 1 - pmf.sum()) * e.size
    p = stats.chisquare(observed, expected).pvalue
    print(f"chi-square against Poisson(2.5): p = {p:.3f}")
    assert p > 1e-3


def test_read_noise_shows_its_set_value(dark):
    # gain 8: 0.19 e- per code; a black level of 32 sigmas keeps the tail off 0
    s = SensorParams(read_noise_e=6.2, dark_current_e_s=0.0, analog_gain=8.0, black_level_dn=1024)
    e = _electrons(capture(dark, MONO, exposure_s=0.01, noise="all", seed=5, sensor=s))
    std = np.sqrt(e.var() - (1 / s.dn_per_electron) ** 2 / 12)  # less the quantisation (Sheppard)
    print(f"read noise: set 6.2 e-, measured {std:.3f} e-")
    assert std == pytest.approx(6.2, rel=0.03)
    assert e.mean() == pytest.approx(0.0, abs=0.05)


def test_dark_current_shows_its_set_value_with_its_own_shot_noise(dark):
    s = SensorParams(read_noise_e=0.0, dark_current_e_s=6.2)
    e = _electrons(capture(dark, MONO, exposure_s=50.0, noise="all", seed=6, sensor=s))  # 310 e-
    print(f"dark current: set 6.2 e-/s, measured {e.mean() / 50:.4f} e-/s, variance / mean {e.var() / e.mean():.4f}")
    assert e.mean() / 50.0 == pytest.approx(6.2, rel=0.03)
    assert e.var() / e.mean() == pytest.approx(1.0, abs=0.03)


def test_dsnu_shows_its_set_value_and_is_fixed(dark):
    s = SensorParams(read_noise_e=0.0, dark_current_e_s=0.0, dsnu_e=2.0, analog_gain=8.0, black_level_dn=512,
                     sensor_seed=11)
    a = _electrons(capture(dark, MONO, exposure_s=0.01, seed=1, sensor=s))
    b = _electrons(capture(dark, MONO, exposure_s=0.01, seed=2, sensor=s))
    std = np.sqrt(a.var() - (1 / s.dn_per_electron) ** 2 / 12)
    print(f"DSNU: set 2 e-, measured {std:.4f} e-")
    assert std == pytest.approx(2.0, rel=0.03)
    np.testing.assert_array_equal(a, b)  # fixed pattern: another frame, the same offsets
    c = _electrons(capture(dark, MONO, exposure_s=0.01, seed=1, sensor=s.with_(sensor_seed=12)))
    assert not np.array_equal(a, c)  # another sensor, another pattern


def test_prnu_shows_its_set_value(bright):
    # EMVA 1288's method: the covariance of two frames of one sensor is the
    # fixed pattern alone (temporal noise is independent between frames).
    s = SensorParams(prnu_percent=1.5, read_noise_e=0.0, dark_current_e_s=0.0, sensor_seed=7)
    t = 4000.0 * 1e-4 / _electrons(capture(bright, MONO, exposure_s=1e-4, noise="off")).mean()
    a = _electrons(capture(bright, MONO, exposure_s=t, seed=1, sensor=s))
    b = _electrons(capture(bright, MONO, exposure_s=t, seed=2, sensor=s))
    prnu = np.sqrt(np.mean((a - a.mean()) * (b - b.mean()))) / a.mean() * 100
    print(f"PRNU: set 1.5 %, measured {prnu:.4f} %")
    assert prnu == pytest.approx(1.5, rel=0.03)


def test_same_seed_same_raw_other_seed_other_raw():
    oi = _oi(50.0, n=64)
    s = SensorParams(dsnu_e=1.0, prnu_percent=1.0)
    a = capture(oi, "rgbw2", seed=42, sensor=s)
    b = capture(oi, "rgbw2", seed=42, sensor=s)
    c = capture(oi, "rgbw2", seed=43, sensor=s)
    np.testing.assert_array_equal(a.raw, b.raw)
    assert not np.array_equal(a.raw, c.raw)
    assert a.seed == 42 and a.settings["sensor"]["sensor_seed"] == 0


def test_noise_all_gives_integer_codes_with_black_level():
    oi = _oi(100.0, n=64)
    r = capture(oi, "bayer", noise="all", seed=1, exposure_policy="reference")  # gain 1: the sensor's own pedestal
    assert np.array_equal(r.raw, np.round(r.raw)) and r.raw.min() >= 0 and r.raw.max() <= 4095
    assert r.black_level_dn == 64
    off = capture(oi, "bayer", noise="off", exposure_policy="reference")
    assert off.black_level_dn == 0 and not np.array_equal(off.raw, np.round(off.raw))
    # the mean of many noisy pixels is the noise-free signal (plus dark current)
    e_all = _electrons(r).mean()
    e_off = _electrons(off).mean()
    dark = SensorParams().dark_current_e_s * r.exposure_s
    assert e_all == pytest.approx(e_off + dark, rel=0.01)


@pytest.mark.parametrize("luminance", [0.01, 1.0, 100.0, 1e4, 1e5])
def test_extreme_light_gives_finite_raw_data(luminance):
    oi = _oi(1.0, n=64)  # auto exposure chosen at 100 cd/m^2 and kept
    bayer = cm.sensor.get_cfa("bayer", spectra="nikon-d5100")  # the signal levels below were measured with it
    r = capture(oi, bayer, luminance_cd_m2=luminance, noise="all", seed=9, exposure_policy="reference")
    assert np.all(np.isfinite(r.raw)) and r.raw.min() >= 0 and r.raw.max() <= 4095
    e = _electrons(r)
    mean, std = e.mean(), e.std()
    shot = capture(oi, bayer, luminance_cd_m2=luminance, noise="shot", seed=9, exposure_policy="reference")
    assert shot.raw.min() >= 0  # no negative electrons before read noise
    print(f"{luminance:g} cd/m^2: mean {mean:.3f} e-, std {std:.3f} e-, wells full "
          f"{100 * r.meta['saturated_fraction']:.1f} %, codes at 4095 {100 * np.mean(r.raw == 4095):.1f} %")
    if luminance == 0.01:
        assert std > 3 * abs(mean)  # noise-dominated: read noise 6.2 e- against ~0.6 e- of signal
    well = SensorParams().well_capacity_e
    assert np.all(shot.raw / shot.dn_per_electron <= well * (1 + 1e-12))
    if luminance >= 1e4:
        # every well is full; read noise then spreads the codes just below the top one
        np.testing.assert_allclose(shot.raw / shot.dn_per_electron, well, rtol=1e-12)
        assert mean > well - 0.5 * SensorParams().read_noise_e and np.mean(r.raw == 4095) > 0.45
        assert r.meta["saturated_fraction"] == 1.0
    else:
        assert r.meta["saturated_fraction"] == 0.0


def test_collect_electrons_at_absurd_means():
    rng = temporal_rng(0)
    s = SensorParams()
    photo = np.array([[0.0, 1e-9, 3.0, 1e6, 1e30]])
    for noise in ("off", "shot", "all"):
        e = collect_electrons(photo, exposure_s=1e6, sensor=s, noise=noise, rng=rng)
        assert np.all(np.isfinite(e)) and e.min() >= 0 and e.max() <= s.well_capacity_e
        assert e[0, -1] == s.well_capacity_e


def test_poisson_quantile_is_scipys_and_stable_under_last_bit_changes():
    """The photon draw is the exact Poisson quantile of one uniform per pixel
    (scipy.stats.poisson.ppf is the independent reference), so a render that
    differs in its last bits moves a few pixels by one electron instead of
    re-dealing the noise of every pixel."""
    from scipy import stats

    from cfa_mitsuba.sensor.noise import poisson_quantile

    rng = np.random.default_rng(5)
    lam = np.concatenate([rng.uniform(0, 2, 20000), rng.uniform(0, 200, 20000), rng.uniform(0, 3e4, 20000),
                          np.zeros(100)])
    u = rng.random(lam.size)
    k = poisson_quantile(lam, u)
    assert np.array_equal(k, stats.poisson.ppf(u, lam))
    assert np.all(np.diff(poisson_quantile(np.linspace(0, 50, 2001), np.full(2001, 0.37))) >= 0)
    moved = poisson_quantile(lam * (1 + 2.0 ** -24), u) - k
    assert set(np.unique(moved)) <= {0.0, 1.0} and np.count_nonzero(moved) < 1e-3 * lam.size
    # one pixel's mean changed: only that pixel's count can change
    lam2 = lam.copy()
    lam2[100] *= 1.5
    assert np.count_nonzero(poisson_quantile(lam2, u) != k) <= 1


def test_poisson_quantile_of_u_zero_is_zero():
    """u = 0 (numpy's generator can return it) is the quantile 0, the
    smallest k with P(X <= k) >= 0, not NaN (its normal quantile is -inf,
    and -inf + inf was NaN).  scipy's ppf(0) is -1 by its own convention,
    so the reference here is the definition."""
    import warnings

    from cfa_mitsuba.sensor.noise import poisson_quantile

    lam = np.array([0.0, 0.3, 5.0, 400.0, 2e4])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert poisson_quantile(lam, np.zeros(lam.size)).tolist() == [0.0] * 5


def test_poisson_quantile_recurrence_steps_give_the_exact_counts():
    """The steps after the first CDF use the mass's recurrence; a draw placed
    exactly on a CDF value (the tie the recurrence cannot decide) and draws
    many counts from the normal start are settled by the exact CDF, so every
    count is the definition's: the smallest k with P(X <= k) >= u."""
    from scipy import special, stats

    from cfa_mitsuba.sensor.noise import poisson_quantile

    rng = np.random.default_rng(11)
    lam = np.concatenate([rng.uniform(0, 1, 3000), rng.uniform(1, 50, 3000), rng.uniform(50, 2e5, 3000)])
    k_true = stats.poisson.ppf(rng.random(lam.size), lam)
    u_on = special.pdtr(k_true, lam)  # u exactly F(k): the answer is k
    u_tail = np.concatenate([np.full(3000, 1e-12), np.full(3000, 1 - 1e-12), np.full(3000, 0.5)])
    for u in (u_on, u_tail):
        got = poisson_quantile(lam, u)
        want = stats.poisson.ppf(u, lam)
        assert np.array_equal(got, want), np.flatnonzero(got != want)[:5]
    assert np.array_equal(poisson_quantile(lam, u_on), k_true)


def test_poisson_approximation_keeps_its_guard():
    """Peizer and Pratt's CDF decides a count only where u is farther from
    it than pp_guard: the guard stays several times the approximation's
    error against scipy's pdtr at every count within 12 sd of means across
    10 .. 1e6 (benchmarks/poisson_pp_error.py prints the whole table)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("pp_error", REPO / "benchmarks" / "poisson_pp_error.py")
    pp_error = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(pp_error)
    for lo, hi in zip(pp_error.EDGES[:-1], pp_error.EDGES[1:]):
        err, ratio, _ = pp_error.band_errors(lo, hi, 40 if hi <= 1e4 else 4, seed=7)
        assert ratio > 4, (lo, hi, err, ratio)


def test_poisson_quantile_equals_scipy_where_the_approximation_decides():
    from scipy import stats

    from cfa_mitsuba.sensor.noise import poisson_quantile

    rng = np.random.default_rng(21)
    lam = np.exp(rng.uniform(np.log(5), np.log(2e6), 200_000))
    u = rng.random(lam.size)
    assert np.array_equal(poisson_quantile(lam, u), stats.poisson.ppf(u, lam))


def test_poisson_start_quantile_is_ndtris_to_its_stated_error():
    """The Cornish-Fisher start takes its normal quantile from Acklam's
    rational approximation in the compiled pass; against scipy's ndtri
    (the independent reference) it stays within the 1.2e-9 relative error
    its docstring states, in the centre and far into both tails."""
    from scipy import special

    from cfa_mitsuba.sensor._poisson_kernel import start_z

    rng = np.random.default_rng(5)
    u = np.concatenate([rng.random(200_000), np.logspace(-300, -1, 3000), 1 - np.logspace(-16, -1, 3000),
                        [0.02425, 1 - 0.02425, 0.5]])
    z, want = start_z(u), special.ndtri(u)
    assert np.all(np.abs(z - want) <= 1.2e-9 * np.maximum(np.abs(want), 1e-300))
    assert start_z(np.array([0.5]))[0] == 0.0


def test_poisson_decision_deviates_bound_the_quantiles():
    """The Peizer-Pratt steps are decided in normal deviates: _z_below(v)
    never exceeds the normal quantile of v and _z_above(w) is never below
    that of w (scipy's ndtri, the independent reference), so a deviate
    test is never looser than comparing u with the approximate CDF; the
    ends give -inf and +inf."""
    from scipy import special

    from cfa_mitsuba.sensor import _poisson_kernel as kernel

    rng = np.random.default_rng(9)
    v = np.concatenate([rng.random(20_000), np.logspace(-300, -1, 2000), 1 - np.logspace(-16, -1, 2000), [0.5]])
    want = special.ndtri(v)
    below = np.array([kernel._z_below(x) for x in v])
    above = np.array([kernel._z_above(x) for x in v])
    assert np.all(below <= want) and np.all(above >= want)
    assert np.all(above - below <= 5e-9 * np.abs(want) + 1e-12)  # and tight: they still decide
    assert kernel._z_below(0.0) == -np.inf and kernel._z_below(-1e-9) == -np.inf
    assert kernel._z_above(1.0) == np.inf and kernel._z_above(1.0 + 1e-9) == np.inf


def test_poisson_counts_do_not_depend_on_the_start(monkeypatch):
    """Every count is decided by a CDF, so a start a whole standard
    deviation off (the start's quantile shifted by 1, run through the
    kernel's Python source) still decides scipy's quantile wherever it
    decides; the shipped kernel's counts are all scipy's."""
    from scipy import stats

    from cfa_mitsuba.sensor import _poisson_kernel as kernel
    from cfa_mitsuba.sensor.noise import poisson_quantile

    rng = np.random.default_rng(8)
    lam = np.exp(rng.uniform(np.log(0.5), np.log(1e5), 50_000))
    u = rng.random(lam.size)
    want = stats.poisson.ppf(u, lam)
    assert np.array_equal(poisson_quantile(lam, u), want)
    start = kernel._start_z.py_func
    monkeypatch.setattr(kernel, "_start_z", lambda v: start(v) + 1.0)
    n = 3000
    counts, decided = np.empty(n), np.zeros(n, dtype=bool)
    kernel._start_and_settle.py_func(lam[:n], u[:n], counts, decided)
    assert decided.mean() > 0.5
    assert np.array_equal(counts[decided], want[:n][decided])


def test_poisson_counts_below_a_mean_of_ten_are_counted_up_exactly():
    """Below a mean of 10 the kernel counts up from 0 with the mass's
    recurrence: scipy's quantile for every draw, for draws exactly on a CDF
    (handed to the exact path) and far in both tails; nearly every such
    pixel is decided there."""
    from scipy import special, stats

    from cfa_mitsuba.sensor import _poisson_kernel as kernel
    from cfa_mitsuba.sensor.noise import poisson_quantile

    rng = np.random.default_rng(12)
    lam = np.concatenate([rng.uniform(0, 10, 60_000), [1e-300, 9.999999, 1e-6]])
    u = rng.random(lam.size)
    assert np.array_equal(poisson_quantile(lam, u), stats.poisson.ppf(u, lam))
    k = stats.poisson.ppf(rng.random(lam.size), lam)
    on = special.pdtr(k, lam)
    assert np.array_equal(poisson_quantile(lam, on), k)
    for tail in (1e-14, 1 - 1e-13):
        v = np.full(lam.size, tail)
        assert np.array_equal(poisson_quantile(lam, v), stats.poisson.ppf(v, lam))
    _, decided = kernel.start_and_settle(lam, u)
    assert decided.mean() > 0.99


def test_the_vectorised_first_attempt_decides_as_the_scalar_pass(monkeypatch):
    """Where the Cornish-Fisher start is certainly the count, the first
    attempt (numpy's logarithms, branch-free passes) decides it: the same
    counts as the scalar pass wherever both decide, nearly every pixel of a
    well-exposed image decided there, and scipy's quantiles in the end, also
    for draws at the edges of Acklam's central region and means at the ends
    of PP_MEANS; an image mostly below those means skips it."""
    from scipy import stats

    from cfa_mitsuba.sensor import _poisson_kernel as kernel
    from cfa_mitsuba.sensor.noise import poisson_quantile

    rng = np.random.default_rng(21)
    lo, hi = kernel.PP_MEANS
    lam = np.concatenate([np.exp(rng.uniform(np.log(lo), np.log(hi), 40_000)), [lo, hi, lo, hi]])
    u = np.concatenate([rng.random(40_000), [0.02425, 1 - 0.02425, 0.5, 0.02]])
    tails = rng.integers(0, lam.size, 2_000)
    u[tails] = rng.choice([0.02425, 0.9757, 0.0243, 0.97575], tails.size) + rng.normal(0, 1e-6, tails.size)
    scalar_k, scalar_decided = np.empty(lam.size), np.zeros(lam.size, dtype=bool)
    kernel._start_and_settle(lam, u, scalar_k, scalar_decided)
    first_k, first_decided = np.empty(lam.size), np.zeros(lam.size, dtype=bool)
    kernel._first_attempt(lam, u, first_k, first_decided)
    assert first_decided.mean() > 0.9
    both = first_decided & scalar_decided
    assert both.sum() > 0.9 * lam.size
    assert np.array_equal(first_k[first_decided], stats.poisson.ppf(u[first_decided], lam[first_decided]))
    assert np.array_equal(poisson_quantile(lam, u), stats.poisson.ppf(u, lam))
    calls = []
    monkeypatch.setattr(kernel, "_first_attempt", lambda *a: calls.append(1))
    kernel.start_and_settle(rng.uniform(0, 5, 1000), rng.random(1000))
    assert not calls
    kernel.start_and_settle(rng.uniform(50, 500, 1000), rng.random(1000))
    assert calls
