"""Users' Mitsuba 3 scene files (``cfa-mitsuba render FILE.xml``).

We keep the scene's geometry, materials, emitters and camera (pose, field of
view, lens) and replace its film, sampler and integrator with ours (the
spectral-quadrature integrator, or the per-band ``specfilm`` route in
scalar_spectral).  Scenes we cannot render correctly are refused with one
line, before anything is rendered:

- not a readable, well-formed Mitsuba ``<scene>`` file, or Mitsuba cannot
  load it (a missing mesh, an unknown plugin);
- no ``<sensor>`` (Mitsuba would invent a camera), or one that is not a
  ``perspective`` or ``thinlens`` camera (the metrics need a field of view);
- no emitter (the render would be black);
- participating media (the integrator traces surfaces only);
- a BSDF outside :data:`SUPPORTED_BSDFS`: the integrator draws one
  direction per path for all bands, which is exact only when a BSDF's
  sampling does not depend on wavelength.

The XML integrator's ``max_depth`` is kept if it sets one (-1, unlimited,
becomes :data:`UNLIMITED_DEPTH`), else :data:`DEFAULT_MAX_DEPTH`.

White reference (``white_radiance``): the central camera ray's first hit
gets a small perfect-white Lambertian square just in front of it, facing
the camera, measured with a radiance meter in the scene's own lights
(direct light only, as for the puppy).
"""

from __future__ import annotations

__all__ = ["SUPPORTED_BSDFS", "DEFAULT_MAX_DEPTH", "UNLIMITED_DEPTH", "DEFAULT_SPP", "user_scene"]

import hashlib
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from ..errors import CfaMitsubaError
from .registry import FULL_REFERENCE_METRICS, Built, RenderConfig, Scene

#: BSDF plugins whose sampling is wavelength-independent (Mitsuba 3.9).
SUPPORTED_BSDFS = frozenset({
    "diffuse", "twosided", "plastic", "roughplastic", "conductor", "roughconductor",
    "dielectric", "roughdielectric", "thindielectric", "null", "mask", "bumpmap", "normalmap",
})
#: Path length for scene files whose integrator does not set one.
DEFAULT_MAX_DEPTH = 5
#: Path length used for an XML max_depth of -1 (unlimited).
UNLIMITED_DEPTH = 8
#: Default samples per pixel for scene files (as the puppy).
DEFAULT_SPP = 100
_CAMERAS = ("perspective", "thinlens")
_FALLBACK_SIZE = (720, 636)


def _fail(path: Path, why: str):
    raise CfaMitsubaError(f"scene file {str(path)!r} {why}")


def _defaults(root) -> dict[str, str]:
    return {d.get("name"): d.get("value", "") for d in root.iter("default") if d.get("name")}


def _resolve(value: str | None, defaults: dict[str, str]) -> str | None:
    if value is None:
        return None
    return re.sub(r"\$(\w+)", lambda m: defaults.get(m.group(1), m.group(0)), value)


def _prop(elem, tag: str, name: str, defaults) -> str | None:
    for child in elem.findall(tag):
        if child.get("name") == name:
            return _resolve(child.get("value"), defaults)
    return None


def _identity(path: Path, text: bytes, root, defaults) -> dict:
    """Hash of the file and of every file it references (meshes, textures,
    includes), so that editing any of them invalidates cached renders."""
    h = hashlib.sha256(text)
    for elem in root.iter():
        for key, value in elem.attrib.items():
            if key == "filename" or (elem.get("name") == "filename" and key == "value"):
                ref = _resolve(value, defaults)
                p = (path.parent / ref) if ref else None
                h.update((ref or "").encode())
                if p is not None and p.is_file():
                    h.update(hashlib.sha256(p.read_bytes()).digest())
    return {"xml_path": str(path.resolve()), "xml_sha256": h.hexdigest()}


def _template(root, sensor) -> tuple[str, str]:
    """The scene XML with placeholders for our integrator and for the sensor
    (returned separately, with placeholders for film and sampler)."""
    for child in list(sensor):
        if child.tag in ("film", "sampler"):
            sensor.remove(child)
    sensor.append(ET.Comment("cfa:film"))
    sensor.append(ET.Comment("cfa:sampler"))
    sensor_xml = ET.tostring(sensor, encoding="unicode")
    for child in list(root):
        if child.tag in ("integrator", "sensor"):
            root.remove(child)
    root.insert(0, ET.Comment("cfa:integrator"))
    root.insert(1, ET.Comment("cfa:sensor"))
    return ET.tostring(root, encoding="unicode"), sensor_xml


def _horizontal_fov(mi, scene) -> float:
    params = mi.traverse(scene.sensors()[0])
    for key in params.keys():
        if key.endswith("x_fov"):
            value = params[key]
            return float(value[0] if hasattr(value, "__len__") else value)
    raise CfaMitsubaError("cannot read the camera's field of view")  # pragma: no cover


def user_scene(path) -> Scene:
    """Validate a Mitsuba 3 scene file and return it as a :class:`Scene`
    (defaults: the file's film size, :data:`DEFAULT_SPP`, its camera's
    horizontal field of view)."""
    p = Path(path)
    if not p.exists():
        raise CfaMitsubaError(f"no such scene file: {str(p)!r}")
    if p.is_dir():
        raise CfaMitsubaError(f"{str(p)!r} is a directory, not a scene file")
    if p.suffix.lower() != ".xml":
        raise CfaMitsubaError(f"unknown scene {str(p)!r}: a scene file must be a Mitsuba 3 .xml file")
    try:
        text = p.read_bytes()
    except OSError as exc:
        raise CfaMitsubaError(f"cannot read scene file {str(p)!r}: {exc.strerror}") from None
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        _fail(p, f"is not well-formed XML ({exc})")
    if root.tag != "scene":
        _fail(p, f"is not a Mitsuba scene (its root element is <{root.tag}>, not <scene>)")
    defaults = _defaults(root)
    sensors = root.findall("sensor")
    if not sensors:
        _fail(p, "has no <sensor>: cfa-mitsuba renders through the scene's own camera")
    sensor = sensors[0]
    if sensor.get("type") not in _CAMERAS:
        _fail(p, f"has a {sensor.get('type')!r} sensor; cfa-mitsuba needs a perspective or thinlens camera")
    if not any(True for _ in root.iter("emitter")):
        _fail(p, "has no emitter: nothing would light it")
    if any(True for _ in root.iter("medium")):
        _fail(p, "uses participating media, which cfa-mitsuba's spectral integrator does not trace")
    bad = sorted({b.get("type") for b in root.iter("bsdf")} - SUPPORTED_BSDFS - {None})
    if bad:
        _fail(p, f"uses BSDF {', '.join(bad)}, whose sampling depends on wavelength or is not supported "
                 f"(supported: {', '.join(sorted(SUPPORTED_BSDFS))})")

    film = sensor.find("film")
    size = list(_FALLBACK_SIZE)
    if film is not None:
        for i, key in enumerate(("width", "height")):
            v = _prop(film, "integer", key, defaults)
            if v is not None:
                try:
                    size[i] = int(v)
                except ValueError:
                    _fail(p, f"has a film {key} of {v!r}, not an integer")
    depth = DEFAULT_MAX_DEPTH
    for integ in root.findall("integrator"):
        v = _prop(integ, "integer", "max_depth", defaults)
        if v is not None:
            try:
                depth = int(v)
            except ValueError:
                _fail(p, f"has an integrator max_depth of {v!r}, not an integer")
            depth = UNLIMITED_DEPTH if depth < 0 else max(1, depth)
    identity = _identity(p, text, root, defaults)
    xml, sensor_xml = _template(root, sensor)

    # Load it once with Mitsuba now: the user learns at once if it cannot be
    # loaded, and we learn the horizontal field of view.
    from . import variant as _variant
    from .engine import _load, _probe_load_settings

    mi = _variant.load(_variant.choose_variant())
    probe_built = Built(meta={}, xml=xml, xml_sensor=sensor_xml, xml_dir=p.parent.resolve())
    scene = _load(mi, probe_built, *_probe_load_settings(size[0], size[1]))
    if not scene.emitters():
        _fail(p, "has no emitter Mitsuba can use: nothing would light it")
    fov = _horizontal_fov(mi, scene)

    return Scene(
        name=p.stem,
        description=f"Mitsuba scene file {p.name}",
        width=size[0], height=size[1], fov_deg=fov, spp=DEFAULT_SPP, oversample=1,
        metrics=FULL_REFERENCE_METRICS, builder=_build, max_depth=depth, path=p.resolve(),
        identity=identity,
    )


def _build(scene: Scene, config: RenderConfig) -> Built:
    from . import variant as _variant
    from .engine import _load, _probe_load_settings

    mi = _variant.load(config.variant)
    root = ET.fromstring(scene.path.read_bytes())
    xml, sensor_xml = _template(root, root.findall("sensor")[0])
    built = Built(meta={}, xml=xml, xml_sensor=sensor_xml, xml_dir=scene.path.parent)
    loaded = _load(mi, built, *_probe_load_settings(config.width, config.height))
    sensor = loaded.sensors()[0]
    # The central ray's first hit (or the scene's centre, if it escapes).
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(0.5, 0.5), mi.Point2f(0.5, 0.5))
    si = loaded.ray_intersect(ray)
    origin = [float(v) for v in _xyz(ray.o)]
    direction = [float(v) for v in _xyz(ray.d)]
    if bool(_scalar(si.is_valid())):
        distance = float(_scalar(si.t))
    else:
        bbox = loaded.bbox()
        centre = [float(v) for v in _xyz(bbox.center())]
        distance = max(1e-3, math.dist(origin, centre))
    center = [o + 0.99 * distance * d for o, d in zip(origin, direction)]
    meta = {
        "fov_deg": _horizontal_fov(mi, loaded),
        "illuminant": "the scene file's emitters",
        "scene_distance_m": distance,
        "geometry": {
            "xml": str(scene.path),
            "xml_sha256": scene.identity.get("xml_sha256"),
            "max_depth": config.max_depth,
            "white_reference": "perfect white Lambertian square facing the camera just in front of the central "
                               "ray's first hit, direct light only, radiance meter; scene units taken as metres",
            "white_reference_center": center,
        },
    }
    probe = {"center": center, "camera": origin, "half_size": 0.01 * distance}
    return Built(meta=meta, xml=xml, xml_sensor=sensor_xml, xml_dir=scene.path.parent, white_probe=probe,
                 band_constant=False)


def _xyz(v):
    return [v[i][0] if hasattr(v[i], "__len__") else v[i] for i in range(3)]


def _scalar(x):
    return x[0] if hasattr(x, "__len__") else x
