"""What a command or a study worker pays before it does any work: the
start of `cfa-mitsuba` commands and the first use of the chain's modules,
this tree against another commit, alternating in one run (A B A B ...), so
a loaded machine slows both alike.

    python benchmarks/bench_startup.py --against REV [--repeat N] [--json PATH]

REV is checked out into a temporary git worktree.  Each case runs as a
fresh interpreter with the tree's folder first on ``PYTHONPATH``, and is
timed from the outside (process start to exit).  Both trees are
byte-compiled first (``compileall``, as setup.sh does), so what is measured
is the imports, not compiling them.  The table gives the median of each
side and their ratio (REV / this tree: above 1, this tree starts faster).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

#: (name, python arguments): what a listing, a command's help, a capture's
#: first spectral lookup, and a study worker's imports of the chain start with
CASES = (
    ("list cfas", ["-m", "cfa_mitsuba", "list", "cfas"]),
    ("capture --help", ["-m", "cfa_mitsuba", "capture", "--help"]),
    ("first spectral lookup", ["-c", "from cfa_mitsuba import spectra; spectra.cmfs_xyz()"]),
    ("chain imports", ["-c", "import cfa_mitsuba.study.chain, cfa_mitsuba.isp, cfa_mitsuba.metrics, "
                             "cfa_mitsuba.sensor, cfa_mitsuba.report.build"]),
)


def _time(tree: Path, args: list[str]) -> float:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, *args], cwd=tempfile.gettempdir(), env=env, capture_output=True,
                          text=True, timeout=300)
    elapsed = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"bench_startup: {args} failed in {tree}: {proc.stderr.strip().splitlines()[-1:]}")
    return elapsed


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", required=True, help="the commit to compare with")
    ap.add_argument("--repeat", type=int, default=5, help="runs of each case on each side (default 5)")
    ap.add_argument("--json", type=Path, help="write the table here")
    args = ap.parse_args(argv)
    from _worktree import checked_out  # benchmarks/, beside this script

    with checked_out(args.against) as other:
        for tree in (REPO, other):
            subprocess.run([sys.executable, "-m", "compileall", "-q", "-j", "0", str(tree / "cfa_mitsuba")],
                           check=True, stdout=subprocess.DEVNULL)
        for tree in (REPO, other):  # the tree's package, not an installed one
            env = {**os.environ, "PYTHONPATH": str(tree)}
            where = subprocess.run([sys.executable, "-c", "import cfa_mitsuba; print(cfa_mitsuba.__file__)"],
                                   cwd=tempfile.gettempdir(), env=env, capture_output=True, text=True).stdout
            if not Path(where.strip()).resolve().is_relative_to(tree.resolve()):
                raise SystemExit(f"bench_startup: {tree} imports cfa_mitsuba from {where.strip()}")
        rows = {}
        for name, case in CASES:
            ours, theirs = [], []
            for i in range(args.repeat):  # A B, then B A: neither side always runs second
                pair = ((REPO, ours), (other, theirs)) if i % 2 == 0 else ((other, theirs), (REPO, ours))
                for tree, out in pair:
                    out.append(_time(tree, case))
            rows[name] = {"this_s": statistics.median(ours), "against_s": statistics.median(theirs)}
            rows[name]["ratio"] = rows[name]["against_s"] / rows[name]["this_s"]
    print(f"{'case':24s} {'this tree (s)':>14s} {args.against[:12]:>14s} {'ratio':>7s}")
    for name, r in rows.items():
        print(f"{name:24s} {r['this_s']:14.2f} {r['against_s']:14.2f} {r['ratio']:7.2f}")
    if args.json:
        head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True).stdout.strip()
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"this": head, "against": args.against, "repeat": args.repeat,
                                         "python": sys.version.split()[0], "cases": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
