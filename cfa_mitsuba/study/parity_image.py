"""Image parity cases (:mod:`.parity`): a scene through optics, sensor and
image processing to one metric's headline value, in one of two modes.

``mode = "default"`` runs this project's study chain
(:class:`~.chain.CameraChain`): the built-in scene as rendered, the
project's optics, box pixel aperture (the photodiode, sqrt(FF) x pitch),
processing and metric conventions.

``mode = "isetcam"`` rebuilds ISETCam's chain from our stages, with
ISETCam's mechanisms where they differ (docs/isetcam-parity.md):

1. scene: ISETCam's own target (``sceneCreate('slanted bar', size,
   slope)``: point-sampled, reflectance 1 where row > slope x column about
   the centre, else 1e-6, equal-energy light), its field of view and
   distance from the case's ``[isetcam]`` table;
2. optics: our diffraction and relative illumination on that scene, zero
   padded by 1/8 of its size each side (``oiCompute``), sampled as ISETCam
   samples it: the focal length is the optics preset's, so the sample
   spacing follows from the scene's field of view
   (:func:`~cfa_mitsuba.optics.isetcam.isetcam_oi_spacing_um`);
3. sensor: ISETCam's read-out of the optical image at the pixel centres
   (Gaussian prefilter + bilinear, :func:`~cfa_mitsuba.optics.isetcam.regrid_isetcam`),
   then our capture (exposure, noise, ADC) with the case's sensor;
4. image: the monochrome volts, or the bilinear demosaic of the mosaic
   without white balance or colour correction (ISETCam's 'sensor space');
5. metric: ISETCam's ISO 12233 conventions (``mtf(convention='isetcam')``)
   on ISETCam's region (``roi_rect_um`` or ``roi_rect_px``, ISETCam's
   ``[x y width height]`` rectangle, 1-based, inclusive), with its
   luminance weights (``luminance_weights``: 0.3, 0.6, 0.1 until ISETCam's
   sfrmat4 update, whose ISO12233 defaults to Rec. 709's 0.213, 0.715,
   0.072 when given none).
"""

from __future__ import annotations

__all__ = ["run_image_case", "sensor_for_case", "optics_for_case", "isetcam_slanted_bar", "isetcam_optical_image"]

import functools
import math
from dataclasses import replace

import numpy as np

from ..errors import CfaMitsubaError

#: v_icam_pixelMTF's scene and sensor (ISET/isetvalidate isetcam/pixel/v_icam_pixelMTF.m),
#: used for the [isetcam] keys a case does not give.
ISETCAM_DEFAULTS = {
    "scene_size_px": 512, "edge_slope": 7.0 / 3.0, "scene_fov_deg": 5.0, "scene_distance_m": 1.0,
    "sensor_size_um": 512.0, "sensor_fov_deg": None, "roi_rect_um": None, "roi_rect_px": None,
    "luminance_weights": [0.3, 0.6, 0.1],
}
#: ISETCam's default sensor size, sensorFormats('qqcif') (rows, cols).
ISETCAM_QQCIF = (72, 88)


def _mround(x: float) -> int:
    """MATLAB's round (halves away from zero)."""
    return int(math.copysign(math.floor(abs(x) + 0.5), x))


def sensor_for_case(case):
    """(SensorParams, CFA name, spectra set or None) from the case's
    ``[sensor]`` table: ``preset`` (``cfa-mitsuba list sensors``), ``cfa``,
    any SensorParams field, and ``isetcam`` (ISETCam's voltage-domain
    values, converted as the presets' are)."""
    from ..sensor import SensorParams, get_sensor_preset
    from ..sensor.presets import _from_isetcam

    table = dict(case.sensor)
    where = f"{case.path}: sensor"
    preset = get_sensor_preset(table.pop("preset")) if "preset" in table else None
    params = preset.params if preset else SensorParams()
    cfa = table.pop("cfa", preset.cfa_name if preset else "bayer")
    spectra = preset.spectra if preset else None
    if "isetcam" in table:
        given = dict(table.pop("isetcam"))
        given.setdefault("conversion_gain_uv_per_e", params.conversion_gain_uv_per_e)
        given.setdefault("voltage_swing_v", params.voltage_swing_v)
        table = {**_from_isetcam(given, where), **table}
    try:
        return params.with_(**table), cfa, spectra
    except (TypeError, CfaMitsubaError) as exc:
        raise CfaMitsubaError(f"{where}: {exc}") from None


def optics_for_case(case):
    """(OpticsParams, focal length in mm) from the case's ``[optics]`` table:
    ``preset`` (default ``isetcam-default``) and any OpticsParams field."""
    from ..optics import get_optics_preset

    table = dict(case.optics)
    preset = get_optics_preset(table.pop("preset", "isetcam-default"))
    try:
        return replace(preset.params, **table), preset.focal_length_mm
    except (TypeError, CfaMitsubaError) as exc:
        raise CfaMitsubaError(f"{case.path}: optics: {exc}") from None


def _isetcam_table(case) -> dict:
    table = dict(case.settings.get("isetcam", {}))
    unknown = sorted(set(table) - set(ISETCAM_DEFAULTS))
    if unknown:
        raise CfaMitsubaError(f"{case.path}: isetcam.{unknown[0]}: unknown key (known: {', '.join(ISETCAM_DEFAULTS)})")
    return {**ISETCAM_DEFAULTS, **table}


def isetcam_slanted_bar(size_px: int, slope: float) -> np.ndarray:
    """ISETCam's slanted bar reflectance (``sceneCreate('slanted bar')``):
    (2 round(size/2) + 1) square, 1 where row > slope x column (both
    centred), else 1e-6, point-sampled."""
    half = _mround(size_px / 2.0)
    y, x = np.mgrid[-half:half + 1, -half:half + 1].astype(np.float64)
    return np.where(y > slope * x, 1.0, 1e-6)


def isetcam_optical_image(refl: np.ndarray, geo: dict, optics, focal_mm: float):
    """The optical image of an achromatic equal-energy target, padded and
    sampled as ISETCam's ``oiCompute``; returns (OpticalImage, spacing um)."""
    from .. import spectra
    from ..optics import compute_optics
    from ..optics.isetcam import isetcam_oi_spacing_um, isetcam_pad_px
    from ..values import SpectralImage

    wl = np.array(spectra.DEFAULT_WAVELENGTHS, dtype=np.float64)
    n = refl.shape[1]
    spacing = isetcam_oi_spacing_um(n, geo["scene_fov_deg"], geo["scene_distance_m"], focal_mm)
    pad = isetcam_pad_px(n)
    padded = np.pad(refl, pad)
    fov = 2.0 * math.degrees(math.atan(math.tan(math.radians(geo["scene_fov_deg"]) / 2.0) * padded.shape[1] / n))
    white = np.ones(wl.size)  # equal energy, W/(m^2 sr nm) at reflectance 1
    scene = SpectralImage(padded[:, :, None] * white[None, None, :], wl,
                          {"white_radiance": white.tolist(), "oversample": 1})
    params = replace(optics, fov_deg=fov, scene_distance_m=geo["scene_distance_m"])
    oi = compute_optics(scene, params, pixel_pitch_um=spacing, oversample=1, fill_factor=1.0)
    lum_white = float(spectra.luminance_cd_m2(white, wl))
    oi.meta["scene_luminance_cd_m2"] = float(refl.mean()) * lum_white  # ISETCam scales before padding
    return oi, spacing


@functools.lru_cache(maxsize=2)
def _slanted_bar_oi(size_px: int, slope: float, fov_deg: float, distance_m: float, optics, focal_mm: float):
    """ISETCam's slanted bar through the optics, kept for the next case with
    the same scene and lens (the optical image does not depend on the pixel;
    callers do not modify it)."""
    geo = {"scene_fov_deg": fov_deg, "scene_distance_m": distance_m}
    return isetcam_optical_image(isetcam_slanted_bar(size_px, slope), geo, optics, focal_mm)


def _sensor_size(geo: dict, pitch_um: float, focal_mm: float, tile) -> tuple[int, int]:
    """ISETCam's sensor size: a square die of ``sensor_size_um`` (v_icam_pixelMTF),
    or ``sensorSetSizeToFOV`` from the qqcif format to ``sensor_fov_deg``."""
    if geo["sensor_fov_deg"] is not None:
        width_um = 2.0 * focal_mm * 1e3 * math.tan(math.radians(geo["sensor_fov_deg"]) / 2.0)
        ratio = width_um / (ISETCAM_QQCIF[1] * pitch_um)
        th, tw = tile
        return (math.ceil(_mround(ISETCAM_QQCIF[0] * ratio) / th) * th,
                math.ceil(_mround(ISETCAM_QQCIF[1] * ratio) / tw) * tw)
    n = _mround(geo["sensor_size_um"] / pitch_um)
    return n, n


def _roi(geo: dict, pitch_um: float, shape):
    """ISETCam's [x y w h] rectangle (1-based, inclusive) as (y0, x0, y1, x1)."""
    if geo["roi_rect_px"] is not None:
        x, y, w, h = (int(v) for v in geo["roi_rect_px"])
    elif geo["roi_rect_um"] is not None:
        x, y, w, h = (_mround(v / pitch_um) for v in geo["roi_rect_um"])
    else:
        return None
    roi = (y - 1, x - 1, y + h, x + w)
    if not (0 <= roi[0] < roi[2] <= shape[0] and 0 <= roi[1] < roi[3] <= shape[1]):
        raise CfaMitsubaError(f"ISETCam rectangle {[x, y, w, h]} lies outside the {shape[0]} x {shape[1]} sensor")
    return roi


def _run_isetcam(case, sensor, cfa_name, spectra_name):
    from .. import isp, metrics
    from ..optics.isetcam import regrid_isetcam
    from ..sensor import capture, get_cfa
    from ..values import OpticalImage

    geo = _isetcam_table(case)
    optics, focal_mm = optics_for_case(case)
    if case.settings["scene"] != "slanted-edge":
        raise CfaMitsubaError(f"{case.path}: mode 'isetcam' has ISETCam's slanted bar only (scene 'slanted-edge')")
    oi, spacing = _slanted_bar_oi(int(geo["scene_size_px"]), float(geo["edge_slope"]), float(geo["scene_fov_deg"]),
                                  float(geo["scene_distance_m"]), optics, focal_mm)
    cfa = get_cfa(cfa_name, spectra=spectra_name) if spectra_name else get_cfa(cfa_name)
    p = sensor.pixel_pitch_um
    rows, cols = _sensor_size(geo, p, focal_mm, cfa.tile_shape)
    pix = regrid_isetcam(oi.irradiance_w_m2_nm, spacing, p, rows, cols)
    meta = {**oi.meta, "pixel_pitch_um": p, "oversample": 1, "fill_factor": sensor.fill_factor}
    sampled = OpticalImage(pix, oi.wavelengths, p, meta, pixel_irradiance_w_m2_nm=pix)
    raw = capture(sampled, cfa, luminance_cd_m2=case.settings["luminance"], noise=case.settings.get("noise", "off"),
                  seed=int(case.settings.get("seed", 0)), sensor=sensor)
    mosaic = np.asarray(raw.raw, dtype=np.float64)
    if len(cfa.channels) == 1:
        image = mosaic
    else:
        image = isp.demosaic(mosaic, cfa, case.settings.get("demosaic", "bilinear"))
        order = [cfa.channels.index(c) for c in ("R", "G", "B")]
        image = image[..., order]
    roi = _roi(geo, p, image.shape)
    weights = tuple(float(w) for w in geo["luminance_weights"])
    result = metrics.mtf(image, roi=roi, pixel_pitch_um=p, convention="isetcam", weights=weights)
    details = {"oi_sample_spacing_um": spacing, "oi_shape": list(oi.irradiance_w_m2_nm.shape[:2]),
               "sensor_shape": [rows, cols], "regrid_kernel_samples": math.ceil(p / spacing - 1e-9),
               "roi": list(result.details["roi"]), "edge_angle_deg": result.details["edge_angle_deg"],
               "nyquist_cy_mm": result.details["nyquist_cy_mm"],
               "mtf50_sfrmat3_cy_mm": float(metrics.mtf(image, roi=roi, pixel_pitch_um=p, weights=weights)),
               "luminance_weights": list(weights)}
    return float(result), result.unit, details


#: ISETCam's image processing for colour (ipCreate: 'MCC optimized' sensor -> XYZ
#: by plain least squares on its own ColorChecker table, no illuminant
#: correction; configs/paper-isetcam.toml) and its colour error
#: (macbethColorError: the camera scaled to the ideal white patch, which is
#: CIELAB's white).
ISETCAM_ISP = {"white_balance": "illuminant", "white_preserving": False, "colour_fit": "mcc-isetcam",
               "regularise": False}
ISETCAM_DELTA_E = {"white": "white-patch"}


def isetcam_chart(scene):
    """Our rendered ``macbeth`` chart with ISETCam's ColorChecker table
    (``data/reflectances/isetcam_macbethChart.csv``) in place of
    colour-science's: each patch (a uniform rectangle of the flat chart)
    re-emits the band means of D65 x ISETCam's reflectance, on the render's
    white scale."""
    from .. import spectra
    from ..isp.colour_matrix import ISETCAM_MACBETH_CSV
    from ..values import SpectralImage

    wl = np.asarray(scene.wavelengths, dtype=np.float64)
    table = np.loadtxt(ISETCAM_MACBETH_CSV, delimiter=",", skiprows=1)
    scale = np.asarray(scene.meta["white_radiance"], dtype=np.float64) / spectra.illuminant("D65", wl)
    d65 = spectra.illuminant_table("D65")
    data = np.array(scene.data, dtype=np.float64)
    patches = scene.meta["geometry"]["patches"]
    for p in patches:
        y0, x0, y1, x1 = p["rect"]
        data[y0:y1, x0:x1] = scale * spectra.band_average_product([d65, (table[:, 0], table[:, 1 + p["index"]])], wl)
    meta = {**scene.meta, "geometry": {**scene.meta["geometry"], "reflectance_set": "ISETCam macbethChart.mat"}}
    return SpectralImage(data, wl, meta)


def _run_default(case, sensor, cfa_name, spectra_name, isp=None, metric_options=None, isetcam_chart_data=False):
    from .. import render
    from ..sensor import get_cfa
    from .chain import CameraChain, ChainSettings

    metric = case.settings["metric"]
    optics, _ = optics_for_case(case)
    own = get_cfa(cfa_name).spectra
    isp = {**(isp or {}), **dict(case.settings.get("isp", {}))}
    options = {**(metric_options or {}), **dict(case.settings.get("metric_options", {}))}
    settings = ChainSettings(optics=optics, sensor=sensor, noise=case.settings.get("noise", "off"),
                             spectra_sets={own: spectra_name} if spectra_name and spectra_name != own else {},
                             isp=isp, metric_options={metric: options})
    scene = render.render_cached(case.settings["scene"], **dict(case.settings.get("render", {})))
    if isetcam_chart_data:
        if case.settings["scene"] != "macbeth":
            raise CfaMitsubaError(f"{case.path}: a colour case in mode 'isetcam' needs scene 'macbeth'")
        scene = isetcam_chart(scene)
    cond = settings.base_condition(luminance=case.settings["luminance"])
    chain = CameraChain(settings)
    out = next(iter(chain.evaluate(scene, cfa_name, [case.settings.get("demosaic", "bilinear")], [metric], cond,
                                   int(case.settings.get("seed", 0)))))
    _, _, _, ev = out
    if isinstance(ev, Exception):
        raise ev
    if metric not in ev.results:
        raise CfaMitsubaError(f"{case.path}: {metric} failed: {ev.failures}")
    result = ev.results[metric]
    details = {"scene_shape": list(scene.data.shape[:2]), "oversample": scene.meta.get("oversample"), "isp": isp,
               "metric_options": options}
    if metric == "mtf":
        details.update(edge_angle_deg=result.details["edge_angle_deg"], roi=list(result.details["roi"]))
    return float(result), result.unit, details


def run_image_case(case):
    """(value, unit, details) of an image or colour case (module doc)."""
    sensor, cfa_name, spectra_name = sensor_for_case(case)
    if case.kind == "colour":
        if case.mode == "isetcam":
            return _run_default(case, sensor, cfa_name, spectra_name, ISETCAM_ISP, ISETCAM_DELTA_E, True)
        return _run_default(case, sensor, cfa_name, spectra_name)
    if case.mode == "isetcam":
        if case.settings["metric"] != "mtf":
            raise CfaMitsubaError(f"{case.path}: mode 'isetcam' supports metric 'mtf' (got {case.settings['metric']!r})")
        return _run_isetcam(case, sensor, cfa_name, spectra_name)
    return _run_default(case, sensor, cfa_name, spectra_name)
