"""``cfa-mitsuba evaluate --renders DIR --cfa A,B --demosaic X,Y [--luminance L] --out DIR``."""

from __future__ import annotations

HELP = "evaluate rendered EXRs with chosen CFAs and demosaics -> metrics.csv"

DESCRIPTION = """\
Render once, evaluate many: every spectral EXR in --renders (as written by
`cfa-mitsuba render`) is captured with each CFA, processed with each
demosaicing method and compared with the ideal XYZ sensor on the metrics its
scene feeds (from the sidecar; a bare spectral EXR gets the image metrics).
Default optics, sensor and processing; use a study config for others.

Example:
  cfa-mitsuba render macbeth --out renders && cfa-mitsuba render chirp --out renders
  cfa-mitsuba evaluate --renders renders --cfa bayer,rgbw1 --demosaic bilinear,pocs --out eval
"""


def _list(text: str) -> list[str]:
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        import argparse

        raise argparse.ArgumentTypeError("expected a comma-separated list")
    return items


def _luminances(text: str) -> list[float]:
    import argparse
    import math

    out = []
    for t in _list(text):
        try:
            v = float(t)
        except ValueError:
            raise argparse.ArgumentTypeError(f"luminance must be a number, got {t!r}") from None
        if not (math.isfinite(v) and v > 0):
            raise argparse.ArgumentTypeError(f"luminance must be positive, got {t!r}")
        out.append(v)
    return out


def add_arguments(parser) -> None:
    parser.add_argument("--renders", required=True, metavar="DIR", help="directory of spectral EXRs (+ sidecars)")
    parser.add_argument("--cfa", required=True, type=_list, metavar="A,B",
                        help="CFA names or FILE.toml, comma-separated (cfa-mitsuba list cfas)")
    parser.add_argument("--demosaic", required=True, type=_list, metavar="X,Y",
                        help="demosaicing methods, comma-separated (cfa-mitsuba list demosaics)")
    parser.add_argument("--luminance", type=_luminances, metavar="L[,L2]",
                        help="mean scene luminance(s) in cd/m^2 (default: each render's own)")
    parser.add_argument("--out", required=True, metavar="DIR", help="where metrics.csv goes")
    parser.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    parser.add_argument("--seeds", type=int, default=3, metavar="N",
                        help="noise realisations per capture: each value is their mean with a 95 %% interval "
                             "(default 3, as in a study; 1 gives zero-width intervals)")
    parser.add_argument("--workers", type=int, metavar="N", help="local worker processes (default 2)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def run(args) -> int:
    from ..errors import CfaMitsubaError
    from ..isp import list_demosaics
    from ..sensor import get_cfa
    from ..study.evaluate_renders import evaluate_renders

    for c in args.cfa:
        get_cfa(c)  # refuse unknown CFAs before any work
    known = [n for n, _ in list_demosaics()]
    for d in args.demosaic:
        if d not in known:
            raise CfaMitsubaError(f"unknown demosaicing method {d!r} (known: {', '.join(known)})")
    if args.workers is not None and args.workers < 1:
        raise CfaMitsubaError(f"--workers must be at least 1, got {args.workers}")
    if args.seeds < 1:
        raise CfaMitsubaError(f"--seeds must be at least 1, got {args.seeds}")
    if args.seed < 0:
        raise CfaMitsubaError(f"--seed must be non-negative, got {args.seed}")
    table = evaluate_renders(args.renders, args.cfa, args.demosaic, args.out,
                             luminances=args.luminance or (None,), seed=args.seed, workers=args.workers,
                             progress=not args.quiet, realisations=args.seeds)
    from pathlib import Path

    print(Path(args.out) / "metrics.csv")
    print(table.to_string(index=False), flush=True)
    return 0
