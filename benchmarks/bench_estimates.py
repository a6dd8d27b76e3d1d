"""A study's size estimate against its measured time, on studies of many
tiny conditions and on the quick study, and the per-task costs fitted from
them (cfa_mitsuba/data/study_costs.toml: ``task_overhead``,
``tables_per_condition``).

    nice -n 5 python benchmarks/bench_estimates.py --json docs/data/bench-estimates.json \
        --results docs/example-report docs/example-report-isetcam
    python benchmarks/bench_estimates.py --from-json docs/data/bench-estimates.json   # no runs: the table again

``--results DIR ...`` adds finished studies of shipped configs (the paper
studies take minutes each: their committed runs are read rather than run
again): the estimate of the config each names (its ``config.json``'s
``path``) beside its ``timing.json``, without the renders and the report,
at the worker count given by ``--workers`` (they must have run with it).

Runs each study once (``--no-report --quiet``, ``--workers N``, a render
cache of its own) and reads its ``timing.json``.  What is compared leaves
the renders out on both sides: a study's renders are costed by
``render_per_megasample_band`` and cost nothing once cached, and these
runs render their small scenes in about a second, so the estimate's render
share (sizing's ``render_seconds``) is taken from the estimate and the
render phase from the measured time.

The tiny studies are one Macbeth chart of 60 x 40 pixels, bayer (or four
CFAs) and bilinear, at N luminances: N conditions of almost no pixels, so
what they measure is what every task and condition costs whatever its
size.  The fit: measured - (the estimate without the two costs) =
task_overhead x tasks / workers + tables_per_condition x conditions, least
squares over the tiny studies.  The quick study is the check on a study of
ordinary size.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

#: name -> (CFAs, luminances) of a tiny study, or the path of a shipped config.
STUDIES = {"tiny-200": (1, 200), "tiny-2000": (1, 2000), "tiny-4cfa-500": (4, 500),
           "quick": REPO / "configs" / "quick.toml"}
_CFAS = ["bayer", "rgb4", "cmy1", "rgbw1"]


def tiny_config(n_cfas: int, n_lum: int) -> str:
    lums = ", ".join(f"{v:.8g}" for v in np.geomspace(10.0, 1000.0, n_lum))
    cfas = ", ".join(f'"{c}"' for c in _CFAS[:n_cfas])
    return (f'name = "tiny-{n_cfas}x{n_lum}"\nseed = 1\nseeds = 2\nscenes = ["macbeth"]\ncfas = [{cfas}]\n'
            f'demosaics = ["bilinear"]\nluminances = [{lums}]\n[render.macbeth]\nwidth = 60\nheight = 40\n'
            "[output]\nreport = false\n")


def _estimate(config_path: Path, workers: int, costs: dict | None = None) -> dict:
    from cfa_mitsuba.study import sizing
    from cfa_mitsuba.study.config import load_config

    size = sizing.study_size(load_config(config_path), workers, costs=costs)
    return {"conditions": size.conditions, "tasks": size.tasks, "estimate_s": size.seconds,
            "estimate_render_s": size.render_seconds}


def run_one(name: str, spec, folder: Path, workers: int) -> dict:
    if isinstance(spec, Path):
        config = spec
    else:
        config = folder / f"{name}.toml"
        config.write_text(tiny_config(*spec))
    out = folder / name
    env = dict(os.environ, CFA_MITSUBA_CACHE=str(folder / "cache"))
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "cfa_mitsuba", "study", str(config), "--out", str(out), "--quiet",
                           "--no-report", "--workers", str(workers)], cwd=REPO, env=env, capture_output=True,
                          text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{name}: the study failed: {proc.stderr.strip().splitlines()[-1]}")
    phases = json.loads((out / "timing.json").read_text())["phases"]
    return {"name": name, "config": str(config.relative_to(REPO)) if config.is_relative_to(REPO) else None,
            "config_text": None if isinstance(spec, Path) else config.read_text(), "process_wall_s": wall,
            "phases": phases, "measured_s": phases["total_s"] - phases.get("render_s", 0.0)}


def from_results(folder: Path) -> dict:
    """A finished study as a run: its config's path and its measured time
    without the renders and the report (module docstring)."""
    config = (folder / json.loads((folder / "config.json").read_text())["path"]).resolve()
    if not config.is_file():
        config = (REPO / "configs" / config.name).resolve()
    phases = json.loads((folder / "timing.json").read_text())["phases"]
    return {"name": folder.name, "config": str(config.relative_to(REPO)), "config_text": None,
            "results": str(folder.resolve().relative_to(REPO)) if folder.resolve().is_relative_to(REPO) else None,
            "phases": phases,
            "measured_s": phases["total_s"] - phases.get("render_s", 0.0) - phases.get("report_s", 0.0)}


def with_estimates(runs: list[dict], workers: int, costs: dict | None = None) -> list[dict]:
    """Each run with the estimate of its config (current costs, or ``costs``)."""
    out = []
    with tempfile.TemporaryDirectory() as d:
        for r in runs:
            path = REPO / r["config"] if r["config"] else Path(d) / f"{r['name']}.toml"
            if not r["config"]:
                path.write_text(r["config_text"])
            e = _estimate(path, workers, costs)
            est = e["estimate_s"] - e["estimate_render_s"]
            out.append({**r, **e, "estimate_without_renders_s": est, "ratio": r["measured_s"] / est})
    return out


def fit(runs: list[dict], workers: int) -> dict:
    """task_overhead and tables_per_condition by least squares over the tiny runs (module docstring)."""
    from cfa_mitsuba.study import sizing

    bare = {**sizing.unit_costs(), "task_overhead": 0.0, "tables_per_condition": 0.0}
    tiny = [r for r in with_estimates(runs, workers, bare) if r["name"].startswith("tiny")]
    a = np.array([[r["tasks"] / workers, r["conditions"]] for r in tiny], dtype=float)
    b = np.array([r["measured_s"] - r["estimate_without_renders_s"] for r in tiny], dtype=float)
    coef = np.linalg.lstsq(a, b, rcond=None)[0]
    return {"task_overhead": float(coef[0]), "tables_per_condition": float(coef[1]),
            "residual_s": [float(v) for v in b - a @ coef]}


def table(runs: list[dict]) -> str:
    """The runs as a table; with the quick study among them, each ratio also
    over quick's: the quick study is made of the per-megapixel units that
    study_costs.toml measured on a quiet machine, so its ratio is this
    machine's slowdown against that one (other work sharing the cores)."""
    quick = next((r["ratio"] for r in runs if r["name"] == "quick"), None)
    w = max([15, *(len(r["name"]) for r in runs)])
    lines = [f"{'study':<{w}} {'conditions':>10} {'tasks':>6} {'estimated s':>11} {'measured s':>10} "
             f"{'measured/estimated':>18}" + (f" {'over quick':>10}" if quick else "")]
    for r in runs:
        over = f" {r['ratio'] / quick:>10.2f}" if quick else ""
        lines.append(f"{r['name']:<{w}} {r['conditions']:>10,} {r['tasks']:>6,} "
                     f"{r['estimate_without_renders_s']:>11.1f} {r['measured_s']:>10.1f} {r['ratio']:>18.2f}{over}")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--studies", default=",".join(STUDIES), help=f"comma-separated, of {', '.join(STUDIES)}")
    ap.add_argument("--json", type=Path, help="write the runs, estimates and fit here")
    ap.add_argument("--from-json", type=Path, help="no runs: the table of these runs with the current costs")
    ap.add_argument("--results", type=Path, nargs="*", default=[],
                    help="finished studies of shipped configs to add (run with --workers N)")
    args = ap.parse_args(argv)
    saved = {}
    if args.from_json:
        saved = json.loads(args.from_json.read_text())
        runs, workers = saved["runs"], saved["workers"]
    else:
        workers = args.workers
        runs = []
        with tempfile.TemporaryDirectory() as d:
            for name in args.studies.split(","):
                runs.append(run_one(name, STUDIES[name], Path(d), workers))
                print(f"ran {name}: {runs[-1]['measured_s']:.1f} s", file=sys.stderr)
        runs += [from_results(folder) for folder in args.results]
    fitted = fit(runs, workers) if sum(r["name"].startswith("tiny") for r in runs) >= 2 else None
    shown = with_estimates(runs, workers)
    load = saved.get("load_average") if args.from_json else os.getloadavg()
    print(f"{workers} worker(s); times without the renders (module docstring); load average "
          f"{', '.join(f'{v:.1f}' for v in load)} on {len(os.sched_getaffinity(0))} core(s)")
    print(table(shown))
    if fitted:
        print(f"fit over the tiny studies: task_overhead = {fitted['task_overhead']:.4g} s, "
              f"tables_per_condition = {fitted['tables_per_condition']:.4g} s "
              f"(residuals {', '.join(f'{v:+.1f}' for v in fitted['residual_s'])} s)")
    if args.json:
        doc = {"workers": workers, "cores": saved.get("cores", len(os.sched_getaffinity(0))), "load_average": load,
               "runs": [{k: v for k, v in r.items()} for r in runs], "fit": fitted,
               "table": [{k: r[k] for k in ("name", "conditions", "tasks", "estimate_without_renders_s",
                                             "measured_s", "ratio")} for r in shown]}
        args.json.write_text(json.dumps(doc, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
