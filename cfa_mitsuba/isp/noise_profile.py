"""The capture's own noise, as a camera's noise profile, and the variance-
stabilising transform that lets one denoiser strength serve every level.

A raw capture's temporal noise (:mod:`cfa_mitsuba.sensor.noise`) in
electrons, for a pixel that collected ``e`` electrons on average (photo
and dark charge), is

    var_e(e) = e + r^2 + d^2 + q^2 / 12

with ``e`` the Poisson (shot) term, r the read noise (electrons rms;
``n^2 r^2`` for a digitally binned read-out of n x n photodiodes, whose
codes are averaged), d the DSNU (a fixed offset per pixel, white across
the image) and q = 1 / (DN per electron) the ADC step in electrons (each
channel's own with per-channel gains).  The image processor works on the
white-balanced mosaic, ``z = gain_c x electrons``, so in its units

    var(z) = a_c z + b_c,   a_c = gain_c,   b_c = gain_c^2 (r^2 + d^2 + q^2 / 12)

per channel c: the DNG ``NoiseProfile`` form (S, O) of a real camera's
metadata (Adobe DNG 1.4, tag 51041), here predicted from the sensor model
at the capture's gain instead of calibrated.  Noise ``shot`` keeps only the
Poisson term (b = 0); noise ``off`` has none (a = b = 0: nothing to remove).
PRNU (a gain error, variance quadratic in the signal; 0 by default) is left
out, as in DNG's profile.

A denoiser made for white Gaussian noise of one level gets Poisson-Gaussian
noise of unit variance at every level through the generalised Anscombe
transformation (GAT) of each channel,

    f(z) = (2 / a) sqrt(a z + 3/8 a^2 + b)        (0 where the root's argument is negative)

and the denoised image comes back through the closed-form approximation
of the exact unbiased inverse of Makitalo and Foi (2013, eq. 21 with the
GAT's normalisation, eq. 4):

    I(D) = a [D^2/4 + sqrt(3/2)/(4 D) - 11/(8 D^2) + 5 sqrt(3/2)/(8 D^3) - 1/8 - b / a^2]

for D >= 1, the algebraic inverse a (D^2/4 - 3/8 - b/a^2) below (the
series diverges there; the two differ by 0.055 a at D = 1).  So a
denoiser's ``sigma`` in the stabilised domain, times the predicted noise
standard deviation sqrt(a z + b) of each channel at each level, is the
strength applied at that level: the noise profile sets the strength, the
tuning constant only scales it.

References
----------
M. Makitalo, A. Foi, "Optimal inversion of the generalized Anscombe
transformation for Poisson-Gaussian noise", IEEE Trans. Image Process.
22(1) (2013) 91-103.  F. J. Anscombe, "The transformation of Poisson,
binomial and negative-binomial data", Biometrika 35 (1948) 246-254.
Adobe, Digital Negative (DNG) Specification 1.4.0.0 (2012), NoiseProfile.
"""

from __future__ import annotations

__all__ = ["NoiseProfile", "noise_profile", "gat_forward", "gat_inverse"]

from dataclasses import dataclass

import numpy as np

from ..errors import CfaMitsubaError

_SQRT_3_2 = np.sqrt(1.5)


@dataclass(frozen=True)
class NoiseProfile:
    """Per-channel noise variance ``a[c] * z + b[c]`` of the white-balanced
    mosaic ``z`` (its units: electrons x white-balance gain).

    Attributes
    ----------
    channels : channel names, the order of ``a`` and ``b``.
    a : (C,) shot-noise slope (balanced units; the channel's gain per electron).
    b : (C,) signal-independent variance (balanced units squared).
    electrons : the same in electrons: ``{'read_e', 'dsnu_e', 'adc_step_e'
        (per channel), 'floor_variance_e2' (per channel)}``, for the record.
    """

    channels: tuple[str, ...]
    a: np.ndarray
    b: np.ndarray
    electrons: dict

    @property
    def noise_free(self) -> bool:
        return not (np.any(self.a > 0) or np.any(self.b > 0))

    def sigma(self, channel: int, level) -> np.ndarray:
        """Predicted noise standard deviation of ``channel`` at ``level``
        (balanced units; negative levels count as 0 signal)."""
        z = np.maximum(np.asarray(level, dtype=np.float64), 0.0)
        return np.sqrt(self.a[channel] * z + self.b[channel])

    def as_meta(self) -> dict:
        return {"channels": list(self.channels), "shot_slope": self.a.tolist(), "floor_variance": self.b.tolist(),
                **{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.electrons.items()}}


def _sensor(raw) -> dict:
    settings = raw.settings if isinstance(raw.settings, dict) else {}
    s = settings.get("sensor")
    return s if isinstance(s, dict) else {}


def noise_profile(raw, gains, channels, per_channel_divisors=None) -> NoiseProfile:
    """The noise profile of a capture's white-balanced mosaic (module doc).

    Parameters
    ----------
    raw : the :class:`~cfa_mitsuba.values.RawImage` (its ``settings``:
        noise mode, read noise, DSNU, read-out; ``dn_per_electron``).
    gains : (C,) white-balance gains per electron of the processing.
    channels : the channel names in the order of ``gains``.
    per_channel_divisors : (C,) each channel's relative analogue gain (its
        DN per electron over ``raw.dn_per_electron``), or None.
    """
    gains = np.asarray(gains, dtype=np.float64)
    settings = raw.settings if isinstance(raw.settings, dict) else {}
    mode = settings.get("noise", "all")
    c = gains.size
    if mode == "off":
        zero = np.zeros(c)
        return NoiseProfile(tuple(channels), zero, zero.copy(), {"noise": "off"})
    if mode not in ("shot", "all"):
        raise CfaMitsubaError(f"raw image: unknown noise mode {mode!r} in its settings")
    sensor = _sensor(raw)
    read = float(sensor.get("read_noise_e") or 0.0) if mode == "all" else 0.0
    dsnu = float(sensor.get("dsnu_e") or 0.0) if mode == "all" else 0.0
    readout = (raw.meta or {}).get("readout") if isinstance(raw.meta, dict) else None
    if isinstance(readout, dict) and readout.get("mode") == "bin" and readout.get("binning") == "digital":
        n = int(readout.get("block") or 1)
        read *= n  # n^2 reads averaged, in the summed charge: variance n^2 r^2
    divisors = np.ones(c) if per_channel_divisors is None else np.asarray(per_channel_divisors, dtype=np.float64)
    step = 1.0 / (float(raw.dn_per_electron) * divisors) if mode == "all" else np.zeros(c)
    floor_e = read**2 + dsnu**2 + step**2 / 12.0
    return NoiseProfile(tuple(channels), gains.copy(), gains**2 * floor_e,
                        {"noise": mode, "read_e": read, "dsnu_e": dsnu, "adc_step_e": step,
                         "floor_variance_e2": floor_e})


def gat_forward(z: np.ndarray, a: float, b: float) -> np.ndarray:
    """The generalised Anscombe transformation (module doc): unit noise
    variance at every level for var(z) = a z + b, a > 0."""
    arg = a * np.asarray(z, dtype=np.float64) + 0.375 * a * a + b
    return (2.0 / a) * np.sqrt(np.maximum(arg, 0.0))


def gat_inverse(d: np.ndarray, a: float, b: float) -> np.ndarray:
    """Makitalo and Foi's closed-form unbiased inverse of :func:`gat_forward`
    (module doc; the algebraic inverse for D < 1)."""
    d = np.asarray(d, dtype=np.float64)
    s2 = b / (a * a)
    safe = np.maximum(d, 1.0)
    closed = (0.25 * safe**2 + 0.25 * _SQRT_3_2 / safe - 1.375 / safe**2 + 0.625 * _SQRT_3_2 / safe**3
              - 0.125 - s2)
    algebraic = 0.25 * d * d - 0.375 - s2
    return a * np.where(d >= 1.0, closed, algebraic)
