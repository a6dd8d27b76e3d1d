"""Design configs: the search space, the objectives and the study the
candidates are measured in, validated before any work starts with the
study's checker (``design.toml: layout.alphabet: must not be empty``).

A config has five parts (docs/design.md lists every key):

* ``[layout]``: tile sizes, the filter alphabet, the spectra set of its
  letters, density bounds per letter, mirror folding;
* ``[spectra]`` (optional): parametric filters (``bandpass``: smooth
  band-pass transmittances with centre, width and peak; ``mixture``:
  non-negative mixtures of a spectra set's curves) for some letters;
* ``[search]``: the engine (exhaustive, NSGA-II, or auto), its sizes, how
  many candidates go through the full chain;
* ``[[objective]]`` / ``[[constraint]]``: study metrics on a scene, a
  luminance and a demosaic, minimised or maximised; constraints bound a
  metric by a number or by a named CFA's value in the same run;
* ``[study]``: an ordinary study config (docs/study.md) without
  ``luminances`` (taken from the objectives): scenes, demosaics, seeds,
  render sizes, sensor, and ``cfas``, the named CFAs compared with.
"""

from __future__ import annotations

__all__ = ["DesignConfig", "Objective", "SpectraSpec", "load_design", "parse_design", "PROXIES_OF",
           "MAX_EXHAUSTIVE", "ENGINES", "FAMILIES", "METHODS", "SNR10", "SNR10_SWEEP", "SNR10_BASES", "BEST", "ORIENTATIONS",
           "EDGE_METRICS"]

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from ..study.checker import _Checker, read_toml

#: The proxies (design/proxy.py) that predict each metric: where the
#: full-chain value comes from (colour fit, noise, frequency structure).
PROXIES_OF = {
    "delta-e": ("colour", "noise"), "delta-e76": ("colour", "noise"), "delta-l": ("noise",),
    "scielab": ("colour", "noise", "aliasing"), "scielab-interior": ("colour", "noise", "aliasing"),
    "ssim": ("noise", "aliasing"), "mdsi": ("noise", "aliasing"), "haarpsi": ("noise", "aliasing"),
    "mtf": ("blur",), "moire": ("aliasing",), "achromatic": ("noise",),
    "ysnr": ("noise",), "ysnr-area": ("noise_area",), "chroma_snr": ("noise",), "info-capacity": ("neg_capacity",),
    "snr10": ("snr10",),
}
#: The design objective read from a study's snr10.csv (study/snr.py), not
#: metrics.csv: the luminance (cd/m^2) at which YSNR reaches 10 on a
#: luminance sweep of the gray bar (``luminances``, default below).
SNR10 = "snr10"
SNR10_SWEEP = (0.3, 1.0, 3.0, 10.0, 30.0, 100.0)
#: ``basis``: the YSNR that snr10 reads (metrics/snr.py): per pixel, or
#: referred to an area (which a demosaic's smoothing does not raise), and
#: the proxy that predicts each.
SNR10_BASES = {"ysnr": "snr10", "ysnr-area": "snr10_area"}
#: ``demosaic = "best"``: per CFA, the best of the study's demosaics on that objective.
BEST = "best"
#: Raw layouts (alphabet ** pixels) per tile size that exhaustive search takes on.
MAX_EXHAUSTIVE = 50_000_000
ENGINES = ("auto", "exhaustive", "nsga2")
#: ``orientation``: the edge as rendered (near-vertical: horizontal
#: frequencies only), or the worse of it and the transposed tile's (the
#: near-horizontal edge's, ISO 12233's two directions; design/orientation.py).
ORIENTATIONS = ("vertical", "both")
#: The metrics measured across the slanted edge, which ``orientation`` applies to.
EDGE_METRICS = ("mtf", "info-capacity")
FAMILIES = ("bandpass", "mixture", "spline")
#: ``[design] method``: layouts (and parametric spectra) by the proxy's
#: search, or the spectra of one fixed layout by gradient (design/gradient_search.py).
METHODS = ("search", "gradient")


@dataclass(frozen=True)
class Objective:
    """One full-chain value: ``metric`` on ``scene`` at ``luminance`` with
    ``demosaic``; ``goal`` 'min' or 'max'.  As a constraint, ``bound`` is a
    number or a named CFA (its value in the same run) and ``goal`` says
    which side is allowed ('max': value <= bound)."""

    metric: str
    scene: str
    luminance: float
    demosaic: str
    goal: str
    bound: object = None
    sweep: tuple = ()        # snr10: the gray bar's luminances (cd/m^2)
    orientation: str = "vertical"  # an edge metric: the edge as rendered, or "both" (design/orientation.py)
    basis: str = "ysnr"      # snr10: the YSNR rows it reads, "ysnr" or "ysnr-area" (SNR10_BASES)

    @property
    def label(self) -> str:
        if self.metric == SNR10:
            basis = "" if self.basis == "ysnr" else f"/{self.basis}"
            return f"{self.metric}@{self.scene}{basis}/{self.demosaic}"
        both = "+transposed" if self.orientation == "both" else ""
        return f"{self.metric}@{self.scene}{both}/L{self.luminance:g}/{self.demosaic}"

    @property
    def unit(self) -> str:
        from ..metrics import get_metric

        return "cd/m^2" if self.metric == SNR10 else get_metric(self.metric).unit

    @property
    def title(self) -> str:
        """The axis name: metric, condition and unit (the report's)."""
        from ..metrics import get_metric

        dem = "best demosaic" if self.demosaic == BEST else self.demosaic
        unit = self.unit
        if self.metric == SNR10:
            which = "area-referred YSNR" if self.basis == "ysnr-area" else "YSNR"
            return f"SNR10: luminance at {which} 10 ({self.scene}, {dem}) [cd/m²]"
        rec = get_metric(self.metric)
        names = {"delta-e": "ΔE00", "mtf": "MTF50", "ysnr": "YSNR", "info-capacity": "information capacity"}
        scene = f"{self.scene}, worse of both directions" if self.orientation == "both" else self.scene
        return (f"{names.get(self.metric, rec.label)} ({scene}, {self.luminance:g} cd/m², {dem})"
                + (f" [{unit}]" if unit else ""))

    @property
    def proxies(self) -> tuple[str, ...]:
        if self.metric == SNR10:
            return (SNR10_BASES[self.basis],)
        return PROXIES_OF.get(self.metric, ("colour", "noise", "aliasing"))


@dataclass(frozen=True)
class SpectraSpec:
    """Parametric filters for ``letters``: ``family`` 'bandpass' with
    (centre_nm, width_nm, peak) bounds, or 'mixture' of ``basis`` (a spectra
    set) with weights in ``weight``."""

    family: str
    letters: tuple[str, ...]
    centre_nm: tuple[float, float] = (400.0, 700.0)
    width_nm: tuple[float, float] = (30.0, 200.0)
    peak: tuple[float, float] = (0.2, 1.0)
    basis: object = ""      # mixture: a spectra set's name, or a tuple of names (a dye library)
    weight: tuple[float, float] = (0.0, 1.0)
    knots: int = 12         # spline: cubic B-spline functions per letter


@dataclass(frozen=True)
class DesignConfig:
    name: str
    description: str
    path: str | None
    seed: int
    tiles: tuple[tuple[int, int], ...]
    alphabet: tuple[str, ...]
    spectra_set: str
    density: dict            # letter -> (min, max) fraction
    mirrors: bool
    spectra: SpectraSpec | None
    engine: dict             # (h, w) -> 'exhaustive' | 'nsga2'
    population: int
    generations: int
    full_chain: int
    agreement_sample: int
    objectives: tuple[Objective, ...]
    constraints: tuple[Objective, ...]
    study: object            # a StudyConfig; its cfas are the named CFAs compared with
    workers: int | None
    method: str = "search"   # [design] method (METHODS)
    gradient: object = None  # method = "gradient": its GradientSpec (design/gradient_search.py)


def _tiles(ck: _Checker, value) -> tuple:
    if not isinstance(value, list) or not value:
        ck.fail("layout.tiles", "must be a non-empty list of sizes like \"2x2\"")
    out = []
    for i, t in enumerate(value):
        key = f"layout.tiles[{i}]"
        try:
            h, w = (int(x) for x in ck.string(t, key).lower().split("x"))
        except ValueError:
            ck.fail(key, f"must be HEIGHTxWIDTH, e.g. \"4x4\" (got {t!r})")
        if not (1 <= h <= 16 and 1 <= w <= 16) or h * w < 2:
            ck.fail(key, f"tile {h}x{w} out of range (1..16 each side, at least 2 pixels)")
        if (h, w) in out:
            ck.fail(key, f"lists {h}x{w} twice")
        out.append((h, w))
    return tuple(out)


def _pair(ck: _Checker, v, key: str, lo=None, hi=None) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2:
        ck.fail(key, "must be [min, max]")
    a, b = ck.number(v[0], f"{key}[0]"), ck.number(v[1], f"{key}[1]")
    if a > b:
        ck.fail(key, f"min {a:g} above max {b:g}")
    if (lo is not None and a < lo) or (hi is not None and b > hi):
        ck.fail(key, f"must lie within [{lo:g}, {hi:g}] (got [{a:g}, {b:g}])")
    return a, b


def _layout(ck: _Checker, data: dict):
    from ..sensor import get_spectra_set, list_spectra_sets

    ck.table(data, "layout", {"tiles": None, "alphabet": None, "spectra_set": None, "density": None,
                              "mirrors": None})
    tiles = _tiles(ck, data.get("tiles"))
    if "alphabet" not in data:
        ck.fail("layout.alphabet", "missing (the filter letters, e.g. [\"R\", \"G\", \"B\"])")
    alphabet = ck.string_list(data["alphabet"], "layout.alphabet")
    if len(alphabet) < 2:
        ck.fail("layout.alphabet", "needs at least 2 letters")
    set_name = ck.string(data.get("spectra_set", "isetcam-rgb"), "layout.spectra_set", tuple(list_spectra_sets()))
    sset = get_spectra_set(set_name)
    density_in = data.get("density", {})
    ck.table(density_in, "layout.density", {a: None for a in alphabet})
    density = {a: _pair(ck, density_in[a], f"layout.density.{a}", 0.0, 1.0) if a in density_in else None
               for a in alphabet}
    for h, w in tiles:
        n = h * w
        lo = {a: (max(1, _ceil(d[0] * n)) if d else 1) for a, d in density.items()}
        hi = {a: (int(d[1] * n + 1e-9) if d else n) for a, d in density.items()}
        bad = next((a for a in alphabet if lo[a] > hi[a]), None)
        if bad or sum(lo.values()) > n or sum(hi.values()) < n:
            key = f"layout.density.{bad}" if bad else "layout.density"
            ck.fail(key, f"no {h}x{w} tile meets the density bounds (each letter needs between "
                         f"{', '.join(f'{a} {lo[a]}..{hi[a]}' for a in alphabet)} of {n} pixels)")
    mirrors = ck.boolean(data.get("mirrors", True), "layout.mirrors")
    return tiles, alphabet, set_name, sset, density, mirrors


def _ceil(x: float) -> int:
    import math

    return int(math.ceil(x - 1e-9))


def _spectra(ck: _Checker, data, alphabet, sset) -> SpectraSpec | None:
    from ..sensor import list_spectra_sets

    if data is None:
        missing = [a for a in alphabet if a not in sset.curves]
        if missing:
            ck.fail("layout.alphabet", f"letter {missing[0]!r} is not a filter of spectra set {sset.name!r} "
                                       f"(it has {', '.join(sset.letters)}); give it under [spectra]")
        return None
    ck.table(data, "spectra", {"family": None, "letters": None, "centre_nm": None, "width_nm": None, "peak": None,
                               "basis": None, "weight": None, "knots": None})
    family = ck.string(data.get("family", ""), "spectra.family", FAMILIES)
    letters = ck.string_list(data.get("letters", list(alphabet)), "spectra.letters")
    for i, a in enumerate(letters):
        if a not in alphabet:
            ck.fail(f"spectra.letters[{i}]", f"{a!r} is not in layout.alphabet")
    fixed = [a for a in alphabet if a not in letters and a not in sset.curves]
    if fixed:
        ck.fail("spectra.letters", f"letter {fixed[0]!r} has no curve in spectra set {sset.name!r}: make it free")
    if family == "spline":
        extra = [k for k in ("centre_nm", "width_nm", "peak", "basis", "weight") if k in data]
        if extra:
            ck.fail(f"spectra.{extra[0]}", "does not apply to family 'spline' (its curves are B-spline coefficients)")
        knots = ck.integer(data.get("knots", 12), "spectra.knots", 4)
        if knots > 60:
            ck.fail("spectra.knots", f"at most 60 functions over 380-720 nm (got {knots})")
        return SpectraSpec(family, letters, knots=knots)
    if "knots" in data:
        ck.fail("spectra.knots", "applies to family 'spline' only")
    if family == "bandpass":
        extra = [k for k in ("basis", "weight") if k in data]
        if extra:
            ck.fail(f"spectra.{extra[0]}", "applies to family 'mixture' only")
        return SpectraSpec(family, letters, _pair(ck, data.get("centre_nm", [400, 700]), "spectra.centre_nm", 350, 800),
                           _pair(ck, data.get("width_nm", [30, 200]), "spectra.width_nm", 5, 1000),
                           _pair(ck, data.get("peak", [0.2, 1.0]), "spectra.peak", 0.0, 1.0))
    extra = [k for k in ("centre_nm", "width_nm", "peak") if k in data]
    if extra:
        ck.fail(f"spectra.{extra[0]}", "applies to family 'bandpass' only")
    raw = data.get("basis", sset.name)
    if isinstance(raw, list):  # a dye library: several spectra sets' curves
        if not raw:
            ck.fail("spectra.basis", "must name at least one spectra set")
        basis = tuple(ck.string(b, f"spectra.basis[{i}]", tuple(list_spectra_sets())) for i, b in enumerate(raw))
    else:
        basis = ck.string(raw, "spectra.basis", tuple(list_spectra_sets()))
    weight = _pair(ck, data.get("weight", [0.0, 1.0]), "spectra.weight", 0.0, 10.0)
    if weight[1] <= 0:
        ck.fail("spectra.weight", "the largest weight must be positive")
    return SpectraSpec(family, letters, basis=basis, weight=weight)


def _objective(ck: _Checker, o, key: str, study, constraint: bool) -> Objective:
    from ..metrics import METRICS, get_metric

    allowed = {"metric": None, "scene": None, "luminance": None, "demosaic": None, "goal": None, "luminances": None,
               "orientation": None, "basis": None}
    if constraint:
        allowed.update(max=None, min=None)
    ck.table(o, key, allowed)
    known = [m for m in METRICS] + [SNR10]
    metric = ck.string(o.get("metric", ""), f"{key}.metric")
    if metric not in known:
        ck.fail(f"{key}.metric", f"unknown objective metric {metric!r} (known: {', '.join(known)})")
    if "luminances" in o and metric != SNR10:
        ck.fail(f"{key}.luminances", "applies to metric = \"snr10\" only (its gray-bar sweep)")
    if "basis" in o and metric != SNR10:
        ck.fail(f"{key}.basis", "applies to metric = \"snr10\" only (the YSNR it reads: \"ysnr\" or \"ysnr-area\")")
    basis = ck.string(o.get("basis", "ysnr"), f"{key}.basis", tuple(SNR10_BASES))
    fed_by = "ysnr" if metric == SNR10 else metric
    feeding = [s.name for s in study.scenes if fed_by in s.metrics or get_metric(fed_by).parent in s.metrics]
    if not feeding:
        ck.fail(f"{key}.metric", f"no scene of [study] feeds {metric!r}")
    scene = ck.string(o.get("scene", feeding[0]), f"{key}.scene", tuple(feeding))
    sweep = ()
    if metric == SNR10:
        if "luminance" in o:
            ck.fail(f"{key}.luminance", "snr10 is read off a sweep: give luminances = [...] (cd/m^2), not luminance")
        sweep = _snr10_sweep(ck, o, key)
        lum = float(min(sweep))
    else:
        lum = ck.number(o.get("luminance", study.luminances[0]), f"{key}.luminance", positive=True)
    if lum != study.luminances[0] and "scene" not in o and metric != SNR10:
        ck.fail(f"{key}.scene", "an objective at another luminance than the first objective's must name its scene")
    demosaic = ck.string(o.get("demosaic", study.demosaics[0]), f"{key}.demosaic", (*study.demosaics, BEST))
    default_goal = "min" if metric == SNR10 else ("max" if get_metric(metric).higher_is_better else "min")
    bound = None
    if constraint:
        if ("max" in o) == ("min" in o):
            ck.fail(key, "give exactly one of max = ... or min = ... (a number or a named CFA of [study] cfas)")
        side = "max" if "max" in o else "min"
        v = o[side]
        if isinstance(v, str):
            if v not in study.cfas:
                ck.fail(f"{key}.{side}", f"{v!r} is not one of [study] cfas ({', '.join(study.cfas)})")
            bound = v
        else:
            bound = ck.number(v, f"{key}.{side}")
        return Objective(metric, scene, lum, demosaic, side, bound, sweep, _orientation(ck, o, key, metric), basis)
    goal = ck.string(o.get("goal", default_goal), f"{key}.goal", ("min", "max"))
    return Objective(metric, scene, lum, demosaic, goal, sweep=sweep, orientation=_orientation(ck, o, key, metric),
                     basis=basis)


def _orientation(ck: _Checker, o: dict, key: str, metric: str) -> str:
    from ..metrics import get_metric

    value = ck.string(o.get("orientation", "vertical"), f"{key}.orientation", ORIENTATIONS)
    if value == "both" and (metric == SNR10 or (get_metric(metric).parent or metric) not in EDGE_METRICS):
        ck.fail(f"{key}.orientation", f"applies to the slanted edge's metrics ({', '.join(EDGE_METRICS)}), "
                                      f"not {metric!r}")
    return value


def _snr10_sweep(ck: _Checker, o: dict, key: str) -> tuple:
    v = o.get("luminances", list(SNR10_SWEEP))
    if not isinstance(v, list) or len(v) < 2:
        ck.fail(f"{key}.luminances", "must be a list of at least 2 luminances (cd/m^2) to find YSNR 10 between")
    return tuple(sorted({ck.number(x, f"{key}.luminances[{i}]", positive=True) for i, x in enumerate(v)}))


def parse_design(data: dict, *, where: str = "design", base: Path | None = None) -> DesignConfig:
    """Validate a design config already parsed from TOML (see :func:`load_design`)."""
    from ..study.config import parse_config

    ck = _Checker(where)
    base = base or Path(".")
    ck.table(data, "", {"name": None, "description": None, "seed": None, "layout": None, "spectra": None,
                        "search": None, "objective": None, "constraint": None, "study": None, "workers": None,
                        "design": None, "gradient": None})
    design = ck.table(data.get("design", {}), "design", {"method": None})
    method = ck.string(design.get("method", "search"), "design.method", METHODS)
    if "gradient" in data and method != "gradient":
        ck.fail("gradient", "applies to [design] method = \"gradient\" only")
    for required in ("layout", "objective", "study"):
        if required not in data:
            ck.fail(required, "missing (required)")
    name, description, seed, workers = ck.header(data)
    tiles, alphabet, set_name, sset, density, mirrors = _layout(ck, ck.table(data["layout"], "layout", {
        "tiles": None, "alphabet": None, "spectra_set": None, "density": None, "mirrors": None}))
    spectra = _spectra(ck, data.get("spectra"), alphabet, sset)

    search = data.get("search", {})
    ck.table(search, "search", {"engine": None, "population": None, "generations": None, "full_chain": None,
                                "agreement_sample": None, "max_exhaustive": None})
    engine = ck.string(search.get("engine", "auto"), "search.engine", ENGINES)
    limit = ck.integer(search.get("max_exhaustive", MAX_EXHAUSTIVE), "search.max_exhaustive", 1)
    engines = {}
    for h, w in tiles:
        raw = len(alphabet) ** (h * w)
        fits = raw <= limit and spectra is None and method == "search"
        if engine == "exhaustive" and not fits:
            why = ("continuous spectra need the stochastic engine" if spectra is not None else
                   f"{h}x{w} tiles of {len(alphabet)} letters are {raw:.3g} raw layouts, above the exhaustive "
                   f"limit {limit:.3g}")
            ck.fail("search.engine", f"'exhaustive' cannot search this space: {why}; use engine = \"nsga2\" "
                                     "(or \"auto\")")
        engines[(h, w)] = "exhaustive" if (engine == "exhaustive" or (engine == "auto" and fits)) else "nsga2"
        if method == "gradient":  # one fixed layout, its spectra by L-BFGS-B (design/gradient_search.py)
            engines[(h, w)] = "gradient"
    population = ck.integer(search.get("population", 40), "search.population", 4)
    generations = ck.integer(search.get("generations", 20), "search.generations", 1)
    full_chain = ck.integer(search.get("full_chain", 6), "search.full_chain", 1)
    sample = ck.integer(search.get("agreement_sample", 3), "search.agreement_sample", 0)

    # the study: the objectives' luminances become its luminances (scored)
    study_in = data["study"]
    if not isinstance(study_in, dict):
        ck.fail("study", "must be a table")
    if "luminances" in study_in:
        ck.fail("study.luminances", "set by the objectives' luminance (give luminance = ... per objective)")
    objs_in, cons_in = data["objective"], data.get("constraint", [])
    for key, v in (("objective", objs_in), ("constraint", cons_in)):
        if not isinstance(v, list) or (key == "objective" and not v):
            ck.fail(key, f"must be one or more [[{key}]] tables")
        for i, o in enumerate(v):
            if not isinstance(o, dict):
                ck.fail(f"{key}[{i}]", "must be a table")
            if "luminance" in o:
                ck.number(o["luminance"], f"{key}[{i}].luminance", positive=True)
    # the first objective's luminance is the study's; any other (scene,
    # luminance) an objective names is a sweep of that scene's metrics there
    lums = [float(o.get("luminance", 100.0)) for o in [*objs_in, *cons_in] if o.get("metric") != SNR10] or [100.0]
    sweeps = list(study_in.get("sweep", [])) if isinstance(study_in.get("sweep", []), list) else study_in["sweep"]
    extra: dict = {}
    for i, o in enumerate([*objs_in, *cons_in]):
        if o.get("metric") == SNR10:  # the gray bar's YSNR at every luminance of its sweep
            scene = o.get("scene", "gray-bar")
            for lum in _snr10_sweep(ck, o, f"objective[{i}]"):
                extra.setdefault((scene, lum), []).append("ysnr")
            continue
        lum = float(o.get("luminance", lums[0]))
        if lum != lums[0] and isinstance(o.get("scene"), str) and isinstance(o.get("metric"), str):
            extra.setdefault((o["scene"], lum), []).append(o["metric"])
    from ..metrics import METRICS

    for (scene, lum), ms in extra.items():
        fed = list(dict.fromkeys((METRICS[m].parent or m) if m in METRICS else m for m in ms))
        if lum == lums[0]:  # the study's own luminance: every metric of the scene is computed there already
            continue
        sweeps.append({"scene": scene, "luminance": [lum], "metrics": fed})
    study_data = {"name": name, "seed": seed, "cfas": ["bayer"], **study_in, "luminances": [lums[0]]}
    if sweeps:
        study_data["sweep"] = sweeps
    study = parse_config(study_data, where=f"{where}: study", base=base)
    objectives = tuple(_objective(ck, o, f"objective[{i}]", study, False) for i, o in enumerate(objs_in))
    if len({o.label for o in objectives}) != len(objectives):
        ck.fail("objective", "lists the same objective twice")
    constraints = tuple(_objective(ck, o, f"constraint[{i}]", study, True) for i, o in enumerate(cons_in))
    gradient = None
    if method == "gradient":
        from .gradient_search import parse_gradient

        gradient = parse_gradient(ck, data.get("gradient"), tiles, alphabet, spectra, objectives)
    return DesignConfig(name=name, description=description, path=None, seed=seed, tiles=tiles, alphabet=alphabet,
                        spectra_set=set_name, density=density, mirrors=mirrors, spectra=spectra, engine=engines,
                        population=population, generations=generations, full_chain=full_chain,
                        agreement_sample=sample, objectives=objectives, constraints=constraints, study=study,
                        workers=workers, method=method, gradient=gradient)


def load_design(path) -> DesignConfig:
    """Read and validate a design config (TOML); a problem raises
    :class:`~cfa_mitsuba.errors.CfaMitsubaError` naming the file and the key."""
    p, data = read_toml(path, "design config")
    return dataclasses.replace(parse_design(data, where=p.name, base=p.parent), path=str(p.resolve()))
