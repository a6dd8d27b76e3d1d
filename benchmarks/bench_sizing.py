"""The per-unit costs of cfa_mitsuba/data/study_costs.toml, from a finished
study: its timing.json divided by the units its config implies
(cfa_mitsuba/study/sizing.py's ``scene_units``, the same counts the
estimate uses, render seeds included).  Give the worker count the study
ran with (each worker makes the optical images of the scenes it meets):

    cfa-mitsuba study configs/paper.toml --out /tmp/paper --workers 2
    python benchmarks/bench_sizing.py /tmp/paper --workers 2

Prints the costs, then the study's estimate with data/study_costs.toml and
with the costs just measured, beside its measured wall time.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def main() -> int:
    from cfa_mitsuba.study import sizing
    from cfa_mitsuba.study.config import load_config

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path)
    ap.add_argument("--workers", type=int, default=1, help="the workers the study ran with (default 1)")
    args = ap.parse_args()
    config = load_config(json.loads((args.results / "config.json").read_text())["path"])
    timing = json.loads((args.results / "timing.json").read_text())
    units = {"optics_mpx_band": 0.0, "capture_mpx": 0.0, "output_mpx": 0.0}
    for spec in config.scenes:
        u = sizing.scene_units(config, spec, args.workers)
        for key in units:
            units[key] += u[key]
    t = timing["tasks"]
    measured = dict(sizing.unit_costs())
    measured["optics_per_megapixel_band"] = t["optics_s"] / units["optics_mpx_band"]
    measured["capture_per_megapixel"] = t["capture_s"] / units["capture_mpx"]
    measured["output_per_megapixel"] = (t["process_s"] + t["metrics_s"]) / units["output_mpx"]
    by_name = {spec.name: spec for spec in config.scenes}
    rendered = [(r["render_time_s"], by_name[r["scene"]]) for r in timing["renders"].values()
                if r["scene"] in by_name and not r["reused"]]  # keys carry the f-number and render seed
    for key in ("optics_per_megapixel_band", "capture_per_megapixel", "output_per_megapixel"):
        print(f"{key} = {measured[key]:.3g}")
    if rendered:
        seconds, spec = max(rendered, key=lambda r: r[0])
        u = sizing.scene_units(config, spec, 1)
        measured["render_per_megasample_band"] = seconds / (u["render_msample_band"] / u["renders"])
        print(f"render_per_megasample_band = {measured['render_per_megasample_band']:.3g}  (the slowest render, "
              f"{spec.name})")
    wall = timing["phases"]["total_s"] - timing["phases"].get("report_s", 0.0)
    print(f"measured: {wall:.1f} s without the report")
    print(f"estimate with data/study_costs.toml: {sizing.study_size(config, args.workers).describe()}")
    print(f"estimate with these costs: {sizing.study_size(config, args.workers, costs=measured).describe()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
