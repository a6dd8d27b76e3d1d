"""Worker memory over thousands of renders of a small user scene, with the
local workers recycled (cfa_mitsuba/study/executors.py) and, as the
control, without.

    nice -n 5 python benchmarks/bench_recycling.py --json docs/data/bench-recycling.json

Mitsuba keeps memory over many scene loads in one process (mitsuba3 issues
1890, 190); a study's workers are therefore recycled after a stated number
of tasks or past a memory ceiling.  This renders the white-panel test scene
(tests/data/scenes/whitepanel: a path-traced user Mitsuba XML) at 16 x 16
pixels and 4 spp, each render a fresh scene load with its own seed, through
the study's own ``LocalExecutor`` on two workers: first with recycling
(``--max-tasks``, default 250, and the default memory ceiling), then without
(the ``control``: no task limit, no ceiling).  Each task reports its worker's
resident memory after the render; the table gives, per window of renders,
the largest resident memory of any worker in each run.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

SCENE = REPO / "tests" / "data" / "scenes" / "whitepanel" / "whitepanel.xml"


def render_once(seed: int) -> tuple[float, float]:
    """One render of the scene (a fresh load); (resident MB after it, seconds)."""
    import cfa_mitsuba as cm
    from cfa_mitsuba.study.executors import _rss_bytes

    t0 = time.perf_counter()
    cm.render.render(str(SCENE), width=16, height=16, spp=4, seed=int(seed))
    return _rss_bytes() / 1e6, time.perf_counter() - t0


def run(n: int, workers: int, max_tasks: int | None, max_memory: int | None) -> dict:
    from cfa_mitsuba.study.executors import LocalExecutor

    rows = []
    t0 = time.perf_counter()
    with LocalExecutor(workers, max_tasks=max_tasks, max_memory=max_memory) as ex:
        for done, (seed, (rss_mb, seconds)) in enumerate(ex.map_unordered(render_once, range(n))):
            rows.append({"order": done, "seed": seed, "rss_mb": round(rss_mb, 1), "render_s": round(seconds, 4)})
        pids = len(ex.worker_pids)
        recycled, ceiling = ex.recycled, ex.max_memory
    return {"renders": n, "workers": workers, "max_tasks": max_tasks, "max_memory_bytes": ceiling,
            "worker_processes": pids, "recycled": recycled, "wall_s": round(time.perf_counter() - t0, 1),
            "rows": rows}


def windows(result: dict, size: int) -> list[float]:
    """The largest resident memory (MB) of any worker in each window of ``size`` renders."""
    rows = result["rows"]
    return [max(r["rss_mb"] for r in rows[i:i + size]) for i in range(0, len(rows), size)]


def summary(runs: dict, size: int) -> str:
    names = list(runs)
    lines = [f"{'renders':>9} " + " ".join(f"{n + ' MB':>16}" for n in names)]
    cols = {n: windows(runs[n], size) for n in names}
    for i in range(max(len(c) for c in cols.values())):
        lines.append(f"{i * size + 1:>4}-{(i + 1) * size:<4} " + " ".join(
            f"{cols[n][i]:>16.0f}" if i < len(cols[n]) else " " * 16 for n in names))
    for n in names:
        r = runs[n]
        lines.append(f"{n}: {r['worker_processes']} worker processes ({r['recycled']} recycled), "
                     f"{r['wall_s']:.0f} s; first window {cols[n][0]:.0f} MB, last {cols[n][-1]:.0f} MB")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--renders", type=int, default=2000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--max-tasks", type=int, default=250, help="the recycled run's task limit per worker")
    ap.add_argument("--window", type=int, default=200, help="renders per row of the table")
    ap.add_argument("--no-control", action="store_true", help="skip the run without recycling")
    ap.add_argument("--json", type=Path, help="write both runs here")
    ap.add_argument("--from-json", type=Path, help="no renders: the table of runs saved by --json")
    args = ap.parse_args(argv)
    if args.from_json:  # no renders: the table and summary of saved runs
        saved = json.loads(args.from_json.read_text())
        runs = {("control" if k == "not recycled" else k): v for k, v in saved["runs"].items()}
        machine = {k: saved[k] for k in ("cores", "load_average")}
    else:
        runs = {"recycled": run(args.renders, args.workers, args.max_tasks, None)}
        if not args.no_control:
            runs["control"] = run(args.renders, args.workers, 10**9, 1 << 60)
        machine = {"cores": len(os.sched_getaffinity(0)), "load_average": os.getloadavg()}
    print(summary(runs, args.window))
    if args.json:
        doc = {"scene": str(SCENE.relative_to(REPO)), "size": [16, 16], "spp": 4, "window": args.window, **machine,
               "summary": {k: _summary(v, args.window) for k, v in runs.items()},
               "runs": {k: {**v, "window_max_rss_mb": windows(v, args.window)} for k, v in runs.items()}}
        args.json.write_text(json.dumps(doc, indent=1) + "\n")
    return 0


def _summary(result: dict, size: int) -> dict:
    """What docs/study.md quotes of a run: renders, processes, recycles, and
    the largest resident memory of any worker in its first and last window
    and over the whole run (MB)."""
    w = windows(result, size)
    return {"renders": result["renders"], "worker_processes": result["worker_processes"],
            "recycled": result["recycled"], "first_window_mb": w[0], "last_window_mb": w[-1], "max_mb": max(w),
            "growth_mb": round(w[-1] - w[0], 1)}


if __name__ == "__main__":
    sys.exit(main())
