"""Run configs/low-light.toml under the exposure program and under the
'bayer' protocol, and keep the small result files the docs cite:

    python3 docs/low-light/run.py [--workers 2]      (a few minutes on 2 cores)

writes docs/low-light/<policy>/{metrics.csv, snr.csv, snr10.csv, cfas.json}
(metrics.csv trimmed to the columns the table reads); then
``python3 -m cfa_mitsuba.report.docs_numbers`` rewrites the table in docs/study.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
import tempfile
from pathlib import Path

import pandas as pd

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
KEEP = ["scene", "cfa", "demosaic", "luminance", "metric", "value", "ci_low", "ci_high", "n", "unit",
        "exposure_s", "analog_gain", "digital_gain", "clipped_fraction"]


def main() -> None:
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.runner import run_study

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    base = load_config(REPO / "configs" / "low-light.toml")
    for policy in ("program", "bayer"):
        cfg = dataclasses.replace(base, capture={**base.capture, "exposure_policy": policy})
        with tempfile.TemporaryDirectory() as tmp:
            run_study(cfg, tmp, workers=args.workers, progress=False)
            dest = HERE / policy
            dest.mkdir(exist_ok=True)
            m = pd.read_csv(Path(tmp) / "metrics.csv")
            m[KEEP].to_csv(dest / "metrics.csv", index=False, float_format="%.6g")
            for name in ("snr.csv", "snr10.csv", "cfas.json"):
                shutil.copy(Path(tmp) / name, dest / name)
        print(f"{policy}: {dest}")


if __name__ == "__main__":
    main()
