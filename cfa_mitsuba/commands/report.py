"""``cfa-mitsuba report RESULTS_DIR``: rebuild a study's report from its files."""

from __future__ import annotations

HELP = "rebuild a study's report.html and figures/ from its results directory"

DESCRIPTION = """\
Rebuild RESULTS_DIR/report.html (one self-contained page: the paper's Tables
1-3, radar and rank plots, MTF, moire, ColorChecker, S-CIELAB, gray-bar and
luminance figures, thumbnails) and RESULTS_DIR/figures/ from what a study
wrote there: metrics.csv (required), scores.csv, ranges.json, timing.json,
config.json and details/.  Nothing is rendered or measured again; a partial
or older results directory gives a report of what it holds.

  cfa-mitsuba report results/quick
  cfa-mitsuba report results/paper --formats png --no-thumbnails
"""


def add_arguments(parser) -> None:
    parser.add_argument("results_dir", metavar="RESULTS_DIR",
                        help="a study's output directory (holds metrics.csv)")
    parser.add_argument("--formats", default="png,svg", metavar="LIST",
                        help="figure files to write under figures/: comma-separated from png, svg, pdf, "
                             "or 'none' (default: png,svg; the page embeds its figures either way)")
    parser.add_argument("--no-thumbnails", dest="thumbnails", action="store_false",
                        help="leave out the sheets of camera outputs (the largest part of the page)")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="processes that draw and encode the figures (default: 2, at most the cores)")
    parser.add_argument("--verbose", action="store_true", help="print the time each figure takes (stderr)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar: print only the report's path")


def run(args) -> int:
    import sys

    from ..report import build_report, report_workers

    text = str(args.formats).strip().lower()
    formats = () if text in ("", "none") else tuple(f.strip() for f in text.split(",") if f.strip())
    log = (lambda msg: print(msg, file=sys.stderr)) if args.verbose else None
    path = build_report(args.results_dir, formats=formats, thumbnails=args.thumbnails, log=log,
                        workers=args.workers if args.workers is not None else report_workers(None),
                        progress=not args.quiet)
    print(path)
    return 0
