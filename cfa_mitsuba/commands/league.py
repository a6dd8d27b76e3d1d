"""``cfa-mitsuba league CONFIG.toml [--out DIR --workers N --scheduler ADDRESS]``."""

from __future__ import annotations

from .argtypes import positive_int

HELP = "every CFA with the demosaics that suit it through the full chain; the best per aspect"

DESCRIPTION = """\
Run a study config with every CFA and demosaic (configs/league.toml: all the
project's CFAs, 3-400 cd/m^2 under the exposure program), keep per CFA the
demosaics that suit it (within 1 dB of its best measured PSNR, `cfa-mitsuba
list demosaics`), and name per aspect (colour, sharpness, detail, moire, low
light, overall) the entries whose rank interval contains 1.  Writes
DIR/league.csv (one row per CFA and kept demosaic, with its source),
DIR/league_decisions.csv, DIR/league.html and DIR/study/.

Examples:
  cfa-mitsuba league configs/league.toml --out docs/example-league
"""


def add_arguments(parser) -> None:
    parser.add_argument("config", metavar="CONFIG.toml", help="a study config (configs/league.toml)")
    parser.add_argument("--out", metavar="DIR", help="results directory (default: results/<config name>)")
    parser.add_argument("--workers", type=positive_int, metavar="N", help="local worker processes (default 2)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="run the study on a Dask cluster")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")


def run(args) -> int:
    import sys
    from pathlib import Path

    from ..design.league import run_league
    from ..io.validate import safe_name
    from ..study.config import load_config

    out = Path(args.out) if args.out else Path("results") / safe_name(load_config(args.config).name)
    page = run_league(args.config, out, workers=args.workers, scheduler=args.scheduler, progress=not args.quiet,
                      log=lambda msg: print(msg, file=sys.stderr))
    print(page)
    return 0
