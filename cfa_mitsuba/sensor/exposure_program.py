"""Exposure programs: how a capture chooses its time and gains.

A camera meters the scene and runs an *exposure program* (ISO 2720's
reflected-light metering; every phone and video camera's auto exposure):

1. the time that brings the brightest pixel's most sensitive channel to
   :data:`~.capture.AUTO_EXPOSURE_LEVEL` (95 %) of its well at base gain,
   metered at the captured luminance (ISETCam's ``autoExposure``, plus the
   brightest pixel of the optical image itself, so no pixel's well fills in
   bright light);
2. that time capped at ``max_exposure_s`` (default 1/30 s: a video frame,
   and the handheld limit of a phone camera);
3. the light still missing made up by analogue gain, up to
   ``max_analog_gain`` (default 16, ISO 100 -> 1600 on a sensor whose
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
  expected on a 2 cd/m^2 grey); ``capture.pedestal_for_gain``;
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
luminance, no gain) and ``each`` (ISETCam's auto exposure at every
luminance, no cap, no gain).  A fixed time is the study's ``fixed``.
"""

from __future__ import annotations

__all__ = ["EXPOSURE_POLICIES", "DEFAULT_MAX_EXPOSURE_S", "DEFAULT_MAX_ANALOG_GAIN", "PEDESTAL_SIGMAS", "ExposureChoice",
           "run_program", "check_program_limits"]

import math
import numbers
from dataclasses import dataclass

from ..errors import require

#: How ``capture(exposure_s="auto")`` chooses the exposure (module doc).
EXPOSURE_POLICIES = ("program", "bayer", "reference", "each")
#: The longest exposure of the program (s): a 30 frame/s video frame.
DEFAULT_MAX_EXPOSURE_S = 1.0 / 30.0
#: The highest analogue gain of the program (16: ISO 100 -> 1600).
DEFAULT_MAX_ANALOG_GAIN = 16.0
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


def run_program(metered_exposure_s: float, max_exposure_s: float = DEFAULT_MAX_EXPOSURE_S,
                max_analog_gain: float = DEFAULT_MAX_ANALOG_GAIN) -> ExposureChoice:
    """The program's time and gains for a metered exposure (module doc).

    Parameters
    ----------
    metered_exposure_s : the time (s) that brings the brightest pixel to
        95 % of its well at base gain.
    max_exposure_s : the longest time (s).
    max_analog_gain : the highest analogue gain (>= 1).

    Examples
    --------
    >>> c = run_program(0.004)              # bright: the metered time, no gain
    >>> c.exposure_s, c.analog_gain, c.digital_gain
    (0.004, 1.0, 1.0)
    >>> c = run_program(1.0)                # dim: 1/30 s, gain 30 = analogue 16 x digital 1.875
    >>> round(c.exposure_s, 6), c.analog_gain, c.digital_gain
    (0.033333, 16.0, 1.875)
    """
    t_max, g_max = check_program_limits(max_exposure_s, max_analog_gain)
    t0 = float(metered_exposure_s)
    require(math.isfinite(t0) and t0 > 0, f"the metered exposure must be a positive time, got {t0!r}")
    if t0 <= t_max:
        return ExposureChoice(t0, 1.0, 1.0, t0)
    need = t0 / t_max
    analog = min(need, g_max)
    return ExposureChoice(t_max, analog, max(need / analog, 1.0), t0)
