"""Sensor-plane irradiance -> raw mosaic (any CFA) or the ideal XYZ image.

Electrons of the pixel at (i, j), whose filter is channel c (ISETCam
``signalCurrent`` / ``spatialIntegration``, research/isetcam.md s. 1.5):

    e = s t A FF sum_b E_b(i, j) QE_cb (lambda_b / (h c)) dlambda_b

with E_b the irradiance averaged over the photosensitive area (W/(m^2 nm),
:func:`cfa_mitsuba.optics.compute_optics`), s the luminance scale (the
requested mean luminance over the scene's), t the exposure (s), A the pixel
area (m^2), FF the fill factor, QE the channel's quantum efficiency and
dlambda the band width (nm).

The ideal sensor (ISETCam ``cameraCompute`` 'idealxyz': same optics and
pixel, no noise, no mosaic) reads CIE 1931 XYZ on an absolute scale:

    X, Y, Z = K_m sum_b [E_b / (pi T_b / (1 + 4 N^2 (1 + |m|)^2))] (xbar, ybar, zbar)_b dlambda_b

i.e. the irradiance referred back to radiance by the on-axis optics factor,
so that Y is in cd/m^2 of the scene: a uniform white field of luminance Lw
reads Y = Lw on the axis (less the relative illumination off it), after the
same OTF and pixel-area integration as the camera.

How 'auto' exposure chooses the time and gains is :mod:`.metering`'s (it
runs the :class:`~.exposure_program.ExposureProgram` it is given).
"""

from __future__ import annotations

__all__ = ["capture", "capture_ideal", "capture_many", "optical_image_for", "IDEAL_NOMINAL_EXPOSURE_S"]

import copy
import math
import numbers

import numpy as np

from .. import spectra as _spectra
from ..errors import CfaMitsubaError, require
from ..optics import OpticsParams, compute_optics, integrate_pixels
from ..values import OpticalImage, RawImage, SpectralImage
from .catalogue import get_cfa
from .cfa import CFA
from .exposure_program import ExposureChoice, ExposureProgram
from .metering import (AUTO_EXPOSURE_LEVEL, DEFAULT_REFERENCE_LUMINANCE_CD_M2, _UNSET, auto_exposure,  # noqa: F401
                       choose_auto_exposure, electrons_per_irradiance, metered_exposure, pedestal_for_gain,
                       program_of, resolve_exposure)
from .noise import collect_electrons, read_out, temporal_rng
from .params import NOISE_MODES, SensorParams
from .photometry import add_photometry as _photometry, band_mean_irradiance, saturation_rel as _saturation_rel
from .physics import apply_crosstalk, channel_map, crosstalk_fractions, with_ir_cut
from .readout import binned_pattern, read_binned, require_block_layout

#: Exposure recorded for the ideal sensor under 'auto': its XYZ scale does
#: not depend on exposure; ISETCam's ideal sensors integrate 1 s
#: (``sensorCreateIdeal``).
IDEAL_NOMINAL_EXPOSURE_S = 1.0


def _mosaic_response(pix: np.ndarray, weights_bc: np.ndarray, cfa: CFA) -> np.ndarray:
    """(H, W) response of each pixel's own channel: pix (H, W, B) @ weights (B, C).

    Each tile position is one strided view times one channel's weights, so
    no pixel is weighted for channels it does not carry (measured 5x faster
    than boolean-mask gathers at 636 x 720 x 31)."""
    h, w, _ = pix.shape
    th, tw = cfa.tile_shape
    lut = {c: i for i, c in enumerate(cfa.channels)}
    if th * tw > 64:  # a large custom tile: one product for all channels, then pick
        idx = cfa.channel_index((h, w))
        full = pix.reshape(h * w, -1) @ weights_bc
        photo = np.take_along_axis(full, idx.reshape(-1, 1), axis=1).reshape(h, w)
    else:
        photo = np.empty((h, w))
        for i in range(th):
            for j in range(tw):
                photo[i::th, j::tw] = pix[i::th, j::tw] @ weights_bc[:, lut[cfa.pattern[i, j]]]
    return np.maximum(photo, 0.0, out=photo)


def optical_image_for(image, sensor: SensorParams, optics: OpticsParams | None = None,
                      oversample=None) -> OpticalImage:
    """The OpticalImage to capture from: computed from a SpectralImage, or an
    OpticalImage checked against the sensor (same pixel pitch)."""
    if isinstance(image, SpectralImage):
        return compute_optics(image, optics, pixel_pitch_um=sensor.pixel_pitch_um, oversample=oversample,
                              fill_factor=sensor.fill_factor)
    if isinstance(image, OpticalImage):
        require(optics is None, "optics settings apply when computing the optical image "
                                "(cm.optics.compute_optics), not to an existing OpticalImage")
        meta = image.meta or {}
        require("pixel_pitch_um" in meta and "oversample" in meta,
                "this OpticalImage was not made by cm.optics.compute_optics (no pixel pitch / oversample)")
        require(oversample is None or int(oversample) == int(meta["oversample"]),
                f"oversample {oversample} differs from the optical image's {meta['oversample']}")
        require(math.isclose(float(meta["pixel_pitch_um"]), sensor.pixel_pitch_um, rel_tol=1e-12),
                f"the optical image was computed for {meta['pixel_pitch_um']} um pixels, "
                f"the sensor has {sensor.pixel_pitch_um} um")
        return image
    raise CfaMitsubaError(f"capture needs a SpectralImage or an OpticalImage, got {type(image).__name__}")


def _pixel_irradiance(oi: OpticalImage, fill_factor: float) -> np.ndarray:
    """(H/K, W/K, B), reusing the optical image's when the fill factor matches."""
    cached = oi.pixel_irradiance_w_m2_nm
    if cached is not None and math.isclose(float(oi.meta.get("fill_factor", -1)), fill_factor, rel_tol=1e-12):
        return cached
    return integrate_pixels(oi.irradiance_w_m2_nm, int(oi.meta["oversample"]), fill_factor)


def _kept(slot: list, oi: OpticalImage, key, make):
    """What ``make()`` gives for the optical image ``oi`` and ``key``, kept
    in the one-entry ``slot`` as (image, key, value) and made again only
    for another image (compared by identity: kept alive in the slot, so its
    id cannot be another image's) or another key (compared by value); the
    old entry is dropped before the new one is made."""
    last = slot[0]
    if last is None or last[0] is not oi or last[1] != key:
        slot[0] = None
        slot[0] = last = (oi, key, make())
    return last[2]


#: The last optical image's mean pixel irradiance per band (:func:`_band_mean`).
_LAST_BAND_MEAN: list = [None]


def _band_mean(oi: OpticalImage, fill_factor: float) -> np.ndarray:
    """The pixel irradiance's mean per band for the photometry of a capture,
    computed once per optical image and fill factor: a study captures many
    CFAs, luminances and noise seeds of one optical image, and this mean
    over the whole (H, W, B) cube was a sixth of a capture's time (16 ms of
    a puppy capture, measured); the same values, reused."""
    return _kept(_LAST_BAND_MEAN, oi, fill_factor,
                 lambda: band_mean_irradiance(_pixel_irradiance(oi, fill_factor)))


def _luminance_scale(oi: OpticalImage, luminance_cd_m2) -> float:
    if luminance_cd_m2 is None:
        return 1.0
    require(isinstance(luminance_cd_m2, numbers.Real) and not isinstance(luminance_cd_m2, bool)
            and math.isfinite(luminance_cd_m2) and luminance_cd_m2 > 0,
            f"luminance must be a positive number of cd/m^2, got {luminance_cd_m2!r}")
    scene = float(oi.meta["scene_luminance_cd_m2"])
    require(scene > 0, "the scene is black (mean luminance 0): it cannot be scaled to a luminance")
    return float(luminance_cd_m2) / scene


def _scaled_meta(oi: OpticalImage, s: float) -> dict:
    meta = copy.deepcopy(oi.meta)
    scene = float(meta["scene_luminance_cd_m2"])
    if "luminance_cd_m2" in meta:
        meta["render_luminance_cd_m2"] = meta["luminance_cd_m2"]
    meta["luminance_cd_m2"] = scene * s
    meta["luminance_scale"] = s
    meta["white_radiance"] = (np.asarray(meta["white_radiance"]) * s).tolist()
    meta["white_luminance_cd_m2"] = float(_spectra.luminance_cd_m2(np.asarray(meta["white_radiance"]),
                                                                   oi.wavelengths))
    meta["brightest_radiance"] = (np.asarray(meta["brightest_radiance"]) * s).tolist()
    meta["brightest_luminance_cd_m2"] = float(meta["brightest_luminance_cd_m2"]) * s
    return meta


def _require_representable(*arrays, exposure: float, scale: float, what: str = "electron count") -> None:
    """Refuse an exposure x luminance product whose signal overflows float64
    (e.g. 1e300 s at 1e300 cd/m^2), instead of passing inf or NaN on."""
    if not all(np.all(np.isfinite(a)) for a in arrays):
        raise CfaMitsubaError(
            f"exposure {exposure:.3g} s at luminance scale {scale:.3g} overflows the {what} "
            "(not a finite number): use a shorter exposure or a lower luminance")


def _check_seed(seed) -> int:
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or int(seed) < 0:
        raise CfaMitsubaError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


#: The noise-free part of the last capture (:func:`_noise_free_signal`), with
#: its optical image and inputs: a study captures several noise seeds of one
#: optical image, CFA and luminance in a row, and the exposure metering and
#: the mosaic's mean response are the same for each (about a quarter of a
#: capture's time, measured).  One entry per process; the optical image is
#: compared by identity, the rest by value.
_LAST_SIGNAL: list = [None]


def _noise_free_signal(oi, cfa, qe, wl, s, exposure_s, sensor, program):
    """What a capture computes before any noise: (exposure choice, exposure
    mode, the sensor at the chosen gain, mean photo-electrons (H, W),
    electrons per radiance (C, B), per-pixel wells and gains or None, (H,
    W)); the arrays read-only."""
    pix = _pixel_irradiance(oi, sensor.fill_factor)
    choice, mode = resolve_exposure(
        exposure_s, lambda: choose_auto_exposure(oi, pix, qe, sensor, s, program))
    exposure = choice.exposure_s
    if choice.analog_gain != 1.0:  # the program's gain on top of the sensor's own, its pedestal raised to match
        sensor = pedestal_for_gain(sensor.with_(analog_gain=sensor.analog_gain * choice.analog_gain))
    h, w, nb = pix.shape
    th, tw = cfa.tile_shape
    require(h >= th and w >= tw, f"the sensor ({w} x {h} pixels) is smaller than the CFA tile ({tw} x {th})")
    factor = np.asarray(oi.meta["on_axis_factor"], dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        k = electrons_per_irradiance(wl, sensor) * (exposure * s)  # (B,)
        weights = (qe * k).T  # (B, C)
        photo = _mosaic_response(pix, weights, cfa)
        if sensor.crosstalk or sensor.crosstalk_700nm:  # before the charge is counted (physics.py)
            k = crosstalk_fractions(sensor, [400.0, 700.0])
            t = (wl - 400.0) / 300.0
            by_wl = _mosaic_response(pix, weights * t[:, None], cfa) if k[1] != k[0] else None
            photo = apply_crosstalk(photo, by_wl, float(k[0]), float(k[1] - k[0]))
        epr = qe * (factor * electrons_per_irradiance(wl, sensor) * exposure)[None, :]
    _require_representable(photo, epr, exposure=exposure, scale=s)

    well = gain = None
    sensor.check_channels(cfa.channels, f"the CFA {cfa.name!r}")
    if sensor.channel_well_e:
        well = channel_map(cfa, photo.shape, {c: sensor.channel_value("channel_well_e", c) for c in cfa.channels})
    if sensor.channel_gain:
        gain = channel_map(cfa, photo.shape, {c: sensor.channel_value("channel_gain", c) for c in cfa.channels})
    for a in (photo, epr, well, gain):
        if isinstance(a, np.ndarray):
            a.flags.writeable = False
    return choice, mode, sensor, photo, epr, well, gain, (h, w)


def capture(image, cfa="bayer", *, luminance_cd_m2: float | None = None, exposure_s="auto",
            noise: str = "all", seed: int = 0, sensor: SensorParams | None = None,
            optics: OpticsParams | None = None, oversample=None, exposure_program: ExposureProgram | None = None,
            reference_luminance_cd_m2=_UNSET, exposure_policy: str | None = None, max_exposure_s: float | None = None,
            max_analog_gain: float | None = None) -> RawImage:
    """Capture a raw mosaic.

    Parameters
    ----------
    image : a SpectralImage (the optics are computed here) or an
        OpticalImage (:func:`cfa_mitsuba.optics.compute_optics`; compute it
        once and capture every CFA from it).
    cfa : a :class:`CFA`, a registry name, a ``.toml`` path, or ``"ideal"``
        (returns :func:`capture_ideal`).
    luminance_cd_m2 : scale the scene to this mean luminance (cd/m^2);
        None keeps its radiance.
    exposure_s : seconds, or ``"auto"``: the time and gains the exposure
        program chooses (:mod:`.exposure_program`).
    noise : ``off``, ``shot`` or ``all`` (:mod:`cfa_mitsuba.sensor.noise`).
    seed : temporal noise seed (non-negative int); the fixed pattern comes
        from ``sensor.sensor_seed``.
    sensor : :class:`SensorParams` (defaults documented there).
    optics, oversample : for a SpectralImage, as in ``compute_optics``.
    exposure_program : the :class:`~.exposure_program.ExposureProgram`
        (policy, limits, reference luminance), passed whole; default
        ``ExposureProgram()``, the program.  Or, for a one-off call, its
        settings as keywords (a value not given keeps the program's default):
    reference_luminance_cd_m2 : for the 'reference' policy, the mean
        luminance at which auto exposure is chosen; None: at the captured
        luminance ('each').  Given without a policy, it selects 'reference'
        (or 'each' for None), the rule before the program.
    exposure_policy : :data:`~.exposure_program.EXPOSURE_POLICIES`.
    max_exposure_s, max_analog_gain : the program's limits.

    Returns
    -------
    RawImage: ``raw`` (H/K, W/K) DN, ``electrons_per_radiance`` (C, B),
    ``white_radiance`` at the captured scale, settings and meta (module doc).
    """
    if isinstance(cfa, str) and cfa == "ideal":
        return capture_ideal(image, luminance_cd_m2=luminance_cd_m2, exposure_s=exposure_s, sensor=sensor,
                             optics=optics, oversample=oversample)
    sensor = sensor or SensorParams()
    if noise not in NOISE_MODES:
        raise CfaMitsubaError(f"unknown noise mode {noise!r} (choose {', '.join(NOISE_MODES)})")
    seed = _check_seed(seed)
    cfa = with_ir_cut(get_cfa(cfa), sensor.ir_cut)
    block = require_block_layout(cfa.pattern, sensor.readout, repr(cfa.name))
    oi = optical_image_for(image, sensor, optics, oversample)
    s = _luminance_scale(oi, luminance_cd_m2)
    wl = np.asarray(oi.wavelengths, dtype=np.float64)
    qe = cfa.sensitivities(wl)  # (C, B)
    program = program_of(exposure_program, exposure_policy, reference_luminance_cd_m2, max_exposure_s,
                          max_analog_gain)
    inputs = (cfa.name, cfa.pattern.shape, cfa.pattern.tobytes(), qe.tobytes(), s, exposure_s, sensor, program,
              repr(oi.meta.get("on_axis_factor")))
    # made again unless this is another noise seed of the last capture
    choice, mode, sensor, photo, epr, well, gain, (h, w) = _kept(
        _LAST_SIGNAL, oi, inputs, lambda: _noise_free_signal(oi, cfa, qe, wl, s, exposure_s, sensor, program))
    epr = epr.copy()  # returned in the RawImage, which its caller may change
    exposure = choice.exposure_s
    th, tw = cfa.tile_shape
    rng = temporal_rng(seed) if noise != "off" else None
    electrons = collect_electrons(photo, exposure_s=exposure, sensor=sensor, noise=noise, rng=rng, well_e=well)
    pattern, dn_per_electron = cfa.pattern.copy(), sensor.dn_per_electron
    if sensor.readout == "bin":
        require(h >= 2 * th and w >= 2 * tw, f"binning needs at least two tiles each way ({2 * tw} x {2 * th} pixels)")
        raw = read_binned(electrons, block, sensor=sensor, noise=noise, rng=rng, gain=gain)
        pattern, dn_per_electron = binned_pattern(cfa.pattern), sensor.dn_per_electron / block**2
        epr = epr * block**2
    else:
        raw = read_out(electrons, sensor=sensor, noise=noise, rng=rng, gain=gain)

    meta = _scaled_meta(oi, s)
    _photometry(meta, _band_mean(oi, sensor.fill_factor), wl, s, exposure)
    # wells that were full before read-out (read noise then spreads their codes)
    full = sensor.well_capacity_e if well is None else well
    meta["saturated_fraction"] = float(np.count_nonzero(electrons >= full)) / electrons.size
    top = raw >= sensor.max_dn if noise == "all" else np.zeros(raw.shape, dtype=bool)  # the ADC's top code
    meta["clipped_fraction"] = (float(np.mean((electrons >= full) | top)) if top.shape == electrons.shape
                                else max(meta["saturated_fraction"], float(np.mean(top))))
    clip_e = min(float(np.min(full)), (sensor.max_dn - (sensor.black_level_dn if noise == "all" else 0.0))
                 / dn_per_electron)
    meta["saturation_rel"] = _saturation_rel(epr, meta["white_radiance"], clip_e)
    meta["readout"] = {"mode": sensor.readout, "block": block, "binning": sensor.binning if sensor.readout == "bin"
                       else None, "native_tile": cfa.tile_text(), "full_shape": [h, w],
                       "pixel_pitch_um": sensor.pixel_pitch_um * (block if sensor.readout == "bin" else 1)}
    recorded = program.record(mode)
    settings = {
        "cfa": {"name": cfa.name, "description": cfa.description, "tile": cfa.tile_text(), "spectra": cfa.spectra},
        "noise": noise,
        "exposure_mode": mode,
        "exposure_s": exposure,
        "exposure_policy": recorded.pop("exposure_policy"),
        "analog_gain": choice.analog_gain,
        "digital_gain": choice.digital_gain,
        "metered_exposure_s": choice.metered_exposure_s,
        **recorded,  # the limits or the reference luminance, where the policy used them
        "auto_exposure_level": AUTO_EXPOSURE_LEVEL if mode == "auto" else None,
        "luminance_cd_m2": meta["luminance_cd_m2"],
        "luminance_scale": s,
        "sensor": sensor.to_dict(),
        "optics": oi.meta["optics"],
        "oversample": int(oi.meta["oversample"]),
    }
    return RawImage(
        raw=raw, pattern=pattern, channels=tuple(cfa.channels), spectra=qe, wavelengths=wl.copy(),
        electrons_per_radiance=epr, white_radiance=np.asarray(meta["white_radiance"]), exposure_s=exposure,
        dn_per_electron=dn_per_electron,
        black_level_dn=float(sensor.black_level_dn) if noise == "all" else 0.0,
        seed=seed, settings=settings, meta=meta,
    )


def capture_ideal(image, *, luminance_cd_m2: float | None = None, exposure_s="auto",
                  sensor: SensorParams | None = None, optics: OpticsParams | None = None,
                  oversample=None) -> RawImage:
    """The ideal XYZ sensor: same optics and pixel, CIE 1931 XYZ at every
    pixel, no noise, no mosaic, no clipping.

    Returns a RawImage whose ``raw`` is (H/K, W/K, 3) XYZ with Y in cd/m^2
    of the scene (module doc), ``pattern`` ``[['XYZ']]``, ``channels``
    ('X', 'Y', 'Z'), ``spectra`` the colour-matching functions (3, B),
    ``electrons_per_radiance`` K_m cmf dlambda (XYZ per unit band radiance,
    so ``raw`` of a uniform field on the axis is ``electrons_per_radiance @
    L``), ``dn_per_electron`` 1 and ``exposure_s`` the given exposure or,
    for 'auto', :data:`IDEAL_NOMINAL_EXPOSURE_S` (the XYZ scale does not
    depend on it).
    """
    sensor = sensor or SensorParams()
    oi = optical_image_for(image, sensor, optics, oversample)
    s = _luminance_scale(oi, luminance_cd_m2)
    choice, mode = resolve_exposure(exposure_s, lambda: ExposureChoice(IDEAL_NOMINAL_EXPOSURE_S))
    exposure = choice.exposure_s
    wl = np.asarray(oi.wavelengths, dtype=np.float64)
    pix = _pixel_irradiance(oi, sensor.fill_factor)
    h, w, nb = pix.shape
    cmfs = _spectra.cmfs_xyz(wl)  # (B, 3)
    per_radiance = cmfs * (_spectra.band_widths(wl) * _spectra.KM_LM_W)[:, None]  # (B, 3)
    factor = np.asarray(oi.meta["on_axis_factor"], dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        xyz = (pix.reshape(-1, nb) @ (per_radiance * (s / factor)[:, None])).reshape(h, w, 3)
    _require_representable(xyz, exposure=exposure, scale=s, what="XYZ image")
    meta = _scaled_meta(oi, s)
    _photometry(meta, _band_mean(oi, sensor.fill_factor), wl, s, exposure)
    settings = {
        "cfa": {"name": "ideal", "description": "CIE 1931 XYZ at every pixel, no noise, no mosaic",
                "tile": "XYZ"},
        "noise": "off",
        "exposure_mode": mode,
        "exposure_s": exposure,
        "luminance_cd_m2": meta["luminance_cd_m2"],
        "luminance_scale": s,
        "xyz_scale": "absolute: Y in cd/m^2 of the scene (irradiance / on-axis optics factor)",
        "sensor": sensor.to_dict(),
        "optics": oi.meta["optics"],
        "oversample": int(oi.meta["oversample"]),
    }
    return RawImage(
        raw=xyz, pattern=np.array([["XYZ"]]), channels=("X", "Y", "Z"), spectra=np.ascontiguousarray(cmfs.T),
        wavelengths=wl.copy(), electrons_per_radiance=np.ascontiguousarray(per_radiance.T),
        white_radiance=np.asarray(meta["white_radiance"]), exposure_s=exposure, dn_per_electron=1.0,
        black_level_dn=0.0, seed=None, settings=settings, meta=meta,
    )


def capture_many(image, cfas, **kwargs) -> dict[str, RawImage]:
    """Capture several CFAs (names, paths, CFA objects, or ``"ideal"``) from
    one scene, computing the optics once.  Keyword arguments as
    :func:`capture`; ``optics`` and ``oversample`` apply to the optics."""
    sensor = kwargs.pop("sensor", None) or SensorParams()
    oi = optical_image_for(image, sensor, kwargs.pop("optics", None), kwargs.pop("oversample", None))
    out = {}
    for c in cfas:
        name = c if isinstance(c, str) and c == "ideal" else get_cfa(c).name
        out[name] = capture(oi, c, sensor=sensor, **kwargs)
    return out
