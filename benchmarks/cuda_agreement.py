"""How the paper study run on a CUDA GPU (the cuda_ad_spectral variant)
agrees with the committed CPU run (llvm_ad_spectral): per scene, the largest
and median relative difference of each value and the fraction of GPU values
inside the CPU run's 95 % interval.

    python benchmarks/cuda_agreement.py [--gpu docs/data/cuda-paper] [--cpu docs/example-report]
                                        [--json docs/data/cuda-paper/agreement.json]

The GPU run: `bash benchmarks/cuda_paper.sh` on a machine with an NVIDIA GPU
(its metrics.csv and timing.json are committed in docs/data/cuda-paper/);
docs/study.md quotes the JSON this writes.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd

KEYS = ["scene", "cfa", "demosaic", "luminance", "metric"]


def agreement(gpu: Path, cpu: Path) -> dict:
    a = pd.read_csv(cpu / "metrics.csv")
    b = pd.read_csv(gpu / "metrics.csv")
    m = a.merge(b, on=KEYS, suffixes=("_cpu", "_gpu"))
    m["rel"] = (m["value_gpu"] - m["value_cpu"]).abs() / m["value_cpu"].abs().clip(lower=1e-12)
    m["inside"] = (m["value_gpu"] >= m["ci_low_cpu"]) & (m["value_gpu"] <= m["ci_high_cpu"])
    per = {scene: {"values": int(len(g)), "max_rel": float(g["rel"].max()), "median_rel": float(g["rel"].median()),
                   "inside_fraction": float(g["inside"].mean())} for scene, g in m.groupby("scene")}
    return {"compared": int(len(m)), "gpu_rows": int(len(b)), "cpu_rows": int(len(a)), "per_scene": per,
            "max_rel": float(m["rel"].max()), "inside_fraction": float(m["inside"].mean())}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gpu", default="docs/data/cuda-paper")
    ap.add_argument("--cpu", default="docs/example-report")
    ap.add_argument("--json", help="write the result here")
    args = ap.parse_args()
    out = agreement(Path(args.gpu), Path(args.cpu))
    print(f"{out['compared']} values compared")
    for scene, r in out["per_scene"].items():
        print(f"  {scene:<14} largest {r['max_rel']:.2e}, median {r['median_rel']:.2e} relative; "
              f"{100 * r['inside_fraction']:.1f} % inside the CPU run's interval")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
