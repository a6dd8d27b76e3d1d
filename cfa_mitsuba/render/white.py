"""The white reference of a rendered scene (the sidecar's ``white_radiance``).

The white is the radiance a perfect white diffuser would have in the scene:
white balance, the colour-correction fit and CIELAB's reference white all
divide by it, so it decides what "white" and "mid grey" mean in every
colour metric.  Three rules (the ``white_from`` setting):

``panel`` (default)
    Charts: the white diffuser under the chart's light, exactly (D65 at the
    chart's scale).  3D scenes (built-in and users' alike): a photographer's
    grey card at the subject.  Camera rays through a 3 x 3 grid of image
    points (at 1/4, 1/2 and 3/4 of the width and height; lens centre) find
    the first surfaces; a small perfect-white Lambertian panel is placed
    just in front of each (1 % of the distance, towards the camera), facing
    the direction from which it gets the most direct light there (the
    direct-light irradiance vector, from :data:`DIRECTION_SAMPLES` emitter
    samples with shadow tests).  Each panel's radiance is measured by a
    radiance meter with all the light the scene carries (the render's path
    depth, interreflections included, :data:`PANEL_SPP` samples).  The
    The white is the panel of median luminance among those with direct light
    (among all, if none has).  Several points, so no single ray decides;
    facing the light, so a panel in the light reads at least as much as any
    diffuse surface beside it.  Its luminance is then kept between the
    image's median and twice its 99th-percentile luminance (its robust
    maximum): a scene of dark surfaces only (nothing above 30 % reflectance)
    would otherwise put all its content in the bottom third of the
    white's scale, and a camera seeing mostly its light sources would have a
    white darker than half its pixels.  A white surface in view facing the
    light sets the 99th percentile itself, so there the white is the
    panel's, unchanged.
``illuminant``
    ISETCam's normalisation by the image: the panel's spectrum scaled so
    that its luminance is the image's 99th-percentile luminance (a robust
    maximum).  Charts: as ``panel`` (their illuminant is known exactly).
(X, Y, Z)
    A white given by the user: CIE 1931 XYZ in cd/m^2 at the render's mean
    luminance; its spectrum is the smooth one D65 x (c0 + c1 t + c2 t^2),
    t = (lambda - 550) / 150 nm, with exactly those XYZ.

If every panel reads zero (no light reaches any), ``panel`` falls back to
``illuminant`` with the spectrum of the image's brightest 1 % of pixels, so
the white is never zero while the image is not black.
"""

from __future__ import annotations

__all__ = ["GRID", "PANEL_SPP", "DIRECTION_SAMPLES", "ROBUST_PERCENTILE", "parse_white_from", "place_panels",
           "measure_panels", "scaled_white", "spectrum_from_xyz"]

import math

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError

#: Image positions (fractions of width and height) of the panels' camera rays.
GRID = (0.25, 0.5, 0.75)
#: Samples per panel for its radiance.
PANEL_SPP = 16384
#: Emitter samples per panel for the direction of most direct light.
DIRECTION_SAMPLES = 1024
#: Percentile of image luminance used as its robust maximum.
ROBUST_PERCENTILE = 99.0
#: Panel offset towards the camera and half size, as fractions of the hit distance.
_OFFSET, _HALF = 0.01, 0.002


def parse_white_from(value):
    """'panel', 'illuminant' or an (X, Y, Z) tuple (cd/m^2) from a setting
    value: one of the words, a string 'X,Y,Z' or a sequence of three numbers."""
    if value is None:
        return "panel"
    if isinstance(value, str) and value.strip().lower() in ("panel", "illuminant"):
        return value.strip().lower()
    parts = value.split(",") if isinstance(value, str) else value
    try:
        xyz = tuple(float(v) for v in parts)
    except (TypeError, ValueError):
        xyz = ()
    if len(xyz) != 3 or not all(math.isfinite(v) and v >= 0 for v in xyz) or xyz[1] <= 0:
        raise CfaMitsubaError(f"white_from (--white-from) must be panel, illuminant or X,Y,Z (three non-negative "
                              f"numbers in cd/m^2, Y > 0), got {value!r}")
    return xyz


def spectrum_from_xyz(xyz, wavelengths) -> np.ndarray:
    """A smooth positive spectral radiance (B,) W/(m^2 sr nm) whose CIE 1931
    XYZ (cd/m^2) is exactly ``xyz``: D65 times a quadratic in wavelength."""
    wl = spectra.validate_wavelengths(wavelengths)
    t = (wl - 550.0) / 150.0
    d65 = spectra.illuminant("D65", wl)
    basis = np.stack([d65, d65 * t, d65 * t * t])
    coeffs = np.linalg.solve(spectra.xyz_from_radiance(basis, wl).T, np.asarray(xyz, dtype=np.float64))
    out = coeffs @ basis
    if not np.all(out > 0):
        raise CfaMitsubaError(f"white_from (--white-from) X,Y,Z = {tuple(xyz)} is too far from white for a smooth "
                              "positive spectrum")
    return out


def _values(x) -> np.ndarray:
    return np.asarray(x, dtype=np.float64).reshape(-1)


def place_panels(mi, scene) -> list[dict]:
    """Panel placements in a loaded scene (module docstring): dicts with
    ``grid`` (u, v), ``center``, ``normal``, ``half_size``, ``distance_m``
    (hit distance) and ``direct`` (whether direct light reaches it)."""
    sensor = scene.sensors()[0]
    scalar = mi.variant().startswith("scalar")
    panels = []
    bbox = scene.bbox()
    for v in GRID:
        for u in GRID:
            ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(u, v), mi.Point2f(0.5, 0.5))
            si = scene.ray_intersect(ray)
            o = np.array([_values(ray.o[i])[0] for i in range(3)])
            d = np.array([_values(ray.d[i])[0] for i in range(3)])
            valid = bool(_values(si.is_valid())[0])
            on_emitter = valid and bool(_values(si.shape.is_emitter())[0]) if not scalar else (
                valid and si.shape is not None and si.shape.is_emitter())
            if on_emitter:
                continue
            if valid:
                t = float(_values(si.t)[0])
            else:  # the ray escapes: a panel at the distance of the scene's centre
                t = max(1e-3, float(np.linalg.norm(np.array([float(_values(bbox.center()[i])[0]) for i in range(3)]) - o)))
            c = o + (1.0 - _OFFSET) * t * d
            e = _irradiance_vector(mi, scene, c)
            norm = float(np.linalg.norm(e))
            direct = norm > 0 and math.isfinite(norm)
            normal = e / norm if direct else -d
            panels.append({"grid": [u, v], "center": c.tolist(), "normal": normal.tolist(),
                           "half_size": _HALF * t, "distance_m": t, "direct": direct})
    return panels


def _irradiance_vector(mi, scene, point: np.ndarray) -> np.ndarray:
    """The direct-light irradiance vector at ``point`` (shadow-tested
    emitter samples, weighted by their radiance over pdf), (3,)."""
    n = DIRECTION_SAMPLES
    side = int(math.isqrt(n))
    g = (np.arange(side) + 0.5) / side
    su, sv = (a.ravel() for a in np.meshgrid(g, g))
    wl = (450.0, 520.0, 560.0, 610.0)
    if mi.variant().startswith("scalar"):
        acc = np.zeros(3)
        for a, b in zip(su, sv):
            it = mi.Interaction3f()
            it.p, it.t, it.time = mi.Point3f(*point), 0.0, 0.0
            it.wavelengths = mi.Spectrum(*wl)
            ds, w = scene.sample_emitter_direction(it, mi.Point2f(a, b), True)
            acc += float(np.mean(np.asarray(w))) * np.array([ds.d[0], ds.d[1], ds.d[2]])
        out = acc / su.size
    else:
        import drjit as dr

        it = dr.zeros(mi.Interaction3f, su.size)
        it.p = mi.Point3f(*(float(x) for x in point))
        it.t = mi.Float(0.0)
        it.wavelengths = mi.Spectrum(*wl)
        ds, w = scene.sample_emitter_direction(it, mi.Point2f(mi.Float(su), mi.Float(sv)), True)
        weight = np.mean([_values(w[i]) for i in range(4)], axis=0)
        dirs = np.stack([_values(ds.d[i]) for i in range(3)], axis=1)
        ok = np.isfinite(weight) & np.all(np.isfinite(dirs), axis=1)
        out = (weight[ok, None] * dirs[ok]).sum(axis=0) / su.size
    return out if np.all(np.isfinite(out)) else np.zeros(3)


def panel_scene_parts(mi, panels: list[dict]) -> tuple[dict, dict]:
    """A ``batch`` sensor of one radiance meter per panel (each just in
    front of its panel, looking at its centre) and the panels' shapes."""
    T = mi.ScalarTransform4f
    sensor = {"type": "batch"}
    shapes = {}
    for k, p in enumerate(panels):
        c, n, h = np.asarray(p["center"]), np.asarray(p["normal"]), float(p["half_size"])
        up = [0.0, 1.0, 0.0] if abs(n[1]) < 0.9 else [1.0, 0.0, 0.0]
        sensor[f"meter_{k}"] = {"type": "radiancemeter",
                                "to_world": T().look_at(origin=(c + 0.1 * h * n).tolist(), target=c.tolist(), up=up),
                                "film": {"type": "hdrfilm", "width": 1, "height": 1, "rfilter": {"type": "box"}}}
        shapes[f"cfa_white_panel_{k}"] = {
            "type": "rectangle", "to_world": T().look_at(origin=c.tolist(), target=(c + n).tolist(), up=up).scale(h),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "uniform", "value": 1.0}}}
    return sensor, shapes


def measure_panels(mi, scene, wavelengths, render) -> tuple[np.ndarray | None, dict]:
    """The ``panel`` white of a loaded 3D ``scene``: (B,) radiance at the
    render's scale (None if no panel has light) and the sidecar's record.

    ``render(sensor, extra, width)`` renders the scene with ``sensor`` (a
    plugin dict without film and sampler) and ``extra`` shapes on a
    ``width`` x 1 film at :data:`PANEL_SPP`, returning (1, width, B)."""
    panels = place_panels(mi, scene)
    if not panels:
        return None, {"panels": [], "rule": "panel", "note": "every grid ray hits an emitter"}
    sensor, shapes = panel_scene_parts(mi, panels)
    radiance = np.asarray(render(sensor, shapes, len(panels)), dtype=np.float64).reshape(len(panels), -1)
    lum = spectra.luminance_cd_m2(radiance, wavelengths)
    for p, y in zip(panels, lum):
        p["luminance_canonical"] = float(y)
    lit = [k for k, p in enumerate(panels) if p["direct"] and lum[k] > 0] or [k for k in range(len(panels)) if lum[k] > 0]
    info = {"panels": panels, "rule": "panel"}
    if not lit:
        return None, info
    chosen = sorted(lit, key=lambda k: lum[k])[len(lit) // 2]
    info["chosen"] = chosen
    return radiance[chosen], info


def robust_max_luminance(data: np.ndarray, wavelengths) -> float:
    """The image's 99th-percentile luminance (cd/m^2 at its scale)."""
    return float(np.percentile(spectra.luminance_cd_m2(data, wavelengths), ROBUST_PERCENTILE))


def bright_spectrum(data: np.ndarray, wavelengths) -> np.ndarray:
    """Mean spectrum of the pixels at or above the 99th-percentile luminance."""
    y = spectra.luminance_cd_m2(data, wavelengths)
    return data[y >= np.percentile(y, ROBUST_PERCENTILE)].mean(axis=0)


def scaled_white(rule, canonical_white, exact: bool, data: np.ndarray, wavelengths,
                 factor: float) -> tuple[np.ndarray, str]:
    """The white at the output scale (``data`` is the output image and
    ``factor`` the scale from the canonical render) under ``rule``, and a
    note on how its level was set."""
    if isinstance(rule, tuple):
        return spectrum_from_xyz(rule, wavelengths), "the given X,Y,Z"
    white = np.asarray(canonical_white, dtype=np.float64) * factor
    if exact:
        return white, "exact"
    y = float(spectra.luminance_cd_m2(white, wavelengths))
    y_img = spectra.luminance_cd_m2(data, wavelengths)
    top = float(np.percentile(y_img, ROBUST_PERCENTILE))
    if rule == "illuminant":
        return white * (top / y), f"scaled to the image's {ROBUST_PERCENTILE:g}th-percentile luminance"
    low, high = float(np.median(y_img)), 2.0 * top
    if y > high:
        return white * (high / y), (f"the panel's {y:.4g} cd/m^2 limited to twice the image's "
                                    f"{ROBUST_PERCENTILE:g}th-percentile luminance")
    if y < low:
        return white * (low / y), f"the panel's {y:.4g} cd/m^2 raised to the image's median luminance"
    return white, "the panel's"
