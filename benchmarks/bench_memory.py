"""Peak memory against cfa_mitsuba.io.limits' estimate, at the paper's size
(issue 15: the estimate within 25 % of the measured peak).

    python benchmarks/bench_memory.py [--spp 16] [--scene puppy]

Each case runs in a fresh Python process that reports its own peak resident
memory (``resource.getrusage(RUSAGE_SELF).ru_maxrss``) when done:

* render: ``cfa-mitsuba render SCENE --no-cache`` at 720 x 636, 31 bands
  (the render's memory does not depend on spp, so --spp only sets the time;
  the paper's puppy uses 256);
* capture: ``cfa-mitsuba capture`` of that EXR with bayer;
* process: ``cfa-mitsuba process`` of that raw file with pocs;
* study task: one ``evaluate_task`` (the scene at 100 cd/m^2, bayer, all four
  demosaics and the scene's metrics) on the cached render, as a study worker
  runs it.

Prints one table (measured, estimated, ratio) and exits 1 if any estimate is
off by more than 25 %.  A renders cache of its own (temporary) is used.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from cfa_mitsuba.io import limits  # noqa: E402

_PEAK = "import resource, sys; print('PEAK', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, file=sys.stderr)"


def _peak(code: str, env: dict) -> int:
    """Run ``code`` in a fresh interpreter; its peak resident memory, bytes."""
    proc = subprocess.run([sys.executable, "-c", code + "\n" + _PEAK], capture_output=True, text=True, cwd=REPO,
                          env=env)
    if proc.returncode != 0:
        raise SystemExit(f"case failed:\n{code}\n{proc.stderr[-3000:]}")
    line = [x for x in proc.stderr.splitlines() if x.startswith("PEAK ")][-1]
    return int(line.split()[1])


def _cli(*args) -> str:
    return (f"from cfa_mitsuba.cli import main\nrc = main({[str(a) for a in args]!r})\n"
            "assert rc == 0, rc")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="puppy", help="scene to render and evaluate (default puppy)")
    ap.add_argument("--spp", type=int, default=16, help="render spp (memory does not depend on it; default 16)")
    ap.add_argument("--width", type=int, default=720)
    ap.add_argument("--height", type=int, default=636)
    args = ap.parse_args()
    w, h, b = args.width, args.height, 31

    with tempfile.TemporaryDirectory(prefix="bench-memory-") as tmp:
        tmp = Path(tmp)
        env = {**os.environ, "CFA_MITSUBA_CACHE": str(tmp / "cache"), "PYTHONPATH": str(REPO)}
        env.pop(limits.MEMORY_ENV, None)
        size = ("--width", w, "--height", h, "--spp", args.spp)
        rows = []
        rows.append((f"render {args.scene} {w} x {h} x {b} bands, {args.spp} spp",
                     _peak(_cli("render", args.scene, "--out", tmp / "r", "--no-cache", *size), env),
                     limits.estimate_render_bytes(w, h, b)))
        exr = tmp / "r" / f"{args.scene}.exr"
        rows.append((f"capture {w} x {h} x {b}, bayer",
                     _peak(_cli("capture", exr, "--cfa", "bayer", "--out", tmp / "raw.npz"), env),
                     limits.estimate_capture_bytes(h, w, b)))
        rows.append((f"process {w} x {h}, bayer (3 channels), pocs",
                     _peak(_cli("process", tmp / "raw.npz", "--demosaic", "pocs", "--out", tmp / "out.npz"), env),
                     limits.estimate_process_bytes(h, w, 3)))
        config = {"scenes": [args.scene], "cfas": ["bayer"],
                  "demosaics": ["bilinear", "laplacian", "adaptive-laplacian", "pocs"],
                  "render": {args.scene: {"width": w, "height": h, "spp": args.spp}}}
        setup = ("from cfa_mitsuba.study.config import parse_config\n"
                 "from cfa_mitsuba.study.runner import plan_study\n"
                 "from cfa_mitsuba.study import tasks\n"
                 f"sources, todo = plan_study(parse_config({json.dumps(config)}), None)\n")
        subprocess.run([sys.executable, "-c", setup + "tasks.render_task(sources[0])"], check=True, cwd=REPO, env=env,
                       capture_output=True)  # into the cache, not measured
        rows.append((f"study task: {args.scene}, bayer, 4 demosaics, its metrics",
                     _peak(setup + "r = tasks.evaluate_task(todo[0])\nassert r.rows, r", env),
                     limits.estimate_task_bytes(h, w, b)))

    print(f"{'case':<58} {'measured':>10} {'estimate':>10} {'ratio':>6}")
    worst = 0.0
    for name, measured, estimate in rows:
        ratio = estimate / measured
        worst = max(worst, abs(ratio - 1))
        print(f"{name:<58} {measured / 2**20:>7.0f} MiB {estimate / 2**20:>6.0f} MiB {ratio:>6.2f}")
    print(f"largest deviation {100 * worst:.1f} % (target: within 25 %)")
    return 0 if worst <= 0.25 else 1


if __name__ == "__main__":
    sys.exit(main())
