"""Child process that loads a user's scene file once before the parent
does (``python -m cfa_mitsuba.render.loadcheck VARIANT FILE.xml
[--allow-outside-paths] [--asset-root DIR] [--define=NAME=VALUE ...]``); why: :func:`.userxml._loads_elsewhere`.

Exit status 0: Mitsuba instantiated the scene.  Exit status
:data:`.userxml.LOADCHECK_REFUSED`: it did not, and the last line on
stderr says why, in the words the parent shows the user.
"""

from __future__ import annotations

import argparse
import sys

from ..errors import CfaMitsubaError
from .userxml import LOADCHECK_REFUSED, load_check


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m cfa_mitsuba.render.loadcheck")
    ap.add_argument("variant")
    ap.add_argument("path")
    ap.add_argument("--allow-outside-paths", action="store_true")
    ap.add_argument("--asset-root")
    ap.add_argument("--define", action="append", default=[])
    args = ap.parse_args(argv)
    try:
        load_check(args.path, args.allow_outside_paths, args.variant, args.define, args.asset_root)
    except CfaMitsubaError as exc:
        print(str(exc), file=sys.stderr)
        return LOADCHECK_REFUSED
    return 0


if __name__ == "__main__":
    sys.exit(main())
