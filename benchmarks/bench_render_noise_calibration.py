"""Calibration of the study's 95 % intervals over render and sensor noise
(study/variance.py): do they cover what a much longer run measures?

    nice -n 5 python3 benchmarks/bench_render_noise_calibration.py \\
        --json docs/data/render-noise-calibration.json     (about 15-25 minutes on 2 busy cores)

A small puppy study (``--size``, default 120 x 106 at ``--spp`` 16, a
render noisier per pixel than the paper's 400 spp at full size, so render
noise is not negligible; 4 CFAs: Bayer, RGBW1, CMY1, RGB4; 2 demosaics:
bilinear and adaptive laplacian; S-CIELAB, SSIM, MDSI, HaarPSI and the
interior S-CIELAB at 100 cd/m^2, S-CIELAB, SSIM and the interior S-CIELAB
at 3 and 12 cd/m^2; 3 sensor seeds) is run ``--replicates`` times with
``render_seeds`` R (each of ``--render-seeds``, default 1 and 2), every
replicate with renders and sensor seeds of its own, and once more with
``--reference-seeds`` (default 8, at least 4 x R) renders, again
independent.  For each replicate, each value's 95 % interval is checked
against the reference run's mean of that value, and each paired CFA
difference's interval (the render component pooled over the comparison's
pairs, as the rank intervals: study/intervals.py) against the reference's
mean difference.  The reference mean is itself noisy (a quarter of the
replicate's render variance at R = 2, an eighth of its sensor variance),
so even exact intervals cover it somewhat less than 95 % of the time.

The JSON (``--json PATH``) records the setup, per R the share of values
and of paired differences covered, with their counts, and the ratio of each
value's half width to its sensor-only half width; docs/study.md quotes it
as generated spans.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CFAS = ["bayer", "rgbw1", "cmy1", "rgb4"]
DEMOSAICS = ["bilinear", "adaptive-laplacian"]
KEYS = ["cfa", "demosaic", "luminance", "metric"]


def _config(name: str, *, render_seeds: int, render_seed: int, study_seed: int, size, spp: int) -> str:
    return f"""
name = "{name}"
seed = {study_seed}
seeds = 3
render_seeds = {render_seeds}
scenes = ["puppy"]
cfas = {json.dumps(CFAS)}
demosaics = {json.dumps(DEMOSAICS)}
luminances = [100]

[[sweep]]
scene = "puppy"
metrics = ["scielab", "ssim"]
luminances = [3, 12]

[render.puppy]
width = {size[0]}
height = {size[1]}
spp = {spp}
seed = {render_seed}

[output]
figures = []
thumbnails = false
report = false
"""


def _run(folder: Path, text: str, workers: int):
    import pandas as pd

    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import run_study

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "study.toml").write_text(text)
    run_study(load_config(folder / "study.toml"), folder / "out", workers=workers, progress=False,
              log=lambda msg: None)
    return (pd.read_csv(folder / "out" / "metrics.csv"), pd.read_csv(folder / "out" / "metrics_realisations.csv"))


def _differences(real):
    """{(a, b, demosaic, luminance, metric): (mean, lo, hi)} of every CFA pair, the study's rule."""
    from cfa_mitsuba.study.intervals import difference_pool, paired_difference

    out = {}
    for (dem, lum, metric), g in real.groupby(["demosaic", "luminance", "metric"]):
        wide = g.pivot_table(index="cfa", columns="realisation", values="value")
        seeds = g.groupby("realisation")["render_seed"].max().reindex(wide.columns).to_numpy()
        pool = difference_pool(wide.to_numpy(float), seeds)
        for i, a in enumerate(wide.index):
            for b in wide.index[i + 1:]:
                m, lo, hi, _ = paired_difference(wide.loc[a].to_numpy(float), wide.loc[b].to_numpy(float), seeds,
                                                 pool)
                out[(a, b, dem, float(lum), metric)] = (m, lo, hi)
    return out


def _coverage(replicates, reference) -> dict:
    """Shares of values and paired differences whose interval covers the reference's mean."""
    ref_m, ref_real = reference
    target = ref_m.set_index(KEYS)["value"]
    ref_diff = {k: v[0] for k, v in _differences(ref_real).items()}
    hits_v = n_v = hits_d = n_d = 0
    ratios = []
    for m, real in replicates:
        for r in m.itertuples(index=False):
            key = (r.cfa, r.demosaic, r.luminance, r.metric)
            if key not in target.index:
                continue
            n_v += 1
            hits_v += int(r.ci_low <= target.loc[key] <= r.ci_high)
            if r.sensor_half_width > 0:
                ratios.append((r.ci_high - r.ci_low) / 2 / r.sensor_half_width)
        for key, (_, lo, hi) in _differences(real).items():
            if key in ref_diff:
                n_d += 1
                hits_d += int(lo <= ref_diff[key] <= hi)
    q = np.percentile(ratios, [5, 25, 50, 75, 95, 100]) if ratios else [np.nan] * 6
    return {"values": {"covered": hits_v, "total": n_v, "share": hits_v / n_v if n_v else None},
            "differences": {"covered": hits_d, "total": n_d, "share": hits_d / n_d if n_d else None},
            "half_width_over_sensor_only": dict(zip(["p5", "p25", "median", "p75", "p95", "max"],
                                                    [float(x) for x in q]))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", metavar="PATH", help="write the results to PATH (JSON)")
    ap.add_argument("--replicates", type=int, default=6)
    ap.add_argument("--render-seeds", default="1,2", help="the render_seeds to calibrate (comma-separated)")
    ap.add_argument("--reference-seeds", type=int, default=8)
    ap.add_argument("--size", default="120x106", help="puppy EXR size WxH")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--keep", metavar="DIR", help="run in DIR and keep the runs (default: a temporary folder)")
    args = ap.parse_args(argv)
    size = tuple(int(x) for x in args.size.lower().split("x"))
    rs = [int(x) for x in args.render_seeds.split(",")]
    if args.reference_seeds < 4 * max(rs):
        ap.error(f"--reference-seeds must be at least 4 x the largest render_seeds ({4 * max(rs)})")
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(args.keep or tmp)
        ref = _run(work / "reference", _config("reference", render_seeds=args.reference_seeds, render_seed=900_000,
                                               study_seed=900_000, size=size, spp=args.spp), args.workers)
        results = {}
        for r in rs:
            reps = [_run(work / f"R{r}-{j}", _config(f"R{r}-{j}", render_seeds=r, render_seed=1000 * (10 * r + j),
                                                     study_seed=1000 * (10 * r + j) + 1, size=size, spp=args.spp),
                         args.workers) for j in range(args.replicates)]
            results[str(r)] = _coverage(reps, ref)
            c = results[str(r)]
            print(f"render_seeds = {r}: values {c['values']['covered']}/{c['values']['total']} "
                  f"({100 * c['values']['share']:.1f} %), paired differences {c['differences']['covered']}/"
                  f"{c['differences']['total']} ({100 * c['differences']['share']:.1f} %); half width over "
                  f"sensor-only: median {c['half_width_over_sensor_only']['median']:.2f}, "
                  f"95th percentile {c['half_width_over_sensor_only']['p95']:.2f}", flush=True)
    out = {"setup": {"scene": "puppy", "size": list(size), "spp": args.spp, "cfas": CFAS, "demosaics": DEMOSAICS,
                     "levels_cd_m2": [3, 12, 100], "sensor_seeds": 3, "replicates": args.replicates,
                     "reference_render_seeds": args.reference_seeds},
           "render_seeds": results, "wall_s": round(time.perf_counter() - t0, 1)}
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")
    print(f"done in {out['wall_s']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
