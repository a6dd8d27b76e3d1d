"""Read a study's results directory (the report's only input).

The report reads files, never the runner's objects, so that
``cfa-mitsuba report RESULTS_DIR`` rebuilds it from what a study left on
disk, including a partial study, an older one, or the ``metrics.csv`` of
``cfa-mitsuba evaluate`` alone.  Everything but ``metrics.csv`` may be
missing; :class:`Results` says what is absent rather than failing.

    metrics.csv   tidy rows: scene, cfa, demosaic, luminance, metric, value, unit
    scores.csv    the scored rows with normalised scores and ranks (optional)
    ranges.json   {metric: [worst, best]} (optional)
    cfas.json     each CFA's tile, channels, spectra set (optional; study/cfa_facts.py)
    timing.json   where the time went (optional; may predate metrics.csv)
    config.json   the validated config (optional)
    details/<scene>/<cfa>/<demosaic>/L<lum>.json|.png|.scielab.npy
    details/<scene>/ideal/L<lum>.json|.png
"""

from __future__ import annotations

__all__ = ["Results", "load_results", "SCORED_METRICS", "safe_label", "lum_tag"]

import json
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError
from ..metrics import scored_metrics
from ..study.conditions import AXES
from ..study.details_layout import ideal_folder, output_folder, safe_label

#: The paper's eight metrics in the order of its tables and radar plots (the metric records).
SCORED_METRICS = scored_metrics()
_COLUMNS = ("scene", "cfa", "demosaic", "luminance", "metric", "value", "unit")


def preferred_scene(scenes: list, config: dict | None) -> str:
    """Of the scenes that measured a metric, the one scored (as the runner
    picks it): the first built-in scene of the study's config (a scene
    without a ``file``), else the first."""
    builtin = [s.get("name") for s in (config or {}).get("scenes") or [] if isinstance(s, dict) and not s.get("file")]
    return next((s for s in scenes if s in builtin), scenes[0])


def lum_tag(luminance: float) -> str:
    """``L100`` for 100 cd/m^2: the stem of the detail files."""
    return f"L{float(luminance):g}"


def _read_json(path: Path):
    """A JSON file of the results, or None when absent or unreadable (a
    FIFO, too large, nested too deeply, not JSON: io/guard.py)."""
    from ..io.guard import read_json

    if not path.exists():
        return None
    try:
        return read_json(path, allow_nan=True)
    except (OSError, ValueError):  # CfaMitsubaError is a ValueError
        return None


@dataclass
class Results:
    """A results directory, loaded.

    ``metrics`` and ``scores`` are pandas DataFrames (``scores`` None when
    there is nothing to score); ``cfas``, ``demosaics``, ``scenes`` keep the
    study's order; ``base_luminances`` are the levels every metric was
    measured at, ``primary_luminance`` the one the figures use.  ``notes``
    collects what the report should tell the reader about the inputs
    themselves (a missing file, a stale timing).
    """

    root: Path
    metrics: object
    scores: object
    ranges: dict
    timing: dict | None
    config: dict
    cfas: list
    demosaics: list
    scenes: list
    base_luminances: list
    primary_luminance: float | None
    scored_here: bool = False
    notes: list = field(default_factory=list)
    #: {CFA label: its tile, channels, spectra set, ...} from cfas.json
    #: (study/cfa_facts.py); empty for results written before it existed
    cfa_facts: dict = field(default_factory=dict)
    #: every row of metrics.csv, sweeps of any axis included (``metrics``
    #: keeps the rows at the study's own values of every axis but luminance)
    all_metrics: object = None
    #: the axes other than luminance that a sweep varied, {axis: values}
    swept_axes: dict = field(default_factory=dict)
    #: the range policy the scores used ('paper', 'study', 'ideal'; None for old results)
    range_policy: str | None = None
    #: scored metrics left out because no CFA differed on them
    constant_metrics: list = field(default_factory=list)
    #: policies.csv (clipping and ranks under every policy), or None
    policies: object = None

    # -- what was measured -------------------------------------------------
    def has_metric(self, metric: str, luminance: float | None = None) -> bool:
        m = self.metrics
        sel = m["metric"] == metric
        if luminance is not None:
            sel &= m["luminance"] == luminance
        return bool(sel.any())

    def scene_for(self, metric: str) -> str | None:
        """The scene whose ``metric`` is scored (as the runner picks it: the
        built-in scene that feeds it, else the first other scene)."""
        if self.scores is not None and len(self.scores):
            s = self.scores[self.scores["metric"] == metric]
            if len(s):
                return str(s["scene"].iloc[0])
        rows = self.metrics[self.metrics["metric"] == metric]
        if not len(rows):
            return None
        return preferred_scene(list(dict.fromkeys(rows["scene"])), self.config)

    def value(self, scene, cfa, demosaic, luminance, metric) -> float | None:
        m = self._index()
        v = m.get((scene, cfa, demosaic, float(luminance), metric))
        return None if v is None else float(v)

    def _index(self) -> dict:
        if not hasattr(self, "_idx"):
            m = self.metrics
            self._idx = {(s, c, d, float(lv), k): v for s, c, d, lv, k, v in
                         zip(m["scene"], m["cfa"], m["demosaic"], m["luminance"], m["metric"], m["value"])}
        return self._idx

    # -- per-evaluation details ---------------------------------------------
    def detail_path(self, scene: str, cfa: str | None, demosaic: str | None, luminance: float,
                    suffix: str = ".json") -> Path:
        details = self.root / "details"
        folder = ideal_folder(details, scene) if cfa is None else output_folder(details, scene, cfa, demosaic)
        return folder / f"{lum_tag(luminance)}{suffix}"

    def detail(self, scene: str, cfa: str | None, demosaic: str | None, luminance: float) -> dict | None:
        """The JSON of one evaluation (``cfa=None``: the ideal sensor), or None."""
        return _cached_json(str(self.detail_path(scene, cfa, demosaic, luminance)))

    def metric_detail(self, metric: str, scene: str, cfa: str | None, demosaic: str | None,
                      luminance: float) -> dict | None:
        d = self.detail(scene, cfa, demosaic, luminance)
        rec = d.get(metric) if isinstance(d, dict) else None
        return rec if isinstance(rec, dict) else None

    def detail_pairs(self, metric: str, lum: float):
        """[(cfa, demosaic, detail record)] of ``metric`` at ``lum`` in study order."""
        scene = self.scene_for(metric)
        out = []
        if scene is None:
            return scene, out
        for d in self.demosaics:
            for c in self.cfas:
                rec = self.metric_detail(metric, scene, c, d, lum)
                if rec is not None:
                    out.append((c, d, rec))
        return scene, out

    def scielab_map(self, scene: str, cfa: str, demosaic: str, luminance: float):
        from ..io.guard import open_regular

        p = self.detail_path(scene, cfa, demosaic, luminance, ".scielab.npy")
        try:
            with open_regular(p) as fh:  # a FIFO or device in the results is not read
                a = np.load(fh, allow_pickle=False)
        except (OSError, ValueError):  # CfaMitsubaError is a ValueError
            return None
        return a if a.ndim == 2 and a.size else None

    def thumbnail_path(self, scene: str, cfa: str | None, demosaic: str | None, luminance: float) -> Path | None:
        p = self.detail_path(scene, cfa, demosaic, luminance, ".png")
        return p if p.is_file() else None

    @property
    def name(self) -> str:
        return str(self.config.get("name") or self.root.resolve().name)


@lru_cache(maxsize=4096)
def _cached_json(path: str):
    return _read_json(Path(path))


def _order(values, preferred=()) -> list:
    seen = list(dict.fromkeys(str(v) for v in values))
    first = [p for p in preferred if p in seen]
    return first + [v for v in seen if v not in first]


def _read_metrics(path: Path):
    import pandas as pd

    from ..io.guard import read_csv

    try:
        m = read_csv(path, "metrics table", dtype={"scene": str, "cfa": str, "demosaic": str, "metric": str, "unit": str},
                        keep_default_na=False, na_values={"value": ["", "nan", "NaN"], "luminance": ["", "nan"]})
    except CfaMitsubaError:
        raise
    except (OSError, ValueError) as exc:
        raise CfaMitsubaError(f"cannot read {str(path)!r}: {exc}") from None
    missing = [c for c in _COLUMNS if c not in m.columns]
    if missing:
        raise CfaMitsubaError(f"{str(path)!r} is not a metrics table: no column(s) {', '.join(missing)}")
    m["value"] = pd.to_numeric(m["value"], errors="coerce")
    m["luminance"] = pd.to_numeric(m["luminance"], errors="coerce")
    return m[np.isfinite(m["value"]) & np.isfinite(m["luminance"])].reset_index(drop=True)


def _read_policies(path: Path):
    from ..io.guard import read_csv

    if not path.is_file():
        return None
    try:
        return read_csv(path)
    except (OSError, ValueError):
        return None


def split_sweeps(metrics):
    """(rows at the study's own values of every axis but luminance, {axis:
    values} of the other axes some sweep varied).  A row belongs to the
    first part when its scene has a base row (``base`` column) with the same
    values of those axes (for its CFA: the spectra set is a CFA's own); tables
    without axis columns are all base."""
    others = [a for a in list(AXES)[1:] if a in metrics.columns]
    if not others or "base" not in metrics.columns:
        return metrics, {}
    base_flag = metrics["base"].astype(str).str.lower().isin(("true", "1"))
    keys = [tuple(str(v) for v in row) for row in metrics[others].itertuples(index=False)]
    ids = list(zip(metrics["scene"], metrics["cfa"], keys))  # a CFA's own spectra set is one of its axes
    base_keys = {i for i, b in zip(ids, base_flag) if b}
    keep = np.array([i in base_keys for i in ids], dtype=bool)
    # an axis is swept when some row outside the base differs from its CFA's base value of it
    base_of = {}
    for (sc, cfa, k), b in zip(ids, base_flag):
        if b:
            base_of.setdefault((sc, cfa), k)
    swept = {}
    for (sc, cfa, k), kept in zip(ids, keep):
        ref = base_of.get((sc, cfa))
        if kept or ref is None:
            continue
        for a, v, r in zip(others, k, ref):
            if v != r:
                swept.setdefault(a, [])
    for a in swept:
        swept[a] = list(dict.fromkeys(metrics[a].tolist()))
    return metrics[keep].reset_index(drop=True), swept


def _base_luminances(metrics, config: dict, scores) -> list[float]:
    lums = [float(v) for v in (config.get("luminances") or [])]
    have = set(float(v) for v in metrics["luminance"].unique())
    lums = [v for v in lums if v in have]
    if not lums and scores is not None and len(scores):
        lums = sorted(float(v) for v in scores["luminance"].unique())
    if not lums and len(metrics):
        # the level with the most distinct metrics (sweeps add only a few)
        counts = metrics.groupby("luminance")["metric"].nunique()
        lums = [float(counts.idxmax())]
    return lums


def _score_here(metrics, base, ranges, config):
    """Scores for a results directory without scores.csv (e.g. the output of
    ``cfa-mitsuba evaluate``): the eight metrics at the base luminances, one
    scene per metric, with the given or the default ranges."""
    import pandas as pd

    from ..study.scoring import score

    df = metrics[metrics["metric"].isin(SCORED_METRICS) & metrics["luminance"].isin(base)]
    keep = []
    for name, group in df.groupby("metric", sort=False):
        keep.append(group[group["scene"] == preferred_scene(list(dict.fromkeys(group["scene"])), config)])
    if not keep:
        return None
    return score(pd.concat(keep).reset_index(drop=True), ranges or None)


def _old_censored(metrics, root: Path):
    """metrics.csv written before ``censored_count``: read under the rule of
    study/censored.py from metrics_realisations.csv (a value with bounds in
    some realisations only is their Kaplan-Meier median, not a bound)."""
    if "censored_count" in metrics.columns or not (root / "metrics_realisations.csv").is_file():
        return metrics
    from ..errors import CfaMitsubaError
    from ..io.guard import read_csv
    from ..study.censored import apply_rule

    try:
        real = read_csv(root / "metrics_realisations.csv", dtype={"scene": str, "cfa": str, "demosaic": str,
                                                                  "metric": str, "unit": str})
    except (OSError, ValueError, CfaMitsubaError):
        return metrics
    return apply_rule(metrics, real)


def load_results(out_dir) -> Results:
    """Load a results directory; :class:`CfaMitsubaError` (one line) when it
    is missing or holds no ``metrics.csv``."""
    import pandas as pd

    from ..io.guard import read_csv

    root = Path(out_dir)
    if root.exists() and not root.is_dir():
        raise CfaMitsubaError(f"{str(root)!r} is a file, not a results directory")
    if not root.is_dir():
        raise CfaMitsubaError(f"no such results directory {str(root)!r}")
    mpath = root / "metrics.csv"
    if not mpath.exists():  # (a FIFO or folder in its place is refused by the reader, naming what it is)
        raise CfaMitsubaError(f"{str(root)!r} is not a results directory (no metrics.csv)")
    _cached_json.cache_clear()
    notes = []
    all_metrics = _old_censored(_read_metrics(mpath), root)
    metrics, swept = split_sweeps(all_metrics)
    config = _read_json(root / "config.json") or {}
    if not (root / "config.json").is_file():
        notes.append("config.json is absent: the study's name, scenes and settings are taken from metrics.csv.")
    ranges = {}
    raw_ranges = _read_json(root / "ranges.json")
    policy, constant = None, []
    if isinstance(raw_ranges, dict):
        policy = raw_ranges.pop("_policy", None)
        constant = [str(c) for c in raw_ranges.pop("_constant", []) or []]
        for k, v in raw_ranges.items():
            try:
                ranges[str(k)] = (float(v[0]), float(v[1]))
            except (TypeError, ValueError, IndexError):
                pass
    scores = None
    scored_here = False
    spath = root / "scores.csv"
    if spath.is_file():
        try:
            scores = read_csv(spath, "scores table", dtype={"scene": str, "cfa": str, "demosaic": str, "metric": str,
                                               "unit": str}, keep_default_na=False,
                                 na_values={"value": [""], "score": [""], "raw_score": [""]})
        except (OSError, ValueError) as exc:
            notes.append(f"scores.csv could not be read ({exc}); scores are recomputed here.")
            scores = None
        if scores is not None and len(scores) == 0:
            scores = None
    base = _base_luminances(metrics, config, scores)
    if scores is None and len(metrics):
        try:
            scores = _score_here(metrics, base, ranges, config)
        except CfaMitsubaError as exc:
            notes.append(f"no scores: {exc}")
            scores = None
        if scores is not None:
            scored_here = True
            notes.append("scores.csv is absent: the scores and ranks here were computed by the report with "
                          + ("the ranges in ranges.json." if ranges else "the default (paper's) ranges."))
            if not ranges:
                from ..study.scoring import DEFAULT_RANGES

                ranges = {k: (r.worst, r.best) for k, r in DEFAULT_RANGES.items()}
    if scores is not None:
        scores["luminance"] = pd.to_numeric(scores["luminance"], errors="coerce")
        if "out_of_range" in scores.columns:
            scores["out_of_range"] = scores["out_of_range"].astype(str).str.lower().isin(("true", "1"))
    timing = _read_json(root / "timing.json")
    if timing is not None:
        try:
            if (root / "timing.json").stat().st_mtime + 1.0 < mpath.stat().st_mtime:
                notes.append("timing.json is older than metrics.csv (written by an earlier run of this study); "
                             "its times may not describe these results.")
                timing = dict(timing, stale=True)
        except OSError:
            pass
    cfa_labels = []
    for c in config.get("cfas") or []:
        c = str(c)
        cfa_labels.append(Path(c).stem if c.lower().endswith(".toml") else c)
    cfas = _order(metrics["cfa"], cfa_labels)
    demosaics = _order(metrics["demosaic"], [str(d) for d in config.get("demosaics") or []])
    scenes = _order(metrics["scene"], [str(s.get("name")) for s in config.get("scenes") or [] if isinstance(s, dict)])
    primary = None
    if base:
        primary = 100.0 if 100.0 in base else base[0]
    return Results(root=root, metrics=metrics, scores=scores, ranges=ranges, timing=timing, config=config,
                   cfas=cfas, demosaics=demosaics, scenes=scenes, base_luminances=base,
                   primary_luminance=primary, scored_here=scored_here, notes=notes, all_metrics=all_metrics,
                   swept_axes=swept, range_policy=policy if isinstance(policy, str) else None,
                   constant_metrics=constant, policies=_read_policies(root / "policies.csv"),
                   cfa_facts=_cfa_facts(root / "cfas.json"))


def _cfa_facts(path: Path) -> dict:
    """cfas.json as {label: record}, keeping only well-formed records (a tile of names)."""
    raw = _read_json(path)
    if not isinstance(raw, dict):
        return {}
    return {str(k): v for k, v in raw.items() if isinstance(v, dict) and isinstance(v.get("pattern"), list)
            and v["pattern"] and all(isinstance(r, list) for r in v["pattern"])}
