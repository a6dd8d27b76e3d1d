"""Exposure programs: how a capture chooses its time and gains.

A camera meters the scene and runs an *exposure program* (ISO 2720's
reflected-light metering; every phone and video camera's auto exposure):

1. the time that brings the brightest pixel's most sensitive channel to
   :data:`~.metering.AUTO_EXPOSURE_LEVEL` (95 %) of its well at base gain,
   metered at the captured luminance (ISETCam's ``autoExposure``, plus the
   brightest pixel of the optical image itself, so no pixel's well fills in
   bright light);
2. that time capped at ``max_exposure_s`` (:class:`ExposureProgram`'s
   default: a video frame, and the handheld limit of a phone camera);
3. the light still missing made up by analogue gain, up to
   ``max_analog_gain`` (its default: ISO 100 -> 1600 on a sensor whose
   base ISO is 100);
4. the rest by digital gain (no limit: an image is always delivered).

The gains keep the brightest pixel at the same code: at gain g the ADC's
top code is reached by 1/g of the well, so the brightest pixel still sits
at 95 % of the ADC's range and nothing clips.

Where the noise enters (:mod:`.noise`, :func:`.capture.capture`), in
electrons unless said:

* before any gain: photon shot noise, dark current and its shot noise,
  PRNU (a gain on the photo-signal), the well's clip; then DSNU and read
  noise (input-referred, electrons rms, the same at every gain: a
  simplification, real pixels' input-referred read noise falls somewhat
  with analogue gain);
* analogue gain: multiplies electrons + DSNU + read noise together (DN per
  electron = gain x (2^bits - 1 - black) / well);
* after the analogue gain: black level, quantisation to integer codes and
  the ADC's clips at 0 and at the top code.  The black level (pedestal) is
  raised with the program's gain to :data:`PEDESTAL_SIGMAS` dark-noise
  sigmas in DN when the sensor's own is less (64 DN is 16 read-noise sigmas
  at gain 1 but one at gain 16, where the clip at code 0 would cut the
  dark tail, bias the mean up and the noise down: YSNR 4.3 measured for 2.7
  expected on a 2 cd/m^2 grey); ``metering.pedestal_for_gain``;
* digital gain: in the image processor, after the ADC, on the
  black-subtracted codes in floating point (an image processor's extra
  bits, no clip): it multiplies signal and every noise alike, the
  quantisation step included, so it changes no SNR.  This ISP reports
  absolute XYZ (it divides the codes by DN per electron and the exposure),
  so the digital gain would change no number: it is recorded (the raw's
  ``settings['digital_gain']``, metrics.csv's ``digital_gain``) and the raw
  keeps the ADC's codes.

So SNR is set by the electrons and the read noise (and, at low gain, the
ADC step); analogue gain costs headroom only.

Policies (:data:`EXPOSURE_POLICIES`): ``program`` (above, per CFA),
``bayer`` (every CFA at the time and gains the program gives Bayer on the
same scene and luminance: the same camera with another CFA), ``reference``
(ISETCam's auto exposure chosen at a reference luminance and kept at every
luminance, no gain), ``each`` (ISETCam's auto exposure at every
luminance, no cap, no gain) and ``fixed`` (the given time, no metering).

The policy and its settings travel as one value, :class:`ExposureProgram`,
parsed once (a study's ``[sensor]``, the capture command's options) and
passed whole to :func:`~.capture.capture`; its fields' defaults are the
program's defaults, written nowhere else.
"""

from __future__ import annotations

__all__ = ["EXPOSURE_POLICIES", "ExposureProgram", "PEDESTAL_SIGMAS", "ExposureChoice", "check_program_limits"]

import math
import numbers
from dataclasses import dataclass

from ..errors import require

#: How a capture chooses its exposure (module doc): the four ways of 'auto'
#: exposure, then ``fixed``, a given time in seconds.
EXPOSURE_POLICIES = ("program", "bayer", "reference", "each", "fixed")
#: Dark-noise sigmas between the black level and code 0 under the program's
#: analogue gain (a Gaussian's tail beyond 6 sigmas: 1e-9 of the pixels).
PEDESTAL_SIGMAS = 6.0


@dataclass(frozen=True)
class ExposureChoice:
    """What an exposure program chose.

    exposure_s : the integration time (s).
    analog_gain : the analogue gain before the ADC (>= 1; multiplies the
        sensor's own ``analog_gain``).
    digital_gain : the gain after the ADC (>= 1).
    metered_exposure_s : the time the metering asked for at base gain (s);
        ``exposure_s x analog_gain x digital_gain`` equals it.
    """

    exposure_s: float
    analog_gain: float = 1.0
    digital_gain: float = 1.0
    metered_exposure_s: float | None = None

    @property
    def total_gain(self) -> float:
        return self.analog_gain * self.digital_gain


def check_program_limits(max_exposure_s, max_analog_gain) -> tuple[float, float]:
    """(max_exposure_s, max_analog_gain) as floats, or one-line errors:
    the time must be positive seconds, the gain at least 1."""
    for name, v, low in (("max_exposure_s", max_exposure_s, 0.0), ("max_analog_gain", max_analog_gain, 1.0)):
        ok = isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)
        ok = ok and (v > low if name == "max_exposure_s" else v >= low)
        require(ok, f"{name} must be {'a positive number of seconds' if low == 0 else 'a number >= 1'}, got {v!r}")
    return float(max_exposure_s), float(max_analog_gain)


#: The exposure program's limits apply to these policies; the reference
#: luminance to ``reference`` only.
PROGRAM_POLICIES = ("program", "bayer")


@dataclass(frozen=True)
class ExposureProgram:
    """How 'auto' exposure chooses the time and gains: the policy and its
    settings as one value (module doc).

    Attributes
    ----------
    policy : one of :data:`EXPOSURE_POLICIES`.
    max_exposure_s : the program's longest time (s): a 30 frame/s video
        frame, and the handheld limit of a phone camera ('program', 'bayer').
    max_analog_gain : the program's highest analogue gain (>= 1; 16 is ISO
        100 -> 1600 on a sensor whose base ISO is 100).
    reference_luminance_cd_m2 : the mean scene luminance (cd/m^2) at which
        the 'reference' policy meters (Bae 2020 sweeps 3 ... 400 cd/m^2
        around 100).

    Examples
    --------
    >>> c = ExposureProgram().choose(0.004)       # bright: the metered time, no gain
    >>> c.exposure_s, c.analog_gain, c.digital_gain
    (0.004, 1.0, 1.0)
    >>> c = ExposureProgram().choose(1.0)         # dim: 1/30 s, gain 30 = analogue 16 x digital 1.875
    >>> round(c.exposure_s, 6), c.analog_gain, c.digital_gain
    (0.033333, 16.0, 1.875)
    """

    policy: str = "program"
    max_exposure_s: float = 1.0 / 30.0
    max_analog_gain: float = 16.0
    reference_luminance_cd_m2: float = 100.0

    def __post_init__(self):
        require(self.policy in EXPOSURE_POLICIES,
                f"unknown exposure policy {self.policy!r} (choose {', '.join(EXPOSURE_POLICIES)})")
        t, g = check_program_limits(self.max_exposure_s, self.max_analog_gain)
        ref = self.reference_luminance_cd_m2
        require(isinstance(ref, numbers.Real) and not isinstance(ref, bool) and math.isfinite(ref) and ref > 0,
                f"reference luminance must be positive, got {ref!r}")
        object.__setattr__(self, "max_exposure_s", t)
        object.__setattr__(self, "max_analog_gain", g)
        object.__setattr__(self, "reference_luminance_cd_m2", float(ref))

    @classmethod
    def from_keywords(cls, exposure_policy: str | None = None, reference_luminance_cd_m2=None, *,
                      reference_given: bool = False, max_exposure_s=None, max_analog_gain=None) -> "ExposureProgram":
        """The program of loose settings, a value left None taking its
        default.  Without a policy: 'program', unless a reference luminance
        was given (``reference_given``): then 'reference', or 'each' for a
        reference of None (the rule before the program existed)."""
        if exposure_policy is None:
            exposure_policy = "program" if not reference_given else (
                "each" if reference_luminance_cd_m2 is None else "reference")
        given = {"max_exposure_s": max_exposure_s, "max_analog_gain": max_analog_gain,
                 "reference_luminance_cd_m2": reference_luminance_cd_m2}
        return cls(exposure_policy, **{k: v for k, v in given.items() if v is not None})

    @classmethod
    def from_table(cls, table: dict) -> "ExposureProgram":
        """The program of a study's ``[sensor]`` keys ``exposure_policy``,
        ``max_exposure_s``, ``max_analog_gain`` and
        ``reference_luminance_cd_m2`` (the others ignored)."""
        keys = {"exposure_policy": "policy", "max_exposure_s": "max_exposure_s",
                "max_analog_gain": "max_analog_gain", "reference_luminance_cd_m2": "reference_luminance_cd_m2"}
        return cls(**{field: table[key] for key, field in keys.items() if key in table})

    def config_keys(self) -> dict:
        """The ``[sensor]`` keys of this program that its policy reads (a
        study's config.json): the policy, and the program's limits or the
        reference luminance where they apply."""
        out = {"exposure_policy": self.policy}
        if self.policy in PROGRAM_POLICIES:
            out.update(max_exposure_s=self.max_exposure_s, max_analog_gain=self.max_analog_gain)
        if self.policy == "reference":
            out["reference_luminance_cd_m2"] = self.reference_luminance_cd_m2
        return out

    def record(self, mode: str) -> dict:
        """What a capture records of the program (its ``settings``): the
        policy ('fixed' for a given time, ``mode`` 'fixed'), and the limits
        or reference luminance it used (None where they did not apply)."""
        auto = mode == "auto"
        return {"exposure_policy": self.policy if auto else "fixed",
                "max_exposure_s": self.max_exposure_s if auto and self.policy in PROGRAM_POLICIES else None,
                "max_analog_gain": self.max_analog_gain if auto and self.policy in PROGRAM_POLICIES else None,
                "reference_luminance_cd_m2": self.reference_luminance_cd_m2 if auto and self.policy == "reference"
                else None}

    def choose(self, metered_exposure_s: float) -> ExposureChoice:
        """The program's time and gains for a metered exposure (module doc):
        ``metered_exposure_s`` is the time (s) that brings the brightest pixel
        to 95 % of its well at base gain."""
        t0 = float(metered_exposure_s)
        require(math.isfinite(t0) and t0 > 0, f"the metered exposure must be a positive time, got {t0!r}")
        if t0 <= self.max_exposure_s:
            return ExposureChoice(t0, 1.0, 1.0, t0)
        need = t0 / self.max_exposure_s
        analog = min(need, self.max_analog_gain)
        return ExposureChoice(self.max_exposure_s, analog, max(need / analog, 1.0), t0)
