"""How fast the project refuses what it cannot do, and how fast two reads
that once took minutes now finish: the timings the test suite used to
assert against a clock (tests/test_hardening*.py check only what is refused
and why; a wall-time limit in a test fails under load).

    python benchmarks/bench_refusals.py [--repeat N] [--json PATH]

Each case is run ``--repeat`` times (default 3); the table gives the best
wall time, the bound the tests once asserted, and the time divided by the
interpreter's own start (``python -c 'import cfa_mitsuba'``, measured in
the same run), so tables from loaded and quiet machines compare.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def _refusal_cases():
    """The test suite's own configs (tests/study/test_stop_and_resume.py), so that what is timed here is
    exactly what the tests refuse, not a copy that can drift from it."""
    import importlib.util

    sys.path.insert(0, str(REPO / "tests"))  # the test module imports its conftest
    path = REPO / "tests" / "study" / "test_stop_and_resume.py"
    spec = importlib.util.spec_from_file_location("refusal_cases", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.SMALL, module._sweep_of_a_million


SMALL, _sweep_of_a_million = _refusal_cases()


def _cli(tmp: Path, *args, env=None) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "cfa_mitsuba", *map(str, args)], cwd=REPO, capture_output=True,
                          text=True, env={**os.environ, "PYTHONPATH": str(REPO), **(env or {})})
    wall = time.perf_counter() - t0
    if proc.returncode != 2:
        raise SystemExit(f"expected a refusal (exit 2), got {proc.returncode}: {proc.stderr[-300:]}")
    return wall


def _cases(tmp: Path) -> dict:
    configs = {"seeds": SMALL.replace("seeds = 2", "seeds = 10000000"), "sweep": _sweep_of_a_million(),
               "long": SMALL + '\n[[sweep]]\nscene = "macbeth"\nseed = [' + ", ".join(map(str, range(10**6))) + "]\n",
               "design": (REPO / "configs" / "design-quick.toml").read_text().replace(
                   'engine = "exhaustive"', 'engine = "nsga2"\npopulation = 100000000')}
    for name, text in configs.items():
        (tmp / f"{name}.toml").write_text(text)

    def study_size_in_process():
        import tomllib

        from cfa_mitsuba.study.config import parse_config
        from cfa_mitsuba.study.sizing import study_size

        config = parse_config(tomllib.loads(configs["sweep"]), where="sweep.toml")
        t0 = time.perf_counter()
        study_size(config, 2)
        return time.perf_counter() - t0

    def exr_10000_channels():
        import numpy as np
        import OpenEXR

        import cfa_mitsuba as cm
        from cfa_mitsuba.io.exr import spectral_channel_name

        chans = {"T." + spectral_channel_name(w)[3:]: np.full((1, 1), 0.5, np.float32)
                 for w in np.linspace(360.0, 830.0, 10000)}
        p = tmp / "many.exr"
        with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
                           "spectralLayoutVersion": "1.0"}, chans) as f:
            f.write(str(p))
        t0 = time.perf_counter()
        cm.io.read_spectral_exr(p)
        return time.perf_counter() - t0

    return {
        "study: 60 million captures refused (command)": (5.0, lambda: _cli(tmp, "study", tmp / "seeds.toml", "--out",
                                                                            tmp / "o1", "--quiet")),
        "study: a million conditions refused (command)": (5.0, lambda: _cli(tmp, "study", tmp / "sweep.toml",
                                                                             "--out", tmp / "o2", "--quiet")),
        "study_size of a million conditions (in process)": (0.5, study_size_in_process),
        "study: 7 MB sweep refused before parsing (command)": (2.0, lambda: _cli(tmp, "study", tmp / "long.toml",
                                                                                  "--out", tmp / "o3", "--quiet")),
        "design: population 1e8 refused (command)": (10.0, lambda: _cli(tmp, "design", tmp / "design.toml",
                                                                        "--out", tmp / "o4", "--quiet")),
        "render: 100 MB memory limit refused (command)": (10.0, lambda: _cli(
            tmp, "render", "macbeth", "--out", tmp / "o5", env={"CFA_MITSUBA_MEMORY_LIMIT": "100M"})),
        "read a 10,000-channel EXR (in process)": (20.0, exr_10000_channels),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", type=Path, help="also write the table to this JSON file")
    args = ap.parse_args()
    warnings.simplefilter("ignore")  # the EXR reader's notices on how it read the file
    with tempfile.TemporaryDirectory(prefix="bench-refusals-") as tmp:
        tmp = Path(tmp)
        start = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", "import cfa_mitsuba"], cwd=REPO, check=True,
                           env={**os.environ, "PYTHONPATH": str(REPO)})
            start.append(time.perf_counter() - t0)
        base = min(start)
        rows = []
        print(f"interpreter start (import cfa_mitsuba): {base:.2f} s, load average {os.getloadavg()[0]:.2f}\n")
        print(f"| case | best of {args.repeat} (s) | the tests' old bound (s) | / interpreter start |")
        print("|---|---|---|---|")
        for name, (bound, run) in _cases(tmp).items():
            best = min(run() for _ in range(args.repeat))
            rows.append({"case": name, "best_s": best, "old_bound_s": bound, "ratio_to_start": best / base})
            print(f"| {name} | {best:.2f} | {bound:g} | {best / base:.2f} |", flush=True)
    if args.json:
        args.json.write_text(json.dumps({"interpreter_start_s": base, "load_average": os.getloadavg()[0],
                                         "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
