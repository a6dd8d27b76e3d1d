"""Study configs: TOML files, validated before any work starts.

A config names the scenes, CFAs, demosaicing methods and luminances to run,
the optics, sensor and image-processing settings, the render quality, the
normalisation ranges and the outputs.  Every key is checked: an unknown key,
a wrong type or an impossible value is refused with the key's dotted path and
the reason, e.g. ``quick.toml: sensor.pixel_pitch_um: must be a positive
number (got -1)``.  ``configs/quick.toml`` and ``configs/paper.toml`` are
complete, commented examples; docs/study.md lists every key.

Paths inside a config (custom CFA TOML files, user scene XML files) are
relative to the config file.
"""

from __future__ import annotations

__all__ = ["StudyConfig", "SceneSpec", "SweepSpec", "load_config", "parse_config"]

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CfaMitsubaError
from .checker import _Checker, _typename, read_toml
from .sweeps import SweepSpec, _sweeps
from ..io.validate import safe_name

from ..metrics import metrics_for_scene

#: Metrics a user scene feeds (the image metrics of DESIGN.md), from the metric records.
IMAGE_METRICS = metrics_for_scene("", natural=True)
#: How a study chooses the exposure: 'reference' (ISETCam's auto exposure,
#: chosen once at the reference luminance and kept at every luminance: the
#: camera of a fixed scene brightness, the default), 'each' (auto exposure at
#: each luminance, ISETCam's default in a sweep), 'fixed' (the given time).
EXPOSURE_POLICIES = ("reference", "each", "fixed")
#: Noise realisations of every capture unless a config says otherwise (each
#: value is their mean with a 95 % interval: study/intervals.py).
DEFAULT_SEEDS = 3


@dataclass(frozen=True)
class SceneSpec:
    """One scene of a study: a built-in name or a user's Mitsuba XML.

    ``render`` holds the render settings that differ from the scene's
    defaults (width, height, spp, oversample, seed, ...), passed to the
    render stage as keywords.
    """

    name: str
    file: str | None = None
    render: dict = field(default_factory=dict)
    metrics: tuple[str, ...] = ()


@dataclass(frozen=True)
class StudyConfig:
    """A validated study (see :func:`load_config`)."""

    name: str
    description: str
    path: str | None
    seed: int
    scenes: tuple[SceneSpec, ...]
    cfas: tuple[str, ...]
    demosaics: tuple[str, ...]
    luminances: tuple[float, ...]
    sweeps: tuple[SweepSpec, ...]
    render: dict
    optics: dict
    sensor: dict
    capture: dict
    isp: dict
    mean_match: bool
    ranges: dict
    clip_scores: bool
    seeds: int
    range_policy: str
    output: dict
    workers: int | None
    metric_options: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    def chain_settings(self):
        """The :class:`~.chain.ChainSettings` of this study (all but the axes)."""
        from ..optics import OpticsParams
        from ..sensor.params import SensorParams
        from .chain import ChainSettings

        return ChainSettings(
            optics=OpticsParams(**self.optics), sensor=SensorParams(**self.sensor),
            noise=self.capture.get("noise", "all"),
            reference_luminance_cd_m2=(None if self.capture.get("exposure_policy") == "each"
                                       else float(self.capture.get("reference_luminance_cd_m2", 100.0))),
            isp=dict(self.isp), mean_match=self.mean_match,
            spectra_sets=dict(self.capture.get("spectra_sets", {})), metric_options=dict(self.metric_options))

    def base_condition(self, luminance: float | None = None):
        """The study's own condition (no sweep) at ``luminance`` (default: the first)."""
        lum = self.luminances[0] if luminance is None else luminance
        return self.chain_settings().base_condition(luminance=lum, exposure=self.capture.get("exposure", "auto"),
                                                    seed=self.seed)


# Render settings a config may override per scene, with their checks.
def _scene_access(ck, c: dict, key: str, base: Path) -> dict:
    """A custom scene's ``defines`` (a table of its ``$name`` parameters, as
    ``render --define``) and ``asset_root`` (one shared folder its files may
    be in, relative to the config, as ``render --asset-root``)."""
    from ..render.xmlscan import check_asset_root, parse_defines

    out = {}
    try:
        if "defines" in c:
            if not isinstance(c["defines"], dict):
                ck.fail(f"{key}.defines", "must be a table of NAME = value")
            out["defines"] = dict(parse_defines(c["defines"]))
        if "asset_root" in c:
            out["asset_root"] = check_asset_root(base / ck.string(c["asset_root"], f"{key}.asset_root"))
    except CfaMitsubaError as exc:
        ck.fail(f"{key}.{'asset_root' if 'asset-root' in str(exc) else 'defines'}", str(exc))
    return out


_RENDER_KEYS = {
    "width": ("integer", 1), "height": ("integer", 1), "spp": ("integer", 1),
    "oversample": ("integer", 1), "seed": ("integer", 0), "fov": ("number", None), "max_depth": ("integer", 1),
}


def _render_overrides(ck: _Checker, data, key: str) -> dict:
    ck.table(data, key, _RENDER_KEYS)
    out = {}
    for k, v in data.items():
        kind, lo = _RENDER_KEYS[k]
        if kind == "integer":
            out[k] = ck.integer(v, f"{key}.{k}", lo)
        else:
            out[k] = ck.number(v, f"{key}.{k}", positive=True, maximum=179.0)
    return out


def _dataclass_table(ck: _Checker, data, key: str, cls, extra: dict) -> dict:
    """Check a table against a params dataclass's fields (type by default
    value) plus ``extra`` {name: checker}; the dataclass's own validation
    then runs on the whole set so impossible combinations are caught too."""
    names = {f.name: f for f in dataclasses.fields(cls)}
    allowed = {**names, **extra}
    ck.table(data, key, allowed)
    params, rest = {}, {}
    for k, v in data.items():
        path = f"{key}.{k}"
        if k in extra:
            rest[k] = extra[k](v, path)
            continue
        default = names[k].default
        if isinstance(default, bool):
            params[k] = ck.boolean(v, path)
        elif isinstance(default, int):
            params[k] = ck.integer(v, path, 0)
        elif isinstance(default, float):
            params[k] = ck.number(v, path)
        elif isinstance(v, dict):  # per-channel values ({R = 1.5, ...}): the dataclass checks them
            params[k] = v
        elif isinstance(v, list):  # per-band values
            params[k] = tuple(ck.number(x, f"{path}[{i}]") for i, x in enumerate(v))
        else:
            params[k] = v if isinstance(v, (int, float, str)) and not isinstance(v, bool) else ck.fail(
                path, f"must be a number, got {_typename(v)}")
    try:
        cls(**params)
    except CfaMitsubaError as exc:
        ck.fail(key, str(exc))
    except TypeError as exc:  # a field the dataclass rejects
        ck.fail(key, str(exc))
    return {**params, **rest}


def _sensor_preset(ck: _Checker, data):
    """(the [sensor] table without ``preset``, the preset or None):
    ``sensor = "imx363"`` or ``[sensor] preset = "imx363"`` starts from a
    measured preset's pixel parameters (``cfa-mitsuba list sensors``); the
    CFAs keep their own spectra sets."""
    from ..sensor import get_sensor_preset

    name = None
    if isinstance(data, str):
        name, data = data, {}
    elif isinstance(data, dict) and "preset" in data:
        data = dict(data)
        name = ck.string(data.pop("preset"), "sensor.preset")
    if name is None:
        return data, None
    try:
        return data, get_sensor_preset(name)
    except CfaMitsubaError as exc:
        ck.fail("sensor" if isinstance(data, dict) and not data else "sensor.preset", str(exc))


def _sensor_values(ck: _Checker, preset, given: dict, cfas, base: Path) -> dict:
    """The [sensor] values over the preset's, checked together; an IR-cut
    CSV resolved against the config's folder; a base readout that every
    CFA of the study can use."""
    from ..sensor import get_cfa
    from ..sensor.params import SensorParams
    from ..sensor.readout import readout_applies

    values = dict(given)
    if preset is not None:
        values = {**{f.name: getattr(preset.params, f.name) for f in dataclasses.fields(SensorParams)}, **given}
    ir = values.get("ir_cut", "")
    if isinstance(ir, str) and ir not in ("", "none"):
        f = base / ir
        if not f.is_file():
            ck.fail("sensor.ir_cut", f"no such file {str(f)!r} (give '', 'none' or a CSV of wavelength_nm, "
                                     "transmittance)")
        values["ir_cut"] = str(f.resolve())
    try:
        SensorParams(**values)
    except (CfaMitsubaError, TypeError) as exc:
        ck.fail("sensor", str(exc))
    readout = values.get("readout", "full")
    for i, c in enumerate(cfas):
        if not readout_applies(get_cfa(c).pattern, readout):
            ck.fail("sensor.readout", f"{readout!r} applies to the block layouts (quad-bayer, nona, tetra2); "
                                      f"cfas[{i}] {c!r} has no same-colour blocks (sweep readout instead: "
                                      "[[sweep]] readout = [...] reads the other CFAs at 'full')")
    return values


def _spectra_map(ck: _Checker, value, key: str) -> dict:
    """``[sensor.spectra_sets]``: {a CFA's own spectra set: the set to use
    instead} for every CFA of the study (configs/paper-isetcam.toml maps the
    paper's families to their ``*-raw`` sets, ISETCam's way of using them)."""
    from ..sensor import list_spectra_sets

    known = tuple(list_spectra_sets())
    if not isinstance(value, dict):
        ck.fail(key, f"must be a table {{set = \"replacement\"}}, got {_typename(value)}")
    for own, new in value.items():
        ck.string(own, f"{key} (key)", known)
        ck.string(new, f"{key}.{own}", known)
    return dict(value)


def parse_config(data: dict, *, where: str = "config", base: Path | None = None) -> StudyConfig:
    """Validate a config already parsed from TOML; see :func:`load_config`."""
    from .. import isp, render, sensor
    from ..optics import OpticsParams
    from ..sensor.params import NOISE_MODES, SensorParams
    from .measured_scenes import image_scene_spec
    from .ranking import DEFAULT_POLICY, POLICIES
    from .scoring import DEFAULT_RANGES

    ck = _Checker(where)
    base = base or Path(".")
    top = {
        "name": None, "description": None, "seed": None, "scenes": None, "custom_scenes": None, "cfas": None,
        "demosaics": None, "luminances": None, "sweep": None, "render": None, "optics": None, "sensor": None,
        "isp": None, "mean_match": None, "normalisation": None, "output": None, "workers": None, "seeds": None,
        "metrics": None,
    }
    ck.table(data, "", top)
    for required in ("scenes", "cfas", "demosaics"):
        if required not in data and not (required == "scenes" and "custom_scenes" in data):
            ck.fail(required, "missing (required)")

    name, description, seed, workers = ck.header(data)
    seeds = ck.integer(data.get("seeds", DEFAULT_SEEDS), "seeds", 1)

    # --- render ---------------------------------------------------------
    known_scenes = [n for n, _ in render.list_scenes()]
    render_cfg = data.get("render", {})
    render_allowed = {"variant": None, "bands": None, **{s: None for s in known_scenes}}
    ck.table(render_cfg, "render", render_allowed)
    render_common = {}
    if "variant" in render_cfg:
        render_common["variant"] = ck.string(render_cfg["variant"], "render.variant",
                                             ("auto", "cuda_ad_spectral", "llvm_ad_spectral", "scalar_spectral"))
        if render_common["variant"] == "auto":
            del render_common["variant"]
    if "bands" in render_cfg:
        from ..spectra import parse_band_grid

        try:
            render_common["bands"] = ck.string(render_cfg["bands"], "render.bands")
            parse_band_grid(render_common["bands"])
        except CfaMitsubaError as exc:
            ck.fail("render.bands", str(exc))

    # --- scenes ---------------------------------------------------------
    scenes = []
    for i, s in enumerate(ck.string_list(data.get("scenes", []), "scenes", allow_empty=True)):
        if s not in known_scenes:
            ck.fail(f"scenes[{i}]", f"unknown scene {s!r} (known: {', '.join(known_scenes)}; "
                                    "user XML scenes go under [[custom_scenes]])")
        over = _render_overrides(ck, render_cfg.get(s, {}), f"render.{s}")
        scenes.append(SceneSpec(s, None, over, metrics_for_scene(s)))
    custom = data.get("custom_scenes", [])
    if not isinstance(custom, list):
        ck.fail("custom_scenes", "must be an array of tables ([[custom_scenes]])")
    for i, c in enumerate(custom):
        key = f"custom_scenes[{i}]"
        if isinstance(c, dict) and "image" in c:  # a measured spectral image (study/measured_scenes.py)
            iname, image, opts = image_scene_spec(ck, c, key, base, [*known_scenes, *(s.name for s in scenes)])
            scenes.append(SceneSpec(iname, image, opts, IMAGE_METRICS))
            continue
        ck.table(c, key, {"name": None, "file": None, "allow_outside_paths": None, "defines": None, "asset_root": None,
                          **_RENDER_KEYS})
        cname = ck.string(c.get("name"), f"{key}.name")
        if safe_name(cname) != cname:  # it names folders under details/: a label, never a path
            ck.fail(f"{key}.name", f"must be a label of letters, digits, '-', '_' and inner '.' (got {cname!r})")
        if "file" not in c:
            ck.fail(f"{key}.file", "missing (the scene's Mitsuba XML file, or image = a measured spectral image)")
        f = base / ck.string(c["file"], f"{key}.file")
        if not f.is_file():
            ck.fail(f"{key}.file", f"no such file {str(f)!r}")
        if cname in known_scenes or any(s.name == cname for s in scenes):
            ck.fail(f"{key}.name", f"{cname!r} is already a scene name")
        access = ("name", "file", "allow_outside_paths", "defines", "asset_root")
        over = _render_overrides(ck, {k: v for k, v in c.items() if k not in access}, key)
        over.update(_scene_access(ck, c, key, base))
        if "allow_outside_paths" in c:  # the scene may name files outside its folder
            if not isinstance(c["allow_outside_paths"], bool):
                ck.fail(f"{key}.allow_outside_paths", "must be true or false")
            over["allow_outside_paths"] = c["allow_outside_paths"]
        scenes.append(SceneSpec(cname, str(f.resolve()), over, IMAGE_METRICS))
    if not scenes:
        ck.fail("scenes", "no scenes to run")
    from .budget import check_scenes

    check_scenes(ck.fail, scenes, render_common)  # renders and tasks within the limits, before any work

    # --- CFAs, demosaics, luminances -----------------------------------
    cfas = []
    for i, c in enumerate(ck.string_list(data["cfas"], "cfas")):
        if c.lower().endswith(".toml"):
            p = base / c
            try:
                sensor.load_cfa_toml(p)
            except CfaMitsubaError as exc:
                ck.fail(f"cfas[{i}]", str(exc))
            cfas.append(str(p.resolve()))
        else:
            if c not in sensor.list_cfas():
                ck.fail(f"cfas[{i}]", f"unknown CFA {c!r} (known: {', '.join(sensor.list_cfas())}; or a .toml file)")
            cfas.append(c)
    known_demosaics = [n for n, _ in isp.list_demosaics()]
    demosaics = ck.string_list(data["demosaics"], "demosaics")
    for i, d in enumerate(demosaics):
        if d not in known_demosaics:
            ck.fail(f"demosaics[{i}]", f"unknown demosaicing method {d!r} (known: {', '.join(known_demosaics)})")
    luminances = ck.number_list(data.get("luminances", [100.0]), "luminances")

    sweeps = tuple(_sweeps(ck, data.get("sweep", []), scenes))

    # --- optics / sensor / isp -----------------------------------------
    optics = _dataclass_table(ck, data.get("optics", {}), "optics", OpticsParams, {})
    capture_extra = {
        "noise": lambda v, k: ck.string(v, k, NOISE_MODES),
        "exposure": lambda v, k: v if v == "auto" else ck.number(v, k, positive=True),
        "reference_luminance_cd_m2": lambda v, k: ck.number(v, k, positive=True),
        "exposure_policy": lambda v, k: ck.string(v, k, EXPOSURE_POLICIES),
        "spectra_sets": lambda v, k: _spectra_map(ck, v, k),
    }
    sensor_cfg, preset = _sensor_preset(ck, data.get("sensor", {}))
    sensor_all = _dataclass_table(ck, sensor_cfg, "sensor", SensorParams, capture_extra)
    capture = {k: sensor_all.pop(k) for k in list(sensor_all) if k in capture_extra}
    sensor_all = _sensor_values(ck, preset, sensor_all, cfas, base)
    if preset is not None:
        capture["sensor_preset"] = preset.name
    policy = capture.get("exposure_policy", "reference")
    fixed = capture.get("exposure", "auto") != "auto"
    if policy == "fixed" and not fixed:
        ck.fail("sensor.exposure", "exposure_policy 'fixed' needs an exposure time in seconds here")
    if policy != "fixed" and fixed:
        ck.fail("sensor.exposure_policy", f"a fixed exposure ({capture['exposure']} s) needs "
                                          "exposure_policy = \"fixed\" (or exposure = \"auto\")")
    if policy == "each" and "reference_luminance_cd_m2" in capture:
        ck.fail("sensor.reference_luminance_cd_m2", "exposure_policy 'each' chooses the exposure at each "
                                                   "luminance: a reference luminance does not apply")
    isp_cfg = data.get("isp", {})
    ck.table(isp_cfg, "isp", {"white_balance": None, "white_preserving": None, "pocs_iterations": None,
                              "colour_fit": None, "regularise": None, "clip_highlights": None})
    isp_opts = {}
    if "white_balance" in isp_cfg:
        isp_opts["white_balance"] = ck.string(isp_cfg["white_balance"], "isp.white_balance",
                                              ("illuminant", "gray-world"))
    if "white_preserving" in isp_cfg:
        isp_opts["white_preserving"] = ck.boolean(isp_cfg["white_preserving"], "isp.white_preserving")
    for flag in ("regularise", "clip_highlights"):  # isp.process's switches (docs/isp.md)
        if flag in isp_cfg:
            isp_opts[flag] = ck.boolean(isp_cfg[flag], f"isp.{flag}")
    if "colour_fit" in isp_cfg:
        isp_opts["colour_fit"] = ck.string(isp_cfg["colour_fit"], "isp.colour_fit", isp.COLOUR_FITS)
    if "pocs_iterations" in isp_cfg:
        isp_opts["pocs_iterations"] = ck.integer(isp_cfg["pocs_iterations"], "isp.pocs_iterations", 1)
    mean_match = ck.boolean(data.get("mean_match", True), "mean_match")
    from .metric_options import metric_options

    options = metric_options(ck, data.get("metrics", {}))

    # --- normalisation --------------------------------------------------
    norm = data.get("normalisation", {})
    ck.table(norm, "normalisation", {"clip": None, "ranges": None, "policy": None})
    clip = ck.boolean(norm.get("clip", True), "normalisation.clip")
    policy = ck.string(norm.get("policy", DEFAULT_POLICY), "normalisation.policy", POLICIES)
    ranges_in = norm.get("ranges", {})
    ck.table(ranges_in, "normalisation.ranges", {m: None for m in DEFAULT_RANGES})
    ranges = {}
    for m, v in ranges_in.items():
        key = f"normalisation.ranges.{m}"
        if not isinstance(v, list) or len(v) != 2:
            ck.fail(key, "must be [worst, best], the values that score 0 and 1")
        worst, best = ck.number(v[0], f"{key}[0]"), ck.number(v[1], f"{key}[1]")
        if worst == best:
            ck.fail(key, "worst and best must differ")
        ranges[m] = (worst, best)
    # --- output ---------------------------------------------------------
    out_cfg = data.get("output", {})
    ck.table(out_cfg, "output", {"figures": None, "thumbnails": None, "report": None})
    figures = ck.string_list(out_cfg.get("figures", ["png", "svg"]), "output.figures", allow_empty=True)
    for i, f in enumerate(figures):
        if f not in ("png", "svg"):
            ck.fail(f"output.figures[{i}]", f"must be png or svg (got {f!r})")
    output = {
        "figures": figures,
        "thumbnails": ck.boolean(out_cfg.get("thumbnails", True), "output.thumbnails"),
        "report": ck.boolean(out_cfg.get("report", True), "output.report"),
    }

    return StudyConfig(
        name=name, description=description, path=None, seed=seed, scenes=tuple(scenes), cfas=tuple(cfas),
        demosaics=demosaics, luminances=luminances, sweeps=tuple(sweeps), render=render_common,
        optics=optics, sensor=sensor_all, capture=capture, isp=isp_opts, mean_match=mean_match,
        ranges=ranges, clip_scores=clip, output=output, workers=workers, seeds=seeds, range_policy=policy,
        metric_options=options,
    )


def load_config(path) -> StudyConfig:
    """Read and validate a study config (TOML).

    Raises :class:`~cfa_mitsuba.errors.CfaMitsubaError` naming the file and
    the offending key for any problem, before any work starts.
    """
    p, data = read_toml(path, "config file")
    cfg = parse_config(data, where=p.name, base=p.parent)
    return dataclasses.replace(cfg, path=str(p.resolve()))
