"""Auto exposure: how a capture meters the scene and chooses its time and
gains (:mod:`.exposure_program` says what each policy does; this module
meters the optical image and runs the policy for :func:`.capture.capture`).

The metering (ISETCam ``autoExposure``, 'luminance'): the time that brings
the brightest pixel's most sensitive channel to :data:`AUTO_EXPOSURE_LEVEL`
of its well at base gain, from the electrons one W/(m^2 nm) of band
irradiance makes in a pixel per second,

    A FF (lambda / h c) dlambda    (:func:`electrons_per_irradiance`),

A the pixel area (m^2), FF the fill factor, lambda / h c photons per joule
and dlambda the band width (nm).
"""

from __future__ import annotations

__all__ = ["auto_exposure", "metered_exposure", "choose_auto_exposure", "resolve_exposure", "program_of",
           "pedestal_for_gain", "electrons_per_irradiance", "DEFAULT_REFERENCE_LUMINANCE_CD_M2",
           "AUTO_EXPOSURE_LEVEL"]

import math
import numbers

import numpy as np

from .. import spectra as _spectra
from ..errors import CfaMitsubaError, require
from ..values import OpticalImage
from .catalogue import get_cfa
from .exposure_program import PEDESTAL_SIGMAS, ExposureChoice, ExposureProgram
from .params import SensorParams
from .physics import with_ir_cut

#: ISETCam's auto exposure (the 'reference' policy) is chosen for the scene
#: scaled to this mean luminance and kept for any other luminance, so that
#: dim scenes really are noisier: the exposure program's default
#: (:class:`~.exposure_program.ExposureProgram`), read from it.
DEFAULT_REFERENCE_LUMINANCE_CD_M2 = ExposureProgram.reference_luminance_cd_m2
#: ISETCam ``autoExposure(oi, sensor, 0.95, 'luminance')``: the brightest
#: pixel reaches 95 % of the well.
AUTO_EXPOSURE_LEVEL = 0.95


def electrons_per_irradiance(wl: np.ndarray, sensor: SensorParams) -> np.ndarray:
    """(B,) electrons per second per unit QE per W/(m^2 nm) of band irradiance:
    A FF (lambda / h c) dlambda."""
    return (sensor.pixel_area_m2 * sensor.fill_factor * _spectra.photons_per_joule(wl)
            * _spectra.band_widths(wl))


def auto_exposure(oi: OpticalImage, spectra_cb: np.ndarray, sensor: SensorParams,
                  reference_luminance_cd_m2: float | None = DEFAULT_REFERENCE_LUMINANCE_CD_M2,
                  luminance_scale: float = 1.0) -> float:
    """Exposure (s) that fills the brightest pixel's well to 95 %.

    ISETCam's rule (``autoExposure.m``, 'luminance'): the scene pixel of
    highest luminance, without OTF or off-axis falloff, taken as a uniform
    field on the axis; the exposure brings its most sensitive channel to
    0.95 x well (dark current left out).  The scene is first scaled to
    ``reference_luminance_cd_m2`` (mean luminance), or by
    ``luminance_scale`` when that is None.

    Parameters
    ----------
    oi : from :func:`cfa_mitsuba.optics.compute_optics`.
    spectra_cb : (C, B) quantum efficiencies of the sensor's channels.
    sensor : the pixel.
    """
    meta = oi.meta
    wl = np.asarray(oi.wavelengths, dtype=np.float64)
    if reference_luminance_cd_m2 is None:
        scale = float(luminance_scale)
    else:
        require(isinstance(reference_luminance_cd_m2, numbers.Real) and not isinstance(reference_luminance_cd_m2, bool)
                and math.isfinite(reference_luminance_cd_m2) and reference_luminance_cd_m2 > 0,
                f"reference luminance must be positive, got {reference_luminance_cd_m2!r}")
        scene = float(meta["scene_luminance_cd_m2"])
        require(scene > 0, "auto exposure needs light: the scene is black (give a fixed exposure)")
        scale = float(reference_luminance_cd_m2) / scene
    irradiance = np.asarray(meta["brightest_radiance"]) * np.asarray(meta["on_axis_factor"]) * scale
    rate = np.asarray(spectra_cb) @ (irradiance * electrons_per_irradiance(wl, sensor))  # e-/s per channel
    peak = float(rate.max())
    require(peak > 0, "auto exposure needs light the sensor sees: the brightest pixel gives no signal")
    return AUTO_EXPOSURE_LEVEL * sensor.well_capacity_e / peak


def resolve_exposure(exposure_s, auto) -> tuple[ExposureChoice, str]:
    """(the choice, 'auto' or 'fixed'): ``auto()`` gives the choice for 'auto'."""
    if isinstance(exposure_s, str):
        if exposure_s.strip().lower() != "auto":
            raise CfaMitsubaError(f"exposure must be a time in seconds or 'auto', got {exposure_s!r}")
        return auto(), "auto"
    ok = isinstance(exposure_s, numbers.Real) and not isinstance(exposure_s, bool)
    ok = ok and math.isfinite(exposure_s) and exposure_s > 0
    require(ok, f"exposure must be a positive number of seconds or 'auto', got {exposure_s!r}")
    return ExposureChoice(float(exposure_s)), "fixed"


#: ``capture``'s reference luminance when the caller gives none: the policy
#: is then the program (a caller that names a reference luminance, or None,
#: keeps the old 'reference' / 'each' rule unless it names a policy).
_UNSET = object()


def program_of(program, policy, reference, max_exposure_s, max_analog_gain) -> ExposureProgram:
    """The capture's :class:`ExposureProgram`: the one given whole, or one
    made once from the loose keywords (not both)."""
    loose = policy is not None or reference is not _UNSET or max_exposure_s is not None or max_analog_gain is not None
    if program is not None:
        require(not loose, "give the exposure program whole (exposure_program=) or as keywords "
                           "(exposure_policy=, max_exposure_s=, ...), not both")
        require(isinstance(program, ExposureProgram),
                f"exposure_program must be an ExposureProgram, got {type(program).__name__}")
        return program
    return ExposureProgram.from_keywords(policy, None if reference is _UNSET else reference,
                                         reference_given=reference is not _UNSET, max_exposure_s=max_exposure_s,
                                         max_analog_gain=max_analog_gain)


def metered_exposure(oi: OpticalImage, pix: np.ndarray, spectra_cb: np.ndarray, sensor: SensorParams,
                     luminance_scale: float) -> float:
    """The time (s) that brings the brightest pixel's most sensitive channel
    to 95 % of the well at base gain, at the captured luminance: the shorter
    of ISETCam's rule (:func:`auto_exposure`, the brightest scene pixel as a
    uniform field on the axis) and the brightest pixel of the optical image
    itself (``pix`` (H, W, B) W/(m^2 nm), after the OTF and the off-axis
    falloff), any channel at any pixel, so that no well fills."""
    wl = np.asarray(oi.wavelengths, dtype=np.float64)
    t_rule = auto_exposure(oi, spectra_cb, sensor, None, luminance_scale)
    w = (np.asarray(spectra_cb) * electrons_per_irradiance(wl, sensor)[None, :]).T * luminance_scale  # (B, C)
    # (C, B) x (B, N) rather than (N, B) x (B, C): the same dot products (to the last bit), 6x faster in
    # OpenBLAS's skinny kernels (measured at 636 x 720 x 31)
    peak = float((w.T @ pix.reshape(-1, pix.shape[-1]).T).max())
    if not (math.isfinite(peak) and peak > 0):
        return t_rule
    return min(t_rule, AUTO_EXPOSURE_LEVEL * sensor.well_capacity_e / peak)


def choose_auto_exposure(oi, pix, qe, sensor, s, program: ExposureProgram) -> ExposureChoice:
    """The exposure the program's policy chooses (module doc of :mod:`.exposure_program`)."""
    policy = program.policy
    require(policy != "fixed", "exposure policy 'fixed' takes an exposure time in seconds, not 'auto'")
    if policy in ("reference", "each"):
        return ExposureChoice(auto_exposure(oi, qe, sensor, None if policy == "each" else
                                            program.reference_luminance_cd_m2, s))
    require(float(oi.meta["scene_luminance_cd_m2"]) > 0,
            "auto exposure needs light: the scene is black (mean luminance 0; give a fixed exposure)")
    if policy == "bayer":  # the same camera with Bayer's filters: its program, for every CFA
        qe = with_ir_cut(get_cfa("bayer"), sensor.ir_cut).sensitivities(np.asarray(oi.wavelengths, dtype=np.float64))
    return program.choose(metered_exposure(oi, pix, qe, sensor, s))


def pedestal_for_gain(sensor: SensorParams) -> SensorParams:
    """The sensor with its black level raised, where needed, to
    :data:`~.exposure_program.PEDESTAL_SIGMAS` dark-noise sigmas (read noise
    and DSNU, in DN at its analogue gain) above code 0, as a designer sets
    the pedestal for the highest gain in use: otherwise the ADC's clip at 0
    cuts the dark tail, biasing the mean up and the noise down (at gain 16
    the default 64 DN is one read-noise sigma).  Solves b = k s g (max - b) /
    well for b (DN per electron = g (max - b) / well)."""
    sigma_e = math.hypot(sensor.read_noise_e, sensor.dsnu_e)
    k = PEDESTAL_SIGMAS * sigma_e * sensor.analog_gain
    need = math.ceil(k * sensor.max_dn / (sensor.well_capacity_e + k))
    return sensor.with_(black_level_dn=float(need)) if need > sensor.black_level_dn else sensor
