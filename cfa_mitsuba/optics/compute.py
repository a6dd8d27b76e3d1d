"""Scene radiance -> sensor-plane irradiance, once per scene.

    E(x, y, lambda) = [pi T(lambda) / (1 + 4 N^2 (1 + |m|)^2)] RI(x, y) L(x, y, lambda)  (*)  PSF_lambda

then averaged over each sensor pixel's photosensitive area.  The result, an
:class:`~cfa_mitsuba.values.OpticalImage`, does not depend on the CFA, the
luminance (a scale factor applied at capture) or the exposure, so one is
computed per scene and reused by every capture (ISETCam's ``oiCompute``,
research/isetcam.md s. 2).
"""

from __future__ import annotations

__all__ = ["compute_optics", "integrate_pixels", "check_oversample", "scene_geometry_inputs"]

import math

import numpy as np

from .. import spectra as _spectra
from ..errors import CfaMitsubaError, require
from ..values import OpticalImage, SpectralImage
from .diffraction import apply_diffraction
from .lens import (DEFAULT_F_NUMBER, DEFAULT_FOV_DEG, DEFAULT_SCENE_DISTANCE_M, OpticsParams, lens_geometry,
                   on_axis_factor, relative_illumination)

#: Default sensor pixel pitch (um): the paper's Nyquist frequency,
#: 227.27 cy/mm (Bae 2020, Fig 6), is 1 / (2 x 2.2 um).
DEFAULT_PIXEL_PITCH_UM = 2.2


def _meta_number(meta: dict, key: str):
    v = meta.get(key)
    if v is None:
        return None
    if isinstance(v, str) and v.strip().lower() in ("inf", "infinity"):
        return math.inf
    try:
        v = float(v)
    except (TypeError, ValueError):
        raise CfaMitsubaError(f"scene sidecar: {key!r} is not a number: {meta.get(key)!r}") from None
    return v


def check_oversample(oversample, height: int, width: int) -> int:
    """Validate K (EXR pixels per sensor pixel along each axis).

    K must be a positive integer dividing both the EXR's height and width:
    a remainder is refused rather than cropped, because cropping would
    silently change the field of view and move the sidecar's geometry.
    """
    if isinstance(oversample, bool) or not isinstance(oversample, (int, np.integer, float)):
        raise CfaMitsubaError(f"oversample must be a positive integer, got {oversample!r}")
    if float(oversample) != int(oversample) or int(oversample) < 1:
        raise CfaMitsubaError(f"oversample must be a positive integer, got {oversample!r}")
    k = int(oversample)
    if height % k or width % k:
        common = [d for d in range(1, min(height, width) + 1) if height % d == 0 and width % d == 0]
        raise CfaMitsubaError(
            f"oversample {k} does not divide the EXR size {width} x {height}; "
            f"use one of {', '.join(map(str, common[:12]))}"
        )
    return k


def scene_geometry_inputs(scene: SpectralImage, params: OpticsParams, oversample=None) -> dict:
    """FOV, distance, f-number and K for a scene: explicit settings win over
    the sidecar, the sidecar over the defaults.  Returns a dict with
    ``fov_deg``, ``scene_distance_m``, ``f_number``, ``oversample`` and where
    each came from (``<key>_source``: option, sidecar or default)."""
    meta = scene.meta or {}
    h, w = scene.data.shape[:2]
    out = {}
    for key, given, default in (
        ("fov_deg", params.fov_deg, DEFAULT_FOV_DEG),
        ("scene_distance_m", params.scene_distance_m, DEFAULT_SCENE_DISTANCE_M),
    ):
        if given is not None:
            out[key], out[key + "_source"] = float(given), "option"
        elif _meta_number(meta, key) is not None:
            out[key], out[key + "_source"] = _meta_number(meta, key), "sidecar"
        else:
            out[key], out[key + "_source"] = default, "default"
    geometry = meta.get("geometry") if isinstance(meta.get("geometry"), dict) else {}
    if params.f_number is not None:
        out["f_number"], out["f_number_source"] = float(params.f_number), "option"
    elif _meta_number(meta, "f_number") is not None:
        out["f_number"], out["f_number_source"] = _meta_number(meta, "f_number"), "sidecar"
    elif _meta_number(geometry, "f_number") is not None:
        out["f_number"], out["f_number_source"] = _meta_number(geometry, "f_number"), "sidecar geometry"
    else:
        out["f_number"], out["f_number_source"] = DEFAULT_F_NUMBER, "default"
    require(out["f_number"] > 0 and math.isfinite(out["f_number"]),
            f"f-number must be positive, got {out['f_number']!r}")
    require(0 < out["fov_deg"] < 180, f"field of view must lie in (0, 180) degrees, got {out['fov_deg']!r}")
    require(out["scene_distance_m"] > 0, f"scene distance must be positive, got {out['scene_distance_m']!r}")
    if oversample is not None:
        out["oversample"], out["oversample_source"] = check_oversample(oversample, h, w), "option"
    elif meta.get("oversample") is not None:
        out["oversample"], out["oversample_source"] = check_oversample(meta["oversample"], h, w), "sidecar"
    else:
        out["oversample"], out["oversample_source"] = 1, "default"
    return out


def _aperture_axis(x: np.ndarray, axis: int, k: int, side: float, workers) -> np.ndarray:
    """Average over a centred aperture of ``side`` pixel pitches along one
    axis, sampled at the pixel centres (module doc of :func:`integrate_pixels`)."""
    import scipy.fft  # here, not at the top: a command that computes no optics does not pay for it

    n = x.shape[axis]
    c = scipy.fft.dct(x, type=2, axis=axis, workers=workers)
    f_px = np.arange(n) * k / (2.0 * n)  # frequency of DCT term i in cycles per sensor pixel
    q = np.sinc(side * f_px) / np.sinc(f_px / k)  # aperture box over the render's box of one sub-sample
    shape = [1] * x.ndim
    shape[axis] = n
    c *= q.reshape(shape)
    if k % 2:  # pixel centres sit on sub-sample centres
        y = scipy.fft.idct(c, type=2, axis=axis, workers=workers)
        return np.take(y, np.arange((k - 1) // 2, n, k), axis=axis)
    # Even K: centres sit on the boundaries between sub-samples; the DCT-II
    # interpolant there is a type-I DCT of the coefficients with a zero
    # appended, divided by 2n.
    pad = [(0, 0)] * x.ndim
    pad[axis] = (0, 1)
    y = scipy.fft.dct(np.pad(c, pad), type=1, axis=axis, workers=workers) / (2.0 * n)
    return np.take(y, np.arange(k // 2, n, k), axis=axis)


def integrate_pixels(irradiance_hwb: np.ndarray, oversample: int, fill_factor: float,
                     workers: int | None = None) -> np.ndarray:
    """Mean irradiance over each pixel's photosensitive area, (H/K, W/K, B).

    The photosensitive area is a centred square of side a = sqrt(FF) x pitch
    (ISETCam ``pixelCreate``: the photodiode is a centred square), so the
    pixel's aperture MTF is sinc(a f) along each axis.

    * FF = 1: the K x K block mean.  Each EXR pixel is a box average of the
      radiance over pitch / K (the render's box filter), so the block mean is
      exactly the average over the whole pixel (transfer sinc(pitch f)); with
      K = 1 the one sample is the pixel's value and is returned as is.
    * FF < 1: the aperture does not fall on sub-sample boundaries, so it is
      applied in the type-II DCT domain (mirror boundaries, as the OTF):
      multiplied by sinc(a f) / sinc(pitch f / K), the aperture over the
      render's box, then the band-limited interpolant is evaluated at the
      pixel centres (on sub-sample centres for odd K, on their boundaries for
      even K).  Exact when the irradiance is band-limited below the EXR's
      Nyquist frequency, which diffraction ensures for K >= 3 at f/4; with
      K = 1 it assumes the render itself is band-limited.  (ISETCam with one
      sample per pixel lets the fill factor scale the signal only.)
    """
    k = int(oversample)
    ff = float(fill_factor)
    h, w, b = irradiance_hwb.shape
    if ff >= 1.0:
        if k == 1:
            return irradiance_hwb
        return irradiance_hwb.reshape(h // k, k, w // k, k, b).mean(axis=(1, 3))
    workers = workers or -1
    side = math.sqrt(ff)
    out = _aperture_axis(irradiance_hwb, 0, k, side, workers)
    out = _aperture_axis(out, 1, k, side, workers)
    # Band-limited interpolation can ring slightly below zero at hard edges.
    return np.ascontiguousarray(np.maximum(out, 0.0))


def _white_radiance(meta: dict, wl: np.ndarray, luminance: np.ndarray) -> tuple[np.ndarray, str]:
    """The radiance of a perfect white diffuser under the scene's light.

    From the sidecar's ``white_radiance`` when present; otherwise the
    sidecar's ``illuminant`` (else D65) scaled to the sidecar's
    ``white_luminance_cd_m2``, else to the scene's brightest pixel: an
    assumption recorded in ``white_source``."""
    b = wl.size
    if meta.get("white_radiance") is not None:
        white = np.asarray(meta["white_radiance"], dtype=np.float64).reshape(-1)
        require(white.size == b, f"scene sidecar: white_radiance has {white.size} values for {b} bands")
        require(bool(np.all(np.isfinite(white)) and np.all(white >= 0) and np.any(white > 0)),
                "scene sidecar: white_radiance must be finite, non-negative and not all zero")
        return white, "sidecar"
    name = str(meta.get("illuminant") or "D65")
    rel = _spectra.illuminant(name, wl)
    rel_lum = float(_spectra.luminance_cd_m2(rel, wl))
    target = _meta_number(meta, "white_luminance_cd_m2")
    if target is not None and target > 0:
        return rel * (target / rel_lum), f"{name} scaled to the sidecar's white luminance"
    peak = float(luminance.max()) if luminance.size else 0.0
    if peak <= 0:
        return rel / rel_lum, f"{name} at 1 cd/m^2 (black scene)"
    return rel * (peak / rel_lum), f"assumed: {name} scaled to the brightest pixel's luminance"


def compute_optics(scene: SpectralImage, params: OpticsParams | None = None, *,
                   pixel_pitch_um: float = DEFAULT_PIXEL_PITCH_UM, oversample=None,
                   fill_factor: float = 1.0, workers: int | None = None) -> OpticalImage:
    """Sensor-plane spectral irradiance of a scene through a thin lens.

    Parameters
    ----------
    scene : radiance, W/(m^2 sr nm), (H, W, B), with its sidecar ``meta``
        (``fov_deg``, ``scene_distance_m``, ``oversample``, ``white_radiance``,
        ... used when present).
    params : lens settings (:class:`OpticsParams`; f/4, T = 1, relative
        illumination and diffraction on, by default).
    pixel_pitch_um : sensor pixel pitch (um); the samples are pitch / K apart.
    oversample : K, EXR pixels per sensor pixel along each axis (default:
        the sidecar's, else 1); must divide the EXR's height and width.
    fill_factor : photosensitive fraction of the pixel area, (0, 1].
    workers : threads for the FFTs (default all cores).

    Returns
    -------
    OpticalImage with ``irradiance_w_m2_nm`` (H, W, B) in W/(m^2 nm),
    ``pixel_irradiance_w_m2_nm`` (H/K, W/K, B) and ``meta`` holding the
    scene's sidecar plus ``optics`` (settings and lens geometry),
    ``oversample``, ``pixel_pitch_um``, ``fill_factor``,
    ``on_axis_factor`` (B,), ``scene_luminance_cd_m2`` (mean luminance of the
    radiance), ``brightest_radiance`` (B,) (the scene pixel of highest
    luminance, for auto exposure), ``white_radiance`` and ``white_source``.

    References
    ----------
    ISETCam ``oiCompute`` -> ``oiCalculateIrradiance``, ``opticsCos4th``,
    ``oiApplyOTF`` (research/isetcam.md s. 2).
    """
    params = params or OpticsParams()
    require(isinstance(scene, SpectralImage), "compute_optics needs a SpectralImage")
    data = np.asarray(scene.data)
    require(data.ndim == 3, f"scene radiance must be (H, W, B), got shape {data.shape}")
    h, w, nb = data.shape
    wl = _spectra.validate_wavelengths(scene.wavelengths)
    require(wl.size == nb, f"scene has {nb} bands but {wl.size} wavelengths")
    require(isinstance(pixel_pitch_um, (int, float)) and math.isfinite(pixel_pitch_um) and pixel_pitch_um > 0,
            f"pixel pitch must be a positive number of um, got {pixel_pitch_um!r}")
    require(isinstance(fill_factor, (int, float)) and 0 < fill_factor <= 1,
            f"fill factor must lie in (0, 1], got {fill_factor!r}")

    # (B, H, W) float64 working copy: bands contiguous for the transforms.
    cube = np.empty((nb, h, w), dtype=np.float64)
    np.copyto(cube, np.moveaxis(data, 2, 0))
    lowest = float(cube.min())  # NaN if any is NaN; one pass instead of elementwise masks
    if not np.isfinite(lowest) or not np.isfinite(float(cube.max())):
        bad = int(cube.size - np.count_nonzero(np.isfinite(cube)))
        raise CfaMitsubaError(f"scene radiance contains {bad} NaN or infinite value(s)")
    if lowest < 0:
        raise CfaMitsubaError(f"scene radiance has negative values (min {lowest:.3g} W/(m^2 sr nm))")

    meta = dict(scene.meta or {})
    geo_in = scene_geometry_inputs(scene, params, oversample)
    k = geo_in["oversample"]
    geom = lens_geometry(w // k, pixel_pitch_um, geo_in["fov_deg"], geo_in["scene_distance_m"], geo_in["f_number"])
    factor = on_axis_factor(geom.f_number, geom.magnification, params.transmittance(nb))

    # Scene statistics before the lens: luminance for scaling, the brightest
    # pixel for auto exposure (ISETCam's oiExtractBright skips OTF and falloff).
    y_weights = _spectra.cmfs_xyz(wl)[:, 1] * _spectra.band_widths(wl) * _spectra.KM_LM_W
    lum = np.tensordot(y_weights, cube, axes=([0], [0]))  # (H, W) cd/m^2
    iy, ix = np.unravel_index(int(np.argmax(lum)), lum.shape)
    brightest = cube[:, iy, ix].copy()
    white, white_source = _white_radiance(meta, wl, lum)

    sample_pitch_um = float(pixel_pitch_um) / k
    if params.relative_illumination:
        cube *= relative_illumination((h, w), sample_pitch_um * 1e-6, geom.image_distance_m,
                                      geom.working_f_number)[None]
    if params.diffraction:
        # the on-axis factor rides on the OTF (the transform is linear)
        cube = apply_diffraction(cube, wl, sample_pitch_um, geom.working_f_number, workers=workers,
                                 band_gain=factor)
        # The OTF truncated at the sampling's Nyquist rings slightly around
        # hard edges; irradiance cannot be negative (ISETCam takes abs()).
        np.maximum(cube, 0.0, out=cube)
    else:
        cube *= factor[:, None, None]
    irradiance = np.ascontiguousarray(np.moveaxis(cube, 0, 2))
    del cube
    pixel = integrate_pixels(irradiance, k, fill_factor, workers=workers)

    meta.update({
        "optics": {**params.to_dict(), **geom.to_dict(), "fov_source": geo_in["fov_deg_source"],
                   "scene_distance_source": geo_in["scene_distance_m_source"],
                   "f_number_source": geo_in["f_number_source"],
                   "boundary": "mirror (DCT-II)"},
        "oversample": k,
        "oversample_source": geo_in["oversample_source"],
        "pixel_pitch_um": float(pixel_pitch_um),
        "fill_factor": float(fill_factor),
        "on_axis_factor": factor.tolist(),
        "scene_luminance_cd_m2": float(lum.mean()),
        "brightest_radiance": brightest.tolist(),
        "brightest_luminance_cd_m2": float(lum[iy, ix]),
        "white_radiance": white.tolist(),
        "white_source": white_source,
    })
    return OpticalImage(irradiance_w_m2_nm=irradiance, wavelengths=np.array(wl), sample_pitch_um=sample_pitch_um,
                        meta=meta, pixel_irradiance_w_m2_nm=pixel)
