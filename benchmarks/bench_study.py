"""Where the quick study's worker time goes, with the optical image shared
by every CFA and demosaic of a (scene, condition) in a worker (the camera
chain, study/chain.py) and without it (computed again for every capture,
``CFA_MITSUBA_NO_OPTICS_MEMO=1``: the per-task work the study did before).

    python benchmarks/bench_study.py [--config configs/quick.toml] [--workers 2] [--repeat 1]

Renders are made once into a temporary cache first (not timed), so both
modes time only the evaluation.  Prints one table: worker time per stage
(summed over tasks, seconds), the evaluation's wall time, and the ratio
before / after.  Compare ratios within one run: the machine is shared.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from cfa_mitsuba.study.chain import NO_MEMO_ENV  # noqa: E402


def run(config: Path, out: Path, workers: int, shared: bool) -> dict:
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import run_study

    if shared:
        os.environ.pop(NO_MEMO_ENV, None)
    else:
        os.environ[NO_MEMO_ENV] = "1"  # inherited by the spawned workers
    try:
        result = run_study(load_config(config), out, workers=workers, progress=False, log=lambda m: None)
    finally:
        os.environ.pop(NO_MEMO_ENV, None)
    t = dict(result.timing["tasks"])
    t["evaluate wall"] = result.timing["phases"]["evaluate_s"]
    return t


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=str(REPO / "configs" / "quick.toml"))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["CFA_MITSUBA_CACHE"] = str(Path(tmp) / "cache")
        run(Path(args.config), Path(tmp) / "warm", args.workers, True)  # renders into the cache
        rows = {"before": [], "after": []}
        for i in range(args.repeat):
            for mode, shared in (("before", False), ("after", True)):
                rows[mode].append(run(Path(args.config), Path(tmp) / f"{mode}{i}", args.workers, shared))
    best = {mode: {k: min(r[k] for r in runs) for k in runs[0]} for mode, runs in rows.items()}
    print(f"quick study evaluation, {args.workers} worker(s), best of {args.repeat} "
          f"(load average {os.getloadavg()[0]:.1f})")
    print(f"{'stage':<16}{'before (s)':>12}{'after (s)':>12}{'before/after':>14}")
    for k in best["after"]:
        b, a = best["before"][k], best["after"][k]
        print(f"{k.replace('_s', ''):<16}{b:>12.2f}{a:>12.2f}{(b / a if a > 0 else float('nan')):>14.2f}")
    tb = sum(v for k, v in best["before"].items() if k.endswith("_s"))
    ta = sum(v for k, v in best["after"].items() if k.endswith("_s"))
    print(f"{'worker total':<16}{tb:>12.2f}{ta:>12.2f}{tb / ta:>14.2f}")
    print(json.dumps({"before": best["before"], "after": best["after"]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
