"""SNR parity cases (:mod:`.parity`, ``kind = "snr"``): a pixel's
signal-to-noise ratio over signal levels, as ISETCam's ``pixelSNR`` /
``sensorSNR`` compute it.

The levels are ``count`` log-spaced fractions of the full well (ISETCam:
of the voltage swing, the same thing at its fixed conversion gain) from
``from_fraction`` to ``to_fraction`` (``[levels]``; ISETCam's pixelSNR:
1e-4 .. 1, 50 levels; sensorSNR: 1e-4 .. 1, 20); ``statistic`` picks the
headline: ``"mean"`` of the curve in dB (v_icam_pixelSNR's assert) or
``"first"``, its value at the lowest level (v_icam_sensorSNR's).

``mode = "isetcam"``: ISETCam's formula, in electrons,
SNR = 10 log10(S^2 / (S + read^2 + DSNU^2 + (PRNU S)^2)) (``sensorSNR.m``;
pixelSNR is the same without DSNU and PRNU): shot, read and fixed-pattern
noise, no dark current, no quantisation, no clipping.

``mode = "default"``: measured on our read-out (:mod:`cfa_mitsuba.sensor.noise`):
``samples`` pixels per level through ``collect_electrons`` and ``read_out``
with noise ``all`` (Poisson photo and dark charge over ``exposure_s``,
PRNU, DSNU, read noise, the ADC), SNR = 20 log10(S / sigma) with sigma the
standard deviation of the read-out in electrons.  The black level is lifted
to 8 read-noise sigmas when the case's is lower, so that the ADC's clip at
code 0 does not cut the noise being measured.

References
----------
ISETCam ``sensor/pixel/pixelSNR.m``, ``sensor/sensorSNR.m``,
``sensor/pixel/pixelSNRluxsec.m`` (horizon-research/isetcam ad56275);
EMVA 1288 Release 4.0, s. 4.6 (SNR of a linear sensor).
"""

from __future__ import annotations

__all__ = ["run_snr_case", "isetcam_snr_db", "measured_snr_db"]

import numpy as np

from ..errors import CfaMitsubaError


def isetcam_snr_db(signal_e, sensor) -> np.ndarray:
    """ISETCam's SNR (dB) at mean signals ``signal_e`` (electrons)."""
    s = np.asarray(signal_e, dtype=np.float64)
    prnu = sensor.prnu_percent / 100.0 * s
    noise = s + sensor.read_noise_e**2 + sensor.dsnu_e**2 + prnu**2
    return 10.0 * np.log10(s * s / noise)


def measured_snr_db(signal_e, sensor, exposure_s: float, samples: int, seed: int = 0) -> np.ndarray:
    """SNR (dB) of our read-out chain at mean photo-signals ``signal_e``
    (electrons), ``samples`` pixels each (module doc)."""
    from ..sensor.noise import collect_electrons, read_out, temporal_rng

    floor = 8.0 * sensor.read_noise_e * sensor.dn_per_electron
    if sensor.black_level_dn < floor:
        sensor = sensor.with_(black_level_dn=float(np.ceil(floor)))
    out = []
    for i, s in enumerate(np.asarray(signal_e, dtype=np.float64)):
        rng = temporal_rng(seed + i)
        photo = np.full((1, int(samples)), s)
        electrons = collect_electrons(photo, exposure_s=exposure_s, sensor=sensor, noise="all", rng=rng)
        dn = read_out(electrons, sensor=sensor, noise="all", rng=rng)
        sigma_e = float(np.std(dn)) / sensor.dn_per_electron
        out.append(20.0 * np.log10(s / sigma_e) if sigma_e > 0 else np.inf)
    return np.asarray(out)


def run_snr_case(case):
    """(value dB, 'dB', details) of an SNR case (module doc)."""
    from .parity_image import sensor_for_case

    sensor, _, _ = sensor_for_case(case)
    levels = dict(case.settings.get("levels", {}))
    unknown = sorted(set(levels) - {"from_fraction", "to_fraction", "count"})
    if unknown:
        raise CfaMitsubaError(f"{case.path}: levels.{unknown[0]}: unknown key (from_fraction, to_fraction, count)")
    lo, hi = float(levels.get("from_fraction", 1e-4)), float(levels.get("to_fraction", 1.0))
    count = int(levels.get("count", 50))
    if not (0 < lo < hi <= 1 and count >= 2):
        raise CfaMitsubaError(f"{case.path}: levels must satisfy 0 < from_fraction < to_fraction <= 1, count >= 2")
    statistic = case.settings.get("statistic", "mean")
    if statistic not in ("mean", "first"):
        raise CfaMitsubaError(f"{case.path}: statistic must be 'mean' or 'first' (got {statistic!r})")
    signal = np.logspace(np.log10(lo), np.log10(hi), count) * sensor.well_capacity_e
    if case.mode == "isetcam":
        snr = isetcam_snr_db(signal, sensor)
    else:
        snr = measured_snr_db(signal, sensor, float(case.settings.get("exposure_s", 0.01)),
                              int(case.settings.get("samples", 20000)))
    value = float(np.mean(snr)) if statistic == "mean" else float(snr[0])
    details = {"well_capacity_e": sensor.well_capacity_e, "read_noise_e": sensor.read_noise_e,
               "signal_e": [float(signal[0]), float(signal[-1])], "snr_db": [float(snr[0]), float(snr[-1])],
               "isetcam_formula_snr_db": [float(v) for v in isetcam_snr_db(signal[[0, -1]], sensor)]}
    return value, "dB", details
