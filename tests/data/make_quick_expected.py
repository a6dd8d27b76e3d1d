"""Regenerate tests/data/quick_expected.csv: the stored values of the
quick study (configs/quick.toml) and their tolerances.

    python3 tests/data/make_quick_expected.py        (about 3 minutes on 2 cores)

The tolerance of each value comes from the render noise, not from the test:
the quick study is run with its renders made at five different render seeds
(everything else, the sensor-noise seed included, unchanged).  The spread
of a metric over those five runs is what Monte Carlo rendering alone can do
to it.  The charts are rendered exactly, so a render seed does not move
them at all; what can move them is another machine's floating point (its
CPU's LLVM code rounding a radiance differently in the last bit).  That is
measured too: the seed-0 renders are re-evaluated three times with the last
bit of 30 % of their float32 values changed at random.  So

    tolerance = 4 x max(standard deviation over the five render seeds,
                        largest change under a last-bit perturbation)

with two floors: one quantisation step for the moire starting point (it is
a chirp column, so it moves in steps of the chirp's frequency increment per
column) and 1e-6 relative for values neither moves.  `value` is the seed-0
run, which is what the test runs.
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
    run_study(cfg, out, workers=2, progress=False, log=lambda m: None)
    every = pd.read_csv(out / "metrics_realisations.csv")
    return every[every["realisation"] == 0].reset_index(drop=True)


def last_bit_change(reference: pd.Series, perturbations=(1, 2, 3)) -> pd.Series:
    """Largest change of each value when the seed-0 renders change in their
    last float32 bit (30 % of the non-zero values, up or down at random); evaluated
    in this process, task by task, exactly as the study does."""
    import dataclasses

    from cfa_mitsuba.study import chain, runner, tasks
    from cfa_mitsuba.study.config import load_config

    cfg = load_config(REPO / "configs" / "quick.toml")
    _, plan = runner.plan_study(cfg, None)
    original = tasks.load_scene_image

    def evaluate(seed: int) -> pd.Series:
        def load(source):
            img = original(source)
            if not seed:
                return img
            rng = np.random.default_rng(seed)
            d = img.data.astype(np.float32)
            toward = np.where(rng.random(d.shape) < 0.5, np.float32(np.inf), np.float32(-np.inf))
            d = np.where((rng.random(d.shape) < 0.3) & (d > 0), np.nextafter(d, toward.astype(np.float32)), d)
            return dataclasses.replace(img, data=d.astype(np.float64))

        tasks.load_scene_image = load
        chain._OPTICAL.items.clear()
        chain._IDEAL.items.clear()
        try:
            rows = [r for t in plan for r in tasks.evaluate_task(dataclasses.replace(t, realisations=1)).rows]
        finally:
            tasks.load_scene_image = original
        return pd.DataFrame(rows).query("realisation == 0").set_index(KEYS)["value"]

    base = evaluate(0)
    same = base.reindex(reference.index)
    # the study's values come back from metrics_realisations.csv, written with 10 significant digits
    if not np.allclose(same, reference, rtol=2e-9, atol=0):
        raise SystemExit("in-process evaluation differs from the study's seed-0 values")
    return pd.concat([(evaluate(p) - base).abs() for p in perturbations], axis=1).max(axis=1)


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
    print("last-bit perturbations ...", file=sys.stderr)
    bit = last_bit_change(first).reindex(first.index)
    floor = np.where(both.index.get_level_values("metric") == "moire", step, 1e-6 * first.abs())
    tol = np.maximum(4.0 * np.maximum(sigma, bit), floor)
    out = pd.DataFrame({"value": first, "sigma_render": sigma, "last_bit_change": bit,
                        "tolerance": tol}).reset_index()
    path = REPO / "tests" / "data" / "quick_expected.csv"
    header = ("# quick.toml stored values; tolerance = max(4 x max(sigma over render seeds "
              f"{' '.join(map(str, SEEDS))}; last-bit change), floor); see make_quick_expected.py\n")
    with open(path, "w") as fh:
        fh.write(header)
        out.to_csv(fh, index=False, float_format="%.10g")
    print(f"wrote {path} ({len(out)} rows)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
