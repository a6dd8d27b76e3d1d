"""``cfa-mitsuba study CONFIG.toml [--out DIR --scheduler ADDRESS --workers N]``."""

from __future__ import annotations

from .argtypes import positive_int

HELP = "run a study from a TOML config: renders, captures, metrics, scores, report"

DESCRIPTION = """\
Run a study: render each scene once (through the shared render cache), then
capture and process every (CFA, demosaic, luminance) and compute the metrics
each scene feeds.  Writes DIR/metrics.csv (tidy), DIR/scores.csv (normalised
scores and ranks), DIR/report.html and DIR/figures/.

An interrupted study (Ctrl-C, a killed process) picks up where it stopped
when run again with the same --out: finished work is kept.

Examples:
  cfa-mitsuba study configs/quick.toml
  cfa-mitsuba study configs/paper.toml --out results/paper --workers 2
  cfa-mitsuba study configs/paper.toml --scheduler tcp://10.0.0.5:8786
"""


def add_arguments(parser) -> None:
    parser.add_argument("config", metavar="CONFIG.toml", help="the study config (see configs/)")
    parser.add_argument("--out", metavar="DIR", help="results directory (default: results/<config name>)")
    parser.add_argument("--workers", type=positive_int, metavar="N",
                        help="local worker processes (default: the config's 'workers', else $CFA_MITSUBA_WORKERS, else 2)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="run on a Dask cluster, e.g. tcp://HOST:8786 (needs the 'dask' extra)")
    parser.add_argument("--worker-max-tasks", type=positive_int, metavar="N",
                        help="recycle a local worker after N tasks (default: the config's worker_max_tasks, else 1000)")
    parser.add_argument("--worker-max-memory", metavar="SIZE",
                        help="recycle a local worker once its memory passes SIZE, e.g. 4G (default: the config's "
                             "worker_max_memory, else 80%% of the memory available per worker)")
    parser.add_argument("--no-report", action="store_true", help="write the tables only, no HTML report")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bars or log lines: print only the result path (warnings still go to stderr)")
    parser.add_argument("--force", action="store_true",
                        help="start a study above the size limits (estimated time over 24 h, over 100,000 tasks)")


def run(args) -> int:
    import time
    from pathlib import Path

    from ..report import build_report, report_workers
    from ..study.config import load_config
    from ..study.runner import run_study, timing_summary, write_timing

    config = load_config(args.config)
    from ..io.progress import stderr_log
    from ..io.validate import safe_name

    # the config's name is a label, never a path: '../../x' must not leave results/
    out = Path(args.out) if args.out else Path("results") / safe_name(config.name)
    from ..io.limits import parse_size

    memory = parse_size(args.worker_max_memory, "--worker-max-memory") if args.worker_max_memory else None
    log = stderr_log(args.quiet)
    result = run_study(config, out, workers=args.workers, scheduler=args.scheduler, progress=not args.quiet,
                       force=args.force, log=log, worker_max_tasks=args.worker_max_tasks, worker_max_memory=memory)
    report = not args.no_report and config.output.get("report", True)
    if report:
        t = time.perf_counter()
        # the figures drawn in as many processes as the study's local workers (at most the cores)
        build_report(result.out_dir, formats=config.output.get("figures", ("png", "svg")),
                     thumbnails=config.output.get("thumbnails", True), timing=result.timing,
                     workers=report_workers(args.workers or config.workers), progress=not args.quiet)
        phases = result.timing["phases"]
        phases["report_s"] = time.perf_counter() - t
        phases["total_s"] += phases["report_s"]
        write_timing(result)
    log(timing_summary(result))
    print(result.out_dir / ("report.html" if report else "metrics.csv"))
    return 0
