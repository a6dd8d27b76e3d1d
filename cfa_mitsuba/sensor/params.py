"""The pixel and read-out chain: defaults, their sources, validation.

Defaults follow ISETCam's default APS pixel (``sensor/pixel/pixelCreate.m``,
``pixelAPSInit``: 2.8 um, voltage swing 1 V, conversion gain 100 uV/e-, so a
10 000 e- well, read noise 1 mV, dark voltage 1 mV/s; research/isetcam.md
s. 1.1), moved to the paper's 2.2 um pitch this way:

* The voltage-domain values stay (swing 1 V, read noise 1 mV rms, dark
  signal 1 mV/s).  The full well scales with the photodiode's area,
  10 000 x (2.2 / 2.8)^2 = 6 173 e- (rounded to 6 200 e-); the conversion
  gain follows as swing / well = 161 uV/e- (a smaller pixel has a smaller
  sense node), so read noise is 1 mV / 161 uV = 6.2 e- and dark current
  1 mV/s = 6.2 e-/s (also 10 e-/s x the area ratio).  For comparison, the
  2.2 um pixel of onsemi's MT9P031 (datasheet rev. 10: SNR_max 38.1 dB,
  pixel dynamic range 70.1 dB) holds 10^(38.1/10) = 6 500 e- (SNR_max =
  sqrt(well)) with about 2 e- read noise: the well matches, the read noise
  is ISETCam's, higher than a modern pixel's.
* Fill factor 1: the quantum efficiencies (``spectra.CAMERA_PEAK_QE``, peak
  0.6 for W) are EMVA 1288-style values referred to the whole pixel area,
  as for a micro-lensed pixel, so a fill factor below 1 would count the
  lost area twice.  ISETCam's 0.75 is available (``fill_factor=0.75``).
* DSNU 0 and PRNU 0, as ISETCam's ``sensorCreate`` (typical EMVA 1288
  datasheet values, 1-2 e- and 0.5-1 %, can be set).
* Analog gain 1 (multiplies the signal; ISETCam divides by its gain).
* ADC: 12 bits (ISETCam's vendor presets; its default is unquantised
  'analog'), black level 64 DN, more than 10 read-noise sigmas above 0 so
  that the dark tail is not clipped; the full well at gain 1 maps to the
  top code: DN per electron = gain x (2^bits - 1 - black) / well.
"""

from __future__ import annotations

__all__ = ["SensorParams", "NOISE_MODES", "READOUT_MODES", "BINNING_MODES", "MIN_PIXEL_PITCH_UM", "MIN_WELL_E",
           "check_channel_names"]

import math
import numbers
from dataclasses import asdict, dataclass, fields, replace

from ..errors import CfaMitsubaError

#: ``off``: no noise of any kind (no DSNU/PRNU, no dark current, no ADC
#: quantisation, no black level; the well still clips).  ``shot``: photon
#: noise only (exact Poisson), no ADC.  ``all``: photon and dark-current shot
#: noise, PRNU, DSNU, read noise, well clipping, analog gain, black level,
#: ADC quantisation and clipping.
NOISE_MODES = ("off", "shot", "all")
#: ``full``: the native mosaic is read and demosaiced; ``remosaic``: read at
#: full resolution, rearranged to a Bayer mosaic by the image processor;
#: ``bin``: each same-colour block of a block layout (quad-bayer, nona,
#: tetra2) summed at read-out into one pixel (:mod:`.readout`).
READOUT_MODES = ("full", "remosaic", "bin")
#: ``charge``: a block's charge is summed on the shared sense node and read
#: once (read noise and DSNU once per binned pixel); ``digital``: every
#: sub-pixel is read and quantised, the codes averaged (read noise once per
#: sub-pixel).
BINNING_MODES = ("charge", "digital")

#: The smallest pixel pitch accepted, um.  A photodiode samples light of
#: 400-700 nm; far below that wavelength it no longer confines the light it
#: absorbs, and the smallest pixels made are 0.56 um (Samsung ISOCELL HP3,
#: 2022).  0.1 um, a quarter of the shortest visible wavelength, is beyond
#: any pixel built or planned.
MIN_PIXEL_PITCH_UM = 0.1
#: The smallest full well accepted: one electron (charge comes in electrons).
MIN_WELL_E = 1.0

_AREA_RATIO = (2.2 / 2.8) ** 2
_WELL_E = 6200.0
_SWING_V = 1.0
_CG_V_PER_E = _SWING_V / _WELL_E
_NOT_NUMBERS = ("readout", "binning", "ir_cut", "channel_well_e", "channel_gain")


def check_channel_names(values: dict, channels, where: str) -> None:
    """Refuse a per-channel setting (``channel_well_e``, ``channel_gain`` in
    ``values``, as given or as pairs) for a channel not among ``channels``
    (those of the CFAs it applies to; ``where`` names them): it would
    silently apply to nothing.  Checked before the setting's values, since
    a channel that does not exist is the first thing wrong with it."""
    known = set(channels)
    for name in ("channel_well_e", "channel_gain"):
        given = values.get(name) or {}
        for c in (given if isinstance(given, dict) else dict(given)):
            if str(c) not in known:
                raise CfaMitsubaError(f"sensor {name} sets channel {str(c)!r}, not a channel of {where} "
                                      f"({', '.join(sorted(known))}): it would apply to nothing")


def _channel_pairs(name: str, value, positive) -> tuple:
    """A per-channel setting ({channel: number} or pairs) as sorted
    (channel, float) pairs, so the params stay hashable."""
    items = value.items() if isinstance(value, dict) else value
    try:
        pairs = [(str(k), v) for k, v in items]
    except (TypeError, ValueError):
        raise CfaMitsubaError(f"sensor {name} must map channel names to numbers, got {value!r}") from None
    for k, v in pairs:
        positive(f"{name}[{k!r}]", v)
    return tuple(sorted((k, float(v)) for k, v in pairs))


@dataclass(frozen=True)
class SensorParams:
    """A sensor: pixel geometry, photodiode and read-out chain.

    Attributes
    ----------
    pixel_pitch_um : pixel pitch (um), square pixels, no gaps.  2.2 (Bae
        2020: Nyquist 227 cy/mm).
    fill_factor : photosensitive fraction of the pixel area, (0, 1]; the
        photodiode is a centred square of side sqrt(FF) x pitch.  1.0.
    well_capacity_e : full-well capacity (electrons).  6200.
    voltage_swing_v : sense-node voltage swing (V); conversion gain =
        swing / well.  1.0 (ISETCam).
    read_noise_e : read noise (electrons rms).  6.2 (ISETCam's 1 mV).
    dark_current_e_s : dark current (electrons per second).  6.2 (ISETCam's
        1 mV/s).
    dsnu_e : dark-signal non-uniformity (electrons rms, a fixed offset per
        pixel).  0.
    prnu_percent : photo-response non-uniformity (percent rms of the photo
        signal, a fixed gain per pixel).  0.
    analog_gain : gain before the ADC (multiplies).  1.
    adc_bits : ADC resolution.  12.
    black_level_dn : offset added before quantisation (DN).  64.
    sensor_seed : seed of the fixed-pattern maps (DSNU, PRNU): one seed is
        one physical sensor.  0.
    readout : :data:`READOUT_MODES`.  ``"full"``.
    binning : :data:`BINNING_MODES`, for ``readout = "bin"``.  ``"charge"``.
    crosstalk : fraction of a pixel's photo-electrons that land in its four
        nearest neighbours (a quarter each) at 400 nm, and at every
        wavelength unless ``crosstalk_700nm`` is given (:mod:`.physics`).  0.
    crosstalk_700nm : the fraction at 700 nm, linear in wavelength from
        ``crosstalk`` at 400 nm (carrier diffusion grows with silicon's
        absorption depth).  None: ``crosstalk`` at every wavelength.
    ir_cut : the IR-cut filter on top of the silicon: ``""`` the spectra
        set's own (the common Largan K098), ``"none"``, or a CSV file
        (``wavelength_nm, transmittance``) (:mod:`.physics`).  ``""``.
    channel_well_e : full well per channel, ``{"R": 5000, ...}`` (electrons;
        other channels: ``well_capacity_e``).  Stored as sorted pairs.
    channel_gain : analogue gain per channel, ``{"B": 2.0, ...}``,
        multiplying ``analog_gain`` (DN clip at the top code).  Stored as
        sorted pairs.
    """

    pixel_pitch_um: float = 2.2
    fill_factor: float = 1.0
    well_capacity_e: float = _WELL_E
    voltage_swing_v: float = _SWING_V
    read_noise_e: float = round(1e-3 / _CG_V_PER_E, 3)
    dark_current_e_s: float = round(1e-3 / _CG_V_PER_E, 3)
    dsnu_e: float = 0.0
    prnu_percent: float = 0.0
    analog_gain: float = 1.0
    adc_bits: int = 12
    black_level_dn: float = 64.0
    sensor_seed: int = 0
    readout: str = "full"
    binning: str = "charge"
    crosstalk: float = 0.0
    crosstalk_700nm: float | None = None
    ir_cut: str = ""
    channel_well_e: tuple = ()
    channel_gain: tuple = ()

    def __post_init__(self):
        def positive(name, v, allow_zero=False):
            ok = isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)
            ok = ok and (v >= 0 if allow_zero else v > 0)
            if not ok:
                raise CfaMitsubaError(f"sensor {name} must be a {'non-negative' if allow_zero else 'positive'} "
                                      f"number, got {v!r}")

        positive("pixel_pitch_um", self.pixel_pitch_um)
        if self.pixel_pitch_um < MIN_PIXEL_PITCH_UM:
            raise CfaMitsubaError(f"sensor pixel_pitch_um {self.pixel_pitch_um:g} um is below {MIN_PIXEL_PITCH_UM:g} "
                                  "um, a quarter of the shortest visible wavelength: no photodiode samples light at "
                                  "that pitch (the smallest made are 0.56 um)")
        positive("fill_factor", self.fill_factor)
        if self.fill_factor > 1:
            raise CfaMitsubaError(f"sensor fill_factor must lie in (0, 1], got {self.fill_factor!r}")
        positive("well_capacity_e", self.well_capacity_e)
        positive("voltage_swing_v", self.voltage_swing_v)
        for name in ("read_noise_e", "dark_current_e_s", "dsnu_e", "prnu_percent", "black_level_dn"):
            positive(name, getattr(self, name), allow_zero=True)
        positive("analog_gain", self.analog_gain)
        if isinstance(self.adc_bits, bool) or not isinstance(self.adc_bits, numbers.Integral) \
                or not 1 <= self.adc_bits <= 32:
            raise CfaMitsubaError(f"sensor adc_bits must be an integer in 1..32, got {self.adc_bits!r}")
        if self.black_level_dn >= 2**self.adc_bits - 1:
            raise CfaMitsubaError(f"black level {self.black_level_dn:g} DN leaves no room in a "
                                  f"{self.adc_bits}-bit ADC")
        if isinstance(self.sensor_seed, bool) or not isinstance(self.sensor_seed, numbers.Integral) \
                or self.sensor_seed < 0:
            raise CfaMitsubaError(f"sensor_seed must be a non-negative integer, got {self.sensor_seed!r}")
        self._check_readout_and_physics(positive)
        self._check_dynamic_range()
        for f in fields(self):  # plain Python numbers (JSON-able settings), whatever numpy type came in
            v = getattr(self, f.name)
            if f.name in _NOT_NUMBERS or (f.name == "crosstalk_700nm" and v is None):
                continue
            object.__setattr__(self, f.name, int(v) if f.name in ("adc_bits", "sensor_seed") else float(v))

    def _check_dynamic_range(self) -> None:
        """A full well of at least one electron that stands above the read
        noise: a pixel whose well is not larger than its read noise has a
        dynamic range (well / read noise, EMVA 1288 s. 4.8) below 1, so no
        signal it can hold is distinguishable from its noise (real pixels:
        10^2 to 10^5)."""
        wells = [("well_capacity_e", float(self.well_capacity_e))]
        wells += [(f"channel_well_e[{c!r}]", float(w)) for c, w in self.channel_well_e]
        for name, well in wells:
            if well < MIN_WELL_E:
                raise CfaMitsubaError(f"sensor {name} {well:g} e- is below one electron: a well holds whole "
                                      "electrons")
            if self.read_noise_e >= well:
                raise CfaMitsubaError(f"sensor {name} {well:g} e- is not above the read noise {self.read_noise_e:g} "
                                      f"e-: a dynamic range (well / read noise) of {well / self.read_noise_e:.3g}, "
                                      "below 1, leaves no signal above the noise (real pixels: 100 to 100,000)")

    def check_channels(self, channels, where: str) -> None:
        """:func:`check_channel_names` of this sensor's per-channel settings."""
        check_channel_names({n: dict(getattr(self, n)) for n in ("channel_well_e", "channel_gain")}, channels, where)

    def _check_readout_and_physics(self, positive) -> None:
        if self.readout not in READOUT_MODES:
            raise CfaMitsubaError(f"sensor readout must be one of {', '.join(READOUT_MODES)}, got {self.readout!r}")
        if self.binning not in BINNING_MODES:
            raise CfaMitsubaError(f"sensor binning must be one of {', '.join(BINNING_MODES)}, got {self.binning!r}")
        for name in ("crosstalk", "crosstalk_700nm"):
            v = getattr(self, name)
            if v is None:
                continue
            positive(name, v, allow_zero=True)
            if v > 0.5:
                raise CfaMitsubaError(f"sensor {name} is a fraction of the signal in [0, 0.5], got {v!r}")
        if not isinstance(self.ir_cut, str):
            raise CfaMitsubaError(f"sensor ir_cut must be '', 'none' or a CSV path, got {self.ir_cut!r}")
        for name in ("channel_well_e", "channel_gain"):
            object.__setattr__(self, name, _channel_pairs(name, getattr(self, name), positive))

    @property
    def conversion_gain_uv_per_e(self) -> float:
        """Sense-node conversion gain (uV per electron) = swing / well."""
        return self.voltage_swing_v / self.well_capacity_e * 1e6

    @property
    def pixel_area_m2(self) -> float:
        return (self.pixel_pitch_um * 1e-6) ** 2

    @property
    def max_dn(self) -> int:
        return 2**self.adc_bits - 1

    @property
    def dn_per_electron(self) -> float:
        """Digital numbers per electron: analog gain x (2^bits - 1 - black
        level) / well, so that at gain 1 a full well reaches the top code.
        The same scale is used with noise ``off`` and ``shot`` (which add no
        black level and do not quantise)."""
        return self.analog_gain * (self.max_dn - self.black_level_dn) / self.well_capacity_e

    def with_(self, **changes) -> "SensorParams":
        """A copy with some settings changed (None values are ignored)."""
        known = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - known)
        if unknown:
            raise CfaMitsubaError(f"unknown sensor setting {unknown[0]!r} (known: {', '.join(sorted(known))})")
        return replace(self, **{k: v for k, v in changes.items() if v is not None})

    def channel_value(self, name: str, channel: str) -> float:
        """The per-channel full well (``channel_well_e``) or gain
        (``channel_gain``, relative: 1 when not given) of ``channel``."""
        pairs = dict(getattr(self, name))
        if name == "channel_well_e":
            return float(pairs.get(channel, self.well_capacity_e))
        return float(pairs.get(channel, 1.0))

    def to_dict(self) -> dict:
        d = asdict(self)
        d["channel_well_e"] = dict(self.channel_well_e)
        d["channel_gain"] = dict(self.channel_gain)
        d["conversion_gain_uv_per_e"] = self.conversion_gain_uv_per_e
        d["dn_per_electron"] = self.dn_per_electron
        return d
