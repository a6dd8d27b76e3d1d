"""Regenerate tests/data/quick_expected.csv: the stored values of the
quick study (configs/quick.toml) and their tolerances.

    python3 tests/data/make_quick_expected.py        (about 3 minutes on 2 cores)

The tolerance of each value comes from the render noise, not from the test:
the quick study is run with its renders made at five different render seeds
(everything else, the sensor-noise seed included, unchanged).  The spread
of a metric over those five runs is what Monte Carlo rendering alone can do
to it; a machine whose floating point differs from ours (another CPU, another
LLVM) perturbs the renders by far less than a change of seed does.  So

    tolerance = 4 x (standard deviation over the five render seeds)

with two floors: one quantisation step for the moire starting point (it is
a chirp column, so it moves in steps of the chirp's frequency increment per
column) and 1e-6 relative for values the render seed does not move at all
(metrics of flat charts rendered exactly).  `value` is the seed-0 run, which
is what the test runs.
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

REPO = Path(__file__).resolve().parents[2]
SEEDS = (0, 1, 2, 3, 4)
KEYS = ["scene", "cfa", "demosaic", "luminance", "metric"]


def run(seed: int, out: Path) -> pd.DataFrame:
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import run_study

    cfg = load_config(REPO / "configs" / "quick.toml")
    scenes = tuple(dataclasses.replace(s, render={**s.render, "seed": seed}) if seed else s for s in cfg.scenes)
    cfg = dataclasses.replace(cfg, scenes=scenes)
    return run_study(cfg, out, workers=2, progress=False, report=False, log=lambda m: None).metrics


def msp_step_cpd(out: Path) -> float:
    """Largest frequency increment between adjacent chirp columns (cy/deg)."""
    import json

    steps = []
    for f in (out / "details" / "chirp").glob("*/*/L*.json"):
        freq = np.asarray(json.loads(f.read_text())["moire"]["frequency_cy_per_deg"], dtype=float)
        steps.append(np.max(np.diff(freq)))
    return float(max(steps))


def main() -> int:
    tables = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in SEEDS:
            print(f"render seed {seed} ...", file=sys.stderr)
            tables.append(run(seed, Path(tmp) / f"s{seed}").set_index(KEYS)["value"].rename(f"s{seed}"))
            if seed == 0:
                step = msp_step_cpd(Path(tmp) / "s0")
    both = pd.concat(tables, axis=1)
    if both.isna().any().any():
        raise SystemExit("the render seeds gave different sets of rows")
    first = tables[0]
    sigma = both.std(axis=1, ddof=1)
    floor = np.where(both.index.get_level_values("metric") == "moire", step, 1e-6 * first.abs())
    tol = np.maximum(4.0 * sigma, floor)
    out = pd.DataFrame({"value": first, "sigma_render": sigma, "tolerance": tol}).reset_index()
    path = REPO / "tests" / "data" / "quick_expected.csv"
    header = ("# quick.toml stored values; tolerance = max(4 x sigma over render seeds "
              f"{', '.join(map(str, SEEDS))}, floor); see make_quick_expected.py\n")
    with open(path, "w") as fh:
        fh.write(header)
        out.to_csv(fh, index=False, float_format="%.10g")
    print(f"wrote {path} ({len(out)} rows)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
