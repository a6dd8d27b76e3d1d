"""``cfa-mitsuba design CONFIG.toml [--out DIR --scheduler ADDRESS --workers N]``."""

from __future__ import annotations

from .argtypes import positive_int

HELP = "search CFA layouts and filter spectra: proxy, full chain, Pareto front, report"

DESCRIPTION = """\
Design a CFA: rank every candidate of the config's search space (tile sizes,
alphabet, density bounds, optional parametric spectra) with a fast proxy,
exhaustively or by NSGA-II, then run the best through the full chain (the
study's renders, seeds and intervals) beside the named CFAs.  Writes
DIR/candidates.csv, DIR/pareto.csv, DIR/fullchain.csv, DIR/cfas/*.toml (one
CFA TOML per candidate run), DIR/agreement.json and DIR/design.html.

An interrupted design continues where it stopped when run again with the
same --out (evaluated candidates and finished full-chain tasks are kept).

Examples:
  cfa-mitsuba design configs/design-quick.toml
  cfa-mitsuba design configs/design-rgbw.toml --out results/rgbw --workers 2
"""


def add_arguments(parser) -> None:
    parser.add_argument("config", metavar="CONFIG.toml", help="the design config (see configs/design-*.toml)")
    parser.add_argument("--out", metavar="DIR", help="results directory (default: results/<config name>)")
    parser.add_argument("--workers", type=positive_int, metavar="N",
                        help="local worker processes for the full chain "
                             "(default: the config's, else $CFA_MITSUBA_WORKERS, else 2)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="run the full chain on a Dask cluster")
    parser.add_argument("--quiet", action="store_true", help="no progress bars or log lines: print only the report's path")
    parser.add_argument("--force", action="store_true", help="start a search estimated above 24 h")


def run(args) -> int:
    from pathlib import Path

    from ..design.config import load_design
    from ..design.run import run_design
    from ..io.validate import safe_name

    from ..io.progress import stderr_log

    config = load_design(args.config)
    out = Path(args.out) if args.out else Path("results") / safe_name(config.name)
    result = run_design(config, out, workers=args.workers, scheduler=args.scheduler, progress=not args.quiet,
                        log=stderr_log(args.quiet), force=args.force)
    print(result.out_dir / "design.html")
    return 0
