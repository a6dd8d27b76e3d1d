"""``cfa-mitsuba parity PATH... [--json]``: run parity cases against ISETCam."""

from __future__ import annotations

HELP = "run parity cases (TOML) that compare this chain with ISETCam's published values"

DESCRIPTION = """\
Run parity cases: each TOML file names an ISETCam script, the value it
gives (expected), a relative tolerance (for a result in dB, that fraction
of the expected dB, printed in dB) and the mode to run our chain in
('isetcam': ISETCam's mechanisms; 'default': this project's physics).
PATH is a case file or a folder of them (*.toml, recursively).  Prints one
line per case (name, mode, expected, value, the difference and the
tolerance, in dB for SNRs and in percent otherwise, verdict); --json prints
one JSON array instead, per case name, expected, value, tolerance and
verdict (agrees / differs) plus mode, kind, unit, relative_difference,
difference and tolerance_abs (in the result's unit), source and details.  docs/isetcam-parity.md explains every case and difference.

  cfa-mitsuba parity tests/parity/isetcam
  cfa-mitsuba parity tests/parity/isetcam/pixel-mtf-2um.toml --json
"""


def add_arguments(parser) -> None:
    parser.add_argument("paths", nargs="+", metavar="PATH", help="a parity case (.toml) or a folder of cases")
    parser.add_argument("--json", action="store_true", help="print one JSON array on stdout")
    parser.add_argument("--quiet", action="store_true", help="no progress bar (the results still print)")


def run(args) -> int:
    import json
    import sys

    from ..io.sidecar import json_default
    from ..study.parity import describe_difference, run_parity

    results = run_parity(args.paths, progress=not (args.quiet or args.json))
    if args.json:
        sys.stdout.write(json.dumps(results, default=json_default, allow_nan=False) + "\n")
        return 0
    for r in results:
        diff, tol = describe_difference(r)
        print(f"{r['name']:<32} {r['mode']:<8} expected {r['expected']:<10g} value {r['value']:<10.4g} "
              f"{r['unit']:<6} {diff:>10} (tolerance {tol:>9})  {r['verdict']}")
    return 0
