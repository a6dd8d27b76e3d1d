"""Users' Mitsuba 3 scene files (``cfa-mitsuba render FILE.xml``).

A scene file is read the way Mitsuba reads it: first walked safely by
:mod:`.xmlscan` (size and nesting bounds, includes, ``<path>`` folders,
``<default>`` parameters, every file confined to the scene's folder), then
parsed by Mitsuba's own parser (``mitsuba.parser.parse_file``: includes
merged, parameters substituted, references resolved), and the checks below
run on what Mitsuba parsed, wherever an element came from.  Every file a
plugin names (a mesh's, a bitmap's or an environment map's ``filename``)
is resolved as Mitsuba would resolve it, checked, and handed to Mitsuba as
that absolute path, so the files hashed into the cache key are the files
rendered.

We keep the scene's geometry, materials, emitters and camera (pose, field
of view, lens) and replace its film, sampler and integrator with ours; a
scene with participating media or a BSDF outside :data:`SUPPORTED_BSDFS`
is rendered band by band by Mitsuba's own ``volpath``/``path``
(:mod:`.stockroute`).
Refused with one line naming the file and line of the element:

- a tinted BSDF: the all-band integrator draws one direction per path
  for all bands, exact only when a BSDF's sampling does not depend on
  wavelength (:data:`SUPPORTED_BSDFS`; others go band by band through
  Mitsuba's ``path``); the ``principled`` and ``principledthin`` BSDFs
  (which Blender's exporter writes) sample by scalar weights and are
  rendered by it, unless a ``spec_tint`` or ``sheen_tint`` is set (Mitsuba
  normalises the tint by a luminance estimated from a path's own 4
  wavelengths, which no all-band evaluation can reproduce) or a
  ``principledthin``'s ``eta`` is a spectrum (its refraction would depend
  on wavelength);
- no ``<sensor>`` (Mitsuba would invent a camera), or a first one that is
  not a ``perspective`` or ``thinlens`` camera (an ``orthographic`` camera
  has no angular field of view: the lens, relative illumination and
  S-CIELAB's samples per degree need one); a horizontal field of view of
  :data:`MAX_FOV_DEG` or more;
- no emitter;
- film sizes, path depths or apertures we cannot render (named by element
  and attribute).

Before a scene file is loaded in this process it is loaded once in a child
process (:mod:`.loadcheck`): a file Mitsuba cannot instantiate is refused
from there, because a failed instantiation leaves Mitsuba's process state
unsafe for later renders (:func:`_loads_elsewhere`).

The camera's field of view follows Mitsuba's own rule for the film it
renders (``mitsuba.parse_fov`` with the render's aspect ratio, whatever
its ``fov_axis``), so ``--width``/``--height`` that change the aspect ratio
change the recorded field of view exactly as they change the render
(:func:`fov_at`).  Scene parameters (``$name``) take ``defines`` (``render
--define NAME=VALUE``, Mitsuba's ``-D``) before the file's ``<default>``s;
``asset_root`` lets the files reach one shared folder besides their own.

The integrator's ``max_depth`` is kept (-1, unlimited, becomes
:data:`UNLIMITED_DEPTH`), else :data:`DEFAULT_MAX_DEPTH`.  A ``thinlens``
camera's f-number is f / (2 R): R its ``aperture_radius`` (scene units
taken as metres), f the focal length that images its field of view onto
the film width in 2.2 um pixels (:func:`.types.focal_length_m`); the
``f_number`` setting replaces R by f / (2 N).
"""

from __future__ import annotations

__all__ = ["SUPPORTED_BSDFS", "TINTED_BSDFS", "DEFAULT_MAX_DEPTH", "UNLIMITED_DEPTH", "DEFAULT_SPP", "MAX_FOV_DEG",
           "user_scene", "files_unchanged", "fov_at"]

import functools
import json
import math
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from ..errors import CfaMitsubaError, one_line
from . import variant as _variant
from . import stockroute as _stockroute
from . import xmlscan
from .loading import inspect_settings
from .types import MAX_FOV_DEG, NATURAL, Built, RenderConfig, Scene, focal_length_m

#: BSDF plugins whose sampling is wavelength-independent (Mitsuba 3.9): a
#: ``blendbsdf`` picks a child by a scalar weight (``eval_1``), ``plastic``
#: and ``pplastic`` by a weight fixed when the plugin is built,
#: ``measured_polarized`` by a fixed lobe weight and GGX width, ``polarizer``
#: passes straight through.
SUPPORTED_BSDFS = frozenset({
    "diffuse", "twosided", "plastic", "roughplastic", "conductor", "roughconductor",
    "dielectric", "roughdielectric", "thindielectric", "null", "mask", "bumpmap", "normalmap",
    "principled", "principledthin", "blendbsdf", "pplastic", "polarizer", "measured_polarized",
})
#: BSDFs exact only without a tint (module docstring): the properties refused when set and not 0.
TINTED_BSDFS = {"principled": ("spec_tint", "sheen_tint"), "principledthin": ("spec_tint", "sheen_tint")}
#: The sensor properties that set its field of view (``mitsuba.parse_fov``).
_FOV_KEYS = ("fov", "fov_axis", "focal_length")
#: Path length for scene files whose integrator does not set one.
DEFAULT_MAX_DEPTH = 5
#: Path length used for an XML max_depth of -1 (unlimited).
UNLIMITED_DEPTH = 8
#: Longest path a scene file may ask for.
MAX_PATH_DEPTH = 64
#: Default samples per pixel for scene files.
DEFAULT_SPP = 100
#: Smallest physically possible f-number (N >= 1 / (2 sin 90 deg)).
MIN_F_NUMBER = 0.5
#: Largest film side (pixels).
MAX_FILM_SIDE = 32768
_CAMERAS = ("perspective", "thinlens")
_FALLBACK_SIZE = (768, 576)  # Mitsuba's hdrfilm default


def _fail(path: Path, why: str):
    raise CfaMitsubaError(f"scene file {str(path)!r}: {why}")


@dataclass
class _Read:
    """A scene file read, parsed by Mitsuba and checked."""

    scan: xmlscan.Scan
    state: object  # mitsuba.parser.ParserState, references resolved, file names absolute
    sensor: int
    camera: str
    size: tuple[int, int]
    depth: int
    fov_deg: float
    aperture_m: float | None
    focus_m: float | None
    files: list[tuple[str, Path]]
    fov_props: tuple[tuple[str, object], ...] = ()
    stock: tuple[str, str] | None = None  # (Mitsuba integrator, reason): :mod:`.stockroute`


def _tag(mi, node) -> str:
    names = {mi.ObjectType.Sensor: "sensor", mi.ObjectType.BSDF: "bsdf", mi.ObjectType.Emitter: "emitter",
             mi.ObjectType.Shape: "shape", mi.ObjectType.Texture: "texture", mi.ObjectType.Medium: "medium",
             mi.ObjectType.PhaseFunction: "phase", mi.ObjectType.Volume: "volume", mi.ObjectType.Film: "film",
             mi.ObjectType.Sampler: "sampler", mi.ObjectType.Integrator: "integrator"}
    return f'<{names.get(node.type, "element")} type="{node.props.plugin_name()}">'


def _children(mi, node) -> list[tuple[str, int]]:
    props = node.props
    return [(k, props[k].index()) for k in props.keys() if props.type(k) == mi.Properties.Type.ResolvedReference]


def _number(props, key, default=None):
    return float(props[key]) if key in props.keys() else default


def fov_at(fov_props, width: int, height: int) -> float:
    """The horizontal field of view (degrees) of a camera whose ``fov``,
    ``fov_axis`` and ``focal_length`` are ``fov_props`` ((key, value)
    pairs) on a film of ``width`` x ``height`` pixels: Mitsuba's own
    ``parse_fov`` at that aspect ratio, as its perspective and thin-lens
    cameras compute it from their film (fov_axis x, y, diagonal, smaller,
    larger; a focal length over the 36 x 24 mm diagonal)."""
    mi = _variant.load(_variant.choose_variant())
    props = mi.Properties("perspective")
    for key, value in fov_props:
        props[key] = value
    return float(mi.parse_fov(props, int(width) / int(height)))


def _fov_props(mi, sp) -> tuple[tuple[str, object], ...]:
    out = []
    for key in _FOV_KEYS:
        if key in sp.keys():
            out.append((key, float(sp[key]) if sp.type(key) == mi.Properties.Type.Float else str(sp[key])))
    return tuple(out)


def _check_tints(mi, nodes, at) -> None:
    for i, n in enumerate(nodes):
        name = n.props.plugin_name() if n.type == mi.ObjectType.BSDF else None
        for key in TINTED_BSDFS.get(name, ()):
            props = n.props
            if key in props.keys() and not (props.type(key) == mi.Properties.Type.Float and float(props[key]) == 0):
                raise CfaMitsubaError(
                    f"{at(i)}, {key}: a tinted principled BSDF cannot be rendered exactly at every band (Mitsuba "
                    "divides the tint by a luminance estimated from a path's own 4 wavelengths); remove the tint "
                    "or set it to 0")
        if name == "principledthin" and "eta" in n.props.keys() and n.props.type("eta") != mi.Properties.Type.Float:
            raise CfaMitsubaError(f"{at(i)}, eta: a spectral index of refraction makes this BSDF's refraction "
                                  "depend on wavelength; give eta as one <float>")


def _read(path: Path, allow_outside_paths: bool, defines=(), asset_root=None) -> _Read:
    scan = xmlscan.scan(path, allow_outside_paths=allow_outside_paths, defines=defines, asset_root=asset_root)
    main = scan.main
    mi = _variant.load(_variant.choose_variant())
    config = mi.parser.ParserConfig(mi.variant())
    # A --define the file does not use is not an error (the same --define
    # spp=16 serves a folder of scenes); Mitsuba's parser refuses it by default.
    config.unused_parameters = mi.LogLevel.Debug
    # Mitsuba's load_file looks up relative names (a <spectrum filename="sub/x.spd">, read while parsing) in
    # the scene's folder first; parse_file alone does not, so the scene's folder is put first here, as
    # load_file does, and the resolver restored after (xmlscan has checked those files with the same order).
    saved = mi.file_resolver()
    resolver = mi.FileResolver(saved)
    resolver.prepend(str(main.parent))
    mi.set_file_resolver(resolver)
    try:
        state = mi.parser.parse_file(config, str(main), **dict(defines))
        mi.parser.transform_upgrade(config, state)
        mi.parser.transform_resolve(config, state)
    except Exception as exc:  # Mitsuba reports parse errors as RuntimeError, with file and line
        _fail(main, f"Mitsuba cannot read it: {one_line(exc, 300)}")
    finally:
        mi.set_file_resolver(saved)
    parsed = {Path(os.path.realpath(str(f))) for f in state.files}
    scanned = {p for role, p in scan.files if role == "xml"}
    # Mitsuba lists only the files that gave it elements (an include of only
    # <default>s is read but not listed): refuse only a file it read that
    # the check did not.
    if not parsed <= scanned:  # pragma: no cover - our walk follows Mitsuba's rules; refuse if it ever does not
        _fail(main, f"Mitsuba read XML files the check did not: {sorted(map(str, parsed - scanned))}")
    nodes = state.nodes

    def at(i: int) -> str:
        return f"{_tag(mi, nodes[i])} at {mi.parser.file_location(state, nodes[i])}"

    try:
        _check_tints(mi, nodes, at)
    except CfaMitsubaError as exc:
        _fail(main, str(exc))
    root = _children(mi, nodes[0])
    sensors = [j for _, j in root if nodes[j].type == mi.ObjectType.Sensor]
    if not sensors:
        _fail(main, "has no <sensor>: cfa-mitsuba renders through the scene's own camera")
    s = sensors[0]
    camera = nodes[s].props.plugin_name()
    if camera == "orthographic":
        _fail(main, f"{at(s)}: an orthographic camera has no angular field of view, which the lens (focal length, "
                    "relative illumination) and S-CIELAB's samples per degree need: use a perspective or thinlens "
                    "camera")
    if camera not in _CAMERAS:
        _fail(main, f"{at(s)}: cfa-mitsuba needs a perspective or thinlens camera")
    if not any(n.type == mi.ObjectType.Emitter for n in nodes):
        _fail(main, "has no emitter: nothing would light it")

    files = list(scan.files)
    for i, n in enumerate(nodes):
        props = n.props
        if "filename" in props.keys() and props.type("filename") == mi.Properties.Type.String:
            name = str(props["filename"])
            where = f'{at(i)}, <string name="filename" value="{name}">'
            real = xmlscan.checked_file(scan, name, scan.resolver, where)
            props["filename"] = str(real)
            files.append(("data", real))

    sp = nodes[s].props
    size = list(_FALLBACK_SIZE)
    for _, j in _children(mi, nodes[s]):
        if nodes[j].type == mi.ObjectType.Film:
            for k, key in enumerate(("width", "height")):
                if key in nodes[j].props.keys():
                    v = int(nodes[j].props[key])
                    if not 1 <= v <= MAX_FILM_SIDE:
                        _fail(main, f'{at(j)}, <integer name="{key}" value="{v}">: must be 1 to {MAX_FILM_SIDE}')
                    size[k] = v
            break
    depth = DEFAULT_MAX_DEPTH
    cands = []
    for _, j in root:
        if nodes[j].type == mi.ObjectType.Integrator:
            cands = [j] + [c for _, c in _children(mi, nodes[j]) if nodes[c].type == mi.ObjectType.Integrator]
            for c in cands:
                if "max_depth" in nodes[c].props.keys():
                    v = int(nodes[c].props["max_depth"])
                    if v > MAX_PATH_DEPTH:
                        _fail(main, f'{at(c)}, <integer name="max_depth" value="{v}">: at most {MAX_PATH_DEPTH} '
                                    "(-1, unlimited, renders with 8)")
                    depth = UNLIMITED_DEPTH if v < 0 else max(1, v)
                    break
            break
    key = next((k for k in ("fov", "focal_length") if k in sp.keys()), "fov")
    shown = f'<float name="fov" value="{_number(sp, "fov")}">' if key == "fov" and "fov" in sp.keys() else (
        f'<string name="focal_length" value="{sp["focal_length"]}">' if key == "focal_length" else "default fov")
    try:
        fov = float(mi.parse_fov(sp, size[0] / size[1]))
    except Exception as exc:  # Mitsuba refuses a field of view outside (0, 180)
        _fail(main, f"{at(s)}, {shown}: cannot read its field of view ({one_line(exc, 300)}); cfa-mitsuba needs more "
                    f"than 0 and less than {MAX_FOV_DEG:g} degrees")
    if not 0 < fov < MAX_FOV_DEG:
        _fail(main, f"{at(s)}, {shown}: a horizontal field of view of {fov:.4g} degrees; cfa-mitsuba needs more than "
                    f"0 and less than {MAX_FOV_DEG:g}")
    aperture = focus = None
    if camera == "thinlens":
        aperture = _number(sp, "aperture_radius")
        if aperture is None or not math.isfinite(aperture) or aperture < 0:
            _fail(main, f'{at(s)}, <float name="aperture_radius">: must be given, finite and not negative '
                        f"(got {aperture})")
        focus = _number(sp, "focus_distance")
    return _Read(scan, state, s, camera, (size[0], size[1]), depth, fov, aperture, focus, files, _fov_props(mi, sp),
                 _stockroute.stock_route(mi, nodes, cands, SUPPORTED_BSDFS))


def _identity(read: _Read, defines) -> dict:
    """The files the render reads, each with its content hash, and the
    scene parameters given: any edit of the scene file, an included file, a
    mesh, texture or spectrum, or another ``--define``, gives a new cache
    key."""
    return {"xml_path": str(read.scan.main), "defines": [list(d) for d in defines],
            "files": [[role, str(p), xmlscan.file_sha256(p)] for role, p in read.files]}


def files_unchanged(scene: Scene) -> bool:
    """Whether every file of ``scene`` (a user XML scene) still has the
    content it had when the scene was read."""
    try:
        return all(xmlscan.file_sha256(Path(p)) == h for _, p, h in scene.identity.get("files", []))
    except CfaMitsubaError:
        return False


def user_scene(path, *, allow_outside_paths: bool = False, defines=None, asset_root=None) -> Scene:
    """Read and check a Mitsuba 3 scene file (module docstring) and return
    it as a :class:`Scene` (defaults: the file's film size, :data:`DEFAULT_SPP`,
    its camera's horizontal field of view and its integrator's path depth).
    ``defines``: scene parameters (``NAME=VALUE`` strings or a table,
    :func:`.xmlscan.parse_defines`); ``asset_root``: one more folder its
    files may be in."""
    p = Path(path)
    if not p.exists():
        raise CfaMitsubaError(f"no such scene file: {str(p)!r}")
    if p.is_dir():
        raise CfaMitsubaError(f"{str(p)!r} is a directory, not a scene file")
    if p.suffix.lower() != ".xml":
        raise CfaMitsubaError(f"unknown scene {str(p)!r}: a scene file must be a Mitsuba 3 .xml file")
    defs = xmlscan.parse_defines(defines)
    root = xmlscan.check_asset_root(asset_root)
    read = _read(p, allow_outside_paths, defs, root)
    return Scene(
        name=p.stem,
        description=f"Mitsuba scene file {p.name}",
        width=read.size[0], height=read.size[1], fov_deg=read.fov_deg, spp=DEFAULT_SPP, oversample=1,
        kind=NATURAL, builder=_build, max_depth=read.depth, path=read.scan.main,
        identity=_identity(read, defs), thin_lens=read.camera == "thinlens", allow_outside_paths=allow_outside_paths,
        defines=defs, asset_root=root, fov_at=functools.partial(fov_at, read.fov_props),
    )


def _lens(scene: Scene, read: _Read, config: RenderConfig) -> tuple[dict, float | None]:
    """The lens's sidecar entries and the aperture radius to render with
    (None: the file's own)."""
    f = focal_length_m(config.width, config.fov_deg)
    if read.camera != "thinlens":
        return {"lens": "perspective (pinhole): no defocus", "focal_length_m": f}, None
    if config.f_number is not None:
        radius, source = f / (2 * float(config.f_number)), "f_number setting"
    else:
        radius, source = read.aperture_m, "the scene file's aperture_radius"
    implied = (f / (2 * radius)) if radius > 0 else None
    lens = {"lens": "Mitsuba thinlens (defocus only; no diffraction, vignetting or distortion)",
            "aperture_radius_m": radius, "focal_length_m": f, "f_number_source": source,
            "focus_distance_m": read.focus_m}
    if implied is not None and implied >= MIN_F_NUMBER:
        lens["f_number"] = implied
    else:  # no lens has N < 0.5: the file's units are not metres, or its aperture is not a camera's
        lens["f_number_implied"] = implied
        lens["f_number_note"] = (f"below {MIN_F_NUMBER}: not recorded as f_number (the optics stage uses its "
                                 "default); set f_number to render this scene through a real lens")
    return lens, (radius if config.f_number is not None else None)


def _build(scene: Scene, config: RenderConfig) -> Built:
    read = _read(scene.path, scene.allow_outside_paths, scene.defines, scene.asset_root)
    lens, radius = _lens(scene, read, config)
    meta = {
        "fov_deg": config.fov_deg,  # the camera's at the render's film size (fov_at)
        "illuminant": "the scene file's emitters",
        "geometry": {"xml": str(scene.path), "files": [[r, str(p)] for r, p in read.files],
                     "defines": dict(scene.defines), "asset_root": scene.asset_root,
                     "max_depth": config.max_depth, **lens},
    }
    if read.stock is not None:
        meta["integrator"] = f"Mitsuba {read.stock[0]} ({read.stock[1]}), one render per band with a single-band specfilm"
    if lens.get("f_number"):
        meta["f_number"] = lens["f_number"]
    if read.focus_m:
        meta["scene_distance_m"] = read.focus_m
    return Built(meta=meta, loader=_loader(read, radius, scene), band_constant=False,
                 stock_integrator=None if read.stock is None else read.stock[0])


def _instantiate(mi, read: _Read, radius: float | None, film, sampler, integrator, *, sensor=None, extra=None):
    """The scene of ``read`` with our plugins in place of its own (see
    :func:`.loading.load_scene` for the arguments)."""
    state = mi.parser.ParserState(read.state)
    nodes = state.nodes
    root = nodes[0].props
    for key, j in _children(mi, nodes[0]):
        if nodes[j].type == mi.ObjectType.Integrator or (
                nodes[j].type == mi.ObjectType.Sensor and (j != read.sensor or sensor is not None)):
            del root[key]
    cam = nodes[read.sensor].props
    for key, j in _children(mi, nodes[read.sensor]):
        if nodes[j].type in (mi.ObjectType.Film, mi.ObjectType.Sampler):
            del cam[key]
    if radius is not None:
        cam["aperture_radius"] = float(radius)
    try:
        if sensor is not None:
            root["cfa_sensor"] = mi.load_dict({**sensor, "film": film, "sampler": sampler})
        else:
            cam["film"] = mi.load_dict(film)
            cam["sampler"] = mi.load_dict(sampler)
        root["cfa_integrator"] = mi.load_dict(integrator)
        for name, shape in (extra or {}).items():
            root[name] = mi.load_dict(shape)
        return mi.parser.instantiate(mi.parser.ParserConfig(mi.variant()), state)
    except Exception as exc:  # Mitsuba reports plugin errors as RuntimeError
        raise CfaMitsubaError(f"Mitsuba cannot load the scene {str(read.scan.main)!r}: {one_line(exc, 300)}") from None


#: (scene identity, variant) of the scene files this process has seen load in a child process.
_LOADS_ELSEWHERE: set[tuple[str, str]] = set()
#: Exit status of :mod:`.loadcheck` for a scene Mitsuba refuses (its message is on stderr).
LOADCHECK_REFUSED = 3


def load_check(path, allow_outside_paths: bool, variant: str, defines=(), asset_root=None) -> None:
    """Instantiate the scene file at ``path`` once, with stock film, sampler
    and integrator (the child side of :func:`_loads_elsewhere`)."""
    mi = _variant.load(variant)
    read = _read(Path(path), allow_outside_paths, xmlscan.parse_defines(defines), xmlscan.check_asset_root(asset_root))
    film, sampler, integrator = inspect_settings(8, 8)
    _instantiate(mi, read, None, film, sampler, integrator)


def _loads_elsewhere(read: _Read, scene: Scene, variant: str) -> None:
    """Load the scene in a child process before it is loaded in this one.

    Needed because when Mitsuba 3.9 fails part way through instantiating a
    scene (an unknown plugin or a bad parameter after an area light was
    built), the half-built emitters stay in Dr.Jit's registry after their
    shapes are freed; the next scene rendered in the same process calls
    them and crashes (seen as a segmentation fault in
    ``Scene.pdf_emitter_direction``).  A file that fails, or crashes
    Mitsuba, in the child is refused here without touching this process;
    one that loads is loaded here.  About 1 s per scene file and variant,
    once per process.
    """
    key = (json.dumps(scene.identity, sort_keys=True), variant)  # the files' content hashes, from user_scene
    if key in _LOADS_ELSEWHERE:
        return
    cmd = [sys.executable, "-m", "cfa_mitsuba.render.loadcheck", variant, str(read.scan.main)]
    if scene.allow_outside_paths:
        cmd.append("--allow-outside-paths")
    if scene.asset_root is not None:
        cmd += ["--asset-root", scene.asset_root]
    for name, value in scene.defines:
        cmd += [f"--define={name}={value}"]
    proc = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if proc.returncode != 0:
        lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
        if proc.returncode == LOADCHECK_REFUSED and lines:
            raise CfaMitsubaError(lines[-1])
        how = (f"signal {-proc.returncode}" if proc.returncode < 0 else f"exit status {proc.returncode}")
        last = f": {lines[-1][:300]}" if lines else ""
        raise CfaMitsubaError(f"Mitsuba failed while loading the scene {str(read.scan.main)!r} ({how}){last}")
    _LOADS_ELSEWHERE.add(key)


def _loader(read: _Read, radius: float | None, scene: Scene):
    def load(mi, film, sampler, integrator, *, sensor=None, extra=None):
        _loads_elsewhere(read, scene, mi.variant())
        return _instantiate(mi, read, radius, film, sampler, integrator, sensor=sensor, extra=extra)

    return load
