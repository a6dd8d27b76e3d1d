"""Study timing benchmarks.

Per phase, against another commit (issue 25)::

    python benchmarks/bench_study.py --paper [--subset bayer,rgbw1] [--against REV [--same-config] [--abba]
                                     [--target RATIO]] [--warm-only] [--keep DIR] [--json FILE] [--workers 2]

runs the study (configs/paper.toml with --paper, else --config) through
``python -m cfa_mitsuba study`` twice per tree: *cold* (an empty render
cache in a temporary folder: every scene rendered) and *warm* (the same
cache again: renders reused), and prints the render, evaluate and report
phases of each (timing.json, wall clock) with the worker time per stage,
and the CPU seconds of the whole run (the study process and its workers:
what other jobs on a shared machine move least) with that CPU time divided
by the cores: no schedule of the same work on this machine finishes sooner,
so a wall-clock target below it needs less work, not better packing.  With
``--against REV`` the same runs are made on commit REV, checked out beside
this tree in a temporary git worktree, in the same invocation (this tree
and REV alternate, so a change of machine load hits both), and the table
adds the ratio REV / this tree.  ``--subset`` keeps only the listed CFAs
(a reduced paper study in minutes); ``--warm-only`` skips the cold runs and
uses the default render cache (renders made there first if missing);
``--same-config`` runs REV's copy of the config in both trees (the same
work where this tree's copy asks for more, e.g. ``render_seeds``);
``--abba`` runs this tree, REV, REV, this tree and keeps each tree's
faster run: a machine that slows (or speeds up) over the runs then favours
neither (measured: run second, REV's evaluate grew from 158 to 193 s over
four invocations while this tree's stayed at 108-111 s);
``--target RATIO`` records the evaluate time RATIO times faster than REV's
(the JSON's ``target``), and every run records each scene's floor
(``scene_floor_s``: the scene's worker seconds over the cores, the wall
time that scene's work alone needs), so a target can be read against what
one scene costs by itself; ``--keep DIR`` keeps each run's metrics CSVs and timing.json; ``--json
FILE`` writes the record (the kept runs, every run's evaluate phase, the
ratios REV / this tree and the command).  Each tree
runs its own copy of the config (its own configs/ file).  Each run's
worker milliseconds per capture by scene and stage (timing.json's
``scenes``) are printed beside the CPU floor per capture.  The chain's
regions of interest (study/roi.py) are on unless ``CFA_MITSUBA_NO_ROI=1``
is set in the environment (both trees inherit it).

The optics memo (the quick study with the optical image shared by every
CFA and demosaic of a scene, against recomputing it per capture,
``CFA_MITSUBA_NO_OPTICS_MEMO=1``)::

    python benchmarks/bench_study.py [--config configs/quick.toml] [--workers 2] [--repeat 1]

Compare ratios within one run: the machine is shared; the load averages
as the runs began and after them are printed with the table and recorded
(``load_average_before``, ``load_average``).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from cfa_mitsuba.io.portable import relative_command  # noqa: E402
from cfa_mitsuba.study.chain import NO_MEMO_ENV  # noqa: E402
from cfa_mitsuba.study.executors import _cpu_count  # noqa: E402


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


def memo_main(args) -> int:
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["CFA_MITSUBA_CACHE"] = str(Path(tmp) / "cache")
        run(Path(args.config or REPO / 'configs' / 'quick.toml'), Path(tmp) / "warm", args.workers, True)  # renders into the cache
        rows = {"before": [], "after": []}
        for i in range(args.repeat):
            for mode, shared in (("before", False), ("after", True)):
                rows[mode].append(run(Path(args.config or REPO / 'configs' / 'quick.toml'), Path(tmp) / f"{mode}{i}", args.workers, shared))
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


PHASES = ("render_s", "evaluate_s", "report_s", "total_s")
STAGES = ("optics_s", "capture_s", "process_s", "metrics_s")


def _subset_config(tree: Path, config: str, cfas: list[str] | None, folder: Path) -> Path:
    """``tree``'s copy of ``config`` (a path relative to the repository), its
    ``cfas`` list replaced by ``cfas`` when given, written into ``folder``."""
    text = (tree / config).read_text()
    if cfas:
        text, n = re.subn(r"^cfas\s*=\s*\[.*?\]", "cfas = " + json.dumps(cfas), text, count=1,
                          flags=re.MULTILINE | re.DOTALL)
        if n != 1:
            raise SystemExit(f"bench_study: {config} has no top-level 'cfas = [...]' to reduce")
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / Path(config).name
    out.write_text(text)
    return out


def _study(tree: Path, config: Path, out: Path, cache: Path | None, workers: int) -> dict:
    """One ``cfa_mitsuba study`` run of ``tree``'s package; its timing.json."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    env.pop("CFA_MITSUBA_NO_OPTICS_MEMO", None)
    if cache is not None:
        env["CFA_MITSUBA_CACHE"] = str(cache)
    cmd = [sys.executable, "-m", "cfa_mitsuba", "study", str(config), "--out", str(out), "--quiet",
           "--workers", str(workers)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"bench_study: the study failed in {tree}:\n{proc.stderr[-3000:]}")
    timing = json.loads((out / "timing.json").read_text())
    # CPU seconds of the study and its worker processes (reaped children count into ours): the measure
    # that machine load moves least, where the wall-clock phases above move with every other job
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {**{k: float(timing["phases"].get(k, 0.0)) for k in PHASES},
            **{k: float(timing["tasks"].get(k, 0.0)) for k in STAGES}, "cpu_s": cpu,
            "scenes": timing.get("scenes", {})}  # worker seconds per stage per scene (a tree before it: none)


def scene_floors(got: dict, cores: int) -> dict:
    """{scene: its worker seconds of every stage over the cores}: the wall
    time no schedule of that scene's work alone finishes sooner on this
    machine (a bound on what leaving out the other scenes' work can reach)."""
    return {scene: sum(float(t.get(s, 0.0)) for s in STAGES) / cores
            for scene, t in (got.get("scenes") or {}).items()}


def add_target(record: dict, ratio: float) -> None:
    """The record's ``target``: the evaluate phase ``ratio`` times faster than
    the tree it is measured against needs (``evaluate_s``), beside each
    scene's floor in this tree's run (:func:`scene_floors`)."""
    against = record["runs"][record["against"]]
    mode = next(iter(against))
    record["target"] = {"ratio": ratio, "mode": mode, "evaluate_s": against[mode]["evaluate_s"] / ratio}


def per_capture_table(name: str, mode: str, got: dict) -> list[str]:
    """The worker milliseconds per capture (one noise realisation of one
    CFA, processed by every demosaic) by scene and stage, from timing.json's
    ``scenes``; and the CPU floor per capture (all CPU time of the run over
    the cores and the captures)."""
    scenes = got.get("scenes") or {}
    if not scenes:
        return [f"{name} {mode}: no per-scene timing (timing.json without 'scenes')"]
    lines = [f"{name} {mode}: worker ms per capture" + " " * 4 + "".join(f"{s[:-2]:>10}" for s in STAGES)
             + f"{'total':>10}{'captures':>10}{'outputs':>9}"]
    for scene, t in scenes.items():
        n = max(int(t.get("captures", 0)), 1)
        per = [1e3 * float(t.get(s, 0.0)) / n for s in STAGES]
        lines.append(f"  {scene:<40}" + "".join(f"{v:>10.1f}" for v in per) + f"{sum(per):>10.1f}"
                     f"{int(t.get('captures', 0)):>10}{int(t.get('outputs', 0)):>9}")
    total = sum(int(t.get("captures", 0)) for t in scenes.values())
    if total:
        lines.append(f"  {'CPU floor (CPU s / cores / captures)':<40}{1e3 * got['cpu_floor_s'] / total:>10.1f} ms")
    return lines


def phases_main(args) -> int:
    given = Path(args.config or REPO / "configs" / "quick.toml").resolve()
    config = "configs/paper.toml" if args.paper else os.path.relpath(given, REPO)
    cfas = args.subset.split(",") if args.subset else None
    runs: dict[str, dict[str, dict]] = {}
    all_evaluate: dict[str, dict[str, list]] = {}  # every run's evaluate phase, in the order run
    before = os.getloadavg()  # what else ran on the machine as the runs began
    with tempfile.TemporaryDirectory() as tmp, contextlib.ExitStack() as other_tree:
        tmp = Path(tmp)
        trees = {"this": REPO}
        if args.against:
            from _worktree import checked_out  # benchmarks/, beside this script

            trees[args.against] = other_tree.enter_context(checked_out(args.against))
        configs = {name: _subset_config(tree, config, cfas, tmp / f"config-{i}") for i, (name, tree) in
                   enumerate(trees.items())}
        if args.same_config and args.against:  # equal work: this tree runs REV's copy of the config
            configs["this"] = configs[args.against]
        order = list(enumerate(trees.items()))
        if args.abba:  # this, REV, REV, this: a machine that drifts during the runs favours neither tree
            order = order + order[::-1]
        for mode in (("warm",) if args.warm_only else ("cold", "warm")):
            for i, (name, tree) in order:
                cache = None if args.warm_only else tmp / f"cache-{i}"  # warm: the cold run's cache again
                out = tmp / f"out-{i}-{mode}"
                if out.exists():
                    shutil.rmtree(out)
                got = _study(tree, configs[name], out, cache, args.workers)
                all_evaluate.setdefault(name, {}).setdefault(mode, []).append(got["evaluate_s"])
                seen = runs.setdefault(name, {}).get(mode)
                # with --abba each tree runs twice: keep the faster run's numbers, each key the run's own
                if seen is None or got["evaluate_s"] < seen["evaluate_s"]:
                    runs[name][mode] = got
                if args.keep:  # the tables, to compare the trees' values
                    kept = Path(args.keep) / f"{'this' if tree == REPO else 'against'}-{mode}"
                    kept.mkdir(parents=True, exist_ok=True)
                    for f in ("metrics.csv", "metrics_realisations.csv", "timing.json"):
                        if (out / f).is_file():
                            shutil.copy2(out / f, kept / f)
                print(f"  {name} {mode}: evaluate {got['evaluate_s']:.1f} s", file=sys.stderr)
    after = os.getloadavg()
    what = f"{config}" + (f" reduced to {', '.join(cfas)}" if cfas else "") + (
        f", {args.against}'s copy in both trees" if args.same_config and args.against else "")
    print(f"{what}, {args.workers} worker(s); load average (1, 5, 15 min) before the runs: "
          + " ".join(f"{x:.2f}" for x in before) + ", after them: " + " ".join(f"{x:.2f}" for x in after))
    names = list(runs)
    cores = _cpu_count()  # the cores this process may run on (its CPU affinity)
    for r in runs.values():  # no schedule finishes before every core has done its share of the CPU time
        for got in r.values():
            got["cpu_floor_s"] = got["cpu_s"] / cores
            got["scene_floor_s"] = scene_floors(got, cores)
    header = f"{'':<24}" + "".join(f"{n[:14] + ' ' + m:>20}" for n in names for m in runs[n])
    if len(names) == 2:
        header += "".join(f"{'ratio ' + m:>14}" for m in runs[names[0]])
    for n in names:  # per capture, by scene and stage, and the floor it is measured against
        for m, got in runs[n].items():
            print("\n".join(per_capture_table(n, m, got)))
    print(header)
    labels = {**{k: k[:-2] + " (s)" for k in PHASES}, **{k: k[:-2] + " (worker s)" for k in STAGES},
              "cpu_s": "CPU, all processes (s)", "cpu_floor_s": f"CPU / {cores} cores (s)"}
    for key, label in labels.items():
        line = f"{label:<24}" + "".join(f"{runs[n][m][key]:>20.1f}" for n in names for m in runs[n])
        if len(names) == 2:
            for m in runs[names[0]]:
                a, b = runs[names[0]][m][key], runs[names[1]][m][key]
                line += f"{(b / a if a > 0 else float('nan')):>14.2f}"
        print(line)
    record = {"config": what, "load_average_before": before, "load_average": after, "cores": cores, "runs": runs}
    if len(names) == 2:
        m = next(iter(runs[names[0]]))  # the ratio REV / this tree of the first mode run
        record["against"] = names[1]
        record["ratio"] = {k: runs[names[1]][m][k] / runs[names[0]][m][k] for k in runs[names[0]][m]
                           if isinstance(runs[names[0]][m][k], float) and runs[names[0]][m][k] > 0}
        if args.target:
            add_target(record, args.target)
    # paths in the record relative to the folder it is written to (io/portable.py)
    record["command"] = "python3 benchmarks/bench_study.py " + relative_command(
        sys.argv[1:], Path(args.json).parent if args.json else Path.cwd())
    record["all_evaluate_s"] = all_evaluate
    print(json.dumps(record))
    if args.json:
        Path(args.json).write_text(json.dumps(record, indent=1) + "\n")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", help="a study config (default configs/quick.toml)")
    ap.add_argument("--paper", action="store_true", help="configs/paper.toml, phases per tree")
    ap.add_argument("--subset", metavar="CFAS", help="comma-separated CFAs: the study reduced to them")
    ap.add_argument("--against", metavar="REV", help="also run commit REV (git worktree beside this tree)")
    ap.add_argument("--same-config", action="store_true",
                    help="with --against: both trees run REV's copy of the config (the same work, when this "
                         "tree's copy asks for more, e.g. render_seeds)")
    ap.add_argument("--warm-only", action="store_true", help="no cold runs; the default render cache")
    ap.add_argument("--keep", metavar="DIR", help="copy each run's metrics CSVs and timing.json into DIR/<tree>-<mode>/")
    ap.add_argument("--abba", action="store_true",
                    help="with --against: run this, REV, REV, this and keep each tree's faster run (drift-fair)")
    ap.add_argument("--json", metavar="FILE", help="also write the record (runs, ratio REV / this, command) to FILE")
    ap.add_argument("--target", type=float, metavar="RATIO",
                    help="with --against: record the evaluate time RATIO times faster than REV's (the JSON's 'target')")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=1, help="optics-memo mode: best of this many")
    args = ap.parse_args()
    if args.target is not None and not (args.target > 0 and args.against):
        ap.error("--target needs --against and a ratio above 0")
    if args.paper or args.against or args.subset or args.warm_only or args.keep or args.json:
        return phases_main(args)
    return memo_main(args)



if __name__ == "__main__":
    sys.exit(main())
