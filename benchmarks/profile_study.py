"""Where a study's evaluation time goes, by function (cProfile).

    python benchmarks/profile_study.py [--paper | --config FILE] [--cfas bayer,rgbw1] [--top 25]
    python benchmarks/profile_study.py [--paper | --config FILE] --after RESULTS_DIR

``--after``: the work after the evaluation instead, on a copy of a finished
study's results directory (the same config): the study run again, which
takes every task from the copy's ``.work/`` and writes the tables, then the
report built in this one process (a study draws it in several: read the
report's share as the work they divide).

Plans the study (configs/paper.toml with --paper), renders what it needs
into the render cache first (not profiled), then runs the evaluation tasks
of the chosen CFAs (default: every CFA) one after another in this process
under cProfile, and prints two tables: the time per camera stage (the
chain's own timers) and the functions with the most time of their own
(``tottime``) and, below, the most cumulative time.  Per-process work that
the study shares between tasks (the optical image, the ideal sensor) is
counted once per (scene, condition), as in a worker.

Times are seconds of this process on a shared machine: read them as
proportions.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def _tasks(config_path: Path, cfas: list[str] | None, details_dir: str | None):
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import plan_study

    config = load_config(config_path)
    sources, tasks = plan_study(config, details_dir)
    if cfas:
        tasks = [t for t in tasks if (t.cfa_label or t.cfa) in cfas]
    return config, sources, tasks


def _table(rows, header) -> str:
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    line = lambda r: "  ".join(str(c).rjust(w) if i else str(c).ljust(w) for i, (c, w) in enumerate(zip(r, widths)))
    return "\n".join([line(header), line(["-" * w for w in widths]), *map(line, rows)])


def _functions(stats: pstats.Stats, key: str, top: int, total: float) -> list:
    stats.sort_stats(key)
    rows = []
    for func in stats.fcn_list[:top]:
        cc, nc, tt, ct, _ = stats.stats[func]
        file, line, name = func
        where = f"{Path(file).name}:{line}" if file != "~" else "(builtin)"
        rows.append([f"{name} [{where}]", nc, f"{tt:.2f}", f"{ct:.2f}", f"{100 * (tt if key == 'tottime' else ct) / total:.1f}"])
    return rows


def _print_functions(prof: cProfile.Profile, top: int, wall: float) -> None:
    stats = pstats.Stats(prof, stream=io.StringIO())
    header = ["function [file:line]", "calls", "own s", "cum s", "%"]
    print(f"\nmost time of their own (% of wall in the function itself)\n")
    print(_table(_functions(stats, "tottime", top, wall), header))
    print(f"\nmost cumulative time (% of wall under the function)\n")
    print(_table(_functions(stats, "cumulative", top, wall), header))


def _after(config_path: Path, results: Path, args) -> int:
    """--after: the tables and the report of a finished study, on a copy, under cProfile."""
    import shutil

    from cfa_mitsuba.report import build_report
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import _task_id, plan_study, run_study

    if not (results / ".work").is_dir():
        print(f"profile_study: {results} holds no finished study (no .work/ folder)", file=sys.stderr)
        return 2
    config = load_config(config_path)
    missing = [t for t in plan_study(config, str(results / "details"))[1]
               if not (results / ".work" / f"{_task_id(t)}.json").is_file()]
    if missing:  # the study would evaluate them: not what is asked for
        print(f"profile_study: {len(missing)} task(s) of {config_path.name} are not finished in {results}",
              file=sys.stderr)
        return 2
    scratch = tempfile.TemporaryDirectory(prefix="profile_after_")
    copy = Path(scratch.name) / results.name
    shutil.copytree(results, copy, ignore=shutil.ignore_patterns("report.html", "figures"))
    prof = cProfile.Profile()
    t0 = time.perf_counter()
    prof.enable()
    result = run_study(config, copy, workers=1, progress=False, log=lambda msg: None)
    t1 = time.perf_counter()
    build_report(copy, formats=config.output.get("figures", ("png", "svg")),
                 thumbnails=config.output.get("thumbnails", True), timing=result.timing)
    prof.disable()
    wall = time.perf_counter() - t0
    stages = [["tables (the study resumed: every task reused)", f"{t1 - t0:.1f}", f"{100 * (t1 - t0) / wall:.1f}"],
              ["report (one process)", f"{wall - (t1 - t0):.1f}", f"{100 * (wall - (t1 - t0)) / wall:.1f}"]]
    print(f"{config_path.name}: after the evaluation of {results}, {wall:.1f} s in one process under cProfile\n")
    print(_table(stages, ["stage", "s", "% of wall"]))
    if args.dump:
        prof.dump_stats(args.dump)
    _print_functions(prof, args.top, wall)
    scratch.cleanup()
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    src = ap.add_mutually_exclusive_group()
    src.add_argument("--paper", action="store_true", help="configs/paper.toml (the default is configs/quick.toml)")
    src.add_argument("--config", help="a study config")
    ap.add_argument("--cfas", help="comma-separated CFA labels to profile (default: all)")
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--dump", help="also write the raw cProfile statistics to this file (pstats/snakeviz read it)")
    ap.add_argument("--no-details", action="store_true",
                    help="skip what a study writes under details/ for its report (curves, maps, thumbnails)")
    ap.add_argument("--after", metavar="RESULTS_DIR",
                    help="profile the tables and the report of this finished study (on a copy) instead")
    args = ap.parse_args(argv)
    config_path = Path(args.config) if args.config else REPO / "configs" / ("paper.toml" if args.paper else "quick.toml")
    if args.after:
        return _after(config_path, Path(args.after), args)
    from cfa_mitsuba.study.tasks import evaluate_task, render_task

    # the details a study writes for its report, into a folder deleted afterwards, as run_study plans them
    scratch = tempfile.TemporaryDirectory(prefix="profile_study_")
    details = None if args.no_details else str(Path(scratch.name) / "details")
    config, sources, tasks = _tasks(config_path, args.cfas.split(",") if args.cfas else None, details)
    t0 = time.perf_counter()
    for s in sources:
        render_task(s)
    print(f"{config_path.name}: {len(tasks)} evaluation task(s), {config.seeds} realisation(s) each; "
          f"renders ready in {time.perf_counter() - t0:.1f} s (not profiled)")
    stages: dict = {}
    prof = cProfile.Profile()
    t0 = time.perf_counter()
    prof.enable()
    for t in tasks:
        for k, v in evaluate_task(t).timing.items():
            stages[k] = stages.get(k, 0.0) + v
    prof.disable()
    wall = time.perf_counter() - t0
    print(f"\nevaluation wall time {wall:.1f} s in one process\n")
    rest = wall - sum(stages.values())  # the rows, the details for the report, the ideal's own rows
    print(_table([[k, f"{v:.1f}", f"{100 * v / wall:.1f}"] for k, v in sorted(stages.items(), key=lambda kv: -kv[1])]
                 + [["outside the stages", f"{rest:.1f}", f"{100 * rest / wall:.1f}"]],
                 ["stage", "s", "% of wall"]))
    if args.dump:
        prof.dump_stats(args.dump)
    _print_functions(prof, args.top, wall)
    scratch.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
