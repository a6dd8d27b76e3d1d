"""The study runner: render each scene once, evaluate every (scene,
luminance, CFA, demosaic), write the tables.  The report is the next stage
(:mod:`cfa_mitsuba.report`); ``cfa-mitsuba study`` builds it from these files.

    results/
      metrics.csv     tidy: scene, cfa, demosaic, the condition axes (luminance,
                      f_number, pixel_pitch_um, exposure, read_noise_e,
                      seed), base (a study condition, not only a sweep's),
                      metric, value, unit, and the capture's exposure_s,
                      analog_gain, digital_gain, clipped_fraction
      snr.csv, snr10.csv  YSNR and chroma SNR against luminance, the
                      luminance of YSNR 10 (:mod:`.snr`; studies that measure ysnr)
      scores.csv      the scored rows with normalised scores and ranks
      timing.json     where the time went
      config.json     the validated config, as run
      sensor_curves.csv  each compared CFA's QE curves as captured (sensor_curves.py)
      mtf.csv, patches.csv, steps.csv  each edge's MTF curve, each ColorChecker
                      patch's error, each gray step's SNR and the dynamic range
                      (detail_tables.py; from the first realisation's details)
      details/        per evaluation: curves and tables (JSON), reduced
                      S-CIELAB maps (.npy), thumbnails (.png)
      figures/, report.html   (cfa_mitsuba.report, built after the runner)

Renders go through the shared render cache (outside the results), so a
second study reuses them.  Each finished evaluation task is saved at once
under ``results/.work/`` (atomically), so a study that was interrupted
(Ctrl-C, a killed process or worker) redoes only the missing tasks when run
again and ends with the same ``metrics.csv`` as an uninterrupted run.
"""

from __future__ import annotations

__all__ = ["StudyResult", "run_study", "plan_study", "write_timing", "timing_summary"]

import hashlib
import json
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from .._version import __version__
from ..errors import CfaMitsubaError
from ..io import atomic_output, check_writable_dir
from ..metrics import scored_metrics
from . import image_store
from .config import StudyConfig
from .cfa_facts import write_cfa_facts
from .sensor_curves import write_sensor_curves
from .tables import order_rows, write_tables
from .snr import write_snr_tables
from .detail_tables import write_detail_tables
from .render_seeds import is_3d as _is_3d, path_traced, render_seeded
from .tasks import EvaluationTask, evaluate_group, render_task

#: Metrics that enter the scores (the paper's eight); other rows in
#: metrics.csv (delta-l, delta-e76, scielab-interior) are reported only.
SCORED_METRICS = scored_metrics()


@dataclass
class StudyResult:
    """What a finished study produced (the tables are pandas DataFrames)."""

    out_dir: Path
    metrics: object
    scores: object
    timing: dict = field(default_factory=dict)
    tasks_total: int = 0
    tasks_reused: int = 0


def _source(scene, render_common: dict, cond=None) -> dict:
    """The render a scene is evaluated on: its settings, plus, for a 3D
    scene, the render settings the condition's axes set when it gives them
    (:attr:`.axes.Axis.render_setting`: the f-number's thin-lens defocus;
    a chart's render depends on none)."""
    from .axes import AXES

    settings = {**render_common, **scene.render}
    given = {} if cond is None else {
        axis.render_setting: float(getattr(cond, name)) if axis.numeric else getattr(cond, name)
        for name, axis in AXES.items() if axis.render_setting is not None and getattr(cond, name) is not None}
    if given and _is_3d(scene):  # asked only when a condition sets one (a measured image is no scene file)
        settings.update(given)
    src = {"kind": "cache", "scene": scene.name, "settings": settings}
    if scene.file:
        src["file"] = scene.file
    return src


def _cfa_label(cfa: str) -> str:
    if cfa.lower().endswith(".toml"):
        from ..sensor import load_cfa_toml

        return load_cfa_toml(cfa).name
    return cfa


def scene_conditions(config: StudyConfig, scene) -> dict:
    """{Condition: (metrics, base)} of one scene: the base conditions (the
    config's luminances, every metric the scene feeds) then each sweep's
    crossed values; a condition reached twice evaluates the union of its
    metrics.  ``base`` says whether the condition is one of the study's own
    (scored) or only a sweep's."""
    from .conditions import cross

    plan: dict = {}
    for lum in config.luminances:
        plan[config.base_condition(lum)] = (list(scene.metrics), True)
    for sw in config.sweeps:
        if scene.name not in sw.scenes:
            continue
        wanted = [m for m in scene.metrics if not sw.metrics or m in sw.metrics]
        values = dict(sw.values)
        bases = [config.base_condition(lum) for lum in
                 (values.pop("luminance") if "luminance" in values else config.luminances)]
        for base in bases:
            for cond in (cross(base, values) if values else [base]):
                have, is_base = plan.setdefault(cond, ([], False))
                have.extend(m for m in wanted if m not in have)
    # luminance ascending, then the order the conditions were first named
    order = {c: i for i, c in enumerate(plan)}
    ordered = sorted(plan, key=lambda c: (c.luminance, order[c]))
    return {c: ([m for m in scene.metrics if m in plan[c][0]], plan[c][1]) for c in ordered}


def plan_study(config: StudyConfig, details_dir: str | None, *, image_store: str | None = None
               ) -> tuple[list[dict], list[dict]]:
    """The render sources and the evaluation tasks of a study, in a fixed
    order (``image_store``: the folder of optical images its workers share,
    :mod:`.image_store`).

    Every value has ``render_seeds x seeds`` realisations, realisation
    ``k = r x seeds + s`` the same render seed r and sensor seed for every
    CFA: a path-traced scene (:func:`path_traced`) gets one render and one
    task per render seed, a chart one render and one task with all the
    realisations (its render does not depend on the seed)."""
    render_common = dict(config.render)
    labels = [_cfa_label(c) for c in config.cfas]
    if len(set(labels)) != len(labels):
        dup = next(lab for lab in labels if labels.count(lab) > 1)
        raise CfaMitsubaError(f"two CFAs of this study are both named {dup!r}")
    chain = config.chain_settings()
    sources, tasks = [], []
    n_render = int(config.render_seeds)
    for scene in config.scenes:
        seeded = n_render > 1 and path_traced(scene)
        for cond, (metrics, base) in scene_conditions(config, scene).items():
            plain = _source(scene, render_common, cond)
            tag = cond.label(config.base_condition(cond.luminance))
            for r in range(n_render if seeded else 1):
                src = render_seeded(plain, r)
                if src not in sources:
                    sources.append(src)
                per_task = config.seeds if seeded else config.seeds * n_render
                for i, (cfa, label) in enumerate(zip(config.cfas, labels)):
                    tasks.append(EvaluationTask(
                        source=src, scene=scene.name, condition=cond, base=base, cfa=cfa, cfa_label=label,
                        demosaics=tuple(config.demosaics), metrics=tuple(metrics), chain=chain,
                        details_dir=details_dir if r == 0 else None, details_tag=tag, realisations=per_task,
                        ideal_rows=i == 0 and r == 0, realisation_offset=r * config.seeds, render_seed=r,
                        image_store=image_store))
    return sources, tasks


def _task_id(task) -> str:
    ident = EvaluationTask.of(task).identity()
    ident["code"] = __version__
    text = json.dumps(ident, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _progress(total: int, desc: str, enabled: bool):
    from ..io.progress import progress_bar  # on a terminal only (issue 50)

    return progress_bar(total, desc, enabled=enabled, unit="task")


def _render_label(src: dict) -> str:
    """The name of a render in timing.json: the scene, with the f-number
    when the condition set the render's aperture and the sampler seed when
    it is not the scene's own."""
    settings = src.get("settings", {})
    f, seed = settings.get("f_number"), settings.get("seed")
    label = src["scene"] if f is None else f"{src['scene']}@f{f:g}"
    return label if not seed else f"{label}#seed{seed}"


def _paper_ranges(config: StudyConfig, render_info: dict) -> dict:
    """The paper's score ranges (scoring.default_ranges) with the MSP range
    for this study's chirp sampling and pixel pitch (the config's own
    ranges are applied on top of the policy's, in tables.write_tables)."""
    from .scoring import default_ranges

    pitch = float(config.sensor.get("pixel_pitch_um", 2.2))
    kwargs = {"pixel_pitch_um": pitch}
    chirp = render_info.get("chirp")
    if chirp and chirp.get("width") and chirp.get("fov_deg"):
        k = int(chirp.get("oversample") or 1)
        kwargs["chirp_samples_per_degree"] = float(chirp["width"]) / k / float(chirp["fov_deg"])
    return dict(default_ranges(**kwargs))


def _run_tasks(executor, fn, items, desc, progress, on_result, *, size=lambda item: 1):
    bar = _progress(sum(size(i) for i in items), desc, progress)
    try:
        for item, result in executor.map_unordered(fn, items):
            on_result(item, result)
            bar.update(size(item))
    finally:
        bar.close()


def _task_groups(tasks: list, render_info: dict, workers: int) -> list[tuple]:
    """The evaluation tasks in groups that share a render and a condition
    (one per CFA), largest first, so that one worker makes a group's
    optical and ideal images once (issue 25: on two workers a third of the
    optics time was the other worker making the same images) and the
    longest groups do not finish last.  Size = pixels x realisations x
    demosaics.  A group is split in halves while there are fewer than four
    groups per worker, so many workers still share the work."""
    groups: dict = {}
    for t in tasks:
        key = (json.dumps(t.source, sort_keys=True, default=str), repr(t.condition), t.render_seed)
        groups.setdefault(key, []).append(t)

    def size(group) -> float:
        info = render_info.get(_render_label(group[0].source)) or {}
        pixels = float(info.get("width") or 1) * float(info.get("height") or 1)
        return pixels * sum(max(1, t.realisations) * max(1, len(t.demosaics)) for t in group)

    out = list(groups.values())
    while len(out) < 4 * max(1, workers):
        big = max(out, key=len, default=[])
        if len(big) < 2:
            break
        out.remove(big)
        out += [big[:len(big) // 2], big[len(big) // 2:]]
    return [tuple(g) for g in sorted(out, key=size, reverse=True)]


def run_study(config: StudyConfig, out_dir, *, workers: int | None = None, scheduler: str | None = None,
              progress: bool = True, log=None, force: bool = False, worker_max_tasks: int | None = None,
              worker_max_memory: int | None = None) -> StudyResult:
    """Run a study's renders and evaluations and write its tables (see the
    module docstring for the outputs); ``timing_summary(result)`` is the
    line to print at the end.

    ``workers``: local processes (default: the config's, capped at the
    cores, else 2); ``scheduler``: a Dask scheduler address instead;
    ``force``: start a study above the size limits (study.sizing);
    ``worker_max_tasks``, ``worker_max_memory``: when a local worker is
    recycled (default: the config's, else study.executors' defaults).
    """
    from .executors import check_scheduler_address, make_executor, thread_budget
    from .sizing import check_study_size, resolve_workers

    log = log or (lambda msg: print(msg, file=sys.stderr))
    if scheduler is not None:  # a malformed (or empty) address is refused before anything is said or written
        check_scheduler_address(scheduler)
    # issue 27: the study's size stated and checked before anything is written
    workers = None if scheduler else resolve_workers(workers, config.workers, log)
    size = check_study_size(config, workers, scheduler=scheduler, force=force, log=log)
    out = check_writable_dir(out_dir)
    work = out / ".work"
    details = out / "details"

    sources, tasks = plan_study(config, str(details), image_store=str(work / image_store.FOLDER))
    timing: dict = {"phases": {}, "tasks": {"optics_s": 0.0, "capture_s": 0.0, "process_s": 0.0, "metrics_s": 0.0}}
    t_start = time.perf_counter()

    from .resume import load_finished  # issue 27: untrusted resume files are recomputed, one notice

    done: dict = load_finished(work, [_task_id(t) for t in tasks], log) if work.is_dir() else {}
    todo = [t for t in tasks if _task_id(t) not in done]
    reused = len(tasks) - len(todo)

    from .shutdown import terminate_cleanly

    executor = make_executor(workers=workers, scheduler=scheduler,
                             max_tasks=worker_max_tasks or config.worker_max_tasks,
                             max_memory=worker_max_memory or config.worker_max_memory)
    render_info: dict = {}
    with terminate_cleanly(log), executor:  # issue 27: SIGTERM stops the workers too
        # Written once the executor is up (a Dask scheduler that cannot be
        # reached leaves nothing behind).
        image_store.fresh(work)  # .work made; no optical image of an earlier run read
        with atomic_output(out / "config.json") as tmp:
            tmp.write_text(json.dumps({**_portable_config(config, out),
                                       "base_condition": config.base_condition().to_dict()}, indent=1, default=str))
        write_sensor_curves(config, out)  # the compared sensors' QE curves, for the report
        log(f"study {config.name!r}: {len(config.scenes)} scene(s), {len(config.cfas)} CFA(s), "
            f"{len(config.demosaics)} demosaic(s); {len(tasks)} evaluation task(s)" + _counted_twice(size, tasks)
            + (f", {reused} already done" if reused else "") + f"; running on {executor.description}")
        t = time.perf_counter()

        def got_render(src, summary):
            render_info[_render_label(src)] = summary

        need_render = sources if todo else []
        # Locally, renders run one at a time in this process with every core
        # (Dr.Jit parallelises a render well; two renders on one thread each
        # would leave a core idle once the quick charts are done).
        render_executor = executor if scheduler else _InProcess(thread_budget(1))
        _run_tasks(render_executor, render_task, need_render, "render", progress, got_render)
        timing["phases"]["render_s"] = time.perf_counter() - t
        timing["renders"] = render_info
        if todo:
            n_new = sum(1 for s in render_info.values() if not s["reused"])
            log(f"renders: {len(render_info) - n_new} reused from the cache, {n_new} rendered "
                f"({sum(s['render_time_s'] for s in render_info.values() if not s['reused']):.1f} s of rendering)")

        t = time.perf_counter()

        def got_eval(task, result):
            tid = _task_id(task)
            with atomic_output(work / f"{tid}.json") as tmp:
                tmp.write_text(json.dumps(result.to_dict()))
            done[tid] = result
            _add_timing(timing, task, result)

        def got_group(group, results):
            for task, result in zip(group, results):
                got_eval(task, result)

        groups = _task_groups(todo, render_info, getattr(executor, "workers", 0) or 1)
        _run_tasks(executor, evaluate_group, groups, "evaluate", progress, got_group, size=len)
        timing["phases"]["evaluate_s"] = time.perf_counter() - t
        _say_recycled(executor, log)
        shutil.rmtree(work / image_store.FOLDER, ignore_errors=True)  # the optical images: not kept past the run

    results = [done[_task_id(task)] for task in tasks]
    rows = [r for result in results for r in result.rows]
    failures = [f for result in results for f in result.failures]
    _write_failures(out, failures, log)
    _require_a_measurement(rows, failures, out)
    order = {
        "scene": [s.name for s in config.scenes], "cfa": [_cfa_label(c) for c in config.cfas],
        "demosaic": list(config.demosaics), "metric": list(SCORED_METRICS),
    }
    realisations = order_rows(rows, order)
    ideal = order_rows([r for result in results for r in result.ideal_rows], order)
    if not render_info:  # everything was reused: the chirp's geometry for the MSP range
        render_info = {_render_label(s): render_task(s) for s in sources if s["scene"] == "chirp"}
    builtin = {s.name for s in config.scenes if s.file is None}
    metrics, scores, ranges, constant = write_tables(
        out, realisations, ideal, paper_ranges=_paper_ranges(config, render_info), overrides=dict(config.ranges),
        policy=config.range_policy, clip=config.clip_scores, builtin_scenes=builtin)
    write_cfa_facts(out, config.cfas, order["cfa"], config.chain_settings(), config.base_condition())
    write_snr_tables(out, metrics)
    write_detail_tables(out, tasks, details)  # mtf.csv, patches.csv, steps.csv: the curves behind the values
    with atomic_output(out / "ranges.json") as tmp:
        tmp.write_text(json.dumps({**{k: _range_pair(v) for k, v in ranges.items()},
                                   "_policy": config.range_policy, "_constant": constant}, indent=1))

    timing["phases"]["total_s"] = time.perf_counter() - t_start
    result = StudyResult(out, metrics, scores, timing, len(tasks), reused)
    write_timing(result)
    return result


def _add_timing(timing: dict, task, result) -> None:
    """Add a task's worker seconds per stage to timing.json's ``tasks`` and
    to its scene's entry in ``scenes`` (with the captures, one per
    realisation the task measured, and the camera outputs, a capture per
    demosaic: the per-capture cost benchmarks/bench_study.py prints)."""
    scene = timing.setdefault("scenes", {}).setdefault(task.scene, {"tasks": 0, "captures": 0, "outputs": 0})
    captures = int(task.realisations) if result.rows else 0
    scene["tasks"] += 1
    scene["captures"] += captures
    scene["outputs"] += captures * len(task.demosaics)
    for k, v in result.timing.items():
        timing["tasks"][k] = timing["tasks"].get(k, 0.0) + v
        scene[k] = scene.get(k, 0.0) + v


def _say_recycled(executor, log) -> None:
    """A long run's one line on the workers it renewed (study.executors), if any."""
    if getattr(executor, "recycled", 0):
        from ..io.limits import format_bytes

        ceiling = f" or past {format_bytes(executor.max_memory)}" if executor.max_memory else ""
        log(f"workers recycled {executor.recycled} time(s) (after {executor.max_tasks} tasks{ceiling})")


def _counted_twice(size, tasks: list) -> str:
    """Why the size line's task count (an upper bound, study/sizing.py) can
    exceed the plan's: a condition that two tables of the config reach (the
    base luminances and a sweep's) runs once."""
    extra = int(getattr(size, "tasks", len(tasks))) - len(tasks)
    if extra <= 0:
        return ""
    return (f" (the size line's {size.tasks:,} counts {extra:,} twice: conditions that the base luminances and "
            "a sweep both reach run once)")


def _portable_config(config: StudyConfig, out: Path) -> dict:
    """config.json's content: the config with its own path, and the CFA and
    scene files it names by absolute path, relative to the output folder
    (io/portable.py), so a committed study records no machine's layout."""
    import os

    from ..io.portable import relative_path

    d = config.to_dict()
    if d.get("path"):
        d["path"] = relative_path(d["path"], out)
    d["cfas"] = [relative_path(c, out) if isinstance(c, str) and os.path.isabs(c) else c for c in d.get("cfas", [])]
    for sc in d.get("scenes", []):
        if isinstance(sc, dict) and isinstance(sc.get("file"), str) and os.path.isabs(sc["file"]):
            sc["file"] = relative_path(sc["file"], out)
    return d


def write_timing(result: StudyResult) -> None:
    """(Re)write ``timing.json`` from ``result.timing``."""
    with atomic_output(result.out_dir / "timing.json") as tmp:
        tmp.write_text(json.dumps(result.timing, indent=1))


class _InProcess:
    """Runs tasks here, one after another, with a Dr.Jit thread budget."""

    def __init__(self, threads: int):
        self.threads = threads

    def map_unordered(self, fn, items):
        import os

        saved = os.environ.get("CFA_MITSUBA_THREADS")
        os.environ["CFA_MITSUBA_THREADS"] = str(self.threads)
        try:
            for item in items:
                yield item, fn(item)
        finally:
            if saved is None:
                os.environ.pop("CFA_MITSUBA_THREADS", None)
            else:
                os.environ["CFA_MITSUBA_THREADS"] = saved


def _require_a_measurement(rows: list, failures: list[dict], out: Path) -> None:
    """A run in which every measurement failed is an error (exit 2), not an
    empty table: one line with the first cause; failures.csv lists all."""
    if rows or not failures:
        return
    f = failures[0]
    where = "/".join(str(f.get(k)) for k in ("scene", "cfa", "demosaic") if f.get(k) is not None)
    raise CfaMitsubaError(f"every one of the {len(failures)} measurement(s) failed (all listed in "
                          f"{out / 'failures.csv'}); the first, {where} {f.get('metric')} at "
                          f"{f.get('luminance')} cd/m^2: {f.get('error')}")


def _write_failures(out: Path, failures: list[dict], log) -> None:
    """failures.csv lists every metric that could not be measured (absent
    from metrics.csv); without failures, no file (a stale one is removed)."""
    target = out / "failures.csv"
    if not failures:
        target.unlink(missing_ok=True)
        return
    import pandas as pd

    with atomic_output(target) as tmp:
        pd.DataFrame(failures).to_csv(tmp, index=False)
    # a warning, not progress: on stderr even under --quiet (the log may be silent)
    def warn(msg):
        print(msg, file=sys.stderr)

    warn(f"warning: {len(failures)} metric value(s) could not be measured; see {target}")
    for f in failures[:5]:
        warn(f"  {f['scene']}/{f['cfa']}/{f['demosaic']}/L{float(f.get('luminance', 0)):g} {f['metric']}: {f['error']}")


def _range_pair(r) -> list[float]:
    """[worst, best] of a ScoreRange or a (worst, best) pair."""
    return [float(r.worst), float(r.best)] if hasattr(r, "worst") else [float(r[0]), float(r[1])]


def timing_summary(result: StudyResult) -> str:
    """The one line that says where a study's time went."""
    timing, n_tasks, reused = result.timing, result.tasks_total, result.tasks_reused
    p, t = timing["phases"], timing["tasks"]
    parts = [f"render {p.get('render_s', 0):.1f} s", f"evaluate {p.get('evaluate_s', 0):.1f} s"]
    if "report_s" in p:
        parts.append(f"report {p['report_s']:.1f} s")
    inner = ", ".join(f"{k[:-2]} {v:.1f} s" for k, v in t.items())
    return (f"done in {p.get('total_s', 0):.1f} s ({'; '.join(parts)}); {n_tasks - reused} task(s) run, "
            f"{reused} reused; worker time: {inner}")
