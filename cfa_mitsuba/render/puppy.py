"""``puppy``: a 3D scene in the spirit of the paper's PUPPY.

A toy dog built from shapes (an orange furry body, brown furry ears and snout,
black nose and eye) stands on a table with a gingham cloth in front of a
grey backdrop, with two printed cards on posts just behind it (a black and
white test chart at the right, a colour print at the upper left), yellow
panels at the upper left, a blue-green panel at the upper centre, a blue
block in the near foreground at the lower right and more objects at several
depths (0.9 to 3 m).  Every surface is Lambertian with a measured
reflectance from colour-science's 'ColorChecker N Ohta' set, constant inside
each band at its band mean (see :mod:`.light`); the fur, the cloth and the
cards are spectral textures (:mod:`.texture`, :mod:`.puppy_textures`):
per-texel mixes of a few of those reflectances, with detail from a few
centimetres down to well below a pixel (the sensor's Nyquist).  Light: one 0.6 m square
D65 area light (band-constant D65) up and to the left of the camera, aimed
at the dog; the shadows are filled by the light the table and the backdrop
reflect.  Path tracing with two bounces (:data:`MAX_DEPTH` = 3: direct light
plus one indirect bounce; a further bounce adds 0.7 % of the light at 1.6
times the cost), all bands along every path.

Default quality: 400 samples per pixel (20 x 20 strata): 256 (16 x 16),
set by the convergence study (docs/convergence.md).  Noise alone would allow less:
the median relative luminance noise per pixel is 0.93 % at 64 spp (180 x
159) and falls as 1/sqrt(spp), 0.66 % at 100 spp (636 x 720, two seeds),
so 100 spp already meets the 1 % target.  But at 100 spp the render's noise
moves the *differences* between CFAs by up to 15 % of their spread (MDSI at
full size); 256 spp brings that to about 6 % for 2.6x the render time
(measured at 256 spp, 636 x 720: 0.36 % luminance noise, 160 s per render)
(about 2.8 us of CPU per sample: some 330 CPU seconds at 636 x 720, paid
once per study because renders are cached).  With the textures (issue 13):
0.76 % median luminance noise at 720 x 636 and 256 spp (a pixel's samples
also integrate sub-pixel texture now) and 131-132 s per render on a busy
2-core machine.  The 0.4-mm fur and the printed backdrop, panels and block
(out of focus: each sample lands somewhere in a blur disc of contrasted
print) raised that to 1.13 % at 256 spp, over the 1 % target, so the
default is now 400 spp (noise falls as 1/sqrt(spp); measured in
docs/scenes.md): 0.88 %, and 0.97 % with the combed fur and the chart's
gratings.  (A uniform D65 sky as extra
fill cost 35 % more per sample and raised the noise; a second area light as
fill raised the noise too.)

Camera: the paper's 10 degree horizontal field of view, 636 x 720, through
Mitsuba's ``thinlens`` focused on the dog at :data:`FOCUS_DISTANCE_M`.  The
lens is the one that images that field onto 720 pixels of 2.2 um (1.584 mm):
focal length f = 0.792 mm / tan(5 deg) = 9.05 mm, at f/2 (aperture radius
f / 2N = 2.26 mm), so that depth of field shows: the blur disc (thin lens,
diameter 2R |d - S| / S on the object, here in pixels of the 720-wide
image) is 5.6 px for the blue block (0.88 m), 3.5 px for the ball (1.55
m), 7 to 9 px for the panels (2.2 to 2.7 m) and 9.3 px for the backdrop.  Mitsuba's
thin lens models defocus only; the optics stage adds diffraction (at the
sidecar's ``f_number``), relative illumination and the pixel aperture.

White reference: the rule of every 3D scene (:mod:`.white`): perfect white
Lambertian panels at the first hits of a 3 x 3 grid of camera rays, each
facing the direction of most direct light, measured with all the light the
scene carries; the directly lit panel of median luminance is the sidecar's
``white_radiance``.

``f_number`` (a render setting) sets the aperture radius f / (2 N); the
default is f/2 (:data:`F_NUMBER`).
"""

from __future__ import annotations

__all__ = ["FOCUS_DISTANCE_M", "F_NUMBER", "FOCAL_LENGTH_M", "MAX_DEPTH", "objects"]

import math

import numpy as np

from .. import spectra
from . import puppy_textures as tex
from .light import band_spectrum, d65_white_radiance
from .types import NATURAL, Built, RenderConfig, Scene

#: Distance (m) from the lens to the plane of focus, through the dog's middle.
FOCUS_DISTANCE_M = 1.2
#: Default f-number of the thin lens (the ``f_number`` setting overrides it).
F_NUMBER = 2.0
#: Focal length (m): the 10 degree field onto 720 x 2.2 um.
FOCAL_LENGTH_M = 0.5 * 720 * 2.2e-6 / math.tan(math.radians(5.0))
#: Longest path (Mitsuba's convention: 2 = direct light only).
MAX_DEPTH = 3
_TABLE_Y = -0.07  # table top height (m); the camera's axis is y = 0
_DOG_Z = -FOCUS_DISTANCE_M
# The cards: centres and half sizes (m); the chart's texture is 1136 x 1008
# texels of 0.075 mm, the colour print's 1072 x 672.
_CHART_CENTRE, _CHART_HALF = (0.0585, 0.047, -1.24), (0.0426, 0.0378)
_PRINT_CENTRE, _PRINT_HALF = (-0.064, 0.066, -1.26), (0.0402, 0.0252)
# Fur tile repeats (around, along) on the body and head, and on the thin parts.
_FUR_BODY, _FUR_THIN = (2.0, 1.0), (1.0, 0.5)
# The gingham tile (12 mm) repeated over the 2 x 2.5 m table.
_CLOTH_REPEATS = (2.0 / 0.012, 2.5 / 0.012)


def _lambert(config: RenderConfig, name: str) -> dict:
    names, refl = spectra.colorchecker(config.wl)
    return {"type": "diffuse", "reflectance": band_spectrum(config, refl[names.index(name)])}


def _unit_sphere(n_lon: int = 48, n_lat: int = 24):
    """Vertices (= normals), texture coordinates and triangles of a UV
    sphere of radius 1 about the y axis: u = longitude / 2 pi, v = polar
    angle from +y / pi (the seam and the poles have their own vertices, so
    that uv never wraps inside a triangle)."""
    theta = np.linspace(0.0, np.pi, n_lat + 1)[:, None]
    phi = np.linspace(0.0, 2 * np.pi, n_lon + 1)[None, :]
    v = np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.cos(theta) + 0 * phi,
                                     np.sin(theta) * np.sin(phi)), axis=-1).reshape(-1, 3)
    uv = np.stack(np.broadcast_arrays(phi / (2 * np.pi), theta / np.pi), axis=-1).reshape(-1, 2)
    faces = []
    cols = n_lon + 1
    for i in range(n_lat):
        for j in range(n_lon):
            a, b = i * cols + j, i * cols + j + 1
            c, d = a + cols, b + cols
            # Counter-clockwise seen from outside (normal = d phi x d theta).
            if i > 0:
                faces.append((a, b, c))
            if i < n_lat - 1:
                faces.append((b, d, c))
    return v, uv, np.array(faces, dtype=np.uint32)


def _ellipsoid(mi, name, center, radii, bsdf, yaw_deg=0.0, roll_deg=0.0):
    """A smooth triangle-mesh ellipsoid with texture coordinates (Mitsuba's
    sphere allows only uniform scale), rotated by ``roll`` about z then
    ``yaw`` about y."""
    v, uv, f = _unit_sphere()
    r = np.asarray(radii, dtype=np.float64)
    cz, sz = math.cos(math.radians(roll_deg)), math.sin(math.radians(roll_deg))
    cy, sy = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    rot = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]]) @ np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    pos = (v * r) @ rot.T + np.asarray(center)
    nrm = (v / r) @ rot.T  # normals transform with the inverse transpose
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    props = mi.Properties()
    props["bsdf"] = bsdf if isinstance(bsdf, mi.BSDF) else mi.load_dict(bsdf)
    mesh = mi.Mesh(name, len(pos), len(f), props=props, has_vertex_normals=True, has_vertex_texcoords=True)
    params = mi.traverse(mesh)
    vt, ft = type(params["vertex_positions"]), type(params["faces"])
    params["vertex_positions"] = vt(pos.astype(np.float32).ravel())
    params["vertex_normals"] = vt(nrm.astype(np.float32).ravel())
    params["vertex_texcoords"] = type(params["vertex_texcoords"])(uv.astype(np.float32).ravel())
    params["faces"] = ft(f.ravel())
    params.update()
    return mesh


def objects() -> list[dict]:
    """The scene's objects for the sidecar: name, shape, reflectance name
    and distance (m) from the lens along the optical axis."""
    return [dict(o) for o in _OBJECTS]


_OBJECTS = (
    {"name": "dog body, head, legs, tail", "shape": "ellipsoids, sphere, cylinders", "reflectance": "orange",
     "texture": "fur", "depth_m": 1.2},
    {"name": "dog ears and snout", "shape": "ellipsoids", "reflectance": "dark skin", "texture": "fur_brown",
     "depth_m": 1.2},
    {"name": "dog nose and eye", "shape": "spheres", "reflectance": "black 2 (1.5 D)", "depth_m": 1.18},
    {"name": "blue letter block", "shape": "cube", "reflectance": "blue", "texture": "toy_block", "depth_m": 0.88},
    {"name": "yellow-green ball", "shape": "sphere", "reflectance": "yellow green", "depth_m": 1.55},
    {"name": "magenta post", "shape": "cylinder", "reflectance": "magenta", "depth_m": 1.8},
    {"name": "yellow panel", "shape": "rectangle", "reflectance": "yellow", "texture": "poster_yellow", "depth_m": 2.2},
    {"name": "orange-yellow panel", "shape": "rectangle", "reflectance": "orange yellow",
     "texture": "poster_orange_yellow", "depth_m": 2.5},
    {"name": "grey ball", "shape": "sphere", "reflectance": "neutral 8 (.23 D)", "depth_m": 2.4},
    {"name": "blue-green panel", "shape": "rectangle", "reflectance": "bluish green", "texture": "poster_blue_green",
     "depth_m": 2.7},
    {"name": "test chart card on a post", "shape": "rectangle", "reflectance": "white 9.5 (.05 D)",
     "texture": "chart", "depth_m": 1.24},
    {"name": "colour print card on a post", "shape": "rectangle", "reflectance": "white 9.5 (.05 D)",
     "texture": "colour_print", "depth_m": 1.26},
    {"name": "card posts", "shape": "cylinders", "reflectance": "neutral 5 (.70 D)", "depth_m": 1.25},
    {"name": "table", "shape": "rectangle", "reflectance": "light skin", "texture": "tablecloth",
     "depth_m": "0.75 to 3.25"},
    {"name": "backdrop", "shape": "rectangle", "reflectance": "neutral 6.5 (.44 D)", "texture": "wallpaper",
     "depth_m": 3.0},
)


def _build(scene: Scene, config: RenderConfig) -> Built:
    import mitsuba as mi

    T = mi.ScalarTransform4f
    wl = config.wl
    white = d65_white_radiance(wl)
    black = _lambert(config, "black 2 (1.5 D)")
    fur, fur_brown = tex.fur(), tex.fur_brown()
    z = _DOG_Z
    body_y = _TABLE_Y + 0.052

    # Fur BSDFs are shared between parts (each distinct BSDF adds code to
    # every BSDF call of the JIT kernel: compile time): one scale for the
    # body and head (texels 0.08-0.12 mm), one for the thin parts (legs,
    # tail, snout, ears: 0.02-0.1 mm).
    shared = {}

    def furry(texture, scale):
        key = (texture.name, scale)
        if key not in shared:
            shared[key] = mi.load_dict(texture.bsdf(mi, config, uv_scale=scale))
        return shared[key]

    def cyl(p0, p1, r, bsdf):
        return {"type": "cylinder", "p0": list(p0), "p1": list(p1), "radius": r, "bsdf": bsdf}

    def sphere(c, r, bsdf):
        return {"type": "sphere", "center": list(c), "radius": r, "bsdf": bsdf}

    def panel(c, half, yaw, bsdf, roll=0.0):
        return {"type": "rectangle", "bsdf": bsdf, "to_world": T().translate(list(c)).rotate([0, 1, 0], yaw)
                .rotate([0, 0, 1], roll).scale([half[0], half[1], 1.0])}

    def poster_bsdf(colour, half):
        tile = tex.POSTER_TILE_M
        return tex.poster(colour).bsdf(mi, config, uv_scale=(2 * half[0] / tile, 2 * half[1] / tile))

    def card(c, half, roll, texture):
        # A rectangle's uv runs from its lower left; the texture's row 0 is its top.
        flipped = type(texture)(texture.name, texture.palette, texture.weights[::-1], texture.texel_m)
        return panel(c, half, 0.0, flipped.bsdf(mi, config, wrap="clamp"), roll)

    head_c = np.array([-0.047, body_y + 0.036, z])
    eye_dir = np.array([-0.45, 0.30, 0.84]) / np.linalg.norm([-0.45, 0.30, 0.84])
    ear = dict(radii=(0.007, 0.019, 0.005), bsdf=furry(fur_brown, _FUR_THIN), roll_deg=-20)
    legs = ((-0.024, 0.013), (-0.024, -0.013), (0.042, 0.013), (0.042, -0.013))
    leg_len = body_y - 0.01 - _TABLE_Y
    obj = {
        # The dog, facing left, its right side towards the camera; fur
        # textures (puppy_textures) with the strands running down its sides.
        "dog_body": _ellipsoid(mi, "dog_body", (0.012, body_y, z), (0.052, 0.027, 0.025),
                               furry(fur, _FUR_BODY)),
        # Mitsuba's sphere has its poles on local z: turned so they are on y.
        "dog_head": {"type": "sphere", "bsdf": furry(fur, _FUR_BODY),
                     "to_world": T().translate(head_c.tolist()).rotate([1, 0, 0], -90).scale(0.026)},
        "dog_snout": _ellipsoid(mi, "dog_snout", head_c + (-0.026, -0.008, 0.0), (0.019, 0.011, 0.012),
                                furry(fur_brown, _FUR_THIN)),
        "dog_nose": sphere(head_c + (-0.044, -0.004, 0.0), 0.0055, black),
        "dog_eye": sphere(head_c + 0.026 * eye_dir, 0.0035, black),
        "dog_ear_near": _ellipsoid(mi, "dog_ear_near", head_c + (0.010, 0.010, 0.020), **ear),
        "dog_ear_far": _ellipsoid(mi, "dog_ear_far", head_c + (0.010, 0.010, -0.020), **ear),
        **{f"dog_leg_{i}": cyl((x, _TABLE_Y, z + dz), (x, body_y - 0.01, z + dz), 0.0075, furry(fur, _FUR_THIN))
           for i, (x, dz) in enumerate(legs)},
        "dog_tail": cyl((0.058, body_y + 0.008, z), (0.078, body_y + 0.040, z), 0.0045, furry(fur, _FUR_THIN)),
        "dog_tail_tip": sphere((0.078, body_y + 0.040, z), 0.0045, furry(fur, _FUR_THIN)),
        # The table and its gingham cloth, the backdrop, panels and props at
        # several depths.
        "table": {"type": "rectangle", "bsdf": tex.tablecloth().bsdf(mi, config, uv_scale=_CLOTH_REPEATS),
                  "to_world": T().translate([0.0, _TABLE_Y, -2.0]).rotate([1, 0, 0], -90).scale([1.0, 1.25, 1.0])},
        "backdrop": panel((0.0, 0.0, -3.0), (2.0, 0.75), 0.0,
                          tex.wallpaper().bsdf(mi, config, uv_scale=(4.0 / 0.048, 1.5 / 0.048))),
        "panel_yellow": panel((-0.115, 0.115, -2.2), (0.075, 0.055), 20.0,
                              poster_bsdf("yellow", (0.075, 0.055))),
        "panel_orange_yellow": panel((-0.045, 0.165, -2.5), (0.06, 0.045), -10.0,
                                     poster_bsdf("orange yellow", (0.06, 0.045))),
        "panel_blue_green": panel((0.035, 0.13, -2.7), (0.085, 0.055), 0.0,
                                  poster_bsdf("bluish green", (0.085, 0.055))),
        # Two printed cards on thin posts just behind the dog (near focus).
        "card_chart": card(_CHART_CENTRE, _CHART_HALF, 4.0, tex.chart()),
        "card_chart_post": cyl((_CHART_CENTRE[0], _TABLE_Y, _CHART_CENTRE[2] - 0.003),
                               (_CHART_CENTRE[0], _CHART_CENTRE[1], _CHART_CENTRE[2] - 0.003), 0.002,
                               _lambert(config, "neutral 5 (.70 D)")),
        "card_colour": card(_PRINT_CENTRE, _PRINT_HALF, -3.0, tex.colour_print()),
        "card_colour_post": cyl((_PRINT_CENTRE[0], _TABLE_Y, _PRINT_CENTRE[2] - 0.003),
                                (_PRINT_CENTRE[0], _PRINT_CENTRE[1], _PRINT_CENTRE[2] - 0.003), 0.002,
                                _lambert(config, "neutral 5 (.70 D)")),
        "block_blue": {"type": "cube", "bsdf": tex.toy_block().bsdf(mi, config, wrap="clamp"),
                       "to_world": T().translate([0.07, _TABLE_Y + 0.026, -0.88]).rotate([0, 1, 0], 25).scale(0.026)},
        "ball_yellow_green": sphere((-0.085, _TABLE_Y + 0.021, -1.55), 0.021, _lambert(config, "yellow green")),
        "post_magenta": cyl((0.12, _TABLE_Y, -1.8), (0.12, _TABLE_Y + 0.075, -1.8), 0.016, _lambert(config, "magenta")),
        "post_magenta_top": {"type": "disk", "bsdf": _lambert(config, "magenta"),
                             "to_world": T().translate([0.12, _TABLE_Y + 0.075, -1.8]).rotate([1, 0, 0], -90).scale(0.016)},
        "ball_grey": sphere((0.16, _TABLE_Y + 0.035, -2.4), 0.035, _lambert(config, "neutral 8 (.23 D)")),
        # The D65 key light (its level is arbitrary: renders are rescaled).
        "key_light": {"type": "rectangle",
                      "to_world": T().look_at(origin=[-0.5, 0.9, -0.4], target=[0.0, -0.02, z], up=[0, 1, 0]).scale(0.3),
                      "emitter": {"type": "area", "radiance": band_spectrum(config, 15.0 * white)}},
    }
    f_number = F_NUMBER if config.f_number is None else float(config.f_number)
    aperture = FOCAL_LENGTH_M / (2 * f_number)
    sensor = {
        "type": "thinlens",
        "fov": float(config.fov_deg),
        "fov_axis": "x",
        "aperture_radius": aperture,
        "focus_distance": FOCUS_DISTANCE_M,
        "near_clip": 0.05,
        "far_clip": 20.0,
        "to_world": T().look_at(origin=[0, 0, 0], target=[0, 0, -1], up=[0, 1, 0]),
    }
    meta = {
        "illuminant": "D65",
        "scene_distance_m": FOCUS_DISTANCE_M,
        "geometry": {
            "objects": objects(),
            "reflectance_set": "ColorChecker N Ohta",
            "textures": [t.record() for t in tex.all_textures().values()],
            "focus_distance_m": FOCUS_DISTANCE_M,
            "aperture_radius_m": aperture,
            "f_number": f_number,
            "focal_length_m": FOCAL_LENGTH_M,
            "lens": "Mitsuba thinlens (defocus only; no diffraction, vignetting or distortion)",
            "lights": "one 0.6 m square D65 area light centred at (-0.5, 0.9, -0.4) m, aimed at the dog",
            "max_depth": MAX_DEPTH,
            "camera": "at the origin looking along -z, y up; the table top is at y = -0.07 m",
        },
    }
    return Built(meta=meta, objects=obj, sensor=sensor)


#: The puppy, registered by :mod:`.builtins`.
SCENE = Scene(
    name="puppy",
    description="3D toy dog on a table, coloured panels and blocks at 0.9-3 m, D65 area light, thin lens focused on the dog (f/2); FOV 10 deg",
    width=720, height=636, fov_deg=10.0, spp=400, oversample=1, kind=NATURAL,
    builder=_build, max_depth=MAX_DEPTH, thin_lens=True, f_number=F_NUMBER,
)
