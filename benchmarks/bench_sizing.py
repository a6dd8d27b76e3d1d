"""The per-unit costs of cfa_mitsuba/data/study_costs.toml, from a finished
study: its timing.json divided by the units its config implies (the counts
of cfa_mitsuba/study/sizing.py).  Run the study with --workers 1 so every
optical image is made once:

    cfa-mitsuba study configs/quick.toml --out /tmp/quick1 --workers 1 --no-report
    python benchmarks/bench_sizing.py /tmp/quick1

Prints the costs, then the study's estimate with them against its measured
wall time.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def main() -> int:
    from cfa_mitsuba.study.budget import _bands
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.sizing import _conditions, _scene_size, study_size

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path)
    args = ap.parse_args()
    config = load_config(json.loads((args.results / "config.json").read_text())["path"])
    timing = json.loads((args.results / "timing.json").read_text())
    bands = _bands(config.render)
    units = {"optics": 0.0, "capture": 0.0, "output": 0.0}
    for spec in config.scenes:
        w, h, spp, k = _scene_size(spec)
        n = _conditions(config, spec)
        units["optics"] += n * w * h / 1e6 * bands
        units["capture"] += n * len(config.cfas) * config.seeds * w * h / 1e6
        units["output"] += n * len(config.cfas) * config.seeds * len(config.demosaics) * w * h / 1e6 / k**2
    t = timing["tasks"]
    print(f"optics_per_megapixel_band = {t['optics_s'] / units['optics']:.3g}")
    print(f"capture_per_megapixel = {t['capture_s'] / units['capture']:.3g}")
    print(f"output_per_megapixel = {(t['process_s'] + t['metrics_s']) / units['output']:.3g}")
    renders = timing["renders"]
    rendered = [(renders[s.name]["render_time_s"], s) for s in config.scenes
                if s.name in renders and not renders[s.name]["reused"]]
    if rendered:
        seconds, spec = max(rendered, key=lambda r: r[0])
        w, h, spp, _ = _scene_size(spec)
        print(f"render_per_megasample_band = {seconds / (w * h / 1e6 * spp * bands):.3g}  (the slowest render, "
              f"{spec.name})")
    size = study_size(config, 1)
    print(f"estimate with data/study_costs.toml: {size.describe()}; "
          f"measured {timing['phases']['total_s']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
