"""A study's size, stated before it starts and refused above the limits.

Counted from the config alone, without building the conditions (a
``[[sweep]]`` crossing three lists of 100 values is 10^6 conditions: counting
them is a product, building them is 1.6 GB):

* **conditions**: per scene, the base luminances plus, per sweep naming the
  scene, its luminances (else the base ones) times the product of its other
  axes' lengths (an upper bound: a condition two tables reach counts twice);
* **tasks**: conditions x CFAs (one evaluation task each; x ``render_seeds`` for
  a path-traced scene);
* **captures**: tasks x ``seeds`` x ``render_seeds`` (the realisations:
  sensor-noise seeds crossed with render seeds; a chart's render is shared
  by its render seeds, a path-traced scene is rendered, and its optical
  image computed, once per render seed);
* **camera outputs**: captures x demosaics;
* **result rows**: camera outputs x the values their metrics give (a metric
  and the values read from its details, ``delta-e`` three), per condition
  (an upper bound as for the conditions).

The time is estimated from measured per-unit costs (``data/study_costs.toml``:
worker seconds per optical image, capture and camera output, per megapixel,
and per evaluation task whatever its size, divided among the workers; plus
the main process's seconds per condition for the tables: the scores and
ranks of every condition, which dominate a study of many tiny conditions;
``benchmarks/bench_estimates.py`` measures the last two and prints
estimated against measured time); the peak memory is
the main process's largest render and its result rows plus one evaluation
task per worker (:mod:`cfa_mitsuba.io.limits`' measured models), so the
memory check covers N workers, not one task, and the rows a study of
millions of realisations collects.

Limits (docs/study.md): a study is refused, before anything is written, when
its estimated time exceeds :data:`MAX_HOURS` or its tasks exceed
:data:`MAX_TASKS`, unless ``--force``; and always when its result rows would
not fit in memory, or N workers would not (fewer workers fit).  ``workers`` from a config is capped at
the cores with a notice; ``--workers N`` is taken as given.
"""

from __future__ import annotations

__all__ = ["StudySize", "study_size", "scene_units", "check_study_size", "resolve_workers", "MAX_HOURS", "MAX_TASKS",
           "unit_costs"]

import functools
import math
from dataclasses import dataclass
from pathlib import Path

from ..errors import CfaMitsubaError

#: Largest estimated wall time (hours) a study starts without ``--force``.
MAX_HOURS = 24.0
#: Largest number of evaluation tasks (resume files, rows held in memory)
#: a study starts without ``--force``.
MAX_TASKS = 100_000
#: A user scene whose film size the config does not give: assumed this size
#: for the estimate only (its render is checked exactly when it is loaded).
_UNKNOWN_SIZE = (512, 512, 1)


@functools.lru_cache(maxsize=1)
def unit_costs() -> dict:
    """The measured per-unit costs (``data/study_costs.toml``), seconds."""
    path = Path(__file__).resolve().parents[1] / "data" / "study_costs.toml"
    from ..io.guard import read_toml

    return read_toml(path, "study costs")["seconds"]


@dataclass(frozen=True)
class StudySize:
    """What a study will do, counted from its config (module docstring)."""

    conditions: int
    tasks: int
    captures: int
    outputs: int
    workers: int
    seconds: float
    peak_bytes: int
    rows: int = 0
    rows_bytes: int = 0
    render_seconds: float = 0.0  # the renders' share of ``seconds`` (nothing when they are cached)

    def describe(self) -> str:
        from ..io.limits import format_bytes

        return (f"{self.conditions:,} condition(s), {self.tasks:,} task(s), {self.captures:,} capture(s), "
                f"{self.outputs:,} camera output(s); about {_duration(self.seconds)} on {self.workers} "
                f"worker(s), peak memory about {format_bytes(self.peak_bytes)}")


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 86400 * 3:
        return f"{seconds / 3600:.1f} h"
    days = seconds / 86400
    return f"{days:,.0f} days" if days < 1e6 else f"{days:.2g} days"


def _cores() -> int:
    from .executors import _cpu_count

    return _cpu_count()


def resolve_workers(cli_workers: int | None, config_workers: int | None, log) -> int | None:
    """The local workers to start: ``--workers`` as given (the user
    insists); a config's ``workers`` capped at the cores, with a notice
    (a 6-task study on 1000 workers took 25.7 s against 4.6 s on one);
    when neither says, ``$CFA_MITSUBA_WORKERS`` or 2 capped at the cores
    (:func:`~.executors.default_workers`, checked here, before any work)."""
    if cli_workers:
        return int(cli_workers)
    if config_workers:
        cores = _cores()
        if config_workers > cores:
            log(f"notice: workers = {config_workers} in the config capped at the {cores} core(s) of this machine "
                f"(--workers {config_workers} insists)")
            return cores
        return int(config_workers)
    from .executors import default_workers

    return default_workers()


def _scene_size(spec) -> tuple[int, int, int, int]:
    """(EXR width, height, spp, oversample K) of a scene in a study."""
    over = spec.render
    try:
        from ..render import get_scene

        default = get_scene(spec.file or spec.name)
        w, h, spp, k = default.width, default.height, default.spp, default.oversample
    except (CfaMitsubaError, OSError, ValueError, AttributeError):
        (w, h, spp), k = _UNKNOWN_SIZE, 1
    return (int(over.get("width", w)), int(over.get("height", h)), int(over.get("spp", spp) or 1),
            int(over.get("oversample", k) or 1))


def _tables(config, scene):
    """(conditions, metric names) of each table that reaches ``scene``: the
    base luminances with the scene's metrics, then each sweep naming it, its
    luminances (else the base ones) times the product of its other axes'
    lengths, with the scene's metrics it names (or all of them)."""
    yield len(config.luminances), scene.metrics
    for sw in config.sweeps:
        if scene.name not in sw.scenes:
            continue
        bases = len(sw.values["luminance"]) if "luminance" in sw.values else len(config.luminances)
        yield (bases * math.prod(len(v) for axis, v in sw.values.items() if axis != "luminance"),
               [m for m in scene.metrics if not sw.metrics or m in sw.metrics])


def _conditions(config, scene) -> int:
    return sum(n for n, _ in _tables(config, scene))


def _values_per_output(names) -> int:
    """Result rows one camera output gives for the metrics ``names``: each
    metric's own and the values read from its details."""
    from ..metrics.registry import METRICS

    return sum(1 + sum(1 for r in METRICS.values() if r.parent == n) for n in names)


def _rows_per_capture(config, scene) -> int:
    """Result rows per capture and demosaic over the scene's conditions,
    counted as :func:`_conditions` counts them."""
    return sum(n * _values_per_output(names) for n, names in _tables(config, scene))


def _path_traced(spec, rule) -> bool:
    """``rule(spec)`` (runner.path_traced), True where the scene cannot be
    loaded (an estimate errs on the larger side)."""
    try:
        return bool(rule(spec))
    except (CfaMitsubaError, OSError, ValueError, AttributeError):
        return True


def scene_units(config, spec, n_workers: int) -> dict:
    """What one scene of ``config`` costs, in the units of
    ``data/study_costs.toml`` (module docstring): its ``conditions``,
    ``tasks``, ``captures`` and camera ``outputs``; ``optics_mpx_band``
    (optical images, one per render seed, condition and worker that meets
    it, x EXR megapixels x bands), ``capture_mpx`` (captures x EXR
    megapixels), ``output_mpx`` (outputs x sensor megapixels),
    ``render_msample_band`` (renders x EXR megapixels x spp x bands), its
    result ``rows``, its ``renders`` and its render ``size`` (width, height,
    bands).
    benchmarks/bench_sizing.py divides a run's times by the same units."""
    from .budget import _bands
    from .render_seeds import path_traced

    bands = _bands(config.render)
    n_render = int(getattr(config, "render_seeds", 1))
    w, h, spp, k = _scene_size(spec)
    renders = n_render if n_render > 1 and _path_traced(spec, path_traced) else 1
    exr_mpx = w * h / 1e6
    n_cond = _conditions(config, spec)
    n_tasks = n_cond * len(config.cfas) * renders  # a path-traced scene: one task per render seed
    n_capt = n_cond * len(config.cfas) * config.seeds * n_render
    n_out = n_capt * len(config.demosaics)
    n_rows = (len(config.cfas) * config.seeds * n_render * len(config.demosaics)
              * _rows_per_capture(config, spec))
    return {"conditions": n_cond, "tasks": n_tasks, "captures": n_capt, "outputs": n_out, "rows": n_rows,
            "optics_mpx_band": renders * n_cond * min(n_workers, max(1, n_tasks)) * exr_mpx * bands,
            "capture_mpx": n_capt * exr_mpx, "output_mpx": n_out * exr_mpx / (k * k),
            "render_msample_band": renders * exr_mpx * spp * bands, "renders": renders, "size": (w, h, bands)}


def study_size(config, workers: int | None, scheduler: str | None = None, costs: dict | None = None) -> StudySize:
    """Count and estimate a study (module docstring) from its config, with
    the per-unit ``costs`` (default :func:`unit_costs`)."""
    from ..io import limits

    n_workers = int(workers) if workers else min(2, _cores())
    cost = unit_costs() if costs is None else costs
    conditions = tasks = captures = outputs = rows = 0
    worker_s = render_s = 0.0
    render_peak = task_peak = 0
    for spec in config.scenes:
        u = scene_units(config, spec, n_workers)
        conditions, tasks, captures, outputs = (conditions + u["conditions"], tasks + u["tasks"],
                                                captures + u["captures"], outputs + u["outputs"])
        rows += u["rows"]
        worker_s += (u["optics_mpx_band"] * cost["optics_per_megapixel_band"]
                     + u["capture_mpx"] * cost["capture_per_megapixel"]
                     + u["output_mpx"] * cost["output_per_megapixel"])
        render_s += u["render_msample_band"] * cost["render_per_megasample_band"]
        w, h, bands = u["size"]
        render_peak = max(render_peak, limits.estimate_render_bytes(w, h, bands))
        task_peak = max(task_peak, limits.estimate_task_bytes(h, w, bands))
    # per-task overhead (issue 51): a task's own bookkeeping in its worker, whatever its size, and the main
    # process's tables, whose scoring and ranks are made per condition (20,000 tiny conditions were
    # estimated at 66 s without them and took 13 minutes)
    worker_s += tasks * cost.get("task_overhead", 0.0)
    main_s = conditions * cost.get("tables_per_condition", 0.0)
    seconds = render_s + cost["worker_start"] + worker_s / n_workers + main_s
    rows_bytes = limits.estimate_result_rows_bytes(rows)
    peak = render_peak + rows_bytes + (0 if scheduler else n_workers * task_peak)
    return StudySize(conditions, tasks, captures, outputs, n_workers, seconds, peak, rows, rows_bytes, render_s)


def check_study_size(config, workers: int | None, *, scheduler: str | None = None, force: bool = False,
                     log=None) -> StudySize:
    """State a study's size (one log line) and refuse it (one
    :class:`CfaMitsubaError` with the estimate) above the limits."""
    from ..io.limits import available_memory_bytes, format_bytes

    size = study_size(config, workers, scheduler)
    where = f"{Path(config.path).name}: " if config.path else ""
    over = []
    if size.seconds > MAX_HOURS * 3600:
        over.append(f"more than the {MAX_HOURS:g} h limit")
    if size.tasks > MAX_TASKS:
        over.append(f"more than the {MAX_TASKS:,}-task limit")
    have, source = available_memory_bytes()
    if have is not None and size.rows_bytes > have:  # the main process's, with or without a scheduler
        also = f"{' and '.join(over)}, and " if over else ""
        raise CfaMitsubaError(
            f"{where}{size.describe()}: {also}its {size.rows:,} result rows alone need about "
            f"{format_bytes(size.rows_bytes)}, more than the {format_bytes(have)} available ({source}); "
            "fewer seeds, sweep values, CFAs or demosaics (--force does not lift a memory limit)")
    if not scheduler and have is not None and size.peak_bytes > have:
        raise CfaMitsubaError(
            f"{where}{size.describe()}: {size.workers} worker(s) need more than the {format_bytes(have)} "
            f"available ({source}); use fewer --workers or smaller renders")
    if over and not force:
        raise CfaMitsubaError(f"{where}{size.describe()}: {' and '.join(over)} (fewer seeds, sweep values, CFAs "
                              "or demosaics; or --force to run it anyway)")
    if log is not None:
        log(f"size: {size.describe()}" + (" (--force)" if over else ""))
    return size
