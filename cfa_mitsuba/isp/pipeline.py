"""The image processor: RawImage -> RenderedImage.

    DN -> electrons (black level, DN per electron) -> white balance
       -> demosaic -> colour matrix -> XYZ (cd/m^2) -> sRGB

Scales and the colour fit: :mod:`cfa_mitsuba.isp.colour_matrix`.  The ideal
sensor's RawImage (``raw`` (H, W, 3), already XYZ on the absolute scale)
passes through unchanged to XYZ and sRGB.
"""

from __future__ import annotations

__all__ = ["process", "prepare", "process_prepared", "PreparedRaw", "PREPARE_KEYWORDS", "WHITE_BALANCE_MODES", "MIN_WHITE_ELECTRONS"]

import functools
import inspect
from dataclasses import dataclass

import numpy as np

from ..errors import CfaMitsubaError
from ..values import RawImage, RenderedImage
from ..colorimetry import realisable
from .colour_matrix import (channel_noise, colour_fit_reflectances, fit_colour_matrix, gray_world_gains, luminance_weights,
                     white_balance_gains, white_response, xyz_to_srgb)
from .demosaic import check_mosaic, check_precision, demosaic as _demosaic, get_demosaic
from .mosaic import geometry
from .denoise import check_denoise_options, denoise_channels, denoise_mosaic
from .noise_profile import NoiseProfile, noise_profile
from .remosaic import channel_gain_divisors, readout_of, remosaic, upsample_blocks
from .sharpen import get_sharpener, sharpen_image

#: ``illuminant``: gains from the sensor's response to the scene's white
#: (known illuminant); ``gray-world``: the image's channel means made equal.
WHITE_BALANCE_MODES = ("illuminant", "gray-world")
#: Fewest electrons a channel must collect from the scene white to be
#: white-balanced.  Far below any physical signal (one photo-electron in
#: 10^30 exposures); it only stops gains of 10^300 (an exposure of 1e-300 s)
#: from overflowing the demosaic and the metrics into NaN.
MIN_WHITE_ELECTRONS = 1e-30


class _DisplayOnDemand(RenderedImage):
    """A :class:`~cfa_mitsuba.values.RenderedImage` whose display ``srgb``
    is encoded from ``xyz`` and ``white_xyz`` on first read (then kept): a
    study reads it for one thumbnail per camera output, not for each noise
    realisation, and the metrics encode their own sRGB (no adaptation), so
    the encoding is mostly never needed.  The same values as encoding at
    once; ``xyz`` is not changed after processing."""

    @property
    def srgb(self):
        value = self.__dict__.get("_srgb")
        if value is None:
            value = self.__dict__["_srgb"] = xyz_to_srgb(self.xyz, self.white_xyz)
        return value

    @srgb.setter
    def srgb(self, value):
        self.__dict__["_srgb"] = value


@dataclass(frozen=True)
class _TileCFA:
    """The CFA a raw file describes (its tile, channel order and spectra)."""

    name: str
    pattern: np.ndarray
    channels: tuple[str, ...]


def _cfa_name(raw: RawImage) -> str:
    info = (raw.settings or {}).get("cfa") or {}
    return str(info.get("name") or "custom") if isinstance(info, dict) else "custom"


def _check(raw: RawImage) -> None:
    if not isinstance(raw, RawImage):
        raise CfaMitsubaError(f"process needs a RawImage, got {type(raw).__name__}")
    c = len(raw.channels)
    wl = np.asarray(raw.wavelengths)
    epr = np.asarray(raw.electrons_per_radiance)
    if epr.shape != (c, wl.size) or np.asarray(raw.white_radiance).shape != (wl.size,):
        raise CfaMitsubaError(
            f"raw image: electrons_per_radiance {epr.shape} / white_radiance "
            f"{np.asarray(raw.white_radiance).shape} do not match {c} channels x {wl.size} bands"
        )
    for name, v in (("dn_per_electron", raw.dn_per_electron), ("black_level_dn", raw.black_level_dn)):
        if not np.isfinite(v) or (name == "dn_per_electron" and v <= 0):
            raise CfaMitsubaError(f"raw image: {name} must be a finite{' positive' if name == 'dn_per_electron' else ''} "
                                  f"number, got {v!r}")


def _saturated_fraction(raw: RawImage) -> float | None:
    bits = ((raw.settings or {}).get("sensor") or {}).get("adc_bits") if isinstance(raw.settings, dict) else None
    if not isinstance(bits, int):
        return None
    return float(np.mean(raw.raw >= 2**bits - 1))


def _sensor_settings(raw: RawImage) -> dict:
    settings = raw.settings if isinstance(raw.settings, dict) else {}
    sensor = settings.get("sensor")
    return sensor if isinstance(sensor, dict) else {}


def _saturation_electrons(raw: RawImage) -> float | None:
    """The most electrons a pixel of this capture can report: the full well
    or the ADC's top code, whichever comes first (None when the capture
    does not record its sensor)."""
    sensor = _sensor_settings(raw)
    bits, well = sensor.get("adc_bits"), sensor.get("well_capacity_e")
    levels = []
    if isinstance(bits, int):
        levels.append((2**bits - 1 - float(raw.black_level_dn)) / float(raw.dn_per_electron))
    if isinstance(well, (int, float)) and well > 0:
        levels.append(float(well))
    return min(levels) if levels else None


def _fit_noise(raw: RawImage, epr: np.ndarray, white: np.ndarray) -> np.ndarray | None:
    """The colour fit's Tikhonov weights: each balanced channel's relative
    noise at an 18 % grey when the scene white fills the most sensitive
    channel's well (the sensor's own design point: its full well and read
    noise), the same for every exposure, gain and luminance of one sensor,
    so that the matrix, and with it the noise gain, cannot change with the
    light; None for a noise-free capture.  A capture that does not record
    its full well is weighted by its own white (the rule before issue 22)."""
    mode = (raw.settings or {}).get("noise") if isinstance(raw.settings, dict) else None
    if mode == "off":
        return None
    sensor = _sensor_settings(raw)
    read = float(sensor.get("read_noise_e") or 0.0) if mode == "all" else 0.0
    white_e = epr @ white
    well = sensor.get("well_capacity_e")
    if isinstance(well, (int, float)) and well > 0 and np.all(white_e > 0):
        white_e = float(well) * white_e / float(white_e.max())
    return channel_noise(white_e, read_noise_e=read)


def _check_white_signal(raw: RawImage, epr: np.ndarray, white: np.ndarray) -> None:
    """Refuse a capture whose channels collect (next to) nothing from the
    scene white: their white-balance gains would be infinite or overflow."""
    with np.errstate(all="ignore"):
        white_e = epr @ white
    if not np.all(np.isfinite(white_e)):
        white_response(epr, white)  # raises, naming the channel
    if np.any(white_e < MIN_WHITE_ELECTRONS):
        c = int(np.argmin(white_e))
        raise CfaMitsubaError(
            f"channel {raw.channels[c]!r} collects {white_e[c]:.3g} electrons from the scene white in this capture "
            f"(exposure {raw.exposure_s:.3g} s): no usable signal to white-balance "
            f"(need at least {MIN_WHITE_ELECTRONS:g}; lengthen the exposure or raise the luminance)")


def process(raw_image: RawImage, demosaic: str = "bilinear", *, white_balance: str = "illuminant",
            white_preserving: bool = True, regularise: bool = True, clip_highlights: bool = True,
            colour_fit: str = "training", demosaic_precision: str = "double", gamut_check: bool = True,
            denoise: str = "none", denoise_options: dict | None = None, sharpen: str = "none",
            sharpen_options: dict | None = None, **options) -> RenderedImage:
    """Process a raw capture into XYZ (absolute, cd/m^2) and display sRGB.

    Parameters
    ----------
    raw_image : :class:`~cfa_mitsuba.values.RawImage` from
        ``cm.sensor.capture`` or ``cm.io.raw_npz.load_raw_npz``.
    demosaic : a registered demosaicing method (``cfa-mitsuba list
        demosaics``).
    white_balance : 'illuminant' (default; gains from the sensor's response
        to ``white_radiance``) or 'gray-world'.
    white_preserving : constrain the colour fit so the scene white maps
        exactly to its XYZ (default True).
    regularise : fit the colour matrix for the sensor's noise (default
        True): Tikhonov weights sigma_c = the relative noise of each balanced
        channel at an 18 % grey, shot noise (and read noise with noise
        'all'), when the scene white fills the most sensitive channel's well
        (:func:`~cfa_mitsuba.isp.colour_matrix.channel_noise`): one matrix per
        sensor and CFA, whatever the light, exposure or gain, so that the
        processing cannot make a capture worse with more light (docs/isp.md);
        a noise-free capture gets the exact fit.  False: always the exact fit.
    clip_highlights : clip every balanced channel at the lowest balanced
        level at which any channel saturates (default True; dcraw's
        highlight mode 0), so a pixel whose wells are full reads the same in
        every channel and maps to a grey, not to the unequal clipped
        channels' colour (a negative XYZ through cmy2's matrix).
    colour_fit : the reflectances the colour matrix is fitted on:
        'training' (default, the 190 training patches) or 'mcc' (the 24
        ColorChecker patches, ISETCam's 'MCC optimized';
        :data:`~cfa_mitsuba.isp.colour_matrix.COLOUR_FITS`).
    demosaic_precision : 'double' (default) or 'single': the demosaicing
        method computes in float32 (:func:`~cfa_mitsuba.isp.demosaic`'s
        ``precision``; a study's default, docs/study.md); the colour
        correction and the output stay float64.
    gamut_check : measure ``meta['isp']['out_of_gamut_fraction']`` (default);
        False leaves it None, for a caller that does not read it (a study's
        chain: the test over every output pixel took about 5 ms of a 636 x
        720 image on average, and 13 ms of a 25 ms 'bilinear' processing of
        the puppy at 3 cd/m^2, where noise puts many pixels past sRGB's
        triangle and each goes to the spectral-locus test).
    denoise : a registered denoiser (``cfa-mitsuba list denoise``; default
        'none'), run in the raw domain before demosaicing or the rgb domain
        after it (``denoise_options={'domain': ...}``), its strength the
        capture's predicted noise times the method's tuning constant
        (:mod:`cfa_mitsuba.isp.denoise`).
    denoise_options : the denoiser's options: ``domain`` ('raw' or 'rgb'),
        ``scale`` (times its tuning constant, default 1) and its own.
    sharpen : a registered sharpener (default 'none'; 'unsharp'), applied
        to the XYZ image after the colour matrix
        (:mod:`cfa_mitsuba.isp.sharpen`).
    sharpen_options : its options (``radius``, ``amount`` for 'unsharp').
    **options : passed to the demosaicing method (e.g. ``iterations=``).
        Methods that take ``luminance_weights`` receive the channels'
        luminance weights under this illuminant unless given.

    Returns
    -------
    :class:`~cfa_mitsuba.values.RenderedImage`: ``xyz`` (H, W, 3) in
    cd/m^2 on the ideal sensor's scale, ``srgb`` (H, W, 3) 0..1 with the
    white mapped to 1, ``white_xyz``, and ``meta`` = the scene's meta plus
    ``isp`` (CFA, method, options, white-balance gains, colour matrix,
    condition number, noise gain) and ``capture`` (the sensor settings).

    Saturated pixels are clipped consistently (``clip_highlights``);
    ``meta['isp']['saturated_fraction']`` reports how many there were,
    ``highlight_clipped_fraction`` how many balanced values the clip
    lowered, ``colour_fit_noise`` the Tikhonov weights (None: exact fit) and
    ``out_of_gamut_fraction`` the output pixels whose XYZ no light has
    (:func:`~cfa_mitsuba.colorimetry.realisable`: negative, or past the
    spectral locus; kept, not clipped, and flagged; None without
    ``gamut_check``).  Negative values after black-level
    subtraction (read noise) are kept, not clipped, so noise stays unbiased
    until the final sRGB encoding clips to 0..1.

    Examples
    --------
    See ``tests/isp/test_pipeline.py``; from a file::

        import cfa_mitsuba as cm
        from cfa_mitsuba.io.raw_npz import load_raw_npz
        img = cm.isp.process(load_raw_npz("raw.npz"), "pocs")
    """
    _check(raw_image)
    check_precision(demosaic_precision)
    _check_gamut_flag(gamut_check)
    _check_white_balance(white_balance)
    if raw_image.is_ideal:
        return _pass_ideal(raw_image)
    prepared = prepare(raw_image, white_balance=white_balance, white_preserving=white_preserving,
                       regularise=regularise, clip_highlights=clip_highlights, colour_fit=colour_fit)
    return process_prepared(prepared, demosaic, demosaic_precision=demosaic_precision, gamut_check=gamut_check,
                            denoise=denoise, denoise_options=denoise_options, sharpen=sharpen,
                            sharpen_options=sharpen_options, **options)


def _check_white_balance(white_balance) -> None:
    if white_balance not in WHITE_BALANCE_MODES:
        raise CfaMitsubaError(f"unknown white balance {white_balance!r} (choose {', '.join(WHITE_BALANCE_MODES)})")


def _check_gamut_flag(gamut_check) -> None:
    if not isinstance(gamut_check, (bool, np.bool_)):
        raise CfaMitsubaError(f"gamut_check must be True or False, got {gamut_check!r}")


def _pass_ideal(raw_image: RawImage) -> RenderedImage:
    """The ideal sensor's XYZ, passed through (checked)."""
    wl = np.asarray(raw_image.wavelengths, dtype=np.float64)
    white = np.asarray(raw_image.white_radiance, dtype=np.float64)
    meta = dict(raw_image.meta or {})
    meta.setdefault("capture", raw_image.settings)
    xyz = np.asarray(raw_image.raw, dtype=np.float64)
    if xyz.shape[2] != 3:
        raise CfaMitsubaError(f"the ideal sensor's image must be (H, W, 3) XYZ, got {xyz.shape}")
    if not np.all(np.isfinite(xyz)):
        raise CfaMitsubaError("the ideal sensor's XYZ image contains NaN or infinite values")
    from .. import spectra

    white_xyz = spectra.xyz_from_radiance(white, wl)
    meta["isp"] = {"cfa": "ideal", "demosaic": None, "note": "ideal XYZ sensor: passed through"}
    return RenderedImage(xyz=xyz.copy(), srgb=xyz_to_srgb(xyz, white_xyz), white_xyz=white_xyz, meta=meta)


@dataclass(frozen=True, eq=False)
class PreparedRaw:
    """A camera capture made ready for demosaicing by :func:`prepare`: what
    :func:`process` computes before the demosaic, the same for every
    demosaicing method.  ``balanced`` (the white-balanced, highlight-clipped
    mosaic, electrons times gain) is read-only; ``settings`` holds the
    keywords it was prepared with."""

    raw_image: RawImage
    cfa: _TileCFA
    balanced: np.ndarray
    gains: np.ndarray
    fit: object
    fit_noise: np.ndarray | None
    clip_level: float | None
    clipped: float
    readout: dict
    saturated_fraction: float | None
    settings: dict

    @functools.cached_property
    def luminance_weights(self) -> np.ndarray:
        """The channels' luminance weights under the scene white (for the
        methods that take ``luminance_weights``), computed on first use."""
        r = self.raw_image
        w = luminance_weights(np.asarray(r.electrons_per_radiance, dtype=np.float64),
                              np.asarray(r.white_radiance, dtype=np.float64),
                              np.asarray(r.wavelengths, dtype=np.float64))
        w.flags.writeable = False
        return w


def prepare(raw_image: RawImage, *, white_balance: str = "illuminant", white_preserving: bool = True,
            regularise: bool = True, clip_highlights: bool = True, colour_fit: str = "training") -> PreparedRaw:
    """The part of :func:`process` that does not depend on the demosaicing
    method, done once: the checks, DN -> electrons, the white balance, the
    highlight clip, the read-out's re-mosaic and the colour fit (keywords as
    for :func:`process`).  ``process(prepare(raw, **kw), method)`` is
    ``process(raw, method, **kw)`` bit for bit; a study prepares each
    capture once for its four methods (about 5 ms of a 636 x 720 capture's
    processing, spent once instead of four times).  The capture must not be
    changed while its preparation is in use.  Not for the ideal sensor's
    image (it needs no processing)."""
    _check(raw_image)
    if raw_image.is_ideal:
        raise CfaMitsubaError("prepare: the ideal sensor's image is XYZ already; process() passes it through")
    _check_white_balance(white_balance)
    wl = np.asarray(raw_image.wavelengths, dtype=np.float64)
    epr = np.asarray(raw_image.electrons_per_radiance, dtype=np.float64)
    white = np.asarray(raw_image.white_radiance, dtype=np.float64)
    _check_white_signal(raw_image, epr, white)
    refl = colour_fit_reflectances(colour_fit, wl)
    fit_noise = _fit_noise(raw_image, epr, white) if regularise else None
    fit = fit_colour_matrix(epr, white, wl, white_preserving=white_preserving, channel_noise=fit_noise,
                            reflectances=refl)

    cfa = _TileCFA(_cfa_name(raw_image), np.asarray(raw_image.pattern, dtype=str), tuple(raw_image.channels))
    mosaic = geometry(cfa)
    dn = check_mosaic(raw_image.raw, cfa)
    electrons = (dn - float(raw_image.black_level_dn)) / float(raw_image.dn_per_electron)
    per_channel = channel_gain_divisors(raw_image, cfa.channels)
    if per_channel is not None:  # each channel's own DN per electron
        electrons = electrons / per_channel[mosaic.index][np.arange(dn.shape[0])[:, None] % mosaic.tile_shape[0],
                                                          np.arange(dn.shape[1])[None, :] % mosaic.tile_shape[1]]
    if white_balance == "illuminant":
        gains = white_balance_gains(epr, white)
    else:
        gains = gray_world_gains(electrons, mosaic.masks(dn.shape), epr, white)
    th, tw = mosaic.tile_shape
    balanced = np.empty_like(electrons)
    for (i, j), c in np.ndenumerate(mosaic.index):
        balanced[i::th, j::tw] = electrons[i::th, j::tw] * gains[c]
    sat_e = _saturation_electrons(raw_image) if clip_highlights else None
    clip_level, clipped = None, 0.0
    if sat_e is not None:
        clip_level = sat_e * float(gains.min())  # where the channel of least headroom saturates, balanced
        over = balanced > clip_level
        clipped = float(np.mean(over))
        balanced = np.where(over, clip_level, balanced)

    readout = readout_of(raw_image)
    if readout.get("mode") == "remosaic":
        balanced, cfa = remosaic(balanced, cfa)
    balanced.flags.writeable = False
    settings = {"white_balance": white_balance, "white_preserving": white_preserving, "regularise": regularise,
                "clip_highlights": clip_highlights, "colour_fit": colour_fit}
    return PreparedRaw(raw_image, cfa, balanced, gains, fit, fit_noise, clip_level, clipped, readout,
                       _saturated_fraction(raw_image), settings)


def _profile(prepared: PreparedRaw) -> NoiseProfile:
    """The noise profile of the prepared mosaic's channels (:mod:`.noise_profile`):
    each channel's white-balance gain and analogue gain looked up by name, so
    that a re-mosaicked capture's channels get their own."""
    raw = prepared.raw_image
    native = tuple(raw.channels)
    gains = dict(zip(native, np.asarray(prepared.gains, dtype=np.float64)))
    divisors = channel_gain_divisors(raw, native)
    div = dict(zip(native, divisors)) if divisors is not None else {}
    chans = prepared.cfa.channels
    return noise_profile(raw, [gains[c] for c in chans], chans, [div.get(c, 1.0) for c in chans] if div else None)


#: the keywords of :func:`process` that :func:`prepare` takes (the rest go to the demosaic)
PREPARE_KEYWORDS = tuple(p for p in inspect.signature(prepare).parameters if p != "raw_image")


def process_prepared(prepared: PreparedRaw, demosaic: str = "bilinear", *, demosaic_precision: str = "double",
                     gamut_check: bool = True, denoise: str = "none", denoise_options: dict | None = None,
                     sharpen: str = "none", sharpen_options: dict | None = None, **options) -> RenderedImage:
    """:func:`process` from the demosaic on, for a capture made ready by
    :func:`prepare` (the same keywords and result as :func:`process`; the
    white balance, highlight clip and colour fit are the preparation's)."""
    if not isinstance(prepared, PreparedRaw):
        raise CfaMitsubaError(f"process_prepared needs a PreparedRaw (from prepare()), got {type(prepared).__name__}")
    check_precision(demosaic_precision)
    _check_gamut_flag(gamut_check)
    raw_image, cfa, fit, gains = prepared.raw_image, prepared.cfa, prepared.fit, prepared.gains
    meta = dict(raw_image.meta or {})
    meta.setdefault("capture", raw_image.settings)
    fn = get_demosaic(demosaic)
    if "luminance_weights" in inspect.signature(fn).parameters and "luminance_weights" not in options:
        options["luminance_weights"] = prepared.luminance_weights
    domain = check_denoise_options(denoise, denoise_options)[1]
    get_sharpener(sharpen)
    balanced, noise_record = prepared.balanced, None
    if domain == "raw" and denoise != "none":
        balanced, noise_record = denoise_mosaic(balanced, geometry(cfa).index, _profile(prepared), denoise,
                                                denoise_options)
    channels = _demosaic(balanced, cfa, demosaic, precision=demosaic_precision, **options)
    if domain == "rgb" and denoise != "none":
        channels, noise_record = denoise_channels(channels, _profile(prepared), denoise, denoise_options)
    xyz = fit.apply(channels)
    xyz, sharpen_record = sharpen_image(xyz, sharpen, sharpen_options)
    readout = prepared.readout
    if readout.get("mode") == "bin":  # back on the full pixel grid (isp/remosaic.py)
        xyz = upsample_blocks(xyz, int(readout["block"]), readout["full_shape"])
    out_of_gamut = float(np.mean(~realisable(xyz))) if gamut_check else None

    ref_gain = gains.min()  # reported relative to the most sensitive channel, as cameras do
    meta["isp"] = {
        "cfa": cfa.name,
        "tile": " / ".join(" ".join(r) for r in cfa.pattern.tolist()),
        "channels": list(cfa.channels),
        "demosaic": demosaic,
        "demosaic_options": {k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v)
                             for k, v in options.items() if k != "info"},
        "demosaic_precision": demosaic_precision,
        "white_balance": prepared.settings["white_balance"],
        "colour_fit": prepared.settings["colour_fit"],
        "white_balance_gains": (gains / ref_gain).tolist(),
        "white_balance_gains_per_electron": gains.tolist(),
        "white_xyz": fit.white_xyz.tolist(),
        "saturated_fraction": prepared.saturated_fraction,
        "readout": readout.get("mode", "full"),
        "highlight_clip_balanced": prepared.clip_level,
        "highlight_clipped_fraction": prepared.clipped,
        "colour_fit_noise": None if prepared.fit_noise is None else prepared.fit_noise.tolist(),
        "out_of_gamut_fraction": out_of_gamut,
        "denoise": noise_record or {"method": "none"},
        "sharpen": sharpen_record,
        **fit.as_meta(),
    }
    return _DisplayOnDemand(xyz=xyz, srgb=None, white_xyz=fit.white_xyz.copy(), meta=meta)
