"""Charge collection and read-out: photon noise, dark current, fixed-pattern
noise, well clipping, read noise, gain, black level and the ADC.

Order (per exposure, for noise ``all``), following the physics and, where
it is a choice, ISETCam's ``sensorCompute`` / ``sensorAddNoise``
(research/isetcam.md s. 1.7):

1. mean photo-electrons x (1 + PRNU z_p): PRNU is a fixed per-pixel gain
   of the photo-response (EMVA 1288's model; ISETCam applies its gain FPN
   to volts after the shot noise, the same to first order);
2. + dark current x exposure; the total is drawn from an exact Poisson
   distribution, so dark charge has its own shot noise (ISETCam uses a
   Gaussian above 25 e-); electrons are never negative.  The draw is the
   Poisson quantile of one uniform number per pixel (:func:`poisson_quantile`),
   so the noise field is a monotone function of the mean: a render that
   differs in its last bits (another CPU, another LLVM) moves a handful of
   pixels by one electron instead of re-dealing every pixel's noise, as a
   rejection sampler's variable use of random numbers would;
3. clipped at the full well;
4. + DSNU z_d (a fixed per-pixel offset, electrons) + read noise
   (Gaussian, electrons rms);
5. x DN per electron (analog gain included) + black level, rounded to an
   integer code and clipped to 0 .. 2^bits - 1.

z_p and z_d are standard-normal maps drawn once per sensor seed (one seed
is one physical sensor); the temporal noise uses the capture seed.  The two
streams come from independent ``numpy.random.SeedSequence`` children, so
equal seeds do not correlate them.

``shot`` keeps only step 1 without PRNU, the Poisson draw and step 3, and
returns electrons x DN per electron unquantised with no black level.
``off`` returns the mean photo-electrons clipped at the well, scaled the
same way.
"""

from __future__ import annotations

__all__ = ["fixed_pattern", "collect_electrons", "read_out", "temporal_rng", "poisson_quantile"]

import functools

import numpy as np

from ..errors import CfaMitsubaError
from .params import NOISE_MODES, SensorParams


def temporal_rng(seed: int) -> np.random.Generator:
    """The generator of one capture's temporal noise."""
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(1,)))


@functools.lru_cache(maxsize=4)
def _fixed_pattern(h: int, w: int, sensor_seed: int):
    rng = np.random.default_rng(np.random.SeedSequence(int(sensor_seed), spawn_key=(2,)))
    prnu_z = rng.standard_normal((h, w))
    dsnu_z = rng.standard_normal((h, w))
    prnu_z.flags.writeable = False
    dsnu_z.flags.writeable = False
    return prnu_z, dsnu_z


def fixed_pattern(shape: tuple[int, int], sensor_seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Standard-normal PRNU and DSNU maps of a sensor, each (H, W), read-only.

    The same ``sensor_seed`` and shape always give the same maps."""
    return _fixed_pattern(int(shape[0]), int(shape[1]), int(sensor_seed))


def _check_mode(noise: str) -> str:
    if noise not in NOISE_MODES:
        raise CfaMitsubaError(f"unknown noise mode {noise!r} (choose {', '.join(NOISE_MODES)})")
    return noise


def collect_electrons(photo_e: np.ndarray, *, exposure_s: float, sensor: SensorParams, noise: str,
                      rng: np.random.Generator | None = None, well_e=None) -> np.ndarray:
    """Electrons in each well at the end of the exposure, before read-out.

    Parameters
    ----------
    photo_e : (H, W) mean photo-electrons (finite, >= 0).
    exposure_s : exposure (s), for the dark current.
    sensor : the pixel's settings.
    noise : ``off``, ``shot`` or ``all`` (module doc).
    rng : temporal noise generator (:func:`temporal_rng`); needed unless
        ``noise`` is ``off``.
    well_e : the full well of each pixel ((H, W), e.g. per channel), or
        None: ``sensor.well_capacity_e``.

    Returns
    -------
    (H, W) float64 electrons in [0, well].
    """
    _check_mode(noise)
    well = float(sensor.well_capacity_e) if well_e is None else np.asarray(well_e, dtype=np.float64)
    mean = np.asarray(photo_e, dtype=np.float64)
    if noise == "off":
        return np.minimum(mean, well)
    if noise == "all":
        if sensor.prnu_percent > 0:
            prnu_z, _ = fixed_pattern(mean.shape, sensor.sensor_seed)
            mean = np.maximum(mean * (1.0 + sensor.prnu_percent / 100.0 * prnu_z), 0.0)
        if sensor.dark_current_e_s > 0:
            mean = mean + sensor.dark_current_e_s * float(exposure_s)
    # Above this mean a Poisson draw exceeds the well with probability
    # ~1 - 1e-300, so capping the mean changes nothing after clipping and
    # keeps numpy's sampler in range for absurd exposures.
    cap = 4.0 * np.max(well) + 100.0 * np.sqrt(np.max(well)) + 1000.0
    electrons = poisson_quantile(np.minimum(mean, cap), rng.random(mean.shape))
    return np.minimum(electrons, well, out=electrons)


def poisson_quantile(mean: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Exact Poisson draws by inversion: the smallest k with P(X <= k) >= u.

    ``mean`` (finite, >= 0) and ``u`` (uniform in [0, 1)) of one shape;
    returns float64 counts.  With ``u`` uniform the result is exactly
    Poisson(mean) distributed; for fixed ``u`` it is non-decreasing in
    ``mean`` (common random numbers).

    Written here because numpy has no Poisson quantile and scipy's
    ``stats.poisson.ppf`` takes about 10x as long: a Cornish-Fisher start
    (normal quantile z: k0 = mean + sqrt(mean) z + (z^2 - 1)/6), then steps
    of one count (:mod:`._poisson_kernel`; one or two settle almost every
    pixel at any mean), each decided only where it is certain:

    1. at means of 10 to 1e6, by Peizer and Pratt's normal approximation of
       the CDF, where ``u`` is farther from it than ``pp_guard`` (at least 8x
       its largest error there, ``benchmarks/poisson_pp_error.py``): all but
       about 0.4 % of such pixels at a mean of 30 and 5e-5 at 3,000, at under
       half the cost of an incomplete gamma function;
    2. at means below 10 (most pixels of a low-light capture), by counting
       up from 0 with the CDF summed from the mass's recurrence (about mean
       + 1 steps, its rounding about 1e-14 relative), where ``u`` is farther
       than 1e-9 (relative) from every CDF on the way: a third of the time
       of the incomplete gamma function and the mass below;
    3. the rest by the exact CDF at the start (``scipy.special.pdtr``, the
       regularised upper incomplete gamma function) and the neighbouring
       CDFs by the mass's recurrence, and where ``u`` lies within 1e-9
       (relative) of one of those, by ``pdtr`` itself.

    So the counts are those of stepping with ``pdtr`` throughout
    (tests/sensor/test_noise.py compares with ``scipy.stats.poisson.ppf``).

    Peizer, D. B., Pratt, J. W., "A normal approximation for binomial, F,
    beta, and other common, related tail probabilities, I", J. Amer. Statist.
    Assoc. 63 (1968) 1416-1456.
    """
    from ._poisson_kernel import start_and_settle

    lam = np.ascontiguousarray(mean, dtype=np.float64).ravel()
    uu = np.ascontiguousarray(u, dtype=np.float64).ravel()
    k, decided = start_and_settle(lam, uu)
    rest = np.flatnonzero(~decided)
    if rest.size == k.size:
        _settle_by_cdf(lam, uu, k)
    elif rest.size:
        kr = k[rest]
        _settle_by_cdf(lam[rest], uu[rest], kr)
        k[rest] = kr
    return k.reshape(np.shape(mean))


def _settle_by_cdf(lam: np.ndarray, u: np.ndarray, k: np.ndarray) -> None:
    """Move the starts ``k`` (1-D float64, in place) to the quantiles by the
    exact CDF at the start and the mass's recurrence from there."""
    from scipy import special

    from ._poisson_kernel import settle

    pmf = np.exp(special.xlogy(k, lam) - lam - special.gammaln(k + 1.0))
    undecided = np.flatnonzero(settle(lam, u, k, special.pdtr(k, lam), pmf))
    if undecided.size:
        k[undecided] = _exact_quantile(lam[undecided], u[undecided], k[undecided])


def _exact_quantile(lam: np.ndarray, u: np.ndarray, k: np.ndarray) -> np.ndarray:
    """The smallest count whose CDF (``scipy.special.pdtr``) reaches ``u``,
    stepping one count at a time from the start ``k`` (1-D float64)."""
    from scipy import special

    k = k.copy()
    idx = np.flatnonzero(special.pdtr(k, lam) < u)
    while idx.size:
        k[idx] += 1.0
        idx = idx[special.pdtr(k[idx], lam[idx]) < u[idx]]
    idx = np.flatnonzero(k > 0)
    while idx.size:
        idx = idx[special.pdtr(k[idx] - 1.0, lam[idx]) >= u[idx]]
        k[idx] -= 1.0
        idx = idx[k[idx] > 0]
    return k


def read_out(electrons: np.ndarray, *, sensor: SensorParams, noise: str,
             rng: np.random.Generator | None = None, gain=None) -> np.ndarray:
    """Digital numbers from collected electrons (module doc, steps 4-5).

    ``gain``: a relative analogue gain per pixel ((H, W), e.g. per channel)
    multiplying ``sensor.dn_per_electron``; None: 1.

    Returns (H, W) float64 DN: integer codes in 0 .. 2^bits - 1 for noise
    ``all``; electrons x DN per electron (unquantised, no black level) for
    ``off`` and ``shot``.
    """
    _check_mode(noise)
    g = sensor.dn_per_electron if gain is None else sensor.dn_per_electron * np.asarray(gain, dtype=np.float64)
    if noise != "all":
        return electrons * g
    v = electrons.copy()
    if sensor.dsnu_e > 0:
        _, dsnu_z = fixed_pattern(v.shape, sensor.sensor_seed)
        v += sensor.dsnu_e * dsnu_z
    if sensor.read_noise_e > 0:
        v += sensor.read_noise_e * rng.standard_normal(v.shape)
    v *= g
    v += sensor.black_level_dn
    np.rint(v, out=v)
    return np.clip(v, 0.0, float(sensor.max_dn), out=v)
