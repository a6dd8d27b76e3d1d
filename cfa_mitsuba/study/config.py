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

__all__ = ["StudyConfig", "SceneSpec", "SweepSpec", "load_config", "parse_config", "IMAGE_METRICS",
           "exposure_program_of"]

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CfaMitsubaError
from .checker import _Checker, _typename, read_toml
from .sweeps import SweepSpec, _sweeps

from .scene_specs import IMAGE_METRICS, SceneSpec, parse_scenes, render_common as render_common_of  # noqa: F401

#: Noise realisations of every capture unless a config says otherwise (each
#: value is their mean with a 95 % interval: study/intervals.py).
DEFAULT_SEEDS = 3
#: Independent renders (sampler seeds) of every path-traced scene unless a
#: config says otherwise (``render_seeds``; study/runner.py ``path_traced``).
DEFAULT_RENDER_SEEDS = 1


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
    demosaic_options: dict = field(default_factory=dict)
    render_seeds: int = DEFAULT_RENDER_SEEDS
    worker_max_tasks: int | None = None  # a local worker is recycled after this many tasks (study.executors)
    worker_max_memory: int | None = None  # ... or once its resident memory passes this many bytes
    #: the :class:`~cfa_mitsuba.sensor.exposure_program.ExposureProgram`,
    #: parsed once from ``[sensor]`` (None: the program's defaults)
    exposure_program: object = None

    def __post_init__(self):
        if self.exposure_program is None:
            from ..sensor.exposure_program import ExposureProgram

            object.__setattr__(self, "exposure_program", ExposureProgram())

    def to_dict(self) -> dict:
        """The config as run (config.json): the exposure program's keys in
        ``capture``, where ``[sensor]`` gives them."""
        out = dataclasses.asdict(self)
        del out["exposure_program"]
        out["capture"] = {**out["capture"], **self.exposure_program.config_keys()}
        return out

    def chain_settings(self):
        """The :class:`~.chain.ChainSettings` of this study (all but the axes),
        built once: every task, condition and table of the study shares it."""
        if "_chain_settings" not in self.__dict__:
            from ..optics import OpticsParams
            from ..sensor.params import SensorParams
            from .chain import ChainSettings

            self.__dict__["_chain_settings"] = ChainSettings(
                optics=OpticsParams(**self.optics), sensor=SensorParams(**self.sensor),
                noise=self.capture.get("noise", "all"), exposure_program=self.exposure_program,
                isp=dict(self.isp), mean_match=self.mean_match,
                spectra_sets=dict(self.capture.get("spectra_sets", {})), metric_options=dict(self.metric_options),
                demosaic_options=dict(self.demosaic_options))
        return self.__dict__["_chain_settings"]

    def base_condition(self, luminance: float | None = None):
        """The study's own condition (no sweep) at ``luminance`` (default: the first)."""
        lum = self.luminances[0] if luminance is None else luminance
        return self.chain_settings().base_condition(luminance=lum, exposure=self.capture.get("exposure", "auto"),
                                                    seed=self.seed)


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


def _sensor_preset(ck: _Checker, data, base: Path = Path(".")):
    """(the [sensor] table without ``preset``, the preset or None):
    ``sensor = "imx363"`` or ``[sensor] preset = "imx363"`` starts from a
    measured preset's pixel parameters (``cfa-mitsuba list sensors``), or a
    sensor file's (``sensor = "my_sensor.toml"``, relative to the config's
    folder); the CFAs keep their own spectra sets."""
    from ..sensor import get_sensor_preset

    name = None
    if isinstance(data, str):
        name, data = data, {}
    elif isinstance(data, dict) and "preset" in data:
        data = dict(data)
        name = ck.string(data.pop("preset"), "sensor.preset")
    if name is None:
        return data, None
    if name.lower().endswith(".toml") and not Path(name).is_absolute():
        name = str((base / name).resolve())
    try:
        return data, get_sensor_preset(name)
    except CfaMitsubaError as exc:
        ck.fail("sensor" if isinstance(data, dict) and not data else "sensor.preset", str(exc))


def _sensor_values(ck: _Checker, preset, given: dict, cfas, base: Path) -> dict:
    """The [sensor] values over the preset's, checked together; an IR-cut
    CSV resolved against the config's folder; a base readout that every
    CFA of the study can use."""
    from ..sensor import get_cfa
    from ..sensor.params import SensorParams, check_channel_names
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
        check_channel_names(values, {ch for c in cfas for ch in get_cfa(c).channels}, "any CFA of this study")
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


def _cfas(ck: _Checker, value, base: Path) -> list[str]:
    """``cfas``: registered names, or CFA TOML files (resolved paths)."""
    from .. import sensor

    cfas = []
    for i, c in enumerate(ck.string_list(value, "cfas")):
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
    return cfas


def _demosaics(ck: _Checker, value, isp_cfg: dict) -> tuple[tuple[str, ...], dict]:
    """``demosaics``: a list of method names, or ``[demosaics.<name>]``
    tables giving each method's options (checked against the method's
    signature as ``[metrics.<name>]`` is).  The old ``[isp]
    pocs_iterations`` is ``[demosaics.pocs] iterations``."""
    from ..isp import list_demosaics
    from ..isp.demosaic import demosaic_parameters
    from .metric_options import function_options

    known = [n for n, _ in list_demosaics()]
    if isinstance(value, dict):
        ck.table(value, "demosaics", {n: None for n in known})
        if not value:
            ck.fail("demosaics", "names no demosaicing method")
        names = tuple(value)
        options = {n: function_options(ck, o, f"demosaics.{n}", demosaic_parameters(n)) for n, o in value.items()}
    else:
        names = ck.string_list(value, "demosaics")
        for i, d in enumerate(names):
            if d not in known:
                ck.fail(f"demosaics[{i}]", f"unknown demosaicing method {d!r} (known: {', '.join(known)})")
        options = {}
    if "pocs_iterations" in isp_cfg:
        if "iterations" in options.get("pocs", {}):
            ck.fail("isp.pocs_iterations", "give [demosaics.pocs] iterations only (pocs_iterations is its old name)")
        its = ck.integer(isp_cfg["pocs_iterations"], "isp.pocs_iterations", 1)
        options.setdefault("pocs", {})["iterations"] = its
    return names, {n: o for n, o in options.items() if o}


def _isp(ck: _Checker, isp_cfg) -> dict:
    """``[isp]``: white balance, the colour fit, the switches, each ISP axis's base value (its record checks it)."""
    from .. import isp
    from .axes import AXES

    isp_axes = {a.field: a for a in AXES.values() if a.applies_to == "isp"}
    ck.table(isp_cfg, "isp", {"white_balance": None, "white_preserving": None, "pocs_iterations": None,
                              "colour_fit": None, "regularise": None, "clip_highlights": None,
                              "demosaic_precision": None, **dict.fromkeys(isp_axes)})
    out = {f: a.check(ck, isp_cfg[f], f"isp.{f}") for f, a in isp_axes.items() if f in isp_cfg}
    if "white_balance" in isp_cfg:
        out["white_balance"] = ck.string(isp_cfg["white_balance"], "isp.white_balance", ("illuminant", "gray-world"))
    for flag in ("white_preserving", "regularise", "clip_highlights"):  # isp.process's switches (docs/isp.md)
        if flag in isp_cfg:
            out[flag] = ck.boolean(isp_cfg[flag], f"isp.{flag}")
    if "colour_fit" in isp_cfg:
        out["colour_fit"] = ck.string(isp_cfg["colour_fit"], "isp.colour_fit", isp.COLOUR_FITS)
    if "demosaic_precision" in isp_cfg:
        from ..isp.demosaic import PRECISIONS

        out["demosaic_precision"] = ck.string(isp_cfg["demosaic_precision"], "isp.demosaic_precision",
                                              tuple(PRECISIONS))
    return out


def one_f_number(optics_table):
    """The one place a study's f-number is decided (issue 46): every scene,
    built-in or a user's, is captured at ``[optics] f_number``, the optics
    default f/4 (:data:`cfa_mitsuba.optics.DEFAULT_F_NUMBER`) when the config
    gives none; ``f_number = "scene"`` asks for each scene's own lens (a
    render's sidecar: the puppy's thin lens is f/2), which is then what
    metrics.csv's ``f_number`` says per scene."""
    if not isinstance(optics_table, dict):
        return optics_table  # the table checker says what is wrong with it
    from ..optics import DEFAULT_F_NUMBER

    out = dict(optics_table)
    if "f_number" not in out:
        out["f_number"] = DEFAULT_F_NUMBER
    elif out["f_number"] == "scene":
        del out["f_number"]
    return out


#: The ``[sensor]`` keys of the exposure program (:class:`~cfa_mitsuba.sensor.exposure_program.ExposureProgram`).
_PROGRAM_KEYS = ("exposure_policy", "max_exposure_s", "max_analog_gain", "reference_luminance_cd_m2")


def exposure_program_of(config: dict | None):
    """The :class:`~cfa_mitsuba.sensor.exposure_program.ExposureProgram` a
    results folder's config.json describes: its ``capture`` keys (and, in a
    config.json written before ``capture`` held them, ``sensor``'s) over the
    program's own defaults; the defaults alone when they do not make a valid
    program.  The report reads a study's exposure from here, so no default
    of the program is written twice."""
    from ..sensor.exposure_program import ExposureProgram

    cfg = config or {}
    keys = {**(cfg.get("sensor") or {}), **(cfg.get("capture") or {})}
    try:
        return ExposureProgram.from_table({k: keys[k] for k in _PROGRAM_KEYS if keys.get(k) is not None})
    except (CfaMitsubaError, TypeError):
        return ExposureProgram()


def _optics_sensor(ck: _Checker, data: dict, cfas, base: Path) -> tuple[dict, dict, dict, object]:
    """(optics, sensor, capture, exposure program): ``[optics]``, ``[sensor]``
    (a preset and its overrides), the capture settings kept in ``[sensor]``
    (noise, exposure, spectra-set replacements) and its exposure program,
    parsed once."""
    from ..optics import OpticsParams
    from ..sensor.exposure_program import EXPOSURE_POLICIES, ExposureProgram
    from ..sensor.params import NOISE_MODES, SensorParams

    optics = _dataclass_table(ck, one_f_number(data.get("optics", {})), "optics", OpticsParams, {})
    capture_extra = {
        "noise": lambda v, k: ck.string(v, k, NOISE_MODES),
        "exposure": lambda v, k: v if v == "auto" else ck.number(v, k, positive=True),
        "reference_luminance_cd_m2": lambda v, k: ck.number(v, k, positive=True),
        "exposure_policy": lambda v, k: ck.string(v, k, EXPOSURE_POLICIES),
        "max_exposure_s": lambda v, k: ck.number(v, k, positive=True),
        "max_analog_gain": lambda v, k: _at_least_one(ck, v, k),
        "spectra_sets": lambda v, k: _spectra_map(ck, v, k),
    }
    sensor_cfg, preset = _sensor_preset(ck, data.get("sensor", {}), base)
    if isinstance(sensor_cfg, dict):  # a channel no CFA has is what is wrong, before its value is judged
        from ..sensor import get_cfa
        from ..sensor.params import check_channel_names

        try:
            check_channel_names({k: v for k, v in sensor_cfg.items() if isinstance(v, dict)},
                                {ch for c in cfas for ch in get_cfa(c).channels}, "any CFA of this study")
        except CfaMitsubaError as exc:
            ck.fail("sensor", str(exc))
    sensor_all = _dataclass_table(ck, sensor_cfg, "sensor", SensorParams, capture_extra)
    capture = {k: sensor_all.pop(k) for k in list(sensor_all) if k in capture_extra}
    sensor_all = _sensor_values(ck, preset, sensor_all, cfas, base)
    if preset is not None:
        capture["sensor_preset"] = preset.name
    policy = capture.get("exposure_policy", ExposureProgram.policy)
    fixed = capture.get("exposure", "auto") != "auto"
    if policy == "fixed" and not fixed:
        ck.fail("sensor.exposure", "exposure_policy 'fixed' needs an exposure time in seconds here")
    if policy != "fixed" and fixed:
        ck.fail("sensor.exposure_policy", f"a fixed exposure ({capture['exposure']} s) needs "
                                          "exposure_policy = \"fixed\" (or exposure = \"auto\")")
    if policy == "each" and "reference_luminance_cd_m2" in capture:
        ck.fail("sensor.reference_luminance_cd_m2", "exposure_policy 'each' chooses the exposure at each "
                                                   "luminance: a reference luminance does not apply")
    if policy in ("program", "bayer") and "reference_luminance_cd_m2" in capture:
        ck.fail("sensor.reference_luminance_cd_m2", f"exposure_policy {policy!r} meters each luminance: a "
                                                   "reference luminance applies to exposure_policy \"reference\" only")
    for key in ("max_exposure_s", "max_analog_gain"):
        if key in capture and policy not in ("program", "bayer"):
            ck.fail(f"sensor.{key}", f"applies to exposure_policy \"program\" or \"bayer\", not {policy!r}")
    program = ExposureProgram.from_table({k: capture.pop(k) for k in _PROGRAM_KEYS if k in capture})
    return optics, sensor_all, capture, program


def _worker_recycling(ck: _Checker, data: dict) -> tuple[int | None, int | None]:
    """``worker_max_tasks`` (an integer >= 1) and ``worker_max_memory`` (bytes,
    or a size such as "4G"), or None for the executor's defaults."""
    from ..io.limits import parse_size

    tasks = ck.integer(data["worker_max_tasks"], "worker_max_tasks", 1) if "worker_max_tasks" in data else None
    memory = data.get("worker_max_memory")
    if memory is not None:
        if isinstance(memory, bool) or not isinstance(memory, (int, str)):
            ck.fail("worker_max_memory", f"must be a size such as \"4G\" or a number of bytes, got {memory!r}")
        try:
            memory = parse_size(memory, "worker_max_memory")
        except CfaMitsubaError as exc:
            ck.fail("worker_max_memory", str(exc).split(": ", 1)[-1])
    return tasks, memory


def _at_least_one(ck: _Checker, v, key: str) -> float:
    x = ck.number(v, key, positive=True)
    if x < 1:
        ck.fail(key, f"must be at least 1 (got {x:g})")
    return x


def _normalisation(ck: _Checker, norm) -> tuple[bool, str, dict]:
    """``[normalisation]``: (clip, range policy, {metric: (worst, best)})."""
    from .ranking import DEFAULT_POLICY, POLICIES
    from .scoring import DEFAULT_RANGES

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
    return clip, policy, ranges


def _output(ck: _Checker, out_cfg) -> dict:
    """``[output]``: figure formats, thumbnails, the report."""
    ck.table(out_cfg, "output", {"figures": None, "thumbnails": None, "report": None})
    figures = ck.string_list(out_cfg.get("figures", ["png", "svg"]), "output.figures", allow_empty=True)
    for i, f in enumerate(figures):
        if f not in ("png", "svg"):
            ck.fail(f"output.figures[{i}]", f"must be png or svg (got {f!r})")
    return {"figures": figures, "thumbnails": ck.boolean(out_cfg.get("thumbnails", True), "output.thumbnails"),
            "report": ck.boolean(out_cfg.get("report", True), "output.report")}


_TOP_KEYS = ("name", "description", "seed", "scenes", "custom_scenes", "cfas", "demosaics", "luminances", "sweep",
             "render", "optics", "sensor", "isp", "mean_match", "normalisation", "output", "workers", "seeds",
             "metrics", "render_seeds", "worker_max_tasks", "worker_max_memory")


def parse_config(data: dict, *, where: str = "config", base: Path | None = None) -> StudyConfig:
    """Validate a config already parsed from TOML; see :func:`load_config`.
    Each table is checked by its own step, in the order the file reads."""
    from .. import render
    from .metric_options import metric_options

    ck = _Checker(where)
    base = base or Path(".")
    ck.table(data, "", dict.fromkeys(_TOP_KEYS))
    for required in ("scenes", "cfas", "demosaics"):
        if required not in data and not (required == "scenes" and "custom_scenes" in data):
            ck.fail(required, "missing (required)")
    name, description, seed, workers = ck.header(data)
    max_tasks, max_memory = _worker_recycling(ck, data)
    seeds = ck.integer(data.get("seeds", DEFAULT_SEEDS), "seeds", 1)
    render_seeds = ck.integer(data.get("render_seeds", DEFAULT_RENDER_SEEDS), "render_seeds", 1)
    render_cfg = data.get("render", {})
    render_common = render_common_of(ck, render_cfg, [n for n, _ in render.list_scenes()])
    scenes = parse_scenes(ck, data, render_cfg, render_common, base)
    cfas = _cfas(ck, data["cfas"], base)
    isp_cfg = data.get("isp", {})
    isp_opts = _isp(ck, isp_cfg)
    demosaics, demosaic_options = _demosaics(ck, data["demosaics"], isp_cfg)
    luminances = ck.number_list(data.get("luminances", [100.0]), "luminances")
    sweeps = tuple(_sweeps(ck, data.get("sweep", []), scenes))
    optics, sensor_all, capture, program = _optics_sensor(ck, data, cfas, base)
    from .physical import check_physical, check_realisations  # issue 27: values no camera meets, by key

    check_physical(ck.fail, luminances, sweeps, program)
    check_realisations(ck.fail, seeds, capture.get("noise", "all"))
    mean_match = ck.boolean(data.get("mean_match", True), "mean_match")
    options = metric_options(ck, data.get("metrics", {}))
    clip, policy, ranges = _normalisation(ck, data.get("normalisation", {}))
    output = _output(ck, data.get("output", {}))
    return StudyConfig(
        name=name, description=description, path=None, seed=seed, scenes=tuple(scenes), cfas=tuple(cfas),
        demosaics=demosaics, luminances=luminances, sweeps=sweeps, render=render_common,
        optics=optics, sensor=sensor_all, capture=capture, isp=isp_opts, mean_match=mean_match,
        ranges=ranges, clip_scores=clip, output=output, workers=workers, seeds=seeds, range_policy=policy,
        metric_options=options, demosaic_options=demosaic_options, render_seeds=render_seeds,
        worker_max_tasks=max_tasks, worker_max_memory=max_memory,
        exposure_program=program,
    )


def load_config(path) -> StudyConfig:
    """Read and validate a study config (TOML).

    Raises :class:`~cfa_mitsuba.errors.CfaMitsubaError` naming the file and
    the offending key for any problem, before any work starts.
    """
    p, data = read_toml(path, "config file")
    cfg = parse_config(data, where=p.name, base=p.parent)
    return dataclasses.replace(cfg, path=str(p.resolve()))
