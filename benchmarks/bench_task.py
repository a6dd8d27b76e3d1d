"""One paper-study capture, stage by stage: time per demosaic and per metric.

    python benchmarks/bench_task.py [--scene puppy] [--cfas bayer,rgbw1] [--luminance 100]
                                    [--repeat 3] [--against REV]

Takes the paper study's (configs/paper.toml) evaluation task of each CFA on
one scene and luminance (the puppy at 100 cd/m^2, 636 x 720, by default),
makes its optical image and ideal image once (not timed, as a study worker
reuses them), then times, best of ``--repeat``: the capture, each demosaic
(white balance, demosaic, colour matrix, sRGB: the chain's ``process``) and
each metric on that demosaic's output (mean-matched, as the study measures
it; what depends on the ideal image alone is computed once per ideal, as in
the study).  With ``--against REV`` the same runs again on commit REV,
checked out beside this tree in a temporary git worktree, in the same
invocation, and the table adds REV's times and the ratio REV / this tree.

The render comes from the render cache (rendered first if missing, not
timed).  Times are CPU seconds of the process (time.process_time: less moved by
other work on a shared machine than wall time); compare the
ratios within one run, and read the load average printed with them.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def measure(scene: str, cfas: list[str], luminance: float, repeat: int) -> dict:
    """{stage: best seconds}: the stages of one task per CFA on ``scene``."""
    from cfa_mitsuba import metrics as m
    from cfa_mitsuba.study.chain import CameraChain
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import plan_study
    from cfa_mitsuba.study.task_values import realisation_seeds
    from cfa_mitsuba.study.tasks import load_scene_image

    config = load_config(REPO / "configs" / "paper.toml")
    _, tasks = plan_study(config, None)
    best: dict[str, float] = {}

    def timed(key, fn, *args, **kw):
        t0 = time.process_time()
        out = fn(*args, **kw)
        best[key] = min(best.get(key, float("inf")), time.process_time() - t0)
        return out

    for cfa in cfas:
        task = next((t for t in tasks if t.scene == scene and t.cfa == cfa and t.condition.luminance == luminance),
                    None)
        if task is None:
            raise SystemExit(f"bench_task: the paper study has no task for {scene} / {cfa} at {luminance:g} cd/m^2")
        cond, chain = task.condition, CameraChain(task.chain)
        key = json.dumps(task.source, sort_keys=True)
        oi = chain.optical(load_scene_image(task.source), cond, key)
        ideal = chain.ideal(oi, cond, key)
        seed = realisation_seeds(cond.seed, task.scene, cond.luminance, 1)[0]
        options = chain.settings.metric_options_for(cond)
        for _ in range(repeat):
            raw = timed(f"{cfa} capture", chain.capture, oi, cfa, cond, seed)
            for method in task.demosaics:
                out = timed(f"{cfa} process {method}", chain.process, raw, method, cond)
                cam = m.mean_match(out.xyz, ideal.xyz) if chain.settings.mean_match else out.xyz
                inputs = chain.inputs(ideal, cam, cond)
                for name in task.metrics:
                    timed(f"{cfa} {method} metric {name}", m.evaluate, name, inputs, **options.get(name, {}))
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="puppy")
    ap.add_argument("--cfas", default="bayer,rgbw1", help="comma-separated paper CFAs (default bayer,rgbw1)")
    ap.add_argument("--luminance", type=float, default=100.0, help="cd/m^2 (a level the paper study has)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--against", metavar="REV", help="also time commit REV (git worktree beside this tree)")
    ap.add_argument("--json", action="store_true", help="print one JSON object {stage: seconds}")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(REPO))
    own = [f"--scene={args.scene}", f"--cfas={args.cfas}", f"--luminance={args.luminance}",
           f"--repeat={args.repeat}"]
    if args.json:
        print(json.dumps(measure(args.scene, args.cfas.split(","), args.luminance, args.repeat)))
        return 0
    this = _run_with_package(REPO, own)  # a fresh process each, so neither inherits the other's caches
    other = None
    if args.against:
        from _worktree import checked_out  # benchmarks/, beside this script

        with checked_out(args.against) as tree:
            other = _run_with_package(tree, own)  # this script, that tree's package
    print(f"{args.scene} at {args.luminance:g} cd/m^2, best of {args.repeat} (seconds; "
          f"load average {' '.join(f'{x:.1f}' for x in os.getloadavg())})")
    head = f"{'stage':<44}{'this':>9}"
    if other:
        head += f"{args.against[:12]:>14}{'ratio':>8}"
    print(head)
    for key, v in this.items():
        line = f"{key:<44}{v:>9.3f}"
        if other and key in other:
            line += f"{other[key]:>14.3f}{other[key] / v:>8.2f}"
        print(line)
    total = sum(this.values())
    line = f"{'total':<44}{total:>9.3f}"
    if other:
        o = sum(other[k] for k in this if k in other)
        line += f"{o:>14.3f}{o / total:>8.2f}"
    print(line)
    return 0


def _run_with_package(tree: Path, args: list[str]) -> dict:
    """This script's measurement with ``tree``'s package imported."""
    env = {**os.environ, "PYTHONPATH": str(tree), "BENCH_TASK_REPO": str(tree)}
    proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), *args, "--json"], env=env,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"bench_task: the run on {tree} failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


if __name__ == "__main__":
    REPO = Path(os.environ.get("BENCH_TASK_REPO", REPO))
    sys.exit(main())
