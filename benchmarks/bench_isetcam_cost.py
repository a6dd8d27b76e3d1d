"""Per-capture cost of our chain beside ISETCam's, in GNU Octave, on the same
capture (issue 49, item 5): the slanted edge and the Macbeth chart at the
paper's sizes, Bayer, bilinear demosaic.

    nice -n 5 python3 benchmarks/bench_isetcam_cost.py [--repeat 5]
        [--isetcam /path/to/isetcam | --octave-json docs/data/isetcam-capture-cost.json]
        [--json docs/data/isetcam-capture-cost.json]

Ours: the paper-isetcam study's (configs/paper-isetcam.toml) evaluation task
of Bayer at 100 cd/m^2 on each scene, cut to one realisation, the bilinear
demosaic and the metric ISETCam's side computes (``mtf`` on the edge,
``delta-e`` on the chart), evaluated whole by ``CameraChain.run`` as a study
worker does: the capture (noise 'all', auto exposure), the processing (white
balance, demosaic, colour matrix) and the metric, after the optical and
ideal images were made once for the scene (a study makes them once per
scene and condition).  The optics (``compute_optics``) and the ideal
sensor's image are timed apart, so each side is given with and without its
optics.  The render is read from the render cache (rendered first if
missing) and never timed.  One warm-up capture, then the median of
``--repeat``; when Octave runs here, ours is measured before and after it
and each value is the mean of the two passes.

ISETCam: benchmarks/isetcam_capture_cost.m run by ``octave`` (found on
PATH, or ``--octave``) on the ISETCam checkout ``--isetcam`` (or
$ISETCAM_ROOT): oiCompute, sensorCompute, ipCompute with 'bilinear' and the
metric, each capture whole (ISETCam has no per-scene reuse of its optical
image in this chain); its header says how the scenes are matched.  Without
Octave, ``--octave-json`` reuses ISETCam's timings from a JSON this script
wrote before (the committed docs/data/isetcam-capture-cost.json: its
``isetcam`` part, kept with its own date) or the .m script's raw output.
ISETCam is run for research only: nothing in the project or its tests needs
Octave or ISETCam.

Times are wall seconds (CPU seconds beside them) on this machine; it is
shared with other work, so read the ratios, which are measured in one run.
Ratio = ISETCam's seconds / ours.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
OCTAVE_SCRIPT = REPO / "benchmarks" / "isetcam_capture_cost.m"
DEFAULT_JSON = REPO / "docs" / "data" / "isetcam-capture-cost.json"
CONFIG = "configs/paper-isetcam.toml"
#: scene -> the metric both sides compute (ISETCam: ISO12233; macbethColorError's dE*ab)
SCENES = {"slanted-edge": "mtf", "macbeth": "delta-e"}
CFA, DEMOSAIC, LUMINANCE = "bayer", "bilinear", 100.0


def _git(*args: str, cwd: Path = REPO) -> str:
    proc = subprocess.run(["git", "-C", str(cwd), *args], capture_output=True, text=True)
    return proc.stdout.strip() if proc.returncode == 0 else ""


def _machine() -> dict:
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cores": os.cpu_count(), "cpu": model, "nice": os.nice(0)}


def _load() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


def _median(runs: list[dict], key: str) -> float:
    return statistics.median(r[key] for r in runs)


def measure_ours(scene: str, metric: str, repeat: int) -> dict:
    """Our per-capture cost on ``scene`` (seconds, medians of ``repeat``)."""
    import cfa_mitsuba as cm
    from cfa_mitsuba.study.chain import CameraChain
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import plan_study
    from cfa_mitsuba.study.tasks import load_scene_image

    _, tasks = plan_study(load_config(REPO / CONFIG), None)
    task = next((t for t in tasks if t.scene == scene and t.cfa == CFA and t.condition.luminance == LUMINANCE), None)
    if task is None:
        raise SystemExit(f"bench_isetcam_cost: {CONFIG} has no {CFA} task on {scene} at {LUMINANCE:g} cd/m^2")
    task = replace(task, demosaics=(DEMOSAIC,), metrics=(metric,), realisations=1, details_dir=None,
                   ideal_rows=False)
    image = load_scene_image(task.source)  # the cached render: not timed
    cond = task.condition

    def optics_once() -> dict:
        chain = CameraChain(task.chain)
        w, c = time.perf_counter(), time.process_time()
        oi = chain.optical(image, cond, None)  # None: no reuse, computed afresh
        w1, c1 = time.perf_counter(), time.process_time()
        chain.ideal(oi, cond, None)
        w2, c2 = time.perf_counter(), time.process_time()
        return {"optics_s": w1 - w, "optics_cpu_s": c1 - c, "ideal_s": w2 - w1, "ideal_cpu_s": c2 - c1}

    def capture_once() -> dict:
        chain = CameraChain(task.chain)  # the optical and ideal images come from the process's memo
        w, c = time.perf_counter(), time.process_time()
        evaluation = chain.run(task, image)
        out = {"capture_total_s": time.perf_counter() - w, "capture_total_cpu_s": time.process_time() - c}
        out.update({k: v for k, v in chain.timing.items() if k in ("capture_s", "process_s", "metrics_s")})
        rows = [row for o in evaluation.outputs for row in o.rows if row.get("metric") == metric]
        out["metric_value"] = float(rows[0]["value"]) if rows else float("nan")
        return out

    optics_once()  # warm-up (imports, first-call costs)
    optic_runs = [optics_once() for _ in range(repeat)]
    CameraChain(task.chain).run(task, image)  # warm-up, and fills the memo the captures read
    runs = [capture_once() for _ in range(repeat)]
    res = {key: _median(optic_runs, key) for key in optic_runs[0]}
    res.update({key: _median(runs, key) for key in runs[0]})
    res["per_capture_s"] = res["capture_total_s"]
    res["per_capture_cpu_s"] = res["capture_total_cpu_s"]
    res["with_optics_s"] = statistics.median(r["capture_total_s"] for r in runs) + res["optics_s"] + res["ideal_s"]
    res["with_optics_cpu_s"] = res["capture_total_cpu_s"] + res["optics_cpu_s"] + res["ideal_cpu_s"]
    res["runs_s"] = [round(r["capture_total_s"], 4) for r in runs]
    res["scene_size"] = list(image.data.shape)
    res["oversample"] = image.meta.get("oversample", 1)
    res["metric"] = metric
    res["version"] = cm.__version__
    return res


def measure_all(repeat: int) -> dict:
    ours = {}
    for name, metric in SCENES.items():
        ours[name] = o = measure_ours(name, metric, repeat)
        print(f"ours    {name:<13} capture {o['capture_s']:.3f} process {o['process_s']:.3f} "
              f"metrics {o['metrics_s']:.3f} per capture {o['per_capture_s']:.3f} s; optics {o['optics_s']:.3f} "
              f"ideal {o['ideal_s']:.3f} s ({metric} {o['metric_value']:.4g})", flush=True)
    return ours


def _mean_of(first: dict, second: dict) -> dict:
    """Each scene's timings as the mean of two passes (``passes_s``: each pass's per-capture median)."""
    out = {}
    for name, a in first.items():
        b = second[name]
        out[name] = {k: (a[k] + b[k]) / 2 if k.endswith("_s") and isinstance(a[k], float) else a[k] for k in a}
        out[name]["runs_s"] = a["runs_s"] + b["runs_s"]
        out[name]["passes_s"] = [a["per_capture_s"], b["per_capture_s"]]
    return out


def run_octave(octave: str, isetcam: Path, repeat: int) -> dict:
    """ISETCam's timings: the .m script under ``octave`` (this process's niceness)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "isetcam.json"
        env = {**os.environ, "ISETCAM_ROOT": str(isetcam), "ISETCAM_COST_JSON": str(out),
               "ISETCAM_COST_REPEAT": str(repeat)}
        cmd = [octave, "--no-gui", "--norc", "--quiet", str(OCTAVE_SCRIPT)]
        proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
        lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("isetcam ")]
        print("\n".join(lines), flush=True)
        if not out.is_file():
            raise SystemExit(f"bench_isetcam_cost: the Octave run wrote no timings (exit {proc.returncode}):\n"
                             f"{proc.stderr[-2000:]}")
        data = json.loads(out.read_text())
    words = [Path(cmd[0]).name, *cmd[1:-1], str(OCTAVE_SCRIPT.relative_to(REPO))]
    part = _isetcam_part(data, source=f"measured in this run: {' '.join(words)}", date=_now())
    part["isetcam_origin"] = _repository(_git("remote", "get-url", "origin", cwd=isetcam))
    return part


def _repository(url: str) -> str:
    """owner/name from a remote's URL or mirror path (a committed result holds no machine's absolute path)."""
    m = re.search(r"([A-Za-z0-9_.-]+)[/+]([A-Za-z0-9_.-]+?)(?:\.git)?(?:/repo)?/?$", url)
    return f"{m.group(1)}/{m.group(2)}" if m else Path(url).name


def _relative_words(words: list[str]) -> list[str]:
    """A command's words with absolute paths written relative to the repository, or by their last part."""
    out = []
    for w in words:
        p = Path(w)
        out.append(w if not p.is_absolute() else str(p.relative_to(REPO)) if p.is_relative_to(REPO) else
                   f"<{p.name}>")
    return out


def _isetcam_part(data: dict, source: str, date: str) -> dict:
    """The .m script's raw output as this script's ``isetcam`` part (scene names as ours)."""
    scenes = {name: data["scenes"][name.replace("-", "_")] for name in SCENES}
    return {"scenes": scenes, "isetcam_commit": data.get("isetcam_commit", ""),
            "octave_version": data.get("octave_version", ""), "repeat": data.get("repeat"),
            "source": source, "date": date}


def read_octave_json(path: Path) -> dict:
    """ISETCam's timings reused from ``path``: this script's output (its
    ``isetcam`` part, date and source kept) or the .m script's raw JSON."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise SystemExit(f"bench_isetcam_cost: cannot read ISETCam timings from {path}: {exc}")
    if "isetcam" in data:
        part = dict(data["isetcam"])
        part["source"] = f"reused from {path} ({part.get('source', '')})"
        return part
    if "scenes" in data:
        return _isetcam_part(data, source=f"reused from {path} (the .m script's output)",
                             date=dt.datetime.fromtimestamp(path.stat().st_mtime, dt.timezone.utc).isoformat())
    raise SystemExit(f"bench_isetcam_cost: {path} holds no ISETCam timings")


def _now() -> str:
    return dt.datetime.now(dt.timezone.utc).replace(microsecond=0).isoformat()


def ratios(ours: dict, iset: dict, cpu: bool = False) -> dict:
    """ISETCam's seconds / ours, per scene: per capture (after the optics),
    with the optics, and per stage; ``cpu``: in CPU seconds of each process
    (less moved by other work on a shared machine than wall time)."""
    c = "_cpu" if cpu else ""
    out = {}
    for name in SCENES:
        o, i = ours[name], iset["scenes"][name]
        out[name] = {
            "capture": i[f"without_optics{c}_s"] / o[f"per_capture{c}_s"],
            "with_optics": i[f"per_capture{c}_s"] / o[f"with_optics{c}_s"],
            "optics": i[f"optics{c}_s"] / (o[f"optics{c}_s"] + o[f"ideal{c}_s"]),
        }
        if not cpu:  # our stages are timed in wall seconds only (CameraChain.timing)
            out[name].update(sensor=i["sensor_s"] / o["capture_s"], isp=i["ip_s"] / o["process_s"],
                             metric=i["metric_s"] / o["metrics_s"])
    return out


def print_table(ours: dict, iset: dict, rat: dict, rat_cpu: dict) -> None:
    print(f"\n{'scene':<14}{'stage (wall seconds)':<28}{'ISETCam s':>11}{'ours s':>10}{'ratio':>9}{'CPU ratio':>11}")
    for name in SCENES:
        o, i, r, rc = ours[name], iset["scenes"][name], rat[name], rat_cpu[name]
        rows = [("optics (+ our ideal image)", i["optics_s"], o["optics_s"] + o["ideal_s"], r["optics"]),
                ("sensor / capture", i["sensor_s"], o["capture_s"], r["sensor"]),
                ("ipCompute / process", i["ip_s"], o["process_s"], r["isp"]),
                ("metric", i["metric_s"], o["metrics_s"], r["metric"]),
                ("per capture (no optics)", i["without_optics_s"], o["per_capture_s"], r["capture"]),
                ("per capture with optics", i["per_capture_s"], o["with_optics_s"], r["with_optics"])]
        cpu = {"optics (+ our ideal image)": rc["optics"], "per capture (no optics)": rc["capture"],
               "per capture with optics": rc["with_optics"]}
        for stage, a, b, x in rows:
            extra = f"{cpu[stage]:>11.1f}" if stage in cpu else ""
            print(f"{name:<14}{stage:<28}{a:>11.3f}{b:>10.3f}{x:>9.1f}{extra}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timed captures per scene and side (median), default 5")
    ap.add_argument("--octave-repeat", type=int, default=3, help="timed ISETCam captures per scene, default 3")
    ap.add_argument("--octave", default=shutil.which("octave"), help="the Octave binary (default: octave on PATH)")
    ap.add_argument("--isetcam", default=os.environ.get("ISETCAM_ROOT"), help="an ISETCam checkout ($ISETCAM_ROOT)")
    ap.add_argument("--octave-json", type=Path, metavar="PATH",
                    help="reuse ISETCam's timings from PATH (this script's JSON or the .m script's) instead of Octave")
    ap.add_argument("--json", type=Path, default=DEFAULT_JSON,
                    help=f"write here (default {DEFAULT_JSON.relative_to(REPO)})")
    args = ap.parse_args(argv)
    if args.repeat < 1 or args.octave_repeat < 1:
        raise SystemExit("bench_isetcam_cost: --repeat and --octave-repeat must be at least 1")
    if args.octave_json is None and not (args.octave and args.isetcam):
        raise SystemExit("bench_isetcam_cost: no Octave or no ISETCam checkout (--octave, --isetcam); pass "
                         "--octave-json docs/data/isetcam-capture-cost.json to reuse the committed ISETCam timings")
    sys.path.insert(0, str(REPO))
    nice = os.nice(0)
    given = argv if argv is not None else sys.argv[1:]
    command = ("" if nice == 0 else f"nice -n {nice} ") + " ".join(["python3", *_relative_words([sys.argv[0], *given])])
    load_before, started = _load(), _now()
    iset = read_octave_json(args.octave_json) if args.octave_json else None  # read before --json overwrites it
    ours = measure_all(args.repeat)
    if iset is None:
        iset = run_octave(args.octave, Path(args.isetcam), args.octave_repeat)
        # ours again after ISETCam (A B A): the load on a shared machine drifts; each value is the mean of both passes
        ours = _mean_of(ours, measure_all(args.repeat))
    rat, rat_cpu = ratios(ours, iset), ratios(ours, iset, cpu=True)
    print_table(ours, iset, rat, rat_cpu)
    result = {
        "what": "per-capture cost, ISETCam (GNU Octave) against cfa-mitsuba, same capture: Bayer, bilinear",
        "command": command, "date": started, "machine": _machine(),
        "load_average": {"before": load_before, "after": _load()},
        "note": ("shared machine (other sessions' jobs ran at the same time), run under nice; wall seconds; "
                 "read the ratios, measured in one run (or against the reused ISETCam timings' date)"),
        "ours": {"commit": _git("rev-parse", "HEAD"),
                 "chain_modified": bool(_git("status", "--porcelain", "--untracked-files=no", "--", "cfa_mitsuba",
                                             "configs")),
                 "config": CONFIG, "cfa": CFA, "demosaic": DEMOSAIC, "luminance_cd_m2": LUMINANCE,
                 "repeat": args.repeat, "scenes": ours},
        "isetcam": iset,
        "ratios": rat,
        "ratios_cpu": rat_cpu,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.json.with_name(args.json.name + ".tmp")
    tmp.write_text(json.dumps(result, indent=1, sort_keys=False) + "\n")
    os.replace(tmp, args.json)  # no half-written file
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
